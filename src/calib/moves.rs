//! A move between two dwells as an observation of the gyro terms (docs/method.md#moves): the rotation the gyros
//! measure over it, integrated with the coning-corrected update of [`crate::nav::strapdown`], and its first-order
//! sensitivity to every gyro parameter, accumulated sample by sample so that nothing of the move is stored.
//!
//! The rates are compensated with a prior calibration `theta_0` before they are integrated (the inverse sensor
//! model of docs/conventions.md#sensor-model: `w = T_g^-1 (w_meas - b_g - G f)`). A change of the parameters
//! changes each sample's angle increment by `delta d_k = -P e_i (...)`, `P = T_g0^-1`, and the move's rotation, to
//! first order, by `delta rho = sum_k C_k delta d_k` in the body frame at the start of the move, where `C_k` is the
//! body's attitude at the middle of sample k relative to the start. The sums kept are therefore
//!   `sum C_k dt`, `sum C_k d_k,j` (j = x, y, z) and `sum C_k f_k,j dt`,
//! nine numbers each, from which the Jacobian of the rotation with respect to the gyro bias (3), scale factors
//! (3), misalignments (6) and g-sensitivity (9) follows at the end (`P` applied once). The white-noise covariance
//! of the rotation is `sum_i var_i sum_k (C_k e_i)(C_k e_i)^T dt^2` for a per-sample rate variance `var_i`.
//!
//! The model is linear about the prior; its error is second order in the change from the prior (for a rotation
//! about a sensor axis, a scale factor change is exact). The host integrates the moves again with each new
//! estimate until the estimate stops changing (docs/method.md#moves).
//!
//! Memory: 348 bytes per move being integrated; a finished move ([`ChannelMove`]) is 404 bytes.

use crate::calib::general::{g_sensitivity_radps_per_mps2, misalignment_index, sensor_matrix, PARAMETERS};
use crate::math::linalg::{cross, Mat3, Vec3};
use crate::nav::strapdown::{MoveIntegrator, Quat};

/// Parameters a move observes, in the estimator's order (see [`crate::calib::general::parameter_name`]): gyro
/// bias x, y, z, then gyro scale factors, misalignments and g-sensitivity (indices 15 to 32).
pub const MOVE_PARAMETERS: [usize; MOVE_COLUMNS] =
    [0, 1, 2, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31, 32];
/// Number of parameters a move observes.
pub const MOVE_COLUMNS: usize = 21;

/// The column of parameter `p` among [`MOVE_PARAMETERS`], if a move observes it.
pub const fn move_column(p: usize) -> Option<usize> {
    match p {
        0..=2 => Some(p),
        15..=32 => Some(p - 12),
        _ => None,
    }
}
/// Most moves one solution takes: one between each two dwells.
pub const MAX_MOVES: usize = crate::calib::general::MAX_DWELLS;

/// Why a move cannot be integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MoveError {
    /// The prior's gyro or accelerometer matrix (`T_g`, `T_a`) is singular or not finite.
    SingularPrior,
}

impl core::fmt::Display for MoveError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MoveError::SingularPrior => f.write_str("the prior's T_g or T_a is singular or not finite"),
        }
    }
}

/// A move being integrated.
#[derive(Clone, Debug, PartialEq)]
pub struct MoveSums {
    prior_si: [f32; MOVE_COLUMNS],
    /// `P = T_g0^-1`.
    inverse: Mat3,
    bias_b_radps: Vec3,
    g_sensitivity: Mat3,
    /// `T_a0^-1` and `b_a0`: the force the g-sensitivity sees is the compensated one.
    accel_inverse: Mat3,
    accel_bias_b_mps2: Vec3,
    integrator: MoveIntegrator,
    /// The attitude after the last pair of increments, `C_b(t)^b(0)`.
    frame: Mat3,
    duration_s: f32,
    /// `sum C_k dt`, s.
    sum_c_dt_s: Mat3,
    /// `sum C_k d_k,j` for j = x, y, z, rad.
    sum_c_angle_rad: [Mat3; 3],
    /// `sum C_k f_k,j dt` for j = x, y, z, m/s.
    sum_c_force_mps: [Mat3; 3],
    /// `sum (C_k e_i)(C_k e_i)^T dt^2` for i = x, y, z, s^2 (upper triangle; symmetric).
    sum_noise_s2: [Mat3; 3],
    /// `sum d_k`, rad, and `sum f_k dt`, m/s: the integrals of the compensated rate and of the force.
    sum_angle_rad: Vec3,
    sum_force_mps: Vec3,
    /// `sum dt^2`, s^2.
    sum_dt2_s2: f32,
    /// The measured force summed over the first [`TURN_REST_SAMPLES`] samples, m/s^2: up at the start of a turn.
    rest_force_sum_mps2: Vec3,
}

