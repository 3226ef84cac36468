//! The recording file of docs/formats.md#recording (CSV, version 1): reading with line-accurate errors, writing,
//! and grouping rows into dwells.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::ops::ControlFlow;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Mutex};

use crate::io::dwell_tally::DwellTally;
use crate::io::error::InputError;

/// Header of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// Geodetic latitude, degrees north.
    pub latitude_deg: f64,
    /// Height above the ellipsoid, m (0 when the header does not say).
    pub height_m: f64,
    /// Nominal sample rate, Hz, if given.
    pub rate_hz: Option<f64>,
    /// Local gravity, m/s^2, if given (otherwise normal gravity is used).
    pub gravity_mps2: Option<f64>,
    /// Free-text header lines that are not `key: value` pairs sinscal knows (kept when writing).
    pub comments: Vec<String>,
    /// The truth of a sinscal simulation (`# truth_*` header keys), absent for measured data.
    pub truth: Option<SimulationTruth>,
    /// How well the labelled attitudes are known, degrees (one standard deviation, each axis), if the header
    /// says (`# pose_tolerance_deg`, docs/formats.md#recording).
    pub pose_tolerance_deg: Option<f64>,
}

/// Largest pose tolerance a header or `--pose-tolerance` may give, degrees: beyond it the small-angle prior
/// means nothing (and the estimator's plausibility check on poses refuses anything beyond 10 deg anyway).
pub const MAX_POSE_TOLERANCE_DEG: f64 = 10.0;

/// The true errors of a simulated IMU, as written by sinscal into the header of a simulated recording
/// (extra `# truth_*: x,y,z` keys; other tools ignore them, as docs/formats.md#recording allows for unknown keys).
#[derive(Clone, Debug, PartialEq)]
pub struct SimulationTruth {
    /// Noise seed of the simulation.
    pub seed: u64,
    /// Gyro bias, body frame, rad/s.
    pub gyro_bias_b_radps: [f64; 3],
    /// Accelerometer bias, body frame, m/s^2.
    pub accel_bias_b_mps2: [f64; 3],
    /// Gyro white noise per sample, rad/s.
    pub gyro_noise_radps: f64,
    /// Accelerometer white noise per sample, m/s^2.
    pub accel_noise_mps2: f64,
    /// Turntable reference offset (e, n, u), rad.
    pub reference_offset_n_rad: [f64; 3],
}

/// Largest latitude a recording may have, degrees: at 89.9 deg the horizontal Earth rate that gives north is
/// 0.026 deg/h, and at a pole there is no north (the heading's standard error divides by `cos L`).
pub const MAX_LATITUDE_DEG: f64 = 89.9;

/// One row (sample) of a recording.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Time, s.
    pub t_s: f64,
    /// Position (dwell) label; 0 = not in a position.
    pub pos: u32,
    /// Reference pitch, degrees.
    pub pitch_deg: f64,
    /// Reference roll, degrees.
    pub roll_deg: f64,
    /// Reference heading, degrees clockwise from north; `None` = unknown.
    pub heading_deg: Option<f64>,
    /// Gyro x, y, z (body), rad/s.
    pub rate_b_radps: [f64; 3],
    /// Accelerometer x, y, z (body), m/s^2.
    pub force_b_mps2: [f64; 3],
    /// Sensor temperature, deg C, if recorded.
    pub temp_c: Option<f64>,
    /// The body axis (0 = x, 1 = y, 2 = z) of a labelled turn the row belongs to: a turn about that axis that
    /// ends where it started (a Ferraris turn), `turn` column `x`, `y` or `z`; only on rows with `pos = 0`.
    pub turn_axis: Option<usize>,
    /// Line number in the file (1-based), for messages.
    pub line: usize,
}

/// A recording in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// Where it came from (file name for messages).
    pub source: String,
    /// Header.
    pub header: Header,
    /// Rows in file order.
    pub rows: Vec<Row>,
    /// Whether the recording has the three gyro columns. Accelerometer-only data (docs/formats.md#columns)
    /// have none; their rows carry `rate_b_radps = [0.0; 3]`, which no command may take as a measurement.
    pub has_gyro: bool,
}

/// The gyro columns, present as a group or absent (accelerometer-only data).
pub const GYRO_COLUMNS: [&str; 3] = ["gx_radps", "gy_radps", "gz_radps"];

/// The optional `turn` column: its cells name the body axis of a labelled turn (docs/formats.md#columns).
pub const TURN_COLUMN: &str = "turn";
/// The `turn` cells of the axes x, y, z.
pub const TURN_AXES: [&str; 3] = ["x", "y", "z"];

/// The optional columns a recording writes beside the required ones and the gyros.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExtraColumns {
    /// `temp_c`.
    pub temp: bool,
    /// `turn`.
    pub turn: bool,
}

/// Largest relative disagreement between the header's `rate_hz` and the median time step of `t_s`.
pub const RATE_TOLERANCE: f64 = 0.01;

const COLUMNS: [&str; 11] = [
    "t_s",
    "pos",
    "pitch_deg",
    "roll_deg",
    "heading_deg",
    "gx_radps",
    "gy_radps",
    "gz_radps",
    "ax_mps2",
    "ay_mps2",
    "az_mps2",
];

impl Recording {
    /// Reads a recording file whole into memory (its rows as f64; for a file read in passes without keeping
    /// its rows, [`RecordingFile`]). Errors are those of [`Recording::parse`], the first in file order.
    pub fn read(path: &Path) -> Result<Recording, InputError> {
        RecordingFile::open(path)?.read_all()
    }

    /// Parses the text of a recording; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Recording, InputError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
        let (header, header_line, column_line, rate_line) =
            parse_header(&mut lines, &|| text.lines().count().max(1), source)?;
        let columns = parse_columns(column_line, header_line, source)?;
        let mut rows = RowParser::new(&columns, source);
        for (n, line) in lines {
            rows.line(n, line)?;
        }
        Recording::assemble(header, header_line, &columns, rows.rows, rate_line, source)
    }

    /// The recording from its parts, after the checks that need every row.
    fn assemble(
        header: Header,
        header_line: usize,
        columns: &Columns,
        rows: Vec<Row>,
        rate_line: Option<usize>,
        source: &str,
    ) -> Result<Recording, InputError> {
        if rows.is_empty() {
            return Err(InputError::at(source, header_line, "no data rows"));
        }
        if let (Some(rate_hz), Some(line)) = (header.rate_hz, rate_line) {
            let steps = TimeSteps::of(rows.iter().map(|r| r.t_s));
            check_rate(rate_hz, &steps).map_err(|reason| InputError::at(source, line, reason))?;
        }
        let has_gyro = columns.gyro.is_some();
        Ok(Recording { source: source.to_string(), header, rows, has_gyro })
    }

    /// Writes the recording in the docs/formats.md#recording format. Numbers are written in Rust's shortest
    /// round-trip form, so reading the file back gives the same f64 values.
    /// Nothing is checked: [`Recording::write`] checks.
    pub fn to_csv(&self) -> String {
        let mut out = Vec::new();
        RecordingWriter::unchecked(&mut out, &self.header, self.has_gyro, RowSource::extra_columns(self))
            .and_then(|mut w| self.rows.iter().try_for_each(|r| w.row(r)))
            .expect("into memory, without the rules, writing cannot fail");
        String::from_utf8(out).expect("the writer writes UTF-8")
    }

    /// Writes the recording to a file, after the reader's rules on what would be written
    /// (docs/formats.md#bad-input): the header's numbers within their bounds, every value finite, times strictly
    /// increasing, and `rate_hz` agreeing with them. Nothing is written when a rule is broken ([`write_file`]).
    pub fn write(&self, path: &Path) -> Result<(), InputError> {
        write_file(path, &self.header, self.has_gyro, RowSource::extra_columns(self), |w| {
            self.rows.iter().try_for_each(|r| w.row(r)).map_err(|e| e.writing(path))
        })
    }

    /// The dwells, in order of first appearance of their label. Rows with the same non-zero label form
    /// one dwell (docs/formats.md#recording); label 0 rows are skipped.
    pub fn dwells(&self) -> Vec<Dwell<'_>> {
        let mut dwells: Vec<Dwell<'_>> = Vec::new();
        // Label -> index: one look-up per row, whatever the number of labels.
        let mut index: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
        for row in self.rows.iter().filter(|r| r.pos != 0) {
            let next = dwells.len();
            let i = *index.entry(row.pos).or_insert(next);
            if i == next {
                dwells.push(Dwell { pos: row.pos, rows: Vec::new() });
            }
            dwells[i].rows.push(row);
        }
        dwells
    }
}

/// Why a recording was not written.
#[derive(Debug)]
pub enum WriteError {
    /// Its reader would refuse it: the rule broken.
    Refused(String),
    /// The output failed.
    Io(std::io::Error),
}

impl WriteError {
    /// The error of writing `path`: `PATH: not written, its reader would refuse it: REASON`, or the I/O error.
    pub fn writing(self, path: &Path) -> InputError {
        match self {
            WriteError::Refused(reason) => InputError::file(
                &path.display().to_string(),
                format!("not written, its reader would refuse it: {reason}"),
            ),
            WriteError::Io(e) => InputError::io(path, e),
        }
    }
}

