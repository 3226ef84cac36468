//! The sensor model of a calibration JSON (docs/formats.md#calibration-json, versions 1 and 2) as numbers to
//! compensate with: `T = I + S + M` of each sensor, the biases and the gyro g-sensitivity, all f64
//! (docs/conventions.md#sensor-model). `sinscal apply` uses it; other commands may.
//!
//! Compensation inverts the model `w_meas = T_g w + b_g + G f`, `f_meas = T_a f + b_a`:
//!
//! ```text
//! f = T_a^-1 (f_meas - b_a),        w = T_g^-1 (w_meas - b_g - G f)
//! ```
//!
//! with the compensated `f` in `G f`. A term that is `null` or absent is the identity (T) or zero (b, G); a
//! parameter that is `null` inside an array (the schedule could not determine it) counts as 0 and is listed in
//! [`CalibrationModel::taken_as_zero`].

use std::path::Path;

use serde_json::Value;
use sinscal::calib::general::{Axes, Term};

use crate::io::error::InputError;

/// A 3x3 matrix, row-major, f64.
pub type M3 = [[f64; 3]; 3];

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const AXES: [char; 3] = ['x', 'y', 'z'];

/// Largest accepted absolute value of an entry of `S + M` (a relative scale-factor error or a misalignment):
/// beyond it the file is not a calibration of this sensor's axes (docs/cli.md#apply).
pub const MAX_T_DEVIATION: f64 = 0.5;

/// Smallest accepted determinant of a `T` matrix: below it `T` is singular (or reverses an axis).
pub const MIN_T_DETERMINANT: f64 = 1e-6;

/// The sensor model of a calibration result, ready to compensate with.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationModel {
    /// File name (without directories), for messages and headers.
    pub source: String,
    /// Schema version: 1 or 2.
    pub version: u32,
    /// Gyro bias `b_g`, body x, y, z, rad/s.
    pub gyro_bias_radps: [f64; 3],
    /// Accelerometer bias `b_a`, body x, y, z, m/s^2.
    pub accel_bias_mps2: [f64; 3],
    /// `T_a = I + S_a + M_a`, row i, column j: axis i's output per unit specific force along j.
    pub accel_t: M3,
    /// `T_g = I + S_g + M_g`, row i, column j: axis i's output per unit rate about j.
    pub gyro_t: M3,
    /// `G`, row i, column j: gyro i's rate error per unit specific force along j, (rad/s)/(m/s^2).
    pub gyro_g_sensitivity_radps_per_mps2: M3,
    /// The terms given with values, in the order of [`Term::ALL`].
    pub terms: Vec<Term>,
    /// Parameters that are `null` in the file and taken as 0 (`gyro_bias_z`, `accel_misalignment_xy`, ...).
    pub taken_as_zero: Vec<String>,
}

/// The JSON field of a term (docs/formats.md#calibration-json-version-2), or `None` for a term that is no part
/// of the sensor's model to compensate with (the reference offset).
fn json_field(term: Term) -> Option<&'static str> {
    match term {
        Term::GyroBias => Some("gyro_bias_radps"),
        Term::AccelBias => Some("accel_bias_mps2"),
        Term::AccelScaleFactor => Some("accel_scale_factor"),
        Term::AccelMisalignment => Some("accel_misalignment"),
        Term::GyroScaleFactor => Some("gyro_scale_factor"),
        Term::GyroMisalignment => Some("gyro_misalignment"),
        Term::GyroGSensitivity => Some("gyro_g_sensitivity_radps_per_mps2"),
        Term::ReferenceOffset => None,
    }
}

