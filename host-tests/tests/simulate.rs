//! `sinscal simulate`: scenario files, the sensor model written out against the simulator on noise-free
//! data, table moves, the time-dependent effects, reproducibility, and the Allan deviation of the
//! simulated noise at several sample rates against the closed forms. All data here are SIMULATION.

use std::f64::consts::PI;

use sinscal_host::calibration::{calibrate, Options};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::simulator::{simulate, ScenarioFile};
use sinscal_host::model::synth::{c_b_n, mul, mul_t_vec, mul_vec, rotation, EARTH_RATE_RADPS};
use sinscal_host::stats::noise::overlapping_allan_deviation;

fn scenario(text: &str) -> ScenarioFile {
    ScenarioFile::parse(text, "test.toml").unwrap_or_else(|e| panic!("{e}"))
}

fn scenarios_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

#[test]
fn scenario_errors_name_the_file_line_and_reason() {
    let e = ScenarioFile::parse("[site]\nlatitude_deg = 45\n\n[gyro]\nbias_rdps = [0, 0, 0]\n", "s.toml").unwrap_err();
    let text = e.to_string();
    assert!(text.starts_with("s.toml:5:") && text.contains("unknown field `bias_rdps`"), "{text}");
    let e = ScenarioFile::parse(
        "[site]\nlatitude_deg = 45\n[gyro]\nmisalignment = [[1e-4, 0, 0], [0, 0, 0], [0, 0, 0]]\n",
        "s.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("gyro.misalignment: the diagonal must be 0"), "{e}");
    let e =
        ScenarioFile::parse("[site]\nlatitude_deg = 45\n[schedule]\nrate_hz = -1\n", "s.toml").unwrap_err().to_string();
    assert!(e.contains("schedule.rate_hz -1 is not a rate in (0, 1000000] Hz"), "{e}");
    let e = ScenarioFile::parse("[site]\nlatitude_deg = 95\n", "s.toml").unwrap_err().to_string();
    assert!(e.contains("latitude_deg 95 is not in [-89.9, 89.9]"), "{e}");
    let e = ScenarioFile::parse("[schedule]\nrate_hz = 100\n", "s.toml").unwrap_err().to_string();
    assert!(e.contains("missing field `site`"), "{e}");
}

#[test]
fn shipped_scenarios_parse_and_are_reproducible_from_the_seed() {
    for name in ["table1-clean.toml", "all-effects.toml"] {
        let file = ScenarioFile::read(&scenarios_dir().join(name)).unwrap_or_else(|e| panic!("{e}"));
        let a = simulate(&file, 7, name).to_csv();
        assert_eq!(a, simulate(&file, 7, name).to_csv(), "{name}");
        assert_ne!(a, simulate(&file, 8, name).to_csv(), "{name}");
        // The file is a valid recording.
        let back = Recording::parse(&a, name).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back.rows.len(), 6 * (6000 + 100) + 5 * 500);
    }
}

