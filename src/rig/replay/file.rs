//! The replay file (header and frames, written by the host from a recording) and the outcome file (what
//! the firmware path produced, written back), both little-endian; the layout is in the parent module.

use embedded_hal::spi;
use heapless::Vec;

use super::run::ReplayOutcome;
use crate::calib::align::{AlignError, DwellValue};
use crate::calib::angles::{
    CalibrationError, CalibrationResult, CalibrationSettings, PositionInput, SolveError, MAX_POSITIONS,
};
use crate::calib::dwell::{Prefilter, MIN_DWELL_SAMPLES};
use crate::calib::general::{AttitudeKnowledge, ChannelError, ChannelSettings, ChannelSolution, Model as Terms};
use crate::calib::prefilter::PrefilterSettings;
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
use crate::run::sampling::SamplingStats;
use crate::run::sequence::{Estimator, SequenceError, SequenceFailure, SequenceSettings, SequenceSolution};
use crate::sensor::adis::Model;

/// File magic.
pub const MAGIC: [u8; 4] = *b"SSRP";
/// File version.
pub const VERSION: u16 = 3;

/// Bytes of a configuration's fixed part (sensor, estimator, site, positions, terms: 14; run settings: 12; rest
/// limits: 12); each position adds 16.
pub const CONFIGURATION_FIXED_BYTES: usize = 14 + 12 + 12;

/// Bytes of a replay file's header with `positions` positions: magic and version, the configuration, the frame
/// count.
pub const fn replay_header_bytes(positions: usize) -> usize {
    6 + CONFIGURATION_FIXED_BYTES + 16 * positions + 4
}

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
            ReplayError::Format => f.write_str("not a sinscal replay file (version 3)"),
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

/// What a replay file asks of the solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplaySolve {
    /// The estimator.
    pub estimator: Estimator,
    /// Which dwell value the solution uses.
    pub dwell_value: DwellValue,
    /// Passes of the angle method at most.
    pub max_passes: u32,
    /// Whether the angle method estimates the reference offset.
    pub estimate_reference_offset: bool,
    /// Bit k: the heading of position k is unknown (64 bits: one per position of [`MAX_POSITIONS`]).
    pub unknown_headings: u64,
}

const _: () = assert!(MAX_POSITIONS <= 64, "unknown_headings holds one bit per position");

/// Settings of a replayed sequence: no settling (the recording's dwells are already the static parts),
/// dwells as long as the table says, at least [`MIN_DWELL_SAMPLES`] samples.
pub fn replay_sequence_settings(prefilter: Prefilter, solve: ReplaySolve) -> SequenceSettings {
    let (dwell_value, max_passes) = (solve.dwell_value, solve.max_passes);
    let mut calibration = CalibrationSettings { dwell_value, max_passes, ..CalibrationSettings::default() };
    calibration.solver.estimate_reference_offset = solve.estimate_reference_offset;
    SequenceSettings {
        settle_samples: 0,
        dwell_samples: u32::MAX,
        min_dwell_samples: MIN_DWELL_SAMPLES,
        prefilter,
        estimator: solve.estimator,
        calibration,
        unknown_headings: solve.unknown_headings,
        ..SequenceSettings::default()
    }
}

/// The bits of a set of terms in the replay file: [`Terms::stored_bits`], bit `TermInfo::stored_bit` of each term.
pub fn terms_bits(model: Terms) -> u16 {
    model.stored_bits()
}

/// The set of terms of [`terms_bits`] (bits no term has are ignored).
pub fn terms_of_bits(bits: u16) -> Terms {
    Terms::from_stored_bits_truncate(bits)
}

