//! Standard errors against disjoint windows (docs/analysis.md#windows): the final model is fitted again on
//! each third of every dwell (the first, middle and last thirds of its blocks), and the three estimates of
//! each parameter are set against their own standard errors. Standard errors that hold give a chi-square of
//! about one per degree of freedom; where the estimates scatter more, the noise has a part that the
//! standard errors do not carry, and the reported standard errors are widened by the square root of the
//! ratio (the Birge ratio, at least one).

use serde::Serialize;

use crate::stats::linfit::{chi_square_quantile_upper, chi_square_upper, fit, Observations};

use super::noise_terms::NoiseModel;
use super::selection::{final_columns, Problem, Selection};
use super::wander::{sandwich_std_errors, white_densities, BlockModel};
use super::ALPHA;

/// Windows per dwell.
pub const WINDOWS: usize = 3;

/// Most parameters the check names.
const MAX_NAMED: usize = 3;

/// The final model's estimates across the windows.
#[derive(Clone, Debug, Serialize)]
pub struct WindowCheck {
    /// Windows (thirds of every dwell).
    pub windows: usize,
    /// Sum over the final model's parameters of the windows' estimates' squared deviations from their
    /// weighted mean, over their variances.
    pub chi_square: f64,
    /// Its degrees of freedom: parameters times windows less one.
    pub dof: f64,
    /// Upper-tail probability of `chi_square` at `dof`.
    pub p_value: f64,
    /// `sqrt(max(1, chi_square / dof))`: the factor the effects' standard errors were widened by.
    pub widened_by: f64,
    /// The parameters of the largest chi-square, largest first.
    pub worst: Vec<WindowParameter>,
}

/// One parameter across the windows.
#[derive(Clone, Debug, Serialize)]
pub struct WindowParameter {
    /// Its name (a base bias, or an effect's candidate name).
    pub name: String,
    /// Its estimate in each window, SI.
    pub estimates: Vec<f64>,
    /// Their standard errors, SI.
    pub std_errors: Vec<f64>,
    /// Its share of the chi-square.
    pub chi_square: f64,
}

impl WindowCheck {
    /// "standard errors across the thirds of every dwell: chi2/dof 1.30 (p 2.1e-1), widened by 1.14; most:
    /// accel_misalignment:yx 4.1".
    pub fn text(&self) -> String {
        let worst: Vec<String> = self.worst.iter().map(|w| format!("{} {:.1}", w.name, w.chi_square)).collect();
        format!(
            "standard errors across the thirds of every dwell: chi2/dof {:.2} (p {:.1e}), widened by {:.2}; most: {}",
            self.chi_square / self.dof,
            self.p_value,
            self.widened_by,
            worst.join(", ")
        )
    }
}

/// The chi-square of estimates about their weighted mean, each over its standard error (`WINDOWS - 1`
/// degrees of freedom for one parameter's windows).
pub(super) fn scatter(estimates: &[f64], std_errors: &[f64]) -> f64 {
    let weights: Vec<f64> = std_errors.iter().map(|s| 1.0 / (s * s).max(f64::MIN_POSITIVE)).collect();
    let mean = estimates.iter().zip(&weights).map(|(e, w)| e * w).sum::<f64>() / weights.iter().sum::<f64>();
    estimates.iter().zip(&weights).map(|(e, w)| (e - mean).powi(2) * w).sum()
}

/// The alias of a noise term whose estimates in the thirds of every dwell differ beyond their standard
/// errors ([`not_stationary`]): an uncertain effect.
pub(super) const NOT_STATIONARY: &str =
    "the thirds of the dwells (it differs between them: its noise is not stationary)";

/// The windows' estimates of one term differ beyond their standard errors: their [`scatter`] is beyond the
/// upper `ALPHA` quantile of chi-square at `WINDOWS - 1` degrees of freedom.
pub(super) fn not_stationary(windows: &[(f64, f64)]) -> bool {
    pairs_scatter(windows).is_some_and(|(chi2, dof)| chi2 > chi_square_quantile_upper(ALPHA, dof))
}

