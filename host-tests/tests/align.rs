//! `sinscal align` (docs/cli.md#align): exact synthetic dwells at known attitudes, including the check values of
//! docs/conventions.md#attitude, are recovered through the core's f32 coarse alignment; accelerometer-only data give
//! pitch and roll; the standard errors agree with the scatter of 200 noisy realisations.

use std::path::Path;

mod common;

use assert_cmd::Command;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde_json::Value;
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec, mul_vec};
use sinscal_host::navigation::alignment::align;

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

const LATITUDE_DEG: f64 = 45.7796;
const G: f64 = 9.8063;

/// A dwell: (pitch, roll, heading) of the truth, and the heading written as reference (None = unknown).
struct Pose {
    attitude: [f64; 3],
    reference_heading: Option<f64>,
}

fn known(pitch: f64, roll: f64, heading: f64) -> Pose {
    Pose { attitude: [pitch, roll, heading], reference_heading: Some(heading) }
}

/// The recording of `poses` at rest, `n` rows each, with white noise of `noise = (gyro rad/s, accel m/s^2)` per
/// sample from `rng` (exact when zero). `pos = 0` rows between dwells.
fn recording(poses: &[Pose], n: usize, has_gyro: bool, noise: (f64, f64), rng: &mut ChaCha8Rng) -> Recording {
    let w_ie = earth_rate_n_radps(LATITUDE_DEG.to_radians());
    let mut rows = Vec::new();
    let mut t = 0.0;
    for (k, p) in poses.iter().enumerate() {
        let [pitch, roll, heading] = p.attitude;
        let c = c_b_n(pitch, roll, heading);
        let f = mul_t_vec(&c, [0.0, 0.0, G]);
        let w = mul_t_vec(&c, w_ie);
        for i in 0..n + 3 {
            let mut e = || -> f64 { StandardNormal.sample(rng) };
            let noisy_w = w.map(|x| x + noise.0 * e());
            let noisy_f = f.map(|x| x + noise.1 * e());
            rows.push(Row {
                t_s: t,
                pos: if i < 3 { 0 } else { k as u32 + 1 },
                pitch_deg: pitch,
                roll_deg: roll,
                heading_deg: p.reference_heading,
                rate_b_radps: if has_gyro { noisy_w } else { [0.0; 3] },
                force_b_mps2: noisy_f,
                temp_c: None,
                turn_axis: None,
                line: 0,
            });
            t += 0.01;
        }
    }
    let header = Header {
        latitude_deg: LATITUDE_DEG,
        height_m: 0.0,
        rate_hz: Some(100.0),
        gravity_mps2: Some(G),
        comments: vec![],
        truth: None,
        pose_tolerance_deg: None,
    };
    Recording { source: "synthetic.csv".to_string(), header, rows, has_gyro }
}

/// The poses of the exact test: the check values of docs/conventions.md#attitude, body x up (roll -90), z down,
/// negative pitch with heading 200, headings either side of north, a reference pitch beyond 90, an unknown heading.
fn exact_poses() -> Vec<Pose> {
    vec![
        known(0.0, 0.0, 90.0),
        known(0.0, 90.0, 0.0),
        known(0.0, -90.0, 0.0),
        known(-30.0, 15.0, 200.0),
        known(20.0, -40.0, 330.0),
        known(0.0, 180.0, 30.0),
        known(3.0, -2.0, 359.5),
        known(-12.0, 100.0, 0.25),
        known(120.0, 10.0, 45.0),
        Pose { attitude: [5.0, 7.0, 75.0], reference_heading: None },
    ]
}

#[test]
fn the_check_values_hold_for_the_synthetic_truth() {
    // The truth of these tests follows docs/conventions.md#attitude (checked here, independently of the core).
    let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|i| (a[i] - b[i]).abs() < 1e-15);
    assert!(close(mul_vec(&c_b_n(0.0, 0.0, 90.0), [0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]), "(0,0,90): body y east");
    assert!(close(mul_vec(&c_b_n(0.0, 90.0, 0.0), [1.0, 0.0, 0.0]), [0.0, 0.0, -1.0]), "(0,90,0): body x down");
    assert!(close(mul_vec(&c_b_n(0.0, -90.0, 0.0), [1.0, 0.0, 0.0]), [0.0, 0.0, 1.0]), "(0,-90,0): body x up");
}

