//! The calibration sequence: a state machine over the positions of a schedule.
//!
//! Per position: wait until the turntable reports "in position", let it settle, collect the dwell, then
//! go on; after the last position, solve with the estimator the settings name ([`Estimator`]: the general
//! estimator by default, or the paper's angle method). Call rate: [`feed_sequence`] once per queue item
//! (100 Hz); it decides from the item's latched turntable signal whether the table is in position.
//!
//! A dwell is aborted, with its reason, and collected again (after settling) when a sample contradicts
//! the announced position (specific force more than [`RestLimits::gravity_angle_max_rad`] away from
//! the direction of up in the body frame), when the body moves (rate or specific force out of bounds),
//! when too many read faults hit it, or when the table leaves before the dwell is long enough. A position
//! aborted [`SequenceSettings::max_aborts`] times fails the sequence. The checks compare squared
//! magnitudes, so no square root or trigonometry runs per sample.
//!
//! Moves (docs/method.md#moves): when the general estimator's model has gyro scale factors or misalignments,
//! the samples between the end of one dwell and the start of the next are integrated into a
//! [`MoveSums`] (at the ADIS output interval, [`SAMPLE_PERIOD_S`]; no prior calibration, so one pass: the
//! host's direct path integrates again with each estimate), at most [`MAX_SEQUENCE_MOVES`] of them. A read
//! fault during a move, or an abort of the position it ends at, drops that move.
//!
//! Turns: samples whose table signal is one of [`TABLE_TURN`](crate::run::sampling::TABLE_TURN) (the table
//! making a labelled full turn about body x, y or z, back to where it started) are a turn, an observation of its
//! own (`MoveSums::finish_turn`: up at its start from the mean force of its first samples); the move between two
//! dwells that holds a turn is not a move (its samples are the turn's), as on the host's direct path. A read
//! fault during a turn drops it, and so does an integrated angle about its axis not within 45 deg of a whole
//! number of turns. The sequence solves when the table leaves its last position: a turn after it is not seen.

use heapless::Vec;

use crate::calib::angles::{
    calibrate_positions, CalibrationError, CalibrationResult, CalibrationSettings, PositionInput, MAX_POSITIONS,
};
use crate::calib::dwell::{DwellCollector, Prefilter, MIN_DWELL_SAMPLES};
use crate::calib::general::{ChannelError, ChannelSettings, ChannelSolution, Term, PARAMETERS};
use crate::calib::limits::{REST_FORCE_ERROR_MAX_MPS2, REST_GRAVITY_ANGLE_MAX_RAD, REST_RATE_MAX_RADPS};
use crate::calib::moves::{pooled_rate_var_radps2, ChannelMove, MoveSums};
use crate::calib::prefilter::{HmmKf, PrefilterError};
use crate::calib::session::{default_channel_settings, session_estimator, SessionDwell};
use crate::math::linalg::{dot, Vec3};
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
use crate::run::sampling::{turn_axis_of, QueueItem, TABLE_IN_POSITION};

/// Most moves a sequence integrates (one between each two of the first 17 positions); a move is about 600
/// bytes.
pub const MAX_SEQUENCE_MOVES: usize = 16;

/// What a motion integrated by the sequence is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    /// A move from this position to the next.
    Between(usize),
    /// A labelled full turn about body `axis` (0, 1, 2).
    Turn(usize),
}

/// A turn being integrated: its axis, its sums, and whether a read fault spoiled it.
#[derive(Clone, Debug)]
struct TurnInProgress {
    axis: usize,
    sums: MoveSums,
    spoiled: bool,
}

/// The interval between two samples of the IMU, s: the ADIS output rate.
pub const SAMPLE_PERIOD_S: f32 = 1.0 / crate::sensor::adis::OUTPUT_RATE_HZ as f32;

