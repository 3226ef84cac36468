//! `sinscal analyze`: what the base model (constant biases and white noise) gets wrong in a recording or an
//! angles file, which effect of the catalogue ([`crate::model::catalogue`], docs/formats.md#effect-catalogue)
//! explains it, and how much that gains. The method is described in docs/analysis.md, the output in
//! docs/formats.md#analysis-json.
//!
//! # The flow for a recording ([`analyze_recording`])
//! 1. `observations`: every dwell is read with its reference attitude and cut into blocks (about 6 s, at
//!    most 200 per dwell). The observations are the block means of the six channels minus what the reference
//!    attitude predicts (`C^T W_ie^n` for the gyros, `C^T [0, 0, g]` for the accelerometers). The base model
//!    is one bias per channel and white noise with one variance per channel.
//! 2. `candidates`: every effect of the catalogue that is linear in its parameter adds one column:
//!    - scale factors, misalignments, g-sensitivity: the predicted rate or force of the block, on the sensed
//!      axis (the sensor model of docs/conventions.md);
//!    - reference offset and position error (a table attitude error `err`, `C_true = (I - [err x]) C_ref`,
//!      the convention of `sinscal simulate` and of `phi0` in docs/method.md): `C^T (e_k x v)` for `v` =
//!      Earth rate and gravity, on all six channels (of one dwell for a position error);
//!    - bias drift: block time; temperature: block mean temperature;
//!    - warm-up `A exp(-(t - t0)/tau)` (t0 = first row): the block mean of the exponential, with `tau`
//!      profiled over a logarithmic grid (two parameters).
//! 3. `selection`: forward selection over these columns (below). The noise variances are estimated with the
//!    coefficients (profile likelihood, [`crate::stats::linfit`]).
//! 4. `sample_tests`: faster effects are tested on the samples themselves, after each dwell's mean and trend
//!    are removed:
//!    - vibration (`vibration`): the largest line of the periodogram summed over dwells, against the median
//!      of its neighbourhood (a line, not a coloured background); amplitude corrected for the interval
//!      averaging of an integrating sensor (`sinc(f dt)`);
//!    - correlated noise (`correlated_noise`): exact Gaussian likelihood of a first-order Gauss-Markov
//!      process plus white noise (Kalman filter), against white noise alone;
//!    - quantisation: the fraction of sample differences on a lattice
//!      ([`crate::stats::noise::detect_quantization`]), against the fraction continuous data give, as a
//!      binomial likelihood ratio.
//! 5. `result`: the effects found, ranked, the base model, the verdict and the criterion in words
//!    make the [`Analysis`]; `summary` ([`summary()`]) is its human text, [`crate::analysis::report`] its
//!    report directory.
//!
//! # Criterion
//! Forward selection: at each step every candidate not yet chosen is fitted together with the chosen ones;
//! the one with the largest likelihood-ratio statistic `LR = 2 (ln L1 - ln L0)` is added if its p-value
//! (chi-square with the candidate's number of parameters) is below `alpha / m` (Bonferroni over the `m`
//! candidates tested, family-wise `alpha` = [`ALPHA`]) and its `delta_bic = -LR + k ln n` is negative.
//! A candidate the criterion admits at a value no plausible instrument has is a misfit, not an effect; one
//! whose estimate correlates beyond [`ALIAS_CORRELATION`] with a chosen one's is named as that one's alias;
//! a time term that only the differences between poses support carries "pose order" as an alias
//! (docs/analysis.md#plausibility, #confounding). Candidates that the base model explains completely (a zero
//! or dependent column) are `unobservable`. Column effects carry their consequence, the error that leaving
//! them out induces in the biases, in standard errors; they rank before the noise effects
//! (docs/analysis.md#verdict).
//!
//! # Angles files ([`analyze_angles`], `angles`)
//! The observations are the per-position angles (docs/formats.md#angles); the base model is the six biases
//! mapped through the alignment equations of docs/method.md (the core's design rows); sensor effects are
//! mapped the same way, the reference offset and position errors enter directly. Time-dependent and noise
//! effects are unobservable. The same selection and result steps follow.
//!
//! The hidden-effect trials (simulated sessions with one effect of the catalogue hidden) are the laboratory's
//! (the crate sinscal-lab, host-tests/lab/).

