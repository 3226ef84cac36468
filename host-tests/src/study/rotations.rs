//! The gyro matrix from a session's rotations as `sinscal calibrate` gives it (docs/method.md#moves), beside the
//! data author's reference, and checked on the session's rests (docs/method.md#held-out-moves).
//!
//! Each fit is a call of the product, `calibrate` with `--model full` and the default options, the whole
//! recording or with some of its moves and turns held out (`--hold-out-moves`): the study has no fit of its
//! own. Each calibration is then checked independently of the estimator ([`super::rests`]): the gravity
//! direction carried by the compensated gyros across every motion between two rests (the moves the fit used
//! and those it did not), and the compensated specific force of the rests that carry no label.

use sinscal::calib::general::Model;

use super::rests::{find_rests, rest_forces, transitions, Rest, RestForce, Transition};
use super::LabelledTurn;
use crate::calibration::result::CalibrationJson;
use crate::calibration::{calibrate, Calibration, Estimates, Options};
use crate::io::calibration_model::CalibrationModel;
use crate::io::error::InputError;
use crate::io::recording::Recording;
use crate::model::synth::M3;

/// One calibration of the session and its checks.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationFit {
    /// What it used ("every move and turn", ...).
    pub name: String,
    /// The command line that gives it (`sinscal calibrate --model full ...`).
    pub command: String,
    /// Moves and turns the fit used.
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
    /// The hand moves' error calibrate named, deg per axis (0: none).
    pub move_error_deg: f64,
    /// Whether every check of the calibration passed (its exit status 0).
    pub checks_passed: bool,
    /// Every motion between two consecutive rests, checked with the calibration.
    pub transitions: Vec<Transition>,
    /// The rests without a label, checked with the calibration.
    pub rests: Vec<RestForce>,
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
    /// Adds a fit, or its refusal.
    fn add(&mut self, fit: Result<RotationFit, (String, String)>) {
        match fit {
            Ok(f) => self.fits.push(f),
            Err(r) => self.refused.push(r),
        }
    }

    fn new(reference_name: &str, reference_t_g: M3) -> RotationStudy {
        RotationStudy {
            reference_name: reference_name.to_string(),
            reference_t_g,
            fits: Vec::new(),
            refused: Vec::new(),
        }
    }
}

/// The model of the rotation fits: every term (`--model full`); the estimator says which the session cannot
/// carry.
pub const ROTATION_MODEL: Model = Model::FULL;

/// `T_g` and its standard errors as calibrate reports them (with the fit scale of each gyro,
/// docs/method.md#fit-scale).
fn gyro_matrix(e: &Estimates) -> (M3, M3) {
    let mut t = [[0.0; 3]; 3];
    let mut std = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let p = if i == j { 15 + i } else { 18 + sinscal::calib::general::misalignment_index(i, j) };
            t[i][j] = e.value_si[p].unwrap_or(0.0) + if i == j { 1.0 } else { 0.0 };
            std[i][j] = e.std_si[p].unwrap_or(0.0);
        }
    }
    (t, std)
}

/// The moves and turns of `cal` as `--hold-out-moves` numbers them (from 1), those `keep` selects.
fn move_numbers(cal: &Calibration, keep: impl Fn(&crate::calibration::UsedMove) -> bool) -> Vec<usize> {
    cal.moves.iter().enumerate().filter(|(_, m)| keep(m)).map(|(k, _)| k + 1).collect()
}

/// The session calibrated by the product with the moves numbered `held_out` (from 1) held out, and checked on
/// `rests`.
fn fit(rec: &Recording, name: &str, held_out: &[usize], rests: &[Rest]) -> Result<RotationFit, (String, String)> {
    let mask = held_out.iter().fold(0u64, |m, k| m | 1 << (k - 1));
    let options = Options { model: ROTATION_MODEL, hold_out_moves: mask, ..Options::default() };
    let cal = calibrate(rec, &options).map_err(|e| (name.to_string(), e.to_string()))?;
    checked_fit(rec, name, held_out, &cal, rests)
}

