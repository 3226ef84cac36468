//! Importers of measured data sets into the recording format of SPEC.md section 2 (`sinscal import`).
//!
//! Three formats are read, each into a [`Recording`] plus a short human summary ([`Imported`]):
//! - [`Format::Psins`]: a PSINS `.imu` file (angle and velocity increment counts, one static pose),
//!   [`parse_psins`];
//! - [`Format::Imucal`] and [`Format::ImucalRaw`]: an imucal Ferraris session with its six labelled static poses,
//!   [`parse_imucal`] (calibrated deg/s and m/s^2 plus a JSON label file) and [`parse_imucal_raw`] (raw counts,
//!   labels in a column);
//! - [`Format::Imutk`]: imu_tk text counts of an accelerometer and a gyro, without labels: static intervals are
//!   detected ([`detect_static_intervals`]) and levelled by their mean specific force, [`parse_imutk`].
//!
//! Every recording says where it came from in its header comments (`# source: ...`, `# source_format: ...`,
//! `# latitude_source: ...`, `# attitude_source: ...`, and the nominal scales used). Malformed input is reported as
//! an [`InputError`] naming the file, the line and the reason; nothing here panics on bad input.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::io::calibration_result::ARCSEC_PER_RAD;
use crate::io::error::InputError;
use crate::io::recording::{Header, Recording, Row};

/// Standard gravity, m/s^2: the "g" of accelerometer ranges given in LSB/g. The f64 twin of the core's
/// f32 `sinscal::nav::earth::STANDARD_GRAVITY_MPS2` (its f32 value would be off by 1.6e-8 relative).
pub const STANDARD_GRAVITY_MPS2: f64 = 9.80665;

/// Sample rate of the imucal example session `example_ferraris_session.csv`, Hz (not written in the file).
pub const IMUCAL_RATE_HZ: f64 = 102.4;

/// Sample rate of imucal's `annotated_session.csv` (raw counts), Hz (not written in the file).
pub const IMUCAL_RAW_RATE_HZ: f64 = 204.8;

/// Nominal accelerometer scale of imucal's raw counts (+-16 g range), LSB per standard g.
pub const IMUCAL_RAW_ACCEL_LSB_PER_G: f64 = 2048.0;

/// Nominal gyro scale of imucal's raw counts (+-2000 deg/s range), LSB per deg/s.
pub const IMUCAL_RAW_GYRO_LSB_PER_DEGPS: f64 = 16.4;

/// Latitude assumed for imucal data when `--latitude-deg` is not given, degrees north: Erlangen (inferred from the
/// data's origin, the FAU MaD-Lab; the data do not state it).
pub const IMUCAL_DEFAULT_LATITUDE_DEG: f64 = 49.6;

/// Latitude assumed for imu_tk data when `--latitude-deg` is not given, degrees north (unknown: not stated).
pub const IMUTK_DEFAULT_LATITUDE_DEG: f64 = 45.0;

/// Gravity written into imu_tk recordings, m/s^2: the value imu_tk's own example uses.
pub const IMUTK_GRAVITY_MPS2: f64 = 9.81744;

/// Nominal (factory reference) accelerometer gains of the imu_tk Xsens data, counts per m/s^2, x, y, z.
pub const IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2: [f64; 3] = [415.0, 413.0, 415.0];

/// Nominal (factory reference) gyro gains of the imu_tk Xsens data, counts per rad/s, x, y, z.
pub const IMUTK_GYRO_GAIN_COUNTS_PER_RADPS: [f64; 3] = [4778.0, 4758.0, 4766.0];

/// Nominal zero of the imu_tk unsigned 16-bit counts.
pub const IMUTK_OFFSET_COUNTS: f64 = 32768.0;

/// Largest difference accepted between the time stamps of the imu_tk accelerometer and gyro files, s.
pub const IMUTK_MAX_TIME_MISMATCH_S: f64 = 1e-6;

/// One labelled static pose of an imucal Ferraris session and the attitude it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FerrarisPose {
    /// imucal's label (`x_p` = body x pointing up, `x_a` = body x pointing down, ...).
    pub label: &'static str,
    /// Position label in the recording.
    pub pos: u32,
    /// Pitch, degrees (SPEC.md section 1).
    pub pitch_deg: f64,
    /// Roll, degrees (SPEC.md section 1).
    pub roll_deg: f64,
    /// The body axis that points up, for messages ("+x", "-z", ...).
    pub up_axis: &'static str,
}

/// The six static poses of a Ferraris session, positions 1..6, with pitch and roll from SPEC.md's
/// C_b^n = Rz(-psi) Rx(theta) Ry(gamma): the up direction seen in the body is Ry(-gamma) Rx(-theta) [0, 0, 1]
/// = [-sin(gamma) cos(theta), sin(theta), cos(gamma) cos(theta)], so roll -90 puts body x up, roll +90 body x
/// down (SPEC.md's check value), pitch +90 body y up, roll 180 body z down. Heading is unknown.
pub const FERRARIS_POSES: [FerrarisPose; 6] = [
    FerrarisPose { label: "x_p", pos: 1, pitch_deg: 0.0, roll_deg: -90.0, up_axis: "+x" },
    FerrarisPose { label: "x_a", pos: 2, pitch_deg: 0.0, roll_deg: 90.0, up_axis: "-x" },
    FerrarisPose { label: "y_p", pos: 3, pitch_deg: 90.0, roll_deg: 0.0, up_axis: "+y" },
    FerrarisPose { label: "y_a", pos: 4, pitch_deg: -90.0, roll_deg: 0.0, up_axis: "-y" },
    FerrarisPose { label: "z_p", pos: 5, pitch_deg: 0.0, roll_deg: 0.0, up_axis: "+z" },
    FerrarisPose { label: "z_a", pos: 6, pitch_deg: 0.0, roll_deg: 180.0, up_axis: "-z" },
];

/// The labels of the three turns of a Ferraris session (their rows get `pos` = 0).
pub const FERRARIS_ROTATIONS: [&str; 3] = ["x_rot", "y_rot", "z_rot"];

/// The static pose of an imucal label, `None` for the turns and unknown labels.
pub fn ferraris_pose(label: &str) -> Option<&'static FerrarisPose> {
    FERRARIS_POSES.iter().find(|p| p.label == label)
}

/// The input formats of `sinscal import`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// PSINS `.imu` text: header lines, then gyro and accel increment counts.
    Psins,
    /// imucal Ferraris session CSV (deg/s, m/s^2, 102.4 Hz) with its `_list.json` labels.
    Imucal,
    /// imucal annotated session CSV (raw counts, 204.8 Hz, a label column).
    ImucalRaw,
    /// imu_tk text counts: accelerometer file and gyro file (t_s x y z), static intervals detected.
    Imutk,
}

