//! The noise model of one channel, named from its Allan variance (docs/analysis.md#noise-model): the
//! classic terms of IEEE Std 952-1997 Annex C plus a first-order Gauss-Markov process and sway,
//!
//! `AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + sigma^2 g(tau / T) + K^2 tau / 3 + R^2 tau^2 / 2`
//! `          + S^2 h(tau / T) / tau^2`
//!
//! (quantisation Q, white noise N, bias instability B, Gauss-Markov sigma with correlation time T, rate random
//! walk K, rate ramp R, sway S: a bounded integral, Gauss-Markov with correlation time T; `g` from
//! [`gauss_markov_allan_variance`], `h` from [`sway_allan_variance`]), fitted by weighted least squares on the
//! overlapping Allan variance at octave-spaced cluster sizes, with non-negative squared coefficients. Each
//! point's weight is its variance `2 AVAR^2 / edf`, with the equivalent degrees of freedom of the overlapping
//! estimator for the model's mixture of noise types at that tau ([`overlapping_allan_edf`], by
//! Satterthwaite's rule) and a model error of [`MODEL_ERROR`], iterated from the measured to the model
//! variance of the best fit without sway.
//!
//! **Sway** bends from white noise to the quantisation slope at its correlation time; chance gives a white
//! record's last Allan points the same bend. So its correlation time is at most a quarter of the longest
//! averaging time fitted (two octaves of points beyond it), the weights never follow a fit with sway (they
//! would weigh the points that call for it as quantisation's), and sway is fitted only beside white noise,
//! the floor its mean falls to (alone, it extrapolated below the data: on the PSINS y gyro 0.49 of the
//! measured Allan deviation at 256 s). Measured on SIMULATION (white noise, 22 records of 600 s, 132
//! channels): sway named on none, quantisation on 2 (as before sway); sway alone and with the weights
//! following it, on 4 of the first 12 channels.
//!
//! **Which terms are named.** Every subset of the seven terms is fitted (the Gauss-Markov or sway correlation
//! time profiled over a log grid and refined; a subset holds at most one of the two, which share the one
//! correlation time of the profile); the subset with the smallest `chi^2 / s^2 + c k` is named, with `k`
//! its parameters (2 for Gauss-Markov and sway), `c` the upper [`TERM_ALPHA`] quantile of chi-square with one degree
//! of freedom and `s^2 >= 1` the over-dispersion of the best fit (its `chi^2` over its degrees of freedom).
//! A named term therefore lowers `chi^2 / s^2` by more than `c` per parameter. Standard errors are those of
//! the weighted least squares (the log correlation time linearised), scaled by the named model's own
//! over-dispersion and by [`CORRELATION_FACTOR`] for the correlation of neighbouring Allan points. The named model is compared with white noise alone by the same criterion.

use std::f64::consts::{LN_2, PI};

use serde::Serialize;

use super::{FigureData, CHANNELS};
use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::{DEG_PER_HOUR, MICRO_G};
use crate::stats::linfit::chi_square_quantile_upper;
use crate::stats::noise::{
    difference_lag1_autocorrelation, gauss_markov_allan_variance, overlapping_allan_deviation, overlapping_allan_edf,
    sway_allan_variance, AllanNoiseKind,
};
use crate::stats::solve::solve_spd;

