//! The body's rotation over a move from its gyro rates (`sinscal::nav::strapdown`), on exact synthetic data with
//! known truth: constant-rate turntable moves about every axis and both directions, their composition, and a
//! coning motion whose attitude is known in closed form (where the coning term of the update shows its worth).

use sinscal::nav::strapdown::{MoveIntegrator, Quat};

/// Quaternion product in f64, scalar first.
fn mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn conj(q: [f64; 4]) -> [f64; 4] {
    [q[0], -q[1], -q[2], -q[3]]
}

fn exp(v: [f64; 3]) -> [f64; 4] {
    let t = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if t == 0.0 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let s = (0.5 * t).sin() / t;
    [(0.5 * t).cos(), s * v[0], s * v[1], s * v[2]]
}

/// The angle of the rotation between the integrated and the true attitude, rad.
fn angle_between(q: Quat, truth: [f64; 4]) -> f64 {
    let q = q.0.map(f64::from);
    let d = mul(conj(truth), q);
    let s = (d[1] * d[1] + d[2] * d[2] + d[3] * d[3]).sqrt();
    2.0 * s.atan2(d[0].abs())
}

#[test]
fn constant_rate_moves_about_every_axis_both_ways_and_their_composition() {
    let dt = 0.01;
    // A turntable's moves: 90 deg at 10 deg/s about x, y, z, both directions, and a tilted axis.
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.6, -0.48, 0.64]];
    let mut truth_all = [1.0, 0.0, 0.0, 0.0];
    let mut all = MoveIntegrator::new(dt as f32);
    let mut worst: f64 = 0.0;
    for axis in axes {
        for sign in [1.0, -1.0] {
            let rate = 10f64.to_radians() * sign;
            let w = [axis[0] * rate, axis[1] * rate, axis[2] * rate];
            let mut one = MoveIntegrator::new(dt as f32);
            // 9 s of rotation: 900 samples of 10 ms.
            for _ in 0..900 {
                one.push(w.map(|x| x as f32));
            }
            let truth = exp(w.map(|x| x * 9.0));
            let e = angle_between(one.rotation(), truth);
            worst = worst.max(e);
            // f32 rounding of 450 quaternion products.
            assert!(e < 1e-5, "axis {axis:?} sign {sign}: error {e:e} rad");
            // The same move appended to one long integration (the rate steps between moves).
            for _ in 0..900 {
                all.push(w.map(|x| x as f32));
            }
            truth_all = mul(truth_all, truth);
        }
    }
    println!("constant-rate moves: largest error {worst:.2e} rad");
    let e = angle_between(all.rotation(), truth_all);
    println!("eight moves in one integration: error {e:.2e} rad");
    assert!(e < 5e-5, "{e:e}");
}

#[test]
fn coning_motion_the_coning_term_removes_the_drift() {
    // The body's attitude q(t) = [cos(a/2), sin(a/2) cos(W t), sin(a/2) sin(W t), 0]: its axis of rotation cones
    // about z. Its body rate is w = 2 vec(q* dq/dt), exact, and the rotation since t = 0 is q(0)* q(t).
    let (a, big_w, dt, seconds) = (0.05f64, 2.0 * std::f64::consts::PI * 2.0, 0.01f64, 60.0f64);
    let q = |t: f64| [(0.5 * a).cos(), (0.5 * a).sin() * (big_w * t).cos(), (0.5 * a).sin() * (big_w * t).sin(), 0.0];
    let dq =
        |t: f64| [0.0, -(0.5 * a).sin() * big_w * (big_w * t).sin(), (0.5 * a).sin() * big_w * (big_w * t).cos(), 0.0];
    let mut with = MoveIntegrator::new(dt as f32);
    let mut without = MoveIntegrator::without_coning(dt as f32);
    let rate = |t: f64| {
        let p = mul(conj(q(t)), dq(t));
        [2.0 * p[1], 2.0 * p[2], 2.0 * p[3]]
    };
    let n = (seconds / dt).round() as usize;
    for k in 1..=n {
        // The mean rate over the interval ending at this sample (Simpson's rule on 64 sub-intervals), as a
        // decimating IMU outputs it.
        let (t0, m) = ((k - 1) as f64 * dt, 64);
        let mut mean = [0.0f64; 3];
        for j in 0..=m {
            let weight = if j == 0 || j == m {
                1.0
            } else if j % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let w = rate(t0 + dt * j as f64 / m as f64);
            for i in 0..3 {
                mean[i] += weight * w[i] / (3.0 * m as f64);
            }
        }
        with.push(mean.map(|x| x as f32));
        without.push(mean.map(|x| x as f32));
    }
    let truth = mul(conj(q(0.0)), q(n as f64 * dt));
    let (e_with, e_without) = (angle_between(with.rotation(), truth), angle_between(without.rotation(), truth));
    println!(
        "coning (half-angle {a} rad at {:.0} Hz, {seconds} s at {:.0} Hz): error {:.2e} rad with the coning term, {:.2e} rad without",
        big_w / (2.0 * std::f64::consts::PI),
        1.0 / dt,
        e_with,
        e_without
    );
    assert!(e_with * 10.0 < e_without, "the coning term must remove most of the drift");
    assert!(e_with < 1e-4, "{e_with:e}");
}
