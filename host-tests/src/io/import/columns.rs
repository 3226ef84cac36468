//! `sinscal import columns`: any file of time, gyro and accelerometer values, read through a described layout
//! ([`Layout`], docs/data.md#described-layouts): text, binary records or a MATLAB matrix; several text files side
//! by side; values converted to rad/s and m/s^2 in sinscal's body axes; positions from a labels file or found as
//! static intervals.

use std::io::Read as _;

use super::layout::{BinaryType, Channel, Layout, Storage, TimeSource};
use super::*;

/// The seven values a record gives: time (NaN when the time comes from a rate), gyro x y z, accel x y z, as raw
/// numbers of the file.
type RawRecord = [f64; 7];

/// One labelled position of a labels file: its time range `[start_s, end_s)` and reference attitude.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// Position number written to the recording.
    pub pos: u32,
    /// First time of the range, s (included).
    pub start_s: f64,
    /// End of the range, s (excluded).
    pub end_s: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Heading, degrees clockwise from north; `None` = unknown.
    pub heading_deg: Option<f64>,
    /// Line in the labels file.
    pub line: usize,
}

/// Where the positions come from.
#[derive(Clone, Debug)]
pub enum Positions {
    /// A labels file's ranges.
    Labels(Vec<Label>),
    /// Static intervals found in the specific force, levelled from it.
    Detect(StaticDetection),
}

/// Parses a labels file: CSV with a header line naming the columns `start_s`, `end_s`, `pitch_deg`, `roll_deg`
/// (required) and `heading_deg`, `pos` (optional; an empty heading or `?` is unknown; without `pos` the ranges are
/// numbered 1, 2, ... in file order); `#` starts a comment line. Ranges must not overlap.
pub fn parse_labels(text: &str, source: &str) -> Result<Vec<Label>, InputError> {
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (header_line, header) = lines.next().ok_or_else(|| InputError::file(source, "no header line"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |name: &str| names.iter().position(|n| *n == name);
    let required = ["start_s", "end_s", "pitch_deg", "roll_deg"].map(|n| (n, column(n)));
    if let Some((missing, _)) = required.iter().find(|(_, c)| c.is_none()) {
        return Err(InputError::at(
            source,
            header_line,
            format!("missing column '{missing}' (columns: start_s, end_s, pitch_deg, roll_deg, heading_deg, pos)"),
        ));
    }
    let [start, end, pitch, roll] = required.map(|(_, c)| c.unwrap_or(0));
    let (heading, pos) = (column("heading_deg"), column("pos"));
    let mut labels: Vec<Label> = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let number = |i: usize, what: &str| -> Result<f64, InputError> {
            let cell = cells.get(i).copied().unwrap_or("");
            parse_finite(cell)
                .ok_or_else(|| InputError::at(source, n, format!("{what} '{cell}' is not a finite number")))
        };
        let heading_deg = match heading.and_then(|i| cells.get(i)).copied().unwrap_or("") {
            "" | "?" => None,
            cell => Some(parse_finite(cell).ok_or_else(|| {
                InputError::at(source, n, format!("heading_deg '{cell}' is not a number, empty or '?'"))
            })?),
        };
        let pos = match pos {
            Some(i) => {
                let cell = cells.get(i).copied().unwrap_or("");
                cell.parse::<u32>()
                    .ok()
                    .filter(|p| (1..=64).contains(p))
                    .ok_or_else(|| InputError::at(source, n, format!("pos '{cell}' is not a position 1 to 64")))?
            }
            None => labels.len() as u32 + 1,
        };
        let label = Label {
            pos,
            start_s: number(start, "start_s")?,
            end_s: number(end, "end_s")?,
            pitch_deg: number(pitch, "pitch_deg")?,
            roll_deg: number(roll, "roll_deg")?,
            heading_deg,
            line: n,
        };
        if label.start_s >= label.end_s {
            return Err(InputError::at(
                source,
                n,
                format!("start_s {} is not below end_s {}", label.start_s, label.end_s),
            ));
        }
        if !(-90.0..=90.0).contains(&label.pitch_deg) {
            return Err(InputError::at(source, n, format!("pitch_deg {} is outside [-90, 90]", label.pitch_deg)));
        }
        if let Some(other) = labels.iter().find(|o| o.start_s < label.end_s && label.start_s < o.end_s) {
            return Err(InputError::at(source, n, format!("the range overlaps the one on line {}", other.line)));
        }
        labels.push(label);
    }
    if labels.is_empty() {
        return Err(InputError::file(source, "no labelled range"));
    }
    Ok(labels)
}

/// What `sinscal import columns` needs besides the inputs.
#[derive(Clone, Debug)]
pub struct ColumnsImport<'a> {
    /// The layout.
    pub layout: &'a Layout,
    /// The layout file's name, for the header.
    pub layout_source: &'a str,
    /// Where the positions come from.
    pub positions: Positions,
    /// The labels file's name, if any.
    pub labels_source: Option<&'a str>,
    /// `--latitude-deg`, which overrides the layout's.
    pub latitude_deg: Option<f64>,
}

