//! Noise analysis of one sampled sensor channel (a gyro axis in rad/s, an accelerometer axis in m/s^2, or
//! any signal in a unit written `u` below), all in f64:
//!
//! - the overlapping Allan deviation ([`overlapping_allan_deviation`], IEEE Std 952-1997 Annex C) and
//!   log-spaced cluster sizes for it ([`log_spaced_clusters`]);
//! - identification of the five standard noise terms from an Allan curve by non-negative weighted least
//!   squares, and the classic graphical read-offs ([`fit_noise_terms`], [`classic_read_offs`]);
//! - the one-sided power spectral density by Welch's method ([`welch_psd`], Welch 1967), on a radix-2
//!   FFT ([`fft_in_place`]);
//! - the Ljung-Box whiteness test of a residual sequence ([`ljung_box`], Ljung & Box 1978), with the
//!   chi-square distribution through the regularized incomplete gamma function ([`chi_square_cdf`]);
//! - detection of an output quantization step ([`detect_quantization`]).
//!
//! Nothing here panics on short, empty or non-finite input: the Allan functions return fewer (or no)
//! points, the read-offs `None`, the special functions NaN outside their domain, the others a
//! [`NoiseError`].

use std::f64::consts::{LN_2, PI};

use crate::stats::solve::nnls_by_enumeration;

/// Why an analysis could not be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoiseError {
    /// Not enough data for the analysis.
    #[error("{what}: needs at least {needed}, got {got}")]
    TooShort {
        /// What was counted (samples, points, non-zero differences...).
        what: &'static str,
        /// The minimum the analysis needs.
        needed: usize,
        /// What was given.
        got: usize,
    },
    /// A parameter or the data out of the analysis' domain.
    #[error("invalid input: {0}")]
    Invalid(&'static str),
}

// ---------------------------------------------------------------------------------------------------
// Compensated arithmetic
// ---------------------------------------------------------------------------------------------------

/// Knuth's TwoSum: `a + b = s + e` exactly, `s` the rounded sum.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// Sum with Neumaier's compensation (error independent of the number of terms, to first order).
fn compensated_sum(values: impl IntoIterator<Item = f64>) -> f64 {
    let (mut s, mut c) = (0.0, 0.0);
    for v in values {
        let (t, e) = two_sum(s, v);
        s = t;
        c += e;
    }
    s + c
}

// ---------------------------------------------------------------------------------------------------
// Allan deviation
// ---------------------------------------------------------------------------------------------------

/// One point of an Allan deviation curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllanPoint {
    /// Cluster size m, in samples.
    pub cluster_size: usize,
    /// Averaging time tau = m / rate, s.
    pub tau_s: f64,
    /// Allan deviation sigma(tau), in the unit of the samples (rad/s for a gyro, m/s^2 for an
    /// accelerometer).
    pub adev: f64,
    /// Number of overlapping second differences averaged (N + 1 - 2m for N samples).
    pub terms: usize,
    /// Approximate 1-sigma relative uncertainty of `adev` (dimensionless): the simple rule
    /// 1 / sqrt(2 (N/m - 1)) for K = N/m independent clusters (IEEE Std 952-1997 Annex C; El-Sheimy, Hou &
    /// Niu, IEEE Trans. Instrum. Meas. 57, 2008). It ignores the noise type and the overlap: treat it as an
    /// approximation, not a confidence interval. Measured on white noise (200,000 samples, 20 records,
    /// tests/noise.rs), the RMS of (error / this value) is about 1.0 at m = 1 (theory for the correlated
    /// m = 1 differences: 1.22, the rule is slightly optimistic there) and 0.6..0.95 for m = 10..10,000
    /// (conservative there: the overlap adds degrees of freedom).
    pub rel_uncertainty: f64,
}

impl AllanPoint {
    /// Allan variance sigma^2(tau), in the unit of the samples squared.
    pub fn avar(&self) -> f64 {
        self.adev * self.adev
    }
}

/// Overlapping Allan deviation of `samples` (a rate-like signal in unit `u`, e.g. rad/s) taken at
/// `rate_hz`, at the cluster sizes `taus` (m, in samples; tau = m / rate_hz in s).
///
/// Estimator (IEEE Std 952-1997 Annex C, with overlapping clusters): with dt = 1/rate_hz and the
/// integrated signal theta_0 = 0, theta_k = dt * sum_{i<k} y_i (k = 0..=N, so N + 1 points for N
/// samples),
///
/// sigma^2(tau) = 1 / (2 tau^2 (N + 1 - 2m)) * sum_{k=0}^{N-2m} (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2.
///
/// The cumulative sum is accumulated as a double-double (TwoSum compensation, after removing the mean,
/// which leaves every second difference unchanged) and each second difference is evaluated from it with
/// compensated additions, so records of 10^5..10^6 samples lose no precision to cancellation.
///
/// Cluster sizes with m = 0 or 2m > N (no complete pair of clusters) are skipped; the output keeps the
/// order of `taus`. Empty, single-sample or non-finite input, or a rate that is not finite and positive,
/// gives an empty vector.
pub fn overlapping_allan_deviation(samples: &[f64], rate_hz: f64, taus: &[usize]) -> Vec<AllanPoint> {
    let n = samples.len();
    if n < 2 || !(rate_hz.is_finite() && rate_hz > 0.0) || samples.iter().any(|y| !y.is_finite()) {
        return Vec::new();
    }
    let mean = compensated_sum(samples.iter().copied()) / n as f64;
    // Cumulative sum in sample units (dt cancels in sigma^2 = sum D^2 dt^2 / (2 m^2 dt^2 terms)).
    let mut hi = Vec::with_capacity(n + 1);
    let mut lo = Vec::with_capacity(n + 1);
    hi.push(0.0);
    lo.push(0.0);
    let (mut s, mut c) = (0.0f64, 0.0f64);
    for &y in samples {
        let (t, e) = two_sum(s, y - mean);
        c += e;
        // Renormalise so that `s` stays the rounded value of the exact sum.
        let (t2, e2) = two_sum(t, c);
        s = t2;
        c = e2;
        hi.push(s);
        lo.push(c);
    }
    let mut out = Vec::new();
    for &m in taus {
        if m == 0 || m > n / 2 {
            continue;
        }
        let terms = n + 1 - 2 * m;
        let mut sum_sq = 0.0;
        for k in 0..terms {
            let (a, b, cc) = (k + 2 * m, k + m, k);
            let (s1, e1) = two_sum(hi[a], -2.0 * hi[b]);
            let (s2, e2) = two_sum(s1, hi[cc]);
            let d = s2 + (e1 + e2 + (lo[a] - 2.0 * lo[b] + lo[cc]));
            sum_sq += d * d;
        }
        let avar = sum_sq / (2.0 * (m as f64).powi(2) * terms as f64);
        let k_clusters = n as f64 / m as f64;
        out.push(AllanPoint {
            cluster_size: m,
            tau_s: m as f64 / rate_hz,
            adev: avar.sqrt(),
            terms,
            rel_uncertainty: 1.0 / (2.0 * (k_clusters - 1.0)).sqrt(),
        });
    }
    out
}

