//! `sinscal study`: synthetic data with a known hidden cause (the study must find it and its extension must
//! recover it), the command line's errors, and the three measured data sets in the directory named by
//! `SINSCAL_DATA` (skipped with a message when it is not set).

use std::path::Path;

mod common;

use assert_cmd::Command;
use common::data_dir;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::study::factory::lower_triangular_form;
use sinscal_host::study::multi_pose::{study_multi_pose, PoseKind};
use sinscal_host::study::psins::study_single_pose;
use sinscal_host::study::{study_dataset, Dataset, Study};

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

fn header(rate_hz: f64, gravity_mps2: f64) -> Header {
    Header {
        latitude_deg: 45.0,
        height_m: 0.0,
        rate_hz: Some(rate_hz),
        gravity_mps2: Some(gravity_mps2),
        comments: vec!["SIMULATION for tests/study.rs".to_string()],
        truth: None,
        pose_tolerance_deg: None,
    }
}

fn row(t_s: f64, pos: u32, rate: [f64; 3], force: [f64; 3]) -> Row {
    common::static_row(t_s, pos, (0.0, 0.0), rate, force)
}

fn cause<'a>(s: &'a Study, name_starts: &str, channel: &str) -> Option<&'a sinscal_host::study::Cause> {
    s.causes.iter().find(|c| c.name.starts_with(name_starts) && c.channels.contains(channel))
}

// -------------------------------------------------------------------------------------------------------------
// Synthetic data with a known hidden cause

/// 30 poses in random directions; the accelerometer has a hidden lower-triangular A (scale factors and
/// misalignments) and a bias, the gyro a hidden g-sensitivity. The study must name both, and its extension must
/// recover A and b.
#[test]
fn synthetic_multi_pose_recovers_hidden_scale_factors_misalignments_and_g_sensitivity() {
    let g = 9.81;
    let rate = 100.0;
    let a_true = [[1.012, 0.0, 0.0], [0.006, 0.991, 0.0], [-0.009, 0.004, 1.018]];
    let b_true = [0.08, -0.05, 0.12];
    let gyro_bias = [0.01, -0.02, 0.005];
    let gsens = [[0.0, 0.0015, 0.0], [-0.0015, 0.0, 0.0], [0.0, 0.0, 0.001]]; // (rad/s)/(m/s^2)
    let (accel_noise, gyro_noise) = (0.01, 0.002);
    let mut r = ChaCha8Rng::seed_from_u64(7);
    let mut n = || -> f64 { StandardNormal.sample(&mut r) };
    let mut rows = Vec::new();
    let mut t = 0.0;
    for pose in 0..30u32 {
        let d = [n(), n(), n()];
        let nd = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let f = d.map(|x| g * x / nd);
        let meas_f: [f64; 3] = [0, 1, 2].map(|i| b_true[i] + (0..3).map(|j| a_true[i][j] * f[j]).sum::<f64>());
        let meas_w: [f64; 3] = [0, 1, 2].map(|i| gyro_bias[i] + (0..3).map(|j| gsens[i][j] * f[j]).sum::<f64>());
        for k in 0..(400 + 20) {
            let pos = if k < 20 { 0 } else { pose + 1 };
            let force = meas_f.map(|v| v + accel_noise * n());
            let w = meas_w.map(|v| v + gyro_noise * n());
            rows.push(row(t, pos, w, force));
            t += 1.0 / rate;
        }
    }
    let rec = Recording { source: "synthetic".to_string(), header: header(rate, g), rows, has_gyro: true };
    let s = study_multi_pose(&rec, PoseKind::Unlabelled, g, "synthetic", vec![], 1, &[]).unwrap();
    let p = s.poses.as_ref().unwrap();
    assert_eq!(p.poses.len(), 30);
    // The extension recovers the hidden A and b. Tolerance: noise of a pose mean 0.01 / sqrt(400) = 5e-4 m/s^2,
    // i.e. 5e-5 relative; 30 poses for 9 parameters: 5e-4 on A and 5e-3 m/s^2 on b is several sigma.
    let a = &p.extended_accel.matrix;
    for i in 0..3 {
        for j in 0..3 {
            assert!((a[i][j] - a_true[i][j]).abs() < 5e-4, "A[{i}][{j}] = {} (true {})", a[i][j], a_true[i][j]);
        }
        assert!((p.extended_accel.bias_mps2[i] - b_true[i]).abs() < 5e-3, "b = {:?}", p.extended_accel.bias_mps2);
    }
    // The gauge helper is consistent: a lower-triangular matrix is its own canonical form.
    let l = lower_triangular_form(&a_true);
    for i in 0..3 {
        for j in 0..3 {
            assert!((l[i][j] - a_true[i][j]).abs() < 1e-12);
        }
    }
    // The disagreement is far above the noise; the held-out gain is large; the cause is named first.
    assert!(p.norm_rms_data_mps2 / p.norm_rms_noise_mps2 > 20.0, "{} {}", p.norm_rms_data_mps2, p.norm_rms_noise_mps2);
    assert!(p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2 > 10.0);
    assert!(p.held_out_norm_rms_extended_mps2 < 3.0 * p.norm_rms_noise_mps2);
    assert_eq!(s.causes[0].name, "accel scale factors and misalignments", "{:?}", s.causes);
    // Gyro: g-sensitivity named, recovered within 1e-4 (rad/s)/(m/s^2) (noise of a pose mean 1e-4 rad/s over
    // forces of 10 m/s^2 on 30 poses).
    assert!(cause(&s, "gyro g-sensitivity", "gx").is_some(), "{:?}", s.causes);
    let gs = p.gyro_g_sensitivity.unwrap();
    for i in 0..3 {
        for j in 0..3 {
            // The fitted matrix multiplies the measured (biased, scaled) force: the tolerance covers that.
            assert!((gs[i][j] - gsens[i][j]).abs() < 1e-4, "G[{i}][{j}] = {} (true {})", gs[i][j], gsens[i][j]);
        }
    }
}

