//! `sinscal navigate`: a static navigation run of a recording (or a simulated one of a simulated IMU),
//! with and without the calibration's biases removed, and what the calibration's standard errors predict.

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

use sinscal::calib::general::Term;

use crate::io::calibration_model::CalibrationModel;
use crate::io::dwell_tally::{DwellTallies, DwellTally};
use crate::io::error::InputError;
use crate::io::recording::{Header, RowSource, SimulationTruth};
use crate::model::synth::{c_b_n, mul_vec, transpose, Scenario, EARTH_RATE_RADPS};
use crate::navigation::strapdown::{
    linear_error_model, navigate_runs, Lockstep, NavError, Run, RunSummary, StaticSetup,
};

/// A calibration JSON file as navigate uses it (docs/formats.md#calibration-json): the whole sensor model to
/// compensate with, and the covariance of its parameters to predict the calibrated run's error.
#[derive(Clone, Debug, PartialEq)]
pub struct NavCalibration {
    /// The sensor model (every term the file gives; its `source` is the file name).
    pub model: CalibrationModel,
    /// The parameters the covariance is of (`gyro_bias_x`, `accel_scale_factor_z`, ...): version 2's
    /// `parameters`; for version 1, the biases with a standard error.
    pub parameters: Vec<String>,
    /// Their covariance, SI: version 2's `covariance`; for version 1, the squared standard errors on the
    /// diagonal. Empty when a determined bias has no standard error.
    pub covariance_si: Vec<Vec<f64>>,
}

impl NavCalibration {
    /// Reads a calibration JSON file.
    pub fn read(path: &Path) -> Result<NavCalibration, InputError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
        let mut model = CalibrationModel::parse(&text, &name)?;
        model.source = path.file_name().map_or_else(|| name.clone(), |f| f.to_string_lossy().into_owned());
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| InputError::at(&name, e.line(), format!("not JSON: {e}")))?;
        // A version 2 file without `parameters` and `covariance` (written by another tool) gives its bias
        // standard errors as version 1 does.
        let has_covariance = !(v["parameters"].is_null() && v["covariance"].is_null());
        let (parameters, covariance_si) =
            if model.version == 2 && has_covariance { covariance_of(&v, &name)? } else { version_1_variances(&v) };
        Ok(NavCalibration { model, parameters, covariance_si })
    }
}

/// Version 2's `parameters` and `covariance` (a square matrix of finite numbers of that size).
fn covariance_of(v: &serde_json::Value, name: &str) -> Result<(Vec<String>, Vec<Vec<f64>>), InputError> {
    let bad = |what: &str| {
        InputError::file(name, format!("'{what}' is not what docs/formats.md#calibration-json-version-2 says"))
    };
    let parameters: Vec<String> = v["parameters"]
        .as_array()
        .ok_or_else(|| bad("parameters"))?
        .iter()
        .map(|p| p.as_str().map(str::to_string).ok_or_else(|| bad("parameters")))
        .collect::<Result<_, _>>()?;
    let rows = v["covariance"].as_array().filter(|r| r.len() == parameters.len()).ok_or_else(|| bad("covariance"))?;
    let covariance = rows
        .iter()
        .map(|row| {
            let row = row.as_array().filter(|r| r.len() == parameters.len()).ok_or_else(|| bad("covariance"))?;
            row.iter().map(|x| x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| bad("covariance"))).collect()
        })
        .collect::<Result<Vec<Vec<f64>>, _>>()?;
    Ok((parameters, covariance))
}

/// The bias standard errors of version 1 as a diagonal covariance (empty when a given bias has none).
fn version_1_variances(v: &serde_json::Value) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut parameters = Vec::new();
    let mut variances = Vec::new();
    for (field, std_field, term) in [
        ("gyro_bias_radps", "gyro_bias_std_radps", "gyro_bias"),
        ("accel_bias_mps2", "accel_bias_std_mps2", "accel_bias"),
    ] {
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            if v[field][i].is_null() {
                continue;
            }
            let Some(std) = v[std_field][i].as_f64().filter(|s| s.is_finite()) else {
                return (Vec::new(), Vec::new());
            };
            parameters.push(format!("{term}_{axis}"));
            variances.push(std * std);
        }
    }
    let n = variances.len();
    let covariance = (0..n).map(|i| (0..n).map(|j| if i == j { variances[i] } else { 0.0 }).collect()).collect();
    (parameters, covariance)
}

