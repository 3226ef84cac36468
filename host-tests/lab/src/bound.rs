//! The Cramer-Rao bound of a calibration from its dwell means under coloured noise
//! (docs/method.md#coloured-noise-monte-carlo).
//!
//! The data are the raw dwell means of the six channels. Under Gaussian noise whose covariance does not depend
//! on the parameters, the Fisher information of the linearised model `ybar = J theta + e` is `J^T Sigma^-1 J`,
//! and `(J^T Sigma^-1 J)^-1` bounds the covariance of every unbiased estimator that uses only the dwell means;
//! generalised least squares with the exact `Sigma` reaches it. `J` is the estimator's design at the truth
//! (docs/method.md#general-estimator), written here in f64 from docs/conventions.md, independently of the core.
//!
//! `Sigma` is exact for the noise of the simulator (`model::simulator`): each channel's noise is independent
//! of the others', so `Sigma` is block-diagonal over the channels, and within a channel the covariance of the
//! means of dwells `a` and `b` (sample `k` covers `[k dt, (k + 1) dt)`, the session starts at sample 0) is the
//! sum of, per kind:
//! - white noise of per-sample standard deviation `s`: `s^2 / N` on the diagonal;
//! - first-order Gauss-Markov of standard deviation `s` and correlation time `T` (AR(1) point values,
//!   `phi = e^(-dt/T)`, autocovariance `s^2 phi^|i-j|`): on the diagonal
//!   `s^2 / N^2 (N (1 + phi) / (1 - phi) - 2 phi (1 - phi^N) / (1 - phi)^2)`; between dwells
//!   `s^2 S_a S_b phi^gap / (N_a N_b)`, `S = (1 - phi^N) / (1 - phi)`, `gap` = the first sample of the later
//!   dwell minus the last of the earlier;
//! - rate random walk `K` (the exact interval average of a Brownian motion started at 0 at t = 0): the
//!   variance of the mean over `[t0, t0 + T]` is `K^2 (t0 + T / 3)`, the covariance of an earlier dwell's mean
//!   with a later one's `K^2` times the earlier dwell's mid-time;
//! - quantisation of the integrated output with step `q`: the mean of `N` outputs is the mean of the inputs
//!   plus `q (c_before - c_last) / N`, with `c` the quantiser's carry (in steps) before the dwell's first
//!   sample and after its last. With carries uniform and independent (the input moves by many steps between
//!   the carries that enter, which holds when the per-sample noise times the square root of the samples
//!   between them exceeds the step): `q^2 / (6 N^2)` on the diagonal, and `-q^2 / (12 N_a N_b)` between dwells
//!   that share a carry (the later one starts right after the earlier one ends), 0 otherwise.

use sinscal::calib::general::PARAMETERS;

use sinscal_host::io::recording::Recording;
use sinscal_host::model::sensor::Triad;
use sinscal_host::model::simulator::{ScenarioFile, TriadModel};
use sinscal_host::model::synth::{c_b_n, cross, earth_rate_n_radps, mul, mul_t_vec, mul_vec, rotation};
use sinscal_host::stats::solve::solve_spd;

/// The noise of one channel, in the channel's SI unit (rad/s for gyros, m/s^2 for accelerometers).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ChannelNoise {
    /// Standard deviation of the white part of one sample, SI.
    pub white_sample_std_si: f64,
    /// Standard deviation of the first-order Gauss-Markov process, SI (0: none).
    pub markov_std_si: f64,
    /// Its correlation time, s.
    pub markov_tau_s: f64,
    /// Random walk of the bias, SI per sqrt(s), starting at 0 at the session's first sample.
    pub random_walk_si_per_sqrt_s: f64,
    /// Output step of the quantiser, SI (0: not quantised).
    pub quantisation_step_si: f64,
}

/// One kind of noise of [`ChannelNoise`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseKind {
    /// White noise.
    White,
    /// First-order Gauss-Markov.
    GaussMarkov,
    /// Rate (or acceleration) random walk.
    RandomWalk,
    /// Quantisation of the integrated output.
    Quantisation,
}

impl NoiseKind {
    /// Every kind, in report order.
    pub const ALL: [NoiseKind; 4] =
        [NoiseKind::White, NoiseKind::GaussMarkov, NoiseKind::RandomWalk, NoiseKind::Quantisation];

    /// The name in reports.
    pub fn name(self) -> &'static str {
        match self {
            NoiseKind::White => "white",
            NoiseKind::GaussMarkov => "Gauss-Markov",
            NoiseKind::RandomWalk => "random walk",
            NoiseKind::Quantisation => "quantisation",
        }
    }
}

