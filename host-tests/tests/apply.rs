//! `sinscal apply`: compensation with a calibration result (docs/cli.md#apply, docs/conventions.md#sensor-model)
//! on exact synthetic data. The measured recording is built in f64 from ideal values with the sensor model
//! `f_meas = T_a f + b_a`, `w_meas = T_g w + b_g + G f` and known terms of both signs; apply must return the ideal
//! values to 1e-12 relative.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use serde_json::{json, Value};
use sinscal_host::io::recording::{Header, Recording, Row};
use sinscal_host::model::synth::{c_b_n, earth_rate_n_radps, mul_t_vec};

fn sinscal() -> Command {
    Command::cargo_bin("sinscal").unwrap()
}

type M3 = [[f64; 3]; 3];
type V3 = [f64; 3];
/// (pos, pose, ideal w, ideal f) of one row.
type IdealRow = (u32, V3, V3, V3);
/// (ideal w, ideal f) per row.
type Ideal = Vec<(V3, V3)>;

fn mul_vec(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i] + b[i])
}

fn norm(a: [f64; 3]) -> f64 {
    a.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The sensor errors of a synthetic IMU.
struct Model {
    accel_bias: [f64; 3],
    accel_scale: [f64; 3],
    /// Off-diagonal only.
    accel_misalignment: M3,
    gyro_bias: [f64; 3],
    gyro_scale: [f64; 3],
    gyro_misalignment: M3,
    g_sensitivity: M3,
}

impl Model {
    fn t(scale: [f64; 3], misalignment: &M3) -> M3 {
        [0, 1, 2].map(|i| [0, 1, 2].map(|j| if i == j { 1.0 + scale[i] } else { misalignment[i][j] }))
    }

    /// Both signs on every kind of term.
    fn full() -> Model {
        Model {
            accel_bias: [2.5e-3, -1.7e-3, 4.1e-3],
            accel_scale: [3.0e-4, -5.0e-4, 8.0e-4],
            accel_misalignment: [[0.0, 2.0e-4, -3.0e-4], [-1.5e-4, 0.0, 4.0e-4], [2.5e-4, -3.5e-4, 0.0]],
            gyro_bias: [3.0e-5, -2.0e-5, 1.0e-5],
            gyro_scale: [-6.0e-4, 4.0e-4, 2.0e-4],
            gyro_misalignment: [[0.0, -1.0e-3, 5.0e-4], [7.0e-4, 0.0, -2.0e-4], [-4.0e-4, 9.0e-4, 0.0]],
            g_sensitivity: [[1.0e-5, -2.0e-5, 3.0e-5], [-4.0e-5, 5.0e-6, 6.0e-5], [2.0e-5, -7.0e-5, -1.0e-5]],
        }
    }

    fn biases_only() -> Model {
        Model {
            accel_bias: [2.5e-3, -1.7e-3, 4.1e-3],
            accel_scale: [0.0; 3],
            accel_misalignment: [[0.0; 3]; 3],
            gyro_bias: [3.0e-5, -2.0e-5, 0.0],
            gyro_scale: [0.0; 3],
            gyro_misalignment: [[0.0; 3]; 3],
            g_sensitivity: [[0.0; 3]; 3],
        }
    }

    fn measure(&self, w: [f64; 3], f: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let t_a = Model::t(self.accel_scale, &self.accel_misalignment);
        let t_g = Model::t(self.gyro_scale, &self.gyro_misalignment);
        let f_meas = add(mul_vec(&t_a, f), self.accel_bias);
        let w_meas = add(add(mul_vec(&t_g, w), self.gyro_bias), mul_vec(&self.g_sensitivity, f));
        (w_meas, f_meas)
    }

    /// A version-2 calibration JSON holding the model's terms (std and covariance are placeholders).
    fn json_v2(&self) -> Value {
        let v3 = |v: [f64; 3]| json!(v);
        let zeros3 = json!([0.0, 0.0, 0.0]);
        let zeros33: M3 = [[0.0; 3]; 3];
        json!({
            "schema": "sinscal-calibration/2",
            "latitude_deg": 45.7796, "gravity_mps2": 9.8063,
            "positions": [],
            "gyro_bias_radps": v3(self.gyro_bias), "gyro_bias_std_radps": zeros3,
            "accel_bias_mps2": v3(self.accel_bias), "accel_bias_std_mps2": zeros3,
            "unobservable": [],
            "method": "channels",
            "model": ["gyro_bias", "accel_bias", "accel_scale_factor", "accel_misalignment", "gyro_scale_factor",
                      "gyro_misalignment", "gyro_g_sensitivity"],
            "accel_scale_factor": v3(self.accel_scale), "accel_scale_factor_std": zeros3,
            "accel_misalignment": self.accel_misalignment, "accel_misalignment_std": zeros33,
            "gyro_scale_factor": v3(self.gyro_scale), "gyro_scale_factor_std": zeros3,
            "gyro_misalignment": self.gyro_misalignment, "gyro_misalignment_std": zeros33,
            "gyro_g_sensitivity_radps_per_mps2": self.g_sensitivity,
            "gyro_g_sensitivity_std_radps_per_mps2": zeros33,
            "reference_offset_rad": null, "reference_offset_std_rad": null,
            "parameters": [], "covariance": [],
            "chi_square": 0.0, "degrees_of_freedom": 0
        })
    }
}

/// The poses (pitch, roll, heading) of the synthetic data: Table 1, x up, tilted ones, a heading of 200.
const POSES: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [0.0, 0.0, 180.0],
    [0.0, 90.0, 0.0],
    [0.0, -90.0, 45.0],
    [90.0, 0.0, 0.0],
    [-35.0, 20.0, 200.0],
    [10.0, 170.0, 300.0],
    [-80.0, -60.0, 120.0],
];

