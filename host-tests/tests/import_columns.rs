//! `sinscal import columns`: described layouts (docs/data.md#described-layouts).
//!
//! - Round trips: a recording written by sinscal's simulator is written again in each layout (text in deg/s with
//!   front-right-down axes, binary f32 and f64 of both byte orders, i16 counts with an offset, increments, a
//!   MAT-file) and imported back to the same samples, to the layout's precision.
//! - The three measured data sets import through the generic path to the recordings of their dedicated importers.
//! - Static intervals are found without labels, and printed.
//! - Bad layouts are refused with a reason: a field beyond the record, an axis mapping that is not a rotation,
//!   time that does not increase, increments read as rates and the reverse.

mod common;

use std::path::{Path, PathBuf};

use sinscal_host::io::import::mat::write_mat_v5;
use sinscal_host::io::import::{
    ferraris_pose, import_columns, import_imucal, import_imutk, import_psins, parse_imucal_labels, parse_labels,
    ColumnsImport, Imported, Layout, Positions, StaticDetection,
};
use sinscal_host::io::recording::{Recording, Row};
use sinscal_host::model::synth::Scenario;

/// A short simulated session: six positions of 4 s at 100 Hz with 2 s moves, every bias and noise of the example.
fn session() -> Recording {
    Scenario { dwell_s: 4.0, ..Scenario::example() }.recording(5, "session.csv")
}

/// The labels file of a recording's dwells: each dwell's time range, widened by half a sample at both ends.
fn labels_of(rec: &Recording) -> String {
    let dt_s = 1.0 / rec.header.rate_hz.unwrap();
    let mut out = "pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n".to_string();
    for d in rec.dwells() {
        let (a, b) = (d.rows[0], d.rows[d.rows.len() - 1]);
        let heading = a.heading_deg.map_or("?".to_string(), |h| format!("{h:?}"));
        out += &format!(
            "{},{:?},{:?},{:?},{:?},{heading}\n",
            d.pos,
            a.t_s - dt_s / 2.0,
            b.t_s + dt_s / 2.0,
            a.pitch_deg,
            a.roll_deg
        );
    }
    out
}

fn import(
    inputs: &[&Path],
    layout_text: &str,
    labels: Option<&str>,
    latitude_deg: Option<f64>,
) -> Result<Imported, String> {
    let layout = Layout::parse(layout_text, "layout.toml").map_err(|e| e.to_string())?;
    let positions = match labels {
        Some(text) => Positions::Labels(parse_labels(text, "labels.csv").map_err(|e| e.to_string())?),
        None => Positions::Detect(StaticDetection { init_static_s: 3.0, ..StaticDetection::default() }),
    };
    let import = ColumnsImport {
        layout: &layout,
        layout_source: "layout.toml",
        positions,
        labels_source: Some("labels.csv"),
        latitude_deg,
    };
    import_columns(inputs, &import).map_err(|e| e.to_string())
}

/// Every row equal in time, position and attitude, and the samples within `tolerance(value)` each.
fn assert_same_rows(got: &[Row], want: &[Row], what: &str, tolerance: &dyn Fn(usize, f64) -> f64) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    let mut worst = 0.0f64;
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let time_tolerance_s = 1e-9 + tolerance(0, w.t_s.abs().max(1.0));
        assert!((g.t_s - w.t_s).abs() <= time_tolerance_s, "{what}: row {k} time {} vs {}", g.t_s, w.t_s);
        // Rows between positions carry no attitude in an import (the simulator writes the table's).
        assert_eq!(g.pos, w.pos, "{what}: row {k}");
        if w.pos != 0 {
            let attitude = |r: &Row| (r.pitch_deg, r.roll_deg, r.heading_deg);
            assert_eq!(attitude(g), attitude(w), "{what}: row {k}");
        }
        let values = |r: &Row| [r.rate_b_radps, r.force_b_mps2].concat();
        for (channel, (a, b)) in values(g).into_iter().zip(values(w)).enumerate() {
            let (err, allowed) = ((a - b).abs(), tolerance(channel, b));
            assert!(err <= allowed, "{what}: row {k} channel {channel}: {a} vs {b}");
            worst = worst.max(err / allowed.max(f64::MIN_POSITIVE));
        }
    }
    println!("{what}: {} rows equal; largest error {worst:.3} of the tolerance", got.len());
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

