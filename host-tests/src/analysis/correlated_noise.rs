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
    let (mut sum_ln_s, mut sum_e2_s, mut sum_e2, mut n) = (0.0, 0.0, 0.0, 0usize);
    let drive = q * (1.0 - phi * phi);
    for d in dwells {
        let (mut x, mut p) = (0.0, q);
        for &y in d {
            let s = p + 1.0;
            let e = y - x;
            sum_ln_s += s.ln();
            sum_e2_s += e * e / s;
            sum_e2 += e * e;
            let k = p / s;
            x += k * e;
            p *= 1.0 - k;
            x *= phi;
            p = phi * phi * p + drive;
        }
        n += d.len();
    }
    let nf = n as f64;
    let var = sum_e2_s / nf;
    (-0.5 * nf * ((std::f64::consts::TAU * var).ln() + 1.0) - 0.5 * sum_ln_s, var, sum_e2 / nf)
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

/// First-order Gauss-Markov plus white noise against white noise alone (exact likelihood).
pub(super) fn gauss_markov_test(dwells: &[Vec<f64>], dt: f64) -> Option<GaussMarkovResult> {
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
    let profile = Profile {
        norm: dwells.iter().map(|d| d.iter().map(|v| v / scale).collect()).collect(),
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
