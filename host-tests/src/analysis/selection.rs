//! The linear problem (observations, the base model's columns, the candidates) and its forward selection
//! by likelihood ratio and BIC: which candidates the data can see at all (the others are `unobservable`),
//! which ones are added, and which others the data cannot tell from them (`aliases`).

use std::borrow::Cow;
use std::collections::HashMap;

use crate::stats::linfit::{chi_square_quantile_upper, chi_square_upper, fit, solve_spd, LinearFit, Observations};

use super::candidates::Candidate;
use super::column::Column;
use super::{Tested, ALIAS_CORRELATION, ALPHA, MAX_COLUMN_BYTES, MAX_EFFECTS};

/// A linear problem: observations, the base columns, the candidates.
pub(super) struct Problem {
    /// The observations and their groups (channels, angle groups).
    pub obs: Observations,
    /// The base model's columns.
    pub base: Vec<Vec<f64>>,
    /// Their names ("gyro_bias_x", ...).
    pub base_names: Vec<String>,
    /// Names of the observation groups.
    pub group_names: Vec<String>,
    /// Units of the observation groups.
    pub group_units: Vec<&'static str>,
    /// Position label of each observation.
    pub obs_pos: Vec<u32>,
    /// Pose of each observation (dwells of one reference attitude share a pose), for the time terms'
    /// confounding test; `None` when the observations have no time (angles).
    pub obs_pose: Option<Vec<usize>>,
    /// Where and when each observation's block lies; `None` for angles.
    pub obs_block: Option<Vec<BlockOf>>,
    /// The candidates, in test order.
    pub candidates: Vec<Candidate>,
    /// What this data cannot see (the selection adds the candidates the base model explains).
    pub unobservable: Vec<String>,
    /// What the observations are ("block means", "angles").
    pub residual_of: &'static str,
}

/// Where and when an observation's block lies (recordings).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct BlockOf {
    /// Index of its dwell.
    pub dwell: usize,
    /// Its length, s.
    pub duration_s: f64,
    /// The middle of its first and last sample times, s.
    pub t_mid_s: f64,
}

/// The final model's columns: the base model's, then the chosen candidates' (dense), in the order of
/// `selection.final_fit.beta`.
pub(super) fn final_columns<'p>(problem: &'p Problem, selection: &Selection) -> Vec<Cow<'p, [f64]>> {
    let base = problem.base.iter().map(|c| Cow::Borrowed(c.as_slice()));
    base.chain(selection.chosen.iter().map(|c| problem.candidates[c.candidate].variants[c.variant].1.dense())).collect()
}

/// A candidate the selection added.
pub(super) struct Chosen {
    /// Index in the problem's candidates.
    pub candidate: usize,
    /// Its variant (time constant) chosen.
    pub variant: usize,
    /// Likelihood-ratio statistic when it was added.
    pub lr: f64,
    /// BIC change.
    pub delta_bic: f64,
    /// p-value of `lr`.
    pub p_value: f64,
    /// RMS residual of its groups before it was added.
    pub rms_before: f64,
    /// The same after.
    pub rms_after: f64,
}

/// The outcome of the forward selection.
pub(super) struct Selection {
    /// The base model alone.
    pub base_fit: LinearFit,
    /// The base model and the chosen candidates.
    pub final_fit: LinearFit,
    /// The candidates added, in order.
    pub chosen: Vec<Chosen>,
    /// Every observable candidate against the base model alone.
    pub tested: Vec<Tested>,
    /// Per chosen candidate: the names it cannot be told from.
    pub aliases: Vec<Vec<String>>,
    /// Per chosen candidate: the names that explained the data nearly as well when it was chosen
    /// ([`RIVAL_BIC`]).
    pub rivals: Vec<Vec<String>>,
    /// Observable candidates.
    pub observable: usize,
    /// Candidates the data want (they pass the criterion) at a value no plausible instrument has.
    pub misfits: Vec<Misfit>,
    /// Time terms the data want only through the differences between poses: confounded with pose order.
    pub confounded: Vec<Confounded>,
    /// Per group: the variance inflation of correlated block residuals ([`block_inflation`]).
    pub inflation: Vec<f64>,
    /// Per column of the final model: its standard error with each channel's random walk of the bias
    /// (`wander::wander_std_errors`); empty until it is computed, and for angles.
    pub wander_std_errors: Vec<f64>,
    /// Per chosen candidate: its standard error with its aliases beside it ([`apart_from_aliases`]).
    pub apart_from_aliases: Vec<ApartFromAliases>,
    /// The best candidate that still passed the criterion when the selection stopped at [`MAX_EFFECTS`], with
    /// its likelihood ratio.
    pub cut_short: Option<(usize, f64)>,
    /// Candidates a first selection admitted whose own standard error could not tell them from zero, left
    /// out of this one (`wander::unsupported`).
    pub unsupported: Vec<Unsupported>,
}

/// A candidate the criterion admitted whose estimate its own standard error (with the bias's wander) cannot
/// tell from zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Unsupported {
    /// Index in the problem's candidates.
    pub candidate: usize,
    /// Its estimate in the first selection's final model, SI.
    pub estimate: f64,
    /// Its standard error there, SI.
    pub std_error: f64,
}

/// A candidate that passes the criterion at an implausible value: the model misses something there.
pub(super) struct Misfit {
    /// Index in the problem's candidates.
    pub candidate: usize,
    /// The value the fit needs, SI.
    pub estimate: f64,
    /// Its standard error, SI.
    pub std_error: f64,
    /// The plausible limit it exceeds, SI.
    pub limit: f64,
    /// Where the fit puts it most: the observation of the largest contribution (its position label and
    /// group).
    pub pos: u32,
    /// See `pos`.
    pub group: usize,
}

/// A time term the criterion admits that a pose-by-pose offset explains as well.
pub(super) struct Confounded {
    /// Index in the problem's candidates.
    pub candidate: usize,
    /// Its likelihood ratio against the current model.
    pub lr: f64,
    /// Its likelihood ratio once every pose has its own offsets (what the dwells show within themselves
    /// and across repeated poses).
    pub lr_within: f64,
    /// Its estimate across the session, SI.
    pub estimate: f64,
    /// Its estimate once every pose has its own offsets, and that estimate's standard error, SI.
    pub estimate_within: f64,
    /// See `estimate_within`.
    pub std_error_within: f64,
    /// The within-pose estimate contradicts the session's (beyond [`CONTRADICTED`] of its standard errors):
    /// the term is not an effect, the differences between the poses are.
    pub contradicted: bool,
}

/// Standard errors of the within-pose estimate beyond which it contradicts a time term's estimate across
/// the session ([`Confounded::contradicted`]).
pub(super) const CONTRADICTED: f64 = 3.0;

/// Forward selection over the problem's candidates; the Bonferroni `m` counts the observable candidates and
/// `extra_tests` more (the sample tests). Adds the unobservable candidates to `problem.unobservable`.
pub(super) fn select(problem: &mut Problem, extra_tests: usize) -> Result<Selection, String> {
    select_at_most(problem, extra_tests, MAX_EFFECTS, &[])
}

