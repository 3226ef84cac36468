//! The extended noise model of one channel: the IEEE Std 952 terms plus, where it helps, one band-limited term
//! (a Gauss-Markov process or a sinusoid), fitted to the Allan variance; and its gain on held-out data (fitted
//! on the first half of the record, its SIMULATION compared with the second half beside the base model's).

use super::generate::{gauss_markov, generate_noise_terms, sine, white};
use super::noise::{clusters, curve, long_index, rms_log10, white_std};
use super::NoiseExtension;
use crate::stats::noise::{
    fft_in_place, fit_noise_terms, gauss_markov_allan_variance, overlapping_allan_deviation, AllanPoint, NoiseTerms,
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

/// The columns of the extended basis a fit uses: quantization, white, bias instability, rate random walk, rate
/// ramp, band-limited term (the last only with a shape).
type Mask = [bool; 6];

/// Every column.
const ALL: Mask = [true; 6];

/// Index of the white term (the base model: never gated) and of the band-limited term in the basis.
const WHITE: usize = 1;
const EXTRA: usize = 5;

/// Names of the IEEE 952 columns of the basis.
const TERM_NAMES: [&str; 5] = ["quantization", "white", "bias instability", "rate random walk", "rate ramp"];

/// The held-out gate of a term: dropping it must raise the held-out chi^2 by at least this much
/// (dimensionless; chi^2 with one degree of freedom at 9 is a 3-sigma change)...
pub const GATE_MIN_DELTA_CHI2: f64 = 9.0;

/// ... and by at least this fraction of the held-out chi^2 with it (dimensionless): the overlapping Allan points
/// are correlated and the model is not exact, so a chi^2 difference in a model that misfits is inflated.
pub const GATE_MIN_RELATIVE_RISE: f64 = 0.10;

/// The points of a curve a fit can use (positive, finite, with an uncertainty).
fn usable(points: &[AllanPoint]) -> Vec<&AllanPoint> {
    points.iter().filter(|q| q.adev > 0.0 && q.adev.is_finite() && q.rel_uncertainty > 0.0).collect()
}

/// Fits the extended noise model to Allan points: the IEEE 952 terms (as [`fit_noise_terms`]: weighted
/// non-negative least squares on the variance, weights 1 / (2 u sigma^2), re-weighted once by the model) plus,
/// optionally, one band-limited term: a Gauss-Markov process (correlation time on a grid of 4 per decade over
/// the curve's tau range) or a sinusoid (frequency on a grid of 12 per decade from 1 / (4 tau_max) to 1 /
/// (2 tau_min)), the one with the smallest weighted residual; it is kept only if it lowers the weighted residual
/// sum by more than 20 %. No held-out gate: [`held_out_noise_extension`] gates the terms.
pub fn fit_extended_noise(points: &[AllanPoint]) -> (NoiseTerms, Option<ExtraTerm>) {
    let p = usable(points);
    match fit_masked(&p, ALL) {
        Some((c, shape)) => (terms_of(&c), extra_term(&c, shape)),
        None => (fit_noise_terms(points).map(|f| f.terms).unwrap_or_default(), None),
    }
}

/// The fit of the columns of `mask` to `p` (at least 6 points); with `mask[EXTRA]`, the best band-limited shape
/// is searched and kept when it lowers the weighted residual by more than 20 %. Returns the six coefficients (variances; zero for
/// the columns left out) and the shape.
fn fit_masked(p: &[&AllanPoint], mask: Mask) -> Option<(Vec<f64>, Option<ExtraShape>)> {
    if p.len() < 6 {
        return None;
    }
    let (c0, ss0) = reweighted_fit(p, None, mask)?;
    if !mask[EXTRA] {
        return Some((c0, None));
    }
    let mut best: Option<(Vec<f64>, f64, ExtraShape)> = None;
    for shape in extra_shapes(p[0].tau_s, p[p.len() - 1].tau_s) {
        if let Some((c, ss)) = reweighted_fit(p, Some(shape), mask) {
            if best.as_ref().is_none_or(|b| ss < b.1) {
                best = Some((c, ss, shape));
            }
        }
    }
    Some(match best {
        Some((c, ss, shape)) if ss < 0.8 * ss0 && c[EXTRA] > 0.0 => (c, Some(shape)),
        _ => (c0, None),
    })
}

/// The band-limited term of fitted coefficients `c` with `shape`.
fn extra_term(c: &[f64], shape: Option<ExtraShape>) -> Option<ExtraTerm> {
    let size = c.get(EXTRA).copied().unwrap_or(0.0).sqrt();
    shape.filter(|_| size > 0.0).map(|s| match s {
        ExtraShape::Gm(tc_s) => ExtraTerm::GaussMarkov { sigma: size, tc_s },
        ExtraShape::Sine(frequency_hz) => ExtraTerm::Sine { amplitude: size, frequency_hz },
    })
}

/// One fit of the extended basis (the columns of `mask`, with the band-limited term `extra`, if any) to the
/// Allan variance of `p`: weighted NNLS, weights from the measured variance, then once more with weights from the
/// fitted model. Returns the six coefficients (variances, zero where left out) and the weighted residual sum of
/// squares of the last fit.
fn reweighted_fit(p: &[&AllanPoint], extra: Option<ExtraShape>, mask: Mask) -> Option<(Vec<f64>, f64)> {
    let cols = |tau: f64| -> Vec<f64> {
        extended_basis(tau, extra).into_iter().enumerate().filter(|(i, _)| mask[*i]).map(|(_, b)| b).collect()
    };
    let measured: Vec<f64> = p.iter().map(|q| q.avar()).collect();
    let mut reference = measured.clone();
    let mut out = None;
    for _ in 0..2 {
        let w: Vec<f64> = p.iter().zip(&reference).map(|(q, r)| 1.0 / (2.0 * q.rel_uncertainty * r)).collect();
        let rows: Vec<Vec<f64>> =
            p.iter().zip(&w).map(|(q, w)| cols(q.tau_s).iter().map(|b| b * w).collect()).collect();
        let y: Vec<f64> = measured.iter().zip(&w).map(|(m, w)| m * w).collect();
        let (cm, _) = nnls_normal(&rows, &y)?;
        let model: Vec<f64> = p.iter().map(|q| cols(q.tau_s).iter().zip(&cm).map(|(b, c)| b * c).sum()).collect();
        let ss: f64 = p
            .iter()
            .zip(&measured)
            .zip(&model)
            .map(|((q, m), md)| ((md - m) / (2.0 * q.rel_uncertainty * md.max(f64::MIN_POSITIVE))).powi(2))
            .sum();
        let mut c = vec![0.0; 6];
        let mut it = cm.into_iter();
        for (i, ci) in c.iter_mut().enumerate().take(if extra.is_some() { 6 } else { 5 }) {
            if mask[i] {
                *ci = it.next().unwrap_or(0.0);
            }
        }
        out = Some((c, ss));
        if model.iter().any(|v| v.is_nan() || *v <= 0.0) {
            break;
        }
        reference = model;
    }
    out
}

/// The held-out misfit of a model (coefficients `c`, shape `extra`) to Allan points `p` of data it was not
/// fitted on: chi^2 = sum over the points of (ln(ADEV data / ADEV model) / u)^2, u the point's relative
/// uncertainty (dimensionless).
fn held_out_chi2(p: &[&AllanPoint], c: &[f64], extra: Option<ExtraShape>) -> f64 {
    p.iter()
        .map(|q| {
            let model: f64 = extended_basis(q.tau_s, extra).iter().zip(c).map(|(b, c)| b * c).sum();
            let z = 0.5 * (q.avar() / model.max(f64::MIN_POSITIVE)).ln() / q.rel_uncertainty;
            z * z
        })
        .sum()
}

/// The held-out verdict on one term of the extended model.
#[derive(Clone, Debug, PartialEq)]
pub struct TermGate {
    /// The term: "quantization", "bias instability", "rate random walk", "rate ramp", or the band-limited term
    /// ("Gauss-Markov, correlation time ... s", "sinusoid at ... Hz").
    pub term: String,
    /// Whether it stays in the extended model.
    pub kept: bool,
    /// Held-out chi^2 of the first half's model with the term (dimensionless).
    pub chi2_with: f64,
    /// Held-out chi^2 of the first half's model refitted without it (dimensionless).
    pub chi2_without: f64,
    /// Why, in words with the numbers.
    pub reason: String,
}

/// The name of column `i` of the basis with the band-limited `shape`.
fn term_name(i: usize, shape: Option<ExtraShape>) -> String {
    match (i, shape) {
        (EXTRA, Some(ExtraShape::Gm(tc))) => format!("Gauss-Markov, correlation time {tc:.3} s"),
        (EXTRA, Some(ExtraShape::Sine(f))) => format!("sinusoid at {f:.3} Hz"),
        _ => TERM_NAMES.get(i).map_or("band-limited term".to_string(), |s| s.to_string()),
    }
}

/// Whether dropping a term that raises the held-out chi^2 from `with` to `without` would lose a significant
/// improvement ([`GATE_MIN_DELTA_CHI2`], [`GATE_MIN_RELATIVE_RISE`]).
pub(crate) fn significant(with: f64, without: f64) -> bool {
    without - with >= GATE_MIN_DELTA_CHI2.max(GATE_MIN_RELATIVE_RISE * with)
}

/// A sinusoid of the model also has to be in the held-out samples: a direct fit on them must find at least
/// this fraction of its amplitude (dimensionless). An Allan-variance fit can use a sinusoid as a curve-fitting
/// device for a hump of another origin; a direct fit cannot.
pub const SINE_DIRECT_MIN_RATIO: f64 = 0.5;

/// The largest amplitude of a sinusoid fitted directly (least squares, mean removed) to `x` sampled at `rate_hz`,
/// over the frequencies within a factor 10^(1/24) of `f_hz` (half a step of the fit's frequency grid); SI of
/// `x`. The frequencies are the bins of one FFT of `x` zero-padded to at least twice its length, so they are
/// 1 / (2 duration) apart or closer: a sinusoid between two of them keeps at least 0.90 of its amplitude. The
/// cost is n log n (a scan of every frequency over every sample was quadratic: 221 s on a 1.85-million-sample
/// recording). `0` for fewer than two samples or a length whose transform cannot be planned.
pub fn direct_sine_amplitude(x: &[f64], rate_hz: f64, f_hz: f64) -> f64 {
    if x.len() < 2 {
        return 0.0;
    }
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let len = (2 * x.len()).next_power_of_two();
    let (mut re, mut im) = (vec![0.0; len], vec![0.0; len]);
    for (r, v) in re.iter_mut().zip(x) {
        *r = v - m;
    }
    if fft_in_place(&mut re, &mut im).is_err() {
        return 0.0;
    }
    let step = 10f64.powf(1.0 / 24.0);
    let bin_hz = rate_hz / len as f64;
    let lo = ((f_hz / step) / bin_hz).ceil().max(1.0) as usize;
    let hi = (((f_hz * step) / bin_hz).floor() as usize).min(len / 2);
    // A band narrower than a bin (a short record) takes the bin nearest `f_hz`.
    let nearest = ((f_hz / bin_hz).round() as usize).clamp(1, len / 2);
    let (lo, hi) = if lo > hi { (nearest, nearest) } else { (lo, hi) };
    (lo..=hi).map(|k| 2.0 * re[k].hypot(im[k]) / n).fold(0.0, f64::max)
}

/// The direct check of a kept sinusoid (coefficients `c`, `shape`) on the held-out samples `second`: `None`
/// when it passes or is no sinusoid; else the verdict that drops it (`with`: the held-out chi^2 with it).
fn sine_check(c: &[f64], shape: Option<ExtraShape>, second: &[f64], rate_hz: f64, with: f64) -> Option<TermGate> {
    let Some(ExtraShape::Sine(f)) = shape else { return None };
    let amplitude = c[EXTRA].sqrt();
    let direct = direct_sine_amplitude(second, rate_hz, f);
    (direct < SINE_DIRECT_MIN_RATIO * amplitude).then(|| TermGate {
        term: term_name(EXTRA, shape),
        kept: false,
        chi2_with: with,
        chi2_without: f64::NAN,
        reason: format!(
            "amplitude {amplitude:.3e} (SI) from the Allan fit, but a direct fit near {f:.3} Hz on the second half \
             finds {direct:.3e} ({:.1} x smaller; at least {SINE_DIRECT_MIN_RATIO} of it is required): a \
             curve-fitting device, not a sinusoid in the data",
            amplitude / direct.max(f64::MIN_POSITIVE)
        ),
    })
}

/// The held-out gate (backward elimination): the full model fitted on the first half (`pf`); terms fitted to zero
/// leave; then, as long as a term's removal (the first half refitted without it) raises the second half's
/// (`ps`) chi^2 by less than [`significant`] asks, the term of the smallest rise leaves; a
/// sinusoid must also pass [`sine_check`] on the second half's samples. The white term is the
/// base model and always stays. Returns the first half's gated coefficients, shape and the verdicts.
fn gate_terms(
    pf: &[&AllanPoint],
    ps: &[&AllanPoint],
    second: &[f64],
    rate_hz: f64,
    allow_extra: bool,
) -> Option<(Vec<f64>, Option<ExtraShape>, Vec<TermGate>)> {
    let (mut c, shape) = fit_masked(pf, [true, true, true, true, true, allow_extra])?;
    let mut mask: Mask = [true, true, true, true, true, shape.is_some()];
    let mut verdicts = Vec::new();
    loop {
        let with = held_out_chi2(ps, &c, shape);
        let zero: Vec<usize> = (0..6).filter(|&i| i != WHITE && mask[i] && c[i] <= 0.0).collect();
        for i in zero {
            mask[i] = false;
            let reason = "fitted to zero on the first half".to_string();
            verdicts.push(TermGate {
                term: term_name(i, shape),
                kept: false,
                chi2_with: with,
                chi2_without: with,
                reason,
            });
        }
        let mut rises: Vec<(usize, Vec<f64>, f64)> = Vec::new();
        for i in (0..6).filter(|&i| i != WHITE && mask[i]) {
            let mut m = mask;
            m[i] = false;
            let (ci, _) = reweighted_fit(pf, shape, m)?;
            let without = held_out_chi2(ps, &ci, shape);
            rises.push((i, ci, without));
        }
        let weakest = rises.iter().enumerate().min_by(|a, b| a.1 .2.total_cmp(&b.1 .2)).map(|(k, _)| k);
        match weakest {
            Some(k) if !significant(with, rises[k].2) => {
                let (i, ci, without) = rises.swap_remove(k);
                mask[i] = false;
                let reason = format!(
                    "held-out chi^2 {with:.1} with it, {without:.1} without (rise {:.1} < max({GATE_MIN_DELTA_CHI2}, {:.0} % of {with:.1}))",
                    without - with,
                    100.0 * GATE_MIN_RELATIVE_RISE
                );
                verdicts.push(TermGate {
                    term: term_name(i, shape),
                    kept: false,
                    chi2_with: with,
                    chi2_without: without,
                    reason,
                });
                c = ci;
            }
            _ => {
                if let Some(verdict) = sine_check(&c, shape.filter(|_| mask[EXTRA]), second, rate_hz, with) {
                    mask[EXTRA] = false;
                    c = reweighted_fit(pf, shape, mask)?.0;
                    verdicts.push(verdict);
                    continue;
                }
                for (i, _, without) in rises {
                    let reason =
                        format!("held-out chi^2 {with:.1} with it, {without:.1} without (rise {:.1})", without - with);
                    verdicts.push(TermGate {
                        term: term_name(i, shape),
                        kept: true,
                        chi2_with: with,
                        chi2_without: without,
                        reason,
                    });
                }
                let shape = shape.filter(|_| mask[EXTRA]);
                return Some((c, shape, verdicts));
            }
        }
    }
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

/// The gate run twice, with and without the band-limited term (which can stand in for an IEEE term on the first
/// half, a Gauss-Markov process for a rate random walk): the model with a band-limited term is taken only when
/// its held-out chi^2 is significantly lower ([`significant`]) than the gated IEEE-only model's; otherwise its
/// band-limited term is reported dropped beside the IEEE-only model's verdicts.
type Gated = (Vec<f64>, Option<ExtraShape>, Vec<TermGate>);
fn with_or_without_extra(pf: &[&AllanPoint], ps: &[&AllanPoint], second: &[f64], rate_hz: f64) -> Option<Gated> {
    let ieee = gate_terms(pf, ps, second, rate_hz, false)?;
    let Some(full) = gate_terms(pf, ps, second, rate_hz, true) else { return Some(ieee) };
    let Some(extra) = full.1 else {
        // The band-limited term was dropped inside the run with it: its verdict goes beside the IEEE-only model's.
        let (c, shape, mut gate) = ieee;
        gate.extend(full.2.into_iter().filter(|g| !TERM_NAMES.contains(&g.term.as_str())));
        return Some((c, shape, gate));
    };
    let (x_full, x_ieee) = (held_out_chi2(ps, &full.0, full.1), held_out_chi2(ps, &ieee.0, None));
    if significant(x_full, x_ieee) {
        return Some(full);
    }
    let (c, shape, mut gate) = ieee;
    gate.push(TermGate {
        term: term_name(EXTRA, Some(extra)),
        kept: false,
        chi2_with: x_full,
        chi2_without: x_ieee,
        reason: format!(
            "held-out chi^2 {x_full:.1} with it (and its own gated IEEE terms), {x_ieee:.1} for the gated IEEE \
             terms alone (fall {:.1} < max({GATE_MIN_DELTA_CHI2}, {:.0} %))",
            x_ieee - x_full,
            100.0 * GATE_MIN_RELATIVE_RISE
        ),
    });
    Some((c, shape, gate))
}

/// The last step of the gate: the extended model as a whole against the base model (white noise of the first
/// half's sample-to-sample std, coefficients `base_c`) on the held-out points `ps`, by the same rule
/// ([`significant`]). When the extension is not significantly better, every kept term is dropped and the extended
/// model is the base model (so it is too when no term is kept).
fn gate_against_base(
    c: Vec<f64>,
    shape: Option<ExtraShape>,
    mut gate: Vec<TermGate>,
    ps: &[&AllanPoint],
    base_c: &[f64],
) -> (Vec<f64>, Option<ExtraShape>, Vec<TermGate>) {
    let (with, base) = (held_out_chi2(ps, &c, shape), held_out_chi2(ps, base_c, None));
    let any_kept = gate.iter().any(|g| g.kept);
    if any_kept && significant(with, base) {
        return (c, shape, gate);
    }
    for g in gate.iter_mut().filter(|g| g.kept) {
        g.kept = false;
        g.reason = format!(
            "{}; but the extended model as a whole does not beat the base model on the held-out half (chi^2 {with:.1} \
             against {base:.1} for white noise alone; a fall of at least max({GATE_MIN_DELTA_CHI2}, {:.0} %) is \
             required)",
            g.reason,
            100.0 * GATE_MIN_RELATIVE_RISE
        );
    }
    let mut c = base_c.to_vec();
    c.push(0.0);
    (c, None, gate)
}

/// The IEEE 952 extension of one channel (`m`: the whole record's cluster sizes), gated on held-out data: fitted
/// on the first half, each term kept only when it improves the second half significantly ([`gate_terms`]); the
/// kept terms refitted on the whole record. On the second half, the data's ADEV against the base SIMULATION
/// (white, std of the first half; stream + 100) and the extended SIMULATION (kept terms of the first half;
/// streams + 200, + 300), and the held-out chi^2 of both models.
pub(crate) fn held_out_noise_extension(
    samples: &[f64],
    rate_hz: f64,
    m: &[usize],
    seed: u64,
    stream: u64,
) -> NoiseExtension {
    let half = samples.len() / 2;
    let (first, second) = (&samples[..half], &samples[half..]);
    let points_first = overlapping_allan_deviation(first, rate_hz, &clusters(half));
    let l2 = second.len();
    let m2 = clusters(l2);
    let points_second = overlapping_allan_deviation(second, rate_hz, &m2);
    let (pf, ps) = (usable(&points_first), usable(&points_second));
    let sigma_first = white_std(&[first]);
    let base_c = [0.0, sigma_first * sigma_first / rate_hz, 0.0, 0.0, 0.0];
    let (c_first, shape_first, gate) =
        with_or_without_extra(&pf, &ps, second, rate_hz).unwrap_or_else(|| (base_c.to_vec(), None, Vec::new()));
    let (c_first, shape_first, gate) = gate_against_base(c_first, shape_first, gate, &ps, &base_c);
    let mut kept: Mask = [false, true, false, false, false, shape_first.is_some()];
    for (i, name) in TERM_NAMES.iter().enumerate() {
        kept[i] |= gate.iter().any(|g| g.kept && g.term == *name);
    }
    let all_points = overlapping_allan_deviation(samples, rate_hz, m);
    let c_all = reweighted_fit(&usable(&all_points), shape_first, kept).map_or_else(|| c_first.clone(), |f| f.0);
    let shape_all = shape_first;
    let (terms_all, extra_all) = (terms_of(&c_all), extra_term(&c_all, shape_all));
    let (terms_first_half, extra_first_half) = (terms_of(&c_first), extra_term(&c_first, shape_first));
    let held_out_data = curve(second, rate_hz, &m2);
    let held_out_base_sim = curve(&white(l2, sigma_first, seed, stream + 100), rate_hz, &m2);
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
        held_out_chi2_base: held_out_chi2(&ps, &base_c, None),
        held_out_chi2_extended: held_out_chi2(&ps, &c_first, shape_first),
        held_out_points: ps.len(),
        gate,
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

#[cfg(test)]
mod tests {
    use super::direct_sine_amplitude;

    /// A sinusoid of 0.3 between the FFT's bins, in white noise of 1 (SI), at 100 Hz: the FFT scan finds its
    /// amplitude within 10 %, and equals the largest least-squares amplitude a brute-force scan of the same
    /// frequencies finds.
    #[test]
    fn the_direct_amplitude_of_a_sinusoid_between_bins_is_found() {
        let (n, rate_hz, f_hz, a) = (5_000usize, 100.0, 7.3137, 0.3);
        let mut state = 12345u64;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / rate_hz;
                let noise = (-2.0 * uniform().max(1e-300).ln()).sqrt() * (std::f64::consts::TAU * uniform()).cos();
                5.0 + a * (std::f64::consts::TAU * f_hz * t + 0.4).sin() + noise
            })
            .collect();
        let found = direct_sine_amplitude(&x, rate_hz, f_hz);
        assert!((found - a).abs() < 0.1 * a, "found {found}, planted {a}");
        // Brute force over a grid 10x finer than the FFT's: the FFT misses at most its scalloping (10 %) plus noise.
        let m = x.iter().sum::<f64>() / n as f64;
        let brute = (0..400)
            .map(|j| {
                let f = f_hz * (1.0 + (j as f64 - 200.0) * 1e-4);
                let (re, im) = x.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, v)| {
                    let (s, c) = (std::f64::consts::TAU * f * i as f64 / rate_hz).sin_cos();
                    (re + (v - m) * c, im + (v - m) * s)
                });
                2.0 * f64::hypot(re, im) / n as f64
            })
            .fold(0.0, f64::max);
        assert!(found <= brute * 1.0001 && found >= 0.9 * brute, "FFT {found}, brute force {brute}");
    }

    /// Fewer than two samples, or a band narrower than a bin, give an amplitude, never a panic.
    #[test]
    fn short_records_give_an_amplitude_without_panicking() {
        assert_eq!(direct_sine_amplitude(&[], 100.0, 5.0), 0.0);
        assert_eq!(direct_sine_amplitude(&[1.0], 100.0, 5.0), 0.0);
        let x = [0.0, 1.0, 0.0, -1.0];
        assert!((direct_sine_amplitude(&x, 100.0, 25.0) - 1.0).abs() < 1e-12);
    }
}
