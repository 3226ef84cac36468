//! The moves between a recording's dwells (docs/method.md#moves): the rows between the end of one dwell and the
//! start of the next, kept as f32 samples and integrated by the core's [`MoveSums`] with the current estimate,
//! again after each solution until the estimate stops changing.

use sinscal::calib::channels::{ChannelError, ChannelEstimator, ChannelSolution, Model, Term, PARAMETERS};
use sinscal::calib::moves::{ChannelMove, MoveSums, MAX_MOVES, MOVE_PARAMETERS};

use crate::io::dwell_tally::DwellTallies;
use crate::io::error::InputError;
use crate::io::recording::RowSource;

/// The samples of one move, as the core reads them (f32).
#[derive(Clone, Debug, PartialEq)]
pub struct MoveSamples {
    /// The dwell before the move (index in file order).
    pub from: usize,
    /// The dwell after it.
    pub to: usize,
    /// Line of the move's first row.
    pub first_line: usize,
    /// Per row: gyro (rad/s), accelerometer (m/s^2), body, and the interval since the row before, s.
    pub samples: Vec<([f32; 3], [f32; 3], f32)>,
}

/// Whether the model has a term that only the moves determine well: a gyro scale factor or misalignment.
pub fn model_uses_moves(model: Model) -> bool {
    model.contains(Term::GyroScaleFactor) || model.contains(Term::GyroMisalignment)
}

/// The moves of a recording: every run of rows with `pos = 0` between two dwells (a run before the first dwell
/// or after the last is not a move). `limit` is the core's limit of dwells.
pub fn collect_moves(recording: &impl RowSource, limit: usize) -> Result<Vec<MoveSamples>, InputError> {
    let source = recording.source();
    let mut tallies = DwellTallies::new(limit, "the core's limit");
    let mut moves = Vec::new();
    let mut current: Option<MoveSamples> = None;
    let mut last_dwell: Option<usize> = None;
    let mut previous_t_s: Option<f64> = None;
    recording.for_each_row(&mut |row| {
        let dwell = tallies.push(row, source)?;
        let dt_s = previous_t_s.map(|t| row.t_s - t);
        previous_t_s = Some(row.t_s);
        match dwell {
            Some(i) => {
                if let Some(m) = current.take() {
                    if m.from != i && !m.samples.is_empty() && moves.len() < MAX_MOVES {
                        moves.push(MoveSamples { to: i, ..m });
                    }
                }
                last_dwell = Some(i);
            }
            None => {
                let Some(from) = last_dwell else { return Ok(()) };
                let dt_s = dt_s.unwrap_or(0.0);
                if dt_s.is_nan() || dt_s <= 0.0 {
                    return Err(InputError::at(source, row.line, "time does not increase within a move".to_string()));
                }
                let m = current.get_or_insert_with(|| MoveSamples {
                    from,
                    to: from,
                    first_line: row.line,
                    samples: Vec::new(),
                });
                m.samples.push((row.rate_b_radps.map(|x| x as f32), row.force_b_mps2.map(|x| x as f32), dt_s as f32));
            }
        }
        Ok(())
    })?;
    Ok(moves)
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
            for (rate, force, dt_s) in &m.samples {
                sums.push(*rate, *force, *dt_s);
            }
            Ok(sums.finish(m.from, m.to, rate_var_radps2))
        })
        .collect()
}

/// Passes of integration and solution at most.
pub const MAX_MOVE_PASSES: u32 = 8;

/// The solution with the moves, without the dwells in `exclude`: the moves integrated with the prior (none at
/// first), solved, and integrated again with the estimate until no gyro parameter changes by more than 1e-3 of
/// its standard error, or the largest change, below 0.05 of its standard error, has stopped shrinking (the rule
/// of the core's Gauss-Newton passes, docs/method.md#how-it-solves: the f32 integration and solution leave
/// changes of a few thousandths of a standard error from pass to pass). Returns the solution, the moves of its
/// last pass and the passes made.
pub fn solve_with_moves(
    estimator: &ChannelEstimator,
    moves: &[MoveSamples],
    rate_var_radps2: [f32; 3],
    exclude: u64,
) -> Result<(ChannelSolution, Vec<ChannelMove>, u32), ChannelError> {
    let mut prior = [0.0f32; PARAMETERS];
    let mut integrated = integrate(moves, &prior, rate_var_radps2)?;
    let solve = |integrated: &[ChannelMove]| {
        if exclude == 0 {
            estimator.solve_with(integrated)
        } else {
            estimator.solve_excluding_with(exclude, integrated)
        }
    };
    let mut solution = solve(&integrated)?;
    let mut passes = 1;
    let mut previous = f32::INFINITY;
    while passes < MAX_MOVE_PASSES {
        let mut largest = 0.0f32;
        for &p in &MOVE_PARAMETERS {
            let Some((value, std)) = solution.estimate(p) else { continue };
            let change = (value - prior[p]).abs();
            largest = largest.max(if std > 0.0 { change / std } else { change });
            prior[p] = value;
        }
        if largest < 1e-3 || (largest < 0.05 && largest >= previous) {
            break;
        }
        previous = largest;
        integrated = integrate(moves, &prior, rate_var_radps2)?;
        solution = solve(&integrated)?;
        passes += 1;
    }
    Ok((solution, integrated, passes))
}
