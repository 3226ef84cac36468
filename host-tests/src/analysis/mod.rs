//! `sinscal analyze`: what the base model (constant biases and white noise) gets wrong in a recording or an
//! angles file, which effect of the catalogue (SPEC.md section 6) explains it, and how much that gains.
//!
//! # Recordings
//! Every dwell is cut into blocks (about 6 s, at most 200 per dwell). The observations are the block means of
//! the six channels minus what the reference attitude predicts (`C^T W_ie^n` for the gyros, `C^T [0, 0, g]` for
//! the accelerometers). The base model is one bias per channel and white noise with one variance per channel.
//! Every effect of the catalogue that is linear in its parameter adds one column:
//! - scale factors, misalignments, g-sensitivity: the predicted rate or force of the block, on the sensed axis;
//! - reference offset and position error (a table attitude error `err`, `C_true = (I - [err x]) C_ref`, the
//!   convention of `sinscal simulate` and of METHOD.md's `phi0`): `C^T (e_k x v)` for `v` = Earth rate and
//!   gravity, on all six channels (of one dwell for a position error);
//! - bias drift: block time; temperature: block mean temperature;
//! - warm-up `A exp(-(t - t0)/tau)` (t0 = first row): the block mean of the exponential, with `tau` profiled
//!   over a logarithmic grid (two parameters).
//!
//! The noise variances are estimated with the coefficients (profile likelihood, [`crate::stats::linfit`]). Faster
//! effects are tested on the samples themselves, after each dwell's mean and trend are removed:
//! - vibration: the largest line of the periodogram summed over dwells, against the median of its
//!   neighbourhood (a line, not a coloured background); amplitude corrected for the interval averaging of an
//!   integrating sensor (`sinc(f dt)`);
//! - correlated noise: exact Gaussian likelihood of a first-order Gauss-Markov process plus white noise
//!   (Kalman filter), against white noise alone;
//! - quantisation: the fraction of sample differences on a lattice ([`crate::stats::noise::detect_quantization`]),
//!   against the fraction continuous data give, as a binomial likelihood ratio.
//!
//! # Criterion
//! Forward selection: at each step every candidate not yet chosen is fitted together with the chosen ones;
//! the one with the largest likelihood-ratio statistic `LR = 2 (ln L1 - ln L0)` is added if its p-value
//! (chi-square with the candidate's number of parameters) is below `alpha / m` (Bonferroni over the `m`
//! candidates tested, family-wise `alpha` = [`ALPHA`]) and its `delta_bic = -LR + k ln n` is negative.
//! Effects are reported strongest (most negative `delta_bic`) first. Candidates that the base model explains
//! completely (a zero or dependent column) are `unobservable`; candidates whose columns are indistinguishable
//! in this data (correlation above [`ALIAS_CORRELATION`] once the base model is removed) are named as
//! `aliases` of the effect found.
//!
//! # Angles files
//! The observations are the per-position angles; the base model is the six biases mapped through the
//! alignment equations of METHOD.md (the core's design rows); sensor effects are mapped the same way, the
//! reference offset and position errors enter directly. Time-dependent and noise effects are unobservable.

pub mod hidden;

use std::path::Path;

use serde::Serialize;

use crate::calibration::site_of;
use crate::io::error::InputError;
use crate::io::recording::Recording;
use crate::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec, M3};
use crate::stats::linfit::{chi_square_quantile_upper, chi_square_upper, fit, solve_spd, LinearFit, Observations};
use crate::stats::noise::{detect_quantization, fft_in_place, ljung_box, GRID_TOLERANCE};

/// Family-wise significance level of the effect search.
pub const ALPHA: f64 = 0.01;
/// Candidates whose base-free columns correlate above this are indistinguishable (aliases).
pub const ALIAS_CORRELATION: f64 = 0.999;
/// Target block length, samples (6 s at 100 Hz).
pub const BLOCK_SAMPLES: usize = 600;
/// Most blocks per dwell.
pub const MAX_BLOCKS_PER_DWELL: usize = 200;
/// Fewest samples a dwell needs.
pub const MIN_DWELL_SAMPLES: usize = 64;
/// Most effects the forward selection adds.
pub const MAX_EFFECTS: usize = 12;
/// Channel names (the recording's columns).
pub const CHANNELS: [&str; 6] = ["gx_radps", "gy_radps", "gz_radps", "ax_mps2", "ay_mps2", "az_mps2"];
const AXES: [&str; 3] = ["x", "y", "z"];
const ENU: [&str; 3] = ["e", "n", "u"];

/// One effect the data support (SPEC.md section 6, with extra fields).
#[derive(Clone, Debug, Serialize)]
pub struct Effect {
    /// Catalogue name.
    pub effect: String,
    /// "gyro", "accel" or "reference".
    pub sensor: String,
    /// Axis or axis pair.
    pub axes: String,
    /// Position label (position errors only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pos: Option<u32>,
    /// Estimate, SI.
    pub estimate: f64,
    /// Its standard error, SI.
    pub std_error: f64,
    /// Unit of the estimate.
    pub unit: String,
    /// BIC change when the effect is added (negative = better).
    pub delta_bic: f64,
    /// RMS residual of the affected channels before the effect was added.
    pub residual_rms_before: f64,
    /// The same after.
    pub residual_rms_after: f64,
    /// Unit of the residuals ("rad/s", "m/s^2", "rad").
    pub residual_unit: String,
    /// What the residuals are: "block means", "samples", "innovations", "angles".
    pub residual_of: String,
    /// Time constant, s (warm-up, correlated noise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_s: Option<f64>,
    /// Frequency, Hz (vibration).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// Likelihood-ratio statistic.
    pub likelihood_ratio: f64,
    /// Parameters the effect adds.
    pub parameters: usize,
    /// p-value of the likelihood ratio, before the Bonferroni factor.
    pub p_value: f64,
    /// Other candidates this data set cannot tell apart from this one.
    pub aliases: Vec<String>,
}

impl Effect {
    /// The extra fields in words: "pos 3", "tau 1.234 s", "f 7.3000 Hz" (comma-separated, empty if none).
    pub fn extras(&self) -> String {
        let mut parts = Vec::new();
        if let Some(p) = self.pos {
            parts.push(format!("pos {p}"));
        }
        if let Some(t) = self.tau_s {
            parts.push(format!("tau {t:.3} s"));
        }
        if let Some(f) = self.frequency_hz {
            parts.push(format!("f {f:.4} Hz"));
        }
        parts.join(", ")
    }
}

/// The base model's fit.
#[derive(Clone, Debug, Serialize)]
pub struct BaseModel {
    /// "bias-only".
    pub name: String,
    /// RMS residual per channel (recordings: of the samples after the biases; angles: per angle group).
    pub residual_rms: std::collections::BTreeMap<String, f64>,
    /// RMS residual of the block means per channel (recordings only).
    #[serde(skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub block_residual_rms: std::collections::BTreeMap<String, f64>,
    /// Log-likelihood of the block means (angles: of the angles).
    pub log_likelihood: f64,
    /// Its BIC.
    pub bic: f64,
    /// Observations the likelihood is over.
    pub observations: usize,
    /// Estimated biases, SI, by name ("gyro_bias_x", ...).
    pub biases: std::collections::BTreeMap<String, f64>,
}

/// One candidate as tested against the base model alone (the whole catalogue that the data can see).
#[derive(Clone, Debug, Serialize)]
pub struct Tested {
    /// "effect:axes" (position errors: "position_error:e:pos3").
    pub name: String,
    /// Estimate, SI, fitted with the base model alone.
    pub estimate: f64,
    /// Its standard error.
    pub std_error: f64,
    /// Likelihood-ratio statistic against the base model.
    pub likelihood_ratio: f64,
}

/// Per-channel diagnostics of a recording.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelDiagnostics {
    /// Channel name.
    pub channel: String,
    /// RMS of the samples after each dwell's mean and trend, in the channel's unit.
    pub detrended_rms: f64,
    /// Ljung-Box p-value (20 lags) of the detrended samples of the longest dwell.
    pub whiteness_p_value: f64,
    /// Largest within-dwell slope over its standard error (white-noise), across dwells.
    pub max_trend_z: f64,
    /// Quantisation step if the samples lie on a lattice.
    pub quantization_step: Option<f64>,
}