/// Writes a recording row by row (docs/formats.md#recording) and checks, as it goes, the rules its reader
/// would check (docs/formats.md#bad-input): the header's numbers within their bounds, every value finite,
/// times strictly increasing, at least one row, and `rate_hz` agreeing with the times.
pub struct RecordingWriter<W: std::io::Write> {
    out: W,
    has_gyro: bool,
    extras: ExtraColumns,
    rate_hz: Option<f64>,
    rows: usize,
    steps: TimeSteps,
    previous_t_s: f64,
    line: String,
    /// Whether the rules are checked ([`Recording::to_csv`] writes without).
    checked: bool,
}

impl<W: std::io::Write> RecordingWriter<W> {
    /// Writes the header and the column line (with the gyro columns if `has_gyro`, and the `extras`).
    pub fn new(
        out: W,
        header: &Header,
        has_gyro: bool,
        extras: ExtraColumns,
    ) -> Result<RecordingWriter<W>, WriteError> {
        check_header_writable(header).map_err(WriteError::Refused)?;
        let mut writer = RecordingWriter::unchecked(out, header, has_gyro, extras)?;
        writer.checked = true;
        Ok(writer)
    }

    /// [`RecordingWriter::new`] without the rules.
    fn unchecked(
        out: W,
        header: &Header,
        has_gyro: bool,
        extras: ExtraColumns,
    ) -> Result<RecordingWriter<W>, WriteError> {
        let h = header;
        let mut text = String::new();
        text.push_str("# sinscal-recording: 1\n");
        for c in &h.comments {
            let _ = writeln!(text, "# {c}");
        }
        let _ = writeln!(text, "# latitude_deg: {}", h.latitude_deg);
        let _ = writeln!(text, "# height_m: {}", h.height_m);
        if let Some(r) = h.rate_hz {
            let _ = writeln!(text, "# rate_hz: {r}");
        }
        if let Some(g) = h.gravity_mps2 {
            let _ = writeln!(text, "# gravity_mps2: {g}");
        }
        if let Some(t) = h.pose_tolerance_deg {
            let _ = writeln!(text, "# pose_tolerance_deg: {t}");
        }
        if let Some(t) = &h.truth {
            let v3 = |v: [f64; 3]| format!("{:e},{:e},{:e}", v[0], v[1], v[2]);
            let _ = writeln!(text, "# truth_seed: {}", t.seed);
            let _ = writeln!(text, "# truth_gyro_bias_radps: {}", v3(t.gyro_bias_b_radps));
            let _ = writeln!(text, "# truth_accel_bias_mps2: {}", v3(t.accel_bias_b_mps2));
            let _ = writeln!(text, "# truth_gyro_noise_radps: {:e}", t.gyro_noise_radps);
            let _ = writeln!(text, "# truth_accel_noise_mps2: {:e}", t.accel_noise_mps2);
            let _ = writeln!(text, "# truth_reference_offset_rad: {}", v3(t.reference_offset_n_rad));
        }
        let names: Vec<&str> = COLUMNS.into_iter().filter(|c| has_gyro || !GYRO_COLUMNS.contains(c)).collect();
        text.push_str(&names.join(","));
        if extras.temp {
            text.push_str(",temp_c");
        }
        if extras.turn {
            text.push(',');
            text.push_str(TURN_COLUMN);
        }
        text.push('\n');
        let mut out = out;
        out.write_all(text.as_bytes()).map_err(WriteError::Io)?;
        Ok(RecordingWriter {
            out,
            has_gyro,
            extras,
            rate_hz: h.rate_hz,
            rows: 0,
            steps: TimeSteps::default(),
            previous_t_s: f64::NEG_INFINITY,
            line: String::new(),
            checked: false,
        })
    }

    /// Writes a row (its `line` is not used).
    pub fn row(&mut self, r: &Row) -> Result<(), WriteError> {
        self.rows += 1;
        let k = self.rows;
        let values = r.rate_b_radps.iter().chain(&r.force_b_mps2).chain(r.temp_c.iter());
        let angles = [r.pitch_deg, r.roll_deg, r.heading_deg.unwrap_or(0.0)];
        if self.checked && (!r.t_s.is_finite() || values.chain(&angles).any(|v| !v.is_finite())) {
            return Err(WriteError::Refused(format!("row {k}: a value is not a finite number")));
        }
        if self.checked && r.turn_axis.is_some_and(|a| a > 2 || r.pos != 0) {
            return Err(WriteError::Refused(format!("row {k}: a turn's axis on a row in a position or beyond z")));
        }
        if self.checked && r.t_s <= self.previous_t_s {
            return Err(WriteError::Refused(format!(
                "row {k}: time {} s does not increase (the previous is {} s)",
                shown(r.t_s),
                shown(self.previous_t_s)
            )));
        }
        self.previous_t_s = r.t_s;
        self.steps.push(r.t_s);
        let out = &mut self.line;
        out.clear();
        let heading = r.heading_deg.map(|h| h.to_string()).unwrap_or_default();
        let [ax, ay, az] = r.force_b_mps2;
        let _ = write!(out, "{},{},{},{},{},", r.t_s, r.pos, r.pitch_deg, r.roll_deg, heading);
        if self.has_gyro {
            let [gx, gy, gz] = r.rate_b_radps;
            let _ = write!(out, "{gx:e},{gy:e},{gz:e},");
        }
        let _ = write!(out, "{ax},{ay},{az}");
        if self.extras.temp {
            let _ = write!(out, ",{}", r.temp_c.map(|t| t.to_string()).unwrap_or_default());
        }
        if self.extras.turn {
            let _ = write!(out, ",{}", r.turn_axis.and_then(|a| TURN_AXES.get(a)).copied().unwrap_or_default());
        }
        out.push('\n');
        self.out.write_all(out.as_bytes()).map_err(WriteError::Io)
    }

    /// The rules on the whole (at least one row, `rate_hz` against the times); the output, flushed.
    pub fn finish(mut self) -> Result<W, WriteError> {
        if self.checked && self.rows == 0 {
            return Err(WriteError::Refused("no data rows".into()));
        }
        if let Some(rate_hz) = self.rate_hz.filter(|_| self.checked) {
            check_rate(rate_hz, &self.steps).map_err(WriteError::Refused)?;
        }
        self.out.flush().map_err(WriteError::Io)?;
        Ok(self.out)
    }
}

/// Where a recording is written, and how.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// A regular file, or none yet, at this path (a symbolic link's target): written to a scratch file beside it
    /// and renamed onto it once whole.
    Replace(std::path::PathBuf),
    /// Something that is not a regular file (a FIFO, a character device): written in place, never replaced.
    InPlace(std::path::PathBuf),
}

/// How `path` is written ([`Output`]): through a symbolic link to its target (relative to the link's folder),
/// in place when it is not a regular file; refused when it is a directory or a read-only file (a rename would
/// replace what may not be written).
pub fn output_of(path: &Path) -> Result<Output, InputError> {
    let mut target = path.to_path_buf();
    // At most 40 links deep, as the kernel resolves them.
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&target).map_err(|e| InputError::io(path, e))?;
                target = match target.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            Ok(m) if m.is_dir() => return Err(InputError::file(&path.display().to_string(), "is a directory")),
            Ok(m) if m.is_file() && m.permissions().readonly() => {
                return Err(InputError::file(
                    &path.display().to_string(),
                    format!("{} is read-only: not replaced", target.display()),
                ))
            }
            Ok(m) if m.is_file() => return Ok(Output::Replace(target)),
            Ok(_) => return Ok(Output::InPlace(target)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Output::Replace(target)),
            Err(e) => return Err(InputError::io(path, e)),
        }
    }
    Err(InputError::file(&path.display().to_string(), "more than 40 symbolic links deep"))
}