/// Significance level of one named term (per parameter).
pub const TERM_ALPHA: f64 = 0.01;
/// Fewest Allan points a fit needs.
pub const MIN_POINTS: usize = 4;
/// Factor on the least-squares standard errors for the correlation of neighbouring octave points (the fit
/// treats them as independent). Measured on SIMULATION (host-tests/tests/noise_model.rs: quantisation, white
/// noise and Gauss-Markov, 8 records of 1 h) before [`MODEL_ERROR`] was added: without the factor the RMS of
/// (error / stated error) over the 24 estimates was 1.50; with both, the same test gives 0.52 (conservative).
pub const CORRELATION_FACTOR: f64 = 1.5;
/// Relative standard deviation added in quadrature to every Allan variance point for the model's own error
/// (the six terms are an approximation of a real sensor's noise: sway, dither, filters): 10 % in variance, 5 %
/// in deviation. Without it the first points (hundreds of thousands of degrees of freedom) decide every fit
/// of measured data alone.
pub const MODEL_ERROR: f64 = 0.1;
/// Sway's correlation time is at most the longest averaging time fitted over this (two octaves).
const SWAY_OCTAVES_BEYOND: f64 = 4.0;
/// Gauss-Markov correlation times tried per decade.
const TC_PER_DECADE: f64 = 8.0;

/// One term of the noise model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Term {
    /// Quantisation noise Q (Allan deviation slope -1).
    Quantization,
    /// White rate noise N: angle / velocity random walk (slope -1/2).
    White,
    /// Bias instability B (flat; the floor is 0.664 B).
    BiasInstability,
    /// First-order Gauss-Markov process sigma, with its correlation time (a hump at 1.89 T).
    GaussMarkov,
    /// Rate random walk K (slope +1/2).
    RateRandomWalk,
    /// Rate ramp R (slope +1).
    RateRamp,
    /// Sway S: the channel's integral (angle, velocity) a Gauss-Markov process of standard deviation S with its
    /// correlation time (slope -1/2 below it, -1 beyond: white noise that integrates to a bounded tilt).
    Sway,
}

impl Term {
    /// Every term, in model order.
    pub const ALL: [Term; 7] = [
        Term::Quantization,
        Term::White,
        Term::BiasInstability,
        Term::GaussMarkov,
        Term::RateRandomWalk,
        Term::RateRamp,
        Term::Sway,
    ];

    /// The symbol used in text and figures: Q, N, B, GM, K, R, S.
    pub fn symbol(self) -> &'static str {
        ["Q", "N", "B", "GM", "K", "R", "S"][self as usize]
    }

    /// The name in words.
    pub fn words(self) -> &'static str {
        [
            "quantisation",
            "white noise (random walk)",
            "bias instability",
            "Gauss-Markov",
            "rate random walk",
            "rate ramp",
            "sway (a bounded angle or velocity)",
        ][self as usize]
    }

    /// Whether the term has a correlation time (Gauss-Markov and sway).
    pub fn has_time(self) -> bool {
        matches!(self, Term::GaussMarkov | Term::Sway)
    }

    /// Parameters the term adds (a correlation time is one more).
    pub fn parameters(self) -> usize {
        if self.has_time() {
            2
        } else {
            1
        }
    }

    /// Allan variance of the term at `tau_s` per unit squared coefficient (`tc_s`: Gauss-Markov correlation
    /// time, s).
    pub fn basis(self, tau_s: f64, tc_s: f64) -> f64 {
        match self {
            Term::Quantization => 3.0 / (tau_s * tau_s),
            Term::White => 1.0 / tau_s,
            Term::BiasInstability => 2.0 * LN_2 / PI,
            Term::GaussMarkov => gauss_markov_allan_variance(1.0, tc_s, tau_s),
            Term::RateRandomWalk => tau_s / 3.0,
            Term::RateRamp => tau_s * tau_s / 2.0,
            Term::Sway => sway_allan_variance(1.0, tc_s, tau_s),
        }
    }

    /// The noise type that sets the degrees of freedom of an Allan point where this term dominates.
    fn edf_kind(self, tau_s: f64, tc_s: f64) -> AllanNoiseKind {
        match self {
            Term::Quantization => AllanNoiseKind::Quantization,
            Term::White => AllanNoiseKind::White,
            Term::BiasInstability => AllanNoiseKind::BiasInstability,
            Term::GaussMarkov if tau_s < tc_s => AllanNoiseKind::RateRandomWalk,
            Term::GaussMarkov => AllanNoiseKind::White,
            Term::RateRandomWalk | Term::RateRamp => AllanNoiseKind::RateRandomWalk,
            Term::Sway if tau_s < tc_s => AllanNoiseKind::White,
            Term::Sway => AllanNoiseKind::Quantization,
        }
    }

    /// SI unit of the coefficient for a gyro (rad/s samples) or an accelerometer (m/s^2 samples).
    pub fn unit_si(self, gyro: bool) -> &'static str {
        let (g, a) = [
            ("rad", "m/s"),
            ("rad/sqrt(s)", "m/s/sqrt(s)"),
            ("rad/s", "m/s^2"),
            ("rad/s", "m/s^2"),
            ("rad/s/sqrt(s)", "m/s^2/sqrt(s)"),
            ("rad/s^2", "m/s^3"),
            ("rad", "m/s"),
        ][self as usize];
        if gyro {
            g
        } else {
            a
        }
    }

    /// The human unit of the coefficient and the SI value of one of it.
    pub fn unit_human(self, gyro: bool) -> (&'static str, f64) {
        let deg = PI / 180.0;
        if gyro {
            [
                ("arcsec", 1.0 / ARCSEC_PER_RAD),
                ("deg/sqrt(h)", deg / 60.0),
                ("deg/h", DEG_PER_HOUR),
                ("deg/h", DEG_PER_HOUR),
                ("deg/h/sqrt(h)", DEG_PER_HOUR / 60.0),
                ("deg/h^2", DEG_PER_HOUR / 3600.0),
                ("arcsec", 1.0 / ARCSEC_PER_RAD),
            ][self as usize]
        } else {
            [
                ("ug*s", MICRO_G),
                ("ug/sqrt(Hz)", MICRO_G),
                ("ug", MICRO_G),
                ("ug", MICRO_G),
                ("ug/sqrt(s)", MICRO_G),
                ("ug/s", MICRO_G),
                ("ug*s", MICRO_G),
            ][self as usize]
        }
    }
}