fn number(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn exact_attitudes_are_recovered_through_the_f32_core() {
    let dir = tempfile::tempdir().unwrap();
    let poses = exact_poses();
    let rec = recording(&poses, 20, true, (0.0, 0.0), &mut ChaCha8Rng::seed_from_u64(0));
    let path = dir.path().join("exact.csv");
    rec.write(&path).unwrap();
    let out = sinscal().arg("align").arg(&path).args(["--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["schema"], "sinscal-alignment/1");
    assert_eq!((v["gyro"].as_bool(), v["gravity_source"].as_str()), (Some(true), Some("header")));
    let positions = v["positions"].as_array().unwrap();
    assert_eq!(positions.len(), poses.len());
    let mut worst = 0.0f64;
    for (p, pose) in positions.iter().zip(&poses) {
        let [pitch, roll, heading] = pose.attitude;
        let got = [number(&p["pitch_deg"]), number(&p["roll_deg"]), number(&p["heading_deg"])];
        for (g, want) in got.iter().zip([pitch, roll, heading]) {
            // Reported in the range of the reference (270 stays 270, 359.5 stays 359.5, pitch 120 stays 120).
            assert!((g - want).abs() < 1e-4, "pose {:?}: got {got:?}", pose.attitude);
            worst = worst.max((g - want).abs());
        }
        // Exact data: the dwell's scatter is zero, so are the standard errors.
        for key in ["pitch_std_deg", "roll_std_deg", "heading_std_deg"] {
            assert!(number(&p[key]) < 1e-9, "{key}: {p}");
        }
        assert!(number(&p["pitch_difference_deg"]).abs() < 1e-4);
        assert!(number(&p["roll_difference_deg"]).abs() < 1e-4);
        match pose.reference_heading {
            Some(_) => assert!(number(&p["heading_difference_deg"]).abs() < 1e-4, "{p}"),
            None => {
                assert!(p["heading_difference_deg"].is_null() && p["reference_heading_deg"].is_null(), "{p}");
            }
        }
        assert!(p["note"].is_null());
        assert_eq!(p["samples"], 20);
    }
    println!("exact attitudes: largest error {worst:e} deg");

    // The human summary: a table with units in its header.
    let out = sinscal().arg("align").arg(&path).assert().success();
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("pitch [deg]") && stdout.contains("heading [deg]") && stdout.contains("diff h [\"]"));
    assert!(stdout.contains("(10 dwells, latitude 45.7796 deg"), "{stdout}");
    assert!(stdout.contains("white noise"), "{stdout}");
}

#[test]
fn accelerometer_only_data_give_pitch_and_roll_and_no_heading() {
    let dir = tempfile::tempdir().unwrap();
    let poses = exact_poses();
    let rec = recording(&poses, 20, false, (0.0, 0.0), &mut ChaCha8Rng::seed_from_u64(0));
    let path = dir.path().join("accel.csv");
    rec.write(&path).unwrap();
    let json = dir.path().join("align.json");
    let out = sinscal().arg("align").arg(&path).arg("--json").arg(&json).assert().success();
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("accelerometer-only: pitch and roll from gravity, no heading"), "{stdout}");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["gyro"], false);
    for (p, pose) in v["positions"].as_array().unwrap().iter().zip(&poses) {
        let [pitch, roll, _] = pose.attitude;
        // f64 from the mean specific force.
        assert!((number(&p["pitch_deg"]) - pitch).abs() < 1e-9, "{p}");
        assert!((number(&p["roll_deg"]) - roll).abs() < 1e-9, "{p}");
        for key in ["heading_deg", "heading_std_deg", "heading_difference_deg"] {
            assert!(p[key].is_null(), "{key}: {p}");
        }
    }
}

#[test]
fn pitch_at_90_leaves_roll_and_heading_null() {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    for has_gyro in [true, false] {
        let poses = [known(90.0, 0.0, 0.0), known(-90.0, 30.0, 50.0), known(0.0, 0.0, 0.0)];
        let r = align(&recording(&poses, 20, has_gyro, (0.0, 0.0), &mut rng)).unwrap();
        for (p, want) in r.positions.iter().zip([90.0, -90.0]) {
            assert!((p.pitch_deg - want).abs() < 1e-4, "{p:?}");
            assert!(p.roll_deg.is_none() && p.heading_deg.is_none() && p.roll_difference_deg.is_none(), "{p:?}");
            assert!(p.note.as_deref().unwrap().contains("gimbal lock"), "{p:?}");
        }
        assert!(r.positions[2].roll_deg.is_some() && r.positions[2].note.is_none());
    }
}