/// The estimator code of the replay file.
pub fn estimator_code(estimator: &Estimator) -> u8 {
    match estimator {
        Estimator::Angles => 0,
        Estimator::Channels(s) if s.use_gyro => 1,
        Estimator::Channels(_) => 2,
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

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Reads the header.
pub fn read_header<R: ByteSource>(source: &mut R) -> Result<ReplayHeader, ReplayError> {
    let mut magic = [0u8; 6];
    source.read_exact(&mut magic)?;
    if magic[..4] != MAGIC || u16_at(&magic, 4) != VERSION {
        return Err(ReplayError::Format);
    }
    let mut header = read_configuration(source)?;
    let mut n = [0u8; 4];
    source.read_exact(&mut n)?;
    header.frames = u32::from_le_bytes(n);
    Ok(header)
}

/// Reads the configuration part of a header: everything between the version and the frame count (sensor
/// model, estimator, site, schedule, run settings). The device's configure message carries the same bytes.
/// The header returned counts no frames.
pub fn read_configuration<R: ByteSource>(source: &mut R) -> Result<ReplayHeader, ReplayError> {
    let mut head = [0u8; 14];
    source.read_exact(&mut head)?;
    let model = match head[0] {
        0 => Model::Adis16470,
        1 => Model::Adis16505_2,
        _ => return Err(ReplayError::Format),
    };
    let site = Site { latitude_rad: f32_at(&head, 2), gravity_mps2: f32_at(&head, 6) };
    let count = u16_at(&head, 10) as usize;
    if count == 0 || count > MAX_POSITIONS {
        return Err(ReplayError::Format);
    }
    let channels = |use_gyro| {
        Estimator::Channels(ChannelSettings { model: terms_of_bits(u16_at(&head, 12)), use_gyro, ..Default::default() })
    };
    let estimator = match head[1] {
        0 => Estimator::Angles,
        1 => channels(true),
        2 => channels(false),
        _ => return Err(ReplayError::Format),
    };
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
    // The limits of rest of the sequence's checks.
    let mut rest = [0u8; 12];
    source.read_exact(&mut rest)?;
    let (rest_force_error_max_mps2, rest_gravity_angle_max_rad, rest_rate_max_radps) =
        (f32_at(&rest, 0), f32_at(&rest, 4), f32_at(&rest, 8));
    let positive = |x: f32| x.is_finite() && x > 0.0;
    if !(positive(rest_force_error_max_mps2) && positive(rest_gravity_angle_max_rad) && positive(rest_rate_max_radps)) {
        return Err(ReplayError::Format);
    }
    let mut schedule = Vec::new();
    let mut labels = Vec::new();
    let mut unknown_headings = 0u64;
    for k in 0..count {
        let mut p = [0u8; 16];
        source.read_exact(&mut p)?;
        let attitude = Attitude { pitch_rad: f32_at(&p, 0), roll_rad: f32_at(&p, 4), heading_rad: f32_at(&p, 8) };
        schedule.push(attitude).map_err(|_| ReplayError::Format)?;
        labels.push(u16_at(&p, 12)).map_err(|_| ReplayError::Format)?;
        if u16_at(&p, 14) & 1 != 0 {
            // k < MAX_POSITIONS <= 64: `schedule.push` above refuses more.
            unknown_headings |= 1u64 << k;
        }
    }
    let solve = ReplaySolve {
        estimator,
        dwell_value,
        max_passes: run[2] as u32,
        estimate_reference_offset: run[3] != 0,
        unknown_headings,
    };
    let mut settings = replay_sequence_settings(prefilter, solve);
    settings.rest_force_error_max_mps2 = rest_force_error_max_mps2;
    settings.rest_gravity_angle_max_rad = rest_gravity_angle_max_rad;
    settings.rest_rate_max_radps = rest_rate_max_radps;
    Ok(ReplayHeader { model, site, schedule, labels, settings, frames: 0 })
}

/// Magic of an encoded outcome.
pub const OUTCOME_MAGIC: [u8; 4] = *b"SSRO";
/// Largest encoded outcome, bytes: the counters and failure (76), [`MAX_POSITIONS`] positions of 424 bytes,
/// and the general estimator's solution (5,416 and 48 per dwell; the angle method's, 520 and 12 per position,
/// is smaller). For 64 positions: 35,696.
pub const MAX_OUTCOME_BYTES: usize = 76 + MAX_POSITIONS * 424 + 5_416 + crate::calib::general::MAX_DWELLS * 48;

/// Writes the encoding into `out`: the whole of it (an error if it does not fit), or only the window of
/// `out.len()` bytes from `window_start` (the rest is computed and dropped: a part for a link reply or a flash
/// write without a buffer of the whole).
struct Writer<'a> {
    out: &'a mut [u8],
    at: usize,
    window_start: Option<usize>,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) -> Result<(), ReplayError> {
        let end = self.at + b.len();
        match self.window_start {
            None => self.out.get_mut(self.at..end).ok_or(ReplayError::Format)?.copy_from_slice(b),
            Some(start) => {
                let (from, to) = (self.at.max(start), end.min(start + self.out.len()));
                if from < to {
                    self.out[from - start..to - start].copy_from_slice(&b[from - self.at..to - self.at]);
                }
            }
        }
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
    fn estimate(&mut self, e: Option<crate::calib::angles::Estimate>) -> Result<(), ReplayError> {
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
    fn estimate(&mut self) -> Result<Option<crate::calib::angles::Estimate>, ReplayError> {
        let present = self.u32()? != 0;
        let (value, std_error) = (self.f32()?, self.f32()?);
        Ok(present.then_some(crate::calib::angles::Estimate { value, std_error }))
    }
}

/// A failure as five words: kind (0 none, 1 a position aborted, 2 the angle method, 3 the general
/// estimator), position, reason code, and two values (f32 bits).
fn failure_code(f: &Option<SequenceFailure>) -> [u32; 5] {
    let bits = |x: f32, y: f32| [x.to_bits(), y.to_bits()];
    let (kind, index, code, [x, y]) = match *f {
        None => (0, 0, 0, [0, 0]),
        Some(SequenceFailure::PositionAborted { index, reason }) => (1, index, reason.code() as u32, [0, 0]),
        Some(SequenceFailure::Calibration(e)) => match e {
            CalibrationError::Align { index, error: AlignError::Degenerate } => (2, index, 1, [0, 0]),
            CalibrationError::Align { index, error: AlignError::NotFinite } => (2, index, 2, [0, 0]),
            CalibrationError::Solve(SolveError::TooManyPositions) => (2, 0, 3, [0, 0]),
            CalibrationError::Solve(SolveError::NoPositions) => (2, 0, 4, [0, 0]),
            CalibrationError::Solve(SolveError::BadInput) => (2, 0, 5, [0, 0]),
            CalibrationError::Implausible { index, level_rad, heading_rad } => {
                (2, index, 6, bits(level_rad, heading_rad))
            }
            CalibrationError::ForceMagnitude { index, ratio } => (2, index, 7, bits(ratio, 0.0)),
        },
        Some(SequenceFailure::Channels(e)) => match e {
            ChannelError::NoDwells => (3, 0, 1, [0, 0]),
            ChannelError::TooManyDwells => (3, 0, 2, [0, 0]),
            ChannelError::BadInput { dwell } => (3, dwell, 3, [0, 0]),
            ChannelError::ForceMagnitude { dwell, ratio } => (3, dwell, 4, bits(ratio, 0.0)),
            ChannelError::GravityDirection { dwell, angle_rad } => (3, dwell, 5, bits(angle_rad, 0.0)),
            ChannelError::HeadingMismatch { dwell, given_rad, fits_rad } => (3, dwell, 6, bits(given_rad, fits_rad)),
            ChannelError::NothingToEstimate => (3, 0, 7, [0, 0]),
            ChannelError::Diverged { parameter, value } => (3, parameter, 8, bits(value, 0.0)),
            ChannelError::TooManyMoves => (3, 0, 9, [0, 0]),
            ChannelError::BadMove { index } => (3, index, 10, [0, 0]),
        },
    };
    [kind, index as u32, code, x, y]
}

/// The failure of [`failure_code`]'s words.
fn failure_of_code(words: [u32; 5]) -> Result<Option<SequenceFailure>, ReplayError> {
    let [kind, index, code, x, y] = words;
    let (index, x, y) = (index as usize, f32::from_bits(x), f32::from_bits(y));
    let calibration = |e| Some(SequenceFailure::Calibration(e));
    let channels = |e| Some(SequenceFailure::Channels(e));
    Ok(match (kind, code) {
        (0, _) => None,
        (1, _) => Some(SequenceFailure::PositionAborted {
            index,
            reason: crate::run::sequence::AbortReason::from_code(code as u8).ok_or(ReplayError::Format)?,
        }),
        (2, 1) => calibration(CalibrationError::Align { index, error: AlignError::Degenerate }),
        (2, 2) => calibration(CalibrationError::Align { index, error: AlignError::NotFinite }),
        (2, 3) => calibration(CalibrationError::Solve(SolveError::TooManyPositions)),
        (2, 4) => calibration(CalibrationError::Solve(SolveError::NoPositions)),
        (2, 5) => calibration(CalibrationError::Solve(SolveError::BadInput)),
        (2, 6) => calibration(CalibrationError::Implausible { index, level_rad: x, heading_rad: y }),
        (2, 7) => calibration(CalibrationError::ForceMagnitude { index, ratio: x }),
        (3, 1) => channels(ChannelError::NoDwells),
        (3, 2) => channels(ChannelError::TooManyDwells),
        (3, 3) => channels(ChannelError::BadInput { dwell: index }),
        (3, 4) => channels(ChannelError::ForceMagnitude { dwell: index, ratio: x }),
        (3, 5) => channels(ChannelError::GravityDirection { dwell: index, angle_rad: x }),
        (3, 6) => channels(ChannelError::HeadingMismatch { dwell: index, given_rad: x, fits_rad: y }),
        (3, 7) => channels(ChannelError::NothingToEstimate),
        (3, 8) => channels(ChannelError::Diverged { parameter: index, value: x }),
        (3, 9) => channels(ChannelError::TooManyMoves),
        (3, 10) => channels(ChannelError::BadMove { index }),
        _ => return Err(ReplayError::Format),
    })
}

fn encode_angles(w: &mut Writer<'_>, r: &CalibrationResult) -> Result<(), ReplayError> {
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
    Ok(())
}

/// The general estimator's solution; the per-dwell arrays for its dwells only.
fn encode_channels(w: &mut Writer<'_>, c: &ChannelSolution) -> Result<(), ReplayError> {
    w.u32(terms_bits(c.model) as u32)?;
    w.f32s(&c.parameters_si)?;
    for bits in [c.observable, c.unobservable] {
        w.u32(bits as u32)?;
        w.u32((bits >> 32) as u32)?;
    }
    for row in &c.covariance_si {
        w.f32s(row)?;
    }
    let n = c.dwells.min(c.heading_rad.len());
    w.u32(n as u32)?;
    w.f32s(&c.heading_rad[..n])?;
    w.f32s(&c.heading_std_rad[..n])?;
    for k in 0..n {
        w.f32s(&c.residual_rate_b_radps[k])?;
        w.f32s(&c.residual_force_b_mps2[k])?;
    }
    w.f32s(&c.dwell_statistic[..n])?;
    w.u32(c.suspect as u32)?;
    w.u32((c.suspect >> 32) as u32)?;
    w.f32(c.chi_square)?;
    w.u32(c.degrees_of_freedom)?;
    w.u32(c.iterations)?;
    w.u32(c.converged as u32)?;
    w.u32(match c.attitude {
        AttitudeKnowledge::Reference => 0,
        AttitudeKnowledge::Unknown => 1,
    })?;
    w.u32(c.earth_rate_resolved as u32)?;
    for up in &c.up_b[..n] {
        w.f32s(up)?;
    }
    w.u32(c.blind_spots)?;
    w.u32(c.gauge as u32)?;
    w.u32((c.gauge >> 32) as u32)
}

/// What the outcome encoding holds, borrowed: from a [`ReplayOutcome`], or from a running device's sequence.
#[derive(Clone, Copy, Debug)]
pub struct OutcomeView<'a> {
    /// Sampling counters.
    pub sampling: SamplingStats,
    /// Dwells aborted (and collected again).
    pub aborted_dwells: u32,
    /// The failure, if the sequence failed.
    pub failure: Option<SequenceFailure>,
    /// Completed positions.
    pub positions: &'a [PositionInput],
    /// The solution, if the sequence got there.
    pub result: Option<&'a SequenceSolution>,
}

impl ReplayOutcome {
    /// The outcome as an [`OutcomeView`].
    pub fn view(&self) -> OutcomeView<'_> {
        OutcomeView {
            sampling: self.sampling,
            aborted_dwells: self.aborted_dwells,
            failure: self.failure,
            positions: &self.positions,
            result: self.result.as_ref(),
        }
    }
}

