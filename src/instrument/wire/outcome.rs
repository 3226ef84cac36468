//! The outcome of a calibration: the sampling counters, the dwells aborted, the failure or the solution, and
//! every completed dwell's statistics. A link reply carries it in parts, an outcome file whole, a record after
//! its configuration. Little-endian, every f32 as its bit pattern:
//! ```text
//! magic "SSRO", sampling counters 10 x u32, aborted dwells u32, failure 5 x u32 (kind, index, reason, two
//! f32 values), positions u32, positions x (samples u32, rejected u32, spikes u32, six vec3 f32, settled gain 2 x
//! f32, mean noise 6 x (var f32, dof f32, cluster u32), Allan 6 x avar f32 x n),
//! solution u32 (SolutionCode) and the solution's fields
//! ```

use heapless::Vec;

use super::codes::{AttitudeCode, EstimatorCode, FailureKind, SolutionCode};
use super::configuration::Configuration;
use super::{Reader, WireError, Writer};
use crate::calib::align::AlignError;
use crate::calib::angles::{BiasSolution, Estimate, SolveError, MAX_PARAMETERS, MAX_POSITIONS};
use crate::calib::angles::{CalibrationError, CalibrationResult, PositionInput};
use crate::calib::dwell::{DwellAllan, DwellSummary, MeanNoise};
use crate::calib::general::{AttitudeKnowledge, ChannelError, ChannelSolution, Model as Terms, MAX_DWELLS, PARAMETERS};
use crate::run::sampling::SamplingStats;
use crate::run::sequence::{AbortReason, SequenceFailure, SequenceSolution};

/// Magic of an encoded outcome.
pub const MAGIC: [u8; 4] = *b"SSRO";
/// Largest encoded outcome, bytes: the counters and failure (76), [`MAX_POSITIONS`] positions of 404 bytes,
/// and the general estimator's solution (5,404 and 48 per dwell; the angle method's, 1,228, is smaller). For 64
/// positions: 34,408.
pub const MAX_BYTES: usize =
    HEAD_BYTES + MAX_POSITIONS * POSITION_BYTES + GENERAL_BYTES + MAX_DWELLS * GENERAL_DWELL_BYTES;

/// Bytes of an outcome before its solution: magic, counters, failure, positions count, solution code.
const HEAD_BYTES: usize = 76;
/// Bytes per position of an outcome: its dwell summary.
const POSITION_BYTES: usize = 404;
/// Bytes of the general estimator's solution without its dwells, and per dwell.
const GENERAL_BYTES: usize = 5_404;
const GENERAL_DWELL_BYTES: usize = 48;
/// Bytes of the angle method's solution: passes, convergence and last correction; nine estimates; two words;
/// a residual for every possible position; chi-square and degrees of freedom; its covariance.
const ANGLES_BYTES: usize = 12 + 9 * 12 + 8 + 12 * MAX_POSITIONS + 8 + 4 * MAX_PARAMETERS * MAX_PARAMETERS;

/// The largest encoded outcome of a schedule of `positions` positions solved by `estimator`, bytes: what a
/// device checks against its storage slot before a run starts (a solved run of every position reaches it).
pub const fn max_bytes_for(positions: usize, estimator: EstimatorCode) -> usize {
    let solution = match estimator {
        EstimatorCode::Angles => ANGLES_BYTES,
        EstimatorCode::General | EstimatorCode::GeneralWithoutGyros => GENERAL_BYTES + GENERAL_DWELL_BYTES * positions,
    };
    HEAD_BYTES + POSITION_BYTES * positions + solution
}

/// What a calibration produced, borrowed: from an [`Outcome`], or from a running device's sequence.
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

/// What a calibration produced, with the configuration it ran.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The configuration.
    pub configuration: Configuration,
    /// Completed positions (attitude and dwell statistics).
    pub positions: Vec<PositionInput, MAX_POSITIONS>,
    /// The solution, if the sequence got there.
    pub result: Option<SequenceSolution>,
    /// The failure, if it failed.
    pub failure: Option<SequenceFailure>,
    /// Sampling counters.
    pub sampling: SamplingStats,
    /// Dwells aborted (and collected again).
    pub aborted_dwells: u32,
}

impl Outcome {
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

