//! An exact calibration session computed by the core's own frames, the same on x86 and on the Cortex-M4F: 24
//! poses (each face up at four headings), every static term of the sensor model with known values of both
//! signs. The on-target tests solve it in QEMU and the host solves it on x86; the two results must agree bit
//! for bit, and both must give back the truth.

use heapless::Vec;

use crate::calib::channels::{g_sensitivity_radps_per_mps2, sensor_matrix, ChannelDwell, PARAMETERS};
use crate::math::linalg::rotation;
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;

/// Poses of the session.
pub const POSES: usize = 24;

/// The site of the session: 45.7796 N, normal gravity at height 0.
pub fn site() -> Site {
    Site::with_normal_gravity(45.7796f32.to_radians(), 0.0)
}

/// The true parameters, SI units, in the order of [`crate::calib::channels::parameter_name`].
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
            });
        }
    }
    out
}
