//! `sinscal import columns`: any file of time, gyro and accelerometer values, read through a described layout
//! ([`Layout`], docs/data.md#described-layouts): text, binary records or a MATLAB matrix; several files side by
//! side, in sequence or as sessions on their own time bases (docs/data.md#several-files); values converted to
//! rad/s and m/s^2 in sinscal's body axes (no gyro: an accelerometer-only recording); time stamps kept with a
//! nominal rate checked against them; positions from a labels file (by time or by file) or found as static
//! intervals.

use std::io::Read as _;

use super::layout::{Arrangement, BinaryType, Channel, Layout, NominalRate, Storage, TimeSource, SESSION_GAP_S};
use super::*;

/// The seven values a record gives: time (NaN when the time comes from a rate), gyro x y z, accel x y z, as raw
/// numbers of the file.
type RawRecord = [f64; 7];

/// One labelled position of a labels file: its time range `[start_s, end_s)` and reference attitude.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// Position number written to the recording.
    pub pos: u32,
    /// First time of the range, s (included); minus infinity: from the file's first record.
    pub start_s: f64,
    /// End of the range, s (excluded); infinity: past the file's last record.
    pub end_s: f64,
    /// Pitch, degrees.
    pub pitch_deg: f64,
    /// Roll, degrees.
    pub roll_deg: f64,
    /// Heading, degrees clockwise from north; `None` = unknown.
    pub heading_deg: Option<f64>,
    /// The input file the range lies in (1 for the first), when the labels give a `file` column: the times are
    /// then that file's own (before a session's shift); `None`: the times are the recording's.
    pub file: Option<usize>,
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

/// The columns of a labels file, found by name in its header line.
struct LabelColumns {
    start: Option<usize>,
    end: Option<usize>,
    pitch: usize,
    roll: usize,
    heading: Option<usize>,
    pos: Option<usize>,
    file: Option<usize>,
}