/// A bias-only accelerometer (A = I) and a constant gyro: nothing to name, no held-out gain.
#[test]
fn synthetic_multi_pose_without_errors_names_no_pose_cause() {
    let g = 9.81;
    let mut r = ChaCha8Rng::seed_from_u64(8);
    let mut n = || -> f64 { StandardNormal.sample(&mut r) };
    let mut rows = Vec::new();
    let mut t = 0.0;
    for pose in 0..20u32 {
        let d = [n(), n(), n()];
        let nd = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        for k in 0..320 {
            let pos = if k < 20 { 0 } else { pose + 1 };
            let force = [0, 1, 2].map(|i| g * d[i] / nd + 0.03 + 0.01 * n());
            rows.push(row(t, pos, [0.001 * n(), 0.001 * n(), 0.001 * n()], force));
            t += 0.01;
        }
    }
    let rec = Recording { source: "synthetic".to_string(), header: header(100.0, g), rows, has_gyro: true };
    let s = study_multi_pose(&rec, PoseKind::Unlabelled, g, "synthetic", vec![], 1, &[]).unwrap();
    let p = s.poses.as_ref().unwrap();
    assert!(p.norm_rms_data_mps2 / p.norm_rms_noise_mps2 < 3.0, "{}", p.norm_rms_data_mps2 / p.norm_rms_noise_mps2);
    assert!(cause(&s, "accel", "ax").is_none() && cause(&s, "gyro", "gx").is_none(), "{:?}", s.causes);
}

/// One static record: white noise on every channel, plus a hidden rate random walk on gz. The study must name
/// correlated noise (rate random walk) on gz only, fit K within 35 %, and its extension must reproduce the
/// second half's Allan curve better than the white base model.
#[test]
fn synthetic_single_pose_finds_hidden_rate_random_walk() {
    let rate: f64 = 100.0;
    let n_samples = 200_000; // 2000 s
    let white_std = 1e-4; // rad/s and m/s^2 per sample
    let k_true = 2e-6; // rad/s/sqrt(s)
    let mut r = ChaCha8Rng::seed_from_u64(9);
    let mut n = || -> f64 { StandardNormal.sample(&mut r) };
    let mut walk = 0.0;
    let rows: Vec<Row> = (0..n_samples)
        .map(|k| {
            walk += k_true / rate.sqrt() * n();
            let w = [white_std * n(), white_std * n(), 5e-5 + walk + white_std * n()];
            let f = [white_std * n(), white_std * n(), 9.8 + white_std * n()];
            row(k as f64 / rate, 1, w, f)
        })
        .collect();
    let rec = Recording { source: "synthetic".to_string(), header: header(rate, 9.8), rows, has_gyro: true };
    let s = study_single_pose(&rec, "synthetic", vec![], 3);
    let gz = s.noise.iter().find(|c| c.channel == "gz").unwrap();
    assert!((gz.white_std / white_std - 1.0).abs() < 0.02, "white std {}", gz.white_std);
    // At the long tau (about 200 s), sigma_K = K sqrt(tau/3) = 1.6e-5 against white 1e-4 / sqrt(2e4) = 7e-7.
    assert!(gz.ratio_at_long_tau > 5.0, "ratio {}", gz.ratio_at_long_tau);
    let c = cause(&s, "correlated noise", "gz").unwrap_or_else(|| panic!("{:?}", s.causes));
    assert!(c.name.contains("rate random walk"), "{c:?}");
    let e = gz.extended.as_ref().unwrap();
    assert!((e.terms_all.rate_random_walk_k / k_true - 1.0).abs() < 0.35, "K {}", e.terms_all.rate_random_walk_k);
    assert!(e.held_out_rms_log10_extended < 0.5 * e.held_out_rms_log10_base, "{e:?}");
    // White channels: no cause, ratio near 1.
    for ch in s.noise.iter().filter(|c| c.channel != "gz") {
        assert!((0.5..2.0).contains(&ch.ratio_at_long_tau), "{} {}", ch.channel, ch.ratio_at_long_tau);
        assert!(s.causes.iter().all(|c| !c.channels.contains(ch.channel)), "{:?}", s.causes);
    }
}

