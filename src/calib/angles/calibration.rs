//! The whole calibration over a set of dwells: alignment of every position, the bias solution, and its
//! refinement by iteration.
//!
//! The relations of docs/method.md#step-4-angles-and-biases are first order. Their neglected terms are products of the
//! misalignment angles, e.g. the heading angle `phi_u = -eps_e / (W cos L)` is really
//! `-eps_e / (W cos L + eps_n)` to leading order, an error of `eps_e eps_n / (W cos L)`: 2.4e-4 deg/h at
//! 0.05 deg/h per axis, 0.024 deg/h at 0.5 deg/h. The refinement removes them: subtract the current bias
//! estimate from the dwell values, express the reference through the current offset estimate, align
//! again, solve for the correction, and repeat until the correction is negligible against its standard
//! error. The first pass is exactly the paper's method; the fixed point is the estimate whose
//! compensated data show no bias at all, to f32 precision.

use crate::calib::align::{position_angles, AlignError, DwellValue};
use crate::calib::angles::solve::{BiasSolution, BiasSolver, Estimate, SolveError, SolverSettings};
use crate::calib::dwell::DwellSummary;
use crate::calib::limits::FORCE_MAGNITUDE_ERROR_MAX_RELATIVE;
use crate::math::linalg::{norm, rotation, Mat3};
use crate::nav::earth::Site;

/// One position: the turntable's attitude and the dwell's statistics.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PositionInput {
    /// Reference attitude `C_b^n` from the turntable.
    pub c_b_n: Mat3,
    /// The dwell.
    pub summary: DwellSummary,
}

/// Settings of a calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationSettings {
    /// The solver's settings.
    pub solver: SolverSettings,
    /// Which dwell value the alignment uses.
    pub dwell_value: DwellValue,
    /// Passes at most (1 = the paper's single linear solution, no refinement).
    pub max_passes: u32,
}

impl Default for CalibrationSettings {
    fn default() -> CalibrationSettings {
        CalibrationSettings { solver: SolverSettings::default(), dwell_value: DwellValue::Mean, max_passes: 6 }
    }
}

/// Why a calibration failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CalibrationError {
    /// The alignment of a position failed (index into the positions).
    Align {
        /// Which position.
        index: usize,
        /// Why.
        error: AlignError,
    },
    /// The solution failed.
    Solve(SolveError),
    /// The first pass's alignment of a position differs from its reference attitude by more than
    /// [`MAX_LEVEL_MISALIGNMENT_RAD`] in level or [`MAX_HEADING_MISALIGNMENT_RAD`] in heading, at any angle: the reference
    /// or the axes do not match the data (a wrong face down, a heading a half turn off).
    Implausible {
        /// Which position.
        index: usize,
        /// Angle between the computed and the reference up axes, rad ([`attitude_difference_rad`]).
        level_rad: f32,
        /// Heading of the computed attitude less the reference's, rad, in (-pi, pi], of the sign of phi_u.
        heading_rad: f32,
    },
    /// The dwell's |f| differs from g by more than [`FORCE_MAGNITUDE_ERROR_MAX_RELATIVE`] (relative): an accelerometer
    /// scale error, or a body not at rest.
    ForceMagnitude {
        /// Which position.
        index: usize,
        /// |f| / g.
        ratio: f32,
    },
}

/// Largest level misalignment (phi_e, phi_n) accepted, rad: 0.05 rad (2.9 deg) is an accelerometer bias
/// of 50 mg. Larger means the reference attitude or the axis convention is wrong.
pub const MAX_LEVEL_MISALIGNMENT_RAD: f32 = 0.05;
/// Largest heading misalignment (phi_u) accepted, rad: 0.5 rad (29 deg) is an east gyro bias of about
/// 0.5 W cos L (about 5 deg/h at 45 deg latitude), beyond which gyrocompassing on the Earth rate
/// is not a calibration method any more.
pub const MAX_HEADING_MISALIGNMENT_RAD: f32 = 0.5;

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CalibrationError::Align { index, error } => {
                write!(f, "position {}: {error}", index + 1)
            }
            CalibrationError::Solve(e) => write!(f, "{e}"),
            CalibrationError::Implausible { index, level_rad, heading_rad } => write!(
                f,
                "position {}: alignment differs from the reference attitude by {:.2} deg in level and {:.2} deg \
                 in heading: the reference or the axes do not match the data (docs/conventions.md: ENU, body x \
                 right, y forward, z up)",
                index + 1,
                level_rad.to_degrees(),
                heading_rad.to_degrees()
            ),
            CalibrationError::ForceMagnitude { index, ratio } => write!(
                f,
                "position {}: |f| is {ratio:.4} g: an accelerometer scale error or a body not at rest",
                index + 1
            ),
        }
    }
}

impl core::error::Error for CalibrationError {}

/// The result of a calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationResult {
    /// The solution: biases accumulated over the passes, reference offset, standard errors and residuals
    /// of the last pass.
    pub solution: BiasSolution,
    /// Passes made.
    pub passes: u32,
    /// Whether the last correction was negligible (below 1e-3 of its standard error, or 1e-5 of the
    /// estimate). Always true for a single pass.
    pub converged: bool,
    /// Largest |correction| / standard error of the last pass.
    pub last_correction_sigma: f32,
}

