//! The general estimator of the core (docs/method.md#general-estimator) on exact synthetic dwell means: every
//! static term of both signs, known and unknown headings, unknown attitudes (the imu_tk case), accelerometer-only
//! data, the structural observability at navigation-grade noise, and the plausibility checks. The data are
//! generated in f64 by the host's own model (model::sensor::Triad, model::synth::c_b_n), independently of the
//! core's formulas.

use sinscal::calib::general::{
    misalignment_index, parameter_name, AttitudeKnowledge, ChannelDwell, ChannelError, ChannelEstimator,
    ChannelSettings, ChannelSolution, Model, Term, GAUGE_PARAMETERS, PARAMETERS,
};
use sinscal::math::linalg::Mat3;
use sinscal::nav::earth::Site;
use sinscal::nav::frames::Attitude;
use sinscal_host::model::sensor::Triad;
use sinscal_host::model::synth::{
    c_b_n, earth_rate_n_radps, mul, mul_t_vec, mul_vec, rotation, transpose, M3, TABLE1_DEG,
};
use sinscal_host::stats::solve::inverse3;
use sinscal_host::study::factory::lower_triangular_form;

const LATITUDE_DEG: f64 = 45.7796;
const G_MPS2: f64 = 9.8063;
const W_RADPS: f64 = 7.292115e-5;

/// The true errors of a simulated IMU, in the order of the core's parameters.
fn truth(sign: f64) -> [f64; PARAMETERS] {
    let mut t = [0.0; PARAMETERS];
    let deg_h = W_RADPS / 15.041; // 1 deg/h in rad/s
    let ug = 9.80665e-6;
    // Biases of both signs, different sizes per axis.
    t[0..3].copy_from_slice(&[0.05 * deg_h, -0.08 * deg_h, 0.03 * deg_h]);
    t[3..6].copy_from_slice(&[120.0 * ug, -80.0 * ug, 60.0 * ug]);
    t[6..9].copy_from_slice(&[150e-6, -90e-6, 200e-6]);
    t[9..15].copy_from_slice(&[40e-6, -60e-6, 25e-6, -35e-6, 50e-6, -20e-6]);
    t[15..18].copy_from_slice(&[300e-6, -250e-6, 180e-6]);
    t[18..24].copy_from_slice(&[-150e-6, 90e-6, 120e-6, -70e-6, 60e-6, -110e-6]);
    let g_sens = 0.02 * deg_h / G_MPS2; // 0.02 deg/h per g
    for (k, s) in [1.0, -0.5, 0.8, -1.2, 0.4, 0.9, -0.3, 1.1, -0.7].iter().enumerate() {
        t[24 + k] = s * g_sens;
    }
    t[33..36].copy_from_slice(&[12e-6, -8e-6, 20e-6]);
    t.map(|x| x * sign)
}

fn misalignment(t: &[f64; PARAMETERS], first: usize) -> M3 {
    let mut m = [[0.0; 3]; 3];
    let mut k = first;
    for (i, row) in m.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            if i != j {
                *cell = t[k];
                k += 1;
            }
        }
    }
    m
}

/// Exact dwell means of a pose (pitch, roll, heading in degrees) for the true errors `t` of `model`.
fn dwell(t: &[f64; PARAMETERS], model: Model, pose: [f64; 3], heading_known: bool) -> ChannelDwell {
    dwell_with(t, model, pose, heading_known, 1.0)
}

/// As [`dwell`], with the Earth rate scaled by `earth` (0: gyros that do not see it).
fn dwell_with(t: &[f64; PARAMETERS], model: Model, pose: [f64; 3], heading_known: bool, earth: f64) -> ChannelDwell {
    let w_n = earth_rate_n_radps(LATITUDE_DEG.to_radians()).map(|x| earth * x);
    dwell_with_rate(t, model, pose, heading_known, w_n)
}