/// Samples at the start of a turn whose mean force gives up in the body (the body is at rest there).
pub const TURN_REST_SAMPLES: u32 = 5;

/// Largest distance of a turn's integrated angle about its axis from a whole number of turns, rad (45 deg):
/// beyond it the labels do not hold a whole turn (a turn cut, or a label on the wrong samples).
pub const TURN_ANGLE_TOLERANCE_RAD: f32 = core::f32::consts::FRAC_PI_4;

/// A turn about one body axis: the integral of the calibrated rate over it is the axis times the turns made (a
/// full turn is no rotation at all, so the rotation alone would not show the axis: a gyro misalignment tilts
/// the measured axis, not the end attitude), plus the Earth's rotation about up. The Ferraris method's
/// observation.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AxisTurn {
    /// Up (the direction of measured gravity) in the body at rest before the turn, a unit vector.
    pub up_b: Vec3,
    /// The reference: the body axis times the whole turns made, rad.
    pub angle_b_rad: Vec3,
    /// The integral of the rate compensated by the prior, rad.
    pub angle_sum_b_rad: Vec3,
}

/// A finished move: what the estimator needs of it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelMove {
    /// The dwell the move starts from (index in the order the dwells were added).
    pub from: usize,
    /// The dwell it ends at.
    pub to: usize,
    /// A turn about one body axis back to where it started (a labelled full turn of a Ferraris session), whatever
    /// the dwells: `from` and `to` are not used, and the observation is the integral of the rate instead of the
    /// rotation ([`AxisTurn`]).
    pub turn: Option<AxisTurn>,
    /// The rotation the compensated gyros measured, `C_b(end)^b(start)`.
    pub rotation: Quat,
    /// Duration, s.
    pub duration_s: f32,
    /// The prior's value of each parameter of [`MOVE_PARAMETERS`], SI.
    pub prior_si: [f32; MOVE_COLUMNS],
    /// Row a, column c: the change of the rotation vector's component a (body frame at the start, rad) per SI
    /// unit of parameter `MOVE_PARAMETERS[c]`, at the prior.
    pub jacobian: [[f32; MOVE_COLUMNS]; 3],
    /// Covariance of the rotation vector from white rate noise, start frame, rad^2.
    pub covariance_rad2: Mat3,
}

fn add_scaled(m: &mut Mat3, c: &Mat3, k: f32) {
    for i in 0..3 {
        for j in 0..3 {
            m.0[i][j] += c.0[i][j] * k;
        }
    }
}

impl MoveSums {
    /// A move to integrate with the rates compensated by the prior `prior_si` (the estimator's parameters: the
    /// gyro terms, and the accelerometer bias and matrix for the force the g-sensitivity sees,
    /// `f = T_a^-1 (f_meas - b_a)`, as docs/conventions.md#sensor-model writes the model).
    pub fn new(prior_si: &[f32; PARAMETERS]) -> Result<MoveSums, MoveError> {
        let t_g = sensor_matrix(prior_si, 15, 18);
        let inverse = t_g.inverse().filter(Mat3::is_finite).ok_or(MoveError::SingularPrior)?;
        let t_a = sensor_matrix(prior_si, 6, 9);
        let accel_inverse = t_a.inverse().filter(Mat3::is_finite).ok_or(MoveError::SingularPrior)?;
        let zero = Mat3([[0.0; 3]; 3]);
        Ok(MoveSums {
            prior_si: MOVE_PARAMETERS.map(|p| prior_si[p]),
            inverse,
            bias_b_radps: [prior_si[0], prior_si[1], prior_si[2]],
            g_sensitivity: g_sensitivity_radps_per_mps2(prior_si),
            accel_inverse,
            accel_bias_b_mps2: [prior_si[3], prior_si[4], prior_si[5]],
            // The interval is given with each sample.
            integrator: MoveIntegrator::new(0.0),
            frame: Mat3::IDENTITY,
            duration_s: 0.0,
            sum_c_dt_s: zero,
            sum_c_angle_rad: [zero; 3],
            sum_c_force_mps: [zero; 3],
            sum_noise_s2: [zero; 3],
            sum_angle_rad: [0.0; 3],
            sum_force_mps: [0.0; 3],
            sum_dt2_s2: 0.0,
            rest_force_sum_mps2: [0.0; 3],
        })
    }

