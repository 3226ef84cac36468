//! Time terms against the slow wander of a bias (docs/analysis.md#confounding): a bias that wanders (a rate
//! random walk) puts ramps into the block means that a drift or a warm-up fitted against white block noise
//! takes for a term. After the selection, every time term chosen is tested again by the exact likelihood of its
//! channel's block means under white block noise plus a random walk of the bias whose size is fitted (a Kalman
//! filter whose normalised innovations whiten the means and the columns): a term that then fails the criterion
//! a random walk explains as well, and is marked uncertain with [`WANDER`] as its alias.
//!
//! The same wander gives the standard errors that hold on measured noise (docs/analysis.md#windows): the
//! sandwich of the selection's weighted least squares under white block noise plus the random walk each
//! channel's block means prefer ([`sandwich_std_errors`]), for the final model's effects and for every
//! candidate tested against the base model.

use crate::stats::linfit::{chi_square_quantile_upper, fit, LinearFit, Observations};

use super::noise_terms::{NoiseModel, Term};
use super::result::std_error_of;
use super::selection::{final_columns, BlockOf, Problem, Selection, Unsupported};
use super::ALPHA;

/// The alias of a time term that the noise model's wander explains.
pub(super) const WANDER: &str = "the bias's slow wander (a random walk explains it as well)";

/// A bias wander of one channel: a rate random walk, with the white noise of its block means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Wander {
    /// White noise density `N` (channel unit times sqrt(s)): a block mean of `T` s has the variance `N^2 / T`.
    pub white_per_sqrt_hz: f64,
    /// Rate random walk `K` (channel unit per sqrt(s)): the bias changes by `K^2 dt` in variance over `dt`.
    pub random_walk_per_sqrt_s: f64,
}

/// Random-walk densities tried per test, from 1e-4 of the largest to it (and none).
const RANDOM_WALK_GRID: usize = 33;

impl Wander {
    /// `v` (one value per block, blocks at middle times `t_s` and of lengths `block_s`, in time order)
    /// whitened: the innovations of the Kalman filter of the random walk (from 0 at the first block) plus each
    /// block mean's white noise, each over its standard deviation; and the sum of the logarithms of the
    /// innovations' variances (the likelihood's determinant). Linear in `v`: applied to the observations and to
    /// every column alike.
    pub fn whiten(&self, t_s: &[f64], block_s: &[f64], v: &[f64]) -> (Vec<f64>, f64) {
        let white = |b: &f64| {
            (self.white_per_sqrt_hz * self.white_per_sqrt_hz / b.max(f64::MIN_POSITIVE)).max(f64::MIN_POSITIVE)
        };
        let variances: Vec<f64> = block_s.iter().map(white).collect();
        whiten_walk(self.random_walk_per_sqrt_s, t_s, &variances, v)
    }
}

/// [`Wander::whiten`] with each value's own white variance given (`variances`, in the values' unit squared).
pub(super) fn whiten_walk(random_walk_per_sqrt_s: f64, t_s: &[f64], variances: &[f64], v: &[f64]) -> (Vec<f64>, f64) {
    let (mut r, mut p, mut log_det) = (0.0, 0.0, 0.0);
    let mut out = Vec::with_capacity(v.len());
    for i in 0..v.len() {
        let dt_s = if i == 0 { 0.0 } else { (t_s[i] - t_s[i - 1]).max(0.0) };
        p += random_walk_per_sqrt_s * random_walk_per_sqrt_s * dt_s;
        let s = p + variances[i];
        let e = v[i] - r;
        out.push(e / s.sqrt());
        log_det += s.ln();
        let gain = p / s;
        r += gain * e;
        p -= gain * p;
    }
    (out, log_det)
}