/// Settings of the sequence.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SequenceSettings {
    /// Samples ignored after the table reports in position.
    pub settle_samples: u32,
    /// Samples of a full dwell (the dwell also ends, complete, when the table leaves after at least
    /// `min_dwell_samples`).
    pub dwell_samples: u32,
    /// Fewest samples of a usable dwell.
    pub min_dwell_samples: u32,
    /// The limits of a sample of a body at rest.
    pub rest: RestLimits,
    /// Most read faults in one dwell.
    pub max_faults_per_dwell: u32,
    /// Aborts of one position before the sequence fails.
    pub max_aborts: u32,
    /// Prefilter of the dwell collector.
    pub prefilter: Prefilter,
    /// The estimator that solves after the last position.
    pub estimator: Estimator,
    /// The angle method's settings (with [`Estimator::Angles`]).
    pub calibration: CalibrationSettings,
    /// Bit k: the heading of position k is unknown (the general estimator estimates it; the angle method
    /// needs every heading, so a sequence with [`Estimator::Angles`] refuses a non-zero mask). 64 bits: one
    /// per position of `MAX_DWELLS`.
    pub unknown_headings: u64,
}

/// The estimator of a sequence.
// The general estimator's settings carry the noise model (208 bytes): boxing is not possible without an
// allocator, and the enum exists once, in the sequence's settings.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Estimator {
    /// The paper's angle method ([`calibrate_positions`]), with [`SequenceSettings::calibration`].
    Angles,
    /// The general estimator (docs/method.md#general-estimator) with these settings.
    Channels(ChannelSettings),
}

/// What a solved sequence gives.
#[allow(clippy::large_enum_variant, reason = "no allocation in the core: one solution, held once by the sequence")]
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SequenceSolution {
    /// The angle method's result.
    Angles(CalibrationResult),
    /// The general estimator's solution.
    Channels(ChannelSolution),
}

/// The limits of a sample of a body at rest: the sequence's checks while it samples (docs/firmware.md#hardening).
/// The configuration carries them (`instrument::wire::configuration`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RestLimits {
    /// Largest | |f| - g |, m/s^2, absolute (default [`REST_FORCE_ERROR_MAX_MPS2`]).
    pub force_error_max_mps2: f32,
    /// Largest angle between the specific force and the announced up direction, rad (default
    /// [`REST_GRAVITY_ANGLE_MAX_RAD`]).
    pub gravity_angle_max_rad: f32,
    /// Largest angular rate magnitude, rad/s (default [`REST_RATE_MAX_RADPS`]).
    pub rate_max_radps: f32,
}

impl Default for RestLimits {
    fn default() -> RestLimits {
        RestLimits {
            force_error_max_mps2: REST_FORCE_ERROR_MAX_MPS2,
            gravity_angle_max_rad: REST_GRAVITY_ANGLE_MAX_RAD,
            rate_max_radps: REST_RATE_MAX_RADPS,
        }
    }
}

impl Default for SequenceSettings {
    fn default() -> SequenceSettings {
        SequenceSettings {
            settle_samples: 200,
            dwell_samples: 6000,
            min_dwell_samples: 1000,
            rest: RestLimits::default(),
            max_faults_per_dwell: 60,
            max_aborts: 3,
            prefilter: Prefilter::paper(),
            estimator: Estimator::Channels(default_channel_settings()),
            calibration: CalibrationSettings::default(),
            unknown_headings: 0,
        }
    }
}

/// Why a dwell was aborted.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AbortReason {
    /// The measured specific force is not along the announced position's up direction.
    GravityContradictsPosition,
    /// Angular rate above the rest bound.
    Rotation,
    /// Specific force magnitude away from g.
    Acceleration,
    /// More read faults than allowed.
    TooManyFaults,
    /// The table left before the dwell had enough samples.
    TableLeft,
    /// A sample was NaN or infinite.
    NotFinite,
}

impl AbortReason {
    /// All reasons, in code order (code = index + 1).
    pub const ALL: [AbortReason; 6] = [
        AbortReason::GravityContradictsPosition,
        AbortReason::Rotation,
        AbortReason::Acceleration,
        AbortReason::TooManyFaults,
        AbortReason::TableLeft,
        AbortReason::NotFinite,
    ];

    /// A small code for logs and files (1..=6).
    pub fn code(self) -> u8 {
        AbortReason::ALL.iter().position(|r| *r == self).map_or(0, |i| i as u8 + 1)
    }