/// [`select`] with the candidates `excluded` never added: those a first selection admitted that their own
/// standard error cannot tell from zero (`wander::unsupported`).
pub(super) fn select_without(
    problem: &mut Problem,
    extra_tests: usize,
    excluded: &[usize],
) -> Result<Selection, String> {
    select_at_most(problem, extra_tests, MAX_EFFECTS, excluded)
}

/// [`select`], adding at most `max_effects` candidates and none of `excluded`.
fn select_at_most(
    problem: &mut Problem,
    extra_tests: usize,
    max_effects: usize,
    excluded: &[usize],
) -> Result<Selection, String> {
    let base_cols: Vec<&[f64]> = problem.base.iter().map(|c| c.as_slice()).collect();
    let base_fit =
        fit(&problem.obs, &base_cols).ok_or("the base model's biases cannot be fitted (dependent columns)")?;
    let base = Projection::new(&problem.obs, base_cols, &base_fit)
        .ok_or("the base model's biases cannot be fitted (dependent columns)")?;
    let mut unobservable = Vec::new();
    let screen = Screen::new(&problem.candidates, &base, &mut unobservable);
    // A second selection (`select_without`) finds the same unobservable candidates: named once.
    for name in unobservable {
        if !problem.unobservable.contains(&name) {
            problem.unobservable.push(name);
        }
    }
    let m = (screen.observable.len() + extra_tests).max(1) as f64;
    let forward = Forward::run(problem, &screen.observable, base_fit.clone(), (m, max_effects), excluded);
    let chosen: Vec<usize> = forward.chosen.iter().map(|c| c.candidate).collect();
    let base_count = problem.base.len();
    let aliases: Vec<Vec<String>> = forward
        .chosen
        .iter()
        .zip(&forward.correlated)
        .enumerate()
        .map(|(j, (c, correlated))| {
            let mut names = screen.aliases(problem, Given::Base(&base), c, &chosen);
            names.extend(correlated.iter().filter(|n| !names.contains(n)).cloned().collect::<Vec<_>>());
            // Given the rest of the final model: the columns of the model but this effect's.
            let rest: Vec<&[f64]> = (0..forward.columns.len())
                .filter(|&k| k != base_count + j)
                .map(|k| forward.columns[k].as_slice())
                .collect();
            if let Some(given) = Projection::new(&problem.obs, rest, &forward.current) {
                let more = screen.aliases(problem, Given::Rest(&given), c, &chosen);
                names.extend(more.into_iter().filter(|n| !names.contains(n)).collect::<Vec<_>>());
            }
            names
        })
        .collect();
    let full_columns: Vec<&[f64]> = forward.columns.iter().map(|c| c.as_slice()).collect();
    let full = Projection::new(&problem.obs, full_columns, &forward.current);
    // The candidates by name, once (the aliases are names), and only when there are aliases; of two of one
    // name (dwells of one position label), the first.
    let mut by_name: HashMap<String, usize> = HashMap::new();
    if aliases.iter().any(|a| !a.is_empty()) {
        for (ci, c) in problem.candidates.iter().enumerate() {
            by_name.entry(c.name()).or_insert(ci);
        }
    }
    let apart_from_aliases: Vec<ApartFromAliases> = (0..forward.chosen.len())
        .map(|j| match &full {
            Some(model) => {
                let alias_candidates =
                    aliases[j].iter().filter_map(|n| by_name.get(n)).map(|&ci| &problem.candidates[ci]);
                apart_from_aliases(model, base_count + j, alias_candidates)
            }
            None => ApartFromAliases::NotDetermined,
        })
        .collect();
    Ok(Selection {
        base_fit,
        final_fit: forward.current,
        chosen: forward.chosen,
        tested: forward.tested,
        aliases,
        rivals: forward.rivals,
        observable: screen.observable.len(),
        misfits: forward.misfits,
        confounded: forward.confounded,
        inflation: forward.inflation,
        wander_std_errors: Vec::new(),
        apart_from_aliases,
        cut_short: forward.cut_short,
        unsupported: Vec::new(),
    })
}

/// What a chosen effect's estimate is worth once any one of its aliases might be in the model instead
/// (docs/analysis.md#confounding).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum ApartFromAliases {
    /// None of its aliases is a candidate (or it has none): its standard error stands as it is.
    NoAliases,
    /// Its standard error grows by this factor (at least 1) when its worst alias is fitted beside it.
    Inflated(f64),
    /// With one of its aliases beside it the estimate is not determined: the data cannot tell which of them
    /// it is, only their combination.
    NotDetermined,
}

/// Standard errors beyond this many times their own with an alias beside them are not determined: the
/// alias's remainder is below 1e-6 of its norm, as [`EXPLAINED`] has it.
const NOT_DETERMINED: f64 = 1e6;

/// Column `j` of the final model (`model`) against each of its aliases that is a candidate (`aliases`), each
/// of their variants fitted beside the model ([`inflation`]). The worst alias's factor.
fn apart_from_aliases<'c>(
    model: &Projection,
    j: usize,
    aliases: impl Iterator<Item = &'c Candidate>,
) -> ApartFromAliases {
    let mut worst: Option<f64> = None;
    for candidate in aliases {
        for (_, column) in &candidate.variants {
            let factor = inflation(model, j, column);
            if factor.is_nan() || factor >= NOT_DETERMINED {
                return ApartFromAliases::NotDetermined;
            }
            worst = Some(worst.map_or(factor, |w: f64| w.max(factor)));
        }
    }
    worst.map_or(ApartFromAliases::NoAliases, ApartFromAliases::Inflated)
}

/// The factor by which the standard error of column `j` of `model` grows when `column` is fitted beside it
/// with the weights held: adding column `c` adds `a a' / r` to the covariance of the estimates
/// (`a = (X'WX)^-1 X'W c`, `r` the weighted square norm of `c`'s remainder), so the standard error grows by
/// `sqrt(1 + a_j^2 / (r C_jj))`. A column the model's columns make ([`EXPLAINED`]) gives infinity when its
/// combination of them holds column `j` (`a_j^2 / C_jj` beyond [`EXPLAINED`] of its norm), else 1.
fn inflation(model: &Projection, j: usize, column: &Column) -> f64 {
    let (g, rest) = model.remainder(column);
    let full = column.weighted_dot_column(&model.weights, column);
    let a_j = dot(&model.inverse[j], &g);
    let along_j = a_j * a_j / model.inverse[j][j].max(f64::MIN_POSITIVE);
    if rest <= 0.0 {
        return if along_j <= EXPLAINED * full { 1.0 } else { f64::INFINITY };
    }
    (1.0 + along_j / rest).sqrt()
}

/// Observation weights: the given standard deviations, else the fit's variance of the group.
fn weights(obs: &Observations, fit: &LinearFit) -> Vec<f64> {
    (0..obs.y.len())
        .map(|i| match &obs.sigma {
            Some(s) => 1.0 / (s[i] * s[i]),
            None => 1.0 / fit.variance[obs.group[i]],
        })
        .collect()
}

/// A remainder whose weighted square norm is below this fraction of its column's is the model's columns
/// (rounding), not a direction the data can see: (1e-6)^2, the column's remainder below 1e-6 of its norm.
const EXPLAINED: f64 = 1e-12;