/// Arguments of `sinscal import`.
#[derive(Clone, Debug, clap::Args)]
pub struct ImportArgs {
    /// Input format.
    #[arg(value_enum)]
    pub format: Format,
    /// Input file(s): one for psins, imucal and imucal-raw; two (accelerometer, then gyro) for imutk.
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// The recording to write (SPEC.md section 2).
    #[arg(long)]
    pub out: PathBuf,
    /// Latitude, degrees north. Default: the file's (psins), 49.6 (imucal, inferred: Erlangen), 45 (imutk, unknown).
    #[arg(long, allow_negative_numbers = true)]
    pub latitude_deg: Option<f64>,
    /// imucal: the JSON label file (default: INPUT with '.csv' replaced by '_list.json').
    #[arg(long)]
    pub labels: Option<PathBuf>,
}

impl ImportArgs {
    /// Checks what clap cannot: the number of inputs of the format, `--labels` only with imucal, and the
    /// latitude's range. The error is a usage error (exit status 2).
    pub fn validate(&self) -> Result<(), clap::Error> {
        let usage = |msg: String| {
            Err(clap::Error::raw(
                clap::error::ErrorKind::WrongNumberOfValues,
                format!("{msg}\n\nFor more information, try 'sinscal import --help'.\n"),
            ))
        };
        let wanted = if self.format == Format::Imutk { 2 } else { 1 };
        if self.inputs.len() != wanted {
            let what = match self.format {
                Format::Imutk => "imutk needs two inputs: the accelerometer file, then the gyro file",
                _ => "this format needs exactly one input file",
            };
            return usage(format!("{what} (got {})", self.inputs.len()));
        }
        if self.labels.is_some() && self.format != Format::Imucal {
            return usage("--labels applies only to the imucal format".to_string());
        }
        if let Some(lat) = self.latitude_deg {
            if !(lat.is_finite() && (-90.0..=90.0).contains(&lat)) {
                return usage(format!("--latitude-deg {lat} is outside [-90, 90]"));
            }
        }
        Ok(())
    }
}

/// Runs `sinscal import` (after [`ImportArgs::validate`]): reads the inputs, writes the recording to `--out`, and
/// returns the human summary to print.
pub fn run(args: &ImportArgs) -> Result<String, InputError> {
    let first = args.inputs.first().ok_or_else(|| InputError::file("sinscal import", "no input file"))?;
    let imported = match args.format {
        Format::Psins => import_psins(first, args.latitude_deg)?,
        Format::Imucal => {
            let labels = args.labels.clone().unwrap_or_else(|| default_labels_path(first));
            import_imucal(first, &labels, args.latitude_deg)?
        }
        Format::ImucalRaw => import_imucal_raw(first, args.latitude_deg)?,
        Format::Imutk => {
            let gyro = args
                .inputs
                .get(1)
                .ok_or_else(|| InputError::file("sinscal import", "imutk needs the gyro file as second input"))?;
            import_imutk(first, gyro, args.latitude_deg, &StaticDetection::default())?
        }
    };
    imported.recording.write(&args.out)?;
    Ok(format!("{}wrote {}\n", imported.summary, args.out.display()))
}

/// An imported recording and its human summary (samples, rate, duration, positions with their sample counts and
/// mean gyro and accelerometer outputs, and where the numbers came from).
#[derive(Clone, Debug)]
pub struct Imported {
    /// The recording (SPEC.md section 2 semantics).
    pub recording: Recording,
    /// Human summary, several lines, ending with a newline.
    pub summary: String,
}

/// Statistics of one position of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionStats {
    /// Position label.
    pub pos: u32,
    /// Number of rows.
    pub samples: usize,
    /// Time of the first row, s.
    pub first_t_s: f64,
    /// Time of the last row, s.
    pub last_t_s: f64,
    /// Pitch of the first row, degrees.
    pub pitch_deg: f64,
    /// Roll of the first row, degrees.
    pub roll_deg: f64,
    /// Heading of the first row, degrees (`None` = unknown).
    pub heading_deg: Option<f64>,
    /// Mean gyro output, body, rad/s.
    pub mean_rate_b_radps: [f64; 3],
    /// Mean accelerometer output, body, m/s^2.
    pub mean_force_b_mps2: [f64; 3],
}

/// Per-position statistics of a recording, in order of first appearance of each label (label 0 is skipped).
pub fn position_stats(recording: &Recording) -> Vec<PositionStats> {
    recording
        .dwells()
        .iter()
        .filter_map(|d| {
            let first = d.rows.first()?;
            let last = d.rows.last()?;
            let count = d.rows.len() as f64;
            let mut rate = [0.0; 3];
            let mut force = [0.0; 3];
            for r in &d.rows {
                for i in 0..3 {
                    rate[i] += r.rate_b_radps[i];
                    force[i] += r.force_b_mps2[i];
                }
            }
            Some(PositionStats {
                pos: d.pos,
                samples: d.rows.len(),
                first_t_s: first.t_s,
                last_t_s: last.t_s,
                pitch_deg: first.pitch_deg,
                roll_deg: first.roll_deg,
                heading_deg: first.heading_deg,
                mean_rate_b_radps: rate.map(|v| v / count),
                mean_force_b_mps2: force.map(|v| v / count),
            })
        })
        .collect()
}

/// The label file of an imucal session: `session.csv` -> `session_list.json` (or `_list.json` appended).
pub fn default_labels_path(csv: &Path) -> PathBuf {
    let name = csv.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.strip_suffix(".csv").unwrap_or(&name);
    csv.with_file_name(format!("{stem}_list.json"))
}

/// Pitch and roll, degrees, of a body whose accelerometer measures `force_b_mps2` at rest (levelling): the up
/// direction u = f / |f| equals Ry(-gamma) Rx(-theta) [0, 0, 1] = [-sin(gamma) cos(theta), sin(theta),
/// cos(gamma) cos(theta)] (SPEC.md section 1), so pitch = atan2(u_y, hypot(u_x, u_z)) in [-90, 90] and
/// roll = atan2(-u_x, u_z) in (-180, 180]. `None` for a zero or non-finite vector.
pub fn level_attitude_deg(force_b_mps2: [f64; 3]) -> Option<(f64, f64)> {
    let [x, y, z] = force_b_mps2;
    let norm = (x * x + y * y + z * z).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    let pitch_deg = y.atan2(x.hypot(z)).to_degrees();
    let mut roll_deg = (-x).atan2(z).to_degrees();
    if roll_deg <= -180.0 {
        roll_deg += 360.0;
    }
    // Adding 0.0 turns -0.0 into 0.0 so files never show "-0".
    Some((pitch_deg + 0.0, roll_deg + 0.0))
}

/// An angle in degrees brought into [0, 360).
fn normalise_deg(angle_deg: f64) -> f64 {
    let r = angle_deg.rem_euclid(360.0);
    if r >= 360.0 {
        0.0
    } else {
        r + 0.0
    }
}

