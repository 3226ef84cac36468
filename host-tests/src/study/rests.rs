//! A calibration checked on a session's rests and on the motions between them, independently of the estimator
//! (docs/method.md#held-out-moves): the direction of gravity at one rest, carried across the motion to the next
//! rest by the compensated gyros, against the direction measured there; and the compensated specific force of
//! the rests that carry no label against gravity.
//!
//! The rests are the labelled dwells (maximal runs of one `pos` above 0) and, where asked, the still periods of
//! the unlabelled rows: a row whose specific force varies, over the second around it, by less than six times
//! the labelled dwells' median variance, in runs of at least [`MIN_REST_S`] that hold neither a labelled row nor
//! a turn.

use std::ops::Range;

use crate::io::calibration_model::CalibrationModel;
use crate::io::import::{detect_static_intervals, StaticDetection};
use crate::io::recording::Recording;

/// Shortest still period of unlabelled rows taken as a rest, s.
pub const MIN_REST_S: f64 = 2.0;

/// One rest of the session.
#[derive(Clone, Debug, PartialEq)]
pub struct Rest {
    /// Its rows (indices into the recording's rows).
    pub rows: Range<usize>,
    /// Its label; 0 for a rest found in the unlabelled rows.
    pub pos: u32,
}

/// The motion between two consecutive rests, checked with a calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct Transition {
    /// Which motion ("turn about x", "move at line 1282 (pose 1 to pose 2)").
    pub label: String,
    /// Whether it holds a labelled turn.
    pub turn: bool,
    /// Whether the calibration's fit used it as an observation.
    pub used_in_fit: bool,
    /// The angle the raw gyros turned through, deg.
    pub angle_deg: f64,
    /// Angle between the gravity direction carried across it and the one measured after it, raw data, deg.
    pub raw_error_deg: f64,
    /// The same with the calibration applied to the gyros and the accelerometers, deg.
    pub calibrated_error_deg: f64,
}

/// The specific force of a rest without a label against gravity.
#[derive(Clone, Debug, PartialEq)]
pub struct RestForce {
    /// Which rest ("rest at line 12").
    pub label: String,
    /// Its samples.
    pub samples: usize,
    /// |mean f| - g of the raw data, m/s^2.
    pub raw_error_mps2: f64,
    /// |mean f| - g with the calibration applied, m/s^2.
    pub calibrated_error_mps2: f64,
}

/// The rests of `rec` in time order: its labelled dwells, and with `unlabelled` the still periods of its
/// unlabelled rows.
pub fn find_rests(rec: &Recording, unlabelled: bool) -> Vec<Rest> {
    let rows = &rec.rows;
    let mut rests: Vec<Rest> = Vec::new();
    for (k, row) in rows.iter().enumerate() {
        match rests.last_mut() {
            Some(r) if row.pos != 0 && r.pos == row.pos && r.rows.end == k => r.rows.end = k + 1,
            _ if row.pos != 0 => rests.push(Rest { rows: k..k + 1, pos: row.pos }),
            _ => {}
        }
    }
    if unlabelled && !rests.is_empty() {
        let mut found = still_periods(rec, &rests);
        rests.append(&mut found);
        rests.sort_by_key(|r| r.rows.start);
    }
    rests
}

/// The still periods of the unlabelled rows (see the module's note).
fn still_periods(rec: &Recording, labelled: &[Rest]) -> Vec<Rest> {
    let rows = &rec.rows;
    let force: Vec<[f64; 3]> = rows.iter().map(|r| r.force_b_mps2).collect();
    let t: Vec<f64> = rows.iter().map(|r| r.t_s).collect();
    let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_by(f64::total_cmp);
    let Some(&step_s) = steps.get(steps.len() / 2) else { return Vec::new() };
    let mut variances: Vec<f64> = labelled.iter().map(|r| force_variance(&force[r.rows.clone()])).collect();
    variances.sort_by(f64::total_cmp);
    let floor = variances[variances.len() / 2];
    let detection =
        StaticDetection { window_s: 1.0, init_static_s: 0.0, threshold_factor: 6.0, min_static_s: MIN_REST_S };
    let Ok(still) = detect_static_intervals(&force, &t, 1.0 / step_s, &detection, floor) else { return Vec::new() };
    still
        .ranges
        .into_iter()
        .filter(|r| rows[r.clone()].iter().all(|row| row.pos == 0 && row.turn_axis.is_none()))
        .map(|rows| Rest { rows, pos: 0 })
        .collect()
}

/// The sum over x, y, z of the population variance of `force`, (m/s^2)^2.
fn force_variance(force: &[[f64; 3]]) -> f64 {
    let n = force.len().max(1) as f64;
    (0..3)
        .map(|i| {
            let mean = force.iter().map(|f| f[i]).sum::<f64>() / n;
            force.iter().map(|f| (f[i] - mean).powi(2)).sum::<f64>() / n
        })
        .sum()
}

/// How a rest is named.
fn rest_name(rec: &Recording, r: &Rest) -> String {
    if r.pos == 0 {
        format!("rest at line {}", rec.rows[r.rows.start].line)
    } else {
        format!("pose {}", r.pos)
    }
}

/// The compensation a check applies: the calibration, or none (raw data).
type Compensate<'a> = Option<&'a CalibrationModel>;

fn force(model: Compensate<'_>, f: [f64; 3]) -> [f64; 3] {
    model.map_or(f, |m| m.compensate_force(f))
}