impl CalibrationModel {
    /// The text of a calibration JSON file, without the byte-order mark some editors write (recordings accept
    /// one too).
    pub fn text_of(path: &Path) -> Result<String, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
        Ok(match text.strip_prefix('\u{feff}') {
            Some(rest) => rest.to_string(),
            None => text,
        })
    }

    /// Reads a calibration JSON file.
    pub fn read(path: &Path) -> Result<CalibrationModel, InputError> {
        let name = path.display().to_string();
        let text = CalibrationModel::text_of(path)?;
        let mut model = CalibrationModel::parse(&text, &name)?;
        model.source = path.file_name().map_or(name, |f| f.to_string_lossy().into_owned());
        Ok(model)
    }

    /// Parses the text of a calibration JSON; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<CalibrationModel, InputError> {
        let v: Value = serde_json::from_str(text).map_err(|e| {
            // serde_json refuses numbers outside the f64 range (1e999): the file's only way to hold infinity.
            let reason = if e.to_string().contains("number out of range") {
                format!("a number is not finite (outside the f64 range): {e}")
            } else {
                format!("not JSON: {e}")
            };
            InputError::at(source, e.line().max(1), reason)
        })?;
        // serde_json keeps the last of two equal keys: a file that says a thing twice is refused instead.
        if let Err(e) = serde_json::from_str::<NoDuplicateKeys>(text) {
            return Err(InputError::at(source, e.line().max(1), e.to_string()));
        }
        let bad = |reason: String| InputError::file(source, reason);
        let version = match v["schema"].as_str() {
            Some("sinscal-calibration/1") => 1,
            Some("sinscal-calibration/2") => 2,
            _ => {
                return Err(bad(format!(
                    "not a calibration result: schema is {}, not 'sinscal-calibration/1' or 'sinscal-calibration/2'",
                    v["schema"]
                )))
            }
        };
        let mut model = CalibrationModel {
            source: source.to_string(),
            version,
            gyro_bias_radps: [0.0; 3],
            accel_bias_mps2: [0.0; 3],
            accel_t: IDENTITY,
            gyro_t: IDENTITY,
            gyro_g_sensitivity_radps_per_mps2: [[0.0; 3]; 3],
            terms: Vec::new(),
            taken_as_zero: Vec::new(),
        };
        for term in Term::ALL {
            let Some(key) = json_field(term) else { continue };
            // Version 1 has only the biases; its other fields, if a tool adds them, are not the model's.
            let required = matches!(term, Term::GyroBias | Term::AccelBias);
            if version == 1 && !required {
                continue;
            }
            // The biases are fields of both versions (a whole term may be null: not estimated).
            if required && v.get(key).is_none() {
                return Err(bad(format!("'{key}' is missing")));
            }
            let field = &v[key];
            if field.is_null() {
                continue;
            }
            let values = read_term(field, term, key, source)?;
            model.terms.push(term);
            for (i, row) in values.iter().enumerate() {
                for (j, x) in row.iter().enumerate() {
                    if x.is_none() {
                        model.taken_as_zero.push(parameter_name(term, i, j));
                    }
                }
            }
            model.add(term, |i: usize, j: usize| values[i][j].unwrap_or(0.0));
        }
        for (t, sensor) in [(&model.accel_t, "accel"), (&model.gyro_t, "gyro")] {
            check_t(t, sensor).map_err(bad)?;
        }
        check_plausible(&model).map_err(bad)?;
        Ok(model)
    }

    /// A model of biases only (`T = I`, `G = 0`); zero biases compensate nothing.
    pub fn biases_only(source: &str, gyro_bias_radps: [f64; 3], accel_bias_mps2: [f64; 3]) -> CalibrationModel {
        CalibrationModel {
            source: source.to_string(),
            version: 2,
            gyro_bias_radps,
            accel_bias_mps2,
            accel_t: IDENTITY,
            gyro_t: IDENTITY,
            gyro_g_sensitivity_radps_per_mps2: [[0.0; 3]; 3],
            terms: if gyro_bias_radps == [0.0; 3] && accel_bias_mps2 == [0.0; 3] {
                Vec::new()
            } else {
                vec![Term::GyroBias, Term::AccelBias]
            },
            taken_as_zero: Vec::new(),
        }
    }

    /// Adds the values of `term` (entry (i, j); (i, 0) for a term of one value per axis) to the model.
    fn add(&mut self, term: Term, value: impl Fn(usize, usize) -> f64) {
        match term {
            Term::GyroBias => self.gyro_bias_radps = [0, 1, 2].map(|i| value(i, 0)),
            Term::AccelBias => self.accel_bias_mps2 = [0, 1, 2].map(|i| value(i, 0)),
            Term::AccelScaleFactor => (0..3).for_each(|i| self.accel_t[i][i] += value(i, 0)),
            Term::GyroScaleFactor => (0..3).for_each(|i| self.gyro_t[i][i] += value(i, 0)),
            Term::AccelMisalignment => add_off_diagonal(&mut self.accel_t, value),
            Term::GyroMisalignment => add_off_diagonal(&mut self.gyro_t, value),
            Term::GyroGSensitivity => {
                self.gyro_g_sensitivity_radps_per_mps2 = [0, 1, 2].map(|i| [0, 1, 2].map(|j| value(i, j)))
            }
            Term::ReferenceOffset => {}
        }
    }

    /// Whether the model has a gyro term other than zero or the identity (what an accelerometer-only recording
    /// cannot use).
    pub fn has_gyro_terms(&self) -> bool {
        self.gyro_bias_radps != [0.0; 3]
            || self.gyro_t != IDENTITY
            || self.gyro_g_sensitivity_radps_per_mps2 != [[0.0; 3]; 3]
    }

    /// The compensated specific force `f = T_a^-1 (f_meas - b_a)`, m/s^2.
    pub fn compensate_force(&self, force_meas_b_mps2: [f64; 3]) -> [f64; 3] {
        let d = [0, 1, 2].map(|i| force_meas_b_mps2[i] - self.accel_bias_mps2[i]);
        solve(&self.accel_t, d)
    }

    /// The compensated angular rate `w = T_g^-1 (w_meas - b_g - G f)`, rad/s, with `f` the compensated specific
    /// force of the same sample ([`CalibrationModel::compensate_force`]).
    pub fn compensate_rate(&self, rate_meas_b_radps: [f64; 3], force_b_mps2: [f64; 3]) -> [f64; 3] {
        let g = &self.gyro_g_sensitivity_radps_per_mps2;
        let d = [0, 1, 2].map(|i| {
            rate_meas_b_radps[i] - self.gyro_bias_radps[i] - (0..3).map(|j| g[i][j] * force_b_mps2[j]).sum::<f64>()
        });
        solve(&self.gyro_t, d)
    }
}