mod angles;
mod candidates;
mod checks;
mod column;
mod correlated_noise;
mod disturbance;
mod model_fit;
pub mod noise_terms;
mod noise_warmup;
mod observations;
mod parallel;
mod recording;
pub mod report;
mod result;
mod sample_colour;
mod sample_tests;
mod selection;
mod settling;
mod summary;
mod vibration;
mod wander;
mod windows;

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::io::error::InputError;
use crate::io::recording::RecordingFile;

pub use angles::{analyze_angles, AnglesFile, AnglesRow};
pub use disturbance::Disturbances;
pub use model_fit::{DwellFit, GroupFit, ModelFit};
pub use recording::analyze_recording;
pub use settling::{Settling, SettlingTest};
pub use summary::summary;
pub use windows::{WindowCheck, WindowParameter};

/// Family-wise significance level of the effect search.
pub const ALPHA: f64 = 0.01;
/// Candidates whose estimates (or base-free columns) correlate beyond this are indistinguishable in the
/// data: aliases, reported as one effect, not two.
pub const ALIAS_CORRELATION: f64 = 0.95;
/// Target block length, samples (6 s at 100 Hz).
pub const BLOCK_SAMPLES: usize = 600;
/// Most blocks per dwell.
pub const MAX_BLOCKS_PER_DWELL: usize = 200;
/// Fewest samples a dwell needs.
pub const MIN_DWELL_SAMPLES: usize = 64;
/// Most effects the forward selection adds.
pub const MAX_EFFECTS: usize = 24;
/// Channel names (the recording's columns).
pub const CHANNELS: [&str; 6] = ["gx_radps", "gy_radps", "gz_radps", "ax_mps2", "ay_mps2", "az_mps2"];
/// Units of the channels.
const CHANNEL_UNITS: [&str; 6] = ["rad/s", "rad/s", "rad/s", "m/s^2", "m/s^2", "m/s^2"];
/// Body axis names.
const AXES: [&str; 3] = ["x", "y", "z"];
/// Navigation axis names.
const ENU: [&str; 3] = ["e", "n", "u"];

/// One effect the data support (docs/formats.md#analysis-json, with extra fields).
#[derive(Clone, Debug, Serialize)]
pub struct Effect {
    /// Catalogue name ([`crate::model::catalogue::EffectKind::name`]).
    pub effect: String,
    /// "gyro", "accel" or "reference" ([`crate::model::catalogue::Sensor::name`]).
    pub sensor: String,
    /// Axis or axis pair.
    pub axes: String,
    /// Position label (position errors only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pos: Option<u32>,
    /// The other face of an up/down pair whose tilt the position error shares (docs/analysis.md#tilts).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pair_pos: Option<u32>,
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
    /// The noise's warm-up (docs/analysis.md#noise-warm-up): the time after the record's first sample at which
    /// the noise has settled, s. The channel's correlated noise is fitted on the samples after it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settled_after_s: Option<f64>,
    /// Frequency, Hz (vibration: of its strongest component).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
    /// A line whose frequency wanders (docs/analysis.md#lines): the span of its components' frequencies, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_spread_hz: Option<f64>,
    /// Likelihood-ratio statistic.
    pub likelihood_ratio: f64,
    /// Parameters the effect adds.
    pub parameters: usize,
    /// p-value of the likelihood ratio, before the Bonferroni factor.
    pub p_value: f64,
    /// Other candidates this data set cannot tell apart from this one.
    pub aliases: Vec<String>,
    /// Other candidates that explained the data nearly as well when this one was chosen (a BIC gain within 6
    /// of its own: a Bayes factor below 20), not among `aliases` (docs/analysis.md#rivals).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rivals: Vec<String>,
    /// Its standard error once the worst of its aliases (those of `aliases` that are candidates) is fitted
    /// beside it, SI: what the estimate is worth when the data cannot tell which of them it is
    /// (docs/analysis.md#confounding). Absent when none of its aliases is a candidate; `null` when the data
    /// determine only their combination, not this effect's share.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_error_with_aliases: Option<Option<f64>>,
    /// What the effect does to the calibration if it is left out (block effects; the noise effects move
    /// no estimate).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub consequence: Option<Consequence>,
    /// The profiled time constant sits at an end of its grid: it is not determined by the data.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub at_grid_edge: bool,
    /// Ranked with the uncertain effects (docs/analysis.md#verdict): a time term confounded with pose order,
    /// the session's halves or the bias's wander, a noise term that differs between the thirds of the
    /// dwells, or a column effect whose time constant is an end of its grid. Set when the effects are ranked.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub uncertain: bool,
}

