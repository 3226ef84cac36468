//! The device's compensation (`sinscal::calib::compensation`, docs/compensation.md) on exact synthetic data with
//! known truth: every term of the sensor model of both signs (docs/conventions.md#sensor-model) distorts true
//! samples in f64 through the host's own model (`model::sensor::Triad`, independent of the core), and the f32
//! compensation must give the true samples back to f32 rounding. Then the compensation of calibrations made by
//! `calibrate` (general estimator with every term, angle method) against the host's f64 `apply` path
//! (`io::calibration_model`) on the same calibration, read back from its JSON: within f32 rounding.
//!
//! The bound: per output component `i`, with `A = T^-1` as the compensation holds it,
//!
//!     |error_i| <= K u sum_j |A_ij| m_j,      u = 2^-24 (f32 unit roundoff), K = 16,
//!
//! where `m_j` is the magnitude of what is subtracted into input `j`: `|f_meas,j| + |b_a,j|` for the specific
//! force, `|w_meas,j| + |b_g,j| + sum_k |G_jk| |f_k|` for the rate. K counts the roundings: one subtraction (1),
//! the `G f` product and its subtraction (4), the matrix-vector product (3), and the adjugate inverse of a `T` near
//! the identity (cofactors 2, determinant 3, reciprocal and scaling 2), 15 in all, and the rounding of the input.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sinscal::calib::angles::CalibrationResult;
use sinscal::calib::compensation::{Compensation, ENCODED_BYTES};
use sinscal::calib::general::{ChannelSolution, Model, PARAMETERS};
use sinscal::sensor::sample::ImuSample;
use sinscal_host::calibration::result::CalibrationJson;
use sinscal_host::calibration::{calibrate, Calibration, Options};
use sinscal_host::io::calibration_model::CalibrationModel;
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::model::sensor::Triad;
use sinscal_host::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec, Scenario, DEG_PER_HOUR, MICRO_G};

type V3 = [f64; 3];

/// f32 unit roundoff.
const U: f64 = 1.0 / (1u64 << 24) as f64;
/// Roundings counted in the bound (module documentation).
const K: f64 = 16.0;
const LATITUDE_DEG: f64 = 45.7796;
const G_MPS2: f64 = 9.8063;

/// Every static term of both signs in the core's layout (`sign` flips them all), MEMS-sized so that each term
/// moves a sample by far more than f32 rounding: biases 1e-5 rad/s and 1e-3 m/s^2, scale factors and
/// misalignments 1e-4 to 1e-3, g-sensitivity 1e-5 (rad/s)/(m/s^2); a reference offset that must be ignored.
fn truth(sign: f32) -> [f32; PARAMETERS] {
    let mut t = [0.0f32; PARAMETERS];
    t[0..3].copy_from_slice(&[3.0e-5, -2.0e-5, 1.0e-5]);
    t[3..6].copy_from_slice(&[2.5e-3, -1.7e-3, 4.1e-3]);
    t[6..9].copy_from_slice(&[3.0e-4, -5.0e-4, 8.0e-4]);
    t[9..15].copy_from_slice(&[2.0e-4, -3.0e-4, -1.5e-4, 4.0e-4, 2.5e-4, -3.5e-4]);
    t[15..18].copy_from_slice(&[-6.0e-4, 4.0e-4, 2.0e-4]);
    t[18..24].copy_from_slice(&[-1.0e-3, 5.0e-4, 7.0e-4, -2.0e-4, -4.0e-4, 9.0e-4]);
    t[24..33].copy_from_slice(&[1.0e-5, -2.0e-5, 3.0e-5, -4.0e-5, 5.0e-6, 6.0e-5, 2.0e-5, -7.0e-5, -1.0e-5]);
    t[33..36].copy_from_slice(&[1e-3, -2e-3, 3e-3]);
    t.map(|x| x * sign)
}

/// The host's model of the IMU with the parameters `t` (widened exactly): (gyro, accelerometer). The
/// misalignments are filled in the layout's order xy, xz, yx, yz, zx, zy.
fn triads(t: &[f32; PARAMETERS]) -> (Triad, Triad) {
    let t = t.map(f64::from);
    let misalignment = |first: usize| {
        let mut m = [[0.0; 3]; 3];
        let mut k = first;
        for i in 0..3 {
            for j in 0..3 {
                if i != j {
                    m[i][j] = t[k];
                    k += 1;
                }
            }
        }
        m
    };
    let g = [[t[24], t[25], t[26]], [t[27], t[28], t[29]], [t[30], t[31], t[32]]];
    let gyro = Triad::new([t[0], t[1], t[2]], [t[15], t[16], t[17]], &misalignment(18), g);
    let accel = Triad::new([t[3], t[4], t[5]], [t[6], t[7], t[8]], &misalignment(9), [[0.0; 3]; 3]);
    (gyro, accel)
}