const SITE: &str = "[site]\nlatitude_deg = 45.7796\n";

#[test]
fn text_in_degrees_per_second_with_front_right_down_axes_round_trips() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    // The sensor's axes: x forward (body y), y right (body x), z down (-body z); gyro in deg/s, time in ms.
    let mut text = "time_ms;wx;wy;wz;fx;fy;fz\n".to_string();
    for r in &rec.rows {
        let (w, f) = (r.rate_b_radps.map(f64::to_degrees), r.force_b_mps2);
        text += &format!("{:?};{:?};{:?};{:?};{:?};{:?};{:?}\n", r.t_s * 1e3, w[1], w[0], -w[2], f[1], f[0], -f[2]);
    }
    let input = write(dir.path(), "frd.txt", text.as_bytes());
    let layout = format!(
        "format = \"text\"\n[text]\ndelimiter = \";\"\nskip_lines = 1\n[time]\nfield = 0\nunit = \"ms\"\n\
         [gyro]\nfields = [1, 2, 3]\nunit = \"deg/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n\
         [axes]\nfrom = \"frd\"\n{SITE}"
    );
    let got = import(&[&input], &layout, Some(&labels_of(&rec)), None).unwrap();
    assert_same_rows(&got.recording.rows, &rec.rows, "text deg/s FRD", &|_, v| {
        4.0 * f64::EPSILON * v.abs().max(1e-300)
    });
    assert_eq!(got.recording.header.rate_hz, Some(100.0));
}

/// The rows as binary records of seven numbers (t, gyro, accel).
fn binary(rec: &Recording, encode: &dyn Fn(f64, &mut Vec<u8>)) -> Vec<u8> {
    let mut out = Vec::new();
    for r in &rec.rows {
        for v in [r.t_s].iter().chain(&r.rate_b_radps).chain(&r.force_b_mps2) {
            encode(*v, &mut out);
        }
    }
    out
}

#[test]
fn binary_f32_and_f64_of_both_byte_orders_round_trip() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    type Encode = fn(f64, &mut Vec<u8>);
    let cases: [(&str, &str, Encode, f64); 4] = [
        ("f64", "little", |v, o| o.extend(v.to_le_bytes()), 0.0),
        ("f64", "big", |v, o| o.extend(v.to_be_bytes()), 0.0),
        ("f32", "little", |v, o| o.extend((v as f32).to_le_bytes()), 0.5 * f32::EPSILON as f64),
        ("f32", "big", |v, o| o.extend((v as f32).to_be_bytes()), 0.5 * f32::EPSILON as f64),
    ];
    for (kind, endian, encode, relative) in cases {
        let input = write(dir.path(), &format!("{kind}{endian}.bin"), &binary(&rec, &encode));
        let layout = format!(
            "format = \"binary\"\n[binary]\ntype = \"{kind}\"\nendian = \"{endian}\"\nfields = 7\n[time]\nfield = 0\n\
             [gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
        );
        let got = import(&[&input], &layout, Some(&labels_of(&rec)), None).unwrap();
        assert_same_rows(&got.recording.rows, &rec.rows, &format!("binary {kind} {endian}"), &|_, v| {
            relative * v.abs()
        });
    }
}

