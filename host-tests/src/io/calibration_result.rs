//! The calibration result as JSON (docs/formats.md#calibration-json) and as a human summary.

use std::fmt::Write as _;

use serde::Serialize;
use sinscal::calib::align::DwellValue;
use sinscal::calib::dwell::Prefilter;
use sinscal::calib::solve::{Estimate, Parameter};

use crate::calibration::{Calibration, GravitySource};
use crate::model::synth::{DEG_PER_HOUR, MICRO_G};

/// Arcseconds per radian.
pub const ARCSEC_PER_RAD: f64 = 206_264.806_247_096_36;

/// One position in the JSON.
#[derive(Debug, Serialize)]
pub struct PositionJson {
    /// Label.
    pub pos: u32,
    /// Reference pitch, degrees.
    pub pitch_deg: f64,
    /// Reference roll, degrees.
    pub roll_deg: f64,
    /// Reference heading, degrees.
    pub heading_deg: f64,
    /// Samples used.
    pub samples: u32,
    /// Misalignment (e, n, u), rad.
    pub phi_rad: [f64; 3],
    /// Standard deviation of each angle from the dwell noise, rad (extra field).
    pub phi_std_rad: [f64; 3],
    /// Residual of the bias model at this position, rad (extra field).
    pub residual_rad: [f64; 3],
}

