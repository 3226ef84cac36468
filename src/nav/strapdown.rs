//! The body's rotation over a move, from its gyro rates: a unit quaternion updated with the two-sample
//! coning-corrected rotation vector (the turntable's moves between dwells, where gyro scale factors and
//! misalignments show; the first part of the rotation calibration).
//!
//! Convention: the quaternion `q = [w, x, y, z]` (scalar first) rotates a vector from the body frame now to the body
//! frame at the start of the move, `v_start = q v_now q*`; the rotation matrix is `C_b(t)^b(0)`. A body-frame
//! rotation vector `phi` over an interval updates it on the right: `q <- q * q(phi)`.
//!
//! The update (two-sample, at a fixed sample interval `dt`): each rate sample is the body's mean rate over the
//! interval that ends with it (what a decimating IMU such as the ADIS outputs: the average of its internal
//! samples), so its angle increment is `d = w dt`; each pair of increments gives `phi = d1 + d2 + (2/3) d1 x d2`
//! (the coning term: the part of a rotation that the increments miss when the rotation axis itself turns). An
//! increment left over at the end is applied alone.

use crate::math::linalg::{cross, Mat3, Vec3};

/// A unit quaternion, scalar first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quat(pub [f32; 4]);

impl Quat {
    /// No rotation.
    pub const IDENTITY: Quat = Quat([1.0, 0.0, 0.0, 0.0]);

    /// The rotation by the angle `|v|` (rad) about `v`: the half-angle cosine and sine, by their series below
    /// 0.05 rad (a sample's rotation on a turntable: 10 deg/s over 20 ms is 0.0035 rad), where the terms left out
    /// (`t^6 / 46080`) are below f32 rounding, and by `cosf`, `sinf` above.
    pub fn from_rotation_vector(v: Vec3) -> Quat {
        let t2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        let (w, s) = if t2 < 2.5e-3 {
            // cos(t/2) and sin(t/2)/t to the t^4 term.
            (1.0 - t2 / 8.0 + t2 * t2 / 384.0, 0.5 - t2 / 48.0 + t2 * t2 / 3840.0)
        } else {
            let t = libm::sqrtf(t2);
            (libm::cosf(0.5 * t), libm::sinf(0.5 * t) / t)
        };
        Quat([w, s * v[0], s * v[1], s * v[2]])
    }

    /// The product `self * r` (first `r`, then `self`, as rotations of a vector).
    pub fn mul(&self, r: &Quat) -> Quat {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = r.0;
        Quat([
            a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
            a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
            a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
            a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
        ])
    }

    /// The inverse rotation.
    pub fn conjugate(&self) -> Quat {
        let [w, x, y, z] = self.0;
        Quat([w, -x, -y, -z])
    }

    /// Scaled back to unit length (the rounding of many products drifts it).
    pub fn normalized(&self) -> Quat {
        let n2: f32 = self.0.iter().map(|c| c * c).sum();
        let k = 1.0 / libm::sqrtf(n2);
        Quat(self.0.map(|c| c * k))
    }

