//! The calibration result as JSON (docs/formats.md#calibration-json) and as a human summary.

use std::fmt::Write as _;

use serde::Serialize;
use sinscal::calib::align::DwellValue;
use sinscal::calib::dwell::Prefilter;
use sinscal::calib::dwell::GATE_WIDTH_SIGMA;
use sinscal::calib::general::{misalignment_index, AttitudeKnowledge, ChannelSolution, Term, PARAMETERS};

use crate::calibration::{Calibration, Estimates, GravitySource, PositionResult};
use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::{DEG_PER_HOUR, MICRO_G};

/// One position in the JSON.
#[derive(Debug, Serialize)]
pub struct PositionJson {
    /// Label.
    pub pos: u32,
    /// Reference pitch, degrees.
    pub pitch_deg: f64,
    /// Reference roll, degrees.
    pub roll_deg: f64,
    /// Reference heading, degrees; the estimate where the reference gives none (`heading_known` false),
    /// null when neither exists (accelerometer-only data).
    pub heading_deg: Option<f64>,
    /// Whether the heading is the reference's.
    pub heading_known: bool,
    /// Extra: up (the direction of gravity) in the body as estimated, a unit vector, when the recording has no
    /// reference attitudes (its pitch and roll were levelled from the data).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub up_estimated_b: Option<[f64; 3]>,
    /// Standard error of an estimated heading, degrees (extra field; absent for a known heading).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heading_std_deg: Option<f64>,
    /// Samples used.
    pub samples: u32,
    /// Extra: samples not used as spikes (beyond the spike gate, docs/method.md#spikes).
    pub spikes: u32,
    /// Misalignment (e, n, u) of the dwell's analytic alignment against the reference, rad; null without a
    /// reference heading or gyro data.
    pub phi_rad: Option<[f64; 3]>,
    /// Standard deviation of each angle from the dwell noise, rad (extra field).
    pub phi_std_rad: Option<[f64; 3]>,
    /// Residual of the angle method at this position, rad (extra field; `--method angles`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_rad: Option<[f64; 3]>,
    /// Measured minus predicted gyro mean, rad/s (`--method channels`; null without gyros).
    pub residual_gyro_radps: Option<[f64; 3]>,
    /// Measured minus predicted accelerometer mean, m/s^2 (`--method channels`).
    pub residual_accel_mps2: Option<[f64; 3]>,
    /// Residuals inconsistent with the model at the 0.1 % level.
    pub suspect: bool,
    /// The dwell's residual statistic (chi-square with the dwell's channel count of degrees of freedom when
    /// the model holds; extra field, `--method channels`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub statistic: Option<f64>,
}

/// A 3x3 term in the JSON (null entries where undetermined).
type Matrix = [[Option<f64>; 3]; 3];

fn is_zero(x: &u32) -> bool {
    *x == 0
}

/// The device's record in the calibration JSON.
#[derive(Clone, Debug, Serialize)]
pub struct RecordJson {
    /// Its sequence number in the device's store.
    pub sequence: u32,
    /// The workstation's UTC time when it started the run that stored it (ISO 8601), if the note carries it.
    pub run_started_utc: Option<String>,
    /// The sequence number of a damaged newer record the device passed over (`null`: none).
    pub damaged_newer_sequence: Option<u32>,
}

