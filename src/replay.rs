//! Replay of a recorded sequence through the firmware path: device frames, driver, sampling queue,
//! calibration sequence, core. The same [`run_replay`] runs in the firmware under QEMU (frames read
//! through semihosting) and on the host (`sinscal calibrate --on host`), so both see identical values.
//!
//! File format (little-endian), written by the host from a recording:
//! ```text
//! magic "SSRP", version u16 = 1, model u8 (0 = ADIS16470, 1 = ADIS16505-2), reserved u8
//! latitude_rad f32, gravity_mps2 f32, positions u16, reserved u16
//! prefilter u8 (0 = none, 1 = HMM/KF with the paper's Q and R), dwell value u8 (0 = mean, 1 = settled),
//! passes u8, estimate reference offset u8, a_gyro f32, a_accel f32
//! positions x (pitch_rad f32, roll_rad f32, heading_rad f32, label u16, reserved u16)
//! frames u32
//! frames x (table u8: 0 = moving, k = in position k of the list (1-based); burst bytes of the model)
//! ```

use embedded_hal::spi::{self, Operation, SpiDevice};
use heapless::spsc::Queue;
use heapless::Vec;

use crate::adis::{reg, Adis, AdisError, Model, BURST32_LEN, BURST_COMMAND, WRITE_FLAG};
use crate::align::DwellValue;
use crate::calibration::{CalibrationResult, CalibrationSettings, PositionInput};
use crate::dwell::{Prefilter, MIN_DWELL_SAMPLES};
use crate::earth::Site;
use crate::frames::Attitude;
use crate::prefilter::PrefilterSettings;
use crate::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
use crate::sequence::{CalibrationSequence, Event, SequenceError, SequenceFailure, SequenceSettings};
use crate::solve::MAX_POSITIONS;

/// File magic.
pub const MAGIC: [u8; 4] = *b"SSRP";
/// File version.
pub const VERSION: u16 = 1;

/// Errors of a replay.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReplayError {
    /// The source ended early or could not be read.
    Read,
    /// Not a replay file, or another version.
    Format,
    /// The sequence could not be set up.
    Sequence(SequenceError),
    /// The driver failed during initialisation.
    Init,
}

impl core::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplayError::Read => f.write_str("replay file ended early or could not be read"),
            ReplayError::Format => f.write_str("not a sinscal replay file (version 1)"),
            ReplayError::Sequence(e) => write!(f, "calibration sequence: {e:?}"),
            ReplayError::Init => f.write_str("IMU initialisation failed"),
        }
    }
}

impl core::error::Error for ReplayError {}

impl spi::Error for ReplayError {
    fn kind(&self) -> spi::ErrorKind {
        spi::ErrorKind::Other
    }
}

/// A byte stream (a file through semihosting, or a slice on the host).
pub trait ByteSource {
    /// Fills `buf` completely or fails.
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ReplayError>;
}

impl ByteSource for &[u8] {
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ReplayError> {
        if self.len() < buf.len() {
            return Err(ReplayError::Read);
        }
        let (head, tail) = self.split_at(buf.len());
        buf.copy_from_slice(head);
        *self = tail;
        Ok(())
    }
}

/// A burst frame, word-aligned so that serving it is a word copy, as a DMA transfer would be.
#[derive(Clone, Debug)]
#[repr(align(4))]
struct Frame([u8; BURST32_LEN]);

/// A simulated ADIS device on the SPI bus that serves recorded burst frames and answers register reads.
#[derive(Clone, Debug)]
pub struct ReplayDevice {
    model: Model,
    frame: Frame,
    pending: Option<u8>,
    registers: [u16; 64],
}

impl ReplayDevice {
    /// A device of `model` with its PROD_ID set.
    pub fn new(model: Model) -> ReplayDevice {
        let mut registers = [0u16; 64];
        registers[register_index(reg::PROD_ID)] = model.product_id();
        ReplayDevice { model, frame: Frame([0; BURST32_LEN]), pending: None, registers }
    }

