//! `sinscal study RECORDING`: any recording studied by path. Synthetic recordings written by the project's
//! writer with a known truth (white noise only: the held-out gate keeps no term; a planted rate random walk:
//! kept; labelled poses with a planted scale factor: found), the command line's refusals, and a shared data set
//! re-imported, cut differently and studied by path (`SINSCAL_DATA`; skipped with a message when it is not set).

use std::path::Path;

mod common;

use assert_cmd::Command;
use common::data_dir;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::study::recording::study_recording;
use sinscal_host::study::{study_dataset, Dataset, NoiseExtension, Study};

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

fn header(rate_hz: f64) -> Header {
    Header {
        latitude_deg: 45.0,
        height_m: 0.0,
        rate_hz: Some(rate_hz),
        gravity_mps2: None,
        comments: vec!["SIMULATION for tests/study_recording.rs".to_string()],
        truth: None,
        pose_tolerance_deg: None,
    }
}

fn row(t_s: f64, pos: u32, attitude_deg: (f64, f64), rate: [f64; 3], force: [f64; 3]) -> Row {
    common::static_row(t_s, pos, attitude_deg, rate, force)
}

/// One static pose of `n` samples at 100 Hz: white noise of 1e-4 (rad/s, m/s^2) per sample on every channel,
/// plus a rate random walk of `k_gz` rad/s/sqrt(s) on gz; written to `dir/name` by the project's writer.
fn single_pose_file(dir: &Path, name: &str, n: usize, k_gz: f64, seed: u64) -> std::path::PathBuf {
    let rate: f64 = 100.0;
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let mut g = || -> f64 { StandardNormal.sample(&mut r) };
    let mut walk = 0.0;
    let rows = (0..n)
        .map(|k| {
            walk += k_gz / rate.sqrt() * g();
            let w = [1e-4 * g(), 1e-4 * g(), 5e-5 + walk + 1e-4 * g()];
            let f = [1e-4 * g(), 1e-4 * g(), 9.8 + 1e-4 * g()];
            row(k as f64 / rate, 1, (0.0, 0.0), w, f)
        })
        .collect();
    let rec = Recording { source: name.to_string(), header: header(rate), rows, has_gyro: true };
    let path = dir.join(name);
    rec.write(&path).unwrap();
    path
}

fn extension<'a>(s: &'a Study, channel: &str) -> &'a NoiseExtension {
    s.noise.iter().find(|c| c.channel == channel).unwrap().extended.as_ref().unwrap()
}

fn kept(e: &NoiseExtension) -> Vec<&str> {
    e.gate.iter().filter(|g| g.kept).map(|g| g.term.as_str()).collect()
}

/// White noise only (200 s at 100 Hz): the held-out gate keeps no term on any channel, so the extended model
/// is the base model, and the command line writes the report with the gate's verdicts.
#[test]
fn white_noise_recording_keeps_no_extended_term() {
    let tmp = tempfile::tempdir().unwrap();
    let path = single_pose_file(tmp.path(), "white.csv", 20_000, 0.0, 11);
    let s = study_recording(&path).unwrap();
    assert_eq!(s.dataset, "white.csv");
    for ch in &s.noise {
        let e = ch.extended.as_ref().unwrap();
        assert!(kept(e).is_empty(), "{}: kept {:?}: {:?}", ch.channel, kept(e), e.gate);
        assert!(e.held_out_chi2_extended == e.held_out_chi2_base, "{}: {e:?}", ch.channel);
    }
    let json = tmp.path().join("s.json");
    sinscal()
        .arg("study")
        .arg(&path)
        .arg("--report")
        .arg(tmp.path().join("r"))
        .arg("--json")
        .arg(&json)
        .assert()
        .success();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["dataset"], "white.csv");
    let gate = v["extended"]["gz_term_gate"].as_array().unwrap();
    assert!(!gate.is_empty() && gate.iter().all(|g| g["kept"] == false), "{gate:?}");
    let md = std::fs::read_to_string(tmp.path().join("r").join("summary.md")).unwrap();
    assert!(md.contains("held-out gate: kept none"), "{md}");
}

/// A planted rate random walk on gz (K = 2e-5 rad/s/sqrt(s), 400 s): the gate keeps the rate random walk on
/// gz, its held-out chi^2 falls by more than half, and K is recovered within 35 %.
#[test]
fn planted_rate_random_walk_is_kept_by_the_gate() {
    let tmp = tempfile::tempdir().unwrap();
    let k_true = 2e-5;
    let path = single_pose_file(tmp.path(), "walk.csv", 40_000, k_true, 12);
    let s = study_recording(&path).unwrap();
    let e = extension(&s, "gz");
    assert!(kept(e).contains(&"rate random walk"), "{:?}", e.gate);
    assert!(e.held_out_chi2_extended < 0.5 * e.held_out_chi2_base, "{e:?}");
    assert!((e.terms_all.rate_random_walk_k / k_true - 1.0).abs() < 0.35, "K {}", e.terms_all.rate_random_walk_k);
    assert!(s.causes.iter().any(|c| c.channels == "gz" && c.name.contains("rate random walk")), "{:?}", s.causes);
}

