//! The `sinscal` command line: exit statuses, messages and the JSON contract (docs/cli.md, docs/formats.md#calibration-json).

use assert_cmd::Command;
use serde_json::Value;
use sinscal_host::model::synth::Scenario;

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

/// The stderr of `sinscal calibrate PATH EXTRA...`, which must exit with status 1.
fn calibrate_fails(path: &std::path::Path, extra: &[&str]) -> String {
    let out = sinscal().arg("calibrate").arg(path).args(extra).assert().code(1);
    String::from_utf8(out.get_output().stderr.clone()).unwrap()
}

fn example_file(dir: &tempfile::TempDir, seconds: f64) -> std::path::PathBuf {
    let path = dir.path().join("example.csv");
    let scenario = Scenario { dwell_s: seconds, ..Scenario::example() };
    scenario.recording(3, "example.csv").write(&path).unwrap();
    path
}

#[test]
fn calibrate_writes_the_spec_json_and_numbers_read_back_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example_file(&dir, 20.0);
    let json_path = dir.path().join("cal.json");
    let out = sinscal().arg("calibrate").arg(&rec).arg("--json").arg(&json_path).assert().success();
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("Gyro bias, body frame [deg/h]"), "{stdout}");
    assert!(stdout.contains("[ug]"));
    assert!(stdout.contains("method: channels"), "{stdout}");

    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    assert_eq!(v["schema"], "sinscal-calibration/2");
    assert_eq!(v["method"], "channels");
    assert_eq!(v["model"], serde_json::json!(["gyro_bias", "accel_bias", "accel_scale_factor"]));
    // Terms not in the model are null; the covariance is square over the determined parameters. Table 1
    // never turns y off the horizontal: its scale factor is unobservable, its value and std null.
    assert!(v["accel_misalignment"].is_null() && v["reference_offset_rad"].is_null());
    assert!(v["accel_scale_factor"][1].is_null() && v["accel_scale_factor"][2].as_f64().is_some());
    let parameters = v["parameters"].as_array().unwrap();
    assert_eq!(parameters.len(), 8);
    let covariance = v["covariance"].as_array().unwrap();
    assert_eq!(covariance.len(), 8);
    assert!(covariance.iter().all(|row| row.as_array().unwrap().len() == 8));
    let sd = v["gyro_bias_std_radps"][0].as_f64().unwrap();
    assert_eq!(covariance[0][0].as_f64().unwrap().sqrt() as f32, sd as f32);
    assert_eq!(v["positions"][0]["heading_known"], true);
    assert!(v["positions"][0]["residual_accel_mps2"].as_array().is_some());
    assert_eq!(v["latitude_deg"], 45.7796);
    assert_eq!(v["positions"].as_array().unwrap().len(), 6);
    // What the errors rest on, and what was checked (docs/formats.md#calibration-json-version-2).
    assert_eq!(v["noise"]["source"], "recording");
    let noise = v["noise"]["channels"].as_array().unwrap();
    assert_eq!(noise.len(), 6);
    assert!(noise.iter().all(|c| c["white_equivalent_var_si"].as_f64().unwrap() > 0.0 && c["model"] == "allan"));
    assert_eq!(v["fit_scale"].as_array().unwrap().len(), 6);
    assert_eq!(v["spikes_rejected"], serde_json::json!([0, 0, 0, 0, 0, 0]));
    assert_eq!(v["pose_tolerance_deg"], 0.0);
    let checks = v["checks"].as_array().unwrap();
    assert!(checks.len() == 5 && checks.iter().all(|c| c["passed"] == true), "{checks:?}");
    let p = &v["positions"][4];
    assert_eq!((p["pos"].as_u64(), p["roll_deg"].as_f64(), p["samples"].as_u64()), (Some(5), Some(90.0), Some(2000)));
    for key in ["gyro_bias_radps", "gyro_bias_std_radps", "accel_bias_mps2", "accel_bias_std_mps2"] {
        let arr = v[key].as_array().unwrap();
        assert_eq!(arr.len(), 3);
        for x in arr {
            let x = x.as_f64().unwrap();
            assert!(x.is_finite());
            // Written from f32: the decimal reads back to an f64 that is exactly an f32.
            assert_eq!(x as f32 as f64, x, "{key}: {x}");
        }
    }
    assert_eq!(v["unobservable"], serde_json::json!(["accel_scale_factor_y"]));

    // The same run as a library call gives the same bits.
    let recording = sinscal_host::io::recording::Recording::read(&rec).unwrap();
    let cal = sinscal_host::calibration::calibrate(&recording, &Default::default()).unwrap();
    let eps_x = cal.estimates.value_si[0].unwrap();
    assert_eq!(v["gyro_bias_radps"][0].as_f64().unwrap(), eps_x);

    // --json - writes only the JSON to stdout.
    let out = sinscal().arg("calibrate").arg(&rec).args(["--json", "-", "--prefilter", "none"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["prefilter"]["kind"], "none");
}