/// As [`dwell_with`] with the Earth rate `w_n_radps` (navigation frame) the gyros see.
fn dwell_with_rate(
    t: &[f64; PARAMETERS],
    model: Model,
    pose: [f64; 3],
    heading_known: bool,
    w_n_radps: [f64; 3],
) -> ChannelDwell {
    let keep = |term: Term, x: f64| if model.contains(term) { x } else { 0.0 };
    let part = |term: Term| -> [f64; PARAMETERS] {
        let (first, count) = term.parameters();
        let mut out = [0.0; PARAMETERS];
        for i in first..first + count {
            out[i] = keep(term, t[i]);
        }
        out
    };
    let (ab, asf, am) = (part(Term::AccelBias), part(Term::AccelScaleFactor), part(Term::AccelMisalignment));
    let (gb, gsf, gm, gg) =
        (part(Term::GyroBias), part(Term::GyroScaleFactor), part(Term::GyroMisalignment), part(Term::GyroGSensitivity));
    let off = part(Term::ReferenceOffset);
    let accel = Triad::new([ab[3], ab[4], ab[5]], [asf[6], asf[7], asf[8]], &misalignment(&am, 9), [[0.0; 3]; 3]);
    let g = [[gg[24], gg[25], gg[26]], [gg[27], gg[28], gg[29]], [gg[30], gg[31], gg[32]]];
    let gyro = Triad::new([gb[0], gb[1], gb[2]], [gsf[15], gsf[16], gsf[17]], &misalignment(&gm, 18), g);
    // The reported attitude sees the true one through the offset: C_true = R(-delta) C_ref.
    let c_ref = c_b_n(pose[0], pose[1], pose[2]);
    let c_true = mul(&rotation([-off[33], -off[34], -off[35]]), &c_ref);
    let f_b = mul_t_vec(&c_true, [0.0, 0.0, G_MPS2]);
    let w_b = mul_t_vec(&c_true, w_n_radps);
    let f = accel.measure(f_b, [0.0; 3]);
    let w = gyro.measure(w_b, f_b);
    let attitude = Attitude::from_degrees(pose[0] as f32, pose[1] as f32, pose[2] as f32);
    ChannelDwell {
        tilt: attitude.tilt(),
        heading_rad: heading_known.then_some(attitude.heading_rad),
        rate_mean_b_radps: w.map(|x| x as f32),
        force_mean_b_mps2: f.map(|x| x as f32),
        // Navigation-grade noise of a 1 min mean: 0.005 deg/h and 1 ug.
        rate_mean_var_b_radps2: [(0.005 * W_RADPS / 15.041) as f32; 3].map(|s| s * s),
        force_mean_var_b_mps2sq: [1e-6 * 9.80665_f32; 3].map(|s| s * s),
        window: None,
    }
}

fn site() -> Site {
    Site { latitude_rad: (LATITUDE_DEG as f32).to_radians(), gravity_mps2: G_MPS2 as f32 }
}

/// 24 poses: each of the six faces up, at four headings.
fn faces_by_headings() -> Vec<[f64; 3]> {
    let faces = [[0.0, 0.0], [180.0, 0.0], [90.0, 0.0], [-90.0, 0.0], [0.0, 90.0], [0.0, -90.0]];
    let mut poses = Vec::new();
    for f in faces {
        for h in [0.0, 90.0, 180.0, 270.0] {
            poses.push([f[0], f[1], h]);
        }
    }
    poses
}

fn solve(model: Model, poses: &[[f64; 3]], heading_known: bool, use_gyro: bool, sign: f64) -> ChannelSolution {
    let t = truth(sign);
    let mut est = ChannelEstimator::new(site(), ChannelSettings { model, use_gyro, ..ChannelSettings::default() });
    for p in poses {
        est.add(dwell(&t, model, *p, heading_known)).expect("dwell");
    }
    est.solve().expect("solve")
}

/// The physical scale a parameter's error is judged against: the Earth rate for gyro biases, g for
/// accelerometer biases, W/g for g-sensitivities, 1 for the dimensionless terms and radians.
fn scale_of(index: usize) -> f64 {
    match index {
        0..=2 => W_RADPS,
        3..=5 => G_MPS2,
        24..=32 => W_RADPS / G_MPS2,
        _ => 1.0,
    }
}

/// Every determined parameter of `model` within `tol` of its scale; returns the worst relative error.
fn assert_recovered(sol: &ChannelSolution, model: Model, sign: f64, tol: f64) -> f64 {
    assert_recovered_against(sol, model, &truth(sign), tol)
}