/// The samples of one dwell: the session's sample index of its first sample and the number of samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DwellSpan {
    /// Index of the first sample (sample `k` covers `[k dt, (k + 1) dt)` from the session's start).
    pub first_sample: u64,
    /// Samples in the dwell.
    pub samples: u64,
}

impl DwellSpan {
    fn last_sample(&self) -> u64 {
        self.first_sample + self.samples - 1
    }
}

/// The covariance of the dwell means of one channel that one kind of its noise makes, SI squared; dwells in
/// time order, not overlapping.
pub fn dwell_mean_covariance_of(
    kind: NoiseKind,
    noise: &ChannelNoise,
    spans: &[DwellSpan],
    dt_s: f64,
) -> Vec<Vec<f64>> {
    let d = spans.len();
    let mut cov = vec![vec![0.0; d]; d];
    for a in 0..d {
        for b in a..d {
            let (x, y) = (spans[a], spans[b]);
            let value = match kind {
                NoiseKind::White => white(noise, x, a == b),
                NoiseKind::GaussMarkov => gauss_markov(noise, x, y, a == b, dt_s),
                NoiseKind::RandomWalk => random_walk(noise, x, a == b, dt_s),
                NoiseKind::Quantisation => quantisation(noise, x, y, a == b),
            };
            cov[a][b] = value;
            cov[b][a] = value;
        }
    }
    cov
}

/// The covariance of the dwell means of one channel under all its noise, SI squared.
pub fn dwell_mean_covariance(noise: &ChannelNoise, spans: &[DwellSpan], dt_s: f64) -> Vec<Vec<f64>> {
    let d = spans.len();
    let mut cov = vec![vec![0.0; d]; d];
    for kind in NoiseKind::ALL {
        let part = dwell_mean_covariance_of(kind, noise, spans, dt_s);
        for a in 0..d {
            for b in 0..d {
                cov[a][b] += part[a][b];
            }
        }
    }
    cov
}

fn white(noise: &ChannelNoise, x: DwellSpan, same: bool) -> f64 {
    if same {
        noise.white_sample_std_si.powi(2) / x.samples as f64
    } else {
        0.0
    }
}

/// `x` before `y` (or the same dwell).
fn gauss_markov(noise: &ChannelNoise, x: DwellSpan, y: DwellSpan, same: bool, dt_s: f64) -> f64 {
    let s2 = noise.markov_std_si.powi(2);
    if s2 == 0.0 || noise.markov_tau_s <= 0.0 {
        return 0.0;
    }
    let rate = dt_s / noise.markov_tau_s;
    let phi = (-rate).exp();
    // 1 - phi^n without cancellation, and the geometric sum S = (1 - phi^n) / (1 - phi).
    let one_minus_power = |n: f64| -(-n * rate).exp_m1();
    let one_minus = one_minus_power(1.0);
    let sum = |n: f64| one_minus_power(n) / one_minus;
    let (na, nb) = (x.samples as f64, y.samples as f64);
    if same {
        s2 / (na * na) * (na * (1.0 + phi) / one_minus - 2.0 * phi * one_minus_power(na) / (one_minus * one_minus))
    } else {
        let gap = (y.first_sample - x.last_sample()) as f64;
        s2 * sum(na) * sum(nb) * phi.powf(gap) / (na * nb)
    }
}

/// `x` before `y` (or the same dwell): the covariance of the exact interval averages of `K W(t)`.
fn random_walk(noise: &ChannelNoise, x: DwellSpan, same: bool, dt_s: f64) -> f64 {
    let k2 = noise.random_walk_si_per_sqrt_s.powi(2);
    let t0 = x.first_sample as f64 * dt_s;
    let t = x.samples as f64 * dt_s;
    if same {
        k2 * (t0 + t / 3.0)
    } else {
        k2 * (t0 + t / 2.0)
    }
}

/// `x` before `y` (or the same dwell).
fn quantisation(noise: &ChannelNoise, x: DwellSpan, y: DwellSpan, same: bool) -> f64 {
    let q2 = noise.quantisation_step_si.powi(2);
    let (na, nb) = (x.samples as f64, y.samples as f64);
    if same {
        q2 / (6.0 * na * na)
    } else if y.first_sample == x.last_sample() + 1 {
        -q2 / (12.0 * na * nb)
    } else {
        0.0
    }
}