/// The random-walk densities the profiles try: none, then from ten times the observations' RMS per square
/// root of their span down to 1e-4 of that, on a logarithmic grid.
fn random_walk_grid(t_s: &[f64], y: &[f64]) -> impl Iterator<Item = f64> {
    let span_s = match (t_s.first(), t_s.last()) {
        (Some(a), Some(b)) => (b - a).max(f64::MIN_POSITIVE),
        _ => f64::MIN_POSITIVE,
    };
    let rms = (y.iter().map(|v| v * v).sum::<f64>() / y.len().max(1) as f64).sqrt();
    let largest_per_sqrt_s = 10.0 * rms / span_s.sqrt();
    std::iter::once(0.0).chain(
        (0..RANDOM_WALK_GRID).map(move |i| largest_per_sqrt_s * 1e-4f64.powf(i as f64 / (RANDOM_WALK_GRID - 1) as f64)),
    )
}

/// The exact log-likelihoods (up to a constant) of `y` under `wander`, at block times `t_s` and lengths
/// `block_s`, with the regression `without` fitted by generalised least squares and with `without` and `own`:
/// the observations and the columns are whitened once for both fits. `None` when the columns are dependent.
fn log_likelihoods(
    wander: Wander,
    (t_s, block_s): (&[f64], &[f64]),
    y: &[f64],
    without: &[Vec<f64>],
    own: &[f64],
) -> Option<(f64, f64)> {
    let (yw, log_det) = wander.whiten(t_s, block_s, y);
    let mut cols: Vec<Vec<f64>> = without.iter().map(|c| wander.whiten(t_s, block_s, c).0).collect();
    cols.push(wander.whiten(t_s, block_s, own).0);
    let n = yw.len();
    let obs = Observations { y: yw, group: vec![0; n], groups: 1, sigma: Some(vec![1.0; n]) };
    let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
    let log_likelihood = |columns: &[&[f64]]| {
        let f = fit(&obs, columns)?;
        Some(-0.5 * (f.residual.iter().map(|r| r * r).sum::<f64>() + log_det))
    };
    Some((log_likelihood(&refs[..refs.len() - 1])?, log_likelihood(&refs)?))
}

/// The likelihood ratio of `own` added to `without` ([`log_likelihoods`]), each side at its best random walk
/// ([`random_walk_grid`]).
fn profiled_ratio(
    white_per_sqrt_hz: f64,
    times: (&[f64], &[f64]),
    y: &[f64],
    without: &[Vec<f64>],
    own: &[f64],
) -> Option<f64> {
    let (mut best_without, mut best_with) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for random_walk_per_sqrt_s in random_walk_grid(times.0, y) {
        let wander = Wander { white_per_sqrt_hz, random_walk_per_sqrt_s };
        if let Some((l0, l1)) = log_likelihoods(wander, times, y, without, own) {
            best_without = best_without.max(l0);
            best_with = best_with.max(l1);
        }
    }
    best_with.is_finite().then_some(2.0 * (best_with - best_without))
}

/// The white noise density `N` of a channel's block means: its noise model's white term, else its white-only
/// fit (channel unit times sqrt(s)).
fn white_density(model: &NoiseModel) -> f64 {
    model.terms.iter().find(|t| t.term == Term::White).unwrap_or(&model.white_only).value_si
}

/// The wander of one channel's block means (in time order) that the likelihood prefers, with `columns`
/// fitted by generalised least squares: its white density `white_per_sqrt_hz` and the random walk of
/// [`random_walk_grid`] of the largest likelihood (none if white noise alone is as likely).
fn likeliest_wander(white_per_sqrt_hz: f64, times: (&[f64], &[f64]), y: &[f64], columns: &[Vec<f64>]) -> Wander {
    let none = Wander { white_per_sqrt_hz, random_walk_per_sqrt_s: 0.0 };
    let Some((own, without)) = columns.split_last() else { return none };
    let mut best = (f64::NEG_INFINITY, none);
    for random_walk_per_sqrt_s in random_walk_grid(times.0, y) {
        let wander = Wander { white_per_sqrt_hz, random_walk_per_sqrt_s };
        if let Some((_, full)) = log_likelihoods(wander, times, y, without, own) {
            if full > best.0 {
                best = (full, wander);
            }
        }
    }
    best.1
}