/// A general-estimator solution that determined every term of `model` at the values `theta`.
fn solution(model: Model, theta: &[f32; PARAMETERS]) -> ChannelSolution {
    let observable = (0..PARAMETERS).filter(|&i| model.has_parameter(i)).fold(0u64, |m, i| m | (1 << i));
    let mut parameters_si = [0.0f32; PARAMETERS];
    for i in 0..PARAMETERS {
        if observable & (1 << i) != 0 {
            parameters_si[i] = theta[i];
        }
    }
    let mut s = ChannelSolution::empty(model, 0);
    s.parameters_si = parameters_si;
    s.observable = observable;
    s.iterations = 1;
    s.converged = true;
    s
}

/// True samples: the even ones at rest in random attitudes (Earth rate and g), the odd ones moving (rates up to 8 rad/s, specific
/// force up to 80 m/s^2 per axis: the ADIS16505-2's ranges), both signs on every axis.
fn true_samples(n: usize, seed: u64) -> Vec<(V3, V3)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let w_ie = earth_rate_n_radps(LATITUDE_DEG.to_radians());
    (0..n)
        .map(|k| {
            if k % 2 == 0 {
                let c =
                    c_b_n(rng.random_range(-90.0..90.0), rng.random_range(-180.0..180.0), rng.random_range(0.0..360.0));
                (mul_t_vec(&c, w_ie), mul_t_vec(&c, [0.0, 0.0, G_MPS2]))
            } else {
                ([0; 3].map(|_| rng.random_range(-8.0..8.0)), [0; 3].map(|_| rng.random_range(-80.0..80.0)))
            }
        })
        .collect()
}

/// The bound of the module documentation for the sample `(w_meas, f_meas)`, with `f` the compensated specific
/// force: (rate bound, force bound).
fn bounds(c: &Compensation, w_meas: [f32; 3], f_meas: [f32; 3], f: V3) -> (V3, V3) {
    let (a, gi, g) = (c.accel_t_inv().0, c.gyro_t_inv().0, c.gyro_g_sensitivity_radps_per_mps2().0);
    let (b_a, b_g) = (c.accel_bias_b_mps2(), c.gyro_bias_b_radps());
    let mag_f: V3 = [0, 1, 2].map(|j| (f_meas[j].abs() + b_a[j].abs()) as f64);
    let mag_w: V3 = [0, 1, 2].map(|j| {
        (w_meas[j].abs() + b_g[j].abs()) as f64 + (0..3).map(|k| (g[j][k] as f64).abs() * f[k].abs()).sum::<f64>()
    });
    let bound = |m: &[[f32; 3]; 3], mag: V3| {
        [0, 1, 2].map(|i| K * U * (0..3).map(|j| (m[i][j] as f64).abs() * mag[j]).sum::<f64>())
    };
    (bound(&gi, mag_w), bound(&a, mag_f))
}

/// Largest error as a fraction of its bound and in SI, per sensor: ((rate ratio, rate), (force ratio, force)).
#[derive(Default)]
struct Worst {
    rate: (f64, f64),
    force: (f64, f64),
}

impl Worst {
    /// Records `got - want` against the bound; fails beyond it.
    fn check(&mut self, what: &str, got: &ImuSample, want: (V3, V3), bound: (V3, V3)) {
        for i in 0..3 {
            let dw = (got.rate_b_radps[i] as f64 - want.0[i]).abs();
            let df = (got.force_b_mps2[i] as f64 - want.1[i]).abs();
            assert!(
                dw <= bound.0[i],
                "{what}: rate {i}: {} vs {} (error {dw:e} > bound {:e})",
                got.rate_b_radps[i],
                want.0[i],
                bound.0[i]
            );
            assert!(
                df <= bound.1[i],
                "{what}: force {i}: {} vs {} (error {df:e} > bound {:e})",
                got.force_b_mps2[i],
                want.1[i],
                bound.1[i]
            );
            self.rate = (self.rate.0.max(dw / bound.0[i]), self.rate.1.max(dw));
            self.force = (self.force.0.max(df / bound.1[i]), self.force.1.max(df));
        }
    }

    fn report(&self, what: &str) {
        println!(
            "{what}: largest error rate {:.3e} rad/s ({:.2e} deg/h, {:.2} of the bound), force {:.3e} m/s^2 ({:.3} ug, \
             {:.2} of the bound)",
            self.rate.1,
            self.rate.1 / DEG_PER_HOUR,
            self.rate.0,
            self.force.1,
            self.force.1 / MICRO_G,
            self.force.0
        );
    }
}