/// A model's columns and weights (its fit's variances): what a candidate column adds to the model is its
/// remainder after them, by weighted least squares, found from the column's products with the model's columns
/// alone, so that a column costs its nonzero entries (a position error's touches one dwell's blocks), not the
/// whole recording.
struct Projection<'a> {
    columns: Vec<&'a [f64]>,
    weights: Vec<f64>,
    /// `(X' W X)^-1`.
    inverse: Vec<Vec<f64>>,
    /// The model's residual, made orthogonal to its columns under the weights.
    residual: Vec<f64>,
    /// Variance group of each observation.
    group: &'a [usize],
    /// The observations' standard deviations are known (no variance is fitted).
    known_sigma: bool,
    /// Per group: its observations, the residual's square sum, `X' r` and `X' X` over its observations.
    count: Vec<f64>,
    rss: Vec<f64>,
    xr: Vec<Vec<f64>>,
    xx: Vec<Vec<Vec<f64>>>,
}

/// A candidate column against a model: its estimate, standard error and likelihood ratio.
#[derive(Clone, Copy)]
struct Score {
    estimate: f64,
    std_error: f64,
    lr: f64,
}

/// `sum a_i b_i`.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

/// `M v`.
fn mat_vec(m: &[Vec<f64>], v: &[f64]) -> Vec<f64> {
    m.iter().map(|row| dot(row, v)).collect()
}

impl<'a> Projection<'a> {
    /// The projection onto `columns` with the weights of `fit`; `None` when the columns are dependent.
    fn new(obs: &'a Observations, columns: Vec<&'a [f64]>, fit: &LinearFit) -> Option<Projection<'a>> {
        let (k, groups) = (columns.len(), obs.groups);
        let weights = weights(obs, fit);
        let (mut a, mut b) = (vec![vec![0.0; k]; k], vec![0.0; k]);
        for (i, (&w, &r)) in weights.iter().zip(&fit.residual).enumerate() {
            for p in 0..k {
                let wx = w * columns[p][i];
                b[p] += wx * r;
                for q in p..k {
                    a[p][q] += wx * columns[q][i];
                }
            }
        }
        for p in 0..k {
            for q in 0..p {
                a[p][q] = a[q][p];
            }
        }
        let (h, inverse) = if k == 0 { (Vec::new(), Vec::new()) } else { solve_spd(&a, &b)? };
        let residual: Vec<f64> = fit
            .residual
            .iter()
            .enumerate()
            .map(|(i, r)| r - (0..k).map(|p| columns[p][i] * h[p]).sum::<f64>())
            .collect();
        let (mut count, mut rss) = (vec![0.0; groups], vec![0.0; groups]);
        let (mut xr, mut xx) = (vec![vec![0.0; k]; groups], vec![vec![vec![0.0; k]; k]; groups]);
        for (i, &r) in residual.iter().enumerate() {
            let g = obs.group[i];
            count[g] += 1.0;
            rss[g] += r * r;
            for p in 0..k {
                xr[g][p] += columns[p][i] * r;
                for q in 0..k {
                    xx[g][p][q] += columns[p][i] * columns[q][i];
                }
            }
        }
        let known_sigma = obs.sigma.is_some();
        Some(Projection { columns, weights, inverse, residual, group: &obs.group, known_sigma, count, rss, xr, xx })
    }

    /// `g = X' W c`, and the weighted square norm of the remainder `c - X (X' W X)^-1 g`, `c' W c - g' (X' W
    /// X)^-1 g`, or 0 when that is below [`EXPLAINED`] of `c' W c`.
    fn remainder(&self, c: &Column) -> (Vec<f64>, f64) {
        let g = c.weighted_products(&self.weights, &self.columns);
        let full = c.weighted_dot_column(&self.weights, c);
        let rest = full - self.quadratic(&g, &g);
        (g, if rest > EXPLAINED * full { rest } else { 0.0 })
    }

    /// `a' (X' W X)^-1 b`.
    fn quadratic(&self, a: &[f64], b: &[f64]) -> f64 {
        dot(a, &mat_vec(&self.inverse, b))
    }

    /// Adding `c` to the model. Known standard deviations: the exact weighted least-squares estimate, its
    /// standard error and likelihood ratio `(c~' W r)^2 / (c~' W c~)` (`c~` the column's remainder). Fitted
    /// variances: the estimate with the weights held, each group's variance fitted again to the residual it
    /// leaves, the estimate and its standard error again with those variances, and the likelihood ratio
    /// `sum n_g ln(RSS_g / RSS_g')` of the group variances fitted again (the fit's own likelihood, the
    /// columns not projected again: one step of its reweighting).
    fn score(&self, c: &Column) -> Score {
        let (g, rest) = self.remainder(c);
        if rest <= 0.0 {
            return Score { estimate: 0.0, std_error: f64::INFINITY, lr: 0.0 };
        }
        let s = c.weighted_dot(&self.weights, &self.residual);
        if self.known_sigma {
            return Score { estimate: s / rest, std_error: 1.0 / rest.sqrt(), lr: s * s / rest };
        }
        // Per group: the remainder's products with the residual and with itself.
        let (groups, k) = (self.count.len(), self.columns.len());
        let (mut cr, mut cc, mut xc) = (vec![0.0; groups], vec![0.0; groups], vec![vec![0.0; k]; groups]);
        c.for_each_nonzero(|i, v| {
            let gi = self.group[i];
            cr[gi] += v * self.residual[i];
            cc[gi] += v * v;
            for (x, col) in xc[gi].iter_mut().zip(&self.columns) {
                *x += v * col[i];
            }
        });
        let a = mat_vec(&self.inverse, &g);
        let rem_r: Vec<f64> = (0..groups).map(|j| cr[j] - dot(&a, &self.xr[j])).collect();
        let rem_sq: Vec<f64> = (0..groups)
            .map(|j| (cc[j] - 2.0 * dot(&a, &xc[j]) + dot(&a, &mat_vec(&self.xx[j], &a))).max(0.0))
            .collect();
        let rss_after = |beta: f64, j: usize| {
            (self.rss[j] - 2.0 * beta * rem_r[j] + beta * beta * rem_sq[j]).max(self.rss[j] * 1e-24).max(1e-300)
        };
        let held = s / rest;
        let variance: Vec<f64> = (0..groups).map(|j| rss_after(held, j) / self.count[j].max(1.0)).collect();
        let info: f64 = (0..groups).filter(|&j| self.count[j] > 0.0).map(|j| rem_sq[j] / variance[j]).sum();
        if info <= 0.0 {
            return Score { estimate: 0.0, std_error: f64::INFINITY, lr: 0.0 };
        }
        let estimate = (0..groups).filter(|&j| self.count[j] > 0.0).map(|j| rem_r[j] / variance[j]).sum::<f64>() / info;
        let lr = (0..groups)
            .filter(|&j| self.count[j] > 0.0 && self.rss[j] > 0.0)
            .map(|j| self.count[j] * (self.rss[j] / rss_after(estimate, j)).ln())
            .sum::<f64>();
        Score { estimate, std_error: 1.0 / info.sqrt(), lr: lr.max(0.0) }
    }
}

