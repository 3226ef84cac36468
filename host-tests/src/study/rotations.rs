//! The gyro matrix from a session's rotations (docs/method.md#moves), beside the data author's reference, with
//! held-out rotations: rotations not used in a fit, integrated with that fit's calibration applied, and their
//! error against the reference rotation in degrees (raw: integrated without any calibration).
//!
//! The static poses are loaded into the general estimator with their attitudes estimated from the data (the
//! poses are hand-placed); the model is the biases, the accelerometer scale factors and the gyro scale factors
//! and misalignments. Two kinds of rotation:
//! - a labelled full turn (Ferraris): it ends where it started, so its reference rotation is the Earth's alone
//!   (a closed move, three components);
//! - a hand move between two static poses: its reference rotation is the one between the two poses' estimated
//!   attitudes, without its part about the vertical (the headings are unknown: two components, the imu_tk
//!   comparison of gravity directions).

use sinscal::calib::general::{ChannelSolution, Model, Term, PARAMETERS};
use sinscal::calib::moves::ChannelMove;
use sinscal::math::linalg::norm;

use super::LabelledTurn;
use crate::calibration::moves::{integrate, solve_with_moves, MoveSamples};
use crate::calibration::{channel_session, ChannelSession, Options};
use crate::io::error::InputError;
use crate::io::recording::Recording;
use crate::model::synth::M3;

/// One rotation held out of a fit.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOut {
    /// Which rotation ("x_rot", "move 3 (pose 3 to 4)").
    pub label: String,
    /// The angle the raw gyros measured, deg.
    pub angle_deg: f64,
    /// Error against the reference, integrated without calibration, deg.
    pub raw_error_deg: f64,
    /// Error against the reference, integrated with the fit's calibration applied, deg.
    pub calibrated_error_deg: f64,
    /// Components compared: 3, or 2 without the part about the vertical.
    pub components: usize,
}

/// One fit of the gyro matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationFit {
    /// What it used ("the three labelled turns", ...).
    pub name: String,
    /// Rotations used.
    pub rotations: usize,
    /// `T_g = I + S + M` (row i = gyro i), 1.
    pub t_g: M3,
    /// Standard errors of its entries, 1 (0 where not determined).
    pub t_g_std: M3,
    /// Gyro bias, rad/s, and its standard error.
    pub gyro_bias_radps: [(f64, f64); 3],
    /// Chi-square and degrees of freedom of the fit.
    pub chi_square: f64,
    /// See `chi_square`.
    pub degrees_of_freedom: u32,
    /// Integration and solution passes.
    pub passes: u32,
    /// Rotations held out of this fit, checked with its calibration.
    pub held_out: Vec<HeldOut>,
}

/// The rotation part of a study.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationStudy {
    /// What the reference matrix is.
    pub reference_name: String,
    /// The reference `T_g` (row i = gyro i), 1.
    pub reference_t_g: M3,
    /// The fits.
    pub fits: Vec<RotationFit>,
    /// Fits the estimator refused: (what they used, why).
    pub refused: Vec<(String, String)>,
}

impl RotationStudy {
    fn new(reference_name: &str, reference_t_g: M3) -> RotationStudy {
        RotationStudy {
            reference_name: reference_name.to_string(),
            reference_t_g,
            fits: Vec::new(),
            refused: Vec::new(),
        }
    }

    /// Adds a fit, or its refusal.
    fn add(&mut self, fit: Result<RotationFit, (String, String)>) {
        match fit {
            Ok(f) => self.fits.push(f),
            Err(r) => self.refused.push(r),
        }
    }
}

/// The model of the rotation fits: the biases, the accelerometer scale factors, the gyro scale factors and
/// misalignments, and the accelerometer misalignments when the poses determine them (`with_accel_misalignment`:
/// many poses; six faces with unknown attitudes do not).
pub fn rotation_model(with_accel_misalignment: bool) -> Model {
    let m = Model::BIASES.with(Term::AccelScaleFactor).with(Term::GyroScaleFactor).with(Term::GyroMisalignment);
    if with_accel_misalignment {
        m.with(Term::AccelMisalignment)
    } else {
        m
    }
}

