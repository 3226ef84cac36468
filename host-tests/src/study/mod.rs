//! `sinscal study`: measured data against a SIMULATION of them, the disagreement named and the model extended.
//!
//! For one of the three measured data sets (PSINS laser gyro, imucal Ferraris session, imu_tk Xsens session;
//! docs/data.md) or any recording given by path ([`recording`]: single pose or at least six poses, labelled
//! unless levelled from its own accelerometers, gravity and rate from its header) a study
//! 1. fits the BASE model: in every static pose a constant mean per channel plus white noise. The white noise's
//!    standard deviation per sample is the data's sample-to-sample noise, the overlapping Allan deviation at the
//!    shortest tau (one sample), which equals the RMS of the first differences divided by sqrt 2 (pooled over the
//!    static poses). For the multi-pose sets the pose means are tied together by the physics of a bias-only
//!    sensor: the accelerometer measures a force of magnitude g plus one constant bias in every pose (direction:
//!    the pose's label for Ferraris, the data's own direction for imu_tk), the gyro one constant bias;
//! 2. SIMULATES the data set with that model (same time stamps, same poses, seeded: reproducible);
//! 3. measures where the data and the SIMULATION disagree (Allan deviation per channel; per pose the norm of the
//!    mean specific force minus g; per pose the gyro means), with PNG figures;
//! 4. names the cause from those numbers ([`Cause`]);
//! 5. extends the model (IEEE Std 952 noise terms with a generator for them; accelerometer scale factors and
//!    misalignments; gyro g-sensitivity or drift; the Ferraris turns' gyro scale factors);
//! 6. measures the gain on data not used for the fit (second half of the record, odd poses, or the left-out pose);
//!    a term of the extended noise model stays only when it improves the held-out half significantly (the gate
//!    of [`noise_extension`]: chi^2 rise of at least max(9, 10 %) when it is removed; a sinusoid must also be
//!    found by a direct fit), and the dropped terms are reported with why.
//!
//! Every simulated number is labelled SIMULATION. Units inside: SI; the human text says its units. What the
//! studies find: docs/data.md#what-sinscal-study-finds; the command: docs/cli.md#study.
//!
//! | file | what |
//! |---|---|
//! | `mod.rs` | the data sets, the result types, reading a data set and [`run`] |
//! | [`recording`] | any recording by path: which study, poses labelled or not, gravity, rate, turns |
//! | [`noise`] | one channel's noise: the white base model, its SIMULATION, the Allan disagreement |
//! | [`noise_extension`] | the IEEE 952 (and band-limited) noise model: its fit, the held-out gate of its terms, its gain on the second half |
//! | [`generate`] | the seeded noise generators of the SIMULATIONs |
//! | [`psins`] | the single-pose study (PSINS laser gyro): noise and the vehicle sway test |
//! | [`multi_pose`] | the pose studies (Ferraris, imu_tk): poses, noise, SIMULATIONs, held-out gains |
//! | [`accel`] | the accelerometer pose models (bias only; scale factors and misalignments) |
//! | [`gyro`] | the gyro pose means (scatter, drift, g-sensitivity) and the Ferraris turns |
//! | [`factory`] | imu_tk: the fitted accelerometer against the factory calibration |
//! | [`causes`] | naming the causes from the numbers |
//!
//! The summary, the JSON and the figures are written by [`crate::study::report`].

pub mod accel;
pub mod accel_gate;
pub mod causes;
pub mod factory;
pub mod generate;
pub mod gyro;
pub mod multi_pose;
pub mod noise;
pub mod noise_extension;
pub mod psins;
pub mod recording;
pub mod report;
pub mod rests;
pub mod rotations;

use std::path::{Path, PathBuf};

use crate::io::error::InputError;
use crate::io::import::{
    import_imucal, import_imutk, import_psins, parse_imucal_labels, StaticDetection, FERRARIS_ROTATIONS,
    IMUCAL_RATE_HZ, IMUTK_GRAVITY_MPS2,
};
use crate::io::recording::{Recording, Row, RowSource};
use crate::model::synth::{mul_vec, DEG_PER_HOUR, M3, MICRO_G};
use crate::stats::noise::NoiseTerms;
use crate::stats::solve::inverse3;
use multi_pose::{study_multi_pose, PoseKind};
use noise_extension::{ExtraTerm, TermGate};
use psins::study_single_pose;