/// The columns the aliases are taken against ([`Screen::aliases`]).
enum Given<'p, 'a> {
    /// The base model (its remainders are the screen's).
    Base(&'p Projection<'a>),
    /// The final model but the effect itself.
    Rest(&'p Projection<'a>),
}

/// What the base model leaves of every candidate's columns.
struct Screen {
    /// Candidates with a variant the base model does not explain.
    observable: Vec<usize>,
    /// Per candidate, per variant: the column's products with the base columns and its remainder's weighted
    /// square norm ([`Projection::remainder`]).
    remainders: Vec<Vec<(Vec<f64>, f64)>>,
}

impl Screen {
    /// Observability: a candidate whose every variant the base model explains is unobservable (its name goes
    /// to `unobservable`).
    fn new(candidates: &[Candidate], base: &Projection, unobservable: &mut Vec<String>) -> Screen {
        let mut screen = Screen { observable: Vec::new(), remainders: Vec::new() };
        for (ci, c) in candidates.iter().enumerate() {
            let rems: Vec<(Vec<f64>, f64)> = c.variants.iter().map(|(_, col)| base.remainder(col)).collect();
            let seen = rems.iter().any(|(_, rest)| *rest > 0.0);
            if seen {
                screen.observable.push(ci);
            } else {
                unobservable.push(c.name());
            }
            screen.remainders.push(rems);
        }
        screen
    }

    /// Aliases of a chosen effect: other observable candidates with (nearly) the same column once the
    /// columns of `given` are removed (the correlation of the two remainders, from the columns' own product
    /// and their products with `given`). With `given` the base model: what the poses alone cannot tell apart;
    /// with the final model but this effect: what the rest of the model makes indistinguishable (a face's
    /// tilt, its pair's shared tilt and a misalignment in six faces of unknown heading, any one of the three
    /// given the other two).
    fn aliases(&self, problem: &Problem, given: Given, c: &Chosen, chosen: &[usize]) -> Vec<String> {
        // The base model's remainders were computed by `Screen::new`; the rest of the model's are computed here.
        let (projection, cached) = match given {
            Given::Base(p) => (p, Some(&self.remainders)),
            Given::Rest(p) => (p, None),
        };
        let remainder = |ci: usize, vi: usize| match cached {
            Some(r) => std::borrow::Cow::Borrowed(&r[ci][vi]),
            None => std::borrow::Cow::Owned(projection.remainder(&problem.candidates[ci].variants[vi].1)),
        };
        let own = &problem.candidates[c.candidate].variants[c.variant].1;
        let own_remainder = remainder(c.candidate, c.variant);
        let (own_g, own_rest) = (&own_remainder.0, own_remainder.1);
        let mut names = Vec::new();
        for &oi in self.observable.iter().filter(|&&oi| oi != c.candidate && !chosen.contains(&oi)) {
            let similar = problem.candidates[oi].variants.iter().enumerate().any(|(vi, (_, col))| {
                let r = remainder(oi, vi);
                let (g, rest) = (&r.0, r.1);
                let product = own.weighted_dot_column(&projection.weights, col) - projection.quadratic(own_g, g);
                own_rest > 0.0 && rest > 0.0 && (product / (own_rest * rest).sqrt()).abs() > ALIAS_CORRELATION
            });
            if similar {
                names.push(problem.candidates[oi].name());
            }
        }
        names
    }
}

/// The best addition at one step: (candidate, variant, fit with it, likelihood ratio).
type Addition = (usize, usize, LinearFit, f64);

/// A candidate's best variant and its score's likelihood ratio (deflated by [`block_inflation`]).
struct Scored {
    candidate: usize,
    variant: usize,
    lr: f64,
}

/// Candidates fitted exactly at a time, best score first ([`Forward::add_best`]).
const EXACT_FITS: usize = 16;

/// The state of the forward selection.
struct Forward<'a> {
    problem: &'a Problem,
    /// ln of the number of observations (the BIC's penalty per parameter).
    ln_n: f64,
    /// Columns of the current model: the base and the chosen candidates.
    columns: Vec<Vec<f64>>,
    /// The current model's fit.
    current: LinearFit,
    chosen: Vec<Chosen>,
    tested: Vec<Tested>,
    /// Per chosen candidate: the candidates whose estimate correlates with its beyond
    /// [`ALIAS_CORRELATION`] (set aside, named as its aliases).
    correlated: Vec<Vec<String>>,
    /// Per chosen candidate: the other candidates of its turn within [`RIVAL_BIC`] of its gain.
    rivals: Vec<Vec<String>>,
    misfits: Vec<Misfit>,
    confounded: Vec<Confounded>,
    /// Candidates set aside (misfit, alias, confounded): not tried again.
    set_aside: Vec<usize>,
    /// Per group: the variance inflation of a sum of neighbouring block residuals ([`block_inflation`]).
    inflation: Vec<f64>,
    /// The best candidate still passing the criterion when [`MAX_EFFECTS`] stopped the selection.
    cut_short: Option<(usize, f64)>,
}

/// A candidate whose BIC gain is within this of the chosen one's when it is chosen is its rival: the data
/// favour the chosen one by a Bayes factor below `exp(RIVAL_BIC / 2)`, 20, not strongly (Kass and Raftery's
/// scale). The analysis names it beside the effect.
pub(super) const RIVAL_BIC: f64 = 6.0;

/// Most the likelihood ratios are deflated for correlated block residuals.
const MAX_INFLATION: f64 = 10.0;

