//! An exact calibration session computed by the core's own frames, the same on x86 and on the Cortex-M4F: 24
//! poses (each face up at four headings), every static term of the sensor model with known values of both
//! signs. The on-target tests solve it in QEMU and the host solves it on x86; the two results must agree bit
//! for bit, and both must give back the truth. Likewise a move between two dwells ([`turning_move`]): known body
//! rates and forces through a gyro with every term, integrated with [`MoveSums`] compensated by that gyro's
//! parameters, finished on both machines and compared bit for bit ([`move_bits_hash`]).

use heapless::Vec;

use crate::calib::general::{g_sensitivity_radps_per_mps2, sensor_matrix, ChannelDwell, PARAMETERS};
use crate::calib::moves::{ChannelMove, MoveError, MoveSums};
use crate::math::linalg::{rotation, Vec3};
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
use crate::nav::strapdown::{MoveIntegrator, Quat};

/// Poses of the session.
pub const POSES: usize = 24;

/// The site of the session: 45.7796 N, normal gravity at height 0.
pub fn site() -> Site {
    Site::with_normal_gravity(45.7796f32.to_radians(), 0.0)
}

/// The true parameters, SI units, in the order of [`crate::calib::general::parameter_name`].
pub fn truth() -> [f32; PARAMETERS] {
    let deg_h = crate::nav::earth::EARTH_RATE_RADPS / 15.041;
    let ug = 9.806_65e-6;
    let mut t = [0.0f32; PARAMETERS];
    let values: [f32; PARAMETERS] = [
        0.05 * deg_h,
        -0.08 * deg_h,
        0.03 * deg_h,
        120.0 * ug,
        -80.0 * ug,
        60.0 * ug,
        150e-6,
        -90e-6,
        200e-6,
        40e-6,
        -60e-6,
        25e-6,
        -35e-6,
        50e-6,
        -20e-6,
        300e-6,
        -250e-6,
        180e-6,
        -150e-6,
        90e-6,
        120e-6,
        -70e-6,
        60e-6,
        -110e-6,
        0.02 * deg_h / 9.8,
        -0.01 * deg_h / 9.8,
        0.016 * deg_h / 9.8,
        -0.024 * deg_h / 9.8,
        0.008 * deg_h / 9.8,
        0.018 * deg_h / 9.8,
        -0.006 * deg_h / 9.8,
        0.022 * deg_h / 9.8,
        -0.014 * deg_h / 9.8,
        12e-6,
        -8e-6,
        20e-6,
    ];
    t.copy_from_slice(&values);
    t
}

/// The scale an error of parameter `index` is judged against: the Earth rate for gyro biases, g for
/// accelerometer biases, their ratio for the g-sensitivity, 1 for the dimensionless terms and radians.
pub fn physical_scale(index: usize) -> f32 {
    match index {
        0..=2 => crate::nav::earth::EARTH_RATE_RADPS,
        3..=5 => 9.8,
        24..=32 => crate::nav::earth::EARTH_RATE_RADPS / 9.8,
        _ => 1.0,
    }
}

/// A hash of the bits of every parameter, for comparing two solutions bit for bit through a text report (the
/// top exponent bit is cleared, so the hash prints as a finite f32).
pub fn bits_hash(parameters_si: &[f32; PARAMETERS]) -> f32 {
    let mut bits: u32 = 0;
    for (i, v) in parameters_si.iter().enumerate() {
        bits = bits.rotate_left(5) ^ v.to_bits() ^ (i as u32);
    }
    f32::from_bits(bits & 0x3fff_ffff)
}