/// Ideal (w, f) per row: each pose at rest (Earth rate and +g up), then a rotating row between poses.
fn ideal_rows() -> Vec<IdealRow> {
    let g = 9.8063;
    let w_ie = earth_rate_n_radps(45.7796f64.to_radians());
    let mut out = Vec::new();
    for (k, p) in POSES.iter().enumerate() {
        let c = c_b_n(p[0], p[1], p[2]);
        let f = mul_t_vec(&c, [0.0, 0.0, g]);
        let w = mul_t_vec(&c, w_ie);
        for _ in 0..3 {
            out.push((k as u32 + 1, *p, w, f));
        }
        // The table turning: rates of both signs, a specific force off gravity.
        let s = if k % 2 == 0 { 1.0 } else { -1.0 };
        out.push((0, *p, add(w, [0.3 * s, -0.2, 0.1 * s]), add(f, [0.05, -0.03 * s, 0.02])));
    }
    out
}

fn recording(model: &Model, has_gyro: bool) -> (Recording, Ideal) {
    let mut rows = Vec::new();
    let mut ideal = Vec::new();
    for (k, (pos, p, w, f)) in ideal_rows().into_iter().enumerate() {
        let (w_meas, f_meas) = model.measure(w, f);
        rows.push(Row {
            t_s: k as f64 * 0.01,
            pos,
            pitch_deg: p[0],
            roll_deg: p[1],
            heading_deg: Some(p[2]),
            rate_b_radps: if has_gyro { w_meas } else { [0.0; 3] },
            force_b_mps2: f_meas,
            temp_c: None,
            turn_axis: None,
            line: 0,
        });
        ideal.push((w, f));
    }
    let header = Header {
        latitude_deg: 45.7796,
        height_m: 12.5,
        rate_hz: Some(100.0),
        gravity_mps2: Some(9.8063),
        comments: vec!["source: synthetic".to_string(), "exact data for apply".to_string()],
        truth: None,
        pose_tolerance_deg: None,
    };
    (Recording { source: "measured.csv".to_string(), header, rows, has_gyro }, ideal)
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(v).unwrap()).unwrap();
    path
}

/// Runs apply; returns its stdout and the compensated recording.
fn run_apply(rec: &Path, cal: &Path, out: &Path) -> (String, Recording) {
    let o = sinscal().arg("apply").arg(rec).arg("--calibration").arg(cal).arg("--out").arg(out).assert().success();
    (String::from_utf8(o.get_output().stdout.clone()).unwrap(), Recording::read(out).unwrap())
}

