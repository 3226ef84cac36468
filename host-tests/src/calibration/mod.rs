//! `sinscal calibrate`: a recording through the no_std core (dwell collection, alignment, solution).
//! Every formula is the core's; this module only reads, converts to f32 at the edge, and checks input.

pub mod checks;
pub mod estimates;
pub mod firmware_path;
pub mod montecarlo;
pub mod moves;
pub mod qemu;
pub mod result;

use std::ops::ControlFlow;

use sinscal::calib::align::{position_angles, DwellValue, PositionAngles};
use sinscal::calib::angles::{
    calibrate_positions, BiasSolution, CalibrationError, CalibrationResult, CalibrationSettings, PositionInput,
    SolverSettings, MAX_POSITIONS,
};
use sinscal::calib::dwell::{pool_mean_noise, DwellCollector, DwellSummary, Prefilter};
use sinscal::calib::general::{
    AttitudeKnowledge, ChannelError, ChannelEstimator, ChannelSettings, ChannelSolution, Model, MAX_DWELLS,
};
use sinscal::calib::prefilter::{CoefficientIdentifier, PrefilterSettings};
use sinscal::calib::session::{session_estimator, SessionDwell};
use sinscal::nav::earth::{normal_gravity_mps2, Site};
use sinscal::nav::frames::Attitude;
use sinscal::sensor::sample::ImuSample;

pub use crate::calibration::estimates::{Estimates, Method};
use crate::io::dwell_tally::{DwellTallies, DwellTally, NO_DWELL};
use crate::io::error::InputError;
use crate::io::noise_file::NoiseTerms;
use crate::io::recording::{DwellAttitude, Header, RowSource};
use sinscal::calib::noise_model::NoiseModel;

/// Which prefilter runs in front of the dwell statistics.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrefilterKind {
    /// The HMM/KF with the paper's Q and R.
    HmmKf,
    /// None: plain dwell means.
    None,
}

/// How the prefilter's coefficient `a` is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coefficient {
    /// A fixed value in [0, 1].
    Fixed(f32),
    /// Identified from the first dwell (mean over the three channels of each sensor).
    Identify,
}

/// Options of a calibration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Prefilter.
    pub prefilter: PrefilterKind,
    /// Prefilter coefficient `a`.
    pub coefficient: Coefficient,
    /// Dwell mean (default) or the prefilter's settled output.
    pub dwell_value: DwellValue,
    /// Estimate the constant reference offset `phi0`.
    pub estimate_reference_offset: bool,
    /// Passes of the solution at most (1 = the paper's single linear pass; more remove its second-order
    /// error).
    pub max_passes: u32,
    /// The estimator.
    pub method: Method,
    /// The terms of the general estimator (the angle method estimates the biases and the offset).
    pub model: Model,
    /// General estimator: estimate every position's pitch and roll from the data (|f| = g), whatever the
    /// recording says; recordings levelled from their own accelerometers are always solved so
    /// (docs/method.md#unknown-attitudes).
    pub estimate_attitudes: bool,
    /// The firmware path's check of rest: the largest | |f| - g | of a sample in a dwell, m/s^2 (a raw,
    /// uncalibrated accelerometer can be further from g than the default allows).
    pub rest_force_tolerance_mps2: f32,
    /// General estimator: use the moves between dwells when the model has gyro scale factors or misalignments
    /// (docs/method.md#moves).
    pub use_moves: bool,
    /// General estimator: how well the recording's attitudes are known, degrees (`--pose-tolerance`); `None`:
    /// the header's `pose_tolerance_deg`, else [`DEFAULT_POSE_TOLERANCE_DEG`].
    pub pose_tolerance_deg: Option<f64>,
    /// General estimator: the channels' noise terms from a noise file (`--noise`, docs/method.md#noise-model);
    /// `None`: the session's own dwell noise.
    pub noise: Option<NoiseTerms>,
    /// General estimator: the moves and turns left out of the fit to check it (bit k = the k-th in the
    /// recording's order, from 0; `--hold-out-moves`): integrated with the calibration afterwards, their
    /// rotation error reported as held out (docs/method.md#held-out-moves).
    pub hold_out_moves: u64,
}