/// The result of `sinscal analyze` (SPEC.md section 6, with extra fields).
#[derive(Clone, Debug, Serialize)]
pub struct Analysis {
    /// "sinscal-analysis/1".
    pub schema: String,
    /// The file analysed.
    pub source: String,
    /// "recording" or "angles".
    pub input: String,
    /// The base model.
    pub base_model: BaseModel,
    /// Effects found, strongest first.
    pub effects: Vec<Effect>,
    /// Catalogue entries this data set cannot see.
    pub unobservable: Vec<String>,
    /// `effects[0].effect` or "none".
    pub verdict: String,
    /// The criterion, in words, with its numbers.
    pub criterion: String,
    /// Family-wise significance level.
    pub alpha: f64,
    /// Candidates tested (m of the Bonferroni correction).
    pub candidates_tested: usize,
    /// Every candidate against the base model alone.
    pub tested: Vec<Tested>,
    /// Per-channel diagnostics (recordings).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub diagnostics: Vec<ChannelDiagnostics>,
    /// Data for the report's figures (not written to JSON).
    #[serde(skip)]
    pub figures: FigureData,
}

/// What the report's figures show.
#[derive(Clone, Debug, Default)]
pub struct FigureData {
    /// Sample rate, Hz (recordings).
    pub rate_hz: f64,
    /// Per channel: the detrended samples of the longest dwell (recordings).
    pub longest_dwell: Vec<Vec<f64>>,
    /// Per channel: white-noise standard deviation of the base model, channel unit.
    pub base_sigma: Vec<f64>,
    /// Per channel: correlated-noise (sigma, tau) found, if any.
    pub correlated: Vec<Option<(f64, f64)>>,
    /// Per channel: quantisation step found, if any.
    pub quantization: Vec<Option<f64>>,
    /// Per channel: vibration (amplitude as seen, frequency) found, if any.
    pub vibration: Vec<Option<(f64, f64)>>,
    /// Per observation group (channel or angle): (position label, base residual, final residual) of each
    /// observation.
    pub residuals: Vec<Vec<(u32, f64, f64)>>,
    /// Group names of `residuals`, with units.
    pub residual_names: Vec<String>,
}

/// A candidate column (or family of columns, one per time constant).
#[derive(Clone, Debug)]
struct Candidate {
    effect: &'static str,
    sensor: &'static str,
    axes: String,
    pos: Option<u32>,
    unit: &'static str,
    variants: Vec<(Option<f64>, Vec<f64>)>,
    groups: Vec<usize>,
}

impl Candidate {
    /// "effect:axes", with the position of a position error ("position_error:e:pos3") and the sensor of
    /// the effects both sensors have ("bias_drift:x (gyro)").
    fn name(&self) -> String {
        match self.pos {
            Some(p) => format!("{}:{}:pos{}", self.effect, self.axes, p),
            None if self.sensor != "reference" && !self.effect.starts_with(self.sensor) => {
                format!("{}:{} ({})", self.effect, self.axes, self.sensor)
            }
            None => format!("{}:{}", self.effect, self.axes),
        }
    }

    fn parameters(&self) -> usize {
        if self.variants.len() > 1 {
            2
        } else {
            1
        }
    }
}

/// A linear problem: observations, the base columns, the candidates.
struct Problem {
    obs: Observations,
    base: Vec<Vec<f64>>,
    base_names: Vec<String>,
    group_names: Vec<String>,
    group_units: Vec<&'static str>,
    obs_pos: Vec<u32>,
    candidates: Vec<Candidate>,
    unobservable: Vec<String>,
    residual_of: &'static str,
}

struct Chosen {
    candidate: usize,
    variant: usize,
    lr: f64,
    delta_bic: f64,
    p_value: f64,
    rms_before: f64,
    rms_after: f64,
}

fn group_rms(fit: &LinearFit, groups: &[usize]) -> f64 {
    (groups.iter().map(|&g| fit.rms[g] * fit.rms[g]).sum::<f64>() / groups.len().max(1) as f64).sqrt()
}

/// Removes the base columns from `column` (weighted least squares with `weights`), for alias and
/// observability checks; returns the remainder.
fn remainder(base: &[&[f64]], weights: &[f64], column: &[f64]) -> Vec<f64> {
    let k = base.len();
    let mut a = vec![vec![0.0; k]; k];
    let mut b = vec![0.0; k];
    for i in 0..column.len() {
        let w = weights[i];
        for p in 0..k {
            b[p] += w * base[p][i] * column[i];
            for q in 0..k {
                a[p][q] += w * base[p][i] * base[q][i];
            }
        }
    }
    let coef = solve_spd(&a, &b).map(|(x, _)| x).unwrap_or_else(|| vec![0.0; k]);
    (0..column.len()).map(|i| column[i] - (0..k).map(|p| coef[p] * base[p][i]).sum::<f64>()).collect()
}

fn weighted_norm(weights: &[f64], v: &[f64]) -> f64 {
    v.iter().zip(weights).map(|(v, w)| w * v * v).sum::<f64>().sqrt()
}

fn weighted_dot(weights: &[f64], a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).zip(weights).map(|((a, b), w)| w * a * b).sum()
}

struct Selection {
    base_fit: LinearFit,
    final_fit: LinearFit,
    chosen: Vec<Chosen>,
    tested: Vec<Tested>,
    aliases: Vec<Vec<String>>,
    observable: usize,
}

/// Forward selection over the problem's candidates; `m` = candidates tested in all (Bonferroni).
fn select(problem: &mut Problem, extra_tests: usize) -> Result<Selection, String> {
    let base_cols: Vec<&[f64]> = problem.base.iter().map(|c| c.as_slice()).collect();
    let base_fit =
        fit(&problem.obs, &base_cols).ok_or("the base model's biases cannot be fitted (dependent columns)")?;
    let n = problem.obs.y.len() as f64;
    let weights: Vec<f64> = (0..problem.obs.y.len())
        .map(|i| match &problem.obs.sigma {
            Some(s) => 1.0 / (s[i] * s[i]),
            None => 1.0 / base_fit.variance[problem.obs.group[i]],
        })
        .collect();
    // Observability: a candidate whose every variant the base model explains is unobservable.
    let mut observable = Vec::new();
    let mut remainders: Vec<Vec<Vec<f64>>> = Vec::new();
    for (ci, c) in problem.candidates.iter().enumerate() {
        let rems: Vec<Vec<f64>> = c.variants.iter().map(|(_, col)| remainder(&base_cols, &weights, col)).collect();
        let seen = c.variants.iter().zip(&rems).any(|((_, col), rem)| {
            let full = weighted_norm(&weights, col);
            full > 0.0 && weighted_norm(&weights, rem) > 1e-6 * full
        });
        if seen {
            observable.push(ci);
        } else {
            problem.unobservable.push(c.name());
        }
        remainders.push(rems);
    }
    let m = (observable.len() + extra_tests).max(1) as f64;
    let mut tested = Vec::new();
    let mut chosen: Vec<Chosen> = Vec::new();
    let mut current = base_fit.clone();
    let mut columns: Vec<Vec<f64>> = problem.base.clone();
    for step in 0..=MAX_EFFECTS {
        let mut best: Option<(usize, usize, LinearFit, f64)> = None;
        for &ci in &observable {
            if chosen.iter().any(|c| c.candidate == ci) {
                continue;
            }
            let c = &problem.candidates[ci];
            let mut best_variant: Option<(usize, LinearFit)> = None;
            for (vi, (_, col)) in c.variants.iter().enumerate() {
                let mut cols: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
                cols.push(col);
                if let Some(f) = fit(&problem.obs, &cols) {
                    if best_variant.as_ref().is_none_or(|(_, b)| f.log_likelihood > b.log_likelihood) {
                        best_variant = Some((vi, f));
                    }
                }
            }
            let Some((vi, f)) = best_variant else { continue };
            let lr = 2.0 * (f.log_likelihood - current.log_likelihood);
            if step == 0 {
                let j = f.beta.len() - 1;
                tested.push(Tested {
                    name: c.name(),
                    estimate: f.beta[j],
                    std_error: f.std_error(j),
                    likelihood_ratio: lr,
                });
            }
            // Ranked by the BIC gain: of two candidates that explain the data equally well, the one with
            // fewer parameters (a temperature coefficient rather than a warm-up of free time constant).
            let gain = lr - c.parameters() as f64 * n.ln();
            if best
                .as_ref()
                .is_none_or(|(bi, _, _, b)| gain > *b - problem.candidates[*bi].parameters() as f64 * n.ln())
            {
                best = Some((ci, vi, f, lr));
            }
        }
        if step == MAX_EFFECTS {
            break;
        }
        let Some((ci, vi, f, lr)) = best else { break };
        let k = problem.candidates[ci].parameters() as f64;
        let p_value = chi_square_upper(lr, k);
        let delta_bic = -lr + k * n.ln();
        if !(lr > chi_square_quantile_upper(ALPHA / m, k) && delta_bic < 0.0) {
            break;
        }
        let groups = problem.candidates[ci].groups.clone();
        chosen.push(Chosen {
            candidate: ci,
            variant: vi,
            lr,
            delta_bic,
            p_value,
            rms_before: group_rms(&current, &groups),
            rms_after: group_rms(&f, &groups),
        });
        columns.push(problem.candidates[ci].variants[vi].1.clone());
        current = f;
    }
    // Aliases of each chosen effect: other observable candidates with (nearly) the same base-free column.
    let mut aliases = Vec::new();
    for c in &chosen {
        let own = &remainders[c.candidate][c.variant];
        let own_norm = weighted_norm(&weights, own);
        let mut names = Vec::new();
        for &oi in &observable {
            if oi == c.candidate {
                continue;
            }
            let similar = remainders[oi].iter().any(|rem| {
                let nrm = weighted_norm(&weights, rem);
                nrm > 0.0 && (weighted_dot(&weights, own, rem) / (own_norm * nrm)).abs() > ALIAS_CORRELATION
            });
            if similar {
                names.push(problem.candidates[oi].name());
            }
        }
        aliases.push(names);
    }
    Ok(Selection { base_fit, final_fit: current, chosen, tested, aliases, observable: observable.len() })
}

