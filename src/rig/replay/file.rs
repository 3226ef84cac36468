//! The replay file (header and frames, written by the host from a recording) and the outcome file (what
//! the firmware path produced, written back), both little-endian; the layout is in the parent module.

use embedded_hal::spi;
use heapless::Vec;

use super::run::ReplayOutcome;
use crate::calib::align::DwellValue;
use crate::calib::calibration::{CalibrationResult, CalibrationSettings, PositionInput};
use crate::calib::dwell::{Prefilter, MIN_DWELL_SAMPLES};
use crate::calib::prefilter::PrefilterSettings;
use crate::calib::solve::MAX_POSITIONS;
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
use crate::run::sampling::SamplingStats;
use crate::run::sequence::{SequenceError, SequenceFailure, SequenceSettings};
use crate::sensor::adis::Model;

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

/// Magic of an encoded outcome.
pub const OUTCOME_MAGIC: [u8; 4] = *b"SSRO";
/// Largest encoded outcome, bytes (24 positions of 424 bytes, the result and the counters: 10,984).
pub const MAX_OUTCOME_BYTES: usize = 11_264;

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
    fn estimate(&mut self, e: Option<crate::calib::solve::Estimate>) -> Result<(), ReplayError> {
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
    fn estimate(&mut self) -> Result<Option<crate::calib::solve::Estimate>, ReplayError> {
        let present = self.u32()? != 0;
        let (value, std_error) = (self.f32()?, self.f32()?);
        Ok(present.then_some(crate::calib::solve::Estimate { value, std_error }))
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
    use crate::calib::dwell::{DwellAllan, DwellSummary, MeanNoise};
    use crate::calib::solve::{BiasSolution, MAX_PARAMETERS};
    use crate::run::sequence::AbortReason as R;
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
        _ => Some(SequenceFailure::Calibration(crate::calib::calibration::CalibrationError::Solve(
            crate::calib::solve::SolveError::BadInput,
        ))),
    };
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
