//! The noise model named from the Allan variance (`sinscal_host::analysis::noise_terms`,
//! docs/analysis.md#noise-model): on SIMULATION sessions of `sinscal simulate` with known noise terms, each
//! planted term is named and recovered within its stated standard error (sway from its own generator), white
//! noise alone names nothing more; and the model as printed for the three measured data sets (SKIPPED when `SINSCAL_DATA` is unset).

mod common;

use sinscal_host::analysis::noise_terms::{noise_model, NoiseModel, Term};
use sinscal_host::io::import::{import_imutk, import_psins, StaticDetection};
use sinscal_host::model::simulator::{simulate, ScenarioFile};

/// The samples of channel `c` (0..3 gyro, 3..6 accelerometer) of a one-position SIMULATION session of
/// `hours` at 100 Hz with the `[gyro]` and `[accel]` noise lines given, mean removed.
fn simulated(gyro: &str, accel: &str, hours: f64, seed: u64, c: usize) -> Vec<f64> {
    let text = format!(
        "[site]\nlatitude_deg = 45.0\nheight_m = 0.0\n\n[schedule]\nrate_hz = 100.0\ndwell_s = {}\nmove_s = 1.0\n\
         settle_s = 0.0\npositions_deg = [[0, 0, 0]]\n\n[gyro]\nbias_radps = [0, 0, 0]\n{gyro}\n\n[accel]\n\
         bias_mps2 = [0, 0, 0]\n{accel}\n",
        hours * 3600.0
    );
    let scenario = ScenarioFile::parse(&text, "noise-model scenario").expect("scenario");
    let rec = simulate(&scenario, seed, "noise-model SIMULATION");
    let y: Vec<f64> = rec
        .rows
        .iter()
        .filter(|r| r.pos == 1)
        .map(|r| if c < 3 { r.rate_b_radps[c] } else { r.force_b_mps2[c - 3] })
        .collect();
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    y.iter().map(|v| v - mean).collect()
}

/// Prints the model and checks that exactly `planted` (term, SI value) are named, each within `z_max` of its
/// standard error. Returns the z-scores.
fn check(label: &str, m: &NoiseModel, planted: &[(Term, f64)], z_max: f64) -> Vec<f64> {
    println!("SIMULATION {label}: {}", m.text());
    let named: Vec<Term> = m.terms.iter().map(|t| t.term).collect();
    let wanted: Vec<Term> = planted.iter().map(|p| p.0).collect();
    assert_eq!(named, wanted, "{label}: named {}", m.named);
    planted
        .iter()
        .zip(&m.terms)
        .map(|((_, truth), t)| {
            let z = (t.value_si - truth) / t.std_error_si;
            println!(
                "  {}: {:.4e} +- {:.2e} {} against {truth:.4e} planted, z = {z:+.2}",
                t.symbol, t.value_si, t.std_error_si, t.unit_si
            );
            assert!(z.abs() <= z_max, "{label}: {} off by {z:.2} standard errors", t.symbol);
            z
        })
        .collect()
}

#[test]
fn white_noise_alone_names_white_noise_only() {
    let n_rad_per_sqrt_s = 5.0e-6;
    let y = simulated(&format!("angle_random_walk_rad_per_sqrt_s = {n_rad_per_sqrt_s}"), "", 1.0, 1, 0);
    let m = noise_model("gx_radps", true, &y, 100.0).expect("model");
    check("white", &m, &[(Term::White, n_rad_per_sqrt_s)], 3.0);
    assert!(!m.better_than_white_only);
    let r = m.lag1_difference_autocorrelation.expect("lag 1");
    assert!((r + 0.5).abs() < 3.0 * m.lag1_std_error, "white noise differences: lag-1 {r}");
}

#[test]
fn quantisation_white_and_gauss_markov_are_each_recovered() {
    // Output step 1.5e-4 rad/s of the integrated output: Q = q dt / sqrt(12).
    let (q_radps, n, gm_sigma, gm_tau_s) = (1.0e-4, 5.0e-6, 2.0e-6, 20.0);
    let gyro = format!(
        "angle_random_walk_rad_per_sqrt_s = {n}\nquantization_radps = [{q_radps}, {q_radps}, {q_radps}]\n\
         bias_instability = {{ sigma_radps = [{gm_sigma}, {gm_sigma}, {gm_sigma}], tau_s = {gm_tau_s} }}"
    );
    let q_rad = q_radps * 0.01 / 12f64.sqrt();
    let mut zs = Vec::new();
    for seed in 1..=8 {
        let y = simulated(&gyro, "", 1.0, seed, 1);
        let m = noise_model("gy_radps", true, &y, 100.0).expect("model");
        let planted = [(Term::Quantization, q_rad), (Term::White, n), (Term::GaussMarkov, gm_sigma)];
        zs.extend(check(&format!("Q + N + GM seed {seed}"), &m, &planted, 3.0));
        let gm = &m.terms[2];
        let (tc, tc_se) = (gm.tau_c_s.expect("tau_c"), gm.tau_c_std_error_s.expect("its error"));
        println!("  GM tau_c {tc:.2} +- {tc_se:.2} s against {gm_tau_s} s, z = {:+.2}", (tc - gm_tau_s) / tc_se);
        assert!(((tc - gm_tau_s) / tc_se).abs() <= 3.0);
        assert!(m.better_than_white_only);
        // Quantisation of an integrated output: differences more negatively correlated than white noise's.
        assert!(m.lag1_difference_autocorrelation.expect("lag 1") < -0.5 - 3.0 * m.lag1_std_error);
    }
    let rms = (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64).sqrt();
    println!("Q + N + GM: RMS z over {} estimates = {rms:.2}", zs.len());
    assert!(rms < 1.3, "stated errors too small: RMS z {rms:.2}");
}

