//! Importers of measured data sets into the recording format of docs/formats.md#recording (`sinscal import`).
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
//! [`mat`] reads the numeric matrices of a MATLAB MAT-file (level 5: MATLAB's `-v6` and `-v7`, compressed or
//! not; version 7.3, HDF5), [`mat::read_mat`]; it refuses text files named `.mat` (such as imu_tk's) and names
//! version 4 files.
//!
//! Every recording says where it came from in its header comments (`# source: ...`, `# source_format: ...`,
//! `# latitude_source: ...`, `# attitude_source: ...`, and the nominal scales used). Malformed input is reported as
//! an [`InputError`] naming the file, the line and the reason; nothing here panics on bad input.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::io::error::InputError;
use crate::io::recording::{Header, Recording, Row};
use crate::io::ARCSEC_PER_RAD;

mod columns;
pub mod gyro_units;
mod imucal;
mod imutk;
pub mod layout;
pub mod mat;
mod psins;

pub use columns::*;
pub use imucal::*;
pub use imutk::*;
pub use layout::Layout;
pub use psins::*;

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

/// The `# attitude_source:` of a recording whose pitch and roll were levelled from its own accelerometers (no
/// reference attitude): `sinscal calibrate` then estimates every position's attitude
/// (docs/method.md#unknown-attitudes).
pub const ATTITUDE_SOURCE_LEVELLED: &str = "accelerometer-levelled";

/// Largest difference accepted between the time stamps of the imu_tk accelerometer and gyro files, s.
pub const IMUTK_MAX_TIME_MISMATCH_S: f64 = 1e-6;

/// One labelled static pose of an imucal Ferraris session and the attitude it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FerrarisPose {
    /// imucal's label (`x_p` = body x pointing up, `x_a` = body x pointing down, ...).
    pub label: &'static str,
    /// Position label in the recording.
    pub pos: u32,
    /// Pitch, degrees (docs/conventions.md).
    pub pitch_deg: f64,
    /// Roll, degrees (docs/conventions.md).
    pub roll_deg: f64,
    /// The body axis that points up, for messages ("+x", "-z", ...).
    pub up_axis: &'static str,
}

/// The six static poses of a Ferraris session, positions 1..6, with pitch and roll from the conventions'
/// C_b^n = Rz(-psi) Rx(theta) Ry(gamma): the up direction seen in the body is Ry(-gamma) Rx(-theta) [0, 0, 1]
/// = [-sin(gamma) cos(theta), sin(theta), cos(gamma) cos(theta)], so roll -90 puts body x up, roll +90 body x
/// down (the check value of docs/conventions.md#attitude), pitch +90 body y up, roll 180 body z down. Heading is unknown.
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
    /// Any layout described by a TOML file (`--layout`): text, binary records or a MAT-file matrix, units, rates or
    /// increments, axes; positions from `--labels` or detected (docs/data.md#described-layouts).
    Columns,
}