/// Distinct cluster sizes m (samples), increasing and about `points_per_decade` per decade, from 1 up to
/// and including (N - 1) / 2 for `n_samples` = N (the largest m with at least two overlapping terms).
/// Empty when N < 3 or `points_per_decade` is 0; `points_per_decade` above 10,000 is taken as 10,000.
pub fn log_spaced_clusters(n_samples: usize, points_per_decade: usize) -> Vec<usize> {
    let m_max = n_samples.saturating_sub(1) / 2;
    if m_max == 0 || points_per_decade == 0 {
        return Vec::new();
    }
    let points_per_decade = points_per_decade.min(10_000);
    let mut out: Vec<usize> = Vec::new();
    for i in 0.. {
        let m = 10f64.powf(i as f64 / points_per_decade as f64).round() as usize;
        if m >= m_max {
            break;
        }
        if out.last() != Some(&m) {
            out.push(m);
        }
    }
    out.push(m_max);
    out
}

// ---------------------------------------------------------------------------------------------------
// Noise terms
// ---------------------------------------------------------------------------------------------------

/// Ratio of the Allan deviation floor of a bias instability (flicker) noise to its coefficient B:
/// sqrt(2 ln 2 / pi) = 0.6643 (IEEE Std 952-1997 Annex C).
pub fn bias_instability_factor() -> f64 {
    (2.0 * LN_2 / PI).sqrt()
}

/// The five noise coefficients of the standard Allan variance model (IEEE Std 952-1997 Annex C):
///
/// sigma^2(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2.
///
/// Units, for samples in unit `u` per sample (tau in s). For a gyro, `u` = rad/s; for an accelerometer,
/// `u` = m/s^2 (then "angle" reads "velocity").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NoiseTerms {
    /// Quantization noise coefficient Q, u*s (gyro: rad, the angle quantization; accelerometer: m/s). For
    /// an integrated (angle) output with step q (u*s), Q = q / sqrt(12); rate samples formed as the
    /// differences of that output times fs are then quantized to q_r = q fs (u), so Q = q_r / (fs sqrt(12)).
    /// (Rounding each rate sample independently to q_r is not this term: it adds white noise,
    /// N = q_r / sqrt(12 fs).) Allan slope -1.
    pub quantization_q: f64,
    /// White noise (angle / velocity random walk) coefficient N, u*s^(1/2) = u/sqrt(Hz) (gyro:
    /// rad/s/sqrt(Hz) = rad/sqrt(s); accelerometer: m/s^2/sqrt(Hz) = m/s/sqrt(s)). For white noise of
    /// standard deviation sigma per sample at rate fs, N = sigma / sqrt(fs). Allan slope -1/2.
    pub random_walk_n: f64,
    /// Bias instability coefficient B, u (gyro: rad/s; accelerometer: m/s^2); the Allan floor is
    /// 0.664 B. Slope 0.
    pub bias_instability_b: f64,
    /// Rate random walk coefficient K, u/s^(1/2) = u*sqrt(Hz) (gyro: rad/s^2/sqrt(Hz) = rad/s^(3/2);
    /// accelerometer: m/s^3/sqrt(Hz) = m/s^(5/2)). For a random walk of the rate with steps of standard
    /// deviation s per sample at rate fs, K = s * sqrt(fs). Allan slope +1/2.
    pub rate_random_walk_k: f64,
    /// Rate ramp coefficient R, u/s (gyro: rad/s^2; accelerometer: m/s^3). Allan slope +1.
    pub ramp_r: f64,
}

impl NoiseTerms {
    /// The coefficients in model order [Q, N, B, K, R].
    pub fn as_array(&self) -> [f64; 5] {
        [self.quantization_q, self.random_walk_n, self.bias_instability_b, self.rate_random_walk_k, self.ramp_r]
    }

    /// Model Allan variance at `tau_s` (s), in u^2.
    pub fn allan_variance(&self, tau_s: f64) -> f64 {
        let b = model_basis(tau_s);
        self.as_array().iter().zip(b).map(|(c, f)| c * c * f).sum()
    }

    /// Model Allan deviation at `tau_s` (s), in u.
    pub fn allan_deviation(&self, tau_s: f64) -> f64 {
        self.allan_variance(tau_s).sqrt()
    }
}

/// The model's basis functions at tau (s): [3/tau^2, 1/tau, 2 ln2/pi, tau/3, tau^2/2].
fn model_basis(tau: f64) -> [f64; 5] {
    [3.0 / (tau * tau), 1.0 / tau, 2.0 * LN_2 / PI, tau / 3.0, tau * tau / 2.0]
}

/// The classic graphical read-offs of an Allan curve (IEEE Std 952-1997 Annex C; El-Sheimy, Hou &
/// Niu 2008). Each is `None` when the curve shows no region of the needed slope.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ClassicReadOffs {
    /// N, u*s^(1/2) (see [`NoiseTerms::random_walk_n`]): the line of slope -1/2 through the points whose
    /// local log-log slope is within [`SLOPE_TOLERANCE`] of -1/2, read at tau = 1 s (the line's log value
    /// is the 1/uncertainty^2-weighted mean over those points).
    pub random_walk_n: Option<f64>,
    /// B, u: the minimum of the Allan deviation divided by 0.664, over the points with a relative
    /// uncertainty of at most [`FLOOR_MAX_REL_UNCERTAINTY`]; `None` when that minimum is at the first or
    /// last such point (no floor visible). Biased high where the N and K terms are not negligible at
    /// the minimum (by sqrt(1 + (2 N K / sqrt(3)) / (0.441 B^2)) for those three terms).
    pub bias_instability_b: Option<f64>,
    /// The averaging time of that minimum, s.
    pub bias_instability_tau_s: Option<f64>,
    /// K, u/s^(1/2): the line of slope +1/2 (as for N), read at tau = 3 s (where sigma = K).
    pub rate_random_walk_k: Option<f64>,
}