/// Every determined parameter of `model` within `tol` of its scale from `t`; returns the worst relative error.
fn assert_recovered_against(sol: &ChannelSolution, model: Model, t: &[f64; PARAMETERS], tol: f64) -> f64 {
    let mut worst = 0.0f64;
    for i in 0..PARAMETERS {
        if !model.has_parameter(i) {
            continue;
        }
        let Some((value, _std)) = sol.estimate(i) else { continue };
        let err = (value as f64 - t[i]).abs() / scale_of(i);
        // Signs included: the estimate has the sign of the truth wherever the truth is above the tolerance.
        if t[i].abs() / scale_of(i) > 10.0 * tol {
            assert_eq!(value.signum() as f64, t[i].signum(), "{}: sign", parameter_name(i));
        }
        assert!(err < tol, "{}: {} vs true {} (error {err:.2e} of its scale)", parameter_name(i), value, t[i]);
        worst = worst.max(err);
    }
    worst
}

#[test]
fn table1_biases_exact_both_signs() {
    for sign in [1.0, -1.0] {
        let sol = solve(Model::BIASES, &TABLE1_DEG, true, true, sign);
        assert_eq!(sol.unobservable, 0, "Table 1 determines every bias");
        let worst = assert_recovered(&sol, Model::BIASES, sign, 1e-6);
        println!("Table 1, biases, sign {sign:+}: worst error {worst:.2e} of scale, {} passes", sol.iterations);
        assert!(sol.converged);
    }
}

#[test]
fn every_static_term_exact_known_heading() {
    for sign in [1.0, -1.0] {
        let sol = solve(Model::FULL, &faces_by_headings(), true, true, sign);
        let names: Vec<&str> =
            (0..PARAMETERS).filter(|i| sol.unobservable & (1 << i) != 0).map(parameter_name).collect();
        assert!(names.is_empty(), "24 poses determine every static term; unobservable: {names:?}");
        let worst = assert_recovered(&sol, Model::FULL, sign, 1e-6);
        println!("full model, 24 poses, sign {sign:+}: worst error {worst:.2e} of scale, {} passes", sol.iterations);
    }
}

#[test]
fn every_static_term_exact_unknown_heading() {
    // Without headings the reference's heading offset is the headings' business: drop it from the model.
    let model = Model::FULL.without(Term::ReferenceOffset);
    for sign in [1.0, -1.0] {
        let sol = solve(model, &faces_by_headings(), false, true, sign);
        let names: Vec<&str> =
            (0..PARAMETERS).filter(|i| sol.unobservable & (1 << i) != 0).map(parameter_name).collect();
        println!("unknown headings, unobservable: {names:?}");
        let worst = assert_recovered(&sol, model, sign, 1e-6);
        println!("full model, unknown headings, sign {sign:+}: worst error {worst:.2e}, {} passes", sol.iterations);
        // The headings themselves come back.
        for (k, pose) in faces_by_headings().iter().enumerate() {
            let err = (sol.heading_rad[k] as f64 - pose[2].to_radians()).rem_euclid(std::f64::consts::TAU);
            let err = err.min(std::f64::consts::TAU - err);
            assert!(err < 1e-4, "dwell {k}: heading {} vs {}", sol.heading_rad[k].to_degrees(), pose[2]);
        }
    }
}

#[test]
fn accelerometer_only_six_faces() {
    let model = Model::FULL;
    let faces =
        [[0.0, 0.0, 0.0], [180.0, 0.0, 0.0], [90.0, 0.0, 0.0], [-90.0, 0.0, 0.0], [0.0, 90.0, 0.0], [0.0, -90.0, 0.0]];
    for sign in [1.0, -1.0] {
        let sol = solve(model.without(Term::ReferenceOffset), &faces, false, false, sign);
        assert_eq!(sol.model, model.without(Term::ReferenceOffset).accelerometer_only());
        // Six faces determine the accelerometer biases and scale factors; misalignments need tilted poses.
        for i in 3..9 {
            assert!(sol.estimate(i).is_some(), "{} must be determined", parameter_name(i));
        }
        assert_recovered(&sol, sol.model, sign, 1e-6);
    }
}