    /// The reason of a code.
    pub fn from_code(code: u8) -> Option<AbortReason> {
        AbortReason::ALL.get((code as usize).checked_sub(1)?).copied()
    }
}

/// What the sequence reports.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The table is in position `index`; settling.
    Settling {
        /// Position index in the schedule.
        index: usize,
    },
    /// Collection of position `index` started.
    DwellStarted {
        /// Position index.
        index: usize,
    },
    /// The dwell of position `index` was aborted; it will be collected again.
    DwellAborted {
        /// Position index.
        index: usize,
        /// Why.
        reason: AbortReason,
        /// The sample of the dwell that caused it.
        at_sample: u32,
    },
    /// Position `index` is done; its statistics are in [`CalibrationSequence::completed`].
    DwellCompleted {
        /// Position index.
        index: usize,
        /// Samples used.
        samples: u32,
        /// Read faults during the dwell.
        faults: u32,
    },
    /// All positions done and solved; the result is [`CalibrationSequence::result`].
    Solved,
    /// The sequence failed.
    Failed(SequenceFailure),
}

/// Why a sequence failed.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SequenceFailure {
    /// A position was aborted too often; the last reason.
    PositionAborted {
        /// Position index.
        index: usize,
        /// Last reason.
        reason: AbortReason,
    },
    /// The angle method failed.
    Calibration(CalibrationError),
    /// The general estimator refused the data or failed (dwell indices are position indices).
    Channels(ChannelError),
}

/// Errors of construction.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SequenceError {
    /// No positions, more than [`MAX_POSITIONS`], or unknown headings with the angle method.
    BadSchedule,
    /// The prefilter settings are invalid.
    Prefilter(PrefilterError),
}

/// Where the sequence is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Phase {
    /// Waiting for the table to report the next position.
    WaitingForTable,
    /// Settling; samples left.
    Settling(u32),
    /// Collecting the dwell.
    Collecting,
    /// The dwell is complete; waiting for the table to leave the position.
    WaitingForTableToLeave,
    /// Solved or failed.
    Finished,
}

/// The calibration sequence.
#[derive(Clone, Debug)]
pub struct CalibrationSequence {
    settings: SequenceSettings,
    site: Site,
    /// The turntable attitude of each position.
    schedule: Vec<Attitude, MAX_POSITIONS>,
    inputs: Vec<PositionInput, MAX_POSITIONS>,
    /// The index of each completed dwell's first sample ([`feed_sequence`]'s count).
    starts: Vec<u32, MAX_POSITIONS>,
    /// The index of the sample being fed (`u32::MAX` before the first), and of the current dwell's first.
    sample: u32,
    dwell_start: u32,
    collector: DwellCollector,
    phase: Phase,
    index: usize,
    dwell_sample: u32,
    faults: u32,
    aborts: u32,
    /// The announced up direction of the current position, body frame (third row of its `C_b^n`).
    up_b: Vec3,
    /// `cos^2` of the largest gravity angle, and the squared bounds of rest, computed once.
    gravity_cos2_max: f32,
    rate2_max_radps2: f32,
    force2_bounds_mps2sq: (f32, f32),
    result: Option<SequenceSolution>,
    /// The moves and turns integrated: what each is and its sums.
    moves: Vec<(Motion, MoveSums), MAX_SEQUENCE_MOVES>,
    /// The move being integrated since the last dwell ended.
    current_move: Option<(usize, MoveSums)>,
    /// Its samples with the table reported moving (a move without any, between contiguous dwells, is no move).
    moving_samples: u32,
    /// The turn being integrated.
    current_turn: Option<TurnInProgress>,
}

