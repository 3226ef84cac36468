//! Bad input is refused with a reason, never a panic nor a quiet wrong answer (docs/cli.md#common-rules,
//! docs/formats.md#bad-input): one test per case, each on a file or an argument built here from
//! the built-in example (a SIMULATION), with its exit status and the words of its message.

mod common;

use std::path::{Path, PathBuf};
use std::process::Stdio;

use assert_cmd::Command;
use sinscal_host::model::synth::Scenario;

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

/// The built-in example with 10-s dwells, as text.
fn example_text() -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("example.csv");
    Scenario { dwell_s: 10.0, ..Scenario::example() }.recording(1, "example.csv").write(&path).unwrap();
    std::fs::read_to_string(path).unwrap()
}

/// `text` written as `name` in `dir`.
fn file(dir: &tempfile::TempDir, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// `args` must exit with `code` and a stderr containing every one of `words`; returns the stderr.
fn refused(args: &[&std::ffi::OsStr], code: i32, words: &[&str]) -> String {
    let out = sinscal().args(args).assert().code(code);
    let stderr = String::from_utf8(out.get_output().stderr.clone()).unwrap();
    for w in words {
        assert!(stderr.contains(w), "missing '{w}' in: {stderr}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

/// The example recording and its calibration JSON, in `dir`.
fn calibrated_example(dir: &tempfile::TempDir) -> (PathBuf, PathBuf) {
    let rec = file(dir, "example.csv", example_text());
    let cal = dir.path().join("cal.json");
    sinscal().arg("calibrate").arg(&rec).arg("--json").arg(&cal).assert().success();
    (rec, cal)
}

fn os(s: &str) -> &std::ffi::OsStr {
    std::ffi::OsStr::new(s)
}

/// The data rows of a recording's text (after the column line), and everything before them.
fn split_rows(text: &str) -> (String, Vec<String>) {
    let mut head = String::new();
    let mut rows = Vec::new();
    let mut in_rows = false;
    for line in text.lines() {
        if in_rows {
            rows.push(line.to_string());
        } else {
            head.push_str(line);
            head.push('\n');
            in_rows = line.starts_with("t_s,");
        }
    }
    (head, rows)
}

#[test]
fn a_latitude_at_a_pole_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = example_text();
    let line = text.lines().find(|l| l.starts_with("# latitude_deg:")).unwrap().to_string();
    for lat in ["90", "-90", "89.95"] {
        let path = file(&dir, "pole.csv", text.replace(&line, &format!("# latitude_deg: {lat}")));
        refused(&[os("calibrate"), path.as_os_str()], 1, &["pole.csv:", "latitude_deg", "outside [-89.9, 89.9]"]);
    }
    let near = file(&dir, "near.csv", text.replace(&line, "# latitude_deg: 89.9"));
    // Accepted: the result is written. The example was simulated at 45.8 deg, so its Earth rate contradicts
    // 89.9 deg and the fit honestly misfits (exit 3).
    let run = sinscal().arg("calibrate").arg(&near).assert().code(3);
    let stderr = String::from_utf8_lossy(&run.get_output().stderr).into_owned();
    assert!(stderr.starts_with("sinscal: check failed: fit: ") && stderr.contains("the residuals are "), "{stderr}");
    assert!(String::from_utf8_lossy(&run.get_output().stdout).contains("checks: "));
}

#[test]
fn a_byte_order_mark_is_read_past() {
    // The same name in two folders: the JSON names its source.
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let text = example_text();
    let plain = file(&a, "example.csv", &text);
    let bom = file(&b, "example.csv", format!("\u{feff}{text}"));
    let json = |p: &Path| {
        let out = sinscal()
            .current_dir(p.parent().unwrap())
            .args(["calibrate", "example.csv", "--json", "-"])
            .assert()
            .success();
        String::from_utf8(out.get_output().stdout.clone()).unwrap()
    };
    assert_eq!(json(&plain), json(&bom));
}

#[test]
fn text_that_is_not_utf8_names_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = example_text();
    let mut lines: Vec<Vec<u8>> = text.lines().map(|l| l.as_bytes().to_vec()).collect();
    lines[99].push(0xff);
    let bytes: Vec<u8> = lines.join(&b'\n').into_iter().chain([b'\n']).collect();
    let path = file(&dir, "binary.csv", bytes);
    refused(&[os("calibrate"), path.as_os_str()], 1, &["binary.csv:100:", "not UTF-8"]);
    // In the header too.
    let mut head = text.into_bytes();
    head.insert(3, 0xfe);
    let path = file(&dir, "binhead.csv", head);
    refused(&[os("calibrate"), path.as_os_str()], 1, &["binhead.csv:1:", "not UTF-8"]);
}

#[test]
fn a_last_line_cut_short_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = example_text();
    // Cut inside the last number: "9.80739226" would be read as "9.807".
    let cut = &text[..text.len() - 8];
    let lines = cut.lines().count();
    let path = file(&dir, "cut.csv", cut);
    refused(&[os("calibrate"), path.as_os_str()], 1, &[&format!("cut.csv:{lines}:"), "no end of line"]);
}

#[test]
fn contiguous_dwells_keep_every_sample_on_the_firmware_path() {
    // No `pos = 0` row between the dwells: the sample at which the table reports the next position is that
    // position's first, on the firmware path as on the direct one.
    let dir = tempfile::tempdir().unwrap();
    let (head, rows) = split_rows(&example_text());
    let kept: Vec<&String> = rows.iter().filter(|r| r.split(',').nth(1) != Some("0")).collect();
    let text = format!("{head}{}\n", kept.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n"));
    let path = file(&dir, "contiguous.csv", text);
    let samples = |extra: &[&str]| -> Vec<u64> {
        let out = sinscal().arg("calibrate").arg(&path).args(["--json", "-"]).args(extra).assert().success();
        let v: serde_json::Value = serde_json::from_slice(&out.get_output().stdout).unwrap();
        v["positions"].as_array().unwrap().iter().map(|p| p["samples"].as_u64().unwrap()).collect()
    };
    let direct = samples(&[]);
    assert_eq!(direct, vec![1000; 6]);
    assert_eq!(samples(&["--on", "host"]), direct);
}

#[test]
fn a_label_beyond_16_bits_is_refused_on_the_firmware_path() {
    let dir = tempfile::tempdir().unwrap();
    let (head, rows) = split_rows(&example_text());
    let relabelled: Vec<String> = rows
        .iter()
        .map(|r| {
            let mut cells: Vec<&str> = r.split(',').collect();
            if cells[1] == "6" {
                cells[1] = "65537";
            }
            cells.join(",")
        })
        .collect();
    let path = file(&dir, "label.csv", format!("{head}{}\n", relabelled.join("\n")));
    // The direct path reads labels as 32-bit numbers; the firmware path holds 16 bits.
    sinscal().arg("calibrate").arg(&path).assert().success();
    refused(&[os("calibrate"), path.as_os_str(), os("--on"), os("host")], 1, &["label.csv:", "65537", "16 bits"]);
}

#[test]
fn numbers_in_messages_are_short() {
    let dir = tempfile::tempdir().unwrap();
    let text = example_text();
    let line = text.lines().find(|l| l.starts_with("# rate_hz:")).unwrap().to_string();
    let path = file(&dir, "rate.csv", text.replace(&line, "# rate_hz: 1e300"));
    let e = refused(&[os("calibrate"), path.as_os_str()], 1, &["rate.csv:", "rate_hz: 1e300", "(0, 1000000] Hz"]);
    assert!(e.len() < 200, "{e}");
    let path = file(&dir, "rate.csv", text.replace(&line, "# rate_hz: -1e20"));
    refused(&[os("analyze"), path.as_os_str()], 1, &["rate_hz: -1e20 is not a rate"]);
}

#[test]
fn a_closed_or_full_standard_output_is_no_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = file(&dir, "example.csv", example_text());
    // The reader closes the pipe before anything is written: a quiet end, status 0.
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("sinscal"))
        .arg("calibrate")
        .arg(&path)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // A full device: the error, status 1.
    if let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") {
        let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("sinscal"))
            .arg("calibrate")
            .arg(&path)
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("writing to standard output"), "{stderr}");
    } else {
        common::skipped_here("the full-device half of this test", "no /dev/full on this machine");
    }
}