/// Normal gravity at 45 deg latitude, 0 m (the header has no gravity_mps2), m/s^2.
const G_45_MPS2: f64 = 9.80619;

/// Six labelled poses (each axis up and down, 20 s each at 100 Hz) of an accelerometer whose z reads 2 % high
/// (biases 0.01, -0.02, 0.03 m/s^2, noise 0.005 m/s^2) and gyros reading `gyro_bias` plus noise of 1e-4 per
/// sample (the recording says rad/s).
fn labelled_pose_rows(gyro_bias: [f64; 3]) -> Vec<Row> {
    let g = G_45_MPS2;
    let attitudes = [(0.0, -90.0), (0.0, 90.0), (90.0, 0.0), (-90.0, 0.0), (0.0, 0.0), (0.0, 180.0)];
    let mut r = ChaCha8Rng::seed_from_u64(13);
    let mut n = || -> f64 { StandardNormal.sample(&mut r) };
    let (mut rows, mut t) = (Vec::new(), 0.0);
    for (p, &(pitch, roll)) in attitudes.iter().enumerate() {
        let (st, ct) = f64::to_radians(pitch).sin_cos();
        let (sg, cg) = f64::to_radians(roll).sin_cos();
        let up = [-sg * ct, st, cg * ct];
        for _ in 0..2000 {
            let f = [g * up[0] + 0.01, g * up[1] - 0.02, 1.02 * g * up[2] + 0.03].map(|v| v + 0.005 * n());
            let w = [gyro_bias[0] + 1e-4 * n(), gyro_bias[1] + 1e-4 * n(), gyro_bias[2] + 1e-4 * n()];
            rows.push(row(t, p as u32 + 1, (pitch, roll), w, f));
            t += 0.01;
        }
    }
    rows
}

/// Six labelled poses of an accelerometer whose z reads 2 % high ([`labelled_pose_rows`]): studied by path as
/// labelled poses, the cause is named and the extended model finds the scale factor within 0.001. The held-out
/// gate (each pose predicted by the fit on the other five) keeps the z scale factor and drops every term the
/// SIMULATION does not have: the other scale factors and the six misalignments, which stay at their identity
/// values in the extended model.
#[test]
fn labelled_pose_recording_finds_planted_scale_factor() {
    let tmp = tempfile::tempdir().unwrap();
    let g = G_45_MPS2;
    let rec =
        Recording { source: "poses".into(), header: header(100.0), rows: labelled_pose_rows([0.0; 3]), has_gyro: true };
    let path = tmp.path().join("poses.csv");
    rec.write(&path).unwrap();
    let s = study_recording(&path).unwrap();
    let p = s.poses.as_ref().unwrap();
    assert!(p.method.contains("labelled"), "{}", p.method);
    assert!((p.gravity_mps2 - g).abs() < 1e-4, "{}", p.gravity_mps2);
    assert!((p.extended_accel.scale_factors()[2] - 0.02).abs() < 1e-3, "{:?}", p.extended_accel.scale_factors());
    assert_eq!(s.causes[0].name, "accel scale factors and misalignments", "{:?}", s.causes);
    let kept: Vec<&str> = p.accel_term_gate.iter().filter(|g| g.kept).map(|g| g.term.as_str()).collect();
    assert_eq!(kept, ["scale factor z"], "{:?}", p.accel_term_gate);
    assert_eq!(p.accel_term_gate.len(), 9, "every term of A has a verdict");
    let a = &p.extended_accel.matrix;
    assert_eq!(
        [a[0][0], a[1][1], a[0][1], a[0][2], a[1][0], a[1][2], a[2][0], a[2][1]],
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    );
}

/// Gyros in deg/s written as rad/s (a consumer gyro's biases of 0.6, -0.4 and 0.5 deg/s read as rad/s): the
/// study is written, and `sinscal study FILE` ends with calibrate's physics check failed, "gyros in deg/s?",
/// status 3. Before, it exited 0 and named gyro scale factors of about 57 as the cause.
#[test]
fn gyros_in_degrees_per_second_fail_the_physics_check_with_status_3() {
    let tmp = tempfile::tempdir().unwrap();
    let rows = labelled_pose_rows([0.6, -0.4, 0.5]);
    let path = tmp.path().join("degrees.csv");
    Recording { source: "degrees".into(), header: header(100.0), rows, has_gyro: true }.write(&path).unwrap();
    let report = tmp.path().join("r");
    let run = sinscal().arg("study").arg(&path).arg("--report").arg(&report).output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("check failed: physics: gyros in deg/s?"), "{stderr}");
    assert!(report.join("summary.md").is_file(), "{stderr}");
}