impl CalibrationSequence {
    /// A sequence over a schedule of turntable attitudes.
    pub fn new(schedule: &[Attitude], site: Site, settings: SequenceSettings) -> Result<Self, SequenceError> {
        Self::check(schedule, &settings)?;
        let mut stored = Vec::new();
        for a in schedule {
            // Capacity checked above.
            let _ = stored.push(*a);
        }
        let c = libm::cosf(settings.rest.gravity_angle_max_rad);
        // The third row of C_b^n: the up direction in the body frame.
        let up_b = schedule[0].c_b_n().row(2);
        let (g, e) = (site.gravity_mps2, settings.rest.force_error_max_mps2);
        Ok(CalibrationSequence {
            collector: DwellCollector::new(&settings.prefilter).map_err(SequenceError::Prefilter)?,
            settings,
            site,
            schedule: stored,
            inputs: Vec::new(),
            starts: Vec::new(),
            sample: u32::MAX,
            dwell_start: 0,
            phase: Phase::WaitingForTable,
            index: 0,
            dwell_sample: 0,
            faults: 0,
            aborts: 0,
            up_b,
            gravity_cos2_max: c * c,
            rate2_max_radps2: settings.rest.rate_max_radps * settings.rest.rate_max_radps,
            force2_bounds_mps2sq: ((g - e) * (g - e), (g + e) * (g + e)),
            result: None,
            moves: Vec::new(),
            current_move: None,
            moving_samples: 0,
            current_turn: None,
        })
    }

    /// Starts this sequence again, in place, over a new schedule, site and settings: the same as replacing it with
    /// [`CalibrationSequence::new`]'s, without a second sequence (tens of kilobytes) on the stack. On an error the
    /// sequence is unchanged.
    pub fn restart(
        &mut self,
        schedule: &[Attitude],
        site: Site,
        settings: SequenceSettings,
    ) -> Result<(), SequenceError> {
        Self::check(schedule, &settings)?;
        self.collector = DwellCollector::new(&settings.prefilter).map_err(SequenceError::Prefilter)?;
        self.schedule.clear();
        for a in schedule {
            // Capacity checked above.
            let _ = self.schedule.push(*a);
        }
        let c = libm::cosf(settings.rest.gravity_angle_max_rad);
        let (g, e) = (site.gravity_mps2, settings.rest.force_error_max_mps2);
        self.up_b = schedule[0].c_b_n().row(2);
        self.gravity_cos2_max = c * c;
        self.rate2_max_radps2 = settings.rest.rate_max_radps * settings.rest.rate_max_radps;
        self.force2_bounds_mps2sq = ((g - e) * (g - e), (g + e) * (g + e));
        self.settings = settings;
        self.site = site;
        self.inputs.clear();
        self.starts.clear();
        self.sample = u32::MAX;
        self.dwell_start = 0;
        self.phase = Phase::WaitingForTable;
        self.index = 0;
        self.dwell_sample = 0;
        self.faults = 0;
        self.aborts = 0;
        self.result = None;
        self.moves.clear();
        self.current_move = None;
        self.moving_samples = 0;
        self.current_turn = None;
        Ok(())
    }

    /// Whether the sequence integrates the moves: the general estimator with gyro data and gyro scale factors
    /// or misalignments in its model.
    fn uses_moves(&self) -> bool {
        match self.settings.estimator {
            Estimator::Channels(s) => {
                s.use_gyro && (s.model.contains(Term::GyroScaleFactor) || s.model.contains(Term::GyroMisalignment))
            }
            Estimator::Angles => false,
        }
    }

    /// Moves and turns integrated so far.
    pub fn moves(&self) -> usize {
        self.moves.len()
    }

    /// One sample between two dwells: into the move being integrated, or into the turn the table signal names;
    /// a read fault ends that move and spoils that turn.
    fn on_move_sample(&mut self, item: &QueueItem) {
        let axis = turn_axis_of(item.table);
        if self.current_turn.as_ref().is_some_and(|t| Some(t.axis) != axis) {
            self.close_turn();
        }
        if let Some(axis) = axis {
            // A move that holds a turn is no move: it ends here, and the samples are the turn's.
            self.current_move = None;
            self.on_turn_sample(axis, item);
            return;
        }
        let Some((_, sums)) = self.current_move.as_mut() else { return };
        if item.table == 0 {
            self.moving_samples = self.moving_samples.saturating_add(1);
        }
        match &item.reading {
            Ok(r) => sums.push(r.sample.rate_b_radps, r.sample.force_b_mps2, SAMPLE_PERIOD_S),
            Err(_) => self.current_move = None,
        }
    }