/// A term of a fitted model, with its value and standard error in SI and in human units.
#[derive(Clone, Debug, Serialize)]
pub struct NamedTerm {
    /// The term (`quantization`, `white`, `bias_instability`, `gauss_markov`, `rate_random_walk`,
    /// `rate_ramp`, `sway`).
    pub term: Term,
    /// Q, N, B, GM, K, R or S.
    pub symbol: String,
    /// The coefficient, SI (`unit_si`).
    pub value_si: f64,
    /// Its standard error, SI.
    pub std_error_si: f64,
    /// SI unit of the coefficient.
    pub unit_si: String,
    /// The coefficient in `unit`.
    pub value: f64,
    /// Its standard error in `unit`.
    pub std_error: f64,
    /// Human unit (deg/sqrt(h), deg/h, arcsec, ug/sqrt(Hz), ug, ug*s, ...).
    pub unit: String,
    /// Gauss-Markov or sway correlation time, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_c_s: Option<f64>,
    /// Its standard error, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tau_c_std_error_s: Option<f64>,
    /// How much `chi^2 / s^2` rises when the term is left out (the others refitted); 0 for a model of one term.
    pub delta_chi_square: f64,
}

impl NamedTerm {
    /// The term's Allan variance at `tau_s`, SI squared.
    pub fn allan_variance(&self, tau_s: f64) -> f64 {
        self.value_si * self.value_si * self.term.basis(tau_s, self.tau_c_s.unwrap_or(1.0))
    }

    /// "N = 0.0123 +- 0.0004 deg/sqrt(h)" (and "tau_c 1.2 +- 0.1 s" for Gauss-Markov and sway).
    pub fn text(&self) -> String {
        let mut s = format!("{} = {} +- {} {}", self.symbol, sig(self.value), sig(self.std_error), self.unit);
        if let (Some(t), Some(e)) = (self.tau_c_s, self.tau_c_std_error_s) {
            s.push_str(&format!(", tau_c {} +- {} s", sig(t), sig(e)));
        }
        s
    }
}