fn read_text(path: &Path) -> Result<String, InputError> {
    std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))
}

fn parse_finite(cell: &str) -> Option<f64> {
    cell.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Exactly `count` whitespace-separated finite numbers; the error is the reason.
fn whitespace_numbers(line: &str, count: usize, what: &str) -> Result<Vec<f64>, String> {
    let cells: Vec<&str> = line.split_whitespace().collect();
    if cells.len() != count {
        return Err(format!("{what}: expected {count} numbers, found {}", cells.len()));
    }
    cells.iter().map(|c| parse_finite(c).ok_or_else(|| format!("{what}: '{c}' is not a finite number"))).collect()
}

fn latitude_checked(latitude_deg: f64, source: &str, line: usize) -> Result<f64, InputError> {
    if (-90.0..=90.0).contains(&latitude_deg) {
        Ok(latitude_deg)
    } else {
        Err(InputError::at(source, line, format!("latitude {latitude_deg} deg is outside [-90, 90]")))
    }
}

fn option_latitude(latitude_deg: Option<f64>, option: &str) -> Result<Option<f64>, InputError> {
    match latitude_deg {
        Some(lat) if !(lat.is_finite() && (-90.0..=90.0).contains(&lat)) => {
            Err(InputError::file(option, format!("{lat} is outside [-90, 90]")))
        }
        other => Ok(other),
    }
}

// ---------------------------------------------------------------------------------------------------------------
// PSINS

/// Reads a PSINS `.imu` file; see [`parse_psins`].
pub fn import_psins(path: &Path, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    parse_psins(&read_text(path)?, &path.display().to_string(), latitude_deg)
}

/// Parses the text of a PSINS `.imu` file (`source` names it in errors and in the `# source:` header).
///
/// Lines starting with '%' are comments. Data line 1: pitch, roll, yaw (deg; PSINS yaw is positive towards west,
/// so heading = -yaw brought into [0, 360)), VE, VN, VU (m/s, ignored). Line 2: latitude (deg), longitude (deg),
/// height (m), t0 (s), sampling interval (ms), g (m/s^2). Line 3: gyro scale per count (arcsec) x, y, z and
/// accelerometer scale per count (ug*s, 1 ug = 1e-6 * g of line 2) x, y, z. Then one line of six integer
/// increment counts per sample (gyro x, y, z, accel x, y, z), converted as
/// rate_radps = count * scale_arcsec * (pi / 648000) / dt_s and force_mps2 = count * scale_ugs * 1e-6 * g / dt_s.
/// Row k has t_s = t0 + k * dt_s. The record is one static pose: every row has pos = 1 and the attitude of line 1.
/// `latitude_deg` overrides the file's latitude.
pub fn parse_psins(text: &str, source: &str, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    let latitude_override = option_latitude(latitude_deg, "--latitude-deg")?;
    let last_line = text.lines().count().max(1);
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty() && !l.starts_with('%'));
    let mut header_line = |what: &str| -> Result<(usize, Vec<f64>), InputError> {
        let (n, line) = lines
            .next()
            .ok_or_else(|| InputError::at(source, last_line, format!("end of file before the {what} line")))?;
        let values = whitespace_numbers(line, 6, what).map_err(|r| InputError::at(source, n, r))?;
        Ok((n, values))
    };
    let (attitude_line, attitude) = header_line("attitude (pitch roll yaw deg, VE VN VU m/s)")?;
    let (site_line, site) = header_line("site (latitude deg, longitude deg, height m, t0 s, interval ms, g m/s^2)")?;
    let (scale_line, scale) = header_line("scale (gyro arcsec x y z, accel ug*s x y z)")?;

    let (pitch_deg, roll_deg, yaw_deg) = (attitude[0], attitude[1], attitude[2]);
    if !(-90.0..=90.0).contains(&pitch_deg) {
        return Err(InputError::at(source, attitude_line, format!("pitch {pitch_deg} deg is outside [-90, 90]")));
    }
    let heading_deg = normalise_deg(-yaw_deg);
    let file_latitude_deg = latitude_checked(site[0], source, site_line)?;
    let (longitude_deg, height_m, t0_s, interval_ms, gravity_mps2) = (site[1], site[2], site[3], site[4], site[5]);
    if interval_ms <= 0.0 {
        return Err(InputError::at(source, site_line, format!("sampling interval {interval_ms} ms is not positive")));
    }
    if !(9.7..=9.9).contains(&gravity_mps2) {
        return Err(InputError::at(
            source,
            site_line,
            format!("g {gravity_mps2} m/s^2 is not a gravity on Earth (9.7..9.9)"),
        ));
    }
    if let Some(bad) = scale.iter().find(|s| **s <= 0.0) {
        return Err(InputError::at(source, scale_line, format!("scale {bad} per count is not positive")));
    }
    let dt_s = interval_ms / 1000.0;
    let rate_hz = 1000.0 / interval_ms;
    let gyro_radps_per_count = [0, 1, 2].map(|i| scale[i] / ARCSEC_PER_RAD / dt_s);
    let accel_mps2_per_count = [3, 4, 5].map(|i| scale[i] * 1e-6 * gravity_mps2 / dt_s);

    let mut rows = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split_whitespace().collect();
        if cells.len() != 6 {
            return Err(InputError::at(
                source,
                n,
                format!("expected 6 integer counts (gyro x y z, accel x y z), found {} fields", cells.len()),
            ));
        }
        let mut counts = [0i64; 6];
        for (slot, cell) in counts.iter_mut().zip(&cells) {
            *slot = cell.parse().map_err(|_| InputError::at(source, n, format!("'{cell}' is not an integer count")))?;
        }
        let k = rows.len() as f64;
        rows.push(Row {
            t_s: t0_s + k * dt_s,
            pos: 1,
            pitch_deg,
            roll_deg,
            heading_deg: Some(heading_deg),
            rate_b_radps: [0, 1, 2].map(|i| counts[i] as f64 * gyro_radps_per_count[i]),
            force_b_mps2: [0, 1, 2].map(|i| counts[i + 3] as f64 * accel_mps2_per_count[i]),
            temp_c: None,
            line: n,
        });
    }
    if rows.is_empty() {
        return Err(InputError::at(source, last_line, "no data lines after the three header lines"));
    }
    let (latitude_deg, latitude_source) = match latitude_override {
        Some(lat) => (lat, format!("command line (--latitude-deg; the file says {file_latitude_deg})")),
        None => (file_latitude_deg, format!("file header (line {site_line})")),
    };
    let comments = vec![
        format!("source: {source}"),
        "source_format: PSINS .imu (gyro angle increments in arcsec and accel velocity increments in ug*s, counts)"
            .to_string(),
        format!("latitude_source: {latitude_source}"),
        format!("longitude_deg: {longitude_deg}"),
        format!(
            "attitude_source: file header line {attitude_line} (PSINS pitch {pitch_deg}, roll {roll_deg}, \
             yaw {yaw_deg} deg positive west; heading = -yaw = {heading_deg} deg)"
        ),
        format!(
            "scale: gyro {} {} {} arcsec/count, accel {} {} {} ug*s/count, g {gravity_mps2} m/s^2, dt {dt_s} s",
            scale[0], scale[1], scale[2], scale[3], scale[4], scale[5]
        ),
    ];
    let recording = Recording {
        source: source.to_string(),
        header: Header {
            latitude_deg,
            height_m,
            rate_hz: Some(rate_hz),
            gravity_mps2: Some(gravity_mps2),
            comments,
            truth: None,
        },
        rows,
    };
    let notes = vec![
        format!("latitude {latitude_deg} deg ({latitude_source}), height {height_m} m, g {gravity_mps2} m/s^2"),
        format!("one static pose: pitch {pitch_deg}, roll {roll_deg}, heading {heading_deg} deg (PSINS yaw {yaw_deg})"),
    ];
    let summary = summarise(&recording, "PSINS .imu", &notes, &|_| String::new());
    Ok(Imported { recording, summary })
}