    /// One sample of a turn about body `axis`: a new turn when none is being integrated and there is room.
    fn on_turn_sample(&mut self, axis: usize, item: &QueueItem) {
        if self.current_turn.is_none() && self.uses_moves() && self.moves.len() < MAX_SEQUENCE_MOVES {
            self.current_turn =
                MoveSums::new(&[0.0; PARAMETERS]).ok().map(|sums| TurnInProgress { axis, sums, spoiled: false });
        }
        let Some(turn) = self.current_turn.as_mut() else { return };
        match &item.reading {
            Ok(r) => turn.sums.push(r.sample.rate_b_radps, r.sample.force_b_mps2, SAMPLE_PERIOD_S),
            Err(_) => turn.spoiled = true,
        }
    }

    /// Ends the turn being integrated: kept when no fault spoiled it and it turned a whole number of turns (at
    /// least one) within [`TURN_ANGLE_TOLERANCE_RAD`](crate::calib::moves::TURN_ANGLE_TOLERANCE_RAD).
    fn close_turn(&mut self) {
        let Some(turn) = self.current_turn.take() else { return };
        if !turn.spoiled && turn.sums.whole_turns(turn.axis).is_some() {
            let _ = self.moves.push((Motion::Turn(turn.axis), turn.sums));
        }
    }

    /// Whether [`CalibrationSequence::new`] would accept this schedule and these settings, without building the
    /// sequence (tens of kilobytes: a device checks a configuration with this, not with a sequence on its stack).
    pub fn check(schedule: &[Attitude], settings: &SequenceSettings) -> Result<(), SequenceError> {
        let angles_without_heading = settings.estimator == Estimator::Angles && settings.unknown_headings != 0;
        if schedule.is_empty() || schedule.len() > MAX_POSITIONS || angles_without_heading {
            return Err(SequenceError::BadSchedule);
        }
        if let Prefilter::HmmKf { gyro, accel } = &settings.prefilter {
            HmmKf::new(gyro).map_err(SequenceError::Prefilter)?;
            HmmKf::new(accel).map_err(SequenceError::Prefilter)?;
        }
        Ok(())
    }

    /// Where the sequence is.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The position being worked on.
    pub fn position(&self) -> usize {
        self.index
    }

    /// The solution, once [`Event::Solved`] was reported.
    pub fn result(&self) -> Option<&SequenceSolution> {
        self.result.as_ref()
    }

    /// Completed positions so far, with their statistics.
    pub fn completed(&self) -> &[PositionInput] {
        &self.inputs
    }

    fn abort(&mut self, reason: AbortReason, in_position: bool) -> Event {
        let event = Event::DwellAborted { index: self.index, reason, at_sample: self.dwell_sample };
        // The body may have moved: the move that ended at this position no longer has its end.
        if self.moves.last().is_some_and(|(m, _)| *m == Motion::Between(self.index.wrapping_sub(1))) {
            self.moves.pop();
        }
        self.aborts = self.aborts.saturating_add(1);
        if self.aborts >= self.settings.max_aborts {
            self.phase = Phase::Finished;
            return Event::Failed(SequenceFailure::PositionAborted { index: self.index, reason });
        }
        if !in_position {
            self.phase = Phase::WaitingForTable;
        } else if self.settings.settle_samples == 0 {
            self.start_dwell();
        } else {
            self.phase = Phase::Settling(self.settings.settle_samples);
        }
        event
    }

    /// Completes the dwell; `table_left` says whether the table has already left the position.
    fn complete(&mut self, table_left: bool) -> Event {
        let summary = match self.collector.summary() {
            Ok(s) => s,
            Err(_) => return self.abort(AbortReason::TableLeft, false),
        };
        let faults = self.faults;
        let Some(attitude) = self.schedule.get(self.index) else { return self.abort(AbortReason::TableLeft, false) };
        let _ = self.inputs.push(PositionInput { c_b_n: attitude.c_b_n(), summary });
        let _ = self.starts.push(self.dwell_start);
        let event = Event::DwellCompleted { index: self.index, samples: summary.samples, faults };
        self.current_move = None;
        self.moving_samples = 0;
        if self.uses_moves() && self.index + 1 < self.schedule.len() && self.moves.len() < MAX_SEQUENCE_MOVES {
            self.current_move = MoveSums::new(&[0.0; PARAMETERS]).ok().map(|s| (self.index, s));
        }
        self.index += 1;
        self.aborts = 0;
        self.phase = if table_left { Phase::WaitingForTable } else { Phase::WaitingForTableToLeave };
        event
    }

