//! The noise generators of the study's SIMULATIONs, all seeded: the simulator's streams
//! ([`crate::model::simulator`]: one ChaCha8 stream per (seed, stream), standard normals) give the same numbers
//! for the same seed. White noise (the base model), the IEEE 952 terms, Gauss-Markov processes and sinusoids
//! (the extended model).

use crate::model::simulator::{normal, rng};
use crate::stats::noise::{gauss_markov_allan_variance, NoiseTerms};

/// A SIMULATION of white noise: `n` samples of standard deviation `std` (SI).
pub(crate) fn white(n: usize, std: f64, seed: u64, stream: u64) -> Vec<f64> {
    let mut r = rng(seed, stream);
    (0..n).map(|_| std * normal(&mut r)).collect()
}

/// The Gauss-Markov processes (standard deviation SI, correlation time s) whose sum approximates a flicker
/// (bias instability) Allan floor of 0.664 B between `tau_lo` and `tau_hi`: correlation times two per decade,
/// equal variances, scaled so that the geometric mean of the sum's ADEV over that range equals 0.664 B.
pub fn flicker_as_gauss_markov(b: f64, tau_lo_s: f64, tau_hi_s: f64) -> Vec<(f64, f64)> {
    if !(b > 0.0 && tau_hi_s > tau_lo_s && tau_lo_s > 0.0) {
        return Vec::new();
    }
    let mut tcs = Vec::new();
    let mut tc = tau_lo_s / 2.0;
    while tc < tau_hi_s {
        tcs.push(tc);
        tc *= 10f64.sqrt();
    }
    let grid: Vec<f64> = (0..=20).map(|i| tau_lo_s * (tau_hi_s / tau_lo_s).powf(i as f64 / 20.0)).collect();
    let log_mean = grid
        .iter()
        .map(|&t| tcs.iter().map(|&tc| gauss_markov_allan_variance(1.0, tc, t)).sum::<f64>().ln())
        .sum::<f64>()
        / grid.len() as f64;
    let target = (2.0 * std::f64::consts::LN_2 / std::f64::consts::PI) * b * b;
    let var = target / log_mean.exp();
    tcs.into_iter().map(|tc| (var.sqrt(), tc)).collect()
}

/// A SIMULATION of `n` samples at `rate_hz` of the IEEE 952 terms (zero mean, seeded): quantization as the
/// difference of white angle noise (Q), white rate noise (N), bias instability as the Gauss-Markov sum of
/// [`flicker_as_gauss_markov`] over [1/rate, n/rate], rate random walk (K, interval-averaged), and a ramp (R).
/// The terms draw from one stream in that order.
pub fn generate_noise_terms(terms: &NoiseTerms, n: usize, rate_hz: f64, seed: u64, stream: u64) -> Vec<f64> {
    let dt = 1.0 / rate_hz;
    let mut r = rng(seed, stream);
    let mut out = vec![0.0; n];
    // Q: y_k = (e_{k+1} - e_k) / dt with e white of std Q (integrated output quantization).
    if terms.quantization_q > 0.0 {
        let mut prev = terms.quantization_q * normal(&mut r);
        for y in out.iter_mut() {
            let next = terms.quantization_q * normal(&mut r);
            *y += (next - prev) / dt;
            prev = next;
        }
    }
    if terms.random_walk_n > 0.0 {
        let s = terms.random_walk_n / dt.sqrt();
        for y in out.iter_mut() {
            *y += s * normal(&mut r);
        }
    }
    for (sigma, tc) in flicker_as_gauss_markov(terms.bias_instability_b, dt, n as f64 * dt) {
        let phi = (-dt / tc).exp();
        let drive = sigma * (1.0 - phi * phi).sqrt();
        let mut x = sigma * normal(&mut r);
        for y in out.iter_mut() {
            *y += x;
            x = phi * x + drive * normal(&mut r);
        }
    }
    if terms.rate_random_walk_k > 0.0 {
        let step = terms.rate_random_walk_k * dt.sqrt();
        let mut b = 0.0;
        for y in out.iter_mut() {
            let (xi1, xi2) = (normal(&mut r), normal(&mut r));
            *y += b + step * (0.5 * xi1 + xi2 / 12f64.sqrt());
            b += step * xi1;
        }
    }
    if terms.ramp_r > 0.0 {
        for (k, y) in out.iter_mut().enumerate() {
            *y += terms.ramp_r * (k as f64 + 0.5) * dt;
        }
    }
    out
}

/// A SIMULATION of a stationary first-order Gauss-Markov process: `n` samples at `rate_hz`, standard deviation
/// `sigma` (SI), correlation time `tc_s`.
pub fn gauss_markov(n: usize, rate_hz: f64, sigma: f64, tc_s: f64, seed: u64, stream: u64) -> Vec<f64> {
    let mut r = rng(seed, stream);
    let phi = (-1.0 / (rate_hz * tc_s)).exp();
    let drive = sigma * (1.0 - phi * phi).sqrt();
    let mut x = sigma * normal(&mut r);
    (0..n)
        .map(|_| {
            let y = x;
            x = phi * x + drive * normal(&mut r);
            y
        })
        .collect()
}

/// A SIMULATION of a sinusoid: `n` samples at `rate_hz` (taken mid-interval) of amplitude `amplitude` (SI) at
/// `frequency_hz`, its phase uniform in [0, 2 pi) from the stream.
pub(crate) fn sine(n: usize, rate_hz: f64, amplitude: f64, frequency_hz: f64, seed: u64, stream: u64) -> Vec<f64> {
    let phase = rand::Rng::random::<f64>(&mut rng(seed, stream)) * std::f64::consts::TAU;
    let w = std::f64::consts::TAU * frequency_hz;
    (0..n).map(|k| amplitude * (w * (k as f64 + 0.5) / rate_hz + phase).sin()).collect()
}