/// Encodes an outcome (every f32 as its bit pattern) into `out`; returns the length.
pub fn encode_outcome(o: &ReplayOutcome, out: &mut [u8]) -> Result<usize, ReplayError> {
    encode_view(&o.view(), Writer { out, at: 0, window_start: None })
}

/// The part of an outcome's encoding from byte `offset`, as much as fits `out`; returns the encoding's whole
/// length (the part written is `out.len()` bytes or up to that end). The encoding is computed each time and
/// nothing but `out` holds it.
pub fn encode_outcome_part(o: &OutcomeView<'_>, offset: usize, out: &mut [u8]) -> usize {
    // A windowed writer never fails.
    encode_view(o, Writer { out, at: 0, window_start: Some(offset) }).unwrap_or(0)
}

fn encode_view(o: &OutcomeView<'_>, mut w: Writer<'_>) -> Result<usize, ReplayError> {
    w.bytes(&OUTCOME_MAGIC)?;
    let s = &o.sampling;
    for v in [s.events, s.readings, s.queue_full, s.bus_errors, s.checksum_errors, s.stalled_counters] {
        w.u32(v)?;
    }
    w.u32(s.status_flags)?;
    w.u32(s.dead_bus_frames)?;
    w.u32(s.missed_samples)?;
    w.u32(s.queue_high_water)?;
    w.u32(o.aborted_dwells)?;
    for v in failure_code(&o.failure) {
        w.u32(v)?;
    }
    w.u32(o.positions.len() as u32)?;
    for p in o.positions {
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
        for m in &d.mean_noise {
            w.f32(m.white_equivalent_var)?;
            w.f32(m.dof)?;
            w.u32(m.cluster_samples)?;
        }
        for a in &d.allan {
            w.f32s(&a.avar)?;
            w.f32(a.prefilter_start_var)?;
        }
    }
    match o.result {
        None => w.u32(0)?,
        Some(SequenceSolution::Angles(r)) => {
            w.u32(1)?;
            encode_angles(&mut w, r)?;
        }
        Some(SequenceSolution::Channels(c)) => {
            w.u32(2)?;
            encode_channels(&mut w, c)?;
        }
    }
    Ok(w.at)
}