/// A number with three significant digits, plain for 1e-3..1e5 and in exponent form otherwise.
pub fn sig(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() {
        "nan".into()
    } else if a == 0.0 || (1e-3..1e5).contains(&a) {
        let decimals = if a == 0.0 { 0 } else { (2 - a.log10().floor() as i32).max(0) as usize };
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

/// One Allan point of the fit.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FitPoint {
    /// Averaging time, s.
    pub tau_s: f64,
    /// Allan deviation, SI.
    pub adev: f64,
    /// Its standard deviation, SI (from the equivalent degrees of freedom of the named model).
    pub adev_std: f64,
    /// Equivalent degrees of freedom.
    pub edf: f64,
}

/// The noise model of one channel (the `noise_model[]` entries of docs/formats.md#analysis-json).
#[derive(Clone, Debug, Serialize)]
pub struct NoiseModel {
    /// Channel name (`gx_radps`, ...).
    pub channel: String,
    /// Samples fitted (the longest dwell, its mean and trend removed).
    pub samples: usize,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// What white noise would make the error of this dwell's mean (its samples' standard deviation over
    /// `sqrt(samples)`), over what the named model says it is (its Allan deviation at the dwell's length):
    /// above 1 the white-noise standard errors are too large, below 1 too small.
    pub white_error_factor: f64,
    /// The named terms' symbols joined by " + " ("Q + N + GM").
    pub named: String,
    /// The named terms.
    pub terms: Vec<NamedTerm>,
    /// Allan points fitted.
    pub points: usize,
    /// The named model's weighted chi-square.
    pub chi_square: f64,
    /// Its degrees of freedom (points minus parameters).
    pub dof: usize,
    /// Over-dispersion `s^2 >= 1` of the best fit of all terms, the scale of the criterion.
    pub overdispersion: f64,
    /// White noise alone (N), fitted with the same weights.
    pub white_only: NamedTerm,
    /// Its chi-square.
    pub white_only_chi_square: f64,
    /// Whether the named model is better than white noise alone by the criterion.
    pub better_than_white_only: bool,
    /// Lag-1 autocorrelation of the sample differences ([`difference_lag1_autocorrelation`]).
    pub lag1_difference_autocorrelation: Option<f64>,
    /// Its standard error, about `1 / sqrt(n)`.
    pub lag1_std_error: f64,
    /// The Allan points fitted (for the figures).
    #[serde(skip)]
    pub fit_points: Vec<FitPoint>,
}

impl NoiseModel {
    /// The named model's Allan deviation at `tau_s`, SI.
    pub fn allan_deviation(&self, tau_s: f64) -> f64 {
        self.terms.iter().map(|t| t.allan_variance(tau_s)).sum::<f64>().sqrt()
    }

    /// One line: the named terms, the comparison with white noise alone and the lag-1 correlation.
    pub fn text(&self) -> String {
        let terms: Vec<String> = self.terms.iter().map(NamedTerm::text).collect();
        let fit = |chi2: f64, k: usize| chi2 / self.points.saturating_sub(k).max(1) as f64;
        let compare = if self.better_than_white_only {
            format!(
                "better than white only ({}; chi2/dof {} against {})",
                self.white_only.text(),
                sig(fit(self.chi_square, self.points - self.dof)),
                sig(fit(self.white_only_chi_square, 1))
            )
        } else {
            format!("not better than white only (chi2/dof {})", sig(fit(self.white_only_chi_square, 1)))
        };
        let lag1 = self
            .lag1_difference_autocorrelation
            .map_or("-".to_string(), |r| format!("{r:+.3} +- {:.3} (white: -0.5)", self.lag1_std_error));
        format!(
            "{}: {}; {compare}; lag-1 correlation of the differences {lag1}; white-noise error of a {:.0}-s mean \
             {}x the named model's",
            self.channel,
            terms.join(", "),
            self.samples as f64 / self.rate_hz,
            sig(self.white_error_factor)
        )
    }
}

/// A fitted subset of terms.
#[derive(Clone, Debug)]
struct SubsetFit {
    terms: Vec<Term>,
    /// Squared coefficients, in the order of `terms`.
    c: Vec<f64>,
    /// Gauss-Markov or sway correlation time, s (when the subset has one).
    tc_s: f64,
    chi2: f64,
    k: usize,
}

impl SubsetFit {
    fn model(&self, tau_s: f64) -> f64 {
        self.terms.iter().zip(&self.c).map(|(t, c)| c * t.basis(tau_s, self.tc_s)).sum()
    }
}

/// The data of one fit: Allan variances at octave-spaced taus and their standard deviations.
struct Curve {
    tau: Vec<f64>,
    m: Vec<usize>,
    avar: Vec<f64>,
    sd: Vec<f64>,
    /// Equivalent degrees of freedom of each point (for the named model's mixture of noise types).
    edf: Vec<f64>,
    n: usize,
}

impl Curve {
    /// Weighted least squares of the subset at correlation time `tc_s`; `None` if singular or a coefficient
    /// is not positive.
    fn fit(&self, terms: &[Term], tc_s: f64) -> Option<(SubsetFit, Vec<Vec<f64>>)> {
        let k = terms.len();
        let cols: Vec<Vec<f64>> = terms
            .iter()
            .map(|t| self.tau.iter().zip(&self.sd).map(|(&tau, s)| t.basis(tau, tc_s) / s).collect())
            .collect();
        let b: Vec<f64> = self.avar.iter().zip(&self.sd).map(|(y, s)| y / s).collect();
        let ata: Vec<Vec<f64>> =
            (0..k).map(|i| (0..k).map(|j| cols[i].iter().zip(&cols[j]).map(|(a, b)| a * b).sum()).collect()).collect();
        let atb: Vec<f64> = cols.iter().map(|c| c.iter().zip(&b).map(|(a, b)| a * b).sum()).collect();
        let (c, inverse) = solve_spd(&ata, &atb)?;
        if c.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return None;
        }
        let mut fit =
            SubsetFit { terms: terms.to_vec(), c, tc_s, chi2: 0.0, k: terms.iter().map(|t| t.parameters()).sum() };
        fit.chi2 = self.chi2(&fit);
        Some((fit, inverse))
    }

    fn chi2(&self, fit: &SubsetFit) -> f64 {
        self.tau.iter().zip(&self.avar).zip(&self.sd).map(|((&t, y), s)| ((fit.model(t) - y) / s).powi(2)).sum()
    }

    /// The best fit of the subset: over the correlation-time grid and a golden-section refinement when it holds
    /// the Gauss-Markov term or sway.
    fn best(&self, terms: &[Term], tc_grid: &[f64]) -> Option<SubsetFit> {
        if !terms.iter().any(|t| t.has_time()) {
            return self.fit(terms, 1.0).map(|f| f.0);
        }
        // Sway's bend from white noise to the quantisation slope is named only where two octaves of points
        // beyond it show it: a white record's last points, low by chance, are not sway.
        let longest_tau = self.tau.last().copied().unwrap_or(0.0);
        let sway_grid: Vec<f64>;
        let tc_grid = if terms.contains(&Term::Sway) {
            sway_grid = tc_grid.iter().copied().filter(|&tc| tc <= longest_tau / SWAY_OCTAVES_BEYOND).collect();
            if sway_grid.is_empty() {
                return None;
            }
            &sway_grid[..]
        } else {
            tc_grid
        };
        let at = |ln_tc: f64| self.fit(terms, ln_tc.exp()).map(|f| f.0);
        let (i, best) = tc_grid
            .iter()
            .enumerate()
            .filter_map(|(i, &tc)| at(tc.ln()).map(|f| (i, f)))
            .min_by(|a, b| a.1.chi2.total_cmp(&b.1.chi2))?;
        let (mut lo, mut hi) = (tc_grid[i.saturating_sub(1)].ln(), tc_grid[(i + 1).min(tc_grid.len() - 1)].ln());
        let cost = |x: f64| at(x).map_or(f64::INFINITY, |f| f.chi2);
        let g = (5f64.sqrt() - 1.0) / 2.0;
        for _ in 0..30 {
            let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
            if cost(a) < cost(b) {
                hi = b;
            } else {
                lo = a;
            }
        }
        match at(0.5 * (lo + hi)) {
            Some(f) if f.chi2 < best.chi2 => Some(f),
            _ => Some(best),
        }
    }

    /// Updates the standard deviations from `model` (Satterthwaite's rule over its terms' noise types).
    fn reweight(&mut self, model: &SubsetFit) {
        for i in 0..self.tau.len() {
            let tau = self.tau[i];
            let parts: Vec<(f64, f64)> = model
                .terms
                .iter()
                .zip(&model.c)
                .map(|(t, c)| {
                    let kind = t.edf_kind(tau, model.tc_s);
                    (c * t.basis(tau, model.tc_s), overlapping_allan_edf(kind, self.n, self.m[i]))
                })
                .collect();
            let total: f64 = parts.iter().map(|p| p.0).sum();
            let denom: f64 = parts.iter().map(|(a, e)| a * a / e).sum();
            if total > 0.0 && denom > 0.0 {
                self.edf[i] = total * total / denom;
                self.sd[i] = total * (2.0 / self.edf[i] + MODEL_ERROR * MODEL_ERROR).sqrt();
            }
        }
    }
}