#[test]
fn schedule_blind_spots_are_listed_as_unobservable_with_null_values() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.csv");
    let scenario =
        Scenario { dwell_s: 5.0, positions_deg: vec![[0.0, 0.0, 0.0], [0.0, 0.0, 180.0]], ..Scenario::example() };
    scenario.recording(1, "two.csv").write(&path).unwrap();
    let names = |v: &Value| -> Vec<String> {
        v["unobservable"].as_array().unwrap().iter().map(|x| x.as_str().unwrap().to_string()).collect()
    };
    // The angle method sees only the east gyro and the horizontal accelerometers of each pose.
    let out = sinscal().arg("calibrate").arg(&path).args(["--method", "angles", "--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(names(&v), ["gyro_bias_y", "gyro_bias_z", "accel_bias_z"]);
    assert!(v["gyro_bias_radps"][1].is_null() && v["gyro_bias_std_radps"][2].is_null());
    assert!(v["gyro_bias_radps"][0].as_f64().is_some());
    // Every channel against a known reference sees every bias in one pose; scale factors need the axis
    // seen at two different values, which two level poses give only for the horizontal axes.
    let out = sinscal()
        .arg("calibrate")
        .arg(&path)
        .args(["--model", "biases,accel_scale_factor", "--json", "-"])
        .assert()
        .success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(names(&v), ["accel_bias_z", "accel_scale_factor_x", "accel_scale_factor_y", "accel_scale_factor_z"]);
    assert!(v["accel_scale_factor"][2].is_null() && v["gyro_bias_radps"][2].as_f64().is_some());
}

/// The text with cell `col` of the first row of dwell `pos` replaced.
fn with_cell(text: &str, pos: u32, col: usize, value: &str) -> String {
    let mut done = false;
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            if !done && !l.starts_with('#') && cells.get(1) == Some(&pos.to_string().as_str()) {
                done = true;
                cells[col] = value;
            }
            cells.join(",")
        })
        .collect();
    assert!(done);
    lines.join("\n") + "\n"
}