/// The core's noise model of `options.noise` for `recording`: its sample interval is the recording's (the
/// header's `rate_hz`, else the median step of its times, one more pass over the rows).
pub fn noise_model_of(recording: &impl RowSource, options: &Options) -> Result<Option<NoiseModel>, InputError> {
    let Some(terms) = options.noise else { return Ok(None) };
    let interval_s = match recording.header().rate_hz {
        Some(rate_hz) => 1.0 / rate_hz,
        None => {
            let mut steps = crate::io::recording::TimeSteps::default();
            recording.for_each_row(&mut |row| {
                steps.push(row.t_s);
                Ok(())
            })?;
            steps.median_s().ok_or_else(|| InputError::file(recording.source(), "too few rows for a sample rate"))?
        }
    };
    let model = terms.model(interval_s, recording.has_gyro()).map_err(|e| InputError::file(recording.source(), e))?;
    Ok(Some(model))
}

/// The pose tolerance of a recording without `pose_tolerance_deg` in its header and without
/// `--pose-tolerance`, degrees: its labels are exact (a turntable's). Chosen by measurement
/// (docs/method.md#poses-known-to-a-tolerance); the importers of hand-placed sessions write their own.
pub const DEFAULT_POSE_TOLERANCE_DEG: f64 = 0.0;

/// The pose tolerance a calibration of a recording with this header uses, degrees.
pub fn pose_tolerance_deg(options: &Options, header: &Header) -> f64 {
    options.pose_tolerance_deg.or(header.pose_tolerance_deg).unwrap_or(DEFAULT_POSE_TOLERANCE_DEG)
}

impl Options {
    /// The default options with the paper's estimator (`--method angles`).
    pub fn angles() -> Options {
        Options { method: Method::Angles, ..Options::default() }
    }
}

/// The estimator `calibrate` uses unless told otherwise, chosen by measurement (docs/method.md#default-estimator).
pub const DEFAULT_METHOD: Method = Method::Channels;
pub use sinscal::calib::session::DEFAULT_MODEL;

impl Default for Options {
    fn default() -> Options {
        Options {
            prefilter: PrefilterKind::HmmKf,
            coefficient: Coefficient::Fixed(1.0),
            dwell_value: DwellValue::Mean,
            estimate_reference_offset: true,
            max_passes: CalibrationSettings::default().max_passes,
            method: DEFAULT_METHOD,
            model: DEFAULT_MODEL,
            estimate_attitudes: false,
            rest_force_tolerance_mps2: sinscal::run::sequence::SequenceSettings::default().rest.force_error_max_mps2,
            use_moves: true,
            pose_tolerance_deg: None,
            noise: None,
            hold_out_moves: 0,
        }
    }
}

/// Where the gravity value came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GravitySource {
    /// The recording's header.
    Header,
    /// WGS-84 normal gravity at the recording's latitude and height.
    NormalGravity,
}

/// One position of a calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct PositionResult {
    /// Position label.
    pub pos: u32,
    /// Line of its first row.
    pub first_line: usize,
    /// Reference attitude, degrees.
    pub attitude: DwellAttitude,
    /// Dwell statistics (core).
    pub summary: DwellSummary,
    /// Alignment of the dwell as measured, against the turntable's attitude (first pass, core); `None` without
    /// a reference heading or gyro data.
    pub angles: Option<PositionAngles>,
}