fn effect_of(problem: &Problem, selection: &Selection, index: usize) -> Effect {
    let c = &selection.chosen[index];
    let cand = &problem.candidates[c.candidate];
    let j = problem.base.len() + index;
    let units: Vec<&str> = cand.groups.iter().map(|&g| problem.group_units[g]).collect();
    Effect {
        effect: cand.effect.to_string(),
        sensor: cand.sensor.to_string(),
        axes: cand.axes.clone(),
        pos: cand.pos,
        estimate: selection.final_fit.beta[j],
        std_error: selection.final_fit.std_error(j),
        unit: cand.unit.to_string(),
        delta_bic: c.delta_bic,
        residual_rms_before: c.rms_before,
        residual_rms_after: c.rms_after,
        residual_unit: units.first().copied().unwrap_or("").to_string(),
        residual_of: problem.residual_of.to_string(),
        tau_s: cand.variants[c.variant].0,
        frequency_hz: None,
        likelihood_ratio: c.lr,
        parameters: cand.parameters(),
        p_value: c.p_value,
        aliases: selection.aliases[index].clone(),
    }
}

// ---------------------------------------------------------------------------------------------------
// Recordings
// ---------------------------------------------------------------------------------------------------

/// A sensor error proportional to the true rate or force: the output `channel` (gx..az = 0..5) sees
/// `parameter * source[axis]`, with `source` the body rate (rad/s) or specific force (m/s^2) of SPEC.md's
/// sensor model (scale factors, misalignments, gyro g-sensitivity).
struct SensorTerm {
    effect: &'static str,
    sensor: &'static str,
    axes: String,
    unit: &'static str,
    channel: usize,
    from_force: bool,
    axis: usize,
}

impl SensorTerm {
    /// The output error per unit parameter at true body rate `rate_b_radps` and force `force_b_mps2`.
    fn per_unit(&self, rate_b_radps: [f64; 3], force_b_mps2: [f64; 3]) -> f64 {
        if self.from_force {
            force_b_mps2[self.axis]
        } else {
            rate_b_radps[self.axis]
        }
    }
}

/// The terms of the catalogue's sensor model: accelerometer scale factors and misalignments, and, with
/// `gyros`, the gyro scale factors, misalignments and g-sensitivity.
fn sensor_terms(gyros: bool) -> Vec<SensorTerm> {
    let mut terms = Vec::new();
    let mut add = |effect: &'static str, sensor, unit, channel: usize, from_force, i: usize, j: usize| {
        let axes =
            if effect.ends_with("scale_factor") { AXES[i].to_string() } else { format!("{}{}", AXES[i], AXES[j]) };
        terms.push(SensorTerm { effect, sensor, axes, unit, channel, from_force, axis: j });
    };
    for i in 0..3 {
        add("accel_scale_factor", "accel", "1", 3 + i, true, i, i);
    }
    for i in 0..3 {
        for j in (0..3).filter(|&j| j != i) {
            add("accel_misalignment", "accel", "1", 3 + i, true, i, j);
        }
    }
    if gyros {
        for i in 0..3 {
            add("gyro_scale_factor", "gyro", "1", i, false, i, i);
        }
        for i in 0..3 {
            for j in (0..3).filter(|&j| j != i) {
                add("gyro_misalignment", "gyro", "1", i, false, i, j);
            }
        }
        for i in 0..3 {
            for j in 0..3 {
                add("gyro_g_sensitivity", "gyro", "(rad/s)/(m/s^2)", i, true, i, j);
            }
        }
    }
    terms
}