/// Tolerance on the local log-log slope for the classic read-offs (dimensionless).
pub const SLOPE_TOLERANCE: f64 = 0.1;
/// Largest relative uncertainty of a point considered for the bias instability floor (dimensionless).
pub const FLOOR_MAX_REL_UNCERTAINTY: f64 = 0.25;

/// Points that can be used, sorted by tau.
fn usable_points(points: &[AllanPoint]) -> Vec<AllanPoint> {
    let mut p: Vec<AllanPoint> = points
        .iter()
        .copied()
        .filter(|p| {
            p.tau_s.is_finite()
                && p.tau_s > 0.0
                && p.adev.is_finite()
                && p.adev > 0.0
                && p.rel_uncertainty.is_finite()
                && p.rel_uncertainty > 0.0
        })
        .collect();
    p.sort_by(|a, b| a.tau_s.total_cmp(&b.tau_s));
    p.dedup_by(|a, b| a.tau_s == b.tau_s);
    p
}

/// Classic read-offs of an Allan curve (any order of points; see [`ClassicReadOffs`] for the rules).
pub fn classic_read_offs(points: &[AllanPoint]) -> ClassicReadOffs {
    let p = usable_points(points);
    let mut out = ClassicReadOffs::default();
    if p.len() < 2 {
        return out;
    }
    let lt: Vec<f64> = p.iter().map(|q| q.tau_s.ln()).collect();
    let ls: Vec<f64> = p.iter().map(|q| q.adev.ln()).collect();
    let n = p.len();
    let slope: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (ls[b] - ls[a]) / (lt[b] - lt[a])
        })
        .collect();
    // log sigma = log C + s * log(tau / tau_read): C = sigma at tau_read on the line of slope s.
    let line = |s: f64, tau_read: f64| -> Option<f64> {
        let (mut sw, mut swv) = (0.0, 0.0);
        for i in 0..n {
            if (slope[i] - s).abs() <= SLOPE_TOLERANCE {
                let w = 1.0 / (p[i].rel_uncertainty * p[i].rel_uncertainty);
                sw += w;
                swv += w * (ls[i] - s * (lt[i] - tau_read.ln()));
            }
        }
        (sw > 0.0).then(|| (swv / sw).exp())
    };
    out.random_walk_n = line(-0.5, 1.0);
    out.rate_random_walk_k = line(0.5, 3.0);
    let reliable: Vec<&AllanPoint> = p.iter().filter(|q| q.rel_uncertainty <= FLOOR_MAX_REL_UNCERTAINTY).collect();
    if reliable.len() >= 3 {
        let (imin, pmin) = reliable.iter().enumerate().min_by(|a, b| a.1.adev.total_cmp(&b.1.adev)).expect("non-empty");
        if imin > 0 && imin + 1 < reliable.len() {
            out.bias_instability_b = Some(pmin.adev / bias_instability_factor());
            out.bias_instability_tau_s = Some(pmin.tau_s);
        }
    }
    out
}

/// The result of [`fit_noise_terms`].
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseFit {
    /// The fitted coefficients (all >= 0).
    pub terms: NoiseTerms,
    /// Number of Allan points used.
    pub points_used: usize,
    /// RMS of the weighted residuals (model - measured variance) / (2 u model) over the points, with u
    /// each point's `rel_uncertainty` (dimensionless; about 1 or less for a model that fits, less because
    /// the rule for u is conservative and neighbouring points are correlated).
    pub weighted_rms_residual: f64,
    /// The classic read-offs of the same curve, for comparison.
    pub classic: ClassicReadOffs,
}

/// Identifies the five noise terms of [`NoiseTerms`] from an Allan curve.
///
/// Method: weighted linear least squares on the Allan *variance*, linear in the squared coefficients
/// c = [Q^2, N^2, B^2, K^2, R^2] with the basis of IEEE Std 952-1997 Annex C, subject to c >= 0.
/// The relative standard deviation of a variance estimate is about twice that of the deviation, so each
/// point's residual is divided by 2 u sigma^2 (u = its `rel_uncertainty`); sigma^2 is the measured
/// variance in a first pass and the first pass' model in a second (re-weighting removes the bias towards
/// low points that weighting by the measured value introduces). Non-negativity is solved exactly by
/// enumeration: the non-negative least-squares optimum is the unconstrained least-squares solution on its
/// own support, so the best of the feasible solutions over all 31 non-empty subsets of the five terms is
/// the optimum (each subset by Householder QR on unit-norm columns, rank-deficient subsets skipped).
///
/// Points with a non-finite or non-positive tau, deviation or uncertainty are ignored. Errors: no usable
/// point.
///
/// The Allan points of one record are correlated and the model is the sum of independent terms, so
/// the fit is an identification, not a likelihood: check it against the curve (e.g. with
/// [`NoiseTerms::allan_deviation`]).
pub fn fit_noise_terms(points: &[AllanPoint]) -> Result<NoiseFit, NoiseError> {
    let p = usable_points(points);
    if p.is_empty() {
        return Err(NoiseError::TooShort { what: "usable Allan points", needed: 1, got: 0 });
    }
    let measured: Vec<f64> = p.iter().map(AllanPoint::avar).collect();
    let mut reference = measured.clone();
    let mut coeffs = [0.0; 5];
    for _pass in 0..2 {
        let rows: Vec<([f64; 5], f64)> = p
            .iter()
            .zip(&measured)
            .zip(&reference)
            .map(|((q, &y), &r)| {
                let s = 1.0 / (2.0 * q.rel_uncertainty * r);
                (model_basis(q.tau_s).map(|f| f * s), y * s)
            })
            .collect();
        match nnls_by_enumeration(&rows) {
            Some(c) => coeffs = c,
            None => break,
        }
        let model: Vec<f64> =
            p.iter().map(|q| model_basis(q.tau_s).iter().zip(&coeffs).map(|(f, c)| f * c).sum()).collect();
        if model.iter().any(|&v| !(v.is_finite() && v > 0.0)) {
            break;
        }
        reference = model;
    }
    let terms = NoiseTerms {
        quantization_q: coeffs[0].sqrt(),
        random_walk_n: coeffs[1].sqrt(),
        bias_instability_b: coeffs[2].sqrt(),
        rate_random_walk_k: coeffs[3].sqrt(),
        ramp_r: coeffs[4].sqrt(),
    };
    let ss: f64 = p
        .iter()
        .zip(&measured)
        .map(|(q, &y)| {
            let m = terms.allan_variance(q.tau_s);
            let r = (m - y) / (2.0 * q.rel_uncertainty * m.max(f64::MIN_POSITIVE));
            r * r
        })
        .sum();
    Ok(NoiseFit {
        terms,
        points_used: p.len(),
        weighted_rms_residual: (ss / p.len() as f64).sqrt(),
        classic: classic_read_offs(&p),
    })
}

