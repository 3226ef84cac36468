//! The recording as the IMU would have delivered it: a replay file (format in `sinscal::rig::replay`) of
//! ADIS16505-2 burst frames, quantised to the device's 32-bit output LSB, with the turntable's position
//! signal; and the calibration of such a replay on the host (`--on host`) or in QEMU (`--on qemu`).

use sinscal::calib::align::position_angles;
use sinscal::instrument::wire::codes::EstimatorCode;
use sinscal::instrument::wire::configuration::{Configuration, RestLimits};
use sinscal::instrument::wire::outcome::{Outcome, MAX_BYTES as MAX_OUTCOME_BYTES};
use sinscal::instrument::wire::Writer;
use sinscal::rig::replay::{read_header, replay_header_bytes, run_replay, ByteSource, ReplayError, ReplayHeader};
use sinscal::run::sequence::{SequenceFailure, SequenceSolution};
use sinscal::sensor::adis::{encode_burst, Burst, Model, BURST32_LEN, I16F16};

use crate::calibration::{
    angle_error, attitude_knowledge, channel_error, prefilter_of, session_dwells, site_of, Calibration, Estimates,
    Method, Options, PositionResult,
};
use crate::io::dwell_tally::{DwellTallies, DwellTally};
use crate::io::error::InputError;
use crate::io::recording::{DwellAttitude, RowSource};
use crate::io::ScratchFile;
use sinscal::calib::session::session_estimator;
use sinscal::run::sequence::Estimator;
use std::io::Write as _;
use std::path::Path;

/// The sensor model the replay files emulate.
pub const REPLAY_MODEL: Model = Model::Adis16505_2;

/// What a replay file was written from: each dwell's label and first line, and its reference attitude, in
/// the order of the file's schedule.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReplayPlan {
    /// The dwells.
    pub dwells: Vec<PlannedDwell>,
    /// Their reference attitudes.
    pub attitudes: Vec<DwellAttitude>,
}

/// A dwell of a replay file: its label in the recording and the line of its first row.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlannedDwell {
    /// Position label.
    pub pos: u32,
    /// Line of its first row.
    pub first_line: usize,
}

/// The replay file of a recording for the given calibration options, in memory ([`replay_parts`]).
pub fn replay_file(rec: &impl RowSource, options: &Options) -> Result<(Vec<u8>, ReplayPlan), InputError> {
    let mut frames = Vec::new();
    let (mut file, plan) = replay_parts(rec, options, &mut frames)?;
    file.extend_from_slice(&frames);
    Ok((file, plan))
}