/// The calibration JSON of docs/formats.md#calibration-json, with extra fields after the contract's.
#[derive(Debug, Serialize)]
pub struct CalibrationJson {
    /// "sinscal-calibration/2".
    pub schema: &'static str,
    /// "channels" or "angles".
    pub method: &'static str,
    /// The terms estimated.
    pub model: Vec<&'static str>,
    /// Latitude, degrees.
    pub latitude_deg: f64,
    /// Gravity used, m/s^2.
    pub gravity_mps2: f64,
    /// Positions.
    pub positions: Vec<PositionJson>,
    /// Gyro bias, body x, y, z, rad/s (null where unobservable).
    pub gyro_bias_radps: [Option<f64>; 3],
    /// Its standard error, rad/s.
    pub gyro_bias_std_radps: [Option<f64>; 3],
    /// Accelerometer bias, body x, y, z, m/s^2.
    pub accel_bias_mps2: [Option<f64>; 3],
    /// Its standard error, m/s^2.
    pub accel_bias_std_mps2: [Option<f64>; 3],
    /// Accelerometer scale factors x, y, z, 1 (null when not in the model).
    pub accel_scale_factor: Option<[Option<f64>; 3]>,
    /// Their standard errors.
    pub accel_scale_factor_std: Option<[Option<f64>; 3]>,
    /// Accelerometer misalignments `[[0, xy, xz], [yx, 0, yz], [zx, zy, 0]]`, 1.
    pub accel_misalignment: Option<Matrix>,
    /// Their standard errors.
    pub accel_misalignment_std: Option<Matrix>,
    /// Gyro scale factors, 1.
    pub gyro_scale_factor: Option<[Option<f64>; 3]>,
    /// Their standard errors.
    pub gyro_scale_factor_std: Option<[Option<f64>; 3]>,
    /// Gyro misalignments, 1.
    pub gyro_misalignment: Option<Matrix>,
    /// Their standard errors.
    pub gyro_misalignment_std: Option<Matrix>,
    /// Gyro g-sensitivity, (rad/s)/(m/s^2).
    pub gyro_g_sensitivity_radps_per_mps2: Option<Matrix>,
    /// Its standard errors.
    pub gyro_g_sensitivity_std_radps_per_mps2: Option<Matrix>,
    /// Reference offset phi0 (e, n, u), rad.
    pub reference_offset_rad: Option<[Option<f64>; 3]>,
    /// Its standard error, rad.
    pub reference_offset_std_rad: Option<[Option<f64>; 3]>,
    /// Names of the determined parameters, in the order of `covariance`.
    pub parameters: Vec<&'static str>,
    /// Their covariance, SI units.
    pub covariance: Vec<Vec<f64>>,
    /// Parameters the schedule cannot determine (structural rank).
    pub unobservable: Vec<&'static str>,
    /// Weighted residual sum of squares.
    pub chi_square: f64,
    /// Its degrees of freedom.
    pub degrees_of_freedom: u32,
    /// The factors the standard errors and the covariance's square root carry beyond the dwell noise, one per
    /// channel (gyro x, y, z, accelerometer x, y, z): `sqrt(chi_square / degrees_of_freedom)` of that channel's
    /// residuals when that chi-square is beyond its 95 % point, else 1 (docs/method.md#fit-scale).
    pub fit_scale: [f64; 6],
    /// Extra: the determined parameters again without the suspect positions (channel method, when some are).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub without_suspect: Option<WithoutSuspectJson>,
    /// Extra: where gravity came from: "header" or "normal_gravity".
    pub gravity_source: &'static str,
    /// Extra: the positions' attitudes: "reference", or "estimated" (channel method on a recording levelled
    /// from its own accelerometers: the direction of gravity of every position is a nuisance parameter).
    pub attitude: &'static str,
    /// Extra: parameters held at zero to fix the body frame when the attitudes are estimated (also in
    /// `unobservable`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub gauge: Vec<&'static str>,
    /// Extra: the prefilter that ran.
    pub prefilter: PrefilterJson,
    /// The noise each channel's errors rest on (docs/formats.md#calibration-json-version-2).
    pub noise: NoiseJson,
    /// Extra: "mean" or "settled".
    pub dwell_value: &'static str,
    /// Samples not used as spikes, per dwell in the order of `positions` (docs/method.md#spikes).
    pub spikes_rejected: Vec<u32>,
    /// How well the labelled attitudes were taken to be known, degrees (one standard deviation, each axis; 0:
    /// exact), docs/method.md#poses-known-to-a-tolerance.
    pub pose_tolerance_deg: f64,
    /// Extra: passes of the solution (1 = the paper's linear solution).
    pub passes: u32,
    /// Extra: whether the refinement converged.
    pub converged: bool,
    /// Extra: the moves between dwells the general estimator used (docs/method.md#moves).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub moves: Vec<crate::calibration::UsedMove>,
    /// Extra: passes of move integration and solution.
    #[serde(skip_serializing_if = "is_zero")]
    pub move_passes: u32,
    /// Extra: the moves' error beyond white rate noise, rad per axis, when they misfit it (docs/method.md#moves).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub move_error_rad: Option<f64>,
    /// Extra: where it ran: "recording" (values read directly), or the firmware path "host" / "qemu".
    pub on: &'static str,
    /// Extra: sampling counters of the firmware path.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<SamplingJson>,
    /// Extra: the device's record (`device run`, `device show`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub record: Option<RecordJson>,
    /// The checks run on the result, passed or failed (docs/formats.md#calibration-json-version-2): a failed one
    /// makes `calibrate` exit with status 3.
    pub checks: Vec<crate::calibration::checks::Check>,
    /// Extra: the recording.
    pub source: String,
    /// Extra: the sinscal version that wrote this.
    pub sinscal_version: &'static str,
}

/// The result without the suspect positions.
#[derive(Debug, Serialize)]
pub struct WithoutSuspectJson {
    /// Labels of the positions left out.
    pub positions: Vec<u32>,
    /// Names of the determined parameters.
    pub parameters: Vec<&'static str>,
    /// Their values, SI.
    pub values: Vec<f64>,
    /// Their standard errors, SI.
    pub std: Vec<f64>,
}

/// Sampling counters of the firmware path.
#[derive(Debug, Serialize)]
pub struct SamplingJson {
    /// Data-ready events.
    pub events: u32,
    /// Good readings.
    pub readings: u32,
    /// Items lost to a full queue.
    pub queue_full: u32,
    /// Bus errors, checksum errors, stalled counters, status flags, dead-bus (all-zero) frames.
    pub faults: [u32; 5],
    /// Samples missed by the data counter.
    pub missed_samples: u32,
}

/// The noise model each channel's errors rest on: where it came from, and per channel what it is.
#[derive(Debug, Serialize)]
pub struct NoiseJson {
    /// "recording": from the recording itself: the dwells' own Allan variances, pooled over the session
    /// (docs/method.md#honest-errors), or with `--noise recording` the noise model named from its longest dwell
    /// (the channels' `model` is then "terms"); "file": the noise model of a noise file (`--noise`,
    /// docs/method.md#noise-model).
    pub source: &'static str,
    /// Gyro x, y, z, accelerometer x, y, z (the gyros absent without gyro data).
    pub channels: Vec<ChannelNoiseJson>,
}