    /// One sample: the gyro and accelerometer outputs (body, rad/s and m/s^2, the means over the interval that
    /// ends with it) and that interval, s.
    pub fn push(&mut self, rate_b_radps: Vec3, force_meas_b_mps2: Vec3, dt_s: f32) {
        if self.integrator.samples() < TURN_REST_SAMPLES {
            for i in 0..3 {
                self.rest_force_sum_mps2[i] += force_meas_b_mps2[i];
            }
        }
        let b_a = self.accel_bias_b_mps2;
        let force_b_mps2 = self.accel_inverse.mul_vec([0, 1, 2].map(|i| force_meas_b_mps2[i] - b_a[i]));
        let gf = self.g_sensitivity.mul_vec(force_b_mps2);
        let raw = [0, 1, 2].map(|i| rate_b_radps[i] - self.bias_b_radps[i] - gf[i]);
        let d = self.inverse.mul_vec(raw).map(|w| w * dt_s);
        // The attitude at the middle of the interval: the last pair's, turned by the waiting increment and half
        // of this one (first order; the terms left out are of the order of the squared increment).
        let (_, pending) = self.integrator.paired();
        let p = pending.unwrap_or([0.0; 3]);
        let lead = [0, 1, 2].map(|i| p[i] + 0.5 * d[i]);
        // `F (I + [lead x])`: row r is `F_r + F_r x lead`.
        let c = Mat3(self.frame.0.map(|f| {
            let x = cross(f, lead);
            [f[0] + x[0], f[1] + x[1], f[2] + x[2]]
        }));
        add_scaled(&mut self.sum_c_dt_s, &c, dt_s);
        for j in 0..3 {
            add_scaled(&mut self.sum_c_angle_rad[j], &c, d[j]);
            add_scaled(&mut self.sum_c_force_mps[j], &c, force_b_mps2[j] * dt_s);
            let col = c.col(j);
            let dt2 = dt_s * dt_s;
            // Symmetric: the upper triangle here, the lower one at the end.
            for a in 0..3 {
                for b in a..3 {
                    self.sum_noise_s2[j].0[a][b] += col[a] * col[b] * dt2;
                }
            }
        }
        for i in 0..3 {
            self.sum_angle_rad[i] += d[i];
            self.sum_force_mps[i] += force_b_mps2[i] * dt_s;
        }
        self.sum_dt2_s2 += dt_s * dt_s;
        self.integrator.push_increment(d);
        if pending.is_some() {
            self.frame = self.integrator.paired().0.to_mat3();
        }
        self.duration_s += dt_s;
    }

    /// Samples pushed.
    pub fn samples(&self) -> u32 {
        self.integrator.samples()
    }

    /// The rotation measured so far, `C_b(now)^b(start)`.
    pub fn rotation(&self) -> Quat {
        self.integrator.rotation()
    }

    /// The move from dwell `from` to dwell `to`, with the per-sample variance of each gyro's output,
    /// (rad/s)^2, for its covariance.
    pub fn finish(&self, from: usize, to: usize, rate_var_radps2: Vec3) -> ChannelMove {
        let p = self.inverse;
        let bias = self.sum_c_dt_s.mul(&p);
        let angle = self.sum_c_angle_rad.map(|m| m.mul(&p));
        let force = self.sum_c_force_mps.map(|m| m.mul(&p));
        let mut covariance_rad2 = Mat3([[0.0; 3]; 3]);
        for (i, n) in self.sum_noise_s2.iter().enumerate() {
            let mut full = *n;
            for a in 0..3 {
                for b in 0..a {
                    full.0[a][b] = n.0[b][a];
                }
            }
            add_scaled(&mut covariance_rad2, &full, rate_var_radps2[i]);
        }
        ChannelMove {
            from,
            to,
            turn: None,
            rotation: self.rotation(),
            duration_s: self.duration_s,
            prior_si: self.prior_si,
            jacobian: jacobian_of(&bias, &angle, &force),
            covariance_rad2,
        }
    }