/// The calibration JSON of docs/formats.md#calibration-json, with extra fields after the contract's.
#[derive(Debug, Serialize)]
pub struct CalibrationJson {
    /// "sinscal-calibration/1".
    pub schema: &'static str,
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
    /// Parameters the schedule cannot determine.
    pub unobservable: Vec<&'static str>,
    /// Extra: reference offset phi0 (e, n, u), rad; absent when not estimated.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_offset_rad: Option<[Option<f64>; 3]>,
    /// Extra: its standard error, rad.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_offset_std_rad: Option<[Option<f64>; 3]>,
    /// Extra: weighted residual sum of squares.
    pub chi_square: f64,
    /// Extra: its degrees of freedom.
    pub degrees_of_freedom: u32,
    /// Extra: where gravity came from: "header" or "normal_gravity".
    pub gravity_source: &'static str,
    /// Extra: the prefilter that ran.
    pub prefilter: PrefilterJson,
    /// Extra: "mean" or "settled".
    pub dwell_value: &'static str,
    /// Extra: passes of the solution (1 = the paper's linear solution).
    pub passes: u32,
    /// Extra: whether the refinement converged.
    pub converged: bool,
    /// Extra: where it ran: "recording" (values read directly), or the firmware path "host" / "qemu".
    pub on: &'static str,
    /// Extra: sampling counters of the firmware path.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampling: Option<SamplingJson>,
    /// Extra: the recording.
    pub source: String,
    /// Extra: the sinscal version that wrote this.
    pub sinscal_version: &'static str,
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
    /// Bus errors, checksum errors, stalled counters, status flags.
    pub faults: [u32; 4],
    /// Samples missed by the data counter.
    pub missed_samples: u32,
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

fn value(e: Option<Estimate>) -> Option<f64> {
    e.map(|e| e.value as f64)
}

fn std(e: Option<Estimate>) -> Option<f64> {
    e.map(|e| e.std_error as f64)
}

fn f64s(v: [f32; 3]) -> [f64; 3] {
    v.map(|x| x as f64)
}

impl CalibrationJson {
    /// Builds the JSON document of a calibration. f32 values are widened to f64 exactly, and serde_json
    /// writes the shortest decimal that reads back to the same f64, hence to the same f32.
    pub fn new(c: &Calibration) -> CalibrationJson {
        let s = &c.solution;
        let positions = c
            .positions
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let cov = p.angles.covariance_rad2.0;
                PositionJson {
                    pos: p.pos,
                    pitch_deg: p.attitude.pitch_deg,
                    roll_deg: p.attitude.roll_deg,
                    heading_deg: p.attitude.heading_deg.unwrap_or(f64::NAN),
                    samples: p.summary.samples,
                    phi_rad: f64s(p.angles.phi_n_rad),
                    phi_std_rad: [0, 1, 2].map(|i| (cov[i][i] as f64).sqrt()),
                    residual_rad: f64s(s.residual_n_rad[k]),
                }
            })
            .collect();
        let offset = s.reference_offset_estimated.then_some(s.reference_offset_n_rad);
        let prefilter = match c.prefilter {
            Prefilter::None => PrefilterJson { kind: "none", a: None, q: None, r: None },
            Prefilter::HmmKf { gyro, accel } => PrefilterJson {
                kind: "hmmkf",
                a: Some([gyro.a as f64, accel.a as f64]),
                q: Some([gyro.q as f64, accel.q as f64]),
                r: Some([gyro.r as f64, accel.r as f64]),
            },
        };
        CalibrationJson {
            schema: "sinscal-calibration/1",
            latitude_deg: c.latitude_deg,
            gravity_mps2: c.site.gravity_mps2 as f64,
            positions,
            gyro_bias_radps: s.gyro_bias_b_radps.map(value),
            gyro_bias_std_radps: s.gyro_bias_b_radps.map(std),
            accel_bias_mps2: s.accel_bias_b_mps2.map(value),
            accel_bias_std_mps2: s.accel_bias_b_mps2.map(std),
            unobservable: Parameter::ALL.iter().filter(|p| s.is_unobservable(**p)).map(|p| p.name()).collect(),
            reference_offset_rad: offset.map(|o| o.map(value)),
            reference_offset_std_rad: offset.map(|o| o.map(std)),
            chi_square: s.chi_square as f64,
            degrees_of_freedom: s.degrees_of_freedom,
            gravity_source: match c.gravity_source {
                GravitySource::Header => "header",
                GravitySource::NormalGravity => "normal_gravity",
            },
            prefilter,
            dwell_value: match c.options.dwell_value {
                DwellValue::Mean => "mean",
                DwellValue::Settled => "settled",
            },
            passes: c.passes,
            converged: c.converged,
            on: c.on,
            sampling: c.sampling.map(|s| SamplingJson {
                events: s.events,
                readings: s.readings,
                queue_full: s.queue_full,
                faults: [s.bus_errors, s.checksum_errors, s.stalled_counters, s.status_flags],
                missed_samples: s.missed_samples,
            }),
            source: c.source.clone(),
            sinscal_version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// Formats an estimate in a display unit: `+0.05012 ± 0.00041`, or `unobservable`.
fn show(e: Option<Estimate>, per_unit: f64, decimals: usize) -> String {
    match e {
        Some(e) => {
            format!("{:+.*} ± {:.*}", decimals, e.value as f64 / per_unit, decimals, e.std_error as f64 / per_unit)
        }
        None => "unobservable".to_string(),
    }
}

/// The human summary of a calibration.
pub fn summary(c: &Calibration) -> String {
    let s = &c.solution;
    let mut out = String::new();
    let gravity_from = match c.gravity_source {
        GravitySource::Header => "from the header",
        GravitySource::NormalGravity => "WGS-84 normal gravity",
    };
    let _ = writeln!(
        out,
        "sinscal calibrate: {} ({} positions, latitude {} deg, g = {:.6} m/s^2 {gravity_from})",
        c.source,
        c.positions.len(),
        c.latitude_deg,
        c.site.gravity_mps2
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
    let passes = if c.passes == 1 {
        "1 pass (the paper's linear solution)".to_string()
    } else {
        format!(
            "{} passes (first-order solution refined{})",
            c.passes,
            if c.converged { ", converged" } else { ", NOT converged: the second-order terms are large" }
        )
    };
    let _ = writeln!(out, "prefilter: {prefilter}; alignment uses the {value}; {passes}\n");
    let _ = writeln!(
        out,
        " pos   pitch    roll  heading  samples |  misalignment phi [arcsec]     e          n          u   | residual [arcsec] e, n, u"
    );
    for (k, p) in c.positions.iter().enumerate() {
        let phi = p.angles.phi_n_rad.map(|x| x as f64 * ARCSEC_PER_RAD);
        let sd = [0, 1, 2].map(|i| (p.angles.covariance_rad2.0[i][i] as f64).sqrt() * ARCSEC_PER_RAD);
        let res = s.residual_n_rad[k].map(|x| x as f64 * ARCSEC_PER_RAD);
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
    let axes = ["x", "y", "z"];
    let _ = writeln!(out, "\nGyro bias, body frame [deg/h] (estimate ± standard error):");
    for (i, axis) in axes.iter().enumerate() {
        let _ = writeln!(out, "  {axis}: {}", show(s.gyro_bias_b_radps[i], DEG_PER_HOUR, 5));
    }
    let _ = writeln!(out, "Accelerometer bias, body frame [ug] (1 ug = 9.80665e-6 m/s^2):");
    for (i, axis) in axes.iter().enumerate() {
        let _ = writeln!(out, "  {axis}: {}", show(s.accel_bias_b_mps2[i], MICRO_G, 2));
    }
    if s.reference_offset_estimated {
        let _ = writeln!(out, "Reference (turntable) offset phi0 [arcsec]:");
        for (i, axis) in ["e", "n", "u"].iter().enumerate() {
            let _ = writeln!(out, "  {axis}: {}", show(s.reference_offset_n_rad[i], 1.0 / ARCSEC_PER_RAD, 2));
        }
    }
    let unobservable: Vec<&str> = Parameter::ALL.iter().filter(|p| s.is_unobservable(**p)).map(|p| p.name()).collect();
    if !unobservable.is_empty() {
        let _ = writeln!(out, "Not determined by this schedule: {}", unobservable.join(", "));
    }
    let _ = writeln!(
        out,
        "Fit: chi-square {:.2} on {} degrees of freedom{}",
        s.chi_square,
        s.degrees_of_freedom,
        if s.degrees_of_freedom > 0 {
            format!(
                " (ratio {:.2}; about 1 when the bias-only model and white noise explain the angles)",
                s.chi_square as f64 / s.degrees_of_freedom as f64
            )
        } else {
            String::new()
        }
    );
    out
}