/// One channel's dwell noise in the JSON.
#[derive(Debug, Serialize)]
pub struct ChannelNoiseJson {
    /// `gyro_x` .. `accel_z`.
    pub channel: &'static str,
    /// "allan": from the Allan variance at `cluster_samples`; "white": the per-sample variance (dwells too short
    /// for two clusters), as for white noise; "terms": the noise file's terms.
    pub model: &'static str,
    /// White-equivalent variance per sample, SI squared ((rad/s)^2 or (m/s^2)^2): a dwell mean of N samples has
    /// the variance `white_equivalent_var_si / N` (with a noise file: at the session's longest dwell).
    pub white_equivalent_var_si: f64,
    /// The cluster size it was taken at, samples (0 with a noise file).
    pub cluster_samples: u32,
    /// Its degrees of freedom (the Allan differences it rests on; absent with a noise file, whose model is
    /// taken as known).
    pub degrees_of_freedom: Option<f64>,
    /// The noise file's terms, SI (`quantisation_u_s`, `white_u_sqrt_s`, `instability_u`, `gauss_markov_u`,
    /// `gauss_markov_time_s`, `random_walk_u_per_sqrt_s`, `ramp_u_per_s`, `sway_u_s`, `sway_time_s`; U = rad/s
    /// or m/s^2).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terms: Option<NoiseTermsJson>,
}

/// A channel's noise terms in the JSON, SI.
#[derive(Debug, Serialize)]
pub struct NoiseTermsJson {
    /// Quantisation Q, U s.
    pub quantisation_u_s: f64,
    /// White noise N, U sqrt(s).
    pub white_u_sqrt_s: f64,
    /// Bias instability B, U.
    pub instability_u: f64,
    /// Gauss-Markov sigma, U.
    pub gauss_markov_u: f64,
    /// Gauss-Markov correlation time, s.
    pub gauss_markov_time_s: f64,
    /// Rate random walk K, U / sqrt(s).
    pub random_walk_u_per_sqrt_s: f64,
    /// Rate ramp R, U / s.
    pub ramp_u_per_s: f64,
    /// Sway S (the standard deviation of the channel's bounded integral), U s.
    pub sway_u_s: f64,
    /// Sway's correlation time, s.
    pub sway_time_s: f64,
}

impl NoiseJson {
    /// The noise the session's dwells were weighted by.
    fn new(c: &Calibration) -> NoiseJson {
        const NAMES: [&str; 6] = ["gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z"];
        let first = if c.has_gyro { 0 } else { 3 };
        if let Some(model) = &c.noise {
            let longest = c.positions.iter().map(|p| p.summary.samples).max().unwrap_or(1).max(1);
            let channels = (first..6)
                .map(|i| {
                    let t = model.channels[i];
                    ChannelNoiseJson {
                        channel: NAMES[i],
                        model: "terms",
                        white_equivalent_var_si: model.mean_variance(i, longest) as f64 * longest as f64,
                        cluster_samples: 0,
                        degrees_of_freedom: None,
                        terms: Some(NoiseTermsJson {
                            quantisation_u_s: t.quantisation_u_s as f64,
                            white_u_sqrt_s: t.white_u_sqrt_s as f64,
                            instability_u: t.instability_u as f64,
                            gauss_markov_u: t.gauss_markov_u as f64,
                            gauss_markov_time_s: t.gauss_markov_time_s as f64,
                            random_walk_u_per_sqrt_s: t.random_walk_u_per_sqrt_s as f64,
                            ramp_u_per_s: t.ramp_u_per_s as f64,
                            sway_u_s: t.sway_u_s as f64,
                            sway_time_s: t.sway_time_s as f64,
                        }),
                    }
                })
                .collect();
            let from_recording = c.options.noise.is_some_and(|t| t.from_recording);
            return NoiseJson { source: if from_recording { "recording" } else { "file" }, channels };
        }
        let pooled = sinscal::calib::dwell::pool_mean_noise(c.positions.iter().map(|p| p.summary));
        let channels = (first..6)
            .map(|i| ChannelNoiseJson {
                channel: NAMES[i],
                model: if pooled[i].cluster_samples > 1 { "allan" } else { "white" },
                white_equivalent_var_si: pooled[i].white_equivalent_var as f64,
                cluster_samples: pooled[i].cluster_samples,
                degrees_of_freedom: Some(pooled[i].dof as f64),
                terms: None,
            })
            .collect();
        NoiseJson { source: "recording", channels }
    }
}

/// The prefilter in the JSON.
#[derive(Debug, Serialize)]
pub struct PrefilterJson {
    /// "hmmkf" or "none".
    pub kind: &'static str,
    /// `a` of the gyro and accelerometer filters.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub a: Option<[f64; 2]>,
    /// Q of the gyro filters, (rad/s)^2, and of the accelerometer filters, (m/s^2)^2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub q: Option<[f64; 2]>,
    /// R of the gyro filters, (rad/s)^2, and of the accelerometer filters, (m/s^2)^2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub r: Option<[f64; 2]>,
}

/// A three-parameter term's values (or standard errors), null when the term is not in the model.
fn triple(e: &Estimates, term: Term, of: &[Option<f64>; PARAMETERS]) -> Option<[Option<f64>; 3]> {
    let (first, _) = term.parameters();
    e.model.contains(term).then(|| [of[first], of[first + 1], of[first + 2]])
}