#[test]
fn increments_and_integer_counts_round_trip() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    let dt_s = 0.01;
    // Angle increments in arcsec and velocity increments in ug*s, as f64 text: value * dt.
    let mut text = String::new();
    for r in &rec.rows {
        let w = r.rate_b_radps.map(|v| v * dt_s * 180.0 / std::f64::consts::PI * 3600.0);
        let f = r.force_b_mps2.map(|v| v * dt_s / (9.80665e-6));
        text += &format!("{:?} {:?} {:?} {:?} {:?} {:?}\n", w[0], w[1], w[2], f[0], f[1], f[2]);
    }
    let input = write(dir.path(), "increments.txt", text.as_bytes());
    let layout = format!(
        "format = \"text\"\n[time]\nrate_hz = 100.0\n[gyro]\nfields = [0, 1, 2]\nunit = \"arcsec\"\nincrements = true\n\
         [accel]\nfields = [3, 4, 5]\nunit = \"ug*s\"\nincrements = true\n{SITE}"
    );
    let got = import(&[&input], &layout, Some(&labels_of(&rec)), None).unwrap();
    assert_same_rows(&got.recording.rows, &rec.rows, "increments arcsec ug*s", &|_, v| {
        16.0 * f64::EPSILON * v.abs().max(1e-300)
    });
    // i16 counts around an offset of 1000, 1e-4 rad/s and 1e-3 m/s^2 per count: within half a count.
    let (gyro_per_count, accel_per_count) = (1e-4, 1e-3);
    let mut bytes = Vec::new();
    for r in &rec.rows {
        for w in r.rate_b_radps {
            bytes.extend(((w / gyro_per_count).round() as i16 + 1000).to_le_bytes());
        }
        for f in r.force_b_mps2 {
            bytes.extend(((f / accel_per_count).round() as i16 + 1000).to_le_bytes());
        }
    }
    let input = write(dir.path(), "counts.bin", &bytes);
    let layout = format!(
        "format = \"binary\"\n[binary]\ntype = \"i16\"\nendian = \"little\"\nfields = 6\n[time]\nrate_hz = 100.0\n\
         [gyro]\nfields = [0, 1, 2]\nunit = \"rad/s\"\noffset = 1000.0\nscale = {gyro_per_count:?}\n\
         [accel]\nfields = [3, 4, 5]\nunit = \"m/s^2\"\noffset = 1000.0\ncounts_per_unit = {:?}\n{SITE}",
        1.0 / accel_per_count
    );
    let got = import(&[&input], &layout, Some(&labels_of(&rec)), None).unwrap();
    // Channels 0 to 2 are the gyro's, 3 to 5 the accelerometer's.
    let half_count =
        |channel: usize, _: f64| if channel >= 3 { 0.5 * accel_per_count } else { 0.5 * gyro_per_count } + 1e-12;
    assert_same_rows(&got.recording.rows, &rec.rows, "i16 counts", &half_count);
}

#[test]
fn a_mat_file_matrix_round_trips() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    let n = rec.rows.len();
    let mut columns = vec![0.0; 7 * n];
    for (k, r) in rec.rows.iter().enumerate() {
        for (j, v) in [r.t_s].iter().chain(&r.rate_b_radps).chain(&r.force_b_mps2).enumerate() {
            columns[j * n + k] = *v;
        }
    }
    let note = [1.0, 2.0];
    let input = write(dir.path(), "imu.mat", &write_mat_v5(&[("note", 1, 2, &note), ("imu", n, 7, &columns)]).unwrap());
    let layout = format!(
        "format = \"mat\"\n[mat]\nvariable = \"imu\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let got = import(&[&input], &layout, Some(&labels_of(&rec)), None).unwrap();
    assert_same_rows(&got.recording.rows, &rec.rows, "MAT-file", &|_, _| 0.0);
    // Two matrices and no name: refused, naming both.
    let unnamed = layout.replace("[mat]\nvariable = \"imu\"\n", "");
    let err = import(&[&input], &unnamed, Some(&labels_of(&rec)), None).unwrap_err();
    assert!(err.contains("note") && err.contains("imu") && err.contains("variable"), "{err}");
}