/// Seed of every SIMULATION of a study (the same seed gives the same numbers).
pub const STUDY_SEED: u64 = 952;

/// Schema name of the study JSON.
pub const SCHEMA: &str = "sinscal-study/1";

/// Channel names, gyro x, y, z then accelerometer x, y, z.
pub const CHANNELS: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// A data ADEV above this multiple of the white-noise SIMULATION's at the longest reliable tau is called
/// correlated noise (dimensionless; the relative uncertainty there is at most 0.25).
pub const CORRELATED_RATIO: f64 = 2.0;

/// A per-pose spread above this multiple of what white noise predicts is called a model error (dimensionless).
pub const POSE_SPREAD_RATIO: f64 = 3.0;

/// A labelled turn of a Ferraris session: (label, body axis 0..3, range of rows of the recording).
pub type LabelledTurn = (String, usize, std::ops::Range<usize>);

/// The measured data sets a study knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Dataset {
    /// PSINS ring-laser-gyro IMU, one static pose on a parked vehicle (psins-lasergyro/lasergyro.imu;
    /// docs/data.md#psins-lasergyro).
    Psins,
    /// imucal consumer MEMS IMU, six labelled poses and three turns
    /// (imucal-ferraris/example_ferraris_session.csv + _list.json; docs/data.md#imucal-ferraris).
    Ferraris,
    /// imu_tk Xsens MTi counts, about 38 hand-placed poses (imu-tk-xsens/xsens_acc.mat + xsens_gyro.mat;
    /// docs/data.md#imu-tk-xsens).
    Imutk,
}

impl Dataset {
    /// The name on the command line and in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Psins => "psins",
            Dataset::Ferraris => "ferraris",
            Dataset::Imutk => "imutk",
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Results

/// One Allan deviation curve: averaging times, s, and deviations in the channel's SI unit (rad/s or m/s^2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Curve {
    /// Averaging times tau, s.
    pub tau_s: Vec<f64>,
    /// Allan deviation at each tau, SI unit of the channel.
    pub adev: Vec<f64>,
}

/// The noise of one channel: data against the base (white) and extended (IEEE 952 terms) SIMULATIONs.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelNoise {
    /// Channel name (`gx` ... `az`).
    pub channel: &'static str,
    /// White-noise standard deviation per sample of the base model, SI (rad/s or m/s^2): the ADEV at one sample
    /// = RMS of first differences / sqrt 2, pooled over the static poses.
    pub white_std: f64,
    /// Sample-rate, Hz.
    pub rate_hz: f64,
    /// ADEV of the data (whole record, or the longest pose of a multi-pose set).
    pub data: Curve,
    /// ADEV of the base SIMULATION of the same samples.
    pub base_sim: Curve,
    /// The longest averaging time with a relative ADEV uncertainty of at most 0.25, s.
    pub long_tau_s: f64,
    /// ADEV(data) / ADEV(base SIMULATION) at `long_tau_s` (dimensionless): the disagreement.
    pub ratio_at_long_tau: f64,
    /// RMS over tau of log10(ADEV base SIMULATION / ADEV data), whole record (dimensionless).
    pub rms_log10_base: f64,
    /// Output step found in the data (SI), if the channel looks quantised.
    pub quantization_step: Option<f64>,
    /// The extension, fitted on the first half and evaluated on the second (single-pose records only).
    pub extended: Option<NoiseExtension>,
}

impl ChannelNoise {
    /// The Allan deviations of the data and of the base SIMULATION at `long_tau_s` (NaN where missing), SI.
    pub fn adev_at_long_tau(&self) -> (f64, f64) {
        let li = self.data.tau_s.iter().rposition(|t| *t <= self.long_tau_s * 1.0001).unwrap_or(0);
        (self.data.adev.get(li).copied().unwrap_or(f64::NAN), self.base_sim.adev.get(li).copied().unwrap_or(f64::NAN))
    }
}