#[test]
fn bad_arguments_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let path = file(&dir, "example.csv", example_text());
    refused(&[os("calibrate"), path.as_os_str(), os("--prefilter-a"), os("2")], 2, &["neither 'auto' nor a number"]);
    refused(&[os("montecarlo"), os("--runs"), os("1")], 2, &["--runs"]);
}

#[test]
fn an_import_never_overwrites_its_input() {
    let dir = tempfile::tempdir().unwrap();
    // Any input path is checked before it is read.
    let input = file(&dir, "session.csv", "t,gx\n");
    let labels = file(&dir, "session_list.json", "{}");
    for out in [&input, &labels] {
        refused(
            &[os("import"), os("imucal"), input.as_os_str(), os("--out"), out.as_os_str()],
            1,
            &["--out is the input", "would overwrite"],
        );
    }
    assert_eq!(std::fs::read_to_string(&input).unwrap(), "t,gx\n");
}

#[test]
fn a_study_of_too_few_samples_is_refused() {
    // A PSINS record of two samples: its three header lines, then two lines of counts.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("psins-lasergyro")).unwrap();
    let imu =
        "0 0 -90.6 0 0 0\n34.2 108.9 380 0 10 9.780327\n0.1 0.1 0.1 125 125 125\n1 2 3 4 5 78000\n1 2 3 4 5 78000\n";
    std::fs::write(dir.path().join("psins-lasergyro/lasergyro.imu"), imu).unwrap();
    let report = dir.path().join("report");
    refused(
        &[os("study"), os("psins"), os("--data"), dir.path().as_os_str(), os("--report"), report.as_os_str()],
        1,
        &["lasergyro.imu", "2 samples", "at least 1024"],
    );
}