fn rate(model: Compensate<'_>, w: [f64; 3], f: [f64; 3]) -> [f64; 3] {
    model.map_or(w, |m| m.compensate_rate(w, m.compensate_force(f)))
}

/// The mean compensated specific force of a rest, m/s^2.
fn mean_force(rec: &Recording, r: &Rest, model: Compensate<'_>) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for row in &rec.rows[r.rows.clone()] {
        let f = force(model, row.force_b_mps2);
        for i in 0..3 {
            sum[i] += f[i];
        }
    }
    sum.map(|s| s / r.rows.len().max(1) as f64)
}

/// `v` turned by the rotation vector `-theta` (rad): a direction fixed in space, in the body frame after the
/// body turned by `theta` (Rodrigues).
fn turn_back(v: [f64; 3], theta: [f64; 3]) -> ([f64; 3], f64) {
    let a = (theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2]).sqrt();
    if a == 0.0 {
        return (v, 0.0);
    }
    let n = theta.map(|x| x / a);
    let cross = [n[1] * v[2] - n[2] * v[1], n[2] * v[0] - n[0] * v[2], n[0] * v[1] - n[1] * v[0]];
    let dot = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
    let (s, c) = a.sin_cos();
    ([0, 1, 2].map(|i| v[i] * c - cross[i] * s + n[i] * dot * (1.0 - c)), a)
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|x| x / n)
}

/// The gravity direction of rest `from` carried by the compensated gyros (trapezoidal steps) over the rows from
/// its last to the first of `to`, against the direction measured at `to`: (error, angle turned through), deg.
pub fn carried_gravity_error(rec: &Recording, from: &Rest, to: &Rest, model: Compensate<'_>) -> (f64, f64) {
    let mut up = unit(mean_force(rec, from, model));
    let mut turned = 0.0;
    let rows = &rec.rows[from.rows.end - 1..=to.rows.start];
    for w in rows.windows(2) {
        let dt = w[1].t_s - w[0].t_s;
        let (a, b) =
            (rate(model, w[0].rate_b_radps, w[0].force_b_mps2), rate(model, w[1].rate_b_radps, w[1].force_b_mps2));
        let (next, angle) = turn_back(up, [0, 1, 2].map(|i| 0.5 * (a[i] + b[i]) * dt));
        up = next;
        turned += angle;
    }
    let measured = unit(mean_force(rec, to, model));
    let cos = (up[0] * measured[0] + up[1] * measured[1] + up[2] * measured[2]).clamp(-1.0, 1.0);
    (cos.acos().to_degrees(), turned.to_degrees())
}

/// Every motion between consecutive rests, checked raw and with `model`; `used(first, next)` says whether the
/// calibration's fit used a motion that starts in the lines `first..next` (the first lines of the two rests).
pub fn transitions(
    rec: &Recording,
    rests: &[Rest],
    model: &CalibrationModel,
    used: impl Fn(Range<usize>) -> bool,
) -> Vec<Transition> {
    rests
        .windows(2)
        .map(|pair| {
            let (from, to) = (&pair[0], &pair[1]);
            let between = &rec.rows[from.rows.end..to.rows.start];
            let turn = between.iter().find_map(|r| r.turn_axis);
            let (raw, angle) = carried_gravity_error(rec, from, to, None);
            let (calibrated, _) = carried_gravity_error(rec, from, to, Some(model));
            let first_line = between.first().map_or(rec.rows[to.rows.start].line, |r| r.line);
            let label = match turn {
                Some(axis) => format!("turn about {}", crate::io::recording::TURN_AXES[axis]),
                None => format!("move at line {first_line} ({} to {})", rest_name(rec, from), rest_name(rec, to)),
            };
            Transition {
                label,
                turn: turn.is_some(),
                used_in_fit: used(rec.rows[from.rows.start].line..rec.rows[to.rows.start].line),
                angle_deg: angle,
                raw_error_deg: raw,
                calibrated_error_deg: calibrated,
            }
        })
        .collect()
}

/// The specific force of every rest without a label against `g_mps2`, raw and with `model`.
pub fn rest_forces(rec: &Recording, rests: &[Rest], model: &CalibrationModel, g_mps2: f64) -> Vec<RestForce> {
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    rests
        .iter()
        .filter(|r| r.pos == 0)
        .map(|r| RestForce {
            label: rest_name(rec, r),
            samples: r.rows.len(),
            raw_error_mps2: norm(mean_force(rec, r, None)) - g_mps2,
            calibrated_error_mps2: norm(mean_force(rec, r, Some(model))) - g_mps2,
        })
        .collect()
}

/// Root mean square of `values` (0 for none).
pub fn rms(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A direction fixed in space, seen from a body that turned +90 deg about x: what was body z is now body y
    /// (`f_b = C_n^b f_n` with `C_b^n = R_x(90 deg)`), exact synthetic data.
    #[test]
    fn a_quarter_turn_about_x_carries_up_from_z_to_y() {
        let (v, a) = turn_back([0.0, 0.0, 1.0], [std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-15 && (v[1] - 1.0).abs() < 1e-15 && v[2].abs() < 1e-15, "{v:?}");
        assert!((a - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        // And back: the same turn about -x.
        let (w, _) = turn_back(v, [-std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        assert!((w[2] - 1.0).abs() < 1e-15, "{w:?}");
    }
}
