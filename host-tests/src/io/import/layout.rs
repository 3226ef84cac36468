//! The layout file of `sinscal import columns` (docs/data.md#described-layouts): how a file's records hold time,
//! gyro and accelerometer values, in which units, as rates or increments, in which axes. Parsed from TOML, checked
//! as a whole before any data are read.

use serde::Deserialize;

use crate::io::error::InputError;

use super::STANDARD_GRAVITY_MPS2;

/// A described layout, checked ([`Layout::parse`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// How the records are stored.
    pub storage: Storage,
    /// Where the time comes from.
    pub time: TimeSource,
    /// The gyro's three fields and their conversion to rad/s; `None`: no gyro (accelerometer-only data, written
    /// without gyro columns).
    pub gyro: Option<Channel>,
    /// The accelerometer's three fields and their conversion to m/s^2.
    pub accel: Channel,
    /// Body (x right, y forward, z up) from the sensor's axes: `body = axes * sensor`, a signed permutation of
    /// determinant +1.
    pub axes: [[f64; 3]; 3],
    /// Site: latitude (degrees north) and local gravity (m/s^2), when the layout gives them.
    pub latitude_deg: Option<f64>,
    /// Local gravity, m/s^2, when the layout gives it (also the "g" of accelerometer values in g).
    pub gravity_mps2: Option<f64>,
    /// Height above the ellipsoid, m (0 when the layout does not say).
    pub height_m: f64,
    /// How several input files make one record stream (`[files]`); `None`: the layout has no `[files]` table (text
    /// files side by side, one binary or MAT-file).
    pub files: Option<Arrangement>,
}

/// How several input files make one record stream (`[files] arrange`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arrangement {
    /// Record k of every file is one record; the fields are numbered on from one file to the next.
    SideBySide,
    /// The files one after another, on one time base: each file's first time follows the last of the one before.
    Sequence,
    /// The files one after another, each on its own time base: each is shifted to start [`SESSION_GAP_S`] after
    /// the end of the one before.
    Sessions,
}

/// The gap between two sessions in the recording, s: session k + 1 is shifted so that its first record lies this
/// long after the last record of session k (more than one sample interval, so that no dwell reads across it).
pub const SESSION_GAP_S: f64 = 1.0;

/// A nominal rate given with a time field: the time stamps are kept and checked against it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NominalRate {
    /// Samples per second.
    pub rate_hz: f64,
    /// The layout file's line that gives it (for the refusal when the time stamps disagree).
    pub line: usize,
}

/// How the records are stored.
#[derive(Clone, Debug, PartialEq)]
pub enum Storage {
    /// Text lines.
    Text {
        /// The field separator; `None`: any whitespace.
        delimiter: Option<char>,
        /// Lines skipped at the start of each file, comments included.
        skip_lines: usize,
        /// Lines starting with this are skipped anywhere.
        comment: Option<String>,
    },
    /// Fixed-size binary records of numbers of one type.
    Binary {
        /// The number type.
        kind: BinaryType,
        /// Byte order.
        little_endian: bool,
        /// Numbers per record.
        fields: usize,
        /// Header bytes before the first record.
        skip_bytes: u64,
    },
    /// A numeric matrix of a MATLAB MAT-file (version 5): one record per row.
    Mat {
        /// The matrix's name; `None`: the file's only numeric matrix.
        variable: Option<String>,
    },
}

/// The number type of binary records.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BinaryType {
    /// IEEE 754 single.
    F32,
    /// IEEE 754 double.
    F64,
    /// Two's complement 16-bit integer.
    I16,
    /// Two's complement 32-bit integer.
    I32,
}

impl BinaryType {
    /// Bytes per number.
    pub fn bytes(self) -> usize {
        match self {
            BinaryType::I16 => 2,
            BinaryType::F32 | BinaryType::I32 => 4,
            BinaryType::F64 => 8,
        }
    }
}

