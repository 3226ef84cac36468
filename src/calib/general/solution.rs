//! The solution ([`ChannelSolution`]): parameters, covariance, observability, the dwells' headings and
//! residuals, the moves' residuals and the fit's statistics, and how a solve fills it in.

use crate::calib::general::estimator::{ChannelEstimator, Pass, State, CHI2_999, MAX_DWELLS};
use crate::calib::general::move_rows::move_used;
use crate::calib::general::nuisance::eliminate_nuisances;
use crate::calib::general::settings::AttitudeKnowledge;
use crate::calib::general::terms::{Model, PARAMETERS};
use crate::calib::moves::{ChannelMove, MAX_MOVES};
use crate::math::linalg::Vec3;
use crate::math::lsq::solve_upper_transposed;

/// The solution.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSolution {
    /// The model estimated (without gyro terms when there were no gyro data).
    pub model: Model,
    /// Every parameter, SI units, in the order of [`parameter_name`](crate::calib::general::parameter_name); 0 for those not estimated.
    pub parameters_si: [f32; PARAMETERS],
    /// Bit i: parameter i is in the model and determined by the schedule.
    pub observable: u64,
    /// Bit i: parameter i is in the model and the schedule cannot determine it.
    pub unobservable: u64,
    /// Bit i: parameter i is unobservable but was solved for as part of the completion that carries what the
    /// schedule sees of the undetermined parameters together (never reported, never compensated).
    pub completion: u64,
    /// Covariance of the determined parameters, SI units; rows and columns of the others are zero.
    pub covariance_si: [[f32; PARAMETERS]; PARAMETERS],
    /// Number of dwells.
    pub dwells: usize,
    /// Heading of every dwell, rad: the reference's, or the estimate for unknown headings.
    pub heading_rad: [f32; MAX_DWELLS],
    /// Standard error of an estimated heading (given the sensor terms), rad; 0 for a given heading.
    pub heading_std_rad: [f32; MAX_DWELLS],
    /// Measured minus predicted gyro mean per dwell, rad/s.
    pub residual_rate_b_radps: [Vec3; MAX_DWELLS],
    /// Measured minus predicted accelerometer mean per dwell, m/s^2.
    pub residual_force_b_mps2: [Vec3; MAX_DWELLS],
    /// Per dwell: its whitened residual sum of squares scaled to the dwell's channel count by its degrees of
    /// freedom left after the fit (a chi-square of that many degrees of freedom when the model holds), or a
    /// negative value when the dwell has no freedom left to test.
    pub dwell_statistic: [f32; MAX_DWELLS],
    /// Bit k: dwell k's residuals exceed the 0.1 % level of that chi-square.
    pub suspect: u64,
    /// Sum of the squared whitened residuals.
    pub chi_square: f32,
    /// Residual degrees of freedom: channel means, less determined parameters, less estimated headings.
    pub degrees_of_freedom: u32,
    /// Gauss-Newton passes made.
    pub iterations: u32,
    /// Whether the last correction was below 1e-3 of every standard error, or stopped shrinking below 0.05 of
    /// them (f32 rounding).
    pub converged: bool,
    /// The attitude knowledge the solution assumed.
    pub attitude: AttitudeKnowledge,
    /// Whether the gyro model included the Earth rate ([`ChannelSettings::earth_rate_resolved`](crate::calib::general::ChannelSettings::earth_rate_resolved)).
    pub earth_rate_resolved: bool,
    /// Up (the direction of measured gravity) in the body of every dwell, a unit vector: the reference's, or
    /// the estimate when the attitudes are unknown.
    pub up_b: [Vec3; MAX_DWELLS],
    /// Number of blind spots of the structural design (singular values below the rank tolerance) before the
    /// body frame is fixed: three more than with reference attitudes when a common rotation of the poses is
    /// invisible.
    pub blind_spots: u32,
    /// Bit i: parameter i is held at zero to fix the body frame ([`GAUGE_PARAMETERS`](crate::calib::general::GAUGE_PARAMETERS)); it is also in
    /// `unobservable`, and the other parameters are estimated in that frame.
    pub gauge: u64,
    /// Moves used (docs/method.md#moves), in the order given.
    pub moves: usize,
    /// Per move: the rotation the calibrated gyros measured less the reference rotation, body frame at the
    /// start of the move, rad (without the part about up when a heading at either end is unknown).
    pub move_residual_rad: [Vec3; MAX_MOVES],
    /// Per move: its whitened residual sum of squares (a chi-square of [`ChannelSolution::move_rows`] degrees
    /// of freedom when the model holds); negative for a move left out.
    pub move_statistic: [f32; MAX_MOVES],
    /// Per move: its rows in the fit (3, or 2 without the part about up; 0 for a move left out).
    pub move_rows: [u8; MAX_MOVES],
    /// Bit k: move k was left out because its rotation at the start was further than
    /// [`crate::calib::moves::MAX_MOVE_MISFIT_RAD`] from the reference's.
    pub moves_refused: u64,
}

