//! The verdict on the final model (docs/analysis.md#model-fit): after the selection, the block-mean residuals
//! the final model leaves are set against what the channel's noise model (named from the Allan variance of
//! the longest dwell) says a block mean scatters by. Where they scatter more, something is still unexplained:
//! the verdict says on which channels, at which time scale (between the dwells: the dwell means wander; or
//! within them: over seconds to a dwell's length) and in which dwells.

use serde::Serialize;

use crate::stats::linfit::chi_square_upper;

use super::noise_terms::{NoiseModel, Term};
use super::selection::BlockOf;
use super::wander::whiten_walk;
use super::{ALPHA, CHANNELS};

/// Most dwells the verdict names.
const MAX_DWELLS_NAMED: usize = 6;

/// How the final model fits the block means, against the noise model.
#[derive(Clone, Debug, Serialize)]
pub struct ModelFit {
    /// "explained" (every group's chi-square within the noise model's, at `alpha` over the groups) or
    /// "unexplained".
    pub verdict: String,
    /// Per observation group (channel, or the force along gravity).
    pub groups: Vec<GroupFit>,
    /// The dwells of a group whose own chi-square is beyond the noise model's (at `alpha` over every dwell
    /// and group), the largest first, at most six.
    pub dwells: Vec<DwellFit>,
}

/// One group's chi-square against the noise model, split into between and within the dwells.
#[derive(Clone, Debug, Serialize)]
pub struct GroupFit {
    /// Group name ("az_mps2").
    pub channel: String,
    /// Unit of the residuals.
    pub unit: String,
    /// Block means.
    pub observations: usize,
    /// RMS of the final model's block-mean residuals, `unit`.
    pub residual_rms: f64,
    /// RMS the noise model gives a block mean (its Allan deviation at each block's length), `unit`.
    pub noise_rms: f64,
    /// Sum of the squared residuals over the noise model's variances.
    pub chi_square: f64,
    /// Observations less the parameters acting on the group (each bias and effect counted whole).
    pub dof: f64,
    /// Upper-tail probability of `chi_square` at `dof`.
    pub p_value: f64,
    /// The part of `chi_square` in the dwells' weighted mean residuals: what wanders from dwell to dwell.
    pub chi_square_between_dwells: f64,
    /// Its degrees of freedom (dwells less the parameters, at least 1).
    pub dof_between_dwells: f64,
    /// The rest: the scatter of the blocks about their dwell's mean (seconds to a dwell's length).
    pub chi_square_within_dwells: f64,
    /// Its degrees of freedom (observations less dwells).
    pub dof_within_dwells: f64,
    /// `p_value` passes `alpha` over the groups.
    pub explained: bool,
}

/// One dwell of one group beyond the noise model.
#[derive(Clone, Debug, Serialize)]
pub struct DwellFit {
    /// Position label of the dwell.
    pub pos: u32,
    /// Group name.
    pub channel: String,
    /// Its block means.
    pub blocks: usize,
    /// Their weighted mean residual, in the group's unit.
    pub mean_residual: f64,
    /// Their chi-square against the noise model.
    pub chi_square: f64,
}

/// The block means of a recording's final fit, as the verdict reads them.
pub(super) struct FitResiduals<'a> {
    /// Final residual of each observation.
    pub residual: &'a [f64],
    /// Group of each observation.
    pub group: &'a [usize],
    /// Where and when each observation's block lies.
    pub block: &'a [BlockOf],
    /// Position label of each observation.
    pub pos: &'a [u32],
    /// Group names and units.
    pub group_names: &'a [String],
    /// See `group_names`.
    pub group_units: &'a [&'static str],
    /// Per group: the parameters of the final model acting on it.
    pub parameters: Vec<usize>,
}

