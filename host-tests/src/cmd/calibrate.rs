//! `sinscal calibrate RECORDING`: the sensor-model terms of a recording (the general estimator or the paper's), through the core directly
//! or through the firmware path (`--on host`, `--on qemu`).

use std::path::{Path, PathBuf};

use clap::ValueEnum;
use sinscal::calib::align::DwellValue;
use sinscal::calib::general::{AttitudeKnowledge, Model};

use crate::calibration::checks::{failed_lines, physics_of_recording};
use crate::calibration::estimates::parse_model;
use crate::calibration::firmware_path::calibrate_on_host;
use crate::calibration::qemu::calibrate_on_qemu;
use crate::calibration::result::{summary, CalibrationJson};
use crate::calibration::{
    calibrate, Calibration, Coefficient, Method, Options, PrefilterKind, DEFAULT_METHOD, DEFAULT_MODEL,
};
use crate::cmd::{write_json, ChecksFailed};
use crate::io::error::InputError;
use crate::io::noise_file::NoiseTerms;
use crate::io::recording::{RecordingFile, RowSource};

/// The prefilter in front of the dwell statistics.
#[derive(Clone, Copy, ValueEnum)]
pub enum PrefilterArg {
    /// The paper's two-state HMM/KF with its Q and R.
    Hmmkf,
    /// No prefilter.
    None,
}

/// Which dwell value the alignment uses.
#[derive(Clone, Copy, ValueEnum)]
pub enum DwellValueArg {
    /// Mean of the (filtered) dwell: minimum variance for white noise.
    Mean,
    /// The prefilter's settled output at the end of the dwell (the paper's alternative).
    Settled,
}

/// The estimator.
#[derive(Clone, Copy, ValueEnum)]
pub enum MethodArg {
    /// The general estimator: every channel of every dwell against the reference.
    Channels,
    /// The paper's: alignment angles per position.
    Angles,
}

/// Where the firmware path runs.
#[derive(Clone, Copy, ValueEnum)]
pub enum OnArg {
    /// Replay through the firmware path on x86 (device frames, driver, queue, sequence, core).
    Host,
    /// Replay through the firmware in QEMU (mps2-an386, Cortex-M4F).
    Qemu,
}

/// Arguments of `sinscal calibrate`.
#[derive(clap::Args)]
pub struct Args {
    /// The recording (CSV).
    recording: PathBuf,
    /// Write the result as JSON (docs/formats.md#calibration-json-version-2) to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    calibration: CalibrationArgs,
    /// Replay through the firmware path (device frames quantised by an ADIS16505-2, driver, sampling
    /// queue, calibration sequence) on this machine or in the emulated Cortex-M4F.
    #[arg(long, value_enum)]
    on: Option<OnArg>,
}

