//! `sinscal import`: the PSINS, imucal and imu_tk importers on small synthetic files (exact conversions, pose
//! mapping, error messages with line numbers, the command line) and on the real data sets in the directory named by
//! the environment variable `SINSCAL_DATA` (skipped with a message when it is not set).

use std::path::PathBuf;

mod common;

use assert_cmd::Command;
use common::{data_dir, data_file};
use sinscal_host::io::import::{
    detect_static_intervals, ferraris_pose, import_imucal, import_imucal_raw, import_imutk, import_psins,
    level_attitude_deg, parse_imucal, parse_imucal_labels, parse_imucal_raw, parse_imutk, parse_psins, position_stats,
    Imported, PositionStats, StaticDetection, FERRARIS_POSES, IMUTK_GRAVITY_MPS2,
};
use sinscal_host::io::recording::Recording;

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

fn assert_close3(what: &str, got: [f64; 3], want: [f64; 3], tol: f64) {
    for i in 0..3 {
        assert!(close(got[i], want[i], tol), "{what}[{i}]: got {:?}, want {want:?} (tolerance {tol})", got);
    }
}

/// docs/conventions.md written out: C_b^n = Rz(-psi) Rx(theta) Ry(gamma), Ra(t) right-handed about axis a.
fn c_b_n(pitch_deg: f64, roll_deg: f64, heading_deg: f64) -> [[f64; 3]; 3] {
    let (st, ct) = pitch_deg.to_radians().sin_cos();
    let (sg, cg) = roll_deg.to_radians().sin_cos();
    let (sp, cp) = (-heading_deg).to_radians().sin_cos();
    let rz = [[cp, -sp, 0.0], [sp, cp, 0.0], [0.0, 0.0, 1.0]];
    let rx = [[1.0, 0.0, 0.0], [0.0, ct, -st], [0.0, st, ct]];
    let ry = [[cg, 0.0, sg], [0.0, 1.0, 0.0], [-sg, 0.0, cg]];
    let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        let mut c = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
            }
        }
        c
    };
    mul(mul(rz, rx), ry)
}

/// The specific force a body at this attitude measures at rest: C_n^b [0, 0, g] = (C_b^n)^T [0, 0, g].
fn force_at_rest_b(pitch_deg: f64, roll_deg: f64, heading_deg: f64, g_mps2: f64) -> [f64; 3] {
    let c = c_b_n(pitch_deg, roll_deg, heading_deg);
    [c[2][0] * g_mps2, c[2][1] * g_mps2, c[2][2] * g_mps2]
}

/// The recording parses back from its CSV with the same header and the same numbers in every row.
fn assert_round_trip(rec: &Recording) -> Recording {
    let again = Recording::parse(&rec.to_csv(), "again.csv").unwrap();
    assert_eq!(again.header, rec.header);
    assert_eq!(again.rows.len(), rec.rows.len());
    for (a, b) in again.rows.iter().zip(&rec.rows) {
        assert_eq!(
            (a.t_s, a.pos, a.pitch_deg, a.roll_deg, a.heading_deg, a.rate_b_radps, a.force_b_mps2, a.temp_c),
            (b.t_s, b.pos, b.pitch_deg, b.roll_deg, b.heading_deg, b.rate_b_radps, b.force_b_mps2, b.temp_c),
            "row of input line {}",
            b.line
        );
    }
    again
}

fn comment<'a>(rec: &'a Recording, key: &str) -> &'a str {
    let prefix = format!("{key}: ");
    rec.header
        .comments
        .iter()
        .find_map(|c| c.strip_prefix(&prefix))
        .unwrap_or_else(|| panic!("no '# {key}:' header comment in {:?}", rec.header.comments))
}

// -------------------------------------------------------------------------------------------------------------
// PSINS

const PSINS: &str = "% PSINS-format SIMU log file.\n\
% 1st line: pitch roll yaw VE VN VU\n\
\n\
0.5 -1.0 -90.6 0 0 0\n\
34.0 108.0 380.0 0.0 10.0 9.780327\n\
0.1 0.2 0.1 125 125 100\n\
2 -3 0 80 0 -80\n\
0 0 7 0 1 80\n\
-5 9 3 0 0 80\n";

#[test]
fn psins_counts_convert_exactly() {
    let Imported { recording: rec, summary } = parse_psins(PSINS, "p.imu", None).unwrap();
    assert_eq!(rec.rows.len(), 3);
    let h = &rec.header;
    assert_eq!((h.latitude_deg, h.height_m, h.rate_hz, h.gravity_mps2), (34.0, 380.0, Some(100.0), Some(9.780327)));
    assert_eq!(comment(&rec, "source"), "p.imu");
    assert!(comment(&rec, "source_format").starts_with("PSINS .imu"));
    let r = &rec.rows[0];
    assert_eq!((r.t_s, r.pos, r.pitch_deg, r.roll_deg, r.line), (0.0, 1, 0.5, -1.0, 7));
    // PSINS yaw -90.6 deg (positive west) is heading 90.6 deg (clockwise from north).
    assert!(close(r.heading_deg.unwrap(), 90.6, 1e-12));
    // 2 counts of 0.1 arcsec in 10 ms = 20 arcsec/s; -3 counts of 0.2 arcsec = -60 arcsec/s.
    let arcsec_per_s = |v: f64| v / 3600.0 * std::f64::consts::PI / 180.0;
    assert!(close(r.rate_b_radps[0], arcsec_per_s(20.0), 1e-18), "{:?}", r.rate_b_radps);
    assert!(close(r.rate_b_radps[1], arcsec_per_s(-60.0), 1e-18));
    assert_eq!(r.rate_b_radps[2], 0.0);
    // 80 counts of 125 ug*s in 10 ms = 1 g of the file; -80 counts of 100 ug*s = -0.8 g.
    assert!(close(r.force_b_mps2[0], 9.780327, 1e-12), "{:?}", r.force_b_mps2);
    assert_eq!(r.force_b_mps2[1], 0.0);
    assert!(close(r.force_b_mps2[2], -0.8 * 9.780327, 1e-12));
    assert!(close(rec.rows[1].force_b_mps2[1], 125e-6 * 9.780327 / 0.01, 1e-15));
    assert!(close(rec.rows[2].t_s, 0.02, 1e-15));
    assert!(summary.contains("3 samples at 100 Hz"), "{summary}");
    assert_round_trip(&rec);

    // --latitude-deg overrides the file's latitude and says so.
    let rec = parse_psins(PSINS, "p.imu", Some(-33.5)).unwrap().recording;
    assert_eq!(rec.header.latitude_deg, -33.5);
    assert!(comment(&rec, "latitude_source").contains("command line"));
}