/// The clean scenario's text with `from` replaced by `to`.
fn scenario_with(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/table1-clean.toml")).unwrap();
    assert!(text.contains(from), "{from}");
    text.replace(from, to)
}

#[test]
fn simulate_never_writes_what_its_reader_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let cases = [
        ("# gravity_mps2 = 9.8063", "gravity_mps2 = 0.0\n#", "site.gravity_mps2 0 is not a gravity on Earth"),
        ("# gravity_mps2 = 9.8063", "gravity_mps2 = nan\n#", "site.gravity_mps2 is not a finite number"),
        ("bias_radps = [2.4240684e-7,", "bias_radps = [inf,", "gyro.bias_radps[0] is not a finite number"),
        ("move_s = 5.0", "move_s = inf", "schedule.move_s is not a finite number"),
        ("rate_hz = 100.0", "rate_hz = 1e9", "schedule.rate_hz 1e9 is not a rate in (0, 1000000] Hz"),
        ("dwell_s = 60.0", "dwell_s = 1e12", "at most 1e7 are simulated"),
        ("latitude_deg = 45.7796", "latitude_deg = 90", "site.latitude_deg 90 is not in [-89.9, 89.9]"),
        (
            "angle_random_walk_rad_per_sqrt_s = 4.8481368e-8",
            "angle_random_walk_rad_per_sqrt_s = 4.8481368e-8\nquantization_radps = [1e-320, 0, 0]",
            "quantization steps must be 0 (off) or at least 1e-15",
        ),
    ];
    for (from, to, words) in cases {
        let scenario = file(&dir, "scenario.toml", scenario_with(from, to));
        refused(&[os("simulate"), scenario.as_os_str(), os("--out"), out.as_os_str()], 1, &["scenario.toml:", words]);
        assert!(!out.exists(), "{words}: a file was written");
    }
}