// ---------------------------------------------------------------------------------------------------
// Power spectral density
// ---------------------------------------------------------------------------------------------------

/// In-place iterative radix-2 decimation-in-time FFT, X_k = sum_n x_n exp(-2 pi i k n / L), of the
/// complex sequence (`re`, `im`) of length L, a power of two (L = 1 is the identity). Twiddle factors are
/// computed directly (not by recurrence), so the error grows as log2 L. For many transforms of one length,
/// [`FftPlan`] computes the twiddle factors once (the same numbers).
///
/// Errors: lengths that differ, or that are not a power of two.
pub fn fft_in_place(re: &mut [f64], im: &mut [f64]) -> Result<(), NoiseError> {
    if im.len() != re.len() {
        return Err(NoiseError::Invalid("FFT: real and imaginary parts of different lengths"));
    }
    FftPlan::new(re.len())?.run(re, im)
}

/// The radix-2 FFT of [`fft_in_place`] for one length, with its twiddle factors.
#[derive(Debug, Clone)]
pub struct FftPlan {
    /// exp(-2 pi i k / L), k = 0..L/2, as (cos, sin).
    twiddles: Vec<(f64, f64)>,
    len: usize,
}

impl FftPlan {
    /// The plan for length `len`. Errors: a length that is not a power of two.
    pub fn new(len: usize) -> Result<FftPlan, NoiseError> {
        if !len.is_power_of_two() {
            return Err(NoiseError::Invalid("FFT: length not a power of two"));
        }
        let twiddles = (0..len / 2)
            .map(|k| {
                let (s, c) = (-2.0 * PI * k as f64 / len as f64).sin_cos();
                (c, s)
            })
            .collect();
        Ok(FftPlan { twiddles, len })
    }

    /// The transform of (`re`, `im`) in place, as [`fft_in_place`]. Errors: lengths other than the plan's.
    pub fn run(&self, re: &mut [f64], im: &mut [f64]) -> Result<(), NoiseError> {
        let n = self.len;
        if re.len() != n || im.len() != n {
            return Err(NoiseError::Invalid("FFT: data length differs from the plan's"));
        }
        // Bit-reversal permutation.
        let mut j = 0usize;
        for i in 1..n {
            let mut bit = n >> 1;
            while j & bit != 0 {
                j ^= bit;
                bit >>= 1;
            }
            j |= bit;
            if i < j {
                re.swap(i, j);
                im.swap(i, j);
            }
        }
        let mut len = 2;
        while len <= n {
            let (half, stride) = (len / 2, n / len);
            for start in (0..n).step_by(len) {
                for k in 0..half {
                    let (wr, wi) = self.twiddles[k * stride];
                    let (a, b) = (start + k, start + k + half);
                    let tr = re[b] * wr - im[b] * wi;
                    let ti = re[b] * wi + im[b] * wr;
                    re[b] = re[a] - tr;
                    im[b] = im[a] - ti;
                    re[a] += tr;
                    im[a] += ti;
                }
            }
            len <<= 1;
        }
        Ok(())
    }
}

/// A one-sided power spectral density.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Bin frequencies k * rate / L, k = 0..=L/2, Hz.
    pub frequencies_hz: Vec<f64>,
    /// One-sided PSD at each frequency, u^2/Hz (gyro: (rad/s)^2/Hz). Bins 0 and L/2 (DC and Nyquist)
    /// are not doubled, so that `sum(density) * resolution_hz` is the mean square of the (segment-mean
    /// removed) signal; white noise therefore reads half its level in the Nyquist bin. Bins 0 and 1 are
    /// affected by the mean removal (see [`welch_psd`]).
    pub density: Vec<f64>,
    /// Bin spacing rate / L, Hz.
    pub resolution_hz: f64,
    /// Number of segments averaged.
    pub segments: usize,
}

impl Psd {
    /// Power in the bins with frequency in [`f_lo_hz`, `f_hi_hz`] (sum of density times bin width), u^2.
    pub fn band_power(&self, f_lo_hz: f64, f_hi_hz: f64) -> f64 {
        self.frequencies_hz
            .iter()
            .zip(&self.density)
            .filter(|(f, _)| **f >= f_lo_hz && **f <= f_hi_hz)
            .map(|(_, d)| d * self.resolution_hz)
            .sum()
    }
}