/// Options of a navigation check.
#[derive(Clone, Debug)]
pub struct NavOptions {
    /// Simulate a static run of this many hours (needs a simulated recording); `None`: navigate the
    /// recording's own static dwell.
    pub hours: Option<f64>,
    /// Which dwell's attitude (and, for measured data, samples) to use; default: the first dwell when
    /// simulating, the longest one otherwise.
    pub position: Option<u32>,
    /// Noise seed of the simulated run (default: the recording's seed + 1).
    pub seed: Option<u64>,
    /// Errors are recorded every this many seconds.
    pub record_interval_s: f64,
}

impl Default for NavOptions {
    fn default() -> NavOptions {
        NavOptions { hours: None, position: None, seed: None, record_interval_s: 10.0 }
    }
}

/// What the calibration's covariance predicts for the calibrated run.
#[derive(Clone, Debug, Serialize)]
pub struct Prediction {
    /// Parameters of the calibration that enter the navigation (biases, scale factors, misalignments,
    /// g-sensitivity), whose covariance the prediction uses.
    pub parameters: usize,
    /// RMS horizontal position error at the end, m.
    pub rms_final_horizontal_position_error_m: f64,
    /// Largest RMS horizontal position error over the run, m.
    pub max_rms_horizontal_position_error_m: f64,
    /// RMS heading error at the end, rad.
    pub rms_final_heading_error_rad: f64,
}

/// The navigation check's result (JSON `sinscal-navigation/1`).
#[derive(Clone, Debug, Serialize)]
pub struct NavReport {
    /// "sinscal-navigation/1".
    pub schema: &'static str,
    /// Recording.
    pub source: String,
    /// Calibration file(s).
    pub calibrations: Vec<String>,
    /// Whether the run is a simulation of the recording's (simulated) IMU.
    pub simulated: bool,
    /// Length, hours.
    pub hours: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Latitude, degrees.
    pub latitude_deg: f64,
    /// Attitude of the body (pitch, roll, heading), degrees.
    pub attitude_deg: [f64; 3],
    /// The runs.
    pub runs: Vec<RunSummary>,
    /// Prediction of the calibrated run's error from the standard errors (bias uncertainty only).
    pub predicted_from_std_errors: Option<Prediction>,
    /// Error histories (for plots), one per run, every `record_interval_s`.
    #[serde(skip)]
    pub histories: Vec<(String, Vec<NavError>)>,
}

/// Runs the navigation check.
pub fn navigate(
    recording: &impl RowSource,
    calibration: &NavCalibration,
    second: Option<&NavCalibration>,
    options: &NavOptions,
    mut progress_h: impl FnMut(f64, f64),
) -> Result<NavReport, InputError> {
    let source = recording.source();
    recording.require_gyro("navigate")?;
    let header = recording.header();
    let mut tallies = DwellTallies::bounded();
    recording.for_each_row(&mut |row| tallies.push(row, source).map(|_| ()))?;
    let dwell = chosen_dwell(source, &tallies.dwells, options)?;
    let (attitude, heading) = dwell.attitude_with_heading(source, "navigation")?;
    let attitude_deg = [attitude.pitch_deg, attitude.roll_deg, heading];
    let rate_hz = sample_rate_hz(source, header.rate_hz, dwell)?;
    let hours = |samples: usize| samples as f64 / rate_hz / 3600.0;
    let mut progress = |done: usize, total: usize| progress_h(hours(done), hours(total));
    let latitude_rad = header.latitude_deg.to_radians();
    let gravity_mps2 = header.gravity_mps2.unwrap_or_else(|| {
        sinscal::nav::earth::normal_gravity_mps2(latitude_rad as f32, header.height_m as f32) as f64
    });
    let c = c_b_n(attitude_deg[0], attitude_deg[1], attitude_deg[2]);
    let record_every = ((options.record_interval_s * rate_hz).round() as usize).max(1);
    let setup = StaticSetup {
        c_b_n: c,
        latitude_rad,
        height_m: header.height_m,
        gravity_mps2,
        dt_s: 1.0 / rate_hz,
        record_every,
    };
    let mut runs = runs_to_compare(calibration, second, header.truth.as_ref());
    let (simulated, samples) = match options.hours {
        Some(hours) => {
            let run = SimulatedRun { source, header, options, gravity_mps2, rate_hz, attitude_deg, hours };
            (true, run.navigate(&setup, &mut runs, &mut progress)?)
        }
        None => {
            // A second pass gives the dwell's rows, as they come, to the runs.
            let mut lockstep = Lockstep::new(&setup, &mut runs, dwell.samples);
            recording.for_each_row(&mut |row| {
                if row.pos == dwell.pos {
                    plausible_sample(source, row)?;
                    lockstep.step(&mut runs, row.rate_b_radps, row.force_b_mps2, &mut progress);
                }
                Ok(())
            })?;
            (false, dwell.samples)
        }
    };
    let hours = samples as f64 / rate_hz / 3600.0;

    let predicted = predict(&setup, calibration, samples, record_every, rate_hz);
    Ok(NavReport {
        schema: "sinscal-navigation/1",
        source: source.to_string(),
        calibrations: std::iter::once(calibration).chain(second).map(|c| c.model.source.clone()).collect(),
        simulated,
        hours,
        rate_hz,
        latitude_deg: header.latitude_deg,
        attitude_deg,
        runs: runs.iter().map(Run::summary).collect(),
        predicted_from_std_errors: predicted,
        histories: runs.into_iter().map(|r| (r.name, r.history)).collect(),
    })
}