/// A candidate the criterion admitted that its own standard error cannot tell from zero.
#[derive(Clone, Debug, Serialize)]
pub struct UnsupportedEffect {
    /// The candidate ("accel_nonlinearity:y").
    pub candidate: String,
    /// Its estimate in the first selection's final model, SI.
    pub estimate: f64,
    /// Its standard error there, with the bias's wander, SI.
    pub std_error: f64,
    /// The SI unit of both.
    pub unit: String,
}

impl UnsupportedEffect {
    /// One line: "accel_nonlinearity:y: estimate +1.19e-5 +- 1.85e-5 1/(m/s^2), within the criterion of zero
    /// by its own standard error: not an effect".
    pub fn text(&self) -> String {
        format!(
            "{}: estimate {:+.3e} +- {:.2e} {}, within the criterion of zero by its own standard error (with the \
             bias's wander): not an effect",
            self.candidate, self.estimate, self.std_error, self.unit
        )
    }
}

/// A candidate that still passed the criterion when the forward selection reached its most effects.
#[derive(Clone, Debug, Serialize)]
pub struct CutShort {
    /// The candidate ("accel_nonlinearity:y").
    pub candidate: String,
    /// Its likelihood ratio against the final model.
    pub likelihood_ratio: f64,
}

/// The error an effect induces in the base model's biases when it is left out (docs/analysis.md#verdict).
#[derive(Clone, Debug, Serialize)]
pub struct Consequence {
    /// The bias it moves most ("accel_bias_z").
    pub bias: String,
    /// By how much, SI.
    pub bias_error: f64,
    /// The same in units of that bias's standard error.
    pub in_std_errors: f64,
}

/// A catalogue effect the criterion admits only at a value no plausible instrument has: the model misses
/// something there (docs/analysis.md#plausibility).
#[derive(Clone, Debug, Serialize)]
pub struct Misfit {
    /// The candidate ("position_error:e:pos3").
    pub candidate: String,
    /// The value the fit needs, SI.
    pub estimate: f64,
    /// Its standard error, SI.
    pub std_error: f64,
    /// The plausible limit it exceeds, SI.
    pub limit: f64,
    /// Unit of the three.
    pub unit: String,
    /// Where the fit puts it most: position label.
    pub pos: u32,
    /// ... and channel (or angle group).
    pub channel: String,
}

/// A time term (drift, warm-up, temperature) that the criterion admits but that a pose-by-pose offset
/// explains as well: time and pose order are confounded in this data (docs/analysis.md#confounding). When
/// the dwells themselves contradict it (`contradicted`), it is not an effect.
#[derive(Clone, Debug, Serialize)]
pub struct Confounded {
    /// The candidate ("bias_drift:x (accel)").
    pub candidate: String,
    /// Its likelihood ratio against the model chosen so far.
    pub likelihood_ratio: f64,
    /// Its likelihood ratio once every pose has its own offsets.
    pub likelihood_ratio_within_poses: f64,
    /// Its estimate across the session, SI (the candidate's unit).
    pub estimate: f64,
    /// Its estimate once every pose has its own offsets (what the dwells show within themselves), SI.
    pub estimate_within_poses: f64,
    /// The standard error of `estimate_within_poses`, SI.
    pub std_error_within_poses: f64,
    /// The SI unit of the three.
    pub unit: String,
    /// The within-pose estimate contradicts the session's (beyond 3 of its standard errors): the term is not
    /// an effect (the poses' differences, such as tilts off their labels, are); otherwise it is one, marked
    /// with the alias "pose order".
    pub contradicted: bool,
}

impl Effect {
    /// The channel of a per-channel effect (gyro x: 0, ... accelerometer z: 5, as [`CHANNELS`]); `None` for the
    /// reference's effects and an axis pair.
    pub fn channel(&self) -> Option<usize> {
        let first = match self.sensor.as_str() {
            "gyro" => 0,
            "accel" => 3,
            _ => return None,
        };
        AXES.iter().position(|a| *a == self.axes).map(|a| first + a)
    }