struct DwellData {
    pos: u32,
    /// Reference C_b^n, when the heading is known.
    c_b_n: Option<M3>,
    /// Reference C_b^n with heading 0 (tilt only), for the gravity prediction.
    c_tilt: M3,
    t: Vec<f64>,
    y: [Vec<f64>; 6],
    temp: Option<Vec<f64>>,
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn unit(k: usize) -> [f64; 3] {
    let mut e = [0.0; 3];
    e[k] = 1.0;
    e
}

/// A dwell's straight-line fit `y = a + b (t - t_mean)`.
struct Trend {
    /// Slope `b`, channel unit per second.
    slope_per_s: f64,
    /// Its standard error for white residuals, same unit.
    slope_std_error_per_s: f64,
    /// `y` minus the line.
    residual: Vec<f64>,
}

fn detrend(t: &[f64], y: &[f64]) -> Trend {
    let n = t.len() as f64;
    let tm = t.iter().sum::<f64>() / n;
    let ym = y.iter().sum::<f64>() / n;
    let stt: f64 = t.iter().map(|t| (t - tm) * (t - tm)).sum();
    let sty: f64 = t.iter().zip(y).map(|(t, y)| (t - tm) * (y - ym)).sum();
    let b = if stt > 0.0 { sty / stt } else { 0.0 };
    let residual: Vec<f64> = t.iter().zip(y).map(|(t, y)| y - ym - b * (t - tm)).collect();
    let s2 = residual.iter().map(|v| v * v).sum::<f64>() / (n - 2.0).max(1.0);
    Trend { slope_per_s: b, slope_std_error_per_s: (s2 / stt).sqrt(), residual }
}

fn block_ranges(n: usize) -> Vec<(usize, usize)> {
    let blocks = (n / BLOCK_SAMPLES).clamp(4, MAX_BLOCKS_PER_DWELL).min(n / 16).max(1);
    (0..blocks).map(|b| (b * n / blocks, (b + 1) * n / blocks)).collect()
}

/// Analyses a recording.
pub fn analyze_recording(recording: &Recording) -> Result<Analysis, InputError> {
    let source = recording.source.as_str();
    let (site, _) = site_of(&recording.header);
    let g = site.gravity_mps2 as f64;
    let lat = recording.header.latitude_deg.to_radians();
    let w_n = earth_rate_n_radps(lat);
    let f_n = [0.0, 0.0, g];
    let t0 = recording.rows.first().map_or(0.0, |r| r.t_s);
    let rate_hz = match recording.header.rate_hz {
        Some(r) => r,
        None if recording.rows.len() > 1 => {
            (recording.rows.len() - 1) as f64 / (recording.rows[recording.rows.len() - 1].t_s - t0)
        }
        None => 100.0,
    };
    let dt = 1.0 / rate_hz;
    let mut dwells = Vec::new();
    for d in recording.dwells() {
        let att = d.attitude(source)?;
        if d.rows.len() < MIN_DWELL_SAMPLES {
            return Err(InputError::at(
                source,
                d.first_line(),
                format!("dwell {}: {} rows, the analysis needs at least {MIN_DWELL_SAMPLES}", d.pos, d.rows.len()),
            ));
        }
        let temp = if d.rows.iter().all(|r| r.temp_c.is_some()) {
            Some(d.rows.iter().map(|r| r.temp_c.unwrap_or(0.0)).collect())
        } else {
            None
        };
        dwells.push(DwellData {
            pos: d.pos,
            c_b_n: att.heading_deg.map(|h| c_b_n(att.pitch_deg, att.roll_deg, h)),
            c_tilt: c_b_n(att.pitch_deg, att.roll_deg, 0.0),
            t: d.rows.iter().map(|r| r.t_s).collect(),
            y: std::array::from_fn(|c| {
                d.rows.iter().map(|r| if c < 3 { r.rate_b_radps[c] } else { r.force_b_mps2[c - 3] }).collect()
            }),
            temp,
        });
    }
    if dwells.is_empty() {
        return Err(InputError::file(source, "no dwell: every row has pos = 0"));
    }
    let has_temp = dwells.iter().all(|d| d.temp.is_some());
    let all_heading = dwells.iter().all(|d| d.c_b_n.is_some());

    // Block observations.
    struct BlockObs {
        dwell: usize,
        channel: usize,
        range: (usize, usize),
    }
    let mut blocks = Vec::new();
    let mut y = Vec::new();
    let mut group = Vec::new();
    let mut obs_pos = Vec::new();
    for (di, d) in dwells.iter().enumerate() {
        let predicted_gyro = d.c_b_n.map(|c| mul_t_vec(&c, w_n));
        let predicted_force = mul_t_vec(&d.c_tilt, f_n);
        for channel in 0..6 {
            let predicted = if channel < 3 {
                match predicted_gyro {
                    Some(p) => p[channel],
                    None => continue, // heading unknown: the Earth rate in the body is unknown
                }
            } else {
                predicted_force[channel - 3]
            };
            for range in block_ranges(d.t.len()) {
                let s = &d.y[channel][range.0..range.1];
                y.push(s.iter().sum::<f64>() / s.len() as f64 - predicted);
                group.push(channel);
                obs_pos.push(d.pos);
                blocks.push(BlockObs { dwell: di, channel, range });
            }
        }
    }
    let nobs = y.len();
    let column = |f: &dyn Fn(&BlockObs) -> f64| -> Vec<f64> { blocks.iter().map(f).collect() };
    let present: Vec<bool> = (0..6).map(|c| group.contains(&c)).collect();
    let mut base = Vec::new();
    let mut base_names = Vec::new();
    let mut unobservable = Vec::new();
    for c in 0..6 {
        let name = if c < 3 { format!("gyro_bias_{}", AXES[c]) } else { format!("accel_bias_{}", AXES[c - 3]) };
        if present[c] {
            base.push(column(&|b: &BlockObs| if b.channel == c { 1.0 } else { 0.0 }));
            base_names.push(name);
        } else {
            unobservable.push(name);
        }
    }

    // Candidates.
    let mut candidates = Vec::new();
    let body = |b: &BlockObs, v_n: [f64; 3], gyro_needs_heading: bool| -> Option<[f64; 3]> {
        let d = &dwells[b.dwell];
        match d.c_b_n {
            Some(c) => Some(mul_t_vec(&c, v_n)),
            None if !gyro_needs_heading => Some(mul_t_vec(&d.c_tilt, v_n)),
            None => None,
        }
    };
    let force_b = |b: &BlockObs| body(b, f_n, false).unwrap_or([0.0; 3]);
    let rate_b = |b: &BlockObs| body(b, w_n, true).unwrap_or([0.0; 3]);
    let one = |effect, sensor, axes: String, unit, col: Vec<f64>, groups: Vec<usize>| Candidate {
        effect,
        sensor,
        axes,
        pos: None,
        unit,
        variants: vec![(None, col)],
        groups,
    };
    for t in sensor_terms(all_heading) {
        let col = column(&|b: &BlockObs| if b.channel == t.channel { t.per_unit(rate_b(b), force_b(b)) } else { 0.0 });
        let groups = vec![t.channel];
        candidates.push(one(t.effect, t.sensor, t.axes, t.unit, col, groups));
    }
    if all_heading {
        // Table attitude errors: d(measurement)/d(err_k) = C^T (e_k x v).
        let attitude_column = |k: usize, only: Option<usize>| {
            column(&|b: &BlockObs| {
                if only.is_some_and(|d| d != b.dwell) {
                    return 0.0;
                }
                let c = dwells[b.dwell].c_b_n.unwrap_or(dwells[b.dwell].c_tilt);
                if b.channel < 3 {
                    mul_t_vec(&c, cross(unit(k), w_n))[b.channel]
                } else {
                    mul_t_vec(&c, cross(unit(k), f_n))[b.channel - 3]
                }
            })
        };
        for k in 0..3 {
            let groups = if k == 2 { vec![0, 1, 2] } else { vec![3, 4, 5] };
            candidates.push(Candidate {
                effect: "reference_offset",
                sensor: "reference",
                axes: ENU[k].into(),
                pos: None,
                unit: "rad",
                variants: vec![(None, attitude_column(k, None))],
                groups,
            });
        }
        if dwells.len() > 1 {
            for (di, d) in dwells.iter().enumerate() {
                for k in 0..3 {
                    let groups = if k == 2 { vec![0, 1, 2] } else { vec![3, 4, 5] };
                    candidates.push(Candidate {
                        effect: "position_error",
                        sensor: "reference",
                        axes: ENU[k].into(),
                        pos: Some(d.pos),
                        unit: "rad",
                        variants: vec![(None, attitude_column(k, Some(di)))],
                        groups,
                    });
                }
            }
        }
    } else {
        for name in
            ["gyro_scale_factor", "gyro_misalignment", "gyro_g_sensitivity", "reference_offset", "position_error"]
        {
            unobservable.push(format!("{name}: heading unknown"));
        }
    }
    let t_mid = {
        let (lo, hi) = (dwells[0].t[0], dwells[dwells.len() - 1].t.last().copied().unwrap_or(0.0));
        0.5 * (lo + hi)
    };
    let span = dwells.iter().flat_map(|d| d.t.iter()).fold(0.0f64, |m, t| m.max(t - t0)).max(dt);
    let tau_grid: Vec<f64> = (0..48).map(|i| 5.0 * (span / 5.0f64).powf(i as f64 / 47.0)).collect();
    for c in 0..6 {
        if !present[c] {
            continue;
        }
        let (sensor, ax, rate_unit) = if c < 3 { ("gyro", AXES[c], "rad/s") } else { ("accel", AXES[c - 3], "m/s^2") };
        let slope_unit = if c < 3 { "(rad/s)/s" } else { "(m/s^2)/s" };
        candidates.push(one(
            "bias_drift",
            sensor,
            ax.into(),
            slope_unit,
            column(&|b: &BlockObs| {
                if b.channel != c {
                    return 0.0;
                }
                let t = &dwells[b.dwell].t[b.range.0..b.range.1];
                t.iter().sum::<f64>() / t.len() as f64 - t_mid
            }),
            vec![c],
        ));
        let variants = tau_grid
            .iter()
            .map(|&tau| {
                let col = column(&|b: &BlockObs| {
                    if b.channel != c {
                        return 0.0;
                    }
                    let t = &dwells[b.dwell].t[b.range.0..b.range.1];
                    t.iter().map(|t| (-(t - t0) / tau).exp()).sum::<f64>() / t.len() as f64
                });
                (Some(tau), col)
            })
            .collect();
        candidates.push(Candidate {
            effect: "bias_warmup",
            sensor,
            axes: ax.into(),
            pos: None,
            unit: rate_unit,
            variants,
            groups: vec![c],
        });
        if has_temp {
            candidates.push(one(
                "temperature_bias",
                sensor,
                ax.into(),
                if c < 3 { "(rad/s)/K" } else { "(m/s^2)/K" },
                column(&|b: &BlockObs| {
                    if b.channel != c {
                        return 0.0;
                    }
                    let temp = dwells[b.dwell].temp.as_ref().map_or(&[][..], |v| &v[b.range.0..b.range.1]);
                    temp.iter().sum::<f64>() / temp.len().max(1) as f64
                }),
                vec![c],
            ));
        } else {
            unobservable.push(format!("temperature_bias:{ax}{}", if c < 3 { " (gyro)" } else { " (accel)" }));
        }
    }
    // Sample-level tests: quantisation, vibration, correlated noise on every channel.
    let extra_tests = 3 * 6;
    let mut problem = Problem {
        obs: Observations { y, group, groups: 6, sigma: None },
        base,
        base_names,
        group_names: CHANNELS.iter().map(|s| s.to_string()).collect(),
        group_units: vec!["rad/s", "rad/s", "rad/s", "m/s^2", "m/s^2", "m/s^2"],
        obs_pos,
        candidates,
        unobservable,
        residual_of: "block means",
    };
    let selection = select(&mut problem, extra_tests).map_err(|e| InputError::file(source, e))?;
    let m = (selection.observable + extra_tests) as f64;
    let mut effects: Vec<Effect> = (0..selection.chosen.len()).map(|i| effect_of(&problem, &selection, i)).collect();

    // Samples after each dwell's mean and trend.
    let mut trends: Vec<Vec<Trend>> = (0..6).map(|c| dwells.iter().map(|d| detrend(&d.t, &d.y[c])).collect()).collect();
    let detrended: Vec<Vec<Vec<f64>>> = trends
        .iter_mut()
        .map(|per_dwell| per_dwell.iter_mut().map(|t| std::mem::take(&mut t.residual)).collect())
        .collect();
    let mut figures = FigureData { rate_hz, ..FigureData::default() };
    let longest = (0..dwells.len()).max_by_key(|&i| dwells[i].t.len()).unwrap_or(0);
    let mut diagnostics = Vec::new();
    for c in 0..6 {
        let (sensor, ax, unit_) = if c < 3 { ("gyro", AXES[c], "rad/s") } else { ("accel", AXES[c - 3], "m/s^2") };
        let mut series = detrended[c].clone();
        let all: Vec<f64> = series.iter().flatten().copied().collect();
        let rms = (all.iter().map(|v| v * v).sum::<f64>() / all.len() as f64).sqrt();
        let raw: Vec<f64> = dwells.iter().flat_map(|d| d.y[c].iter().copied()).collect();
        // Quantisation.
        let mut q_step = None;
        if let Ok(q) = detect_quantization(&raw) {
            let n = q.nonzero_differences as f64;
            let k = (q.fraction_on_grid * n).round();
            let p0 = 2.0 * GRID_TOLERANCE;
            let p1 = (k / n).clamp(1e-12, 1.0);
            let lr = if p1 > p0 {
                2.0 * (k * (p1 / p0).ln() + if n > k { (n - k) * ((1.0 - p1) / (1.0 - p0)).ln() } else { 0.0 })
            } else {
                0.0
            };
            let delta_bic = -lr + n.ln();
            if q.quantized && lr > chi_square_quantile_upper(ALPHA / m, 1.0) && delta_bic < 0.0 {
                let se = quantization_std_error(&raw, q.step);
                q_step = Some(q.step);
                effects.push(Effect {
                    effect: "quantization".into(),
                    sensor: sensor.into(),
                    axes: ax.into(),
                    pos: None,
                    estimate: q.step,
                    std_error: se,
                    unit: unit_.into(),
                    delta_bic,
                    residual_rms_before: rms,
                    residual_rms_after: (rms * rms - q.step * q.step / 12.0).max(0.0).sqrt(),
                    residual_unit: unit_.into(),
                    residual_of: "samples".into(),
                    tau_s: None,
                    frequency_hz: None,
                    likelihood_ratio: lr,
                    parameters: 1,
                    p_value: chi_square_upper(lr, 1.0),
                    aliases: Vec::new(),
                });
            }
        }
        // Vibration.
        let mut vib = None;
        if let Some(v) = vibration_test(&series, dt) {
            // Parameters: amplitude, frequency, a phase per dwell. The statistic is tested as chi-square
            // with one degree per phase and one for the amplitude, Bonferroni over the frequencies searched.
            let dof = series.len() as f64 + 1.0;
            let threshold = chi_square_quantile_upper(ALPHA / (m * v.independent_frequencies), dof);
            let delta_bic = -v.lr + (dof + 1.0) * (all.len() as f64).ln();
            if v.lr > threshold && delta_bic < 0.0 {
                let corr = sinc(v.frequency_hz * dt);
                vib = Some((v.amplitude_seen, v.frequency_hz));
                effects.push(Effect {
                    effect: "vibration".into(),
                    sensor: sensor.into(),
                    axes: ax.into(),
                    pos: None,
                    estimate: v.amplitude_seen / corr,
                    std_error: v.amplitude_std / corr,
                    unit: unit_.into(),
                    delta_bic,
                    residual_rms_before: rms,
                    residual_rms_after: (rms * rms - 0.5 * v.amplitude_seen * v.amplitude_seen).max(0.0).sqrt(),
                    residual_unit: unit_.into(),
                    residual_of: "samples".into(),
                    tau_s: None,
                    frequency_hz: Some(v.frequency_hz),
                    likelihood_ratio: v.lr,
                    parameters: dof as usize + 1,
                    p_value: chi_square_upper(v.lr, dof),
                    aliases: Vec::new(),
                });
                for (s, (re, im)) in series.iter_mut().zip(&v.per_dwell) {
                    let w = std::f64::consts::TAU * v.frequency_hz * dt;
                    for (i, x) in s.iter_mut().enumerate() {
                        let ph = w * i as f64;
                        *x -= re * ph.cos() - im * ph.sin();
                    }
                }
            }
        }
        // Correlated noise.
        let mut corr_found = None;
        if let Some(gm) = gauss_markov_test(&series, dt) {
            let delta_bic = -gm.lr + 2.0 * (all.len() as f64).ln();
            if gm.lr > chi_square_quantile_upper(ALPHA / m, 2.0) && delta_bic < 0.0 {
                corr_found = Some((gm.sigma, gm.tau_s));
                effects.push(Effect {
                    effect: "correlated_noise".into(),
                    sensor: sensor.into(),
                    axes: ax.into(),
                    pos: None,
                    estimate: gm.sigma,
                    std_error: gm.sigma_std,
                    unit: unit_.into(),
                    delta_bic,
                    residual_rms_before: gm.rms_white,
                    residual_rms_after: gm.rms_innovation,
                    residual_unit: unit_.into(),
                    residual_of: "innovations".into(),
                    tau_s: Some(gm.tau_s),
                    frequency_hz: None,
                    likelihood_ratio: gm.lr,
                    parameters: 2,
                    p_value: chi_square_upper(gm.lr, 2.0),
                    aliases: Vec::new(),
                });
            }
        }
        let long = &detrended[c][longest];
        let whiteness = ljung_box(long, 20).map(|l| l.p_value).unwrap_or(f64::NAN);
        let max_trend_z = trends[c].iter().map(|t| (t.slope_per_s / t.slope_std_error_per_s).abs()).fold(0.0, f64::max);
        diagnostics.push(ChannelDiagnostics {
            channel: CHANNELS[c].into(),
            detrended_rms: rms,
            whiteness_p_value: whiteness,
            max_trend_z,
            quantization_step: q_step,
        });
        figures.longest_dwell.push(long.clone());
        figures.base_sigma.push(rms);
        figures.correlated.push(corr_found);
        figures.quantization.push(q_step);
        figures.vibration.push(vib);
    }
    effects.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));

    let mut residual_rms = std::collections::BTreeMap::new();
    let mut block_rms = std::collections::BTreeMap::new();
    for c in 0..6 {
        if present[c] {
            // Samples minus the base model: the dwell's deviation from the fitted bias (block level) plus the
            // detrended part (diagnostics).
            let block = selection.base_fit.rms[c];
            block_rms.insert(CHANNELS[c].to_string(), block);
            let detrended_rms = diagnostics[c].detrended_rms;
            residual_rms.insert(CHANNELS[c].to_string(), (detrended_rms * detrended_rms + block * block).sqrt());
        }
    }
    figures.residual_names = CHANNELS.iter().map(|s| s.to_string()).collect();
    figures.residuals = residuals_by_group(&problem, &selection);
    Ok(finish(problem, selection, effects, residual_rms, block_rms, nobs, m, "recording", source, diagnostics, figures))
}