fn assert_ideal(got: &Recording, ideal: &[([f64; 3], [f64; 3])], gyro: bool) {
    let mut worst = (0.0f64, 0.0f64);
    for (row, (w, f)) in got.rows.iter().zip(ideal) {
        let df = norm([0, 1, 2].map(|i| row.force_b_mps2[i] - f[i])) / norm(*f);
        assert!(df <= 1e-12, "line {}: f {:?} vs ideal {f:?} (relative {df:e})", row.line, row.force_b_mps2);
        worst.1 = worst.1.max(df);
        if gyro {
            let dw = norm([0, 1, 2].map(|i| row.rate_b_radps[i] - w[i])) / norm(*w);
            assert!(dw <= 1e-12, "line {}: w {:?} vs ideal {w:?} (relative {dw:e})", row.line, row.rate_b_radps);
            worst.0 = worst.0.max(dw);
        }
    }
    println!("largest relative error: w {:e}, f {:e}", worst.0, worst.1);
}

#[test]
fn version_2_returns_the_ideal_values() {
    let dir = tempfile::tempdir().unwrap();
    let model = Model::full();
    let (rec, ideal) = recording(&model, true);
    let rec_path = dir.path().join("measured.csv");
    rec.write(&rec_path).unwrap();
    let cal = write_json(dir.path(), "cal2.json", &model.json_v2());
    let out = dir.path().join("compensated.csv");
    let (stdout, got) = run_apply(&rec_path, &cal, &out);
    assert!(got.has_gyro);
    assert_ideal(&got, &ideal, true);
    // The header keeps the input's keys and names the calibration.
    assert_eq!(got.header.latitude_deg, 45.7796);
    assert_eq!((got.header.height_m, got.header.rate_hz, got.header.gravity_mps2), (12.5, Some(100.0), Some(9.8063)));
    assert_eq!(got.header.comments, ["source: synthetic", "exact data for apply", "calibration: cal2.json"]);
    assert!(stdout.contains("sinscal-calibration/2"), "{stdout}");
    assert!(stdout.contains("accel S_a + M_a [ppm]") && stdout.contains("gyro G [(deg/h)/g]"), "{stdout}");
    assert!(!stdout.contains("taken as 0"), "{stdout}");

    // Applying again (a second stage) keeps the first key and numbers the new one.
    let again = dir.path().join("again.csv");
    let (_, twice) = run_apply(&out, &cal, &again);
    assert_eq!(twice.header.comments[2..], ["calibration: cal2.json", "calibration_2: cal2.json"]);
}

#[test]
fn version_1_subtracts_the_biases_and_nulls_count_as_zero() {
    let dir = tempfile::tempdir().unwrap();
    let model = Model::biases_only();
    let (rec, ideal) = recording(&model, true);
    let rec_path = dir.path().join("measured.csv");
    rec.write(&rec_path).unwrap();
    let v1 = json!({
        "schema": "sinscal-calibration/1", "latitude_deg": 45.7796, "gravity_mps2": 9.8063, "positions": [],
        "gyro_bias_radps": [model.gyro_bias[0], model.gyro_bias[1], null], "gyro_bias_std_radps": [1e-8, 1e-8, null],
        "accel_bias_mps2": model.accel_bias, "accel_bias_std_mps2": [1e-5, 1e-5, 1e-5],
        "unobservable": ["gyro_bias_z"],
        // Version 1 has only the biases: a term another tool adds is not applied.
        "accel_scale_factor": [0.1, 0.1, 0.1]
    });
    let cal = write_json(dir.path(), "cal1.json", &v1);
    let (stdout, got) = run_apply(&rec_path, &cal, &dir.path().join("out.csv"));
    assert_ideal(&got, &ideal, true);
    assert!(stdout.contains("sinscal-calibration/1"), "{stdout}");
    assert!(stdout.contains("taken as 0 (null in the calibration: not determined by its schedule): gyro_bias_z"));
}

