//! The estimator ([`ChannelEstimator`]): the dwells, the checks before a fit, and Gauss-Newton over the
//! dwells' whitened rows (and the moves'), folded into square-root information factors.

use heapless::Vec;

use crate::calib::general::error::ChannelError;
use crate::calib::general::move_rows::move_used;
use crate::calib::general::nuisance::eliminate_nuisances;
use crate::calib::general::settings::{AttitudeKnowledge, ChannelSettings};
use crate::calib::general::solution::ChannelSolution;
use crate::calib::general::terms::{columns, implausible_parameter, Model, PARAMETERS};
use crate::calib::moves::{ChannelMove, MAX_MOVES};
use crate::calib::noise_model::Window;
use crate::math::linalg::{dot, norm, Mat3, Vec3};
use crate::math::lsq::{inverse_gram, solve_upper, SqrtInfo};
use crate::nav::earth::{Site, EARTH_RATE_RADPS};
use crate::nav::frames::heading_rotation;

/// Most dwells one solution takes (a bit mask of `u64` marks suspect dwells).
pub const MAX_DWELLS: usize = 64;

/// One dwell as the estimator sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelDwell {
    /// The reference attitude without heading, `Rx(pitch) Ry(roll)` ([`crate::nav::frames::Attitude::tilt`]).
    pub tilt: Mat3,
    /// The reference heading, rad, clockwise from north; `None` when unknown.
    pub heading_rad: Option<f32>,
    /// Mean gyro output, body, rad/s (ignored without gyro data).
    pub rate_mean_b_radps: Vec3,
    /// Mean accelerometer output, body, m/s^2.
    pub force_mean_b_mps2: Vec3,
    /// Variance of each gyro mean, (rad/s)^2.
    pub rate_mean_var_b_radps2: Vec3,
    /// Variance of each accelerometer mean, (m/s^2)^2.
    pub force_mean_var_b_mps2sq: Vec3,
    /// The dwell's samples in its session; with a noise model in the settings and every used dwell's window,
    /// the covariance includes the correlation between dwells (docs/method.md#noise-model).
    pub window: Option<Window>,
}

impl ChannelDwell {
    /// Channel `ch`'s mean and the variance it is weighted by (gyro x, y, z in rad/s and (rad/s)^2,
    /// accelerometer x, y, z in m/s^2 and (m/s^2)^2).
    pub(super) fn channel(&self, ch: usize) -> (f32, f32) {
        if ch < 3 {
            (self.rate_mean_b_radps[ch], self.rate_mean_var_b_radps2[ch])
        } else {
            (self.force_mean_b_mps2[ch - 3], self.force_mean_var_b_mps2sq[ch - 3])
        }
    }
}

/// Chi-square quantiles at 0.999 for 1 to 9 degrees of freedom (a dwell's six channels and the priors of its
/// three attitude angles).
pub(super) const CHI2_999: [f32; 9] = [10.828, 13.816, 16.266, 18.467, 20.515, 22.458, 24.322, 26.124, 27.877];

/// Units of f32 rounding (`f32::EPSILON` times the magnitude) that the fit's arithmetic accumulates in a
/// residual ([`ChannelEstimator::rounding_ratio`]).
const ROUNDING_ULPS: f32 = 32.0;

/// The estimator: dwells collected, solved on demand.
#[derive(Clone, Debug)]
pub struct ChannelEstimator {
    pub(super) site: Site,
    pub(super) settings: ChannelSettings,
    pub(super) dwells: Vec<ChannelDwell, MAX_DWELLS>,
    /// The error of a move between dwells beyond white rate noise, rad per axis (0: none; not for a turn).
    pub(super) move_error_rad: f32,
}

impl ChannelEstimator {
    /// An estimator for one site.
    pub fn new(site: Site, settings: ChannelSettings) -> ChannelEstimator {
        ChannelEstimator { site, settings, dwells: Vec::new(), move_error_rad: 0.0 }
    }

    /// Gives every move between dwells an error of `rad` per axis beyond white rate noise, in quadrature
    /// (hand moves: docs/method.md#moves); a labelled turn keeps its own. Negative or not finite: 0.
    pub fn set_move_error_rad(&mut self, rad: f32) {
        self.move_error_rad = if rad.is_finite() && rad > 0.0 { rad } else { 0.0 };
    }

    /// The error of a move beyond white rate noise, rad per axis ([`ChannelEstimator::set_move_error_rad`]).
    pub fn move_error_rad(&self) -> f32 {
        self.move_error_rad
    }

