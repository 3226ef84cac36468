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

/// A SIMULATION of one level 600-s pose with the example's white noise, written to `dir/static.csv`.
fn static_pose(dir: &std::path::Path, seed: u64) -> std::path::PathBuf {
    let path = dir.join("static.csv");
    let scenario = Scenario { dwell_s: 600.0, positions_deg: vec![[0.0, 0.0, 0.0]], ..Scenario::example() };
    scenario.recording(seed, "static.csv").write(&path).unwrap();
    path
}

#[test]
fn white_noise_of_a_simulated_static_pose_is_named_with_its_coefficient() {
    let dir = tempfile::tempdir().unwrap();
    let v = noise_file(&static_pose(dir.path(), 5));
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

fn calibrate_json(args: &[&std::ffi::OsStr], json: &std::path::Path) -> Value {
    Command::cargo_bin("sinscal").unwrap().arg("calibrate").args(args).arg("--json").arg(json).assert().success();
    serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
}

/// `calibrate --noise`: SIMULATION. The built-in example (white noise: 0.1 deg/h and 1000 ug per sample at
/// 100 Hz) weighted by the noise file of a simulated 600-s static pose of the same white noise: its standard
/// errors are those of the true noise (a hand-written noise file of the true N) within 10 % (the file's N is
/// an estimate), the JSON names the file as the noise source, and the firmware path (`--on host`, the noise
/// model in the device's configuration) gives the same values and errors.
#[test]
fn calibrate_with_a_noise_file_weights_by_it_on_either_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = static_pose(dir.path(), 7);
    noise_file(&path);
    let noise = path.with_extension("noise.json");
    let truth = dir.path().join("truth.json");
    let channels: Vec<String> = ["gx_radps", "gy_radps", "gz_radps", "ax_mps2", "ay_mps2", "az_mps2"]
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let n = [4.848_137e-7, 9.806_65e-3][i / 3] * 0.1;
            format!(r#"{{"channel": "{c}", "terms": [{{"term": "white", "value_si": {n:e}}}]}}"#)
        })
        .collect();
    std::fs::write(&truth, format!(r#"{{"schema": "sinscal-noise/1", "channels": [{}]}}"#, channels.join(",")))
        .unwrap();
    let example = dir.path().join("example.csv");
    Command::cargo_bin("sinscal").unwrap().arg("example").arg("--out").arg(&example).assert().success();
    let own = calibrate_json(&[example.as_os_str()], &dir.path().join("own.json"));
    let known =
        calibrate_json(&[example.as_os_str(), "--noise".as_ref(), truth.as_os_str()], &dir.path().join("t.json"));
    let args = [example.as_os_str(), "--noise".as_ref(), noise.as_os_str()];
    let filed = calibrate_json(&args, &dir.path().join("file.json"));
    let on_host =
        calibrate_json(&[&args[..], &["--on".as_ref(), "host".as_ref()]].concat(), &dir.path().join("h.json"));
    assert_eq!((own["noise"]["source"].as_str(), filed["noise"]["source"].as_str()), (Some("recording"), Some("file")));
    assert_eq!(on_host["noise"]["source"], "file");
    assert!(filed["noise"]["channels"][0]["terms"]["white_u_sqrt_s"].as_f64().unwrap() > 0.0);
    println!("fit scale: own noise {}, noise file {}", own["fit_scale"], filed["fit_scale"]);
    for key in ["gyro_bias_std_radps", "accel_bias_std_mps2"] {
        for i in 0..3 {
            let at = |v: &Value| v[key][i].as_f64().unwrap();
            let (a, t, b, h) = (at(&own), at(&known), at(&filed), at(&on_host));
            println!("{key}[{i}]: own noise {a:e}, true noise {t:e}, noise file {b:e}, --on host {h:e}");
            assert!((b / t - 1.0).abs() < 0.1, "{key}[{i}]: {b:e} against the truth's {t:e}");
            assert!((h / b - 1.0).abs() < 1e-3, "{key}[{i}]: --on host {h:e} against {b:e}");
        }
    }
    // The values: the firmware path reads the samples as the ADIS's fixed-point words, within a small part of
    // their standard errors of the direct path's.
    for (key, std) in [("gyro_bias_radps", "gyro_bias_std_radps"), ("accel_bias_mps2", "accel_bias_std_mps2")] {
        for i in 0..3 {
            let z =
                (filed[key][i].as_f64().unwrap() - on_host[key][i].as_f64().unwrap()) / filed[std][i].as_f64().unwrap();
            println!("{key}[{i}]: --on host - direct = {z:.4} standard errors");
            assert!(z.abs() < 0.05, "{key}[{i}]: {z}");
        }
    }
}

/// `--noise` refusals: a file that is not a noise file (exit 1, named), and the angle method (exit 2).
#[test]
fn calibrate_refuses_a_file_that_is_not_a_noise_file() {
    let dir = tempfile::tempdir().unwrap();
    let example = dir.path().join("example.csv");
    Command::cargo_bin("sinscal").unwrap().arg("example").arg("--out").arg(&example).assert().success();
    let not_noise = dir.path().join("x.json");
    std::fs::write(&not_noise, r#"{"schema": "sinscal/2"}"#).unwrap();
    let out = Command::cargo_bin("sinscal")
        .unwrap()
        .arg("calibrate")
        .arg(&example)
        .arg("--noise")
        .arg(&not_noise)
        .assert()
        .code(1)
        .get_output()
        .stderr
        .clone();
    let text = String::from_utf8_lossy(&out);
    assert!(text.contains("not a noise file"), "{text}");
    let angles = Command::cargo_bin("sinscal")
        .unwrap()
        .args(["calibrate", "--method", "angles", "--noise"])
        .arg(&not_noise)
        .arg(&example)
        .assert()
        .code(2);
    let text = String::from_utf8_lossy(&angles.get_output().stderr).to_string();
    assert!(text.contains("--noise"), "{text}");
}

/// `calibrate --noise recording`: the model named from the recording's own longest dwell is the one
/// `sinscal noise` writes for it (the same errors as with that file), and the JSON says where it came from;
/// a recording whose dwells are too short to name it is refused with the reason (exit 1).
#[test]
fn calibrate_with_the_recordings_own_noise_model() {
    let dir = tempfile::tempdir().unwrap();
    let example = dir.path().join("example.csv");
    Command::cargo_bin("sinscal").unwrap().arg("example").arg("--out").arg(&example).assert().success();
    noise_file(&example);
    let file = example.with_extension("noise.json");
    let own =
        calibrate_json(&[example.as_os_str(), "--noise".as_ref(), "recording".as_ref()], &dir.path().join("r.json"));
    let filed =
        calibrate_json(&[example.as_os_str(), "--noise".as_ref(), file.as_os_str()], &dir.path().join("f.json"));
    assert_eq!((own["noise"]["source"].as_str(), filed["noise"]["source"].as_str()), (Some("recording"), Some("file")));
    assert_eq!(own["noise"]["channels"][3]["model"], "terms");
    for key in ["gyro_bias_std_radps", "accel_bias_std_mps2", "gyro_bias_radps", "accel_bias_mps2"] {
        assert_eq!(own[key], filed[key], "{key}");
    }
    // Dwells of 3 s: too few Allan octaves above 1 s.
    let short = dir.path().join("short.csv");
    Scenario { dwell_s: 3.0, ..Scenario::example() }.recording(5, "short.csv").write(&short).unwrap();
    let out = Command::cargo_bin("sinscal")
        .unwrap()
        .arg("calibrate")
        .arg(&short)
        .args(["--noise", "recording"])
        .assert()
        .code(1);
    let text = String::from_utf8_lossy(&out.get_output().stderr).to_string();
    assert!(text.contains("too few to name"), "{text}");
}