#[test]
fn x_up_x_down_with_unknown_heading() {
    // An x-up / x-down pair: the x gyro bias and scale factor from +-W sin L, the x accelerometer bias and
    // scale factor from +-g, no heading needed.
    let model = Model::BIASES.with(Term::AccelScaleFactor).with(Term::GyroScaleFactor);
    let poses = [[0.0, -90.0, 0.0], [0.0, 90.0, 0.0]];
    let t = truth(1.0);
    let mut est = ChannelEstimator::new(site(), ChannelSettings { model, ..ChannelSettings::default() });
    for p in &poses {
        est.add(dwell(&t, model, *p, false)).expect("dwell");
    }
    let sol = est.solve().expect("solve");
    for (i, name) in [(0, "gyro_bias_x"), (15, "gyro_scale_factor_x"), (3, "accel_bias_x"), (6, "accel_scale_factor_x")]
    {
        let (value, _) = sol.estimate(i).unwrap_or_else(|| panic!("{name} must be determined"));
        let err = (value as f64 - t[i]).abs() / scale_of(i);
        println!("{name}: {value:e} (true {:e}, error {err:.1e} of scale)", t[i]);
        assert!(err < 1e-6, "{name}");
    }
    // What two poses cannot see is reported as unobservable, not guessed.
    for i in [6 + 1, 6 + 2, 15 + 1, 15 + 2] {
        assert!(sol.unobservable & (1 << i) != 0, "{} must be unobservable", parameter_name(i));
    }
}

#[test]
fn navigation_grade_noise_never_makes_a_bias_unobservable() {
    // The structural test does not look at the noise: a fibre-optic gyro's 1 min means (3 deg/h per sample,
    // 100 ug per sample at 100 Hz) leave every Table 1 bias determined, with honest (large) errors.
    let t = truth(1.0);
    let mut est = ChannelEstimator::new(site(), ChannelSettings::default());
    for p in &TABLE1_DEG {
        let mut d = dwell(&t, Model::BIASES, *p, true);
        let rate_std = 3.0 * W_RADPS / 15.041 / (6000f64).sqrt();
        let force_std = 100e-6 * 9.80665 / (6000f64).sqrt();
        d.rate_mean_var_b_radps2 = [(rate_std * rate_std) as f32; 3];
        d.force_mean_var_b_mps2sq = [(force_std * force_std) as f32; 3];
        est.add(d).expect("dwell");
    }
    let sol = est.solve().expect("solve");
    assert_eq!(sol.unobservable, 0);
    for i in 0..3 {
        let (_, std) = sol.estimate(i).expect("determined");
        assert!(std > 0.0 && std.is_finite());
    }
}

#[test]
fn implausible_data_are_refused_with_the_dwell() {
    let t = truth(1.0);
    let add_all = |est: &mut ChannelEstimator, edit: &dyn Fn(usize, &mut ChannelDwell)| {
        for (k, p) in TABLE1_DEG.iter().enumerate() {
            let mut d = dwell(&t, Model::BIASES, *p, true);
            edit(k, &mut d);
            est.add(d).expect("dwell");
        }
    };
    // Accelerometers 1.5x too large.
    let mut est = ChannelEstimator::new(site(), ChannelSettings::default());
    add_all(&mut est, &|_, d| d.force_mean_b_mps2 = d.force_mean_b_mps2.map(|x| 1.5 * x));
    assert!(matches!(est.solve(), Err(ChannelError::ForceMagnitude { dwell: 0, .. })));
    // A wrong face down at dwell 3: the data are of the pose upside down.
    let mut est = ChannelEstimator::new(site(), ChannelSettings::default());
    add_all(&mut est, &|k, d| {
        if k == 2 {
            d.force_mean_b_mps2 = d.force_mean_b_mps2.map(|x| -x);
        }
    });
    let e = est.solve().expect_err("wrong face");
    assert!(matches!(e, ChannelError::GravityDirection { dwell: 2, .. }), "{e}");
    // A half-turn heading error at dwell 4: data at 270, labelled 90.
    let mut est = ChannelEstimator::new(site(), ChannelSettings::default());
    add_all(&mut est, &|k, d| {
        if k == 3 {
            d.heading_rad = Some(90f32.to_radians());
        }
    });
    let e = est.solve().expect_err("heading");
    println!("{e}");
    assert!(matches!(e, ChannelError::HeadingMismatch { dwell: 3, .. }), "{e}");
}