/// The replay file of a recording for the given calibration options in one pass over its rows: one frame per
/// row is written to `frames` as the rows come, and the file's header (the schedule of the dwells found, and the
/// frame count), which comes before the frames in the file, is returned. Nothing is kept of the rows.
pub fn replay_parts(
    rec: &impl RowSource,
    options: &Options,
    frames: &mut dyn std::io::Write,
) -> Result<(Vec<u8>, ReplayPlan), InputError> {
    let source = rec.source();
    if attitude_knowledge(rec.header()) == sinscal::calib::general::AttitudeKnowledge::Unknown {
        return Err(InputError::file(
            source,
            "the firmware path takes the recording's attitudes as its reference, and this recording's were \
             levelled from its own accelerometers: calibrate it without --on (docs/method.md#unknown-attitudes)",
        ));
    }
    // The sequence integrates the moves at the ADIS's output interval: a recording at another rate would give
    // every move the wrong angle.
    let adis_hz = f64::from(sinscal::sensor::adis::OUTPUT_RATE_HZ);
    let moves = rec.has_gyro()
        && options.method == Method::Channels
        && crate::calibration::moves::model_uses_moves(options.model);
    if let Some(rate_hz) = rec.header().rate_hz.filter(|r| moves && (r / adis_hz - 1.0).abs() > 1e-3) {
        return Err(InputError::file(
            source,
            format!(
                "the firmware path integrates the moves at the IMU's {adis_hz} Hz and this recording is at \
                 {rate_hz} Hz: its moves would turn by the wrong angles; calibrate it without --on, or without \
                 gyro scale factors and misalignments in --model"
            ),
        ));
    }
    let prefilter = prefilter_of(options, rec)?;
    let (dwells, rows) = write_frames(rec, frames)?;
    let frames = u32::try_from(rows)
        .map_err(|_| InputError::file(source, format!("{rows} rows: the replay file counts its frames in 32 bits")))?;
    let (site, _) = site_of(rec.header());
    let estimator = match options.method {
        Method::Angles => EstimatorCode::Angles,
        Method::Channels if rec.has_gyro() => EstimatorCode::General,
        Method::Channels => EstimatorCode::GeneralWithoutGyros,
    };
    let mut configuration = Configuration {
        estimator,
        terms: options.model,
        prefilter,
        dwell_value: options.dwell_value,
        max_passes: options.max_passes.min(255) as u8,
        estimate_reference_offset: options.estimate_reference_offset,
        // The limits of rest: the force tolerance asked for, the sequence's default gravity angle and rate.
        rest: RestLimits { force_error_max_mps2: options.rest_force_tolerance_mps2, ..RestLimits::default() },
        pose_tolerance_rad: (crate::calibration::pose_tolerance_deg(options, rec.header()) as f32).to_radians(),
        noise: crate::calibration::noise_model_of(rec, options)?,
        ..Configuration::new(REPLAY_MODEL, site)
    };
    let mut attitudes = Vec::new();
    for (k, d) in dwells.iter().enumerate() {
        // The angle method needs every heading; the general estimator estimates an unknown one.
        let att = match options.method {
            Method::Angles => d.attitude_with_heading(source, "the angle method")?.0,
            Method::Channels => d.attitude(source)?,
        };
        let [pitch_rad, roll_rad, heading_rad] =
            [att.pitch_deg, att.roll_deg, att.heading_deg.unwrap_or(0.0)].map(|v| (v as f32).to_radians());
        // The replay file holds a label in 16 bits: a larger one would be clipped and two labels could
        // collide.
        let label = u16::try_from(d.pos).map_err(|_| {
            InputError::at(
                source,
                d.first_line,
                format!("position label {} does not fit the firmware path's 16 bits (at most 65535)", d.pos),
            )
        })?;
        // At most MAX_POSITIONS dwells (write_frames refuses more): both pushes fit.
        let _ = configuration.schedule.push(sinscal::nav::frames::Attitude { pitch_rad, roll_rad, heading_rad });
        let _ = configuration.labels.push(label);
        if att.heading_deg.is_none() {
            configuration.unknown_headings |= 1u64 << k;
        }
        attitudes.push(att);
    }
    let header = ReplayHeader { configuration, frames };
    let mut head = vec![0u8; replay_header_bytes(dwells.len())];
    header.encode(&mut Writer::new(&mut head));
    let dwells = dwells.iter().map(|d| PlannedDwell { pos: d.pos, first_line: d.first_line }).collect();
    Ok((head, ReplayPlan { dwells, attitudes }))
}

/// One frame per row of `rec` to `out` (the table byte: the row's dwell in order of first appearance, from 1;
/// between dwells 0, or in a labelled turn `TABLE_TURN` of its axis), with the dwells found, each one contiguous
/// stretch of rows (one turntable stop, as the firmware path needs). A turn after the last dwell is refused: the
/// device's sequence solves when the table leaves its last position. Returns the dwells and the number of rows.
fn write_frames(rec: &impl RowSource, out: &mut dyn std::io::Write) -> Result<(Vec<DwellTally>, u64), InputError> {
    let source = rec.source();
    let mut tallies = DwellTallies::new(sinscal::calib::angles::MAX_POSITIONS, "the core's limit");
    let lsb_rate = (REPLAY_MODEL.radps_per_lsb() as f64) / 65536.0;
    let lsb_force = (REPLAY_MODEL.accel_mps2_per_lsb() as f64) / 65536.0;
    let quantise = |value: f64, lsb: f64, line: usize, what: &str| -> Result<I16F16, InputError> {
        let counts = (value / lsb).round();
        if counts.abs() >= i32::MAX as f64 {
            return Err(InputError::at(source, line, format!("{what} {value} is outside the ADIS16505-2 range")));
        }
        Ok(I16F16::from_bits(counts as i32))
    };
    let mut record = [0u8; 1 + BURST32_LEN];
    let (mut rows, mut previous) = (0u64, 0);
    // The first line of a turn after the last dwell so far.
    let mut turn_after: Option<usize> = None;
    rec.for_each_row(&mut |row| {
        if row.pos != 0 {
            turn_after = None;
        } else if row.turn_axis.is_some() && turn_after.is_none() {
            turn_after = Some(row.line);
        }
        let known = tallies.dwells.len();
        let dwell = tallies.push(row, source)?;
        if dwell.is_some_and(|i| i < known) && row.pos != previous {
            return Err(InputError::at(
                source,
                row.line,
                format!("dwell {} is not contiguous: the firmware path needs one stretch per position", row.pos),
            ));
        }
        previous = row.pos;
        let mut gyro = [I16F16::ZERO; 3];
        let mut accel = [I16F16::ZERO; 3];
        for i in 0..3 {
            gyro[i] = quantise(row.rate_b_radps[i], lsb_rate, row.line, "angular rate")?;
            accel[i] = quantise(row.force_b_mps2[i], lsb_force, row.line, "specific force")?;
        }
        let temp_raw = (row.temp_c.unwrap_or(25.0) / 0.1).round().clamp(i16::MIN as f64, i16::MAX as f64) as i16;
        let burst = Burst { diag_stat: 0, gyro_lsb: gyro, accel_lsb: accel, temp_raw, data_counter: rows as u16 };
        rows += 1;
        // At most MAX_POSITIONS (24) dwells: the table byte holds every index.
        record[0] = match (dwell, row.turn_axis) {
            (Some(i), _) => i as u8 + 1,
            (None, Some(axis)) => sinscal::run::sampling::TABLE_TURN[axis.min(2)],
            (None, None) => 0,
        };
        encode_burst(REPLAY_MODEL, &burst, &mut record[1..]);
        out.write_all(&record).map_err(|e| InputError::file(source, format!("writing the replay file: {e}")))
    })?;
    if let Some(line) = turn_after {
        return Err(InputError::at(
            source,
            line,
            "a labelled turn after the last dwell: the device's sequence solves when the table leaves its last \
             position, so it never sees the turn (docs/method.md#moves); turn before the last position, or \
             calibrate without --on"
                .to_string(),
        ));
    }
    Ok((tallies.at_least_one(source)?, rows))
}

