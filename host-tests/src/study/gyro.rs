//! The gyro in the multi-pose studies: the scatter of the per-pose means against white noise, the per-pose mean
//! models (constant bias, drift, g-sensitivity) and their gain on held-out poses, and the labelled Ferraris
//! turns integrated into angles (the gyro scale factors).

use super::{rms, LabelledTurn, Pose, Turn};
use crate::io::recording::Recording;
use crate::model::synth::M3;
use crate::stats::solve::least_squares_normal;

/// The scatter of the per-pose gyro means (RMS over poses and axes of mean - overall mean, rad/s) and what
/// white noise of std `sigma` per sample (rad/s) gives for it.
pub(crate) fn gyro_spread(poses: &[Pose], sigma: [f64; 3]) -> (f64, f64) {
    let n = poses.len() as f64;
    let overall: [f64; 3] = [0, 1, 2].map(|i| poses.iter().map(|p| p.mean_rate_radps[i]).sum::<f64>() / n);
    let spread = rms(poses.iter().flat_map(|p| (0..3).map(move |i| p.mean_rate_radps[i] - overall[i])));
    let noise = rms(poses.iter().flat_map(|p| (0..3).map(move |i| sigma[i] / (p.samples as f64).sqrt())));
    (spread, noise)
}

/// Held-out RMS residual (rad/s) of per-pose gyro mean models fitted on even poses, evaluated on odd ones
/// (constant bias, bias + drift, bias + g-sensitivity), and the g-sensitivity matrix fitted on all poses,
/// (rad/s)/(m/s^2).
pub(crate) fn gyro_models(poses: &[Pose]) -> (Vec<(&'static str, f64)>, Option<M3>) {
    type Design = (&'static str, fn(&Pose) -> Vec<f64>);
    let designs: [Design; 3] = [
        ("constant bias", |_| vec![1.0]),
        ("bias + drift", |p| vec![1.0, p.t_mid_s]),
        ("bias + g-sensitivity", |p| vec![1.0, p.mean_force_mps2[0], p.mean_force_mps2[1], p.mean_force_mps2[2]]),
    ];
    let (fit, test): (Vec<&Pose>, Vec<&Pose>) = poses.iter().partition(|p| !p.held_out);
    let mut out = Vec::new();
    for (name, design) in designs {
        let rows: Vec<Vec<f64>> = fit.iter().map(|p| design(p)).collect();
        let mut res = Vec::new();
        for i in 0..3 {
            let y: Vec<f64> = fit.iter().map(|p| p.mean_rate_radps[i]).collect();
            let Some(beta) = least_squares_normal(&rows, &y) else { continue };
            for p in &test {
                let pred: f64 = design(p).iter().zip(&beta).map(|(a, b)| a * b).sum();
                res.push(p.mean_rate_radps[i] - pred);
            }
        }
        if res.len() == 3 * test.len() && !test.is_empty() {
            out.push((name, rms(res)));
        }
    }
    let rows: Vec<Vec<f64>> = poses.iter().map(|p| designs[2].1(p)).collect();
    let mut g_sens = [[0.0; 3]; 3];
    let mut ok = true;
    for i in 0..3 {
        let y: Vec<f64> = poses.iter().map(|p| p.mean_rate_radps[i]).collect();
        match least_squares_normal(&rows, &y) {
            Some(beta) => g_sens[i] = [beta[1], beta[2], beta[3]],
            None => ok = false,
        }
    }
    (out, ok.then_some(g_sens))
}

/// The labelled turns (label, body axis, row range) of `rec` integrated into angles: raw, and with the static
/// gyro bias (the sample-weighted mean of the pose means) removed; the scale factor if each was one full turn.
/// Turns outside the record or shorter than two rows are dropped.
pub(crate) fn integrate_turns(rec: &Recording, poses: &[Pose], turns: &[LabelledTurn]) -> Vec<Turn> {
    let gyro_bias: [f64; 3] = [0, 1, 2].map(|i| {
        poses.iter().map(|p| p.mean_rate_radps[i] * p.samples as f64).sum::<f64>()
            / poses.iter().map(|p| p.samples as f64).sum::<f64>()
    });
    turns
        .iter()
        .filter(|(_, _, range)| range.end <= rec.rows.len() && range.len() >= 2)
        .map(|(label, axis, range)| {
            let rows = &rec.rows[range.clone()];
            let (mut raw, mut corrected) = (0.0, 0.0);
            for w in rows.windows(2) {
                let dt = w[1].t_s - w[0].t_s;
                raw += w[0].rate_b_radps[*axis] * dt;
                corrected += (w[0].rate_b_radps[*axis] - gyro_bias[*axis]) * dt;
            }
            Turn {
                label: label.clone(),
                axis: *axis,
                duration_s: rows[rows.len() - 1].t_s - rows[0].t_s,
                raw_angle_rad: raw,
                angle_rad: corrected,
                scale_factor: corrected.abs() / std::f64::consts::TAU - 1.0,
            }
        })
        .collect()
}