/// Sample standard deviation.
fn std(x: &[f64]) -> f64 {
    let m = x.iter().sum::<f64>() / x.len() as f64;
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

#[test]
fn standard_errors_match_the_scatter_of_200_noisy_realisations() {
    // Noise per sample: gyro 1e-7 rad/s (about 0.02 deg/h), accelerometer 0.02 m/s^2; 200 rows per dwell. The
    // heading's error then has a gyro part (1.4e-4 rad) and a level part through tan L (1.5e-4 rad) of the same
    // size: without the coupling term the scatter would be 1.45 times the reported error, outside the band.
    let poses = [known(0.0, 0.0, 0.0), known(-30.0, 15.0, 200.0), known(20.0, -40.0, 330.0), known(0.0, 90.0, 90.0)];
    let runs = 200;
    for has_gyro in [true, false] {
        let mut rng = ChaCha8Rng::seed_from_u64(if has_gyro { 11 } else { 12 });
        // [pose][angle] -> (values, reported standard errors)
        let mut values = vec![[vec![], vec![], vec![]]; poses.len()];
        let mut reported = vec![[vec![], vec![], vec![]]; poses.len()];
        for _ in 0..runs {
            let r = align(&recording(&poses, 200, has_gyro, (1e-7, 0.02), &mut rng)).unwrap();
            for (k, p) in r.positions.iter().enumerate() {
                let angles = [Some(p.pitch_deg), p.roll_deg, p.heading_deg];
                let stds = [Some(p.pitch_std_deg), p.roll_std_deg, p.heading_std_deg];
                for i in 0..3 {
                    if let (Some(a), Some(s)) = (angles[i], stds[i]) {
                        values[k][i].push(a);
                        reported[k][i].push(s);
                    }
                }
            }
        }
        for (k, pose) in poses.iter().enumerate() {
            for (i, name) in ["pitch", "roll", "heading"].iter().enumerate() {
                if !has_gyro && i == 2 {
                    assert!(values[k][i].is_empty());
                    continue;
                }
                assert_eq!(values[k][i].len(), runs);
                let ratio = std(&values[k][i]) / rms(&reported[k][i]);
                println!(
                    "gyro {has_gyro}, pose {:?}, {name}: scatter {:.3e} deg, reported {:.3e} deg, ratio {ratio:.3}",
                    pose.attitude,
                    std(&values[k][i]),
                    rms(&reported[k][i])
                );
                assert!((0.8..=1.25).contains(&ratio), "{name} at {:?}: ratio {ratio}", pose.attitude);
            }
        }
    }
}

#[test]
fn short_dwells_and_bad_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording(
        &[known(0.0, 0.0, 0.0), known(0.0, 0.0, 90.0)],
        20,
        true,
        (0.0, 0.0),
        &mut ChaCha8Rng::seed_from_u64(0),
    );
    let text = rec.to_csv();
    // Keep 5 rows of dwell 2.
    let mut kept = 0;
    let short: Vec<&str> = text
        .lines()
        .filter(|l| {
            if l.split(',').nth(1) != Some("2") {
                return true;
            }
            kept += 1;
            kept <= 5
        })
        .collect();
    let path = dir.path().join("short.csv");
    std::fs::write(&path, short.join("\n") + "\n").unwrap();
    let e = stderr_of_failure(&path);
    assert!(e.contains("short.csv:") && e.contains("dwell 2: 5 rows, align needs at least 10"), "{e}");
    // Bad recordings are refused by the reader with the line and the reason.
    let path = dir.path().join("dup.csv");
    std::fs::write(&path, text.replace("ax_mps2,ay_mps2", "ax_mps2,ax_mps2")).unwrap();
    assert!(stderr_of_failure(&path).contains("column 'ax_mps2' appears twice"));
}

fn stderr_of_failure(path: &Path) -> String {
    let o = sinscal().arg("align").arg(path).assert().code(1);
    let e = String::from_utf8(o.get_output().stderr.clone()).unwrap();
    assert_eq!(e.lines().count(), 1, "{e}");
    e
}

#[test]
fn real_imutk_poses_levelled_by_the_importer_agree_with_align() {
    // The imu_tk importer gives each detected pose the pitch and roll of its mean specific force
    // (docs/data.md#imu-tk-xsens); align computes them through the core's alignment: the two must agree.
    let Some(dir) = common::data_dir() else { return };
    let acc = common::data_file(&dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = common::data_file(&dir, "imu-tk-xsens/xsens_gyro.mat");
    let detection = sinscal_host::io::import::StaticDetection::default();
    let rec = sinscal_host::io::import::import_imutk(&acc, &gyro, None, &detection).unwrap().recording;
    let r = align(&rec).unwrap();
    let mut worst = 0.0f64;
    for p in &r.positions {
        assert!(p.heading_difference_deg.is_none(), "the headings of imu_tk poses are unknown");
        if let Some(roll) = p.roll_difference_deg {
            worst = worst.max(p.pitch_difference_deg.abs()).max(roll.abs());
        }
    }
    println!("imutk: {} poses, largest level difference {worst:e} deg", r.positions.len());
    assert!(r.positions.len() >= 35 && worst < 1e-3, "{worst}");
}