/// The session's dwell means (navigation-grade weights: 0.005 deg/h and 1 ug per mean), headings known.
pub fn session() -> Vec<ChannelDwell, POSES> {
    let site = site();
    let t = truth();
    let (t_a, t_g) = (sensor_matrix(&t, 6, 9), sensor_matrix(&t, 15, 18));
    let g = g_sensitivity_radps_per_mps2(&t);
    let faces = [[0.0, 0.0], [180.0, 0.0], [90.0, 0.0], [-90.0, 0.0], [0.0, 90.0], [0.0, -90.0]];
    let mut out = Vec::new();
    for face in faces {
        for heading in [0.0f32, 90.0, 180.0, 270.0] {
            let attitude = Attitude::from_degrees(face[0], face[1], heading);
            let c_true = rotation([-t[33], -t[34], -t[35]]).mul(&attitude.c_b_n()).transpose();
            let f_b = c_true.mul_vec(site.force_at_rest_n_mps2());
            let w_b = c_true.mul_vec(site.earth_rate_n_radps());
            let (fa, wg, gf) = (t_a.mul_vec(f_b), t_g.mul_vec(w_b), g.mul_vec(f_b));
            let rate_std = 0.005 * crate::nav::earth::EARTH_RATE_RADPS / 15.041;
            let force_std = 9.806_65e-6;
            let _ = out.push(ChannelDwell {
                tilt: attitude.tilt(),
                heading_rad: Some(attitude.heading_rad),
                rate_mean_b_radps: [0, 1, 2].map(|i| wg[i] + t[i] + gf[i]),
                force_mean_b_mps2: [0, 1, 2].map(|i| fa[i] + t[3 + i]),
                rate_mean_var_b_radps2: [rate_std * rate_std; 3],
                force_mean_var_b_mps2sq: [force_std * force_std; 3],
                window: None,
            });
        }
    }
    out
}

/// Samples of [`turning_move`].
pub const MOVE_SAMPLES: u32 = 1000;
/// Sample interval of [`turning_move`], s (100 Hz).
pub const MOVE_DT_S: f32 = 0.01;
/// Per-sample variance of each gyro's output that [`turning_move`] is finished with, (rad/s)^2.
pub const MOVE_RATE_VAR_RADPS2: f32 = 1e-6;

/// The gyro of [`turning_move`], and the prior its rates are compensated with: a consumer-grade gyro with every
/// term of both signs (biases of 0.46 to 1.15 deg/s, scale factors and misalignments of 1e-3 to 3e-3,
/// g-sensitivity of 5e-5 to 3e-4 (rad/s)/(m/s^2)); the accelerometer terms are [`truth`]'s (a move does not use
/// them).
pub fn move_prior() -> [f32; PARAMETERS] {
    let mut p = truth();
    let gyro: [f32; 21] = [
        0.012, -0.008, 0.02, // bias, rad/s
        2e-3, -1.5e-3, 3e-3, // scale factors
        4e-3, -2e-3, 1e-3, -3e-3, 2.5e-3, -1e-3, // misalignments xy, xz, yx, yz, zx, zy
        1e-4, -2e-4, 3e-4, -1e-4, 2e-4, -3e-4, 5e-5, -5e-5, 1.5e-4, // g-sensitivity, (rad/s)/(m/s^2)
    ];
    p[0..3].copy_from_slice(&gyro[0..3]);
    p[15..33].copy_from_slice(&gyro[3..21]);
    p
}

/// The true body rate (rad/s) and specific force (m/s^2) of sample `k` of [`turning_move`]: a rate whose axis
/// turns and whose magnitude changes (0.32 to 0.59 rad/s), and a force that changes on every axis.
pub fn move_motion(k: u32) -> (Vec3, Vec3) {
    let k = k as f32;
    let rate_b_radps = [0.3 - 0.0006 * k, 0.1 + 0.0004 * k, -0.2 + 1e-7 * k * k];
    let force_b_mps2 = [1.2 - 0.002 * k, -0.5 + 0.0015 * k, 9.7 - 0.0003 * k];
    (rate_b_radps, force_b_mps2)
}