/// Octave-spaced cluster sizes 1, 2, 4, ... with at least three clusters in the record.
fn octaves(n: usize) -> Vec<usize> {
    std::iter::successors(Some(1usize), |m| m.checked_mul(2)).take_while(|m| 3 * m <= n).collect()
}

/// Every non-empty subset of the terms with at most one correlation time, fitted (the best over the
/// correlation time for Gauss-Markov and sway).
fn all_subsets(curve: &Curve, tc_grid: &[f64]) -> Vec<SubsetFit> {
    (1u32..1 << Term::ALL.len())
        .filter_map(|mask| {
            let terms: Vec<Term> = Term::ALL.into_iter().filter(|t| mask & (1 << *t as u32) != 0).collect();
            let k: usize = terms.iter().map(|t| t.parameters()).sum();
            let one_time = terms.iter().filter(|t| t.has_time()).count() <= 1;
            // Sway only beside white noise: the floor its mean falls to, which the last points may not show.
            let sway_floored = !terms.contains(&Term::Sway) || terms.contains(&Term::White);
            if k >= curve.tau.len() || !one_time || !sway_floored {
                return None;
            }
            curve.best(&terms, tc_grid)
        })
        .collect()
}

/// The over-dispersion of the best fit and the subset that minimises `chi^2 / s^2 + c k`.
fn choose(fits: &[SubsetFit], points: usize) -> Option<(f64, SubsetFit)> {
    let best = fits.iter().min_by(|a, b| a.chi2.total_cmp(&b.chi2))?;
    let s2 = (best.chi2 / points.saturating_sub(best.k).max(1) as f64).max(1.0);
    let c = chi_square_quantile_upper(TERM_ALPHA, 1.0);
    let crit = |f: &SubsetFit| f.chi2 + c * f.k as f64;
    let chosen = fits.iter().min_by(|a, b| crit(a).total_cmp(&crit(b)))?;
    Some((s2, chosen.clone()))
}