/// The calibration options of `calibrate` and `device run`.
#[derive(clap::Args)]
pub struct CalibrationArgs {
    /// The estimator (default: channels, chosen by measurement: docs/method.md#default-estimator).
    #[arg(long, value_enum)]
    method: Option<MethodArg>,
    /// The general estimator's terms: 'biases', 'full', or a comma list of gyro_bias, accel_bias,
    /// accel_scale_factor, accel_misalignment, gyro_scale_factor, gyro_misalignment, gyro_g_sensitivity,
    /// reference_offset (default: biases,accel_scale_factor).
    #[arg(long, value_parser = parse_model)]
    model: Option<Model>,
    /// Prefilter in front of the dwell statistics.
    #[arg(long, value_enum, default_value = "hmmkf")]
    prefilter: PrefilterArg,
    /// The prefilter's coefficient a in [0, 1], or 'auto' to identify it from the first dwell.
    #[arg(long, default_value = "1", value_parser = parse_prefilter_a)]
    prefilter_a: Coefficient,
    /// Which dwell value the alignment uses.
    #[arg(long, value_enum, default_value = "mean")]
    dwell_value: DwellValueArg,
    /// Take the turntable reference as exact (do not estimate the constant offset phi0).
    #[arg(long)]
    no_reference_offset: bool,
    /// Channel method: estimate every position's pitch and roll from the data (|f| = g) instead of taking the
    /// recording's as a reference (hand-placed poses); automatic for recordings levelled from their own
    /// accelerometers.
    #[arg(long)]
    estimate_attitudes: bool,
    /// Passes of the solution at most: 1 = the paper's single linear solution; more remove its
    /// second-order error by realigning the bias-compensated dwells.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=50))]
    passes: u32,
    /// Firmware path (`--on`, `device run`): a dwell's sample is at rest while | |f| - g | stays within this,
    /// m/s^2 (default 0.5); a raw, uncalibrated accelerometer may need more.
    #[arg(long, value_parser = parse_tolerance)]
    rest_force_tolerance: Option<f32>,
    /// Channel method: do not use the moves between dwells and the labelled turns (they are used when the model
    /// has gyro scale factors or misalignments: docs/method.md#moves).
    #[arg(long)]
    no_moves: bool,
    /// Channel method: how well the recording's attitudes are known, degrees (one standard deviation, each axis;
    /// 0 = exact labels): each dwell's attitude error is a nuisance with that prior. Default: the header's
    /// pose_tolerance_deg, else 0 (docs/method.md#poses-known-to-a-tolerance).
    #[arg(long, value_parser = parse_pose_tolerance)]
    pose_tolerance: Option<f64>,
    /// Channel method: weight each dwell by the noise model of this noise file (made once from a static run
    /// of the IMU by `sinscal noise`), or with 'recording' by the model named from the recording's own longest
    /// dwell: the variance of a dwell mean is the model's at the dwell's length, with the correlation between
    /// dwells (docs/method.md#noise-model). Default: the session's own dwell noise.
    #[arg(long, value_name = "NOISE_FILE|recording")]
    noise: Option<std::path::PathBuf>,
    /// Channel method: leave these moves and turns out of the fit to check it, numbered from 1 in the
    /// recording's order as the summary lists them (e.g. 2,4): each is integrated with the calibration
    /// afterwards and its rotation error reported as held out (docs/method.md#held-out-moves).
    #[arg(long, value_name = "LIST", value_parser = parse_move_list)]
    hold_out_moves: Option<u64>,
}

impl CalibrationArgs {
    /// `options` completed from the open recording (after every usage error has been reported): the noise
    /// model named from it (`--noise recording`), and without `--model` outside the firmware path the default
    /// for its attitudes ([`default_model`]).
    pub fn with_recording(
        &self,
        options: Options,
        firmware_path: bool,
        rec: &impl RowSource,
    ) -> anyhow::Result<Options> {
        let noise = match &self.noise {
            Some(path) if path.as_os_str() == NOISE_FROM_RECORDING => Some(noise_of_recording(rec)?),
            _ => options.noise,
        };
        let model = match self.model {
            None if !firmware_path && options.method == Method::Channels => default_model(self.estimate_attitudes, rec),
            _ => options.model,
        };
        Ok(Options { noise, model, ..options })
    }
}

/// The model `calibrate` fits without `--model`: [`DEFAULT_MODEL`] (chosen on turntable sessions), and for
/// poses whose attitudes are estimated from the data (hand-placed, `--estimate-attitudes`, or levelled from
/// the accelerometers by an importer; not on the firmware path, which takes them as a reference) every term: a
/// hand-held sensor has them all, and the `|f| = g` fit of many poses has the freedom for them. Measured on the imu_tk Xsens session (docs/method.md#default-estimator):
/// chi-square 304 on 190 degrees of freedom with every term, 4,678 on 199 with imu_tk's own terms (biases,
/// scale factors and misalignments of both triads), 17 times the dwell noise with the turntable default.
pub fn default_model(estimate_attitudes: bool, rec: &impl RowSource) -> Model {
    let unknown = crate::calibration::attitude_knowledge(rec.header()) == AttitudeKnowledge::Unknown;
    if estimate_attitudes || unknown {
        Model::FULL
    } else {
        DEFAULT_MODEL
    }
}

/// The `--noise` value that names the model from the recording itself.
pub const NOISE_FROM_RECORDING: &str = "recording";

/// The noise terms of the recording's own longest dwell, as `sinscal noise` names them (its noise file, read
/// back as a noise file is read).
fn noise_of_recording(rec: &impl RowSource) -> anyhow::Result<NoiseTerms> {
    let file = crate::cmd::noise::characterise(rec, crate::cmd::noise::DEFAULT_MIN_TAU_S)?;
    let text = serde_json::to_string(&file)?;
    let terms = crate::io::noise_file::NoiseFile::parse(&text, rec.source())?.terms;
    Ok(NoiseTerms { from_recording: true, ..terms })
}