impl ChannelSolution {
    /// A solution of `model` over `dwells` dwells with nothing in it yet: every parameter, residual and
    /// statistic zero (the dwells' and moves' statistics -1: none), reference attitudes, the Earth rate resolved.
    pub fn empty(model: Model, dwells: usize) -> ChannelSolution {
        ChannelSolution {
            model,
            parameters_si: [0.0; PARAMETERS],
            observable: 0,
            unobservable: 0,
            completion: 0,
            covariance_si: [[0.0; PARAMETERS]; PARAMETERS],
            dwells,
            heading_rad: [0.0; MAX_DWELLS],
            heading_std_rad: [0.0; MAX_DWELLS],
            residual_rate_b_radps: [[0.0; 3]; MAX_DWELLS],
            residual_force_b_mps2: [[0.0; 3]; MAX_DWELLS],
            dwell_statistic: [-1.0; MAX_DWELLS],
            suspect: 0,
            chi_square: 0.0,
            degrees_of_freedom: 0,
            iterations: 0,
            converged: false,
            attitude: AttitudeKnowledge::Reference,
            earth_rate_resolved: true,
            up_b: [[0.0; 3]; MAX_DWELLS],
            blind_spots: 0,
            gauge: 0,
            moves: 0,
            move_residual_rad: [[0.0; 3]; MAX_MOVES],
            move_statistic: [-1.0; MAX_MOVES],
            move_rows: [0; MAX_MOVES],
            moves_refused: 0,
        }
    }

    /// Value and standard error of parameter `index`, or `None` when it is not in the model or undetermined.
    pub fn estimate(&self, index: usize) -> Option<(f32, f32)> {
        if index < PARAMETERS && self.observable & (1 << index) != 0 {
            Some((self.parameters_si[index], libm::sqrtf(self.covariance_si[index][index].max(0.0))))
        } else {
            None
        }
    }
}