#[test]
fn psins_yaw_becomes_a_heading_in_0_to_360() {
    for (yaw_deg, heading_deg) in [(0.0, 0.0), (10.0, 350.0), (-370.0, 10.0), (180.0, 180.0), (-90.6, 90.6)] {
        let text = PSINS.replace("0.5 -1.0 -90.6", &format!("0.5 -1.0 {yaw_deg}"));
        let rec = parse_psins(&text, "p.imu", None).unwrap().recording;
        let h = rec.rows[0].heading_deg.unwrap();
        assert!(close(h, heading_deg, 1e-9) && (0.0..360.0).contains(&h), "yaw {yaw_deg}: heading {h}");
        assert!(h.is_sign_positive(), "yaw {yaw_deg}: heading {h} is -0");
    }
}

#[test]
fn psins_bad_lines_name_file_line_and_reason() {
    let err = |text: &str| parse_psins(text, "p.imu", None).unwrap_err().to_string();
    assert_eq!(
        err(&PSINS.replace("0 0 7 0 1 80", "0 0 7 0 1")),
        "p.imu:8: expected 6 integer counts (gyro x y z, accel x y z), found 5 fields"
    );
    assert_eq!(err(&PSINS.replace("-5 9 3", "-5 9.5 3")), "p.imu:9: '9.5' is not an integer count");
    assert!(err(&PSINS.replace("9.780327\n", "12.0\n")).starts_with("p.imu:5: g 12 m/s^2 is not a gravity"));
    assert!(err(&PSINS.replace("34.0 108.0", "95.0 108.0")).starts_with("p.imu:5: latitude 95 deg"));
    assert!(err(&PSINS.replace(" 10.0 9.78", " 0 9.78")).starts_with("p.imu:5: sampling interval 0 ms"));
    assert_eq!(
        err(&PSINS.replace("0.1 0.2 0.1 125", "0.1 0.2 x 125")),
        "p.imu:6: scale (gyro arcsec x y z, accel ug*s x y z): 'x' is not a finite number"
    );
    assert!(err(&PSINS.replace("0.5 -1.0 -90.6 0 0 0", "0.5 -1.0")).starts_with("p.imu:4: attitude"));
    let header_only: String = PSINS.lines().take(6).map(|l| format!("{l}\n")).collect();
    assert_eq!(err(&header_only), "p.imu:6: no data lines after the three header lines");
    assert!(err("% only a comment\n").contains("end of file before the attitude"));
}

// -------------------------------------------------------------------------------------------------------------
// imucal

#[test]
fn ferraris_labels_follow_the_spec_rotation() {
    // The check value of docs/conventions.md#attitude: (pitch 0, roll 90, heading 0) has body x pointing down.
    let c = c_b_n(0.0, 90.0, 0.0);
    assert!(close(c[2][0], -1.0, 1e-15), "{c:?}");
    let g_mps2 = 9.8;
    let expected_up = [
        ("x_p", [g_mps2, 0.0, 0.0]),
        ("x_a", [-g_mps2, 0.0, 0.0]),
        ("y_p", [0.0, g_mps2, 0.0]),
        ("y_a", [0.0, -g_mps2, 0.0]),
        ("z_p", [0.0, 0.0, g_mps2]),
        ("z_a", [0.0, 0.0, -g_mps2]),
    ];
    for (label, force) in expected_up {
        let pose = ferraris_pose(label).unwrap();
        for heading_deg in [0.0, 37.0, 270.0] {
            let f = force_at_rest_b(pose.pitch_deg, pose.roll_deg, heading_deg, g_mps2);
            assert_close3(&format!("{label} at heading {heading_deg}"), f, force, 1e-12);
        }
    }
    assert_eq!(FERRARIS_POSES.map(|p| p.pos), [1, 2, 3, 4, 5, 6]);
    assert!(ferraris_pose("x_rot").is_none());

    // Levelling inverts the rotation for any attitude away from pitch +-90.
    for (pitch_deg, roll_deg) in [(0.0, 0.0), (10.0, -20.0), (-45.0, 135.0), (30.0, 180.0), (5.0, -90.0)] {
        let f = force_at_rest_b(pitch_deg, roll_deg, 123.0, 9.8);
        let (p, r) = level_attitude_deg(f).unwrap();
        assert!(close(p, pitch_deg, 1e-9) && close(r, roll_deg, 1e-9), "({pitch_deg}, {roll_deg}) -> ({p}, {r})");
    }
    assert_eq!(level_attitude_deg([0.0, 0.0, 0.0]), None);
}