#[test]
fn an_import_never_writes_what_its_reader_refuses() {
    // A PSINS record whose start time swallows its sampling interval, and one whose interval is absurd.
    let dir = tempfile::tempdir().unwrap();
    let counts = "1 2 3 4 5 78000\n".repeat(200);
    let cases = [
        ("34.2 108.9 380 1e15 10 9.780327", "time 1e15 s does not increase"),
        ("34.2 108.9 380 0 1e-300 9.780327", "rate_hz 1e303 is not a rate"),
    ];
    for (site, words) in cases {
        let imu = format!("0 0 -90.6 0 0 0\n{site}\n0.1 0.1 0.1 125 125 125\n{counts}");
        let input = file(&dir, "record.imu", imu);
        let out = dir.path().join("record.csv");
        refused(
            &[os("import"), os("psins"), input.as_os_str(), os("--out"), out.as_os_str()],
            1,
            &["record.csv:", "not written, its reader would refuse it", words],
        );
        assert!(!out.exists());
    }
}

#[test]
fn an_implausible_calibration_is_refused_before_it_is_used() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, cal) = calibrated_example(&dir);
    let mut v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&cal).unwrap()).unwrap();
    v["gyro_bias_radps"][0] = serde_json::json!(1e308);
    let big = file(&dir, "big.json", v.to_string());
    for command in ["navigate", "apply"] {
        let mut args = vec![os(command), rec.as_os_str(), os("--calibration"), big.as_os_str()];
        let out = dir.path().join("applied.csv");
        if command == "apply" {
            args.extend([os("--out"), out.as_os_str()]);
        }
        refused(&args, 1, &["big.json:", "gyro_bias_radps[0] = 1e308 rad/s", "beyond the plausible"]);
    }
}

#[test]
fn angles_beyond_a_radian_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let head = "# sinscal-angles: 1\n# latitude_deg: 45.7796\n\
                pos,pitch_deg,roll_deg,heading_deg,phi_e_rad,phi_n_rad,phi_u_rad,phi_e_std_rad,phi_n_std_rad,phi_u_std_rad\n";
    let rows = [(1, 0, 0, 0), (2, 0, 0, 180), (3, 0, 0, 90), (4, 0, 0, 270), (5, 0, 90, 0), (6, 0, 270, 0)];
    let body = |std: &str| -> String {
        rows.iter().map(|(p, a, b, c)| format!("{p},{a},{b},{c},1e-5,-2e-5,3e-4,1e-6,1e-6,{std}\n")).collect()
    };
    let good = file(&dir, "angles.csv", format!("{head}{}", body("1e-5")));
    sinscal().arg("analyze").arg(&good).assert().success();
    let bad = file(&dir, "angles.csv", format!("{head}{}", body("1e308")));
    refused(&[os("analyze"), bad.as_os_str()], 1, &["angles.csv:4:", "at most 1 rad"]);
    // At a pole the heading angle has no horizontal Earth rate to rest on: refused at the header line, with the
    // limit, not as "dependent columns" of the fit.
    let polar = file(&dir, "angles.csv", format!("{}{}", head.replace("45.7796", "90"), body("1e-5")));
    refused(&[os("analyze"), polar.as_os_str()], 1, &["angles.csv:2:", "latitude_deg 90 outside [-89.9, 89.9]"]);
}

