//! Time terms against the slow wander of a bias (docs/analysis.md#confounding): a bias that wanders (a rate
//! random walk) puts ramps into the block means that a drift or a warm-up fitted against white block noise
//! takes for a term. After the selection, every time term chosen is tested again by the exact likelihood of its
//! channel's block means under white block noise plus a random walk of the bias whose size is fitted (a Kalman
//! filter whose normalised innovations whiten the means and the columns): a term that then fails the criterion
//! a random walk explains as well, and is marked uncertain with [`WANDER`] as its alias.

use crate::stats::linfit::{chi_square_quantile_upper, fit, Observations};

use super::noise_terms::{NoiseModel, Term};
use super::selection::{final_columns, Problem, Selection};
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
        let (mut r, mut p, mut log_det) = (0.0, 0.0, 0.0);
        let mut out = Vec::with_capacity(v.len());
        for i in 0..v.len() {
            let dt_s = if i == 0 { 0.0 } else { (t_s[i] - t_s[i - 1]).max(0.0) };
            p += self.random_walk_per_sqrt_s * self.random_walk_per_sqrt_s * dt_s;
            let noise = (self.white_per_sqrt_hz * self.white_per_sqrt_hz / block_s[i].max(f64::MIN_POSITIVE))
                .max(f64::MIN_POSITIVE);
            let s = p + noise;
            let e = v[i] - r;
            out.push(e / s.sqrt());
            log_det += s.ln();
            let gain = p / s;
            r += gain * e;
            p -= gain * p;
        }
        (out, log_det)
    }
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

/// The likelihood ratio of `own` added to `without` ([`log_likelihoods`]), each side at its best random walk:
/// `K` from none up to ten times the observations' RMS per square root of their span, on a logarithmic grid.
fn profiled_ratio(
    white_per_sqrt_hz: f64,
    times: (&[f64], &[f64]),
    y: &[f64],
    without: &[Vec<f64>],
    own: &[f64],
) -> Option<f64> {
    let (t_s, _) = times;
    let span_s = (t_s.last()? - t_s.first()?).max(f64::MIN_POSITIVE);
    let rms = (y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64).sqrt();
    let largest_per_sqrt_s = 10.0 * rms / span_s.sqrt();
    let grid =
        (0..RANDOM_WALK_GRID).map(|i| largest_per_sqrt_s * 1e-4f64.powf(i as f64 / (RANDOM_WALK_GRID - 1) as f64));
    let (mut best_without, mut best_with) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    for random_walk_per_sqrt_s in std::iter::once(0.0).chain(grid) {
        let wander = Wander { white_per_sqrt_hz, random_walk_per_sqrt_s };
        if let Some((l0, l1)) = log_likelihoods(wander, times, y, without, own) {
            best_without = best_without.max(l0);
            best_with = best_with.max(l1);
        }
    }
    best_with.is_finite().then_some(2.0 * (best_with - best_without))
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
        let white_per_sqrt_hz =
            model.terms.iter().find(|t| t.term == Term::White).unwrap_or(&model.white_only).value_si;
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

#[cfg(test)]
mod tests {
    use super::*;

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