// -------------------------------------------------------------------------------------------------------------
// Command line

#[test]
fn cli_missing_data_directory_is_one_line_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    let run = sinscal()
        .args(["study", "psins", "--data"])
        .arg(tmp.path())
        .arg("--report")
        .arg(tmp.path().join("r"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    let reason: Vec<&str> = stderr.lines().filter(|l| l.starts_with("sinscal:")).collect();
    assert_eq!(reason.len(), 1, "{stderr}");
    assert!(reason[0].contains("lasergyro.imu") && reason[0].contains("missing"), "{stderr}");
    let run = sinscal().args(["study", "psins", "--report", "x"]).env_remove("SINSCAL_DATA").output().unwrap();
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("SINSCAL_DATA"));
}

#[test]
fn cli_usage_errors_exit_2() {
    let run = sinscal().args(["study", "psins"]).output().unwrap();
    assert_eq!(run.status.code(), Some(2), "--report is required");
}

// -------------------------------------------------------------------------------------------------------------
// Real data (SINSCAL_DATA)

/// Runs the command line on a data set into a temporary report directory; returns the JSON and the directory.
fn run_cli(dir: &Path, dataset: &str) -> (serde_json::Value, tempfile::TempDir) {
    let tmp = tempfile::tempdir().unwrap();
    let json = tmp.path().join("study.json");
    sinscal()
        .args(["study", dataset, "--data"])
        .arg(dir)
        .arg("--report")
        .arg(tmp.path())
        .arg("--json")
        .arg(&json)
        .assert()
        .success();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["schema"], "sinscal-study/1");
    assert_eq!(v["dataset"], dataset);
    for key in ["base", "disagreement", "cause", "extended", "gain"] {
        assert!(!v[key].is_null(), "{key} missing");
    }
    let md = std::fs::read_to_string(tmp.path().join("summary.md")).unwrap();
    for f in v["figures"].as_array().unwrap() {
        let name = f.as_str().unwrap();
        assert!(md.contains(name), "summary.md does not link {name}");
        let png = std::fs::read(tmp.path().join(name)).unwrap();
        assert!(png.len() > 1000 && png.starts_with(b"\x89PNG"), "{name}");
    }
    assert!(md.contains("SIMULATION"));
    (v, tmp)
}

#[test]
fn real_psins_correlated_noise_and_vehicle_sway() {
    let Some(dir) = data_dir() else { return };
    let s = study_dataset(Dataset::Psins, &dir).unwrap();
    for c in &s.causes {
        eprintln!("psins cause: {} ({}): {}", c.name, c.channels, c.evidence);
    }
    // Horizontal accelerometers follow g x the tilt the horizontal gyros integrate: the vehicle sways.
    for sw in &s.sway {
        assert!(sw.correlation > 0.7, "{sw:?}");
        assert!((sw.slope_mps2_per_rad.abs() / 9.78 - 1.0).abs() < 0.1, "{sw:?}");
    }
    assert!(cause(&s, "vehicle sway", "ax").is_some() && cause(&s, "vehicle sway", "ay").is_some());
    // Horizontal channels: Allan deviation at the long tau well above the white-noise SIMULATION.
    for name in ["gx", "gy", "ax", "ay"] {
        let ch = s.noise.iter().find(|c| c.channel == name).unwrap();
        assert!(ch.ratio_at_long_tau > 2.0, "{name}: {}", ch.ratio_at_long_tau);
        assert!(cause(&s, "correlated noise", name).is_some(), "{name}");
    }
    // The extension beats the base model on the held-out second half for the accelerometers by a factor 1.5.
    for name in ["ax", "ay", "az"] {
        let e = s.noise.iter().find(|c| c.channel == name).unwrap().extended.clone().unwrap();
        assert!(e.held_out_rms_log10_extended * 1.5 < e.held_out_rms_log10_base, "{name}: {e:?}");
    }
    let (v, _tmp) = run_cli(&dir, "psins");
    assert!(v["gain"]["az_held_out_rms_log10_adev"]["extended"].as_f64().unwrap() < 0.5);
}