/// The parameter name of entry (i, j) of a term (docs/formats.md#calibration-json-version-2): `<term>_<axes>`.
fn parameter_name(term: Term, i: usize, j: usize) -> String {
    term.parameter_index(i, j).map_or_else(String::new, |p| sinscal::calib::general::parameter_name(p).to_string())
}

fn add_off_diagonal(t: &mut M3, value: impl Fn(usize, usize) -> f64) {
    for (i, row) in t.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            if i != j {
                *x += value(i, j);
            }
        }
    }
}

/// The values of a term as rows (a vector: three rows of one value); `None` = `null`.
fn read_term(field: &Value, term: Term, key: &str, source: &str) -> Result<Vec<Vec<Option<f64>>>, InputError> {
    let bad = |reason: String| InputError::file(source, reason);
    let number = |x: &Value, at: String| -> Result<Option<f64>, InputError> {
        match x {
            Value::Null => Ok(None),
            x => match x.as_f64() {
                Some(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(bad(format!("'{key}'{at} is {x}, not a finite number or null"))),
            },
        }
    };
    let array3 = |x: &Value, what: &str| -> Result<Vec<Value>, InputError> {
        x.as_array().filter(|a| a.len() == 3).cloned().ok_or_else(|| bad(format!("'{key}' is not {what} (or null)")))
    };
    let axes = term.info().axes;
    if matches!(axes, Axes::Body | Axes::Navigation) {
        let a = array3(field, "an array of 3 numbers or nulls")?;
        return a.iter().enumerate().map(|(i, x)| Ok(vec![number(x, format!("[{i}]"))?])).collect();
    }
    let rows = array3(field, "a 3x3 array of numbers or nulls")?;
    let mut out = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let row = array3(row, "a 3x3 array of numbers or nulls")?;
        let mut values = Vec::new();
        for (j, x) in row.iter().enumerate() {
            let v = number(x, format!("[{i}][{j}]"))?;
            if axes == Axes::OffDiagonal && i == j {
                if v.is_some_and(|v| v != 0.0) {
                    return Err(bad(format!(
                        "'{key}'[{i}][{i}] is {x}: the diagonal of a misalignment is 0 (scale factors are separate)"
                    )));
                }
                values.push(Some(0.0));
            } else {
                values.push(v);
            }
        }
        out.push(values);
    }
    Ok(out)
}