    /// Sets the burst the next burst read returns.
    pub fn load_frame(&mut self, bytes: &[u8]) {
        let n = self.model.burst_len().min(bytes.len());
        self.frame.0[..n].copy_from_slice(&bytes[..n]);
    }

    /// A register's value (as last written).
    pub fn register(&self, address: u8) -> u16 {
        self.registers[register_index(address)]
    }
}

/// Index of a register in the device's register file: byte address without the write flag, in words.
fn register_index(address: u8) -> usize {
    ((address & !WRITE_FLAG) / 2) as usize
}

impl spi::ErrorType for ReplayDevice {
    type Error = ReplayError;
}

impl SpiDevice for ReplayDevice {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ReplayError> {
        match operations {
            [Operation::Write(cmd), Operation::Read(buf)] if *cmd == BURST_COMMAND => {
                let n = buf.len().min(self.model.burst_len());
                buf[..n].copy_from_slice(&self.frame.0[..n]);
                if n < buf.len() {
                    buf[n..].fill(0);
                }
            }
            [Operation::Write([address, value])] if address & WRITE_FLAG != 0 => {
                let index = register_index(*address);
                let current = self.registers[index].to_be_bytes();
                self.registers[index] = if address & 1 == 0 {
                    u16::from_be_bytes([current[0], *value])
                } else {
                    u16::from_be_bytes([*value, current[1]])
                };
            }
            [Operation::Write([address, _])] => self.pending = Some(*address),
            [Operation::Read(buf)] => {
                let value = self.pending.take().map_or(0, |a| self.registers[register_index(a)]);
                let bytes = value.to_be_bytes();
                for (i, b) in buf.iter_mut().enumerate() {
                    *b = bytes.get(i).copied().unwrap_or(0);
                }
            }
            _ => return Err(ReplayError::Format),
        }
        Ok(())
    }
}

/// The header of a replay file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayHeader {
    /// Sensor model of the frames.
    pub model: Model,
    /// Site.
    pub site: Site,
    /// Schedule: turntable attitudes.
    pub schedule: Vec<Attitude, MAX_POSITIONS>,
    /// The recording's position labels, in schedule order.
    pub labels: Vec<u16, MAX_POSITIONS>,
    /// The run settings carried by the file (prefilter, dwell value, passes, offset); the sequence runs
    /// with settle 0 and dwells delimited by the table signal, as recorded.
    pub settings: SequenceSettings,
    /// Number of frames that follow.
    pub frames: u32,
}

/// Settings of a replayed sequence: no settling (the recording's dwells are already the static parts),
/// dwells as long as the table says, at least [`MIN_DWELL_SAMPLES`] samples.
pub fn replay_sequence_settings(
    prefilter: Prefilter,
    dwell_value: DwellValue,
    max_passes: u32,
    estimate_reference_offset: bool,
) -> SequenceSettings {
    let mut calibration = CalibrationSettings { dwell_value, max_passes, ..CalibrationSettings::default() };
    calibration.solver.estimate_reference_offset = estimate_reference_offset;
    SequenceSettings {
        settle_samples: 0,
        dwell_samples: u32::MAX,
        min_dwell_samples: MIN_DWELL_SAMPLES,
        prefilter,
        calibration,
        ..SequenceSettings::default()
    }
}

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Reads the header.
pub fn read_header<R: ByteSource>(source: &mut R) -> Result<ReplayHeader, ReplayError> {
    let mut head = [0u8; 20];
    source.read_exact(&mut head)?;
    if head[..4] != MAGIC || u16_at(&head, 4) != VERSION {
        return Err(ReplayError::Format);
    }
    let model = match head[6] {
        0 => Model::Adis16470,
        1 => Model::Adis16505_2,
        _ => return Err(ReplayError::Format),
    };
    let site = Site { latitude_rad: f32_at(&head, 8), gravity_mps2: f32_at(&head, 12) };
    let count = u16_at(&head, 16) as usize;
    if count == 0 || count > MAX_POSITIONS {
        return Err(ReplayError::Format);
    }
    let mut run = [0u8; 12];
    source.read_exact(&mut run)?;
    let prefilter = match run[0] {
        0 => Prefilter::None,
        1 => Prefilter::HmmKf {
            gyro: PrefilterSettings::paper_gyro().with_a(f32_at(&run, 4)),
            accel: PrefilterSettings::paper_accel().with_a(f32_at(&run, 8)),
        },
        _ => return Err(ReplayError::Format),
    };
    let dwell_value = match run[1] {
        0 => DwellValue::Mean,
        1 => DwellValue::Settled,
        _ => return Err(ReplayError::Format),
    };
    let settings = replay_sequence_settings(prefilter, dwell_value, run[2] as u32, run[3] != 0);
    let mut schedule = Vec::new();
    let mut labels = Vec::new();
    for _ in 0..count {
        let mut p = [0u8; 16];
        source.read_exact(&mut p)?;
        let attitude = Attitude { pitch_rad: f32_at(&p, 0), roll_rad: f32_at(&p, 4), heading_rad: f32_at(&p, 8) };
        schedule.push(attitude).map_err(|_| ReplayError::Format)?;
        labels.push(u16_at(&p, 12)).map_err(|_| ReplayError::Format)?;
    }
    let mut n = [0u8; 4];
    source.read_exact(&mut n)?;
    Ok(ReplayHeader { model, site, schedule, labels, settings, frames: u32::from_le_bytes(n) })
}