/// A calibration of the session (`held_out`: the moves it left out, numbered from 1) checked on `rests`.
fn checked_fit(
    rec: &Recording,
    name: &str,
    held_out: &[usize],
    cal: &Calibration,
    rests: &[Rest],
) -> Result<RotationFit, (String, String)> {
    let list = held_out.iter().map(usize::to_string).collect::<Vec<_>>().join(",");
    let command = format!(
        "sinscal calibrate --model full{}",
        if held_out.is_empty() { String::new() } else { format!(" --hold-out-moves {list}") }
    );
    let refused = |e: String| (name.to_string(), e);
    let Some(solution) = cal.channels.as_ref() else { return Err(refused("no general estimator".into())) };
    let text = serde_json::to_string(&CalibrationJson::new(cal)).map_err(|e| refused(e.to_string()))?;
    let model = CalibrationModel::parse(&text, "the study's calibration").map_err(|e| refused(e.to_string()))?;
    let fitted: Vec<usize> = cal.moves.iter().filter(|m| !m.held_out && !m.refused).map(|m| m.first_line).collect();
    let used = |lines: std::ops::Range<usize>| fitted.iter().any(|l| lines.contains(l));
    let (t_g, t_g_std) = gyro_matrix(&cal.estimates);
    let g = cal.site.gravity_mps2 as f64;
    Ok(RotationFit {
        name: name.to_string(),
        command,
        rotations: fitted.len(),
        t_g,
        t_g_std,
        gyro_bias_radps: [0, 1, 2]
            .map(|i| (cal.estimates.value_si[i].unwrap_or(0.0), cal.estimates.std_si[i].unwrap_or(0.0))),
        chi_square: solution.chi_square as f64,
        degrees_of_freedom: solution.degrees_of_freedom,
        passes: cal.move_passes,
        move_error_deg: cal.move_error_rad.to_degrees(),
        checks_passed: crate::calibration::checks::checks(cal).iter().all(|c| c.passed),
        transitions: transitions(rec, rests, &model, used),
        rests: rest_forces(rec, rests, &model, g),
    })
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

/// The Ferraris session calibrated with every move and turn (the product's answer), with its three labelled
/// turns only (the hand moves held out) and with its hand moves only (the turns held out); each checked on the
/// session's rests, labelled and not.
pub fn ferraris_rotations(rec: &Recording, turns: &[LabelledTurn]) -> Result<RotationStudy, InputError> {
    let mut study =
        RotationStudy::new("imucal's Ferraris formulas on the same turns", ferraris_gyro_matrix(rec, turns));
    let options = Options { model: ROTATION_MODEL, ..Options::default() };
    let all = calibrate(rec, &options)?;
    let hand = move_numbers(&all, |m| m.turn.is_none());
    let turned = move_numbers(&all, |m| m.turn.is_some());
    let rests = find_rests(rec, true);
    study.add(checked_fit(rec, "every move and turn", &[], &all, &rests));
    for (name, held_out) in [
        ("the three labelled turns (the hand moves held out)", hand),
        ("the hand moves between the faces (the turns held out)", turned),
    ] {
        study.add(fit(rec, name, &held_out, &rests));
    }
    Ok(study)
}

/// The imu_tk session calibrated with every hand move between its static poses, and with every other move
/// held out (2nd, 4th, ...), each checked on the motions between its poses. The reference is the Xsens factory
/// gyro misalignment (its gains are the importer's nominal gains, so its scale factors are 0 here).
pub fn imutk_rotations(rec: &Recording) -> Result<RotationStudy, InputError> {
    let mut study = RotationStudy::new(
        "Xsens factory calibration (gyro misalignment; gains = the importer's nominal gains)",
        [[1.0, -0.01, -0.02], [0.0, 1.0, 0.04], [-0.01, 0.01, 1.0]],
    );
    let options = Options { model: ROTATION_MODEL, ..Options::default() };
    let all = calibrate(rec, &options)?;
    let every_other = move_numbers(&all, |_| true).into_iter().filter(|k| k % 2 == 0).take(64).collect::<Vec<_>>();
    let rests = find_rests(rec, false);
    study.add(checked_fit(rec, "every hand move", &[], &all, &rests));
    study.add(fit(rec, "every other hand move (1st, 3rd, ...)", &every_other, &rests));
    Ok(study)
}