#[test]
fn version_2_nulls_inside_arrays_count_as_zero_and_are_named() {
    let dir = tempfile::tempdir().unwrap();
    // The data have no x-y accelerometer misalignment and no z gyro scale factor: the file says null for them.
    let mut model = Model::full();
    model.accel_misalignment[0][1] = 0.0;
    model.gyro_scale[2] = 0.0;
    let (rec, ideal) = recording(&model, true);
    let rec_path = dir.path().join("measured.csv");
    rec.write(&rec_path).unwrap();
    let mut v = model.json_v2();
    v["accel_misalignment"][0][1] = Value::Null;
    v["gyro_scale_factor"][2] = Value::Null;
    v["unobservable"] = json!(["accel_misalignment_xy", "gyro_scale_factor_z"]);
    // A term not in the model is null: identity.
    v["model"] = json!([
        "gyro_bias",
        "accel_bias",
        "accel_scale_factor",
        "accel_misalignment",
        "gyro_scale_factor",
        "gyro_misalignment",
        "gyro_g_sensitivity",
        "reference_offset"
    ]);
    let cal = write_json(dir.path(), "cal.json", &v);
    let (stdout, got) = run_apply(&rec_path, &cal, &dir.path().join("out.csv"));
    assert_ideal(&got, &ideal, true);
    assert!(
        stdout.contains(
            "taken as 0 (null in the calibration: not determined by its schedule): \
                             accel_misalignment_xy, gyro_scale_factor_z"
        ),
        "{stdout}"
    );

    // Whole terms null: identity and zero. Only the biases remain.
    let model = Model::biases_only();
    let (rec, ideal) = recording(&model, true);
    rec.write(&rec_path).unwrap();
    let mut v = model.json_v2();
    for key in ["accel_scale_factor", "accel_misalignment", "gyro_scale_factor", "gyro_misalignment"] {
        v[key] = Value::Null;
    }
    v.as_object_mut().unwrap().remove("gyro_g_sensitivity_radps_per_mps2");
    let cal = write_json(dir.path(), "biases.json", &v);
    let (_, got) = run_apply(&rec_path, &cal, &dir.path().join("out2.csv"));
    assert_ideal(&got, &ideal, true);
}

#[test]
fn accelerometer_only_recordings_get_the_accelerometer_terms_and_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let model = Model::full();
    let (rec, ideal) = recording(&model, false);
    let rec_path = dir.path().join("accel.csv");
    rec.write(&rec_path).unwrap();
    assert!(!std::fs::read_to_string(&rec_path).unwrap().contains("gx_radps"));
    let cal = write_json(dir.path(), "cal2.json", &model.json_v2());
    let (stdout, got) = run_apply(&rec_path, &cal, &dir.path().join("out.csv"));
    assert!(!got.has_gyro);
    assert!(got.rows.iter().all(|r| r.rate_b_radps == [0.0; 3]));
    assert_ideal(&got, &ideal, false);
    assert!(stdout.contains("no gyro columns (accelerometer-only): the calibration's gyro terms are ignored"));
    assert!(!stdout.contains("gyro bias b_g"), "{stdout}");
}

/// Runs apply expecting exit 1 with one line on stderr; returns it. The output file must not appear.
fn refused(rec: &Path, cal: &Path, out: &Path) -> String {
    let existed = out.exists();
    let o = sinscal().arg("apply").arg(rec).arg("--calibration").arg(cal).arg("--out").arg(out).assert().code(1);
    let stderr = String::from_utf8(o.get_output().stderr.clone()).unwrap();
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    assert_eq!(out.exists(), existed, "{stderr}");
    stderr
}