#[test]
fn bad_input_exits_1_with_file_line_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example_file(&dir, 1.0);
    let text = std::fs::read_to_string(&rec).unwrap();
    let cases = [
        ("time.csv", text.replace("\n0.01,", "\n0,"), "does not increase"),
        ("column.csv", text.replace(",gz_radps,", ",gz,"), "missing column 'gz_radps'"),
        ("number.csv", text.replacen(",1,0,0,0,", ",1,0,0,x,", 1), "column 'heading_deg': 'x' is not a finite number"),
        ("nan.csv", with_cell(&text, 1, 5, "NaN"), "column 'gx_radps': 'NaN' is not a finite number"),
        ("inf.csv", with_cell(&text, 2, 10, "inf"), "column 'az_mps2': 'inf' is not a finite number"),
    ];
    for (name, body, want) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, body).unwrap();
        let out = sinscal().arg("calibrate").arg(&path).assert().code(1);
        let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
        assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
        assert!(stderr.contains(name) && stderr.contains(want), "{stderr}");
        let line: usize = stderr.split(':').nth(2).unwrap().trim().parse().expect("a line number");
        assert!(line > 5, "{stderr}");
    }

    // A dwell too short to use: keep 5 rows of position 6.
    let short = dir.path().join("short.csv");
    let mut kept_of_6 = 0;
    let body: Vec<&str> = text
        .lines()
        .filter(|l| {
            if l.split(',').nth(1) != Some("6") {
                return true;
            }
            kept_of_6 += 1;
            kept_of_6 <= 5
        })
        .collect();
    std::fs::write(&short, body.join("\n") + "\n").unwrap();
    let stderr = calibrate_fails(&short, &[]);
    assert!(stderr.contains("dwell 6") && stderr.contains("too short"), "{stderr}");

    // Missing file.
    let stderr = String::from_utf8(
        sinscal().args(["calibrate", "/nonexistent/x.csv"]).assert().code(1).get_output().stderr.clone(),
    )
    .unwrap();
    assert!(stderr.contains("/nonexistent/x.csv"), "{stderr}");

    // Unknown heading: the angle method needs it, and says so; the general estimator estimates it.
    let unknown = dir.path().join("unknown.csv");
    std::fs::write(&unknown, text.replace(",2,0,0,180,", ",2,0,0,,")).unwrap();
    let stderr = calibrate_fails(&unknown, &["--method", "angles"]);
    assert!(stderr.contains("dwell 2: heading is unknown"), "{stderr}");
    let out = sinscal().arg("calibrate").arg(&unknown).args(["--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["positions"][1]["heading_known"], false);
    let heading = v["positions"][1]["heading_deg"].as_f64().unwrap();
    let heading_std = v["positions"][1]["heading_std_deg"].as_f64().unwrap();
    assert!((heading - 180.0).abs() < 4.0 * heading_std + 0.5, "estimated heading {heading} ± {heading_std}");

    // A pose placed 0.05 deg off its label (pitch 0.05 written as 0): suspect, and the result without it given.
    let tilted = dir.path().join("tilted.csv");
    std::fs::write(&tilted, text.replace(",3,0,0,90,", ",3,0.05,0,90,")).unwrap();
    // With the labels taken as exact the fit fails its check (exit 3), the result written all the same.
    let out = sinscal().arg("calibrate").arg(&tilted).args(["--json", "-"]).assert().code(3);
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("check failed: fit"), "{stderr}");
    // The fit check tries the labels known to a degree, which fit: it names the cause.
    assert!(stderr.contains("poses off their labels? with --pose-tolerance 1 the fit passes"), "{stderr}");
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    let suspect: Vec<bool> =
        v["positions"].as_array().unwrap().iter().map(|p| p["suspect"].as_bool().unwrap()).collect();
    // The tilt leaks into the fit through the shared terms (Table 1 leaves few residual degrees of freedom), so
    // other poses may be flagged too and the largest statistic need not be the tilted pose's; it is flagged.
    assert!(suspect[2], "{suspect:?}");
    // Left out one at a time, worst first: the tilted pose goes first.
    assert_eq!(v["without_suspect"]["positions"][0], 3);
    let stdout =
        String::from_utf8(sinscal().arg("calibrate").arg(&tilted).assert().code(3).get_output().stdout.clone())
            .unwrap();
    assert!(stdout.contains("SUSPECT") && stdout.contains("Without position(s) 3 "), "{stdout}");
    // The labels known to 0.1 deg: the tilt is a nuisance, the fit passes its check.
    sinscal().arg("calibrate").arg(&tilted).args(["--pose-tolerance", "0.1"]).assert().success();

    // Accelerometer-only data: the accelerometer terms alone.
    let acc_only = dir.path().join("acc.csv");
    let acc_text: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                return l.to_string();
            }
            let cells: Vec<&str> = l.split(',').collect();
            [&cells[..5], &cells[8..]].concat().join(",")
        })
        .collect();
    std::fs::write(&acc_only, acc_text.join("\n") + "\n").unwrap();
    let out = sinscal().arg("calibrate").arg(&acc_only).args(["--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["model"], serde_json::json!(["accel_bias", "accel_scale_factor"]));
    assert!(v["gyro_bias_radps"][0].is_null() && v["accel_bias_mps2"][0].as_f64().is_some());
    assert!(v["positions"][0]["residual_gyro_radps"].is_null());
    let stderr = calibrate_fails(&acc_only, &["--method", "angles"]);
    assert!(stderr.contains("no gyro columns"), "{stderr}");

    // A reference that does not match the data (axes or attitude wrong).
    let wrong = dir.path().join("wrong.csv");
    // Position 3 reported with roll 90 (body x down) while the data have z up: an axis mismatch.
    std::fs::write(&wrong, text.replace(",3,0,0,90,", ",3,0,90,90,")).unwrap();
    let stderr = calibrate_fails(&wrong, &[]);
    assert!(stderr.contains("dwell 3") && stderr.contains("from where the reference attitude puts it"), "{stderr}");
    let stderr = calibrate_fails(&wrong, &["--method", "angles"]);
    assert!(stderr.contains("dwell 3") && stderr.contains("differs from the reference attitude"), "{stderr}");
}

#[test]
fn usage_errors_exit_2() {
    sinscal().assert().code(2);
    sinscal().args(["calibrate"]).assert().code(2);
    sinscal().args(["calibrate", "x.csv", "--prefilter", "bogus"]).assert().code(2);
    sinscal().args(["calibrate", "x.csv", "--estimate-attitudes", "--on", "host"]).assert().code(2);
    sinscal().args(["calibrate", "x.csv", "--estimate-attitudes", "--method", "angles"]).assert().code(2);
}

#[test]
fn demo_runs_the_built_in_example() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ex.csv");
    let json = dir.path().join("ex.json");
    let o = sinscal().arg("demo").arg("--out").arg(&out).arg("--json").arg(&json).assert().success();
    let stdout = String::from_utf8(o.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("SIMULATION"), "{stdout}");
    assert!(stdout.contains("Truth of the simulation"));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    // The example's biases: gyro x +0.05 deg/h, accel y -80 ug; the estimates land within 4 sigma.
    let (eps, sd) = (v["gyro_bias_radps"][0].as_f64().unwrap(), v["gyro_bias_std_radps"][0].as_f64().unwrap());
    assert!((eps - 0.05 * sinscal_host::model::synth::DEG_PER_HOUR).abs() < 4.0 * sd);
    let (nab, sd) = (v["accel_bias_mps2"][1].as_f64().unwrap(), v["accel_bias_std_mps2"][1].as_f64().unwrap());
    assert!((nab + 80.0 * sinscal_host::model::synth::MICRO_G).abs() < 4.0 * sd);
}

