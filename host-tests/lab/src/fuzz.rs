//! Every reader of sinscal as a fuzz target (docs/formats.md#bad-input): bytes in, the input accepted (with
//! finite values) or refused with a reason; anything else (a panic, a non-finite value accepted, the file
//! reader disagreeing with the text reader, a link request without its one reply) is a failure. The readers
//! that take paths (the importers, `import columns`) get the input written to a scratch file; the two-file
//! importers (imucal, imu_tk) get the bytes before the first zero byte as the first file and the rest as the
//! second. The stable mutation harness
//! (`host-tests/lab/tests/fuzz_readers.rs`) and the cargo-fuzz targets (`host-tests/fuzz/`) run these same
//! functions, from the same seeds.

use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
use sinscal::calib::compensation::Compensation;
use sinscal::instrument::device::Device;
use sinscal::instrument::link::{encode_frame, FrameReceiver, MAX_BODY_BYTES, MAX_WIRE_BYTES};
use sinscal::instrument::message::kind as msg;
use sinscal::instrument::store::RecordStore;
use sinscal::instrument::wire::record::Record;
use sinscal::rig::replay::{run_replay, ReplayError};
use sinscal::run::sampling::SamplingStats;
use sinscal::run::sequence::SequenceSolution;
use sinscal::sensor::adis::{decode_burst, encode_burst, AdisError, Burst, Model, I16F16};

use sinscal_host::analysis::AnglesFile;
use sinscal_host::calibration::firmware_path::{replay_file, ReplayPlan};
use sinscal_host::calibration::Options;
use sinscal_host::device::{configuration_body, Provenance};
use sinscal_host::io::calibration_model::CalibrationModel;
use sinscal_host::io::error::InputError;
use sinscal_host::io::import::{
    import_columns, import_imucal, import_imucal_raw, import_imutk, import_psins, parse_labels, ColumnsImport,
    Imported, Layout, Positions, StaticDetection,
};
use sinscal_host::io::recording::Recording;
use sinscal_host::io::ScratchFile;
use sinscal_host::model::simulator::ScenarioFile;
use sinscal_host::model::synth::Scenario;

/// A reader under test: bytes in, `Ok(true)` accepted (with finite values), `Ok(false)` refused.
pub type Reader = fn(&[u8]) -> Result<bool, String>;

fn text(bytes: &[u8]) -> Option<&str> {
    std::str::from_utf8(bytes).ok()
}

/// The recording text reader (`Recording::parse`).
pub fn read_recording(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match Recording::parse(t, "fuzz.csv") {
        Err(_) => Ok(false),
        Ok(r) => {
            let finite = r.rows.iter().all(|row| {
                row.t_s.is_finite()
                    && row.rate_b_radps.iter().chain(&row.force_b_mps2).all(|v| v.is_finite())
                    && [row.pitch_deg, row.roll_deg].iter().all(|v| v.is_finite())
            });
            if finite {
                Ok(true)
            } else {
                Err("a recording with a non-finite value was accepted".into())
            }
        }
    }
}

/// The file reader (chunks parsed on the available cores) against the text reader: what the file reader
/// accepts, the text reader accepts with the same rows (the file reader also refuses a last line without an
/// end of line, which the text reader cannot see).
pub fn read_recording_file(bytes: &[u8]) -> Result<bool, String> {
    let file = ScratchFile::new("fuzz.csv");
    std::fs::write(file.path(), bytes).map_err(|e| e.to_string())?;
    let from_file = Recording::read(file.path());
    let from_text = text(bytes).map(|t| Recording::parse(t, "fuzz.csv"));
    match (from_file, from_text) {
        (Err(_), _) => Ok(false),
        (Ok(f), Some(Ok(t))) if f.rows == t.rows && f.header == t.header => read_recording(bytes),
        (Ok(_), _) => Err("the file reader accepted what the text reader refuses or reads otherwise".into()),
    }
}

/// The angles file reader.
pub fn read_angles(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match AnglesFile::parse(t, "fuzz.angles") {
        Err(_) => Ok(false),
        Ok(a) => {
            let finite =
                a.rows.iter().all(|r| r.phi_rad.iter().chain(r.phi_std_rad.iter().flatten()).all(|v| v.is_finite()));
            if finite {
                Ok(true)
            } else {
                Err("an angles file with a non-finite value was accepted".into())
            }
        }
    }
}

/// The scenario reader (with its checks: finite numbers, bounded sizes).
pub fn read_scenario(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    Ok(ScenarioFile::parse(t, "fuzz.toml").is_ok())
}

/// The calibration JSON reader (`apply`, `navigate`).
pub fn read_calibration(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match CalibrationModel::parse(t, "fuzz.json") {
        Err(_) => Ok(false),
        Ok(m) => {
            let values = m.gyro_bias_radps.iter().chain(&m.accel_bias_mps2).chain(m.accel_t.iter().flatten());
            if values.chain(m.gyro_t.iter().flatten()).all(|v| v.is_finite()) {
                Ok(true)
            } else {
                Err("a calibration with a non-finite value was accepted".into())
            }
        }
    }
}

