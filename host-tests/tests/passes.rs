//! The commands that read a recording file in passes without keeping its rows (`RecordingFile`) give what the
//! recording in memory gives, bit for bit: calibrate (every estimator, prefilter and `--on host`), navigate,
//! analyze and apply. SIMULATION data of the built-in example, with a dwell split in two by `pos = 0` rows
//! (one label, two stretches) where the command allows it.

use std::path::{Path, PathBuf};

use sinscal::calib::general::Model;
use sinscal_host::analysis::analyze_recording;
use sinscal_host::calibration::firmware_path::calibrate_on_host;
use sinscal_host::calibration::result::CalibrationJson;
use sinscal_host::calibration::{calibrate, Coefficient, Options, PrefilterKind};
use sinscal_host::cmd::apply::apply;
use sinscal_host::io::calibration_model::CalibrationModel;
use sinscal_host::io::recording::{Recording, RecordingFile};
use sinscal_host::model::synth::Scenario;
use sinscal_host::navigation::check::{navigate, NavCalibration, NavOptions};

/// The example recording written to `dir`, and read back whole.
fn written(dir: &Path, rec: &Recording) -> (PathBuf, Recording) {
    let path = dir.join("example.csv");
    rec.write(&path).unwrap();
    let whole = Recording::read(&path).unwrap();
    (path, whole)
}

/// The example with the middle tenth of its first dwell's rows labelled 0: one label in two stretches.
fn split_first_dwell(mut rec: Recording) -> Recording {
    let first: Vec<usize> = (0..rec.rows.len()).filter(|&i| rec.rows[i].pos == 1).collect();
    let n = first.len();
    for &i in &first[n * 9 / 20..n * 11 / 20] {
        rec.rows[i].pos = 0;
    }
    rec
}

fn json(cal: &sinscal_host::calibration::Calibration) -> String {
    serde_json::to_string(&CalibrationJson::new(cal)).unwrap()
}

#[test]
fn calibrate_from_a_file_is_calibrate_of_the_rows_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let (path, whole) = written(dir.path(), &split_first_dwell(Scenario::example().recording(2, "e.csv")));
    assert!(whole.rows.iter().any(|r| r.pos == 0) && whole.dwells()[0].rows.len() < 6000);
    let file = RecordingFile::open(&path).unwrap();
    let options = [
        Options::default(),
        Options::angles(),
        Options { model: Model::FULL, ..Options::default() },
        Options { prefilter: PrefilterKind::None, ..Options::default() },
        Options { coefficient: Coefficient::Identify, ..Options::angles() },
    ];
    for o in options {
        let (a, b) = (calibrate(&whole, &o).unwrap(), calibrate(&file, &o).unwrap());
        assert_eq!(json(&a), json(&b), "{:?} {:?}", o.method, o.coefficient);
        if o.coefficient == Coefficient::Identify {
            // The coefficient was identified (not the default a = 1), from the first dwell's rows only.
            assert!(matches!(b.prefilter, sinscal::calib::dwell::Prefilter::HmmKf { gyro, .. } if gyro.a < 1.0));
        }
    }
}

#[test]
fn the_firmware_path_from_a_file_is_the_firmware_path_of_the_rows_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let (path, whole) = written(dir.path(), &Scenario::example().recording(3, "e.csv"));
    let file = RecordingFile::open(&path).unwrap();
    for o in [Options::default(), Options::angles()] {
        let (a, b) = (calibrate_on_host(&whole, &o).unwrap(), calibrate_on_host(&file, &o).unwrap());
        assert_eq!(json(&a), json(&b));
        assert_eq!(b.sampling.unwrap().readings as usize, whole.rows.len());
    }
    // One label in two stretches is refused from the file as from memory, at the same line.
    let (path, whole) = written(dir.path(), &split_first_dwell(Scenario::example().recording(3, "e.csv")));
    let file = RecordingFile::open(&path).unwrap();
    let (a, b) = (calibrate_on_host(&whole, &Options::default()), calibrate_on_host(&file, &Options::default()));
    let (a, b) = (a.unwrap_err().to_string(), b.unwrap_err().to_string());
    assert_eq!(a, b);
    assert!(a.contains("dwell 1 is not contiguous"), "{a}");
}

#[test]
fn navigate_analyze_and_apply_from_a_file_are_those_of_the_rows_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let (path, whole) = written(dir.path(), &split_first_dwell(Scenario::example().recording(5, "e.csv")));
    let file = RecordingFile::open(&path).unwrap();
    let cal_path = dir.path().join("cal.json");
    std::fs::write(&cal_path, json(&calibrate(&whole, &Options::default()).unwrap())).unwrap();

    let nav = NavCalibration::read(&cal_path).unwrap();
    for options in [NavOptions::default(), NavOptions { position: Some(1), ..NavOptions::default() }] {
        let a = navigate(&whole, &nav, None, &options, |_, _| {}).unwrap();
        let b = navigate(&file, &nav, None, &options, |_, _| {}).unwrap();
        assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&b).unwrap());
        assert_eq!(a.histories, b.histories);
    }

    let (a, b) = (analyze_recording(&whole).unwrap(), analyze_recording(&file).unwrap());
    assert_eq!(serde_json::to_string(&a).unwrap(), serde_json::to_string(&b).unwrap());

    let model = CalibrationModel::read(&cal_path).unwrap();
    let (out_a, out_b) = (dir.path().join("a.csv"), dir.path().join("b.csv"));
    assert_eq!(apply(&whole, &model, &out_a).unwrap(), whole.rows.len());
    assert_eq!(apply(&file, &model, &out_b).unwrap(), whole.rows.len());
    assert_eq!(std::fs::read(&out_a).unwrap(), std::fs::read(&out_b).unwrap());
    // The compensated file reads back, with the calibration named in its header.
    let applied = Recording::read(&out_b).unwrap();
    assert!(applied.header.comments.iter().any(|c| c == "calibration: cal.json"), "{:?}", applied.header.comments);
    assert_ne!(applied.rows[10].force_b_mps2, whole.rows[10].force_b_mps2);
}

#[test]
fn apply_that_cannot_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let (path, whole) = written(dir.path(), &Scenario::example().recording(6, "e.csv"));
    let cal_path = dir.path().join("cal.json");
    std::fs::write(&cal_path, json(&calibrate(&whole, &Options::default()).unwrap())).unwrap();
    let model = CalibrationModel::read(&cal_path).unwrap();
    let file = RecordingFile::open(&path).unwrap();
    let out = dir.path().join("missing").join("out.csv");
    let e = apply(&file, &model, &out).unwrap_err().to_string();
    assert!(e.contains("missing") && e.contains("No such file"), "{e}");
    // A recording whose last line was cut after the scratch file was started: refused, nothing left behind.
    let text = std::fs::read_to_string(&path).unwrap();
    let cut = dir.path().join("cut.csv");
    std::fs::write(&cut, &text[..text.len() - 3]).unwrap();
    let out = dir.path().join("out.csv");
    let e = apply(&RecordingFile::open(&cut).unwrap(), &model, &out).unwrap_err().to_string();
    assert!(e.contains("the last line has no end of line"), "{e}");
    let mut left: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    left.sort();
    assert_eq!(left, ["cal.json", "cut.csv", "example.csv"]);
}