/// Largest angular rate a navigated sample may have, rad/s: beyond any strapdown IMU's range (2,000 deg/s, 35
/// rad/s, is the largest of common parts) by a margin.
pub const MAX_NAVIGATION_RATE_RADPS: f64 = 100.0;
/// Largest specific force a navigated sample may have, m/s^2: beyond any strapdown IMU's range (40 g) by a
/// margin.
pub const MAX_NAVIGATION_FORCE_MPS2: f64 = 2000.0;

/// Refuses a sample of the navigated dwell beyond any IMU's range (a rate of 1e200 rad/s would otherwise make
/// every figure NaN), at its line.
fn plausible_sample(source: &str, row: &crate::io::recording::Row) -> Result<(), InputError> {
    let norm = |v: [f64; 3]| v[0].hypot(v[1]).hypot(v[2]);
    let (rate, force) = (norm(row.rate_b_radps), norm(row.force_b_mps2));
    let shown = crate::io::recording::shown;
    if rate > MAX_NAVIGATION_RATE_RADPS || force > MAX_NAVIGATION_FORCE_MPS2 {
        return Err(InputError::at(
            source,
            row.line,
            format!(
                "|w| = {} rad/s, |f| = {} m/s^2: beyond any strapdown IMU's range ({MAX_NAVIGATION_RATE_RADPS} \
                 rad/s, {MAX_NAVIGATION_FORCE_MPS2} m/s^2), not a sample of a static dwell",
                shown(rate),
                shown(force)
            ),
        ));
    }
    Ok(())
}

/// The dwell to navigate: `--position`, else the first dwell for a simulated run, else the longest.
fn chosen_dwell<'a>(
    source: &str,
    dwells: &'a [DwellTally],
    options: &NavOptions,
) -> Result<&'a DwellTally, InputError> {
    if dwells.is_empty() {
        return Err(InputError::file(source, "no dwell (every row has pos = 0): nothing static to navigate"));
    }
    Ok(match options.position {
        Some(p) => dwells
            .iter()
            .find(|d| d.pos == p)
            .ok_or_else(|| InputError::file(source, format!("no dwell with pos = {p}")))?,
        None if options.hours.is_some() => &dwells[0],
        None => dwells.iter().max_by_key(|d| d.samples).expect("non-empty"),
    })
}

/// Slowest sample rate `navigate` integrates, Hz: an IMU slower than this is no strapdown IMU, and a recording
/// whose times are in milliseconds reads as 0.1 Hz.
pub const MIN_NAVIGATION_RATE_HZ: f64 = 1.0;

/// The header's rate, or the rate measured over the dwell when the header has none; at least
/// [`MIN_NAVIGATION_RATE_HZ`].
fn sample_rate_hz(source: &str, header_rate_hz: Option<f64>, dwell: &DwellTally) -> Result<f64, InputError> {
    let rate_hz = match header_rate_hz {
        Some(r) if r > 0.0 => r,
        _ => {
            let span = dwell.last_t_s - dwell.first_t_s;
            if dwell.samples < 2 || span <= 0.0 {
                return Err(InputError::file(source, "no rate_hz in the header and a dwell too short to measure it"));
            }
            (dwell.samples - 1) as f64 / span
        }
    };
    if rate_hz < MIN_NAVIGATION_RATE_HZ {
        return Err(InputError::file(
            source,
            format!(
                "a sample rate of {} Hz ({}): below the {MIN_NAVIGATION_RATE_HZ} Hz of any strapdown IMU; times in \
                 milliseconds? (t_s is in seconds)",
                crate::io::recording::shown(rate_hz),
                if header_rate_hz.is_some() { "the header's rate_hz" } else { "measured over the dwell's times" }
            ),
        ));
    }
    Ok(rate_hz)
}