/// `v` less its least-squares line over the index.
fn detrended(v: &[f64]) -> Vec<f64> {
    let n = v.len() as f64;
    let mid = (n - 1.0) / 2.0;
    let mean = v.iter().sum::<f64>() / n;
    let sxx: f64 = (0..v.len()).map(|i| (i as f64 - mid).powi(2)).sum();
    let sxy: f64 = v.iter().enumerate().map(|(i, y)| (i as f64 - mid) * (y - mean)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    v.iter().enumerate().map(|(i, y)| y - mean - slope * (i as f64 - mid)).collect()
}

/// Fewest blocks a dwell needs to show the correlation of its block residuals.
const MIN_RUN_BLOCKS: usize = 8;

/// Per observation group: `(1 + rho) / (1 - rho)` (at least 1, at most [`MAX_INFLATION`]), with `rho` the
/// lag-1 correlation between neighbouring blocks of a dwell of the residuals about each dwell's own line
/// (what the dwells show within themselves, whatever the model misses between poses, and free of a smooth
/// drift or warm-up within a dwell that a candidate is there to explain). Block means of noise
/// slower than a block (a vehicle's sway, bias instability) are correlated: a sum of `B` of them varies
/// `(1 + rho) / (1 - rho)` times more than white block means would (first-order autoregression), so a
/// likelihood ratio computed as if they were independent is that much too large. Only dwells of at least
/// [`MIN_RUN_BLOCKS`] blocks count; `rho` is corrected for the line removed (`E rho_hat = rho - (2 + 4 rho)
/// / B`) and counted only beyond four standard errors. Angles, or no dwell long enough: 1.
fn block_inflation(problem: &Problem, residual: &[f64]) -> Vec<f64> {
    let groups = problem.obs.groups;
    if problem.obs_pose.is_none() {
        return vec![1.0; groups];
    }
    let g = &problem.obs.group;
    let (mut lag0, mut lag1, mut blocks, mut runs) =
        (vec![0.0; groups], vec![0.0; groups], vec![0.0; groups], vec![0.0; groups]);
    let mut start = 0;
    while start < residual.len() {
        let same = |i: usize| g[i] == g[start] && problem.obs_pos[i] == problem.obs_pos[start];
        let end = (start..residual.len()).find(|&i| !same(i)).unwrap_or(residual.len());
        if end - start >= MIN_RUN_BLOCKS {
            let run = detrended(&residual[start..end]);
            let k = g[start];
            lag0[k] += run.iter().map(|r| r * r).sum::<f64>();
            lag1[k] += run.windows(2).map(|w| w[0] * w[1]).sum::<f64>();
            blocks[k] += run.len() as f64;
            runs[k] += 1.0;
        }
        start = end;
    }
    (0..groups)
        .map(|k| {
            if lag0[k] <= 0.0 || runs[k] == 0.0 {
                return 1.0;
            }
            let b = blocks[k] / runs[k];
            let rho = ((lag1[k] / lag0[k] * b + 2.0) / (b - 4.0)).clamp(0.0, 0.9);
            // Only a correlation the data show beyond doubt, four standard errors (`1 / sqrt(blocks)` for the
            // raw estimate, times `B / (B - 4)` for the correction): white block means keep their likelihood
            // ratios as they are, in every channel of every session (two standard errors let one white
            // channel in twenty through, measured in the hidden-effect trials).
            let rho_se = b / (b - 4.0) / blocks[k].sqrt();
            let rho = if rho > 4.0 * rho_se { rho } else { 0.0 };
            ((1.0 + rho) / (1.0 - rho)).clamp(1.0, MAX_INFLATION)
        })
        .collect()
}

/// Why a candidate that passes the criterion is not added.
enum Vetoed {
    Implausible(Misfit),
    /// Its estimate correlates with that of the chosen candidate of this index.
    Alias(usize),
}

/// A column fitted once every pose has its own offsets ([`Forward::within_poses`]).
struct WithinPoses {
    lr: f64,
    estimate: f64,
    std_error: f64,
}

/// The alias of a time term whose estimates in the two halves of the session disagree
/// ([`Forward::halves_disagree`]): an uncertain effect.
pub(super) const HALVES: &str = "the session's halves (it differs between them: slow wander, not a term)";

/// Standard errors of their difference beyond which the two halves' estimates of a time term disagree.
const HALVES_DISAGREE: f64 = 3.0;

/// The alias of a time term that only the differences between poses support.
pub(super) const POSE_ORDER: &str = "pose order (the poses are not revisited)";

impl<'a> Forward<'a> {
    /// Adds candidates of `observable` while the best passes the criterion (at most `max_effects`); the
    /// first step also records every candidate against the base model alone; `m` is the Bonferroni count.
    fn run(
        problem: &'a Problem,
        observable: &[usize],
        base_fit: LinearFit,
        (m, max_effects): (f64, usize),
        excluded: &[usize],
    ) -> Forward<'a> {
        let ln_n = (problem.obs.y.len() as f64).ln();
        let mut f = Forward {
            problem,
            ln_n,
            columns: problem.base.clone(),
            current: base_fit,
            chosen: Vec::new(),
            tested: Vec::new(),
            correlated: Vec::new(),
            rivals: Vec::new(),
            misfits: Vec::new(),
            confounded: Vec::new(),
            set_aside: excluded.to_vec(),
            inflation: Vec::new(),
            cut_short: None,
        };
        f.inflation = block_inflation(problem, &f.current.residual);
        for step in 0..=max_effects {
            let ranked = f.ranked_additions(observable, step == 0);
            if step == max_effects {
                f.cut_short = f.still_passing(&ranked, m);
                break;
            }
            if !f.add_best(&ranked, m) {
                break;
            }
        }
        f
    }

    /// The first of `ranked` whose exact likelihood ratio passes the criterion (the vetoes not applied):
    /// what the selection leaves out when it stops at [`MAX_EFFECTS`]. Only the first [`EXACT_FITS`] are
    /// fitted.
    fn still_passing(&self, ranked: &[Scored], m: f64) -> Option<(usize, f64)> {
        ranked.iter().take(EXACT_FITS).find_map(|s| {
            let (ci, _, _, lr) = self.exact(s.candidate, s.variant)?;
            let k = self.problem.candidates[ci].parameters() as f64;
            (lr > chi_square_quantile_upper(ALPHA / m, k) && -lr + k * self.ln_n < 0.0).then_some((ci, lr))
        })
    }

    /// Fits exactly (the variances fitted again) the candidates of `ranked` in turns of [`EXACT_FITS`], best
    /// score first, and adds the first of a turn, by its exact gain, that passes the criterion and is not
    /// vetoed. Stops when a turn's weakest score is below half the criterion of one parameter: the score and
    /// the exact likelihood ratio differ only by the variances fitted again. False when none is added.
    fn add_best(&mut self, ranked: &[Scored], m: f64) -> bool {
        let half_criterion = 0.5 * chi_square_quantile_upper(ALPHA / m, 1.0);
        for turn in ranked.chunks(EXACT_FITS) {
            let mut exact: Vec<(f64, Addition)> = turn
                .iter()
                .filter_map(|s| self.exact(s.candidate, s.variant))
                .map(|a| (a.3 - self.problem.candidates[a.0].parameters() as f64 * self.ln_n, a))
                .collect();
            exact.sort_by(|a, b| b.0.total_cmp(&a.0));
            if self.add_first_acceptable(exact.into_iter().map(|(_, a)| a).collect(), m) {
                return true;
            }
            if turn.last().is_none_or(|s| s.lr < half_criterion) {
                break;
            }
        }
        false
    }

    /// Adds the first of `ranked` that passes the criterion and is not vetoed; the vetoed ones are set
    /// aside with their reason. False when none is added.
    fn add_first_acceptable(&mut self, ranked: Vec<Addition>, m: f64) -> bool {
        // Every addition that passes the criterion, with its BIC gain: the rivals of the one added.
        let passing: Vec<(usize, f64)> = ranked
            .iter()
            .filter_map(|(ci, _, _, lr)| {
                let k = self.problem.candidates[*ci].parameters() as f64;
                let gain = lr - k * self.ln_n;
                (*lr > chi_square_quantile_upper(ALPHA / m, k) && gain > 0.0).then_some((*ci, gain))
            })
            .collect();
        for addition in ranked {
            let ci = addition.0;
            let Some(&(_, gain)) = passing.iter().find(|(c, _)| *c == ci) else {
                continue;
            };
            match self.veto(&addition) {
                None => {
                    let confounded = self.pose_order(&addition, m);
                    if let Some(c) = confounded.as_ref().filter(|c| c.contradicted) {
                        // The dwells contradict the term: the differences between the poses are not it.
                        self.set_aside.push(c.candidate);
                        self.confounded.extend(confounded);
                        continue;
                    }
                    let halves_disagree = self.halves_disagree(&addition);
                    self.add(addition);
                    self.refine_time_constants();
                    let q = self.chosen.len() - 1;
                    self.rivals[q] = passing
                        .iter()
                        .filter(|(c, g)| *c != ci && *g > gain - RIVAL_BIC && !self.set_aside.contains(c))
                        .map(|(c, _)| self.problem.candidates[*c].name())
                        .collect();
                    if let Some(c) = confounded {
                        self.correlated[q].push(POSE_ORDER.to_string());
                        self.confounded.push(c);
                    }
                    if halves_disagree {
                        self.correlated[q].push(HALVES.to_string());
                    }
                    return true;
                }
                Some(reason) => {
                    self.set_aside.push(ci);
                    let name = self.problem.candidates[ci].name();
                    match reason {
                        Vetoed::Implausible(misfit) => self.misfits.push(misfit),
                        Vetoed::Alias(q) => self.correlated[q].push(name),
                    }
                }
            }
        }
        false
    }

    /// Why `addition`, which passes the criterion, must not be added: an implausible value, or an estimate
    /// correlated beyond [`ALIAS_CORRELATION`] with a chosen one's.
    fn veto(&self, (ci, vi, f, _): &Addition) -> Option<Vetoed> {
        let problem = self.problem;
        let candidate = &problem.candidates[*ci];
        let j = f.beta.len() - 1;
        let estimate = f.beta[j];
        if let Some(limit) = candidate.limit.filter(|l| estimate.abs() > *l) {
            let at = candidate.variants[*vi].1.argmax_abs();
            let misfit = Misfit {
                candidate: *ci,
                estimate,
                std_error: f.std_error(j),
                limit,
                pos: problem.obs_pos.get(at).copied().unwrap_or(0),
                group: problem.obs.group.get(at).copied().unwrap_or(0),
            };
            return Some(Vetoed::Implausible(misfit));
        }
        let correlation = |a: usize, b: usize| {
            let c = &f.covariance;
            c[a][b] / (c[a][a] * c[b][b]).sqrt().max(f64::MIN_POSITIVE)
        };
        let base = problem.base.len();
        if let Some(q) = (0..self.chosen.len()).find(|&q| correlation(j, base + q).abs() > ALIAS_CORRELATION) {
            return Some(Vetoed::Alias(q));
        }
        None
    }

    /// A time term that passes the criterion only through the differences between poses: once every pose
    /// has its own offsets its likelihood ratio fails the criterion. When the within-pose estimate agrees
    /// with the session's (within [`CONTRADICTED`] standard errors), the term is added, with [`POSE_ORDER`] as
    /// its alias: in a schedule that visits each pose once, a drift and a pose-dependent term are equally
    /// possible. When it contradicts it (a drift whose within-dwell slopes the data deny: tilts of the poses
    /// off their labels), it is not added.
    fn pose_order(&self, (ci, vi, f, lr): &Addition, m: f64) -> Option<Confounded> {
        let candidate = &self.problem.candidates[*ci];
        if !candidate.effect.is_time_term() {
            return None;
        }
        let k = candidate.parameters() as f64;
        let within = self.within_poses(&candidate.variants[*vi].1.dense())?;
        if within.lr > chi_square_quantile_upper(ALPHA / m, k) {
            return None;
        }
        let estimate = f.beta[f.beta.len() - 1];
        let contradicted = (within.estimate - estimate).abs() > CONTRADICTED * within.std_error;
        Some(Confounded {
            candidate: *ci,
            lr: *lr,
            lr_within: within.lr,
            estimate,
            estimate_within: within.estimate,
            std_error_within: within.std_error,
            contradicted,
        })
    }

    /// A time term's column split in two, on the first and the second half of each of its groups'
    /// observations (dwells and blocks are in time order within a group), fitted with the current model: the
    /// two estimates differ by more than [`HALVES_DISAGREE`] standard errors of their difference. A drift or
    /// warm-up that a wander of the bias makes (a random walk over one long dwell) changes between the halves;
    /// a term does not. False for other effects, or when the split columns are dependent.
    fn halves_disagree(&self, (ci, vi, _, _): &Addition) -> bool {
        let problem = self.problem;
        let candidate = &problem.candidates[*ci];
        if !candidate.effect.is_time_term() {
            return false;
        }
        let column = candidate.variants[*vi].1.dense();
        let groups = &problem.obs.group;
        let mut seen = vec![0usize; problem.obs.groups];
        let totals: Vec<usize> = (0..problem.obs.groups).map(|g| groups.iter().filter(|&&x| x == g).count()).collect();
        let (mut first, mut second) = (vec![0.0; column.len()], vec![0.0; column.len()]);
        for (i, &g) in groups.iter().enumerate() {
            if 2 * seen[g] < totals[g] {
                first[i] = column[i];
            } else {
                second[i] = column[i];
            }
            seen[g] += 1;
        }
        let mut cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
        cols.push(&first);
        cols.push(&second);
        let Some(f) = fit(&problem.obs, &cols) else { return false };
        let (a, b) = (f.beta.len() - 2, f.beta.len() - 1);
        let variance = f.covariance[a][a] + f.covariance[b][b] - 2.0 * f.covariance[a][b];
        (f.beta[a] - f.beta[b]).abs() > HALVES_DISAGREE * variance.max(0.0).sqrt() * self.inflation_of(candidate).sqrt()
    }

    /// The likelihood ratio, estimate and standard error of `column` once every pose has its own offset per
    /// group (which absorbs the biases and every term that depends on the pose alone), with the time terms
    /// chosen so far. `None` without poses, when the columns are dependent, or when the pose columns would
    /// take more than a quarter of [`MAX_COLUMN_BYTES`] (then no veto).
    fn within_poses(&self, column: &[f64]) -> Option<WithinPoses> {
        let problem = self.problem;
        let poses = problem.obs_pose.as_ref()?;
        let n_poses = poses.iter().max().map_or(0, |m| m + 1);
        let pose_column_bytes = (n_poses * problem.obs.groups * poses.len() * std::mem::size_of::<f64>()) as u64;
        if pose_column_bytes > MAX_COLUMN_BYTES / 4 {
            return None;
        }
        let mut cols: Vec<Vec<f64>> = Vec::new();
        for g in 0..problem.obs.groups {
            for p in 0..n_poses {
                let col: Vec<f64> =
                    (0..poses.len()).map(|i| f64::from(u8::from(poses[i] == p && problem.obs.group[i] == g))).collect();
                if col.iter().any(|&v| v != 0.0) {
                    cols.push(col);
                }
            }
        }
        for (q, c) in self.chosen.iter().enumerate() {
            if problem.candidates[c.candidate].effect.is_time_term() {
                cols.push(self.columns[problem.base.len() + q].clone());
            }
        }
        let without: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        let mut with = without.clone();
        with.push(column);
        let (f0, f1) = (fit(&problem.obs, &without)?, fit(&problem.obs, &with)?);
        let j = f1.beta.len() - 1;
        Some(WithinPoses {
            lr: 2.0 * (f1.log_likelihood - f0.log_likelihood),
            estimate: f1.beta[j],
            std_error: f1.std_error(j),
        })
    }

    /// Every candidate not yet chosen nor set aside, scored against the current model with its variances
    /// held, at its best variant, best BIC gain first: of two candidates that explain the data equally well,
    /// the one with fewer parameters (a temperature coefficient rather than a warm-up of free time
    /// constant). With `record`, each candidate's score goes to `tested`.
    fn ranked_additions(&mut self, observable: &[usize], record: bool) -> Vec<Scored> {
        let problem = self.problem;
        let cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
        let Some(model) = Projection::new(&problem.obs, cols, &self.current) else {
            return Vec::new();
        };
        let mut ranked: Vec<(f64, Scored)> = Vec::new();
        let open = |ci: &usize| !self.chosen.iter().any(|c| c.candidate == *ci) && !self.set_aside.contains(ci);
        for &ci in observable.iter().filter(|ci| open(ci)) {
            let c = &problem.candidates[ci];
            // Of the variants the model does not explain (a finite standard error), the one of the largest score.
            let scores = c.variants.iter().map(|(_, col)| model.score(col)).enumerate();
            let seen = scores.filter(|(_, s)| s.std_error.is_finite());
            let Some((vi, score)) = seen.max_by(|a, b| a.1.lr.total_cmp(&b.1.lr)) else { continue };
            let lr = score.lr / self.inflation_of(c);
            if record {
                self.tested.push(Tested {
                    name: c.name(),
                    estimate: score.estimate,
                    std_error: score.std_error,
                    likelihood_ratio: lr,
                    column: (ci, vi),
                });
            }
            let gain = lr - c.parameters() as f64 * self.ln_n;
            ranked.push((gain, Scored { candidate: ci, variant: vi, lr }));
        }
        ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
        ranked.into_iter().map(|(_, s)| s).collect()
    }

    /// The variance inflation of `c`'s groups ([`block_inflation`]).
    fn inflation_of(&self, c: &Candidate) -> f64 {
        c.groups.iter().map(|&g| self.inflation[g]).fold(1.0, f64::max)
    }

    /// Variant `vi` of candidate `ci` fitted with the current columns, its variances fitted again; `None` when
    /// the columns are dependent.
    fn exact(&self, ci: usize, vi: usize) -> Option<Addition> {
        let c = &self.problem.candidates[ci];
        let col = c.variants[vi].1.dense();
        let mut cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
        cols.push(&col);
        let f = fit(&self.problem.obs, &cols)?;
        let lr = 2.0 * (f.log_likelihood - self.current.log_likelihood) / self.inflation_of(c);
        Some((ci, vi, f, lr))
    }

    /// The time constant of every chosen term but the last, profiled again given the model as it now is: each
    /// moves along its grid, one step at a time, while the fit's likelihood grows and the estimate stays
    /// plausible. A warm-up chosen before the scale factors took its time constant from what they had not yet
    /// explained; a drift then made up the difference of shape (docs/analysis.md#time-constants).
    fn refine_time_constants(&mut self) {
        let base = self.problem.base.len();
        for q in 0..self.chosen.len().saturating_sub(1) {
            let candidate = &self.problem.candidates[self.chosen[q].candidate];
            if candidate.variants.len() < 2 || candidate.variants.iter().any(|(tau, _)| tau.is_none()) {
                continue;
            }
            for direction in [-1isize, 1] {
                while let Some(v) = self.chosen[q].variant.checked_add_signed(direction) {
                    let Some((_, col)) = candidate.variants.get(v) else { break };
                    let col = col.dense().into_owned();
                    let mut cols: Vec<&[f64]> = self.columns.iter().map(|c| c.as_slice()).collect();
                    cols[base + q] = &col;
                    let Some(f) = fit(&self.problem.obs, &cols) else { break };
                    let plausible = candidate.limit.is_none_or(|l| f.beta[base + q].abs() <= l);
                    if !(plausible && f.log_likelihood > self.current.log_likelihood + 1e-9) {
                        break;
                    }
                    self.columns[base + q] = col;
                    self.current = f;
                    self.chosen[q].variant = v;
                }
            }
        }
    }

    /// Adds a candidate that passed the criterion and the vetoes.
    fn add(&mut self, (ci, vi, f, lr): Addition) {
        let candidate = &self.problem.candidates[ci];
        let k = candidate.parameters() as f64;
        let p_value = chi_square_upper(lr, k);
        let delta_bic = -lr + k * self.ln_n;
        self.correlated.push(Vec::new());
        self.rivals.push(Vec::new());
        self.chosen.push(Chosen {
            candidate: ci,
            variant: vi,
            lr,
            delta_bic,
            p_value,
            rms_before: group_rms(&self.current, &candidate.groups),
            rms_after: group_rms(&f, &candidate.groups),
        });
        self.columns.push(candidate.variants[vi].1.dense().into_owned());
        self.current = f;
    }
}