#[test]
fn every_term_of_both_signs_gives_the_true_sample_back() {
    for sign in [1.0f32, -1.0] {
        let theta = truth(sign);
        let c = Compensation::from_channels(&solution(Model::FULL, &theta)).unwrap();
        let (gyro, accel) = triads(&theta);
        let mut worst = [Worst::default(), Worst::default()];
        let mut moved = (0.0f64, 0.0f64);
        for (k, (w, f)) in true_samples(100_000, 7).into_iter().enumerate() {
            // The distortion in f64, then the sensor's f32 output.
            let f_meas = accel.measure(f, [0.0; 3]).map(|x| x as f32);
            let w_meas = gyro.measure(w, f).map(|x| x as f32);
            let got = c.apply(&ImuSample { rate_b_radps: w_meas, force_b_mps2: f_meas });
            worst[k % 2].check(&format!("sign {sign:+}, sample {k}"), &got, (w, f), bounds(&c, w_meas, f_meas, f));
            // The terms matter: the raw outputs are far from the truth (else this test could not fail).
            for i in 0..3 {
                moved.0 = moved.0.max((w_meas[i] as f64 - w[i]).abs());
                moved.1 = moved.1.max((f_meas[i] as f64 - f[i]).abs());
            }
        }
        worst[0].report(&format!("truth, sign {sign:+}, at rest"));
        worst[1].report(&format!("truth, sign {sign:+}, moving"));
        println!("  the distortion moved the samples by up to {:.3e} rad/s, {:.3e} m/s^2", moved.0, moved.1);
        assert!(worst[1].rate.1 < 1e-3 * moved.0 && worst[1].force.1 < 1e-3 * moved.1);
    }
}

#[test]
fn a_term_left_out_or_undetermined_is_identity_or_zero() {
    let theta = truth(1.0);
    // Biases and accelerometer scale factors only (the default model); accel_bias_y undetermined.
    let model = Model::BIASES.with(sinscal::calib::general::Term::AccelScaleFactor);
    let mut s = solution(model, &theta);
    s.observable &= !(1 << 4);
    s.unobservable |= 1 << 4;
    s.parameters_si[4] = 0.5; // must not be used
    let c = Compensation::from_channels(&s).unwrap();
    assert_eq!(c.accel_bias_b_mps2(), [theta[3], 0.0, theta[5]]);
    assert_eq!(c.gyro_t(), sinscal::math::linalg::Mat3::IDENTITY);
    assert_eq!(c.gyro_g_sensitivity_radps_per_mps2().0, [[0.0; 3]; 3]);
    let t_a = c.accel_t().0;
    assert_eq!([t_a[0][0], t_a[1][1], t_a[2][2]], [1.0 + theta[6], 1.0 + theta[7], 1.0 + theta[8]]);
    assert_eq!([t_a[0][1], t_a[1][0], t_a[2][0]], [0.0; 3]);
}

/// 24 poses: each face up at four headings (every static term determined).
fn faces_by_headings() -> Vec<[f64; 3]> {
    let faces = [[0.0, 0.0], [180.0, 0.0], [90.0, 0.0], [-90.0, 0.0], [0.0, 90.0], [0.0, -90.0]];
    faces.iter().flat_map(|f| [0.0, 90.0, 180.0, 270.0].map(|h| [f[0], f[1], h])).collect()
}

/// An exact recording of the IMU with parameters `theta`: 40 rows at rest per pose. Returns it with the ideal
/// (w, f) of every row.
fn exact_recording(theta: &[f32; PARAMETERS]) -> (Recording, Vec<(V3, V3)>) {
    let (gyro, accel) = triads(theta);
    let w_ie = earth_rate_n_radps(LATITUDE_DEG.to_radians());
    let (mut rows, mut ideal) = (Vec::new(), Vec::new());
    for (k, p) in faces_by_headings().iter().enumerate() {
        let c = c_b_n(p[0], p[1], p[2]);
        let (w, f) = (mul_t_vec(&c, w_ie), mul_t_vec(&c, [0.0, 0.0, G_MPS2]));
        for _ in 0..40 {
            rows.push(Row {
                t_s: rows.len() as f64 * 0.01,
                pos: k as u32 + 1,
                pitch_deg: p[0],
                roll_deg: p[1],
                heading_deg: Some(p[2]),
                rate_b_radps: gyro.measure(w, f),
                force_b_mps2: accel.measure(f, [0.0; 3]),
                temp_c: None,
                turn_axis: None,
                line: 0,
            });
            ideal.push((w, f));
        }
    }
    let header = Header {
        latitude_deg: LATITUDE_DEG,
        height_m: 0.0,
        rate_hz: Some(100.0),
        gravity_mps2: Some(G_MPS2),
        comments: vec!["source: exact synthetic data for the compensation".to_string()],
        truth: None,
        pose_tolerance_deg: None,
    };
    (Recording { source: "exact.csv".to_string(), header, rows, has_gyro: true }, ideal)
}

