//! The moves between a recording's dwells (docs/method.md#moves): the rows between the end of one dwell and the
//! start of the next, kept as f32 samples and integrated by the core's [`MoveSums`] with the current estimate,
//! again after each solution until the estimate stops changing.

use sinscal::calib::general::{
    implausible_parameter, AttitudeKnowledge, ChannelError, ChannelEstimator, ChannelSolution, Model, Term, PARAMETERS,
};
use sinscal::calib::moves::{ChannelMove, MoveSums, MAX_MOVES, MOVE_PARAMETERS};

use crate::io::error::InputError;
use crate::io::recording::Row;

/// The samples of one move, as the core reads them (f32).
#[derive(Clone, Debug, PartialEq)]
pub struct MoveSamples {
    /// The dwell before the move (index in file order).
    pub from: usize,
    /// The dwell after it.
    pub to: usize,
    /// Line of the move's first row.
    pub first_line: usize,
    /// A labelled turn about this body axis (0, 1, 2) back to where it started (a Ferraris turn): `from` and `to`
    /// are then not used, and up at the start is the direction of the mean force of its first
    /// [`TURN_REST_SAMPLES`](sinscal::calib::moves::TURN_REST_SAMPLES).
    pub turn_axis: Option<usize>,
    /// Its rows.
    pub samples: Vec<MoveRow>,
}

/// One row of a move as the core reads it (f32).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveRow {
    /// Gyro output, body, rad/s.
    pub rate_b_radps: [f32; 3],
    /// Accelerometer output, body, m/s^2.
    pub force_b_mps2: [f32; 3],
    /// The interval since the row before, s.
    pub dt_s: f32,
}

impl MoveRow {
    /// The row of `row`, `dt_s` after the one before.
    fn of(row: &Row, dt_s: f64) -> MoveRow {
        MoveRow {
            rate_b_radps: row.rate_b_radps.map(|x| x as f32),
            force_b_mps2: row.force_b_mps2.map(|x| x as f32),
            dt_s: dt_s as f32,
        }
    }
}

/// Whether the model has a term that only the moves determine well: a gyro scale factor or misalignment.
pub fn model_uses_moves(model: Model) -> bool {
    model.contains(Term::GyroScaleFactor) || model.contains(Term::GyroMisalignment)
}

/// The moves of a recording: every run of rows with `pos = 0` between two dwells (a run before the first dwell
/// or after the last is not a move), and every labelled turn (a run of rows with the same `turn` axis, wherever
/// it lies), gathered row by row beside the dwells' pass ([`MoveCollector::push`]). A run between two dwells
/// that holds a labelled turn is not a move: its turns are the observations (the rows are not used twice).
#[derive(Debug, Default)]
pub struct MoveCollector {
    moves: Vec<MoveSamples>,
    current: Option<MoveSamples>,
    /// Whether the current run holds a labelled turn.
    current_holds_turn: bool,
    turn: Option<MoveSamples>,
    last_dwell: Option<usize>,
    previous_t_s: Option<f64>,
}

impl MoveCollector {
    /// One row, with the index of its dwell (`None` for `pos = 0`).
    pub fn push(&mut self, row: &Row, dwell: Option<usize>, source: &str) -> Result<(), InputError> {
        let dt_s = self.previous_t_s.map(|t| row.t_s - t);
        self.previous_t_s = Some(row.t_s);
        if self.turn.as_ref().is_some_and(|t| t.turn_axis != row.turn_axis) {
            self.finish_turn();
        }
        if let (Some(axis), Some(dt_s)) = (row.turn_axis, dt_s) {
            if dt_s.is_nan() || dt_s <= 0.0 {
                return Err(InputError::at(source, row.line, "time does not increase within a turn".to_string()));
            }
            let from = self.last_dwell.unwrap_or(0);
            let turn = self.turn.get_or_insert_with(|| MoveSamples {
                from,
                to: from,
                first_line: row.line,
                turn_axis: Some(axis),
                samples: Vec::new(),
            });
            turn.samples.push(MoveRow::of(row, dt_s));
            self.current_holds_turn = true;
        }
        match dwell {
            Some(i) => {
                if let Some(m) = self.current.take() {
                    let whole = !self.current_holds_turn;
                    if whole && m.from != i && !m.samples.is_empty() && self.moves.len() < MAX_MOVES {
                        self.moves.push(MoveSamples { to: i, ..m });
                    }
                }
                self.current_holds_turn = false;
                self.last_dwell = Some(i);
            }
            None => {
                let Some(from) = self.last_dwell else { return Ok(()) };
                let dt_s = dt_s.unwrap_or(0.0);
                if dt_s.is_nan() || dt_s <= 0.0 {
                    return Err(InputError::at(source, row.line, "time does not increase within a move".to_string()));
                }
                let m = self.current.get_or_insert_with(|| MoveSamples {
                    from,
                    to: from,
                    first_line: row.line,
                    turn_axis: None,
                    samples: Vec::new(),
                });
                m.samples.push(MoveRow::of(row, dt_s));
            }
        }
        Ok(())
    }