/// What a replay produced.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayOutcome {
    /// The header.
    pub header: ReplayHeader,
    /// Completed positions (attitude and dwell statistics).
    pub positions: Vec<PositionInput, MAX_POSITIONS>,
    /// The solution, if the sequence got there.
    pub result: Option<CalibrationResult>,
    /// The failure, if it failed.
    pub failure: Option<SequenceFailure>,
    /// Sampling counters.
    pub sampling: SamplingStats,
    /// Dwells aborted (and collected again).
    pub aborted_dwells: u32,
}

/// Replays a file: frames through the replay device, the ADIS driver, the sampling queue and the
/// calibration sequence. `on_event` sees every event of the sequence (the firmware logs them).
pub fn run_replay<R: ByteSource>(
    mut source: R,
    mut on_event: impl FnMut(&Event),
) -> Result<ReplayOutcome, ReplayError> {
    let header = read_header(&mut source)?;
    let settings = header.settings;
    let model = header.model;
    let mut imu = Adis::new(ReplayDevice::new(model), model);
    imu.init().map_err(|_: AdisError<ReplayError>| ReplayError::Init)?;
    let mut sequence =
        CalibrationSequence::new(&header.schedule, header.site, settings).map_err(ReplayError::Sequence)?;
    let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
    let mut stats = SamplingStats::default();
    let mut failure = None;
    let mut aborted_dwells = 0;
    let mut record = [0u8; 1 + BURST32_LEN];
    let record_len = 1 + model.burst_len();
    let mut handle = |event: Event| {
        match event {
            Event::Failed(f) => failure = Some(f),
            Event::DwellAborted { .. } => aborted_dwells += 1,
            _ => {}
        }
        on_event(&event);
    };
    for _ in 0..header.frames {
        source.read_exact(&mut record[..record_len])?;
        let table = record[0];
        imu.spi_mut().load_frame(&record[1..record_len]);
        // What the data-ready interrupt does.
        on_data_ready(&mut imu, &mut producer, &mut stats);
        // What the processing loop does.
        while let Some(event) = process_next(&mut consumer, |item| {
            let in_position = table as usize == sequence.position() + 1;
            sequence.on_sample(in_position, item)
        }) {
            if let Some(event) = event {
                handle(event);
            }
        }
    }
    while let Some(event) = sequence.finish() {
        handle(event);
    }
    let result = sequence.result().copied();
    let mut positions = Vec::new();
    for p in sequence.completed() {
        let _ = positions.push(*p);
    }
    Ok(ReplayOutcome { header, positions, result, failure, sampling: stats, aborted_dwells })
}

/// Magic of an encoded outcome.
pub const OUTCOME_MAGIC: [u8; 4] = *b"SSRO";
/// Largest encoded outcome, bytes.
pub const MAX_OUTCOME_BYTES: usize = 4096;