/// The model of docs/formats.md#effect-catalogue written out here, independently of the simulator's loop, on noise-free
/// data: scale factors, misalignments, g-sensitivity, biases, the reference offset and a position error.
#[test]
fn noise_free_dwells_follow_the_sensor_model_written_out() {
    let text = r#"
        [site]
        latitude_deg = 30.0
        gravity_mps2 = 9.79
        [schedule]
        dwell_s = 1.0
        move_s = 2.0
        reference_offset_enu_rad = [1e-4, -2e-4, 3e-4]
        position_error = [{ pos = 5, enu_rad = [0.0, 5e-4, 0.0] }]
        [gyro]
        bias_radps = [1e-5, -2e-5, 3e-5]
        scale_factor = [1e-3, -2e-3, 3e-3]
        misalignment = [[0, 1e-3, -1e-3], [2e-3, 0, 5e-4], [-3e-4, 7e-4, 0]]
        g_sensitivity_radps_per_mps2 = [[1e-6, 0, 2e-6], [0, -3e-6, 0], [4e-6, 0, 0]]
        [accel]
        bias_mps2 = [1e-3, 2e-3, -3e-3]
        scale_factor = [-1e-3, 5e-4, 2e-3]
        misalignment = [[0, -1e-3, 2e-3], [1e-3, 0, 0], [0, 3e-3, 0]]
    "#;
    let file = scenario(text);
    let rec = simulate(&file, 1, "model");
    let lat = 30f64.to_radians();
    let w_n = [0.0, EARTH_RATE_RADPS * lat.cos(), EARTH_RATE_RADPS * lat.sin()];
    let f_n = [0.0, 0.0, 9.79];
    let gain = |scale: [f64; 3], mis: [[f64; 3]; 3]| {
        let mut g = mis;
        for i in 0..3 {
            g[i][i] += 1.0 + scale[i];
        }
        g
    };
    let gg = gain(file.gyro.scale_factor, file.gyro.misalignment);
    let ga = gain(file.accel.scale_factor, file.accel.misalignment);
    let mut checked = 0;
    for (k, p) in file.schedule.positions_deg.iter().enumerate() {
        let mut err = file.schedule.reference_offset_enu_rad;
        if k == 4 {
            err[1] += 5e-4;
        }
        let c = mul(&rotation(err.map(|x| -x)), &c_b_n(p[0], p[1], p[2]));
        let (w_b, f_b) = (mul_t_vec(&c, w_n), mul_t_vec(&c, f_n));
        let g_f = mul_vec(&file.gyro.g_sensitivity_radps_per_mps2, f_b);
        let w_exp = [0, 1, 2].map(|i| mul_vec(&gg, w_b)[i] + g_f[i] + file.gyro.bias_radps[i]);
        let f_exp = [0, 1, 2].map(|i| mul_vec(&ga, f_b)[i] + file.accel.bias_mps2[i]);
        for row in rec.rows.iter().filter(|r| r.pos == k as u32 + 1) {
            for i in 0..3 {
                assert!((row.rate_b_radps[i] - w_exp[i]).abs() < 1e-16, "pos {} gyro {i}", k + 1);
                assert!((row.force_b_mps2[i] - f_exp[i]).abs() < 1e-12, "pos {} accel {i}", k + 1);
            }
            checked += 1;
        }
    }
    assert_eq!(checked, 600);
}

/// A move of +90 deg in heading (clockwise from north) is a rotation of -90 deg about body z (docs/conventions.md#attitude:
/// C_b^n = Rz(-psi) ...): the gyro's z integral over the move and the settling is -pi/2 plus Earth's
/// vertical rate over that time.
#[test]
fn a_move_integrates_to_the_attitude_change_with_the_spec_sign() {
    let text = r#"
        [site]
        latitude_deg = 45.0
        [schedule]
        dwell_s = 1.0
        move_s = 4.0
        settle_s = 0.5
        positions_deg = [[0, 0, 0], [0, 0, 90]]
    "#;
    let rec = simulate(&scenario(text), 1, "move");
    let dt = 0.01;
    let between: Vec<_> =
        rec.rows.iter().skip_while(|r| r.pos != 1).skip_while(|r| r.pos == 1).take_while(|r| r.pos == 0).collect();
    assert_eq!(between.len(), 450);
    let integral: f64 = between.iter().map(|r| r.rate_b_radps[2] * dt).sum();
    let earth = EARTH_RATE_RADPS * 45f64.to_radians().sin() * 4.5;
    assert!((integral - (-PI / 2.0 + earth)).abs() < 1e-9, "{integral}");
    // The reported heading moves monotonically from 0 to 90 during the move.
    assert!(between.windows(2).all(|w| w[1].heading_deg.unwrap() >= w[0].heading_deg.unwrap()));
}

fn mean_of(rec: &Recording, pos: u32, f: impl Fn(&sinscal_host::io::recording::Row) -> f64) -> (f64, f64) {
    let rows: Vec<_> = rec.rows.iter().filter(|r| r.pos == pos).collect();
    let t = rows.iter().map(|r| r.t_s).sum::<f64>() / rows.len() as f64;
    (t, rows.iter().map(|r| f(r)).sum::<f64>() / rows.len() as f64)
}