/// The noise of the six channels (gyro x, y, z, accelerometer x, y, z) of a scenario as the simulator makes it
/// (`model::simulator`): white density over the root of the sample interval, Gauss-Markov, random walk and
/// quantisation step of each triad.
pub fn channel_noises(scenario: &ScenarioFile) -> [ChannelNoise; 6] {
    let dt_s = 1.0 / scenario.schedule.rate_hz;
    let of = |m: &TriadModel, axis: usize| ChannelNoise {
        white_sample_std_si: m.white_density / dt_s.sqrt(),
        markov_std_si: m.gauss_markov.map_or(0.0, |(sigma, _)| sigma[axis]),
        markov_tau_s: m.gauss_markov.map_or(0.0, |(_, tau)| tau),
        random_walk_si_per_sqrt_s: m.random_walk,
        quantisation_step_si: m.quantization[axis],
    };
    let (gyro, accel) = (scenario.gyro_model(), scenario.accel_model());
    [of(&gyro, 0), of(&gyro, 1), of(&gyro, 2), of(&accel, 0), of(&accel, 1), of(&accel, 2)]
}

/// The dwells of a recording as spans of samples (the first row's time over the sample interval), in the
/// recording's order; `None` without a rate.
pub fn dwell_spans(recording: &Recording) -> Option<Vec<DwellSpan>> {
    let rate_hz = recording.header.rate_hz?;
    Some(
        recording
            .dwells()
            .iter()
            .map(|d| DwellSpan { first_sample: (d.rows[0].t_s * rate_hz).round() as u64, samples: d.rows.len() as u64 })
            .collect(),
    )
}

/// A session as the bound sees it: the site and the reference attitudes of the dwells.
#[derive(Clone, Debug, PartialEq)]
pub struct Session {
    /// Latitude, rad.
    pub latitude_rad: f64,
    /// Gravity, m/s^2.
    pub gravity_mps2: f64,
    /// Reference attitude (pitch, roll, heading) of each dwell, degrees; the truth has no reference offset.
    pub positions_deg: Vec<[f64; 3]>,
}

/// The design of the general estimator at the truth `theta_si` (the core's parameter layout,
/// docs/formats.md#calibration-json-version-2): per dwell, rows gyro x, y, z, accelerometer x, y, z, each the
/// derivative of the predicted dwell mean by every parameter (docs/method.md#general-estimator):
/// `w = T_g C^T w_n + b_g + G C^T f_n`, `f = T_a C^T f_n + b_a`, `C = R(-delta) C_ref` with the reference offset
/// `delta`, whose columns are first order as the estimator's: `d(C^T v) / d delta_m = C^T (e_m x v)`.
pub fn design(session: &Session, theta_si: &[f64; PARAMETERS]) -> Vec<[[f64; PARAMETERS]; 6]> {
    let w_n = earth_rate_n_radps(session.latitude_rad);
    let f_n = [0.0, 0.0, session.gravity_mps2];
    let matrix = |scale: usize, misalignment: usize| -> [[f64; 3]; 3] {
        let mut t = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                t[i][j] = if i == j {
                    1.0 + theta_si[scale + i]
                } else {
                    theta_si[misalignment + sinscal::calib::general::misalignment_index(i, j)]
                };
            }
        }
        t
    };
    let (t_a, t_g) = (matrix(6, 9), matrix(15, 18));
    let g = [0, 1, 2].map(|i| [0, 1, 2].map(|j| theta_si[24 + 3 * i + j]));
    let offset = [-theta_si[33], -theta_si[34], -theta_si[35]];
    session
        .positions_deg
        .iter()
        .map(|p| {
            let c = mul(&rotation(offset), &c_b_n(p[0], p[1], p[2]));
            let (f_b, w_b) = (mul_t_vec(&c, f_n), mul_t_vec(&c, w_n));
            let mut rows = [[0.0; PARAMETERS]; 6];
            for i in 0..3 {
                let (gy, ac) = (&mut rows[i], i);
                gy[i] = 1.0;
                gy[15 + i] = w_b[i];
                for j in 0..3 {
                    if i != j {
                        gy[18 + sinscal::calib::general::misalignment_index(i, j)] = w_b[j];
                    }
                    gy[24 + 3 * i + j] = f_b[j];
                }
                let a = &mut rows[3 + ac];
                a[3 + i] = 1.0;
                a[6 + i] = f_b[i];
                for j in 0..3 {
                    if i != j {
                        a[9 + sinscal::calib::general::misalignment_index(i, j)] = f_b[j];
                    }
                }
            }
            for m in 0..3 {
                let mut e = [0.0; 3];
                e[m] = 1.0;
                let (dw_b, df_b) = (mul_t_vec(&c, cross(e, w_n)), mul_t_vec(&c, cross(e, f_n)));
                let (dg, dgf, da) = (mul_vec(&t_g, dw_b), mul_vec(&g, df_b), mul_vec(&t_a, df_b));
                for i in 0..3 {
                    rows[i][33 + m] = dg[i] + dgf[i];
                    rows[3 + i][33 + m] = da[i];
                }
            }
            rows
        })
        .collect()
}