    /// The settings.
    pub fn settings(&self) -> &ChannelSettings {
        &self.settings
    }

    /// Dwells added.
    pub fn dwells(&self) -> &[ChannelDwell] {
        &self.dwells
    }

    /// Adds a dwell.
    pub fn add(&mut self, dwell: ChannelDwell) -> Result<(), ChannelError> {
        let index = self.dwells.len();
        let finite = |v: Vec3| v.iter().all(|x| x.is_finite());
        let positive = |v: Vec3| v.iter().all(|x| x.is_finite() && *x > 0.0);
        let gyro_ok =
            !self.settings.use_gyro || (finite(dwell.rate_mean_b_radps) && positive(dwell.rate_mean_var_b_radps2));
        let heading_ok = dwell.heading_rad.is_none_or(|h| h.is_finite());
        let tilt_ok = self.settings.attitude == AttitudeKnowledge::Unknown || dwell.tilt.is_finite();
        if !(gyro_ok
            && heading_ok
            && tilt_ok
            && finite(dwell.force_mean_b_mps2)
            && positive(dwell.force_mean_var_b_mps2sq))
        {
            return Err(ChannelError::BadInput { dwell: index });
        }
        self.dwells.push(dwell).map_err(|_| ChannelError::TooManyDwells)
    }

    pub(super) fn model(&self) -> Model {
        if self.settings.use_gyro {
            self.settings.model
        } else {
            self.settings.model.accelerometer_only()
        }
    }

    /// The checks before any fit: |f| against g, and the direction of measured gravity against the reference
    /// (when the attitudes are a reference).
    pub(super) fn check_plausible(&self) -> Result<(), ChannelError> {
        let g = self.site.gravity_mps2;
        for (dwell, d) in self.dwells.iter().enumerate() {
            let f = d.force_mean_b_mps2;
            let ratio = norm(f) / g;
            // NaN fails the test too.
            let within = (ratio - 1.0).abs() <= self.settings.force_magnitude_error_max_relative;
            if !within {
                return Err(ChannelError::ForceMagnitude { dwell, ratio });
            }
            if self.settings.attitude == AttitudeKnowledge::Unknown {
                continue;
            }
            let up_b = d.tilt.transpose().mul_vec([0.0, 0.0, 1.0]);
            let cos = (dot(f, up_b) / norm(f)).clamp(-1.0, 1.0);
            let angle_rad = libm::acosf(cos);
            let within = angle_rad <= self.settings.pose_gravity_angle_max_rad;
            if !within {
                return Err(ChannelError::GravityDirection { dwell, angle_rad });
            }
        }
        Ok(())
    }

    /// Solves with every dwell, after the plausibility checks; a dwell whose residuals fit a heading a quarter
    /// or half turn from its reference heading is refused.
    pub fn solve(&self) -> Result<ChannelSolution, ChannelError> {
        self.solve_with(&[])
    }

    /// [`ChannelEstimator::solve`] with the moves between dwells as observations of the gyro terms as well
    /// (docs/method.md#moves).
    pub fn solve_with(&self, moves: &[ChannelMove]) -> Result<ChannelSolution, ChannelError> {
        self.check_plausible()?;
        let solution = self.solve_excluding_with(0, moves)?;
        // A model of which the schedule determines no term at all is no calibration (one static pose with every
        // term: each is confounded with another).
        if (0..PARAMETERS).all(|p| solution.estimate(p).is_none()) {
            return Err(ChannelError::NothingToEstimate);
        }
        self.check_headings(&solution, moves)?;
        Ok(solution)
    }

    /// Each move joins two dwells that were added, and its numbers are finite.
    pub(super) fn check_moves(&self, moves: &[ChannelMove]) -> Result<(), ChannelError> {
        if moves.len() > MAX_MOVES {
            return Err(ChannelError::TooManyMoves);
        }
        for (index, m) in moves.iter().enumerate() {
            let finite = m.rotation.0.iter().all(|x| x.is_finite())
                && m.duration_s.is_finite()
                && m.duration_s > 0.0
                && m.jacobian.iter().flatten().all(|x| x.is_finite())
                && m.prior_si.iter().all(|x| x.is_finite())
                && m.covariance_rad2.is_finite();
            let ends = match m.turn {
                Some(t) => {
                    let up = t.up_b;
                    let finite = up.iter().chain(&t.angle_b_rad).chain(&t.angle_sum_b_rad).all(|x| x.is_finite());
                    finite && (norm(up) - 1.0).abs() < 1e-3
                }
                None => m.from < self.dwells.len() && m.to < self.dwells.len(),
            };
            if !ends || !finite {
                return Err(ChannelError::BadMove { index });
            }
        }
        Ok(())
    }