/// Writes a recording file at `path`: `rows` writes the rows through the writer (with the reader's rules), which
/// streams them through a buffer. A regular file (or a symbolic link's target, [`output_of`]) is written to a
/// scratch file beside it, renamed onto it once every row is written and the writer's closing checks pass: a
/// refusal or an I/O error leaves it as it was and no scratch file. A FIFO or a device is written in place. The
/// text is never whole in memory. Returns what `rows` returns.
pub fn write_file<T>(
    path: &Path,
    header: &Header,
    has_gyro: bool,
    extras: ExtraColumns,
    rows: impl FnOnce(&mut RecordingWriter<std::io::BufWriter<std::fs::File>>) -> Result<T, InputError>,
) -> Result<T, InputError> {
    let write = |file: std::fs::File| -> Result<T, InputError> {
        let out = std::io::BufWriter::with_capacity(1 << 20, file);
        let mut writer = RecordingWriter::new(out, header, has_gyro, extras).map_err(|e| e.writing(path))?;
        let value = rows(&mut writer)?;
        writer.finish().map_err(|e| e.writing(path))?;
        Ok(value)
    };
    let target = match output_of(path)? {
        Output::InPlace(target) => {
            let file = std::fs::OpenOptions::new().write(true).open(&target).map_err(|e| InputError::io(path, e))?;
            return write(file);
        }
        Output::Replace(target) => target,
    };
    let name = target.file_name().map_or("out".into(), |n| n.to_string_lossy().into_owned());
    let partial = target.with_file_name(format!(".{name}.partial"));
    let file = std::fs::File::create(&partial).map_err(|e| InputError::io(path, e))?;
    let written = write(file).and_then(|value| {
        std::fs::rename(&partial, &target).map_err(|e| InputError::io(path, e))?;
        Ok(value)
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    written
}

/// The reader's rules on a header to be written: latitude, height, rate and gravity within their bounds.
fn check_header_writable(h: &Header) -> Result<(), String> {
    if !latitude_ok(h.latitude_deg) {
        return Err(format!(
            "latitude_deg {} outside [-{MAX_LATITUDE_DEG}, {MAX_LATITUDE_DEG}]",
            shown(h.latitude_deg)
        ));
    }
    if !h.height_m.is_finite() {
        return Err(format!("height_m {} is not a finite number", h.height_m));
    }
    if let Some(r) = h.rate_hz.filter(|&r| !rate_ok(r)) {
        return Err(format!("rate_hz {} is not a rate in (0, {MAX_RATE_HZ}] Hz", shown(r)));
    }
    if let Some(g) = h.gravity_mps2.filter(|&g| !gravity_ok(g)) {
        return Err(format!("gravity_mps2 {} is not a gravity on Earth (9.7..9.9)", shown(g)));
    }
    Ok(())
}

/// The rows of a recording in file order, as often as a command needs them: a [`Recording`] in memory, or a
/// [`RecordingFile`] read again at each pass, one row at a time (docs/formats.md#speed-and-memory).
pub trait RowSource {
    /// Where the rows come from (file name for messages).
    fn source(&self) -> &str;
    /// The header.
    fn header(&self) -> &Header;
    /// Whether the rows have the three gyro columns (otherwise `rate_b_radps = [0.0; 3]`).
    fn has_gyro(&self) -> bool;
    /// Whether the rows have a `temp_c` column.
    fn has_temp(&self) -> bool;
    /// Whether the rows have a `turn` column.
    fn has_turns(&self) -> bool;
    /// The optional columns the rows have.
    fn extra_columns(&self) -> ExtraColumns {
        ExtraColumns { temp: self.has_temp(), turn: self.has_turns() }
    }
    /// Gives the rows to `sink`, in file order, while it returns `Continue`: at `Break` the pass ends there, the
    /// rest of the rows unread (and unchecked; a later whole pass checks them). The first error (of the
    /// reader's or the sink's) stops the pass.
    fn for_each_row_while(&self, sink: RowSink<'_>) -> Result<(), InputError>;

    /// Gives every row to `sink`, in file order; the first error (of the reader's or the sink's) stops the pass.
    fn for_each_row(&self, sink: &mut dyn FnMut(&Row) -> Result<(), InputError>) -> Result<(), InputError> {
        self.for_each_row_while(&mut |row| sink(row).map(ControlFlow::Continue))
    }

    /// Refuses accelerometer-only data for a command that needs the gyros: `command` names it
    /// ("navigate", "study"). The message is `FILE: no gyro columns: COMMAND needs gyros`.
    fn require_gyro(&self, command: &str) -> Result<(), InputError> {
        if self.has_gyro() {
            Ok(())
        } else {
            Err(InputError::file(self.source(), format!("no gyro columns: {command} needs gyros")))
        }
    }
}

impl RowSource for Recording {
    fn source(&self) -> &str {
        &self.source
    }
    fn header(&self) -> &Header {
        &self.header
    }
    fn has_gyro(&self) -> bool {
        self.has_gyro
    }
    fn has_temp(&self) -> bool {
        self.rows.iter().any(|r| r.temp_c.is_some())
    }
    fn has_turns(&self) -> bool {
        self.rows.iter().any(|r| r.turn_axis.is_some())
    }
    fn for_each_row_while(&self, sink: RowSink<'_>) -> Result<(), InputError> {
        for row in &self.rows {
            if sink(row)?.is_break() {
                break;
            }
        }
        Ok(())
    }
}

/// A recording file read in passes: [`RecordingFile::open`] reads and checks its header, and each pass
/// reads its rows one chunk of lines at a time, parsed on the available cores, without keeping them.
/// Memory does not grow with the file's length.
#[derive(Clone, Debug)]
pub struct RecordingFile {
    path: std::path::PathBuf,
    source: String,
    header: Header,
    has_gyro: bool,
    has_temp: bool,
    has_turns: bool,
    /// Lines up to and including the column line.
    head_lines: usize,
    column_line: String,
    header_line: usize,
    rate_line: Option<usize>,
}

impl RecordingFile {
    /// Opens a recording file and reads its header and column line (errors as [`Recording::parse`]'s); the
    /// rows are read, and checked, at each pass.
    pub fn open(path: &Path) -> Result<RecordingFile, InputError> {
        let source = path.display().to_string();
        let mut reader = BufReader::new(File::open(path).map_err(|e| InputError::io(path, e))?);
        // The header, up to and including the column line (the first line that is neither blank nor `#`).
        let mut head: Vec<String> = Vec::new();
        loop {
            let mut bytes = Vec::new();
            let n = read_line_capped(&mut reader, &mut bytes)
                .map_err(|e| InputError::at(&source, head.len() + 1, e.to_string()))?;
            if n == 0 {
                break;
            }
            let line = utf8_line(&bytes, head.len() + 1, &source)?;
            // A byte-order mark (some editors write one) is not part of the first line.
            let line = if head.is_empty() { line.strip_prefix('\u{feff}').unwrap_or(line) } else { line };
            let line = strip_line_end(line).to_string();
            let is_column_line = !line.trim().is_empty() && !line.starts_with('#');
            head.push(line);
            if is_column_line {
                break;
            }
        }
        let mut lines = head.iter().enumerate().map(|(i, l)| (i + 1, l.as_str()));
        let (header, header_line, column_line, rate_line) = parse_header(&mut lines, &|| head.len(), &source)?;
        let columns = parse_columns(column_line, header_line, &source)?;
        let (has_gyro, has_temp, has_turns) = (columns.gyro.is_some(), columns.temp.is_some(), columns.turn.is_some());
        Ok(RecordingFile {
            path: path.to_path_buf(),
            column_line: column_line.to_string(),
            source,
            header,
            has_gyro,
            has_temp,
            has_turns,
            head_lines: head.len(),
            header_line,
            rate_line,
        })
    }

    /// The whole recording in memory.
    pub fn read_all(&self) -> Result<Recording, InputError> {
        let mut rows = Vec::new();
        self.for_each_row(&mut |row| {
            rows.push(row.clone());
            Ok(())
        })?;
        let (source, header, has_gyro) = (self.source.clone(), self.header.clone(), self.has_gyro);
        Ok(Recording { source, header, rows, has_gyro })
    }

    /// A pass over the rows in chunks of `chunk_bytes` (then to the end of a line); the file's end and rate are
    /// checked only by a pass that reads every row.
    fn pass(&self, chunk_bytes: u64, sink: RowSink<'_>) -> Result<(), InputError> {
        let (path, source) = (self.path.as_path(), self.source.as_str());
        let mut reader = BufReader::with_capacity(1 << 20, File::open(path).map_err(|e| InputError::io(path, e))?);
        for line in 1..=self.head_lines {
            read_line_capped(&mut reader, &mut Vec::new()).map_err(|e| InputError::at(source, line, e.to_string()))?;
        }
        let columns = parse_columns(&self.column_line, self.header_line, source)?;
        let mut steps = TimeSteps::default();
        let mut last_line = None;
        let flow = read_rows(&mut reader, (self.head_lines, chunk_bytes), &columns, source, path, &mut |row| {
            steps.push(row.t_s);
            last_line = Some(row.line);
            sink(row)
        })?;
        if flow.is_break() {
            return Ok(());
        }
        let Some(last_line) = last_line else {
            return Err(InputError::at(source, self.header_line, "no data rows"));
        };
        require_final_line_end(path, last_line, source)?;
        if let (Some(rate_hz), Some(line)) = (self.header.rate_hz, self.rate_line) {
            check_rate(rate_hz, &steps).map_err(|reason| InputError::at(source, line, reason))?;
        }
        Ok(())
    }
}

impl RowSource for RecordingFile {
    fn source(&self) -> &str {
        &self.source
    }
    fn header(&self) -> &Header {
        &self.header
    }
    fn has_gyro(&self) -> bool {
        self.has_gyro
    }
    fn has_temp(&self) -> bool {
        self.has_temp
    }
    fn has_turns(&self) -> bool {
        self.has_turns
    }
    fn for_each_row_while(&self, sink: RowSink<'_>) -> Result<(), InputError> {
        self.pass(CHUNK_BYTES, sink)
    }
}

/// The rows of one dwell.
#[derive(Clone, Debug)]
pub struct Dwell<'a> {
    /// Position label.
    pub pos: u32,
    /// Its rows, in file order.
    pub rows: Vec<&'a Row>,
}

/// A turntable attitude read off a dwell, degrees.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DwellAttitude {
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Heading, degrees clockwise from north, `None` if unknown.
    pub heading_deg: Option<f64>,
}

/// Largest spread of a reference angle within one dwell that is still read as "not moving", degrees.
pub const MAX_DWELL_ATTITUDE_SPREAD_DEG: f64 = 0.01;

impl Dwell<'_> {
    /// The line of the dwell's first row.
    pub fn first_line(&self) -> usize {
        self.rows[0].line
    }

    /// The dwell's rows tallied (first line, samples, attitude).
    pub fn tally(&self) -> DwellTally {
        let mut tally = DwellTally::new(self.rows[0]);
        self.rows[1..].iter().for_each(|r| tally.push(r));
        tally
    }

    /// The reference attitude of the dwell ([`DwellTally::attitude`]).
    pub fn attitude(&self, source: &str) -> Result<DwellAttitude, InputError> {
        self.tally().attitude(source)
    }
}