    /// The whole turns (at least one) the integrated rate about body axis `axis` makes, when it is within
    /// [`TURN_ANGLE_TOLERANCE_RAD`] of them.
    pub fn whole_turns(&self, axis: usize) -> Option<f32> {
        let angle = self.sum_angle_rad[axis.min(2)];
        let turns = libm::roundf(angle / core::f32::consts::TAU);
        let near = libm::fabsf(angle - turns * core::f32::consts::TAU) <= TURN_ANGLE_TOLERANCE_RAD;
        (turns != 0.0 && near).then_some(turns)
    }

    /// The move as a turn about body axis `axis` (0, 1, 2) that ends where it started, up in the body at rest
    /// before it the direction of the mean measured force of its first [`TURN_REST_SAMPLES`]: the reference is
    /// the axis times the whole turns nearest to the integrated rate. `None` when that force has no direction.
    pub fn finish_turn(&self, axis: usize, rate_var_radps2: Vec3) -> Option<ChannelMove> {
        let sum = self.rest_force_sum_mps2;
        let n = crate::math::linalg::norm(sum);
        if n.is_nan() || n <= 0.0 {
            return None;
        }
        let up_b = sum.map(|x| x / n);
        let p = self.inverse;
        // The integral's sensitivities: `-P e_i` times dt, d_j or f_j dt summed (no transport).
        let bias = scaled(&p, self.duration_s);
        let angle = [0, 1, 2].map(|j| scaled(&p, self.sum_angle_rad[j]));
        let force = [0, 1, 2].map(|j| scaled(&p, self.sum_force_mps[j]));
        let turns = libm::roundf(self.sum_angle_rad[axis.min(2)] / core::f32::consts::TAU);
        let mut angle_b_rad = [0.0; 3];
        angle_b_rad[axis.min(2)] = turns * core::f32::consts::TAU;
        let mut covariance_rad2 = Mat3([[0.0; 3]; 3]);
        for i in 0..3 {
            covariance_rad2.0[i][i] = rate_var_radps2[i] * self.sum_dt2_s2;
        }
        Some(ChannelMove {
            from: 0,
            to: 0,
            turn: Some(AxisTurn { up_b, angle_b_rad, angle_sum_b_rad: self.sum_angle_rad }),
            rotation: self.rotation(),
            duration_s: self.duration_s,
            prior_si: self.prior_si,
            jacobian: jacobian_of(&bias, &angle, &force),
            covariance_rad2,
        })
    }
}

/// The Jacobian of a move from its sensitivity matrices (each already times `P`): column i of the bias matrix,
/// of the angle matrix j (for `T_ij`) and of the force matrix j (for `G_ij`), negated.
fn jacobian_of(bias: &Mat3, angle: &[Mat3; 3], force: &[Mat3; 3]) -> [[f32; MOVE_COLUMNS]; 3] {
    let mut jacobian = [[0.0f32; MOVE_COLUMNS]; 3];
    for (c, &param) in MOVE_PARAMETERS.iter().enumerate() {
        // The parameter's matrix and the column i of it: `-(M P) e_i`.
        let (m, i) = match param {
            0..=2 => (bias, param),
            15..=17 => (&angle[param - 15], param - 15),
            18..=23 => {
                let k = param - 18;
                let (i, j) = (0..3)
                    .flat_map(|i| (0..3).map(move |j| (i, j)))
                    .find(|&(i, j)| i != j && misalignment_index(i, j) == k)
                    .unwrap_or((0, 1));
                (&angle[j], i)
            }
            _ => {
                let k = param - 24;
                (&force[k % 3], k / 3)
            }
        };
        for (a, row) in jacobian.iter_mut().enumerate() {
            row[c] = -m.0[a][i];
        }
    }
    jacobian
}