    /// The rotation vector (angle times unit axis, rad; the angle in [0, pi]).
    pub fn to_rotation_vector(&self) -> Vec3 {
        // The same rotation with a non-negative scalar part: the angle within [0, pi].
        let q = if self.0[0] < 0.0 { self.0.map(|c| -c) } else { self.0 };
        let s = libm::sqrtf(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if s < 1e-6 {
            // angle / sin(angle/2) -> 2 for small angles.
            return [2.0 * q[1], 2.0 * q[2], 2.0 * q[3]];
        }
        let k = 2.0 * libm::atan2f(s, q[0]) / s;
        [k * q[1], k * q[2], k * q[3]]
    }

    /// The quaternion of a rotation matrix (Shepperd's method: from its largest of the four squared
    /// components, so that no division is by a small number), with a non-negative scalar part.
    pub fn from_mat3(m: &Mat3) -> Quat {
        let a = m.0;
        let trace = a[0][0] + a[1][1] + a[2][2];
        let candidates = [trace, a[0][0], a[1][1], a[2][2]];
        let mut k = 0;
        for i in 1..4 {
            if candidates[i] > candidates[k] {
                k = i;
            }
        }
        let q = match k {
            0 => {
                let s = 2.0 * libm::sqrtf(1.0 + trace);
                [0.25 * s, (a[2][1] - a[1][2]) / s, (a[0][2] - a[2][0]) / s, (a[1][0] - a[0][1]) / s]
            }
            1 => {
                let s = 2.0 * libm::sqrtf((1.0 + a[0][0] - a[1][1] - a[2][2]).max(0.0));
                [(a[2][1] - a[1][2]) / s, 0.25 * s, (a[0][1] + a[1][0]) / s, (a[0][2] + a[2][0]) / s]
            }
            2 => {
                let s = 2.0 * libm::sqrtf((1.0 + a[1][1] - a[0][0] - a[2][2]).max(0.0));
                [(a[0][2] - a[2][0]) / s, (a[0][1] + a[1][0]) / s, 0.25 * s, (a[1][2] + a[2][1]) / s]
            }
            _ => {
                let s = 2.0 * libm::sqrtf((1.0 + a[2][2] - a[0][0] - a[1][1]).max(0.0));
                [(a[1][0] - a[0][1]) / s, (a[0][2] + a[2][0]) / s, (a[1][2] + a[2][1]) / s, 0.25 * s]
            }
        };
        let q = if q[0] < 0.0 { q.map(|c| -c) } else { q };
        Quat(q).normalized()
    }

    /// The rotation matrix (it maps a vector of the body frame now to the body frame at the start).
    pub fn to_mat3(&self) -> Mat3 {
        let [w, x, y, z] = self.0;
        Mat3([
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
            [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
            [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
        ])
    }
}

/// The body's rotation since the start of a move, from gyro rates at a fixed sample interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveIntegrator {
    dt_s: f32,
    coning: bool,
    attitude: Quat,
    /// The first increment of a pair, waiting for the second.
    pending: Option<Vec3>,
    samples: u32,
}

impl MoveIntegrator {
    /// An integrator for rates sampled every `dt_s` seconds, with the coning correction.
    pub fn new(dt_s: f32) -> MoveIntegrator {
        MoveIntegrator { dt_s, coning: true, attitude: Quat::IDENTITY, pending: None, samples: 0 }
    }

    /// The same without the coning term (each increment applied alone): the first-order update, kept to measure
    /// what the coning term gains.
    pub fn without_coning(dt_s: f32) -> MoveIntegrator {
        MoveIntegrator { coning: false, ..MoveIntegrator::new(dt_s) }
    }

    /// One rate sample, body frame, rad/s: the mean rate over the interval that ends with it.
    pub fn push(&mut self, rate_b_radps: Vec3) {
        self.push_increment(rate_b_radps.map(|w| w * self.dt_s));
    }

    /// One angle increment, body frame, rad: the rotation vector of one sample interval to first order (the
    /// rate times its interval, when the intervals differ).
    pub fn push_increment(&mut self, increment: Vec3) {
        self.samples = self.samples.saturating_add(1);
        if !self.coning {
            self.apply(increment);
            return;
        }
        match self.pending.take() {
            None => self.pending = Some(increment),
            Some(first) => {
                let c = cross(first, increment);
                let k = 2.0 / 3.0;
                let phi = [
                    first[0] + increment[0] + k * c[0],
                    first[1] + increment[1] + k * c[1],
                    first[2] + increment[2] + k * c[2],
                ];
                self.apply(phi);
            }
        }
    }

    fn apply(&mut self, phi: Vec3) {
        self.attitude = self.attitude.mul(&Quat::from_rotation_vector(phi)).normalized();
    }

    /// The rotation after the last pair of increments, and the increment waiting for its pair.
    pub fn paired(&self) -> (Quat, Option<Vec3>) {
        (self.attitude, self.pending)
    }

    /// Samples pushed.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The rotation over the samples pushed (an unpaired last increment applied alone).
    pub fn rotation(&self) -> Quat {
        match self.pending {
            Some(last) => self.attitude.mul(&Quat::from_rotation_vector(last)).normalized(),
            None => self.attitude,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::linalg::rotation;

    #[test]
    fn quaternion_agrees_with_rodrigues_and_is_right_handed() {
        for v in [
            [0.0, 0.0, core::f32::consts::FRAC_PI_2],
            [0.3, -1.1, 0.4],
            [1e-4, 2e-4, -3e-4],
            [0.02, -0.03, 0.035],
            [-2.0, 0.5, 1.0],
        ] {
            let q = Quat::from_rotation_vector(v);
            let (m, r) = (q.to_mat3(), rotation(v));
            for i in 0..3 {
                for j in 0..3 {
                    assert!((m.0[i][j] - r.0[i][j]).abs() < 2e-6, "{v:?}: {m:?} vs {r:?}");
                }
            }
            let back = q.to_rotation_vector();
            for k in 0..3 {
                assert!((back[k] - v[k]).abs() < 2e-6 * (1.0 + v[k].abs()), "{v:?} -> {back:?}");
            }
        }
        // A quarter turn about z takes x to y.
        let y = Quat::from_rotation_vector([0.0, 0.0, core::f32::consts::FRAC_PI_2]).to_mat3().mul_vec([1.0, 0.0, 0.0]);
        assert!((y[1] - 1.0).abs() < 1e-6 && y[0].abs() < 1e-6);
        // Back from the matrix, also near a half turn and about each axis.
        for v in [[0.3, -1.1, 0.4], [3.1, 0.0, 0.0], [0.0, -3.0, 0.1], [0.05, 0.1, 3.1], [0.0; 3]] {
            let q = Quat::from_rotation_vector(v);
            let q = if q.0[0] < 0.0 { Quat(q.0.map(|c| -c)) } else { q };
            let back = Quat::from_mat3(&rotation(v));
            for k in 0..4 {
                assert!((back.0[k] - q.0[k]).abs() < 2e-6, "{v:?}: {back:?} vs {q:?}");
            }
        }
        // Products compose: a then b equals the matrix product.
        let (a, b) = ([0.2, 0.1, -0.3], [-0.4, 0.25, 0.1]);
        let qab = Quat::from_rotation_vector(a).mul(&Quat::from_rotation_vector(b)).to_mat3();
        let mab = rotation(a).mul(&rotation(b));
        for i in 0..3 {
            for j in 0..3 {
                assert!((qab.0[i][j] - mab.0[i][j]).abs() < 2e-6);
            }
        }
    }
}
