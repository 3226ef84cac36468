//! Attitude conventions of docs/conventions.md and the misalignment angles of docs/method.md#step-3-misalignment-angles.
//!
//! Navigation frame n: East-North-Up. Body frame b: x right, y forward, z up. The turntable reports
//! pitch (nose up positive, about body x), roll (right wing down positive, about body y) and heading
//! (clockwise from north, 90 deg = east), and
//!     C_b^n = Rz(-heading) * Rx(pitch) * Ry(roll)
//! where `Ra(t)` is the right-handed (active) rotation about axis `a` by angle `t`.

use crate::math::linalg::{Mat3, Vec3};

/// Attitude of the body as a turntable reports it, in radians. Euler angles are an input format only:
/// everything downstream works with the direction cosine matrix [`Attitude::c_b_n`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Attitude {
    /// Pitch, rad, nose up positive (rotation about body x).
    pub pitch_rad: f32,
    /// Roll, rad, right wing down positive (rotation about body y).
    pub roll_rad: f32,
    /// True heading, rad, clockwise from north (pi/2 = east).
    pub heading_rad: f32,
}

impl Attitude {
    /// An attitude from angles in degrees (the unit of the recording files).
    pub fn from_degrees(pitch_deg: f32, roll_deg: f32, heading_deg: f32) -> Attitude {
        Attitude {
            pitch_rad: pitch_deg.to_radians(),
            roll_rad: roll_deg.to_radians(),
            heading_rad: heading_deg.to_radians(),
        }
    }

    /// The body-to-navigation direction cosine matrix `C_b^n = Rz(-psi) Rx(theta) Ry(gamma)`.
    pub fn c_b_n(&self) -> Mat3 {
        heading_rotation(self.heading_rad).mul(&self.tilt())
    }

    /// The attitude without its heading, `Rx(theta) Ry(gamma)`: `C_b^n = heading_rotation(psi) * tilt`. The
    /// direction of gravity in the body depends on it alone.
    pub fn tilt(&self) -> Mat3 {
        rot_x(self.pitch_rad).mul(&rot_y(self.roll_rad))
    }
}

/// The heading part of `C_b^n`: `Rz(-psi)` for the heading `psi` (clockwise from north).
pub fn heading_rotation(heading_rad: f32) -> Mat3 {
    rot_z(-heading_rad)
}

/// sin and cos of an angle, with exact values at multiples of 90 degrees, where turntable positions
/// usually are (libm's `cosf(pi/2)` is -4.4e-8, not 0: a spurious 0.01 arcsec tilt).
fn sin_cos(angle_rad: f32) -> (f32, f32) {
    let quarter = angle_rad / core::f32::consts::FRAC_PI_2;
    let nearest = libm::roundf(quarter);
    if (quarter - nearest).abs() < 1e-7 {
        match (nearest as i32).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        (libm::sinf(angle_rad), libm::cosf(angle_rad))
    }
}

/// Right-handed rotation about x by `t`.
fn rot_x(t: f32) -> Mat3 {
    let (s, c) = sin_cos(t);
    Mat3([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
}

/// Right-handed rotation about y by `t`.
fn rot_y(t: f32) -> Mat3 {
    let (s, c) = sin_cos(t);
    Mat3([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
}

/// Right-handed rotation about z by `t`.
fn rot_z(t: f32) -> Mat3 {
    let (s, c) = sin_cos(t);
    Mat3([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
}

/// Misalignment `phi = (phi_e, phi_n, phi_u)`, rad, of a computed attitude against the true one
/// (docs/conventions.md, docs/method.md#step-3-misalignment-angles):
///     C_hat_b^n = (I - [phi x]) C_b^n,   i.e.   [phi x] = I - C_hat_b^n (C_b^n)^T
/// read off the skew-symmetric part of `I - C_hat (C)^T`, so that a computed matrix that is not exactly
/// orthogonal (the analytic alignment of noisy vectors) still gives the first-order angles.
pub fn misalignment_n_rad(c_hat_b_n: &Mat3, c_b_n: &Mat3) -> Vec3 {
    let p = c_hat_b_n.mul(&c_b_n.transpose()).0;
    // E = I - P; [phi x] = [[0,-u,n],[u,0,-e],[-n,e,0]] => e = (E21 - E12)/2 = (P12 - P21)/2, etc.
    [0.5 * (p[1][2] - p[2][1]), 0.5 * (p[2][0] - p[0][2]), 0.5 * (p[0][1] - p[1][0])]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_vec(a: Vec3, b: Vec3) {
        for i in 0..3 {
            assert!((a[i] - b[i]).abs() < 1e-6, "{a:?} != {b:?}");
        }
    }

    #[test]
    fn spec_check_values() {
        // docs/conventions.md: (0,0,90) has body y pointing east.
        let c = Attitude::from_degrees(0.0, 0.0, 90.0).c_b_n();
        assert_vec(c.mul_vec([0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]);
        // (0,90,0) has body x pointing down and body z pointing east.
        let c = Attitude::from_degrees(0.0, 90.0, 0.0).c_b_n();
        assert_vec(c.mul_vec([1.0, 0.0, 0.0]), [0.0, 0.0, -1.0]);
        assert_vec(c.mul_vec([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0]);
        // Pitch up: the nose (body y) rises. Roll positive: the right wing (body x) goes down.
        let c = Attitude::from_degrees(10.0, 0.0, 0.0).c_b_n();
        assert!(c.mul_vec([0.0, 1.0, 0.0])[2] > 0.17);
        let c = Attitude::from_degrees(0.0, 10.0, 0.0).c_b_n();
        assert!(c.mul_vec([1.0, 0.0, 0.0])[2] < -0.17);
        // Heading 30 deg: the nose points 30 deg east of north.
        let c = Attitude::from_degrees(0.0, 0.0, 30.0).c_b_n();
        assert_vec(c.mul_vec([0.0, 1.0, 0.0]), [0.5, 0.866_025_4, 0.0]);
    }

    #[test]
    fn c_b_n_is_a_rotation() {
        let c = Attitude::from_degrees(12.0, -33.0, 217.0).c_b_n();
        let p = c.mul(&c.transpose());
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p.0[i][j] - want).abs() < 1e-6);
            }
        }
        assert!((c.det() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn misalignment_recovers_a_small_rotation_with_spec_sign() {
        // C_hat = (I - [phi x]) C  =>  the angles come back with the same sign.
        let c = Attitude::from_degrees(5.0, 80.0, 123.0).c_b_n();
        let phi = [2e-4f32, -3e-4, 5e-3];
        let c_hat = Mat3::IDENTITY;
        let i_minus_skew = Mat3([[1.0, phi[2], -phi[1]], [-phi[2], 1.0, phi[0]], [phi[1], -phi[0], 1.0]]);
        let c_hat = c_hat.mul(&i_minus_skew).mul(&c);
        let got = misalignment_n_rad(&c_hat, &c);
        for i in 0..3 {
            assert!((got[i] - phi[i]).abs() < 2e-7, "{got:?}");
        }
    }
}
