//! The imucal importers: a Ferraris session in deg/s and m/s^2 with its JSON label file, and the raw
//! annotated session in counts.

use super::*;

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
    // serde_json keeps the last of two equal keys: labels given twice are refused instead.
    if let Err(e) = serde_json::from_str::<crate::io::calibration_model::NoDuplicateKeys>(text) {
        return Err(InputError::at(source, e.line().max(1), e.to_string()));
    }
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
/// pose's position and attitude ([`FERRARIS_POSES`], heading empty); all other rows get pos = 0 (pitch 0, roll 0,
/// heading empty), and those of a turn label (`x_rot`, `y_rot`, `z_rot`) its axis in the `turn` column. The latitude is `latitude_deg` or [`IMUCAL_DEFAULT_LATITUDE_DEG`]
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
    let (rows, first_sample, last_sample) = imucal_session_rows(lines, &columns, &index, &labels, csv_source)?;
    if rows.is_empty() {
        return Err(InputError::at(csv_source, column_line_number, "no data rows"));
    }
    let samples = (first_sample.unwrap_or(0), last_sample.unwrap_or(0));
    check_every_pose_sampled(&rows, &labels, labels_text, labels_source, csv_source, samples)?;
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

/// The rows of an imucal session with its first and last sample index (`None` without rows).
type SessionRows = (Vec<Row>, Option<u64>, Option<u64>);

/// Reads the data rows of an imucal session (`index` = the columns n_samples, gyr_x/y/z, acc_x/y/z) and labels
/// each by the static pose whose range holds its sample index; also returns the first and last sample index.
fn imucal_session_rows<'a>(
    lines: impl Iterator<Item = (usize, &'a str)>,
    columns: &[String],
    index: &[usize],
    labels: &[LabelRange],
    csv_source: &str,
) -> Result<SessionRows, InputError> {
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
        let holding = || labels.iter().filter(|r| (r.start..r.end).contains(&sample));
        let pose = holding().find_map(|r| ferraris_pose(&r.label));
        let turn = holding().find_map(|r| turn_axis(&r.label));
        let rate_b_radps = rate_degps.map(f64::to_radians);
        rows.push(labelled_row(sample as f64 / IMUCAL_RATE_HZ, (pose, turn), rate_b_radps, force_b_mps2, n));
    }
    Ok((rows, first_sample, previous))
}

/// Refuses a session in which some Ferraris pose has no sample (`samples` = the first and last sample index).
fn check_every_pose_sampled(
    rows: &[Row],
    labels: &[LabelRange],
    labels_text: &str,
    labels_source: &str,
    csv_source: &str,
    (first_sample, last_sample): (u64, u64),
) -> Result<(), InputError> {
    // A label past the data is not clipped to it: its rows would not be what the label says.
    if let Some(r) = labels.iter().find(|r| r.end > last_sample + 1 || r.start < first_sample) {
        return Err(InputError::at(
            labels_source,
            json_line_of(labels_text, &r.label),
            format!(
                "label '{}' [{}, {}) reaches past the samples of {csv_source} ({first_sample}..{last_sample})",
                r.label, r.start, r.end
            ),
        ));
    }
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
    Ok(())
}

/// The body axis of a Ferraris turn label (`x_rot`, `y_rot`, `z_rot`), `None` for any other label.
fn turn_axis(label: &str) -> Option<usize> {
    FERRARIS_ROTATIONS.iter().position(|r| *r == label)
}

/// A row of an imucal session: the pose's position and attitude, or pos = 0 outside the static poses, with the
/// axis of the labelled turn it belongs to.
fn labelled_row(
    t_s: f64,
    (pose, turn): (Option<&FerrarisPose>, Option<usize>),
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
        turn_axis: turn.filter(|_| pose.is_none()),
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
            pose_tolerance_deg: Some(HAND_PLACED_POSE_TOLERANCE_DEG),
        },
        rows,
        has_gyro: true,
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

/// The pose tolerance an imucal session's header carries, degrees: its faces are placed by hand on a table,
/// about a degree off (docs/method.md#poses-known-to-a-tolerance; measured on the shared Ferraris session:
/// chi-square per degree of freedom 1.18, 0.94 and 0.88 at 0.5, 1 and 2 deg, against 15,882 with exact labels).
pub const HAND_PLACED_POSE_TOLERANCE_DEG: f64 = 1.0;

/// Parses imucal's `annotated_session.csv`: columns `part` (the label), `samples` (sample index), `acc_x/y/z` and
/// `gyr_x/y/z` in raw counts, found by name, at [`IMUCAL_RAW_RATE_HZ`]. The rows are grouped by label in the file;
/// they are sorted by sample index (which must not repeat), and t_s = samples / 204.8.
///
/// Counts are converted with the nominal scales [`IMUCAL_RAW_ACCEL_LSB_PER_G`] (g = [`STANDARD_GRAVITY_MPS2`]) and
/// [`IMUCAL_RAW_GYRO_LSB_PER_DEGPS`]; the header comments and the summary say so. Labels map to positions as in
/// [`parse_imucal`]; the turns get pos = 0 and their axis; any other label is an error.
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
        let t_s = sample as f64 / IMUCAL_RAW_RATE_HZ;
        samples.push((sample, labelled_row(t_s, (pose, turn_axis(label)), rate_b_radps, force_b_mps2, n)));
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