/// Reads the `# truth_*` keys of a simulated recording; all or none must be present.
fn parse_truth(keys: &[(usize, String, String)], source: &str) -> Result<Option<SimulationTruth>, InputError> {
    if keys.is_empty() {
        return Ok(None);
    }
    let find = |name: &str| keys.iter().find(|(_, k, _)| k == name);
    let line = keys[0].0;
    let numbers = |name: &str, count: usize| -> Result<Vec<f64>, InputError> {
        let (n, _, v) =
            find(name).ok_or_else(|| InputError::at(source, line, format!("header has truth keys but no '{name}'")))?;
        let values: Option<Vec<f64>> = v.split(',').map(parse_finite).collect();
        match values {
            Some(values) if values.len() == count => Ok(values),
            _ => Err(InputError::at(source, *n, format!("header {name}: '{v}' is not {count} finite numbers"))),
        }
    };
    let v3 = |name: &str| -> Result<[f64; 3], InputError> {
        let v = numbers(name, 3)?;
        Ok([v[0], v[1], v[2]])
    };
    Ok(Some(SimulationTruth {
        seed: numbers("truth_seed", 1)?[0] as u64,
        gyro_bias_b_radps: v3("truth_gyro_bias_radps")?,
        accel_bias_b_mps2: v3("truth_accel_bias_mps2")?,
        gyro_noise_radps: numbers("truth_gyro_noise_radps", 1)?[0],
        accel_noise_mps2: numbers("truth_accel_noise_mps2", 1)?[0],
        reference_offset_n_rad: v3("truth_reference_offset_rad")?,
    }))
}

fn parse_finite(cell: &str) -> Option<f64> {
    cell.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Where the columns of a recording are: their names, the indices of the required columns (`t_s`, `pos`, the
/// attitude and the accelerometers), of the gyros if present, and of `temp_c` and `turn` if present.
struct Columns<'a> {
    names: Vec<&'a str>,
    /// `t_s`, `pos`, `pitch_deg`, `roll_deg`, `heading_deg`, `ax_mps2`, `ay_mps2`, `az_mps2`.
    index: [usize; 8],
    gyro: Option<[usize; 3]>,
    temp: Option<usize>,
    turn: Option<usize>,
}

/// Finds the columns by name: every name at most once, the required ones present, the gyros all three or none.
fn parse_columns<'t>(column_line: &'t str, line: usize, source: &str) -> Result<Columns<'t>, InputError> {
    let bad = |reason: String| InputError::at(source, line, reason);
    let names: Vec<&str> = column_line.split(',').map(str::trim).collect();
    for (i, name) in names.iter().enumerate() {
        if let Some(j) = names[i + 1..].iter().position(|n| n == name) {
            return Err(bad(format!("column '{name}' appears twice (columns {} and {})", i + 1, i + j + 2)));
        }
    }
    let find = |name: &str| names.iter().position(|c| *c == name);
    let mut index = [0usize; 8];
    let required = COLUMNS.iter().filter(|c| !GYRO_COLUMNS.contains(c));
    for (slot, name) in index.iter_mut().zip(required) {
        *slot = find(name).ok_or_else(|| bad(format!("missing column '{name}'")))?;
    }
    let gyro = GYRO_COLUMNS.map(find);
    let gyro = match gyro {
        [Some(x), Some(y), Some(z)] => Some([x, y, z]),
        [None, None, None] => None,
        _ => {
            let missing: Vec<String> =
                GYRO_COLUMNS.iter().zip(gyro).filter(|(_, i)| i.is_none()).map(|(n, _)| format!("'{n}'")).collect();
            return Err(bad(format!(
                "missing column {}: the gyro columns are all three or none (accelerometer-only data)",
                missing.join(", ")
            )));
        }
    };
    let temp = find("temp_c");
    let turn = find(TURN_COLUMN);
    if turn.is_some() && gyro.is_none() {
        return Err(bad(format!("column '{TURN_COLUMN}' without the gyro columns: a turn is seen by the gyros")));
    }
    Ok(Columns { names, index, gyro, temp, turn })
}

/// Whether the text before the colon of a `# ...: ...` header line is a key (one word of letters, digits, `_`,
/// `-`, `.`) rather than free text that happens to hold a colon.
fn is_key(key: &str) -> bool {
    !key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
}

/// The header lines up to the column line: the header, the line number of the column line, its text, and the
/// line of `rate_hz` (for the rate check).
fn parse_header<'t>(
    lines: &mut impl Iterator<Item = (usize, &'t str)>,
    line_count: &dyn Fn() -> usize,
    source: &str,
) -> Result<(Header, usize, &'t str, Option<usize>), InputError> {
    let bad = |line: usize, reason: String| InputError::at(source, line, reason);
    let mut version = None;
    let mut latitude = None;
    let mut height_m = 0.0;
    let mut rate_hz = None;
    let mut rate_line = None;
    let mut gravity = None;
    let mut pose_tolerance_deg = None;
    let mut comments = Vec::new();
    let mut truth_keys: Vec<(usize, String, String)> = Vec::new();
    let mut seen: Vec<(String, usize)> = Vec::new();
    let (header_line, column_line) = loop {
        let Some((n, line)) = lines.next() else {
            return Err(bad(line_count().max(1), "no column line after the header".into()));
        };
        if line.trim().is_empty() {
            continue;
        }
        let Some(rest) = line.strip_prefix('#') else {
            break (n, line);
        };
        let Some((key, value)) = rest.split_once(':') else {
            comments.push(rest.trim().to_string());
            continue;
        };
        let key = key.trim();
        if !is_key(key) {
            comments.push(rest.trim().to_string());
            continue;
        }
        if let Some((_, first)) = seen.iter().find(|(k, _)| k == key) {
            return Err(bad(n, format!("header key '{key}' appears twice (first at line {first})")));
        }
        seen.push((key.to_string(), n));
        // A value may carry a trailing comment after whitespace, as in the example of docs/formats.md#recording.
        let value = value.split_whitespace().next().unwrap_or("");
        let number = |what: &str| -> Result<f64, InputError> {
            parse_finite(value).ok_or_else(|| bad(n, format!("header {what}: '{value}' is not a finite number")))
        };
        match key {
            "sinscal-recording" => version = Some((n, value.to_string())),
            "latitude_deg" => latitude = Some(number("latitude_deg")?),
            "height_m" => height_m = number("height_m")?,
            "rate_hz" => {
                let r = number("rate_hz")?;
                if !rate_ok(r) {
                    return Err(bad(n, format!("header rate_hz: {} is not a rate in (0, {MAX_RATE_HZ}] Hz", shown(r))));
                }
                rate_hz = Some(r);
                rate_line = Some(n);
            }
            "gravity_mps2" => gravity = Some(number("gravity_mps2")?),
            "pose_tolerance_deg" => {
                let t = number("pose_tolerance_deg")?;
                if !(0.0..=MAX_POSE_TOLERANCE_DEG).contains(&t) {
                    return Err(bad(
                        n,
                        format!("header pose_tolerance_deg: {} is not in [0, {MAX_POSE_TOLERANCE_DEG}] deg", shown(t)),
                    ));
                }
                pose_tolerance_deg = Some(t);
            }
            k if k.starts_with("truth_") => truth_keys.push((n, k.to_string(), value.to_string())),
            _ => comments.push(rest.trim().to_string()),
        }
    };
    match version {
        Some((_, v)) if v == "1" => {}
        Some((n, v)) => return Err(bad(n, format!("unsupported recording version '{v}' (this sinscal reads 1)"))),
        None => return Err(bad(1, "not a sinscal recording: no '# sinscal-recording: 1' header line".into())),
    }
    let latitude_deg = latitude.ok_or_else(|| bad(header_line, "header has no 'latitude_deg'".into()))?;
    if !latitude_ok(latitude_deg) {
        return Err(bad(
            header_line,
            format!(
                "latitude_deg {} outside [-{MAX_LATITUDE_DEG}, {MAX_LATITUDE_DEG}]: nearer a pole the \
                 horizontal Earth rate that gives north vanishes",
                shown(latitude_deg)
            ),
        ));
    }
    if let Some(g) = gravity {
        if !gravity_ok(g) {
            return Err(bad(header_line, format!("gravity_mps2 {} is not a gravity on Earth (9.7..9.9)", shown(g))));
        }
    }
    let truth = parse_truth(&truth_keys, source)?;
    let header = Header { latitude_deg, height_m, rate_hz, gravity_mps2: gravity, comments, truth, pose_tolerance_deg };
    Ok((header, header_line, column_line, rate_line))
}

/// The time steps of a recording's rows, gathered one row at a time in memory that does not grow with the row
/// count: the steps are counted in bins of relative width 2^-20 (1e-6), with their sum, and the median is the
/// mean of the steps in the bin that holds it. The median is robust to the gaps between dwells that
/// docs/formats.md#columns allows.
#[derive(Clone, Debug, Default)]
pub struct TimeSteps {
    previous_t_s: Option<f64>,
    /// The step of the last row and its bin, so that a regular recording costs no look-up per row.
    last: Option<(u64, u64, f64)>,
    /// Bin (the step's bits without its 32 lowest) -> count and sum of the steps, s.
    bins: std::collections::HashMap<u64, (u64, f64)>,
}

impl TimeSteps {
    /// The steps of the times `t_s`, in order.
    pub fn of(times_s: impl Iterator<Item = f64>) -> TimeSteps {
        let mut steps = TimeSteps::default();
        times_s.for_each(|t| steps.push(t));
        steps
    }