/// A 30-sample Ferraris session: gyro 1, -2, 0.5 deg/s, accel of the labelled pose (or 0.1, 0.2, 0.3 elsewhere).
fn ferraris_csv() -> String {
    let mut text = String::from("n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n");
    for n in 0..30 {
        let accel = match n {
            2..=3 => "9.8,0,0",
            5..=6 => "-9.8,0,0",
            8..=9 => "0,9.8,0",
            11..=12 => "0,-9.8,0",
            14..=15 => "0,0,9.8",
            17..=18 => "0,0,-9.8",
            _ => "0.1,0.2,0.3",
        };
        text.push_str(&format!("{n},1,-2,0.5,{accel}\n"));
    }
    text
}

const FERRARIS_LABELS: &str = "{\n\
  \"x_p\": {\"start\": 2, \"end\": 4},\n\
  \"x_a\": {\"start\": 5, \"end\": 7},\n\
  \"y_p\": {\"start\": 8, \"end\": 10},\n\
  \"y_a\": [11, 13],\n\
  \"z_p\": {\"start\": 14, \"end\": 16},\n\
  \"z_a\": {\"start\": 17, \"end\": 19},\n\
  \"x_rot\": {\"start\": 20, \"end\": 25}\n\
}\n";

#[test]
fn ferraris_session_rows_get_positions_and_attitudes_of_their_labels() {
    let Imported { recording: rec, summary } =
        parse_imucal(&ferraris_csv(), "s.csv", FERRARIS_LABELS, "s_list.json", None).unwrap();
    assert_eq!(rec.rows.len(), 30);
    assert_eq!(rec.header.latitude_deg, 49.6);
    assert_eq!(comment(&rec, "latitude_source"), "inferred (Erlangen)");
    assert!(summary.contains("inferred"), "{summary}");
    assert_eq!(rec.header.rate_hz, Some(102.4));
    assert_eq!(rec.header.gravity_mps2, None);
    let pos: Vec<u32> = rec.rows.iter().map(|r| r.pos).collect();
    assert_eq!(pos, [0, 0, 1, 1, 0, 2, 2, 0, 3, 3, 0, 4, 4, 0, 5, 5, 0, 6, 6, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    // The turn label's rows [20, 25) carry its axis in the `turn` column; no other row has one.
    let turns: Vec<Option<usize>> = rec.rows.iter().map(|r| r.turn_axis).collect();
    assert_eq!(turns, (0..30).map(|n| (20..25).contains(&n).then_some(0)).collect::<Vec<_>>());
    let r = &rec.rows[3];
    assert_eq!((r.t_s, r.pitch_deg, r.roll_deg, r.heading_deg, r.line), (3.0 / 102.4, 0.0, -90.0, None, 5));
    assert_eq!(r.rate_b_radps, [1f64.to_radians(), (-2f64).to_radians(), 0.5f64.to_radians()]);
    assert_eq!(r.force_b_mps2, [9.8, 0.0, 0.0]);
    assert!(rec.rows.iter().all(|r| r.heading_deg.is_none()));
    // Every labelled row's accelerometer agrees with the rotation of [0, 0, g] by its pose.
    for r in rec.rows.iter().filter(|r| r.pos != 0) {
        let f = force_at_rest_b(r.pitch_deg, r.roll_deg, 0.0, 9.8);
        assert_close3(&format!("pos {}", r.pos), r.force_b_mps2, f, 1e-12);
    }
    let stats = position_stats(&rec);
    assert_eq!(
        stats.iter().map(|s| (s.pos, s.samples)).collect::<Vec<_>>(),
        [(1, 2), (2, 2), (3, 2), (4, 2), (5, 2), (6, 2)]
    );
    assert_round_trip(&rec);

    let rec = parse_imucal(&ferraris_csv(), "s.csv", FERRARIS_LABELS, "s_list.json", Some(10.0)).unwrap().recording;
    assert_eq!(rec.header.latitude_deg, 10.0);
    assert!(comment(&rec, "latitude_source").contains("command line"));
}

#[test]
fn ferraris_bad_input_names_file_line_and_reason() {
    let csv = ferraris_csv();
    let err =
        |csv: &str, labels: &str| parse_imucal(csv, "s.csv", labels, "s_list.json", None).unwrap_err().to_string();
    assert_eq!(
        err(&csv.replace("\n4,1,-2", "\n4,1,x"), FERRARIS_LABELS),
        "s.csv:6: column 'gyr_y': 'x' is not a finite number"
    );
    assert_eq!(
        err(&csv.replace("\n4,1,-2,0.5,", "\n4,1,-2,"), FERRARIS_LABELS),
        "s.csv:6: 6 cells, the column line has 7"
    );
    assert!(
        err(&csv.replace("\n5,1", "\n3,1"), FERRARIS_LABELS).starts_with("s.csv:7: sample index 3 does not increase")
    );
    assert_eq!(err(&csv.replace(",acc_z", ",acc_q"), FERRARIS_LABELS), "s.csv:1: missing column 'acc_z'");
    // Label file problems: JSON syntax, missing, overlapping, reversed and unknown labels.
    assert!(err(&csv, &FERRARIS_LABELS.replace("\"y_p\": {", "\"y_p\" {")).starts_with("s_list.json:4: not valid JSON"));
    assert_eq!(
        err(&csv, &FERRARIS_LABELS.replace("\"z_a\": {\"start\": 17, \"end\": 19},\n", "")),
        "s_list.json: label 'z_a' (body -z up) is missing"
    );
    assert!(err(&csv, &FERRARIS_LABELS.replace("\"start\": 14", "\"start\": 12")).starts_with("s_list.json:"));
    assert!(err(&csv, &FERRARIS_LABELS.replace("\"start\": 14", "\"start\": 12")).contains("overlap"));
    assert_eq!(
        err(&csv, &FERRARIS_LABELS.replace("\"start\": 8, \"end\": 10", "\"start\": 10, \"end\": 8")),
        "s_list.json:4: label 'y_p': start 10 is not below end 8"
    );
    assert!(err(&csv, &FERRARIS_LABELS.replace("x_rot", "w_rot")).starts_with("s_list.json:8: unknown label 'w_rot'"));
    assert!(err(&csv, &FERRARIS_LABELS.replace("\"start\": 17, \"end\": 19", "\"start\": 40, \"end\": 50"))
        .starts_with("s_list.json:7: label 'z_a' [40, 50) reaches past the samples of s.csv (0..29)"));
    // An end past the data is not clipped to it, and a label given twice is not read as its last value.
    assert!(err(&csv, &FERRARIS_LABELS.replace("\"start\": 20, \"end\": 25", "\"start\": 20, \"end\": 31"))
        .starts_with("s_list.json:8: label 'x_rot' [20, 31) reaches past the samples"));
    let twice = FERRARIS_LABELS.replace("\"x_rot\"", "\"x_p\": {\"start\": 2, \"end\": 3},\n  \"x_rot\"");
    let e = err(&csv, &twice);
    assert!(e.starts_with("s_list.json:") && e.contains("key 'x_p' appears twice"), "{e}");
    assert!(parse_imucal_labels("[1, 2]", "l.json")
        .unwrap_err()
        .to_string()
        .starts_with("l.json:1: expected a JSON object"));
}

/// An annotated session in raw counts, its rows grouped by label as imucal writes them (not in time order).
const RAW: &str = "part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n\
x_a,3,-2048.0,0,0,16.4,-32.8,0\n\
x_a,4,-2048.0,0,0,16.4,-32.8,0\n\
x_p,0,2048.0,0,0,0,0,8.2\n\
x_p,1,2048,0,0,0,0,8.2\n\
x_rot,2,0,1024,0,1640,0,0\n\
y_a,5,0,-2048,0,0,0,0\n\
y_p,6,0,2048,0,0,0,0\n\
z_a,7,0,0,-2048,0,0,0\n\
z_p,8,0,0,2048,0,0,0\n";

#[test]
fn imucal_raw_counts_convert_with_the_nominal_scales_and_rows_are_sorted_in_time() {
    let Imported { recording: rec, summary } = parse_imucal_raw(RAW, "a.csv", None).unwrap();
    assert!(summary.contains("2048 LSB/g") && summary.contains("16.4 LSB/(deg/s)"), "{summary}");
    assert!(comment(&rec, "scale").contains("2048 LSB/g"));
    assert_eq!(rec.header.rate_hz, Some(204.8));
    let order: Vec<(f64, u32, usize)> = rec.rows.iter().map(|r| (r.t_s * 204.8, r.pos, r.line)).collect();
    assert_eq!(
        order.iter().map(|o| (o.0.round() as u32, o.1, o.2)).collect::<Vec<_>>(),
        [(0, 1, 4), (1, 1, 5), (2, 0, 6), (3, 2, 2), (4, 2, 3), (5, 4, 7), (6, 3, 8), (7, 6, 9), (8, 5, 10)]
    );
    let x_a = &rec.rows[3];
    assert_eq!((x_a.t_s, x_a.roll_deg), (3.0 / 204.8, 90.0));
    assert!(close(x_a.force_b_mps2[0], -9.80665, 1e-12), "{:?}", x_a.force_b_mps2);
    assert!(close(x_a.rate_b_radps[0], 1f64.to_radians(), 1e-15));
    assert!(close(x_a.rate_b_radps[1], (-2f64).to_radians(), 1e-15));
    assert!(close(rec.rows[0].rate_b_radps[2], 0.5f64.to_radians(), 1e-15));
    for r in rec.rows.iter().filter(|r| r.pos != 0) {
        let f = force_at_rest_b(r.pitch_deg, r.roll_deg, 0.0, 9.80665);
        assert_close3(&format!("pos {}", r.pos), r.force_b_mps2, f, 1e-12);
    }
    assert_round_trip(&rec);

    let err = |text: &str| parse_imucal_raw(text, "a.csv", None).unwrap_err().to_string();
    assert!(err(&RAW.replace("y_a,5", "w_a,5")).starts_with("a.csv:7: unknown label 'w_a'"));
    assert_eq!(err(&RAW.replace("y_p,6", "y_p,4")), "a.csv:8: sample index 4 repeats (first on line 3)");
    assert_eq!(err(&RAW.replace("z_a,7", "z_a,-7")), "a.csv:9: column 'samples': '-7' is not a sample index");
    assert_eq!(err(&RAW.replace("0,0,-2048,0", "0,0,nan,0")), "a.csv:9: column 'acc_z': 'nan' is not a finite number");
}

// -------------------------------------------------------------------------------------------------------------
// imu_tk

/// Synthetic imu_tk files at 100 Hz: static z up (0-8 s), moving, static x up (10-15 s), moving, static y up for
/// only 2 s (17-19 s), moving, static y down (21-26 s). Accelerometer counts of 1 g = 4074 (9.8169 m/s^2), a
/// +-1 count dither on every axis; gyro counts: x 1 rad/s, y -0.5 rad/s, z 0 throughout.
fn imutk_files() -> (String, String) {
    let mut acc = String::new();
    let mut gyro = String::new();
    for k in 0..2600u32 {
        let t_s = 0.03 + f64::from(k) * 0.01;
        let s = f64::from(k) / 100.0;
        let one_g = 4074.0;
        let (mut x, mut y, mut z) = match s {
            s if s < 8.0 => (0.0, 0.0, one_g),
            s if (10.0..15.0).contains(&s) => (one_g, 0.0, 0.0),
            s if (17.0..19.0).contains(&s) => (0.0, one_g, 0.0),
            s if s >= 21.0 => (0.0, -one_g, 0.0),
            _ => {
                let phase = f64::from(k) * 0.2;
                (1500.0 * phase.sin(), 1500.0 * phase.cos(), one_g - 800.0)
            }
        };
        let dither = if k % 2 == 0 { 1.0 } else { -1.0 };
        x += dither;
        y -= dither;
        z += dither;
        let c = |v: f64| 32768.0 + v.round();
        acc.push_str(&format!("   {t_s:.7e}   {:.7e}   {:.7e}   {:.7e}\n", c(x), c(y), c(z)));
        gyro.push_str(&format!(
            "   {t_s:.7e}   {:.7e}   {:.7e}   {:.7e}\n",
            32768.0 + 4778.0,
            32768.0 - 2379.0,
            32768.0
        ));
    }
    (acc, gyro)
}

fn short_detection() -> StaticDetection {
    StaticDetection { init_static_s: 5.0, ..StaticDetection::default() }
}

#[test]
fn imutk_static_intervals_become_levelled_positions() {
    let (acc, gyro) = imutk_files();
    let Imported { recording: rec, summary } =
        parse_imutk(&acc, "acc.mat", &gyro, "gyro.mat", None, &short_detection()).unwrap();
    assert_eq!(rec.rows.len(), 2600);
    assert_eq!(rec.header.rate_hz, Some(100.0));
    assert_eq!(rec.header.gravity_mps2, Some(IMUTK_GRAVITY_MPS2));
    assert_eq!(rec.header.latitude_deg, 45.0);
    assert!(comment(&rec, "latitude_source").contains("unknown"));
    assert_eq!(comment(&rec, "attitude_source"), "accelerometer-levelled");
    assert!(comment(&rec, "scale").contains("nominal factory gains"));
    assert!(summary.contains("3 position(s)"), "{summary}");
    // Exact conversions: 4778 gyro counts are 1 rad/s on x, -2379 counts -0.5 rad/s on y.
    let r = &rec.rows[0];
    assert_eq!(r.rate_b_radps, [1.0, -0.5, 0.0]);
    assert_eq!(r.force_b_mps2, [1.0 / 415.0, -1.0 / 413.0, 4075.0 / 415.0]);
    assert_eq!((r.t_s, r.line, r.heading_deg), (0.03, 1, None));

    let stats = position_stats(&rec);
    let summary_of = |s: &PositionStats| (s.pos, s.samples, s.first_t_s, s.pitch_deg, s.roll_deg);
    assert_eq!(stats.len(), 3, "{:?}", stats.iter().map(summary_of).collect::<Vec<_>>());
    // The centred 1 s window trims up to half a window at the moving ends, nothing at the record's ends.
    let expect = [(0.03, 750..=800, 0.0, 0.0), (10.03, 400..=500, 0.0, -90.0), (21.03, 450..=500, -90.0, 0.0)];
    for (s, (first_t_s, samples, pitch_deg, roll_deg)) in stats.iter().zip(expect) {
        assert!(close(s.first_t_s, first_t_s, 0.6), "{:?}", summary_of(s));
        assert!(samples.contains(&s.samples), "{:?}", summary_of(s));
        assert!(close(s.pitch_deg, pitch_deg, 0.1), "{:?}", summary_of(s));
        // At pitch -90 the roll is not defined; elsewhere it must match.
        if pitch_deg.abs() < 89.0 {
            assert!(close(s.roll_deg, roll_deg, 0.1), "{:?}", summary_of(s));
        }
    }
    assert_eq!(stats[0].first_t_s, 0.03);
    assert!(rec.rows.iter().filter(|r| r.pos == 0).all(|r| r.heading_deg.is_none()));
    assert_round_trip(&rec);
}

#[test]
fn static_detection_works_on_noiseless_data() {
    // Constant input: variance 0 everywhere; the quantisation floor keeps the threshold positive.
    let force = vec![[0.0, 0.0, 9.8]; 1000];
    let t_s: Vec<f64> = (0..1000).map(|k| f64::from(k) * 0.01).collect();
    let found = detect_static_intervals(&force, &t_s, 100.0, &short_detection(), 1e-6).unwrap();
    assert_eq!(found.ranges, vec![0..1000usize]);
    assert_eq!((found.half_window_samples, found.min_samples), (50, 300));
    let e = detect_static_intervals(&force[..100], &t_s[..100], 100.0, &short_detection(), 1e-6).unwrap_err();
    assert!(e.contains("shorter than the initial static period"), "{e}");
}

#[test]
fn imutk_bad_input_names_file_line_and_reason() {
    let (acc, gyro) = imutk_files();
    let err = |acc: &str, gyro: &str| {
        parse_imutk(acc, "acc.mat", gyro, "gyro.mat", None, &short_detection()).unwrap_err().to_string()
    };
    let replace_line = |text: &str, line: usize, with: &str| -> String {
        text.lines()
            .enumerate()
            .map(|(i, l)| if i + 1 == line { format!("{with}\n") } else { format!("{l}\n") })
            .collect()
    };
    assert_eq!(
        err(&replace_line(&acc, 7, "0.09 1 2"), &gyro),
        "acc.mat:7: sample line (t_s x y z): expected 4 numbers, found 3"
    );
    assert_eq!(
        err(&acc, &replace_line(&gyro, 9, "0.11 70000 32768 32768")),
        "gyro.mat:9: count 70000 is outside the unsigned 16-bit range 0..65535"
    );
    assert_eq!(
        err(&acc, &replace_line(&gyro, 9, "0.115 32768 32768 32768")),
        "gyro.mat:9: time 0.115 s differs from the accelerometer's 0.11 s at the same sample"
    );
    assert_eq!(
        err(&replace_line(&acc, 3, "0.03 32768 32768 32768"), &gyro),
        "acc.mat:3: time 0.03 s does not increase (previous sample: 0.04 s)"
    );
    let shorter: String = gyro.lines().take(2000).map(|l| format!("{l}\n")).collect();
    assert_eq!(err(&acc, &shorter), "gyro.mat: 2000 samples, the accelerometer file acc.mat has 2600");
    assert!(
        err(&acc, &replace_line(&gyro, 5, "0.07 x 1 2")).starts_with("gyro.mat:5: sample line (t_s x y z): 'x' is not")
    );
    let short_acc: String = acc.lines().take(300).map(|l| format!("{l}\n")).collect();
    let short_gyro: String = gyro.lines().take(300).map(|l| format!("{l}\n")).collect();
    assert!(err(&short_acc, &short_gyro).starts_with("acc.mat: the record lasts 2.99 s, shorter than the initial"));
}

// -------------------------------------------------------------------------------------------------------------
// Command line

#[test]
fn cli_imports_psins_and_reports_bad_input_and_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(&dir, "p.imu", PSINS);
    let out = dir.path().join("p.csv");
    let run = sinscal().args(["import", "psins"]).arg(&input).arg("--out").arg(&out).assert().success();
    let stdout = String::from_utf8(run.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("3 samples at 100 Hz"), "{stdout}");
    assert!(stdout.contains("1 position(s)") && stdout.contains("mean gyro") && stdout.contains("wrote"), "{stdout}");
    let rec = Recording::read(&out).unwrap();
    assert_eq!(rec.rows.len(), 3);
    assert_eq!(rec.header.latitude_deg, 34.0);
    assert_eq!(rec.rows[0].force_b_mps2, parse_psins(PSINS, "x", None).unwrap().recording.rows[0].force_b_mps2);

    // Bad input: exit 1, one line naming file and line.
    let bad = write(&dir, "bad.imu", &PSINS.replace("0 0 7 0 1 80", "0 0 7 0 1 x"));
    let run = sinscal().args(["import", "psins"]).arg(&bad).arg("--out").arg(&out).assert().code(1);
    let stderr = String::from_utf8(run.get_output().stderr.clone()).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("bad.imu:8: 'x' is not an integer count"), "{stderr}");

    // Usage errors: exit 2.
    let run = sinscal().args(["import", "matlab"]).arg(&input).arg("--out").arg(&out).assert().code(2);
    let stderr = String::from_utf8(run.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("invalid value 'matlab'") && stderr.contains("imutk"), "{stderr}");
    let run = sinscal().args(["import", "imutk"]).arg(&input).arg("--out").arg(&out).assert().code(2);
    let stderr = String::from_utf8(run.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("imutk needs two inputs"), "{stderr}");
    sinscal().args(["import", "psins"]).arg(&input).assert().code(2);
    sinscal()
        .args(["import", "psins"])
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .args(["--latitude-deg", "91"])
        .assert()
        .code(2);
    // A negative latitude is a value, not an option.
    sinscal()
        .args(["import", "psins"])
        .arg(&input)
        .arg("--out")
        .arg(&out)
        .args(["--latitude-deg", "-33.9"])
        .assert()
        .success();
    assert_eq!(Recording::read(&out).unwrap().header.latitude_deg, -33.9);
}