/// Refuses a `T` that is far from the identity or singular.
fn check_t(t: &M3, sensor: &str) -> Result<(), String> {
    for i in 0..3 {
        for j in 0..3 {
            let deviation = t[i][j] - IDENTITY[i][j];
            if deviation.abs() > MAX_T_DEVIATION {
                let name = if i == j {
                    format!("{sensor}_scale_factor_{}", AXES[i])
                } else {
                    format!("{sensor}_misalignment_{}{}", AXES[i], AXES[j])
                };
                // Six significant digits: 1.51 - 1 is not exactly 0.51.
                let deviation = format!("{deviation:.5e}").parse::<f64>().unwrap_or(deviation);
                return Err(format!(
                    "{name} = {deviation}: T_{} = I + S + M is far from the identity (|S + M| entries above \
                     {MAX_T_DEVIATION}): not a calibration of these axes",
                    &sensor[..1]
                ));
            }
        }
    }
    let d = det(t);
    if d.is_nan() || d < MIN_T_DETERMINANT {
        return Err(format!(
            "T_{} = I + S + M is singular (det {d:e}, at least {MIN_T_DETERMINANT:e} is needed): it cannot be inverted",
            &sensor[..1]
        ));
    }
    Ok(())
}

/// A JSON value read only to refuse an object that has one key twice (at any depth): its `Deserialize`
/// walks the document and fails on the second occurrence, naming the key.
pub(crate) struct NoDuplicateKeys;

impl<'de> serde::Deserialize<'de> for NoDuplicateKeys {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(NoDuplicateKeys)
    }
}

impl<'de> serde::de::Visitor<'de> for NoDuplicateKeys {
    type Value = NoDuplicateKeys;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut keys = std::collections::HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if !keys.insert(key.clone()) {
                return Err(serde::de::Error::custom(format!("key '{key}' appears twice")));
            }
            map.next_value::<NoDuplicateKeys>()?;
        }
        Ok(NoDuplicateKeys)
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        while seq.next_element::<NoDuplicateKeys>()?.is_some() {}
        Ok(NoDuplicateKeys)
    }

    fn visit_bool<E>(self, _: bool) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
    fn visit_str<E>(self, _: &str) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
    fn visit_unit<E>(self) -> Result<Self::Value, E> {
        Ok(NoDuplicateKeys)
    }
}

/// Largest gyro bias a plausible instrument has, rad/s (5.7 deg/s: consumer MEMS gyros reach 1 to 3 deg/s).
pub const MAX_GYRO_BIAS_RADPS: f64 = 0.1;
/// Largest accelerometer bias a plausible instrument has, m/s^2 (0.2 g: the raw counts of a consumer MEMS
/// read with its nominal offset are 0.1 g off).
pub const MAX_ACCEL_BIAS_MPS2: f64 = 2.0;
/// Largest scale factor error and misalignment, 1 (5 %, 2.9 degrees).
pub const MAX_SCALE_OR_MISALIGNMENT: f64 = 0.05;
/// Largest gyro g-sensitivity, (rad/s)/(m/s^2) (0.56 (deg/s)/g; MEMS gyros are specified at 0.01 to 0.1).
pub const MAX_G_SENSITIVITY_RADPS_PER_MPS2: f64 = 1e-3;
/// Largest level error of a reference attitude, rad (2.9 degrees: a face placed by hand on a cube).
pub const MAX_LEVEL_ERROR_RAD: f64 = 0.05;