/// `--pose-tolerance`: degrees in [0, 10] (a bad value is a usage error, exit 2).
fn parse_pose_tolerance(text: &str) -> Result<f64, String> {
    let most = crate::io::recording::MAX_POSE_TOLERANCE_DEG;
    match text.parse::<f64>() {
        Ok(x) if (0.0..=most).contains(&x) => Ok(x),
        _ => Err(format!("'{text}' is not a tolerance in degrees between 0 and {most}")),
    }
}

/// `--hold-out-moves`: a comma list of move numbers from 1 to 64, as a bit set (bit k = move k + 1).
fn parse_move_list(text: &str) -> Result<u64, String> {
    let mut bits = 0u64;
    for item in text.split(',') {
        match item.trim().parse::<u32>() {
            Ok(k @ 1..=64) => bits |= 1 << (k - 1),
            _ => return Err(format!("'{}' is not a move number from 1 to 64", item.trim())),
        }
    }
    Ok(bits)
}

/// `--rest-force-tolerance`: a positive number of m/s^2 (a bad value is a usage error, exit 2).
fn parse_tolerance(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(x) if x.is_finite() && x > 0.0 && x < 9.0 => Ok(x),
        _ => Err(format!("'{text}' is not a tolerance in m/s^2 between 0 and 9")),
    }
}

/// `--prefilter-a`: 'auto' or a number in [0, 1] (a bad value is a usage error, exit 2).
fn parse_prefilter_a(text: &str) -> Result<Coefficient, String> {
    if text == "auto" {
        return Ok(Coefficient::Identify);
    }
    match text.parse::<f32>() {
        Ok(a) if (0.0..=1.0).contains(&a) => Ok(Coefficient::Fixed(a)),
        _ => Err(format!("'{text}' is neither 'auto' nor a number in [0, 1]")),
    }
}

impl CalibrationArgs {
    /// The calibration options these arguments ask for; `firmware_path` when they go through the firmware
    /// path (which takes the recording's attitudes as its reference).
    pub fn options(&self, firmware_path: bool) -> anyhow::Result<Options> {
        let coefficient = self.prefilter_a;
        let usage = |text: &str| -> ! {
            clap::Error::raw(clap::error::ErrorKind::ArgumentConflict, format!("{text}\n")).exit()
        };
        let method = match self.method {
            Some(MethodArg::Angles) => Method::Angles,
            Some(MethodArg::Channels) => Method::Channels,
            None => DEFAULT_METHOD,
        };
        if self.estimate_attitudes && method == Method::Angles {
            usage("--estimate-attitudes: the angle method needs the reference attitudes (--method channels)")
        }
        if self.estimate_attitudes && firmware_path {
            usage("--estimate-attitudes: the firmware path takes the recording's attitudes as its reference")
        }
        if self.hold_out_moves.is_some() && (method == Method::Angles || firmware_path || self.no_moves) {
            usage(
                "--hold-out-moves: the moves are observations of the host's general estimator only (--method \
                   channels, without --on and --no-moves)",
            )
        }
        if self.noise.is_some() && method == Method::Angles {
            usage("--noise: the angle method weights by its own dwell noise (--method channels)")
        }
        let noise = match &self.noise {
            // Named from the recording once it is open ([`CalibrationArgs::with_recording`]).
            Some(path) if path.as_os_str() == NOISE_FROM_RECORDING => None,
            Some(path) => Some(crate::io::noise_file::NoiseFile::read(path)?.terms),
            None => None,
        };
        let model = match self.model {
            Some(_) if method == Method::Angles => {
                usage("--model: the angle method estimates the biases (and the reference offset) only")
            }
            Some(model) => model,
            // Outside the firmware path the default depends on the recording ([`CalibrationArgs::with_recording`]).
            None => DEFAULT_MODEL,
        };
        Ok(Options {
            method,
            model,
            prefilter: match self.prefilter {
                PrefilterArg::Hmmkf => PrefilterKind::HmmKf,
                PrefilterArg::None => PrefilterKind::None,
            },
            coefficient,
            dwell_value: match self.dwell_value {
                DwellValueArg::Mean => DwellValue::Mean,
                DwellValueArg::Settled => DwellValue::Settled,
            },
            estimate_reference_offset: !self.no_reference_offset,
            max_passes: self.passes,
            estimate_attitudes: self.estimate_attitudes,
            rest_force_tolerance_mps2: self
                .rest_force_tolerance
                .unwrap_or(sinscal::run::sequence::SequenceSettings::default().rest.force_error_max_mps2),
            use_moves: !self.no_moves,
            pose_tolerance_deg: self.pose_tolerance,
            noise,
            hold_out_moves: self.hold_out_moves.unwrap_or(0),
        })
    }
}

