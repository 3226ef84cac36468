//! `sinscal navigate`: a static navigation run of a recording (or a simulated one of a simulated IMU),
//! with and without the calibration's biases removed, and what the calibration's standard errors predict.

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;

use crate::io::error::InputError;
use crate::io::recording::{Dwell, Header, Recording, SimulationTruth};
use crate::model::synth::{c_b_n, mul_vec, Scenario};
use crate::navigation::strapdown::{linear_error_model, navigate_runs, NavError, Run, RunSummary, StaticSetup};

/// The biases (and their standard errors) of a calibration JSON file (docs/formats.md#calibration-json).
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationBiases {
    /// File name.
    pub source: String,
    /// Gyro bias, body, rad/s (unobservable entries: 0).
    pub gyro_bias_radps: [f64; 3],
    /// Accelerometer bias, body, m/s^2 (unobservable entries: 0).
    pub accel_bias_mps2: [f64; 3],
    /// Standard errors, rad/s (unobservable: None).
    pub gyro_bias_std_radps: [Option<f64>; 3],
    /// Standard errors, m/s^2 (unobservable: None).
    pub accel_bias_std_mps2: [Option<f64>; 3],
}

impl CalibrationBiases {
    /// Reads a calibration JSON file.
    pub fn read(path: &Path) -> Result<CalibrationBiases, InputError> {
        let name = path.display().to_string();
        let short = path.file_name().map_or(name.clone(), |f| f.to_string_lossy().into_owned());
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| InputError::at(&name, e.line(), format!("not JSON: {e}")))?;
        // Version 2 (docs/formats.md#calibration-json-version-2) has every field of version 1: navigate reads its
        // biases and leaves the other terms out.
        if v["schema"] != "sinscal-calibration/1" && v["schema"] != "sinscal-calibration/2" {
            return Err(InputError::file(
                &name,
                "not a calibration result: schema is not 'sinscal-calibration/1' or 'sinscal-calibration/2'",
            ));
        }
        let triple = |key: &str| -> Result<[Option<f64>; 3], InputError> {
            let arr = v[key]
                .as_array()
                .filter(|a| a.len() == 3)
                .ok_or_else(|| InputError::file(&name, format!("'{key}' is not an array of 3 numbers or nulls")))?;
            let mut out = [None; 3];
            for (slot, x) in out.iter_mut().zip(arr) {
                *slot = match x {
                    serde_json::Value::Null => None,
                    x => Some(x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                        InputError::file(&name, format!("'{key}' holds '{x}', not a finite number or null"))
                    })?),
                };
            }
            Ok(out)
        };
        Ok(CalibrationBiases {
            source: short,
            gyro_bias_radps: triple("gyro_bias_radps")?.map(|x| x.unwrap_or(0.0)),
            accel_bias_mps2: triple("accel_bias_mps2")?.map(|x| x.unwrap_or(0.0)),
            gyro_bias_std_radps: triple("gyro_bias_std_radps")?,
            accel_bias_std_mps2: triple("accel_bias_std_mps2")?,
        })
    }
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