    /// The standard error as printed: "exact" for 0 (a quantisation step on which every difference lies),
    /// otherwise three significant digits.
    pub fn std_error_text(&self) -> String {
        if self.std_error == 0.0 {
            "exact".to_string()
        } else {
            format!("{:.2e}", self.std_error)
        }
    }

    /// The standard error the estimate carries whichever of its aliases the data are given to (SI): with
    /// aliases, `std_error_with_aliases` (never below `std_error`); `None` when the data determine only its
    /// combination with an alias (docs/analysis.md#confounding).
    pub fn std_error_across_models(&self) -> Option<f64> {
        match self.std_error_with_aliases {
            None => Some(self.std_error),
            Some(with_aliases) => with_aliases.map(|s| s.max(self.std_error)),
        }
    }

    /// The aliases in words, with what the estimate is worth apart from them: "indistinguishable here from:
    /// a, b; with them: +- 1.23e-4" (or "...; with them: not determined, only the combination is"); empty
    /// without aliases.
    pub fn aliases_text(&self) -> String {
        if self.aliases.is_empty() {
            return String::new();
        }
        let mut text = format!("indistinguishable here from: {}", self.aliases.join(", "));
        match self.std_error_with_aliases {
            Some(Some(s)) => text += &format!("; with them: +- {s:.2e}"),
            Some(None) => text += "; with them: not determined, only the combination is",
            None => {}
        }
        text
    }

    /// The rivals in words: "nearly as good here (Bayes factor below 20): a, b"; empty without rivals.
    pub fn rivals_text(&self) -> String {
        if self.rivals.is_empty() {
            return String::new();
        }
        format!("nearly as good here (Bayes factor below 20): {}", self.rivals.join(", "))
    }