/// The IEEE 952 noise extension of one channel and its gain on held-out data.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseExtension {
    /// The terms kept by the held-out gate, refitted to the whole record's ADEV (Q u*s, N u*sqrt(s), B u, K u/sqrt(s), R u/s; u = rad/s or m/s^2).
    pub terms_all: NoiseTerms,
    /// The kept terms fitted to the first half's ADEV (used for the held-out evaluation).
    pub terms_first_half: NoiseTerms,
    /// A band-limited term fitted beside the IEEE terms on the whole record, when it improves the fit (the
    /// catalogue's `correlated_noise` or `vibration`: sway and other motion).
    pub extra_all: Option<ExtraTerm>,
    /// The same on the first half (used for the held-out evaluation).
    pub extra_first_half: Option<ExtraTerm>,
    /// ADEV of the second half of the data.
    pub held_out_data: Curve,
    /// ADEV of the base SIMULATION (white, std from the first half) of the second half.
    pub held_out_base_sim: Curve,
    /// ADEV of the extended SIMULATION (terms of the first half) of the second half.
    pub held_out_extended_sim: Curve,
    /// RMS over tau of log10(ADEV SIMULATION / ADEV data) on the second half, base model (dimensionless).
    pub held_out_rms_log10_base: f64,
    /// The same for the extended model (dimensionless).
    pub held_out_rms_log10_extended: f64,
    /// Held-out chi^2 of the base model (white, std of the first half) on the second half's Allan points:
    /// sum of (ln(ADEV data / ADEV model) / relative uncertainty)^2 (dimensionless).
    pub held_out_chi2_base: f64,
    /// The same for the gated extended model of the first half (dimensionless).
    pub held_out_chi2_extended: f64,
    /// Number of Allan points of the second half in those chi^2.
    pub held_out_points: usize,
    /// The held-out verdict on each term of the extension (kept or dropped, and why).
    pub gate: Vec<TermGate>,
    /// The term that dominates the fitted model at the long tau: "white", "quantization", "bias instability",
    /// "rate random walk" or "rate ramp".
    pub dominant_term: &'static str,
}

/// Vehicle sway test: horizontal accelerometer against g times the tilt integrated from the gyro.
#[derive(Clone, Debug, PartialEq)]
pub struct Sway {
    /// Which pair: "ay vs +g*theta_x" or "ax vs -g*theta_y".
    pub pair: &'static str,
    /// Correlation coefficient of the high-passed 1-s means (dimensionless).
    pub correlation: f64,
    /// Regression slope of the accelerometer on the tilt, m/s^2 per rad (a real tilt gives +-g).
    pub slope_mps2_per_rad: f64,
    /// RMS of the high-passed accelerometer 1-s means, m/s^2.
    pub accel_rms_mps2: f64,
    /// RMS of the high-passed tilt, rad.
    pub tilt_rms_rad: f64,
}

/// One static pose of a multi-pose set.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Position label (1, 2, ...).
    pub pos: u32,
    /// Name (imucal label or "pose N").
    pub name: String,
    /// Samples.
    pub samples: usize,
    /// Mid time, s.
    pub t_mid_s: f64,
    /// Mean gyro output, rad/s.
    pub mean_rate_radps: [f64; 3],
    /// Mean accelerometer output, m/s^2.
    pub mean_force_mps2: [f64; 3],
    /// Labelled up direction in the body (Ferraris), unit vector.
    pub up_b: Option<[f64; 3]>,
    /// |mean force - base bias| - g, data, m/s^2.
    pub norm_minus_g_data_mps2: f64,
    /// The same in the base SIMULATION, m/s^2.
    pub norm_minus_g_base_sim_mps2: f64,
    /// The same in the extended SIMULATION (base calibration applied, so that it shows the pattern the data
    /// show), m/s^2.
    pub norm_minus_g_extended_sim_mps2: f64,
    /// |f calibrated by the extended model| - g, data, m/s^2 (model fitted on all poses).
    pub norm_minus_g_extended_mps2: f64,
    /// Standard deviation of the norm of the pose mean that white noise gives, m/s^2.
    pub norm_noise_std_mps2: f64,
    /// Whether the pose was held out of the fits of the gain evaluation (odd poses / left-out pose).
    pub held_out: bool,
}

/// An accelerometer model f_meas = A f + b (A = I + S + M).
#[derive(Clone, Debug, PartialEq)]
pub struct AccelModel {
    /// Bias, m/s^2.
    pub bias_mps2: [f64; 3],
    /// A, dimensionless (row i: output axis i).
    pub matrix: M3,
}