/// The host's f64 model of a calibration, through its JSON as `sinscal apply` reads it.
fn host_model(cal: &Calibration) -> CalibrationModel {
    let text = serde_json::to_string_pretty(&CalibrationJson::new(cal)).unwrap();
    CalibrationModel::parse(&text, "cal.json").unwrap()
}

/// `Compensation::apply` against the host's f64 path on measured samples made from `samples` with `theta`.
fn against_host(
    what: &str,
    c: &Compensation,
    host: &CalibrationModel,
    theta: &[f32; PARAMETERS],
    samples: &[(V3, V3)],
) {
    let (gyro, accel) = triads(theta);
    let mut worst = [Worst::default(), Worst::default()];
    for (k, (w, f)) in samples.iter().enumerate() {
        let f_meas = accel.measure(*f, [0.0; 3]).map(|x| x as f32);
        let w_meas = gyro.measure(*w, *f).map(|x| x as f32);
        let got = c.apply(&ImuSample { rate_b_radps: w_meas, force_b_mps2: f_meas });
        let f_host = host.compensate_force(f_meas.map(f64::from));
        let w_host = host.compensate_rate(w_meas.map(f64::from), f_host);
        worst[k % 2].check(&format!("{what}, sample {k}"), &got, (w_host, f_host), bounds(c, w_meas, f_meas, f_host));
    }
    worst[0].report(&format!("{what}, at rest"));
    worst[1].report(&format!("{what}, moving"));
}

#[test]
fn device_and_host_apply_agree_on_a_calibration_with_every_term() {
    for sign in [1.0f32, -1.0] {
        let theta = truth(sign);
        let (rec, ideal) = exact_recording(&theta);
        let cal = calibrate(&rec, &Options { model: Model::FULL, ..Options::default() }).unwrap();
        let s = cal.channels.as_ref().expect("the general estimator's solution");
        assert_eq!(s.unobservable, 0, "24 poses determine every term");
        let c = Compensation::from_channels(s).unwrap();
        let host = host_model(&cal);
        assert_eq!(host.terms.len(), 7, "every term in the JSON: {:?}", host.terms);
        against_host(&format!("every term, sign {sign:+}"), &c, &host, &theta, &true_samples(100_000, 11));
        // The recording's own rows come back to their ideal values to the estimator's precision.
        let mut worst = (0.0f64, 0.0f64);
        for (row, (w, f)) in rec.rows.iter().zip(&ideal) {
            let got = c.apply(&ImuSample {
                rate_b_radps: row.rate_b_radps.map(|x| x as f32),
                force_b_mps2: row.force_b_mps2.map(|x| x as f32),
            });
            for i in 0..3 {
                worst.0 = worst.0.max((got.rate_b_radps[i] as f64 - w[i]).abs());
                worst.1 = worst.1.max((got.force_b_mps2[i] as f64 - f[i]).abs());
            }
        }
        println!(
            "  recording rows compensated vs ideal: rate {:.2e} deg/h, force {:.3} ug",
            worst.0 / DEG_PER_HOUR,
            worst.1 / MICRO_G
        );
        assert!(worst.0 < 1e-3 * DEG_PER_HOUR && worst.1 < 1.0 * MICRO_G, "{worst:?}");
        // Stored and read back, the compensation is the same to the bit.
        let mut bytes = [0u8; ENCODED_BYTES];
        c.encode(&mut bytes);
        assert_eq!(Compensation::decode(&bytes), Some(c));
    }
}

#[test]
fn device_and_host_apply_agree_on_an_angle_method_calibration() {
    let scenario = Scenario {
        gyro_bias_b_radps: [0.05, -0.08, 0.03].map(|x| x * DEG_PER_HOUR),
        accel_bias_b_mps2: [120.0, -80.0, -60.0].map(|x| x * MICRO_G),
        ..Scenario::table1_exact()
    };
    let cal = calibrate(&scenario.recording(0, "exact.csv"), &Options::angles()).unwrap();
    let solution = cal.solution.expect("the angle method's solution");
    let result =
        CalibrationResult { solution, passes: cal.passes, converged: cal.converged, last_correction_sigma: 0.0 };
    let c = Compensation::from_angles(&result).unwrap();
    for i in 0..3 {
        assert!((c.gyro_bias_b_radps()[i] as f64 - scenario.gyro_bias_b_radps[i]).abs() < 1e-6 * DEG_PER_HOUR);
        assert!((c.accel_bias_b_mps2()[i] as f64 - scenario.accel_bias_b_mps2[i]).abs() < 0.01 * MICRO_G);
    }
    let host = host_model(&cal);
    let mut theta = [0.0f32; PARAMETERS];
    theta[0..3].copy_from_slice(&c.gyro_bias_b_radps());
    theta[3..6].copy_from_slice(&c.accel_bias_b_mps2());
    against_host("angle method (biases)", &c, &host, &theta, &true_samples(50_000, 13));
}