/// The factor a standard error is widened by when its estimates in the windows scatter beyond their own
/// standard errors: `sqrt(max(1, chi2 / dof))` of [`scatter`] (the Birge ratio); 1 for fewer than two
/// windows.
pub(super) fn widening(windows: &[(f64, f64)]) -> f64 {
    pairs_scatter(windows).map_or(1.0, |(chi2, dof)| (chi2 / dof).max(1.0).sqrt())
}

/// [`scatter`] of (estimate, standard error) pairs and its degrees of freedom; `None` for fewer than two.
fn pairs_scatter(windows: &[(f64, f64)]) -> Option<(f64, f64)> {
    if windows.len() < 2 {
        return None;
    }
    let (estimates, std_errors): (Vec<f64>, Vec<f64>) = windows.iter().copied().unzip();
    Some((scatter(&estimates, &std_errors), (windows.len() - 1) as f64))
}

/// The `k`-th of [`WINDOWS`] thirds of every dwell's samples (`k < WINDOWS`).
pub(super) fn window_of_samples(series: &[Vec<f64>], k: usize) -> Vec<Vec<f64>> {
    series.iter().map(|d| d[d.len() * k / WINDOWS..d.len() * (k + 1) / WINDOWS].to_vec()).collect()
}

/// A term's estimate and standard error by `each` on every [`window_of_samples`] of `series`; empty when a
/// window gives none.
pub(super) fn in_windows(series: &[Vec<f64>], each: impl Fn(&[Vec<f64>]) -> Option<(f64, f64)>) -> Vec<(f64, f64)> {
    in_windows_indexed(series, |_, w| each(w))
}

/// [`in_windows`] with each window's index `k` given to `each`.
pub(super) fn in_windows_indexed(
    series: &[Vec<f64>],
    each: impl Fn(usize, &[Vec<f64>]) -> Option<(f64, f64)>,
) -> Vec<(f64, f64)> {
    (0..WINDOWS).map(|k| each(k, &window_of_samples(series, k))).collect::<Option<Vec<_>>>().unwrap_or_default()
}

/// The first samples of the `k`-th [`window_of_samples`] of `series`, whose dwells start at `starts` (samples
/// in the record's time).
pub(super) fn window_starts(series: &[Vec<f64>], starts: &[f64], k: usize) -> Vec<f64> {
    series.iter().zip(starts).map(|(d, s)| s + (d.len() * k / WINDOWS) as f64).collect()
}

/// The window (0, 1 or 2) of each observation: the third of its dwell's blocks of its group it lies in, in
/// time order. `None` when a dwell has fewer blocks than windows.
fn windows_of(problem: &Problem) -> Option<Vec<usize>> {
    let blocks = problem.obs_block.as_ref()?;
    let mut runs: std::collections::BTreeMap<(usize, usize), Vec<usize>> = Default::default();
    for (i, b) in blocks.iter().enumerate() {
        runs.entry((b.dwell, problem.obs.group[i])).or_default().push(i);
    }
    let mut window = vec![0; blocks.len()];
    for rows in runs.values_mut() {
        if rows.len() < WINDOWS {
            return None;
        }
        rows.sort_by(|&a, &b| blocks[a].t_mid_s.total_cmp(&blocks[b].t_mid_s));
        for (r, &i) in rows.iter().enumerate() {
            window[i] = r * WINDOWS / rows.len();
        }
    }
    Some(window)
}

/// The final model fitted on one window's observations: its estimates and their standard errors (the larger
/// of the fit's and the sandwich's with the wander, as the effects report them). `None` when its columns are
/// dependent there.
fn window_fit(
    problem: &Problem,
    columns: &[&[f64]],
    rows: &[usize],
    white_per_sqrt_hz: &[Option<f64>],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let blocks = problem.obs_block.as_ref()?;
    let on_rows = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let obs = Observations {
        y: on_rows(&problem.obs.y),
        group: rows.iter().map(|&i| problem.obs.group[i]).collect(),
        groups: problem.obs.groups,
        sigma: problem.obs.sigma.as_ref().map(|s| on_rows(s)),
    };
    let own: Vec<Vec<f64>> = columns.iter().map(|c| on_rows(c)).collect();
    let refs: Vec<&[f64]> = own.iter().map(|c| c.as_slice()).collect();
    let f = fit(&obs, &refs)?;
    let own_blocks: Vec<_> = rows.iter().map(|&i| blocks[i]).collect();
    let model = BlockModel { obs: &obs, blocks: &own_blocks, columns: &refs, fit: &f };
    let sandwich = sandwich_std_errors(&model, white_per_sqrt_hz);
    let std_errors = (0..refs.len()).map(|j| f.std_error(j).max(sandwich[j])).collect();
    Some((f.beta, std_errors))
}