/// One-sided power spectral density by Welch's method (P. D. Welch, "The use of fast Fourier transform
/// for the estimation of power spectra", IEEE Trans. Audio Electroacoust. AU-15, 1967): segments of
/// `segment_len` = L samples (a power of two, at least 2) with 50% overlap (hop L/2, trailing samples
/// that do not fill a segment are dropped), each with its mean removed and a periodic Hann window
/// w_n = 0.5 - 0.5 cos(2 pi n / L) applied; the periodograms |X_k|^2 / (rate_hz * sum w_n^2) are averaged
/// and doubled for 0 < k < L/2. White noise of variance sigma^2 at rate fs reads 2 sigma^2 / fs; a
/// sinusoid of amplitude A puts A^2/2 into the bins of its peak (about 4 bins wide).
///
/// The mean removal acts through the window on the two lowest bins: bin 0 reads about 0, and bin 1
/// reads 5/6 of the level of white noise (for this window E|X_1|^2 = sigma^2 (sum w^2 - |W_1|^2 / L) with
/// W_1 = -L/4 and sum w^2 = 3L/8); read a spectrum from bin 2 up. Without the mean removal a constant
/// offset (a sensor bias) would leak into bins 0 and 1 instead.
///
/// Errors: `segment_len` not a power of two or below 2, rate not finite and positive, non-finite samples,
/// or fewer samples than one segment.
pub fn welch_psd(samples: &[f64], rate_hz: f64, segment_len: usize) -> Result<Psd, NoiseError> {
    let l = segment_len;
    if l < 2 || !l.is_power_of_two() {
        return Err(NoiseError::Invalid("Welch: segment length must be a power of two, at least 2"));
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(NoiseError::Invalid("Welch: sample rate must be finite and positive"));
    }
    if samples.len() < l {
        return Err(NoiseError::TooShort { what: "Welch: samples", needed: l, got: samples.len() });
    }
    if samples.iter().any(|y| !y.is_finite()) {
        return Err(NoiseError::Invalid("Welch: non-finite sample"));
    }
    let window: Vec<f64> = (0..l).map(|i| 0.5 - 0.5 * (2.0 * PI * i as f64 / l as f64).cos()).collect();
    let u: f64 = window.iter().map(|w| w * w).sum();
    let hop = l / 2;
    let segments = (samples.len() - l) / hop + 1;
    let bins = l / 2 + 1;
    let mut acc = vec![0.0; bins];
    let (mut re, mut im) = (vec![0.0; l], vec![0.0; l]);
    let plan = FftPlan::new(l)?;
    for s in 0..segments {
        let seg = &samples[s * hop..s * hop + l];
        let mean = compensated_sum(seg.iter().copied()) / l as f64;
        for i in 0..l {
            re[i] = (seg[i] - mean) * window[i];
            im[i] = 0.0;
        }
        plan.run(&mut re, &mut im)?;
        for k in 0..bins {
            acc[k] += re[k] * re[k] + im[k] * im[k];
        }
    }
    let norm = 1.0 / (rate_hz * u * segments as f64);
    let density: Vec<f64> =
        acc.iter().enumerate().map(|(k, a)| if k == 0 || k == l / 2 { a * norm } else { 2.0 * a * norm }).collect();
    let resolution_hz = rate_hz / l as f64;
    Ok(Psd { frequencies_hz: (0..bins).map(|k| k as f64 * resolution_hz).collect(), density, resolution_hz, segments })
}

// ---------------------------------------------------------------------------------------------------
// Whiteness test
// ---------------------------------------------------------------------------------------------------

/// The result of [`ljung_box`].
#[derive(Debug, Clone, PartialEq)]
pub struct LjungBox {
    /// Q = n (n + 2) sum_{k=1}^{h} r_k^2 / (n - k), dimensionless.
    pub q_statistic: f64,
    /// Number of lags h.
    pub lags: usize,
    /// Degrees of freedom of the reference chi-square distribution (= h).
    pub degrees_of_freedom: usize,
    /// P(chi^2_h >= Q): the probability of a Q at least this large for a white sequence. Small values
    /// (e.g. < 0.05) reject whiteness.
    pub p_value: f64,
    /// Sample autocorrelations r_1..r_h (dimensionless).
    pub autocorrelation: Vec<f64>,
}

/// Ljung-Box portmanteau test of whiteness (G. M. Ljung & G. E. P. Box, "On a measure of lack of fit in
/// time series models", Biometrika 65, 1978) over `lags` = h lags: with the sample autocorrelations
/// r_k = sum_{t=k}^{n-1} (x_t - mean)(x_{t-k} - mean) / sum_t (x_t - mean)^2,
/// Q = n (n + 2) sum_{k=1}^{h} r_k^2 / (n - k), compared with chi-square of h degrees of freedom. (For
/// the residuals of a fitted ARMA(p, q) model, the reference would have h - p - q degrees of freedom;
/// use [`chi_square_cdf`] directly for that.)
///
/// Errors: h = 0, fewer than h + 2 samples, non-finite samples, or a constant sequence.
pub fn ljung_box(residuals: &[f64], lags: usize) -> Result<LjungBox, NoiseError> {
    let n = residuals.len();
    if lags == 0 {
        return Err(NoiseError::Invalid("Ljung-Box: at least one lag"));
    }
    if n < lags.saturating_add(2) {
        return Err(NoiseError::TooShort { what: "Ljung-Box: samples", needed: lags.saturating_add(2), got: n });
    }
    if residuals.iter().any(|y| !y.is_finite()) {
        return Err(NoiseError::Invalid("Ljung-Box: non-finite sample"));
    }
    let mean = compensated_sum(residuals.iter().copied()) / n as f64;
    let x: Vec<f64> = residuals.iter().map(|v| v - mean).collect();
    let c0: f64 = x.iter().map(|v| v * v).sum();
    if c0 <= 0.0 {
        return Err(NoiseError::Invalid("Ljung-Box: constant sequence"));
    }
    let nf = n as f64;
    let mut q = 0.0;
    let mut r = Vec::with_capacity(lags);
    for k in 1..=lags {
        let ck: f64 = x[k..].iter().zip(&x[..n - k]).map(|(a, b)| a * b).sum();
        let rk = ck / c0;
        r.push(rk);
        q += rk * rk / (nf - k as f64);
    }
    q *= nf * (nf + 2.0);
    Ok(LjungBox {
        q_statistic: q,
        lags,
        degrees_of_freedom: lags,
        p_value: regularized_gamma_q(lags as f64 / 2.0, q / 2.0),
        autocorrelation: r,
    })
}

/// Natural logarithm of the gamma function for x > 0 (Lanczos approximation, g = 7, 9 terms; relative
/// error about 1e-15). NaN for x <= 0 or non-finite x.
pub fn ln_gamma(x: f64) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return f64::NAN;
    }
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x), positive for 0 < x < 1.
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    let x = x - 1.0;
    let mut a = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    let t = x + 7.5;
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized lower incomplete gamma function P(a, x) = gamma(a, x) / Gamma(a), a > 0, x >= 0: by its
/// series for x < a + 1 and by the continued fraction of Q = 1 - P otherwise (Press et al., Numerical
/// Recipes, 3rd ed., section 6.2; relative error about 1e-14). NaN outside the domain.
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if !(a.is_finite() && a > 0.0) || x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return 0.0;
    }
    if x == f64::INFINITY {
        return 1.0;
    }
    if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_continued_fraction(a, x)
    }
}

/// Regularized upper incomplete gamma function Q(a, x) = 1 - P(a, x), computed without cancellation for
/// large x (see [`regularized_gamma_p`]). NaN outside the domain.
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    if !(a.is_finite() && a > 0.0) || x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return 1.0;
    }
    if x == f64::INFINITY {
        return 0.0;
    }
    if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_continued_fraction(a, x)
    }
}