/// `m` times `k`.
fn scaled(m: &Mat3, k: f32) -> Mat3 {
    Mat3(m.0.map(|row| row.map(|x| x * k)))
}

/// The per-sample variance of each gyro for the moves' covariance, (rad/s)^2: the raw sample variance pooled
/// over the dwells (each weighted by its degrees of freedom). The moves are not prefiltered, so the dwell means'
/// honest noise (with the prefilter's start and the Allan extrapolation) is not theirs.
pub fn pooled_rate_var_radps2(summaries: impl Iterator<Item = crate::calib::dwell::DwellSummary>) -> Vec3 {
    let (mut sum, mut dof) = ([0.0f32; 3], 0.0f32);
    for s in summaries {
        let n = s.samples.saturating_sub(1) as f32;
        for (slot, std) in sum.iter_mut().zip(s.rate_sample_std_b_radps) {
            *slot += n * std * std;
        }
        dof += n;
    }
    if dof > 0.0 {
        sum.map(|v| v / dof)
    } else {
        sum
    }
}

/// A move whose rotation at the prior is further than this from the reference's (rad, 45 deg) is no move of the
/// reference: rows with `pos = 0` between dwells that do not hold the table's turn (a recording without its
/// moves), or a move to the wrong position. It is left out of the solution (docs/method.md#moves).
pub const MAX_MOVE_MISFIT_RAD: f32 = core::f32::consts::FRAC_PI_4;

/// The parts of rotation `q` about the unit axis `u` and across it: `q = t s` with `t` about `u` (the twist) and
/// `s` (the swing) about an axis at right angles to `u`; returns `(s, t)`. A rotation `r` applied before,
/// `r q`, changes the swing by `t* r t` to first order: a perturbation turned back by the twist.
pub fn swing_about(q: &Quat, u: Vec3) -> (Quat, Quat) {
    let [w, x, y, z] = q.0;
    let along = x * u[0] + y * u[1] + z * u[2];
    let n = libm::sqrtf(w * w + along * along);
    if n < 1e-12 {
        // A half turn about an axis at right angles to u: no twist.
        return (*q, Quat::IDENTITY);
    }
    let twist = Quat([w / n, along * u[0] / n, along * u[1] / n, along * u[2] / n]);
    (twist.conjugate().mul(q).normalized(), twist)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn swing_has_no_part_about_the_axis() {
        let q = Quat::from_rotation_vector([0.3, -0.2, 1.2]);
        let u = [0.0, 0.0, 1.0];
        let (s, t) = swing_about(&q, u);
        // Twist then swing is the rotation.
        let back = t.mul(&s).to_rotation_vector();
        let v0 = q.to_rotation_vector();
        assert!((0..3).all(|i| (back[i] - v0[i]).abs() < 1e-5), "{back:?} vs {v0:?}");
        let v = s.to_rotation_vector();
        assert!(v[2].abs() < 1e-6, "{v:?}");
        // A rotation about u alone has no swing.
        let t = swing_about(&Quat::from_rotation_vector([0.0, 0.0, 2.0]), u).0.to_rotation_vector();
        assert!(t.iter().all(|x| x.abs() < 1e-6), "{t:?}");
    }

    #[test]
    fn move_columns_are_the_move_parameters() {
        for (c, &p) in MOVE_PARAMETERS.iter().enumerate() {
            assert_eq!(move_column(p), Some(c));
        }
        assert_eq!((0..PARAMETERS).filter(|&p| move_column(p).is_some()).count(), MOVE_COLUMNS);
    }

    #[test]
    fn a_singular_prior_is_refused() {
        let mut prior = [0.0f32; PARAMETERS];
        prior[15] = -1.0;
        assert_eq!(MoveSums::new(&prior).err(), Some(MoveError::SingularPrior));
        // The accelerometer matrix too (it compensates the force the g-sensitivity sees).
        let mut prior = [0.0f32; PARAMETERS];
        prior[6] = -1.0;
        assert_eq!(MoveSums::new(&prior).err(), Some(MoveError::SingularPrior));
    }
}