/// The final model across the windows of every dwell; `None` for angles, when a dwell is shorter than
/// [`WINDOWS`] blocks, or when a window cannot fit the model.
pub(super) fn window_check(problem: &Problem, selection: &Selection, models: &[NoiseModel]) -> Option<WindowCheck> {
    let window = windows_of(problem)?;
    let columns = final_columns(problem, selection);
    let columns: Vec<&[f64]> = columns.iter().map(|c| c.as_ref()).collect();
    let white_per_sqrt_hz = white_densities(problem, models);
    let fits: Vec<(Vec<f64>, Vec<f64>)> = (0..WINDOWS)
        .map(|k| {
            let rows: Vec<usize> = (0..window.len()).filter(|&i| window[i] == k).collect();
            window_fit(problem, &columns, &rows, &white_per_sqrt_hz)
        })
        .collect::<Option<_>>()?;
    let names = problem
        .base_names
        .iter()
        .cloned()
        .chain(selection.chosen.iter().map(|c| problem.candidates[c.candidate].name()));
    let mut parameters: Vec<WindowParameter> = names
        .enumerate()
        .map(|(j, name)| {
            let estimates: Vec<f64> = fits.iter().map(|(b, _)| b[j]).collect();
            let std_errors: Vec<f64> = fits.iter().map(|(_, s)| s[j]).collect();
            let chi_square = scatter(&estimates, &std_errors);
            WindowParameter { name, estimates, std_errors, chi_square }
        })
        .collect();
    let chi_square: f64 = parameters.iter().map(|p| p.chi_square).sum();
    let dof = (parameters.len() * (WINDOWS - 1)) as f64;
    parameters.sort_by(|a, b| b.chi_square.total_cmp(&a.chi_square));
    parameters.truncate(MAX_NAMED);
    Some(WindowCheck {
        windows: WINDOWS,
        chi_square,
        dof,
        p_value: chi_square_upper(chi_square, dof),
        widened_by: (chi_square / dof).max(1.0).sqrt(),
        worst: parameters,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_within_their_errors_are_not_widened_and_scattered_ones_are_by_the_birge_ratio() {
        // About the weighted mean 1: chi2 = 0.25 + 0 + 0.25 = 0.5 over 2 dof: no widening.
        assert_eq!(widening(&[(0.5, 1.0), (1.0, 1.0), (1.5, 1.0)]), 1.0);
        // Ten times the spread: chi2 = 50 over 2 dof, widened by 5.
        let w = widening(&[(-4.0, 1.0), (1.0, 1.0), (6.0, 1.0)]);
        assert!((w - 5.0).abs() < 1e-12, "{w}");
        // One window alone says nothing.
        assert_eq!(widening(&[(3.0, 0.1)]), 1.0);
        // Stationary within chi2(2)'s upper 1 % (9.21), not beyond it.
        assert!(!not_stationary(&[(0.5, 1.0), (1.0, 1.0), (1.5, 1.0)]));
        assert!(!not_stationary(&[(-1.0, 1.0), (1.0, 1.0), (3.0, 1.0)]), "chi2 8");
        assert!(not_stationary(&[(-1.5, 1.0), (1.0, 1.0), (3.5, 1.0)]), "chi2 12.5");
    }

    #[test]
    fn the_windows_of_samples_are_the_thirds_of_every_dwell() {
        let series = vec![(0..9).map(f64::from).collect::<Vec<_>>(), (0..4).map(f64::from).collect()];
        assert_eq!(window_of_samples(&series, 0), vec![vec![0.0, 1.0, 2.0], vec![0.0]]);
        assert_eq!(window_of_samples(&series, 1), vec![vec![3.0, 4.0, 5.0], vec![1.0]]);
        assert_eq!(window_of_samples(&series, 2), vec![vec![6.0, 7.0, 8.0], vec![2.0, 3.0]]);
    }
}