/// The noise model of one channel's `samples` (SI: rad/s for a gyro, m/s^2 for an accelerometer) at
/// `rate_hz`. `None` when the record gives fewer than [`MIN_POINTS`] Allan points or no term fits.
pub fn noise_model(channel: &str, gyro: bool, samples: &[f64], rate_hz: f64) -> Option<NoiseModel> {
    noise_model_above(channel, gyro, samples, rate_hz, 0.0)
}

/// [`noise_model`] fitted to the Allan points at `tau >= min_tau_s` only: the model of the noise at the
/// averaging times that matter (a dwell mean of seconds does not see a ring-laser gyro's dither at tens of
/// milliseconds, whose shape no term of the model has and which would otherwise decide the fit).
pub fn noise_model_above(
    channel: &str,
    gyro: bool,
    samples: &[f64],
    rate_hz: f64,
    min_tau_s: f64,
) -> Option<NoiseModel> {
    let n = samples.len();
    let points = overlapping_allan_deviation(samples, rate_hz, &octaves(n));
    let points: Vec<_> =
        points.into_iter().filter(|p| p.adev.is_finite() && p.adev > 0.0 && p.tau_s >= min_tau_s).collect();
    if points.len() < MIN_POINTS {
        return None;
    }
    let mut curve = Curve {
        tau: points.iter().map(|p| p.tau_s).collect(),
        m: points.iter().map(|p| p.cluster_size).collect(),
        avar: points.iter().map(|p| p.avar()).collect(),
        sd: Vec::new(),
        edf: points.iter().map(|p| overlapping_allan_edf(AllanNoiseKind::White, n, p.cluster_size)).collect(),
        n,
    };
    curve.sd =
        curve.avar.iter().zip(&curve.edf).map(|(y, e)| y * (2.0 / e + MODEL_ERROR * MODEL_ERROR).sqrt()).collect();
    let record_s = n as f64 / rate_hz;
    let decades = (record_s / 2.0 / (2.0 / rate_hz)).log10().max(0.0);
    let tc_grid: Vec<f64> = (0..=(decades * TC_PER_DECADE).ceil() as usize)
        .map(|i| 2.0 / rate_hz * 10f64.powf(i as f64 / TC_PER_DECADE))
        .collect();
    // The weights follow the best fit of all terms (the closest to the data), not the named model; sway left
    // out, whose bend would otherwise weigh the points that call for it.
    for _pass in 0..3 {
        let fits = all_subsets(&curve, &tc_grid);
        let without_sway = fits.iter().filter(|f| !f.terms.contains(&Term::Sway));
        let best = without_sway.min_by(|a, b| a.chi2.total_cmp(&b.chi2))?;
        curve.reweight(best);
    }
    let fits = all_subsets(&curve, &tc_grid);
    let (s2, chosen) = choose(&fits, curve.tau.len())?;
    let white = curve.fit(&[Term::White], 1.0)?;
    let terms = named_terms(&curve, &chosen, &fits, s2, gyro)?;
    let white_only = named_terms(&curve, &white.0, &fits, s2, gyro)?.pop()?;
    let k = chosen.k;
    let mean = samples.iter().sum::<f64>() / n as f64;
    let sample_std = (samples.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1).max(1) as f64).sqrt();
    let named_adev_record: f64 = terms.iter().map(|t| t.allan_variance(record_s)).sum::<f64>().sqrt();
    Some(NoiseModel {
        channel: channel.into(),
        samples: n,
        rate_hz,
        white_error_factor: sample_std / (n as f64).sqrt() / named_adev_record.max(f64::MIN_POSITIVE),
        named: chosen.terms.iter().map(|t| t.symbol()).collect::<Vec<_>>().join(" + "),
        terms,
        points: curve.tau.len(),
        chi_square: chosen.chi2,
        dof: curve.tau.len() - k,
        overdispersion: s2,
        white_only,
        white_only_chi_square: white.0.chi2,
        better_than_white_only: chosen.terms != [Term::White],
        lag1_difference_autocorrelation: difference_lag1_autocorrelation(samples),
        lag1_std_error: 1.0 / ((n.max(2) - 1) as f64).sqrt(),
        fit_points: (0..curve.tau.len())
            .map(|i| {
                let edf = curve.edf[i];
                let adev = curve.avar[i].sqrt();
                FitPoint { tau_s: curve.tau[i], adev, adev_std: adev / (2.0 * edf).sqrt(), edf }
            })
            .collect(),
    })
}