/// A move of [`MOVE_SAMPLES`] samples from dwell 0 to dwell 1: the outputs `T_g w + b_g + G f` and `T_a f + b_a` of
/// [`move_motion`] under [`move_prior`], integrated with [`MoveSums`] compensated by that prior and finished
/// with [`MOVE_RATE_VAR_RADPS2`] on every axis; and beside it the rotation of the true rates
/// ([`MoveIntegrator`]), which the compensated rotation must equal to the f32 rounding of the compensation.
pub fn turning_move() -> Result<(ChannelMove, Quat), MoveError> {
    let prior = move_prior();
    let t_g = sensor_matrix(&prior, 15, 18);
    let g = g_sensitivity_radps_per_mps2(&prior);
    let t_a = sensor_matrix(&prior, 6, 9);
    let mut sums = MoveSums::new(&prior)?;
    let mut truth = MoveIntegrator::new(MOVE_DT_S);
    for k in 0..MOVE_SAMPLES {
        let (w, f) = move_motion(k);
        let (tw, gf, ta) = (t_g.mul_vec(w), g.mul_vec(f), t_a.mul_vec(f));
        // The outputs of the sensor model: `T_g w + b_g + G f` and `T_a f + b_a`.
        let f_meas = [0, 1, 2].map(|i| ta[i] + prior[3 + i]);
        sums.push([0, 1, 2].map(|i| tw[i] + prior[i] + gf[i]), f_meas, MOVE_DT_S);
        truth.push(w);
    }
    Ok((sums.finish(0, 1, [MOVE_RATE_VAR_RADPS2; 3]), truth.rotation()))
}

/// FNV-1a (32 bits) over the bits of a finished move's rotation (4), duration, Jacobian (3 x 21, row by row)
/// and covariance (3 x 3, row by row), each f32's bytes little-endian first. A change of any one byte changes
/// the hash (each step of FNV-1a is a bijection of the state).
pub fn move_bits_hash(m: &ChannelMove) -> u32 {
    let values = m
        .rotation
        .0
        .iter()
        .chain(core::iter::once(&m.duration_s))
        .chain(m.jacobian.iter().flatten())
        .chain(m.covariance_rad2.0.iter().flatten());
    let mut hash: u32 = 0x811c_9dc5;
    for v in values {
        for byte in v.to_bits().to_le_bytes() {
            hash = (hash ^ u32::from(byte)).wrapping_mul(0x0100_0193);
        }
    }
    hash
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_turning_move_compensated_is_the_true_rotation_and_observes_every_gyro_term() {
        let (m, truth) = turning_move().unwrap();
        let error = m.rotation.conjugate().mul(&truth).to_rotation_vector();
        let error_rad = crate::math::linalg::norm(error);
        // 1.8e-7 rad on x86 and on the Cortex-M4F; the biases alone would turn the uncompensated rotation by 0.25
        // rad over the 10 s.
        assert!(error_rad < 2e-6, "{error_rad}");
        assert!((m.duration_s - 10.0).abs() < 1e-3, "{}", m.duration_s);
        for c in 0..crate::calib::moves::MOVE_COLUMNS {
            assert!((0..3).any(|a| m.jacobian[a][c] != 0.0), "column {c} of the Jacobian is zero");
        }
        assert!(m.covariance_rad2.0[0][0] > 0.0 && m.covariance_rad2.is_finite());
    }

    #[test]
    fn the_move_hash_sees_every_value() {
        let (m, _) = turning_move().unwrap();
        let hash = move_bits_hash(&m);
        let flipped = |f: &dyn Fn(&mut ChannelMove)| {
            let mut n = m;
            f(&mut n);
            move_bits_hash(&n)
        };
        let flip = |x: &mut f32| *x = f32::from_bits(x.to_bits() ^ 1);
        assert_ne!(flipped(&|n| flip(&mut n.rotation.0[3])), hash);
        assert_ne!(flipped(&|n| flip(&mut n.duration_s)), hash);
        for a in 0..3 {
            for c in 0..crate::calib::moves::MOVE_COLUMNS {
                assert_ne!(flipped(&|n| flip(&mut n.jacobian[a][c])), hash, "jacobian {a} {c}");
            }
            for b in 0..3 {
                assert_ne!(flipped(&|n| flip(&mut n.covariance_rad2.0[a][b])), hash, "covariance {a} {b}");
            }
        }
        // The prior is not hashed: it is the input.
        assert_eq!(flipped(&|n| flip(&mut n.prior_si[0])), hash);
    }
}