#[test]
fn navigate_runs_both_ways_and_writes_json_and_a_figure() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example_file(&dir, 30.0);
    let cal = dir.path().join("cal.json");
    sinscal().arg("calibrate").arg(&rec).arg("--json").arg(&cal).assert().success();
    let nav_json = dir.path().join("nav.json");
    let png = dir.path().join("nav.png");
    let out = sinscal()
        .arg("navigate")
        .arg(&rec)
        .arg("--calibration")
        .arg(&cal)
        .args(["--hours", "0.1", "--json"])
        .arg(&nav_json)
        .arg("--plot")
        .arg(&png)
        .assert()
        .success();
    let stdout = String::from_utf8(out.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("SIMULATED static run"), "{stdout}");
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("navigate: 100%"), "progress: {stderr}");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&nav_json).unwrap()).unwrap();
    assert_eq!(v["schema"], "sinscal-navigation/1");
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 3);
    assert_eq!(runs[0]["name"], "uncompensated");
    assert!(runs[0]["max_horizontal_position_error_m"].as_f64().unwrap() > 0.0);
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[1..4], b"PNG");

    // Without --hours: the recording's own longest dwell (30 s here), as for measured data.
    let out =
        sinscal().arg("navigate").arg(&rec).arg("--calibration").arg(&cal).args(["--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["simulated"], false);
    assert!((v["hours"].as_f64().unwrap() * 3600.0 - 30.0).abs() < 0.02);

    // Bad input: a calibration file that is not one, --hours on data without a simulated truth.
    let not_cal = dir.path().join("x.json");
    std::fs::write(&not_cal, "{\"schema\": \"other\"}").unwrap();
    let e = sinscal().arg("navigate").arg(&rec).arg("--calibration").arg(&not_cal).assert().code(1);
    assert!(String::from_utf8_lossy(&e.get_output().stderr).contains("not a calibration result"));
    let measured = dir.path().join("measured.csv");
    let text: String = std::fs::read_to_string(&rec)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("# truth_"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&measured, text).unwrap();
    let e =
        sinscal().arg("navigate").arg(&measured).arg("--calibration").arg(&cal).args(["--hours", "1"]).assert().code(1);
    assert!(String::from_utf8_lossy(&e.get_output().stderr).contains("no truth_* header"));
}

#[test]
fn accelerometer_only_recordings_are_analysed_and_refused_where_gyros_are_needed() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example_file(&dir, 1.0);
    let mut recording = sinscal_host::io::recording::Recording::read(&rec).unwrap();
    recording.has_gyro = false;
    let accel = dir.path().join("accel.csv");
    recording.write(&accel).unwrap();
    let cal = dir.path().join("cal.json");
    std::fs::write(
        &cal,
        r#"{"schema": "sinscal-calibration/1", "gyro_bias_radps": [0, 0, 0], "gyro_bias_std_radps": [0, 0, 0],
            "accel_bias_mps2": [0, 0, 0], "accel_bias_std_mps2": [0, 0, 0]}"#,
    )
    .unwrap();
    let out = sinscal().arg("navigate").arg(&accel).arg("--calibration").arg(&cal).assert().code(1);
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    let line = stderr.lines().find(|l| l.starts_with("sinscal:")).unwrap_or_default();
    assert_eq!(line, format!("sinscal: {}: no gyro columns: navigate needs gyros", accel.display()), "{stderr}");
    // analyze reads the accelerometers alone: the gyros are absent (no diagnostics, no noise model, no
    // effect, their terms named "no gyro columns"), not zeros measured.
    let json = dir.path().join("accel.json");
    sinscal().arg("analyze").arg(&accel).arg("--json").arg(&json).assert().success();
    let a: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let channels = |key: &str| -> Vec<String> {
        a[key].as_array().unwrap().iter().map(|d| d["channel"].as_str().unwrap().to_string()).collect()
    };
    assert_eq!(channels("diagnostics"), ["ax_mps2", "ay_mps2", "az_mps2"]);
    assert_eq!(channels("noise_model"), ["ax_mps2", "ay_mps2", "az_mps2"]);
    assert!(a["effects"].as_array().unwrap().iter().all(|e| e["sensor"] != "gyro"), "{}", a["effects"]);
    let unobservable = a["unobservable"].to_string();
    assert!(unobservable.contains("gyro_scale_factor: no gyro columns"), "{unobservable}");
}

#[test]
fn navigate_reads_the_biases_of_a_version_2_calibration() {
    let dir = tempfile::tempdir().unwrap();
    let rec = example_file(&dir, 2.0);
    let v2 = dir.path().join("cal2.json");
    std::fs::write(
        &v2,
        r#"{"schema": "sinscal-calibration/2", "method": "channels", "model": ["gyro_bias", "accel_bias"],
            "gyro_bias_radps": [2.4e-7, -1.4e-7, null], "gyro_bias_std_radps": [1e-8, 1e-8, null],
            "accel_bias_mps2": [1e-3, -8e-4, 5e-4], "accel_bias_std_mps2": [1e-5, 1e-5, 1e-5],
            "accel_scale_factor": null, "unobservable": ["gyro_bias_z"]}"#,
    )
    .unwrap();
    let out =
        sinscal().arg("navigate").arg(&rec).arg("--calibration").arg(&v2).args(["--json", "-"]).assert().success();
    let v: Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
    assert_eq!(v["calibrations"][0], "cal2.json");
    assert_eq!(v["runs"].as_array().unwrap().len(), 3);
}