    /// The turn being gathered, as an observation.
    fn finish_turn(&mut self) {
        if let Some(t) = self.turn.take() {
            if !t.samples.is_empty() && self.moves.len() < MAX_MOVES {
                self.moves.push(t);
            }
        }
    }

    /// The moves and turns gathered (a run after the last dwell is dropped, a turn there is not).
    pub fn finish(mut self) -> Vec<MoveSamples> {
        self.finish_turn();
        self.moves
    }
}

/// The moves integrated by the core with the rates compensated by `prior_si`; `rate_var_radps2` is the
/// per-sample variance of each gyro's output.
pub fn integrate(
    moves: &[MoveSamples],
    prior_si: &[f32; PARAMETERS],
    rate_var_radps2: [f32; 3],
) -> Result<Vec<ChannelMove>, ChannelError> {
    moves
        .iter()
        .enumerate()
        .map(|(index, m)| {
            let mut sums = MoveSums::new(prior_si).map_err(|_| ChannelError::BadMove { index })?;
            for r in &m.samples {
                sums.push(r.rate_b_radps, r.force_b_mps2, r.dt_s);
            }
            let Some(axis) = m.turn_axis else { return Ok(sums.finish(m.from, m.to, rate_var_radps2)) };
            sums.finish_turn(axis, rate_var_radps2).ok_or(ChannelError::BadMove { index })
        })
        .collect()
}

/// Largest distance of a labelled turn's raw integrated angle about its axis from a whole number of turns (at
/// least one), deg: beyond it the labels do not hold a whole turn (a turn cut, or a label on the wrong rows). The
/// core's tolerance, which the device's sequence applies.
pub const TURN_ANGLE_TOLERANCE_DEG: f64 =
    sinscal::calib::moves::TURN_ANGLE_TOLERANCE_RAD as f64 * 180.0 / std::f64::consts::PI;

/// Refuses a labelled turn whose raw gyro, integrated about its axis, is not within
/// [`TURN_ANGLE_TOLERANCE_DEG`] of a whole number of turns (at least one): its reference would be wrong.
pub fn check_turns(moves: &[MoveSamples], source: &str) -> Result<(), InputError> {
    for m in moves {
        let Some(axis) = m.turn_axis else { continue };
        let angle_deg: f64 =
            m.samples.iter().map(|r| f64::from(r.rate_b_radps[axis]) * f64::from(r.dt_s)).sum::<f64>().to_degrees();
        let turns = (angle_deg / 360.0).round();
        if turns == 0.0 || (angle_deg - 360.0 * turns).abs() > TURN_ANGLE_TOLERANCE_DEG {
            return Err(InputError::at(
                source,
                m.first_line,
                format!(
                    "the labelled turn about {} turns {angle_deg:.1} deg: not a whole turn within \
                     {TURN_ANGLE_TOLERANCE_DEG:.0} deg (a turn cut, or its label on other rows)",
                    crate::io::recording::TURN_AXES[axis]
                ),
            ));
        }
    }
    Ok(())
}

/// Passes of integration and solution at most.
pub const MAX_MOVE_PASSES: u32 = 10;

/// Significance at which the moves between dwells misfit white rate noise, so that their error beyond it is
/// named ([`move_error_update`]).
pub const MOVE_MISFIT_ALPHA: f64 = 0.001;

/// The moves' error beyond white rate noise, rad per axis, after a solution with `current` (rad): 0 while the
/// moves between dwells (not the labelled turns) fit their noise (their chi-square below its upper
/// [`MOVE_MISFIT_ALPHA`] quantile); otherwise the error that brings their chi-square to its degrees of freedom,
/// by one step of `error^2 <- error^2 S / R` from their mean square residual per row at first (S their chi-square,
/// R their rows: hand moves, whose rotations white rate noise does not explain; docs/method.md#moves).
pub fn move_error_update(solution: &ChannelSolution, moves: &[MoveSamples], current: f32) -> f32 {
    let (mut chi2, mut rows, mut square_rad2) = (0.0f64, 0u32, 0.0f64);
    for (k, m) in moves.iter().enumerate().take(MAX_MOVES) {
        if m.turn_axis.is_some() || solution.move_statistic[k] < 0.0 {
            continue;
        }
        chi2 += solution.move_statistic[k] as f64;
        rows += u32::from(solution.move_rows[k]);
        square_rad2 += solution.move_residual_rad[k].iter().map(|x| (*x as f64).powi(2)).sum::<f64>();
    }
    if rows == 0 {
        return 0.0;
    }
    let r = rows as f64;
    if current <= 0.0 {
        let misfit = chi2 > crate::stats::linfit::chi_square_quantile_upper(MOVE_MISFIT_ALPHA, r);
        return if misfit { (square_rad2 / r).sqrt() as f32 } else { 0.0 };
    }
    ((current as f64).powi(2) * chi2 / r).sqrt() as f32
}

