//! The extended noise model of one channel: the IEEE Std 952 terms plus, where it helps, one band-limited term
//! (a Gauss-Markov process or a sinusoid), fitted to the Allan variance; and its gain on held-out data (fitted
//! on the first half of the record, its SIMULATION compared with the second half beside the base model's).

use super::generate::{gauss_markov, generate_noise_terms, sine, white};
use super::noise::{clusters, curve, long_index, rms_log10, white_std};
use super::NoiseExtension;
use crate::stats::noise::{
    fit_noise_terms, gauss_markov_allan_variance, overlapping_allan_deviation, AllanPoint, NoiseTerms,
};
use crate::stats::solve::nnls_normal;

/// A band-limited term of the extended noise model beside the IEEE 952 terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ExtraTerm {
    /// First-order Gauss-Markov process: standard deviation (SI unit of the channel), correlation time, s.
    GaussMarkov {
        /// Standard deviation, SI.
        sigma: f64,
        /// Correlation time, s.
        tc_s: f64,
    },
    /// Sinusoid (vibration, sway): amplitude (SI unit of the channel), frequency, Hz; random phase.
    Sine {
        /// Amplitude, SI.
        amplitude: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
    },
}

/// The shape of a candidate band-limited term before its size is fitted: Gauss-Markov correlation time, s, or
/// sinusoid frequency, Hz.
#[derive(Clone, Copy)]
enum ExtraShape {
    Gm(f64),
    Sine(f64),
}

impl ExtraTerm {
    /// A SIMULATION of the term: `n` samples at `rate_hz`, seeded.
    pub fn generate(&self, n: usize, rate_hz: f64, seed: u64, stream: u64) -> Vec<f64> {
        match *self {
            ExtraTerm::GaussMarkov { sigma, tc_s } => gauss_markov(n, rate_hz, sigma, tc_s, seed, stream),
            ExtraTerm::Sine { amplitude, frequency_hz } => sine(n, rate_hz, amplitude, frequency_hz, seed, stream),
        }
    }

    /// A short description with units (`unit` = the channel's SI unit).
    pub fn describe(&self, unit: &str) -> String {
        match *self {
            ExtraTerm::GaussMarkov { sigma, tc_s } => {
                format!("Gauss-Markov sigma {sigma:.3e} {unit}, correlation time {tc_s:.3} s")
            }
            ExtraTerm::Sine { amplitude, frequency_hz } => {
                format!("sinusoid amplitude {amplitude:.3e} {unit} at {frequency_hz:.3} Hz")
            }
        }
    }
}

/// The Allan variance basis of the extended noise model at `tau` (s): the five IEEE 952 terms
/// [3/tau^2, 1/tau, 2 ln2/pi, tau/3, tau^2/2] and a unit-variance Gauss-Markov process or a unit-amplitude
/// sinusoid (Allan variance sin^4(pi f tau) / (pi f tau)^2).
fn extended_basis(tau: f64, extra: Option<ExtraShape>) -> Vec<f64> {
    let mut b = vec![
        3.0 / (tau * tau),
        1.0 / tau,
        2.0 * std::f64::consts::LN_2 / std::f64::consts::PI,
        tau / 3.0,
        tau * tau / 2.0,
    ];
    match extra {
        Some(ExtraShape::Gm(tc)) => b.push(gauss_markov_allan_variance(1.0, tc, tau)),
        Some(ExtraShape::Sine(f)) => {
            let x = std::f64::consts::PI * f * tau;
            b.push(x.sin().powi(4) / (x * x));
        }
        None => {}
    }
    b
}

/// Fits the extended noise model to Allan points: the IEEE 952 terms (as [`fit_noise_terms`]: weighted
/// non-negative least squares on the variance, weights 1 / (2 u sigma^2), re-weighted once by the model) plus,
/// optionally, one band-limited term: a Gauss-Markov process (correlation time on a grid of 4 per decade over
/// the curve's tau range) or a sinusoid (frequency on a grid of 12 per decade from 1 / (4 tau_max) to 1 /
/// (2 tau_min)), the one with the smallest weighted residual; it is kept only if it lowers the weighted residual
/// sum by more than 20 %.
pub fn fit_extended_noise(points: &[AllanPoint]) -> (NoiseTerms, Option<ExtraTerm>) {
    let p: Vec<&AllanPoint> =
        points.iter().filter(|q| q.adev > 0.0 && q.adev.is_finite() && q.rel_uncertainty > 0.0).collect();
    let fallback = || (fit_noise_terms(points).map(|f| f.terms).unwrap_or_default(), None);
    if p.len() < 6 {
        return fallback();
    }
    let Some((c0, ss0)) = reweighted_fit(&p, None) else { return fallback() };
    let mut best: Option<(Vec<f64>, f64, ExtraShape)> = None;
    for shape in extra_shapes(p[0].tau_s, p[p.len() - 1].tau_s) {
        if let Some((c, ss)) = reweighted_fit(&p, Some(shape)) {
            if best.as_ref().is_none_or(|b| ss < b.1) {
                best = Some((c, ss, shape));
            }
        }
    }
    match best {
        Some((c, ss, shape)) if ss < 0.8 * ss0 && c[5] > 0.0 => (
            terms_of(&c),
            Some(match shape {
                ExtraShape::Gm(tc_s) => ExtraTerm::GaussMarkov { sigma: c[5].sqrt(), tc_s },
                ExtraShape::Sine(frequency_hz) => ExtraTerm::Sine { amplitude: c[5].sqrt(), frequency_hz },
            }),
        ),
        _ => (terms_of(&c0), None),
    }
}

