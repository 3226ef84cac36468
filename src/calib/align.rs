//! Analytic coarse alignment at one position (docs/method.md#step-2-alignment), its misalignment against the turntable
//! (step 3), and the covariance of those angles from the dwell statistics.

use crate::calib::dwell::DwellSummary;
use crate::math::linalg::{cross, norm, Mat3, Vec3};
use crate::nav::earth::Site;
use crate::nav::frames::misalignment_n_rad;

/// Why an alignment cannot be computed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AlignError {
    /// Specific force and angular rate are (nearly) parallel, or one is zero: the three reference
    /// vectors are coplanar and the attitude is not determined (at a pole, or with no signal).
    Degenerate,
    /// An input is NaN or infinite.
    NotFinite,
}

impl core::fmt::Display for AlignError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            AlignError::Degenerate => "specific force and angular rate are parallel: attitude not determined",
            AlignError::NotFinite => "alignment input is NaN or infinite",
        })
    }
}

impl core::error::Error for AlignError {}

/// The smallest accepted `sin` of the angle between measured specific force and angular rate.
/// (At latitude 89.9 deg the angle is 0.1 deg, sin = 1.7e-3.)
pub const MIN_FORCE_RATE_SINE: f32 = 1e-3;

/// Analytic coarse alignment from the dwell's specific force `f_b` and angular rate `w_b`.
///
/// With the reference vectors of a body at rest, `f_n = [0, 0, g]` (pointing up: the specific force, not
/// gravity) and `w_n = [0, W cos L, W sin L]`, form in each frame
///     v1 = f,   v2 = f x w,   v3 = (f x w) x f
/// and with `M = [v1 v2 v3]` the matrix whose COLUMNS are these vectors, `M_n = C_b^n M_b`, so
///     C_hat_b^n = M_n M_b^-1   ( = [v^n]^-T [v^b]^T of docs/method.md#step-2-alignment when the brackets hold the vectors as columns).
/// The result is not exactly orthogonal for noisy input; [`misalignment_n_rad`] reads the first-order
/// angles from its skew-symmetric part.
pub fn coarse_align(force_b_mps2: Vec3, rate_b_radps: Vec3, site: &Site) -> Result<Mat3, AlignError> {
    if !(force_b_mps2.iter().chain(rate_b_radps.iter()).all(|x| x.is_finite())) {
        return Err(AlignError::NotFinite);
    }
    let frame = |f: Vec3, w: Vec3| {
        let v2 = cross(f, w);
        Mat3::from_cols(f, v2, cross(v2, f))
    };
    let v2_b = cross(force_b_mps2, rate_b_radps);
    let denominator = norm(force_b_mps2) * norm(rate_b_radps);
    if denominator <= 0.0 || !denominator.is_finite() || norm(v2_b) < MIN_FORCE_RATE_SINE * denominator {
        return Err(AlignError::Degenerate);
    }
    let m_n = frame(site.force_at_rest_n_mps2(), site.earth_rate_n_radps());
    let m_b_inv = frame(force_b_mps2, rate_b_radps).inverse().ok_or(AlignError::Degenerate)?;
    let c_hat_b_n = m_n.mul(&m_b_inv);
    if !c_hat_b_n.is_finite() {
        return Err(AlignError::NotFinite);
    }
    Ok(c_hat_b_n)
}

/// Which value of the dwell the alignment uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DwellValue {
    /// The mean of the (prefiltered) channel over the dwell (default; minimum variance for white noise).
    Mean,
    /// The prefilter's state after the last sample (the paper's "settled output").
    Settled,
}

/// The alignment result of one position.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PositionAngles {
    /// The computed attitude `C_hat_b^n`.
    pub c_hat_b_n: Mat3,
    /// Misalignment against the reference, `(phi_e, phi_n, phi_u)`, rad (docs/conventions.md).
    pub phi_n_rad: Vec3,
    /// Covariance of `phi_n_rad` from the dwell's noise (white-noise model), rad^2.
    pub covariance_rad2: Mat3,
}