/// The static poses in the general estimator, and the hand moves between them.
fn session(rec: &Recording, with_accel_misalignment: bool) -> Result<ChannelSession, InputError> {
    let model = rotation_model(with_accel_misalignment);
    let options = Options { model, estimate_attitudes: true, ..Options::default() };
    channel_session(rec, &options, true)
}

/// `T_g` and its standard errors from a solution.
fn gyro_matrix(s: &ChannelSolution) -> (M3, M3) {
    let mut t = [[0.0; 3]; 3];
    let mut std = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let p = if i == j { 15 + i } else { 18 + sinscal::calib::general::misalignment_index(i, j) };
            let (v, e) = s.estimate(p).map_or((0.0, 0.0), |(v, e)| (v as f64, e as f64));
            t[i][j] = v + if i == j { 1.0 } else { 0.0 };
            std[i][j] = e;
        }
    }
    (t, std)
}

/// Fits the gyro matrix with `fitted` and checks `held_out` (with their labels) against it.
fn fit(
    s: &ChannelSession,
    name: &str,
    fitted: &[MoveSamples],
    held_out: &[(String, MoveSamples)],
) -> Result<RotationFit, (String, String)> {
    let rate_var = s.rate_var_radps2;
    let bad = |e: sinscal::calib::general::ChannelError| (name.to_string(), e.to_string());
    let (solution, _, passes, _) = solve_with_moves(&s.estimator, fitted, rate_var, 0).map_err(bad)?;
    if !solution.converged {
        return Err((name.to_string(), format!("the fit did not converge in {passes} passes")));
    }
    let samples: Vec<MoveSamples> = held_out.iter().map(|(_, m)| m.clone()).collect();
    let raw = integrate(&samples, &[0.0; PARAMETERS], rate_var).map_err(bad)?;
    let calibrated = integrate(&samples, &solution.parameters_si, rate_var).map_err(bad)?;
    let raw_errors = s.estimator.move_residuals(&[0.0; PARAMETERS], &solution, &raw);
    let calibrated_errors = s.estimator.move_residuals(&solution.parameters_si, &solution, &calibrated);
    let held_out = held_out
        .iter()
        .zip(&raw)
        .enumerate()
        .map(|(k, ((label, m), r)): (usize, (&(String, MoveSamples), &ChannelMove))| {
            let twist_free = m.turn_axis.is_none() && {
                let dwells = s.estimator.dwells();
                dwells[m.from].heading_rad.is_none() || dwells[m.to].heading_rad.is_none()
            };
            HeldOut {
                label: label.clone(),
                angle_deg: (norm(r.rotation.to_rotation_vector()) as f64).to_degrees(),
                raw_error_deg: (norm(raw_errors[k]) as f64).to_degrees(),
                calibrated_error_deg: (norm(calibrated_errors[k]) as f64).to_degrees(),
                components: if twist_free { 2 } else { 3 },
            }
        })
        .collect();
    let (t_g, t_g_std) = gyro_matrix(&solution);
    Ok(RotationFit {
        name: name.to_string(),
        rotations: fitted.len(),
        t_g,
        t_g_std,
        gyro_bias_radps: [0, 1, 2].map(|i| solution.estimate(i).map_or((0.0, 0.0), |(v, e)| (v as f64, e as f64))),
        chi_square: solution.chi_square as f64,
        degrees_of_freedom: solution.degrees_of_freedom,
        passes,
        held_out,
    })
}

/// The label of a hand move between two poses.
/// The imucal label of the turn about body axis `axis`.
fn turn_label(axis: usize) -> String {
    crate::io::import::FERRARIS_ROTATIONS.get(axis).copied().unwrap_or("turn").to_string()
}

fn move_label(rec_positions: &[crate::calibration::PositionResult], m: &MoveSamples) -> String {
    format!("move at line {} (pose {} to {})", m.first_line, rec_positions[m.from].pos, rec_positions[m.to].pos)
}

