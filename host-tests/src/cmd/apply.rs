//! `sinscal apply RECORDING --calibration CAL.json --out RECORDING`: a recording compensated with a
//! calibration result of either JSON version (docs/cli.md#apply).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sinscal::calib::general::Term;

use crate::calibration::checks::failed_in_json;
use crate::cmd::ChecksFailed;
use crate::io::calibration_model::{CalibrationModel, M3};
use crate::io::error::InputError;
use crate::io::recording::{write_file, RecordingFile, RowSource, WriteError};
use crate::model::synth::{DEG_PER_HOUR, MICRO_G};

/// Arguments of `sinscal apply`.
#[derive(clap::Args)]
pub struct Args {
    /// The recording to compensate (docs/formats.md#recording).
    recording: PathBuf,
    /// The calibration result, schema sinscal-calibration/1 or /2 (docs/formats.md#calibration-json).
    #[arg(long)]
    calibration: PathBuf,
    /// The compensated recording to write (not the input).
    #[arg(long)]
    out: PathBuf,
}

/// Runs `sinscal apply`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { recording, calibration, out } = args;
    for (other, what) in [(&recording, "the input recording"), (&calibration, "the calibration")] {
        if crate::io::same_file(other, &out) {
            return Err(InputError::file(
                &out.display().to_string(),
                format!("--out is {what}: apply writes a new file and never overwrites its input"),
            )
            .into());
        }
    }
    // The rows are read and written one at a time, never held (docs/formats.md#speed-and-memory).
    let rec = RecordingFile::open(&recording)?;
    let model = CalibrationModel::read(&calibration)?;
    let rows = apply(&rec, &model, &out)?;
    super::out(&summary(&rec, rows, &model, &out))?;
    // The output is written; a calibration that failed its checks, or whose estimates are implausible, still
    // makes the run fail loudly (exit 3, docs/cli.md#checks).
    let text = CalibrationModel::text_of(&calibration)?;
    let document: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| InputError::at(&calibration.display().to_string(), e.line().max(1), e.to_string()))?;
    let failed = failed_in_json(&document);
    if failed.is_empty() {
        Ok(())
    } else {
        Err(ChecksFailed(failed).into())
    }
}

/// Writes the recording compensated with the model to `out`: every row's specific force, and its rate when the
/// recording has gyros (docs/conventions.md#sensor-model). The header keeps every key of the input and adds
/// `calibration: <file name>` (`calibration_2`, `calibration_3`, ... when the input was compensated before).
/// The rows go through one at a time into a scratch file beside `out`, renamed to `out` when every row is
/// written: a refusal leaves no partial file ([`write_file`]). Returns the number of rows.
pub fn apply(rec: &impl RowSource, model: &CalibrationModel, out: &Path) -> Result<usize, InputError> {
    let refused = |e: WriteError| e.writing(out);
    let mut header = rec.header().clone();
    let key = calibration_key(&header.comments);
    header.comments.push(format!("{key}: {}", model.source));
    write_file(out, &header, rec.has_gyro(), rec.extra_columns(), |writer| {
        let mut rows = 0;
        rec.for_each_row(&mut |row| {
            let mut row = row.clone();
            let f = model.compensate_force(row.force_b_mps2);
            if rec.has_gyro() {
                row.rate_b_radps = model.compensate_rate(row.rate_b_radps, f);
            }
            row.force_b_mps2 = f;
            rows += 1;
            writer.row(&row).map_err(refused)
        })?;
        Ok(rows)
    })
}

/// `calibration`, or the first free `calibration_N` (N = 2, 3, ...) when the header already names one.
fn calibration_key(comments: &[String]) -> String {
    let taken = |key: &str| comments.iter().any(|c| c.split_once(':').is_some_and(|(k, _)| k.trim() == key));
    if !taken("calibration") {
        return "calibration".to_string();
    }
    (2..).map(|n| format!("calibration_{n}")).find(|k| !taken(k)).expect("a free key")
}

/// The human summary: what was applied, in human units.
fn summary(rec: &RecordingFile, rows: usize, model: &CalibrationModel, out: &Path) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "sinscal apply: {} -> {} ({} rows), compensated with {} (sinscal-calibration/{})",
        rec.source(),
        out.display(),
        rows,
        model.source,
        model.version
    );
    let _ = writeln!(s, "  f = T_a^-1 (f_meas - b_a),  w = T_g^-1 (w_meas - b_g - G f),  T = I + S + M");
    let has = |term: Term| model.terms.contains(&term);
    let _ = writeln!(s, "\n  {:<34} {:>14} {:>14} {:>14}", "term", "x", "y", "z");
    let vector = |s: &mut String, label: &str, v: [f64; 3], scale: f64| {
        let _ = writeln!(s, "  {label:<34} {:>+14.4} {:>+14.4} {:>+14.4}", v[0] / scale, v[1] / scale, v[2] / scale);
    };
    let matrix = |s: &mut String, label: &str, m: &M3, identity: bool, scale: f64| {
        for (i, row) in m.iter().enumerate() {
            let v: Vec<f64> =
                row.iter().enumerate().map(|(j, x)| (x - if identity && i == j { 1.0 } else { 0.0 }) * scale).collect();
            let label = if i == 0 { label.to_string() } else { String::new() };
            let axis = ["x", "y", "z"][i];
            let _ = writeln!(s, "  {label:<28} row {axis} {:>+14.3} {:>+14.3} {:>+14.3}", v[0], v[1], v[2]);
        }
    };
    let gyro_used = rec.has_gyro();
    if has(Term::GyroBias) && gyro_used {
        vector(&mut s, "gyro bias b_g [deg/h]", model.gyro_bias_radps, DEG_PER_HOUR);
    }
    if has(Term::AccelBias) {
        vector(&mut s, "accel bias b_a [ug]", model.accel_bias_mps2, MICRO_G);
    }
    if has(Term::AccelScaleFactor) || has(Term::AccelMisalignment) {
        matrix(&mut s, "accel S_a + M_a [ppm]", &model.accel_t, true, 1e6);
    }
    if gyro_used && (has(Term::GyroScaleFactor) || has(Term::GyroMisalignment)) {
        matrix(&mut s, "gyro S_g + M_g [ppm]", &model.gyro_t, true, 1e6);
    }
    if gyro_used && has(Term::GyroGSensitivity) {
        // (deg/h)/g with g = 9.80665 m/s^2, the unit of data sheets.
        let scale = MICRO_G * 1e6 / DEG_PER_HOUR;
        matrix(&mut s, "gyro G [(deg/h)/g]", &model.gyro_g_sensitivity_radps_per_mps2, false, scale);
    }
    if model.terms.is_empty() {
        let _ = writeln!(s, "  (no term has values: the output equals the input)");
    }
    if !model.taken_as_zero.is_empty() {
        let _ = writeln!(
            s,
            "\ntaken as 0 (null in the calibration: not determined by its schedule): {}",
            model.taken_as_zero.join(", ")
        );
    }
    if !rec.has_gyro() && model.has_gyro_terms() {
        let _ = writeln!(
            s,
            "\nnote: the recording has no gyro columns (accelerometer-only): the calibration's gyro terms are ignored"
        );
    }
    s
}