#[test]
fn cli_imucal_finds_the_label_file_beside_the_session() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(&dir, "s.csv", &ferraris_csv());
    write(&dir, "s_list.json", FERRARIS_LABELS);
    let out = dir.path().join("r.csv");
    let run = sinscal().args(["import", "imucal"]).arg(&input).arg("--out").arg(&out).assert().success();
    let stdout = String::from_utf8(run.get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("6 position(s)") && stdout.contains("inferred"), "{stdout}");
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("# latitude_source: inferred (Erlangen)\n"), "{text}");
    // Without the label file: exit 1 naming it.
    std::fs::remove_file(dir.path().join("s_list.json")).unwrap();
    let run = sinscal().args(["import", "imucal"]).arg(&input).arg("--out").arg(&out).assert().code(1);
    let stderr = String::from_utf8(run.get_output().stderr.clone()).unwrap();
    assert!(stderr.contains("s_list.json"), "{stderr}");
}

// -------------------------------------------------------------------------------------------------------------
// Real data (SINSCAL_DATA)

fn print_stats(name: &str, rec: &Recording) {
    for s in position_stats(rec) {
        eprintln!(
            "{name}: pos {:>2} samples {:>6} from {:>8.2} s for {:>7.2} s, pitch {:>7.2} roll {:>8.2}, gyro [deg/s] \
             {:+.4} {:+.4} {:+.4}, accel [m/s^2] {:+.4} {:+.4} {:+.4}",
            s.pos,
            s.samples,
            s.first_t_s,
            s.last_t_s - s.first_t_s,
            s.pitch_deg,
            s.roll_deg,
            s.mean_rate_b_radps[0].to_degrees(),
            s.mean_rate_b_radps[1].to_degrees(),
            s.mean_rate_b_radps[2].to_degrees(),
            s.mean_force_b_mps2[0],
            s.mean_force_b_mps2[1],
            s.mean_force_b_mps2[2]
        );
    }
}