/// The dwell means the model predicts at `theta_si` (rows as in [`design`]), without noise; the reference offset
/// turns the reference attitude exactly, `C_true = R(-delta) C_ref` (docs/method.md#general-estimator).
pub fn predict(session: &Session, theta_si: &[f64; PARAMETERS]) -> Vec<[f64; 6]> {
    let w_n = earth_rate_n_radps(session.latitude_rad);
    let f_n = [0.0, 0.0, session.gravity_mps2];
    let offset = [-theta_si[33], -theta_si[34], -theta_si[35]];
    let mut gyro_misalignment = [[0.0; 3]; 3];
    let mut accel_misalignment = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            if i != j {
                let k = sinscal::calib::general::misalignment_index(i, j);
                gyro_misalignment[i][j] = theta_si[18 + k];
                accel_misalignment[i][j] = theta_si[9 + k];
            }
        }
    }
    let bias = |first: usize| [theta_si[first], theta_si[first + 1], theta_si[first + 2]];
    let g = [0, 1, 2].map(|i| [0, 1, 2].map(|j| theta_si[24 + 3 * i + j]));
    let gyro = Triad::new(bias(0), bias(15), &gyro_misalignment, g);
    let accel = Triad::new(bias(3), bias(6), &accel_misalignment, [[0.0; 3]; 3]);
    session
        .positions_deg
        .iter()
        .map(|p| {
            let c = mul(&rotation(offset), &c_b_n(p[0], p[1], p[2]));
            let (f_b, w_b) = (mul_t_vec(&c, f_n), mul_t_vec(&c, w_n));
            let (w, f) = (gyro.measure(w_b, f_b), accel.measure(f_b, [0.0; 3]));
            [w[0], w[1], w[2], f[0], f[1], f[2]]
        })
        .collect()
}

/// The bound for a set of parameters (the others known), and the generalised least-squares gain that reaches
/// it.
#[derive(Clone, Debug, PartialEq)]
pub struct Bound {
    /// The parameters, in the core's layout.
    pub parameters: Vec<usize>,
    /// `(J^T Sigma^-1 J)^-1`, SI, in the order of `parameters`.
    pub covariance_si: Vec<Vec<f64>>,
    /// `(J^T Sigma^-1 J)^-1 J^T Sigma^-1`: row per parameter, column per datum (channel-major: channel `c`,
    /// dwell `k` at `c * dwells + k`). Applied to the dwell means minus their prediction at the truth, it gives
    /// the generalised least-squares error.
    pub gain: Vec<Vec<f64>>,
}

impl Bound {
    /// The bound's standard deviation of each parameter, SI.
    pub fn std_si(&self) -> Vec<f64> {
        (0..self.parameters.len()).map(|i| self.covariance_si[i][i].max(0.0).sqrt()).collect()
    }
}

/// The rows of the design for `parameters`, channel-major (channel `c`, dwell `k` at `c * dwells + k`).
fn rows_of(design: &[[[f64; PARAMETERS]; 6]], parameters: &[usize]) -> Vec<Vec<f64>> {
    (0..6).flat_map(|c| design.iter().map(move |d| parameters.iter().map(|&p| d[c][p]).collect())).collect()
}

/// The inverse of a symmetric positive definite matrix; `None` when singular.
fn inverse(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    solve_spd(a, &vec![0.0; a.len()]).map(|(_, inv)| inv)
}

