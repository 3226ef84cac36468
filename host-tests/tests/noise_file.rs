//! `sinscal noise` (docs/cli.md#noise): each channel's noise terms with standard errors, from a static
//! recording. SIMULATION with known white noise (the built-in example's: 0.1 deg/h and 1000 ug per sample at
//! 100 Hz, one 600-s pose): the white-noise coefficient N of every channel within 3 of its standard errors of the
//! truth. REAL DATA (`SINSCAL_DATA`, skipped and says so without it): the PSINS ring-laser record names terms
//! beyond white noise on every channel.

mod common;

use assert_cmd::Command;
use serde_json::Value;
use sinscal_host::model::synth::Scenario;

fn noise_file(recording: &std::path::Path) -> Value {
    let out = recording.with_extension("noise.json");
    Command::cargo_bin("sinscal").unwrap().arg("noise").arg(recording).arg("--out").arg(&out).assert().success();
    serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
}

#[test]
fn white_noise_of_a_simulated_static_pose_is_named_with_its_coefficient() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("static.csv");
    let scenario = Scenario { dwell_s: 600.0, positions_deg: vec![[0.0, 0.0, 0.0]], ..Scenario::example() };
    scenario.recording(5, "static.csv").write(&path).unwrap();
    let v = noise_file(&path);
    assert_eq!(v["schema"], "sinscal-noise/1");
    assert_eq!((v["samples"].as_u64(), v["rate_hz"].as_f64()), (Some(60_000), Some(100.0)));
    let channels = v["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 6);
    // N = per-sample standard deviation x sqrt(sample period).
    let truth = [4.848_137e-7, 9.806_65e-3].map(|sigma| sigma * 0.1);
    for (i, c) in channels.iter().enumerate() {
        let white = c["terms"].as_array().unwrap().iter().find(|t| t["term"] == "white");
        let white = white.unwrap_or_else(|| panic!("{}: white noise not named: {}", c["channel"], c["named"]));
        let (n, se) = (white["value_si"].as_f64().unwrap(), white["std_error_si"].as_f64().unwrap());
        let want = truth[i / 3];
        println!("{}: N {n:e} +- {se:e}, truth {want:e}", c["channel"]);
        assert!((n - want).abs() < 3.0 * se && se < 0.2 * want, "{}: {n:e} +- {se:e} vs {want:e}", c["channel"]);
    }
}

#[test]
fn the_psins_record_names_more_than_white_noise() {
    let Some(dir) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("psins.csv");
    let rec = sinscal_host::io::import::import_psins(&common::data_file(&dir, "psins-lasergyro/lasergyro.imu"), None)
        .unwrap()
        .recording;
    rec.write(&path).unwrap();
    let v = noise_file(&path);
    for c in v["channels"].as_array().unwrap() {
        println!("{}", c["named"]);
        assert_eq!(c["better_than_white_only"], true, "{}", c["channel"]);
        assert!(c["terms"].as_array().unwrap().iter().all(|t| t["std_error_si"].as_f64().unwrap() > 0.0));
    }
}