/// `C z` for the covariance of a random walk of unit density sampled at `t_s` (ascending), from zero at the
/// first time: `C_ij = min(t_i, t_j) - t_0`, in one pass each way.
fn random_walk_times(t_s: &[f64], z: &[f64]) -> Vec<f64> {
    let t0 = t_s.first().copied().unwrap_or(0.0);
    let mut after: Vec<f64> = vec![0.0; z.len()];
    for i in (0..z.len().saturating_sub(1)).rev() {
        after[i] = after[i + 1] + z[i + 1];
    }
    let mut before = 0.0;
    (0..z.len())
        .map(|i| {
            before += (t_s[i] - t0) * z[i];
            before + (t_s[i] - t0) * after[i]
        })
        .collect()
}

/// A fitted linear model of block means (a recording's, or one window's of it), as
/// [`sandwich_std_errors`] reads it.
pub(super) struct BlockModel<'a> {
    /// The observations.
    pub obs: &'a Observations,
    /// Where and when each observation's block lies.
    pub blocks: &'a [BlockOf],
    /// The model's columns, in the order of `fit.beta`.
    pub columns: &'a [&'a [f64]],
    /// Their weighted least-squares fit.
    pub fit: &'a LinearFit,
}

/// Per column of the final model ([`final_columns`]): [`sandwich_std_errors`]. Empty when the observations
/// have no time (angles).
pub(super) fn wander_std_errors(problem: &Problem, selection: &Selection, models: &[NoiseModel]) -> Vec<f64> {
    let Some(blocks) = &problem.obs_block else { return Vec::new() };
    let columns = final_columns(problem, selection);
    let columns: Vec<&[f64]> = columns.iter().map(|c| c.as_ref()).collect();
    let model = BlockModel { obs: &problem.obs, blocks, columns: &columns, fit: &selection.final_fit };
    sandwich_std_errors(&model, &white_densities(problem, models))
}

/// Most candidates times observations [`widen_tested`] refits (each candidate costs a fit of the whole
/// recording): 10,000 dwells have some 20,000 position-error candidates on 240,000 block means.
const MAX_TESTED_REFITS: usize = 50_000_000;

/// Widens the standard error of every candidate of `selection.tested` (each fitted with the base model
/// alone) to its sandwich with each channel's random walk of the bias, the walk being the one the final
/// model's residuals prefer (profiled once per channel, not per candidate: the base model's residuals hold
/// the effects found, which a walk profiled on them would take for wander). Angles, and recordings past
/// [`MAX_TESTED_REFITS`]: unchanged (the effects always get theirs, [`wander_std_errors`]).
pub(super) fn widen_tested(problem: &Problem, selection: &mut Selection, models: &[NoiseModel]) {
    let Some(blocks) = &problem.obs_block else { return };
    if selection.tested.len().saturating_mul(problem.obs.y.len()) > MAX_TESTED_REFITS {
        return;
    }
    let final_columns = final_columns(problem, selection);
    let final_refs: Vec<&[f64]> = final_columns.iter().map(|c| c.as_ref()).collect();
    let final_model = BlockModel { obs: &problem.obs, blocks, columns: &final_refs, fit: &selection.final_fit };
    let wanders = group_wanders(&final_model, &white_densities(problem, models));
    let base: Vec<&[f64]> = problem.base.iter().map(|c| c.as_slice()).collect();
    for t in &mut selection.tested {
        let (ci, vi) = t.column;
        let own = problem.candidates[ci].variants[vi].1.dense();
        let mut columns = base.clone();
        columns.push(&own);
        let Some(f) = fit(&problem.obs, &columns) else { continue };
        let model = BlockModel { obs: &problem.obs, blocks, columns: &columns, fit: &f };
        if let Some(&se) = sandwich(&model, &wanders).last() {
            t.std_error = t.std_error.max(se);
        }
    }
}

/// Per observation group: the white density of its channel's noise model ([`white_density`]); `None` for a
/// group without one (the force along gravity).
pub(super) fn white_densities(problem: &Problem, models: &[NoiseModel]) -> Vec<Option<f64>> {
    let of = |name: &String| models.iter().find(|m| &m.channel == name).map(white_density);
    problem.group_names.iter().map(of).collect()
}