// ---------------------------------------------------------------------------------------------------------------
// imucal

/// A labelled range of sample indices, `[start, end)` (Python slice semantics, as imucal uses them).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelRange {
    /// Label (`x_p`, ..., `z_rot`).
    pub label: String,
    /// First sample index.
    pub start: u64,
    /// One past the last sample index.
    pub end: u64,
}

/// The line (1-based) where `"label"` first appears in a JSON text, for messages.
fn json_line_of(text: &str, label: &str) -> usize {
    let key = format!("\"{label}\"");
    text.find(&key).map_or(1, |at| text[..at].matches('\n').count() + 1)
}

/// Parses an imucal label file: a JSON object mapping each label to `{"start": s, "end": e}` or to `[s, e]`,
/// sample indices with `end` exclusive. All six static labels must be there, `start < end`, and the static ranges
/// must not overlap; the turns (`x_rot`, `y_rot`, `z_rot`) are optional; other labels are errors.
pub fn parse_imucal_labels(text: &str, source: &str) -> Result<Vec<LabelRange>, InputError> {
    let value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| InputError::at(source, e.line().max(1), format!("not valid JSON: {e}")))?;
    let object = value.as_object().ok_or_else(|| {
        InputError::at(source, 1, "expected a JSON object of labels ({\"x_p\": {\"start\": .., \"end\": ..}, ...})")
    })?;
    let mut ranges = Vec::new();
    for (label, range) in object {
        let line = json_line_of(text, label);
        if ferraris_pose(label).is_none() && !FERRARIS_ROTATIONS.contains(&label.as_str()) {
            return Err(InputError::at(
                source,
                line,
                format!("unknown label '{label}' (expected x_p, x_a, y_p, y_a, z_p, z_a, x_rot, y_rot, z_rot)"),
            ));
        }
        let (start, end) = match range {
            serde_json::Value::Object(o) => (o.get("start"), o.get("end")),
            serde_json::Value::Array(a) if a.len() == 2 => (a.first(), a.get(1)),
            _ => (None, None),
        };
        let index = |v: Option<&serde_json::Value>| v.and_then(serde_json::Value::as_u64);
        let (Some(start), Some(end)) = (index(start), index(end)) else {
            return Err(InputError::at(
                source,
                line,
                format!("label '{label}': expected {{\"start\": s, \"end\": e}} or [s, e] with sample indices >= 0"),
            ));
        };
        if start >= end {
            return Err(InputError::at(source, line, format!("label '{label}': start {start} is not below end {end}")));
        }
        ranges.push(LabelRange { label: label.clone(), start, end });
    }
    for pose in &FERRARIS_POSES {
        if !ranges.iter().any(|r| r.label == pose.label) {
            return Err(InputError::file(
                source,
                format!("label '{}' (body {} up) is missing", pose.label, pose.up_axis),
            ));
        }
    }
    let statics: Vec<&LabelRange> = ranges.iter().filter(|r| ferraris_pose(&r.label).is_some()).collect();
    for (i, a) in statics.iter().enumerate() {
        for b in &statics[i + 1..] {
            if a.start < b.end && b.start < a.end {
                return Err(InputError::at(
                    source,
                    json_line_of(text, &b.label),
                    format!(
                        "labels '{}' [{}, {}) and '{}' [{}, {}) overlap",
                        a.label, a.start, a.end, b.label, b.start, b.end
                    ),
                ));
            }
        }
    }
    Ok(ranges)
}

/// Column indices of `names` in a CSV column line, or an error naming the first missing one.
fn csv_columns<const N: usize>(
    column_line: &str,
    names: [&str; N],
    source: &str,
    line: usize,
) -> Result<(Vec<String>, [usize; N]), InputError> {
    let columns: Vec<String> = column_line.split(',').map(|c| c.trim().to_string()).collect();
    let mut index = [0usize; N];
    for (slot, name) in index.iter_mut().zip(names) {
        *slot = columns
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| InputError::at(source, line, format!("missing column '{name}'")))?;
    }
    Ok((columns, index))
}

/// The header comments and notes shared by the two imucal importers.
fn imucal_site(latitude_deg: Option<f64>) -> Result<(f64, String), InputError> {
    Ok(match option_latitude(latitude_deg, "--latitude-deg")? {
        Some(lat) => (lat, "command line (--latitude-deg)".to_string()),
        None => (IMUCAL_DEFAULT_LATITUDE_DEG, "inferred (Erlangen)".to_string()),
    })
}

fn imucal_label_name(pos: u32) -> String {
    FERRARIS_POSES.iter().find(|p| p.pos == pos).map(|p| format!("{} ({} up)", p.label, p.up_axis)).unwrap_or_default()
}

fn imucal_attitude_comment() -> String {
    let poses: Vec<String> = FERRARIS_POSES
        .iter()
        .map(|p| format!("{}=pos {} pitch {} roll {}", p.label, p.pos, p.pitch_deg, p.roll_deg))
        .collect();
    format!("attitude_source: imucal labels ({}); heading unknown", poses.join(", "))
}

/// Reads an imucal Ferraris session and its label file; see [`parse_imucal`].
pub fn import_imucal(csv: &Path, labels: &Path, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    parse_imucal(
        &read_text(csv)?,
        &csv.display().to_string(),
        &read_text(labels)?,
        &labels.display().to_string(),
        latitude_deg,
    )
}