/// The result of a calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    /// Recording name.
    pub source: String,
    /// Latitude from the header, degrees.
    pub latitude_deg: f64,
    /// Site as the core sees it.
    pub site: Site,
    /// Where g came from.
    pub gravity_source: GravitySource,
    /// The prefilter that ran.
    pub prefilter: Prefilter,
    /// Options used.
    pub options: Options,
    /// Positions in order.
    pub positions: Vec<PositionResult>,
    /// The parameters, whichever estimator made them.
    pub estimates: Estimates,
    /// The angle method's solution (core), with `--method angles`.
    pub solution: Option<BiasSolution>,
    /// The general estimator's solution (core), with `--method channels`.
    pub channels: Option<ChannelSolution>,
    /// Whether the recording has gyro data.
    pub has_gyro: bool,
    /// The general estimator's result without its suspect positions (their labels), when some are suspect and
    /// enough remain.
    pub without_suspect: Option<(Vec<u32>, Estimates)>,
    /// Passes made and convergence of the refinement (core).
    pub passes: u32,
    /// Whether the refinement converged.
    pub converged: bool,
    /// Sampling counters of the firmware path (`--on host|qemu`); `None` when the recording's values were
    /// read directly.
    pub sampling: Option<sinscal::run::sampling::SamplingStats>,
    /// "recording", "host" or "qemu".
    pub on: &'static str,
    /// The moves the general estimator used, in order (empty when it used none).
    pub moves: Vec<UsedMove>,
    /// Passes of move integration and solution (0 without moves).
    pub move_passes: u32,
    /// The moves' error beyond white rate noise, rad per axis, named from their residuals when they misfit it
    /// (0: they fit, or none were used; docs/method.md#moves).
    pub move_error_rad: f64,
    /// The pose tolerance the general estimator used, degrees (0: exact labels; the angle method's is 0).
    pub pose_tolerance_deg: f64,
    /// What the fit check adds when it fails: the alternative that fits (`sinscal calibrate` sets it).
    pub fit_hint: Option<String>,
    /// The noise model the general estimator weighted the dwells by (`--noise`); `None`: the session's own
    /// dwell noise.
    pub noise: Option<NoiseModel>,
    /// The device's record this calibration was stored as or read from (`device run`, `device show`); `None`
    /// elsewhere.
    pub record: Option<RecordIdentity>,
}

/// Which stored record a calibration is: its sequence number, when its run started, and a damaged newer record
/// the device passed over.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordIdentity {
    /// The record's sequence number in the device's store.
    pub sequence: u32,
    /// The workstation's UTC time when it started the run that stored the record (from the record's note;
    /// `None` for a record whose note does not carry it).
    pub run_started_utc: Option<String>,
    /// The sequence number of a damaged record newer than this one: the device fell back to this record.
    pub damaged_newer: Option<u32>,
}

/// A move the general estimator used: between which dwells, where, how long, how far it turned, and how far the
/// calibrated gyros' rotation is from the reference's. Its fields are the calibration JSON's `moves` entries.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct UsedMove {
    /// Label of the dwell before it (0 for a labelled turn).
    pub from_pos: u32,
    /// Label of the dwell after it (0 for a labelled turn).
    pub to_pos: u32,
    /// The body axis of a labelled turn (`x`, `y`, `z`), `None` for a move between dwells.
    pub turn: Option<&'static str>,
    /// Line of its first row.
    pub first_line: usize,
    /// Duration, s.
    pub duration_s: f64,
    /// The angle the gyros measured, deg (of a turn: the angle turned, not the end's rotation).
    pub angle_deg: f64,
    /// The rotation error after the fit, body frame at the start of the move, rad.
    pub residual_rad: [f64; 3],
    /// Its whitened sum of squares (negative when left out).
    pub statistic: f64,
    /// Whether it was left out: its rotation was more than 45 deg from the reference's (no move of the table).
    pub refused: bool,
    /// Whether it was held out of the fit (`--hold-out-moves`): its residual is the calibration's error on a
    /// rotation it did not see.
    pub held_out: bool,
}