/// RMS residual over the observation groups `groups`.
fn group_rms(fit: &LinearFit, groups: &[usize]) -> f64 {
    (groups.iter().map(|&g| fit.rms[g] * fit.rms[g]).sum::<f64>() / groups.len().max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::catalogue::{EffectKind, Sensor};

    /// Observations of known standard deviation 0.5 at `t = 0, 0.1, ...`: a line, with a small wiggle.
    fn line(n: usize) -> (Observations, Vec<Vec<f64>>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.1).collect();
        let y = t.iter().map(|t| 1.0 + 0.3 * t + 0.2 * (7.0 * t).sin()).collect();
        let obs = Observations { y, group: vec![0; n], groups: 1, sigma: Some(vec![0.5; n]) };
        (obs, vec![vec![1.0; n], t])
    }

    /// A problem of one accelerometer channel: observations `y` (variance fitted), its bias as the base
    /// model, every observation in position 1, and `candidates`.
    fn one_channel(y: Vec<f64>, candidates: Vec<Candidate>) -> Problem {
        let n = y.len();
        Problem {
            obs: Observations { y, group: vec![0; n], groups: 1, sigma: None },
            base: vec![vec![1.0; n]],
            base_names: vec!["accel_bias_x".into()],
            group_names: vec!["ax_mps2".into()],
            group_units: vec!["m/s^2"],
            obs_pos: vec![1; n],
            obs_pose: None,
            obs_block: None,
            candidates,
            unobservable: Vec::new(),
            residual_of: "block means",
        }
    }

    /// The factor of [`inflation`] is the ratio of the slope's standard errors fitted with and without the
    /// alias (to 1e-9), for an alias along the slope (`t^2`) and one along a single observation; an alias the
    /// model's columns make (exactly dependent) gives at least [`NOT_DETERMINED`] when it holds the slope, 1
    /// when it does not (the constant column).
    #[test]
    fn the_inflation_is_the_ratio_of_the_refitted_standard_errors() {
        let n = 40;
        let (obs, columns) = line(n);
        let refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
        let without = fit(&obs, &refs).unwrap();
        let model = Projection::new(&obs, refs.clone(), &without).unwrap();
        let square: Vec<f64> = columns[1].iter().map(|t| t * t).collect();
        let first: Vec<f64> = (0..n).map(|i| f64::from(u8::from(i == 0))).collect();
        for alias in [square, first] {
            let mut with_alias = refs.clone();
            with_alias.push(&alias);
            let with = fit(&obs, &with_alias).unwrap();
            let want = with.std_error(1) / without.std_error(1);
            let got = inflation(&model, 1, &Column::new(alias.clone()));
            assert!(want > 1.0 && (got - want).abs() < 1e-9 * want, "{got} vs {want}");
        }
        let dependent: Vec<f64> = columns[1].iter().map(|t| 2.0 - 3.0 * t).collect();
        assert!(inflation(&model, 1, &Column::new(dependent)) >= NOT_DETERMINED);
        assert_eq!(inflation(&model, 1, &Column::new(vec![2.0; n])), 1.0);
    }

    /// Three effects in the data, each at about 40 of its standard errors, and one candidate of nothing: a
    /// selection of at most two effects stops with the third still passing (`cut_short` names it); one of at
    /// most three finds all three and is not cut short.
    #[test]
    fn a_selection_stopped_by_its_most_effects_names_the_candidate_still_passing() {
        let n = 120;
        let wave = |k: f64| (0..n).map(move |i| (k * i as f64).sin()).collect::<Vec<f64>>();
        let columns = [wave(0.3), wave(0.7), wave(1.9), wave(2.6)];
        let noise = wave(7.77);
        let y: Vec<f64> =
            (0..n).map(|i| 2.0 * columns[0][i] - 1.5 * columns[1][i] + columns[2][i] + 0.1 * noise[i]).collect();
        let problem = |max_effects: usize| {
            let candidates = columns
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let axes = ["x", "y", "z"][k % 3].to_string();
                    let effect = if k < 3 { EffectKind::AccelScaleFactor } else { EffectKind::AccelNonlinearity };
                    Candidate::single(effect, Sensor::Accel, axes, Column::new(c.clone()), vec![0])
                })
                .collect();
            let mut p = one_channel(y.clone(), candidates);
            let s = select_at_most(&mut p, 0, max_effects, &[]).unwrap();
            let names: Vec<String> = s.chosen.iter().map(|c| p.candidates[c.candidate].name()).collect();
            (names, s.cut_short.map(|(ci, lr)| (p.candidates[ci].name(), lr)))
        };
        let (names, cut_short) = problem(2);
        assert_eq!(names, ["accel_scale_factor:x", "accel_scale_factor:y"]);
        let (name, lr) = cut_short.expect("cut short");
        assert!(name == "accel_scale_factor:z" && lr > 100.0, "{name} {lr}");
        let (names, cut_short) = problem(3);
        assert_eq!(names, ["accel_scale_factor:x", "accel_scale_factor:y", "accel_scale_factor:z"]);
        assert!(cut_short.is_none(), "{cut_short:?}");
    }

    /// A warm-up (2 at 23 s, white noise 0.1) and a step of 0.5 over the first 30 s (a pose visited early;
    /// the candidate `accel_scale_factor:x`), with a drift among the candidates, on a grid of time constants
    /// 8 % apart. The warm-up enters first. Without profiling its time constant again once the step is in, it
    /// stays at 26.0 s (13 % long) and the drift, which makes up the difference of shape, is added (likelihood
    /// ratio 9.6); profiled again, it is within 10 % of 23 s and the drift is not added.
    #[test]
    fn a_time_constant_is_profiled_again_once_the_static_terms_are_in() {
        let n = 400;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.25).collect();
        let tau_true = 23.0;
        let step: Vec<f64> = t.iter().map(|&t| f64::from(u8::from(t < 30.0))).collect();
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(7);
        let noise: Vec<f64> = (0..n).map(|_| 0.1 * crate::model::simulator::normal(&mut rng)).collect();
        let y: Vec<f64> = (0..n).map(|i| 2.0 * (-t[i] / tau_true).exp() + 0.5 * step[i] + noise[i]).collect();
        let grid: Vec<f64> = (0..48).map(|k| 5.0 * 40f64.powf(k as f64 / 47.0)).collect();
        let warmup = Candidate {
            effect: EffectKind::BiasWarmup,
            sensor: Sensor::Accel,
            axes: "x".into(),
            pos: None,
            pair_pos: None,
            variants: grid
                .iter()
                .map(|&tau| (Some(tau), Column::new(t.iter().map(|t| (-t / tau).exp()).collect())))
                .collect(),
            groups: vec![0],
            limit: None,
        };
        let column = |v: &[f64]| Column::new(v.to_vec());
        let drift: Vec<f64> = t.iter().map(|t| t - 50.0).collect();
        let mut p = one_channel(
            y,
            vec![
                warmup,
                Candidate::single(EffectKind::AccelScaleFactor, Sensor::Accel, "x".into(), column(&step), vec![0]),
                Candidate::single(EffectKind::BiasDrift, Sensor::Accel, "x".into(), column(&drift), vec![0]),
            ],
        );
        let s = select_at_most(&mut p, 0, 3, &[]).unwrap();
        let names: Vec<String> = s.chosen.iter().map(|c| p.candidates[c.candidate].name()).collect();
        assert_eq!(names, ["bias_warmup:x (accel)", "accel_scale_factor:x"], "the drift is not added");
        let tau = p.candidates[0].variants[s.chosen[0].variant].0.unwrap();
        assert!((tau / tau_true - 1.0).abs() < 0.1, "tau {tau} s");
    }

    /// Two candidates that explain the data nearly equally (each is half of what was put in, their columns
    /// correlated 0.9, below the aliases' 0.95; white noise of 1) and a third, distinct and weaker one, all
    /// beyond the criterion:
    /// the first chosen names the second as its rival, not the third (a BIC gain far below); the third has none.
    #[test]
    fn a_candidate_nearly_as_good_is_named_as_a_rival() {
        let n = 200;
        let wave = |k: f64| (0..n).map(move |i| (k * i as f64).sin()).collect::<Vec<f64>>();
        let (a, b, c) = (wave(0.3), wave(1.1), wave(2.3));
        let first: Vec<f64> = (0..n).map(|i| a[i]).collect();
        let second: Vec<f64> = (0..n).map(|i| 0.9 * a[i] + 0.436 * b[i]).collect();
        let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(3);
        let y: Vec<f64> = (0..n)
            .map(|i| 0.5 * (first[i] + second[i]) + 0.6 * c[i] + crate::model::simulator::normal(&mut rng))
            .collect();
        let candidate = |axes: &str, col: &[f64]| {
            Candidate::single(
                EffectKind::AccelScaleFactor,
                Sensor::Accel,
                axes.into(),
                Column::new(col.to_vec()),
                vec![0],
            )
        };
        let mut p = one_channel(y, vec![candidate("x", &first), candidate("y", &second), candidate("z", &c)]);
        let s = select_at_most(&mut p, 0, 3, &[]).unwrap();
        let names: Vec<String> = s.chosen.iter().map(|c| p.candidates[c.candidate].name()).collect();
        let rival = if names[0] == "accel_scale_factor:x" { "accel_scale_factor:y" } else { "accel_scale_factor:x" };
        assert!(names.len() == 2 && names[1] == "accel_scale_factor:z", "{names:?}");
        assert_eq!(s.rivals[0], [rival]);
        assert!(s.rivals[1].is_empty(), "{:?}", s.rivals[1]);
    }
}
