//! The rows of a move between dwells (docs/method.md#moves): its rotation against the reference's, whitened
//! by its covariance, or structural.

use crate::calib::general::estimator::{ChannelEstimator, MAX_DWELLS};
use crate::calib::general::nuisance::tilt_of_up;
use crate::calib::general::settings::AttitudeKnowledge;
use crate::calib::general::solution::ChannelSolution;
use crate::calib::general::terms::{columns, PARAMETERS};
use crate::calib::moves::{move_column, swing_about, ChannelMove, MAX_MOVES, MAX_MOVE_MISFIT_RAD, MOVE_PARAMETERS};
use crate::math::linalg::{cholesky3, cross, dot, norm, rotation, Mat3, Vec3};
use crate::nav::earth::EARTH_RATE_RADPS;
use crate::nav::frames::heading_rotation;
use crate::nav::strapdown::Quat;

impl ChannelEstimator {
    /// The moves whose rotation at their prior is further than [`MAX_MOVE_MISFIT_RAD`] from the reference's at
    /// the dwells' `attitude` (bit k: move k).
    pub(super) fn gross_misfits(&self, moves: &[ChannelMove], attitude: &[Mat3; MAX_DWELLS]) -> u64 {
        let mut refused = 0u64;
        for (k, m) in moves.iter().enumerate().take(MAX_MOVES) {
            if m.turn.is_some() || m.from >= self.dwells.len() || m.to >= self.dwells.len() {
                continue;
            }
            let e = self.rotation_misfit(m, attitude).e_rad;
            // NaN is refused too.
            if norm(e).is_nan() || norm(e) > MAX_MOVE_MISFIT_RAD {
                refused |= 1 << k;
            }
        }
        refused
    }

    /// The rotation error of each of `moves` (at most [`MAX_MOVES`]) at the parameters `parameters_si`, with the
    /// dwells' attitudes of `solution` (body frame at the start of each move, rad; without the part about up
    /// when a heading at either end is unknown): moves held out of the fit, checked against a calibration.
    pub fn move_residuals(
        &self,
        parameters_si: &[f32; PARAMETERS],
        solution: &ChannelSolution,
        moves: &[ChannelMove],
    ) -> [Vec3; MAX_MOVES] {
        let mut attitude = [Mat3::IDENTITY; MAX_DWELLS];
        for (k, d) in self.dwells.iter().enumerate() {
            let tilt = if self.settings.attitude == AttitudeKnowledge::Unknown {
                tilt_of_up(solution.up_b[k])
            } else {
                d.tilt
            };
            attitude[k] = heading_rotation(solution.heading_rad[k]).mul(&tilt);
        }
        let (cols, n) = columns(solution.model);
        let ones = [1.0f32; PARAMETERS];
        let mut out = [[0.0f32; 3]; MAX_MOVES];
        for (slot, m) in out.iter_mut().zip(moves) {
            *slot = self.move_rows(m, parameters_si, &attitude, &cols, n, &ones, false).residual_rad;
        }
        out
    }