/// A misalignment term as a matrix with zeros on the diagonal.
fn misalignment(e: &Estimates, term: Term, of: &[Option<f64>; PARAMETERS]) -> Option<Matrix> {
    let (first, _) = term.parameters();
    e.model.contains(term).then(|| {
        core::array::from_fn(|i| {
            core::array::from_fn(|j| if i == j { Some(0.0) } else { of[first + misalignment_index(i, j)] })
        })
    })
}

/// A full 3x3 term (the g-sensitivity), row by row.
fn full_matrix(e: &Estimates, term: Term, of: &[Option<f64>; PARAMETERS]) -> Option<Matrix> {
    let (first, _) = term.parameters();
    e.model.contains(term).then(|| core::array::from_fn(|i| core::array::from_fn(|j| of[first + 3 * i + j])))
}

fn f64s(v: [f32; 3]) -> [f64; 3] {
    v.map(|x| x as f64)
}

impl PositionJson {
    /// Position `k` (`p`) of a calibration.
    fn new(c: &Calibration, k: usize, p: &PositionResult) -> PositionJson {
        let channels = c.channels.as_ref();
        let resolved = channels.filter(|s| c.has_gyro && s.earth_rate_resolved);
        let estimated_heading = resolved.map(|s| (s.heading_rad[k] as f64).to_degrees());
        PositionJson {
            pos: p.pos,
            pitch_deg: p.attitude.pitch_deg,
            roll_deg: p.attitude.roll_deg,
            heading_deg: p.attitude.heading_deg.or(estimated_heading.map(|h| h.rem_euclid(360.0))),
            heading_known: p.attitude.heading_deg.is_some(),
            up_estimated_b: channels.filter(|s| estimated(s)).map(|s| f64s(s.up_b[k])),
            heading_std_deg: resolved
                .filter(|_| p.attitude.heading_deg.is_none())
                .map(|s| (s.heading_std_rad[k] as f64).to_degrees()),
            samples: p.summary.samples,
            spikes: p.summary.spikes,
            phi_rad: p.angles.map(|a| f64s(a.phi_n_rad)),
            phi_std_rad: p.angles.map(|a| [0, 1, 2].map(|i| (a.covariance_rad2.0[i][i] as f64).sqrt())),
            residual_rad: c.solution.as_ref().map(|s| f64s(s.residual_n_rad[k])),
            residual_gyro_radps: channels.filter(|_| c.has_gyro).map(|s| f64s(s.residual_rate_b_radps[k])),
            residual_accel_mps2: channels.map(|s| f64s(s.residual_force_b_mps2[k])),
            suspect: channels.is_some_and(|s| s.suspect & (1 << k) != 0),
            statistic: channels.map(|s| s.dwell_statistic[k] as f64).filter(|x| *x >= 0.0),
        }
    }
}