fn to_f32(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// The site of a recording: gravity from the header, otherwise WGS-84 normal gravity at its latitude and
/// height (docs/conventions.md), and which of the two it is.
pub fn site_of(header: &Header) -> (Site, GravitySource) {
    let latitude_rad = (header.latitude_deg as f32).to_radians();
    match header.gravity_mps2 {
        Some(g) => (Site { latitude_rad, gravity_mps2: g as f32 }, GravitySource::Header),
        None => (
            Site { latitude_rad, gravity_mps2: normal_gravity_mps2(latitude_rad, header.height_m as f32) },
            GravitySource::NormalGravity,
        ),
    }
}

/// What a recording knows of its attitudes: unknown when its header says the pitch and roll were levelled from
/// its own accelerometers (`# attitude_source: accelerometer-levelled`, the imu_tk import), a reference otherwise.
pub fn attitude_knowledge(header: &Header) -> AttitudeKnowledge {
    let levelled = header.comments.iter().any(|c| {
        c.split_once(':').is_some_and(|(key, value)| {
            key.trim() == "attitude_source"
                && value.split_whitespace().next() == Some(crate::io::import::ATTITUDE_SOURCE_LEVELLED)
        })
    });
    if levelled {
        AttitudeKnowledge::Unknown
    } else {
        AttitudeKnowledge::Reference
    }
}

/// Whether gyros of per-sample noise variance `noise_var` (the pooled honest noise, gyro x, y, z first) resolve
/// the Earth rate in dwells of `samples`: the standard error of the median dwell's mean, on its worst axis, is
/// below a third of the Earth rate.
pub fn gyros_resolve_earth_rate(noise_var: &[f32; 6], samples: impl Iterator<Item = u32>) -> bool {
    let mut counts: Vec<u32> = samples.collect();
    if counts.is_empty() {
        return false;
    }
    counts.sort_unstable();
    let n = counts[counts.len() / 2].max(1) as f32;
    let worst = noise_var[..3].iter().fold(0.0f32, |m, v| m.max(*v));
    (worst / n).sqrt() < sinscal::nav::earth::EARTH_RATE_RADPS / 3.0
}

/// The prefilter the options ask for; `a` identified from the recording's first dwell when they say so (a
/// pass over the rows of its label).
pub fn prefilter_of(options: &Options, recording: &impl RowSource) -> Result<Prefilter, InputError> {
    Ok(match options.prefilter {
        PrefilterKind::None => Prefilter::None,
        PrefilterKind::HmmKf => {
            let [a_gyro, a_accel] = match options.coefficient {
                Coefficient::Fixed(a) => [a, a],
                Coefficient::Identify => identify_coefficients(recording)?,
            };
            Prefilter::HmmKf {
                gyro: PrefilterSettings::paper_gyro().with_a(a_gyro),
                accel: PrefilterSettings::paper_accel().with_a(a_accel),
            }
        }
    })
}

/// The dwells of a recording in one pass, at least one and at most `limit`: each dwell's tally and its
/// statistics from the core's collector, fed its rows in file order; the moves between them in the same pass
/// when `moves` is given.
pub fn collect_dwells(
    recording: &impl RowSource,
    prefilter: &Prefilter,
    limit: usize,
    mut moves: Option<&mut moves::MoveCollector>,
) -> Result<Vec<(DwellTally, DwellSummary)>, InputError> {
    let source = recording.source();
    let fresh = DwellCollector::new(prefilter).map_err(|e| InputError::file(source, format!("prefilter: {e}")))?;
    let mut tallies = DwellTallies::new(limit, "the core's limit");
    let mut collectors: Vec<DwellCollector> = Vec::new();
    recording.for_each_row(&mut |row| {
        let dwell = tallies.push(row, source)?;
        if let Some(m) = moves.as_deref_mut() {
            m.push(row, dwell, source)?;
        }
        let Some(i) = dwell else { return Ok(()) };
        if i == collectors.len() {
            collectors.push(fresh.clone());
        }
        let sample = ImuSample { rate_b_radps: to_f32(row.rate_b_radps), force_b_mps2: to_f32(row.force_b_mps2) };
        collectors[i]
            .update(&sample)
            .map_err(|e| InputError::at(source, row.line, format!("{e} (after conversion to f32)")))
    })?;
    tallies
        .at_least_one(source)?
        .into_iter()
        .zip(collectors)
        .map(|(tally, collector)| {
            let summary = collector.summary().map_err(|e| {
                InputError::at(source, tally.first_line, format!("dwell {}: {e}: too short to use", tally.pos))
            })?;
            Ok((tally, summary))
        })
        .collect()
}

/// Runs a calibration of a recording with the estimator the options name.
pub fn calibrate(recording: &impl RowSource, options: &Options) -> Result<Calibration, InputError> {
    match options.method {
        Method::Angles => calibrate_angles(recording, options),
        Method::Channels => calibrate_channels(recording, options),
    }
}

/// The general estimator (docs/method.md#general-estimator) on a recording: headings and gyro columns optional.
pub fn calibrate_channels(recording: &impl RowSource, options: &Options) -> Result<Calibration, InputError> {
    let source = recording.source();
    let header = recording.header();
    let has_gyro = recording.has_gyro();
    let (site, gravity_source) = site_of(header);
    let with_moves = has_gyro && options.use_moves && moves::model_uses_moves(options.model);
    let ChannelSession { estimator, positions, rate_var_radps2, prefilter, moves: all_moves } =
        channel_session(recording, options, with_moves)?;
    let (move_samples, held) = moves::hold_out(all_moves, options.hold_out_moves, source)?;
    let (solution, integrated, move_passes, move_error_rad) = if move_samples.is_empty() {
        (estimator.solve().map_err(|e| channel_error(e, &positions, source))?, Vec::new(), 0, 0.0)
    } else {
        moves::solve_with_moves(&estimator, &move_samples, rate_var_radps2, 0)
            .map_err(|e| channel_error(e, &positions, source))?
    };
    let mut used_moves = used_moves(&move_samples, &integrated, &solution, &positions);
    let checked = moves::check_held_out(&estimator, &solution, &held, rate_var_radps2)
        .map_err(|e| channel_error(e, &positions, source))?;
    used_moves.extend(held_out_moves(&held, &checked, &positions));
    used_moves.sort_by_key(|m| m.first_line);
    let without_suspect = leave_out_suspects(&estimator, &solution, &positions, &move_samples, rate_var_radps2);
    Ok(Calibration {
        pose_tolerance_deg: pose_tolerance_deg(options, header),
        noise: estimator.settings().noise,
        fit_hint: None,
        record: None,
        without_suspect,
        source: source.to_string(),
        latitude_deg: header.latitude_deg,
        site,
        gravity_source,
        prefilter,
        options: *options,
        positions,
        estimates: Estimates::from_session(&estimator, &solution, 0),
        solution: None,
        passes: solution.iterations,
        converged: solution.converged,
        channels: Some(solution),
        has_gyro,
        sampling: None,
        on: "recording",
        moves: used_moves,
        move_passes,
        move_error_rad: f64::from(move_error_rad),
    })
}

/// The general estimator of a recording with its dwells loaded, before any solution.
pub struct ChannelSession {
    /// The estimator.
    pub estimator: ChannelEstimator,
    /// The positions in file order.
    pub positions: Vec<PositionResult>,
    /// The per-sample variance of each gyro for the moves, (rad/s)^2 (`calib::moves::pooled_rate_var_radps2`).
    pub rate_var_radps2: [f32; 3],
    /// The prefilter that ran.
    pub prefilter: Prefilter,
    /// The moves between the dwells, when asked for (gathered in the dwells' pass).
    pub moves: Vec<moves::MoveSamples>,
}

/// The dwells of a recording loaded into the general estimator as `options` say, and with `with_moves` the
/// moves between them, in one pass over the rows.
pub fn channel_session(
    recording: &impl RowSource,
    options: &Options,
    with_moves: bool,
) -> Result<ChannelSession, InputError> {
    let source = recording.source();
    let header = recording.header();
    let has_gyro = recording.has_gyro();
    let (site, _) = site_of(header);
    let prefilter = prefilter_of(options, recording)?;
    let mut collector = with_moves.then(moves::MoveCollector::default);
    let dwells = collect_dwells(recording, &prefilter, MAX_DWELLS, collector.as_mut())?;
    let moves = collector.map_or_else(Vec::new, moves::MoveCollector::finish);
    moves::check_turns(&moves, source)?;
    let mut positions = Vec::with_capacity(dwells.len());
    for (dwell, summary) in dwells {
        let attitude = dwell.attitude(source)?;
        let angles = match (has_gyro, attitude.heading_deg) {
            (true, Some(h)) => {
                let c = Attitude::from_degrees(attitude.pitch_deg as f32, attitude.roll_deg as f32, h as f32).c_b_n();
                position_angles(&summary, options.dwell_value, &c, &site).ok()
            }
            _ => None,
        };
        positions.push(PositionResult { pos: dwell.pos, first_line: dwell.first_line, attitude, summary, angles });
    }
    let attitude = if options.estimate_attitudes { AttitudeKnowledge::Unknown } else { attitude_knowledge(header) };
    // With reference attitudes whose headings are known the Earth rate is always in the gyro model
    // ("unobservable" stays a property of the schedule). Without attitudes, or with headings unknown (labelled
    // faces), it is in the model only where the gyros resolve it: a heading from the Earth rate of a gyro that
    // does not resolve it is a nuisance the data do not inform (docs/method.md#unknown-attitudes).
    let noise = pool_mean_noise(positions.iter().map(|p| p.summary)).map(|m| m.white_equivalent_var);
    let headings_known = positions.iter().all(|p| p.attitude.heading_deg.is_some());
    let earth_rate_resolved = (attitude == AttitudeKnowledge::Reference && headings_known)
        || !has_gyro
        || gyros_resolve_earth_rate(&noise, positions.iter().map(|p| p.summary.samples));
    let settings = ChannelSettings {
        model: options.model,
        use_gyro: has_gyro,
        attitude,
        earth_rate_resolved,
        pose_tolerance_rad: (pose_tolerance_deg(options, header) as f32).to_radians(),
        noise: noise_model_of(recording, options)?,
        ..ChannelSettings::default()
    };
    let estimator = session_estimator(session_dwells(&positions), site, settings, options.dwell_value)
        .map_err(|e| channel_error(e, &positions, source))?;
    let rate_var_radps2 = sinscal::calib::moves::pooled_rate_var_radps2(positions.iter().map(|p| p.summary));
    Ok(ChannelSession { estimator, positions, rate_var_radps2, prefilter, moves })
}

/// What the report says of each move used.
fn used_moves(
    samples: &[moves::MoveSamples],
    integrated: &[sinscal::calib::moves::ChannelMove],
    solution: &ChannelSolution,
    positions: &[PositionResult],
) -> Vec<UsedMove> {
    samples
        .iter()
        .zip(integrated)
        .enumerate()
        .map(|(k, (m, c))| UsedMove {
            residual_rad: solution.move_residual_rad[k].map(|x| x as f64),
            statistic: solution.move_statistic[k] as f64,
            refused: k < 64 && solution.moves_refused & (1 << k) != 0,
            ..move_report(m, c, positions)
        })
        .collect()
}

/// What the report says of a move or turn whatever its fit: where, how long, the angle turned; no residual
/// yet, the statistic of a move left out.
fn move_report(
    m: &moves::MoveSamples,
    c: &sinscal::calib::moves::ChannelMove,
    positions: &[PositionResult],
) -> UsedMove {
    UsedMove {
        from_pos: if m.turn_axis.is_some() { 0 } else { positions[m.from].pos },
        to_pos: if m.turn_axis.is_some() { 0 } else { positions[m.to].pos },
        turn: m.turn_axis.and_then(|a| crate::io::recording::TURN_AXES.get(a).copied()),
        first_line: m.first_line,
        duration_s: c.duration_s as f64,
        angle_deg: (sinscal::math::linalg::norm(match c.turn {
            Some(t) => t.angle_sum_b_rad,
            None => c.rotation.to_rotation_vector(),
        }) as f64)
            .to_degrees(),
        residual_rad: [0.0; 3],
        statistic: -1.0,
        refused: false,
        held_out: false,
    }
}

/// What the report says of each move held out of the fit: its rotation error with the calibration applied.
fn held_out_moves(
    samples: &[moves::MoveSamples],
    checked: &[(sinscal::calib::moves::ChannelMove, [f32; 3])],
    positions: &[PositionResult],
) -> Vec<UsedMove> {
    samples
        .iter()
        .zip(checked)
        .map(|(m, (c, residual))| UsedMove {
            residual_rad: residual.map(|x| x as f64),
            held_out: true,
            ..move_report(m, c, positions)
        })
        .collect()
}

/// The positions as the core's session: the reference attitude, whether it gives the heading, the statistics.
pub fn session_dwells(positions: &[PositionResult]) -> impl Iterator<Item = SessionDwell<'_>> + Clone {
    // Each dwell's first sample counted from the first dwell's: rows are consecutive lines, and only the
    // distances between dwells matter (docs/method.md#noise-model).
    let origin = positions.iter().map(|p| p.first_line).min().unwrap_or(0);
    positions.iter().map(move |p| SessionDwell {
        first_sample: u32::try_from(p.first_line - origin).ok(),
        attitude: Attitude::from_degrees(
            p.attitude.pitch_deg as f32,
            p.attitude.roll_deg as f32,
            p.attitude.heading_deg.unwrap_or(0.0) as f32,
        ),
        heading_known: p.attitude.heading_deg.is_some(),
        summary: &p.summary,
    })
}