/// Where the time of a record comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum TimeSource {
    /// A field, multiplied by `seconds_per_unit`.
    Field {
        /// The time's field.
        field: usize,
        /// Seconds per unit of the field.
        seconds_per_unit: f64,
        /// The nominal rate, when the layout gives one with the field (`rate_hz`): the recording's rate, checked
        /// against the time stamps; `None`: the rate is measured from them.
        nominal: Option<NominalRate>,
    },
    /// A field that counts samples at `rate_hz`: `t = value / rate_hz`.
    Samples {
        /// The sample number's field.
        field: usize,
        /// Samples per second.
        rate_hz: f64,
    },
    /// A constant rate: record k is at `start_s + k / rate_hz`.
    Rate {
        /// Records per second.
        rate_hz: f64,
        /// Time of the first record, s.
        start_s: f64,
    },
}

/// Three fields of one sensor and their conversion: `si = (raw - offset) * scale / counts_per_unit * unit_si`, per
/// axis, then divided by the sample interval when the values are increments.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The sensor's x, y, z fields (0-based, counted across the input files in order).
    pub fields: [usize; 3],
    /// Subtracted from the raw value first (counts of an unsigned output, for example).
    pub offset: [f64; 3],
    /// Multiplies the raw value after the offset (the unit per count of raw counts).
    pub scale: [f64; 3],
    /// Divides the raw value after the offset (the counts per unit of a data sheet's gain).
    pub counts_per_unit: [f64; 3],
    /// The unit in SI: rad/s (rad for increments) or m/s^2 (m/s for increments) per unit of the scaled value.
    pub unit_si: f64,
    /// The unit as written in the layout.
    pub unit: String,
    /// Whether the values are increments over the sample (angle, velocity) rather than rates.
    pub increments: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LayoutFile {
    format: String,
    text: Option<TextFile>,
    binary: Option<BinaryFile>,
    mat: Option<MatFile>,
    time: TimeFile,
    gyro: Option<ChannelFile>,
    accel: Option<ChannelFile>,
    axes: Option<AxesFile>,
    site: Option<SiteFile>,
    files: Option<FilesFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FilesFile {
    arrange: String,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct TextFile {
    delimiter: Option<String>,
    skip_lines: Option<usize>,
    comment: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BinaryFile {
    #[serde(rename = "type")]
    kind: BinaryType,
    endian: String,
    fields: usize,
    skip_bytes: Option<u64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct MatFile {
    variable: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TimeFile {
    field: Option<usize>,
    unit: Option<String>,
    rate_hz: Option<toml::Spanned<f64>>,
    start_s: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum PerAxis {
    One(f64),
    Three([f64; 3]),
}

impl PerAxis {
    fn axes(&self) -> [f64; 3] {
        match self {
            PerAxis::One(v) => [*v; 3],
            PerAxis::Three(v) => *v,
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ChannelFile {
    fields: [usize; 3],
    unit: String,
    scale: Option<PerAxis>,
    counts_per_unit: Option<PerAxis>,
    offset: Option<PerAxis>,
    increments: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AxesFile {
    from: Option<String>,
    x: Option<String>,
    y: Option<String>,
    z: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SiteFile {
    latitude_deg: Option<f64>,
    gravity_mps2: Option<f64>,
    height_m: Option<f64>,
}

/// Degrees per radian.
const RAD_PER_DEG: f64 = std::f64::consts::PI / 180.0;

impl Layout {
    /// Parses and checks a layout file's text; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<Layout, InputError> {
        let file: LayoutFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
            match line {
                Some(line) => InputError::at(source, line, e.message().to_string()),
                None => InputError::file(source, e.message().to_string()),
            }
        })?;
        let bad = |reason: String| InputError::file(source, reason);
        let site = file.site.as_ref();
        let latitude_deg = site.and_then(|s| s.latitude_deg);
        if let Some(lat) = latitude_deg {
            if !(lat.is_finite() && (-90.0..=90.0).contains(&lat)) {
                return Err(bad(format!("[site] latitude_deg {lat} is outside [-90, 90]")));
            }
        }
        let gravity_mps2 = site.and_then(|s| s.gravity_mps2);
        if let Some(g) = gravity_mps2 {
            if !crate::io::recording::gravity_ok(g) {
                return Err(bad(format!("[site] gravity_mps2 {g} is not a gravity on Earth (9.7..9.9)")));
            }
        }
        let height_m = site.and_then(|s| s.height_m).unwrap_or(0.0);
        if !(height_m.is_finite() && (-1000.0..=10_000.0).contains(&height_m)) {
            return Err(bad(format!("[site] height_m {height_m} is outside [-1000, 10000]")));
        }
        let storage = storage(&file).map_err(bad)?;
        let line_of = |offset: usize| text[..offset.min(text.len())].matches('\n').count() + 1;
        let time = time_source(&file.time, &line_of).map_err(bad)?;
        let g = gravity_mps2.unwrap_or(STANDARD_GRAVITY_MPS2);
        let gyro = file.gyro.as_ref().map(|c| channel(c, "gyro", &gyro_unit)).transpose().map_err(bad)?;
        let accel_file = file.accel.as_ref().ok_or_else(|| {
            bad("no [accel] table: a recording holds the accelerometers (gyro-only data cannot be imported); \
                 [gyro] may be left out for accelerometer-only data"
                .to_string())
        })?;
        let accel = channel(accel_file, "accel", &|u, inc| accel_unit(u, inc, g)).map_err(bad)?;
        let axes = axes(file.axes.as_ref()).map_err(bad)?;
        let files = file.files.as_ref().map(|f| arrangement(&f.arrange)).transpose().map_err(bad)?;
        let layout = Layout { storage, time, gyro, accel, axes, latitude_deg, gravity_mps2, height_m, files };
        // One field read as two quantities (gyro fields pointing at the accelerometer's) is a layout mistake.
        let slots = layout.slots();
        for (k, &(slot, field)) in slots.iter().enumerate() {
            if let Some(&(other, _)) = slots[..k].iter().find(|(_, f)| *f == field) {
                let name = |s: usize| ["time", "gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z"][s];
                return Err(bad(format!("field {field} is read as both {} and {}", name(other), name(slot))));
            }
        }
        // Every binary file holds the whole record, but for files side by side (their fields numbered on).
        if let (Storage::Binary { fields, .. }, false) =
            (&layout.storage, layout.files == Some(Arrangement::SideBySide))
        {
            let fields = *fields;
            if let Some((_, f)) = layout.slots().into_iter().find(|&(_, f)| f >= fields) {
                return Err(bad(format!(
                    "field {f} is beyond the binary record of {fields} fields (0 to {})",
                    fields - 1
                )));
            }
        }
        Ok(layout)
    }

    /// Every field the layout reads, with its slot in a record's seven values (0 time, if a field; 1 to 3 gyro
    /// x y z; 4 to 6 accel x y z): `(slot, field)`.
    pub fn slots(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::with_capacity(7);
        if let TimeSource::Field { field, .. } | TimeSource::Samples { field, .. } = self.time {
            out.push((0, field));
        }
        for i in 0..3 {
            if let Some(gyro) = &self.gyro {
                out.push((1 + i, gyro.fields[i]));
            }
            out.push((4 + i, self.accel.fields[i]));
        }
        out
    }

    /// One line saying what the layout is, for the recording's header.
    pub fn describe(&self) -> String {
        let storage = match &self.storage {
            Storage::Text { delimiter, skip_lines, .. } => format!(
                "text, {} separated, {skip_lines} line(s) skipped",
                delimiter.map_or("whitespace".to_string(), |d| format!("'{d}'"))
            ),
            Storage::Binary { kind, little_endian, fields, skip_bytes } => format!(
                "binary {kind:?} {}, {fields} fields per record, {skip_bytes} header bytes",
                if *little_endian { "little-endian" } else { "big-endian" }
            ),
            Storage::Mat { variable } => format!("MAT-file matrix {}", variable.as_deref().unwrap_or("(the only one)")),
        };
        let time = match self.time {
            TimeSource::Field { field, seconds_per_unit, nominal: None } => {
                format!("time field {field} x {seconds_per_unit} s")
            }
            TimeSource::Field { field, seconds_per_unit, nominal: Some(n) } => {
                format!("time field {field} x {seconds_per_unit} s at a nominal {} Hz", n.rate_hz)
            }
            TimeSource::Samples { field, rate_hz } => format!("time field {field} in samples at {rate_hz} Hz"),
            TimeSource::Rate { rate_hz, start_s } => format!("time from {rate_hz} Hz from {start_s} s"),
        };
        let channel = |c: &Channel, name: &str| {
            format!(
                "{name} fields {:?} in {}{} (offset {:?}, scale {:?}, counts per unit {:?})",
                c.fields,
                c.unit,
                if c.increments { " increments" } else { "" },
                c.offset,
                c.scale,
                c.counts_per_unit
            )
        };
        let gyro = self.gyro.as_ref().map_or("no gyro (accelerometer-only)".to_string(), |c| channel(c, "gyro"));
        let files = match self.files {
            None => "",
            Some(Arrangement::SideBySide) => "; files side by side",
            Some(Arrangement::Sequence) => "; files in sequence",
            Some(Arrangement::Sessions) => "; files as sessions",
        };
        format!(
            "{storage}; {time}; {gyro}; {}; body from sensor axes {:?}{files}",
            channel(&self.accel, "accel"),
            self.axes
        )
    }
}

fn storage(file: &LayoutFile) -> Result<Storage, String> {
    let only = |name: &str| {
        let given = [("text", file.text.is_some()), ("binary", file.binary.is_some()), ("mat", file.mat.is_some())];
        match given.iter().find(|(n, g)| *g && *n != name) {
            Some((other, _)) => Err(format!("format = \"{name}\" with a [{other}] table")),
            None => Ok(()),
        }
    };
    match file.format.as_str() {
        "text" => {
            only("text")?;
            let t = file.text.as_ref();
            let delimiter = match t.and_then(|t| t.delimiter.as_deref()) {
                None | Some("whitespace") => None,
                Some(d) if d.chars().count() == 1 => d.chars().next(),
                Some("\\t" | "tab") => Some('\t'),
                Some(d) => return Err(format!("[text] delimiter '{d}': one character, \"tab\" or \"whitespace\"")),
            };
            let comment = t.and_then(|t| t.comment.clone()).filter(|c| !c.is_empty());
            Ok(Storage::Text { delimiter, skip_lines: t.and_then(|t| t.skip_lines).unwrap_or(0), comment })
        }
        "binary" => {
            only("binary")?;
            let b = file.binary.as_ref().ok_or("format = \"binary\" needs a [binary] table (type, endian, fields)")?;
            let little_endian = match b.endian.as_str() {
                "little" => true,
                "big" => false,
                other => return Err(format!("[binary] endian \"{other}\": \"little\" or \"big\"")),
            };
            if b.fields == 0 || b.fields > 4096 {
                return Err(format!("[binary] fields {}: a record holds 1 to 4096 fields", b.fields));
            }
            Ok(Storage::Binary { kind: b.kind, little_endian, fields: b.fields, skip_bytes: b.skip_bytes.unwrap_or(0) })
        }
        "mat" => {
            only("mat")?;
            Ok(Storage::Mat { variable: file.mat.as_ref().and_then(|m| m.variable.clone()) })
        }
        other => Err(format!("format \"{other}\": \"text\", \"binary\" or \"mat\"")),
    }
}

/// `[files] arrange`.
fn arrangement(name: &str) -> Result<Arrangement, String> {
    match name {
        "side-by-side" => Ok(Arrangement::SideBySide),
        "sequence" => Ok(Arrangement::Sequence),
        "sessions" => Ok(Arrangement::Sessions),
        other => Err(format!("[files] arrange \"{other}\": \"side-by-side\", \"sequence\" or \"sessions\"")),
    }
}

/// `[time]`; `line_of` turns a byte offset of the layout's text into its line.
fn time_source(t: &TimeFile, line_of: &dyn Fn(usize) -> usize) -> Result<TimeSource, String> {
    let rate_line = t.rate_hz.as_ref().map(|r| line_of(r.span().start));
    let rate_hz = t.rate_hz.as_ref().map(|r| *r.get_ref());
    if let Some(rate_hz) = rate_hz {
        if !(rate_hz.is_finite() && rate_hz > 0.0 && rate_hz <= 1e6) {
            return Err(format!("[time] rate_hz {rate_hz} is not a sample rate (0 to 1 MHz)"));
        }
    }
    if let (Some(field), Some("samples")) = (t.field, t.unit.as_deref()) {
        let rate_hz = rate_hz.ok_or("[time] unit \"samples\" needs rate_hz")?;
        return Ok(TimeSource::Samples { field, rate_hz });
    }
    match (t.field, rate_hz) {
        (Some(field), rate_hz) => {
            let seconds_per_unit = match t.unit.as_deref().unwrap_or("s") {
                "s" => 1.0,
                "ms" => 1e-3,
                "us" => 1e-6,
                "ns" => 1e-9,
                other => return Err(format!("[time] unit \"{other}\": \"s\", \"ms\", \"us\", \"ns\" or \"samples\"")),
            };
            if t.start_s.is_some() {
                return Err("[time] start_s goes with rate_hz, not with a time field".to_string());
            }
            let nominal = rate_hz.map(|rate_hz| NominalRate { rate_hz, line: rate_line.unwrap_or(0) });
            Ok(TimeSource::Field { field, seconds_per_unit, nominal })
        }
        (None, Some(rate_hz)) => {
            if t.unit.is_some() {
                return Err("[time] unit goes with a time field, not with rate_hz".to_string());
            }
            let start_s = t.start_s.unwrap_or(0.0);
            if !start_s.is_finite() {
                return Err("[time] start_s is not finite".to_string());
            }
            Ok(TimeSource::Rate { rate_hz, start_s })
        }
        (None, None) => Err("[time]: give the time's field (with its unit) or rate_hz".to_string()),
    }
}

/// A gyro unit in SI: rad/s per unit (rates), rad per unit (increments).
fn gyro_unit(unit: &str, increments: bool) -> Result<f64, String> {
    match (unit, increments) {
        ("rad/s", false) | ("rad", true) => Ok(1.0),
        ("deg/s", false) | ("deg", true) => Ok(RAD_PER_DEG),
        ("deg/h", false) => Ok(RAD_PER_DEG / 3600.0),
        ("arcsec", true) => Ok(RAD_PER_DEG / 3600.0),
        ("rad" | "deg" | "arcsec", false) => {
            Err(format!("[gyro] unit \"{unit}\" is an angle: set increments = true, or give a rate unit"))
        }
        ("rad/s" | "deg/s" | "deg/h", true) => {
            Err(format!("[gyro] unit \"{unit}\" is a rate: increments need an angle unit (rad, deg, arcsec)"))
        }
        _ => Err(format!("[gyro] unit \"{unit}\": rad/s, deg/s, deg/h (rates) or rad, deg, arcsec (increments)")),
    }
}

/// An accelerometer unit in SI: m/s^2 per unit (rates), m/s per unit (increments); `g` is the layout's gravity.
fn accel_unit(unit: &str, increments: bool, g: f64) -> Result<f64, String> {
    match (unit, increments) {
        ("m/s^2", false) | ("m/s", true) => Ok(1.0),
        ("g", false) | ("g*s", true) => Ok(g),
        ("mg", false) | ("mg*s", true) => Ok(g * 1e-3),
        ("ug", false) | ("ug*s", true) => Ok(g * 1e-6),
        ("m/s" | "g*s" | "mg*s" | "ug*s", false) => {
            Err(format!("[accel] unit \"{unit}\" is a velocity: set increments = true, or give an acceleration unit"))
        }
        ("m/s^2" | "g" | "mg" | "ug", true) => Err(format!(
            "[accel] unit \"{unit}\" is an acceleration: increments need a velocity unit (m/s, g*s, mg*s, ug*s)"
        )),
        _ => Err(format!("[accel] unit \"{unit}\": m/s^2, g, mg, ug (rates) or m/s, g*s, mg*s, ug*s (increments)")),
    }
}

fn channel(c: &ChannelFile, name: &str, unit: &dyn Fn(&str, bool) -> Result<f64, String>) -> Result<Channel, String> {
    let increments = c.increments.unwrap_or(false);
    let unit_si = unit(&c.unit, increments)?;
    if c.scale.is_some() && c.counts_per_unit.is_some() {
        return Err(format!("[{name}] give scale (units per count) or counts_per_unit, not both"));
    }
    let scale = c.scale.as_ref().map_or([1.0; 3], PerAxis::axes);
    let counts_per_unit = c.counts_per_unit.as_ref().map_or([1.0; 3], PerAxis::axes);
    if let Some(s) = counts_per_unit.iter().find(|s| !(s.is_finite() && **s != 0.0)) {
        return Err(format!("[{name}] counts_per_unit {s} is not a finite non-zero number"));
    }
    let offset = c.offset.as_ref().map_or([0.0; 3], PerAxis::axes);
    if let Some(s) = scale.iter().find(|s| !(s.is_finite() && **s != 0.0)) {
        return Err(format!("[{name}] scale {s} is not a finite non-zero number"));
    }
    if let Some(o) = offset.iter().find(|o| !o.is_finite()) {
        return Err(format!("[{name}] offset {o} is not finite"));
    }
    let f = c.fields;
    if f[0] == f[1] || f[0] == f[2] || f[1] == f[2] {
        return Err(format!("[{name}] fields {f:?}: three different fields"));
    }
    Ok(Channel { fields: f, offset, scale, counts_per_unit, unit_si, unit: c.unit.clone(), increments })
}

/// A signed sensor axis ("+x", "-z", "x") as a row of the body-from-sensor matrix.
fn signed_axis(text: &str, body: char) -> Result<[f64; 3], String> {
    let (sign, axis) = match text.trim() {
        t if t.starts_with('-') => (-1.0, &t[1..]),
        t if t.starts_with('+') => (1.0, &t[1..]),
        t => (1.0, t),
    };
    let mut row = [0.0; 3];
    match axis {
        "x" => row[0] = sign,
        "y" => row[1] = sign,
        "z" => row[2] = sign,
        _ => return Err(format!("[axes] {body} = \"{text}\": a sensor axis with its sign, such as \"+y\" or \"-z\"")),
    }
    Ok(row)
}

/// Body-from-sensor matrices of the named conventions: the sensor's x, y, z are right-forward-up (sinscal's own,
/// "rfu" or "enu"), front-right-down ("frd" or "ned": x forward, y right, z down), front-left-up ("flu").
fn named_axes(name: &str) -> Option<[[f64; 3]; 3]> {
    match name {
        "rfu" | "enu" => Some([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        "frd" | "ned" => Some([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]),
        "flu" => Some([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
        _ => None,
    }
}

fn axes(a: Option<&AxesFile>) -> Result<[[f64; 3]; 3], String> {
    let Some(a) = a else { return Ok(named_axes("rfu").unwrap_or_default()) };
    let m = match (&a.from, &a.x, &a.y, &a.z) {
        (Some(name), None, None, None) => named_axes(name)
            .ok_or_else(|| format!("[axes] from = \"{name}\": \"rfu\" (= \"enu\"), \"frd\" (= \"ned\") or \"flu\""))?,
        (None, Some(x), Some(y), Some(z)) => [signed_axis(x, 'x')?, signed_axis(y, 'y')?, signed_axis(z, 'z')?],
        _ => return Err("[axes]: give `from` (a named convention) or all of x, y, z, not both".to_string()),
    };
    let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if det.abs() < 0.5 {
        return Err(format!("[axes] {m:?} uses a sensor axis twice: not a rotation"));
    }
    if det < 0.0 {
        return Err(format!(
            "[axes] {m:?} has determinant -1: a mirror image, not a rotation (one sign is wrong, or two axes are \
             swapped)"
        ));
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ACCEL: &str = "[accel]\nfields = [1, 2, 3]\nunit = \"m/s^2\"\n";

    #[test]
    fn a_time_field_with_a_nominal_rate_keeps_the_rate_and_its_line() {
        let text = format!("format = \"text\"\n[time]\nfield = 0\nunit = \"ms\"\n\nrate_hz = 200\n{ACCEL}");
        let layout = Layout::parse(&text, "l.toml").unwrap();
        let nominal = Some(NominalRate { rate_hz: 200.0, line: 6 });
        assert_eq!(layout.time, TimeSource::Field { field: 0, seconds_per_unit: 1e-3, nominal });
        assert!(layout.describe().contains("time field 0 x 0.001 s at a nominal 200 Hz"), "{}", layout.describe());
        let bad = Layout::parse(&text.replace("rate_hz = 200", "rate_hz = -2"), "l.toml").unwrap_err();
        assert_eq!(bad.to_string(), "l.toml: [time] rate_hz -2 is not a sample rate (0 to 1 MHz)");
    }

    #[test]
    fn without_gyro_the_layout_reads_the_accelerometer_and_the_time_only() {
        let layout = Layout::parse(&format!("format = \"text\"\n[time]\nfield = 0\n{ACCEL}"), "l.toml").unwrap();
        assert_eq!(layout.gyro, None);
        assert_eq!(layout.slots(), vec![(0, 0), (4, 1), (5, 2), (6, 3)]);
        assert!(layout.describe().contains("; no gyro (accelerometer-only); accel fields [1, 2, 3]"));
    }

    #[test]
    fn the_files_table_names_an_arrangement() {
        let accel = ACCEL.replace("[1, 2, 3]", "[4, 5, 6]");
        let base = format!(
            "format = \"binary\"\n[binary]\ntype = \"f32\"\nendian = \"little\"\nfields = 4\n[time]\nfield = 0\n{accel}"
        );
        // Without [files], a binary record holds every field; side by side, the fields number on.
        let one = Layout::parse(&base, "l.toml").unwrap_err().to_string();
        assert!(one.contains("field 4 is beyond the binary record of 4 fields"), "{one}");
        let two = Layout::parse(&format!("{base}[files]\narrange = \"side-by-side\"\n"), "l.toml").unwrap();
        assert_eq!(two.files, Some(Arrangement::SideBySide));
        assert!(two.describe().ends_with("; files side by side"));
        let sessions = Layout::parse(&format!("{base}[files]\narrange = \"sessions\"\n"), "l.toml").unwrap_err();
        assert!(sessions.to_string().contains("field 4 is beyond the binary record of 4 fields"));
        let unknown = Layout::parse(&format!("{base}[files]\narrange = \"zip\"\n"), "l.toml").unwrap_err();
        assert_eq!(
            unknown.to_string(),
            "l.toml: [files] arrange \"zip\": \"side-by-side\", \"sequence\" or \"sessions\""
        );
    }
}