#[test]
fn bad_calibrations_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let model = Model::full();
    let (rec, _) = recording(&model, true);
    let rec_path = dir.path().join("measured.csv");
    rec.write(&rec_path).unwrap();
    let out = dir.path().join("out.csv");
    let good = model.json_v2();
    let text = serde_json::to_string_pretty(&good).unwrap();

    let mut other = good.clone();
    other["schema"] = json!("sinscal-calibration/3");
    let e = refused(&rec_path, &write_json(dir.path(), "schema.json", &other), &out);
    assert!(e.contains("schema.json: not a calibration result: schema is \"sinscal-calibration/3\""), "{e}");

    // Non-finite numbers: out of the f64 range (JSON's only infinity), or written as strings.
    let path = dir.path().join("inf.json");
    std::fs::write(&path, text.replacen("\"chi_square\": 0.0", "\"chi_square\": 1e999", 1)).unwrap();
    let e = refused(&rec_path, &path, &out);
    assert!(e.contains("inf.json:") && e.contains("a number is not finite"), "{e}");
    let mut nan = good.clone();
    nan["accel_scale_factor"][1] = json!("NaN");
    let e = refused(&rec_path, &write_json(dir.path(), "nan.json", &nan), &out);
    assert!(e.contains("'accel_scale_factor'[1] is \"NaN\", not a finite number or null"), "{e}");

    // T far from the identity.
    let mut far = good.clone();
    far["gyro_misalignment"][2][0] = json!(-0.6);
    let e = refused(&rec_path, &write_json(dir.path(), "far.json", &far), &out);
    assert!(e.contains("gyro_misalignment_zx = -0.6: T_g = I + S + M is far from the identity"), "{e}");
    let mut far = good.clone();
    far["accel_scale_factor"][0] = json!(0.51);
    let e = refused(&rec_path, &write_json(dir.path(), "far2.json", &far), &out);
    assert!(e.contains("accel_scale_factor_x = 0.51: T_a"), "{e}");

    // Singular T with every entry of S + M within 0.5.
    let mut singular = good.clone();
    singular["accel_scale_factor"] = json!([-0.5, -0.5, 0.0]);
    singular["accel_misalignment"] = json!([[0.0, 0.5, 0.0], [0.5, 0.0, 0.0], [0.0, 0.0, 0.0]]);
    let e = refused(&rec_path, &write_json(dir.path(), "singular.json", &singular), &out);
    assert!(e.contains("T_a = I + S + M is singular"), "{e}");

    // A misalignment with a diagonal, a bias array of the wrong length, no bias field at all.
    let mut diagonal = good.clone();
    diagonal["accel_misalignment"][1][1] = json!(1e-3);
    let e = refused(&rec_path, &write_json(dir.path(), "diag.json", &diagonal), &out);
    assert!(e.contains("'accel_misalignment'[1][1] is 0.001: the diagonal of a misalignment is 0"), "{e}");
    let mut short = good.clone();
    short["gyro_bias_radps"] = json!([1.0, 2.0]);
    let e = refused(&rec_path, &write_json(dir.path(), "short.json", &short), &out);
    assert!(e.contains("'gyro_bias_radps' is not an array of 3 numbers or nulls"), "{e}");
    let mut missing = good.clone();
    missing.as_object_mut().unwrap().remove("accel_bias_mps2");
    let e = refused(&rec_path, &write_json(dir.path(), "missing.json", &missing), &out);
    assert!(e.contains("'accel_bias_mps2' is missing"), "{e}");

    // Not JSON.
    let path = dir.path().join("text.json");
    std::fs::write(&path, "calibration\n").unwrap();
    assert!(refused(&rec_path, &path, &out).contains("text.json:1: not JSON"));
}

#[test]
fn out_equal_to_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let model = Model::full();
    let (rec, _) = recording(&model, true);
    let rec_path = dir.path().join("measured.csv");
    rec.write(&rec_path).unwrap();
    let before = std::fs::read(&rec_path).unwrap();
    let cal = write_json(dir.path(), "cal.json", &model.json_v2());
    let e = refused(&rec_path, &cal, &rec_path);
    assert!(e.contains("measured.csv: --out is the input recording"), "{e}");
    // Another spelling of the same path.
    let spelled = dir.path().join(".").join("measured.csv");
    assert!(refused(&rec_path, &cal, &spelled).contains("--out is the input recording"));
    // The calibration file is not overwritten either.
    assert!(refused(&rec_path, &cal, &cal).contains("--out is the calibration"));
    assert_eq!(std::fs::read(&rec_path).unwrap(), before);
    // Usage errors: --out and --calibration are required.
    sinscal().arg("apply").arg(&rec_path).arg("--calibration").arg(&cal).assert().code(2);
    sinscal().arg("apply").arg(&rec_path).arg("--out").arg(dir.path().join("x.csv")).assert().code(2);
}