/// How far the computed attitude is from the reference, at any angle (the misalignment angles are first
/// order, and a half turn about up has no skew-symmetric part at all): the angle between the two up axes, rad,
/// and the heading difference, rad, in (-pi, pi], of the sign of `phi_u` (`R = C_hat C^T = I - [phi x]` for
/// small angles, so `R[0][1] - R[1][0] = 2 phi_u`).
pub fn attitude_difference_rad(c_hat_b_n: &Mat3, c_b_n: &Mat3) -> (f32, f32) {
    let r = c_hat_b_n.mul(&c_b_n.transpose()).0;
    let level_rad = libm::acosf(r[2][2].clamp(-1.0, 1.0));
    let heading_rad = libm::atan2f(r[0][1] - r[1][0], r[0][0] + r[1][1]);
    (level_rad, heading_rad)
}

/// Calibrates from a set of positions (any number up to [`MAX_POSITIONS`](crate::calib::angles::MAX_POSITIONS)).
pub fn calibrate_positions(
    positions: &[PositionInput],
    site: &Site,
    settings: &CalibrationSettings,
) -> Result<CalibrationResult, CalibrationError> {
    // Estimates accumulated over the passes (unobservable parameters stay at zero: nothing is known of them).
    let mut gyro_bias_b_radps = [0.0f32; 3];
    let mut accel_bias_b_mps2 = [0.0f32; 3];
    let mut offset_n_rad = [0.0f32; 3];
    let mut passes = 0;
    let mut last: Option<BiasSolution> = None;
    let mut last_sigma = f32::INFINITY;
    let mut converged = false;
    while passes < settings.max_passes.max(1) {
        passes += 1;
        // The reference seen through the current offset: C' = R(-phi0) C, so that C_hat ~ C' for exact data.
        let correct_reference = rotation(offset_n_rad.map(|x| -x));
        let mut solver = BiasSolver::new(*site, settings.solver);
        for (index, p) in positions.iter().enumerate() {
            let mut s = p.summary;
            for i in 0..3 {
                s.rate_mean_b_radps[i] -= gyro_bias_b_radps[i];
                s.rate_settled_b_radps[i] -= gyro_bias_b_radps[i];
                s.force_mean_b_mps2[i] -= accel_bias_b_mps2[i];
                s.force_settled_b_mps2[i] -= accel_bias_b_mps2[i];
            }
            let c_b_n = correct_reference.mul(&p.c_b_n);
            // Plausibility first: checked on the data as measured (the first pass), not after corrections.
            if passes == 1 {
                let ratio = norm(p.summary.force_mean_b_mps2) / site.gravity_mps2;
                if (ratio - 1.0).abs() > FORCE_MAGNITUDE_ERROR_MAX_RELATIVE || ratio.is_nan() {
                    return Err(CalibrationError::ForceMagnitude { index, ratio });
                }
            }
            let angles = position_angles(&s, settings.dwell_value, &c_b_n, site)
                .map_err(|error| CalibrationError::Align { index, error })?;
            if passes == 1 {
                let (level_rad, heading_rad) = attitude_difference_rad(&angles.c_hat_b_n, &c_b_n);
                let too_far =
                    level_rad > MAX_LEVEL_MISALIGNMENT_RAD || heading_rad.abs() > MAX_HEADING_MISALIGNMENT_RAD;
                if too_far || level_rad.is_nan() || heading_rad.is_nan() {
                    return Err(CalibrationError::Implausible { index, level_rad, heading_rad });
                }
            }
            solver.add(&c_b_n, angles.phi_n_rad, &angles.covariance_rad2).map_err(CalibrationError::Solve)?;
        }
        let mut sol = solver.solve().map_err(CalibrationError::Solve)?;
        // Accumulate the corrections; the standard errors are those of the last (linear) pass.
        let mut sigma = 0.0f32;
        let mut small = true;
        let mut step = |total: &mut [f32; 3], est: &mut [Option<Estimate>; 3]| {
            for i in 0..3 {
                match est[i].as_mut() {
                    Some(e) => {
                        let correction = e.value;
                        total[i] += correction;
                        e.value = total[i];
                        let ratio = if e.std_error > 0.0 { correction.abs() / e.std_error } else { 0.0 };
                        sigma = sigma.max(ratio);
                        small &= ratio < 1e-3 || correction.abs() <= 1e-5 * total[i].abs();
                    }
                    None => total[i] = 0.0,
                }
            }
        };
        step(&mut gyro_bias_b_radps, &mut sol.gyro_bias_b_radps);
        step(&mut accel_bias_b_mps2, &mut sol.accel_bias_b_mps2);
        if sol.reference_offset_estimated {
            step(&mut offset_n_rad, &mut sol.reference_offset_n_rad);
        }
        last = Some(sol);
        last_sigma = sigma;
        if small || settings.max_passes <= 1 {
            converged = true;
            break;
        }
    }
    let solution = last.ok_or(CalibrationError::Solve(SolveError::NoPositions))?;
    Ok(CalibrationResult { solution, passes, converged, last_correction_sigma: last_sigma })
}
