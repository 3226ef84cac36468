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
use crate::calib::dwell::DwellSummary;
use crate::calib::solve::{BiasSolution, BiasSolver, Estimate, SolveError, SolverSettings};
use crate::math::linalg::{rotation, Mat3};
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
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CalibrationError::Align { index, error } => {
                write!(f, "position {}: {error}", index + 1)
            }
            CalibrationError::Solve(e) => write!(f, "{e}"),
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

/// Calibrates from a set of positions (any number up to [`crate::calib::solve::MAX_POSITIONS`]).
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
            let angles = position_angles(&s, settings.dwell_value, &c_b_n, site)
                .map_err(|error| CalibrationError::Align { index, error })?;
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