fn residuals_by_group(problem: &Problem, selection: &Selection) -> Vec<Vec<(u32, f64, f64)>> {
    let mut out = vec![Vec::new(); problem.obs.groups];
    for i in 0..problem.obs.y.len() {
        out[problem.obs.group[i]].push((
            problem.obs_pos[i],
            selection.base_fit.residual[i],
            selection.final_fit.residual[i],
        ));
    }
    out
}

#[allow(clippy::too_many_arguments)]
fn finish(
    problem: Problem,
    selection: Selection,
    effects: Vec<Effect>,
    residual_rms: std::collections::BTreeMap<String, f64>,
    block_residual_rms: std::collections::BTreeMap<String, f64>,
    nobs: usize,
    m: f64,
    input: &str,
    source: &str,
    diagnostics: Vec<ChannelDiagnostics>,
    figures: FigureData,
) -> Analysis {
    let k = problem.base.len() as f64;
    let ll = selection.base_fit.log_likelihood;
    let biases =
        problem.base_names.iter().enumerate().map(|(j, name)| (name.clone(), selection.base_fit.beta[j])).collect();
    let verdict = effects.first().map_or("none".to_string(), |e| e.effect.clone());
    let mut unobservable = problem.unobservable.clone();
    if input == "angles" {
        unobservable.extend(
            ["bias_drift", "bias_warmup", "correlated_noise", "vibration", "quantization", "temperature_bias"]
                .iter()
                .map(|s| format!("{s}: angles only")),
        );
    }
    Analysis {
        schema: "sinscal-analysis/1".into(),
        source: source.into(),
        input: input.into(),
        base_model: BaseModel {
            name: "bias-only".into(),
            residual_rms,
            block_residual_rms,
            log_likelihood: ll,
            bic: -2.0 * ll + (k + problem.obs.groups as f64) * (nobs as f64).ln(),
            observations: nobs,
            biases,
        },
        effects,
        unobservable,
        verdict,
        criterion: format!(
            "forward selection; an effect is added when its likelihood-ratio p-value is below alpha/m = {:.3e} \
             (alpha = {ALPHA}, Bonferroni over m = {} candidates) and its delta BIC is negative",
            ALPHA / m,
            m as usize
        ),
        alpha: ALPHA,
        candidates_tested: m as usize,
        tested: selection.tested,
        diagnostics,
        figures,
    }
}

fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-12 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    }
}

/// Standard error of a quantisation step: least squares of the on-grid differences `d_i = n_i q`.
fn quantization_std_error(raw: &[f64], step: f64) -> f64 {
    let (mut snn, mut see, mut k) = (0.0, 0.0, 0.0);
    for w in raw.windows(2) {
        let d = (w[1] - w[0]).abs();
        let n = (d / step).round();
        if n >= 1.0 && (d / step - n).abs() <= GRID_TOLERANCE {
            snn += n * n;
            see += (d - n * step).powi(2);
            k += 1.0;
        }
    }
    if k < 2.0 || snn == 0.0 {
        return f64::NAN;
    }
    (see / (k - 1.0) / snn).sqrt()
}

struct VibrationResult {
    frequency_hz: f64,
    amplitude_seen: f64,
    amplitude_std: f64,
    lr: f64,
    independent_frequencies: f64,
    /// Per dwell: complex amplitude (re, im) of the line, `x_i ~ re cos(w i) - im sin(w i)`.
    per_dwell: Vec<(f64, f64)>,
}

/// Direct DFT of `x` at `cycles_per_sample`: sum x_i e^{-i w i}.
fn dft_at(x: &[f64], cycles_per_sample: f64) -> (f64, f64) {
    let w = std::f64::consts::TAU * cycles_per_sample;
    let (c, s) = (w.cos(), w.sin());
    let (mut cr, mut ci) = (1.0f64, 0.0f64);
    let (mut re, mut im) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        if i % 256 == 0 {
            let ph = w * i as f64;
            cr = ph.cos();
            ci = -ph.sin();
        }
        re += v * cr;
        im += v * ci;
        let nr = cr * c + ci * s;
        let ni = ci * c - cr * s;
        cr = nr;
        ci = ni;
    }
    (re, im)
}

/// The strongest spectral line of the dwells' detrended samples against the local background.
fn vibration_test(dwells: &[Vec<f64>], dt: f64) -> Option<VibrationResult> {
    let n_max = dwells.iter().map(|d| d.len()).max()?;
    let n_min = dwells.iter().map(|d| d.len()).min()?;
    if n_min < MIN_DWELL_SAMPLES {
        return None;
    }
    let len = (n_max.next_power_of_two() * 4).min(1 << 20);
    let mut power = vec![0.0; len / 2];
    for d in dwells {
        let (mut re, mut im) = (vec![0.0; len], vec![0.0; len]);
        let step = if d.len() > len { d.len() / len + 1 } else { 1 };
        for (i, v) in d.iter().step_by(step).enumerate().take(len) {
            re[i] = *v;
        }
        fft_in_place(&mut re, &mut im).ok()?;
        for k in 0..len / 2 {
            power[k] += (re[k] * re[k] + im[k] * im[k]) / d.len() as f64;
        }
    }
    // Lines below three cycles per shortest dwell are too close to the removed trend.
    let k_min = ((3.0 * len as f64 / n_min as f64).ceil() as usize).max(2);
    if k_min + 20 >= len / 2 {
        return None;
    }
    let k_hat = (k_min..len / 2 - 1).max_by(|&a, &b| power[a].total_cmp(&power[b]))?;
    let half_window = 150.min(len / 4);
    let mut neighbours: Vec<f64> = (k_hat.saturating_sub(half_window).max(k_min)..(k_hat + half_window).min(len / 2))
        .filter(|&k| k.abs_diff(k_hat) > 12)
        .map(|k| power[k])
        .collect();
    if neighbours.len() < 20 {
        return None;
    }
    neighbours.sort_by(f64::total_cmp);
    let p = dwells.len() as f64;
    // Median of Gamma(P, 1): P (1 - 1/(9P))^3 (Wilson-Hilferty).
    let background = neighbours[neighbours.len() / 2] / (p * (1.0 - 1.0 / (9.0 * p)).powi(3));
    // Refine the frequency by golden section on the summed periodogram, within one bin.
    let score = |f: f64| -> f64 {
        dwells
            .iter()
            .map(|d| {
                let (re, im) = dft_at(d, f);
                (re * re + im * im) / d.len() as f64
            })
            .sum()
    };
    let (mut a, mut b) = ((k_hat as f64 - 1.0) / len as f64, (k_hat as f64 + 1.0) / len as f64);
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - gr * (b - a), a + gr * (b - a));
    let (mut sc, mut sd) = (score(c), score(d));
    for _ in 0..40 {
        if sc > sd {
            b = d;
            d = c;
            sd = sc;
            c = b - gr * (b - a);
            sc = score(c);
        } else {
            a = c;
            c = d;
            sc = sd;
            d = a + gr * (b - a);
            sd = score(d);
        }
    }
    let f = 0.5 * (a + b);
    // One amplitude, a phase per dwell: RSS(A) = RSS0 - 2 A sum|X_p| + A^2 N / 2, so
    // A = 2 sum|X_p| / N and the reduction is 2 (sum|X_p|)^2 / N, in units of the background variance.
    let mut per_dwell = Vec::new();
    let mut sum_abs = 0.0;
    let mut total = 0.0;
    for dw in dwells {
        let n = dw.len() as f64;
        let (re, im) = dft_at(dw, f);
        sum_abs += re.hypot(im);
        total += n;
        per_dwell.push((re, im, n));
    }
    let amplitude = 2.0 * sum_abs / total;
    let lr = 2.0 * sum_abs * sum_abs / total / background;
    // The line removed from each dwell: the common amplitude at the dwell's own phase.
    let per_dwell = per_dwell
        .into_iter()
        .map(|(re, im, _)| {
            let m = re.hypot(im).max(1e-300);
            (amplitude * re / m, amplitude * im / m)
        })
        .collect();
    Some(VibrationResult {
        frequency_hz: f / dt,
        amplitude_seen: amplitude,
        amplitude_std: (2.0 * background / total).sqrt(),
        lr,
        independent_frequencies: (n_min as f64 / 2.0).max(1.0),
        per_dwell,
    })
}

struct GaussMarkovResult {
    sigma: f64,
    sigma_std: f64,
    tau_s: f64,
    lr: f64,
    rms_white: f64,
    rms_innovation: f64,
}

/// Concentrated log-likelihood of AR(1) (stationary variance `q`, coefficient `phi`) plus unit white noise
/// with a common scale: returns (log-likelihood, white variance, innovation mean square).
fn ar1_white_loglik(dwells: &[Vec<f64>], phi: f64, q: f64) -> (f64, f64, f64) {
    let (mut sum_ln_s, mut sum_e2_s, mut sum_e2, mut n) = (0.0, 0.0, 0.0, 0usize);
    let drive = q * (1.0 - phi * phi);
    for d in dwells {
        let (mut x, mut p) = (0.0, q);
        for &y in d {
            let s = p + 1.0;
            let e = y - x;
            sum_ln_s += s.ln();
            sum_e2_s += e * e / s;
            sum_e2 += e * e;
            let k = p / s;
            x += k * e;
            p *= 1.0 - k;
            x *= phi;
            p = phi * phi * p + drive;
        }
        n += d.len();
    }
    let nf = n as f64;
    let var = sum_e2_s / nf;
    (-0.5 * nf * ((std::f64::consts::TAU * var).ln() + 1.0) - 0.5 * sum_ln_s, var, sum_e2 / nf)
}