/// A navigated sample beyond any IMU's range (a rate of 1e200 rad/s, a force of 1e30 m/s^2) once made every
/// figure NaN with exit 0; refused now at its line, with the value and the range.
#[test]
fn navigate_refuses_a_sample_beyond_any_imu_range() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, cal) = calibrated_example(&dir);
    let text = std::fs::read_to_string(&rec).unwrap();
    let (head, rows) = split_rows(&text);
    // The middle row of the last dwell (the longest: all dwells have the same length, and ties go to the last).
    let last_pos = rows.iter().filter_map(|r| r.split(',').nth(1)).rfind(|p| *p != "0").unwrap().to_string();
    let in_dwell: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].split(',').nth(1) == Some(&last_pos)).collect();
    let at = in_dwell[in_dwell.len() / 2];
    for (column, value, shown) in [(5, "1e200", "|w| = 1e200 rad/s"), (8, "1e30", "|f| = 1e30 m/s^2")] {
        let mut bad = rows.clone();
        let mut cells: Vec<String> = bad[at].split(',').map(str::to_string).collect();
        cells[column] = value.to_string();
        bad[at] = cells.join(",");
        let path = file(&dir, "spiked.csv", format!("{head}{}\n", bad.join("\n")));
        let stderr = refused(&[os("navigate"), path.as_os_str(), os("--calibration"), cal.as_os_str()], 1, &[shown]);
        assert!(stderr.contains("beyond any strapdown IMU's range") && !stderr.contains("NaN"), "{stderr}");
    }
}

#[test]
fn hours_that_are_not_a_duration_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, cal) = calibrated_example(&dir);
    for hours in ["nan", "0", "49", "inf"] {
        refused(
            &[os("navigate"), rec.as_os_str(), os("--calibration"), cal.as_os_str(), os("--hours"), os(hours)],
            2,
            &["is not a number of hours in (0, 48]"],
        );
    }
}

#[test]
fn a_line_longer_than_64_kib_is_refused_without_reading_it_whole() {
    let dir = tempfile::tempdir().unwrap();
    let (head, rows) = split_rows(&example_text());
    let long = ",".repeat(70_000);
    let path = file(&dir, "long.csv", format!("{head}{}\n{long}\n", rows[..10].join("\n")));
    let line = format!("long.csv:{}:", head.lines().count() + 11);
    refused(&[os("calibrate"), path.as_os_str()], 1, &[&line, "a line longer than 65536 bytes"]);
    let path = file(&dir, "longhead.csv", format!("# {long}\n{head}"));
    refused(&[os("calibrate"), path.as_os_str()], 1, &["longhead.csv:1:", "a line longer than 65536 bytes"]);
}

#[test]
fn a_calibration_that_says_a_thing_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (rec, cal) = calibrated_example(&dir);
    let text = std::fs::read_to_string(&cal).unwrap();
    // The second gyro_bias_radps would win silently in a plain JSON reader.
    let twice =
        text.replacen("\"gyro_bias_radps\":", "\"gyro_bias_radps\": [0.0, 0.0, 0.0],\n  \"gyro_bias_radps\":", 1);
    let path = file(&dir, "twice.json", twice);
    let out = dir.path().join("applied.csv");
    refused(
        &[os("apply"), rec.as_os_str(), os("--calibration"), path.as_os_str(), os("--out"), out.as_os_str()],
        1,
        &["twice.json:", "key 'gyro_bias_radps' appears twice"],
    );
}

#[test]
fn a_label_beyond_32_bits_is_named_as_such() {
    // 4294967297 = 2^32 + 1: an integer, but no label (they are 32-bit); the message says which limit it passed.
    let dir = tempfile::tempdir().unwrap();
    let (head, mut rows) = split_rows(&example_text());
    let mut cells: Vec<String> = rows[0].split(',').map(str::to_string).collect();
    cells[1] = "4294967297".into();
    rows[0] = cells.join(",");
    let path = file(&dir, "big-label.csv", format!("{head}{}\n", rows.join("\n")));
    refused(&[os("calibrate"), path.as_os_str()], 1, &["4294967297 is beyond the largest label, 4294967295"]);
    // A label that is not a number at all says so, quoting at most 80 characters of it.
    cells[1] = "x".repeat(300);
    rows[0] = cells.join(",");
    let path = file(&dir, "long-label.csv", format!("{head}{}\n", rows.join("\n")));
    let stderr =
        refused(&[os("calibrate"), path.as_os_str()], 1, &["is not a non-negative integer", "(300 characters)"]);
    assert!(!stderr.contains(&"x".repeat(81)), "{stderr}");
}