#[test]
fn real_psins_lasergyro_matches_provenance() {
    let Some(dir) = data_dir() else { return };
    let path = data_file(&dir, "psins-lasergyro/lasergyro.imu");
    let rec = import_psins(&path, None).unwrap().recording;
    let h = &rec.header;
    assert_eq!(
        (h.latitude_deg, h.height_m, h.rate_hz, h.gravity_mps2),
        (34.246048, 380.0, Some(100.0), Some(9.780327))
    );
    assert_eq!(rec.rows.len(), 184_718);
    let stats = position_stats(&rec);
    assert_eq!(stats.len(), 1);
    let s = &stats[0];
    assert!(close(s.heading_deg.unwrap(), 90.6, 1e-9));
    eprintln!(
        "psins: {} samples, {:.2} s, mean rate [rad/s] {:.3e} {:.3e} {:.3e}, mean force [m/s^2] {:.4} {:.4} {:.4}",
        s.samples,
        s.last_t_s - s.first_t_s,
        s.mean_rate_b_radps[0],
        s.mean_rate_b_radps[1],
        s.mean_rate_b_radps[2],
        s.mean_force_b_mps2[0],
        s.mean_force_b_mps2[1],
        s.mean_force_b_mps2[2]
    );
    // docs/data.md#psins-lasergyro: mean rate [-5.95e-05, 2.12e-06, 4.05e-05] rad/s, mean force [-0.061, 0.158, 9.794] m/s^2.
    assert_close3("mean rate", s.mean_rate_b_radps, [-5.95e-05, 2.12e-06, 4.05e-05], 0.01 * 5.95e-5);
    assert_close3("mean force", s.mean_force_b_mps2, [-0.061, 0.158, 9.794], 0.01 * 9.794);
    assert_close3("mean force (3 decimals)", s.mean_force_b_mps2, [-0.061, 0.158, 9.794], 0.001);
    assert_round_trip(&rec);
}