/// Per column of `model`: the standard error of its estimate (the weighted least squares of `model.fit`)
/// when each channel's block means carry, besides their white noise, the random walk of the bias that their
/// likelihood prefers ([`likeliest_wander`]; none when white noise alone is as likely). It is the sandwich
/// `A (X' W S W X) A`, with `A` the fit's covariance, `W` its weights and `S` the block means' covariance:
/// `N^2 / T` on the diagonal plus `K^2 (min(t_i, t_j) - t_0)`. A group without a noise model (the force along
/// gravity: `None` in `white_per_sqrt_hz`, one per group) keeps the fit's own variance.
pub(super) fn sandwich_std_errors(model: &BlockModel, white_per_sqrt_hz: &[Option<f64>]) -> Vec<f64> {
    sandwich(model, &group_wanders(model, white_per_sqrt_hz))
}

/// A group's rows in time order.
fn rows_in_time(obs: &Observations, blocks: &[BlockOf], g: usize) -> Vec<usize> {
    let mut rows: Vec<usize> = (0..obs.y.len()).filter(|&i| obs.group[i] == g).collect();
    rows.sort_by(|&a, &b| blocks[a].t_mid_s.total_cmp(&blocks[b].t_mid_s));
    rows
}

/// Per group of `model`: the wander its block means prefer with the model's columns
/// ([`likeliest_wander`]); `None` for a group without a white density.
fn group_wanders(model: &BlockModel, white_per_sqrt_hz: &[Option<f64>]) -> Vec<Option<Wander>> {
    let BlockModel { obs, blocks, columns, .. } = *model;
    (0..obs.groups)
        .map(|g| {
            let white = white_per_sqrt_hz[g]?;
            let rows = rows_in_time(obs, blocks, g);
            let on_rows = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let own: Vec<Vec<f64>> =
                columns.iter().filter(|c| rows.iter().any(|&i| c[i] != 0.0)).map(|c| on_rows(c)).collect();
            let t_s: Vec<f64> = rows.iter().map(|&i| blocks[i].t_mid_s).collect();
            let block_s: Vec<f64> = rows.iter().map(|&i| blocks[i].duration_s).collect();
            Some(likeliest_wander(white, (&t_s, &block_s), &on_rows(&obs.y), &own))
        })
        .collect()
}

/// [`sandwich_std_errors`] with each group's wander given.
fn sandwich(model: &BlockModel, wanders: &[Option<Wander>]) -> Vec<f64> {
    let BlockModel { obs, blocks, columns, fit } = *model;
    let p = columns.len();
    let mut meat = vec![vec![0.0; p]; p];
    for (g, &wander) in wanders.iter().enumerate() {
        let rows = rows_in_time(obs, blocks, g);
        let weight = |i: usize| match &obs.sigma {
            Some(s) => 1.0 / (s[i] * s[i]),
            None => 1.0 / fit.variance[g],
        };
        let local: Vec<usize> = (0..p).filter(|&j| rows.iter().any(|&i| columns[j][i] != 0.0)).collect();
        let weighted: Vec<Vec<f64>> =
            local.iter().map(|&j| rows.iter().map(|&i| weight(i) * columns[j][i]).collect()).collect();
        let t_s: Vec<f64> = rows.iter().map(|&i| blocks[i].t_mid_s).collect();
        let block_s: Vec<f64> = rows.iter().map(|&i| blocks[i].duration_s).collect();
        // `S z` for each weighted column: the white part, then the walk's.
        let covaried: Vec<Vec<f64>> = weighted
            .iter()
            .map(|z| {
                let white: Vec<f64> = (0..rows.len())
                    .map(|r| match wander {
                        Some(w) => w.white_per_sqrt_hz.powi(2) / block_s[r].max(f64::MIN_POSITIVE) * z[r],
                        None => z[r] / weight(rows[r]),
                    })
                    .collect();
                match wander {
                    Some(w) if w.random_walk_per_sqrt_s > 0.0 => {
                        let k2 = w.random_walk_per_sqrt_s.powi(2);
                        white.iter().zip(random_walk_times(&t_s, z)).map(|(a, b)| a + k2 * b).collect()
                    }
                    _ => white,
                }
            })
            .collect();
        for (a, &ja) in local.iter().enumerate() {
            for (b, &jb) in local.iter().enumerate() {
                meat[ja][jb] += weighted[a].iter().zip(&covaried[b]).map(|(x, y)| x * y).sum::<f64>();
            }
        }
    }
    let a = &fit.covariance;
    (0..p)
        .map(|j| {
            let row: Vec<f64> = (0..p).map(|k| (0..p).map(|l| a[j][l] * meat[l][k]).sum()).collect();
            (0..p).map(|k| row[k] * a[k][j]).sum::<f64>().max(0.0).sqrt()
        })
        .collect()
}