    /// Ends the sequence when the data end: completes a dwell in progress (reported first), then solves
    /// once every position is complete. Call until it returns `None`.
    pub fn finish(&mut self) -> Option<Event> {
        if self.phase == Phase::Collecting && self.dwell_sample >= self.settings.min_dwell_samples {
            // Report the completed dwell; the next call solves if it was the last.
            return Some(self.complete(false));
        }
        if self.phase == Phase::Finished || self.index < self.schedule.len() {
            return None;
        }
        self.phase = Phase::Finished;
        Some(match self.solve() {
            Ok(result) => {
                self.result = Some(result);
                Event::Solved
            }
            Err(e) => Event::Failed(e),
        })
    }

    /// The solution of the completed positions with the settings' estimator.
    fn solve(&self) -> Result<SequenceSolution, SequenceFailure> {
        match self.settings.estimator {
            Estimator::Angles => calibrate_positions(&self.inputs, &self.site, &self.settings.calibration)
                .map(SequenceSolution::Angles)
                .map_err(SequenceFailure::Calibration),
            Estimator::Channels(settings) => {
                let mask = self.settings.unknown_headings;
                let dwells = self.inputs.iter().zip(&self.schedule).enumerate().map(|(k, (p, a))| SessionDwell {
                    attitude: *a,
                    heading_known: mask.checked_shr(k as u32).unwrap_or(0) & 1 == 0,
                    summary: &p.summary,
                    first_sample: self.starts.get(k).copied(),
                });
                let dwell_value = self.settings.calibration.dwell_value;
                // The moves with the gyros' raw sample variance pooled over the dwells.
                let var = pooled_rate_var_radps2(self.inputs.iter().map(|p| p.summary));
                let mut moves: Vec<ChannelMove, MAX_SEQUENCE_MOVES> = Vec::new();
                for (motion, sums) in &self.moves {
                    // Capacity: as many as the sums.
                    let finished = match *motion {
                        Motion::Between(from) => Some(sums.finish(from, from + 1, var)),
                        Motion::Turn(axis) => sums.finish_turn(axis, var),
                    };
                    if let Some(m) = finished {
                        let _ = moves.push(m);
                    }
                }
                session_estimator(dwells, self.site, settings, dwell_value)
                    .and_then(|estimator| estimator.solve_with(&moves))
                    .map(SequenceSolution::Channels)
                    .map_err(SequenceFailure::Channels)
            }
        }
    }

    /// One queue item, with the decision whether the table is in the position the sequence works on at that
    /// sample ([`feed_sequence`] decides it from `item.table`; here `item.table` only tells a sample of a move,
    /// 0 = moving, from one of contiguous dwells).
    pub fn on_sample(&mut self, in_position: bool, item: &QueueItem) -> Option<Event> {
        if matches!(self.phase, Phase::WaitingForTableToLeave | Phase::WaitingForTable | Phase::Settling(_)) {
            self.on_move_sample(item);
        }
        match self.phase {
            Phase::Finished => None,
            Phase::WaitingForTableToLeave => {
                if !in_position {
                    self.phase = Phase::WaitingForTable;
                }
                if self.index == self.schedule.len() {
                    return self.finish();
                }
                None
            }
            Phase::WaitingForTable => {
                if self.index >= self.schedule.len() {
                    return self.finish();
                }
                if !in_position {
                    return None;
                }
                self.phase = Phase::Settling(self.settings.settle_samples);
                if self.settings.settle_samples == 0 {
                    self.start_dwell();
                    let started = Event::DwellStarted { index: self.index };
                    // The first in-position sample belongs to the dwell.
                    return self.collect(in_position, item).or(Some(started));
                }
                Some(Event::Settling { index: self.index })
            }
            Phase::Settling(left) => {
                if !in_position {
                    self.phase = Phase::WaitingForTable;
                    return None;
                }
                if left <= 1 {
                    self.start_dwell();
                    return Some(Event::DwellStarted { index: self.index });
                }
                self.phase = Phase::Settling(left - 1);
                None
            }
            Phase::Collecting => self.collect(in_position, item),
        }
    }