/// The runs: uncompensated, calibrated, the second calibration if any, and the truth removed when the
/// recording is a simulation that states it.
fn runs_to_compare(
    calibration: &NavCalibration,
    second: Option<&NavCalibration>,
    truth: Option<&SimulationTruth>,
) -> Vec<Run> {
    let calibrated = |c: &NavCalibration| Run {
        name: format!("calibrated ({})", c.model.source),
        compensation: c.model.clone(),
        history: Vec::new(),
    };
    let mut runs = vec![Run::with_biases("uncompensated", [0.0; 3], [0.0; 3]), calibrated(calibration)];
    runs.extend(second.map(calibrated));
    if let Some(t) = truth {
        runs.push(Run::with_biases("true errors removed", t.gyro_bias_b_radps, t.accel_bias_b_mps2));
    }
    runs
}

/// Longest simulated static run, hours.
pub const MAX_HOURS: f64 = 48.0;

/// Most samples a simulated static run may have (48 h at 1.16 kHz; a few minutes of navigation).
pub const MAX_SIMULATED_SAMPLES: f64 = 2e8;

/// A SIMULATED static run of `hours` of the IMU of a recording written by sinscal's simulator (its truth
/// header: biases and white noise), with a new noise seed.
struct SimulatedRun<'a> {
    source: &'a str,
    header: &'a Header,
    options: &'a NavOptions,
    gravity_mps2: f64,
    rate_hz: f64,
    attitude_deg: [f64; 3],
    hours: f64,
}

impl SimulatedRun<'_> {
    /// Navigates the runs over the simulated samples; the number of samples.
    fn navigate(
        &self,
        setup: &StaticSetup,
        runs: &mut [Run],
        progress: &mut impl FnMut(usize, usize),
    ) -> Result<usize, InputError> {
        let (source, header, hours) = (self.source, self.header, self.hours);
        let truth = header.truth.as_ref().ok_or_else(|| {
            InputError::file(
                source,
                "--hours simulates the recording's IMU, but this recording has no truth_* header (it is \
                 not a sinscal simulation); without --hours the recording's own static dwell is navigated",
            )
        })?;
        if !(hours > 0.0 && hours <= MAX_HOURS) {
            return Err(InputError::file(source, format!("--hours {hours}: must be in (0, {MAX_HOURS}]")));
        }
        let steps = hours * 3600.0 * self.rate_hz;
        if steps > MAX_SIMULATED_SAMPLES {
            return Err(InputError::file(
                source,
                format!(
                    "--hours {hours} at the recording's {} Hz is {} samples: at most {MAX_SIMULATED_SAMPLES:e} \
                     are simulated (fewer hours, or a recording at a lower rate)",
                    crate::io::recording::shown(self.rate_hz),
                    crate::io::recording::shown(steps)
                ),
            ));
        }
        let scenario = Scenario {
            latitude_deg: header.latitude_deg,
            height_m: header.height_m,
            gravity_mps2: self.gravity_mps2,
            rate_hz: self.rate_hz,
            gyro_bias_b_radps: truth.gyro_bias_b_radps,
            accel_bias_b_mps2: truth.accel_bias_b_mps2,
            gyro_noise_radps: truth.gyro_noise_radps,
            accel_noise_mps2: truth.accel_noise_mps2,
            // The static run happens on a fixture whose attitude is known exactly.
            reference_offset_n_rad: [0.0; 3],
            ..Scenario::table1_exact()
        };
        let (w, f) = scenario.exact_sample(self.attitude_deg);
        let mut rng = ChaCha8Rng::seed_from_u64(self.options.seed.unwrap_or(truth.seed.wrapping_add(1)));
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        let samples = (hours * 3600.0 * self.rate_hz).round() as usize;
        let noisy = |_| {
            let mut wn = w;
            let mut fnoisy = f;
            for i in 0..3 {
                wn[i] += scenario.gyro_noise_radps * unit.sample(&mut rng);
                fnoisy[i] += scenario.accel_noise_mps2 * unit.sample(&mut rng);
            }
            (wn, fnoisy)
        };
        navigate_runs(setup, samples, noisy, runs, progress);
        Ok(samples)
    }
}