/// 20 hand-placed poses (pitch, roll, heading in degrees): the six faces and fourteen tilted ones, headings
/// spread over the circle.
const HAND_PLACED_DEG: [[f64; 3]; 20] = [
    [0.0, 0.0, 0.0],
    [0.0, 180.0, 40.0],
    [90.0, 0.0, 80.0],
    [-90.0, 0.0, 120.0],
    [0.0, 90.0, 160.0],
    [0.0, -90.0, 200.0],
    [30.0, 20.0, 10.0],
    [-35.0, 50.0, 75.0],
    [50.0, -30.0, 140.0],
    [-20.0, -60.0, 210.0],
    [60.0, 120.0, 250.0],
    [-55.0, 150.0, 300.0],
    [15.0, -130.0, 330.0],
    [-70.0, -100.0, 20.0],
    [40.0, 70.0, 95.0],
    [-10.0, 35.0, 185.0],
    [75.0, -160.0, 275.0],
    [25.0, 100.0, 355.0],
    [-45.0, -20.0, 45.0],
    [10.0, -75.0, 125.0],
];

/// `I + S + M` of one sensor from the true parameters (scale factors from `scale_first`, misalignments from
/// `misalignment_first`), f64.
fn sensor_matrix_f64(t: &[f64; PARAMETERS], scale_first: usize, misalignment_first: usize) -> M3 {
    let mut m = misalignment(t, misalignment_first);
    for i in 0..3 {
        m[i][i] = 1.0 + t[scale_first + i];
    }
    m
}

/// The true parameters in the body frame the estimator fixes without reference attitudes: body x along
/// accelerometer x, body y in the accelerometers' x-y plane. With `T_a = L Q` (L lower-triangular, Q a
/// rotation), the body vectors become `Q v`, so `T_a -> L`, `T_g -> T_g Q^T`, `G -> G Q^T`; biases unchanged.
/// Returns the parameters and Q.
fn in_accelerometer_frame(t: &[f64; PARAMETERS]) -> ([f64; PARAMETERS], M3) {
    let t_a = sensor_matrix_f64(t, 6, 9);
    let l = lower_triangular_form(&t_a);
    let q = mul(&inverse3(&l).expect("L invertible"), &t_a);
    let t_g = mul(&sensor_matrix_f64(t, 15, 18), &transpose(&q));
    let g = mul(&[[t[24], t[25], t[26]], [t[27], t[28], t[29]], [t[30], t[31], t[32]]], &transpose(&q));
    let mut out = *t;
    for i in 0..3 {
        out[6 + i] = l[i][i] - 1.0;
        out[15 + i] = t_g[i][i] - 1.0;
        for j in 0..3 {
            if i != j {
                out[9 + misalignment_index(i, j)] = l[i][j];
                out[18 + misalignment_index(i, j)] = t_g[i][j];
            }
            out[24 + 3 * i + j] = g[i][j];
        }
    }
    (out, q)
}

/// Solves exact dwells of the hand-placed poses with the given attitude knowledge; without reference attitudes
/// the dwells carry no tilt (identity) and no heading, so nothing of the truth reaches the estimator but the
/// means.
fn solve_hand_placed(model: Model, use_gyro: bool, attitude: AttitudeKnowledge, sign: f64) -> ChannelSolution {
    solve_hand_placed_with(ChannelSettings { model, use_gyro, attitude, ..ChannelSettings::default() }, sign)
}

