//! Plausibility first, on every path (docs/method.md#plausibility-first): a reference heading a half turn off
//! at one dwell, a wrong face down, and accelerometers 1.5 times too large are refused with exit status 1,
//! the dwell and the reason, by both estimators, whether `calibrate` reads the recording directly, replays it
//! through the firmware path on x86 (`--on host`) or runs the firmware in QEMU (`--on qemu`). SIMULATION data
//! (the built-in example) with one error put in.

mod common;

use assert_cmd::Command;
use sinscal_host::model::synth::Scenario;

/// The stderr of `sinscal calibrate PATH EXTRA...`, which must exit with status 1.
fn calibrate_fails(path: &std::path::Path, extra: &[&str]) -> String {
    let out = Command::cargo_bin("sinscal").unwrap().arg("calibrate").arg(path).args(extra).assert().code(1);
    String::from_utf8(out.get_output().stderr.clone()).unwrap()
}

/// Every accelerometer value of the recording's rows times `factor` (columns ax, ay, az: 8, 9, 10).
fn scale_accelerometers(text: &str, factor: f64) -> String {
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            let mut cells: Vec<String> = l.split(',').map(str::to_string).collect();
            if l.starts_with('#') || cells.len() < 11 || cells[8].parse::<f64>().is_err() {
                return l.to_string();
            }
            for cell in &mut cells[8..11] {
                *cell = format!("{}", cell.parse::<f64>().unwrap() * factor);
            }
            cells.join(",")
        })
        .collect();
    lines.join("\n") + "\n"
}

#[test]
fn implausible_references_and_data_exit_1_with_the_dwell_on_every_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("example.csv");
    Scenario { dwell_s: 12.0, ..Scenario::example() }.recording(5, "example.csv").write(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(",3,0,0,90,"), "the example's position 3 is level at heading 90");
    // (file, what is wrong, the dwell named, what the direct path says per method, what the sequence says).
    let cases = [
        ("half_turn.csv", text.replace(",3,0,0,90,", ",3,0,0,270,"), 3, ["heading 90", "in heading"], None),
        (
            "face_down.csv",
            text.replace(",3,0,0,90,", ",3,180,0,90,"),
            3,
            ["from where the reference attitude puts it", "in level"],
            Some("GravityContradictsPosition"),
        ),
        ("scale.csv", scale_accelerometers(&text, 1.5), 1, ["|f| is 1.50", "|f| is 1.50"], Some("Acceleration")),
    ];
    let mut ons = vec![None, Some("host")];
    if common::qemu_available(" (--on qemu only)") {
        ons.push(Some("qemu"));
    }
    for (name, body, dwell, direct, sequence) in cases {
        let file = dir.path().join(name);
        std::fs::write(&file, body).unwrap();
        for (m, method) in ["channels", "angles"].into_iter().enumerate() {
            for on in &ons {
                let mut args = vec!["--method", method];
                if let Some(on) = on {
                    args.extend(["--on", on]);
                }
                let stderr = calibrate_fails(&file, &args);
                let dwell_named =
                    stderr.contains(&format!("dwell {dwell}:")) || stderr.contains(&format!("(dwell {dwell})"));
                assert!(dwell_named, "{name} {args:?}: {stderr}");
                // The firmware's sequence checks every sample against the announced face and |f|, so a
                // wrong face or scale stops the dwell there; a heading is only seen by the solution.
                let want = match (on, sequence) {
                    (Some(_), Some(reason)) => reason,
                    _ => direct[m],
                };
                assert!(stderr.contains(want), "{name} {args:?}: wanted '{want}' in: {stderr}");
            }
        }
    }
}