/// The solution with the moves, without the dwells in `exclude`: the moves integrated with the prior (none at
/// first), solved, and integrated again with the estimate until no gyro parameter changes by more than 1e-3 of
/// its standard error, or the change stops shrinking below 0.05 of it (the rounding of f32). The solution's
/// `converged` is false when the passes ran out first; an estimate that leaves every instrument's range is
/// refused ([`ChannelError::Diverged`]). When the poses are not known exactly (a pose tolerance, or attitudes
/// estimated: hand-placed poses) and the moves between them misfit their white rate noise, their error beyond it
/// is named from their residuals ([`move_error_update`]) and updated after every solution.
/// Returns the solution, the moves of its last pass, the passes made and the moves' error (rad per axis, 0 when
/// they fit).
pub fn solve_with_moves(
    estimator: &ChannelEstimator,
    moves: &[MoveSamples],
    rate_var_radps2: [f32; 3],
    exclude: u64,
) -> Result<(ChannelSolution, Vec<ChannelMove>, u32, f32), ChannelError> {
    let mut estimator = estimator.clone();
    let mut prior = [0.0f32; PARAMETERS];
    let mut integrated = integrate(moves, &prior, rate_var_radps2)?;
    let solve = |estimator: &ChannelEstimator, integrated: &[ChannelMove]| {
        if exclude == 0 {
            estimator.solve_with(integrated)
        } else {
            estimator.solve_excluding_with(exclude, integrated)
        }
    };
    // Only between poses not known exactly (hand-placed): a turntable's moves that misfit fail the fit check.
    let settings = estimator.settings();
    let hand_placed = settings.pose_tolerance_rad > 0.0 || settings.attitude == AttitudeKnowledge::Unknown;
    let start_rad = if settings.pose_tolerance_rad > 0.0 { settings.pose_tolerance_rad } else { HAND_MOVE_START_RAD };
    let mut solution = match solve(&estimator, &integrated) {
        Ok(s) => s,
        Err(e) if !hand_placed => return Err(e),
        // Hand moves weighted by their white rate noise alone can pull the fit away (a hand move misses by a
        // degree, where white noise allows arcseconds): solved again with the moves' error started at the
        // poses' tolerance, then named from the residuals as below.
        first => {
            estimator.set_move_error_rad(start_rad);
            match solve(&estimator, &integrated) {
                Ok(s) => s,
                Err(e) => return Err(first.err().unwrap_or(e)),
            }
        }
    };
    for _ in 0..if hand_placed { MOVE_ERROR_STEPS } else { 0 } {
        let error = move_error_update(&solution, moves, estimator.move_error_rad());
        if error == estimator.move_error_rad() {
            break;
        }
        estimator.set_move_error_rad(error);
        solution = solve(&estimator, &integrated)?;
    }
    let mut passes = 1;
    let mut previous = f32::INFINITY;
    let mut settled = false;
    loop {
        if let Some(parameter) = implausible_parameter(&solution.parameters_si) {
            return Err(ChannelError::Diverged { parameter, value: solution.parameters_si[parameter] });
        }
        let mut largest = 0.0f32;
        for &p in &MOVE_PARAMETERS {
            let Some((value, std)) = solution.estimate(p) else { continue };
            let change = (value - prior[p]).abs();
            largest = largest.max(if std > 0.0 { change / std } else { change });
            prior[p] = value;
        }
        if largest < 1e-3 || (largest < 0.05 && largest > 0.5 * previous) {
            settled = true;
            break;
        }
        if passes == MAX_MOVE_PASSES {
            break;
        }
        previous = largest;
        integrated = integrate(moves, &prior, rate_var_radps2)?;
        solution = solve(&estimator, &integrated)?;
        if estimator.move_error_rad() > 0.0 {
            estimator.set_move_error_rad(move_error_update(&solution, moves, estimator.move_error_rad()));
            solution = solve(&estimator, &integrated)?;
        }
        passes += 1;
    }
    solution.converged &= settled;
    Ok((solution, integrated, passes, estimator.move_error_rad()))
}