/// Aligns one dwell and measures its misalignment against the reference attitude `c_b_n`.
pub fn position_angles(
    summary: &DwellSummary,
    value: DwellValue,
    c_b_n: &Mat3,
    site: &Site,
) -> Result<PositionAngles, AlignError> {
    let sq = |v: Vec3| [v[0] * v[0], v[1] * v[1], v[2] * v[2]];
    let (force, rate, force_var, rate_var) = match value {
        DwellValue::Mean => {
            let n = summary.samples as f32;
            let fv = sq(summary.force_sample_std_b_mps2).map(|v| v / n);
            let wv = sq(summary.rate_sample_std_b_radps).map(|v| v / n);
            (summary.force_mean_b_mps2, summary.rate_mean_b_radps, fv, wv)
        }
        DwellValue::Settled => {
            let [gain_gyro, gain_accel] = summary.settled_noise_gain;
            let fv = sq(summary.force_sample_std_b_mps2).map(|v| v * gain_accel);
            let wv = sq(summary.rate_sample_std_b_radps).map(|v| v * gain_gyro);
            (summary.force_settled_b_mps2, summary.rate_settled_b_radps, fv, wv)
        }
    };
    let c_hat_b_n = coarse_align(force, rate, site)?;
    Ok(PositionAngles {
        c_hat_b_n,
        phi_n_rad: misalignment_n_rad(&c_hat_b_n, c_b_n),
        covariance_rad2: angle_covariance_rad2(c_b_n, force_var, rate_var, site),
    })
}

/// Covariance of the misalignment angles, rad^2, from the variances of the dwell values of the body-frame
/// channels (`force_var_b_mps2sq`, (m/s^2)^2; `rate_var_b_radps2`, (rad/s)^2; channels independent).
///
/// First order (docs/method.md#step-4-angles-and-biases with the errors `df`, `dw` in place of the biases):
///     phi_e = -df_n / g,   phi_n = df_e / g,   phi_u = -dw_e / (W cos L) + tan L df_e / g
/// with `df_n = C_b^n df_b` and `dw_n = C_b^n dw_b`. Note the correlation of `phi_n` and `phi_u` through
/// `df_e`.
pub fn angle_covariance_rad2(c_b_n: &Mat3, force_var_b_mps2sq: Vec3, rate_var_b_radps2: Vec3, site: &Site) -> Mat3 {
    let c = &c_b_n.0;
    let weighted = |r1: usize, r2: usize, var: Vec3| (0..3).map(|j| c[r1][j] * c[r2][j] * var[j]).sum::<f32>();
    let (e, n) = (0, 1);
    let g2 = site.gravity_mps2 * site.gravity_mps2;
    let omega = site.earth_rate_north_radps();
    let tan = site.tan_latitude();
    let var_fe = weighted(e, e, force_var_b_mps2sq) / g2;
    let var_fn = weighted(n, n, force_var_b_mps2sq) / g2;
    let cov_fe_fn = weighted(e, n, force_var_b_mps2sq) / g2;
    let var_we = weighted(e, e, rate_var_b_radps2) / (omega * omega);
    let ee = var_fn;
    let nn = var_fe;
    let en = -cov_fe_fn;
    let uu = var_we + tan * tan * var_fe;
    let nu = tan * var_fe;
    let eu = -tan * cov_fe_fn;
    Mat3([[ee, en, eu], [en, nn, nu], [eu, nu, uu]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nav::frames::Attitude;

    fn site() -> Site {
        Site { latitude_rad: 45.7796f32.to_radians(), gravity_mps2: 9.8063 }
    }

    #[test]
    fn exact_vectors_give_the_true_attitude() {
        let s = site();
        for (p, r, h) in [(0.0, 0.0, 0.0), (0.0, 90.0, 0.0), (3.0, -20.0, 250.0), (0.0, 0.0, 270.0)] {
            let c = Attitude::from_degrees(p, r, h).c_b_n();
            let f_b = c.transpose().mul_vec(s.force_at_rest_n_mps2());
            let w_b = c.transpose().mul_vec(s.earth_rate_n_radps());
            let phi = misalignment_n_rad(&coarse_align(f_b, w_b, &s).unwrap(), &c);
            assert!(phi.iter().all(|x| x.abs() < 3e-7), "({p},{r},{h}): {phi:?}");
        }
    }

    #[test]
    fn parallel_force_and_rate_are_rejected() {
        let s = site();
        assert_eq!(coarse_align([0.0, 0.0, 9.8], [0.0, 0.0, 7e-5], &s), Err(AlignError::Degenerate));
        assert_eq!(coarse_align([0.0, 0.0, 9.8], [0.0; 3], &s), Err(AlignError::Degenerate));
        assert_eq!(coarse_align([f32::NAN, 0.0, 9.8], [0.0, 7e-5, 0.0], &s), Err(AlignError::NotFinite));
    }

    #[test]
    fn covariance_is_symmetric_and_positive() {
        let s = site();
        let c = Attitude::from_degrees(0.0, 0.0, 30.0).c_b_n();
        let p = angle_covariance_rad2(&c, [1e-8, 2e-8, 3e-8], [1e-16, 2e-16, 3e-16], &s);
        for i in 0..3 {
            assert!(p.0[i][i] > 0.0);
            for j in 0..3 {
                assert_eq!(p.0[i][j], p.0[j][i]);
            }
        }
    }
}