#[test]
fn static_intervals_are_found_without_labels_and_printed() {
    // Six poses that each tilt the body differently: the specific force shows every move (a turn about the
    // vertical alone does not change it, and the detection, on the accelerometers as imu_tk's, cannot see it).
    let positions_deg = vec![
        [0.0, 0.0, 0.0],
        [0.0, 90.0, 0.0],
        [90.0, 0.0, 0.0],
        [0.0, -90.0, 0.0],
        [-90.0, 0.0, 0.0],
        [0.0, 180.0, 0.0],
    ];
    let rec = Scenario { dwell_s: 6.0, positions_deg, ..Scenario::example() }.recording(5, "tilts.csv");
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for r in &rec.rows {
        let (w, f) = (r.rate_b_radps, r.force_b_mps2);
        text += &format!("{:?},{:?},{:?},{:?},{:?},{:?},{:?}\n", r.t_s, w[0], w[1], w[2], f[0], f[1], f[2]);
    }
    let input = write(dir.path(), "session.csv", text.as_bytes());
    let layout = format!(
        "format = \"text\"\n[text]\ndelimiter = \",\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let got = import(&[&input], &layout, None, None).unwrap();
    println!("{}", got.summary);
    let found = got.recording.dwells();
    let truth = rec.dwells();
    assert_eq!(found.len(), truth.len(), "one interval per dwell");
    for (f, t) in found.iter().zip(&truth) {
        // Each interval lies within its dwell and the settling before it, and covers most of the dwell.
        let (t0, t1) = (t.rows[0].t_s, t.rows[t.rows.len() - 1].t_s);
        let (f0, f1) = (f.rows[0].t_s, f.rows[f.rows.len() - 1].t_s);
        println!("interval {}: {f0:.2} to {f1:.2} s; dwell {t0:.2} to {t1:.2} s", f.pos);
        // The table rests for its settling time (2 s) before each dwell: that is static too.
        assert!(f0 >= t0 - 2.0 - 0.6 && f1 <= t1 + 0.6, "pos {}", f.pos);
        assert!(
            f.rows.len() as f64 >= 0.6 * t.rows.len() as f64,
            "pos {}: {} of {} rows",
            f.pos,
            f.rows.len(),
            t.rows.len()
        );
    }
    assert!(got.summary.contains("interval(s)") && got.summary.contains("start[s]"), "{}", got.summary);
    assert!(got.recording.header.comments.iter().any(|c| c.contains("accelerometer-levelled")));
}

#[test]
fn bad_layouts_are_refused_with_a_reason() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for r in &rec.rows {
        let (w, f) = (r.rate_b_radps, r.force_b_mps2);
        text += &format!("{:?} {:?} {:?} {:?} {:?} {:?} {:?}\n", r.t_s, w[0], w[1], w[2], f[0], f[1], f[2]);
    }
    let input = write(dir.path(), "s.txt", text.as_bytes());
    let base = format!(
        "format = \"text\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n\
         [accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let labels = labels_of(&rec);
    let refused = |layout: &str, input: &Path, want: &[&str]| {
        let err = import(&[input], layout, Some(&labels), None).unwrap_err();
        println!("refused: {err}");
        assert!(want.iter().all(|w| err.contains(w)), "expected {want:?} in: {err}");
    };
    refused(&base.replace("[4, 5, 6]", "[4, 5, 9]"), &input, &["field 9", "beyond"]);
    refused(
        &format!("{base}[axes]\nx = \"+y\"\ny = \"+x\"\nz = \"+z\"\n"),
        &input,
        &["determinant -1", "not a rotation"],
    );
    refused(&format!("{base}[axes]\nx = \"+x\"\ny = \"+x\"\nz = \"+z\"\n"), &input, &["twice", "not a rotation"]);
    refused(&base.replace("unit = \"rad/s\"", "unit = \"deg\""), &input, &["angle", "increments = true"]);
    // Increments read as rates: velocity increments (force x dt) with increments = false.
    let mut inc = String::new();
    for r in &rec.rows {
        let f = r.force_b_mps2.map(|v| v * 0.01);
        inc += &format!("{:?} 0 0 0 {:?} {:?} {:?}\n", r.t_s, f[0], f[1], f[2]);
    }
    let inc_input = write(dir.path(), "inc.txt", inc.as_bytes());
    refused(&base, &inc_input, &["median |specific force|", "look like velocity increments", "increments = true"]);
    let as_increments = base.replace("unit = \"m/s^2\"", "unit = \"m/s\"\nincrements = true");
    refused(&as_increments, &input, &["look like rates", "increments = false"]);
    // Time that does not increase: two rows swapped.
    let mut lines: Vec<&str> = text.lines().collect();
    lines.swap(10, 11);
    let swapped = write(dir.path(), "swapped.txt", (lines.join("\n") + "\n").as_bytes());
    refused(&base, &swapped, &["swapped.txt:12:", "does not increase"]);
    // A record too short for the layout, and a binary file that ends inside a record.
    let short = write(dir.path(), "short.txt", format!("{}0.5 1 2\n", text).as_bytes());
    refused(&base, &short, &["short.txt:", "3 fields, the first record has 7"]);
    // A record with a field more is not read past, and one field read as two quantities is a layout mistake.
    let long = write(
        dir.path(),
        "long.txt",
        format!(
            "{}1000 1 2 3 4 5 6 7
",
            text
        )
        .as_bytes(),
    );
    refused(&base, &long, &["long.txt:", "8 fields, the first record has 7"]);
    refused(&base.replace("[1, 2, 3]", "[4, 5, 6]"), &input, &["field 4 is read as both gyro x and accel x"]);
    let bin = format!(
        "format = \"binary\"\n[binary]\ntype = \"f64\"\nendian = \"little\"\nfields = 7\n[time]\nfield = 0\n\
         [gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let mut bytes = binary(&rec, &|v, o| o.extend(v.to_le_bytes()));
    bytes.truncate(bytes.len() - 3);
    let cut = write(dir.path(), "cut.bin", &bytes);
    refused(&bin, &cut, &["ends 53 bytes into record"]);
    // No latitude anywhere.
    let err = import(&[&input], &base.replace(SITE, ""), Some(&labels), None).unwrap_err();
    assert!(err.contains("latitude is unknown"), "{err}");
    // Unknown keys in the layout.
    let err = Layout::parse(&format!("{base}[gyro2]\nfields = [1, 2, 3]\n"), "l.toml").unwrap_err().to_string();
    assert!(err.contains("gyro2"), "{err}");
}

fn layout_file(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("layouts").join(name)).unwrap()
}

#[test]
fn real_data_the_three_data_sets_import_through_the_generic_path_as_through_their_own() {
    let Some(data) = common::data_dir() else { return };
    // PSINS: one pose, its attitude from the header (heading = -yaw = 90.6 deg).
    let imu = common::data_file(&data, "psins-lasergyro/lasergyro.imu");
    let dedicated = import_psins(&imu, None).unwrap().recording;
    let generic = import(
        &[&imu],
        &layout_file("psins.toml"),
        Some("start_s,end_s,pitch_deg,roll_deg,heading_deg\n0,1e9,0,0,90.6\n"),
        None,
    )
    .unwrap()
    .recording;
    // Angle and velocity increments scaled in another order of operations: equal to a few ulp.
    assert_same_rows(&generic.rows, &dedicated.rows, "PSINS", &|_, v| 4.0 * f64::EPSILON * v.abs());
    assert_eq!(
        (generic.header.latitude_deg, generic.header.height_m, generic.header.rate_hz, generic.header.gravity_mps2),
        (
            dedicated.header.latitude_deg,
            dedicated.header.height_m,
            dedicated.header.rate_hz,
            dedicated.header.gravity_mps2
        )
    );
    // imucal: the six labelled poses of its JSON list as a labels file (sample indices / 102.4 Hz).
    let csv = common::data_file(&data, "imucal-ferraris/example_ferraris_session.csv");
    let list = common::data_file(&data, "imucal-ferraris/example_ferraris_session_list.json");
    let dedicated = import_imucal(&csv, &list, None).unwrap().recording;
    let mut labels = "pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n".to_string();
    for r in parse_imucal_labels(&std::fs::read_to_string(&list).unwrap(), "list").unwrap() {
        if let Some(p) = ferraris_pose(&r.label) {
            labels += &format!(
                "{},{:?},{:?},{:?},{:?},?\n",
                p.pos,
                r.start as f64 / 102.4,
                r.end as f64 / 102.4,
                p.pitch_deg,
                p.roll_deg
            );
        }
    }
    let generic = import(&[&csv], &layout_file("imucal.toml"), Some(&labels), None).unwrap().recording;
    assert_same_rows(&generic.rows, &dedicated.rows, "imucal", &|_, _| 0.0);
    assert_eq!(
        (generic.header.latitude_deg, generic.header.rate_hz),
        (dedicated.header.latitude_deg, dedicated.header.rate_hz)
    );
    // imu_tk: two files side by side, counts, static intervals found with the dedicated importer's defaults.
    let (acc, gyro) = (
        common::data_file(&data, "imu-tk-xsens/xsens_acc.mat"),
        common::data_file(&data, "imu-tk-xsens/xsens_gyro.mat"),
    );
    let dedicated = import_imutk(&acc, &gyro, None, &StaticDetection::default()).unwrap().recording;
    let layout = Layout::parse(&layout_file("imutk.toml"), "imutk.toml").unwrap();
    let import = ColumnsImport {
        layout: &layout,
        layout_source: "imutk.toml",
        positions: Positions::Detect(StaticDetection::default()),
        labels_source: None,
        latitude_deg: None,
    };
    let generic = import_columns(&[&acc, &gyro], &import).unwrap().recording;
    assert_same_rows(&generic.rows, &dedicated.rows, "imu_tk", &|_, _| 0.0);
    assert_eq!(generic.dwells().len(), 37);
    assert_eq!(
        (generic.header.latitude_deg, generic.header.rate_hz, generic.header.gravity_mps2),
        (dedicated.header.latitude_deg, dedicated.header.rate_hz, dedicated.header.gravity_mps2)
    );
}

#[test]
fn the_command_line_reads_a_layout_and_labels_and_refuses_a_missing_layout() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    let bytes = binary(&rec, &|v, o| o.extend(v.to_be_bytes()));
    let input = write(dir.path(), "imu.bin", &bytes);
    let layout = format!(
        "format = \"binary\"\n[binary]\ntype = \"f64\"\nendian = \"big\"\nfields = 7\n[time]\nfield = 0\n\
         [gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let layout_path = write(dir.path(), "layout.toml", layout.as_bytes());
    let labels_path = write(dir.path(), "labels.csv", labels_of(&rec).as_bytes());
    let out = dir.path().join("out.csv");
    let sinscal = || assert_cmd::Command::cargo_bin("sinscal").unwrap();
    let run = sinscal()
        .args(["import", "columns"])
        .arg(&input)
        .arg("--layout")
        .arg(&layout_path)
        .arg("--labels")
        .arg(&labels_path)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(stdout.contains("6 position(s)") && stdout.contains("wrote"), "{stdout}");
    let back = Recording::read(&out).unwrap();
    assert_same_rows(&back.rows, &rec.rows, "through the command line and the recording file", &|_, v| {
        f64::EPSILON * v.abs()
    });
    // The same positions as --position flags instead of a labels file.
    let dt_s = 0.01;
    let flags: Vec<String> = rec
        .dwells()
        .iter()
        .map(|d| {
            let (a, b) = (d.rows[0], d.rows[d.rows.len() - 1]);
            let heading = a.heading_deg.map_or("?".to_string(), |h| format!("{h:?}"));
            format!("{:?},{:?},{:?},{:?},{heading}", a.t_s - dt_s / 2.0, b.t_s + dt_s / 2.0, a.pitch_deg, a.roll_deg)
        })
        .collect();
    let out_flags = dir.path().join("out-flags.csv");
    let mut cmd = sinscal();
    cmd.args(["import", "columns"]).arg(&input).arg("--layout").arg(&layout_path).arg("--out").arg(&out_flags);
    for f in &flags {
        cmd.arg("--position").arg(f);
    }
    let run = cmd.output().unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert_same_rows(&Recording::read(&out_flags).unwrap().rows, &rec.rows, "--position flags", &|_, v| {
        f64::EPSILON * v.abs()
    });
    let missing = sinscal().args(["import", "columns"]).arg(&input).arg("--out").arg(&out).output().unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("--layout"));
    // A layout naming a field beyond the record: status 1 with the reason.
    let bad = write(dir.path(), "bad.toml", layout.replace("fields = 7", "fields = 5").as_bytes());
    let refused = sinscal()
        .args(["import", "columns"])
        .arg(&input)
        .arg("--layout")
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("beyond the binary record of 5 fields"));
}