/// Chi-square cumulative distribution P(chi^2_k <= x) = P(k/2, x/2) for `dof` = k > 0 degrees of
/// freedom (k need not be an integer). 0 for x <= 0; NaN for k <= 0 or NaN x.
pub fn chi_square_cdf(x: f64, dof: f64) -> f64 {
    if x.is_nan() || !(dof.is_finite() && dof > 0.0) {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 0.0;
    }
    regularized_gamma_p(dof / 2.0, x / 2.0)
}

/// F cumulative distribution P(F <= f) for `d1` and `d2` degrees of freedom (the ratio of two independent
/// chi-squares, each divided by its degrees of freedom): the regularised incomplete beta function
/// `I_x(d1/2, d2/2)` at `x = d1 f / (d1 f + d2)`. 0 for f <= 0; NaN for degrees of freedom that are not positive.
pub fn f_cdf(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() || !(d1.is_finite() && d1 > 0.0 && d2 > 0.0) {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 0.0;
    }
    if d2.is_infinite() {
        return chi_square_cdf(d1 * f, d1);
    }
    regularized_beta(d1 * f / (d1 * f + d2), d1 / 2.0, d2 / 2.0)
}

/// The regularised incomplete beta function `I_x(a, b)`, by its continued fraction (modified Lentz) on the
/// side where it converges fast (`x < (a + 1) / (a + b + 2)`), and the symmetry `I_x(a, b) = 1 - I_{1-x}(b, a)`
/// on the other.
fn regularized_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        (front * beta_fraction(x, a, b) / a).clamp(0.0, 1.0)
    } else {
        (1.0 - front * beta_fraction(1.0 - x, b, a) / b).clamp(0.0, 1.0)
    }
}

/// The continued fraction of `I_x(a, b)` (its even and odd terms `d_2m`, `d_2m+1`), modified Lentz.
fn beta_fraction(x: f64, a: f64, b: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let clamp = |v: f64| if v.abs() < TINY { TINY } else { v };
    let mut c = 1.0;
    let mut d = 1.0 / clamp(1.0 - (a + b) * x / (a + 1.0));
    let mut h = d;
    for m in 1..10_000 {
        let m = m as f64;
        let even = m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m));
        d = 1.0 / clamp(1.0 + even * d);
        c = clamp(1.0 + even / c);
        h *= d * c;
        let odd = -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
        d = 1.0 / clamp(1.0 + odd * d);
        c = clamp(1.0 + odd / c);
        let step = d * c;
        h *= step;
        if (step - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

fn gamma_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..10_000 {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    (sum * (-x + a * x.ln() - ln_gamma(a)).exp()).clamp(0.0, 1.0)
}

/// Q(a, x) by the modified Lentz continued fraction, for x >= a + 1.
fn gamma_continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..10_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    ((-x + a * x.ln() - ln_gamma(a)).exp() * h).clamp(0.0, 1.0)
}

/// Allan variance at averaging time `tau_s` of a first-order Gauss-Markov process of standard deviation
/// `sigma` (any unit; the result is in that unit squared) and correlation time `tau_c_s` (IEEE Std 952):
/// `sigma^2 (tau_c/tau)^2 (2 x - 3 + 4 e^-x - e^-2x)` with `x = tau / tau_c` (series `2/3 x` for small `x`).
pub fn gauss_markov_allan_variance(sigma: f64, tau_c_s: f64, tau_s: f64) -> f64 {
    let x = tau_s / tau_c_s;
    if x < 1e-4 {
        return sigma * sigma * 2.0 / 3.0 * x;
    }
    sigma * sigma * (tau_c_s / tau_s).powi(2) * (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp())
}

/// Allan variance of sway at averaging time `tau_s`: a channel whose integral is a first-order Gauss-Markov
/// process of standard deviation `sigma` (rad for a gyro, m/s for an accelerometer) and correlation time
/// `tau_c_s`: `sigma^2 (3 - 4 e^-x + e^-2x) / tau^2` with `x = tau / tau_c`; white noise of `N^2 = 2 sigma^2 /
/// tau_c` for `tau << tau_c`, quantisation of `Q = sigma` for `tau >> tau_c`.
pub fn sway_allan_variance(sigma: f64, tau_c_s: f64, tau_s: f64) -> f64 {
    let x = tau_s / tau_c_s;
    let shape = if x < 1e-3 { 2.0 * x - 2.0 / 3.0 * x.powi(3) } else { 3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp() };
    sigma * sigma * shape / (tau_s * tau_s)
}

/// The power-law noise types of an Allan variance, in the terms of a rate sensor (IEEE Std 952-1997 Annex C),
/// with the names of the frequency-standards literature in brackets: they set the equivalent degrees of
/// freedom of an Allan point ([`overlapping_allan_edf`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AllanNoiseKind {
    /// Quantisation of an integrated output (white phase noise), Allan slope -1.
    Quantization,
    /// White rate noise, angle/velocity random walk (white frequency noise), slope -1/2.
    White,
    /// Bias instability (flicker frequency noise), slope 0.
    BiasInstability,
    /// Rate random walk (random-walk frequency noise), slope +1/2; used for the rate ramp too.
    RateRandomWalk,
}

/// Equivalent degrees of freedom of the overlapping Allan variance at cluster size `m` of `n_samples` rate
/// samples for one noise type: the variance estimate is distributed as `sigma^2 chi^2_edf / edf`, so its
/// relative standard deviation is `sqrt(2 / edf)`. The approximations of Howe, Allan & Barnes (Proc. 35th
/// Frequency Control Symposium, 1981), as tabulated in NIST Special Publication 1065 (Riley 2008, section
/// 5.3), with `N = n_samples + 1` phase (angle) points. At least 1; 0 when `m` is 0 or `2 m > n_samples`.
pub fn overlapping_allan_edf(kind: AllanNoiseKind, n_samples: usize, m: usize) -> f64 {
    if m == 0 || 2 * m > n_samples {
        return 0.0;
    }
    let (n, m) = (n_samples as f64 + 1.0, m as f64);
    let edf = match kind {
        AllanNoiseKind::Quantization => (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m)),
        AllanNoiseKind::White => {
            (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0)
        }
        AllanNoiseKind::BiasInstability if m < 1.5 => 2.0 * (n - 2.0).powi(2) / (2.3 * n - 4.9),
        AllanNoiseKind::BiasInstability => 5.0 * n * n / (4.0 * m * (n + 3.0 * m)),
        AllanNoiseKind::RateRandomWalk => {
            (n - 2.0) / m * ((n - 1.0).powi(2) - 3.0 * m * (n - 1.0) + 4.0 * m * m) / (n - 3.0).powi(2)
        }
    };
    if edf.is_finite() {
        edf.max(1.0)
    } else {
        1.0
    }
}