/// The replay file through the firmware path (header, frames, the calibration sequence).
pub fn read_replay(bytes: &[u8]) -> Result<bool, String> {
    let outcome: Result<_, ReplayError> = run_replay(bytes, |_| {});
    Ok(outcome.is_ok())
}

/// The ADIS16505-2 burst decoder.
pub fn read_burst(bytes: &[u8]) -> Result<bool, String> {
    let decoded: Result<Burst, AdisError<()>> = decode_burst(Model::Adis16505_2, bytes);
    Ok(decoded.is_ok())
}

/// The MAT-file reader (`io::import::mat::read_mat`): what it accepts is at least one matrix whose value count is
/// its rows times its columns, every value finite.
pub fn read_mat(bytes: &[u8]) -> Result<bool, String> {
    match sinscal_host::io::import::mat::read_mat(bytes, "fuzz.mat") {
        Err(_) => Ok(false),
        Ok(matrices) if matrices.is_empty() => Err("a MAT-file without a matrix was accepted".into()),
        Ok(matrices) => {
            for m in &matrices {
                if m.rows.checked_mul(m.cols) != Some(m.data.len()) {
                    return Err(format!(
                        "'{}': {}x{} with {} values was accepted",
                        m.name,
                        m.rows,
                        m.cols,
                        m.data.len()
                    ));
                }
                if !m.data.iter().all(|v| v.is_finite()) {
                    return Err(format!("'{}': a non-finite value was accepted", m.name));
                }
            }
            Ok(true)
        }
    }
}

/// The layout file of `sinscal import columns` (`io::import::Layout::parse`): what it accepts names three
/// different fields per sensor, finite non-zero scales and a body-from-sensor matrix that is a rotation.
pub fn read_layout(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match sinscal_host::io::import::Layout::parse(t, "fuzz.toml") {
        Err(_) => Ok(false),
        Ok(layout) => {
            let m = layout.axes;
            let det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            let scales_ok = layout.gyro.iter().chain([&layout.accel]).all(|c| {
                c.scale.iter().chain(&c.counts_per_unit).all(|s| s.is_finite() && *s != 0.0)
                    && c.fields[0] != c.fields[1]
                    && c.fields[1] != c.fields[2]
                    && c.fields[0] != c.fields[2]
            });
            if det != 1.0 {
                Err(format!("an axis mapping of determinant {det} was accepted"))
            } else if !scales_ok {
                Err("a zero or non-finite scale, or a field used twice, was accepted".into())
            } else {
                Ok(true)
            }
        }
    }
}

/// The labels file of `sinscal import columns` (`io::import::parse_labels`): what it accepts are finite ranges
/// that do not overlap, with pitch in [-90, 90].
pub fn read_labels(bytes: &[u8]) -> Result<bool, String> {
    let Some(t) = text(bytes) else { return Ok(false) };
    match sinscal_host::io::import::parse_labels(t, "fuzz.csv") {
        Err(_) => Ok(false),
        Ok(labels) => {
            for (i, a) in labels.iter().enumerate() {
                if !(a.start_s.is_finite() && a.end_s.is_finite() && a.start_s < a.end_s) {
                    return Err(format!("range [{}, {}) was accepted", a.start_s, a.end_s));
                }
                if !(-90.0..=90.0).contains(&a.pitch_deg) || !a.roll_deg.is_finite() {
                    return Err(format!("pitch {} roll {} was accepted", a.pitch_deg, a.roll_deg));
                }
                if labels[i + 1..].iter().any(|b| b.start_s < a.end_s && a.start_s < b.end_s) {
                    return Err("overlapping ranges were accepted".into());
                }
            }
            Ok(true)
        }
    }
}

/// Every value of a recording finite: samples, attitudes, known headings and temperatures, and the header's
/// numbers.
fn recording_finite(r: &Recording) -> bool {
    let h = &r.header;
    let header = [Some(h.latitude_deg), Some(h.height_m), h.rate_hz, h.gravity_mps2, h.pose_tolerance_deg];
    header.iter().flatten().all(|v| v.is_finite())
        && r.rows.iter().all(|row| {
            let optional = [row.heading_deg, row.temp_c];
            [row.t_s, row.pitch_deg, row.roll_deg].iter().chain(optional.iter().flatten()).all(|v| v.is_finite())
                && row.rate_b_radps.iter().chain(&row.force_b_mps2).all(|v| v.is_finite())
        })
}