/// How a unit error of calibration parameter `name` changes the sensor outputs at rest (the body's rate
/// `rate_b_radps` and specific force `force_b_mps2`): `(d rate, d force)`, body frame, per unit of the
/// parameter (docs/conventions.md#sensor-model: `w_meas = T_g w + b_g + G f`, `f_meas = T_a f + b_a`). `None`
/// for a parameter that does not enter the navigation (the turntable's reference offset).
pub fn output_sensitivity(name: &str, rate_b_radps: [f64; 3], force_b_mps2: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
    let axis = |c: char| "xyz".find(c);
    // The JSON's name to the core's term (the name is the JSON edge; the term decides the rest).
    let (term_name, axes) = name.rsplit_once('_')?;
    let term = Term::ALL.into_iter().find(|t| t.name() == term_name)?;
    let mut chars = axes.chars();
    let i = axis(chars.next()?)?;
    let j = match chars.next() {
        None => None,
        Some(c) => Some(axis(c)?),
    };
    let (mut dw, mut df) = ([0.0; 3], [0.0; 3]);
    match (term, j) {
        (Term::GyroBias, None) => dw[i] = 1.0,
        (Term::AccelBias, None) => df[i] = 1.0,
        (Term::GyroScaleFactor, None) => dw[i] = rate_b_radps[i],
        (Term::AccelScaleFactor, None) => df[i] = force_b_mps2[i],
        (Term::GyroMisalignment, Some(j)) => dw[i] = rate_b_radps[j],
        (Term::AccelMisalignment, Some(j)) => df[i] = force_b_mps2[j],
        (Term::GyroGSensitivity, Some(j)) => dw[i] = force_b_mps2[j],
        (Term::ReferenceOffset, _) => return None,
        // A term's axes other than its own (a scale factor with two axes, a misalignment with one).
        (
            Term::GyroBias
            | Term::AccelBias
            | Term::GyroScaleFactor
            | Term::AccelScaleFactor
            | Term::GyroMisalignment
            | Term::AccelMisalignment
            | Term::GyroGSensitivity,
            _,
        ) => return None,
    }
    Some((dw, df))
}

/// The RMS errors that the calibration's covariance predicts for the calibrated run: the closed-form error
/// model's response to each parameter's error at the run's attitude, combined through the full covariance
/// (`e(t)^T P e(t)`, correlations included; noise during the run not included). `None` without a covariance.
fn predict(
    setup: &StaticSetup,
    cal: &NavCalibration,
    samples: usize,
    record_every: usize,
    rate_hz: f64,
) -> Option<Prediction> {
    if cal.parameters.is_empty() {
        return None;
    }
    let c = &setup.c_b_n;
    let (sl, cl) = setup.latitude_rad.sin_cos();
    let rate_b = mul_vec(&transpose(c), [0.0, EARTH_RATE_RADPS * cl, EARTH_RATE_RADPS * sl]);
    let force_b = mul_vec(&transpose(c), [0.0, 0.0, setup.gravity_mps2]);
    let steps = samples / record_every;
    // Per parameter, its response over the run (zero for a parameter that does not enter the navigation).
    let responses: Vec<Option<Vec<NavError>>> = cal
        .parameters
        .iter()
        .map(|name| {
            let (dw, df) = output_sensitivity(name, rate_b, force_b)?;
            let (eps, nabla) = (mul_vec(c, dw), mul_vec(c, df));
            let (lat, h, g) = (setup.latitude_rad, setup.height_m, setup.gravity_mps2);
            Some(linear_error_model(lat, h, g, eps, nabla, record_every as f64 / rate_hz, steps))
        })
        .collect();
    let mut var_pos = vec![0.0f64; steps + 1];
    let mut var_heading = vec![0.0f64; steps + 1];
    for (p, rp) in responses.iter().enumerate() {
        for (q, rq) in responses.iter().enumerate() {
            let (Some(rp), Some(rq)) = (rp, rq) else { continue };
            let pq = cal.covariance_si[p][q];
            for k in 0..=steps {
                let (a, b) = (&rp[k], &rq[k]);
                var_pos[k] += pq * (a.position_en_m[0] * b.position_en_m[0] + a.position_en_m[1] * b.position_en_m[1]);
                var_heading[k] += pq * a.attitude_n_rad[2] * b.attitude_n_rad[2];
            }
        }
    }
    let used = responses.iter().filter(|r| r.is_some()).count();
    Some(Prediction {
        parameters: used,
        rms_final_horizontal_position_error_m: var_pos.last()?.max(0.0).sqrt(),
        max_rms_horizontal_position_error_m: var_pos.iter().fold(0.0f64, |m, v| m.max(v.max(0.0).sqrt())),
        rms_final_heading_error_rad: var_heading.last()?.max(0.0).sqrt(),
    })
}