#[test]
fn rate_random_walk_and_rate_ramp_are_recovered() {
    let (n, k) = (5.0e-4, 4.0e-6);
    let accel = format!("velocity_random_walk_mps_per_sqrt_s = {n}\nacceleration_random_walk_mps2_per_sqrt_s = {k}");
    let y = simulated("", &accel, 2.0, 3, 4);
    let m = noise_model("ay_mps2", false, &y, 100.0).expect("model");
    check("N + K", &m, &[(Term::White, n), (Term::RateRandomWalk, k)], 3.0);

    let (n, r) = (5.0e-6, 1.0e-9);
    let gyro = format!("angle_random_walk_rad_per_sqrt_s = {n}\ndrift_radps_per_s = [0, 0, {r}]");
    let y = simulated(&gyro, "", 2.0, 4, 2);
    let m = noise_model("gz_radps", true, &y, 100.0).expect("model");
    check("N + R", &m, &[(Term::White, n), (Term::RateRamp, r)], 3.0);
}

/// SIMULATION: white noise and sway (the rate of an angle that is a first-order Gauss-Markov process, as a
/// vehicle's sway leaves a bounded tilt), `hours` at 100 Hz.
fn white_and_sway(n_rad_per_sqrt_s: f64, sway_rad: f64, sway_time_s: f64, hours: f64, seed: u64) -> Vec<f64> {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let dt = 0.01;
    let a = (-dt / sway_time_s).exp();
    let drive = sway_rad * (1.0 - a * a).sqrt();
    let mut normal = move || -> f64 { StandardNormal.sample(&mut rng) };
    let mut angle = sway_rad * normal();
    (0..(hours * 360_000.0) as usize)
        .map(|_| {
            let before = angle;
            angle = a * angle + drive * normal();
            let white = normal();
            (angle - before) / dt + n_rad_per_sqrt_s / dt.sqrt() * white
        })
        .collect()
}

/// A planted sway is found beside its white-noise floor: both named, with sway's correlation time, each within
/// its standard errors; white noise alone from the same generator names no sway.
#[test]
fn sway_is_found_where_it_is_planted() {
    let (n, sway_rad, sway_time_s) = (2.0e-5, 1.0e-4, 5.0);
    let mut zs = Vec::new();
    for seed in 1..=4 {
        let y = white_and_sway(n, sway_rad, sway_time_s, 1.0, seed);
        let m = noise_model("gx_radps", true, &y, 100.0).expect("model");
        zs.extend(check(&format!("N + S seed {seed}"), &m, &[(Term::White, n), (Term::Sway, sway_rad)], 3.0));
        let sway = &m.terms[1];
        let (tc, tc_se) = (sway.tau_c_s.expect("tau_c"), sway.tau_c_std_error_s.expect("its error"));
        let z = (tc - sway_time_s) / tc_se;
        println!("  S tau_c {tc:.2} +- {tc_se:.2} s against {sway_time_s} s, z = {z:+.2}");
        assert!(z.abs() <= 3.0);
        zs.push(z);
        let y = white_and_sway(n, 0.0, sway_time_s, 1.0, seed + 100);
        let m = noise_model("gx_radps", true, &y, 100.0).expect("model");
        check(&format!("N alone seed {}", seed + 100), &m, &[(Term::White, n)], 3.0);
    }
    let rms = (zs.iter().map(|z| z * z).sum::<f64>() / zs.len() as f64).sqrt();
    println!("N + S and its time: RMS z over {} estimates = {rms:.2}", zs.len());
    assert!(rms < 1.3, "stated errors too small: RMS z {rms:.2}");
}

#[test]
fn noise_model_of_the_measured_data_sets() {
    let Some(dir) = common::data_dir() else { return };
    let psins = import_psins(&common::data_file(&dir, "psins-lasergyro/lasergyro.imu"), None).expect("psins");
    let acc = common::data_file(&dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = common::data_file(&dir, "imu-tk-xsens/xsens_gyro.mat");
    let xsens = import_imutk(&acc, &gyro, None, &StaticDetection::default()).expect("imutk");
    let sets = [
        ("psins-lasergyro", psins.recording),
        ("imucal-ferraris", common::ferraris_session(&dir)),
        ("imu-tk-xsens", xsens.recording),
    ];
    for (name, recording) in sets {
        let analysis = sinscal_host::analysis::analyze_recording(&recording).expect("analysis");
        println!("{name} ({} channels):", analysis.noise_model.len());
        assert!(!analysis.noise_model.is_empty(), "{name}: no noise model");
        for m in &analysis.noise_model {
            println!("  {}", m.text());
            assert!(m.terms.iter().all(|t| t.value_si > 0.0 && t.std_error_si.is_finite()));
            // White only is the named model or is worse by the criterion.
            assert_eq!(m.better_than_white_only, m.named != "N", "{name} {}", m.channel);
        }
    }
}