impl CalibrationJson {
    /// Builds the JSON document of a calibration. f32 values are widened to f64 exactly, and serde_json
    /// writes the shortest decimal that reads back to the same f64, hence to the same f32.
    pub fn new(c: &Calibration) -> CalibrationJson {
        let e = &c.estimates;
        let positions = c.positions.iter().enumerate().map(|(k, p)| PositionJson::new(c, k, p)).collect();
        let prefilter = match c.prefilter {
            Prefilter::None => PrefilterJson { kind: "none", a: None, q: None, r: None },
            Prefilter::HmmKf { gyro, accel } => PrefilterJson {
                kind: "hmmkf",
                a: Some([gyro.a as f64, accel.a as f64]),
                q: Some([gyro.q as f64, accel.q as f64]),
                r: Some([gyro.r as f64, accel.r as f64]),
            },
        };
        let (value, std) = (&e.value_si, &e.std_si);
        CalibrationJson {
            schema: "sinscal-calibration/2",
            method: e.method.name(),
            model: e.model_names(),
            latitude_deg: c.latitude_deg,
            gravity_mps2: c.site.gravity_mps2 as f64,
            positions,
            gyro_bias_radps: [value[0], value[1], value[2]],
            gyro_bias_std_radps: [std[0], std[1], std[2]],
            accel_bias_mps2: [value[3], value[4], value[5]],
            accel_bias_std_mps2: [std[3], std[4], std[5]],
            accel_scale_factor: triple(e, Term::AccelScaleFactor, value),
            accel_scale_factor_std: triple(e, Term::AccelScaleFactor, std),
            accel_misalignment: misalignment(e, Term::AccelMisalignment, value),
            accel_misalignment_std: misalignment(e, Term::AccelMisalignment, std),
            gyro_scale_factor: triple(e, Term::GyroScaleFactor, value),
            gyro_scale_factor_std: triple(e, Term::GyroScaleFactor, std),
            gyro_misalignment: misalignment(e, Term::GyroMisalignment, value),
            gyro_misalignment_std: misalignment(e, Term::GyroMisalignment, std),
            gyro_g_sensitivity_radps_per_mps2: full_matrix(e, Term::GyroGSensitivity, value),
            gyro_g_sensitivity_std_radps_per_mps2: full_matrix(e, Term::GyroGSensitivity, std),
            reference_offset_rad: triple(e, Term::ReferenceOffset, value),
            reference_offset_std_rad: triple(e, Term::ReferenceOffset, std),
            parameters: e.determined_names(),
            covariance: e.covariance_si.clone(),
            unobservable: e.unobservable_names(),
            chi_square: e.chi_square,
            degrees_of_freedom: e.degrees_of_freedom,
            fit_scale: e.std_scale,
            without_suspect: c.without_suspect.as_ref().map(|(positions, w)| WithoutSuspectJson {
                positions: positions.clone(),
                parameters: w.determined_names(),
                values: w.determined.iter().map(|&i| w.value_si[i].unwrap_or(f64::NAN)).collect(),
                std: w.determined.iter().map(|&i| w.std_si[i].unwrap_or(f64::NAN)).collect(),
            }),
            gravity_source: match c.gravity_source {
                GravitySource::Header => "header",
                GravitySource::NormalGravity => "normal_gravity",
            },
            attitude: if c.channels.as_ref().is_some_and(estimated) { "estimated" } else { "reference" },
            gauge: c.channels.as_ref().map_or_else(Vec::new, gauge_names),
            prefilter,
            spikes_rejected: c.positions.iter().map(|p| p.summary.spikes).collect(),
            noise: NoiseJson::new(c),
            pose_tolerance_deg: c.pose_tolerance_deg,
            dwell_value: match c.options.dwell_value {
                DwellValue::Mean => "mean",
                DwellValue::Settled => "settled",
            },
            passes: c.passes,
            converged: c.converged,
            moves: c.moves.clone(),
            move_passes: c.move_passes,
            move_error_rad: (c.move_error_rad > 0.0).then_some(c.move_error_rad),
            on: c.on,
            sampling: c.sampling.map(|s| SamplingJson {
                events: s.events,
                readings: s.readings,
                queue_full: s.queue_full,
                faults: [s.bus_errors, s.checksum_errors, s.stalled_counters, s.status_flags, s.dead_bus_frames],
                missed_samples: s.missed_samples,
            }),
            record: c.record.as_ref().map(|r| RecordJson {
                sequence: r.sequence,
                run_started_utc: r.run_started_utc.clone(),
                damaged_newer_sequence: r.damaged_newer,
            }),
            checks: crate::calibration::checks::checks(c),
            source: c.source.clone(),
            sinscal_version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// Whether a solution estimated the positions' attitudes (no reference attitudes).
fn estimated(s: &ChannelSolution) -> bool {
    s.attitude == AttitudeKnowledge::Unknown
}

/// Names of the parameters a solution held at zero to fix the body frame.
fn gauge_names(s: &ChannelSolution) -> Vec<&'static str> {
    (0..PARAMETERS).filter(|i| s.gauge & (1 << i) != 0).map(sinscal::calib::general::parameter_name).collect()
}

/// The pitch and roll (degrees) that put the body direction `up_b` up (docs/conventions.md#attitude).
fn pitch_roll_deg(up_b: [f32; 3]) -> (f64, f64) {
    let u = up_b.map(f64::from);
    (u[1].atan2(u[0].hypot(u[2])).to_degrees(), (-u[0]).atan2(u[2]).to_degrees())
}

/// Formats an estimate in a display unit: `+0.05012 ± 0.00041`, `unobservable`, or `-`.
fn show(e: &Estimates, index: usize, per_unit: f64, decimals: usize) -> String {
    match (e.value_si[index], e.std_si[index]) {
        (Some(v), Some(sd)) => format!("{:+.*} ± {:.*}", decimals, v / per_unit, decimals, sd / per_unit),
        _ if e.unobservable.contains(&index) => "unobservable".to_string(),
        _ => "-".to_string(),
    }
}

/// One term's lines in the summary.
fn show_term(out: &mut String, e: &Estimates, term: Term, title: &str, per_unit: f64, decimals: usize) {
    if !e.model.contains(term) {
        return;
    }
    let (first, count) = term.parameters();
    let _ = writeln!(out, "{title}:");
    for i in first..first + count {
        let name = sinscal::calib::general::parameter_name(i);
        let axes = name.rsplit('_').next().unwrap_or("");
        let _ = writeln!(out, "  {axes:<2} {}", show(e, i, per_unit, decimals));
    }
}

/// How the poses were taken: exact labels, known to a tolerance, or estimated.
fn poses_line(c: &Calibration) -> String {
    if c.channels.as_ref().is_some_and(estimated) {
        "estimated from the data (|f| = g)".to_string()
    } else if c.pose_tolerance_deg > 0.0 {
        format!(
            "the labels known to {} deg (one standard deviation, each axis): each dwell's attitude error is a \
             nuisance with that prior",
            c.pose_tolerance_deg
        )
    } else {
        "the labels taken as exact".to_string()
    }
}

/// What the dwells were weighted by: the noise file's model or the session's own dwell noise.
fn noise_line(c: &Calibration) -> String {
    if c.options.noise.is_some_and(|t| t.from_recording) {
        "each dwell weighted by the noise model of the recording's longest dwell at its length, with the \
         correlation between dwells (docs/method.md#noise-model)"
            .to_string()
    } else if c.noise.is_some() {
        "each dwell weighted by the noise file's model at its length, with the correlation between dwells \
         (docs/method.md#noise-model)"
            .to_string()
    } else {
        "each dwell weighted by the session's own dwell noise (its Allan variances, pooled)".to_string()
    }
}

/// The spike gate's count: which dwells lost samples as spikes, or that none did.
fn spikes_line(c: &Calibration) -> String {
    let hit: Vec<String> = c
        .positions
        .iter()
        .filter(|p| p.summary.spikes > 0)
        .map(|p| format!("{} in position {}", p.summary.spikes, p.pos))
        .collect();
    if hit.is_empty() {
        format!("no sample beyond the gate (at least {} standard deviations of its dwell's level)", GATE_WIDTH_SIGMA)
    } else {
        format!(
            "samples not used as spikes (beyond the gate, at least {} standard deviations of the dwell's level): {}",
            GATE_WIDTH_SIGMA,
            hit.join(", ")
        )
    }
}

/// The human summary of a calibration.
pub fn summary(c: &Calibration) -> String {
    let e = &c.estimates;
    let mut out = String::new();
    let gravity_from = match c.gravity_source {
        GravitySource::Header => "from the header",
        GravitySource::NormalGravity => "WGS-84 normal gravity",
    };
    let _ = writeln!(
        out,
        "sinscal calibrate: {} ({} positions, latitude {} deg, g = {:.6} m/s^2 {gravity_from}{})",
        c.source,
        c.positions.len(),
        c.latitude_deg,
        c.site.gravity_mps2,
        if c.has_gyro { "" } else { "; no gyro data" }
    );
    let prefilter = match c.prefilter {
        Prefilter::None => "none (plain dwell means)".to_string(),
        Prefilter::HmmKf { gyro, accel } => {
            format!("HMM/KF, paper's Q and R, a = {:.3} (gyro), {:.3} (accel)", gyro.a, accel.a)
        }
    };
    let value = match c.options.dwell_value {
        DwellValue::Mean => "dwell mean",
        DwellValue::Settled => "settled filter output",
    };
    let method = match e.method {
        crate::calibration::Method::Angles if c.passes == 1 => {
            "angles (the paper's alignment-angle method, 1 pass: its linear solution)".to_string()
        }
        crate::calibration::Method::Angles => format!(
            "angles (the paper's alignment-angle method, {} passes{})",
            c.passes,
            if c.converged { ", converged" } else { ", NOT converged: the second-order terms are large" }
        ),
        crate::calibration::Method::Channels => format!(
            "channels (every channel of every dwell{}; model {}; {} Gauss-Newton passes{})",
            if c.channels.as_ref().is_some_and(estimated) {
                "; attitudes estimated, not taken from the recording: the direction of gravity of every position \
                 is estimated with the sensor model, |f| = g (docs/method.md#unknown-attitudes)"
            } else {
                ""
            },
            e.model_names().join(", "),
            c.passes,
            if c.converged { ", converged" } else { ", NOT converged" }
        ),
    };
    let _ = writeln!(out, "method: {method}\nprefilter: {prefilter}; the {value} of each dwell");
    let _ = writeln!(out, "spike gate: {}", spikes_line(c));
    if c.channels.is_some() {
        let _ = writeln!(out, "poses: {}", poses_line(c));
        let _ = writeln!(out, "noise: {}", noise_line(c));
    }
    let _ = writeln!(out);
    positions_table(&mut out, c);
    moves_table(&mut out, c);
    terms(&mut out, e);
    if c.channels.as_ref().is_some_and(|s| c.has_gyro && !s.earth_rate_resolved) {
        let _ = writeln!(
            out,
            "Gyros: their dwell means do not resolve the Earth rate ({:.1} deg/h): no heading is estimated, its \
             vertical part W sin L stays in the gyro model and its horizontal part, of unknown direction, is noise \
             (docs/method.md#unknown-attitudes); the dwells exercise the gyro scale factors and misalignments only \
             through the vertical part{}",
            sinscal::nav::earth::EARTH_RATE_RADPS as f64 / DEG_PER_HOUR,
            if c.moves.is_empty() { "" } else { " (the moves do)" }
        );
    }
    if let Some(s) = c.channels.as_ref().filter(|s| s.gauge != 0) {
        let _ = writeln!(
            out,
            "Body frame: the accelerometer triad (x along accelerometer x, y in its x-y plane): {} held at 0, the \
             other terms in that frame (a common rotation of all positions is not seen without reference attitudes)",
            gauge_names(s).join(", ")
        );
    }
    fit(&mut out, e, crate::calibration::checks::noise_dof(c));
    suspects(&mut out, c);
    if let Some(r) = &c.record {
        let started = r.run_started_utc.as_deref().map_or(String::new(), |t| format!(", its run started {t}"));
        let _ = writeln!(out, "Stored record: {}{started}", r.sequence);
    }
    checks_line(&mut out, &crate::calibration::checks::checks(c));
    out
}

/// "checks: all N passed", or the failed ones, one a line (docs/cli.md#checks).
fn checks_line(out: &mut String, checks: &[crate::calibration::checks::Check]) {
    let failed = crate::calibration::checks::failed_lines(checks);
    if failed.is_empty() {
        let _ = writeln!(out, "checks: all {} passed", checks.len());
    } else {
        let _ = writeln!(out, "checks: {} of {} failed (exit status 3):", failed.len(), checks.len());
        for line in failed {
            let _ = writeln!(out, "  {line}");
        }
    }
}

/// The moves used: where, how long, how far they turned, and the rotation error left after the fit.
fn moves_table(out: &mut String, c: &Calibration) {
    if c.moves.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "Moves between positions (the gyro rotation against the reference; {} passes of integration and solution):",
        c.move_passes
    );
    let _ = writeln!(
        out,
        " from -> to      line  duration      angle | error after the fit [arcsec]: x    y    z | statistic"
    );
    if c.move_error_rad > 0.0 {
        let _ = writeln!(
            out,
            " the moves between positions misfit their white rate noise: each weighted with an error of {:.3} deg \
             per axis more, named from their residuals (hand moves; docs/method.md#moves)",
            c.move_error_rad.to_degrees()
        );
    }
    for m in &c.moves {
        let r = m.residual_rad.map(|x| x * ARCSEC_PER_RAD);
        let between = match m.turn {
            Some(axis) => format!("turn about {axis}"),
            None => format!("{:>4} -> {:<4}", m.from_pos, m.to_pos),
        };
        let _ = writeln!(
            out,
            " {between:<12} {:>6} {:>8.2} s {:>6.1} deg | {:>+9.2} {:>+9.2} {:>+9.2} | {}",
            m.first_line,
            m.duration_s,
            m.angle_deg,
            r[0],
            r[1],
            r[2],
            if m.held_out {
                "held out of the fit: the calibration's error on it".to_string()
            } else if m.refused {
                "left out: more than 45 deg from the reference's rotation, no move of the table".to_string()
            } else if m.statistic >= 0.0 {
                format!("{:.1}", m.statistic)
            } else {
                "left out".to_string()
            }
        );
    }
}

/// The per-position table: channel residuals (channel method) or alignment angles (angle method).
fn positions_table(out: &mut String, c: &Calibration) {
    match &c.channels {
        Some(s) => {
            let _ = writeln!(
                out,
                " pos   pitch    roll  heading  samples | residual gyro [deg/h]  x       y       z   | residual accel [ug]  x        y        z    | statistic"
            );
            for (k, p) in c.positions.iter().enumerate() {
                let heading = match p.attitude.heading_deg {
                    Some(h) => format!("{h:>8.2}"),
                    None if c.has_gyro && s.earth_rate_resolved => {
                        format!("{:>7.1}?", (s.heading_rad[k] as f64).to_degrees().rem_euclid(360.0))
                    }
                    None => "       ?".to_string(),
                };
                let (pitch, roll) = if estimated(s) {
                    let (p, r) = pitch_roll_deg(s.up_b[k]);
                    (format!("{p:>6.2}?"), format!("{r:>6.2}?"))
                } else {
                    (format!("{:>7.2}", p.attitude.pitch_deg), format!("{:>7.2}", p.attitude.roll_deg))
                };
                let rg = s.residual_rate_b_radps[k].map(|x| x as f64 / DEG_PER_HOUR);
                let rg: [String; 3] = rg.map(|x| if c.has_gyro { format!("{x:>+9.4}") } else { format!("{:>9}", "-") });
                let ra = s.residual_force_b_mps2[k].map(|x| x as f64 / MICRO_G);
                let stat = s.dwell_statistic[k];
                let _ = writeln!(
                    out,
                    "{:>4} {pitch} {roll} {heading} {:>8} |  {} {} {} |  {:>+9.2} {:>+9.2} {:>+9.2} | {}{}",
                    p.pos,
                    p.summary.samples,
                    rg[0],
                    rg[1],
                    rg[2],
                    ra[0],
                    ra[1],
                    ra[2],
                    if stat >= 0.0 { format!("{stat:.1}") } else { "-".to_string() },
                    if s.suspect & (1 << k) != 0 { "  SUSPECT" } else { "" }
                );
            }
            if estimated(s) {
                let _ = writeln!(
                    out,
                    "(? = estimated: pitch and roll from calibrated gravity{}, in the body frame of the calibration)",
                    if c.has_gyro && s.earth_rate_resolved { ", heading from the Earth rate" } else { "" }
                );
            } else if c.positions.iter().any(|p| p.attitude.heading_deg.is_none()) && c.has_gyro {
                let _ = writeln!(
                    out,
                    "(? = heading unknown in the recording: {})",
                    if s.earth_rate_resolved {
                        "estimated from the Earth rate"
                    } else {
                        "not estimated, the gyros do not resolve the Earth rate"
                    }
                );
            }
        }
        None => {
            let _ = writeln!(
                out,
                " pos   pitch    roll  heading  samples |  misalignment phi [arcsec]     e          n          u   | residual [arcsec] e, n, u"
            );
            let residuals = c.solution.as_ref().map(|s| s.residual_n_rad);
            for (k, p) in c.positions.iter().enumerate() {
                let Some(angles) = p.angles else { continue };
                let phi = angles.phi_n_rad.map(|x| x as f64 * ARCSEC_PER_RAD);
                let sd = [0, 1, 2].map(|i| (angles.covariance_rad2.0[i][i] as f64).sqrt() * ARCSEC_PER_RAD);
                let res = residuals.map_or([0.0; 3], |r| r[k].map(|x| x as f64 * ARCSEC_PER_RAD));
                let _ = writeln!(
                    out,
                    "{:>4} {:>7.2} {:>7.2} {:>8.2} {:>8} |  {:>+9.2}±{:<6.2} {:>+9.2}±{:<6.2} {:>+9.1}±{:<6.1} | {:>+7.2} {:>+7.2} {:>+7.1}",
                    p.pos,
                    p.attitude.pitch_deg,
                    p.attitude.roll_deg,
                    p.attitude.heading_deg.unwrap_or(f64::NAN),
                    p.summary.samples,
                    phi[0],
                    sd[0],
                    phi[1],
                    sd[1],
                    phi[2],
                    sd[2],
                    res[0],
                    res[1],
                    res[2]
                );
            }
        }
    }
}

/// Every term of the model, estimate ± standard error in a display unit, and the unobservable parameters.
fn terms(out: &mut String, e: &Estimates) {
    let _ = writeln!(out);
    show_term(out, e, Term::GyroBias, "Gyro bias, body frame [deg/h] (estimate ± standard error)", DEG_PER_HOUR, 5);
    show_term(out, e, Term::AccelBias, "Accelerometer bias, body frame [ug] (1 ug = 9.80665e-6 m/s^2)", MICRO_G, 2);
    show_term(out, e, Term::AccelScaleFactor, "Accelerometer scale factor [ppm]", 1e-6, 2);
    show_term(
        out,
        e,
        Term::AccelMisalignment,
        "Accelerometer misalignment, axis i along j [arcsec]",
        1.0 / ARCSEC_PER_RAD,
        2,
    );
    show_term(out, e, Term::GyroScaleFactor, "Gyro scale factor [ppm]", 1e-6, 1);
    show_term(out, e, Term::GyroMisalignment, "Gyro misalignment, axis i about j [arcsec]", 1.0 / ARCSEC_PER_RAD, 1);
    show_term(out, e, Term::GyroGSensitivity, "Gyro g-sensitivity [(deg/h)/g]", DEG_PER_HOUR / 9.80665, 4);
    show_term(
        out,
        e,
        Term::ReferenceOffset,
        "Reference (turntable) offset phi0, e n u [arcsec]",
        1.0 / ARCSEC_PER_RAD,
        2,
    );
    let unobservable = e.unobservable_names();
    if !unobservable.is_empty() {
        let _ = writeln!(out, "Not determined by this schedule: {}", unobservable.join(", "));
    }
}

/// The chi-square of the fit and, when it is significant, what the model misses.
fn fit(out: &mut String, e: &Estimates, noise_dof: f64) {
    let dof = e.degrees_of_freedom;
    let _ = write!(out, "Fit: chi-square {:.2} on {dof} degrees of freedom", e.chi_square);
    if dof > 0 {
        let ratio = e.chi_square / dof as f64;
        let p_value = crate::calibration::checks::fit_p_value(e, noise_dof).unwrap_or(1.0);
        let _ = write!(out, " (ratio {ratio:.2}, p = {p_value:.3})");
        if p_value < crate::calibration::checks::MISFIT_LEVEL {
            let _ = write!(
                out,
                "\n  The model misses something: the residuals are {:.1} times what the dwell noise explains.",
                ratio.sqrt()
            );
        }
        if e.std_scale != [1.0; 6] {
            let s = e.std_scale;
            let _ = write!(
                out,
                "\n  Fit scale per channel (the factor a channel's terms' standard errors above carry beyond the dwell \
                 noise alone): gyro x {:.2}, y {:.2}, z {:.2}; accelerometer x {:.2}, y {:.2}, z {:.2}.",
                s[0], s[1], s[2], s[3], s[4], s[5]
            );
        }
    }
    let _ = writeln!(out);
}

/// The suspect positions and the result without them.
fn suspects(out: &mut String, c: &Calibration) {
    if let Some(s) = &c.channels {
        let suspects: Vec<String> = c
            .positions
            .iter()
            .enumerate()
            .filter(|(k, _)| s.suspect & (1 << k) != 0)
            .map(|(_, p)| p.pos.to_string())
            .collect();
        if !suspects.is_empty() {
            let _ = writeln!(
                out,
                "Suspect positions (residuals beyond the 0.1 % level of the noise): {}",
                suspects.join(", ")
            );
            match &c.without_suspect {
                Some((left_out, w)) => {
                    let labels: Vec<String> = left_out.iter().map(u32::to_string).collect();
                    let _ = writeln!(
                        out,
                        "Without position(s) {} (the worst, left out one at a time until none is suspect; biases, \
                         estimate ± standard error):",
                        labels.join(", ")
                    );
                    let _ = writeln!(
                        out,
                        "  gyro [deg/h]: {}, {}, {}",
                        show(w, 0, DEG_PER_HOUR, 5),
                        show(w, 1, DEG_PER_HOUR, 5),
                        show(w, 2, DEG_PER_HOUR, 5)
                    );
                    let _ = writeln!(
                        out,
                        "  accel [ug]: {}, {}, {}",
                        show(w, 3, MICRO_G, 2),
                        show(w, 4, MICRO_G, 2),
                        show(w, 5, MICRO_G, 2)
                    );
                }
                None => {
                    let _ = writeln!(out, "Too few positions remain without them to solve again.");
                }
            }
        }
    }
}