#[test]
fn real_imucal_ferraris_session_matches_provenance_and_reaches_calibrate() {
    let Some(dir) = data_dir() else { return };
    let csv = data_file(&dir, "imucal-ferraris/example_ferraris_session.csv");
    data_file(&dir, "imucal-ferraris/example_ferraris_session_list.json");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("ferraris.csv");
    // Through the command line, with the label file found beside the session.
    sinscal().args(["import", "imucal"]).arg(&csv).arg("--out").arg(&out).assert().success();
    let rec = Recording::read(&out).unwrap();
    assert_eq!(rec.rows.len(), 10_376);
    print_stats("imucal", &rec);
    // docs/data.md#imucal-ferraris, the per-pose table: label, n, acc mean [m/s^2], gyr mean [deg/s] (printed to 3 decimals).
    let table: [(&str, usize, [f64; 3], [f64; 3]); 6] = [
        ("x_p", 731, [10.314, -0.547, 0.508], [-0.593, -0.367, 0.059]),
        ("x_a", 741, [-9.240, -0.715, 0.240], [-0.601, -0.375, 0.057]),
        ("y_p", 484, [0.394, 9.217, 0.404], [-0.608, -0.365, 0.059]),
        ("y_a", 412, [0.684, -10.450, 0.364], [-0.599, -0.375, 0.061]),
        ("z_p", 453, [0.504, -0.594, 10.437], [-0.600, -0.362, 0.061]),
        ("z_a", 607, [0.651, -0.630, -9.640], [-0.599, -0.374, 0.056]),
    ];
    let stats = position_stats(&rec);
    assert_eq!(stats.len(), 6);
    for (label, n, acc_mps2, gyr_degps) in table {
        let pose = ferraris_pose(label).unwrap();
        let s = stats.iter().find(|s| s.pos == pose.pos).unwrap();
        assert_eq!((s.samples, s.pitch_deg, s.roll_deg, s.heading_deg), (n, pose.pitch_deg, pose.roll_deg, None));
        assert_close3(&format!("{label} accel"), s.mean_force_b_mps2, acc_mps2, 0.0015);
        assert_close3(&format!("{label} gyro"), s.mean_rate_b_radps.map(f64::to_degrees), gyr_degps, 0.0015);
        // The measured gravity lies along the pose's up axis.
        let f = force_at_rest_b(pose.pitch_deg, pose.roll_deg, 0.0, 1.0);
        let along: f64 = (0..3).map(|i| f[i] * s.mean_force_b_mps2[i]).sum();
        assert!(along > 9.0, "{label}: {along}");
    }
    assert!(comment(&rec, "latitude_source").contains("inferred"));
    // The three labelled turns, x, y and z in that order, each one run of rows in the `turn` column.
    let starts = rec.rows.windows(2).filter(|w| w[1].turn_axis.is_some() && w[0].turn_axis != w[1].turn_axis);
    let axes: Vec<usize> = starts.filter_map(|w| w[1].turn_axis).collect();
    assert_eq!(axes, [0, 1, 2], "the turns x_rot, y_rot, z_rot");
    println!("imucal: {} rows in the three labelled turns", rec.rows.iter().filter(|r| r.turn_axis.is_some()).count());
    // The library import gives the same recording as the file the command line wrote.
    let direct =
        import_imucal(&csv, &dir.join("imucal-ferraris/example_ferraris_session_list.json"), None).unwrap().recording;
    assert_eq!(
        assert_round_trip(&direct).rows.iter().map(|r| r.force_b_mps2).collect::<Vec<_>>(),
        rec.rows.iter().map(|r| r.force_b_mps2).collect::<Vec<_>>()
    );

    // `sinscal calibrate` reads it; the headings are unknown, which the calibration may refuse, but only with a
    // one-line reason and exit status 1, never a crash; or its result may fail its checks (exit 3, one line per
    // failed check: the MEMS session misfits the bias and scale-factor model).
    let run = sinscal().arg("calibrate").arg(&out).output().unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    eprintln!("imucal: sinscal calibrate exit {:?}: {}", run.status.code(), stderr.trim());
    match run.status.code() {
        Some(0) => {}
        Some(1) => {
            assert_eq!(stderr.lines().count(), 1, "{stderr}");
            assert!(!stderr.contains("panicked"), "{stderr}");
        }
        Some(3) => {
            assert!(stderr.lines().all(|l| l.starts_with("sinscal: check failed: ")), "{stderr}");
            assert!(stderr.contains("sinscal: check failed: fit: the residuals are "), "{stderr}");
        }
        other => panic!("sinscal calibrate exit {other:?}: {stderr}"),
    }
}

