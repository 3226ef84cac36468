//! The nuisance angles of a dwell (its heading when unknown, its tilt when the attitudes are unknown):
//! profiled before each pass, and eliminated from the dwell's rows.

use crate::calib::general::estimator::{ChannelDwell, ChannelEstimator};
use crate::calib::general::linearise::{sensor_matrix, DwellRows, DWELL_ROWS};
use crate::calib::general::settings::AttitudeKnowledge;
use crate::calib::general::terms::{Model, PARAMETERS};
use crate::math::linalg::{norm, rotation, Mat3, Vec3};
use crate::nav::frames::{heading_rotation, Attitude};

/// Removes the nuisance columns from a dwell's rows by Householder reflections, one column at a time: the
/// first rows then carry all the nuisance information and are dropped (their number is returned); the rest are
/// orthogonal to the nuisance directions. This is the Schur complement of the nuisances in square-root form.
pub(super) fn eliminate_nuisances(d: &mut DwellRows, n: usize) -> usize {
    let m = d.rows;
    let mut top = 0;
    for col in 0..3 {
        if top >= m {
            break;
        }
        let h_norm = libm::sqrtf(d.h[top..m].iter().map(|x| x[col] * x[col]).sum());
        if h_norm == 0.0 {
            continue;
        }
        let alpha = if d.h[top][col] >= 0.0 { -h_norm } else { h_norm };
        let mut u = [0.0f32; DWELL_ROWS];
        for r in top..m {
            u[r] = d.h[r][col];
        }
        u[top] -= alpha;
        let uu: f32 = u[top..m].iter().map(|x| x * x).sum();
        if uu == 0.0 {
            continue;
        }
        // Reflect every column: the parameters', the right-hand side and the later nuisance columns.
        for c in 0..n + 4 {
            let value = |d: &DwellRows, r: usize| match c {
                c if c < n => d.a[r][c],
                c if c == n => d.y[r],
                c => d.h[r][c - n - 1],
            };
            let s: f32 = (top..m).map(|r| u[r] * value(d, r)).sum();
            let k = 2.0 * s / uu;
            for r in top..m {
                match c {
                    c if c < n => d.a[r][c] -= k * u[r],
                    c if c == n => d.y[r] -= k * u[r],
                    c => d.h[r][c - n - 1] -= k * u[r],
                }
            }
        }
        top += 1;
    }
    top
}

/// The tilt (`Rx(pitch) Ry(roll)`) that puts body direction `up_b` (any length) up.
pub(super) fn tilt_of_up(up_b: Vec3) -> Mat3 {
    let pitch_rad = libm::atan2f(up_b[1], libm::hypotf(up_b[0], up_b[2]));
    let roll_rad = libm::atan2f(-up_b[0], up_b[2]);
    Attitude { pitch_rad, roll_rad, heading_rad: 0.0 }.tilt()
}

impl ChannelEstimator {
    /// The weighted cost of one dwell at `heading` over the tilt `tilt` (gyro rows only: gravity does not see
    /// the heading).
    pub(super) fn heading_cost(
        &self,
        d: &ChannelDwell,
        tilt: &Mat3,
        theta: &[f32; PARAMETERS],
        heading: f32,
        model: Model,
    ) -> f32 {
        let lin = self.linearise(theta, &heading_rotation(heading).mul(tilt), model);
        let mut c = 0.0;
        for i in 0..3 {
            let r = d.rate_mean_b_radps[i] - lin.pred[i];
            c += r * r / d.rate_mean_var_b_radps2[i];
        }
        c
    }