/// Marks every time term of `selection` that a random walk of its channel's bias explains as well: with
/// the block means' white noise from the channel's noise model (its `N`, else its white-only fit) and a
/// random walk of free size (profiled), the term's likelihood ratio fails the criterion at `alpha / m`. A
/// group without a noise model (the force along gravity, angles) is not tested.
pub(super) fn mark_wander(problem: &Problem, selection: &mut Selection, models: &[NoiseModel], m: f64) {
    let Some(blocks) = &problem.obs_block else { return };
    let columns = final_columns(problem, selection);
    let mut marked = Vec::new();
    for (q, chosen) in selection.chosen.iter().enumerate() {
        let candidate = &problem.candidates[chosen.candidate];
        let [g] = candidate.groups[..] else { continue };
        let Some(model) = models.iter().find(|x| x.channel == problem.group_names[g]) else { continue };
        if !candidate.effect.is_time_term() {
            continue;
        }
        let white_per_sqrt_hz = white_density(model);
        let rows: Vec<usize> = (0..problem.obs.y.len()).filter(|&i| problem.obs.group[i] == g).collect();
        let on_rows = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        let t_s: Vec<f64> = rows.iter().map(|&i| blocks[i].t_mid_s).collect();
        let block_s: Vec<f64> = rows.iter().map(|&i| blocks[i].duration_s).collect();
        let term = problem.base.len() + q;
        let without: Vec<Vec<f64>> = columns
            .iter()
            .enumerate()
            .filter(|(j, c)| *j != term && rows.iter().any(|&i| c[i] != 0.0))
            .map(|(_, c)| on_rows(c))
            .collect();
        let y = on_rows(&problem.obs.y);
        let Some(ratio) = profiled_ratio(white_per_sqrt_hz, (&t_s, &block_s), &y, &without, &on_rows(&columns[term]))
        else {
            continue;
        };
        if ratio <= chi_square_quantile_upper(ALPHA / m, candidate.parameters() as f64) {
            marked.push(q);
        }
    }
    for q in marked {
        selection.aliases[q].push(WANDER.to_string());
    }
}