/// The channels whose noise models give the group's block-mean variance: the group's own, or (the force
/// along gravity) the three accelerometers', averaged.
fn noise_variance(group_name: &str, models: &[NoiseModel], tau_s: f64) -> Option<f64> {
    let of = |name: &str| models.iter().find(|m| m.channel == name).map(|m| m.allan_deviation(tau_s).powi(2));
    if CHANNELS.contains(&group_name) {
        return of(group_name);
    }
    let accels: Vec<f64> = CHANNELS[3..].iter().filter_map(|c| of(c)).collect();
    (accels.len() == 3).then(|| accels.iter().sum::<f64>() / 3.0)
}

/// The rate random walk `K` the group's noise model names (the channel unit per sqrt(s); 0 when none): the
/// group's own, or (the force along gravity) the root mean square of the three accelerometers'.
fn noise_walk(group_name: &str, models: &[NoiseModel]) -> f64 {
    let of = |name: &str| {
        let model = models.iter().find(|m| m.channel == name);
        model.and_then(|m| m.terms.iter().find(|t| t.term == Term::RateRandomWalk)).map_or(0.0, |t| t.value_si)
    };
    if CHANNELS.contains(&group_name) {
        return of(group_name);
    }
    (CHANNELS[3..].iter().map(|c| of(c).powi(2)).sum::<f64>() / 3.0).sqrt()
}

/// A channel's noise warm-up (docs/analysis.md#noise-warm-up), as the block means see it.
pub(super) struct NoiseWarmupOf {
    /// The channel ("gx_radps", ...).
    pub channel: &'static str,
    /// The standard deviation it adds to each sample, channel unit.
    pub excess: f64,
    /// The record time at which it has settled, s.
    pub settled_at_s: f64,
    /// Samples per second.
    pub rate_hz: f64,
}