    /// The heading that fits dwell `d` over `tilt` best given `theta`: a 5 deg grid, then Gauss-Newton in one
    /// dimension.
    pub(super) fn profile_heading(
        &self,
        d: &ChannelDwell,
        tilt: &Mat3,
        theta: &[f32; PARAMETERS],
        model: Model,
    ) -> f32 {
        let step = core::f32::consts::PI / 36.0;
        let mut best = (f32::INFINITY, 0.0f32);
        for i in 0..72 {
            let h = i as f32 * step;
            let c = self.heading_cost(d, tilt, theta, h, model);
            if c < best.0 {
                best = (c, h);
            }
        }
        let mut heading = best.1;
        for _ in 0..6 {
            let lin = self.linearise(theta, &heading_rotation(heading).mul(tilt), model);
            let (mut num, mut den) = (0.0f32, 0.0f32);
            for i in 0..3 {
                let r = d.rate_mean_b_radps[i] - lin.pred[i];
                let w = 1.0 / d.rate_mean_var_b_radps2[i];
                num += lin.d_attitude[i][2] * r * w;
                den += lin.d_attitude[i][2] * lin.d_attitude[i][2] * w;
            }
            if den <= 0.0 {
                break;
            }
            let delta = (num / den).clamp(-step, step);
            heading += delta;
            if delta.abs() < 1e-7 {
                break;
            }
        }
        heading
    }

    /// Which attitude angles of dwell `d` are nuisance parameters: tilt about e and n (unknown attitudes, or
    /// known to a tolerance), heading (gyro data used and resolving the Earth rate, and the heading unknown or
    /// known to a tolerance).
    pub(super) fn nuisances(&self, d: &ChannelDwell) -> [bool; 3] {
        let prior = self.priors(d);
        let tilt = self.settings.attitude == AttitudeKnowledge::Unknown || prior[0];
        let heading =
            self.settings.use_gyro && self.settings.earth_rate_resolved && (d.heading_rad.is_none() || prior[2]);
        [tilt, tilt, heading]
    }

    /// Which of dwell `d`'s attitude angles are nuisances with the prior N(0, tolerance^2) about the reference:
    /// the tilt when the attitudes are a reference known to a tolerance, the heading when it is given too and
    /// the gyros see it.
    pub(super) fn priors(&self, d: &ChannelDwell) -> [bool; 3] {
        let s = &self.settings;
        let tolerance = s.attitude == AttitudeKnowledge::Reference && s.pose_tolerance_rad > 0.0;
        let heading = tolerance && s.use_gyro && s.earth_rate_resolved && d.heading_rad.is_some();
        [tolerance, tolerance, heading]
    }

    /// The reference attitude of dwell `d` (its heading 0 when unknown).
    fn reference_attitude(d: &ChannelDwell) -> Mat3 {
        heading_rotation(d.heading_rad.unwrap_or(0.0)).mul(&d.tilt)
    }

    /// The small-angle attitude error (e, n, u), rad, that takes dwell `d`'s reference attitude to `c`:
    /// `c = (I - [phi x]) C_ref` to first order.
    pub(super) fn attitude_offset(d: &ChannelDwell, c: &Mat3) -> Vec3 {
        // M = c C_ref^T = I - [phi x]: phi from its antisymmetric part.
        let m = c.mul(&Self::reference_attitude(d).transpose()).0;
        [0.5 * (m[1][2] - m[2][1]), 0.5 * (m[2][0] - m[0][2]), 0.5 * (m[0][1] - m[1][0])]
    }

    /// Appends the prior rows of dwell `d`'s attitude angles known to a tolerance to its whitened `rows`, at
    /// the attitude `c`: per angle, `0 = phi + noise` with noise N(0, tolerance^2), that is the residual
    /// `-phi / tolerance` and the nuisance column `1 / tolerance`.
    pub(super) fn add_prior_rows(&self, d: &ChannelDwell, c: &Mat3, rows: &mut DwellRows) {
        let prior = self.priors(d);
        if prior == [false; 3] {
            return;
        }
        let phi = Self::attitude_offset(d, c);
        let inverse = 1.0 / self.settings.pose_tolerance_rad;
        for m in 0..3 {
            if prior[m] && rows.rows < DWELL_ROWS {
                let r = rows.rows;
                rows.a[r] = [0.0; PARAMETERS];
                rows.y[r] = -phi[m] * inverse;
                rows.h[r] = [0.0; 3];
                rows.h[r][m] = inverse;
                rows.rows += 1;
            }
        }
    }