/// The terms of `fit` with standard errors (the inverse normal matrix with the log correlation time as one more
/// parameter, scaled by the fit's over-dispersion) and what leaving each out costs.
fn named_terms(curve: &Curve, fit: &SubsetFit, fits: &[SubsetFit], s2: f64, gyro: bool) -> Option<Vec<NamedTerm>> {
    let gm = fit.terms.iter().position(|t| t.has_time());
    let mut cols: Vec<Vec<f64>> = fit
        .terms
        .iter()
        .map(|t| curve.tau.iter().zip(&curve.sd).map(|(&tau, s)| t.basis(tau, fit.tc_s) / s).collect())
        .collect();
    if let Some(j) = gm {
        let h = 1e-4_f64;
        cols.push(
            curve
                .tau
                .iter()
                .zip(&curve.sd)
                .map(|(&tau, s)| {
                    let timed = fit.terms[j];
                    let up = timed.basis(tau, fit.tc_s * h.exp());
                    let down = timed.basis(tau, fit.tc_s * (-h).exp());
                    fit.c[j] * (up - down) / (2.0 * h) / s
                })
                .collect(),
        );
    }
    let p = cols.len();
    let ata: Vec<Vec<f64>> =
        (0..p).map(|i| (0..p).map(|j| cols[i].iter().zip(&cols[j]).map(|(a, b)| a * b).sum()).collect()).collect();
    let (_, inverse) = solve_spd(&ata, &vec![0.0; p])?;
    let own_s2 = (fit.chi2 / curve.tau.len().saturating_sub(fit.k).max(1) as f64).max(1.0);
    let out = fit
        .terms
        .iter()
        .enumerate()
        .map(|(j, &term)| {
            let value_si = fit.c[j].sqrt();
            let std_error_si = CORRELATION_FACTOR * (inverse[j][j] * own_s2).sqrt() / (2.0 * value_si);
            let (unit, per) = term.unit_human(gyro);
            let without: Vec<Term> = fit.terms.iter().copied().filter(|t| *t != term).collect();
            let delta_chi_square = fits.iter().find(|f| f.terms == without).map_or(0.0, |f| (f.chi2 - fit.chi2) / s2);
            let tc = gm.map(|_| fit.tc_s).filter(|_| term.has_time());
            NamedTerm {
                term,
                symbol: term.symbol().into(),
                value_si,
                std_error_si,
                unit_si: term.unit_si(gyro).into(),
                value: value_si / per,
                std_error: std_error_si / per,
                unit: unit.into(),
                tau_c_s: tc,
                tau_c_std_error_s: tc.map(|t| CORRELATION_FACTOR * t * (inverse[p - 1][p - 1] * own_s2).sqrt()),
                delta_chi_square,
            }
        })
        .collect();
    Some(out)
}

/// The noise model of every channel of the figure data that has samples (the longest dwell of a recording,
/// its mean and trend removed); empty for angles files.
pub(super) fn noise_models(figures: &FigureData) -> Vec<NoiseModel> {
    figures
        .longest_dwell
        .iter()
        .enumerate()
        .filter(|(_, s)| s.iter().any(|v| *v != 0.0))
        .filter_map(|(c, s)| noise_model(CHANNELS[c], c < 3, s, figures.rate_hz))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_read_with_three_significant_digits() {
        assert_eq!(sig(0.012345), "0.0123");
        assert_eq!(sig(12.345), "12.3");
        assert_eq!(sig(1234.6), "1235");
        assert_eq!(sig(1.5e-5), "1.50e-5");
        assert_eq!(sig(0.0), "0");
    }

    #[test]
    fn octave_clusters_leave_three_clusters() {
        assert_eq!(octaves(100), vec![1, 2, 4, 8, 16, 32]);
        assert!(octaves(2).is_empty());
    }
}