/// The biases and the g-sensitivity within the plausible limits above (also the effect catalogue's, in
/// `model::catalogue`: the limits `analyze` holds its effects to): a value beyond them is not a
/// calibration of any instrument, and compensating with it gives numbers that mean nothing (a bias of 1e308
/// rad/s navigates to NaN).
fn check_plausible(model: &CalibrationModel) -> Result<(), String> {
    let limits: [(&str, Vec<f64>, f64, &str); 3] = [
        ("gyro_bias_radps", model.gyro_bias_radps.to_vec(), MAX_GYRO_BIAS_RADPS, "rad/s"),
        ("accel_bias_mps2", model.accel_bias_mps2.to_vec(), MAX_ACCEL_BIAS_MPS2, "m/s^2"),
        (
            "gyro_g_sensitivity_radps_per_mps2",
            model.gyro_g_sensitivity_radps_per_mps2.iter().flatten().copied().collect(),
            MAX_G_SENSITIVITY_RADPS_PER_MPS2,
            "(rad/s)/(m/s^2)",
        ),
    ];
    for (field, values, limit, unit) in limits {
        if let Some((k, v)) = values.iter().enumerate().find(|(_, v)| v.is_nan() || v.abs() > limit) {
            return Err(format!(
                "{field}[{k}] = {} {unit} is beyond the plausible {} {unit} of any instrument",
                crate::io::recording::shown(*v),
                crate::io::recording::shown(limit)
            ));
        }
    }
    Ok(())
}

/// Determinant of a 3x3 matrix.
pub fn det(a: &M3) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

/// `a^-1 b` by Gaussian elimination with partial pivoting (`a` checked non-singular, near the identity).
fn solve(a: &M3, b: [f64; 3]) -> [f64; 3] {
    let mut m = [[0.0; 4]; 3];
    for i in 0..3 {
        m[i][..3].copy_from_slice(&a[i]);
        m[i][3] = b[i];
    }
    for col in 0..3 {
        let pivot = (col..3).max_by(|&p, &q| m[p][col].abs().total_cmp(&m[q][col].abs())).unwrap_or(col);
        m.swap(col, pivot);
        for row in col + 1..3 {
            let factor = m[row][col] / m[col][col];
            for k in col..4 {
                m[row][k] -= factor * m[col][k];
            }
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let rest: f64 = (i + 1..3).map(|k| m[i][k] * x[k]).sum();
        x[i] = (m[i][3] - rest) / m[i][i];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    const V1: &str = r#"{"schema": "sinscal-calibration/1", "gyro_bias_radps": [1e-6, null, -2e-6],
        "gyro_bias_std_radps": [1e-8, null, 1e-8], "accel_bias_mps2": [1e-3, -2e-3, 3e-3],
        "accel_bias_std_mps2": [1e-5, 1e-5, 1e-5], "unobservable": ["gyro_bias_y"]}"#;

    #[test]
    fn version_1_has_biases_only_and_nulls_are_taken_as_zero() {
        let m = CalibrationModel::parse(V1, "c.json").unwrap();
        assert_eq!(m.version, 1);
        assert_eq!(m.gyro_bias_radps, [1e-6, 0.0, -2e-6]);
        assert_eq!(m.taken_as_zero, ["gyro_bias_y"]);
        assert_eq!(m.terms, [Term::GyroBias, Term::AccelBias]);
        assert_eq!((m.accel_t, m.gyro_t), (IDENTITY, IDENTITY));
        assert_eq!(m.compensate_force([1.0, 2.0, 3.0]), [1.0 - 1e-3, 2.0 + 2e-3, 3.0 - 3e-3]);
    }

    #[test]
    fn solve_inverts() {
        let a = [[1.01, 0.002, -0.003], [0.001, 0.99, 0.004], [-0.002, 0.003, 1.02]];
        let x = [0.3, -9.7, 1.5];
        let b = [0, 1, 2].map(|i| (0..3).map(|j| a[i][j] * x[j]).sum::<f64>());
        let got = solve(&a, b);
        for i in 0..3 {
            assert!((got[i] - x[i]).abs() < 1e-14, "{got:?}");
        }
    }
}