/// Runs `sinscal calibrate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let options = args.calibration.options(args.on.is_some())?;
    // The rows are read in passes, never held (docs/formats.md#speed-and-memory).
    let rec = RecordingFile::open(&args.recording)?;
    let options = args.calibration.with_recording(options, args.on.is_some(), &rec)?;
    let cal = match args.on {
        None => calibrate(&rec, &options),
        Some(OnArg::Host) => calibrate_on_host(&rec, &options),
        Some(OnArg::Qemu) => calibrate_on_qemu(&rec, &options),
    };
    let mut cal = cal.map_err(|e| with_physics_hint(e, &rec, &options))?;
    cal.fit_hint = fit_hint(&cal, &rec, &options);
    finish(&cal, args.json.as_deref())
}

/// The pose tolerance the fit check tries when exact labels misfit, degrees (a hand-placed pose).
const HINT_POSE_TOLERANCE_DEG: f64 = 1.0;

/// When the general estimator's fit fails its check, the alternative that fits, as the check's hint: the labels
/// known to a degree (the misfit is the poses', not the sensor's), else every static term (`--model full`: the
/// model misses sensor terms). The same calibration again on the workstation, once per alternative, only when
/// the fit failed.
fn fit_hint(cal: &Calibration, rec: &RecordingFile, options: &Options) -> Option<String> {
    let channels = cal.channels.as_ref()?;
    if crate::calibration::checks::fit(&cal.estimates, crate::calibration::checks::noise_dof(cal)).passed {
        return None;
    }
    let exact = cal.pose_tolerance_deg == 0.0 && channels.attitude == AttitudeKnowledge::Reference;
    let tolerant = Options { pose_tolerance_deg: Some(HINT_POSE_TOLERANCE_DEG), ..*options };
    let full = Options { model: Model::FULL, ..*options };
    let trials = [
        (exact, tolerant, format!("poses off their labels? with --pose-tolerance {HINT_POSE_TOLERANCE_DEG}")),
        (options.model != Model::FULL, full, "sensor terms missing from the model? with --model full".to_string()),
    ];
    trials.into_iter().filter(|(tried, _, _)| *tried).find_map(|(_, trial, what)| {
        let alternative = calibrate(rec, &trial).ok()?;
        let e = &alternative.estimates;
        let fits = crate::calibration::checks::fit(e, crate::calibration::checks::noise_dof(&alternative)).passed;
        fits.then(|| {
            format!(
                "{what} the fit passes (chi-square {:.2} on {} degrees of freedom)",
                e.chi_square, e.degrees_of_freedom
            )
        })
    })
}

/// Prints the summary (unless the JSON goes to stdout) and writes the JSON if asked; then fails with
/// [`ChecksFailed`] (exit status 3) when the result fails one of its checks.
pub fn finish(cal: &Calibration, json: Option<&Path>) -> anyhow::Result<()> {
    let document = CalibrationJson::new(cal);
    match json {
        Some(path) if path == Path::new("-") => write_json(path, &document)?,
        Some(path) => {
            super::out(&summary(cal))?;
            write_json(path, &document)?;
        }
        None => super::out(&summary(cal))?,
    }
    let failed = failed_lines(&document.checks);
    if failed.is_empty() {
        Ok(())
    } else {
        Err(ChecksFailed(failed).into())
    }
}

/// A calibration that the input refused, with the physics check's hint when the dwells contradict gravity or
/// the Earth rate (the reason the input was refused, more often than not).
fn with_physics_hint(e: InputError, rec: &RecordingFile, options: &Options) -> anyhow::Error {
    match physics_of_recording(rec, options) {
        Some(check) if !check.passed => anyhow::anyhow!("{e} (check failed: physics: {})", check.detail),
        _ => e.into(),
    }
}