    /// The attitude of dwell `d` that fits its means best given `theta`, with its heading: the tilt that puts
    /// the calibrated measured gravity `T_a^-1 (f - b_a)` up (unknown attitudes) or the reference's (known to a
    /// tolerance), the heading profiled over it when unknown, then Gauss-Newton on every nuisance angle with all
    /// of the dwell's rows and the priors of the angles known to a tolerance.
    pub(super) fn profile_attitude(&self, d: &ChannelDwell, theta: &[f32; PARAMETERS], model: Model) -> (Mat3, f32) {
        let prior = self.priors(d);
        let tilt = if self.settings.attitude == AttitudeKnowledge::Unknown {
            let b_a = [theta[3], theta[4], theta[5]];
            let f = [0, 1, 2].map(|i| d.force_mean_b_mps2[i] - b_a[i]);
            let t_a = sensor_matrix(theta, 6, 9);
            tilt_of_up(t_a.inverse().map_or(f, |t| t.mul_vec(f)))
        } else {
            d.tilt
        };
        let prior_weight = if prior == [false; 3] {
            0.0
        } else {
            1.0 / (self.settings.pose_tolerance_rad * self.settings.pose_tolerance_rad)
        };
        let active = self.nuisances(d);
        let mut heading = match d.heading_rad {
            Some(h) => h,
            None if active[2] => self.profile_heading(d, &tilt, theta, model),
            None => 0.0,
        };
        let mut c = heading_rotation(heading).mul(&tilt);
        let first = if self.settings.use_gyro { 0 } else { 3 };
        for _ in 0..4 {
            let lin = self.linearise(theta, &c, model);
            // The priors: N(0, tolerance^2) on each angle's offset from the reference.
            let offset = Self::attitude_offset(d, &c);
            let mut normal = Mat3::IDENTITY;
            let mut rhs = [0.0f32; 3];
            for a in 0..3 {
                if prior[a] {
                    normal.0[a][a] += prior_weight;
                    rhs[a] -= offset[a] * prior_weight;
                }
            }
            for ch in first..6 {
                let (measured, var) = d.channel(ch);
                let r = measured - lin.pred[ch];
                let j = [0, 1, 2].map(|m| if active[m] { lin.d_attitude[ch][m] } else { 0.0 });
                for a in 0..3 {
                    rhs[a] += j[a] * r / var;
                    for b in 0..3 {
                        normal.0[a][b] += j[a] * j[b] / var;
                    }
                }
            }
            // Equilibrated solve (the tilt and heading rows differ by orders of magnitude); an inactive angle
            // keeps its unit diagonal and a zero step.
            let scale = [0, 1, 2].map(|a| if normal.0[a][a] > 0.0 { 1.0 / libm::sqrtf(normal.0[a][a]) } else { 0.0 });
            let mut scaled = normal;
            for a in 0..3 {
                for b in 0..3 {
                    scaled.0[a][b] *= scale[a] * scale[b];
                }
                if scale[a] == 0.0 {
                    scaled.0[a][a] = 1.0;
                }
            }
            let Some(inverse) = scaled.inverse() else { break };
            let step = inverse.mul_vec([0, 1, 2].map(|a| rhs[a] * scale[a]));
            let mut phi = [0, 1, 2].map(|a| step[a] * scale[a]);
            let size = norm(phi);
            if !size.is_finite() {
                break;
            }
            if size > 0.1 {
                phi = phi.map(|x| x * 0.1 / size);
            }
            c = rotation([-phi[0], -phi[1], -phi[2]]).mul(&c);
            heading += phi[2];
            if size < 1e-7 {
                break;
            }
        }
        (c, heading)
    }
}