/// Parses a labels file: CSV with a header line naming the columns `start_s`, `end_s`, `pitch_deg`, `roll_deg`
/// (required) and `heading_deg`, `pos`, `file` (optional; an empty heading or `?` is unknown; without `pos` the
/// ranges are numbered 1, 2, ... in file order; with `file`, the input file a range lies in, whose own times
/// `start_s` and `end_s` are, and which may be left out or empty for the whole file); `#` starts a comment line.
/// Ranges (of one file) must not overlap.
pub fn parse_labels(text: &str, source: &str) -> Result<Vec<Label>, InputError> {
    let mut lines =
        text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (header_line, header) = lines.next().ok_or_else(|| InputError::file(source, "no header line"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let column = |name: &str| names.iter().position(|n| *n == name);
    let file = column("file");
    let required: &[&str] =
        if file.is_some() { &["pitch_deg", "roll_deg"] } else { &["start_s", "end_s", "pitch_deg", "roll_deg"] };
    if let Some(missing) = required.iter().find(|n| column(n).is_none()) {
        return Err(InputError::at(
            source,
            header_line,
            format!(
                "missing column '{missing}' (columns: start_s, end_s, pitch_deg, roll_deg, heading_deg, pos, file)"
            ),
        ));
    }
    let columns = LabelColumns {
        start: column("start_s"),
        end: column("end_s"),
        pitch: column("pitch_deg").unwrap_or(0),
        roll: column("roll_deg").unwrap_or(0),
        heading: column("heading_deg"),
        pos: column("pos"),
        file,
    };
    let mut labels: Vec<Label> = Vec::new();
    for (n, line) in lines {
        let label = parse_label(line, n, &columns, labels.len(), source)?;
        let overlapping = |o: &&Label| o.file == label.file && o.start_s < label.end_s && label.start_s < o.end_s;
        if let Some(other) = labels.iter().find(overlapping) {
            return Err(InputError::at(source, n, format!("the range overlaps the one on line {}", other.line)));
        }
        labels.push(label);
    }
    if labels.is_empty() {
        return Err(InputError::file(source, "no labelled range"));
    }
    Ok(labels)
}

/// One line of a labels file (line `n`; `earlier` ranges before it).
fn parse_label(line: &str, n: usize, c: &LabelColumns, earlier: usize, source: &str) -> Result<Label, InputError> {
    let cells: Vec<&str> = line.split(',').map(str::trim).collect();
    let cell = |i: usize| cells.get(i).copied().unwrap_or("");
    let number = |i: usize, what: &str| -> Result<f64, InputError> {
        parse_finite(cell(i))
            .ok_or_else(|| InputError::at(source, n, format!("{what} '{}' is not a finite number", cell(i))))
    };
    // With a file column, a time left out or empty is that file's start or end.
    let time = |i: Option<usize>, what: &str, whole: f64| match i {
        Some(i) if !(c.file.is_some() && cell(i).is_empty()) => number(i, what),
        _ => Ok(whole),
    };
    let heading_deg =
        match c.heading.map_or("", cell) {
            "" | "?" => None,
            text => Some(parse_finite(text).ok_or_else(|| {
                InputError::at(source, n, format!("heading_deg '{text}' is not a number, empty or '?'"))
            })?),
        };
    let pos = match c.pos {
        Some(i) => cell(i)
            .parse::<u32>()
            .ok()
            .filter(|p| (1..=64).contains(p))
            .ok_or_else(|| InputError::at(source, n, format!("pos '{}' is not a position 1 to 64", cell(i))))?,
        None => earlier as u32 + 1,
    };
    let file = match c.file {
        Some(i) => Some(cell(i).parse::<usize>().ok().filter(|f| *f >= 1).ok_or_else(|| {
            InputError::at(source, n, format!("file '{}' is not an input file's number (1 for the first)", cell(i)))
        })?),
        None => None,
    };
    let label = Label {
        pos,
        start_s: time(c.start, "start_s", f64::NEG_INFINITY)?,
        end_s: time(c.end, "end_s", f64::INFINITY)?,
        pitch_deg: number(c.pitch, "pitch_deg")?,
        roll_deg: number(c.roll, "roll_deg")?,
        heading_deg,
        file,
        line: n,
    };
    if label.start_s >= label.end_s {
        return Err(InputError::at(source, n, format!("start_s {} is not below end_s {}", label.start_s, label.end_s)));
    }
    if !(-90.0..=90.0).contains(&label.pitch_deg) {
        return Err(InputError::at(source, n, format!("pitch_deg {} is outside [-90, 90]", label.pitch_deg)));
    }
    Ok(label)
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
    let records = match layout.files {
        Some(Arrangement::Sequence | Arrangement::Sessions) => read_in_sequence(inputs, &sources, layout)?,
        Some(Arrangement::SideBySide) | None => read_side_by_side(inputs, &sources, layout)?,
    };
    records_to_recording(records, &sources, import)
}

/// The records read from the inputs, and which file each came from.
struct Records {
    /// The raw values of each record.
    values: Vec<RawRecord>,
    /// Each record's line in its file (text), or its record (binary) or row (MAT-file) number.
    lines: Vec<usize>,
    /// The files read one after another, each with its records; one part for files read side by side.
    parts: Vec<Part>,
}

/// The records of one input file of files read in sequence, or of all the files read side by side.
#[derive(Clone, Debug)]
struct Part {
    /// The file's name (the first file's, for files side by side: the lines are its).
    source: String,
    /// Its records.
    records: Range<usize>,
    /// What its times were shifted by on the recording's time base, s (sessions; 0 otherwise).
    shift_s: f64,
}

/// The inputs read side by side: record k of every file is one record. Text files are read as before `[files]`
/// existed; binary and MAT-files only with a `[files]` table when there are several.
fn read_side_by_side(inputs: &[&Path], sources: &[String], layout: &Layout) -> Result<Records, InputError> {
    let (values, lines) = match &layout.storage {
        Storage::Text { .. } => {
            let texts = inputs.iter().map(|p| read_text(p)).collect::<Result<Vec<_>, _>>()?;
            read_text_records(&texts, sources, layout)?
        }
        Storage::Binary { .. } | Storage::Mat { .. } if inputs.len() != 1 && layout.files.is_none() => {
            return Err(InputError::file(
                &sources.join(" + "),
                "binary and MAT-file layouts read one input file unless the layout's [files] arrange says how \
                 several are read",
            ));
        }
        _ => read_numeric_side_by_side(inputs, sources, layout)?,
    };
    let records = 0..values.len();
    Ok(Records { values, lines, parts: vec![Part { source: sources[0].clone(), records, shift_s: 0.0 }] })
}

/// Binary or MAT-files side by side: each file's fields are numbered on from the previous file's, and every file
/// must hold as many records as the first.
fn read_numeric_side_by_side(
    inputs: &[&Path],
    sources: &[String],
    layout: &Layout,
) -> Result<(Vec<RawRecord>, Vec<usize>), InputError> {
    let mut budget = super::mat::ValueBudget::new();
    let mut merged: Option<(Vec<RawRecord>, Vec<usize>)> = None;
    let mut first_field = 0usize;
    let mut only = String::new();
    for (input, source) in inputs.iter().zip(sources) {
        let file = read_numeric_file(input, source, layout, first_field, &mut budget)?;
        let here: Vec<usize> = layout
            .slots()
            .iter()
            .filter(|(_, f)| (first_field..first_field + file.width).contains(f))
            .map(|s| s.0)
            .collect();
        first_field += file.width;
        only = file.what.clone();
        let Some((values, _)) = merged.as_mut() else {
            merged = Some((file.values, file.lines));
            continue;
        };
        let (n, first_n) = (file.values.len(), values.len());
        if n != first_n {
            let (at, reason) = if n > first_n {
                (first_n + 1, format!("{n} records, more than the {first_n} of {}", sources[0]))
            } else {
                (n.max(1), format!("the file ends after {n} records, {} has {first_n}", sources[0]))
            };
            return Err(InputError::at(source, at, format!("{reason}: files side by side hold as many records")));
        }
        for (record, mine) in values.iter_mut().zip(&file.values) {
            for &slot in &here {
                record[slot] = mine[slot];
            }
        }
    }
    if let Some((_, f)) = layout.slots().into_iter().find(|&(_, f)| f >= first_field) {
        let what = if inputs.len() == 1 { only } else { format!("the records ({first_field} fields in all)") };
        return Err(InputError::file(&sources.join(" + "), format!("field {f} is beyond {what}")));
    }
    Ok(merged.unwrap_or_default())
}

/// The inputs read one after another (`[files] arrange = "sequence"` or `"sessions"`): every file has the
/// layout's fields, and is one part.
fn read_in_sequence(inputs: &[&Path], sources: &[String], layout: &Layout) -> Result<Records, InputError> {
    let mut budget = super::mat::ValueBudget::new();
    let mut records = Records { values: Vec::new(), lines: Vec::new(), parts: Vec::new() };
    for (input, source) in inputs.iter().zip(sources) {
        let (values, lines) = match layout.storage {
            Storage::Text { .. } => read_text_records(&[read_text(input)?], std::slice::from_ref(source), layout)?,
            _ => {
                let file = read_numeric_file(input, source, layout, 0, &mut budget)?;
                if let Some((_, f)) = layout.slots().into_iter().find(|&(_, f)| f >= file.width) {
                    return Err(InputError::file(source, format!("field {f} is beyond {}", file.what)));
                }
                (file.values, file.lines)
            }
        };
        if values.is_empty() {
            return Err(InputError::file(source, "no records"));
        }
        let at = records.values.len();
        records.parts.push(Part { source: source.clone(), records: at..at + values.len(), shift_s: 0.0 });
        records.values.extend(values);
        records.lines.extend(lines);
    }
    Ok(records)
}

/// The records of one binary or MAT-file, with the layout's fields `first_field..first_field + width`.
struct NumericFile {
    values: Vec<RawRecord>,
    lines: Vec<usize>,
    /// Fields per record.
    width: usize,
    /// The record or matrix, for messages ("the binary record of 7 fields").
    what: String,
}

/// Reads one binary or MAT-file whose fields are the layout's from `first_field` on; a MAT-file's values come
/// out of `budget`. With a `[files]` table, a MAT-file's row vector (1 x n) is read as a column.
fn read_numeric_file(
    input: &Path,
    source: &str,
    layout: &Layout,
    first_field: usize,
    budget: &mut super::mat::ValueBudget,
) -> Result<NumericFile, InputError> {
    let wanted_in = |width: usize| -> Vec<(usize, usize)> {
        let range = first_field..first_field + width;
        layout.slots().into_iter().filter(|(_, f)| range.contains(f)).map(|(s, f)| (s, f - first_field)).collect()
    };
    match &layout.storage {
        Storage::Binary { kind, little_endian, fields, skip_bytes } => {
            let file = std::fs::File::open(input).map_err(|e| InputError::io(input, e))?;
            let spec =
                BinarySpec { kind: *kind, little_endian: *little_endian, fields: *fields, skip_bytes: *skip_bytes };
            let reader = std::io::BufReader::with_capacity(1 << 20, file);
            let (values, lines) = read_binary_records(reader, source, &spec, &wanted_in(*fields))?;
            Ok(NumericFile { values, lines, width: *fields, what: format!("the binary record of {fields} fields") })
        }
        Storage::Mat { variable } => {
            let bytes = std::fs::read(input).map_err(|e| InputError::io(input, e))?;
            let mut matrix = mat_matrix(&bytes, source, variable.as_deref(), budget)?;
            drop(bytes);
            if layout.files.is_some() && matrix.rows == 1 {
                (matrix.rows, matrix.cols) = (matrix.cols, 1);
            }
            let (values, lines) = read_mat_records(&matrix, source, &wanted_in(matrix.cols))?;
            let what = format!("the matrix '{}' of {} columns", matrix.name, matrix.cols);
            Ok(NumericFile { values, lines, width: matrix.cols, what })
        }
        Storage::Text { .. } => Err(InputError::file(source, "a text layout: not a binary or MAT-file")),
    }
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
    wanted: &[(usize, usize)],
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
        for &(slot, f) in wanted {
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

/// The MAT-file's matrix that the layout names (or its only one), its values out of `budget`.
fn mat_matrix(
    bytes: &[u8],
    source: &str,
    variable: Option<&str>,
    budget: &mut super::mat::ValueBudget,
) -> Result<super::mat::MatMatrix, InputError> {
    let mut matrices = super::mat::read_mat_within(bytes, source, budget)?;
    let names: Vec<String> = matrices.iter().map(|m| m.name.clone()).collect();
    let index = match variable {
        Some(v) => matrices.iter().position(|m| m.name == v).ok_or_else(|| {
            InputError::file(source, format!("no numeric matrix '{v}' (found: {})", names.join(", ")))
        })?,
        None if matrices.len() == 1 => 0,
        None => {
            return Err(InputError::file(
                source,
                format!("{} matrices ({}): name one with [mat] variable", matrices.len(), names.join(", ")),
            ))
        }
    };
    Ok(matrices.swap_remove(index))
}

/// Reads the records of a MAT-file matrix: one per row, the fields its columns (`wanted`: slot and column).
fn read_mat_records(
    matrix: &super::mat::MatMatrix,
    source: &str,
    wanted: &[(usize, usize)],
) -> Result<(Vec<RawRecord>, Vec<usize>), InputError> {
    let records = (0..matrix.rows)
        .map(|r| {
            let mut record = [f64::NAN; 7];
            for &(slot, f) in wanted {
                record[slot] = matrix.get(r, f).ok_or_else(|| {
                    InputError::file(source, format!("matrix '{}' has no row {} column {f}", matrix.name, r + 1))
                })?;
            }
            Ok(record)
        })
        .collect::<Result<Vec<RawRecord>, InputError>>()?;
    Ok((records, (1..=matrix.rows).collect()))
}

/// Times of the records on the recording's time base, s, checked finite and strictly increasing. Files in
/// sequence share one time base (a file's first time must follow the last of the file before: files that overlap
/// are refused); each session keeps its own and is shifted to start [`SESSION_GAP_S`] after the session before
/// (the shift is kept in its part). A constant rate counts the records from each session's first.
fn record_times(records: &mut Records, time: &TimeSource, sessions: bool) -> Result<Vec<f64>, InputError> {
    let mut t_s: Vec<f64> = Vec::with_capacity(records.values.len());
    for p in 0..records.parts.len() {
        let part = &records.parts[p];
        let counted_from = if sessions { part.records.start } else { 0 };
        t_s.extend(part.records.clone().map(|k| {
            let r = &records.values[k];
            match *time {
                TimeSource::Field { seconds_per_unit, .. } => r[0] * seconds_per_unit,
                TimeSource::Samples { rate_hz, .. } => r[0] / rate_hz,
                TimeSource::Rate { rate_hz, start_s } => start_s + (k - counted_from) as f64 / rate_hz,
            }
        }));
        let first = part.records.start;
        if sessions && p > 0 {
            let shift_s = t_s[first - 1] + SESSION_GAP_S - t_s[first];
            t_s[first..].iter_mut().for_each(|t| *t += shift_s);
            records.parts[p].shift_s = shift_s;
        }
        let part = &records.parts[p];
        for k in part.records.clone().filter(|&k| k > 0) {
            let (before, now) = (t_s[k - 1], t_s[k]);
            if now > before && now.is_finite() {
                continue;
            }
            let reason = if k == first {
                let previous = &records.parts[p - 1].source;
                format!(
                    "time {now} s is not after the last record of {previous} ({before} s): the files overlap in \
                     time; [files] arrange = \"sessions\" gives each file its own time base"
                )
            } else {
                format!("time {now} s does not increase (the record before: {before} s)")
            };
            return Err(InputError::at(&part.source, records.lines[k], reason));
        }
    }
    Ok(t_s)
}

/// The time steps between consecutive records of one part, s (not across files in sequence or sessions).
fn steps_within_parts(t_s: &[f64], parts: &[Part]) -> Vec<f64> {
    parts.iter().flat_map(|p| t_s[p.records.clone()].windows(2).map(|w| w[1] - w[0])).collect()
}

/// The median of `values` (at least one), reordering them.
fn median_of(values: &mut [f64]) -> f64 {
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The nominal rate, Hz: from the layout, or the median interval of the times rounded to 0.01 Hz.
fn nominal_rate_hz(dt_s: &mut [f64], time: &TimeSource) -> f64 {
    match *time {
        TimeSource::Rate { rate_hz, .. }
        | TimeSource::Samples { rate_hz, .. }
        | TimeSource::Field { nominal: Some(NominalRate { rate_hz, .. }), .. } => rate_hz,
        TimeSource::Field { nominal: None, .. } => (100.0 / median_of(dt_s)).round() / 100.0,
    }
}

/// A nominal rate given with time stamps, checked against them: the median step must be `1 / rate_hz` within
/// [`crate::io::recording::RATE_TOLERANCE`] (the recording's own rate check), else the layout's `rate_hz` line is
/// refused. Returns what the time stamps show (measured rate, jitter) for the summary and the header.
fn check_nominal_rate(
    dt_s: &mut [f64],
    nominal: &NominalRate,
    layout_source: &str,
    source: &str,
) -> Result<String, InputError> {
    let nominal_step_s = 1.0 / nominal.rate_hz;
    let mean_step_s = dt_s.iter().sum::<f64>() / dt_s.len() as f64;
    let spread_s = (dt_s.iter().map(|d| (d - mean_step_s).powi(2)).sum::<f64>() / dt_s.len() as f64).sqrt();
    let largest_jitter_s = dt_s.iter().map(|d| (d - nominal_step_s).abs()).fold(0.0, f64::max);
    let median_step_s = median_of(dt_s);
    let shown = crate::io::recording::shown;
    if (median_step_s / nominal_step_s - 1.0).abs() > crate::io::recording::RATE_TOLERANCE {
        return Err(InputError::at(
            layout_source,
            nominal.line,
            format!(
                "[time] rate_hz {} disagrees with the time stamps of {source}: the median time step is {} s ({} Hz), \
                 1/rate_hz is {} s (more than 1 % apart)",
                shown(nominal.rate_hz),
                shown(median_step_s),
                shown(1.0 / median_step_s),
                shown(nominal_step_s)
            ),
        ));
    }
    Ok(format!(
        "kept, nominal rate {} Hz checked against them (median step {} s, within 1 %); measured {} Hz (mean step {} \
         s); jitter: step standard deviation {} s, largest |step - 1/rate_hz| {} s",
        shown(nominal.rate_hz),
        shown(median_step_s),
        shown(1.0 / mean_step_s),
        shown(mean_step_s),
        shown(spread_s),
        shown(largest_jitter_s)
    ))
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

/// Sets the rows of each labelled range to its position and attitude; a range without a row is refused. A label
/// of a file (`file` column) covers that file's records, in its own times; with sessions, a range that holds
/// records of two files is refused (the gap between sessions is no dwell).
fn apply_labels(rows: &mut [Row], labels: &[Label], source: &str, files: &Files<'_>) -> Result<(), InputError> {
    for label in labels {
        let (lo, hi, shift_s) = match label.file {
            None => (0, rows.len(), 0.0),
            Some(f) => {
                if !files.in_sequence {
                    return Err(InputError::at(
                        source,
                        label.line,
                        format!(
                            "a range of file {f}: the files side by side are one record stream; a range names its \
                             file with [files] arrange = \"sequence\" or \"sessions\""
                        ),
                    ));
                }
                let part = f.checked_sub(1).and_then(|i| files.parts.get(i)).ok_or_else(|| {
                    InputError::at(source, label.line, format!("file {f}: there are {} input files", files.parts.len()))
                })?;
                (part.records.start, part.records.end, part.shift_s)
            }
        };
        let span = &rows[lo..hi];
        let first = lo + span.partition_point(|r| r.t_s - shift_s < label.start_s);
        let end = lo + span.partition_point(|r| r.t_s - shift_s < label.end_s);
        if first == end {
            let (a, b) = (span.first().map_or(0.0, |r| r.t_s - shift_s), span.last().map_or(0.0, |r| r.t_s - shift_s));
            return Err(InputError::at(
                source,
                label.line,
                format!(
                    "[{} s, {} s) holds no record (the records run from {a} s to {b} s)",
                    label.start_s, label.end_s
                ),
            ));
        }
        let touched: Vec<&str> = files
            .parts
            .iter()
            .filter(|p| p.records.start < end && first < p.records.end)
            .map(|p| p.source.as_str())
            .collect();
        if files.sessions && touched.len() > 1 {
            return Err(InputError::at(
                source,
                label.line,
                format!(
                    "[{} s, {} s) holds records of {}: a position lies within one session (the gap between sessions \
                     is no dwell)",
                    label.start_s,
                    label.end_s,
                    touched.join(" and ")
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

/// The input files as the recording's rows see them.
struct Files<'a> {
    /// Each file's rows (one part for files side by side).
    parts: &'a [Part],
    /// Whether the files were read one after another (`sequence` or `sessions`).
    in_sequence: bool,
    /// Whether each file is a session on its own time base.
    sessions: bool,
}

/// Finds the static intervals and levels each from its mean specific force (heading unknown); an interval ends
/// where a file ends (a file in sequence or a session is a pose of its own). Returns the rule as text, with the
/// intervals found.
fn detect_positions(
    rows: &mut [Row],
    files: &Files<'_>,
    layout: &Layout,
    rate_hz: f64,
    d: &StaticDetection,
    source: &str,
) -> Result<String, InputError> {
    let force: Vec<[f64; 3]> = rows.iter().map(|r| r.force_b_mps2).collect();
    let t_s: Vec<f64> = rows.iter().map(|r| r.t_s).collect();
    let intervals = detect_static_intervals(&force, &t_s, rate_hz, d, quantisation_floor_mps2sq(layout))
        .map_err(|r| InputError::file(source, r))?;
    let min_samples = ((d.min_static_s * rate_hz).round() as usize).max(1);
    let ranges: Vec<Range<usize>> = intervals
        .ranges
        .iter()
        .flat_map(|r| {
            files.parts.iter().filter_map(move |p| {
                let (lo, hi) = (r.start.max(p.records.start), r.end.min(p.records.end));
                (hi >= lo + min_samples).then_some(lo..hi)
            })
        })
        .collect();
    if ranges.is_empty() {
        return Err(InputError::file(
            source,
            format!(
                "no static interval found (threshold {:.3e} (m/s^2)^2 = {} x the first {} s): give a labels file or \
                 change the --static-* options",
                intervals.threshold_mps2sq, d.threshold_factor, d.init_static_s
            ),
        ));
    }
    level_intervals(rows, &ranges, source)?;
    Ok(format!(
        "sliding {} s window, sum of the 3 accel variances < {} x the first {} s ({:.3e} (m/s^2)^2, threshold {:.3e}), \
         at least {} s: {} interval(s)",
        d.window_s,
        d.threshold_factor,
        d.init_static_s,
        intervals.init_variance_mps2sq,
        intervals.threshold_mps2sq,
        d.min_static_s,
        ranges.len()
    ))
}

/// The recording of converted records, with positions, header and summary.
fn records_to_recording(
    mut records: Records,
    sources: &[String],
    import: &ColumnsImport<'_>,
) -> Result<Imported, InputError> {
    let layout = import.layout;
    let source = sources.join(" + ");
    if records.values.len() < 2 {
        return Err(InputError::file(&source, format!("{} record(s): too few", records.values.len())));
    }
    let sessions = layout.files == Some(Arrangement::Sessions);
    let t_s = record_times(&mut records, &layout.time, sessions)?;
    let (rate_hz, time_stamps) = rate_of(&t_s, &records.parts, import, &source)?;
    let mut rows = convert_rows(&records, &t_s, layout, rate_hz);
    drop(records.values);
    check_gravity(&rows, &layout.accel, rate_hz, &source)?;
    let (latitude_deg, latitude_source) = latitude_of(import)?;
    let files = Files {
        parts: &records.parts,
        in_sequence: layout.files.is_some_and(|a| a != Arrangement::SideBySide),
        sessions,
    };
    let (attitude_source, detection) = place_positions(&mut rows, &files, import, rate_hz, &source)?;
    let gyro_check = match &layout.gyro {
        Some(gyro) => {
            Some(super::gyro_units::check_gyro_units(&rows, latitude_deg, rate_hz, gyro.increments, &source)?)
        }
        None => None,
    };
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
    for (key, text) in files_and_time_stamps(&files, time_stamps) {
        comments.push(format!("{key}: {text}"));
        notes.push(format!("{}: {text}", key.replace('_', " ")));
    }
    notes.push(match gyro_check {
        Some(Some((s, std))) => format!(
            "gyro unit checked against the Earth rate's vertical part: {} +- {} times it (1 for a right unit)",
            crate::io::recording::shown(s),
            crate::io::recording::shown(std)
        ),
        Some(None) => "gyro unit not checked against the Earth rate: the dwells do not resolve it".to_string(),
        None => "no gyro in the layout: an accelerometer-only recording (written without gyro columns)".to_string(),
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
        has_gyro: layout.gyro.is_some(),
    };
    let summary = summarise(&recording, "described layout", &notes, &|_| String::new());
    Ok(Imported { recording, summary })
}

/// The recording's rate, Hz ([`nominal_rate_hz`]), and what kept time stamps show against a nominal rate
/// ([`check_nominal_rate`]).
fn rate_of(
    t_s: &[f64],
    parts: &[Part],
    import: &ColumnsImport<'_>,
    source: &str,
) -> Result<(f64, Option<String>), InputError> {
    let mut dt_s = steps_within_parts(t_s, parts);
    if dt_s.is_empty() {
        return Err(InputError::file(source, "no file holds two records: no time step to take the rate from"));
    }
    let time = &import.layout.time;
    let time_stamps = match time {
        TimeSource::Field { nominal: Some(n), .. } => {
            Some(check_nominal_rate(&mut dt_s, n, import.layout_source, source)?)
        }
        _ => None,
    };
    Ok((nominal_rate_hz(&mut dt_s, time), time_stamps))
}

/// The positions of the rows, from the labels or found as static intervals: where the attitudes came from, and
/// the detection's rule.
fn place_positions(
    rows: &mut [Row],
    files: &Files<'_>,
    import: &ColumnsImport<'_>,
    rate_hz: f64,
    source: &str,
) -> Result<(String, Option<String>), InputError> {
    match &import.positions {
        Positions::Labels(labels) => {
            let labels_source = import.labels_source.unwrap_or("labels");
            apply_labels(rows, labels, labels_source, files)?;
            Ok((format!("labels file {labels_source}"), None))
        }
        Positions::Detect(d) => {
            let rule = detect_positions(rows, files, import.layout, rate_hz, d, source)?;
            Ok((ATTITUDE_SOURCE_LEVELLED.to_string(), Some(rule)))
        }
    }
}

/// The rows of the records: times, values converted to SI in the body axes (no gyro: zeros, not written), no
/// positions yet.
fn convert_rows(records: &Records, t_s: &[f64], layout: &Layout, rate_hz: f64) -> Vec<Row> {
    let dt_s = 1.0 / rate_hz;
    records
        .values
        .iter()
        .zip(t_s.iter().zip(&records.lines))
        .map(|(r, (t, n))| Row {
            t_s: *t,
            pos: 0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            heading_deg: None,
            rate_b_radps: layout.gyro.as_ref().map_or([0.0; 3], |g| convert(&r[1..4], g, &layout.axes, dt_s)),
            force_b_mps2: convert(&r[4..7], &layout.accel, &layout.axes, dt_s),
            temp_c: None,
            turn_axis: None,
            line: *n,
        })
        .collect()
}

/// The latitude and where it came from: `--latitude-deg`, else the layout's.
fn latitude_of(import: &ColumnsImport<'_>) -> Result<(f64, String), InputError> {
    match (import.latitude_deg, import.layout.latitude_deg) {
        (Some(lat), _) => Ok((lat, "command line (--latitude-deg)".to_string())),
        (None, Some(lat)) => Ok((lat, format!("layout {}", import.layout_source))),
        (None, None) => Err(InputError::file(
            import.layout_source,
            "the latitude is unknown: give [site] latitude_deg in the layout or --latitude-deg",
        )),
    }
}

/// The header keys (and summary lines) of several files and of kept time stamps: `files` (in sequence) or
/// `sessions` (with each file's shift), and `time_stamps`.
fn files_and_time_stamps(files: &Files<'_>, time_stamps: Option<String>) -> Vec<(&'static str, String)> {
    let mut out = Vec::new();
    if files.in_sequence && files.parts.len() > 1 {
        let each = |p: &Part| {
            let (a, b) = (p.records.start + 1, p.records.end);
            if files.sessions {
                format!("{} (records {a} to {b}, times shifted by {} s)", p.source, p.shift_s)
            } else {
                format!("{} (records {a} to {b})", p.source)
            }
        };
        let list: Vec<String> = files.parts.iter().map(each).collect();
        out.push(if files.sessions {
            (
                "sessions",
                format!(
                    "{} files, each on its own time base, each shifted to start {SESSION_GAP_S} s after the one \
                     before: {}",
                    list.len(),
                    list.join(", ")
                ),
            )
        } else {
            ("files", format!("{} files in sequence on one time base: {}", list.len(), list.join(", ")))
        });
    }
    if let Some(text) = time_stamps {
        out.push(("time_stamps", text));
    }
    out
}