    /// Suspect dwells with a known heading and tilt: refit without the dwell and test whether its gyro means
    /// fit a heading 90, 180 or 270 deg off far better than the reference's.
    pub(super) fn check_headings(&self, solution: &ChannelSolution, moves: &[ChannelMove]) -> Result<(), ChannelError> {
        let unknown_tilt = self.settings.attitude == AttitudeKnowledge::Unknown;
        if !self.settings.use_gyro || !self.settings.earth_rate_resolved || unknown_tilt || solution.suspect == 0 {
            return Ok(());
        }
        for (k, d) in self.dwells.iter().enumerate() {
            let Some(given) = d.heading_rad else { continue };
            if solution.suspect & (1 << k) == 0 {
                continue;
            }
            let without = self.solve_excluding_with(1 << k, moves)?;
            let cost = |heading: f32| self.heading_cost(d, &d.tilt, &without.parameters_si, heading, without.model);
            let at_given = cost(given);
            for quarter in 1..4 {
                let other = given + quarter as f32 * core::f32::consts::FRAC_PI_2;
                let c = cost(other);
                if c < CHI2_999[2] && at_given > CHI2_999[2] && c < 0.1 * at_given {
                    return Err(ChannelError::HeadingMismatch { dwell: k, given_rad: given, fits_rad: other });
                }
            }
        }
        Ok(())
    }

    /// Solves without the dwells marked in `exclude` (bit k = dwell k); no plausibility checks.
    pub fn solve_excluding(&self, exclude: u64) -> Result<ChannelSolution, ChannelError> {
        self.solve_excluding_with(exclude, &[])
    }

    /// [`ChannelEstimator::solve_excluding`] with moves; a move to or from a dwell left out is left out too.
    pub fn solve_excluding_with(&self, exclude: u64, moves: &[ChannelMove]) -> Result<ChannelSolution, ChannelError> {
        if self.dwells.is_empty() {
            return Err(ChannelError::NoDwells);
        }
        // Each move's dwells exist (an index beyond them would otherwise panic in its rows).
        self.check_moves(moves)?;
        let model = self.model();
        let (cols, n) = columns(model);
        if n == 0 {
            return Err(ChannelError::NothingToEstimate);
        }
        let used = |k: usize| exclude & (1u64 << k) == 0;
        let unknown_tilt = self.settings.attitude == AttitudeKnowledge::Unknown;
        let mut theta = [0.0f32; PARAMETERS];
        let mut heading = [0.0f32; MAX_DWELLS];
        let mut attitude = [Mat3::IDENTITY; MAX_DWELLS];
        for (k, d) in self.dwells.iter().enumerate() {
            heading[k] = d.heading_rad.unwrap_or(0.0);
            attitude[k] = heading_rotation(heading[k]).mul(&d.tilt);
        }
        let mut pass = Pass::default();
        let rounding = self.rounding_ratio();
        let mut iterations = 0;
        let mut converged = false;
        let mut previous = f32::INFINITY;
        let mut refused = 0u64;
        while iterations < self.settings.max_iterations.max(1) {
            iterations += 1;
            // Every dwell's nuisance angles, the left-out ones too (their residuals are reported).
            for (k, d) in self.dwells.iter().enumerate() {
                if unknown_tilt || self.priors(d) != [false; 3] {
                    (attitude[k], heading[k]) = self.profile_attitude(d, &theta, model);
                } else if self.nuisances(d)[2] {
                    heading[k] = self.profile_heading(d, &d.tilt, &theta, model);
                    attitude[k] = heading_rotation(heading[k]).mul(&d.tilt);
                }
            }
            if iterations == 1 {
                refused = self.gross_misfits(moves, &attitude);
            }
            pass = self.pass(&theta, &attitude, &cols, n, used, UsedMoves { all: moves, refused });
            let mut largest = 0.0f32;
            for c in 0..n {
                let p = cols[c];
                let step = pass.step_si[c];
                theta[p] += step;
                let std = libm::sqrtf(pass.cov_scaled[c][c].max(0.0)) * pass.scale[c];
                if std > 0.0 {
                    largest = largest.max(step.abs() / std);
                }
            }
            // Converged when the step is negligible against the standard errors, or when it has stopped
            // shrinking at a small level (the rounding of f32 on data far more precise than its errors). Both
            // levels are raised where the dwell means are more precise than the arithmetic's rounding.
            if largest < 1e-3 * rounding || (largest < 0.05 * rounding && largest > 0.5 * previous) {
                converged = true;
                break;
            }
            previous = largest;
        }
        // A fit that did not converge and left every instrument's range ran away: refused. (A converged fit
        // keeps its estimate, however imprecise: its standard error says so.)
        if let Some(parameter) = implausible_parameter(&theta).filter(|_| !converged) {
            return Err(ChannelError::Diverged { parameter, value: theta[parameter] });
        }
        let state = State { theta: &theta, heading: &heading, attitude: &attitude, cols: &cols, n, model, refused };
        Ok(self.finish(&state, &pass, used, iterations, converged, moves))
    }