impl ChannelEstimator {
    pub(super) fn finish(
        &self,
        state: &State<'_>,
        pass: &Pass,
        used: impl Fn(usize) -> bool,
        iterations: u32,
        converged: bool,
        moves: &[ChannelMove],
    ) -> ChannelSolution {
        let State { theta, heading, attitude, cols, n, model, .. } = *state;
        let mut sol = ChannelSolution::empty(model, self.dwells.len());
        sol.heading_rad = *heading;
        sol.iterations = iterations;
        sol.converged = converged;
        sol.attitude = self.settings.attitude;
        sol.earth_rate_resolved = self.settings.earth_rate_resolved;
        sol.blind_spots = pass.blind_spots;
        sol.gauge = pass.gauge;
        sol.moves_refused = state.refused;
        let correlation = self.correlation_term(state, pass, &used);
        for c in 0..n {
            let p = cols[c];
            if pass.determined[c] {
                sol.observable |= 1 << p;
                sol.parameters_si[p] = theta[p];
                for d in 0..n {
                    if pass.determined[d] {
                        let extra = correlation.as_ref().map_or(0.0, |e| e[c][d]);
                        sol.covariance_si[p][cols[d]] = (pass.cov_scaled[c][d] + extra) * pass.scale[c] * pass.scale[d];
                    }
                }
            } else {
                sol.unobservable |= 1 << p;
                if pass.solved[c] {
                    sol.completion |= 1 << p;
                }
            }
        }
        let first = if self.settings.use_gyro { 0 } else { 3 };
        let mut channels = 0u32;
        let mut nuisances = 0u32;
        for (k, d) in self.dwells.iter().enumerate() {
            sol.up_b[k] = attitude[k].row(2);
            let lin = self.linearise(theta, &attitude[k], model);
            let nuisance = self.nuisances(d);
            let mut rows = self.rows(d, &lin, cols, n, &pass.scale, false, nuisance);
            self.add_prior_rows(d, &attitude[k], &mut rows);
            for i in 0..3 {
                sol.residual_rate_b_radps[k][i] = if first == 0 { d.rate_mean_b_radps[i] - lin.pred[i] } else { 0.0 };
                sol.residual_force_b_mps2[k][i] = d.force_mean_b_mps2[i] - lin.pred[3 + i];
            }
            if !used(k) {
                continue;
            }
            let h_norm2: f32 = rows.h[..rows.rows].iter().map(|h| h[2] * h[2]).sum();
            if nuisance[2] && h_norm2 > 0.0 {
                sol.heading_std_rad[k] = 1.0 / libm::sqrtf(h_norm2);
            }
            // The dwell's own freedom: its nuisance angles take one row each (the residuals are at the
            // profiled optimum, so the reflection leaves the residual sum of squares unchanged).
            let skip = eliminate_nuisances(&mut rows, n);
            // Leverage of the dwell's remaining rows: h = |R^-T a|^2 over the determined columns.
            let mut chi2 = 0.0f32;
            let mut leverage = skip as f32;
            for r in 0..rows.rows {
                chi2 += rows.y[r] * rows.y[r];
                if r < skip {
                    continue;
                }
                let mut a = [0.0f32; PARAMETERS];
                for (slot, &c) in a.iter_mut().zip(pass.kept.iter()).take(pass.kept_count) {
                    *slot = rows.a[r][c];
                }
                let b = solve_upper_transposed(&pass.restricted, &a, pass.kept_count);
                leverage += b.iter().take(pass.kept_count).map(|x| x * x).sum::<f32>();
            }
            nuisances += skip as u32;
            channels += rows.rows as u32;
            sol.chi_square += chi2;
            let free = rows.rows as f32 - leverage;
            if free >= 0.5 {
                let statistic = chi2 * rows.rows as f32 / free;
                sol.dwell_statistic[k] = statistic;
                if statistic > CHI2_999[rows.rows - 1] {
                    sol.suspect |= 1 << k;
                }
            }
        }
        if self.settings.use_gyro {
            channels += self.finish_moves(&mut sol, state, pass, &used, moves);
        }
        sol.degrees_of_freedom = channels.saturating_sub(pass.kept_count as u32 + nuisances);
        sol
    }

    /// Each move's residual, and the statistics of those used: their chi-square is added to the solution's;
    /// returns their rows.
    pub(super) fn finish_moves(
        &self,
        sol: &mut ChannelSolution,
        state: &State<'_>,
        pass: &Pass,
        used: &impl Fn(usize) -> bool,
        moves: &[ChannelMove],
    ) -> u32 {
        let State { theta, attitude, cols, n, refused, .. } = *state;
        let mut channels = 0;
        for (k, m) in moves.iter().enumerate().take(MAX_MOVES) {
            let rows = self.move_rows(m, theta, attitude, cols, n, &pass.scale, false);
            sol.move_residual_rad[k] = rows.residual_rad;
            sol.moves += 1;
            if !move_used(m, used) || refused & (1 << k) != 0 {
                continue;
            }
            let chi2: f32 = rows.y[..rows.rows].iter().map(|y| y * y).sum();
            sol.move_statistic[k] = chi2;
            sol.move_rows[k] = rows.rows as u8;
            sol.chi_square += chi2;
            channels += rows.rows as u32;
        }
        channels
    }
}