/// An importer's result: refused (`Ok(false)`), or accepted with rows, every value finite.
fn imported(result: Result<Imported, InputError>, what: &str) -> Result<bool, String> {
    match result {
        Err(_) => Ok(false),
        Ok(i) if i.recording.rows.is_empty() => Err(format!("{what}: a recording without rows was accepted")),
        Ok(i) if recording_finite(&i.recording) => Ok(true),
        Ok(_) => Err(format!("{what}: a recording with a non-finite value was accepted")),
    }
}

/// `bytes` written to a new scratch file (under `TMPDIR`, removed when dropped) for the readers that take paths.
fn scratch(name: &str, bytes: &[u8]) -> Result<ScratchFile, String> {
    let file = ScratchFile::new(name);
    std::fs::write(file.path(), bytes).map_err(|e| format!("{}: {e}", file.path().display()))?;
    Ok(file)
}

/// The two files of a two-file input: the bytes before the first zero byte and those after it (no zero byte:
/// all of it is the first file and the second is empty).
fn two_files(bytes: &[u8]) -> (&[u8], &[u8]) {
    match bytes.iter().position(|&b| b == 0) {
        Some(at) => (&bytes[..at], &bytes[at + 1..]),
        None => (bytes, &[]),
    }
}

/// The PSINS importer (`import_psins`) on a file.
pub fn read_psins(bytes: &[u8]) -> Result<bool, String> {
    let file = scratch("fuzz.imu", bytes)?;
    imported(import_psins(file.path(), None), "psins")
}

/// The imucal Ferraris importer (`import_imucal`): the session CSV and its labels JSON, separated by a zero byte.
pub fn read_imucal(bytes: &[u8]) -> Result<bool, String> {
    let (csv, labels) = two_files(bytes);
    let (csv, labels) = (scratch("fuzz.csv", csv)?, scratch("fuzz.json", labels)?);
    imported(import_imucal(csv.path(), labels.path(), None), "imucal")
}

/// The imucal raw-counts importer (`import_imucal_raw`): labels in a column.
pub fn read_imucal_raw(bytes: &[u8]) -> Result<bool, String> {
    let file = scratch("fuzz.csv", bytes)?;
    imported(import_imucal_raw(file.path(), None), "imucal-raw")
}

/// The static detection of the imu_tk target: the seed's 10 Hz session is shorter than imu_tk's defaults need.
fn imutk_detection() -> StaticDetection {
    StaticDetection { window_s: 1.0, init_static_s: 5.0, threshold_factor: 6.0, min_static_s: 2.0 }
}

/// The imu_tk importer (`import_imutk`): the accelerometer file and the gyro file, separated by a zero byte.
pub fn read_imutk(bytes: &[u8]) -> Result<bool, String> {
    let (acc, gyro) = two_files(bytes);
    let (acc, gyro) = (scratch("acc.mat", acc)?, scratch("gyro.mat", gyro)?);
    imported(import_imutk(acc.path(), gyro.path(), None, &imutk_detection()), "imutk")
}

/// The site of the `import columns` layouts.
const COLUMNS_SITE: &str = "[site]\nlatitude_deg = 45.7796\n";

/// The text layout of the `columns-text` target: comma-separated, a header line, `#` comments, time in s, the
/// gyro in deg/s, the accelerometer in m/s^2 with front-right-down axes.
const COLUMNS_TEXT_LAYOUT: &str = "format = \"text\"\n[text]\ndelimiter = \",\"\nskip_lines = 1\ncomment = \"#\"\n\
    [time]\nfield = 0\nunit = \"s\"\n[gyro]\nfields = [1, 2, 3]\nunit = \"deg/s\"\n[accel]\nfields = [4, 5, 6]\n\
    unit = \"m/s^2\"\n[axes]\nx = \"y\"\ny = \"x\"\nz = \"-z\"\n";

/// The binary layout of the `columns-binary` target: big-endian f32 records of seven fields after an 8-byte
/// header, time in s.
const COLUMNS_BINARY_LAYOUT: &str = "format = \"binary\"\n[binary]\ntype = \"f32\"\nendian = \"big\"\nfields = 7\n\
    skip_bytes = 8\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\n\
    unit = \"m/s^2\"\n";

/// The MAT-file layout of the `columns-mat` target: the matrix `imu`, one row per sample (t, gyro, accel).
const COLUMNS_MAT_LAYOUT: &str = "format = \"mat\"\n[mat]\nvariable = \"imu\"\n[time]\nfield = 0\n[gyro]\n\
    fields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n";

/// The labels of the `columns-*` targets' seed session: six poses of 1 s, 0.5 s apart.
const COLUMNS_LABELS: &str = "pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n1,0,1,0,0,0\n2,1.5,2.5,0,180,?\n\
    3,3,4,90,0,90\n4,4.5,5.5,-90,0,\n5,6,7,0,90,0\n6,7.5,8.5,0,-90,270\n";