    /// How many times the f32 rounding of the fit's arithmetic ([`ROUNDING_ULPS`] units of f32 rounding of
    /// gravity and of the Earth rate, the magnitudes its residuals are computed from) exceeds the smallest
    /// standard deviation of a dwell mean (of its accelerometers, and of its gyros when they are used); 1 when
    /// it does not. A step of the fit cannot shrink
    /// below that rounding: measured on a noise-free SIMULATION of the paper's six positions, whose dwell
    /// means are as precise as f32 holds them, the steps stalled at about one of their standard errors and
    /// the fit never converged (`sinscal calibrate`, exit 3).
    fn rounding_ratio(&self) -> f32 {
        let rounding = |magnitude: f32| ROUNDING_ULPS * f32::EPSILON * magnitude;
        let (rate_radps, force_mps2) = (rounding(EARTH_RATE_RADPS), rounding(self.site.gravity_mps2));
        let mut ratio = 1.0f32;
        for d in &self.dwells {
            for i in 0..3 {
                if self.settings.use_gyro {
                    ratio = ratio.max(rate_radps / libm::sqrtf(d.rate_mean_var_b_radps2[i].max(f32::MIN_POSITIVE)));
                }
                ratio = ratio.max(force_mps2 / libm::sqrtf(d.force_mean_var_b_mps2sq[i].max(f32::MIN_POSITIVE)));
            }
        }
        ratio
    }

    /// One Gauss-Newton pass at `theta` and the dwells' `attitude`: structural rank, weighted solution of the
    /// determined parameters and of a completion of the undetermined ones (see [`Pass::solved`]).
    pub(super) fn pass(
        &self,
        theta: &[f32; PARAMETERS],
        attitude: &[Mat3; MAX_DWELLS],
        cols: &[usize; PARAMETERS],
        n: usize,
        used: impl Fn(usize) -> bool,
        moves: UsedMoves<'_>,
    ) -> Pass {
        let design = Design { theta, attitude, cols, n };
        let (norm_w, mut norm_s, peak_s) = self.column_norms(&design, &used, moves);
        self.drop_unexercised(&design, &used, &peak_s, &mut norm_s);
        let mut scale = [1.0f32; PARAMETERS];
        let mut scale_s = [1.0f32; PARAMETERS];
        for c in 0..n {
            if norm_w[c] > 0.0 {
                scale[c] = 1.0 / libm::sqrtf(norm_w[c]);
            }
            if norm_s[c] > 0.0 {
                scale_s[c] = 1.0 / libm::sqrtf(norm_s[c]);
            } else {
                scale_s[c] = 0.0;
            }
        }
        let (weighted, structure) = self.factors(&design, &used, moves, &scale, &scale_s);
        let (determined, blind_spots, gauge) = self.structural_rank(&structure.r, cols, n);
        let solved = self.completion(&structure.r, &determined, &scale_s, gauge, cols, n);
        let pass = Pass { scale, determined, solved, blind_spots, gauge, ..Pass::default() };
        restricted_solution(pass, &weighted, n)
    }