/// One fit of the extended basis (with the band-limited term `extra`, if any) to the Allan variance of `p`:
/// weighted NNLS, weights from the measured variance, then once more with weights from the fitted model.
/// Returns the coefficients (variances) and the weighted residual sum of squares of the last fit.
fn reweighted_fit(p: &[&AllanPoint], extra: Option<ExtraShape>) -> Option<(Vec<f64>, f64)> {
    let measured: Vec<f64> = p.iter().map(|q| q.avar()).collect();
    let mut reference = measured.clone();
    let mut out = None;
    for _ in 0..2 {
        let w: Vec<f64> = p.iter().zip(&reference).map(|(q, r)| 1.0 / (2.0 * q.rel_uncertainty * r)).collect();
        let rows: Vec<Vec<f64>> =
            p.iter().zip(&w).map(|(q, w)| extended_basis(q.tau_s, extra).iter().map(|b| b * w).collect()).collect();
        let y: Vec<f64> = measured.iter().zip(&w).map(|(m, w)| m * w).collect();
        let (c, _) = nnls_normal(&rows, &y)?;
        let model: Vec<f64> =
            p.iter().map(|q| extended_basis(q.tau_s, extra).iter().zip(&c).map(|(b, c)| b * c).sum()).collect();
        let ss: f64 = p
            .iter()
            .zip(&measured)
            .zip(&model)
            .map(|((q, m), md)| ((md - m) / (2.0 * q.rel_uncertainty * md.max(f64::MIN_POSITIVE))).powi(2))
            .sum();
        out = Some((c, ss));
        if model.iter().any(|v| v.is_nan() || *v <= 0.0) {
            break;
        }
        reference = model;
    }
    out
}

/// The candidate band-limited terms for a curve from `tmin` to `tmax` (s): Gauss-Markov correlation times from
/// `tmin`, 4 per decade, below `tmax`; then sinusoid frequencies from 1 / (4 tmax), 12 per decade, below
/// 1 / (2 tmin).
fn extra_shapes(tmin: f64, tmax: f64) -> Vec<ExtraShape> {
    let mut shapes = Vec::new();
    let mut tc = tmin;
    while tc < tmax {
        shapes.push(ExtraShape::Gm(tc));
        tc *= 10f64.powf(0.25);
    }
    let mut f = 1.0 / (4.0 * tmax);
    while f < 0.5 / tmin {
        shapes.push(ExtraShape::Sine(f));
        f *= 10f64.powf(1.0 / 12.0);
    }
    shapes
}

/// The IEEE 952 terms from the first five fitted variances.
fn terms_of(c: &[f64]) -> NoiseTerms {
    NoiseTerms {
        quantization_q: c[0].sqrt(),
        random_walk_n: c[1].sqrt(),
        bias_instability_b: c[2].sqrt(),
        rate_random_walk_k: c[3].sqrt(),
        ramp_r: c[4].sqrt(),
    }
}

/// The term that dominates the Allan variance of `t` at `tau` (s).
fn dominant_term(t: &NoiseTerms, tau: f64) -> &'static str {
    let parts = [
        ("quantization", 3.0 * t.quantization_q.powi(2) / (tau * tau)),
        ("white", t.random_walk_n.powi(2) / tau),
        ("bias instability", 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI * t.bias_instability_b.powi(2)),
        ("rate random walk", t.rate_random_walk_k.powi(2) * tau / 3.0),
        ("rate ramp", t.ramp_r.powi(2) * tau * tau / 2.0),
    ];
    parts.iter().max_by(|a, b| a.1.total_cmp(&b.1)).map_or("white", |p| p.0)
}

/// The IEEE 952 extension of one channel (`m`: the whole record's cluster sizes): fitted on the whole record
/// and on the first half; on the second half, the data's ADEV against the base SIMULATION (white, std of the
/// first half; stream + 100) and the extended SIMULATION (terms of the first half; streams + 200, + 300).
pub(crate) fn held_out_noise_extension(
    samples: &[f64],
    rate_hz: f64,
    m: &[usize],
    seed: u64,
    stream: u64,
) -> NoiseExtension {
    let half = samples.len() / 2;
    let (first, second) = (&samples[..half], &samples[half..]);
    let (terms_all, extra_all) = fit_extended_noise(&overlapping_allan_deviation(samples, rate_hz, m));
    let points_first = overlapping_allan_deviation(first, rate_hz, &clusters(half));
    let (terms_first_half, extra_first_half) = fit_extended_noise(&points_first);
    let l2 = second.len();
    let m2 = clusters(l2);
    let held_out_data = curve(second, rate_hz, &m2);
    let held_out_base_sim = curve(&white(l2, white_std(&[first]), seed, stream + 100), rate_hz, &m2);
    let mut ext = generate_noise_terms(&terms_first_half, l2, rate_hz, seed, stream + 200);
    if let Some(extra) = extra_first_half {
        for (y, x) in ext.iter_mut().zip(extra.generate(l2, rate_hz, seed, stream + 300)) {
            *y += x;
        }
    }
    let held_out_extended_sim = curve(&ext, rate_hz, &m2);
    let long_tau = m2.get(long_index(l2, &m2)).map_or(1.0, |c| *c as f64 / rate_hz);
    NoiseExtension {
        held_out_rms_log10_base: rms_log10(&held_out_base_sim, &held_out_data, l2, rate_hz),
        held_out_rms_log10_extended: rms_log10(&held_out_extended_sim, &held_out_data, l2, rate_hz),
        dominant_term: dominant_term(&terms_all, long_tau),
        terms_all,
        terms_first_half,
        extra_all,
        extra_first_half,
        held_out_data,
        held_out_base_sim,
        held_out_extended_sim,
    }
}