/// The layout of the `columns-sessions` target: two whitespace-separated text files (t, gyro rad/s, accel m/s^2),
/// each a session on its own time base.
const COLUMNS_SESSIONS_LAYOUT: &str = "format = \"text\"\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\n\
    unit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\nunit = \"m/s^2\"\n[files]\narrange = \"sessions\"\n";

/// The labels of the `columns-sessions` target: three poses in each file, in the file's own times.
const COLUMNS_FILE_LABELS: &str = "file,pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n1,1,0,1,0,0,0\n\
    1,2,1.5,2.5,0,180,?\n1,3,3,4,90,0,90\n2,4,0,1,-90,0,\n2,5,1.5,2.5,0,90,0\n2,6,3,4,0,-90,270\n";

/// The layout of the `columns-side-by-side` target: two binary files of little-endian f32 records of four fields
/// side by side, time and gyro in the first, accelerometer (and a spare field) in the second.
const COLUMNS_SIDE_BY_SIDE_LAYOUT: &str = "format = \"binary\"\n[binary]\ntype = \"f32\"\nendian = \"little\"\n\
    fields = 4\n[time]\nfield = 0\n[gyro]\nfields = [1, 2, 3]\nunit = \"rad/s\"\n[accel]\nfields = [4, 5, 6]\n\
    unit = \"m/s^2\"\n[files]\narrange = \"side-by-side\"\n";

/// `sinscal import columns` (`import_columns`) of a data file through a fixed layout and the fixed labels.
fn read_columns(layout: &str, name: &str, bytes: &[u8]) -> Result<bool, String> {
    read_columns_files(layout, &[(name, bytes)], COLUMNS_LABELS)
}

/// `import columns` of two text files (split at the first zero byte) as sessions, positions by file.
pub fn read_columns_sessions(bytes: &[u8]) -> Result<bool, String> {
    let (a, b) = two_files(bytes);
    read_columns_files(COLUMNS_SESSIONS_LAYOUT, &[("a.txt", a), ("b.txt", b)], COLUMNS_FILE_LABELS)
}

/// `import columns` of two binary files side by side: the first and the second half of the bytes.
pub fn read_columns_side_by_side(bytes: &[u8]) -> Result<bool, String> {
    let (a, b) = bytes.split_at(bytes.len() / 2);
    read_columns_files(COLUMNS_SIDE_BY_SIDE_LAYOUT, &[("a.bin", a), ("b.bin", b)], COLUMNS_LABELS)
}

/// `import columns` of the files `(name, bytes)` through a fixed layout and labels.
fn read_columns_files(layout: &str, files: &[(&str, &[u8])], labels: &str) -> Result<bool, String> {
    let layout = Layout::parse(&format!("{layout}{COLUMNS_SITE}"), "fuzz.toml").map_err(|e| e.to_string())?;
    let labels = parse_labels(labels, "labels.csv").map_err(|e| e.to_string())?;
    let import = ColumnsImport {
        layout: &layout,
        layout_source: "fuzz.toml",
        positions: Positions::Labels(labels),
        labels_source: Some("labels.csv"),
        latitude_deg: None,
    };
    let scratches = files.iter().map(|(name, bytes)| scratch(name, bytes)).collect::<Result<Vec<_>, _>>()?;
    let paths: Vec<&std::path::Path> = scratches.iter().map(|f| f.path()).collect();
    imported(import_columns(&paths, &import), files[0].0)
}

/// `import columns` of a text file (comma-separated, a header line, comments).
pub fn read_columns_text(bytes: &[u8]) -> Result<bool, String> {
    read_columns(COLUMNS_TEXT_LAYOUT, "columns.csv", bytes)
}

/// `import columns` of a binary file (big-endian f32 records after a header).
pub fn read_columns_binary(bytes: &[u8]) -> Result<bool, String> {
    read_columns(COLUMNS_BINARY_LAYOUT, "columns.bin", bytes)
}

/// `import columns` of a MAT-file (the matrix `imu`).
pub fn read_columns_mat(bytes: &[u8]) -> Result<bool, String> {
    read_columns(COLUMNS_MAT_LAYOUT, "columns.mat", bytes)
}

/// A NOR flash in RAM for the device of the link targets (erased to 0xFF, writes AND, bounds checked).
struct RamFlash(Vec<u8>);

impl ErrorType for RamFlash {
    type Error = NorFlashErrorKind;
}

impl RamFlash {
    fn range(&self, offset: u32, len: usize) -> Result<std::ops::Range<usize>, NorFlashErrorKind> {
        let start = offset as usize;
        let end = start.checked_add(len).filter(|&e| e <= self.0.len()).ok_or(NorFlashErrorKind::OutOfBounds)?;
        Ok(start..end)
    }
}

impl ReadNorFlash for RamFlash {
    const READ_SIZE: usize = 1;
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.0[r]);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.0.len()
    }
}