/// As [`solve_hand_placed`] with any settings; gyros that do not resolve the Earth rate see its vertical part
/// alone (the horizontal part, whose direction they cannot know, is noise; this exact draw of it is zero).
fn solve_hand_placed_with(settings: ChannelSettings, sign: f64) -> ChannelSolution {
    let (t, model, attitude) = (truth(sign), settings.model, settings.attitude);
    let w_n = earth_rate_n_radps(LATITUDE_DEG.to_radians());
    let w_n = if settings.earth_rate_resolved { w_n } else { [0.0, 0.0, w_n[2]] };
    let mut est = ChannelEstimator::new(site(), settings);
    for p in &HAND_PLACED_DEG {
        let mut d = dwell_with_rate(&t, model, *p, attitude == AttitudeKnowledge::Reference, w_n);
        if attitude == AttitudeKnowledge::Unknown {
            d.tilt = Mat3::IDENTITY;
        }
        est.add(d).expect("dwell");
    }
    est.solve().expect("solve")
}

fn bits(indices: &[usize]) -> u64 {
    indices.iter().fold(0, |b, i| b | 1 << i)
}

fn names(mask: u64) -> Vec<&'static str> {
    (0..PARAMETERS).filter(|i| mask & (1 << i) != 0).map(parameter_name).collect()
}

#[test]
fn unknown_attitudes_accelerometer_only_in_the_accelerometer_frame() {
    // The imu_tk method: |T_a^-1 (f - b_a)| = g on hand-placed poses, accelerometer bias, scale factors and
    // misalignments (9 parameters from one equation per pose).
    let model = Model::EMPTY.with(Term::AccelBias).with(Term::AccelScaleFactor).with(Term::AccelMisalignment);
    for sign in [1.0, -1.0] {
        // With reference attitudes every one of the nine is determined: the control.
        let known = solve_hand_placed(model, false, AttitudeKnowledge::Reference, sign);
        assert_eq!((known.blind_spots, known.unobservable, known.gauge), (0, 0, 0));
        let worst = assert_recovered(&known, model, sign, 1e-6);
        println!("reference attitudes, sign {sign:+}: worst error {worst:.2e} of scale");
        // Without them, a common rotation of every pose is invisible: three blind spots, the antisymmetric
        // part of the misalignments. Holding xy, xz, yz at zero fixes the body frame to the accelerometers; the
        // rest is then determined, and equal to the truth in that frame.
        let sol = solve_hand_placed(model, false, AttitudeKnowledge::Unknown, sign);
        println!("unknown attitudes: blind spots {}, unobservable {:?}", sol.blind_spots, names(sol.unobservable));
        assert_eq!(sol.blind_spots, 3, "a common rotation: three blind spots");
        assert_eq!(sol.gauge, bits(&GAUGE_PARAMETERS));
        assert_eq!(sol.unobservable, sol.gauge, "only the gauge is not determined: {:?}", names(sol.unobservable));
        assert_eq!(names(sol.gauge), ["accel_misalignment_xy", "accel_misalignment_xz", "accel_misalignment_yz"]);
        let (expected, q) = in_accelerometer_frame(&truth(sign));
        let worst = assert_recovered_against(&sol, model, &expected, 1e-6);
        // One equation per pose, nine parameters, two nuisance angles per pose.
        assert_eq!(sol.degrees_of_freedom, 20 - 9);
        // Exact data fit to the f32 resolution of the means (0.1 ug against the 1 ug weights), well inside
        // the noise: the Gauss-Newton steps then wander at 0.1 standard error, so no convergence flag is asked.
        assert!(sol.chi_square < sol.degrees_of_freedom as f32, "chi-square {}", sol.chi_square);
        // The poses come back too, in that frame: up_b = Q C^T e_u.
        let mut worst_up_rad = 0.0f64;
        for (k, p) in HAND_PLACED_DEG.iter().enumerate() {
            let up = mul_vec(&q, mul_t_vec(&c_b_n(p[0], p[1], p[2]), [0.0, 0.0, 1.0]));
            let est = sol.up_b[k].map(|x| x as f64);
            let d = [0, 1, 2].map(|i| est[i] - up[i]);
            worst_up_rad = worst_up_rad.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
        }
        assert!(worst_up_rad < 1e-6, "up directions: {worst_up_rad:.2e} rad");
        println!(
            "unknown attitudes, sign {sign:+}: worst error {worst:.2e} of scale, up directions within \
             {worst_up_rad:.1e} rad, {} passes, chi-square {:.2e}",
            sol.iterations, sol.chi_square
        );
    }
}

