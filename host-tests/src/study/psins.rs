//! The single-pose study (the PSINS laser-gyro record, one static pose on a parked vehicle): the six channels'
//! noise against the white base model and its extension, and the vehicle sway test (does the horizontal
//! accelerometer follow g times the tilt the gyro integrates?).

use super::causes::name_causes;
use super::noise::channel_noise;
use super::{channel_value, mean, rms, ChannelNoise, Study, Sway, CHANNELS};
use crate::io::recording::Recording;

/// Channel `c` of every row (0..3 gyro, rad/s; 3..6 accelerometer, m/s^2).
fn column(rec: &Recording, c: usize) -> Vec<f64> {
    rec.rows.iter().map(|r| channel_value(r, c)).collect()
}

/// High-pass: the series less its centred moving average over `2 h + 1` points (clipped at the ends).
fn high_pass(x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    let mut pre = vec![0.0; n + 1];
    for k in 0..n {
        pre[k + 1] = pre[k] + x[k];
    }
    (0..n)
        .map(|k| {
            let (lo, hi) = (k.saturating_sub(h), (k + h + 1).min(n));
            x[k] - (pre[hi] - pre[lo]) / (hi - lo) as f64
        })
        .collect()
}

/// The sway test of one pair: 1-s means of the accelerometer channel against `sign` g times the tilt integrated
/// from the gyro channel, both high-passed over 61 s. `sign` is `+g` or `-g` in m/s^2.
pub fn sway_test(pair: &'static str, accel: &[f64], gyro: &[f64], rate_hz: f64, sign: f64) -> Sway {
    let block = rate_hz.round().max(1.0) as usize;
    let dt = 1.0 / rate_hz;
    let gmean = mean(gyro);
    let mut theta = 0.0;
    let (mut a_means, mut tilt) = (Vec::new(), Vec::new());
    for (a_chunk, g_chunk) in accel.chunks_exact(block).zip(gyro.chunks_exact(block)) {
        let mut acc_theta = 0.0;
        for &w in g_chunk {
            theta += (w - gmean) * dt;
            acc_theta += theta;
        }
        a_means.push(mean(a_chunk));
        tilt.push(acc_theta / block as f64);
    }
    let a = high_pass(&a_means, 30);
    let t: Vec<f64> = high_pass(&tilt, 30).iter().map(|v| sign * v).collect();
    let (sa, st) = (rms(a.iter().copied()), rms(t.iter().copied()));
    let cov: f64 = a.iter().zip(&t).map(|(x, y)| x * y).sum::<f64>() / a.len().max(1) as f64;
    Sway {
        pair,
        correlation: cov / (sa * st),
        slope_mps2_per_rad: sign * cov / (st * st),
        accel_rms_mps2: sa,
        tilt_rms_rad: st,
    }
}

/// Study of a single static record (the PSINS set): the six channels' noise and the sway tests.
pub fn study_single_pose(rec: &Recording, dataset: &str, sources: Vec<String>, seed: u64) -> Study {
    let rate_hz = rec.header.rate_hz.unwrap_or(100.0);
    let g = rec.header.gravity_mps2.unwrap_or(9.80665);
    let cols: Vec<Vec<f64>> = (0..6).map(|c| column(rec, c)).collect();
    let noise: Vec<ChannelNoise> = (0..6)
        .map(|c| {
            eprintln!(
                "study {dataset}: Allan deviation and SIMULATIONs of {} ({} samples)",
                CHANNELS[c],
                cols[c].len()
            );
            channel_noise(CHANNELS[c], &cols[c], rate_hz, seed, c as u64 * 1000)
        })
        .collect();
    let sway = vec![
        sway_test("ay vs +g*theta_x", &cols[4], &cols[0], rate_hz, g),
        sway_test("ax vs -g*theta_y", &cols[3], &cols[1], rate_hz, -g),
    ];
    let mut study =
        Study { dataset: dataset.to_string(), sources, seed, rate_hz, noise, sway, poses: None, causes: Vec::new() };
    study.causes = name_causes(&study);
    study
}