impl AccelModel {
    /// Scale factors A_ii - 1 (dimensionless).
    pub fn scale_factors(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.matrix[i][i] - 1.0)
    }

    /// The specific force that explains a measured `f`: A^-1 (f - b), m/s^2.
    pub fn calibrate(&self, f: [f64; 3]) -> [f64; 3] {
        let inv = inverse3(&self.matrix).unwrap_or(IDENTITY);
        mul_vec(&inv, [0, 1, 2].map(|i| f[i] - self.bias_mps2[i]))
    }
}

/// The multi-pose part of a study.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseStudy {
    /// Gravity used, m/s^2.
    pub gravity_mps2: f64,
    /// "labelled orientations (Ferraris)" or "|f| = g (orientations unknown)".
    pub method: &'static str,
    /// The static poses.
    pub poses: Vec<Pose>,
    /// Base accelerometer model (bias only), fitted on all poses.
    pub base_accel: AccelModel,
    /// Extended accelerometer model (bias, and the scale factors and misalignments that the held-out gate
    /// keeps), fitted on all poses.
    pub extended_accel: AccelModel,
    /// The held-out gate's verdict on each scale factor and misalignment of the extended accelerometer model
    /// (docs/cli.md#held-out-gate-of-the-pose-model), in the order they were decided.
    pub accel_term_gate: Vec<noise_extension::TermGate>,
    /// RMS over poses of |f - b| - g of the data, base model, m/s^2.
    pub norm_rms_data_mps2: f64,
    /// RMS over poses of the white-noise standard deviation of the pose's norm, m/s^2.
    pub norm_rms_noise_mps2: f64,
    /// RMS over held-out poses of |f calibrated| - g, base model fitted without them, m/s^2.
    pub held_out_norm_rms_base_mps2: f64,
    /// The same for the extended model, m/s^2.
    pub held_out_norm_rms_extended_mps2: f64,
    /// How poses were held out: "odd poses (fit on even)" or "leave one pose out".
    pub held_out_rule: &'static str,
    /// Gyro per-pose means: RMS over poses and axes of (mean - overall mean), rad/s.
    pub gyro_spread_rms_radps: f64,
    /// What white noise gives for that RMS, rad/s.
    pub gyro_spread_noise_radps: f64,
    /// Gyro per-pose-mean models on held-out poses: (name, RMS residual rad/s) for "constant bias",
    /// "bias + drift", "bias + g-sensitivity", when there are enough poses.
    pub gyro_models_held_out_radps: Vec<(&'static str, f64)>,
    /// The g-sensitivity matrix fitted on all poses, (rad/s)/(m/s^2), when tested.
    pub gyro_g_sensitivity: Option<M3>,
    /// Ferraris turns: (label, integrated angle raw deg, bias-removed deg, scale factor |angle|/360 - 1).
    pub turns: Vec<Turn>,
    /// imu_tk: the fitted accelerometer against the factory calibration.
    pub factory: Option<FactoryComparison>,
    /// The gyro matrix from the session's rotations beside the data author's (docs/method.md#moves).
    pub rotations: Option<rotations::RotationStudy>,
}

/// One labelled 360-degree turn of a Ferraris session.
#[derive(Clone, Debug, PartialEq)]
pub struct Turn {
    /// Label (x_rot, y_rot, z_rot).
    pub label: String,
    /// Body axis 0, 1, 2.
    pub axis: usize,
    /// Duration, s.
    pub duration_s: f64,
    /// Integral of the raw gyro output over the turn, rad.
    pub raw_angle_rad: f64,
    /// Integral after removing the static gyro bias, rad.
    pub angle_rad: f64,
    /// |angle| / 2 pi - 1 (dimensionless): the gyro scale factor if the turn was one full turn.
    pub scale_factor: f64,
}

/// imu_tk: fitted accelerometer gains and misalignments beside the factory calibration, in one gauge: the
/// lower-triangular factor L of K = L Q (Q a rotation, unobservable from |f| = g), K in counts per m/s^2.
#[derive(Clone, Debug, PartialEq)]
pub struct FactoryComparison {
    /// Fitted gains L_ii, counts per m/s^2 (g = 9.81744 m/s^2).
    pub fitted_gain_counts_per_mps2: [f64; 3],
    /// Factory gains of the same canonical form, counts per m/s^2.
    pub factory_gain_counts_per_mps2: [f64; 3],
    /// Fitted normalised lower off-diagonals L_10/L_11, L_20/L_22, L_21/L_22 (dimensionless).
    pub fitted_misalignment: [f64; 3],
    /// Factory, reading counts = diag(gain) M f.
    pub factory_misalignment: [f64; 3],
    /// Factory, reading counts = diag(gain) M^-1 f (the other convention).
    pub factory_misalignment_inverse: [f64; 3],
    /// Fitted offsets, counts.
    pub fitted_offset_counts: [f64; 3],
}