#[test]
fn skip_lines_past_the_end_says_so() {
    // A layout that skips every line of the file: the message names the lines and the skip, not a field.
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "short.txt", b"t wx wy wz fx fy fz\n0 0 0 0 0 0 9.8\n");
    let layout = format!(
        "format = \"text\"\n[text]\nskip_lines = 5\n[time]\nfield = 0\nunit = \"s\"\n\
         [gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
    );
    let err = import(&[&input], &layout, None, None).expect_err("no records").to_string();
    assert!(err.contains("no records: the file has 2 lines, skip_lines skips 5"), "{err}");
}

/// The declared gyro unit against the data (the Earth rate's vertical part, and no gyro's bias above 0.2 rad/s):
/// rad/s declared as deg/s, rates declared as increments and gyro fields that hold the accelerometer's values
/// are refused, naming the mistake; the right unit passes, and the import says what it found. SIMULATION: the
/// example's navigation-grade gyros (0.1 deg/h of noise) resolve the Earth rate.
#[test]
fn gyro_units_that_contradict_the_earth_rate_are_refused_with_the_mistake() {
    let rec = session();
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for r in &rec.rows {
        let (w, f) = (r.rate_b_radps, r.force_b_mps2);
        text += &format!(
            "{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}\n",
            r.t_s, w[0], w[1], w[2], f[0], f[1], f[2], f[0], f[1], f[2]
        );
    }
    let input = write(dir.path(), "rates.txt", text.as_bytes());
    let layout = |gyro: &str| {
        format!(
            "format = \"text\"\n[time]\nfield = 0\n[gyro]\n{gyro}\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n{SITE}"
        )
    };
    let labels = labels_of(&rec);
    let right = import(&[&input], &layout("fields = [1, 2, 3]\nunit = \"rad/s\""), Some(&labels), None).unwrap();
    let note = right.summary.lines().find(|n| n.contains("gyro unit checked")).expect("the check is reported");
    println!("{note}");
    let cases = [
        ("fields = [1, 2, 3]\nunit = \"deg/s\"", "rad/s declared as deg/s"),
        ("fields = [1, 2, 3]\nunit = \"rad\"\nincrements = true", "rates declared as increments"),
        ("fields = [7, 8, 9]\nunit = \"rad/s\"", "the gyro fields read what the accelerometer fields read"),
    ];
    for (gyro, words) in cases {
        let err = import(&[&input], &layout(gyro), Some(&labels), None).unwrap_err();
        println!("{err}");
        assert!(err.contains(words), "{gyro}: {err}");
    }
}

/// REAL DATA (`SINSCAL_DATA`): the imucal Ferraris session's gyros (deg/s) declared as rad/s read 5.3 "rad/s"
/// at rest and are refused naming deg/s; declared right, they pass, and the import says that these consumer
/// gyros do not resolve the Earth rate (their unit is not checked against it).
#[test]
fn real_data_ferraris_gyros_in_deg_per_second_declared_as_rad_per_second_are_refused() {
    let Some(data) = common::data_dir() else { return };
    let csv = common::data_file(&data, "imucal-ferraris/example_ferraris_session.csv");
    let right = layout_file("imucal.toml");
    let wrong = right.replace("unit = \"deg/s\"", "unit = \"rad/s\"");
    assert_ne!(wrong, right, "the imucal layout declares deg/s");
    let err = import(&[&csv], &wrong, None, None).unwrap_err();
    assert!(err.contains("rad/s at rest") && err.contains("deg/s declared as rad/s?"), "{err}");
    let imported = import(&[&csv], &right, None, None).unwrap();
    assert!(imported.summary.contains("gyro unit not checked against the Earth rate"), "{}", imported.summary);
}