    /// The rotation error of a move between two dwells at its prior (start frame, rad), the basis of its rows
    /// (three, or two without the part about up when a heading at either end is unknown), the number of rows,
    /// and whether the horizontal Earth rate's direction is unknown.
    pub(super) fn rotation_misfit(&self, m: &ChannelMove, attitude: &[Mat3; MAX_DWELLS]) -> Misfit {
        let w_n = self.site.earth_rate_n_radps();
        let (c_from, c_to) = (attitude[m.from], attitude[m.to]);
        // The body's rotation relative to inertial space: the navigation frame turns with the Earth.
        let earth = rotation(w_n.map(|w| w * m.duration_s));
        let (from, to) = (&self.dwells[m.from], &self.dwells[m.to]);
        let unresolved = [from, to].iter().any(|d| d.heading_rad.is_none() && !self.nuisances(d)[2]);
        let twist_free = from.heading_rad.is_none() || to.heading_rad.is_none();
        let reference = c_from.transpose().mul(&earth).mul(&c_to);
        let up = c_from.row(2);
        let q_ref = Quat::from_mat3(&reference);
        let misfit = m.rotation.mul(&q_ref.conjugate());
        if twist_free {
            // Two directions at right angles to up.
            let helper = if up[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
            let b1 = cross(up, helper);
            let b1 = b1.map(|x| x / norm(b1));
            let (swing, twist) = swing_about(&misfit, up);
            let basis = [b1, cross(up, b1), [0.0; 3]];
            // A change of the move's rotation (start frame) reaches the swing turned back by the twist.
            let frame = twist.conjugate().to_mat3();
            Misfit { e_rad: swing.to_rotation_vector(), basis, rows: 2, unresolved, frame }
        } else {
            Misfit {
                e_rad: misfit.to_rotation_vector(),
                basis: IDENTITY_BASIS,
                rows: 3,
                unresolved,
                frame: Mat3::IDENTITY,
            }
        }
    }

    /// The rows of one move at `theta` and the dwells' `attitude`: whitened by its covariance, or, `structural`,
    /// in units of the Earth rate over the move with entries below 1e-6 of it set to zero; model columns `cols`
    /// scaled by `scale`. Without a heading at either end the part about up at the start is left out (two
    /// rows): the reference does not say how far the body turned about the vertical.
    #[allow(clippy::too_many_arguments, reason = "the same arguments as the dwells' rows")]
    pub(super) fn move_rows(
        &self,
        m: &ChannelMove,
        theta: &[f32; PARAMETERS],
        attitude: &[Mat3; MAX_DWELLS],
        cols: &[usize; PARAMETERS],
        n: usize,
        scale: &[f32; PARAMETERS],
        structural: bool,
    ) -> MoveRows {
        let w_n = self.site.earth_rate_n_radps();
        let Misfit { e_rad: misfit, basis, rows, unresolved, frame } = match m.turn {
            // The integral of the rate against the turns made and the Earth's rotation about up (its horizontal
            // part turns with the body and is added as noise below).
            Some(t) => {
                let vertical = w_n[2] * m.duration_s;
                let e_rad = [0, 1, 2].map(|i| t.angle_sum_b_rad[i] - t.angle_b_rad[i] - t.up_b[i] * vertical);
                Misfit { e_rad, basis: IDENTITY_BASIS, rows: 3, unresolved: true, frame: Mat3::IDENTITY }
            }
            None => self.rotation_misfit(m, attitude),
        };
        // The Jacobian in the residual's frame.
        let mut jacobian = [[0.0f32; MOVE_PARAMETERS.len()]; 3];
        for (c, _) in MOVE_PARAMETERS.iter().enumerate() {
            let column = frame.mul_vec([m.jacobian[0][c], m.jacobian[1][c], m.jacobian[2][c]]);
            for a in 0..3 {
                jacobian[a][c] = column[a];
            }
        }
        // The error at theta: the prior's plus the linear change since the prior.
        let mut e = misfit;
        for (c, &p) in MOVE_PARAMETERS.iter().enumerate() {
            let delta = theta[p] - m.prior_si[c];
            for (a, slot) in e.iter_mut().enumerate() {
                *slot += jacobian[a][c] * delta;
            }
        }
        // The covariance in the basis; an unknown heading also leaves the horizontal Earth rate's direction
        // unknown when it is not estimated: its angle over the move is added as noise.
        let mut cov = frame.mul(&m.covariance_rad2).mul(&frame.transpose());
        if m.turn.is_none() {
            for i in 0..3 {
                cov.0[i][i] += self.move_error_rad * self.move_error_rad;
            }
        }
        if unresolved {
            let horizontal = self.site.earth_rate_north_radps() * m.duration_s;
            for i in 0..3 {
                cov.0[i][i] += horizontal * horizontal;
            }
        }
        let mut out = MoveRows { a: [[0.0; PARAMETERS]; 3], y: [0.0; 3], rows, residual_rad: e };
        let unit = if structural { 1.0 / (EARTH_RATE_RADPS * m.duration_s) } else { 1.0 };
        for (r, b) in basis.iter().enumerate().take(rows) {
            out.y[r] = if structural { 0.0 } else { -dot(*b, e) };
            for (c, &p) in cols.iter().enumerate().take(n) {
                let Some(mc) = move_column(p) else { continue };
                let x = (0..3).map(|k| b[k] * jacobian[k][mc]).sum::<f32>() * unit;
                out.a[r][c] = if structural && x.abs() < 1e-6 { 0.0 } else { x * scale[c] };
            }
        }
        if structural {
            return out;
        }
        // Whitening: rows times the inverse of the Cholesky factor of B cov B^T.
        let mut s = [[0.0f32; 3]; 3];
        for i in 0..rows {
            for j in 0..rows {
                s[i][j] = dot(basis[i], cov.mul_vec(basis[j]));
            }
        }
        let Some(l) = cholesky3(&s, rows) else {
            out.rows = 0;
            return out;
        };
        for c in 0..n + 1 {
            // Forward substitution on column c (c == n: the right-hand side).
            let mut x = [0.0f32; 3];
            for i in 0..rows {
                let mut v = if c < n { out.a[i][c] } else { out.y[i] };
                for (j, xj) in x.iter().enumerate().take(i) {
                    v -= l[i][j] * xj;
                }
                x[i] = v / l[i][i];
            }
            for (i, xi) in x.iter().enumerate().take(rows) {
                if c < n {
                    out.a[i][c] = *xi;
                } else {
                    out.y[i] = *xi;
                }
            }
        }
        out
    }
}

/// The rows of x, y and z.
pub(super) const IDENTITY_BASIS: [Vec3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A move's error at its prior, in the frame of its residual.
pub(super) struct Misfit {
    /// The error, rad.
    pub(super) e_rad: Vec3,
    /// The directions of its rows (the first `rows`).
    pub(super) basis: [Vec3; 3],
    pub(super) rows: usize,
    /// Whether the horizontal Earth rate's direction over the move is unknown.
    pub(super) unresolved: bool,
    /// From a change of the move's rotation (start frame) to the residual's frame.
    pub(super) frame: Mat3,
}

/// Whether a move is used when the dwells `used` are: a closed move always, another when both its dwells are.
pub(super) fn move_used(m: &ChannelMove, used: &impl Fn(usize) -> bool) -> bool {
    m.turn.is_some() || (used(m.from) && used(m.to))
}

/// The rows of one move (up to three), its residual and its number of rows.
pub(super) struct MoveRows {
    pub(super) a: [[f32; PARAMETERS]; 3],
    pub(super) y: [f32; 3],
    pub(super) rows: usize,
    /// The rotation error at the parameters, start frame, rad.
    pub(super) residual_rad: Vec3,
}