impl NorFlash for RamFlash {
    const WRITE_SIZE: usize = 4;
    const ERASE_SIZE: usize = 1024;
    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let r = self.range(from, to.saturating_sub(from) as usize)?;
        self.0[r].fill(0xFF);
        Ok(())
    }
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let r = self.range(offset, bytes.len())?;
        for (d, s) in self.0[r].iter_mut().zip(bytes) {
            *d &= *s;
        }
        Ok(())
    }
}

/// Received bytes through the device's end of the link: the frame receiver, and the device answering every
/// frame (or its refusal). Every answer must be one frame that the workstation's receiver accepts, with the
/// request's sequence number (or an error reply). `Ok(true)` when a request got a reply other than an error.
fn serve(wire: &[u8]) -> Result<bool, String> {
    let store = RecordStore::new(RamFlash(vec![0xFF; 32 * 1024]), 16 * 1024).map_err(|e| format!("{e:?}"))?;
    let mut device = Device::new(Model::Adis16505_2, store);
    let (mut rx, mut host) = (FrameReceiver::new(), FrameReceiver::new());
    let mut reply = vec![0u8; MAX_WIRE_BYTES];
    let sampling = SamplingStats::default();
    let mut answered = false;
    for &byte in wire {
        let Some(frame) = rx.push(byte) else { continue };
        let request = frame.as_ref().ok().map(|f| (f.kind, f.seq));
        let (n, _) = device.on_frame(frame, &sampling, &mut reply);
        let frames: Vec<_> =
            reply[..n].iter().filter_map(|&b| host.push(b).map(|r| r.map(|f| (f.kind, f.seq)))).collect();
        match (frames.as_slice(), request) {
            ([Ok((msg::ERROR, _))], _) => {}
            ([Ok((k, seq))], Some((rk, rseq))) if *k == rk | msg::REPLY && *seq == rseq => answered = true,
            _ => return Err(format!("request {request:?}: the reply's frames are {frames:?}")),
        }
    }
    Ok(answered)
}

/// The device link's frame decoder (`link::FrameReceiver`: stuffing, length, CRC, version) on raw received bytes,
/// each frame answered by the device.
pub fn read_link_frames(bytes: &[u8]) -> Result<bool, String> {
    serve(bytes)
}

/// The device's request decoders (configure, annotate, offsets, ...): the input is a series of requests, each
/// `kind u8, body length u16 LE, body` (a short last one takes what is left), framed with a right CRC (which
/// mutations of raw frames rarely keep) and answered by the device.
pub fn read_link_requests(bytes: &[u8]) -> Result<bool, String> {
    let mut wire = Vec::new();
    let mut frame = vec![0u8; MAX_WIRE_BYTES];
    let (mut rest, mut seq) = (bytes, 0u8);
    while let [kind, rest_after_kind @ ..] = rest {
        let (len, body_and_more) = match rest_after_kind {
            [a, b, more @ ..] => (u16::from_le_bytes([*a, *b]) as usize, more),
            _ => (0, &[][..]),
        };
        let (body, more) = body_and_more.split_at(len.min(body_and_more.len()).min(MAX_BODY_BYTES));
        seq = seq.wrapping_add(1);
        let n = encode_frame(*kind, seq, body, &mut frame).ok_or("a request's frame could not be encoded")?;
        wire.extend_from_slice(&frame[..n]);
        rest = more;
    }
    serve(&wire)
}

/// The workstation's reading of a calibration record from the device (`device::calibration_of_record`: the
/// record's head, the configuration, the provenance note, the outcome): what it accepts has finite estimates.
pub fn read_link_record(bytes: &[u8]) -> Result<bool, String> {
    let record = sinscal_host::device::DeviceRecord { bytes: bytes.to_vec(), sequence: 1 };
    match sinscal_host::device::calibration_of_record(&record, None) {
        Err(_) => Ok(false),
        Ok(c) => {
            let e = &c.estimates;
            if e.value_si.iter().chain(&e.std_si).flatten().all(|v| v.is_finite()) {
                Ok(true)
            } else {
                Err("a record with a non-finite estimate was accepted".into())
            }
        }
    }
}

/// The wire bytes of a workstation's session with the device: identify, configure (`configuration`), annotate,
/// status, start, abort, the first parts of the result and the record, stream on, erase.
fn link_session(configuration: &[u8]) -> Vec<(u8, Vec<u8>)> {
    let mut annotate = vec![0, 0, 5, 0];
    annotate.extend_from_slice(b"{\"a\"}");
    vec![
        (msg::IDENTIFY, vec![]),
        (msg::CONFIGURE, configuration.to_vec()),
        (msg::ANNOTATE, annotate),
        (msg::STATUS, vec![]),
        (msg::START, vec![]),
        (msg::ABORT, vec![]),
        (msg::READ_RESULT, 0u32.to_le_bytes().to_vec()),
        (msg::READ_RECORD, 0u32.to_le_bytes().to_vec()),
        (msg::STREAM, vec![1]),
        (msg::ERASE, vec![]),
    ]
}