/// Parses an imucal Ferraris session (`example_ferraris_session.csv`: columns `n_samples`, `gyr_x/y/z` in deg/s,
/// `acc_x/y/z` in m/s^2, found by name, at [`IMUCAL_RATE_HZ`]) and its label file ([`parse_imucal_labels`]).
///
/// Row times are t_s = n_samples / 102.4. Rows whose sample index lies in a static label's `[start, end)` get that
/// pose's position and attitude ([`FERRARIS_POSES`], heading empty); all other rows, the turns included, get
/// pos = 0 (pitch 0, roll 0, heading empty). The latitude is `latitude_deg` or [`IMUCAL_DEFAULT_LATITUDE_DEG`]
/// (inferred); gravity is left to the normal-gravity formula.
pub fn parse_imucal(
    csv_text: &str,
    csv_source: &str,
    labels_text: &str,
    labels_source: &str,
    latitude_deg: Option<f64>,
) -> Result<Imported, InputError> {
    let labels = parse_imucal_labels(labels_text, labels_source)?;
    let (latitude_deg, latitude_source) = imucal_site(latitude_deg)?;
    let mut lines = csv_text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty());
    let (column_line_number, column_line) =
        lines.next().ok_or_else(|| InputError::at(csv_source, 1, "empty file: no column line"))?;
    let (columns, index) = csv_columns(
        column_line,
        ["n_samples", "gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z"],
        csv_source,
        column_line_number,
    )?;
    let mut rows: Vec<Row> = Vec::new();
    let mut previous: Option<u64> = None;
    let mut first_sample: Option<u64> = None;
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != columns.len() {
            return Err(InputError::at(
                csv_source,
                n,
                format!("{} cells, the column line has {}", cells.len(), columns.len()),
            ));
        }
        let sample_cell = cells[index[0]];
        let sample: u64 = sample_cell.parse().map_err(|_| {
            InputError::at(csv_source, n, format!("column 'n_samples': '{sample_cell}' is not a sample index"))
        })?;
        if let Some(p) = previous {
            if sample <= p {
                return Err(InputError::at(
                    csv_source,
                    n,
                    format!("sample index {sample} does not increase (previous row: {p})"),
                ));
            }
        }
        previous = Some(sample);
        first_sample.get_or_insert(sample);
        let num = |i: usize| -> Result<f64, InputError> {
            parse_finite(cells[index[i]]).ok_or_else(|| {
                InputError::at(
                    csv_source,
                    n,
                    format!("column '{}': '{}' is not a finite number", columns[index[i]], cells[index[i]]),
                )
            })
        };
        let rate_degps = [num(1)?, num(2)?, num(3)?];
        let force_b_mps2 = [num(4)?, num(5)?, num(6)?];
        let pose = labels.iter().filter(|r| (r.start..r.end).contains(&sample)).find_map(|r| ferraris_pose(&r.label));
        rows.push(labelled_row(sample as f64 / IMUCAL_RATE_HZ, pose, rate_degps.map(f64::to_radians), force_b_mps2, n));
    }
    if rows.is_empty() {
        return Err(InputError::at(csv_source, column_line_number, "no data rows"));
    }
    let first_sample = first_sample.unwrap_or(0);
    let last_sample = previous.unwrap_or(0);
    for pose in &FERRARIS_POSES {
        if !rows.iter().any(|r| r.pos == pose.pos) {
            let range = labels.iter().find(|r| r.label == pose.label);
            let (start, end) = range.map_or((0, 0), |r| (r.start, r.end));
            return Err(InputError::at(
                labels_source,
                json_line_of(labels_text, pose.label),
                format!(
                    "label '{}' [{start}, {end}) holds no sample of {csv_source} (samples {first_sample}..{last_sample})",
                    pose.label
                ),
            ));
        }
    }
    let comments = vec![
        format!("source: {csv_source} (labels: {labels_source})"),
        format!(
            "source_format: imucal Ferraris session (gyr deg/s, acc m/s^2, {IMUCAL_RATE_HZ} Hz, labels [start, end) \
             sample indices)"
        ),
        format!("latitude_source: {latitude_source}"),
        imucal_attitude_comment(),
    ];
    imucal_finish(
        rows,
        csv_source,
        latitude_deg,
        &latitude_source,
        comments,
        IMUCAL_RATE_HZ,
        "imucal Ferraris session",
        vec![],
    )
}

/// A row of an imucal session: the pose's position and attitude, or pos = 0 outside the static poses.
fn labelled_row(
    t_s: f64,
    pose: Option<&FerrarisPose>,
    rate_b_radps: [f64; 3],
    force_b_mps2: [f64; 3],
    line: usize,
) -> Row {
    Row {
        t_s,
        pos: pose.map_or(0, |p| p.pos),
        pitch_deg: pose.map_or(0.0, |p| p.pitch_deg),
        roll_deg: pose.map_or(0.0, |p| p.roll_deg),
        heading_deg: None,
        rate_b_radps,
        force_b_mps2,
        temp_c: None,
        line,
    }
}

#[allow(clippy::too_many_arguments)]
fn imucal_finish(
    rows: Vec<Row>,
    source: &str,
    latitude_deg: f64,
    latitude_source: &str,
    comments: Vec<String>,
    rate_hz: f64,
    title: &str,
    mut notes: Vec<String>,
) -> Result<Imported, InputError> {
    let recording = Recording {
        source: source.to_string(),
        header: Header {
            latitude_deg,
            height_m: 0.0,
            rate_hz: Some(rate_hz),
            gravity_mps2: None,
            comments,
            truth: None,
        },
        rows,
    };
    notes.insert(
        0,
        format!(
            "latitude {latitude_deg} deg ({latitude_source}; not stated in the data), height 0 m, gravity: normal \
             gravity; heading unknown (empty)"
        ),
    );
    let summary = summarise(&recording, title, &notes, &imucal_label_name);
    Ok(Imported { recording, summary })
}

/// Reads imucal's annotated session (raw counts); see [`parse_imucal_raw`].
pub fn import_imucal_raw(path: &Path, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    parse_imucal_raw(&read_text(path)?, &path.display().to_string(), latitude_deg)
}