/// A named cause with the numbers that show it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cause {
    /// Short name ("correlated noise", "vehicle sway", "accel scale factors and misalignments", ...).
    pub name: String,
    /// Channels or sensor concerned.
    pub channels: String,
    /// The numbers, in words with units.
    pub evidence: String,
}

/// A complete study.
#[derive(Clone, Debug)]
pub struct Study {
    /// The data set.
    pub dataset: String,
    /// Files read.
    pub sources: Vec<String>,
    /// Seed of the SIMULATIONs.
    pub seed: u64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Noise of each channel.
    pub noise: Vec<ChannelNoise>,
    /// Sway tests (single-pose records).
    pub sway: Vec<Sway>,
    /// Multi-pose part.
    pub poses: Option<PoseStudy>,
    /// The causes the numbers show, strongest first.
    pub causes: Vec<Cause>,
}

// ---------------------------------------------------------------------------------------------------------------
// Small numerics shared by the study's files

/// The 3 x 3 identity.
const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// `|v|`.
fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// `a - b`.
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Root mean square; NaN for no values.
fn rms(values: impl IntoIterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in values {
        s += v * v;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        (s / n as f64).sqrt()
    }
}

/// Channel `c` of a row, SI: 0..3 the gyro (rad/s), 3..6 the accelerometer (m/s^2), as in [`CHANNELS`].
fn channel_value(r: &Row, c: usize) -> f64 {
    if c < 3 {
        r.rate_b_radps[c]
    } else {
        r.force_b_mps2[c - 3]
    }
}