#[test]
fn unknown_attitudes_every_static_term() {
    // With gyros too, every static term and the reference offset: the offset is indistinguishable from the
    // poses' own attitudes (three more blind spots), the common rotation as above; everything else is
    // determined in the accelerometer frame, the gyro terms from the Earth rate and gravity.
    let model = Model::FULL;
    for sign in [1.0, -1.0] {
        let sol = solve_hand_placed(model, true, AttitudeKnowledge::Unknown, sign);
        println!(
            "unknown attitudes, gyros: blind spots {}, unobservable {:?}",
            sol.blind_spots,
            names(sol.unobservable)
        );
        let offset = Term::ReferenceOffset.parameters().0;
        assert_eq!(sol.blind_spots, 6, "three for the common rotation, three for the offset");
        assert_eq!(sol.gauge, bits(&GAUGE_PARAMETERS));
        assert_eq!(sol.unobservable, sol.gauge | bits(&[offset, offset + 1, offset + 2]));
        let (expected, _) = in_accelerometer_frame(&truth(sign));
        let worst = assert_recovered_against(&sol, model, &expected, 1e-6);
        // Per pose: six channel means, three nuisance angles (tilt about e and n, heading).
        assert_eq!(sol.degrees_of_freedom, 20 * 3 - (36 - 6));
        assert!(sol.chi_square < sol.degrees_of_freedom as f32, "chi-square {}", sol.chi_square);
        println!(
            "unknown attitudes, every static term, sign {sign:+}: worst error {worst:.2e} of scale, {} passes",
            sol.iterations
        );
    }
}

#[test]
fn unknown_attitudes_gyros_that_do_not_resolve_the_earth_rate() {
    // MEMS gyros in hand-placed poses: without a heading a static pose shows the gyros gravity and the Earth
    // rate's vertical part, both along up: their bias and g-sensitivity (in the accelerometer frame) and, of a
    // scale factor and the diagonal g-sensitivity of the same axis, only `W sin L S_ii + g G_ii`, so neither of
    // the pair is determined.
    let model = Model::BIASES
        .with(Term::AccelScaleFactor)
        .with(Term::AccelMisalignment)
        .with(Term::GyroScaleFactor)
        .with(Term::GyroGSensitivity);
    let settings = ChannelSettings {
        model,
        attitude: AttitudeKnowledge::Unknown,
        earth_rate_resolved: false,
        ..ChannelSettings::default()
    };
    for sign in [1.0, -1.0] {
        let sol = solve_hand_placed_with(settings, sign);
        println!("no Earth rate: blind spots {}, unobservable {:?}", sol.blind_spots, names(sol.unobservable));
        let scale = Term::GyroScaleFactor.parameters().0;
        let g_sens = Term::GyroGSensitivity.parameters().0;
        assert_eq!(sol.blind_spots, 6, "the common rotation and three scale factors seen with the g-sensitivity");
        let pairs = bits(&[scale, scale + 1, scale + 2, g_sens, g_sens + 4, g_sens + 8]);
        assert_eq!(sol.unobservable, bits(&GAUGE_PARAMETERS) | pairs);
        let (expected, _) = in_accelerometer_frame(&truth(sign));
        // The gyro rows carry the horizontal Earth rate's variance ((W cos L)^2 / 2, 10^7 times the dwell noise
        // here), so in f32 the gyro terms come back to 1e-4 of their scale, not 1e-6.
        let worst = assert_recovered_against(&sol, model, &expected, 1e-4);
        // Per pose: one accelerometer row (two tilt angles), three gyro rows, no heading.
        // (Each scale factor and diagonal g-sensitivity pair counts once: the data fix their sum.)
        assert_eq!(sol.degrees_of_freedom, 20 * 4 - (3 + 3 + 3 + 3 + 9));
        assert!(sol.chi_square < sol.degrees_of_freedom as f32, "chi-square {}", sol.chi_square);
        assert!(!sol.earth_rate_resolved && sol.heading_std_rad.iter().all(|s| *s == 0.0));
        println!("no Earth rate, sign {sign:+}: worst error {worst:.2e} of scale, {} passes", sol.iterations);
    }
}