struct Writer<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) -> Result<(), ReplayError> {
        let end = self.at + b.len();
        self.out.get_mut(self.at..end).ok_or(ReplayError::Format)?.copy_from_slice(b);
        self.at = end;
        Ok(())
    }
    fn u32(&mut self, v: u32) -> Result<(), ReplayError> {
        self.bytes(&v.to_le_bytes())
    }
    fn f32(&mut self, v: f32) -> Result<(), ReplayError> {
        self.bytes(&v.to_bits().to_le_bytes())
    }
    fn f32s(&mut self, v: &[f32]) -> Result<(), ReplayError> {
        v.iter().try_for_each(|x| self.f32(*x))
    }
    fn estimate(&mut self, e: Option<crate::solve::Estimate>) -> Result<(), ReplayError> {
        match e {
            Some(e) => {
                self.u32(1)?;
                self.f32(e.value)?;
                self.f32(e.std_error)
            }
            None => self.f32s(&[0.0, 0.0, 0.0]),
        }
    }
}

struct Reader<'a> {
    input: &'a [u8],
}

impl Reader<'_> {
    fn u32(&mut self) -> Result<u32, ReplayError> {
        let mut b = [0u8; 4];
        self.input.read_exact(&mut b)?;
        Ok(u32::from_le_bytes(b))
    }
    fn f32(&mut self) -> Result<f32, ReplayError> {
        Ok(f32::from_bits(self.u32()?))
    }
    fn vec3(&mut self) -> Result<[f32; 3], ReplayError> {
        Ok([self.f32()?, self.f32()?, self.f32()?])
    }
    fn estimate(&mut self) -> Result<Option<crate::solve::Estimate>, ReplayError> {
        let present = self.u32()? != 0;
        let (value, std_error) = (self.f32()?, self.f32()?);
        Ok(present.then_some(crate::solve::Estimate { value, std_error }))
    }
}

fn failure_code(f: &Option<SequenceFailure>) -> [u32; 3] {
    match f {
        None => [0, 0, 0],
        Some(SequenceFailure::PositionAborted { index, reason }) => [1, *index as u32, reason.code() as u32],
        Some(SequenceFailure::Calibration(_)) => [2, 0, 0],
    }
}

/// Encodes an outcome (every f32 as its bit pattern) into `out`; returns the length.
pub fn encode_outcome(o: &ReplayOutcome, out: &mut [u8]) -> Result<usize, ReplayError> {
    let mut w = Writer { out, at: 0 };
    w.bytes(&OUTCOME_MAGIC)?;
    let s = &o.sampling;
    for v in [s.events, s.readings, s.queue_full, s.bus_errors, s.checksum_errors, s.stalled_counters] {
        w.u32(v)?;
    }
    w.u32(s.status_flags)?;
    w.u32(s.missed_samples)?;
    w.u32(o.aborted_dwells)?;
    for v in failure_code(&o.failure) {
        w.u32(v)?;
    }
    w.u32(o.positions.len() as u32)?;
    for p in &o.positions {
        let d = &p.summary;
        w.u32(d.samples)?;
        w.u32(d.rejected)?;
        for v in [
            d.rate_mean_b_radps,
            d.force_mean_b_mps2,
            d.rate_sample_std_b_radps,
            d.force_sample_std_b_mps2,
            d.rate_settled_b_radps,
            d.force_settled_b_mps2,
        ] {
            w.f32s(&v)?;
        }
        w.f32s(&d.settled_noise_gain)?;
    }
    match &o.result {
        None => w.u32(0)?,
        Some(r) => {
            w.u32(1)?;
            w.u32(r.passes)?;
            w.u32(r.converged as u32)?;
            w.f32(r.last_correction_sigma)?;
            let b = &r.solution;
            for e in b.gyro_bias_b_radps.iter().chain(&b.accel_bias_b_mps2).chain(&b.reference_offset_n_rad) {
                w.estimate(*e)?;
            }
            w.u32(b.reference_offset_estimated as u32)?;
            w.u32(b.positions as u32)?;
            for r in &b.residual_n_rad {
                w.f32s(r)?;
            }
            w.f32(b.chi_square)?;
            w.u32(b.degrees_of_freedom)?;
            for row in &b.covariance_si {
                w.f32s(row)?;
            }
        }
    }
    Ok(w.at)
}