/// Reads `inputs` through the layout into a recording.
pub fn import_columns(inputs: &[&Path], import: &ColumnsImport<'_>) -> Result<Imported, InputError> {
    let layout = import.layout;
    let sources: Vec<String> = inputs.iter().map(|p| p.display().to_string()).collect();
    let (records, lines) = match &layout.storage {
        Storage::Text { .. } => {
            let texts = inputs.iter().map(|p| read_text(p)).collect::<Result<Vec<_>, _>>()?;
            read_text_records(&texts, &sources, layout)?
        }
        Storage::Binary { .. } | Storage::Mat { .. } if inputs.len() != 1 => {
            return Err(InputError::file(&sources.join(" + "), "binary and MAT-file layouts read one input file"));
        }
        Storage::Binary { kind, little_endian, fields, skip_bytes } => {
            let file = std::fs::File::open(inputs[0]).map_err(|e| InputError::io(inputs[0], e))?;
            let spec =
                BinarySpec { kind: *kind, little_endian: *little_endian, fields: *fields, skip_bytes: *skip_bytes };
            read_binary_records(std::io::BufReader::with_capacity(1 << 20, file), &sources[0], &spec, layout)?
        }
        Storage::Mat { variable } => {
            let bytes = std::fs::read(inputs[0]).map_err(|e| InputError::io(inputs[0], e))?;
            read_mat_records(&bytes, &sources[0], variable.as_deref(), layout)?
        }
    };
    records_to_recording(records, lines, &sources, import)
}

/// Reads the needed fields of text records; several files are read side by side (field numbers continue from one
/// file to the next; every file must have as many records). Returns the records and the first file's line numbers.
fn read_text_records(
    texts: &[String],
    sources: &[String],
    layout: &Layout,
) -> Result<(Vec<RawRecord>, Vec<usize>), InputError> {
    let Storage::Text { delimiter, skip_lines, comment } = &layout.storage else {
        return Err(InputError::file(&sources.join(" + "), "not a text layout"));
    };
    let wanted = layout.slots();
    let mut records: Vec<RawRecord> = Vec::new();
    let mut lines: Vec<usize> = Vec::new();
    let mut first_field = 0usize;
    for (k, (text, source)) in texts.iter().zip(sources).enumerate() {
        let data = text
            .lines()
            .enumerate()
            .skip(*skip_lines)
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !comment.as_deref().is_some_and(|c| l.starts_with(c)));
        // The record width is the first record's; the fields this file gives, found once from it.
        let mut fields_here = None;
        let mut mine: Vec<(usize, usize)> = Vec::new();
        let mut count = 0usize;
        for (n, line) in data {
            let cells = split_fields(line, *delimiter);
            if fields_here.is_none() {
                let width = cells.len();
                fields_here = Some(width);
                mine = wanted
                    .iter()
                    .filter(|(_, f)| (first_field..first_field + width).contains(f))
                    .map(|&(slot, f)| (slot, f - first_field))
                    .collect();
            }
            if fields_here.is_some_and(|width| cells.len() != width) {
                let width = fields_here.unwrap_or(0);
                return Err(InputError::at(
                    source,
                    n,
                    format!("{} fields, the first record has {width}: every record has the same fields", cells.len()),
                ));
            }
            if count == records.len() {
                if k > 0 {
                    return Err(InputError::at(source, n, format!("more records than {}", sources[0])));
                }
                records.push([f64::NAN; 7]);
                lines.push(n);
            }
            for &(slot, f) in &mine {
                let cell = cells.get(f).copied().ok_or_else(|| {
                    InputError::at(
                        source,
                        n,
                        format!("{} fields: field {} is beyond the record", cells.len(), f + first_field),
                    )
                })?;
                records[count][slot] = parse_finite(cell).ok_or_else(|| {
                    let quoted = crate::io::recording::clipped(cell);
                    InputError::at(source, n, format!("field {}: '{quoted}' is not a finite number", f + first_field))
                })?;
            }
            count += 1;
        }
        if fields_here.is_none() {
            let total = text.lines().count();
            return Err(InputError::file(
                source,
                format!(
                    "no records: the file has {total} lines, skip_lines skips {skip_lines}, and the rest are empty \
                     or comments"
                ),
            ));
        }
        if count != records.len() {
            return Err(InputError::file(source, format!("{count} records, {} has {}", sources[0], records.len())));
        }
        first_field += fields_here.unwrap_or(0);
    }
    if let Some((_, f)) = wanted.iter().find(|(_, f)| *f >= first_field) {
        return Err(InputError::file(
            &sources.join(" + "),
            format!("field {f} is beyond the records ({first_field} fields in all)"),
        ));
    }
    Ok((records, lines))
}