/// A calibration record as the device stores it, of the seed recording's replay through the firmware path.
fn seed_record(rec: &Recording, options: &Options, replay: &[u8], plan: &ReplayPlan) -> Vec<u8> {
    let outcome = run_replay(replay, |_| {}).expect("the seed replays");
    let compensation = match outcome.result.as_ref().expect("the seed's replay solves") {
        SequenceSolution::Channels(c) => Compensation::from_channels(c),
        SequenceSolution::Angles(r) => Compensation::from_angles(r),
    }
    .expect("the seed's solution gives a compensation");
    let header_len = sinscal::rig::replay::replay_header_bytes(outcome.configuration.schedule.len());
    let configuration = configuration_body(&replay[..header_len]).expect("the seed's header reads");
    let note = Provenance::of(rec, options, plan).to_bytes();
    let record = Record::new(compensation, &configuration, &note, outcome.view());
    let mut bytes = vec![0u8; record.record_bytes()];
    record.write_part(0, &mut bytes);
    bytes
}

/// The seed of `columns-*`: 9 s at 10 Hz, the six labelled poses of [`COLUMNS_LABELS`] (force along the pose's
/// down axis) and the moves between them; rows `t, gyro deg/s, accel m/s^2`.
fn columns_rows() -> Vec<[f64; 7]> {
    (0..90)
        .map(|k| {
            let t = f64::from(k) * 0.1;
            let f = match t {
                t if t < 1.0 => [0.0, 0.0, 9.8],
                t if (1.5..2.5).contains(&t) => [0.0, 0.0, -9.8],
                t if (3.0..4.0).contains(&t) => [9.8, 0.0, 0.0],
                t if (4.5..5.5).contains(&t) => [-9.8, 0.0, 0.0],
                t if (6.0..7.0).contains(&t) => [0.0, 9.8, 0.0],
                t if (7.5..8.5).contains(&t) => [0.0, -9.8, 0.0],
                _ => [3.0, 3.0, 8.0],
            };
            [t, 0.01, -0.02, 0.004, f[0], f[1], f[2]]
        })
        .collect()
}

/// The seed of `imutk`: accelerometer and gyro counts at 10 Hz, static z up, x up and y up between moves.
fn imutk_seed() -> Vec<u8> {
    let (mut acc, mut gyro) = (String::new(), String::new());
    for k in 0..220u32 {
        let t_s = 0.03 + f64::from(k) * 0.1;
        let one_g = 4074.0;
        let (x, y, z) = match f64::from(k) / 10.0 {
            s if s < 8.0 => (0.0, 0.0, one_g),
            s if (10.0..15.0).contains(&s) => (one_g, 0.0, 0.0),
            s if s >= 17.0 => (0.0, one_g, 0.0),
            _ => {
                let phase = f64::from(k) * 0.7;
                (1500.0 * phase.sin(), 1500.0 * phase.cos(), one_g - 800.0)
            }
        };
        let d = if k % 2 == 0 { 1.0 } else { -1.0 };
        acc += &format!("{t_s:.2} {:.0} {:.0} {:.0}\n", 32768.0 + x + d, 32768.0 + y - d, 32768.0 + z + d);
        gyro += &format!("{t_s:.2} 37546 30389 32768\n");
    }
    [acc.as_bytes(), &[0], gyro.as_bytes()].concat()
}

/// The importers' seeds: small files of each format (docs/data.md), as the importers' tests write them (PSINS,
/// imucal's Ferraris session and labels, imucal's raw session).
fn importer_seeds() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let psins = "% PSINS-format SIMU log file.\n% pitch roll yaw VE VN VU\n\n0.5 -1.0 -90.6 0 0 0\n\
                 34.0 108.0 380.0 0.0 10.0 9.780327\n0.1 0.2 0.1 125 125 100\n2 -3 0 80 0 -80\n0 0 7 0 1 80\n\
                 -5 9 3 0 0 80\n";
    let mut ferraris = String::from("n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n");
    for n in 0..30 {
        let accel = match n {
            2..=3 => "9.8,0,0",
            5..=6 => "-9.8,0,0",
            8..=9 => "0,9.8,0",
            11..=12 => "0,-9.8,0",
            14..=15 => "0,0,9.8",
            17..=18 => "0,0,-9.8",
            _ => "0.1,0.2,0.3",
        };
        ferraris += &format!("{n},1,-2,0.5,{accel}\n");
    }
    let ferraris_labels = "{\"x_p\": {\"start\": 2, \"end\": 4}, \"x_a\": {\"start\": 5, \"end\": 7},\n\
                           \"y_p\": {\"start\": 8, \"end\": 10}, \"y_a\": [11, 13],\n\
                           \"z_p\": {\"start\": 14, \"end\": 16}, \"z_a\": {\"start\": 17, \"end\": 19},\n\
                           \"x_rot\": {\"start\": 20, \"end\": 25}}\n";
    let imucal = [ferraris.as_bytes(), &[0], ferraris_labels.as_bytes()].concat();
    let imucal_raw = "part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\nx_a,3,-2048.0,0,0,16.4,-32.8,0\n\
                      x_a,4,-2048.0,0,0,16.4,-32.8,0\nx_p,0,2048.0,0,0,0,0,8.2\nx_p,1,2048,0,0,0,0,8.2\n\
                      x_rot,2,0,1024,0,1640,0,0\ny_a,5,0,-2048,0,0,0,0\ny_p,6,0,2048,0,0,0,0\n\
                      z_a,7,0,0,-2048,0,0,0\nz_p,8,0,0,2048,0,0,0\n";
    (psins.as_bytes().to_vec(), imucal, imucal_raw.as_bytes().to_vec())
}