    /// Adds the next row's time, s.
    pub fn push(&mut self, t_s: f64) {
        if let Some(previous) = self.previous_t_s.replace(t_s) {
            let step_s = t_s - previous;
            let bin = step_s.to_bits() >> 32;
            match &mut self.last {
                Some((b, count, sum)) if *b == bin => {
                    *count += 1;
                    *sum += step_s;
                }
                _ => {
                    self.flush();
                    self.last = Some((bin, 1, step_s));
                }
            }
        }
    }

    fn flush(&mut self) {
        if let Some((bin, count, sum)) = self.last.take() {
            let entry = self.bins.entry(bin).or_insert((0, 0.0));
            entry.0 += count;
            entry.1 += sum;
        }
    }

    /// The median step, s, to 1e-6 relative (`None` for fewer than two rows). Steps are positive: the
    /// readers refuse times that do not increase before they get here.
    pub fn median_s(&self) -> Option<f64> {
        let mut all = self.clone();
        all.flush();
        let mut bins: Vec<(u64, (u64, f64))> = all.bins.into_iter().collect();
        bins.sort_unstable_by_key(|(bin, _)| *bin);
        let total: u64 = bins.iter().map(|(_, (count, _))| count).sum();
        let mut below = 0;
        for (_, (count, sum)) in bins {
            below += count;
            if 2 * below > total.saturating_sub(1) {
                return Some(sum / count as f64);
            }
        }
        None
    }
}

/// Highest sample rate a recording may state, Hz: no IMU samples faster, and every size that follows from
/// the rate (samples per dwell, navigation steps) stays bounded.
pub const MAX_RATE_HZ: f64 = 1e6;

/// A latitude a recording may have (within [`MAX_LATITUDE_DEG`] of the equator), degrees.
pub fn latitude_ok(latitude_deg: f64) -> bool {
    latitude_deg.abs() <= MAX_LATITUDE_DEG
}

/// A sample rate a recording may state: in (0, [`MAX_RATE_HZ`]] Hz.
pub fn rate_ok(rate_hz: f64) -> bool {
    rate_hz > 0.0 && rate_hz <= MAX_RATE_HZ
}

/// A gravity on Earth (9.7 to 9.9 m/s^2), as a recording may state it.
pub fn gravity_ok(gravity_mps2: f64) -> bool {
    (9.7..=9.9).contains(&gravity_mps2)
}

/// A field quoted in a message: at most 80 characters of it, and its length when it is longer.
pub fn clipped(field: &str) -> String {
    let count = field.chars().count();
    if count <= 80 {
        field.to_string()
    } else {
        format!("{}... ({count} characters)", field.chars().take(80).collect::<String>())
    }
}

/// `x` for a message: six significant digits, in exponent form when it is large or small (`1e300` is not
/// printed as 301 digits, nor 0.009999999999990905 as it falls out of a subtraction).
pub fn shown(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    if (1e-4..1e7).contains(&x.abs()) {
        format!("{:.5e}", x).parse::<f64>().map_or(x.to_string(), |r| r.to_string())
    } else {
        let e = format!("{x:.5e}");
        // 1.00000e300 -> 1e300, 2.50000e-7 -> 2.5e-7
        match e.split_once('e') {
            Some((m, p)) => format!("{}e{p}", m.trim_end_matches('0').trim_end_matches('.')),
            None => e,
        }
    }
}

/// The header's `rate_hz` against the time column: the median time step must be `1 / rate_hz` within
/// [`RATE_TOLERANCE`] (docs/formats.md#rate-check). The error is the reason.
fn check_rate(rate_hz: f64, steps: &TimeSteps) -> Result<(), String> {
    let Some(median_dt) = steps.median_s() else { return Ok(()) };
    let nominal_dt = 1.0 / rate_hz;
    if (median_dt - nominal_dt).abs() > RATE_TOLERANCE * nominal_dt {
        // Six significant digits: the float noise of the time column (0.009999999999990905 s) is not news.
        return Err(format!(
            "rate_hz {} disagrees with the time column: the median time step is {} s ({} Hz), \
             1/rate_hz is {} s (more than 1 % apart)",
            shown(rate_hz),
            shown(median_dt),
            shown(1.0 / median_dt),
            shown(nominal_dt)
        ));
    }
    Ok(())
}

/// The error of a time that does not increase, at line `n`.
fn time_does_not_increase(source: &str, n: usize, t_s: f64, previous_t: f64) -> InputError {
    InputError::at(source, n, format!("time {t_s} s does not increase (previous row: {previous_t} s)"))
}

/// Bytes of a chunk of data lines (then to the end of its last line).
const CHUNK_BYTES: u64 = 1 << 20;

/// The rows of one chunk of lines, parsed on its own: its first row's time is not checked (`first_t`
/// keeps it for the check against the previous chunk), and parsing stops at the first error.
struct ChunkRows {
    rows: Vec<Row>,
    first_t: Option<(usize, f64)>,
    error: Option<InputError>,
}

/// Parses the lines of `bytes`, the first being line `first_line` of `source`.
fn parse_chunk(bytes: &[u8], first_line: usize, columns: &Columns, source: &str) -> ChunkRows {
    let mut parser = RowParser::new(columns, source);
    let error = match std::str::from_utf8(bytes) {
        Err(e) => {
            let line = first_line + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count();
            Some(InputError::at(source, line, "not UTF-8 text (a binary file, or another encoding)"))
        }
        Ok(text) => {
            text.lines().enumerate().find_map(|(i, l)| parser.line(first_line + i, l.trim_end_matches('\r')).err())
        }
    };
    ChunkRows { rows: parser.rows, first_t: parser.first_t, error }
}

/// The newlines of `bytes`: eight bytes at a time, as a word whose bytes equal to `\n` are found with bit
/// operations (a byte is zero after the XOR exactly when it was a newline) and counted by their top bits. A
/// filtered count does one byte at a time: a tenth of the reading's instructions went there, in the one thread
/// that reads.
fn count_newlines(bytes: &[u8]) -> usize {
    const ONES: u64 = u64::from_ne_bytes([0x01; 8]);
    const LOW7: u64 = u64::from_ne_bytes([0x7f; 8]);
    const NEWLINES: u64 = u64::from_ne_bytes([b'\n'; 8]);
    let mut words = bytes.chunks_exact(8);
    let mut n = 0usize;
    for word in words.by_ref() {
        let x = u64::from_ne_bytes(word.try_into().unwrap_or([0; 8])) ^ NEWLINES;
        // High bit of each byte set where the byte of x is non-zero (no carry crosses bytes: each byte is at most
        // 0x7f + 0x7f before the OR).
        let non_zero = ((x & LOW7) + LOW7) | x;
        n += (!non_zero & (ONES << 7)).count_ones() as usize;
    }
    n + words.remainder().iter().filter(|&&b| b == b'\n').count()
}

/// Reads the next chunk of whole lines of `reader` into `bytes` (nothing at the end of the file); on an error,
/// `bytes` holds what was read before it.
fn read_chunk(reader: &mut impl BufRead, chunk_bytes: u64, bytes: &mut Vec<u8>) -> std::io::Result<()> {
    reader.by_ref().take(chunk_bytes).read_to_end(bytes)?;
    if bytes.len() as u64 == chunk_bytes {
        read_line_capped(reader, bytes)?;
    }
    Ok(())
}

/// What a pass gives each row to: `Break` ends the pass early ([`RowSource::for_each_row_while`]).
pub type RowSink<'s> = &'s mut dyn FnMut(&Row) -> Result<ControlFlow<()>, InputError>;

/// Longest line a recording (or any text file sinscal reads) may have, bytes: a row of eleven numbers is about
/// 200.
pub const MAX_LINE_BYTES: u64 = 1 << 16;

/// The reason for a line of [`MAX_LINE_BYTES`] or more.
fn long_line() -> String {
    format!("a line longer than {MAX_LINE_BYTES} bytes: not a line of a text file sinscal reads")
}

/// The text of the file at `path`, read line by line: a line of [`MAX_LINE_BYTES`] or more is refused at its
/// line number before the rest is read (a file of one 300-MB line is not held whole), as is text that is not
/// UTF-8.
pub fn read_text_capped(path: &Path) -> Result<String, InputError> {
    let source = path.display().to_string();
    let mut reader = std::io::BufReader::new(std::fs::File::open(path).map_err(|e| InputError::io(path, e))?);
    let mut bytes = Vec::new();
    for line in 1.. {
        match read_line_capped(&mut reader, &mut bytes) {
            Ok(0) => break,
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::InvalidData => {
                return Err(InputError::at(&source, line, e.to_string()))
            }
            Err(e) => return Err(InputError::io(path, e)),
        }
    }
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        InputError::file(&source, format!("byte {at} is not UTF-8: not a text file"))
    })
}

/// Reads to the end of the line into `bytes`, at most [`MAX_LINE_BYTES`]: a longer line is an error (a file of
/// one 100-MB line would otherwise be held whole).
fn read_line_capped(reader: &mut impl BufRead, bytes: &mut Vec<u8>) -> std::io::Result<usize> {
    let n = reader.by_ref().take(MAX_LINE_BYTES).read_until(b'\n', bytes)?;
    if n as u64 == MAX_LINE_BYTES && bytes.last() != Some(&b'\n') {
        return Err(std::io::Error::new(std::io::ErrorKind::InvalidData, long_line()));
    }
    Ok(n)
}