/// Lag-1 autocorrelation of the first differences `d_k = x_{k+1} - x_k` of `samples` (dimensionless), the
/// signature of the noise at the highest frequencies: -1/2 for white noise, -2/3 for the quantisation of an
/// integrated output (white angle noise), towards -1 for an alternating component (the dither of a
/// ring-laser gyro, a line near the Nyquist frequency), above -1/2 for low-pass (correlated) noise. Its
/// standard error is about `1 / sqrt(n)` for `n` differences. `None` with fewer than 3 samples, a non-finite
/// sample or constant differences.
pub fn difference_lag1_autocorrelation(samples: &[f64]) -> Option<f64> {
    if samples.len() < 3 || samples.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let d: Vec<f64> = samples.windows(2).map(|w| w[1] - w[0]).collect();
    let mean = compensated_sum(d.iter().copied()) / d.len() as f64;
    let c0: f64 = d.iter().map(|v| (v - mean) * (v - mean)).sum();
    let c1: f64 = d.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum();
    (c0 > 0.0).then(|| c1 / c0)
}

// ---------------------------------------------------------------------------------------------------
// Quantization
// ---------------------------------------------------------------------------------------------------

/// The result of [`detect_quantization`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantization {
    /// Estimated output step, in the unit of the samples (the largest step of which the non-zero
    /// differences are integer multiples; when `quantized` is false, the smallest cluster of differences,
    /// not a real step).
    pub step: f64,
    /// Fraction of the non-zero sample differences that are integer multiples of `step` within
    /// [`GRID_TOLERANCE`] steps (dimensionless, 0..=1). About 2 x GRID_TOLERANCE for continuous data.
    pub fraction_on_grid: f64,
    /// Number of non-zero sample differences examined.
    pub nonzero_differences: usize,
    /// Whether the data look quantized: `fraction_on_grid` >= [`QUANTIZED_FRACTION`].
    pub quantized: bool,
}

impl Quantization {
    /// Standard deviation of the rounding error of a uniform quantizer with this step, step / sqrt(12),
    /// in the unit of the samples.
    pub fn rounding_noise_std(&self) -> f64 {
        self.step / 12f64.sqrt()
    }
}