/// First-order Gauss-Markov plus white noise against white noise alone (exact likelihood).
fn gauss_markov_test(dwells: &[Vec<f64>], dt: f64) -> Option<GaussMarkovResult> {
    let n: usize = dwells.iter().map(|d| d.len()).sum();
    let n_min = dwells.iter().map(|d| d.len()).min()?;
    if n_min < MIN_DWELL_SAMPLES {
        return None;
    }
    let ss: f64 = dwells.iter().flatten().map(|v| v * v).sum();
    let s2 = ss / n as f64;
    if s2 <= 0.0 {
        return None;
    }
    // Normalise so that the white variance is of order one.
    let scale = s2.sqrt();
    let norm: Vec<Vec<f64>> = dwells.iter().map(|d| d.iter().map(|v| v / scale).collect()).collect();
    let ll_at = |ln_tau: f64, ln_q: f64| ar1_white_loglik(&norm, (-dt / ln_tau.exp()).exp(), ln_q.exp()).0;
    let (tau_lo, tau_hi) = ((2.0 * dt).ln(), (n_min as f64 * dt / 4.0).max(4.0 * dt).ln());
    let (q_lo, q_hi) = ((1e-3f64).ln(), (1e3f64).ln());
    let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
    for i in 0..12 {
        let lt = tau_lo + (tau_hi - tau_lo) * i as f64 / 11.0;
        for j in 0..10 {
            let lq = q_lo + (q_hi - q_lo) * j as f64 / 9.0;
            let ll = ll_at(lt, lq);
            if ll > best.0 {
                best = (ll, lt, lq);
            }
        }
    }
    // Coordinate refinement with shrinking steps.
    let (mut lt, mut lq) = (best.1, best.2);
    let mut ll = best.0;
    let (mut st, mut sq) = ((tau_hi - tau_lo) / 11.0, (q_hi - q_lo) / 9.0);
    for _ in 0..30 {
        let mut moved = false;
        for (dl, dq) in [(st, 0.0), (-st, 0.0), (0.0, sq), (0.0, -sq)] {
            let (a, b) = ((lt + dl).clamp(tau_lo, tau_hi), (lq + dq).clamp(q_lo - 4.0, q_hi + 4.0));
            let v = ll_at(a, b);
            if v > ll {
                ll = v;
                lt = a;
                lq = b;
                moved = true;
            }
        }
        if !moved {
            st *= 0.5;
            sq *= 0.5;
        }
    }
    let phi = (-dt / lt.exp()).exp();
    let (_, var_w, e2) = ar1_white_loglik(&norm, phi, lq.exp());
    // Both likelihoods of the normalised data shift by the same -n ln(scale): the ratio is unchanged.
    let ll0_norm = -0.5 * n as f64 * (std::f64::consts::TAU.ln() + 1.0);
    let lr = (2.0 * (ll - ll0_norm)).max(0.0);
    let sigma = (lq.exp() * var_w).sqrt() * scale;
    // Curvature of the profile likelihood in ln q at the optimum: SE(ln sigma) = SE(ln q) / 2.
    let h = 0.05;
    let curv = (ll_at(lt, lq + h) - 2.0 * ll + ll_at(lt, lq - h)) / (h * h);
    let sigma_std = if curv < 0.0 { sigma * 0.5 / (-curv).sqrt() } else { f64::NAN };
    Some(GaussMarkovResult {
        sigma,
        sigma_std,
        tau_s: lt.exp(),
        lr,
        rms_white: s2.sqrt(),
        rms_innovation: e2.sqrt() * scale,
    })
}

// ---------------------------------------------------------------------------------------------------
// Angles files
// ---------------------------------------------------------------------------------------------------

/// One position of an angles file (SPEC.md section 3).
#[derive(Clone, Debug, PartialEq)]
pub struct AnglesRow {
    /// Position label.
    pub pos: u32,
    /// Reference pitch, roll, heading, degrees.
    pub attitude_deg: [f64; 3],
    /// Alignment error (e, n, u), rad.
    pub phi_rad: [f64; 3],
    /// Its standard deviations, rad, if given.
    pub phi_std_rad: Option<[f64; 3]>,
}

/// An angles file.
#[derive(Clone, Debug, PartialEq)]
pub struct AnglesFile {
    /// File name.
    pub source: String,
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// Gravity, m/s^2, if given.
    pub gravity_mps2: Option<f64>,
    /// Positions.
    pub rows: Vec<AnglesRow>,
}

impl AnglesFile {
    /// Parses the text of an angles file.
    pub fn parse(text: &str, source: &str) -> Result<AnglesFile, InputError> {
        let mut latitude = None;
        let mut gravity = None;
        let mut version = None;
        let mut names: Option<(usize, Vec<String>)> = None;
        let mut rows = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let n = i + 1;
            let line = line.trim();
            if line.is_empty() {
                continue;
            }
            if let Some(h) = line.strip_prefix('#') {
                if let Some((k, v)) = h.split_once(':') {
                    let v = v.split_whitespace().next().unwrap_or("");
                    let num = || {
                        v.parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| {
                            InputError::at(source, n, format!("header {}: '{v}' is not a number", k.trim()))
                        })
                    };
                    match k.trim() {
                        "sinscal-angles" => version = Some((n, v.to_string())),
                        "latitude_deg" => latitude = Some(num()?),
                        "gravity_mps2" => gravity = Some(num()?),
                        _ => {}
                    }
                }
                continue;
            }
            let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
            let Some((_, cols)) = &names else {
                names = Some((n, cells.iter().map(|c| c.to_string()).collect()));
                continue;
            };
            if cells.len() != cols.len() {
                return Err(InputError::at(
                    source,
                    n,
                    format!("{} cells, the column line has {}", cells.len(), cols.len()),
                ));
            }
            let get = |name: &str| -> Result<Option<f64>, InputError> {
                match cols.iter().position(|c| c == name) {
                    None => Ok(None),
                    Some(j) => cells[j].parse::<f64>().ok().filter(|v| v.is_finite()).map(Some).ok_or_else(|| {
                        InputError::at(source, n, format!("column '{name}': '{}' is not a finite number", cells[j]))
                    }),
                }
            };
            let need = |name: &str| -> Result<f64, InputError> {
                get(name)?.ok_or_else(|| InputError::at(source, n, format!("missing column '{name}'")))
            };
            let pos = need("pos")?;
            if pos < 1.0 || pos.fract() != 0.0 {
                return Err(InputError::at(source, n, format!("pos {pos} is not a positive integer")));
            }
            let stds = [get("phi_e_std_rad")?, get("phi_n_std_rad")?, get("phi_u_std_rad")?];
            let phi_std_rad = match stds {
                [Some(a), Some(b), Some(c)] if a > 0.0 && b > 0.0 && c > 0.0 => Some([a, b, c]),
                [None, None, None] => None,
                _ => return Err(InputError::at(source, n, "phi_*_std_rad: all three, positive, or none")),
            };
            rows.push(AnglesRow {
                pos: pos as u32,
                attitude_deg: [need("pitch_deg")?, need("roll_deg")?, need("heading_deg")?],
                phi_rad: [need("phi_e_rad")?, need("phi_n_rad")?, need("phi_u_rad")?],
                phi_std_rad,
            });
        }
        match version {
            Some((_, v)) if v == "1" => {}
            Some((n, v)) => {
                return Err(InputError::at(
                    source,
                    n,
                    format!("unsupported angles version '{v}' (this sinscal reads 1)"),
                ))
            }
            None => return Err(InputError::file(source, "not an angles file: no '# sinscal-angles: 1' line")),
        }
        let latitude_deg = latitude.ok_or_else(|| InputError::file(source, "header has no latitude_deg"))?;
        if rows.len() < 3 {
            return Err(InputError::file(source, format!("{} positions; the analysis needs at least 3", rows.len())));
        }
        let with_std = rows.iter().filter(|r| r.phi_std_rad.is_some()).count();
        if with_std != 0 && with_std != rows.len() {
            return Err(InputError::file(source, "standard deviations given for some positions only"));
        }
        Ok(AnglesFile { source: source.into(), latitude_deg, gravity_mps2: gravity, rows })
    }
}