/// The command line's refusals: a name that is neither a file nor a data set, an accelerometer-only recording,
/// a recording of 3 poses: one line on stderr, exit 1.
#[test]
fn cli_refusals_are_one_line_exit_1() {
    let tmp = tempfile::tempdir().unwrap();
    let accel_only = tmp.path().join("accel.csv");
    let mut text =
        "# sinscal-recording: 1\n# latitude_deg: 45\nt_s,pos,pitch_deg,roll_deg,heading_deg,ax_mps2,ay_mps2,az_mps2\n"
            .to_string();
    for k in 0..10 {
        text.push_str(&format!("{}.0,1,0,0,,0,0,9.8\n", k));
    }
    std::fs::write(&accel_only, text).unwrap();
    let three = tmp.path().join("three.csv");
    let rows =
        (0..300).map(|k| row(k as f64 * 0.01, 1 + k as u32 / 100, (0.0, 0.0), [0.0; 3], [0.0, 0.0, 9.8])).collect();
    Recording { source: "three".into(), header: header(100.0), rows, has_gyro: true }.write(&three).unwrap();
    let cases: [(&std::ffi::OsStr, &str); 3] = [
        ("nosuchset".as_ref(), "not a data set (psins, ferraris, imutk)"),
        (accel_only.as_os_str(), "no gyro columns: study needs gyros"),
        (three.as_os_str(), "3 static poses"),
    ];
    for (arg, want) in cases {
        let run = sinscal().arg("study").arg(arg).args(["--report"]).arg(tmp.path().join("r")).output().unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{stderr}");
        let lines: Vec<&str> = stderr.lines().filter(|l| l.starts_with("sinscal:")).collect();
        assert_eq!(lines.len(), 1, "{stderr}");
        assert!(lines[0].contains(want), "{stderr}");
    }
}

/// The PSINS set re-imported (`sinscal import psins`), its first 10 % of rows dropped, written under another
/// name and studied by path: the report has disagreement, cause, extended model and held-out gain; its figures
/// agree with the built-in study of the whole set within the stated tolerances (a tenth of the record is gone,
/// and the halves of the gain split elsewhere): white std within 10 %, the long-tau ratios of the horizontal
/// channels above 2 in both and within a factor 1.5, sway correlations within 0.1; and the gate keeps no
/// sinusoid on any channel in either (the Allan fit's sinusoids are 2.5 to 42 x larger than direct fits).
#[test]
fn real_psins_reimported_and_cut_studied_by_path() {
    let Some(dir) = data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let full = tmp.path().join("psins.csv");
    sinscal()
        .args(["import", "psins"])
        .arg(dir.join("psins-lasergyro/lasergyro.imu"))
        .arg("--out")
        .arg(&full)
        .assert()
        .success();
    let mut rec = Recording::read(&full).unwrap();
    let cut = rec.rows.len() / 10;
    rec.rows.drain(..cut);
    let path = tmp.path().join("vehicle-rest-b.csv");
    rec.write(&path).unwrap();
    let json = tmp.path().join("s.json");
    let report = tmp.path().join("report");
    sinscal().arg("study").arg(&path).arg("--report").arg(&report).arg("--json").arg(&json).assert().success();
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["dataset"], "vehicle-rest-b.csv");
    for key in ["disagreement", "cause", "extended", "gain"] {
        assert!(!v[key].is_null(), "{key} missing");
    }
    for ch in ["gx", "gy", "gz", "ax", "ay", "az"] {
        assert!(v["extended"][format!("{ch}_term_gate")].is_array(), "{ch}");
        assert!(v["gain"][format!("{ch}_held_out_chi2")]["base"].as_f64().is_some(), "{ch}");
    }
    assert!(std::fs::read_to_string(report.join("summary.md")).unwrap().contains("held-out gate"));
    let (s, b) = (study_recording(&path).unwrap(), study_dataset(Dataset::Psins, &dir).unwrap());
    for (c, d) in s.noise.iter().zip(&b.noise) {
        eprintln!(
            "{}: white std {:.4e} / {:.4e}, long-tau ratio {:.2} / {:.2}, kept {:?} / {:?} (cut / built-in)",
            c.channel,
            c.white_std,
            d.white_std,
            c.ratio_at_long_tau,
            d.ratio_at_long_tau,
            kept(c.extended.as_ref().unwrap()),
            kept(d.extended.as_ref().unwrap())
        );
        assert!((c.white_std / d.white_std - 1.0).abs() < 0.1, "{}", c.channel);
        for e in [c.extended.as_ref().unwrap(), d.extended.as_ref().unwrap()] {
            assert!(kept(e).iter().all(|t| !t.starts_with("sinusoid")), "{}: {:?}", c.channel, e.gate);
        }
        if ["gx", "gy", "ax", "ay"].contains(&c.channel) {
            assert!(c.ratio_at_long_tau > 2.0 && d.ratio_at_long_tau > 2.0, "{}", c.channel);
            let q = c.ratio_at_long_tau / d.ratio_at_long_tau;
            assert!((1.0 / 1.5..1.5).contains(&q), "{}: {q}", c.channel);
        }
    }
    for (x, y) in s.sway.iter().zip(&b.sway) {
        assert!((x.correlation - y.correlation).abs() < 0.1, "{x:?} {y:?}");
    }
    assert!(s.causes.iter().any(|c| c.name.starts_with("vehicle sway")), "{:?}", s.causes);
}