    /// The moves a pass uses: with gyro data, those whose dwells are used and that are not gross misfits.
    fn moves_used<'m>(
        &self,
        used: &'m impl Fn(usize) -> bool,
        moves: UsedMoves<'m>,
    ) -> impl Iterator<Item = &'m ChannelMove> + 'm {
        let UsedMoves { all, refused } = moves;
        let use_gyro = self.settings.use_gyro;
        all.iter()
            .enumerate()
            .filter(move |(k, m)| use_gyro && move_used(m, used) && (*k >= 64 || refused & (1 << k) == 0))
            .map(|(_, m)| m)
    }

    /// Column norms of the weighted and the structural designs (for equilibration), and the largest entry of
    /// each column of the structural design.
    fn column_norms(
        &self,
        design: &Design<'_>,
        used: &impl Fn(usize) -> bool,
        moves: UsedMoves<'_>,
    ) -> ([f32; PARAMETERS], [f32; PARAMETERS], [f32; PARAMETERS]) {
        let Design { theta, attitude, cols, n } = *design;
        let model = self.model();
        let zero = [0.0f32; PARAMETERS];
        let ones = [1.0f32; PARAMETERS];
        let none = [false; 3];
        let mut norm_w = [0.0f32; PARAMETERS];
        let mut norm_s = [0.0f32; PARAMETERS];
        let mut peak_s = [0.0f32; PARAMETERS];
        let mut add = |w: &[[f32; PARAMETERS]], s: &[[f32; PARAMETERS]], rows: usize| {
            for c in 0..n {
                for r in 0..rows {
                    norm_w[c] += w[r][c] * w[r][c];
                    norm_s[c] += s[r][c] * s[r][c];
                    peak_s[c] = peak_s[c].max(s[r][c].abs());
                }
            }
        };
        for (k, d) in self.dwells.iter().enumerate().filter(|(k, _)| used(*k)) {
            let lin = self.linearise(theta, &attitude[k], model);
            let lin_s = self.linearise(&zero, &attitude[k], model);
            let w = self.rows(d, &lin, cols, n, &ones, false, none);
            let s = self.rows(d, &lin_s, cols, n, &ones, true, none);
            add(&w.a, &s.a, w.rows);
        }
        for m in self.moves_used(used, moves) {
            let w = self.move_rows(m, theta, attitude, cols, n, &ones, false);
            let s = self.move_rows(m, theta, attitude, cols, n, &ones, true);
            add(&w.a, &s.a, w.rows);
        }
        (norm_w, norm_s, peak_s)
    }

    /// The weighted and the structural square-root information factors of the used dwells (their nuisance
    /// angles eliminated) and moves, columns scaled by `scale` and `scale_s`.
    fn factors(
        &self,
        design: &Design<'_>,
        used: &impl Fn(usize) -> bool,
        moves: UsedMoves<'_>,
        scale: &[f32; PARAMETERS],
        scale_s: &[f32; PARAMETERS],
    ) -> (SqrtInfo<PARAMETERS>, SqrtInfo<PARAMETERS>) {
        let Design { theta, attitude, cols, n } = *design;
        let model = self.model();
        let zero = [0.0f32; PARAMETERS];
        let mut weighted = SqrtInfo::<PARAMETERS>::new(n);
        let mut structure = SqrtInfo::<PARAMETERS>::new(n);
        for (k, d) in self.dwells.iter().enumerate().filter(|(k, _)| used(*k)) {
            let lin = self.linearise(theta, &attitude[k], model);
            let lin_s = self.linearise(&zero, &attitude[k], model);
            let nuisance = self.nuisances(d);
            let mut w = self.rows(d, &lin, cols, n, scale, false, nuisance);
            self.add_prior_rows(d, &attitude[k], &mut w);
            // The schedule's structure: angles known to a tolerance are known (a prior is not the schedule).
            let prior = self.priors(d);
            let free = [0, 1, 2].map(|m| nuisance[m] && !prior[m]);
            let mut s = self.rows(d, &lin_s, cols, n, scale_s, true, free);
            let skip_w = eliminate_nuisances(&mut w, n);
            let skip_s = eliminate_nuisances(&mut s, n);
            for r in skip_w..w.rows {
                weighted.add_row(&w.a[r], w.y[r]);
            }
            for r in skip_s..s.rows {
                structure.add_row(&s.a[r], 0.0);
            }
        }
        for m in self.moves_used(used, moves) {
            let w = self.move_rows(m, theta, attitude, cols, n, scale, false);
            let s = self.move_rows(m, theta, attitude, cols, n, scale_s, true);
            for r in 0..w.rows {
                weighted.add_row(&w.a[r], w.y[r]);
                structure.add_row(&s.a[r], 0.0);
            }
        }
        (weighted, structure)
    }
}

/// The point a pass linearises at: the parameters, the dwells' attitudes and the model's columns.
#[derive(Clone, Copy)]
pub(super) struct Design<'a> {
    pub(super) theta: &'a [f32; PARAMETERS],
    pub(super) attitude: &'a [Mat3; MAX_DWELLS],
    pub(super) cols: &'a [usize; PARAMETERS],
    pub(super) n: usize,
}