/// Arithmetic mean (0 for no values).
fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// The unit the human text gives a channel's noise in: (its value in SI, its name): deg/h for the gyros
/// (`g...`), ug for the accelerometers.
pub(crate) fn unit_of(channel: &str) -> (f64, &'static str) {
    if channel.starts_with('g') {
        (DEG_PER_HOUR, "deg/h")
    } else {
        (MICRO_G, "ug")
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Reading a data set, running the study

/// Fewest samples a single-pose record needs for its noise study (below, its statistics are not numbers).
pub const MIN_SINGLE_POSE_SAMPLES: usize = 1024;

/// Reads the data set from `data_dir` and runs its study (no files written).
pub fn study_dataset(dataset: Dataset, data_dir: &Path) -> Result<Study, InputError> {
    let file = |relative: &str| -> Result<PathBuf, InputError> {
        let path = data_dir.join(relative);
        if path.is_file() {
            Ok(path)
        } else {
            Err(InputError::file(&path.display().to_string(), format!("missing (the {} data set)", dataset.name())))
        }
    };
    match dataset {
        Dataset::Psins => {
            let path = file("psins-lasergyro/lasergyro.imu")?;
            eprintln!("study psins: reading {}", path.display());
            let rec = import_psins(&path, None)?.recording;
            rec.require_gyro("study")?;
            if rec.rows.len() < MIN_SINGLE_POSE_SAMPLES {
                return Err(InputError::file(
                    &path.display().to_string(),
                    format!(
                        "{} samples: the noise study needs at least {MIN_SINGLE_POSE_SAMPLES} (its Allan deviation \
                         spans octaves of cluster sizes, and its check holds out half of the record)",
                        rec.rows.len()
                    ),
                ));
            }
            Ok(study_single_pose(&rec, "psins", vec![path.display().to_string()], STUDY_SEED))
        }
        Dataset::Ferraris => study_ferraris(
            &file("imucal-ferraris/example_ferraris_session.csv")?,
            &file("imucal-ferraris/example_ferraris_session_list.json")?,
        ),
        Dataset::Imutk => {
            let acc = file("imu-tk-xsens/xsens_acc.mat")?;
            let gyro = file("imu-tk-xsens/xsens_gyro.mat")?;
            eprintln!("study imutk: reading {} and {}", acc.display(), gyro.display());
            let rec = import_imutk(&acc, &gyro, None, &StaticDetection::default())?.recording;
            rec.require_gyro("study")?;
            let sources = vec![acc.display().to_string(), gyro.display().to_string()];
            study_multi_pose(&rec, PoseKind::Unlabelled, IMUTK_GRAVITY_MPS2, "imutk", sources, STUDY_SEED, &[])
        }
    }
}

/// The Ferraris study: the session `csv` with its `labels`, the labelled turns, normal gravity at the site.
fn study_ferraris(csv: &Path, labels: &Path) -> Result<Study, InputError> {
    eprintln!("study ferraris: reading {}", csv.display());
    let rec = import_imucal(csv, labels, None)?.recording;
    rec.require_gyro("study")?;
    let turns = ferraris_turns(&rec, labels)?;
    let g = sinscal::nav::earth::normal_gravity_mps2(
        (rec.header.latitude_deg as f32).to_radians(),
        rec.header.height_m as f32,
    ) as f64;
    let sources = vec![csv.display().to_string(), labels.display().to_string()];
    study_multi_pose(&rec, PoseKind::Labelled, g, "ferraris", sources, STUDY_SEED, &turns)
}

/// The labelled turns of a Ferraris session as (label, body axis, row range): the rows whose sample index lies
/// in the label's range, plus one row past the end so that the last labelled sample's interval is integrated.
pub fn ferraris_turns(rec: &Recording, labels: &Path) -> Result<Vec<LabelledTurn>, InputError> {
    let label_text = std::fs::read_to_string(labels).map_err(|e| InputError::io(labels, e))?;
    let ranges = parse_imucal_labels(&label_text, &labels.display().to_string())?;
    let rate = IMUCAL_RATE_HZ;
    let mut turns = Vec::new();
    for (axis, label) in FERRARIS_ROTATIONS.iter().enumerate() {
        if let Some(r) = ranges.iter().find(|r| r.label == *label) {
            let rows: Vec<usize> = (0..rec.rows.len())
                .filter(|&k| {
                    let s = (rec.rows[k].t_s * rate).round() as u64;
                    (r.start..r.end).contains(&s)
                })
                .collect();
            if let (Some(first), Some(last)) = (rows.first(), rows.last()) {
                turns.push((label.to_string(), axis, *first..(*last + 2).min(rec.rows.len())));
            }
        }
    }
    Ok(turns)
}

/// Runs `sinscal study`: reads the data set or the recording ([`recording::target_of`]), writes `summary.md`
/// and the figures into `report_dir` and, with `json`, the JSON ('-' = stdout, then the summary is not printed).
/// Returns the study and the lines of the checks it failed. A recording's dwells are held against gravity and
/// the Earth rate as `calibrate` holds them (its `physics` check: gyros in deg/s, headings half a turn off,
/// ...); when they fail, the study is still written, and the line says so.
pub fn run(
    target: &str,
    data_dir: Option<&Path>,
    report_dir: &Path,
    json_path: Option<&Path>,
) -> anyhow::Result<(Study, Vec<String>)> {
    let (study, failed) = match recording::target_of(target)? {
        recording::Target::Recording(path) => {
            let rec = recording::read_recording(&path)?;
            let physics = crate::calibration::checks::physics_of_recording(&rec, &Default::default());
            let failed = crate::calibration::checks::failed_lines(physics.iter());
            (recording::study_of(rec, &path)?, failed)
        }
        recording::Target::Dataset(dataset) => (study_dataset(dataset, &resolve_data_dir(data_dir)?)?, Vec::new()),
    };
    crate::study::report::write_report(&study, report_dir, json_path)?;
    Ok((study, failed))
}

/// The data directory of the built-in data sets: `data_dir`, else $SINSCAL_DATA; it must be a directory.
fn resolve_data_dir(data_dir: Option<&Path>) -> Result<PathBuf, InputError> {
    let data_dir: PathBuf = match data_dir {
        Some(d) => d.to_path_buf(),
        None => std::env::var_os("SINSCAL_DATA").map(PathBuf::from).ok_or_else(|| {
            InputError::file("sinscal study", "no data directory: give --data DIR or set SINSCAL_DATA")
        })?,
    };
    if !data_dir.is_dir() {
        return Err(InputError::file(&data_dir.display().to_string(), "not a directory (the data directory)"));
    }
    Ok(data_dir)
}