/// Parses imucal's `annotated_session.csv`: columns `part` (the label), `samples` (sample index), `acc_x/y/z` and
/// `gyr_x/y/z` in raw counts, found by name, at [`IMUCAL_RAW_RATE_HZ`]. The rows are grouped by label in the file;
/// they are sorted by sample index (which must not repeat), and t_s = samples / 204.8.
///
/// Counts are converted with the nominal scales [`IMUCAL_RAW_ACCEL_LSB_PER_G`] (g = [`STANDARD_GRAVITY_MPS2`]) and
/// [`IMUCAL_RAW_GYRO_LSB_PER_DEGPS`]; the header comments and the summary say so. Labels map to positions as in
/// [`parse_imucal`]; the turns get pos = 0; any other label is an error.
pub fn parse_imucal_raw(text: &str, source: &str, latitude_deg: Option<f64>) -> Result<Imported, InputError> {
    let (latitude_deg, latitude_source) = imucal_site(latitude_deg)?;
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r'))).filter(|(_, l)| !l.trim().is_empty());
    let (column_line_number, column_line) =
        lines.next().ok_or_else(|| InputError::at(source, 1, "empty file: no column line"))?;
    let (columns, index) = csv_columns(
        column_line,
        ["part", "samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"],
        source,
        column_line_number,
    )?;
    let mpss_per_count = STANDARD_GRAVITY_MPS2 / IMUCAL_RAW_ACCEL_LSB_PER_G;
    let radps_per_count = (1.0 / IMUCAL_RAW_GYRO_LSB_PER_DEGPS).to_radians();
    let mut samples: Vec<(u64, Row)> = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != columns.len() {
            return Err(InputError::at(
                source,
                n,
                format!("{} cells, the column line has {}", cells.len(), columns.len()),
            ));
        }
        let label = cells[index[0]];
        let pose = ferraris_pose(label);
        if pose.is_none() && !FERRARIS_ROTATIONS.contains(&label) {
            return Err(InputError::at(
                source,
                n,
                format!("unknown label '{label}' in column 'part' (expected x_p, x_a, y_p, y_a, z_p, z_a or a *_rot)"),
            ));
        }
        let sample_cell = cells[index[1]];
        // The file writes indices as integers or as "12.0".
        let sample = sample_cell
            .parse::<u64>()
            .ok()
            .or_else(|| parse_finite(sample_cell).filter(|v| *v >= 0.0 && v.fract() == 0.0).map(|v| v as u64))
            .ok_or_else(|| {
                InputError::at(source, n, format!("column 'samples': '{sample_cell}' is not a sample index"))
            })?;
        let num = |i: usize| -> Result<f64, InputError> {
            parse_finite(cells[index[i]]).ok_or_else(|| {
                InputError::at(
                    source,
                    n,
                    format!("column '{}': '{}' is not a finite number", columns[index[i]], cells[index[i]]),
                )
            })
        };
        let force_b_mps2 = [num(2)?, num(3)?, num(4)?].map(|c| c * mpss_per_count);
        let rate_b_radps = [num(5)?, num(6)?, num(7)?].map(|c| c * radps_per_count);
        samples.push((sample, labelled_row(sample as f64 / IMUCAL_RAW_RATE_HZ, pose, rate_b_radps, force_b_mps2, n)));
    }
    if samples.is_empty() {
        return Err(InputError::at(source, column_line_number, "no data rows"));
    }
    samples.sort_by_key(|(s, r)| (*s, r.line));
    for pair in samples.windows(2) {
        if pair[0].0 == pair[1].0 {
            let (first, second) = (pair[0].1.line.min(pair[1].1.line), pair[0].1.line.max(pair[1].1.line));
            return Err(InputError::at(
                source,
                second,
                format!("sample index {} repeats (first on line {first})", pair[0].0),
            ));
        }
    }
    let rows: Vec<Row> = samples.into_iter().map(|(_, r)| r).collect();
    let scales = format!(
        "nominal {IMUCAL_RAW_ACCEL_LSB_PER_G} LSB/g (g = {STANDARD_GRAVITY_MPS2} m/s^2, +-16 g) and \
         {IMUCAL_RAW_GYRO_LSB_PER_DEGPS} LSB/(deg/s) (+-2000 deg/s): scales not calibrated"
    );
    let comments = vec![
        format!("source: {source}"),
        format!(
            "source_format: imucal annotated session (raw counts, {IMUCAL_RAW_RATE_HZ} Hz, label column 'part', \
             rows sorted by 'samples')"
        ),
        format!("scale: {scales}"),
        format!("latitude_source: {latitude_source}"),
        imucal_attitude_comment(),
    ];
    let notes = vec![format!("counts converted with {scales}")];
    imucal_finish(
        rows,
        source,
        latitude_deg,
        &latitude_source,
        comments,
        IMUCAL_RAW_RATE_HZ,
        "imucal annotated session (raw)",
        notes,
    )
}

// ---------------------------------------------------------------------------------------------------------------
// imu_tk

/// Parameters of the static-interval detection of imu_tk data ([`detect_static_intervals`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticDetection {
    /// Length of the centred sliding window, s (default 1 s: 101 samples at 100 Hz).
    pub window_s: f64,
    /// Length of the static period at the start of the record that sets the noise level, s (default 50 s).
    pub init_static_s: f64,
    /// Threshold as a multiple of the initial period's variance (default 6; on the Xsens data any factor from 2 to
    /// 20 finds the same 37 to 38 poses).
    pub threshold_factor: f64,
    /// Shortest static interval kept, s (default 3 s).
    pub min_static_s: f64,
}

impl Default for StaticDetection {
    fn default() -> Self {
        StaticDetection { window_s: 1.0, init_static_s: 50.0, threshold_factor: 6.0, min_static_s: 3.0 }
    }
}

/// Static intervals found in a record, and the numbers that found them.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticIntervals {
    /// Sample index ranges (end exclusive), in time order.
    pub ranges: Vec<Range<usize>>,
    /// Variance of the initial static period (sum over the three axes), (m/s^2)^2.
    pub init_variance_mps2sq: f64,
    /// The threshold applied to the windowed variance, (m/s^2)^2.
    pub threshold_mps2sq: f64,
    /// Half-width of the sliding window, samples.
    pub half_window_samples: usize,
    /// Shortest run of static samples kept.
    pub min_samples: usize,
}