#[test]
fn time_dependent_effects_appear_where_the_model_puts_them() {
    let base = "[site]\nlatitude_deg = 45.0\n[schedule]\ndwell_s = 20.0\n";
    let clean = simulate(&scenario(base), 1, "clean");
    // Bias drift: the dwell means move by slope x elapsed time.
    let drift = simulate(&scenario(&format!("{base}[accel]\ndrift_mps2_per_s = [0, 2e-6, 0]\n")), 1, "drift");
    for pos in 1..=6 {
        let (t, with) = mean_of(&drift, pos, |r| r.force_b_mps2[1]);
        let (_, without) = mean_of(&clean, pos, |r| r.force_b_mps2[1]);
        assert!(((with - without) - 2e-6 * (t + 0.005)).abs() < 1e-12, "pos {pos}");
    }
    // Warm-up: A exp(-t/tau), exact interval averages.
    let warm = simulate(
        &scenario(&format!("{base}[gyro]\nwarmup = {{ amplitude_radps = [0, 0, 1e-5], tau_s = 30.0 }}\n")),
        1,
        "w",
    );
    let d0 = warm.rows[0].rate_b_radps[2] - clean.rows[0].rate_b_radps[2];
    assert!((d0 - 1e-5 * 30.0 / 0.01 * (1.0 - (-0.01f64 / 30.0).exp())).abs() < 1e-18, "{d0}");
    // Temperature: a temp_c column, and the bias follows k (T - T_ref).
    let temp = simulate(
        &scenario(&format!(
            "{base}[accel]\ntemperature_coefficient_mps2_per_k = [1e-4, 0, 0]\n[temperature]\nstart_c = 20.0\nend_c = 30.0\ntau_s = 100.0\nreference_c = 20.0\n"
        )),
        1,
        "t",
    );
    let last = temp.rows.last().expect("rows");
    let t_c = last.temp_c.expect("temperature column");
    assert!((t_c - (30.0 - 10.0 * (-(last.t_s + 0.005) / 100.0f64).exp())).abs() < 1e-12);
    let d = last.force_b_mps2[0] - clean.rows.last().expect("rows").force_b_mps2[0];
    assert!((d - 1e-4 * (t_c - 20.0)).abs() < 1e-12, "{d}");
    // Vibration: the interval average of A sin(2 pi f t + phase) has amplitude A sinc(f dt); sampled at four
    // phases per period (25 Hz at 100 Hz) its mean square is exactly half the squared amplitude.
    let vib = simulate(
        &scenario(&format!("{base}[gyro]\nvibration = {{ amplitude_radps = [1e-4, 0, 0], frequency_hz = 25.0 }}\n")),
        1,
        "v",
    );
    let diffs: Vec<f64> =
        vib.rows.iter().zip(&clean.rows).map(|(a, b)| a.rate_b_radps[0] - b.rate_b_radps[0]).collect();
    let rms = (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
    let sinc = (PI * 25.0 * 0.01).sin() / (PI * 25.0 * 0.01);
    assert!((rms - 1e-4 * sinc / 2f64.sqrt()).abs() < 1e-4 * 1e-6, "rms {rms}, expected {}", 1e-4 * sinc / 2f64.sqrt());
    // Quantisation: every output a multiple of the step; the integral keeps within one step of the truth.
    let q = 1e-3;
    let quant = simulate(
        &scenario(&format!(
            "{base}[accel]\nquantization_mps2 = [{q}, {q}, {q}]\nvelocity_random_walk_mps_per_sqrt_s = 1e-3\n"
        )),
        1,
        "q",
    );
    let noisy = simulate(&scenario(&format!("{base}[accel]\nvelocity_random_walk_mps_per_sqrt_s = 1e-3\n")), 1, "n");
    let (mut sum_q, mut sum_n) = (0.0, 0.0);
    for (a, b) in quant.rows.iter().zip(&noisy.rows) {
        for i in 0..3 {
            let steps = a.force_b_mps2[i] / q;
            assert!((steps - steps.round()).abs() < 1e-6, "{}", a.force_b_mps2[i]);
        }
        sum_q += a.force_b_mps2[2];
        sum_n += b.force_b_mps2[2];
        assert!((sum_q - sum_n).abs() <= 0.5 * q + 1e-9);
    }
}

#[test]
fn calibration_recovers_the_biases_of_the_clean_scenario() {
    let file = ScenarioFile::read(&scenarios_dir().join("table1-clean.toml")).unwrap_or_else(|e| panic!("{e}"));
    for seed in [1, 2] {
        let rec = simulate(&file, seed, "clean");
        let cal = calibrate(&rec, &Options::default()).unwrap_or_else(|e| panic!("{e}"));
        for i in 0..3 {
            let e = &cal.estimates;
            let (g, g_std) = (e.value_si[i].expect("observable"), e.std_si[i].expect("observable"));
            let (a, a_std) = (e.value_si[3 + i].expect("observable"), e.std_si[3 + i].expect("observable"));
            let zg = (g - file.gyro.bias_radps[i]) / g_std;
            let za = (a - file.accel.bias_mps2[i]) / a_std;
            assert!(zg.abs() < 4.0 && za.abs() < 4.0, "seed {seed} axis {i}: z {zg:.2} {za:.2}");
        }
    }
}

/// Allan deviation of the simulated gyro noise at 50, 200 and 1000 Hz against the sum of the closed
/// forms (IEEE Std 952-1997 Annex C): angle random walk N^2/tau, rate random walk K^2 tau/3, first-order
/// Gauss-Markov, and quantisation 3 Q^2 / tau^2 with Q = q dt / sqrt(12) (q the output step). The same
/// densities are given at every rate; the curves must agree with the closed form within 3 times the
/// estimator's relative uncertainty.
#[test]
fn simulated_noise_has_the_closed_form_allan_deviation_at_every_rate() {
    let (n, k, sigma, t_gm) = (1e-4, 2e-6, 3e-5, 5.0);
    let duration_s = 600.0;
    for rate in [50.0f64, 200.0, 1000.0] {
        let dt = 1.0 / rate;
        // An output step of 0.7 of the white noise per sample: the integrated signal crosses several steps
        // between samples, so the quantisation error is white and uniform, which the closed form assumes
        // (a step much larger than the noise leaves a slowly wandering, non-white error).
        let q = 0.7 * n / dt.sqrt();
        let text = format!(
            "[site]\nlatitude_deg = 0.0\n[schedule]\nrate_hz = {rate}\ndwell_s = {duration_s}\nsettle_s = 0.0\npositions_deg = [[0, 0, 0]]\n\
             [gyro]\nangle_random_walk_rad_per_sqrt_s = {n}\nrate_random_walk_radps_per_sqrt_s = {k}\n\
             bias_instability = {{ sigma_radps = [{sigma}, {sigma}, {sigma}], tau_s = {t_gm} }}\nquantization_radps = [{q}, {q}, {q}]\n"
        );
        let rec = simulate(&scenario(&text), 11, "allan");
        let big_q = q * dt / 12f64.sqrt();
        let closed = |tau: f64| {
            let x = t_gm / tau;
            let gm =
                2.0 * sigma * sigma * t_gm / tau * (1.0 - 0.5 * x * (3.0 - 4.0 * (-1.0 / x).exp() + (-2.0 / x).exp()));
            (n * n / tau + k * k * tau / 3.0 + gm + 3.0 * big_q * big_q / (tau * tau)).sqrt()
        };
        let taus_s = [0.02, 0.1, 1.0, 5.0, 20.0, 60.0];
        let clusters: Vec<usize> = taus_s.iter().map(|t| (t * rate) as usize).filter(|&m| m >= 1).collect();
        for axis in 0..3 {
            let x: Vec<f64> = rec.rows.iter().map(|r| r.rate_b_radps[axis]).collect();
            for p in overlapping_allan_deviation(&x, rate, &clusters) {
                let expected = closed(p.tau_s);
                let rel = p.adev / expected - 1.0;
                println!("rate {rate:6} Hz axis {axis} tau {:6.2} s: adev {:.4e}, closed form {expected:.4e} ({:+.1} %, bound {:.1} %)", p.tau_s, p.adev, 100.0 * rel, 300.0 * p.rel_uncertainty);
                assert!(rel.abs() < 3.0 * p.rel_uncertainty + 0.02, "rate {rate} axis {axis} tau {}", p.tau_s);
            }
        }
    }
}