    fn start_dwell(&mut self) {
        if let Some(attitude) = self.schedule.get(self.index) {
            self.up_b = attitude.c_b_n().row(2);
        }
        self.close_turn();
        if let Some((from, sums)) = self.current_move.take() {
            if from + 1 == self.index && self.moving_samples > 0 {
                let _ = self.moves.push((Motion::Between(from), sums));
            }
        }
        self.collector.reset();
        self.dwell_sample = 0;
        self.faults = 0;
        self.phase = Phase::Collecting;
    }

    fn collect(&mut self, in_position: bool, item: &QueueItem) -> Option<Event> {
        if !in_position {
            if self.dwell_sample >= self.settings.min_dwell_samples.max(MIN_DWELL_SAMPLES) {
                let event = self.complete(true);
                // The sample the table left with is the move's first.
                self.on_move_sample(item);
                return Some(event);
            }
            return Some(self.abort(AbortReason::TableLeft, false));
        }
        if self.dwell_sample == 0 {
            self.dwell_start = self.sample;
        }
        self.dwell_sample = self.dwell_sample.saturating_add(1);
        let reading = match &item.reading {
            Ok(r) => r,
            Err(_) => {
                self.faults = self.faults.saturating_add(1);
                if self.faults > self.settings.max_faults_per_dwell {
                    return Some(self.abort(AbortReason::TooManyFaults, true));
                }
                return None;
            }
        };
        // The checks below let NaN through (every comparison with NaN is false); the collector refuses it.
        let f = reading.sample.force_b_mps2;
        let w = reading.sample.rate_b_radps;
        let f2 = dot(f, f);
        // The angle between f and the announced up direction (a unit vector) is within the bound when
        // f.up > 0 and (f.up)^2 >= cos^2(max) |f|^2.
        let along = dot(f, self.up_b);
        if along <= 0.0 || along * along < self.gravity_cos2_max * f2 {
            return Some(self.abort(AbortReason::GravityContradictsPosition, true));
        }
        if dot(w, w) > self.rate2_max_radps2 {
            return Some(self.abort(AbortReason::Rotation, true));
        }
        let (lo, hi) = self.force2_bounds_mps2sq;
        if f2 < lo || f2 > hi {
            return Some(self.abort(AbortReason::Acceleration, true));
        }
        if self.collector.update(&reading.sample).is_err() {
            return Some(self.abort(AbortReason::NotFinite, true));
        }
        if self.dwell_sample >= self.settings.dwell_samples {
            return Some(self.complete(false));
        }
        None
    }
}

/// Feeds one queue item to the sequence, as every processing loop does (the firmware's and the replay's):
/// the table is in the sequence's position when the item's latched signal is [`TABLE_IN_POSITION`] or the
/// position's number (`position + 1`). Returns up to two events.
///
/// Contiguous dwells (no sample between two positions, as a replay can have them): the sample that ends a
/// dwell because the table reports the next position is that position's first sample, not lost, so it is
/// fed a second time, to the next position. A board that only says "in position" cannot tell one position
/// from the next; its table must report "moving" (0) in between.
#[inline]
pub fn feed_sequence(sequence: &mut CalibrationSequence, item: &QueueItem) -> [Option<Event>; 2] {
    let table = item.table;
    let in_position = table == TABLE_IN_POSITION || table as usize == sequence.position() + 1;
    sequence.sample = sequence.sample.wrapping_add(1);
    let first = sequence.on_sample(in_position, item);
    let next = !in_position
        && matches!(first, Some(Event::DwellCompleted { .. }))
        && table as usize == sequence.position() + 1;
    let second = if next { sequence.on_sample(true, item) } else { None };
    [first, second]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn abort_reason_codes_round_trip() {
        for r in AbortReason::ALL {
            assert_eq!(AbortReason::from_code(r.code()), Some(r));
        }
        assert_eq!(AbortReason::from_code(0), None);
        assert_eq!(AbortReason::from_code(7), None);
    }
}