/// The fields of a text line: split at `delimiter` and trimmed, or at any whitespace.
fn split_fields(line: &str, delimiter: Option<char>) -> Vec<&str> {
    match delimiter {
        Some(d) => line.split(d).map(str::trim).collect(),
        None => line.split_whitespace().collect(),
    }
}

/// A binary layout's record format.
struct BinarySpec {
    kind: BinaryType,
    little_endian: bool,
    fields: usize,
    skip_bytes: u64,
}

/// Reads binary records as a stream (one record in memory at a time besides the needed fields).
fn read_binary_records(
    mut input: impl std::io::Read,
    source: &str,
    spec: &BinarySpec,
    layout: &Layout,
) -> Result<(Vec<RawRecord>, Vec<usize>), InputError> {
    let io = |e: std::io::Error| InputError::file(source, format!("read error: {e}"));
    let skipped = std::io::copy(&mut input.by_ref().take(spec.skip_bytes), &mut std::io::sink()).map_err(io)?;
    if skipped < spec.skip_bytes {
        return Err(InputError::file(
            source,
            format!("{skipped} bytes: shorter than the {} header bytes", spec.skip_bytes),
        ));
    }
    let size = spec.kind.bytes();
    let record_bytes = size * spec.fields;
    let wanted = layout.slots();
    let mut buf = vec![0u8; record_bytes];
    let mut records = Vec::new();
    loop {
        let mut got = 0;
        while got < record_bytes {
            match input.read(&mut buf[got..]).map_err(io)? {
                0 => break,
                n => got += n,
            }
        }
        if got == 0 {
            break;
        }
        if got < record_bytes {
            return Err(InputError::file(
                source,
                format!(
                    "the file ends {got} bytes into record {} (records of {record_bytes} bytes)",
                    records.len() + 1
                ),
            ));
        }
        let mut record = [f64::NAN; 7];
        for &(slot, f) in &wanted {
            let b = &buf[f * size..(f + 1) * size];
            let value = decode(spec.kind, spec.little_endian, b);
            if !value.is_finite() {
                return Err(InputError::file(source, format!("record {}: field {f} is not finite", records.len() + 1)));
            }
            record[slot] = value;
        }
        records.push(record);
    }
    let lines = (1..=records.len()).collect();
    Ok((records, lines))
}

/// One number of a binary record.
fn decode(kind: BinaryType, little_endian: bool, b: &[u8]) -> f64 {
    let mut a = [0u8; 8];
    a[..b.len()].copy_from_slice(b);
    if !little_endian {
        a[..b.len()].reverse();
    }
    match kind {
        BinaryType::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
        BinaryType::F64 => f64::from_le_bytes(a),
        BinaryType::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
        BinaryType::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
    }
}