/// Gives the data rows of `reader`, whose last line read was line `line`, to `sink` in file order: chunks of
/// `chunk_bytes` (then to the end of a line) are read here, parsed on the available cores and joined in file
/// order (docs/formats.md#speed-and-memory). At most [`CHUNKS_IN_FLIGHT`] chunks are read and not yet given
/// to the sink, so memory does not grow with the file. The first error in file order is returned, as
/// [`Recording::parse`] would.
fn read_rows(
    reader: &mut (impl BufRead + Send),
    (line, chunk_bytes): (usize, u64),
    columns: &Columns,
    source: &str,
    path: &Path,
    sink: RowSink<'_>,
) -> Result<ControlFlow<()>, InputError> {
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 4);
    let (work_tx, work_rx) = mpsc::sync_channel::<(usize, usize, Vec<u8>)>(CHUNKS_IN_FLIGHT);
    let work_rx = Mutex::new(work_rx);
    let (done_tx, done_rx) = mpsc::channel::<(usize, ChunkRows)>();
    // A chunk is read only with a ticket, which comes back when its rows have gone to the sink.
    let (ticket_tx, ticket_rx) = mpsc::sync_channel::<()>(CHUNKS_IN_FLIGHT);
    for _ in 0..CHUNKS_IN_FLIGHT {
        let _ = ticket_tx.send(());
    }
    let stop = AtomicBool::new(false);
    let (joined, read) = std::thread::scope(|scope| {
        let stop = &stop;
        // An error of the reading carries the line it happened in.
        let producer = scope.spawn(move || -> Result<(), (usize, std::io::Error)> {
            let (mut index, mut line) = (0, line);
            while !stop.load(Ordering::Relaxed) && ticket_rx.recv().is_ok() {
                let mut bytes = Vec::with_capacity(chunk_bytes as usize + 4096);
                let read = read_chunk(reader, chunk_bytes, &mut bytes);
                let lines = count_newlines(&bytes);
                read.map_err(|e| (line + lines + 1, e))?;
                if bytes.is_empty() {
                    break;
                }
                if work_tx.send((index, line + 1, bytes)).is_err() {
                    break;
                }
                (index, line) = (index + 1, line + lines);
            }
            Ok(())
        });
        for _ in 0..workers {
            let (done_tx, work_rx) = (done_tx.clone(), &work_rx);
            // After an error the chunks still queued are taken and dropped, so that the reader is never left
            // blocked on a full queue.
            scope.spawn(move || {
                while let Some((index, first, bytes)) = work_rx.lock().ok().and_then(|rx| rx.recv().ok()) {
                    if !stop.load(Ordering::Relaxed) {
                        let _ = done_tx.send((index, parse_chunk(&bytes, first, columns, source)));
                    }
                }
            });
        }
        drop(done_tx);
        let joined = join_chunks(done_rx, ticket_tx, source, sink);
        if !matches!(joined, Ok(ControlFlow::Continue(()))) {
            stop.store(true, Ordering::Relaxed);
        }
        (joined, producer.join())
    });
    if joined?.is_break() {
        return Ok(ControlFlow::Break(()));
    }
    match read {
        Ok(Ok(())) => Ok(ControlFlow::Continue(())),
        Ok(Err((line, e))) if e.kind() == std::io::ErrorKind::InvalidData => {
            Err(InputError::at(source, line, e.to_string()))
        }
        Ok(Err((_, e))) => Err(InputError::io(path, e)),
        Err(panic) => std::panic::resume_unwind(panic),
    }
}

/// Chunks read and not yet given to the sink, at most: with [`CHUNK_BYTES`] of text and its rows, about 16 MB.
const CHUNKS_IN_FLIGHT: usize = 6;

/// Gives the chunks' rows to `sink` in file order, with the time check across chunks, and returns each
/// chunk's ticket; the first error in file order, or the sink's `Break`. Dropping `tickets` on return stops
/// the reading.
fn join_chunks(
    done: mpsc::Receiver<(usize, ChunkRows)>,
    tickets: mpsc::SyncSender<()>,
    source: &str,
    sink: RowSink<'_>,
) -> Result<ControlFlow<()>, InputError> {
    let mut pending = std::collections::BTreeMap::new();
    let (mut next, mut previous_t) = (0, None);
    for (index, chunk) in done {
        pending.insert(index, chunk);
        while let Some(chunk) = pending.remove(&next) {
            next += 1;
            if let (Some((n, t_s)), Some(prev)) = (chunk.first_t, previous_t) {
                if t_s <= prev {
                    return Err(time_does_not_increase(source, n, t_s, prev));
                }
            }
            for row in &chunk.rows {
                if sink(row)?.is_break() {
                    return Ok(ControlFlow::Break(()));
                }
            }
            if let Some(e) = chunk.error {
                return Err(e);
            }
            previous_t = chunk.rows.last().map(|r| r.t_s).or(previous_t);
            let _ = tickets.send(());
        }
    }
    Ok(ControlFlow::Continue(()))
}

/// `bytes` (line `line` of `source`) as text; an error naming the line when it is not UTF-8.
fn utf8_line<'b>(bytes: &'b [u8], line: usize, source: &str) -> Result<&'b str, InputError> {
    std::str::from_utf8(bytes)
        .map_err(|_| InputError::at(source, line, "not UTF-8 text (a binary file, or another encoding)"))
}

/// A file whose last line has no end of line may have been cut short, and a number cut short reads as
/// another number (`9.80665` as `9.8`): the file is refused, with its last line named.
fn require_final_line_end(path: &Path, last_line: usize, source: &str) -> Result<(), InputError> {
    use std::io::{Seek, SeekFrom};
    let io = |e| InputError::io(path, e);
    let mut file = File::open(path).map_err(io)?;
    if file.seek(SeekFrom::End(0)).map_err(io)? == 0 {
        return Ok(());
    }
    file.seek(SeekFrom::End(-1)).map_err(io)?;
    let mut last = [0u8; 1];
    file.read_exact(&mut last).map_err(io)?;
    if last[0] == b'\n' {
        Ok(())
    } else {
        Err(InputError::at(
            source,
            last_line,
            "the last line has no end of line: the file may be cut short (a number cut short reads as another \
             number); end it with a newline if it is whole",
        ))
    }
}

/// A line without its end: `\n`, then any `\r` (LF or CRLF files).
fn strip_line_end(line: &str) -> &str {
    line.strip_suffix('\n').unwrap_or(line).trim_end_matches('\r')
}

/// A cell without surrounding white space; a cell that starts and ends with a printable ASCII byte (nearly
/// every cell) is returned as it is, without the Unicode scan of `trim`.
fn trim_cell(cell: &str) -> &str {
    match (cell.as_bytes().first(), cell.as_bytes().last()) {
        (Some(a), Some(b)) if a.is_ascii_graphic() && b.is_ascii_graphic() => cell,
        _ => cell.trim(),
    }
}

/// The cells of a data row that the reader uses, by slot: the eight of [`Columns::index`], then the gyros,
/// then `temp_c` and `turn`.
const SLOTS: usize = 13;
/// Slot of `temp_c`.
const TEMP_SLOT: usize = 11;
/// Slot of `turn`.
const TURN_SLOT: usize = 12;

/// Reads the data rows after the column line, one line at a time, without allocating per line.
struct RowParser<'c> {
    columns: &'c Columns<'c>,
    source: &'c str,
    /// Per column of the file: its slot, if the reader uses it.
    slot_of: Vec<Option<usize>>,
    /// Per slot: its column of the file.
    column_of: [usize; SLOTS],
    previous_t: Option<f64>,
    /// The line and time of the first row (whose time is not checked against an earlier one).
    first_t: Option<(usize, f64)>,
    rows: Vec<Row>,
}