/// The moves split into those the fit uses and those `hold_out` (bit k = the k-th move, from 0) keeps out of it
/// to check it; a bit beyond the moves is bad input.
pub fn hold_out(
    moves: Vec<MoveSamples>,
    hold_out: u64,
    source: &str,
) -> Result<(Vec<MoveSamples>, Vec<MoveSamples>), InputError> {
    let named = 64 - hold_out.leading_zeros() as usize;
    if named > moves.len() {
        return Err(InputError::file(
            source,
            format!(
                "--hold-out-moves: move {named} named, the recording has {} moves and turns the model uses",
                moves.len()
            ),
        ));
    }
    let (held, fitted): (Vec<_>, Vec<_>) =
        moves.into_iter().enumerate().partition(|(k, _)| *k < 64 && hold_out & (1 << k) != 0);
    Ok((fitted.into_iter().map(|(_, m)| m).collect(), held.into_iter().map(|(_, m)| m).collect()))
}

/// The moves held out of a solution, integrated with its calibration, each with its rotation error against the
/// solution's attitudes (rad, body frame at the start of the move; without the part about up when a heading is
/// unknown).
pub fn check_held_out(
    estimator: &ChannelEstimator,
    solution: &ChannelSolution,
    held: &[MoveSamples],
    rate_var_radps2: [f32; 3],
) -> Result<Vec<(ChannelMove, [f32; 3])>, ChannelError> {
    let integrated = integrate(held, &solution.parameters_si, rate_var_radps2)?;
    let residuals = estimator.move_residuals(&solution.parameters_si, solution, &integrated);
    Ok(integrated.into_iter().zip(residuals).collect())
}

/// Steps of the moves' error after the first solution ([`move_error_update`]).
const MOVE_ERROR_STEPS: usize = 4;

/// The hand moves' error, rad per axis, a second start takes when the first solution (the moves weighted by
/// their white rate noise alone) ran away (refused as diverged), and the poses have no tolerance of their own
/// (attitudes estimated): 1 deg, a hand-placed pose's usual error.
const HAND_MOVE_START_RAD: f32 = 0.017_453_292;

#[cfg(test)]
mod tests {
    use super::*;

    fn row(line: usize, pos: u32, turn_axis: Option<usize>) -> Row {
        Row {
            t_s: line as f64 * 0.01,
            pos,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            heading_deg: None,
            rate_b_radps: [0.0, 0.0, 1.0],
            force_b_mps2: [0.0, 0.0, 9.8],
            temp_c: None,
            turn_axis,
            line,
        }
    }

    /// Collects `rows` (the dwell index of a row: its `pos` less one, `None` for 0).
    fn collect(rows: &[Row]) -> Vec<MoveSamples> {
        let mut c = MoveCollector::default();
        for r in rows {
            c.push(r, r.pos.checked_sub(1).map(|p| p as usize), "r.csv").unwrap();
        }
        c.finish()
    }

    /// A labelled turn of a whole turn is taken; one cut to half a turn, or of no turn at all, is refused with
    /// its line.
    #[test]
    fn a_turn_that_is_not_a_whole_turn_is_refused() {
        // 1 rad/s about z for 628 samples of 10 ms: 359.8 deg.
        let turn = |n: usize| vec![row(1, 1, None)].into_iter().chain((2..2 + n).map(|l| row(l, 0, Some(2))));
        assert!(check_turns(&collect(&turn(628).collect::<Vec<_>>()), "r.csv").is_ok());
        for n in [314, 20] {
            let e = check_turns(&collect(&turn(n).collect::<Vec<_>>()), "r.csv").unwrap_err().to_string();
            assert!(e.contains("r.csv:2:") && e.contains("not a whole turn"), "{e}");
        }
    }

    /// A run between two dwells is a move; with a labelled turn in it, the turn alone (its rows are not used
    /// twice); a turn after the last dwell is kept, a plain run there is not.
    #[test]
    fn turns_are_gathered_wherever_they_lie_and_replace_the_move_that_holds_them() {
        let plain = [row(1, 1, None), row(2, 0, None), row(3, 0, None), row(4, 2, None), row(5, 0, None)];
        let moves = collect(&plain);
        assert_eq!(
            moves.iter().map(|m| (m.from, m.to, m.turn_axis, m.samples.len())).collect::<Vec<_>>(),
            [(0, 1, None, 2)]
        );
        let turned = [
            row(1, 1, None),
            row(2, 0, None),
            row(3, 0, Some(2)),
            row(4, 0, Some(2)),
            row(5, 2, None),
            row(6, 0, Some(0)),
            row(7, 0, Some(0)),
            row(8, 0, Some(1)),
        ];
        let moves = collect(&turned);
        let seen: Vec<(Option<usize>, usize, usize)> =
            moves.iter().map(|m| (m.turn_axis, m.first_line, m.samples.len())).collect();
        assert_eq!(seen, [(Some(2), 3, 2), (Some(0), 6, 2), (Some(1), 8, 1)]);
    }
}