    /// Encodes the outcome into `out`; returns the length, or an error when it does not fit.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, WireError> {
        let mut w = Writer::new(out);
        encode_view(&self.view(), &mut w);
        w.written().ok_or(WireError)
    }

    /// Decodes an outcome written by [`Outcome::encode`] or [`encode_part`], with the configuration it ran.
    pub fn decode(configuration: &Configuration, bytes: &[u8]) -> Result<Outcome, WireError> {
        decode_fields(configuration, &mut Reader::new(bytes)).ok_or(WireError)?
    }
}

/// The part of an outcome's encoding from byte `offset`, as much as fits `out`; returns the encoding's whole
/// length (the part written is `out.len()` bytes or up to that end). The encoding is computed each time and
/// nothing but `out` holds it.
pub fn encode_part(o: &OutcomeView<'_>, offset: usize, out: &mut [u8]) -> usize {
    let mut w = Writer::window(out, offset);
    encode_view(o, &mut w);
    w.position()
}

fn encode_view(o: &OutcomeView<'_>, w: &mut Writer<'_>) {
    w.bytes(&MAGIC);
    for v in o.sampling.counters() {
        w.u32(v);
    }
    w.u32(o.aborted_dwells);
    for v in failure_words(&o.failure) {
        w.u32(v);
    }
    w.u32(o.positions.len() as u32);
    for p in o.positions {
        encode_dwell(w, &p.summary);
    }
    match o.result {
        None => {
            w.u32(SolutionCode::None.code());
        }
        Some(SequenceSolution::Angles(r)) => {
            w.u32(SolutionCode::Angles.code());
            encode_angles(w, r);
        }
        Some(SequenceSolution::Channels(c)) => {
            w.u32(SolutionCode::General.code());
            encode_general(w, c);
        }
    }
}

fn encode_dwell(w: &mut Writer<'_>, d: &DwellSummary) {
    w.u32(d.samples).u32(d.rejected).u32(d.spikes);
    for v in [
        d.rate_mean_b_radps,
        d.force_mean_b_mps2,
        d.rate_sample_std_b_radps,
        d.force_sample_std_b_mps2,
        d.rate_settled_b_radps,
        d.force_settled_b_mps2,
    ] {
        w.f32s(&v);
    }
    w.f32s(&d.settled_noise_gain);
    for m in &d.mean_noise {
        w.f32(m.white_equivalent_var).f32(m.dof).u32(m.cluster_samples);
    }
    for a in &d.allan {
        w.f32s(&a.avar);
    }
}

