//! Correlated noise on the samples: the exact Gaussian likelihood (Kalman filter) of a first-order
//! Gauss-Markov process plus white noise, maximised over its time constant and variance, against white noise
//! alone.

use super::MIN_DWELL_SAMPLES;

/// A Gauss-Markov process fitted.
pub(super) struct GaussMarkovResult {
    /// Its standard deviation, channel unit.
    pub sigma: f64,
    /// Standard error of `sigma`.
    pub sigma_std: f64,
    /// Its time constant, s.
    pub tau_s: f64,
    /// Likelihood-ratio statistic against white noise alone.
    pub lr: f64,
    /// RMS of the samples (white noise alone).
    pub rms_white: f64,
    /// RMS of the filter's innovations.
    pub rms_innovation: f64,
}

/// Concentrated log-likelihood of AR(1) (stationary variance `q`, coefficient `phi`) plus unit white noise
/// with a common scale: returns (log-likelihood, white variance, innovation mean square).
fn ar1_white_loglik(dwells: &[Vec<f64>], phi: f64, q: f64) -> (f64, f64, f64) {
    let sums = filter_sums(dwells, phi, q);
    let n: usize = dwells.iter().map(Vec::len).sum();
    let nf = n as f64;
    let var = sums.e2_s / nf;
    (-0.5 * nf * ((std::f64::consts::TAU * var).ln() + 1.0) - 0.5 * sums.ln_s, var, sums.e2 / nf)
}

/// What the likelihood needs from the Kalman filter of every dwell: the sums over all samples of `ln s`,
/// `e^2 / s` and `e^2` (innovation `e`, its variance `s` in units of the white variance).
#[derive(Default)]
struct FilterSums {
    ln_s: f64,
    e2_s: f64,
    e2: f64,
}

/// Dwells filtered in lock step (independent chains for the processor; more than this adds nothing).
const LANES: usize = 6;

/// The Kalman filter of AR(1) plus unit white noise over every dwell, each started at its stationary prior
/// (`x = 0`, `p = q`). The gain sequence does not depend on the data, so it is computed once for all dwells:
/// while it changes (the transient), step by step for all dwells at once; once the Riccati recursion has
/// converged (to the rounding of f64), with the constant gain, dwells in lock step. The sums are those of
/// the filter run dwell by dwell, in another order (and `e^2 / s` summed over the dwells at one step before
/// the division by their common `s`): they agree to the rounding of f64 (docs/analysis.md#speed-and-memory).
fn filter_sums(dwells: &[Vec<f64>], phi: f64, q: f64) -> FilterSums {
    let drive = q * (1.0 - phi * phi);
    let n_max = dwells.iter().map(Vec::len).max().unwrap_or(0);
    let mut x = vec![0.0; dwells.len()];
    let mut sums = FilterSums::default();
    let (mut p, mut i) = (q, 0);
    let mut steady = false;
    while i < n_max {
        let s = p + 1.0;
        let k = p / s;
        let (mut e2, mut active) = (0.0, 0usize);
        for (d, xd) in dwells.iter().zip(x.iter_mut()) {
            if let Some(&y) = d.get(i) {
                let e = y - *xd;
                e2 += e * e;
                *xd = (*xd + k * e) * phi;
                active += 1;
            }
        }
        sums.ln_s += active as f64 * s.ln();
        sums.e2_s += e2 / s;
        sums.e2 += e2;
        i += 1;
        let p_next = phi * phi * (p * (1.0 - k)) + drive;
        steady = (p_next - p).abs() <= 4.0 * f64::EPSILON * p;
        p = p_next;
        if steady {
            break;
        }
    }
    if steady && i < n_max {
        let s = p + 1.0;
        let k = p / s;
        let remaining: usize = dwells.iter().map(|d| d.len().saturating_sub(i)).sum();
        let mut e2 = 0.0;
        for (group, xs) in dwells.chunks(LANES).zip(x.chunks_mut(LANES)) {
            e2 += steady_group(group, xs, i, k, phi);
        }
        sums.ln_s += remaining as f64 * s.ln();
        sums.e2_s += e2 / s;
        sums.e2 += e2;
    }
    sums
}

/// The steady filter (gain `k`) over samples `from..` of a group of at most [`LANES`] dwells with states
/// `x`: the common length in lock step, then each dwell's rest. Returns the sum of the squared innovations.
fn steady_group(group: &[Vec<f64>], x: &mut [f64], from: usize, k: f64, phi: f64) -> f64 {
    let common = group.iter().map(Vec::len).min().unwrap_or(0).max(from);
    let mut e2 = match group.len() {
        1 => lanes::<1>(group, x, from..common, k, phi),
        2 => lanes::<2>(group, x, from..common, k, phi),
        3 => lanes::<3>(group, x, from..common, k, phi),
        4 => lanes::<4>(group, x, from..common, k, phi),
        5 => lanes::<5>(group, x, from..common, k, phi),
        _ => lanes::<6>(group, x, from..common, k, phi),
    };
    for (d, xd) in group.iter().zip(x.iter_mut()) {
        let rest = d.get(common..).unwrap_or(&[]);
        e2 += lanes::<1>(std::slice::from_ref(d), std::slice::from_mut(xd), common..common + rest.len(), k, phi);
    }
    e2
}