/// Analyses an angles file.
pub fn analyze_angles(file: &AnglesFile) -> Result<Analysis, InputError> {
    let header = crate::io::recording::Header {
        latitude_deg: file.latitude_deg,
        height_m: 0.0,
        rate_hz: None,
        gravity_mps2: file.gravity_mps2,
        comments: Vec::new(),
        truth: None,
    };
    let (site, _) = site_of(&header);
    let g = site.gravity_mps2 as f64;
    let lat = file.latitude_deg.to_radians();
    let w_n = earth_rate_n_radps(lat);
    let f_n = [0.0, 0.0, g];
    let known = file.rows[0].phi_std_rad.is_some();
    let mut y = Vec::new();
    let mut group = Vec::new();
    let mut sigma = Vec::new();
    let mut obs_pos = Vec::new();
    // Per observation: the design row (6 biases) and the sensor-frame predictions of its position.
    let mut design = Vec::new();
    let mut predicted = Vec::new();
    let mut which = Vec::new();
    for (pi, r) in file.rows.iter().enumerate() {
        let c = c_b_n(r.attitude_deg[0], r.attitude_deg[1], r.attitude_deg[2]);
        let c32 = sinscal::math::linalg::Mat3(std::array::from_fn(|i| std::array::from_fn(|j| c[i][j] as f32)));
        let rows = sinscal::calib::solve::design_rows_si(&c32, &site);
        for k in 0..3 {
            y.push(r.phi_rad[k]);
            group.push(if k == 2 { 1 } else { 0 });
            sigma.push(r.phi_std_rad.map_or(1.0, |s| s[k]));
            obs_pos.push(r.pos);
            design.push(std::array::from_fn::<f64, 6, _>(|j| rows[k][j] as f64));
            predicted.push((mul_t_vec(&c, w_n), mul_t_vec(&c, f_n)));
            which.push((pi, k));
        }
    }
    let nobs = y.len();
    let base: Vec<Vec<f64>> = (0..6).map(|j| design.iter().map(|d| d[j]).collect()).collect();
    let base_names = ["gyro_bias_x", "gyro_bias_y", "gyro_bias_z", "accel_bias_x", "accel_bias_y", "accel_bias_z"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let mut candidates = Vec::new();
    let single = |effect, sensor, axes: String, unit, col: Vec<f64>| Candidate {
        effect,
        sensor,
        axes,
        pos: None,
        unit,
        variants: vec![(None, col)],
        groups: vec![0, 1],
    };
    // A sensor error at a position maps to the angles through the design rows.
    for t in sensor_terms(true) {
        let col = (0..nobs).map(|i| design[i][t.channel] * t.per_unit(predicted[i].0, predicted[i].1)).collect();
        candidates.push(single(t.effect, t.sensor, t.axes, t.unit, col));
    }
    for k in 0..3 {
        let col: Vec<f64> = which.iter().map(|&(_, kk)| if kk == k { 1.0 } else { 0.0 }).collect();
        candidates.push(Candidate {
            groups: vec![if k == 2 { 1 } else { 0 }],
            ..single("reference_offset", "reference", ENU[k].into(), "rad", col)
        });
    }
    for (pi, r) in file.rows.iter().enumerate() {
        for k in 0..3 {
            let col: Vec<f64> = which.iter().map(|&(p, kk)| if p == pi && kk == k { 1.0 } else { 0.0 }).collect();
            candidates.push(Candidate {
                pos: Some(r.pos),
                groups: vec![if k == 2 { 1 } else { 0 }],
                ..single("position_error", "reference", ENU[k].into(), "rad", col)
            });
        }
    }
    let mut problem = Problem {
        obs: Observations { y, group, groups: 2, sigma: if known { Some(sigma) } else { None } },
        base,
        base_names,
        group_names: vec!["phi_en_rad".into(), "phi_u_rad".into()],
        group_units: vec!["rad", "rad"],
        obs_pos,
        candidates,
        unobservable: Vec::new(),
        residual_of: "angles",
    };
    let selection = select(&mut problem, 0).map_err(|e| InputError::file(&file.source, e))?;
    let m = selection.observable as f64;
    let mut effects: Vec<Effect> = (0..selection.chosen.len()).map(|i| effect_of(&problem, &selection, i)).collect();
    effects.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    let mut residual_rms = std::collections::BTreeMap::new();
    for (gi, name) in problem.group_names.iter().enumerate() {
        residual_rms.insert(name.clone(), selection.base_fit.rms[gi]);
    }
    let figures = FigureData {
        residuals: residuals_by_group(&problem, &selection),
        residual_names: problem.group_names.clone(),
        ..FigureData::default()
    };
    Ok(finish(
        problem,
        selection,
        effects,
        residual_rms,
        Default::default(),
        nobs,
        m,
        "angles",
        &file.source,
        Vec::new(),
        figures,
    ))
}

/// Reads `path` as an angles file when it starts with `# sinscal-angles`, otherwise as a recording, and
/// analyses it.
pub fn analyze_path(path: &Path) -> Result<Analysis, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
    let source = path.display().to_string();
    if text.lines().take(20).any(|l| l.trim_start().starts_with("# sinscal-angles")) {
        analyze_angles(&AnglesFile::parse(&text, &source)?)
    } else {
        analyze_recording(&Recording::parse(&text, &source)?)
    }
}

/// Human summary of an analysis (units stated).
pub fn summary(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "analysis of {} ({})", a.source, a.input);
    let _ = writeln!(
        s,
        "base model: constant biases + white noise, {} observations, ln L = {:.2}, BIC = {:.2}",
        a.base_model.observations, a.base_model.log_likelihood, a.base_model.bic
    );
    for (k, v) in &a.base_model.residual_rms {
        let _ = writeln!(s, "  residual RMS {k}: {v:.4e}");
    }
    let _ = writeln!(s, "criterion: {}", a.criterion);
    if a.effects.is_empty() {
        let _ = writeln!(s, "verdict: none (the base model is adequate)");
    } else {
        let _ = writeln!(s, "verdict: {}", a.verdict);
        for e in &a.effects {
            let _ = write!(
                s,
                "  {:<20} {:<9} {:<4} estimate {:+.4e} +- {:.2e} {}  delta BIC {:.1}  residual RMS {:.3e} -> {:.3e} {} ({})",
                e.effect,
                e.sensor,
                e.axes,
                e.estimate,
                e.std_error,
                e.unit,
                e.delta_bic,
                e.residual_rms_before,
                e.residual_rms_after,
                e.residual_unit,
                e.residual_of
            );
            let extras = e.extras();
            if !extras.is_empty() {
                let _ = write!(s, "  {extras}");
            }
            if !e.aliases.is_empty() {
                let _ = write!(s, "  (indistinguishable here from: {})", e.aliases.join(", "));
            }
            let _ = writeln!(s);
        }
    }
    if !a.unobservable.is_empty() {
        let _ = writeln!(s, "unobservable with this data: {}", a.unobservable.join(", "));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attitude_columns_map_to_the_angles_they_are() {
        // The alignment equations (the core's design rows) applied to the sensor signature of a table
        // attitude error err, C^T (e_k x v), give err back: the sign convention of the recording analysis
        // (C_true = (I - [err x]) C_ref) is the one of the angles and of METHOD.md's phi0.
        let lat = 45.7796f64.to_radians();
        let site = sinscal::nav::earth::Site::with_normal_gravity(lat as f32, 0.0);
        let g = site.gravity_mps2 as f64;
        let w_n = earth_rate_n_radps(lat);
        for att in crate::model::synth::TABLE1_DEG {
            let c = c_b_n(att[0], att[1], att[2]);
            let c32 = sinscal::math::linalg::Mat3(std::array::from_fn(|i| std::array::from_fn(|j| c[i][j] as f32)));
            let rows = sinscal::calib::solve::design_rows_si(&c32, &site);
            for k in 0..3 {
                let dw = mul_t_vec(&c, cross(unit(k), w_n));
                let df = mul_t_vec(&c, cross(unit(k), [0.0, 0.0, g]));
                for (r, row) in rows.iter().enumerate() {
                    let phi: f64 = (0..3).map(|j| row[j] as f64 * dw[j] + row[3 + j] as f64 * df[j]).sum();
                    let want = if r == k { 1.0 } else { 0.0 };
                    assert!((phi - want).abs() < 1e-5, "att {att:?} k {k} row {r}: {phi}");
                }
            }
        }
    }
}