/// Arguments of `sinscal import`.
#[derive(Clone, Debug, clap::Args)]
pub struct ImportArgs {
    /// Input format.
    #[arg(value_enum)]
    pub format: Format,
    /// Input file(s): one for psins, imucal and imucal-raw; two (accelerometer, then gyro) for imutk; for columns,
    /// one, or several read as the layout's [files] says (side by side, the fields numbered on from one file to the
    /// next: the default for text files; in sequence; or as sessions).
    #[arg(required = true, num_args = 1..)]
    pub inputs: Vec<PathBuf>,
    /// The recording to write (docs/formats.md#recording).
    #[arg(long)]
    pub out: PathBuf,
    /// Latitude, degrees north. Default: the file's (psins), 49.6 (imucal, inferred: Erlangen), 45 (imutk, unknown).
    #[arg(long, allow_negative_numbers = true)]
    pub latitude_deg: Option<f64>,
    /// imucal: the JSON label file (default: INPUT with '.csv' replaced by '_list.json'). columns: a CSV of
    /// positions (start_s, end_s, pitch_deg, roll_deg, heading_deg, pos, file); without it static intervals are
    /// detected.
    #[arg(long)]
    pub labels: Option<PathBuf>,
    /// columns: the layout file (TOML, docs/data.md#described-layouts).
    #[arg(long)]
    pub layout: Option<PathBuf>,
    /// columns: a position as `START_S,END_S,PITCH_DEG,ROLL_DEG[,HEADING_DEG]` (heading empty or '?' = unknown),
    /// instead of a labels file; repeat it for each position (numbered 1, 2, ... in order).
    #[arg(long, value_name = "START_S,END_S,PITCH_DEG,ROLL_DEG[,HEADING_DEG]")]
    pub position: Vec<String>,
    /// columns, files in sequence or sessions: the position of a whole input file as `PITCH_DEG,ROLL_DEG[,
    /// HEADING_DEG]`, one flag per input file in order (file k is position k), instead of a labels file.
    #[arg(long, value_name = "PITCH_DEG,ROLL_DEG[,HEADING_DEG]", allow_hyphen_values = true)]
    pub file_position: Vec<String>,
    /// Static detection (imutk, columns without --labels): length of the sliding window, s.
    #[arg(long, default_value_t = StaticDetection::default().window_s)]
    pub static_window_s: f64,
    /// Static detection: length of the static period at the start that sets the noise level, s.
    #[arg(long, default_value_t = StaticDetection::default().init_static_s)]
    pub static_init_s: f64,
    /// Static detection: threshold as a multiple of that period's variance.
    #[arg(long, default_value_t = StaticDetection::default().threshold_factor)]
    pub static_threshold: f64,
    /// Static detection: shortest static interval kept, s.
    #[arg(long, default_value_t = StaticDetection::default().min_static_s)]
    pub static_min_s: f64,
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
        if self.format == Format::Columns {
            if self.layout.is_none() {
                return usage("columns needs --layout FILE (docs/data.md#described-layouts)".to_string());
            }
        } else if self.layout.is_some() {
            return usage("--layout applies only to the columns format".to_string());
        } else if self.inputs.len() != wanted {
            let what = match self.format {
                Format::Imutk => "imutk needs two inputs: the accelerometer file, then the gyro file",
                _ => "this format needs exactly one input file",
            };
            return usage(format!("{what} (got {})", self.inputs.len()));
        }
        if self.labels.is_some() && !matches!(self.format, Format::Imucal | Format::Columns) {
            return usage("--labels applies only to the imucal and columns formats".to_string());
        }
        if !self.position.is_empty() && (self.format != Format::Columns || self.labels.is_some()) {
            return usage("--position applies only to the columns format, and not with --labels".to_string());
        }
        if !self.file_position.is_empty() {
            if self.format != Format::Columns || self.labels.is_some() || !self.position.is_empty() {
                return usage(
                    "--file-position applies only to the columns format, and not with --labels or --position".into(),
                );
            }
            if self.file_position.len() != self.inputs.len() {
                return usage(format!(
                    "--file-position: one per input file ({} flags for {} files)",
                    self.file_position.len(),
                    self.inputs.len()
                ));
            }
        }
        let d = self.static_detection();
        let positive = [d.window_s, d.init_static_s, d.threshold_factor, d.min_static_s];
        if positive.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return usage(
                "--static-window-s, --static-init-s, --static-threshold and --static-min-s are positive".into(),
            );
        }
        if let Some(lat) = self.latitude_deg {
            if !(lat.is_finite() && (-90.0..=90.0).contains(&lat)) {
                return usage(format!("--latitude-deg {lat} is outside [-90, 90]"));
            }
        }
        Ok(())
    }
}

impl ImportArgs {
    /// The static detection of the `--static-*` options.
    pub fn static_detection(&self) -> StaticDetection {
        StaticDetection {
            window_s: self.static_window_s,
            init_static_s: self.static_init_s,
            threshold_factor: self.static_threshold,
            min_static_s: self.static_min_s,
        }
    }
}

/// Runs `sinscal import` (after [`ImportArgs::validate`]): reads the inputs, writes the recording to `--out`, and
/// returns the human summary to print.
pub fn run(args: &ImportArgs) -> Result<String, InputError> {
    let first = args.inputs.first().ok_or_else(|| InputError::file("sinscal import", "no input file"))?;
    let mut inputs: Vec<&Path> = args.inputs.iter().map(|p| p.as_path()).collect();
    let labels = args.labels.clone().unwrap_or_else(|| default_labels_path(first));
    if args.format == Format::Imucal {
        inputs.push(&labels);
    }
    if args.format == Format::Columns {
        inputs.extend(args.labels.iter().map(|p| p.as_path()));
        inputs.extend(args.layout.iter().map(|p| p.as_path()));
    }
    refuse_output_onto_input(&args.out, &inputs)?;
    let imported = match args.format {
        Format::Psins => import_psins(first, args.latitude_deg)?,
        Format::Imucal => import_imucal(first, &labels, args.latitude_deg)?,
        Format::ImucalRaw => import_imucal_raw(first, args.latitude_deg)?,
        Format::Imutk => {
            let gyro = args
                .inputs
                .get(1)
                .ok_or_else(|| InputError::file("sinscal import", "imutk needs the gyro file as second input"))?;
            import_imutk(first, gyro, args.latitude_deg, &args.static_detection())?
        }
        Format::Columns => run_columns(args)?,
    };
    imported.recording.write(&args.out)?;
    Ok(format!("{}wrote {}\n", imported.summary, args.out.display()))
}