#[test]
fn real_imucal_annotated_session_imports_with_nominal_scales() {
    let Some(dir) = data_dir() else { return };
    let path = data_file(&dir, "imucal-ferraris/annotated_session.csv");
    let Imported { recording: rec, summary } = import_imucal_raw(&path, None).unwrap();
    assert_eq!(rec.rows.len(), 9_414);
    assert!(summary.contains("2048 LSB/g"));
    print_stats("imucal-raw", &rec);
    let stats = position_stats(&rec);
    let counts: Vec<(u32, usize)> = stats.iter().map(|s| (s.pos, s.samples)).collect();
    assert_eq!(counts, [(1, 1028), (2, 1061), (3, 734), (4, 848), (5, 881), (6, 1044)]);
    for s in &stats {
        let f = force_at_rest_b(s.pitch_deg, s.roll_deg, 0.0, 1.0);
        let along: f64 = (0..3).map(|i| f[i] * s.mean_force_b_mps2[i]).sum();
        let norm = s.mean_force_b_mps2.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(along > 9.0 && close(norm, 9.81, 0.5), "pos {}: along {along}, norm {norm}", s.pos);
    }
    assert_round_trip(&rec);
}

#[test]
fn real_imutk_xsens_static_detection_finds_the_poses() {
    let Some(dir) = data_dir() else { return };
    let acc = data_file(&dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = data_file(&dir, "imu-tk-xsens/xsens_gyro.mat");
    let rec = import_imutk(&acc, &gyro, None, &StaticDetection::default()).unwrap().recording;
    assert_eq!(rec.rows.len(), 51_175);
    assert_eq!(rec.header.rate_hz, Some(100.0));
    assert_eq!(rec.header.gravity_mps2, Some(9.81744));
    assert_eq!(comment(&rec, "attitude_source"), "accelerometer-levelled");
    print_stats("imutk", &rec);
    let stats = position_stats(&rec);
    let first = &stats[0];
    let first_s = first.last_t_s - first.first_t_s;
    eprintln!(
        "imutk: {} samples, {} static poses, first pose {:.2} s from {:.2} s ({} samples)",
        rec.rows.len(),
        stats.len(),
        first_s,
        first.first_t_s,
        first.samples
    );
    assert!((35..=45).contains(&stats.len()), "{} static poses", stats.len());
    // docs/data.md#imu-tk-xsens: about 50 s static at the start (the first 51.7 s are z up).
    assert!(first.first_t_s < 0.1 && (48.0..=53.0).contains(&first_s), "first pose {first_s} s");
    let f = first.mean_force_b_mps2;
    assert!(f[2] > 8.0 && f[2].abs() > 5.0 * f[0].abs().max(f[1].abs()), "first pose force {f:?}");
    assert!(first.pitch_deg.abs() < 15.0 && first.roll_deg.abs() < 15.0);
    assert!(stats.iter().all(|s| s.samples >= 300 && s.heading_deg.is_none()));
    assert_round_trip(&rec);
}

#[test]
fn imutk_files_swapped_are_refused_as_swapped() {
    // The gyro file given as the accelerometer's: its median |f| at the accelerometer's gains is not g, the other
    // file's is. Both said; and a file that is neither is refused with its median |f|.
    let (acc, gyro) = imutk_files();
    let err = parse_imutk(&gyro, "gyro.mat", &acc, "acc.mat", None, &short_detection()).unwrap_err().to_string();
    assert!(err.starts_with("gyro.mat: the accelerometer and gyro files seem swapped"), "{err}");
    assert!(err.contains("acc.mat's is 9.8"), "{err}");
    let err = parse_imutk(&gyro, "gyro.mat", &gyro, "gyro2.mat", None, &short_detection()).unwrap_err().to_string();
    assert!(err.contains("not imu_tk accelerometer counts"), "{err}");
}