/// Reads the records of a MAT-file matrix: one per row, the fields its columns.
fn read_mat_records(
    bytes: &[u8],
    source: &str,
    variable: Option<&str>,
    layout: &Layout,
) -> Result<(Vec<RawRecord>, Vec<usize>), InputError> {
    let matrices = super::mat::read_mat(bytes, source)?;
    let names: Vec<&str> = matrices.iter().map(|m| m.name.as_str()).collect();
    let matrix = match variable {
        Some(v) => matrices.iter().find(|m| m.name == v).ok_or_else(|| {
            InputError::file(source, format!("no numeric matrix '{v}' (found: {})", names.join(", ")))
        })?,
        None if matrices.len() == 1 => &matrices[0],
        None => {
            return Err(InputError::file(
                source,
                format!("{} matrices ({}): name one with [mat] variable", matrices.len(), names.join(", ")),
            ))
        }
    };
    let wanted = layout.slots();
    if let Some((_, f)) = wanted.iter().find(|(_, f)| *f >= matrix.cols) {
        return Err(InputError::file(
            source,
            format!("field {f} is beyond the matrix '{}' of {} columns", matrix.name, matrix.cols),
        ));
    }
    let records = (0..matrix.rows)
        .map(|r| {
            let mut record = [f64::NAN; 7];
            for &(slot, f) in &wanted {
                record[slot] = matrix.get(r, f).ok_or_else(|| {
                    InputError::file(source, format!("matrix '{}' has no row {} column {f}", matrix.name, r + 1))
                })?;
            }
            Ok(record)
        })
        .collect::<Result<Vec<RawRecord>, InputError>>()?;
    Ok((records, (1..=matrix.rows).collect()))
}

/// Times of the records, s, checked finite and strictly increasing.
fn record_times(
    records: &[RawRecord],
    lines: &[usize],
    source: &str,
    time: &TimeSource,
) -> Result<Vec<f64>, InputError> {
    let t_s: Vec<f64> = match *time {
        TimeSource::Field { seconds_per_unit, .. } => records.iter().map(|r| r[0] * seconds_per_unit).collect(),
        TimeSource::Samples { rate_hz, .. } => records.iter().map(|r| r[0] / rate_hz).collect(),
        TimeSource::Rate { rate_hz, start_s } => (0..records.len()).map(|k| start_s + k as f64 / rate_hz).collect(),
    };
    for (k, w) in t_s.windows(2).enumerate() {
        if w[1] <= w[0] || !w[1].is_finite() {
            return Err(InputError::at(
                source,
                lines[k + 1],
                format!("time {} s does not increase (the record before: {} s)", w[1], w[0]),
            ));
        }
    }
    Ok(t_s)
}

/// The nominal rate, Hz: from the layout, or the median interval of the times rounded to 0.01 Hz.
fn nominal_rate_hz(t_s: &[f64], time: &TimeSource) -> f64 {
    match *time {
        TimeSource::Rate { rate_hz, .. } | TimeSource::Samples { rate_hz, .. } => rate_hz,
        TimeSource::Field { .. } => {
            let mut dt_s: Vec<f64> = t_s.windows(2).map(|w| w[1] - w[0]).collect();
            let mid = dt_s.len() / 2;
            let (_, median_dt_s, _) = dt_s.select_nth_unstable_by(mid, f64::total_cmp);
            (100.0 / *median_dt_s).round() / 100.0
        }
    }
}

/// One sensor's three values in SI, in the body axes.
fn convert(raw: &[f64], c: &Channel, axes: &[[f64; 3]; 3], per_sample_s: f64) -> [f64; 3] {
    let divisor = if c.increments { per_sample_s } else { 1.0 };
    let sensor = [0, 1, 2].map(|i| (raw[i] - c.offset[i]) * c.scale[i] / c.counts_per_unit[i] * c.unit_si / divisor);
    [0, 1, 2].map(|i| axes[i][0] * sensor[0] + axes[i][1] * sensor[1] + axes[i][2] * sensor[2])
}