/// Decodes an outcome written by [`encode_outcome`], with the header of the replay file it came from.
pub fn decode_outcome(header: &ReplayHeader, bytes: &[u8]) -> Result<ReplayOutcome, ReplayError> {
    use crate::dwell::DwellSummary;
    use crate::sequence::AbortReason as R;
    use crate::solve::{BiasSolution, MAX_PARAMETERS};
    let mut r = Reader { input: bytes };
    let mut magic = [0u8; 4];
    r.input.read_exact(&mut magic)?;
    if magic != OUTCOME_MAGIC {
        return Err(ReplayError::Format);
    }
    let sampling = SamplingStats {
        events: r.u32()?,
        readings: r.u32()?,
        queue_full: r.u32()?,
        bus_errors: r.u32()?,
        checksum_errors: r.u32()?,
        stalled_counters: r.u32()?,
        status_flags: r.u32()?,
        missed_samples: r.u32()?,
    };
    let aborted_dwells = r.u32()?;
    let [kind, index, reason] = [r.u32()?, r.u32()?, r.u32()?];
    let failure = match kind {
        0 => None,
        1 => Some(SequenceFailure::PositionAborted {
            index: index as usize,
            reason: R::from_code(reason as u8).ok_or(ReplayError::Format)?,
        }),
        _ => Some(SequenceFailure::Calibration(crate::calibration::CalibrationError::Solve(
            crate::solve::SolveError::BadInput,
        ))),
    };
    let count = r.u32()? as usize;
    if count > header.schedule.len() {
        return Err(ReplayError::Format);
    }
    let mut positions = Vec::new();
    for k in 0..count {
        let summary = DwellSummary {
            samples: r.u32()?,
            rejected: r.u32()?,
            rate_mean_b_radps: r.vec3()?,
            force_mean_b_mps2: r.vec3()?,
            rate_sample_std_b_radps: r.vec3()?,
            force_sample_std_b_mps2: r.vec3()?,
            rate_settled_b_radps: r.vec3()?,
            force_settled_b_mps2: r.vec3()?,
            settled_noise_gain: [r.f32()?, r.f32()?],
        };
        let _ = positions.push(PositionInput { c_b_n: header.schedule[k].c_b_n(), summary });
    }
    let result = if r.u32()? == 0 {
        None
    } else {
        let passes = r.u32()?;
        let converged = r.u32()? != 0;
        let last_correction_sigma = r.f32()?;
        let mut est = [None; MAX_PARAMETERS];
        for e in est.iter_mut() {
            *e = r.estimate()?;
        }
        let reference_offset_estimated = r.u32()? != 0;
        let npos = r.u32()? as usize;
        let mut residual_n_rad = [[0.0f32; 3]; MAX_POSITIONS];
        for res in residual_n_rad.iter_mut() {
            *res = r.vec3()?;
        }
        let chi_square = r.f32()?;
        let degrees_of_freedom = r.u32()?;
        let mut covariance_si = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
        for row in covariance_si.iter_mut() {
            for c in row.iter_mut() {
                *c = r.f32()?;
            }
        }
        Some(CalibrationResult {
            solution: BiasSolution {
                gyro_bias_b_radps: [est[0], est[1], est[2]],
                accel_bias_b_mps2: [est[3], est[4], est[5]],
                reference_offset_n_rad: [est[6], est[7], est[8]],
                reference_offset_estimated,
                positions: npos,
                residual_n_rad,
                chi_square,
                degrees_of_freedom,
                covariance_si,
            },
            passes,
            converged,
            last_correction_sigma,
        })
    };
    Ok(ReplayOutcome { header: header.clone(), positions, result, failure, sampling, aborted_dwells })
}