/// The solution without its worst dwells: the dwell with the largest statistic among the suspect ones is left
/// out and the rest solved again, until no dwell is suspect, at most half the dwells are out, or fewer than two
/// would remain. Returns the labels left out and the last solution, when any was left out.
pub fn leave_out_suspects(
    estimator: &ChannelEstimator,
    solution: &ChannelSolution,
    positions: &[PositionResult],
    move_samples: &[moves::MoveSamples],
    rate_var_radps2: [f32; 3],
) -> Option<(Vec<u32>, Estimates)> {
    let mut mask = 0u64;
    let mut current = solution.clone();
    let mut out = 0;
    while current.suspect & !mask != 0 && out < positions.len() / 2 && positions.len() - out > 2 {
        let worst = (0..positions.len())
            .filter(|k| current.suspect & !mask & (1 << k) != 0)
            .max_by(|&a, &b| current.dwell_statistic[a].total_cmp(&current.dwell_statistic[b]))?;
        mask |= 1 << worst;
        out += 1;
        current = if move_samples.is_empty() {
            estimator.solve_excluding(mask).ok()?
        } else {
            moves::solve_with_moves(estimator, move_samples, rate_var_radps2, mask).ok()?.0
        };
    }
    if mask == 0 {
        return None;
    }
    let labels = positions.iter().enumerate().filter(|(k, _)| mask & (1 << k) != 0).map(|(_, p)| p.pos).collect();
    Some((labels, Estimates::from_session(estimator, &current, mask)))
}