fn decode_dwell(r: &mut Reader<'_>) -> Option<DwellSummary> {
    let mut d = DwellSummary {
        samples: r.u32()?,
        rejected: r.u32()?,
        spikes: r.u32()?,
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
    for m in d.mean_noise.iter_mut() {
        *m = MeanNoise { white_equivalent_var: r.f32()?, dof: r.f32()?, cluster_samples: r.u32()? };
    }
    for a in d.allan.iter_mut() {
        r.f32s(&mut a.avar)?;
    }
    // The dwell's samples, those rejected and the spikes are counted in one 32-bit counter: their sum fits it.
    d.samples.checked_add(d.rejected)?.checked_add(d.spikes)?;
    Some(d)
}

fn decode_fields(configuration: &Configuration, r: &mut Reader<'_>) -> Option<Result<Outcome, WireError>> {
    if r.bytes(4)? != MAGIC {
        return Some(Err(WireError));
    }
    let mut counters = [0u32; 10];
    for c in counters.iter_mut() {
        *c = r.u32()?;
    }
    let sampling = SamplingStats::from_counters(counters);
    let aborted_dwells = r.u32()?;
    let Ok(failure) = failure_of_words([r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?]) else {
        return Some(Err(WireError));
    };
    let count = r.u32()? as usize;
    if count > configuration.schedule.len() {
        return Some(Err(WireError));
    }
    let mut positions = Vec::new();
    for attitude in &configuration.schedule[..count] {
        let summary = decode_dwell(r)?;
        // count <= the schedule's length <= MAX_POSITIONS.
        let _ = positions.push(PositionInput { c_b_n: attitude.c_b_n(), summary });
    }
    let result = match SolutionCode::from_code(r.u32()?) {
        Some(SolutionCode::None) => None,
        Some(SolutionCode::Angles) => Some(SequenceSolution::Angles(decode_angles(r)?)),
        Some(SolutionCode::General) => match decode_general(r)? {
            Ok(c) => Some(SequenceSolution::Channels(c)),
            Err(e) => return Some(Err(e)),
        },
        None => return Some(Err(WireError)),
    };
    Some(Ok(Outcome { configuration: configuration.clone(), positions, result, failure, sampling, aborted_dwells }))
}

/// A failure as five words: kind ([`FailureKind`]), position, reason code, and two values (f32 bits). The
/// reason codes are the tables of [`angles_reason`] and [`general_reason`].
fn failure_words(f: &Option<SequenceFailure>) -> [u32; 5] {
    let (kind, index, code, [x, y]) = match *f {
        None => (FailureKind::None, 0, 0, [0.0, 0.0]),
        Some(SequenceFailure::PositionAborted { index, reason }) => {
            (FailureKind::PositionAborted, index, reason.code() as u32, [0.0, 0.0])
        }
        Some(SequenceFailure::Calibration(e)) => {
            let (index, code, values) = angles_reason(&e);
            (FailureKind::Angles, index, code, values)
        }
        Some(SequenceFailure::Channels(e)) => {
            let (index, code, values) = general_reason(&e);
            (FailureKind::General, index, code, values)
        }
    };
    [kind.code(), index as u32, code, x.to_bits(), y.to_bits()]
}

/// The angle method's refusal as (position, reason code, two values).
fn angles_reason(e: &CalibrationError) -> (usize, u32, [f32; 2]) {
    match *e {
        CalibrationError::Align { index, error: AlignError::Degenerate } => (index, 1, [0.0; 2]),
        CalibrationError::Align { index, error: AlignError::NotFinite } => (index, 2, [0.0; 2]),
        CalibrationError::Solve(SolveError::TooManyPositions) => (0, 3, [0.0; 2]),
        CalibrationError::Solve(SolveError::NoPositions) => (0, 4, [0.0; 2]),
        CalibrationError::Solve(SolveError::BadInput) => (0, 5, [0.0; 2]),
        CalibrationError::Implausible { index, level_rad, heading_rad } => (index, 6, [level_rad, heading_rad]),
        CalibrationError::ForceMagnitude { index, ratio } => (index, 7, [ratio, 0.0]),
    }
}

/// The general estimator's refusal as (dwell or parameter, reason code, two values).
fn general_reason(e: &ChannelError) -> (usize, u32, [f32; 2]) {
    match *e {
        ChannelError::NoDwells => (0, 1, [0.0; 2]),
        ChannelError::TooManyDwells => (0, 2, [0.0; 2]),
        ChannelError::BadInput { dwell } => (dwell, 3, [0.0; 2]),
        ChannelError::ForceMagnitude { dwell, ratio } => (dwell, 4, [ratio, 0.0]),
        ChannelError::GravityDirection { dwell, angle_rad } => (dwell, 5, [angle_rad, 0.0]),
        ChannelError::HeadingMismatch { dwell, given_rad, fits_rad } => (dwell, 6, [given_rad, fits_rad]),
        ChannelError::NothingToEstimate => (0, 7, [0.0; 2]),
        ChannelError::Diverged { parameter, value } => (parameter, 8, [value, 0.0]),
        ChannelError::TooManyMoves => (0, 9, [0.0; 2]),
        ChannelError::BadMove { index } => (index, 10, [0.0; 2]),
    }
}

/// The failure of [`failure_words`]' words.
fn failure_of_words(words: [u32; 5]) -> Result<Option<SequenceFailure>, WireError> {
    let [kind, index, code, x, y] = words;
    let (index, x, y) = (index as usize, f32::from_bits(x), f32::from_bits(y));
    let angles = |e| Some(SequenceFailure::Calibration(e));
    let general = |e| Some(SequenceFailure::Channels(e));
    Ok(match (FailureKind::from_code(kind).ok_or(WireError)?, code) {
        (FailureKind::None, _) => None,
        (FailureKind::PositionAborted, _) => Some(SequenceFailure::PositionAborted {
            index,
            reason: AbortReason::from_code(code as u8).ok_or(WireError)?,
        }),
        (FailureKind::Angles, 1) => angles(CalibrationError::Align { index, error: AlignError::Degenerate }),
        (FailureKind::Angles, 2) => angles(CalibrationError::Align { index, error: AlignError::NotFinite }),
        (FailureKind::Angles, 3) => angles(CalibrationError::Solve(SolveError::TooManyPositions)),
        (FailureKind::Angles, 4) => angles(CalibrationError::Solve(SolveError::NoPositions)),
        (FailureKind::Angles, 5) => angles(CalibrationError::Solve(SolveError::BadInput)),
        (FailureKind::Angles, 6) => angles(CalibrationError::Implausible { index, level_rad: x, heading_rad: y }),
        (FailureKind::Angles, 7) => angles(CalibrationError::ForceMagnitude { index, ratio: x }),
        (FailureKind::General, 1) => general(ChannelError::NoDwells),
        (FailureKind::General, 2) => general(ChannelError::TooManyDwells),
        (FailureKind::General, 3) => general(ChannelError::BadInput { dwell: index }),
        (FailureKind::General, 4) => general(ChannelError::ForceMagnitude { dwell: index, ratio: x }),
        (FailureKind::General, 5) => general(ChannelError::GravityDirection { dwell: index, angle_rad: x }),
        (FailureKind::General, 6) => general(ChannelError::HeadingMismatch { dwell: index, given_rad: x, fits_rad: y }),
        (FailureKind::General, 7) => general(ChannelError::NothingToEstimate),
        (FailureKind::General, 8) => general(ChannelError::Diverged { parameter: index, value: x }),
        (FailureKind::General, 9) => general(ChannelError::TooManyMoves),
        (FailureKind::General, 10) => general(ChannelError::BadMove { index }),
        _ => return Err(WireError),
    })
}

fn encode_estimate(w: &mut Writer<'_>, e: Option<Estimate>) {
    match e {
        Some(e) => w.u32(1).f32(e.value).f32(e.std_error),
        None => w.f32s(&[0.0, 0.0, 0.0]),
    };
}

fn decode_estimate(r: &mut Reader<'_>) -> Option<Option<Estimate>> {
    let present = r.u32()? != 0;
    let (value, std_error) = (r.f32()?, r.f32()?);
    Some(present.then_some(Estimate { value, std_error }))
}

fn encode_angles(w: &mut Writer<'_>, r: &CalibrationResult) {
    w.u32(r.passes).u32(r.converged as u32).f32(r.last_correction_sigma);
    let b = &r.solution;
    for e in b.gyro_bias_b_radps.iter().chain(&b.accel_bias_b_mps2).chain(&b.reference_offset_n_rad) {
        encode_estimate(w, *e);
    }
    w.u32(b.reference_offset_estimated as u32).u32(b.positions as u32);
    for r in &b.residual_n_rad {
        w.f32s(r);
    }
    w.f32(b.chi_square).u32(b.degrees_of_freedom);
    for row in &b.covariance_si {
        w.f32s(row);
    }
}

fn decode_angles(r: &mut Reader<'_>) -> Option<CalibrationResult> {
    let (passes, converged, last_correction_sigma) = (r.u32()?, r.u32()? != 0, r.f32()?);
    let mut est = [None; MAX_PARAMETERS];
    for e in est.iter_mut() {
        *e = decode_estimate(r)?;
    }
    let (reference_offset_estimated, positions) = (r.u32()? != 0, r.u32()? as usize);
    let mut residual_n_rad = [[0.0f32; 3]; MAX_POSITIONS];
    for res in residual_n_rad.iter_mut() {
        *res = r.vec3()?;
    }
    let (chi_square, degrees_of_freedom) = (r.f32()?, r.u32()?);
    let mut covariance_si = [[0.0f32; MAX_PARAMETERS]; MAX_PARAMETERS];
    for row in covariance_si.iter_mut() {
        r.f32s(row)?;
    }
    // The solution's numbers are finite as the estimator writes them: a stored NaN or infinity is corruption.
    let estimates = est.iter().flatten().flat_map(|e| [e.value, e.std_error]);
    if !estimates.chain(covariance_si.iter().flatten().copied()).chain([chi_square]).all(|v| v.is_finite()) {
        return None;
    }
    let solution = BiasSolution {
        gyro_bias_b_radps: [est[0], est[1], est[2]],
        accel_bias_b_mps2: [est[3], est[4], est[5]],
        reference_offset_n_rad: [est[6], est[7], est[8]],
        reference_offset_estimated,
        positions,
        residual_n_rad,
        chi_square,
        degrees_of_freedom,
        covariance_si,
    };
    Some(CalibrationResult { solution, passes, converged, last_correction_sigma })
}

/// The general estimator's solution; the per-dwell arrays for its dwells only.
fn encode_general(w: &mut Writer<'_>, c: &ChannelSolution) {
    w.u32(c.model.stored_bits() as u32).f32s(&c.parameters_si).u64(c.observable).u64(c.unobservable).u64(c.completion);
    for row in &c.covariance_si {
        w.f32s(row);
    }
    let n = c.dwells.min(c.heading_rad.len());
    w.u32(n as u32).f32s(&c.heading_rad[..n]).f32s(&c.heading_std_rad[..n]);
    for k in 0..n {
        w.f32s(&c.residual_rate_b_radps[k]).f32s(&c.residual_force_b_mps2[k]);
    }
    w.f32s(&c.dwell_statistic[..n]).u64(c.suspect).f32(c.chi_square);
    w.u32(c.degrees_of_freedom).u32(c.iterations).u32(c.converged as u32);
    let attitude = match c.attitude {
        AttitudeKnowledge::Reference => AttitudeCode::Reference,
        AttitudeKnowledge::Unknown => AttitudeCode::Unknown,
    };
    w.u32(attitude.code()).u32(c.earth_rate_resolved as u32);
    for up in &c.up_b[..n] {
        w.f32s(up);
    }
    w.u32(c.blind_spots).u64(c.gauge);
}

fn decode_general(r: &mut Reader<'_>) -> Option<Result<ChannelSolution, WireError>> {
    let Some(model) = u16::try_from(r.u32()?).ok().and_then(Terms::from_stored_bits) else {
        return Some(Err(WireError));
    };
    let mut parameters_si = [0.0f32; PARAMETERS];
    r.f32s(&mut parameters_si)?;
    let (observable, unobservable, completion) = (r.u64()?, r.u64()?, r.u64()?);
    let mut covariance_si = [[0.0f32; PARAMETERS]; PARAMETERS];
    for row in covariance_si.iter_mut() {
        r.f32s(row)?;
    }
    // The solution's numbers are finite as the estimator writes them: a stored NaN or infinity is corruption.
    if !parameters_si.iter().chain(covariance_si.iter().flatten()).all(|v| v.is_finite()) {
        return Some(Err(WireError));
    }
    let dwells = r.u32()? as usize;
    if dwells > MAX_DWELLS {
        return Some(Err(WireError));
    }
    let mut c = ChannelSolution::empty(model, dwells);
    (c.parameters_si, c.observable, c.unobservable, c.completion, c.covariance_si) =
        (parameters_si, observable, unobservable, completion, covariance_si);
    r.f32s(&mut c.heading_rad[..dwells])?;
    r.f32s(&mut c.heading_std_rad[..dwells])?;
    for k in 0..dwells {
        c.residual_rate_b_radps[k] = r.vec3()?;
        c.residual_force_b_mps2[k] = r.vec3()?;
    }
    r.f32s(&mut c.dwell_statistic[..dwells])?;
    (c.suspect, c.chi_square, c.degrees_of_freedom) = (r.u64()?, r.f32()?, r.u32()?);
    if !c.chi_square.is_finite() {
        return Some(Err(WireError));
    }
    (c.iterations, c.converged) = (r.u32()?, r.u32()? != 0);
    c.attitude = match AttitudeCode::from_code(r.u32()?) {
        Some(AttitudeCode::Reference) => AttitudeKnowledge::Reference,
        Some(AttitudeCode::Unknown) => AttitudeKnowledge::Unknown,
        None => return Some(Err(WireError)),
    };
    c.earth_rate_resolved = r.u32()? != 0;
    for k in 0..dwells {
        c.up_b[k] = r.vec3()?;
    }
    (c.blind_spots, c.gauge) = (r.u32()?, r.u64()?);
    Some(Ok(c))
}