#[test]
fn a_calibration_json_with_a_byte_order_mark_is_read_as_without() {
    // Recordings accept a byte-order mark; a calibration JSON an editor saved with one is read the same.
    let dir = tempfile::tempdir().unwrap();
    let (rec, cal) = calibrated_example(&dir);
    let mut bom = vec![0xef, 0xbb, 0xbf];
    bom.extend(std::fs::read(&cal).unwrap());
    let cal_bom = file(&dir, "cal-bom.json", bom);
    let (plain, marked) = (dir.path().join("plain.csv"), dir.path().join("marked.csv"));
    for (c, out) in [(&cal, &plain), (&cal_bom, &marked)] {
        sinscal().arg("apply").arg("--calibration").arg(c).arg("--out").arg(out).arg(&rec).assert().success();
    }
    let strip = |p: &Path| {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("# calibration"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(strip(&plain), strip(&marked));
}

#[test]
fn a_flash_image_that_is_a_directory_is_named_not_read_as_empty() {
    // It used to say "no calibration record is stored": the firmware could not open it and saw an empty flash.
    let dir = tempfile::tempdir().unwrap();
    let flash = dir.path().as_os_str();
    refused(&[os("device"), os("show"), os("--qemu"), os("--flash"), flash], 1, &["a directory, not a flash image"]);
}

#[test]
fn align_of_readings_that_are_not_gravity_is_refused_with_the_reason() {
    // All-zero readings printed "+- NaN" and "force and rate are parallel"; readings in g aligned silently.
    let dir = tempfile::tempdir().unwrap();
    let (head, rows) = split_rows(&example_text());
    for (name, scale) in [("zeros.csv", 0.0), ("in-g.csv", 1.0 / 9.80665)] {
        let scaled: Vec<String> = rows
            .iter()
            .map(|row| {
                let mut cells: Vec<String> = row.split(',').map(str::to_string).collect();
                for cell in &mut cells[5..11] {
                    *cell = format!("{:?}", cell.parse::<f64>().unwrap() * scale);
                }
                cells.join(",")
            })
            .collect();
        let path = file(&dir, name, format!("{head}{}\n", scaled.join("\n")));
        let stderr = refused(&[os("align"), path.as_os_str()], 1, &["dwell 1:", "define no attitude"]);
        assert!(!stderr.contains("NaN"), "{stderr}");
    }
}

#[test]
fn navigate_of_times_in_milliseconds_is_refused_with_the_hint() {
    // Times in ms without a rate_hz: read as 0.1 Hz, this ran a 16.7-h navigation of absurd values.
    let dir = tempfile::tempdir().unwrap();
    let (_, cal) = calibrated_example(&dir);
    let (head, rows) = split_rows(&example_text());
    let head: String = head.lines().filter(|l| !l.starts_with("# rate_hz")).map(|l| format!("{l}\n")).collect();
    let ms: Vec<String> = rows
        .iter()
        .map(|row| {
            let (t, rest) = row.split_once(',').unwrap();
            format!("{:?},{rest}", t.parse::<f64>().unwrap() * 1000.0)
        })
        .collect();
    let path = file(&dir, "ms.csv", format!("{head}{}\n", ms.join("\n")));
    let args = [os("navigate"), os("--calibration"), cal.as_os_str(), path.as_os_str()];
    refused(&args, 1, &["a sample rate of 0.1 Hz", "times in milliseconds?"]);
}