/// Decodes an outcome written by [`encode_outcome`], with the header of the replay file it came from.
pub fn decode_outcome(header: &ReplayHeader, bytes: &[u8]) -> Result<ReplayOutcome, ReplayError> {
    use crate::calib::dwell::{DwellAllan, DwellSummary, MeanNoise};
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
        dead_bus_frames: r.u32()?,
        missed_samples: r.u32()?,
        queue_high_water: r.u32()?,
    };
    let aborted_dwells = r.u32()?;
    let failure = failure_of_code([r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?])?;
    let count = r.u32()? as usize;
    if count > header.schedule.len() {
        return Err(ReplayError::Format);
    }
    let mut positions = Vec::new();
    for k in 0..count {
        let mut summary = DwellSummary {
            samples: r.u32()?,
            rejected: r.u32()?,
            rate_mean_b_radps: r.vec3()?,
            force_mean_b_mps2: r.vec3()?,
            rate_sample_std_b_radps: r.vec3()?,
            force_sample_std_b_mps2: r.vec3()?,
            rate_settled_b_radps: r.vec3()?,
            force_settled_b_mps2: r.vec3()?,
            settled_noise_gain: [r.f32()?, r.f32()?],
            mean_noise: [MeanNoise::default(); 6],
            allan: [DwellAllan::default(); 6],
        };
        for m in summary.mean_noise.iter_mut() {
            *m = MeanNoise { white_equivalent_var: r.f32()?, dof: r.f32()?, cluster_samples: r.u32()? };
        }
        for a in summary.allan.iter_mut() {
            for v in a.avar.iter_mut() {
                *v = r.f32()?;
            }
            a.prefilter_start_var = r.f32()?;
        }
        let _ = positions.push(PositionInput { c_b_n: header.schedule[k].c_b_n(), summary });
    }
    let result = match r.u32()? {
        0 => None,
        1 => Some(SequenceSolution::Angles(decode_angles(&mut r)?)),
        2 => Some(SequenceSolution::Channels(decode_channels(&mut r)?)),
        _ => return Err(ReplayError::Format),
    };
    Ok(ReplayOutcome { header: header.clone(), positions, result, failure, sampling, aborted_dwells })
}