/// A core error of the general estimator with the dwell's label and line.
pub fn channel_error(e: ChannelError, positions: &[PositionResult], source: &str) -> InputError {
    let dwell = match e {
        ChannelError::BadInput { dwell }
        | ChannelError::ForceMagnitude { dwell, .. }
        | ChannelError::GravityDirection { dwell, .. }
        | ChannelError::HeadingMismatch { dwell, .. } => positions.get(dwell),
        _ => None,
    };
    dwell_error(dwell, e.to_string(), source)
}

/// The paper's estimator (docs/method.md#step-5-schedule-and-solution) on a recording: headings and gyros needed.
pub fn calibrate_angles(recording: &impl RowSource, options: &Options) -> Result<Calibration, InputError> {
    let source = recording.source();
    let header = recording.header();
    if !recording.has_gyro() {
        return Err(InputError::file(
            source,
            "no gyro columns: the angle method needs them (--method channels calibrates the accelerometers alone)",
        ));
    }
    let (site, gravity_source) = site_of(header);
    let prefilter = prefilter_of(options, recording)?;
    let dwells = collect_dwells(recording, &prefilter, MAX_POSITIONS, None)?;
    let settings = CalibrationSettings {
        solver: SolverSettings {
            estimate_reference_offset: options.estimate_reference_offset,
            ..SolverSettings::default()
        },
        dwell_value: options.dwell_value,
        max_passes: options.max_passes,
    };
    let mut inputs = Vec::with_capacity(dwells.len());
    let mut positions = Vec::with_capacity(dwells.len());
    for (dwell, summary) in dwells {
        let at = |reason: String| InputError::at(source, dwell.first_line, format!("dwell {}: {reason}", dwell.pos));
        let (attitude, heading_deg) = dwell.attitude_with_heading(source, "the calibration")?;
        let c_b_n =
            Attitude::from_degrees(attitude.pitch_deg as f32, attitude.roll_deg as f32, heading_deg as f32).c_b_n();
        let angles = position_angles(&summary, options.dwell_value, &c_b_n, &site).map_err(|e| at(e.to_string()))?;
        inputs.push(PositionInput { c_b_n, summary });
        let angles = Some(angles);
        positions.push(PositionResult { pos: dwell.pos, first_line: dwell.first_line, attitude, summary, angles });
    }
    let CalibrationResult { solution, passes, converged, .. } =
        calibrate_positions(&inputs, &site, &settings).map_err(|e| angle_error(e, &positions, source))?;
    Ok(Calibration {
        pose_tolerance_deg: 0.0,
        noise: None,
        fit_hint: None,
        record: None,
        source: source.to_string(),
        latitude_deg: header.latitude_deg,
        site,
        gravity_source,
        prefilter,
        options: *options,
        positions,
        estimates: Estimates::from_angles(&solution),
        solution: Some(solution),
        channels: None,
        has_gyro: true,
        without_suspect: None,
        passes,
        converged,
        sampling: None,
        on: "recording",
        moves: Vec::new(),
        move_passes: 0,
        move_error_rad: 0.0,
    })
}