/// What the calibration's standard errors predict for the calibrated run.
#[derive(Clone, Debug, Serialize)]
pub struct Prediction {
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
    recording: &Recording,
    calibration: &CalibrationBiases,
    second: Option<&CalibrationBiases>,
    options: &NavOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<NavReport, InputError> {
    let source = recording.source.as_str();
    recording.require_gyro("navigate")?;
    let header = &recording.header;
    let dwells = recording.dwells();
    let dwell = chosen_dwell(source, &dwells, options)?;
    let (attitude, heading) = dwell.attitude_with_heading(source, "navigation")?;
    let attitude_deg = [attitude.pitch_deg, attitude.roll_deg, heading];
    let rate_hz = sample_rate_hz(source, header.rate_hz, dwell)?;
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
            let rows = &dwell.rows;
            let at = |k: usize| (rows[k].rate_b_radps, rows[k].force_b_mps2);
            navigate_runs(&setup, rows.len(), at, &mut runs, &mut progress);
            (false, rows.len())
        }
    };
    let hours = samples as f64 / rate_hz / 3600.0;

    let predicted = predict(&setup, calibration, samples, record_every, rate_hz);
    Ok(NavReport {
        schema: "sinscal-navigation/1",
        source: source.to_string(),
        calibrations: std::iter::once(calibration.source.clone()).chain(second.map(|s| s.source.clone())).collect(),
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

/// The dwell to navigate: `--position`, else the first dwell for a simulated run, else the longest.
fn chosen_dwell<'a>(source: &str, dwells: &'a [Dwell<'a>], options: &NavOptions) -> Result<&'a Dwell<'a>, InputError> {
    if dwells.is_empty() {
        return Err(InputError::file(source, "no dwell (every row has pos = 0): nothing static to navigate"));
    }
    Ok(match options.position {
        Some(p) => dwells
            .iter()
            .find(|d| d.pos == p)
            .ok_or_else(|| InputError::file(source, format!("no dwell with pos = {p}")))?,
        None if options.hours.is_some() => &dwells[0],
        None => dwells.iter().max_by_key(|d| d.rows.len()).expect("non-empty"),
    })
}

/// The header's rate, or the rate measured over the dwell when the header has none.
fn sample_rate_hz(source: &str, header_rate_hz: Option<f64>, dwell: &Dwell) -> Result<f64, InputError> {
    Ok(match header_rate_hz {
        Some(r) if r > 0.0 => r,
        _ => {
            let span = dwell.rows.last().unwrap().t_s - dwell.rows[0].t_s;
            if dwell.rows.len() < 2 || span <= 0.0 {
                return Err(InputError::file(source, "no rate_hz in the header and a dwell too short to measure it"));
            }
            (dwell.rows.len() - 1) as f64 / span
        }
    })
}

/// The runs: uncompensated, calibrated, the second calibration if any, and the truth removed when the
/// recording is a simulation that states it.
fn runs_to_compare(
    calibration: &CalibrationBiases,
    second: Option<&CalibrationBiases>,
    truth: Option<&SimulationTruth>,
) -> Vec<Run> {
    let mut runs = vec![
        Run { name: "uncompensated".into(), gyro_bias_radps: [0.0; 3], accel_bias_mps2: [0.0; 3], history: vec![] },
        Run {
            name: format!("calibrated ({})", calibration.source),
            gyro_bias_radps: calibration.gyro_bias_radps,
            accel_bias_mps2: calibration.accel_bias_mps2,
            history: vec![],
        },
    ];
    if let Some(second) = second {
        runs.push(Run {
            name: format!("calibrated ({})", second.source),
            gyro_bias_radps: second.gyro_bias_radps,
            accel_bias_mps2: second.accel_bias_mps2,
            history: vec![],
        });
    }
    if let Some(t) = truth {
        runs.push(Run {
            name: "true errors removed".into(),
            gyro_bias_radps: t.gyro_bias_b_radps,
            accel_bias_mps2: t.accel_bias_b_mps2,
            history: vec![],
        });
    }
    runs
}

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
        if !(hours > 0.0 && hours <= 48.0) {
            return Err(InputError::file(source, format!("--hours {hours}: must be in (0, 48]")));
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

/// The RMS errors that the calibration's standard errors predict for the calibrated run: the closed-form
/// error model's response to each body-frame bias, weighted by its variance (biases taken as
/// uncorrelated; noise during the run not included). `None` if a standard error is missing.
fn predict(
    setup: &StaticSetup,
    cal: &CalibrationBiases,
    samples: usize,
    record_every: usize,
    rate_hz: f64,
) -> Option<Prediction> {
    let stds: Vec<f64> =
        cal.gyro_bias_std_radps.iter().chain(cal.accel_bias_std_mps2.iter()).copied().collect::<Option<_>>()?;
    let steps = samples / record_every;
    let mut var_pos = vec![0.0f64; steps + 1];
    let mut var_heading = vec![0.0f64; steps + 1];
    for (i, sd) in stds.iter().enumerate() {
        let mut unit = [0.0; 3];
        unit[i % 3] = 1.0;
        let (eps, nabla) =
            if i < 3 { (mul_vec(&setup.c_b_n, unit), [0.0; 3]) } else { ([0.0; 3], mul_vec(&setup.c_b_n, unit)) };
        let response = linear_error_model(
            setup.latitude_rad,
            setup.height_m,
            setup.gravity_mps2,
            eps,
            nabla,
            record_every as f64 / rate_hz,
            steps,
        );
        for (k, e) in response.iter().enumerate() {
            var_pos[k] += sd * sd * (e.position_en_m[0].powi(2) + e.position_en_m[1].powi(2));
            var_heading[k] += sd * sd * e.attitude_n_rad[2].powi(2);
        }
    }
    Some(Prediction {
        rms_final_horizontal_position_error_m: var_pos.last()?.sqrt(),
        max_rms_horizontal_position_error_m: var_pos.iter().fold(0.0f64, |m, v| m.max(v.sqrt())),
        rms_final_heading_error_rad: var_heading.last()?.sqrt(),
    })
}