/// imucal's Ferraris formulas for the gyro matrix: the gyro output less the static bias (the mean of every
/// static sample), integrated over each labelled turn, divided by the turn's angle (-2 pi: the session's turns
/// are negative): column j of `T_g` from the turn about axis j.
pub fn ferraris_gyro_matrix(rec: &Recording, turns: &[LabelledTurn]) -> M3 {
    let (mut sum, mut n) = ([0.0f64; 3], 0.0f64);
    for row in rec.rows.iter().filter(|r| r.pos != 0) {
        for (s, w) in sum.iter_mut().zip(row.rate_b_radps) {
            *s += w;
        }
        n += 1.0;
    }
    let bias = sum.map(|s| s / n.max(1.0));
    let mut t = [[0.0; 3]; 3];
    for (_, axis, range) in turns {
        let rows = &rec.rows[range.clone()];
        let mut angle = [0.0f64; 3];
        for w in rows.windows(2) {
            let dt = w[1].t_s - w[0].t_s;
            for i in 0..3 {
                angle[i] += (w[1].rate_b_radps[i] - bias[i]) * dt;
            }
        }
        for i in 0..3 {
            t[i][*axis] = angle[i] / -std::f64::consts::TAU;
        }
    }
    t
}

/// The Ferraris session: fitted with its three labelled turns (imucal's data), then with the hand moves
/// between the faces, each checked on the other's rotations, and with both.
pub fn ferraris_rotations(rec: &Recording, turns: &[LabelledTurn]) -> Result<RotationStudy, InputError> {
    // The turns and the hand moves as `calibrate` gathers them: the turns from the recording's `turn` column.
    let s = session(rec, false)?;
    let (turned, moved): (Vec<&MoveSamples>, Vec<&MoveSamples>) = s.moves.iter().partition(|m| m.turn_axis.is_some());
    let closed: Vec<(String, MoveSamples)> =
        turned.into_iter().map(|m| (turn_label(m.turn_axis.unwrap_or(0)), m.clone())).collect();
    let hand: Vec<(String, MoveSamples)> =
        moved.into_iter().map(|m| (move_label(&s.positions, m), m.clone())).collect();
    let only = |v: &[(String, MoveSamples)]| v.iter().map(|(_, m)| m.clone()).collect::<Vec<_>>();
    let both: Vec<MoveSamples> = only(&closed).into_iter().chain(only(&hand)).collect();
    let mut study =
        RotationStudy::new("imucal's Ferraris formulas on the same turns", ferraris_gyro_matrix(rec, turns));
    study.add(fit(&s, "the three labelled turns", &only(&closed), &hand));
    study.add(fit(&s, "the hand moves between the faces", &only(&hand), &closed));
    study.add(fit(&s, "the turns and the hand moves", &both, &[]));
    Ok(study)
}

/// The imu_tk session: fitted with every hand move between its static poses, and with every other move, checked
/// on the rest. The reference is the Xsens factory gyro misalignment (its gains are the importer's nominal
/// gains, so its scale factors are 0 here).
pub fn imutk_rotations(rec: &Recording) -> Result<RotationStudy, InputError> {
    let s = session(rec, true)?;
    let hand: Vec<(String, MoveSamples)> = s.moves.iter().map(|m| (move_label(&s.positions, m), m.clone())).collect();
    let all: Vec<MoveSamples> = hand.iter().map(|(_, m)| m.clone()).collect();
    let even: Vec<MoveSamples> = hand.iter().step_by(2).map(|(_, m)| m.clone()).collect();
    let odd: Vec<(String, MoveSamples)> = hand.iter().skip(1).step_by(2).cloned().collect();
    let mut study = RotationStudy::new(
        "Xsens factory calibration (gyro misalignment; gains = the importer's nominal gains)",
        [[1.0, -0.01, -0.02], [0.0, 1.0, 0.04], [-0.01, 0.01, 1.0]],
    );
    study.add(fit(&s, "every hand move", &all, &[]));
    study.add(fit(&s, "every other hand move (1st, 3rd, ...)", &even, &odd));
    Ok(study)
}