/// A core error of the angle method with the dwell's label and line.
pub fn angle_error(e: CalibrationError, positions: &[PositionResult], source: &str) -> InputError {
    let index = match e {
        CalibrationError::Align { index, .. }
        | CalibrationError::Implausible { index, .. }
        | CalibrationError::ForceMagnitude { index, .. } => Some(index),
        _ => None,
    };
    dwell_error(index.and_then(|k| positions.get(k)), e.to_string(), source)
}

/// An error message of the core that starts with "position k: " or "dwell k: " (counted from 1 in the
/// order given), with the dwell's label and line instead.
fn dwell_error(dwell: Option<&PositionResult>, text: String, source: &str) -> InputError {
    match dwell {
        Some(p) => {
            let reason = text.split_once(": ").map_or(text.as_str(), |(_, r)| r);
            InputError::at(source, p.first_line, format!("dwell {}: {reason}", p.pos))
        }
        None => InputError::file(source, text),
    }
}

/// One row of the first dwell into the six identifiers.
fn update_identifiers(ids: &mut [CoefficientIdentifier; 6], row: &crate::io::recording::Row) {
    let channels = [to_f32(row.rate_b_radps), to_f32(row.force_b_mps2)];
    for (i, id) in ids.iter_mut().enumerate() {
        id.update(channels[i / 3][i % 3]);
    }
}