/// Finds static intervals in a specific-force record sampled at `rate_hz` (times `t_s`, one per sample).
///
/// Rule: for every sample k the windowed variance V_k is the sum over x, y, z of the population variance of the
/// specific force over the samples [k - h, k + h] (clipped at the ends), h = round(window_s * rate_hz / 2). The
/// reference V0 is the same sum over the initial static period (t - t_first < init_static_s). A sample is static
/// when V_k < threshold_factor * max(V0, floor_variance_mps2sq) (the floor is the quantisation variance, so that
/// noiseless data still have a usable threshold). Maximal runs of static samples of at least
/// round(min_static_s * rate_hz) samples are the static intervals. The error is the reason (record shorter than
/// the initial period, or too few samples).
pub fn detect_static_intervals(
    force_b_mps2: &[[f64; 3]],
    t_s: &[f64],
    rate_hz: f64,
    detection: &StaticDetection,
    floor_variance_mps2sq: f64,
) -> Result<StaticIntervals, String> {
    let n = force_b_mps2.len();
    if n < 2 || t_s.len() != n {
        return Err(format!("{n} samples: too few for static detection"));
    }
    let t_first = t_s[0];
    let duration_s = t_s[n - 1] - t_first;
    if duration_s < detection.init_static_s {
        return Err(format!(
            "the record lasts {duration_s:.2} s, shorter than the initial static period of {} s that sets the \
             detection threshold",
            detection.init_static_s
        ));
    }
    let init_count = t_s.iter().take_while(|t| **t - t_first < detection.init_static_s).count().max(2);
    let mut mean = [0.0; 3];
    for f in &force_b_mps2[..init_count] {
        for i in 0..3 {
            mean[i] += f[i] / init_count as f64;
        }
    }
    let init_variance_mps2sq: f64 =
        force_b_mps2[..init_count].iter().map(|f| (0..3).map(|i| (f[i] - mean[i]).powi(2)).sum::<f64>()).sum::<f64>()
            / init_count as f64;
    let threshold_mps2sq = detection.threshold_factor * init_variance_mps2sq.max(floor_variance_mps2sq);

    // Prefix sums of the force less the initial mean (small numbers: no cancellation in the variance).
    let mut sum = vec![[0.0f64; 3]; n + 1];
    let mut sum_sq = vec![[0.0f64; 3]; n + 1];
    for (k, f) in force_b_mps2.iter().enumerate() {
        for i in 0..3 {
            let d = f[i] - mean[i];
            sum[k + 1][i] = sum[k][i] + d;
            sum_sq[k + 1][i] = sum_sq[k][i] + d * d;
        }
    }
    let half_window_samples = ((detection.window_s * rate_hz / 2.0).round() as usize).max(1);
    let min_samples = ((detection.min_static_s * rate_hz).round() as usize).max(1);
    let is_static = |k: usize| -> bool {
        let lo = k.saturating_sub(half_window_samples);
        let hi = (k + half_window_samples + 1).min(n);
        let m = (hi - lo) as f64;
        let variance: f64 = (0..3)
            .map(|i| {
                let mean_i = (sum[hi][i] - sum[lo][i]) / m;
                ((sum_sq[hi][i] - sum_sq[lo][i]) / m - mean_i * mean_i).max(0.0)
            })
            .sum();
        variance < threshold_mps2sq
    };
    let mut ranges = Vec::new();
    let mut start: Option<usize> = None;
    for k in 0..=n {
        let quiet = k < n && is_static(k);
        match (quiet, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                if k - s >= min_samples {
                    ranges.push(s..k);
                }
                start = None;
            }
            _ => {}
        }
    }
    Ok(StaticIntervals { ranges, init_variance_mps2sq, threshold_mps2sq, half_window_samples, min_samples })
}

/// One imu_tk file: (line, t_s, counts x y z) per sample.
fn parse_imutk_counts(text: &str, source: &str) -> Result<Vec<(usize, f64, [f64; 3])>, InputError> {
    let mut samples: Vec<(usize, f64, [f64; 3])> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('%') || line.starts_with('#') {
            continue;
        }
        let v = whitespace_numbers(line, 4, "sample line (t_s x y z)").map_err(|r| InputError::at(source, n, r))?;
        if let Some((_, previous_t_s, _)) = samples.last() {
            if v[0] <= *previous_t_s {
                return Err(InputError::at(
                    source,
                    n,
                    format!("time {} s does not increase (previous sample: {previous_t_s} s)", v[0]),
                ));
            }
        }
        let counts = [v[1], v[2], v[3]];
        if let Some(c) = counts.iter().find(|c| !(0.0..=65535.0).contains(*c)) {
            return Err(InputError::at(source, n, format!("count {c} is outside the unsigned 16-bit range 0..65535")));
        }
        samples.push((n, v[0], counts));
    }
    if samples.len() < 2 {
        return Err(InputError::file(source, format!("{} samples: too few", samples.len())));
    }
    Ok(samples)
}

/// Reads imu_tk's accelerometer and gyro files; see [`parse_imutk`].
pub fn import_imutk(
    acc: &Path,
    gyro: &Path,
    latitude_deg: Option<f64>,
    detection: &StaticDetection,
) -> Result<Imported, InputError> {
    parse_imutk(
        &read_text(acc)?,
        &acc.display().to_string(),
        &read_text(gyro)?,
        &gyro.display().to_string(),
        latitude_deg,
        detection,
    )
}