/// The chosen effects other than time terms (which [`mark_wander`] marks instead) that the criterion admitted
/// on the likelihood of white block means but whose estimate their own standard error, with the bias's
/// wander ([`super::result::std_error_of`]), cannot tell from zero: `(estimate / std_error)^2` (per parameter)
/// within the criterion at `alpha / m`. The analysis then selects again without them, until none is left
/// (docs/analysis.md#criterion).
pub(super) fn unsupported(problem: &Problem, selection: &Selection, m: f64) -> Vec<Unsupported> {
    let base = problem.base.len();
    (0..selection.chosen.len())
        .filter_map(|q| {
            let candidate = selection.chosen[q].candidate;
            let c = &problem.candidates[candidate];
            if c.effect.is_time_term() {
                return None;
            }
            let (estimate, std_error) = (selection.final_fit.beta[base + q], std_error_of(problem, selection, q));
            let wald = (estimate / std_error).powi(2);
            (wald <= chi_square_quantile_upper(ALPHA / m, c.parameters() as f64)).then_some(Unsupported {
                candidate,
                estimate,
                std_error,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_walk_covariance_product_is_the_matrix_product() {
        // C_ij = min(t_i, t_j) - t_0, written out, against the two-pass product.
        let t = [2.0, 2.5, 4.0, 7.0, 7.5];
        let z = [1.0, -2.0, 0.5, 3.0, -1.5];
        let fast = random_walk_times(&t, &z);
        for i in 0..t.len() {
            let direct: f64 = (0..t.len()).map(|j| (t[i].min(t[j]) - t[0]) * z[j]).sum();
            assert!((fast[i] - direct).abs() < 1e-12, "{i}: {} against {direct}", fast[i]);
        }
    }

    #[test]
    fn the_sandwich_of_a_mean_is_its_variance_under_white_noise_and_a_walk() {
        // One channel, one bias column: the estimate is the mean of the block means, whose variance is
        // (1/n^2) (sum N^2 / T_i + K^2 sum_ij (min(t_i, t_j) - t_0)). The walk's K is the one the likelihood
        // prefers: a sawtooth far above the white noise makes it nonzero, and the sandwich uses it.
        let n = 40;
        let t_s: Vec<f64> = (0..n).map(|i| 10.0 * i as f64).collect();
        let y: Vec<f64> =
            (0..n).map(|i| if (i / 5) % 2 == 0 { (i % 5) as f64 } else { 5.0 - (i % 5) as f64 }).collect();
        let obs = Observations { y: y.clone(), group: vec![0; n], groups: 1, sigma: None };
        let ones = vec![1.0; n];
        let columns: Vec<&[f64]> = vec![&ones];
        let f = fit(&obs, &columns).unwrap();
        let blocks: Vec<BlockOf> = t_s.iter().map(|&t| BlockOf { dwell: 0, duration_s: 10.0, t_mid_s: t }).collect();
        let white_per_sqrt_hz = 0.01;
        let wander = likeliest_wander(white_per_sqrt_hz, (&t_s, &[10.0; 40]), &y, std::slice::from_ref(&ones));
        assert!(wander.random_walk_per_sqrt_s > 0.0, "{wander:?}");
        let k2 = wander.random_walk_per_sqrt_s.powi(2);
        let walk: f64 = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| t_s[i].min(t_s[j])).sum();
        let expected = ((n as f64 * white_per_sqrt_hz.powi(2) / 10.0 + k2 * walk) / (n * n) as f64).sqrt();
        let model = BlockModel { obs: &obs, blocks: &blocks, columns: &columns, fit: &f };
        let se = sandwich_std_errors(&model, &[Some(white_per_sqrt_hz)]);
        assert!((se[0] / expected - 1.0).abs() < 1e-9, "{} against {expected}", se[0]);
        // Far larger than the white standard error of the mean, N / sqrt(T n).
        assert!(se[0] > 10.0 * white_per_sqrt_hz / (10.0 * n as f64).sqrt());
    }

    #[test]
    fn white_noise_alone_is_only_scaled() {
        // No wander: each value over the block mean's standard deviation N / sqrt(T).
        let w = Wander { white_per_sqrt_hz: 2.0, random_walk_per_sqrt_s: 0.0 };
        let (out, log_det) = w.whiten(&[0.0, 10.0, 20.0], &[4.0, 4.0, 4.0], &[1.0, -2.0, 3.0]);
        for (o, v) in out.iter().zip([1.0, -2.0, 3.0]) {
            assert!((o - v).abs() < 1e-12, "{out:?}");
        }
        assert!(log_det.abs() < 1e-12);
    }

    #[test]
    fn a_random_walk_is_whitened_to_its_steps() {
        // A pure random walk (no white noise to speak of), sampled every 1 s: the innovations are the steps
        // over K sqrt(dt), and a straight line becomes a constant (a drift is a bias on the steps).
        let w = Wander { white_per_sqrt_hz: 1e-9, random_walk_per_sqrt_s: 0.5 };
        let t: Vec<f64> = (0..6).map(f64::from).collect();
        let walk = [0.0, 0.5, 0.0, 1.0, 1.5, 1.0];
        let (out, _) = w.whiten(&t, &[1.0; 6], &walk);
        for i in 1..6 {
            assert!((out[i] - (walk[i] - walk[i - 1]) / 0.5).abs() < 1e-6, "{out:?}");
        }
        let line: Vec<f64> = t.iter().map(|t| 0.25 * t).collect();
        let (out, _) = w.whiten(&t, &[1.0; 6], &line);
        assert!(out[1..].iter().all(|v| (v - 0.5).abs() < 1e-6), "{out:?}");
    }
}