#[test]
fn real_ferraris_accel_scale_misalignment_and_gyro_scale() {
    let Some(dir) = data_dir() else { return };
    let s = study_dataset(Dataset::Ferraris, &dir).unwrap();
    let p = s.poses.as_ref().unwrap();
    eprintln!(
        "ferraris: norm RMS {:.4} vs noise {:.2e} m/s^2; held-out {:.4} -> {:.4} m/s^2",
        p.norm_rms_data_mps2, p.norm_rms_noise_mps2, p.held_out_norm_rms_base_mps2, p.held_out_norm_rms_extended_mps2
    );
    assert_eq!(p.poses.len(), 6);
    assert!(p.norm_rms_data_mps2 / p.norm_rms_noise_mps2 > 50.0);
    assert!(p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2 > 3.0);
    assert_eq!(s.causes[0].name, "accel scale factors and misalignments");
    // The z accelerometer reads about 2 % high.
    assert!(p.extended_accel.scale_factors()[2] > 0.01);
    // Turns: the raw integrals of docs/data.md#imucal-ferraris, -371.9, -354.8, -359.2 deg; x and y far from 360 deg.
    let raw: Vec<f64> = p.turns.iter().map(|t| t.raw_angle_rad.to_degrees()).collect();
    for (got, want) in raw.iter().zip([-371.9, -354.8, -359.2]) {
        assert!((got - want).abs() < 0.2, "{raw:?}");
    }
    assert!(cause(&s, "gyro scale factor", "gx").is_some() && cause(&s, "gyro scale factor", "gy").is_some());
    run_cli(&dir, "ferraris");
}

#[test]
fn real_imutk_accel_matches_factory_and_gyro_g_sensitivity() {
    let Some(dir) = data_dir() else { return };
    let s = study_dataset(Dataset::Imutk, &dir).unwrap();
    let p = s.poses.as_ref().unwrap();
    eprintln!("imutk causes: {:?}", s.causes.iter().map(|c| &c.name).collect::<Vec<_>>());
    assert!(p.poses.len() >= 30);
    assert!(p.norm_rms_data_mps2 / p.norm_rms_noise_mps2 > 50.0);
    assert!(p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2 > 10.0);
    assert_eq!(s.causes[0].name, "accel scale factors and misalignments");
    // Against the factory calibration: gains within 0.5 %, lower misalignments within 0.005 in the
    // diag(gain) M convention, and that convention closer than the inverse one.
    let f = p.factory.as_ref().unwrap();
    for i in 0..3 {
        let rel = f.fitted_gain_counts_per_mps2[i] / f.factory_gain_counts_per_mps2[i] - 1.0;
        assert!(rel.abs() < 0.005, "gain {i}: {f:?}");
    }
    let dist = |m: [f64; 3]| (0..3).map(|i| (m[i] - f.fitted_misalignment[i]).powi(2)).sum::<f64>().sqrt();
    assert!(dist(f.factory_misalignment) < dist(f.factory_misalignment_inverse), "{f:?}");
    assert!((f.fitted_misalignment[1] - f.factory_misalignment[1]).abs() < 0.005, "{f:?}");
    assert!((f.fitted_misalignment[2] - f.factory_misalignment[2]).abs() < 0.005, "{f:?}");
    // Gyro per-pose means scatter by several times the noise (docs/data.md#imu-tk-xsens: about +-7 counts); g-sensitivity
    // explains most of it on the odd poses.
    assert!(p.gyro_spread_rms_radps / p.gyro_spread_noise_radps > 3.0);
    let held = |name: &str| p.gyro_models_held_out_radps.iter().find(|m| m.0 == name).unwrap().1;
    assert!(held("bias + g-sensitivity") < 0.5 * held("constant bias"));
    assert!(cause(&s, "gyro g-sensitivity", "gx").is_some(), "{:?}", s.causes);
    run_cli(&dir, "imutk");
}