/// Refuses an accelerometer that does not measure gravity: the median |f| of the record must be between 0.5 g and
/// 2 g. The reason names the likely mistake (increments read as rates, or the reverse, or a unit off by g).
fn check_gravity(rows: &[Row], accel: &Channel, rate_hz: f64, source: &str) -> Result<(), InputError> {
    // Every row up to 100,000 rows, an even sample of them beyond.
    let step = (rows.len() / 100_000).max(1);
    let norm = |f: [f64; 3]| (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    let mut norms: Vec<f64> = rows.iter().step_by(step).map(|r| norm(r.force_b_mps2)).collect();
    let mid = norms.len() / 2;
    let (_, median_mps2, _) = norms.select_nth_unstable_by(mid, f64::total_cmp);
    let median_mps2 = *median_mps2;
    let g_mps2 = STANDARD_GRAVITY_MPS2;
    if (0.5 * g_mps2..=2.0 * g_mps2).contains(&median_mps2) {
        return Ok(());
    }
    let hint = if !accel.increments && (0.5 * g_mps2 / rate_hz..=2.0 * g_mps2 / rate_hz).contains(&median_mps2) {
        "it is g times the sample interval: the values look like velocity increments (set increments = true)"
            .to_string()
    } else if accel.increments && (0.5 * g_mps2 * rate_hz..=2.0 * g_mps2 * rate_hz).contains(&median_mps2) {
        "it is g divided by the sample interval: the values look like rates (set increments = false)".to_string()
    } else {
        "check [accel] unit, scale and offset".to_string()
    };
    Err(InputError::file(
        source,
        format!("the median |specific force| is {median_mps2:.6} m/s^2, not a gravity near {g_mps2} m/s^2: {hint}"),
    ))
}

/// The quantisation variance of the specific force, summed over the axes, (m/s^2)^2: the floor of the static
/// detection's threshold (noise-free data still get a usable one). For integer outputs (integer binary types, or
/// a scale or offset given, as counts have) one step is the scale; for floating-point values, 1e-12.
fn quantisation_floor_mps2sq(layout: &Layout) -> f64 {
    let integer = matches!(layout.storage, Storage::Binary { kind: BinaryType::I16 | BinaryType::I32, .. });
    let a = &layout.accel;
    let counts = a.scale != [1.0; 3] || a.counts_per_unit != [1.0; 3] || a.offset != [0.0; 3];
    if integer || counts {
        (0..3).map(|i| (a.scale[i] / a.counts_per_unit[i] * a.unit_si).powi(2) / 12.0).sum()
    } else {
        1e-12
    }
}

/// Sets the rows of each labelled range to its position and attitude; a range without a row is refused.
fn apply_labels(rows: &mut [Row], labels: &[Label], source: &str) -> Result<(), InputError> {
    for label in labels {
        let first = rows.partition_point(|r| r.t_s < label.start_s);
        let end = rows.partition_point(|r| r.t_s < label.end_s);
        if first == end {
            let (a, b) = (rows.first().map_or(0.0, |r| r.t_s), rows.last().map_or(0.0, |r| r.t_s));
            return Err(InputError::at(
                source,
                label.line,
                format!(
                    "[{} s, {} s) holds no record (the records run from {a} s to {b} s)",
                    label.start_s, label.end_s
                ),
            ));
        }
        for row in &mut rows[first..end] {
            row.pos = label.pos;
            row.pitch_deg = label.pitch_deg;
            row.roll_deg = label.roll_deg;
            row.heading_deg = label.heading_deg;
        }
    }
    Ok(())
}

/// Finds the static intervals and levels each from its mean specific force (heading unknown). Returns the rule
/// as text, with the intervals found.
fn detect_positions(
    rows: &mut [Row],
    layout: &Layout,
    rate_hz: f64,
    d: &StaticDetection,
    source: &str,
) -> Result<String, InputError> {
    let force: Vec<[f64; 3]> = rows.iter().map(|r| r.force_b_mps2).collect();
    let t_s: Vec<f64> = rows.iter().map(|r| r.t_s).collect();
    let intervals = detect_static_intervals(&force, &t_s, rate_hz, d, quantisation_floor_mps2sq(layout))
        .map_err(|r| InputError::file(source, r))?;
    if intervals.ranges.is_empty() {
        return Err(InputError::file(
            source,
            format!(
                "no static interval found (threshold {:.3e} (m/s^2)^2 = {} x the first {} s): give a labels file or \
                 change the --static-* options",
                intervals.threshold_mps2sq, d.threshold_factor, d.init_static_s
            ),
        ));
    }
    level_intervals(rows, &intervals.ranges, source)?;
    Ok(format!(
        "sliding {} s window, sum of the 3 accel variances < {} x the first {} s ({:.3e} (m/s^2)^2, threshold {:.3e}), \
         at least {} s: {} interval(s)",
        d.window_s,
        d.threshold_factor,
        d.init_static_s,
        intervals.init_variance_mps2sq,
        intervals.threshold_mps2sq,
        d.min_static_s,
        intervals.ranges.len()
    ))
}

/// The recording of converted records, with positions, header and summary.
fn records_to_recording(
    records: Vec<RawRecord>,
    lines: Vec<usize>,
    sources: &[String],
    import: &ColumnsImport<'_>,
) -> Result<Imported, InputError> {
    let layout = import.layout;
    let source = sources.join(" + ");
    if records.len() < 2 {
        return Err(InputError::file(&source, format!("{} record(s): too few", records.len())));
    }
    let t_s = record_times(&records, &lines, &sources[0], &layout.time)?;
    let rate_hz = nominal_rate_hz(&t_s, &layout.time);
    let dt_s = 1.0 / rate_hz;
    let mut rows: Vec<Row> = records
        .iter()
        .zip(t_s.iter().zip(&lines))
        .map(|(r, (t, n))| Row {
            t_s: *t,
            pos: 0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            heading_deg: None,
            rate_b_radps: convert(&r[1..4], &layout.gyro, &layout.axes, dt_s),
            force_b_mps2: convert(&r[4..7], &layout.accel, &layout.axes, dt_s),
            temp_c: None,
            turn_axis: None,
            line: *n,
        })
        .collect();
    drop(records);
    check_gravity(&rows, &layout.accel, rate_hz, &source)?;
    let (latitude_deg, latitude_source) = match (import.latitude_deg, layout.latitude_deg) {
        (Some(lat), _) => (lat, "command line (--latitude-deg)".to_string()),
        (None, Some(lat)) => (lat, format!("layout {}", import.layout_source)),
        (None, None) => {
            return Err(InputError::file(
                import.layout_source,
                "the latitude is unknown: give [site] latitude_deg in the layout or --latitude-deg",
            ))
        }
    };
    let (attitude_source, detection) = match &import.positions {
        Positions::Labels(labels) => {
            let labels_source = import.labels_source.unwrap_or("labels");
            apply_labels(&mut rows, labels, labels_source)?;
            (format!("labels file {labels_source}"), None)
        }
        Positions::Detect(d) => {
            let rule = detect_positions(&mut rows, layout, rate_hz, d, &source)?;
            (ATTITUDE_SOURCE_LEVELLED.to_string(), Some(rule))
        }
    };
    let gyro_scale =
        super::gyro_units::check_gyro_units(&rows, latitude_deg, rate_hz, layout.gyro.increments, &source)?;
    let mut comments = vec![
        format!("source: {source}"),
        format!("source_format: described layout {}: {}", import.layout_source, layout.describe()),
        format!("latitude_source: {latitude_source}"),
        format!("attitude_source: {attitude_source}"),
    ];
    let mut notes = vec![
        format!("layout {}: {}", import.layout_source, layout.describe()),
        format!("latitude {latitude_deg} deg ({latitude_source}); positions from {attitude_source}"),
    ];
    notes.push(match gyro_scale {
        Some((s, std)) => format!(
            "gyro unit checked against the Earth rate's vertical part: {} +- {} times it (1 for a right unit)",
            crate::io::recording::shown(s),
            crate::io::recording::shown(std)
        ),
        None => "gyro unit not checked against the Earth rate: the dwells do not resolve it".to_string(),
    });
    if let Some(rule) = detection {
        comments.push(format!("static_detection: {rule}"));
        notes.push(format!("static intervals: {rule} (heading unknown; pitch and roll levelled from the mean force)"));
    }
    let recording = Recording {
        source,
        header: Header {
            latitude_deg,
            height_m: layout.height_m,
            rate_hz: Some(rate_hz),
            gravity_mps2: layout.gravity_mps2,
            comments,
            truth: None,
            pose_tolerance_deg: None,
        },
        rows,
        has_gyro: true,
    };
    let summary = summarise(&recording, "described layout", &notes, &|_| String::new());
    Ok(Imported { recording, summary })
}