/// The `import columns` seeds: one session as text (gyro in deg/s, front-right-down axes), as big-endian f32
/// records after an 8-byte header, and as a MAT-file matrix.
fn columns_seeds() -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    let rows = columns_rows();
    let mut columns_text = String::from("t,gx,gy,gz,ax,ay,az\n# a comment line\n");
    for r in &rows {
        let (w, f) = (r[1..4].iter().map(|v| v.to_degrees()), [r[5], r[4], -r[6]]);
        let cells: Vec<String> = std::iter::once(r[0]).chain(w).chain(f).map(|v| format!("{v:?}")).collect();
        columns_text += &(cells.join(",") + "\n");
    }
    let mut columns_binary = b"IMU\0\0\0\0\x07".to_vec();
    for v in rows.iter().flatten() {
        columns_binary.extend_from_slice(&(*v as f32).to_be_bytes());
    }
    let n = rows.len();
    let by_column: Vec<f64> = (0..7 * n).map(|i| rows[i % n][i / n]).collect();
    let columns_mat = sinscal_host::io::import::mat::write_mat_v5(&[("note", 1, 1, &[1.0]), ("imu", n, 7, &by_column)])
        .expect("the seed MAT-file is written");
    (columns_text.into_bytes(), columns_binary, columns_mat)
}

/// The seeds of the several-file `import columns` targets: the session of [`columns_rows`] as two text files of
/// three poses each (the second's times from 0 again) with a zero byte between them, and as two binary files
/// side by side (t and gyro; accelerometer and a spare field), one after the other.
fn columns_files_seeds() -> (Vec<u8>, Vec<u8>) {
    let rows = columns_rows();
    let text = |rows: &[[f64; 7]], t0: f64| -> String {
        let line = |r: &[f64; 7]| {
            let cells: Vec<String> =
                std::iter::once(r[0] - t0).chain(r[1..].iter().copied()).map(|v| format!("{v:?}")).collect();
            cells.join(" ") + "\n"
        };
        rows.iter().map(line).collect()
    };
    let sessions = [text(&rows[..45], 0.0).into_bytes(), vec![0], text(&rows[45..], 4.5).into_bytes()].concat();
    let f32s =
        |values: &mut dyn Iterator<Item = f64>| -> Vec<u8> { values.flat_map(|v| (v as f32).to_le_bytes()).collect() };
    let first = f32s(&mut rows.iter().flat_map(|r| r[..4].to_vec()));
    let second = f32s(&mut rows.iter().flat_map(|r| [r[4], r[5], r[6], 20.0]));
    (sessions, [first, second].concat())
}