fn decode_angles(r: &mut Reader<'_>) -> Result<CalibrationResult, ReplayError> {
    use crate::calib::angles::{BiasSolution, MAX_PARAMETERS};
    let passes = r.u32()?;
    let converged = r.u32()? != 0;
    let last_correction_sigma = r.f32()?;
    let mut est = [None; MAX_PARAMETERS];
    for e in est.iter_mut() {
        *e = r.estimate()?;
    }
    let reference_offset_estimated = r.u32()? != 0;
    let positions = r.u32()? as usize;
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
    Ok(CalibrationResult {
        solution: BiasSolution {
            gyro_bias_b_radps: [est[0], est[1], est[2]],
            accel_bias_b_mps2: [est[3], est[4], est[5]],
            reference_offset_n_rad: [est[6], est[7], est[8]],
            reference_offset_estimated,
            positions,
            residual_n_rad,
            chi_square,
            degrees_of_freedom,
            covariance_si,
        },
        passes,
        converged,
        last_correction_sigma,
    })
}

fn decode_channels(r: &mut Reader<'_>) -> Result<ChannelSolution, ReplayError> {
    use crate::calib::general::{MAX_DWELLS, PARAMETERS};
    let model = terms_of_bits(r.u32()? as u16);
    let mut parameters_si = [0.0f32; PARAMETERS];
    for p in parameters_si.iter_mut() {
        *p = r.f32()?;
    }
    let mut u64_word = || -> Result<u64, ReplayError> { Ok(r.u32()? as u64 | (r.u32()? as u64) << 32) };
    let (observable, unobservable) = (u64_word()?, u64_word()?);
    let mut covariance_si = [[0.0f32; PARAMETERS]; PARAMETERS];
    for row in covariance_si.iter_mut() {
        for c in row.iter_mut() {
            *c = r.f32()?;
        }
    }
    let dwells = r.u32()? as usize;
    if dwells > MAX_DWELLS {
        return Err(ReplayError::Format);
    }
    let mut c = ChannelSolution::empty(model, dwells);
    c.parameters_si = parameters_si;
    c.observable = observable;
    c.unobservable = unobservable;
    c.covariance_si = covariance_si;
    for k in 0..dwells {
        c.heading_rad[k] = r.f32()?;
    }
    for k in 0..dwells {
        c.heading_std_rad[k] = r.f32()?;
    }
    for k in 0..dwells {
        c.residual_rate_b_radps[k] = r.vec3()?;
        c.residual_force_b_mps2[k] = r.vec3()?;
    }
    for k in 0..dwells {
        c.dwell_statistic[k] = r.f32()?;
    }
    c.suspect = r.u32()? as u64 | (r.u32()? as u64) << 32;
    c.chi_square = r.f32()?;
    c.degrees_of_freedom = r.u32()?;
    c.iterations = r.u32()?;
    c.converged = r.u32()? != 0;
    c.attitude = match r.u32()? {
        0 => AttitudeKnowledge::Reference,
        1 => AttitudeKnowledge::Unknown,
        _ => return Err(ReplayError::Format),
    };
    c.earth_rate_resolved = r.u32()? != 0;
    for k in 0..dwells {
        c.up_b[k] = r.vec3()?;
    }
    c.blind_spots = r.u32()?;
    c.gauge = r.u32()? as u64 | (r.u32()? as u64) << 32;
    Ok(c)
}