/// The Cramer-Rao bound of `parameters` from the dwell means with the design `design` and, per channel (gyro x,
/// y, z, accelerometer x, y, z), the covariance of its dwell means; `None` when the parameters are not
/// determined (the information matrix is singular) or a covariance is not positive definite.
pub fn cramer_rao(
    design: &[[[f64; PARAMETERS]; 6]],
    covariance: &[Vec<Vec<f64>>; 6],
    parameters: &[usize],
) -> Option<Bound> {
    let d = design.len();
    let rows = rows_of(design, parameters);
    let p = parameters.len();
    // Sigma^-1 J, channel block by channel block.
    let mut weighted = vec![vec![0.0; p]; 6 * d];
    for (c, cov) in covariance.iter().enumerate() {
        let inv = inverse(cov)?;
        for a in 0..d {
            for b in 0..d {
                for k in 0..p {
                    weighted[c * d + a][k] += inv[a][b] * rows[c * d + b][k];
                }
            }
        }
    }
    let mut fisher = vec![vec![0.0; p]; p];
    for (row, w) in rows.iter().zip(&weighted) {
        for i in 0..p {
            for j in 0..p {
                fisher[i][j] += row[i] * w[j];
            }
        }
    }
    let covariance_si = inverse(&fisher)?;
    let gain =
        (0..p).map(|i| weighted.iter().map(|w| (0..p).map(|j| covariance_si[i][j] * w[j]).sum()).collect()).collect();
    Some(Bound { parameters: parameters.to_vec(), covariance_si, gain })
}

/// The variances the general estimator gives the dwell means (docs/method.md#how-it-solves), from their exact
/// covariance: per channel one white-equivalent noise of the session, `q = mean over the dwells of N_k
/// Sigma_kk`, over each dwell's samples, `q / N_k`.
pub fn pooled_variances(covariance: &[Vec<Vec<f64>>; 6], spans: &[DwellSpan]) -> [Vec<f64>; 6] {
    core::array::from_fn(|c| {
        let q = spans.iter().enumerate().map(|(k, s)| s.samples as f64 * covariance[c][k][k]).sum::<f64>()
            / spans.len() as f64;
        spans.iter().map(|s| q / s.samples as f64).collect()
    })
}