impl<'c> RowParser<'c> {
    fn new(columns: &'c Columns<'c>, source: &'c str) -> RowParser<'c> {
        let mut slot_of = vec![None; columns.names.len()];
        let mut column_of = [0; SLOTS];
        let used = columns
            .index
            .iter()
            .copied()
            .map(Some)
            .chain(columns.gyro.map_or([None; 3], |g| g.map(Some)))
            .chain([columns.temp, columns.turn]);
        for (slot, column) in used.enumerate() {
            if let Some(c) = column {
                slot_of[c] = Some(slot);
                column_of[slot] = c;
            }
        }
        RowParser { columns, source, slot_of, column_of, previous_t: None, first_t: None, rows: Vec::new() }
    }

    /// Line `n` of the file (its end removed): a data row, or a blank or `#` line (skipped).
    fn line(&mut self, n: usize, line: &str) -> Result<(), InputError> {
        if line.len() as u64 >= MAX_LINE_BYTES {
            return Err(InputError::at(self.source, n, long_line()));
        }
        if line.starts_with('#') || trim_cell(line).is_empty() {
            return Ok(());
        }
        let bad = |reason: String| InputError::at(self.source, n, reason);
        let names = &self.columns.names;
        let mut cells = [""; SLOTS];
        let mut count = 0;
        // The cells, cut at the commas in one scan of the bytes (a comma is ASCII, so every cut is a character
        // boundary): `split(',')` searches anew for each of a dozen short cells, a quarter of a row's reading.
        let mut start = 0;
        for (end, _) in line.bytes().enumerate().filter(|&(_, b)| b == b',').chain(std::iter::once((line.len(), b',')))
        {
            if let Some(&Some(slot)) = self.slot_of.get(count) {
                cells[slot] = trim_cell(&line[start..end]);
            }
            count += 1;
            start = end + 1;
        }
        if count != names.len() {
            return Err(bad(format!("{count} cells, the column line has {}", names.len())));
        }
        let num = |slot: usize| -> Result<f64, InputError> {
            parse_finite(cells[slot]).ok_or_else(|| {
                bad(format!("column '{}': '{}' is not a finite number", names[self.column_of[slot]], cells[slot]))
            })
        };
        let t_s = num(0)?;
        match self.previous_t {
            Some(prev) if t_s <= prev => return Err(time_does_not_increase(self.source, n, t_s, prev)),
            Some(_) => {}
            None => self.first_t = Some((n, t_s)),
        }
        self.previous_t = Some(t_s);
        let pos: u32 = cells[1].parse().map_err(|_| {
            let digits = !cells[1].is_empty() && cells[1].bytes().all(|b| b.is_ascii_digit());
            bad(if digits {
                format!("column 'pos': {} is beyond the largest label, {} (32 bits)", clipped(cells[1]), u32::MAX)
            } else {
                format!("column 'pos': '{}' is not a non-negative integer", clipped(cells[1]))
            })
        })?;
        let heading_deg = if cells[4].is_empty() { None } else { Some(num(4)?) };
        let pitch_deg = num(2)?;
        let roll_deg = num(3)?;
        let rate_b_radps = match self.columns.gyro {
            Some(_) => [num(8)?, num(9)?, num(10)?],
            None => [0.0; 3],
        };
        let temp_c = match self.columns.temp {
            Some(_) if !cells[TEMP_SLOT].is_empty() => Some(num(TEMP_SLOT)?),
            _ => None,
        };
        let turn_axis = match cells[TURN_SLOT] {
            "" => None,
            cell => {
                let axis = TURN_AXES.iter().position(|a| *a == cell).ok_or_else(|| {
                    bad(format!("column '{TURN_COLUMN}': '{cell}' is not an axis (x, y, z or empty)"))
                })?;
                if pos != 0 {
                    return Err(bad(format!(
                        "column '{TURN_COLUMN}': a turn about {cell} in position {pos} (a turn's rows have pos 0)"
                    )));
                }
                Some(axis)
            }
        };
        self.rows.push(Row {
            t_s,
            pos,
            pitch_deg,
            roll_deg,
            heading_deg,
            rate_b_radps,
            force_b_mps2: [num(5)?, num(6)?, num(7)?],
            temp_c,
            turn_axis,
            line: n,
        });
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str =
        "# sinscal-recording: 1\n# latitude_deg: 45.7796\n# height_m: 0                (optional)\n# rate_hz: 100\n\
        t_s,pos,pitch_deg,roll_deg,heading_deg,gx_radps,gy_radps,gz_radps,ax_mps2,ay_mps2,az_mps2\n\
        0.00,1,0,0,0,1.2e-06,5.1e-05,5.2e-05,1.0e-04,-3.0e-04,9.8063\n\
        0.01,1,0,0,0,1.2e-06,5.1e-05,5.2e-05,1.0e-04,-3.0e-04,9.8063\n";

    /// The recording of a file read in chunks of `chunk_bytes`.
    fn read_in_chunks(path: &Path, chunk_bytes: u64) -> Result<Recording, InputError> {
        let file = RecordingFile::open(path)?;
        let mut rows = Vec::new();
        file.pass(chunk_bytes, &mut |row| {
            rows.push(row.clone());
            Ok(ControlFlow::Continue(()))
        })?;
        Ok(Recording { source: file.source.clone(), header: file.header.clone(), rows, has_gyro: file.has_gyro })
    }

    fn err(text: &str) -> String {
        Recording::parse(text, "r.csv").unwrap_err().to_string()
    }

    #[test]
    fn reads_the_spec_example_and_round_trips() {
        let r = Recording::parse(GOOD, "r.csv").unwrap();
        assert_eq!(r.header.latitude_deg, 45.7796);
        assert_eq!(r.rows.len(), 2);
        assert_eq!(r.rows[1].line, 7);
        assert_eq!(r.rows[0].rate_b_radps, [1.2e-6, 5.1e-5, 5.2e-5]);
        let again = Recording::parse(&r.to_csv(), "r.csv").unwrap();
        assert_eq!(
            again.rows.iter().map(|x| x.force_b_mps2).collect::<Vec<_>>(),
            r.rows.iter().map(|x| x.force_b_mps2).collect::<Vec<_>>()
        );
        assert_eq!(again.rows[0].rate_b_radps, r.rows[0].rate_b_radps);
    }

    #[test]
    fn reading_a_file_in_chunks_gives_what_parsing_its_text_gives() {
        let mut good = GOOD.to_string();
        for k in 2..40 {
            good.push_str(&format!("{},1,0,0,0,{k}e-6,0,0,0,0,9.8\r\n\n# note\n", 0.01 * k as f64));
        }
        let texts = [
            good.clone(),
            good.replace("0.15,1,", "0.05,1,"),
            good.replace("0.2,1,0,0,0,20e-6", "0.2,1,0,0,0,x"),
            good.replace("0.3,1,0,0,0,30e-6,0,0,", "0.3,1,0,0,0,30e-6,0,"),
            good.replace("0.25,1,", "0.25,y,").replace("0.36,1,", "0.01,1,"),
            // A line longer than MAX_LINE_BYTES, across chunk ends: refused at its line whatever the chunks.
            good.replace("0.3,1,", &format!("0.3,1,{}", "0".repeat(MAX_LINE_BYTES as usize))),
        ];
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.csv");
        for text in texts {
            std::fs::write(&path, &text).unwrap();
            let source = path.display().to_string();
            let parsed = Recording::parse(&text, &source).map_err(|e| e.to_string());
            for chunk_bytes in [1, 7, 40, 64, 100, 333, 1 << 20] {
                let read = read_in_chunks(&path, chunk_bytes).map_err(|e| e.to_string());
                assert_eq!(read, parsed, "chunks of {chunk_bytes} bytes");
            }
        }
    }

    #[test]
    fn newlines_are_counted_in_blocks_and_the_rest() {
        for len in [0, 1, 127, 128, 129, 1000, 4096 + 17] {
            let bytes: Vec<u8> = (0..len).map(|i| if i % 7 == 3 || i % 128 == 127 { b'\n' } else { b'1' }).collect();
            let expected = bytes.iter().filter(|&&b| b == b'\n').count();
            assert_eq!(count_newlines(&bytes), expected, "{len} bytes");
        }
        // Every byte a newline: eight in each word.
        assert_eq!(count_newlines(&[b'\n'; 256]), 256);
    }

    #[test]
    fn a_pass_that_breaks_reads_no_further_and_a_whole_pass_still_checks_everything() {
        // 40 rows, then a bad time at row 20 and a bad cell at row 39: a pass that stops after row 10 gives ten
        // rows and no error, in chunks of any size; a whole pass is refused at the first bad line.
        let mut text = GOOD.to_string();
        for k in 2..40 {
            text.push_str(&format!("{},1,0,0,0,{k}e-6,0,0,0,0,9.8\n", 0.01 * k as f64));
        }
        let text = text.replace("0.2,1,", "0.001,1,").replace("0.39,1,0,0,0,39e-6", "0.39,1,0,0,0,x");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.csv");
        std::fs::write(&path, &text).unwrap();
        let file = RecordingFile::open(&path).unwrap();
        for chunk_bytes in [1, 40, 333, 1 << 20] {
            let mut seen = 0;
            let stopped = file.pass(chunk_bytes, &mut |_| {
                seen += 1;
                Ok(if seen == 10 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) })
            });
            assert_eq!((stopped.map_err(|e| e.to_string()), seen), (Ok(()), 10), "chunks of {chunk_bytes} bytes");
        }
        let whole = file.for_each_row(&mut |_| Ok(())).unwrap_err().to_string();
        assert!(whole.contains(":24: time") || whole.contains("does not increase"), "{whole}");
        let refused = Recording::parse(&text.replace("0.001,1,", "0.2,1,"), "r.csv").unwrap_err();
        assert!(refused.to_string().contains("'x' is not a finite number"), "{refused}");
        // The same in memory: the pass ends at the break.
        let in_memory = Recording::parse(&text.replace("0.001,1,", "0.2,1,").replace(",x", ",0"), "r.csv").unwrap();
        let mut seen = 0;
        in_memory
            .for_each_row_while(&mut |_| {
                seen += 1;
                Ok(if seen == 3 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) })
            })
            .unwrap();
        assert_eq!((seen, in_memory.rows.len()), (3, 40));
    }

    #[test]
    fn columns_in_any_order_and_optional_temperature() {
        let text = "# sinscal-recording: 1\n# latitude_deg: 10\n\
            pos,t_s,temp_c,ax_mps2,ay_mps2,az_mps2,gx_radps,gy_radps,gz_radps,pitch_deg,roll_deg,heading_deg\n\
            3,0.5,21.5,0,0,9.8,1e-5,2e-5,3e-5,0,90,\n";
        let r = Recording::parse(text, "r.csv").unwrap();
        assert_eq!(r.rows[0].pos, 3);
        assert_eq!(r.rows[0].temp_c, Some(21.5));
        assert_eq!(r.rows[0].heading_deg, None);
        assert_eq!(r.rows[0].roll_deg, 90.0);
        assert_eq!(r.rows[0].rate_b_radps, [1e-5, 2e-5, 3e-5]);
    }

    /// The `turn` column: an axis on rows with `pos = 0`, read and written back; an axis that is not x, y or z,
    /// a turn in a position and a turn without gyros are refused.
    #[test]
    fn the_turn_column_names_the_axis_of_a_labelled_turn() {
        let head = "# sinscal-recording: 1\n# latitude_deg: 10\n\
            t_s,pos,pitch_deg,roll_deg,heading_deg,gx_radps,gy_radps,gz_radps,ax_mps2,ay_mps2,az_mps2,turn\n";
        let text =
            format!("{head}0.0,1,0,0,,0,0,0,0,0,9.8,\n0.1,0,0,0,,0,0,6.3,0,0,9.8,z\n0.2,0,0,0,,0,0,0,0,0,9.8,\n");
        let r = Recording::parse(&text, "r.csv").unwrap();
        assert_eq!(r.rows.iter().map(|r| r.turn_axis).collect::<Vec<_>>(), [None, Some(2), None]);
        assert!(RowSource::has_turns(&r));
        let again = Recording::parse(&r.to_csv(), "r.csv").unwrap();
        assert_eq!(again.rows.iter().map(|r| r.turn_axis).collect::<Vec<_>>(), [None, Some(2), None]);
        let bad_axis = format!("{head}0.0,0,0,0,,0,0,0,0,0,9.8,w\n");
        assert!(err(&bad_axis).contains("'w' is not an axis"), "{}", err(&bad_axis));
        let in_position = format!("{head}0.0,2,0,0,,0,0,0,0,0,9.8,x\n");
        assert!(err(&in_position).contains("in position 2"), "{}", err(&in_position));
        let no_gyro = "# sinscal-recording: 1\n# latitude_deg: 10\n\
            t_s,pos,pitch_deg,roll_deg,heading_deg,ax_mps2,ay_mps2,az_mps2,turn\n0.0,0,0,0,,0,0,9.8,x\n";
        assert!(err(no_gyro).contains("without the gyro columns"), "{}", err(no_gyro));
    }

    #[test]
    fn bad_input_names_file_line_and_reason() {
        assert_eq!(err("t_s\n1\n"), "r.csv:1: not a sinscal recording: no '# sinscal-recording: 1' header line");
        assert!(err(&GOOD.replace(",ay_mps2", ",ay")).contains("missing column 'ay_mps2'"));
        assert!(err(&GOOD.replace("0.01,1,0,0,0,1.2e-06", "0.01,1,0,0,0,NaN"))
            .starts_with("r.csv:7: column 'gx_radps': 'NaN'"));
        assert!(err(&GOOD.replace("0.01,1,0,0,0,1.2e-06", "0.01,1,0,0,0,inf")).contains("not a finite number"));
        assert!(err(&GOOD.replace("0.01,1,", "0.00,1,")).starts_with("r.csv:7: time 0 s does not increase"));
        assert!(err(&GOOD.replace("0.01,1,", "0.01,x,")).contains("'pos': 'x'"));
        assert!(err(&GOOD.replace("# latitude_deg: 45.7796\n", "")).contains("no 'latitude_deg'"));
        assert!(err(&GOOD.replace("-3.0e-04,9.8063\n0.01", "9.8063\n0.01")).starts_with("r.csv:6: 10 cells"));
        assert!(err(&GOOD.replace("recording: 1", "recording: 2")).contains("unsupported recording version '2'"));
    }

    #[test]
    fn moving_table_within_a_dwell_is_an_error() {
        let text = GOOD.replace("0.01,1,0,0,0,", "0.01,1,0,0,0.5,");
        let r = Recording::parse(&text, "r.csv").unwrap();
        let e = r.dwells()[0].attitude("r.csv").unwrap_err().to_string();
        assert!(e.contains("the table moves"), "{e}");
        // Headings either side of north average to north, not to 180.
        let text = GOOD.replace("0.00,1,0,0,0,", "0.00,1,0,0,359.999,").replace("0.01,1,0,0,0,", "0.01,1,0,0,0.001,");
        let r = Recording::parse(&text, "r.csv").unwrap();
        let h = r.dwells()[0].attitude("r.csv").unwrap().heading_deg.unwrap();
        assert!((h - 360.0).abs() < 1e-9, "{h}");
    }

    #[test]
    fn accelerometer_only_round_trip() {
        let text = "# sinscal-recording: 1\n# latitude_deg: 10\n# rate_hz: 50\n\
            t_s,pos,pitch_deg,roll_deg,heading_deg,ax_mps2,ay_mps2,az_mps2\n\
            0,1,0,90,,-9.81,1e-3,2.5e-4\n0.02,1,0,90,,-9.8100001,-1e-3,0.1\n";
        let r = Recording::parse(text, "a.csv").unwrap();
        assert!(!r.has_gyro);
        assert_eq!(r.rows[1].rate_b_radps, [0.0; 3]);
        let csv = r.to_csv();
        assert!(csv.contains("heading_deg,ax_mps2,ay_mps2,az_mps2\n"), "{csv}");
        assert!(!csv.contains("gx_radps"));
        let again = Recording::parse(&csv, "a.csv").unwrap();
        assert!(!again.has_gyro);
        assert_eq!(
            again.rows.iter().map(|x| x.force_b_mps2).collect::<Vec<_>>(),
            [[-9.81, 1e-3, 2.5e-4], [-9.8100001, -1e-3, 0.1]]
        );
        assert_eq!(again.header, r.header);
        assert_eq!(r.require_gyro("navigate").unwrap_err().to_string(), "a.csv: no gyro columns: navigate needs gyros");
        assert!(Recording::parse(GOOD, "r.csv").unwrap().require_gyro("navigate").is_ok());
    }

    #[test]
    fn one_or_two_gyro_columns_are_bad_input_naming_the_missing_ones() {
        let e = err(&GOOD.replace("gy_radps,gz_radps,", "a,b,"));
        assert_eq!(
            e,
            "r.csv:5: missing column 'gy_radps', 'gz_radps': the gyro columns are all three or none \
             (accelerometer-only data)"
        );
        let e = err(&GOOD.replace(",gx_radps,", ",gyro_x,"));
        assert!(e.starts_with("r.csv:5: missing column 'gx_radps': the gyro columns"), "{e}");
    }

    #[test]
    fn duplicate_columns_and_header_keys_are_bad_input() {
        let e = err(&GOOD.replace("ax_mps2,ay_mps2,az_mps2", "ax_mps2,gx_radps,az_mps2"));
        assert_eq!(e, "r.csv:5: column 'gx_radps' appears twice (columns 6 and 10)");
        let e = err(&GOOD.replace("# rate_hz: 100\n", "# rate_hz: 100\n# latitude_deg: 45.7796\n"));
        assert_eq!(e, "r.csv:5: header key 'latitude_deg' appears twice (first at line 2)");
        // Unknown keys too; free text holding a colon is not a key.
        let e = err(&GOOD.replace("# rate_hz: 100\n", "# source: a\n# rate_hz: 100\n# source: b\n"));
        assert_eq!(e, "r.csv:6: header key 'source' appears twice (first at line 4)");
        let text = GOOD.replace("# rate_hz: 100\n", "# made at 10:00\n# rate_hz: 100\n# made at 10:00\n");
        assert_eq!(Recording::parse(&text, "r.csv").unwrap().header.comments.len(), 2);
    }

    #[test]
    fn the_median_time_step_is_found_without_holding_the_steps() {
        // Regular 0.01-s steps with gaps between dwells: the median is the step.
        let mut times: Vec<f64> = (0..1000).map(|k| 0.01 * k as f64).collect();
        times.extend((0..1000).map(|k| 60.0 + 0.01 * k as f64));
        let m = TimeSteps::of(times.iter().copied()).median_s().unwrap();
        assert!((m - 0.01).abs() < 1e-12, "{m}");
        // Jittered steps (+-2.5 %): within 1e-6 of the exact median (the lower middle of an even count).
        let mut x = 12345u64;
        let mut times = vec![0.0];
        for _ in 0..10_000 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let jitter = (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            times.push(times[times.len() - 1] + 0.001 * (1.0 + 0.05 * jitter));
        }
        let mut steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let exact = steps[(steps.len() - 1) / 2];
        let m = TimeSteps::of(times.into_iter()).median_s().unwrap();
        assert!(((m - exact) / exact).abs() < 1e-6, "{m} {exact}");
        assert_eq!(TimeSteps::of([1.0].into_iter()).median_s(), None);
    }

    #[test]
    fn rate_hz_is_checked_against_the_time_column() {
        // 0.01 s steps: 100 Hz passes, 99.5 Hz (0.5 %) passes, 98 Hz (2 %) does not.
        assert!(Recording::parse(&GOOD.replace("rate_hz: 100", "rate_hz: 99.5"), "r.csv").is_ok());
        let e = err(&GOOD.replace("rate_hz: 100", "rate_hz: 98"));
        assert!(
            e.starts_with("r.csv:4: rate_hz 98 disagrees with the time column: the median time step is 0.01 s"),
            "{e}"
        );
        assert!(e.ends_with("(100 Hz), 1/rate_hz is 0.0102041 s (more than 1 % apart)"), "{e}");
        assert!(err(&GOOD.replace("rate_hz: 100", "rate_hz: 0")).starts_with("r.csv:4: header rate_hz: 0 is not"));
        // Gaps between dwells do not move the median.
        let mut text = GOOD.to_string();
        for k in 2..8 {
            text.push_str(&format!("{},1,0,0,0,0,0,0,0,0,9.8\n", 0.01 * k as f64));
        }
        text.push_str("60.0,2,0,0,0,0,0,0,0,0,9.8\n60.01,2,0,0,0,0,0,0,0,0,9.8\n");
        assert!(Recording::parse(&text, "r.csv").is_ok());
        // Without rate_hz there is nothing to check.
        assert!(Recording::parse(&GOOD.replace("# rate_hz: 100\n", "").replace("0.01,", "0.5,"), "r.csv").is_ok());
    }
}