/// Parses imu_tk text counts: an accelerometer file and a gyro file (`xsens_acc.mat`, `xsens_gyro.mat`: plain
/// text despite the name), each with lines `t_s x y z`, x, y, z in unsigned 16-bit counts. The two files must have
/// the same number of samples at the same times (within [`IMUTK_MAX_TIME_MISMATCH_S`]).
///
/// Conversion with the nominal factory gains: force_mps2 = (count - 32768) / [`IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2`],
/// rate_radps = (count - 32768) / [`IMUTK_GYRO_GAIN_COUNTS_PER_RADPS`] (no misalignment, no measured offsets; the
/// header says so). The rate is 1 / median(dt). There are no labels: static intervals are found by
/// [`detect_static_intervals`] on the specific force with `detection` (quantisation floor: the sum over the axes
/// of (1 count / gain)^2 / 12), and interval k becomes position k = 1, 2, ... with the pitch and roll of its mean
/// specific force ([`level_attitude_deg`]) and an empty heading; samples between intervals get pos = 0 (pitch 0,
/// roll 0, heading empty). Gravity is [`IMUTK_GRAVITY_MPS2`] (imu_tk's example value); the latitude is
/// `latitude_deg` or [`IMUTK_DEFAULT_LATITUDE_DEG`] (unknown).
pub fn parse_imutk(
    acc_text: &str,
    acc_source: &str,
    gyro_text: &str,
    gyro_source: &str,
    latitude_deg: Option<f64>,
    detection: &StaticDetection,
) -> Result<Imported, InputError> {
    let latitude = option_latitude(latitude_deg, "--latitude-deg")?;
    let acc = parse_imutk_counts(acc_text, acc_source)?;
    let gyro = parse_imutk_counts(gyro_text, gyro_source)?;
    if acc.len() != gyro.len() {
        return Err(InputError::file(
            gyro_source,
            format!("{} samples, the accelerometer file {acc_source} has {}", gyro.len(), acc.len()),
        ));
    }
    for ((_, t_acc_s, _), (n, t_gyro_s, _)) in acc.iter().zip(&gyro) {
        if (t_acc_s - t_gyro_s).abs() > IMUTK_MAX_TIME_MISMATCH_S {
            return Err(InputError::at(
                gyro_source,
                *n,
                format!("time {t_gyro_s} s differs from the accelerometer's {t_acc_s} s at the same sample"),
            ));
        }
    }
    let mut dt_s: Vec<f64> = acc.windows(2).map(|w| w[1].1 - w[0].1).collect();
    dt_s.sort_by(f64::total_cmp);
    let median_dt_s = dt_s[dt_s.len() / 2];
    let rate_hz = (100.0 / median_dt_s).round() / 100.0;

    let force: Vec<[f64; 3]> = acc
        .iter()
        .map(|(_, _, c)| [0, 1, 2].map(|i| (c[i] - IMUTK_OFFSET_COUNTS) / IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2[i]))
        .collect();
    let rate: Vec<[f64; 3]> = gyro
        .iter()
        .map(|(_, _, c)| [0, 1, 2].map(|i| (c[i] - IMUTK_OFFSET_COUNTS) / IMUTK_GYRO_GAIN_COUNTS_PER_RADPS[i]))
        .collect();
    let t_s: Vec<f64> = acc.iter().map(|(_, t, _)| *t).collect();
    let floor_variance_mps2sq: f64 = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2.iter().map(|g| 1.0 / (g * g) / 12.0).sum();
    let intervals = detect_static_intervals(&force, &t_s, rate_hz, detection, floor_variance_mps2sq)
        .map_err(|r| InputError::file(acc_source, r))?;

    let mut rows: Vec<Row> = acc
        .iter()
        .zip(force.iter().zip(&rate))
        .map(|((n, t, _), (f, w))| Row {
            t_s: *t,
            pos: 0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            heading_deg: None,
            rate_b_radps: *w,
            force_b_mps2: *f,
            temp_c: None,
            line: *n,
        })
        .collect();
    for (k, range) in intervals.ranges.iter().enumerate() {
        let count = range.len() as f64;
        let mut mean = [0.0; 3];
        for f in &force[range.clone()] {
            for i in 0..3 {
                mean[i] += f[i] / count;
            }
        }
        let (pitch_deg, roll_deg) = level_attitude_deg(mean).ok_or_else(|| {
            InputError::at(
                acc_source,
                acc[range.start].0,
                "static interval with zero mean specific force: cannot level",
            )
        })?;
        for row in &mut rows[range.clone()] {
            row.pos = k as u32 + 1;
            row.pitch_deg = pitch_deg;
            row.roll_deg = roll_deg;
        }
    }
    let (latitude_deg, latitude_source) = match latitude {
        Some(lat) => (lat, "command line (--latitude-deg)".to_string()),
        None => (
            IMUTK_DEFAULT_LATITUDE_DEG,
            format!(
                "unknown, {IMUTK_DEFAULT_LATITUDE_DEG} assumed (inferred: not stated in the data; set --latitude-deg)"
            ),
        ),
    };
    let [ax, ay, az] = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2;
    let [gx, gy, gz] = IMUTK_GYRO_GAIN_COUNTS_PER_RADPS;
    let gains = format!(
        "nominal factory gains: accel diag [{ax}, {ay}, {az}] counts/(m/s^2), gyro diag [{gx}, {gy}, {gz}] \
         counts/(rad/s), offset {IMUTK_OFFSET_COUNTS} counts, no misalignment"
    );
    let rule = format!(
        "sliding {} s window ({} samples each side), sum of the 3 accel variances < {} x initial {} s variance \
         ({:.3e} (m/s^2)^2, threshold {:.3e}), at least {} s",
        detection.window_s,
        intervals.half_window_samples,
        detection.threshold_factor,
        detection.init_static_s,
        intervals.init_variance_mps2sq,
        intervals.threshold_mps2sq,
        detection.min_static_s
    );
    let comments = vec![
        format!("source: {acc_source} + {gyro_source}"),
        "source_format: imu_tk text counts (t_s x y z, unsigned 16-bit counts, accelerometer and gyro files)"
            .to_string(),
        format!("scale: {gains}"),
        format!("latitude_source: {latitude_source}"),
        format!("gravity_source: imu_tk example value {IMUTK_GRAVITY_MPS2} m/s^2"),
        "attitude_source: accelerometer-levelled".to_string(),
        format!("static_detection: {rule}"),
    ];
    let recording = Recording {
        source: acc_source.to_string(),
        header: Header {
            latitude_deg,
            height_m: 0.0,
            rate_hz: Some(rate_hz),
            gravity_mps2: Some(IMUTK_GRAVITY_MPS2),
            comments,
            truth: None,
        },
        rows,
    };
    let notes = vec![
        format!(
            "latitude {latitude_deg} deg ({latitude_source}), g {IMUTK_GRAVITY_MPS2} m/s^2 (imu_tk's example value)"
        ),
        format!("counts converted with the {gains}"),
        format!("static intervals: {rule}; {} found", intervals.ranges.len()),
        "pitch and roll of each interval: levelled from its mean specific force (nominal gains: errors of degrees); \
         heading unknown (empty)"
            .to_string(),
    ];
    let summary = summarise(&recording, "imu_tk text counts", &notes, &|_| String::new());
    Ok(Imported { recording, summary })
}

// ---------------------------------------------------------------------------------------------------------------
// Summary

/// The human summary of an imported recording.
fn summarise(recording: &Recording, title: &str, notes: &[String], name: &dyn Fn(u32) -> String) -> String {
    let mut out = String::new();
    let rows = &recording.rows;
    let duration_s = match (rows.first(), rows.last()) {
        (Some(a), Some(b)) => b.t_s - a.t_s,
        _ => 0.0,
    };
    let rate = recording.header.rate_hz.map_or("unknown".to_string(), |r| format!("{r} Hz"));
    let _ = writeln!(out, "sinscal import: {} ({title})", recording.source);
    let _ = writeln!(out, "  {} samples at {rate}, {duration_s:.2} s", rows.len());
    for note in notes {
        let _ = writeln!(out, "  {note}");
    }
    let stats = position_stats(recording);
    let in_positions: usize = stats.iter().map(|s| s.samples).sum();
    let _ = writeln!(
        out,
        "  {} position(s), {in_positions} samples in positions, {} with pos 0",
        stats.len(),
        rows.len() - in_positions
    );
    let _ = writeln!(
        out,
        "  {:>4} {:<12} {:>8} {:>9} {:>8} {:>7} {:>8} {:>8}  {:>32}  {:>30}",
        "pos",
        "label",
        "samples",
        "start[s]",
        "dur[s]",
        "pitch",
        "roll",
        "heading",
        "mean gyro x y z [deg/s]",
        "mean accel x y z [m/s^2]"
    );
    for s in &stats {
        let heading = s.heading_deg.map_or("-".to_string(), |h| format!("{h:.2}"));
        let w = s.mean_rate_b_radps.map(f64::to_degrees);
        let f = s.mean_force_b_mps2;
        let _ = writeln!(
            out,
            "  {:>4} {:<12} {:>8} {:>9.2} {:>8.2} {:>7.2} {:>8.2} {:>8}  {:>+10.6} {:>+10.6} {:>+10.6}  {:>+9.4} {:>+9.4} {:>+9.4}",
            s.pos,
            name(s.pos),
            s.samples,
            s.first_t_s,
            s.last_t_s - s.first_t_s,
            s.pitch_deg,
            s.roll_deg,
            heading,
            w[0],
            w[1],
            w[2],
            f[0],
            f[1],
            f[2]
        );
    }
    out
}