/// The variance a noise warm-up of `warmups` adds to the mean of `block` in group `group_name` (the force
/// along gravity: the three accelerometers' averaged, as [`noise_variance`] averages their noise): the
/// excess's variance over the block's samples, times the share of them before it settled.
fn warmup_variance(group_name: &str, warmups: &[NoiseWarmupOf], block: &BlockOf) -> f64 {
    let of = |name: &str| {
        let w = warmups.iter().find(|w| w.channel == name)?;
        let start_s = block.t_mid_s - 0.5 * block.duration_s;
        let share = ((w.settled_at_s - start_s) / block.duration_s.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        Some(w.excess * w.excess * share / (block.duration_s * w.rate_hz).max(1.0))
    };
    if CHANNELS.contains(&group_name) {
        return of(group_name).unwrap_or(0.0);
    }
    CHANNELS[3..].iter().map(|c| of(c).unwrap_or(0.0)).sum::<f64>() / 3.0
}

/// The verdict on `fit` against `models` and the channels' noise warm-ups; `None` when no group has a noise
/// model.
pub(super) fn model_fit(fit: &FitResiduals, models: &[NoiseModel], warmups: &[NoiseWarmupOf]) -> Option<ModelFit> {
    let variance = |name: &str, block: &BlockOf| {
        noise_variance(name, models, block.duration_s).map(|v| v + warmup_variance(name, warmups, block))
    };
    model_fit_with(fit, variance, |name| noise_walk(name, models))
}

/// The verdict on `fit`, `variance(group name, block)` giving the noise variance of a block mean and
/// `walk_of(group name)` the rate random walk of its bias (`K`, the unit per sqrt(s)).
fn model_fit_with(
    fit: &FitResiduals,
    variance_of: impl Fn(&str, &BlockOf) -> Option<f64>,
    walk_of: impl Fn(&str) -> f64,
) -> Option<ModelFit> {
    let groups_present: Vec<usize> = (0..fit.group_names.len()).filter(|g| fit.group.contains(g)).collect();
    let mut groups = Vec::new();
    let mut dwells = Vec::new();
    let dwell_cells = dwell_count(fit);
    for &g in &groups_present {
        let name = &fit.group_names[g];
        let rows: Vec<usize> = (0..fit.residual.len()).filter(|&i| fit.group[i] == g).collect();
        let variance: Option<Vec<f64>> =
            rows.iter().map(|&i| variance_of(name, &fit.block[i]).filter(|v| *v > 0.0)).collect();
        let Some(variance) = variance else { continue };
        let (group, named) = group_fit(fit, g, (&rows, &variance), walk_of(name), dwell_cells);
        groups.push(group);
        dwells.extend(named);
    }
    if groups.is_empty() {
        return None;
    }
    let level = ALPHA / groups.len() as f64;
    for group in groups.iter_mut() {
        group.explained = group.p_value > level;
    }
    dwells.sort_by(|a, b| b.chi_square.total_cmp(&a.chi_square));
    dwells.truncate(MAX_DWELLS_NAMED);
    let verdict = if groups.iter().all(|g| g.explained) { "explained" } else { "unexplained" };
    Some(ModelFit { verdict: verdict.into(), groups, dwells })
}

/// Dwell-group cells with observations: the Bonferroni count of the dwell test.
fn dwell_count(fit: &FitResiduals) -> usize {
    let mut cells: Vec<(usize, usize)> = (0..fit.residual.len()).map(|i| (fit.block[i].dwell, fit.group[i])).collect();
    cells.sort_unstable();
    cells.dedup();
    cells.len().max(1)
}

/// One dwell's sums over its blocks in a group's fit.
#[derive(Default)]
struct DwellSums {
    /// `sum r / v` (residual `r`, noise variance `v` of the block mean).
    weighted_residual: f64,
    /// `sum 1 / v`.
    weight: f64,
    /// `sum r^2 / v`.
    chi_square: f64,
    /// Blocks.
    blocks: usize,
    /// The dwell's label.
    pos: u32,
    /// Sum of the blocks' middle times, s.
    t_mid_sum_s: f64,
}

/// Group `g`'s fit (its observations `rows`, their noise variances `variance`) and its dwells beyond the
/// noise model at `alpha` over `dwell_cells`. Between the dwells, the dwells' mean residuals are whitened with
/// the bias's rate random walk `walk_per_sqrt_s` (the noise model's `K`): a bias that wanders by what the
/// noise model says moves the dwell means by that much, and is not unexplained.
fn group_fit(
    fit: &FitResiduals,
    g: usize,
    (rows, variance): (&[usize], &[f64]),
    walk_per_sqrt_s: f64,
    dwell_cells: usize,
) -> (GroupFit, Vec<DwellFit>) {
    let name = fit.group_names[g].clone();
    let within_and_means: f64 = rows.iter().zip(variance).map(|(&i, v)| fit.residual[i].powi(2) / v).sum();
    let mut per_dwell: std::collections::BTreeMap<usize, DwellSums> = Default::default();
    for (&i, v) in rows.iter().zip(variance) {
        let d = per_dwell.entry(fit.block[i].dwell).or_insert(DwellSums { pos: fit.pos[i], ..Default::default() });
        d.weighted_residual += fit.residual[i] / v;
        d.weight += 1.0 / v;
        d.chi_square += fit.residual[i].powi(2) / v;
        d.blocks += 1;
        d.t_mid_sum_s += fit.block[i].t_mid_s;
    }
    // Per dwell, in time order: its mean time, s, its weighted mean residual and that mean's variance.
    let mut means: Vec<(f64, f64, f64)> = per_dwell
        .values()
        .map(|d| (d.t_mid_sum_s / d.blocks as f64, d.weighted_residual / d.weight, 1.0 / d.weight))
        .collect();
    means.sort_by(|a, b| a.0.total_cmp(&b.0));
    let unwhitened: f64 = per_dwell.values().map(|d| d.weighted_residual.powi(2) / d.weight).sum();
    let (t_s, mean, mean_variance): (Vec<f64>, Vec<f64>, Vec<f64>) =
        (means.iter().map(|m| m.0).collect(), means.iter().map(|m| m.1).collect(), means.iter().map(|m| m.2).collect());
    let between: f64 = whiten_walk(walk_per_sqrt_s, &t_s, &mean_variance, &mean).0.iter().map(|e| e * e).sum();
    let chi_square = within_and_means - unwhitened + between;
    let n = rows.len() as f64;
    let p = fit.parameters[g] as f64;
    let dwells = per_dwell.len() as f64;
    let dof = (n - p).max(1.0);
    let level = ALPHA / dwell_cells as f64;
    let named = per_dwell
        .values()
        .filter(|d| chi_square_upper(d.chi_square, d.blocks as f64) < level)
        .map(|d| DwellFit {
            pos: d.pos,
            channel: name.clone(),
            blocks: d.blocks,
            mean_residual: d.weighted_residual / d.weight,
            chi_square: d.chi_square,
        })
        .collect();
    let rms = |v: &mut dyn Iterator<Item = f64>| (v.sum::<f64>() / n).sqrt();
    let group = GroupFit {
        channel: name,
        unit: fit.group_units[g].into(),
        observations: rows.len(),
        residual_rms: rms(&mut rows.iter().map(|&i| fit.residual[i].powi(2))),
        noise_rms: rms(&mut variance.iter().copied()),
        chi_square,
        dof,
        p_value: chi_square_upper(chi_square, dof),
        chi_square_between_dwells: between,
        dof_between_dwells: (dwells - p).max(1.0),
        chi_square_within_dwells: chi_square - between,
        dof_within_dwells: (n - dwells).max(1.0),
        explained: true,
    };
    (group, named)
}

impl ModelFit {
    /// Lines of text: the verdict, each group's chi-square per degree of freedom between and within the
    /// dwells, and the dwells beyond the noise model.
    pub fn lines(&self) -> Vec<String> {
        let mut out = vec![format!(
            "model fit: {} by the noise model (block means against each channel's named noise at the block's \
             length; chi2/dof, alpha {ALPHA} over the groups)",
            self.verdict
        )];
        for g in &self.groups {
            let ratio = |chi2: f64, dof: f64| chi2 / dof;
            out.push(format!(
                "  {}: residual RMS {:.3e} {u} against noise {:.3e} {u}; chi2/dof {:.2} (p {:.1e}): between dwells \
                 {:.2}, within dwells {:.2}{}",
                g.channel,
                g.residual_rms,
                g.noise_rms,
                ratio(g.chi_square, g.dof),
                g.p_value,
                ratio(g.chi_square_between_dwells, g.dof_between_dwells),
                ratio(g.chi_square_within_dwells, g.dof_within_dwells),
                if g.explained { "" } else { ": unexplained" },
                u = g.unit,
            ));
        }
        out.extend(self.dwells.iter().map(|d| format!("  {}", d.text())));
        out
    }
}

impl DwellFit {
    /// "unexplained in pos 3 ay_mps2: 4 blocks, mean residual +8.673e-3, chi2/blocks 66.5".
    pub fn text(&self) -> String {
        format!(
            "unexplained in pos {} {}: {} blocks, mean residual {:+.3e}, chi2/blocks {:.1}",
            self.pos,
            self.channel,
            self.blocks,
            self.mean_residual,
            self.chi_square / self.blocks as f64
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// The block means of a test: their residuals, places and position labels.
    struct Means {
        residual: Vec<f64>,
        group: Vec<usize>,
        block: Vec<BlockOf>,
        pos: Vec<u32>,
        group_names: Vec<String>,
    }

    impl Means {
        fn fit(&self) -> FitResiduals<'_> {
            FitResiduals {
                residual: &self.residual,
                group: &self.group,
                block: &self.block,
                pos: &self.pos,
                group_names: &self.group_names,
                group_units: &["m/s^2"; 6],
                parameters: vec![1; 6],
            }
        }
    }

    /// Six dwells of ten 6-s blocks on one channel (ax), residuals white with the standard deviation `sigma`,
    /// plus `offset(dwell)`.
    fn residuals(sigma: f64, offset: impl Fn(usize) -> f64) -> Means {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut residual, mut block, mut pos) = (Vec::new(), Vec::new(), Vec::new());
        for d in 0..6 {
            for k in 0..10 {
                let z: f64 = StandardNormal.sample(&mut rng);
                residual.push(sigma * z + offset(d));
                block.push(BlockOf { dwell: d, duration_s: 6.0, t_mid_s: 100.0 * d as f64 + 6.0 * k as f64 });
                pos.push(d as u32 + 1);
            }
        }
        let group_names = CHANNELS.iter().map(|c| c.to_string()).collect();
        Means { group: vec![3; residual.len()], residual, block, pos, group_names }
    }

    #[test]
    fn residuals_as_large_as_the_noise_are_explained() {
        let sigma = 1e-3;
        let variance = |name: &str, block: &BlockOf| {
            assert_eq!((name, block.duration_s), ("ax_mps2", 6.0));
            Some(sigma * sigma)
        };
        let fit = model_fit_with(&residuals(sigma, |_| 0.0).fit(), variance, |_| 0.0).unwrap();
        assert_eq!(fit.verdict, "explained");
        let g = &fit.groups[0];
        assert!((g.chi_square / g.dof - 1.0).abs() < 0.4, "{g:?}");
        assert!((g.chi_square_between_dwells + g.chi_square_within_dwells - g.chi_square).abs() < 1e-9);
        assert!(fit.dwells.is_empty(), "{:?}", fit.dwells);
    }

    #[test]
    fn a_dwell_off_by_more_than_the_noise_is_named_between_the_dwells() {
        // Dwell 3 (pos 4) sits 3 sigma off: its ten blocks give a chi-square of about 90 on 10.
        let sigma = 1e-3;
        let offset = |d: usize| if d == 3 { 3.0 * sigma } else { 0.0 };
        let fit = model_fit_with(&residuals(sigma, offset).fit(), |_, _| Some(sigma * sigma), |_| 0.0).unwrap();
        assert_eq!(fit.verdict, "unexplained");
        let g = &fit.groups[0];
        assert!(!g.explained);
        assert!(g.chi_square_between_dwells / g.dof_between_dwells > 10.0, "{g:?}");
        assert!(g.chi_square_within_dwells / g.dof_within_dwells < 1.5, "{g:?}");
        assert_eq!(fit.dwells.first().map(|d| (d.pos, d.channel.as_str())), Some((4, "ax_mps2")), "{:?}", fit.dwells);
        assert!((fit.dwells[0].mean_residual / sigma - 3.0).abs() < 1.0);
    }

    #[test]
    fn dwell_means_that_wander_by_the_noise_models_walk_are_explained() {
        // The dwell means (100 s apart) follow a random walk of K = 1e-3 per sqrt(s): steps of 1e-2, ten
        // times the blocks' noise. Without the walk the dwells are unexplained; with the noise model's K the
        // walk's innovations are its steps over their standard deviations, and the fit is explained.
        let (sigma, k) = (1e-4, 1e-3);
        let steps = [0.0, 1.2, -0.4, 0.9, -1.5, 0.3];
        let walk = |d: usize| steps[..=d].iter().sum::<f64>() * k * 100f64.sqrt();
        let fit_of = |walk_per_sqrt_s: f64| {
            model_fit_with(&residuals(sigma, walk).fit(), |_, _| Some(sigma * sigma), |_| walk_per_sqrt_s).unwrap()
        };
        let without = fit_of(0.0);
        assert_eq!(without.verdict, "unexplained", "{without:?}");
        let with = fit_of(k);
        assert_eq!(with.verdict, "explained", "{with:?}");
        let g = &with.groups[0];
        assert!(g.chi_square_between_dwells / g.dof_between_dwells < 3.0, "{g:?}");
    }

    #[test]
    fn without_a_noise_model_there_is_no_verdict() {
        assert!(model_fit_with(&residuals(1e-3, |_| 0.0).fit(), |_, _| None, |_| 0.0).is_none());
    }
}