/// Identifies the prefilter coefficient `a` of the gyros and of the accelerometers from the recording's first
/// dwell: its rows from the first to the first row of another label, as the device sees it (the rest of the
/// recording is not read).
pub fn identify_coefficients(recording: &impl RowSource) -> Result<[f32; 2], InputError> {
    let mut ids = [CoefficientIdentifier::new(); 6];
    let mut first: Option<(u32, usize)> = None;
    recording.for_each_row_while(&mut |row| {
        let Some(&(label, _)) = first.as_ref() else {
            if row.pos != 0 {
                first = Some((row.pos, row.line));
                update_identifiers(&mut ids, row);
            }
            return Ok(ControlFlow::Continue(()));
        };
        if row.pos != label {
            return Ok(ControlFlow::Break(()));
        }
        update_identifiers(&mut ids, row);
        Ok(ControlFlow::Continue(()))
    })?;
    let Some((_, line)) = first else {
        return Err(InputError::file(recording.source(), NO_DWELL));
    };
    let mut out = [0.0; 2];
    for (sensor, slot) in out.iter_mut().enumerate() {
        let mut sum = 0.0;
        for id in &ids[3 * sensor..3 * sensor + 3] {
            sum += id.coefficient().ok_or_else(|| {
                InputError::at(
                    recording.source(),
                    line,
                    "first dwell too short or constant: cannot identify the coefficient a",
                )
            })?;
        }
        *slot = sum / 3.0;
    }
    Ok(out)
}