/// The positions of a device's outcome with the dwells of its plan, each with its alignment angles when its
/// heading is known.
fn positions_of_outcome(
    source: &str,
    options: &Options,
    plan: &ReplayPlan,
    outcome: &Outcome,
) -> Result<Vec<PositionResult>, InputError> {
    let site = outcome.configuration.site;
    let ReplayPlan { dwells, attitudes } = plan;
    // A record's plan comes from its note: it must have a dwell for every position of the outcome.
    if outcome.positions.len() > dwells.len().min(attitudes.len()) {
        return Err(InputError::file(
            source,
            format!("the outcome has {} positions, its plan {} dwells", outcome.positions.len(), dwells.len()),
        ));
    }
    let mut positions = Vec::new();
    for (k, p) in outcome.positions.iter().enumerate() {
        let angles =
            match attitudes[k].heading_deg {
                Some(_) => Some(position_angles(&p.summary, options.dwell_value, &p.c_b_n, &site).map_err(|e| {
                    InputError::at(source, dwells[k].first_line, format!("dwell {}: {e}", dwells[k].pos))
                })?),
                None => None,
            };
        positions.push(PositionResult {
            pos: outcome.configuration.labels[k] as u32,
            first_line: dwells[k].first_line,
            attitude: attitudes[k],
            summary: p.summary,
            angles,
        });
    }
    Ok(positions)
}

/// The calibration of a replay outcome, in the host's report types (angles per position recomputed with
/// the core from the replayed dwell statistics where the heading is known). A refusal of the core comes back
/// with the dwell's label and line, as on the direct path.
pub fn calibration_from_outcome(
    rec: &impl RowSource,
    options: &Options,
    plan: &ReplayPlan,
    outcome: &Outcome,
) -> Result<Calibration, InputError> {
    let source = rec.source();
    let site = outcome.configuration.site;
    let dwells = &plan.dwells;
    let positions = positions_of_outcome(source, options, plan, outcome)?;
    if let Some(f) = &outcome.failure {
        return Err(match *f {
            SequenceFailure::PositionAborted { index, reason } => InputError::at(
                source,
                dwells.get(index).map_or(0, |d| d.first_line),
                format!(
                    "calibration sequence failed: position {} (dwell {}) aborted: {reason:?}",
                    index + 1,
                    outcome.configuration.labels.get(index).copied().unwrap_or(0)
                ),
            ),
            SequenceFailure::Calibration(e) => angle_error(e, &positions, source),
            SequenceFailure::Channels(e) => channel_error(e, &positions, source),
            _ => InputError::file(source, "calibration sequence failed"),
        });
    }
    let result = outcome.result.as_ref().ok_or_else(|| {
        InputError::file(
            source,
            format!(
                "the calibration sequence ended after {} of {} positions",
                outcome.positions.len(),
                outcome.configuration.schedule.len()
            ),
        )
    })?;
    let on_firmware = |estimates, solution, channels, without_suspect, passes, converged| Calibration {
        pose_tolerance_deg: (outcome.configuration.pose_tolerance_rad as f64).to_degrees(),
        noise: outcome.configuration.noise,
        fit_hint: None,
        record: None,
        source: source.to_string(),
        latitude_deg: rec.header().latitude_deg,
        site,
        gravity_source: site_of(rec.header()).1,
        prefilter: outcome.configuration.prefilter,
        options: *options,
        positions: positions.clone(),
        estimates,
        solution,
        channels,
        has_gyro: rec.has_gyro(),
        without_suspect,
        passes,
        converged,
        sampling: Some(outcome.sampling),
        on: "host",
        // The outcome does not carry the moves' residuals.
        moves: Vec::new(),
        move_passes: 0,
        move_error_rad: 0.0,
    };
    let calibration = match result {
        SequenceSolution::Angles(r) => {
            on_firmware(Estimates::from_angles(&r.solution), Some(r.solution), None, None, r.passes, r.converged)
        }
        SequenceSolution::Channels(c) => {
            // The firmware's solution as it is: nothing is solved again here. The dwells' noise, which the
            // report's fit statistics divide by, comes from the firmware's dwell statistics. The result without
            // suspect dwells is a second fit that the device does not make: only the direct path reports it.
            let settings = match outcome.configuration.sequence_estimator() {
                Estimator::Channels(s) => s,
                Estimator::Angles => return Err(InputError::file(source, "replay outcome: estimator mismatch")),
            };
            let estimator = session_estimator(session_dwells(&positions), site, settings, options.dwell_value)
                .map_err(|e| channel_error(e, &positions, source))?;
            let estimates = Estimates::from_session(&estimator, c, 0);
            on_firmware(estimates, None, Some(c.clone()), None, c.iterations, c.converged)
        }
    };
    // An outcome read from a device or a record is not trusted: dwell statistics far beyond any sensor's (a
    // corrupt record) scale the standard errors past f32's range.
    let e = &calibration.estimates;
    if !e.value_si.iter().chain(&e.std_si).flatten().all(|v| v.is_finite()) {
        return Err(InputError::file(source, "the outcome's estimates or standard errors are not finite numbers"));
    }
    Ok(calibration)
}