/// `L` dwells of `group` (states `x`) through the steady filter over the sample `range`, in lock step.
fn lanes<const L: usize>(group: &[Vec<f64>], x: &mut [f64], range: std::ops::Range<usize>, k: f64, phi: f64) -> f64 {
    let ys: [&[f64]; L] = std::array::from_fn(|l| group.get(l).and_then(|d| d.get(range.clone())).unwrap_or(&[]));
    let n = ys.iter().map(|y| y.len()).min().unwrap_or(0);
    let ys = ys.map(|y| &y[..n]);
    let mut xs: [f64; L] = std::array::from_fn(|l| x.get(l).copied().unwrap_or(0.0));
    let mut acc = [0.0; L];
    for i in 0..n {
        for l in 0..L {
            let e = ys[l][i] - xs[l];
            acc[l] += e * e;
            xs[l] = (xs[l] + k * e) * phi;
        }
    }
    for (xd, v) in x.iter_mut().zip(xs) {
        *xd = v;
    }
    acc.iter().sum()
}

/// The likelihood over (ln tau, ln q) of the samples normalised to a white variance of order one.
struct Profile {
    /// The normalised samples, per dwell.
    norm: Vec<Vec<f64>>,
    /// Sample interval, s.
    dt: f64,
    /// Search range of ln tau.
    tau: (f64, f64),
    /// Search range of ln q.
    q: (f64, f64),
}

impl Profile {
    fn ll_at(&self, ln_tau: f64, ln_q: f64) -> f64 {
        ar1_white_loglik(&self.norm, (-self.dt / ln_tau.exp()).exp(), ln_q.exp()).0
    }

    /// The best of a 12 x 10 grid: (log-likelihood, ln tau, ln q).
    fn grid(&self) -> (f64, f64, f64) {
        let ((tau_lo, tau_hi), (q_lo, q_hi)) = (self.tau, self.q);
        let mut best = (f64::NEG_INFINITY, 0.0, 0.0);
        for i in 0..12 {
            let lt = tau_lo + (tau_hi - tau_lo) * i as f64 / 11.0;
            for j in 0..10 {
                let lq = q_lo + (q_hi - q_lo) * j as f64 / 9.0;
                let ll = self.ll_at(lt, lq);
                if ll > best.0 {
                    best = (ll, lt, lq);
                }
            }
        }
        best
    }

    /// Coordinate refinement of `start` with shrinking steps.
    fn refine(&self, start: (f64, f64, f64)) -> (f64, f64, f64) {
        let ((tau_lo, tau_hi), (q_lo, q_hi)) = (self.tau, self.q);
        let (mut ll, mut lt, mut lq) = start;
        let (mut st, mut sq) = ((tau_hi - tau_lo) / 11.0, (q_hi - q_lo) / 9.0);
        for _ in 0..30 {
            let mut moved = false;
            for (dl, dq) in [(st, 0.0), (-st, 0.0), (0.0, sq), (0.0, -sq)] {
                let (a, b) = ((lt + dl).clamp(tau_lo, tau_hi), (lq + dq).clamp(q_lo - 4.0, q_hi + 4.0));
                let v = self.ll_at(a, b);
                if v > ll {
                    ll = v;
                    lt = a;
                    lq = b;
                    moved = true;
                }
            }
            if !moved {
                st *= 0.5;
                sq *= 0.5;
            }
        }
        (ll, lt, lq)
    }
}

/// First-order Gauss-Markov plus white noise against white noise alone (exact likelihood). The samples are
/// normalised in place.
pub(super) fn gauss_markov_test(mut dwells: Vec<Vec<f64>>, dt: f64) -> Option<GaussMarkovResult> {
    let n: usize = dwells.iter().map(|d| d.len()).sum();
    let n_min = dwells.iter().map(|d| d.len()).min()?;
    if n_min < MIN_DWELL_SAMPLES {
        return None;
    }
    let ss: f64 = dwells.iter().flatten().map(|v| v * v).sum();
    let s2 = ss / n as f64;
    if s2 <= 0.0 {
        return None;
    }
    // Normalise so that the white variance is of order one.
    let scale = s2.sqrt();
    for v in dwells.iter_mut().flatten() {
        *v /= scale;
    }
    let profile = Profile {
        norm: dwells,
        dt,
        tau: ((2.0 * dt).ln(), (n_min as f64 * dt / 4.0).max(4.0 * dt).ln()),
        q: ((1e-3f64).ln(), (1e3f64).ln()),
    };
    let (ll, lt, lq) = profile.refine(profile.grid());
    let phi = (-dt / lt.exp()).exp();
    let (_, var_w, e2) = ar1_white_loglik(&profile.norm, phi, lq.exp());
    // Both likelihoods of the normalised data shift by the same -n ln(scale): the ratio is unchanged.
    let ll0_norm = -0.5 * n as f64 * (std::f64::consts::TAU.ln() + 1.0);
    let lr = (2.0 * (ll - ll0_norm)).max(0.0);
    let sigma = (lq.exp() * var_w).sqrt() * scale;
    // Curvature of the profile likelihood in ln q at the optimum: SE(ln sigma) = SE(ln q) / 2.
    let h = 0.05;
    let curv = (profile.ll_at(lt, lq + h) - 2.0 * ll + profile.ll_at(lt, lq - h)) / (h * h);
    let sigma_std = if curv < 0.0 { sigma * 0.5 / (-curv).sqrt() } else { f64::NAN };
    Some(GaussMarkovResult {
        sigma,
        sigma_std,
        tau_s: lt.exp(),
        lr,
        rms_white: s2.sqrt(),
        rms_innovation: e2.sqrt() * scale,
    })
}