/// The consecutive pairs `(x_i, x_{i+1})` of the concatenation of `parts`.
pub fn joined_pairs<'a>(parts: &'a [&'a [f64]]) -> impl Iterator<Item = (f64, f64)> + 'a {
    let mut values = parts.iter().flat_map(|p| p.iter().copied());
    let first = values.next();
    values.scan(first, |previous, v| previous.replace(v).map(|p| (p, v)))
}

/// Tolerance, in steps, for a difference to count as an integer multiple of the step.
pub const GRID_TOLERANCE: f64 = 0.05;
/// Fraction of on-grid differences above which data are called quantized.
pub const QUANTIZED_FRACTION: f64 = 0.9;
/// Largest divisor tried when the smallest difference is a multiple of the step (e.g. differences of 2q
/// and 3q only give q).
const MAX_DIVISOR: usize = 8;

/// Most decimals [`print_step`] tries.
const MAX_PRINTED_DECIMALS: i32 = 15;

/// The step of the decimal digits `parts` were printed with: the largest `10^-d` (`d` from 0 to 15) of
/// which every finite sample is a whole multiple, up to the rounding of its parse (1e-6 of the step, or four
/// units in the last place), within 15 significant digits. `None` when there is no such step: binary data,
/// or text printed to full precision.
pub fn print_step(parts: &[&[f64]]) -> Option<f64> {
    let mut samples = parts.iter().flat_map(|p| p.iter()).filter(|v| v.is_finite()).peekable();
    samples.peek()?;
    let on = |v: f64, scale: f64| {
        let s = v * scale;
        s.abs() < 1e15 && (s - s.round()).abs() <= 1e-6f64.max(s.abs() * 4.0 * f64::EPSILON)
    };
    (0..=MAX_PRINTED_DECIMALS)
        .map(|d| 10f64.powi(d))
        .find(|&scale| samples.clone().all(|&v| on(v, scale)))
        .map(|s| 1.0 / s)
}

/// A lattice step that is the samples' print step (within 1 %, [`print_step`]): the file's digits, not the
/// sensor's quantisation. A sensor whose own step is that power of ten cannot be told from it.
pub fn is_print_step(step: f64, print_step: Option<f64>) -> bool {
    print_step.is_some_and(|p| (step / p - 1.0).abs() < 0.01)
}

/// Estimates the output step of `samples` (any unit) and whether they look quantized.
///
/// Method: a floating-point greatest common divisor of the sample differences. The non-zero absolute
/// differences |x_{i+1} - x_i| (larger than 1e-12 of the largest |x|) are sorted; the base value is the
/// mean of the smallest cluster of them (differences within 10% of each other) holding at least
/// max(2, 0.1%) of them; the step is the base divided by the smallest d = 1..=8 for which at least
/// [`QUANTIZED_FRACTION`] of the differences lie within [`GRID_TOLERANCE`] steps of an integer multiple,
/// then refined by least squares over those differences (step = sum n_i d_i / sum n_i^2). When no divisor
/// reaches the fraction, the data are reported as not quantized, with the base as `step`.
///
/// Errors: fewer than 8 non-zero differences (e.g. constant, empty or non-finite data).
pub fn detect_quantization(samples: &[f64]) -> Result<Quantization, NoiseError> {
    detect_quantization_joined(&[samples])
}

/// [`detect_quantization`] of the concatenation of `parts`, without copying them (the difference across each
/// join counts, as in the concatenated samples).
pub fn detect_quantization_joined(parts: &[&[f64]]) -> Result<Quantization, NoiseError> {
    const MIN_DIFFS: usize = 8;
    let scale = parts.iter().flat_map(|p| p.iter()).filter(|v| v.is_finite()).fold(0.0f64, |m, v| m.max(v.abs()));
    let zero = 1e-12 * scale;
    let mut d: Vec<f64> =
        joined_pairs(parts).map(|(a, b)| (b - a).abs()).filter(|v| v.is_finite() && *v > zero).collect();
    if d.len() < MIN_DIFFS {
        return Err(NoiseError::TooShort { what: "non-zero sample differences", needed: MIN_DIFFS, got: d.len() });
    }
    // Values equal under total_cmp are the same bits: the unstable sort gives the stable one's order.
    d.sort_unstable_by(f64::total_cmp);
    let min_count = (d.len() / 1000).max(2);
    let mut base = d[0];
    let mut i = 0;
    while i < d.len() {
        let j = d[i..].iter().position(|&v| v > 1.1 * d[i]).map_or(d.len(), |p| i + p);
        if j - i >= min_count {
            base = d[i..j].iter().sum::<f64>() / (j - i) as f64;
            break;
        }
        i = j;
    }
    let on_grid = |step: f64| -> (f64, f64, f64) {
        // (fraction on grid, sum n d, sum n^2) over the on-grid differences.
        let (mut count, mut snd, mut snn) = (0usize, 0.0, 0.0);
        for &v in &d {
            let r = v / step;
            let n = r.round();
            if n >= 1.0 && (r - n).abs() <= GRID_TOLERANCE {
                count += 1;
                snd += n * v;
                snn += n * n;
            }
        }
        (count as f64 / d.len() as f64, snd, snn)
    };
    for div in 1..=MAX_DIVISOR {
        let step = base / div as f64;
        let (fraction, snd, snn) = on_grid(step);
        if fraction >= QUANTIZED_FRACTION {
            let refined = snd / snn;
            let (fraction, _, _) = on_grid(refined);
            return Ok(Quantization {
                step: refined,
                fraction_on_grid: fraction,
                nonzero_differences: d.len(),
                quantized: fraction >= QUANTIZED_FRACTION,
            });
        }
    }
    let (fraction, _, _) = on_grid(base);
    Ok(Quantization { step: base, fraction_on_grid: fraction, nonzero_differences: d.len(), quantized: false })
}

#[cfg(test)]
mod tests {

    #[test]
    fn the_print_step_is_the_largest_power_of_ten_of_which_every_sample_is_a_multiple() {
        use super::{is_print_step, print_step};
        // Printed with three decimals (one sample has fewer): 1e-3, whatever the spacing of the values.
        let printed: Vec<f64> = ["0.125", "-3.5", "12.007", "0.001"].iter().map(|s| s.parse().unwrap()).collect();
        assert_eq!(print_step(&[&printed]), Some(1e-3));
        // Large values with ten decimals (the parse's rounding is well below the step).
        let fine: Vec<f64> = ["9.8031477330", "-9.7999999999"].iter().map(|s| s.parse().unwrap()).collect();
        assert_eq!(print_step(&[&fine]), Some(1e-10));
        // Full precision (a thirds' digits go on forever): no print step.
        assert_eq!(print_step(&[&[1.0 / 3.0, 2.0 / 3.0]]), None);
        assert_eq!(print_step(&[&[]]), None);
        // A lattice at the print step is the file's; a coarser one is the sensor's.
        assert!(is_print_step(1.0004e-6, Some(1e-6)));
        assert!(!is_print_step(2.5e-6, Some(1e-6)));
        assert!(!is_print_step(1e-6, None));
    }

    #[test]
    fn f_distribution_matches_closed_forms_and_tables() {
        // d1 = d2 = 2: P(F <= f) = f / (1 + f) exactly; d1 = d2 = 1: the median is 1.
        for f in [0.01, 0.3, 1.0, 2.5, 40.0] {
            assert!((f_cdf(f, 2.0, 2.0) - f / (1.0 + f)).abs() < 1e-12, "{f}");
        }
        assert!((f_cdf(1.0, 1.0, 1.0) - 0.5).abs() < 1e-12);
        // Table values (upper 5 % and 0.1 % points): F(5, 10) 3.326, F(6, 12) 0.999 point 8.379.
        assert!((f_cdf(3.326, 5.0, 10.0) - 0.95).abs() < 2e-4);
        assert!((f_cdf(8.379, 6.0, 12.0) - 0.999).abs() < 2e-5);
        // Many denominator degrees of freedom: d1 F is chi-square with d1.
        assert!((f_cdf(2.0, 4.0, 1e7) - chi_square_cdf(8.0, 4.0)).abs() < 1e-5);
        assert_eq!(f_cdf(-1.0, 3.0, 3.0), 0.0);
        assert!(f_cdf(1.0, 0.0, 3.0).is_nan());
    }
    use super::*;

    #[test]
    fn compensated_cumulative_sum_keeps_second_differences_exact() {
        // A large offset plus a tiny alternating signal: naive cumulative sums would lose it.
        let samples: Vec<f64> = (0..100_000).map(|i| 1.0e6 + if i % 2 == 0 { 1e-6 } else { -1e-6 }).collect();
        let p = overlapping_allan_deviation(&samples, 1.0, &[1]);
        // Alternating +-a about the mean: the second difference of the cumulative sums at m = 1 is +-2a,
        // so avar = 4a^2 / 2. (a from the stored values: 1e6 + 1e-6 is rounded to a multiple of 1.2e-10.)
        let a = ((samples[0] - 1.0e6) - (samples[1] - 1.0e6)) / 2.0;
        let expected = (2.0f64).sqrt() * a;
        assert!((p[0].adev / expected - 1.0).abs() < 1e-6, "{}", p[0].adev);
    }

    #[test]
    fn subset_least_squares_is_exact_on_consistent_data() {
        let c = [1e-6, 4e-4, 0.0, 2.5e-5, 0.0];
        let rows: Vec<([f64; 5], f64)> = (0..30)
            .map(|i| {
                let tau = 10f64.powf(-2.0 + i as f64 / 6.0);
                let b = model_basis(tau);
                let y: f64 = b.iter().zip(&c).map(|(b, c)| b * c).sum();
                (b.map(|v| v / y), 1.0)
            })
            .collect();
        let x = nnls_by_enumeration(&rows).unwrap();
        for (x, c) in x.iter().zip(&c) {
            assert!((x - c).abs() <= 1e-9 * c.max(1e-6), "{x} vs {c}");
        }
    }
}