/// The exact covariance of the weighted least-squares estimator that treats the dwell means as independent
/// with the variances `variance` (per channel and dwell) when their covariance is `covariance`:
/// `(J^T W J)^-1 J^T W Sigma W J (J^T W J)^-1`, `W = diag(1 / variance)`. With the variances of
/// [`pooled_variances`] it is what the general estimator's weighting achieves when its noise estimate is exact,
/// and against the bound what treating the dwell means as independent costs. `None` when singular.
pub fn independent_weighting_covariance(
    design: &[[[f64; PARAMETERS]; 6]],
    covariance: &[Vec<Vec<f64>>; 6],
    variance: &[Vec<f64>; 6],
    parameters: &[usize],
) -> Option<Vec<Vec<f64>>> {
    let d = design.len();
    let rows = rows_of(design, parameters);
    let p = parameters.len();
    let weight = |c: usize, k: usize| 1.0 / variance[c][k];
    let mut normal = vec![vec![0.0; p]; p];
    for (r, row) in rows.iter().enumerate() {
        for i in 0..p {
            for j in 0..p {
                normal[i][j] += row[i] * weight(r / d, r % d) * row[j];
            }
        }
    }
    let inv = inverse(&normal)?;
    // The estimator's gain (J^T W J)^-1 J^T W, then gain Sigma gain^T.
    let gain: Vec<Vec<f64>> = (0..p)
        .map(|i| {
            rows.iter()
                .enumerate()
                .map(|(r, row)| (0..p).map(|j| inv[i][j] * row[j]).sum::<f64>() * weight(r / d, r % d))
                .collect()
        })
        .collect();
    let mut out = vec![vec![0.0; p]; p];
    for (c, cov) in covariance.iter().enumerate() {
        for i in 0..p {
            for j in 0..p {
                let mut s = 0.0;
                for a in 0..d {
                    for b in 0..d {
                        s += gain[i][c * d + a] * cov[a][b] * gain[j][c * d + b];
                    }
                }
                out[i][j] += s;
            }
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinscal::calib::general::{ChannelDwell, ChannelEstimator, ChannelSettings, Model, Term};
    use sinscal::nav::earth::Site;
    use sinscal::nav::frames::Attitude;
    use sinscal_host::model::simulator::{simulate, GaussMarkovSpec, ScheduleSpec, SiteSpec};
    use sinscal_host::model::synth::{DEG_PER_HOUR, MICRO_G, TABLE1_DEG};

    /// The covariance of two dwell means written as the double sum over their samples of the per-sample
    /// covariance, each kind's from its own definition (not from the closed forms): white `s^2 [i = j]`,
    /// Gauss-Markov `s^2 phi^|i-j|`, the interval averages of `K W(t)` `K^2 dt (min(i, j) + 1/2 - [i = j] / 6)`, and
    /// quantisation through the carries: output `k` is the input plus `q (c_{k-1} - c_k)`.
    fn brute_force(kind: NoiseKind, n: &ChannelNoise, a: DwellSpan, b: DwellSpan, dt_s: f64) -> f64 {
        let samples = |s: DwellSpan| s.first_sample..s.first_sample + s.samples;
        let mut sum = 0.0;
        if kind == NoiseKind::Quantisation {
            // Sum over carries m of the weight each dwell puts on c_m: +1 on c_{first-1}, -1 on c_last.
            let weight = |s: DwellSpan, m: u64| {
                (if m + 1 == s.first_sample { 1.0 } else { 0.0 }) - if m == s.last_sample() { 1.0 } else { 0.0 }
            };
            for m in 0..=b.last_sample().max(a.last_sample()) {
                sum += weight(a, m) * weight(b, m) * n.quantisation_step_si.powi(2) / 12.0;
            }
            return sum / (a.samples * b.samples) as f64;
        }
        for i in samples(a) {
            for j in samples(b) {
                let same = if i == j { 1.0 } else { 0.0 };
                sum += match kind {
                    NoiseKind::White => n.white_sample_std_si.powi(2) * same,
                    NoiseKind::GaussMarkov => {
                        n.markov_std_si.powi(2) * (-dt_s / n.markov_tau_s).exp().powi(i.abs_diff(j) as i32)
                    }
                    NoiseKind::RandomWalk => {
                        n.random_walk_si_per_sqrt_s.powi(2) * dt_s * (i.min(j) as f64 + 0.5 - same / 6.0)
                    }
                    NoiseKind::Quantisation => 0.0,
                };
            }
        }
        sum / (a.samples * b.samples) as f64
    }

    #[test]
    fn closed_forms_are_the_double_sums_of_the_per_sample_covariance() {
        let n = ChannelNoise {
            white_sample_std_si: 2.0,
            markov_std_si: 1.5,
            markov_tau_s: 0.37,
            random_walk_si_per_sqrt_s: 0.8,
            quantisation_step_si: 3.0,
        };
        let dt_s = 0.01;
        // Dwells of different lengths, one right after another (they share a quantiser carry), one after a gap.
        let spans = [
            DwellSpan { first_sample: 7, samples: 50 },
            DwellSpan { first_sample: 57, samples: 80 },
            DwellSpan { first_sample: 190, samples: 64 },
        ];
        for kind in NoiseKind::ALL {
            let cov = dwell_mean_covariance_of(kind, &n, &spans, dt_s);
            for a in 0..3 {
                for b in a..3 {
                    let expected = brute_force(kind, &n, spans[a], spans[b], dt_s);
                    let scale = (brute_force(kind, &n, spans[a], spans[a], dt_s)
                        * brute_force(kind, &n, spans[b], spans[b], dt_s))
                    .sqrt();
                    assert!(
                        (cov[a][b] - expected).abs() <= 1e-9 * scale,
                        "{kind:?} ({a}, {b}): {} vs {expected}",
                        cov[a][b]
                    );
                }
            }
        }
    }

    /// Continuous time: the mean of `K W(t)` over `[t0, t0 + T]` has variance `K^2 (t0 + T / 3)`, exactly, at any
    /// sample interval (the simulator draws the exact interval averages).
    #[test]
    fn random_walk_means_have_the_continuous_time_variance() {
        let n = ChannelNoise { random_walk_si_per_sqrt_s: 1e-3, ..ChannelNoise::default() };
        for dt_s in [0.01, 0.1, 1.0] {
            let span = DwellSpan { first_sample: (12.0 / dt_s) as u64, samples: (60.0 / dt_s) as u64 };
            let var = dwell_mean_covariance(&n, &[span], dt_s)[0][0];
            assert!((var / (1e-6 * (12.0 + 20.0)) - 1.0).abs() < 1e-12, "dt {dt_s}: {var}");
        }
    }

    fn table1_session() -> Session {
        Session { latitude_rad: 45.7796f64.to_radians(), gravity_mps2: 9.8063, positions_deg: TABLE1_DEG.to_vec() }
    }

    fn some_truth() -> [f64; PARAMETERS] {
        let mut theta = [0.0; PARAMETERS];
        for (i, t) in theta.iter_mut().enumerate() {
            // Small values of both signs in every parameter, of the order of a real sensor's.
            *t = 1e-4 * (((i * 7919) % 13) as f64 - 6.0) / 6.0;
        }
        theta[0] = 0.05 * DEG_PER_HOUR;
        theta[3] = 100.0 * MICRO_G;
        // The offset columns are first order (as the estimator's): exact derivatives at a zero offset.
        theta[33..].fill(0.0);
        theta
    }

    #[test]
    fn design_is_the_derivative_of_the_prediction() {
        let session = table1_session();
        let theta = some_truth();
        let rows = design(&session, &theta);
        for p in 0..PARAMETERS {
            let step = 1e-6;
            let (mut up, mut down) = (theta, theta);
            up[p] += step;
            down[p] -= step;
            let (hi, lo) = (predict(&session, &up), predict(&session, &down));
            for (k, row) in rows.iter().enumerate() {
                for c in 0..6 {
                    let numeric = (hi[k][c] - lo[k][c]) / (2.0 * step);
                    let scale = if c < 3 { 7.3e-5 } else { 9.8 };
                    assert!(
                        (numeric - row[c][p]).abs() < 1e-6 * scale,
                        "{} dwell {k} channel {c}: {numeric} vs {}",
                        sinscal::calib::general::parameter_name(p),
                        row[c][p]
                    );
                }
            }
        }
    }

    /// White noise: the bound is the estimator's own covariance (its weights are then exact), for models with
    /// and without terms that couple the channels.
    #[test]
    fn on_white_noise_the_bound_is_the_estimators_covariance() {
        let session = table1_session();
        let mut theta = [0.0; PARAMETERS];
        theta[0] = 0.05 * DEG_PER_HOUR;
        theta[4] = -80.0 * MICRO_G;
        theta[8] = -1e-4;
        let predicted = predict(&session, &theta);
        // Different noise on every channel, so that the weighting matters.
        let var: [f64; 6] = [2.0e-14, 3.0e-14, 1.5e-14, 1.0e-10, 2.0e-10, 4.0e-10];
        let site = Site { latitude_rad: session.latitude_rad as f32, gravity_mps2: session.gravity_mps2 as f32 };
        let models =
            [Model::BIASES.with(Term::AccelScaleFactor), Model::BIASES.with(Term::ReferenceOffset), Model::FULL];
        for model in models {
            let mut estimator = ChannelEstimator::new(site, ChannelSettings { model, ..ChannelSettings::default() });
            for (p, y) in session.positions_deg.iter().zip(&predicted) {
                let a = Attitude::from_degrees(p[0] as f32, p[1] as f32, p[2] as f32);
                estimator
                    .add(ChannelDwell {
                        tilt: a.tilt(),
                        heading_rad: Some(a.heading_rad),
                        rate_mean_b_radps: [y[0] as f32, y[1] as f32, y[2] as f32],
                        force_mean_b_mps2: [y[3] as f32, y[4] as f32, y[5] as f32],
                        rate_mean_var_b_radps2: [var[0] as f32, var[1] as f32, var[2] as f32],
                        force_mean_var_b_mps2sq: [var[3] as f32, var[4] as f32, var[5] as f32],
                        window: None,
                    })
                    .unwrap();
            }
            let solution = estimator.solve().unwrap();
            let determined: Vec<usize> = (0..PARAMETERS).filter(|&i| solution.estimate(i).is_some()).collect();
            // The completion (docs/method.md#observability) is free in the solution: free in the bound too.
            let solved: Vec<usize> =
                (0..PARAMETERS).filter(|&i| determined.contains(&i) || solution.completion & (1 << i) != 0).collect();
            let spans: Vec<DwellSpan> =
                (0..6).map(|k| DwellSpan { first_sample: 1000 * k as u64, samples: 1 }).collect();
            let covariance = var.map(|v| {
                let n = ChannelNoise { white_sample_std_si: v.sqrt(), ..ChannelNoise::default() };
                dwell_mean_covariance(&n, &spans, 0.01)
            });
            let bound = cramer_rao(&design(&session, &theta), &covariance, &solved).unwrap();
            for (i, &a) in solved.iter().enumerate().filter(|(_, a)| determined.contains(a)) {
                for (j, &b) in solved.iter().enumerate().filter(|(_, b)| determined.contains(b)) {
                    let core = solution.covariance_si[a][b] as f64;
                    let scale = (bound.covariance_si[i][i] * bound.covariance_si[j][j]).sqrt();
                    assert!(
                        (core - bound.covariance_si[i][j]).abs() < 2e-3 * scale,
                        "{model:?} ({}, {}): core {core:e} bound {:e}",
                        sinscal::calib::general::parameter_name(a),
                        sinscal::calib::general::parameter_name(b),
                        bound.covariance_si[i][j]
                    );
                }
            }
        }
    }

    /// The scenario of the sample-statistics check: three short dwells, one kind of noise on the gyros.
    fn short_scenario(kind: NoiseKind) -> ScenarioFile {
        let mut s = ScenarioFile {
            site: SiteSpec { latitude_deg: 45.0, height_m: 0.0, gravity_mps2: Some(9.8) },
            schedule: ScheduleSpec {
                rate_hz: 100.0,
                dwell_s: 1.0,
                move_s: 0.2,
                settle_s: 0.1,
                positions_deg: TABLE1_DEG[..3].to_vec(),
                ..ScheduleSpec::default()
            },
            ..ScenarioFile::default()
        };
        match kind {
            NoiseKind::White => s.gyro.angle_random_walk_rad_per_sqrt_s = 1e-5,
            NoiseKind::GaussMarkov => s.gyro.bias_instability = Some(GaussMarkovSpec { sigma: [1e-4; 3], tau_s: 0.5 }),
            NoiseKind::RandomWalk => s.gyro.rate_random_walk_radps_per_sqrt_s = 1e-4,
            // Quantisation of white noise of a third of the step per sample: the carries are uniform.
            NoiseKind::Quantisation => {
                s.gyro.angle_random_walk_rad_per_sqrt_s = 1e-5;
                s.gyro.quantization_radps = [3e-4; 3];
            }
        }
        s
    }

    /// The dwell means of the three gyro channels of a simulated session (each channel an independent replicate).
    fn gyro_means(s: &ScenarioFile, seed: u64) -> [Vec<f64>; 3] {
        let rec = simulate(s, seed, "bound-check");
        let dwells = rec.dwells();
        [0, 1, 2].map(|i| {
            dwells.iter().map(|d| d.rows.iter().map(|r| r.rate_b_radps[i]).sum::<f64>() / d.rows.len() as f64).collect()
        })
    }

    /// The closed forms against the sample covariance of simulated dwell means (the simulator of `sinscal
    /// simulate`), every kind alone; quantisation as the difference of the means with and without the quantiser
    /// on the same random numbers, which is the quantisation error alone.
    #[test]
    fn covariance_of_simulated_dwell_means_matches_the_closed_forms() {
        const SESSIONS: u64 = 1500;
        for kind in NoiseKind::ALL {
            let s = short_scenario(kind);
            let unquantised = {
                let mut u = s.clone();
                u.gyro.quantization_radps = [0.0; 3];
                u
            };
            // The noise of the means: against the noise-free session, or for quantisation against the same
            // session unquantised.
            let quiet = gyro_means(&ScenarioFile { gyro: Default::default(), ..s.clone() }, 0);
            let mut samples: Vec<Vec<f64>> = Vec::new();
            for seed in 0..SESSIONS {
                let means = gyro_means(&s, seed);
                let reference =
                    if kind == NoiseKind::Quantisation { gyro_means(&unquantised, seed) } else { quiet.clone() };
                for i in 0..3 {
                    samples.push(means[i].iter().zip(&reference[i]).map(|(a, b)| a - b).collect());
                }
            }
            let rec = simulate(&s, 0, "bound-check");
            let spans = dwell_spans(&rec).unwrap();
            let noise = channel_noises(&s)[0];
            let formula = dwell_mean_covariance_of(kind, &noise, &spans, 0.01);
            check_sample_covariance(kind, &samples, &formula);
        }
    }

    /// Every entry of the sample covariance (about the known zero mean) within four standard errors of the
    /// formula, and the diagonal within 10 %.
    fn check_sample_covariance(kind: NoiseKind, samples: &[Vec<f64>], formula: &[Vec<f64>]) {
        let n = samples.len() as f64;
        let d = formula.len();
        for a in 0..d {
            for b in a..d {
                let sample = samples.iter().map(|m| m[a] * m[b]).sum::<f64>() / n;
                let se = ((formula[a][a] * formula[b][b] + formula[a][b].powi(2)) / n).sqrt();
                assert!(
                    (sample - formula[a][b]).abs() < 4.0 * se,
                    "{kind:?} ({a}, {b}): sample {sample:e}, formula {:e}, standard error {se:e}",
                    formula[a][b]
                );
                if a == b {
                    assert!((sample / formula[a][a] - 1.0).abs() < 0.1, "{kind:?} ({a}, {a})");
                }
            }
        }
    }
}