    /// The extra fields in words: "pos 3", "tau 1.234 s", "f 7.3000 Hz" (comma-separated, empty if none).
    pub fn extras(&self) -> String {
        let mut parts = Vec::new();
        match (self.pos, self.pair_pos) {
            (Some(p), Some(q)) => parts.push(format!("pos {p} and {q} (shared)")),
            (Some(p), None) => parts.push(format!("pos {p}")),
            _ => {}
        }
        if let Some(t) = self.tau_s {
            parts.push(format!("tau {t:.3} s"));
        }
        if let Some(t) = self.settled_after_s {
            parts.push(format!("settled after {t:.1} s"));
        }
        if let Some(f) = self.frequency_hz {
            parts.push(format!("f {f:.4} Hz"));
        }
        if let Some(s) = self.frequency_spread_hz {
            parts.push(format!("its frequency wanders over {s:.4} Hz"));
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
    pub residual_rms: BTreeMap<String, f64>,
    /// RMS residual of the block means per channel (recordings only).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub block_residual_rms: BTreeMap<String, f64>,
    /// Log-likelihood of the block means (angles: of the angles).
    pub log_likelihood: f64,
    /// Its BIC.
    pub bic: f64,
    /// Observations the likelihood is over.
    pub observations: usize,
    /// Estimated biases, SI, by name ("gyro_bias_x", ...).
    pub biases: BTreeMap<String, f64>,
}

/// One candidate as tested against the base model alone (the whole catalogue that the data can see).
#[derive(Clone, Debug, Serialize)]
pub struct Tested {
    /// "effect:axes" (position errors: "position_error:e:pos3").
    pub name: String,
    /// Estimate, SI, fitted with the base model alone.
    pub estimate: f64,
    /// Its standard error: the larger of the fit's and the one with each channel's random walk of the bias
    /// (docs/analysis.md#windows).
    pub std_error: f64,
    /// Likelihood-ratio statistic against the base model.
    pub likelihood_ratio: f64,
    /// The candidate and its variant tested (indices into the analysis's candidates).
    #[serde(skip)]
    pub(crate) column: (usize, usize),
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
    /// Quantisation step if the samples lie on a lattice (not the one of their printed digits).
    pub quantization_step: Option<f64>,
    /// The step of the decimal digits the samples were printed with (`10^-d`), if every sample is a whole
    /// multiple of one: a lattice at this step is the file's, not the sensor's quantisation.
    pub print_step: Option<f64>,
    /// The noise's colour at the scale of a few samples (the sensor's own filter): the coefficients
    /// `[theta_1, theta_2]` of the moving average `w_t + theta_1 w_(t-1) + theta_2 w_(t-2)` of white noise
    /// that the detrended samples are, dimensionless; the correlated-noise test runs on the samples freed of
    /// it (docs/analysis.md#the-noise-at-the-scale-of-a-few-samples).
    pub sample_colour_ma: [f64; 2],
    /// Seconds whose noise stands far above the channel's own level (docs/analysis.md#disturbances); absent
    /// when none does. The noise terms include them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disturbances: Option<Disturbances>,
}

/// The result of `sinscal analyze` (docs/formats.md#analysis-json, with extra fields).
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
    /// Effects found, ranked (docs/analysis.md#verdict).
    pub effects: Vec<Effect>,
    /// Catalogue entries this data set cannot see.
    pub unobservable: Vec<String>,
    /// Effects the data want at impossible values.
    pub misfits: Vec<Misfit>,
    /// Time terms confounded with the order of the poses.
    pub confounded: Vec<Confounded>,
    /// Candidates the criterion admitted on the likelihood of white block means whose estimate their own
    /// standard error (with the bias's wander) cannot tell from zero: not effects; the selection ran again
    /// without them (docs/analysis.md#criterion).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub unsupported: Vec<UnsupportedEffect>,
    /// `effects[0].effect` or "none".
    pub verdict: String,
    /// The criterion, in words, with its numbers.
    pub criterion: String,
    /// Family-wise significance level.
    pub alpha: f64,
    /// Candidates tested (m of the Bonferroni correction).
    pub candidates_tested: usize,
    /// The forward selection stopped at its most effects ([`MAX_EFFECTS`]) while a candidate still passed
    /// the criterion: that candidate and its likelihood ratio (docs/analysis.md#criterion). The final model
    /// is then incomplete, and the `selection` check fails.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cut_short: Option<CutShort>,
    /// Every candidate against the base model alone.
    pub tested: Vec<Tested>,
    /// Per-channel diagnostics (recordings).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub diagnostics: Vec<ChannelDiagnostics>,
    /// Per channel: the noise terms named from the Allan variance of the longest dwell (recordings).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub noise_model: Vec<noise_terms::NoiseModel>,
    /// The verdict on the final model: its block-mean residuals against the noise model, and what is still
    /// unexplained (recordings; docs/analysis.md#model-fit).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub model_fit: Option<ModelFit>,
    /// The final model fitted again on each third of every dwell: do its standard errors hold across them
    /// (recordings; docs/analysis.md#windows)?
    #[serde(skip_serializing_if = "Option::is_none")]
    pub windows: Option<WindowCheck>,
    /// Settling after a move (docs/analysis.md#settling-after-a-move): the seconds left out at the start and
    /// end of the dwells whose first or last half-seconds differ from their rest beyond its noise; absent when
    /// none do (and for angles).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settling: Option<settling::Settling>,
    /// The checks of the analysis (docs/cli.md#checks): `fit` (recordings) and `plausibility`, passed or
    /// failed; a failed one makes `analyze` exit with status 3.
    pub checks: Vec<crate::calibration::checks::Check>,
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
    /// Per channel: the spectral lines found (amplitude as seen, frequency), strongest first.
    pub vibration: Vec<Vec<(f64, f64)>>,
    /// Per channel: each one-second block's time after the record's first row (s) and standard deviation
    /// (channel unit), in time order (the noise warm-up's test: docs/analysis.md#noise-warm-up).
    pub noise_level: Vec<Vec<(f64, f64)>>,
    /// Per observation group (channel or angle): (position label, base residual, final residual) of each
    /// observation.
    pub residuals: Vec<Vec<(u32, f64, f64)>>,
    /// Group names of `residuals`, with units.
    pub residual_names: Vec<String>,
}

/// One line on a time term confounded with pose order: its likelihood ratios and estimates across the
/// session and within the poses, and whether it stays an effect.
fn confounded_text(c: &Confounded) -> String {
    let (what, verdict) = if c.contradicted {
        ("not an effect", "the dwells contradict it: the differences between the poses (tilts off their labels, for one) are not a time term")
    } else {
        ("an uncertain effect", "a pose-dependent term explains it as well")
    };
    format!(
        "confounded with pose order, {what}: {} (likelihood ratio {:.1}; {:.1} once every pose has its own offset; \
         estimate {:+.3e} {u} across the session, {:+.3e} +- {:.2e} {u} within the poses: {verdict})",
        c.candidate,
        c.likelihood_ratio,
        c.likelihood_ratio_within_poses,
        c.estimate,
        c.estimate_within_poses,
        c.std_error_within_poses,
        u = c.unit,
    )
}

/// The most memory the selection's candidate columns may take, bytes (docs/analysis.md#memory-limit).
pub const MAX_COLUMN_BYTES: u64 = 768 << 20;

/// Bytes the selection holds per entry of a candidate's column: the entry (a value and its index) and the
/// scores' and exact fits' working copies.
const BYTES_PER_COLUMN_ENTRY: u64 = 16;

/// Refuses `what` when its candidates' column `entries` would pass [`MAX_COLUMN_BYTES`], before any is built.
fn check_column_memory(what: &str, observations: usize, entries: u64, source: &str) -> Result<(), InputError> {
    let bytes = entries * BYTES_PER_COLUMN_ENTRY;
    if bytes <= MAX_COLUMN_BYTES {
        return Ok(());
    }
    Err(InputError::file(
        source,
        format!(
            "analyze: {what} give {observations} observations and {entries} candidate column entries, {} MB of \
             columns, beyond the {} MB the analysis holds (docs/analysis.md#memory-limit): analyze fewer at a time",
            bytes >> 20,
            MAX_COLUMN_BYTES >> 20
        ),
    ))
}

/// What a noise warm-up of channel `channel` (0 to 5, gx to az) of `recording` that settles at `settled_s` after
/// its first row must exceed (docs/analysis.md#noise-warm-up): the standard error of the test's difference of
/// mean log-variances of one-second blocks before and after, and the settled blocks' mean variance (channel
/// unit squared). `None` when either side has too few blocks. For the campaign of planted effects.
pub fn noise_warmup_scale(
    recording: &impl crate::io::recording::RowSource,
    channel: usize,
    settled_s: f64,
) -> Result<Option<(f64, f64)>, InputError> {
    let session = observations::Session::read(recording)?;
    let series: Vec<Vec<f64>> =
        session.dwells.iter().map(|d| sample_tests::detrend(&d.t, &d.y[channel]).residual).collect();
    let times: Vec<&[f64]> = session.dwells.iter().map(|d| &d.t[..]).collect();
    Ok(noise_warmup::scale_at(&series, &times, session.t0, session.dt, settled_s))
}

/// Reads `path` as an angles file when it starts with `# sinscal-angles`, otherwise as a recording (line by
/// line, docs/analysis.md#speed-and-memory), and analyses it.
pub fn analyze_path(path: &Path) -> Result<Analysis, InputError> {
    use std::io::BufRead;
    let file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
    let mut is_angles = false;
    for line in std::io::BufReader::new(file).lines().take(20) {
        is_angles |= line.map_err(|e| InputError::io(path, e))?.trim_start().starts_with("# sinscal-angles");
    }
    if is_angles {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
        analyze_angles(&AnglesFile::parse(&text, &path.display().to_string())?)
    } else {
        recording::analyze_recording(&RecordingFile::open(path)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_past_the_limit_are_refused_before_they_are_built() {
        // 48 Mi entries of 16 bytes are the 768 MB; one more is refused, with the numbers.
        let limit_entries = MAX_COLUMN_BYTES / BYTES_PER_COLUMN_ENTRY;
        assert!(check_column_memory("10000 dwells", 2_000_000, limit_entries, "x.csv").is_ok());
        let err = check_column_memory("10000 dwells", 2_000_000, limit_entries + 1, "x.csv").unwrap_err().to_string();
        assert!(err.contains("10000 dwells give 2000000 observations and 50331649 candidate column entries"), "{err}");
        assert!(err.contains("768 MB of columns, beyond the 768 MB"), "{err}");
    }
}