/// The valid inputs the fuzzing starts from, per target: its name, its reader and a valid input that sinscal
/// writes itself.
pub fn seeds() -> Vec<(&'static str, Reader, Vec<u8>)> {
    let scenario = Scenario { dwell_s: 1.0, ..Scenario::example() };
    let rec = scenario.recording(1, "seed.csv");
    let cal = sinscal_host::calibration::calibrate(&rec, &Options::default()).expect("the seed calibrates");
    let cal_json = serde_json::to_string_pretty(&sinscal_host::calibration::result::CalibrationJson::new(&cal))
        .expect("the calibration serialises");
    let angles = "# sinscal-angles: 1\n# latitude_deg: 45.7796\n\
                  pos,pitch_deg,roll_deg,heading_deg,phi_e_rad,phi_n_rad,phi_u_rad,phi_e_std_rad,phi_n_std_rad,phi_u_std_rad\n\
                  1,0,0,0,1e-5,-2e-5,3e-4,1e-6,1e-6,1e-5\n2,0,0,180,2e-5,1e-5,-3e-4,1e-6,1e-6,1e-5\n\
                  3,0,0,90,1e-5,1e-5,2e-4,1e-6,1e-6,1e-5\n4,0,0,270,-1e-5,2e-5,1e-4,1e-6,1e-6,1e-5\n\
                  5,0,90,0,3e-5,-1e-5,3e-4,1e-6,1e-6,1e-5\n6,0,270,0,1e-5,1e-5,-2e-4,1e-6,1e-6,1e-5\n";
    let scenario_toml = include_str!("../../scenarios/all-effects.toml").to_string();
    let (replay, plan) = replay_file(&rec, &Options::default()).expect("the seed replays");
    let record = seed_record(&rec, &Options::default(), &replay, &plan);
    let header_len = sinscal::rig::replay::replay_header_bytes(6);
    let configuration = configuration_body(&replay[..header_len]).expect("the seed's header reads");
    let session = link_session(&configuration);
    let mut link_frames = Vec::new();
    let mut frame = vec![0u8; MAX_WIRE_BYTES];
    let mut link_requests = Vec::new();
    for (seq, (kind, body)) in session.iter().enumerate() {
        let n = encode_frame(*kind, seq as u8 + 1, body, &mut frame).expect("the seed's frames fit");
        link_frames.extend_from_slice(&frame[..n]);
        link_requests.push(*kind);
        link_requests.extend_from_slice(&(body.len() as u16).to_le_bytes());
        link_requests.extend_from_slice(body);
    }
    let (psins, imucal, imucal_raw) = importer_seeds();
    let (columns_text, columns_binary, columns_mat) = columns_seeds();
    let (columns_sessions, columns_side_by_side) = columns_files_seeds();
    let mut burst = vec![0u8; Model::Adis16505_2.burst_len()];
    let lsb = |x: f64| I16F16::from_num(x);
    let b = Burst {
        diag_stat: 0,
        gyro_lsb: [lsb(100.5), lsb(-200.25), lsb(300.0)],
        accel_lsb: [lsb(10.0), lsb(20.0), lsb(3000.0)],
        temp_raw: 25,
        data_counter: 7,
    };
    encode_burst(Model::Adis16505_2, &b, &mut burst);
    // Small MAT-files: little-endian and uncompressed (a 1x1 with a small-element name, a 3x2), and
    // big-endian with compressed elements (MATLAB's default -v7 layout).
    use sinscal_host::io::import::mat::{write_mat, ByteOrder};
    let values = [0.25, -1.5, 3.0, 1e-3, 9.81, -0.0];
    let matrices: [sinscal_host::io::import::mat::NamedMatrix<'_>; 2] =
        [("t", 1, 1, &[2.5]), ("acc_counts", 3, 2, &values)];
    let mat = write_mat(&matrices, ByteOrder::Little, false).expect("the seed MAT-file is written");
    let mat_compressed = write_mat(&matrices, ByteOrder::Big, true).expect("the seed MAT-file is written");
    // And a version 7.3 file (HDF5 behind MATLAB's user block), its datasets compressed as MATLAB writes them.
    let mat_v73 = sinscal_host::io::import::mat::write_mat_v73(&matrices, true).expect("the seed MAT-file is written");
    vec![
        ("recording", read_recording as Reader, rec.to_csv().into_bytes()),
        ("recording-file", read_recording_file as Reader, rec.to_csv().into_bytes()),
        ("angles", read_angles as Reader, angles.as_bytes().to_vec()),
        ("scenario", read_scenario as Reader, scenario_toml.into_bytes()),
        ("calibration", read_calibration as Reader, cal_json.into_bytes()),
        ("replay", read_replay as Reader, replay),
        ("burst", read_burst as Reader, burst),
        ("mat", read_mat as Reader, mat),
        ("mat-compressed", read_mat as Reader, mat_compressed),
        ("layout", read_layout as Reader, include_str!("../../layouts/imutk.toml").as_bytes().to_vec()),
        (
            "labels",
            read_labels as Reader,
            b"pos,start_s,end_s,pitch_deg,roll_deg,heading_deg\n1,0,4.5,0,-90,?\n2,5,9,90,0,12.5\n".to_vec(),
        ),
        ("mat-v73", read_mat as Reader, mat_v73),
        ("psins", read_psins as Reader, psins),
        ("imucal", read_imucal as Reader, imucal),
        ("imucal-raw", read_imucal_raw as Reader, imucal_raw),
        ("imutk", read_imutk as Reader, imutk_seed()),
        ("columns-text", read_columns_text as Reader, columns_text),
        ("columns-binary", read_columns_binary as Reader, columns_binary),
        ("columns-mat", read_columns_mat as Reader, columns_mat),
        ("columns-sessions", read_columns_sessions as Reader, columns_sessions),
        ("columns-side-by-side", read_columns_side_by_side as Reader, columns_side_by_side),
        ("link-frames", read_link_frames as Reader, link_frames),
        ("link-requests", read_link_requests as Reader, link_requests),
        ("link-record", read_link_record as Reader, record),
    ]
}