/// `calibrate --on host`: the replay file through the firmware path on x86. The replay file is written to a
/// scratch file and read back as the firmware reads it, so memory does not grow with the recording. The
/// outcome goes through the same byte encoding as the firmware's, so both report from identical bits.
pub fn calibrate_on_host(rec: &impl RowSource, options: &Options) -> Result<Calibration, InputError> {
    let source = rec.source();
    let replay = ScratchFile::new("replay.ssrp");
    let plan = write_replay_file(rec, options, &replay)?;
    let fail = |e: String| InputError::file(source, format!("replay: {e}"));
    let open = || std::fs::File::open(replay.path()).map(|f| ReadSource(std::io::BufReader::new(f)));
    let outcome = run_replay(open().map_err(|e| fail(e.to_string()))?, |_| {}).map_err(|e| fail(e.to_string()))?;
    let mut bytes = vec![0u8; MAX_OUTCOME_BYTES];
    let n = outcome.encode(&mut bytes).map_err(|e| fail(e.to_string()))?;
    let header = read_header(&mut open().map_err(|e| fail(e.to_string()))?).map_err(|e| fail(e.to_string()))?;
    let decoded = Outcome::decode(&header.configuration, &bytes[..n]).map_err(|e| fail(e.to_string()))?;
    calibration_from_outcome(rec, options, &plan, &decoded)
}

/// Writes the replay file of a recording ([`replay_parts`]) to `file`: the frames go to a second scratch file
/// as the rows are read, then the header and the frames are copied into `file`.
pub fn write_replay_file(
    rec: &impl RowSource,
    options: &Options,
    file: &ScratchFile,
) -> Result<ReplayPlan, InputError> {
    let fail = |path: &Path, e: std::io::Error| InputError::file(rec.source(), format!("{}: {e}", path.display()));
    let frames = ScratchFile::new("frames.bin");
    let mut out = std::io::BufWriter::new(std::fs::File::create(frames.path()).map_err(|e| fail(frames.path(), e))?);
    let (head, plan) = replay_parts(rec, options, &mut out)?;
    out.into_inner().map_err(|e| fail(frames.path(), e.into_error()))?;
    let mut whole = std::fs::File::create(file.path()).map_err(|e| fail(file.path(), e))?;
    whole.write_all(&head).map_err(|e| fail(file.path(), e))?;
    let mut frames_in = std::fs::File::open(frames.path()).map_err(|e| fail(frames.path(), e))?;
    std::io::copy(&mut frames_in, &mut whole).map_err(|e| fail(file.path(), e))?;
    Ok(plan)
}

/// The firmware's byte source on a host reader.
pub struct ReadSource<R>(pub R);

impl<R: std::io::Read> ByteSource for ReadSource<R> {
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), ReplayError> {
        self.0.read_exact(buf).map_err(|_| ReplayError::Read)
    }
}