/// The pass's step and covariance from the weighted factor restricted to the determined columns of `pass`
/// (triangularised again).
fn restricted_solution(mut pass: Pass, weighted: &SqrtInfo<PARAMETERS>, n: usize) -> Pass {
    let mut kept = [0usize; PARAMETERS];
    let mut m = 0;
    for (c, &d) in pass.solved.iter().enumerate().take(n) {
        if d {
            kept[m] = c;
            m += 1;
        }
    }
    let mut restricted = SqrtInfo::<PARAMETERS>::new(m);
    for i in 0..n {
        let mut row = [0.0f32; PARAMETERS];
        for (slot, &c) in row.iter_mut().zip(kept.iter()).take(m) {
            *slot = weighted.r[i][c];
        }
        restricted.add_row(&row, weighted.z[i]);
    }
    let x = solve_upper(&restricted.r, &restricted.z, m);
    let mut cov_kept = [[0.0f32; PARAMETERS]; PARAMETERS];
    inverse_gram(&restricted.r, m, &mut cov_kept);
    for (i, &ci) in kept.iter().enumerate().take(m) {
        pass.step_si[ci] = x[i] * pass.scale[ci];
        for (j, &cj) in kept.iter().enumerate().take(m) {
            pass.cov_scaled[ci][cj] = cov_kept[i][j];
        }
    }
    pass.restricted = restricted.r;
    pass.kept = kept;
    pass.kept_count = m;
    pass
}

/// The moves of a pass: all of them, and those left out as gross misfits (bit k: move k).
#[derive(Clone, Copy)]
pub(super) struct UsedMoves<'a> {
    pub(super) all: &'a [ChannelMove],
    pub(super) refused: u64,
}

/// The state of one solve that [`ChannelEstimator::finish`] reports.
#[derive(Clone, Copy)]
pub(super) struct State<'a> {
    pub(super) theta: &'a [f32; PARAMETERS],
    pub(super) heading: &'a [f32; MAX_DWELLS],
    pub(super) attitude: &'a [Mat3; MAX_DWELLS],
    pub(super) cols: &'a [usize; PARAMETERS],
    pub(super) n: usize,
    pub(super) model: Model,
    /// Moves left out as gross misfits (bit k: move k).
    pub(super) refused: u64,
}

/// What one Gauss-Newton pass leaves for the next and for the final statistics.
pub(super) struct Pass {
    /// The step, SI units, by model column.
    pub(super) step_si: [f32; PARAMETERS],
    /// Covariance of the equilibrated parameters, by model column.
    pub(super) cov_scaled: [[f32; PARAMETERS]; PARAMETERS],
    /// The equilibration, by model column: the design's columns are multiplied by it, so it is also the SI
    /// units per equilibrated unit of each parameter.
    pub(super) scale: [f32; PARAMETERS],
    /// Whether each model column is determined by the schedule.
    pub(super) determined: [bool; PARAMETERS],
    /// Whether each model column is solved for: the determined ones, and a completion of the undetermined ones
    /// that the schedule sees in combination (a vertical accelerometer's bias and scale factor from one pose:
    /// their sum is seen, neither alone). The completion carries that combination, so that it is fitted and not
    /// left in the residuals as a misfit; its parameters stay unobservable (never reported, never compensated).
    pub(super) solved: [bool; PARAMETERS],
    /// The weighted factor of the solved columns.
    pub(super) restricted: [[f32; PARAMETERS]; PARAMETERS],
    /// Model columns of the solved parameters, and their number.
    pub(super) kept: [usize; PARAMETERS],
    pub(super) kept_count: usize,
    /// Blind spots of the structural design before the gauge, and the gauge's parameter bits.
    pub(super) blind_spots: u32,
    pub(super) gauge: u64,
}

impl Default for Pass {
    fn default() -> Pass {
        Pass {
            step_si: [0.0; PARAMETERS],
            cov_scaled: [[0.0; PARAMETERS]; PARAMETERS],
            scale: [0.0; PARAMETERS],
            determined: [false; PARAMETERS],
            solved: [false; PARAMETERS],
            restricted: [[0.0; PARAMETERS]; PARAMETERS],
            kept: [0; PARAMETERS],
            kept_count: 0,
            blind_spots: 0,
            gauge: 0,
        }
    }
}