/// `sinscal import columns`: the layout, the positions (labels file or detection) and the inputs.
fn run_columns(args: &ImportArgs) -> Result<Imported, InputError> {
    let layout_path = args.layout.as_deref().ok_or_else(|| InputError::file("sinscal import", "no --layout"))?;
    let layout_source = layout_path.display().to_string();
    let layout = Layout::parse(&read_text(layout_path)?, &layout_source)?;
    let labels_source = match &args.labels {
        Some(p) => Some(p.display().to_string()),
        None if !args.position.is_empty() => Some("--position flags".to_string()),
        None if !args.file_position.is_empty() => Some("--file-position flags".to_string()),
        None => None,
    };
    let positions = match &args.labels {
        Some(p) => Positions::Labels(parse_labels(&read_text(p)?, &p.display().to_string())?),
        None if !args.position.is_empty() => {
            // The flags as the lines of a labels file (line k + 1 of it is the k-th --position).
            let lines: Vec<&str> = args.position.iter().map(|p| p.as_str()).collect();
            let text = format!("start_s,end_s,pitch_deg,roll_deg,heading_deg\n{}\n", lines.join("\n"));
            Positions::Labels(parse_labels(&text, "--position")?)
        }
        None if !args.file_position.is_empty() => {
            // The flags as the lines of a labels file of whole files (line k + 1 is the k-th flag, for file k).
            let lines: Vec<String> =
                args.file_position.iter().enumerate().map(|(k, p)| format!("{},{p}", k + 1)).collect();
            let text = format!("file,pitch_deg,roll_deg,heading_deg\n{}\n", lines.join("\n"));
            Positions::Labels(parse_labels(&text, "--file-position")?)
        }
        None => Positions::Detect(args.static_detection()),
    };
    let latitude_deg = option_latitude(args.latitude_deg, "--latitude-deg")?;
    let import = ColumnsImport {
        layout: &layout,
        layout_source: &layout_source,
        positions,
        labels_source: labels_source.as_deref(),
        latitude_deg,
    };
    let inputs: Vec<&Path> = args.inputs.iter().map(|p| p.as_path()).collect();
    import_columns(&inputs, &import)
}

/// The output must not be one of the inputs: the import would overwrite what it reads.
fn refuse_output_onto_input(out: &Path, inputs: &[&Path]) -> Result<(), InputError> {
    for input in inputs {
        if crate::io::same_file(input, out) {
            return Err(InputError::file(
                &out.display().to_string(),
                format!("--out is the input {}: the import would overwrite what it reads", input.display()),
            ));
        }
    }
    Ok(())
}

/// An imported recording and its human summary (samples, rate, duration, positions with their sample counts and
/// mean gyro and accelerometer outputs, and where the numbers came from).
#[derive(Clone, Debug)]
pub struct Imported {
    /// The recording (docs/formats.md#recording semantics).
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
/// cos(gamma) cos(theta)] (docs/conventions.md), so pitch = atan2(u_y, hypot(u_x, u_z)) in [-90, 90] and
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

/// Interval k of `ranges` (rows in time order) becomes position k + 1, levelled from its mean specific force
/// ([`level_attitude_deg`]), heading unknown. The error names the row's line where the mean force is zero.
fn level_intervals(rows: &mut [Row], ranges: &[Range<usize>], source: &str) -> Result<(), InputError> {
    for (k, range) in ranges.iter().enumerate() {
        let count = range.len() as f64;
        let mut mean = [0.0; 3];
        for row in &rows[range.clone()] {
            for i in 0..3 {
                mean[i] += row.force_b_mps2[i] / count;
            }
        }
        let (pitch_deg, roll_deg) = level_attitude_deg(mean).ok_or_else(|| {
            InputError::at(
                source,
                rows[range.start].line,
                "static interval with zero mean specific force: cannot level",
            )
        })?;
        for row in &mut rows[range.clone()] {
            row.pos = k as u32 + 1;
            row.pitch_deg = pitch_deg;
            row.roll_deg = roll_deg;
            row.heading_deg = None;
        }
    }
    Ok(())
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
    crate::io::recording::read_text_capped(path)
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
        // An accelerometer-only recording has no gyro means: "-".
        let w = s.mean_rate_b_radps.map(|v| match recording.has_gyro {
            true => format!("{:>+10.6}", v.to_degrees()),
            false => format!("{:>10}", "-"),
        });
        let f = s.mean_force_b_mps2;
        let _ = writeln!(
            out,
            "  {:>4} {:<12} {:>8} {:>9.2} {:>8.2} {:>7.2} {:>8.2} {:>8}  {} {} {}  {:>+9.4} {:>+9.4} {:>+9.4}",
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
