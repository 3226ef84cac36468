//! `sinscal study`: measured data against a SIMULATION of them, the disagreement named and the model extended.
//!
//! For one of the three measured data sets (PSINS laser gyro, imucal Ferraris session, imu_tk Xsens session) a
//! study
//! 1. fits the BASE model: in every static pose a constant mean per channel plus white noise. The white noise's
//!    standard deviation per sample is the data's sample-to-sample noise, the overlapping Allan deviation at the
//!    shortest tau (one sample), which equals the RMS of the first differences divided by sqrt 2 (pooled over the
//!    static poses). For the multi-pose sets the pose means are tied together by the physics of a bias-only
//!    sensor: the accelerometer measures a force of magnitude g plus one constant bias in every pose (direction:
//!    the pose's label for Ferraris, the data's own direction for imu_tk), the gyro one constant bias;
//! 2. SIMULATES the data set with that model (same time stamps, same poses, seeded: reproducible);
//! 3. measures where the data and the SIMULATION disagree (Allan deviation per channel; per pose the norm of the
//!    mean specific force minus g; per pose the gyro means), with PNG figures;
//! 4. names the cause from those numbers ([`Cause`]);
//! 5. extends the model (IEEE Std 952 noise terms with a generator for them; accelerometer scale factors and
//!    misalignments; gyro g-sensitivity or drift; the Ferraris turns' gyro scale factors);
//! 6. measures the gain on data not used for the fit (second half of the record, odd poses, or the left-out pose).
//!
//! Every simulated number is labelled SIMULATION. Units inside: SI; the human text says its units.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use rand_chacha::ChaCha8Rng;
use serde_json::{json, Map, Value};

use crate::io::error::InputError;
use crate::io::import::{
    import_imucal, import_imutk, import_psins, position_stats, StaticDetection, FERRARIS_POSES,
    IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2, IMUTK_GRAVITY_MPS2,
};
use crate::io::recording::Recording;
use crate::model::simulator::{normal, rng};
use crate::model::synth::{mul_vec, DEG_PER_HOUR, M3, MICRO_G};
use crate::stats::noise::{
    fit_noise_terms, gauss_markov_allan_variance, log_spaced_clusters, overlapping_allan_deviation, NoiseTerms,
};

/// Seed of every SIMULATION of a study (the same seed gives the same numbers).
pub const STUDY_SEED: u64 = 952;

/// Schema name of the study JSON.
pub const SCHEMA: &str = "sinscal-study/1";

/// Channel names, gyro x, y, z then accelerometer x, y, z.
pub const CHANNELS: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// A data ADEV above this multiple of the white-noise SIMULATION's at the longest reliable tau is called
/// correlated noise (dimensionless; the relative uncertainty there is at most 0.25).
pub const CORRELATED_RATIO: f64 = 2.0;

/// A per-pose spread above this multiple of what white noise predicts is called a model error (dimensionless).
pub const POSE_SPREAD_RATIO: f64 = 3.0;

/// The measured data sets a study knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Dataset {
    /// PSINS ring-laser-gyro IMU, one static pose on a parked vehicle (psins-lasergyro/lasergyro.imu).
    Psins,
    /// imucal consumer MEMS IMU, six labelled poses and three turns
    /// (imucal-ferraris/example_ferraris_session.csv + _list.json).
    Ferraris,
    /// imu_tk Xsens MTi counts, about 38 hand-placed poses (imu-tk-xsens/xsens_acc.mat + xsens_gyro.mat).
    Imutk,
}

impl Dataset {
    /// The name on the command line and in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Dataset::Psins => "psins",
            Dataset::Ferraris => "ferraris",
            Dataset::Imutk => "imutk",
        }
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Results

/// One Allan deviation curve: averaging times, s, and deviations in the channel's SI unit (rad/s or m/s^2).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Curve {
    /// Averaging times tau, s.
    pub tau_s: Vec<f64>,
    /// Allan deviation at each tau, SI unit of the channel.
    pub adev: Vec<f64>,
}

/// The noise of one channel: data against the base (white) and extended (IEEE 952 terms) SIMULATIONs.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelNoise {
    /// Channel name (`gx` ... `az`).
    pub channel: &'static str,
    /// White-noise standard deviation per sample of the base model, SI (rad/s or m/s^2): the ADEV at one sample
    /// = RMS of first differences / sqrt 2, pooled over the static poses.
    pub white_std: f64,
    /// Sample-rate, Hz.
    pub rate_hz: f64,
    /// ADEV of the data (whole record, or the longest pose of a multi-pose set).
    pub data: Curve,
    /// ADEV of the base SIMULATION of the same samples.
    pub base_sim: Curve,
    /// The longest averaging time with a relative ADEV uncertainty of at most 0.25, s.
    pub long_tau_s: f64,
    /// ADEV(data) / ADEV(base SIMULATION) at `long_tau_s` (dimensionless): the disagreement.
    pub ratio_at_long_tau: f64,
    /// RMS over tau of log10(ADEV base SIMULATION / ADEV data), whole record (dimensionless).
    pub rms_log10_base: f64,
    /// Output step found in the data (SI), if the channel looks quantised.
    pub quantization_step: Option<f64>,
    /// The extension, fitted on the first half and evaluated on the second (single-pose records only).
    pub extended: Option<NoiseExtension>,
}

/// The IEEE 952 noise extension of one channel and its gain on held-out data.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseExtension {
    /// Terms fitted to the whole record's ADEV (Q u*s, N u*sqrt(s), B u, K u/sqrt(s), R u/s; u = rad/s or m/s^2).
    pub terms_all: NoiseTerms,
    /// Terms fitted to the first half's ADEV (used for the held-out evaluation).
    pub terms_first_half: NoiseTerms,
    /// A band-limited term fitted beside the IEEE terms on the whole record, when it improves the fit (the
    /// catalogue's `correlated_noise` or `vibration`: sway and other motion).
    pub extra_all: Option<ExtraTerm>,
    /// The same on the first half (used for the held-out evaluation).
    pub extra_first_half: Option<ExtraTerm>,
    /// ADEV of the second half of the data.
    pub held_out_data: Curve,
    /// ADEV of the base SIMULATION (white, std from the first half) of the second half.
    pub held_out_base_sim: Curve,
    /// ADEV of the extended SIMULATION (terms of the first half) of the second half.
    pub held_out_extended_sim: Curve,
    /// RMS over tau of log10(ADEV SIMULATION / ADEV data) on the second half, base model (dimensionless).
    pub held_out_rms_log10_base: f64,
    /// The same for the extended model (dimensionless).
    pub held_out_rms_log10_extended: f64,
    /// The term that dominates the fitted model at the long tau: "white", "quantization", "bias instability",
    /// "rate random walk" or "rate ramp".
    pub dominant_term: &'static str,
}

/// Vehicle sway test: horizontal accelerometer against g times the tilt integrated from the gyro.
#[derive(Clone, Debug, PartialEq)]
pub struct Sway {
    /// Which pair: "ay vs +g*theta_x" or "ax vs -g*theta_y".
    pub pair: &'static str,
    /// Correlation coefficient of the high-passed 1-s means (dimensionless).
    pub correlation: f64,
    /// Regression slope of the accelerometer on the tilt, m/s^2 per rad (a real tilt gives +-g).
    pub slope_mps2_per_rad: f64,
    /// RMS of the high-passed accelerometer 1-s means, m/s^2.
    pub accel_rms_mps2: f64,
    /// RMS of the high-passed tilt, rad.
    pub tilt_rms_rad: f64,
}

/// One static pose of a multi-pose set.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Position label (1, 2, ...).
    pub pos: u32,
    /// Name (imucal label or "pose N").
    pub name: String,
    /// Samples.
    pub samples: usize,
    /// Mid time, s.
    pub t_mid_s: f64,
    /// Mean gyro output, rad/s.
    pub mean_rate_radps: [f64; 3],
    /// Mean accelerometer output, m/s^2.
    pub mean_force_mps2: [f64; 3],
    /// Labelled up direction in the body (Ferraris), unit vector.
    pub up_b: Option<[f64; 3]>,
    /// |mean force - base bias| - g, data, m/s^2.
    pub norm_minus_g_data_mps2: f64,
    /// The same in the base SIMULATION, m/s^2.
    pub norm_minus_g_base_sim_mps2: f64,
    /// The same in the extended SIMULATION (base calibration applied, so that it shows the pattern the data
    /// show), m/s^2.
    pub norm_minus_g_extended_sim_mps2: f64,
    /// |f calibrated by the extended model| - g, data, m/s^2 (model fitted on all poses).
    pub norm_minus_g_extended_mps2: f64,
    /// Standard deviation of the norm of the pose mean that white noise gives, m/s^2.
    pub norm_noise_std_mps2: f64,
    /// Whether the pose was held out of the fits of the gain evaluation (odd poses / left-out pose).
    pub held_out: bool,
}

/// An accelerometer model f_meas = A f + b (A = I + S + M).
#[derive(Clone, Debug, PartialEq)]
pub struct AccelModel {
    /// Bias, m/s^2.
    pub bias_mps2: [f64; 3],
    /// A, dimensionless (row i: output axis i).
    pub matrix: M3,
}

impl AccelModel {
    /// Scale factors A_ii - 1 (dimensionless).
    pub fn scale_factors(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.matrix[i][i] - 1.0)
    }

    /// The specific force that explains a measured `f`: A^-1 (f - b), m/s^2.
    pub fn calibrate(&self, f: [f64; 3]) -> [f64; 3] {
        let inv = inverse(&self.matrix).unwrap_or(IDENTITY);
        mul_vec(&inv, [0, 1, 2].map(|i| f[i] - self.bias_mps2[i]))
    }
}

/// The multi-pose part of a study.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseStudy {
    /// Gravity used, m/s^2.
    pub gravity_mps2: f64,
    /// "labelled orientations (Ferraris)" or "|f| = g (orientations unknown)".
    pub method: &'static str,
    /// The static poses.
    pub poses: Vec<Pose>,
    /// Base accelerometer model (bias only), fitted on all poses.
    pub base_accel: AccelModel,
    /// Extended accelerometer model (bias, 3 scale factors, misalignments), fitted on all poses.
    pub extended_accel: AccelModel,
    /// RMS over poses of |f - b| - g of the data, base model, m/s^2.
    pub norm_rms_data_mps2: f64,
    /// RMS over poses of the white-noise standard deviation of the pose's norm, m/s^2.
    pub norm_rms_noise_mps2: f64,
    /// RMS over held-out poses of |f calibrated| - g, base model fitted without them, m/s^2.
    pub held_out_norm_rms_base_mps2: f64,
    /// The same for the extended model, m/s^2.
    pub held_out_norm_rms_extended_mps2: f64,
    /// How poses were held out: "odd poses (fit on even)" or "leave one pose out".
    pub held_out_rule: &'static str,
    /// Gyro per-pose means: RMS over poses and axes of (mean - overall mean), rad/s.
    pub gyro_spread_rms_radps: f64,
    /// What white noise gives for that RMS, rad/s.
    pub gyro_spread_noise_radps: f64,
    /// Gyro per-pose-mean models on held-out poses: (name, RMS residual rad/s) for "constant bias",
    /// "bias + drift", "bias + g-sensitivity", when there are enough poses.
    pub gyro_models_held_out_radps: Vec<(&'static str, f64)>,
    /// The g-sensitivity matrix fitted on all poses, (rad/s)/(m/s^2), when tested.
    pub gyro_g_sensitivity: Option<M3>,
    /// Ferraris turns: (label, integrated angle raw deg, bias-removed deg, scale factor |angle|/360 - 1).
    pub turns: Vec<Turn>,
    /// imu_tk: the fitted accelerometer against the factory calibration.
    pub factory: Option<FactoryComparison>,
}

/// One labelled 360-degree turn of a Ferraris session.
#[derive(Clone, Debug, PartialEq)]
pub struct Turn {
    /// Label (x_rot, y_rot, z_rot).
    pub label: String,
    /// Body axis 0, 1, 2.
    pub axis: usize,
    /// Duration, s.
    pub duration_s: f64,
    /// Integral of the raw gyro output over the turn, rad.
    pub raw_angle_rad: f64,
    /// Integral after removing the static gyro bias, rad.
    pub angle_rad: f64,
    /// |angle| / 2 pi - 1 (dimensionless): the gyro scale factor if the turn was one full turn.
    pub scale_factor: f64,
}

/// imu_tk: fitted accelerometer gains and misalignments beside the factory calibration, in one gauge: the
/// lower-triangular factor L of K = L Q (Q a rotation, unobservable from |f| = g), K in counts per m/s^2.
#[derive(Clone, Debug, PartialEq)]
pub struct FactoryComparison {
    /// Fitted gains L_ii, counts per m/s^2 (g = 9.81744 m/s^2).
    pub fitted_gain_counts_per_mps2: [f64; 3],
    /// Factory gains of the same canonical form, counts per m/s^2.
    pub factory_gain_counts_per_mps2: [f64; 3],
    /// Fitted normalised lower off-diagonals L_10/L_11, L_20/L_22, L_21/L_22 (dimensionless).
    pub fitted_misalignment: [f64; 3],
    /// Factory, reading counts = diag(gain) M f.
    pub factory_misalignment: [f64; 3],
    /// Factory, reading counts = diag(gain) M^-1 f (the other convention).
    pub factory_misalignment_inverse: [f64; 3],
    /// Fitted offsets, counts.
    pub fitted_offset_counts: [f64; 3],
}

/// A named cause with the numbers that show it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cause {
    /// Short name ("correlated noise", "vehicle sway", "accel scale factors and misalignments", ...).
    pub name: String,
    /// Channels or sensor concerned.
    pub channels: String,
    /// The numbers, in words with units.
    pub evidence: String,
}

/// A complete study.
#[derive(Clone, Debug)]
pub struct Study {
    /// The data set.
    pub dataset: String,
    /// Files read.
    pub sources: Vec<String>,
    /// Seed of the SIMULATIONs.
    pub seed: u64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Noise of each channel.
    pub noise: Vec<ChannelNoise>,
    /// Sway tests (single-pose records).
    pub sway: Vec<Sway>,
    /// Multi-pose part.
    pub poses: Option<PoseStudy>,
    /// The causes the numbers show, strongest first.
    pub causes: Vec<Cause>,
}

// ---------------------------------------------------------------------------------------------------------------
// Small numerics

const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn inverse(a: &M3) -> Option<M3> {
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if !(det.is_finite() && det.abs() > 1e-300) {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (r0, r1) = ((j + 1) % 3, (j + 2) % 3);
            let (c0, c1) = ((i + 1) % 3, (i + 2) % 3);
            inv[i][j] = (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / det;
        }
    }
    Some(inv)
}

/// Solves the square system `a x = b` by Gaussian elimination with partial pivoting; `None` if singular.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[p][k].is_nan() || a[p][k].abs() <= 1e-300 {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in (k + 1)..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = ((k + 1)..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Linear least squares min |X beta - y| by the normal equations (small, well-conditioned designs).
fn least_squares(rows: &[Vec<f64>], y: &[f64]) -> Option<Vec<f64>> {
    let p = rows.first()?.len();
    if rows.len() < p {
        return None;
    }
    let mut ata = vec![vec![0.0; p]; p];
    let mut aty = vec![0.0; p];
    for (r, &yv) in rows.iter().zip(y) {
        for i in 0..p {
            aty[i] += r[i] * yv;
            for j in 0..p {
                ata[i][j] += r[i] * r[j];
            }
        }
    }
    solve(ata, aty)
}

/// Gauss-Newton with a numerical (central-difference) Jacobian and step halving: minimises sum r_k(p)^2.
fn gauss_newton(mut p: Vec<f64>, residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> Vec<f64> {
    let cost = |p: &[f64]| residuals(p).iter().map(|r| r * r).sum::<f64>();
    let mut c = cost(&p);
    for _ in 0..100 {
        let r = residuals(&p);
        let n = p.len();
        let mut jac = vec![vec![0.0; n]; r.len()];
        for j in 0..n {
            let h = 1e-6 * p[j].abs().max(1e-3);
            let mut a = p.clone();
            let mut b = p.clone();
            a[j] += h;
            b[j] -= h;
            let (ra, rb) = (residuals(&a), residuals(&b));
            for k in 0..r.len() {
                jac[k][j] = (ra[k] - rb[k]) / (2.0 * h);
            }
        }
        let neg: Vec<f64> = r.iter().map(|v| -v).collect();
        let Some(step) = least_squares(&jac, &neg) else { break };
        let mut t = 1.0;
        let mut improved = false;
        for _ in 0..30 {
            let q: Vec<f64> = p.iter().zip(&step).map(|(a, s)| a + t * s).collect();
            let cq = cost(&q);
            if cq <= c {
                let small = step.iter().zip(&p).all(|(s, a)| (t * s).abs() <= 1e-12 * a.abs().max(1e-6));
                p = q;
                improved = cq < c;
                c = cq;
                if small {
                    return p;
                }
                break;
            }
            t *= 0.5;
        }
        if !improved {
            break;
        }
    }
    p
}

fn rms(values: impl IntoIterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in values {
        s += v * v;
        n += 1;
    }
    if n == 0 {
        f64::NAN
    } else {
        (s / n as f64).sqrt()
    }
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// RMS of first differences / sqrt 2 of several segments pooled, SI: the ADEV at one sample.
fn white_std(segments: &[&[f64]]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for seg in segments {
        for w in seg.windows(2) {
            s += (w[1] - w[0]).powi(2);
            n += 1;
        }
    }
    (s / (2.0 * n.max(1) as f64)).sqrt()
}

// ---------------------------------------------------------------------------------------------------------------
// Allan deviation helpers and the IEEE 952 generator

/// Cluster sizes for a record of `n` samples: about 6 per decade, up to n / 3.
fn clusters(n: usize) -> Vec<usize> {
    log_spaced_clusters(n, 6).into_iter().filter(|m| *m * 3 <= n).collect()
}

fn curve(samples: &[f64], rate_hz: f64, m: &[usize]) -> Curve {
    let p = overlapping_allan_deviation(samples, rate_hz, m);
    Curve { tau_s: p.iter().map(|q| q.tau_s).collect(), adev: p.iter().map(|q| q.adev).collect() }
}

/// The largest tau with K = N / m >= 9 clusters (relative uncertainty <= 0.25), as an index into `m`.
fn long_index(n: usize, m: &[usize]) -> usize {
    m.iter().rposition(|&c| c * 9 <= n).unwrap_or(0)
}

/// RMS over the points with K >= 9 of log10(sim / data).
fn rms_log10(sim: &Curve, data: &Curve, n: usize, rate_hz: f64) -> f64 {
    rms(sim
        .tau_s
        .iter()
        .zip(&sim.adev)
        .zip(&data.adev)
        .filter(|((t, _), _)| (*t * rate_hz).round() as usize * 9 <= n)
        .map(|((_, s), d)| (s / d).log10()))
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
            ExtraTerm::Sine { amplitude, frequency_hz } => {
                let phase = rand::Rng::random::<f64>(&mut rng(seed, stream)) * std::f64::consts::TAU;
                let w = std::f64::consts::TAU * frequency_hz;
                (0..n).map(|k| amplitude * (w * (k as f64 + 0.5) / rate_hz + phase).sin()).collect()
            }
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

/// Non-negative weighted least squares on the Allan variance (rows already weighted), by enumerating supports.
fn nnls(rows: &[Vec<f64>], y: &[f64]) -> Option<(Vec<f64>, f64)> {
    let p = rows.first()?.len();
    let mut best: Option<(Vec<f64>, f64)> = None;
    for mask in 1u32..(1 << p) {
        let cols: Vec<usize> = (0..p).filter(|j| mask & (1 << j) != 0).collect();
        let norms: Vec<f64> = cols.iter().map(|&j| rows.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt()).collect();
        if norms.iter().any(|v| v.is_nan() || *v <= 0.0) {
            continue;
        }
        let sub_rows: Vec<Vec<f64>> =
            rows.iter().map(|r| cols.iter().zip(&norms).map(|(&j, n)| r[j] / n).collect()).collect();
        let Some(x) = least_squares(&sub_rows, y) else { continue };
        if x.iter().any(|v| *v < 0.0) {
            continue;
        }
        let mut c = vec![0.0; p];
        for ((&j, v), n) in cols.iter().zip(&x).zip(&norms) {
            c[j] = v / n;
        }
        let ss: f64 =
            rows.iter().zip(y).map(|(r, yv)| (r.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>() - yv).powi(2)).sum();
        if best.as_ref().is_none_or(|b| ss < b.1) {
            best = Some((c, ss));
        }
    }
    best
}

/// Fits the extended noise model to Allan points: the IEEE 952 terms (as [`fit_noise_terms`]: weighted
/// non-negative least squares on the variance, weights 1 / (2 u sigma^2), re-weighted once by the model) plus,
/// optionally, one band-limited term: a Gauss-Markov process (correlation time on a grid of 4 per decade over
/// the curve's tau range) or a sinusoid (frequency on a grid of 12 per decade from 1 / (4 tau_max) to 1 /
/// (2 tau_min)), the one with the smallest weighted residual; it is kept only if it lowers the weighted residual
/// sum by more than 20 %.
pub fn fit_extended_noise(points: &[crate::stats::noise::AllanPoint]) -> (NoiseTerms, Option<ExtraTerm>) {
    let p: Vec<&crate::stats::noise::AllanPoint> =
        points.iter().filter(|q| q.adev > 0.0 && q.adev.is_finite() && q.rel_uncertainty > 0.0).collect();
    let fallback = || (fit_noise_terms(points).map(|f| f.terms).unwrap_or_default(), None);
    if p.len() < 6 {
        return fallback();
    }
    let fit = |tc: Option<ExtraShape>| -> Option<(Vec<f64>, f64)> {
        let measured: Vec<f64> = p.iter().map(|q| q.avar()).collect();
        let mut reference = measured.clone();
        let mut out = None;
        for _ in 0..2 {
            let w: Vec<f64> = p.iter().zip(&reference).map(|(q, r)| 1.0 / (2.0 * q.rel_uncertainty * r)).collect();
            let rows: Vec<Vec<f64>> =
                p.iter().zip(&w).map(|(q, w)| extended_basis(q.tau_s, tc).iter().map(|b| b * w).collect()).collect();
            let y: Vec<f64> = measured.iter().zip(&w).map(|(m, w)| m * w).collect();
            let (c, _) = nnls(&rows, &y)?;
            let model: Vec<f64> =
                p.iter().map(|q| extended_basis(q.tau_s, tc).iter().zip(&c).map(|(b, c)| b * c).sum()).collect();
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
    };
    let Some((c0, ss0)) = fit(None) else { return fallback() };
    let (tmin, tmax) = (p[0].tau_s, p[p.len() - 1].tau_s);
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
    let mut best: Option<(Vec<f64>, f64, ExtraShape)> = None;
    for shape in shapes {
        if let Some((c, ss)) = fit(Some(shape)) {
            if best.as_ref().is_none_or(|b| ss < b.1) {
                best = Some((c, ss, shape));
            }
        }
    }
    let to_terms = |c: &[f64]| NoiseTerms {
        quantization_q: c[0].sqrt(),
        random_walk_n: c[1].sqrt(),
        bias_instability_b: c[2].sqrt(),
        rate_random_walk_k: c[3].sqrt(),
        ramp_r: c[4].sqrt(),
    };
    match best {
        Some((c, ss, shape)) if ss < 0.8 * ss0 && c[5] > 0.0 => (
            to_terms(&c),
            Some(match shape {
                ExtraShape::Gm(tc_s) => ExtraTerm::GaussMarkov { sigma: c[5].sqrt(), tc_s },
                ExtraShape::Sine(frequency_hz) => ExtraTerm::Sine { amplitude: c[5].sqrt(), frequency_hz },
            }),
        ),
        _ => (to_terms(&c0), None),
    }
}

fn white(n: usize, std: f64, seed: u64, stream: u64) -> Vec<f64> {
    let mut r = rng(seed, stream);
    (0..n).map(|_| std * normal(&mut r)).collect()
}

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

/// The noise study of one channel of a single static record: base white SIMULATION, ADEV disagreement, and the
/// IEEE 952 extension fitted on the first half and evaluated on the second.
pub fn channel_noise(channel: &'static str, samples: &[f64], rate_hz: f64, seed: u64, stream: u64) -> ChannelNoise {
    let n = samples.len();
    let m = clusters(n);
    let sigma = white_std(&[samples]);
    let data = curve(samples, rate_hz, &m);
    let base_sim = curve(&white(n, sigma, seed, stream), rate_hz, &m);
    let li = long_index(n, &m).min(data.adev.len().saturating_sub(1));
    let ratio = data.adev.get(li).copied().unwrap_or(f64::NAN) / base_sim.adev.get(li).copied().unwrap_or(f64::NAN);
    let half = n / 2;
    let extended = (half >= 1000).then(|| {
        let (first, second) = (&samples[..half], &samples[half..]);
        let points_all = overlapping_allan_deviation(samples, rate_hz, &m);
        let (terms_all, extra_all) = fit_extended_noise(&points_all);
        let m_half = clusters(half);
        let points_first = overlapping_allan_deviation(first, rate_hz, &m_half);
        let (terms_first_half, extra_first_half) = fit_extended_noise(&points_first);
        let m2 = clusters(second.len());
        let held_out_data = curve(second, rate_hz, &m2);
        let sigma_first = white_std(&[first]);
        let held_out_base_sim = curve(&white(second.len(), sigma_first, seed, stream + 100), rate_hz, &m2);
        let mut ext = generate_noise_terms(&terms_first_half, second.len(), rate_hz, seed, stream + 200);
        if let Some(extra) = extra_first_half {
            for (y, x) in ext.iter_mut().zip(extra.generate(second.len(), rate_hz, seed, stream + 300)) {
                *y += x;
            }
        }
        let held_out_extended_sim = curve(&ext, rate_hz, &m2);
        let l2 = second.len();
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
    });
    let quantization_step =
        crate::stats::noise::detect_quantization(samples).ok().filter(|q| q.quantized).map(|q| q.step);
    ChannelNoise {
        channel,
        white_std: sigma,
        rate_hz,
        rms_log10_base: rms_log10(&base_sim, &data, n, rate_hz),
        long_tau_s: m.get(li).map_or(f64::NAN, |c| *c as f64 / rate_hz),
        ratio_at_long_tau: ratio,
        data,
        base_sim,
        quantization_step,
        extended,
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Single pose (PSINS)

fn column(rec: &Recording, c: usize) -> Vec<f64> {
    rec.rows.iter().map(|r| if c < 3 { r.rate_b_radps[c] } else { r.force_b_mps2[c - 3] }).collect()
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
/// from the gyro channel, both high-passed over 61 s.
pub fn sway_test(pair: &'static str, accel: &[f64], gyro: &[f64], rate_hz: f64, gravity_mps2: f64, sign: f64) -> Sway {
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
    let _ = gravity_mps2;
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
        sway_test("ay vs +g*theta_x", &cols[4], &cols[0], rate_hz, g, g),
        sway_test("ax vs -g*theta_y", &cols[3], &cols[1], rate_hz, g, -g),
    ];
    let mut study =
        Study { dataset: dataset.to_string(), sources, seed, rate_hz, noise, sway, poses: None, causes: Vec::new() };
    study.causes = name_causes(&study);
    study
}

// ---------------------------------------------------------------------------------------------------------------
// Multi-pose

/// How the poses' orientations are known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PoseKind {
    /// imucal labels: each pose has a known up axis; the turns are labelled too.
    Labelled,
    /// No labels: only |f| = g is known (imu_tk).
    Unlabelled,
}

/// Bias-only fit with labelled up directions: b = mean over poses of (m_k - g u_k), m/s^2.
fn base_labelled(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64) -> AccelModel {
    let mut b = [0.0; 3];
    for (m, u) in means.iter().zip(ups) {
        for i in 0..3 {
            b[i] += (m[i] - g * u[i]) / means.len() as f64;
        }
    }
    AccelModel { bias_mps2: b, matrix: IDENTITY }
}

/// Ferraris fit: per output axis m_k,i = b_i + g sum_j A_ij u_k,j by least squares (needs 4 poses spanning
/// the three axes).
fn extended_labelled(means: &[[f64; 3]], ups: &[[f64; 3]], g: f64) -> Option<AccelModel> {
    let rows: Vec<Vec<f64>> = ups.iter().map(|u| vec![1.0, g * u[0], g * u[1], g * u[2]]).collect();
    let mut model = AccelModel { bias_mps2: [0.0; 3], matrix: IDENTITY };
    for i in 0..3 {
        let y: Vec<f64> = means.iter().map(|m| m[i]).collect();
        let x = least_squares(&rows, &y)?;
        model.bias_mps2[i] = x[0];
        model.matrix[i] = [x[1], x[2], x[3]];
    }
    Some(model)
}

/// Bias-only fit by Gauss-Newton on |m_k - b| = g.
fn base_unlabelled(means: &[[f64; 3]], g: f64) -> AccelModel {
    let p =
        gauss_newton(vec![0.0; 3], &|p: &[f64]| means.iter().map(|m| norm(sub(*m, [p[0], p[1], p[2]])) - g).collect());
    AccelModel { bias_mps2: [p[0], p[1], p[2]], matrix: IDENTITY }
}

/// imu_tk-style fit by Gauss-Newton on |T (m_k - b)| = g with T lower-triangular (6 parameters: 3 scale, 3
/// misalignments; the rotation of the body frame is not observable from |f| and is fixed by the triangular
/// form: body x = accelerometer x, body y in the accelerometers' x-y plane). A = T^-1 (lower-triangular too).
fn extended_unlabelled(means: &[[f64; 3]], g: f64) -> Option<AccelModel> {
    let t_of = |p: &[f64]| -> M3 { [[p[3], 0.0, 0.0], [p[4], p[5], 0.0], [p[6], p[7], p[8]]] };
    let residuals = |p: &[f64]| -> Vec<f64> {
        let t = t_of(p);
        means.iter().map(|m| norm(mul_vec(&t, sub(*m, [p[0], p[1], p[2]]))) - g).collect()
    };
    if means.len() < 9 {
        return None;
    }
    let p = gauss_newton(vec![0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0], &residuals);
    Some(AccelModel { bias_mps2: [p[0], p[1], p[2]], matrix: inverse(&t_of(&p))? })
}

/// The lower-triangular L (positive diagonal) of a = L Q, Q orthogonal (an LQ decomposition by Gram-Schmidt on
/// the rows of `a`, first row first).
pub fn lower_triangular_form(a: &M3) -> M3 {
    // Rows of a = L Q: q_0 = a_0 / |a_0|, q_1 from a_1 less its q_0 part, q_2 likewise.
    let mut q: Vec<[f64; 3]> = Vec::new();
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        let mut v = a[i];
        for (j, qj) in q.iter().enumerate() {
            let d: f64 = (0..3).map(|k| a[i][k] * qj[k]).sum();
            l[i][j] = d;
            for k in 0..3 {
                v[k] -= d * qj[k];
            }
        }
        let nv = norm(v);
        l[i][i] = nv;
        q.push(v.map(|x| x / nv));
    }
    l
}

fn gyro_spread(poses: &[Pose], sigma: [f64; 3]) -> (f64, f64) {
    let n = poses.len() as f64;
    let overall: [f64; 3] = [0, 1, 2].map(|i| poses.iter().map(|p| p.mean_rate_radps[i]).sum::<f64>() / n);
    let spread = rms(poses.iter().flat_map(|p| (0..3).map(move |i| p.mean_rate_radps[i] - overall[i])));
    let noise = rms(poses.iter().flat_map(|p| (0..3).map(move |i| sigma[i] / (p.samples as f64).sqrt())));
    (spread, noise)
}

/// Held-out RMS residual (rad/s) of per-pose gyro mean models fitted on even poses, evaluated on odd ones.
fn gyro_models(poses: &[Pose]) -> (Vec<(&'static str, f64)>, Option<M3>) {
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
            let Some(beta) = least_squares(&rows, &y) else { continue };
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
        match least_squares(&rows, &y) {
            Some(beta) => g_sens[i] = [beta[1], beta[2], beta[3]],
            None => ok = false,
        }
    }
    (out, ok.then_some(g_sens))
}

/// Study of a multi-pose recording: the six channels' noise on the longest pose, the per-pose accelerometer
/// norms and gyro means against the base model and its SIMULATION, the extended accelerometer model and its gain
/// on held-out poses, the gyro per-pose models; `turns` are the Ferraris turns as (label, axis, sample range).
pub fn study_multi_pose(
    rec: &Recording,
    kind: PoseKind,
    gravity_mps2: f64,
    dataset: &str,
    sources: Vec<String>,
    seed: u64,
    turns: &[(String, usize, std::ops::Range<usize>)],
) -> Result<Study, InputError> {
    let g = gravity_mps2;
    let rate_hz = rec.header.rate_hz.unwrap_or(100.0);
    let dwells = rec.dwells();
    if dwells.len() < 6 {
        return Err(InputError::file(&rec.source, format!("{} static poses: a study needs at least 6", dwells.len())));
    }
    let stats = position_stats(rec);
    // Noise: pooled white std per channel, ADEV on the longest pose.
    let seg = |d: &crate::io::recording::Dwell<'_>, c: usize| -> Vec<f64> {
        d.rows.iter().map(|r| if c < 3 { r.rate_b_radps[c] } else { r.force_b_mps2[c - 3] }).collect()
    };
    let longest = dwells.iter().max_by_key(|d| d.rows.len()).expect("non-empty");
    let mut noise = Vec::new();
    let mut sigma = [0.0; 6];
    for c in 0..6 {
        let segs: Vec<Vec<f64>> = dwells.iter().map(|d| seg(d, c)).collect();
        let refs: Vec<&[f64]> = segs.iter().map(|s| s.as_slice()).collect();
        sigma[c] = white_std(&refs);
        let mut ch = channel_noise(CHANNELS[c], &seg(longest, c), rate_hz, seed, c as u64 * 1000);
        ch.extended = None;
        ch.white_std = sigma[c];
        noise.push(ch);
    }
    let labelled_up = |pos: u32| -> Option<[f64; 3]> {
        let p = FERRARIS_POSES.iter().find(|p| p.pos == pos)?;
        let (st, ct) = p.pitch_deg.to_radians().sin_cos();
        let (sg, cg) = p.roll_deg.to_radians().sin_cos();
        Some([-sg * ct, st, cg * ct].map(|v: f64| if v.abs() < 1e-12 { 0.0 } else { v }))
    };
    let mut poses: Vec<Pose> = stats
        .iter()
        .enumerate()
        .map(|(k, s)| Pose {
            pos: s.pos,
            name: match kind {
                PoseKind::Labelled => FERRARIS_POSES
                    .iter()
                    .find(|p| p.pos == s.pos)
                    .map_or(format!("pose {}", s.pos), |p| p.label.to_string()),
                PoseKind::Unlabelled => format!("pose {}", s.pos),
            },
            samples: s.samples,
            t_mid_s: 0.5 * (s.first_t_s + s.last_t_s),
            mean_rate_radps: s.mean_rate_b_radps,
            mean_force_mps2: s.mean_force_b_mps2,
            up_b: if kind == PoseKind::Labelled { labelled_up(s.pos) } else { None },
            norm_minus_g_data_mps2: 0.0,
            norm_minus_g_base_sim_mps2: 0.0,
            norm_minus_g_extended_sim_mps2: 0.0,
            norm_minus_g_extended_mps2: 0.0,
            norm_noise_std_mps2: 0.0,
            held_out: k % 2 == 1,
        })
        .collect();
    let means: Vec<[f64; 3]> = poses.iter().map(|p| p.mean_force_mps2).collect();
    let ups: Vec<[f64; 3]> = poses.iter().map(|p| p.up_b.unwrap_or([0.0, 0.0, 1.0])).collect();
    let (base, extended, method) = match kind {
        PoseKind::Labelled => (
            base_labelled(&means, &ups, g),
            extended_labelled(&means, &ups, g)
                .ok_or_else(|| InputError::file(&rec.source, "the labelled poses do not span the three axes"))?,
            "labelled orientations (Ferraris): m = A g u + b per pose, u the labelled up axis",
        ),
        PoseKind::Unlabelled => (
            base_unlabelled(&means, g),
            extended_unlabelled(&means, g)
                .ok_or_else(|| InputError::file(&rec.source, "fewer than 9 static poses: cannot fit 9 parameters"))?,
            "|f| = g over static poses (orientations unknown): |T (m - b)| = g, T lower-triangular, A = T^-1",
        ),
    };
    // Held-out evaluation.
    let (held_out_rule, base_res, ext_res) = match kind {
        PoseKind::Labelled => {
            let (mut rb, mut re) = (Vec::new(), Vec::new());
            for k in 0..poses.len() {
                let keep: Vec<usize> = (0..poses.len()).filter(|&j| j != k).collect();
                let m: Vec<[f64; 3]> = keep.iter().map(|&j| means[j]).collect();
                let u: Vec<[f64; 3]> = keep.iter().map(|&j| ups[j]).collect();
                let b = base_labelled(&m, &u, g);
                rb.push(norm(b.calibrate(means[k])) - g);
                if let Some(e) = extended_labelled(&m, &u, g) {
                    re.push(norm(e.calibrate(means[k])) - g);
                }
            }
            for p in poses.iter_mut() {
                p.held_out = true;
            }
            ("leave one pose out (each pose predicted by the fit on the other five)", rb, re)
        }
        PoseKind::Unlabelled => {
            let fit: Vec<[f64; 3]> = poses.iter().zip(&means).filter(|(p, _)| !p.held_out).map(|(_, m)| *m).collect();
            let b = base_unlabelled(&fit, g);
            let e = extended_unlabelled(&fit, g)
                .ok_or_else(|| InputError::file(&rec.source, "fewer than 9 even poses: cannot fit 9 parameters"))?;
            let test = poses.iter().zip(&means).filter(|(p, _)| p.held_out).map(|(_, m)| *m);
            let rb = test.clone().map(|m| norm(b.calibrate(m)) - g).collect();
            let re = test.map(|m| norm(e.calibrate(m)) - g).collect();
            ("odd poses (models fitted on the even poses)", rb, re)
        }
    };
    // Base and extended SIMULATIONs of the poses (same samples, same pose directions).
    let mut r = rng(seed, 77);
    let mut r_ext = rng(seed, 78);
    let n_sigma = [sigma[3], sigma[4], sigma[5]];
    for (k, p) in poses.iter_mut().enumerate() {
        let dir = match p.up_b {
            Some(u) => u,
            None => {
                let v = extended.calibrate(means[k]);
                let nv = norm(v);
                v.map(|x| x / nv)
            }
        };
        let n = p.samples as f64;
        let sim_mean = |model: &AccelModel, r: &mut ChaCha8Rng| -> [f64; 3] {
            let f = mul_vec(&model.matrix, dir.map(|x| g * x));
            [0, 1, 2].map(|i| f[i] + model.bias_mps2[i] + n_sigma[i] / n.sqrt() * normal(r))
        };
        let base_dir = match p.up_b {
            Some(u) => u,
            None => {
                let v = sub(means[k], base.bias_mps2);
                let nv = norm(v);
                v.map(|x| x / nv)
            }
        };
        let base_sim: [f64; 3] = {
            let f = base_dir.map(|x| g * x);
            [0, 1, 2].map(|i| f[i] + base.bias_mps2[i] + n_sigma[i] / n.sqrt() * normal(&mut r))
        };
        let ext_sim = sim_mean(&extended, &mut r_ext);
        p.norm_minus_g_data_mps2 = norm(sub(means[k], base.bias_mps2)) - g;
        p.norm_minus_g_base_sim_mps2 = norm(sub(base_sim, base.bias_mps2)) - g;
        p.norm_minus_g_extended_sim_mps2 = norm(sub(ext_sim, base.bias_mps2)) - g;
        p.norm_minus_g_extended_mps2 = norm(extended.calibrate(means[k])) - g;
        let u = sub(means[k], base.bias_mps2);
        let nu = norm(u);
        p.norm_noise_std_mps2 = ((0..3).map(|i| (u[i] / nu * n_sigma[i]).powi(2)).sum::<f64>() / n).sqrt();
    }
    let (spread, spread_noise) = gyro_spread(&poses, [sigma[0], sigma[1], sigma[2]]);
    let (gyro_models_held_out_radps, gyro_g_sensitivity) =
        if kind == PoseKind::Unlabelled { gyro_models(&poses) } else { (Vec::new(), None) };
    let gyro_bias: [f64; 3] = [0, 1, 2].map(|i| {
        poses.iter().map(|p| p.mean_rate_radps[i] * p.samples as f64).sum::<f64>()
            / poses.iter().map(|p| p.samples as f64).sum::<f64>()
    });
    let turns = turns
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
        .collect();
    let factory = (dataset == "imutk").then(|| factory_comparison(&extended));
    let pose_study = PoseStudy {
        gravity_mps2: g,
        method,
        norm_rms_data_mps2: rms(poses.iter().map(|p| p.norm_minus_g_data_mps2)),
        norm_rms_noise_mps2: rms(poses.iter().map(|p| p.norm_noise_std_mps2)),
        held_out_norm_rms_base_mps2: rms(base_res),
        held_out_norm_rms_extended_mps2: rms(ext_res),
        held_out_rule,
        gyro_spread_rms_radps: spread,
        gyro_spread_noise_radps: spread_noise,
        gyro_models_held_out_radps,
        gyro_g_sensitivity,
        turns,
        factory,
        poses,
        base_accel: base,
        extended_accel: extended,
    };
    let mut study = Study {
        dataset: dataset.to_string(),
        sources,
        seed,
        rate_hz,
        noise,
        sway: Vec::new(),
        poses: Some(pose_study),
        causes: Vec::new(),
    };
    study.causes = name_causes(&study);
    Ok(study)
}

/// The imu_tk comparison: our model in the importer's units is f_imp = A f + b with f_imp = (counts - 32768) /
/// nominal gain, so counts = diag(nominal gain) A f + (32768 + nominal gain * b); the factory model is counts =
/// diag(gain) M f + offset. Both are brought into the lower-triangular gauge (K = L Q).
fn factory_comparison(model: &AccelModel) -> FactoryComparison {
    let nominal = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2;
    let k_fit: M3 = [0, 1, 2].map(|i| [0, 1, 2].map(|j| nominal[i] * model.matrix[i][j]));
    let l_fit = lower_triangular_form(&k_fit);
    let m_factory: M3 = [[1.0, 0.0, -0.01], [0.01, 1.0, 0.01], [0.02, 0.01, 1.0]];
    let gain_factory = [415.0, 413.0, 415.0];
    let k_factory = |m: &M3| -> M3 { [0, 1, 2].map(|i| [0, 1, 2].map(|j| gain_factory[i] * m[i][j])) };
    let l_f = lower_triangular_form(&k_factory(&m_factory));
    let l_fi = lower_triangular_form(&k_factory(&inverse(&m_factory).unwrap_or(IDENTITY)));
    let mis = |l: &M3| [l[1][0] / l[1][1], l[2][0] / l[2][2], l[2][1] / l[2][2]];
    FactoryComparison {
        fitted_gain_counts_per_mps2: [l_fit[0][0], l_fit[1][1], l_fit[2][2]],
        factory_gain_counts_per_mps2: [l_f[0][0], l_f[1][1], l_f[2][2]],
        fitted_misalignment: mis(&l_fit),
        factory_misalignment: mis(&l_f),
        factory_misalignment_inverse: mis(&l_fi),
        fitted_offset_counts: [0, 1, 2].map(|i| 32768.0 + nominal[i] * model.bias_mps2[i]),
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Causes

fn unit_of(channel: &str) -> (f64, &'static str) {
    if channel.starts_with('g') {
        (DEG_PER_HOUR, "deg/h")
    } else {
        (MICRO_G, "ug")
    }
}

/// Names the causes the numbers of a study show, strongest first.
pub fn name_causes(s: &Study) -> Vec<Cause> {
    let mut causes: Vec<(f64, Cause)> = Vec::new();
    if let Some(p) = &s.poses {
        let ratio = p.norm_rms_data_mps2 / p.norm_rms_noise_mps2;
        let gain = p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2;
        if ratio > POSE_SPREAD_RATIO {
            let sf = p.extended_accel.scale_factors();
            let a = &p.extended_accel.matrix;
            causes.push((
                ratio,
                Cause {
                    name: if gain > 2.0 {
                        "accel scale factors and misalignments".to_string()
                    } else {
                        "accel pose-dependent error not explained by scale factors and misalignments".to_string()
                    },
                    channels: "ax ay az".to_string(),
                    evidence: format!(
                        "|mean f - b| - g over the poses: RMS {:.4} m/s^2 = {:.0} x the {:.2e} m/s^2 that white noise \
                         gives (bias-only base model); fitted scale factors {:+.4} {:+.4} {:+.4}, misalignments \
                         A_yx {:+.4} A_zx {:+.4} A_zy {:+.4} (dimensionless); held-out RMS {:.4} -> {:.4} m/s^2 \
                         ({:.0} x smaller)",
                        p.norm_rms_data_mps2,
                        ratio,
                        p.norm_rms_noise_mps2,
                        sf[0],
                        sf[1],
                        sf[2],
                        a[1][0],
                        a[2][0],
                        a[2][1],
                        p.held_out_norm_rms_base_mps2,
                        p.held_out_norm_rms_extended_mps2,
                        gain
                    ),
                },
            ));
        }
        let gratio = p.gyro_spread_rms_radps / p.gyro_spread_noise_radps;
        if gratio > POSE_SPREAD_RATIO {
            let constant = p.gyro_models_held_out_radps.iter().find(|m| m.0 == "constant bias").map(|m| m.1);
            let best = p.gyro_models_held_out_radps.iter().min_by(|a, b| a.1.total_cmp(&b.1));
            let (name, detail) = match (constant, best) {
                (Some(c), Some(b)) if b.0 != "constant bias" && b.1 < 0.8 * c => (
                    format!("gyro {}", b.0.trim_start_matches("bias + ")),
                    format!(
                        "; on the odd poses the {} model leaves {:.4} deg/s RMS against {:.4} deg/s for a constant \
                         bias",
                        b.0,
                        b.1.to_degrees(),
                        c.to_degrees()
                    ),
                ),
                (Some(c), Some(_)) => (
                    "gyro bias varying from pose to pose (not drift, not g-sensitivity)".to_string(),
                    format!(
                        "; neither drift nor g-sensitivity beats a constant bias on the odd poses ({:.4} deg/s RMS)",
                        c.to_degrees()
                    ),
                ),
                _ => ("gyro bias varying from pose to pose".to_string(), String::new()),
            };
            causes.push((
                gratio,
                Cause {
                    name,
                    channels: "gx gy gz".to_string(),
                    evidence: format!(
                        "per-pose gyro means scatter by {:.4} deg/s RMS, {:.1} x the {:.4} deg/s white noise gives{detail}",
                        p.gyro_spread_rms_radps.to_degrees(),
                        gratio,
                        p.gyro_spread_noise_radps.to_degrees()
                    ),
                },
            ));
        }
        for t in &p.turns {
            if t.scale_factor.abs() > 0.005 {
                causes.push((
                    t.scale_factor.abs() * 100.0,
                    Cause {
                        name: "gyro scale factor".to_string(),
                        channels: CHANNELS[t.axis].to_string(),
                        evidence: format!(
                            "{}: the gyro integrates {:.1} deg ({:.1} deg raw) over a labelled full turn: scale \
                             factor {:+.4} (if the turn is exactly 360 deg)",
                            t.label,
                            t.angle_rad.to_degrees(),
                            t.raw_angle_rad.to_degrees(),
                            t.scale_factor
                        ),
                    },
                ));
            }
        }
    }
    for sw in &s.sway {
        if sw.correlation > 0.5 {
            causes.push((
                10.0 * sw.correlation,
                Cause {
                    name: "vehicle sway (real tilt motion)".to_string(),
                    channels: sw.pair.to_string(),
                    evidence: format!(
                        "high-passed 1-s means: correlation {:.3}, slope {:.2} m/s^2/rad (g = tilt), accel RMS {:.0} \
                         ug, tilt RMS {:.1} arcsec",
                        sw.correlation,
                        sw.slope_mps2_per_rad,
                        sw.accel_rms_mps2 / MICRO_G,
                        sw.tilt_rms_rad * crate::io::calibration_result::ARCSEC_PER_RAD
                    ),
                },
            ));
        }
    }
    for ch in &s.noise {
        if ch.ratio_at_long_tau < 1.0 / CORRELATED_RATIO {
            let (u, uname) = unit_of(ch.channel);
            let li = ch.data.tau_s.iter().rposition(|t| *t <= ch.long_tau_s * 1.0001).unwrap_or(0);
            causes.push((
                1.0 / ch.ratio_at_long_tau,
                Cause {
                    name: "sample-to-sample noise not white (averages faster: quantisation / vibration)".to_string(),
                    channels: ch.channel.to_string(),
                    evidence: format!(
                        "ADEV at tau {:.1} s: data {:.4} {uname}, white-noise SIMULATION {:.4} {uname} ({:.2} x): the \
                         per-sample scatter does not average like white noise",
                        ch.long_tau_s,
                        ch.data.adev.get(li).copied().unwrap_or(f64::NAN) / u,
                        ch.base_sim.adev.get(li).copied().unwrap_or(f64::NAN) / u,
                        ch.ratio_at_long_tau
                    ),
                },
            ));
        }
        if ch.ratio_at_long_tau > CORRELATED_RATIO {
            let (u, uname) = unit_of(ch.channel);
            let term = ch.extended.as_ref().map_or("correlated noise", |e| e.dominant_term);
            let name = match term {
                "white" | "quantization" => "correlated noise".to_string(),
                other => format!("correlated noise ({other})"),
            };
            let gain = ch.extended.as_ref().map_or(String::new(), |e| {
                format!(
                    "; held-out RMS log10(ADEV sim/data) {:.3} (base) -> {:.3} (extended)",
                    e.held_out_rms_log10_base, e.held_out_rms_log10_extended
                )
            });
            let li = ch.data.tau_s.iter().rposition(|t| *t <= ch.long_tau_s * 1.0001).unwrap_or(0);
            causes.push((
                ch.ratio_at_long_tau,
                Cause {
                    name,
                    channels: ch.channel.to_string(),
                    evidence: format!(
                        "ADEV at tau {:.1} s: data {:.4} {uname}, white-noise SIMULATION {:.4} {uname} ({:.1} x){gain}",
                        ch.long_tau_s,
                        ch.data.adev.get(li).copied().unwrap_or(f64::NAN) / u,
                        ch.base_sim.adev.get(li).copied().unwrap_or(f64::NAN) / u,
                        ch.ratio_at_long_tau
                    ),
                },
            ));
        }
    }
    causes.sort_by(|a, b| b.0.total_cmp(&a.0));
    causes.into_iter().map(|c| c.1).collect()
}

// ---------------------------------------------------------------------------------------------------------------
// Loading, report, JSON

/// Reads the data set from `data_dir` and runs its study (no files written).
pub fn study_dataset(dataset: Dataset, data_dir: &Path) -> Result<Study, InputError> {
    let file = |relative: &str| -> Result<PathBuf, InputError> {
        let path = data_dir.join(relative);
        if path.is_file() {
            Ok(path)
        } else {
            Err(InputError::file(&path.display().to_string(), format!("missing (the {} data set)", dataset.name())))
        }
    };
    match dataset {
        Dataset::Psins => {
            let path = file("psins-lasergyro/lasergyro.imu")?;
            eprintln!("study psins: reading {}", path.display());
            let rec = import_psins(&path, None)?.recording;
            Ok(study_single_pose(&rec, "psins", vec![path.display().to_string()], STUDY_SEED))
        }
        Dataset::Ferraris => {
            let csv = file("imucal-ferraris/example_ferraris_session.csv")?;
            let labels = file("imucal-ferraris/example_ferraris_session_list.json")?;
            eprintln!("study ferraris: reading {}", csv.display());
            let rec = import_imucal(&csv, &labels, None)?.recording;
            let label_text = std::fs::read_to_string(&labels).map_err(|e| InputError::io(&labels, e))?;
            let ranges = crate::io::import::parse_imucal_labels(&label_text, &labels.display().to_string())?;
            let rate = crate::io::import::IMUCAL_RATE_HZ;
            let mut turns = Vec::new();
            for (axis, label) in crate::io::import::FERRARIS_ROTATIONS.iter().enumerate() {
                if let Some(r) = ranges.iter().find(|r| r.label == *label) {
                    let rows: Vec<usize> = (0..rec.rows.len())
                        .filter(|&k| {
                            let s = (rec.rows[k].t_s * rate).round() as u64;
                            (r.start..r.end).contains(&s)
                        })
                        .collect();
                    if let (Some(first), Some(last)) = (rows.first(), rows.last()) {
                        // One sample past the end so that the last labelled sample's interval is integrated.
                        turns.push((label.to_string(), axis, *first..(*last + 2).min(rec.rows.len())));
                    }
                }
            }
            let g = sinscal::nav::earth::normal_gravity_mps2(
                (rec.header.latitude_deg as f32).to_radians(),
                rec.header.height_m as f32,
            ) as f64;
            study_multi_pose(
                &rec,
                PoseKind::Labelled,
                g,
                "ferraris",
                vec![csv.display().to_string(), labels.display().to_string()],
                STUDY_SEED,
                &turns,
            )
        }
        Dataset::Imutk => {
            let acc = file("imu-tk-xsens/xsens_acc.mat")?;
            let gyro = file("imu-tk-xsens/xsens_gyro.mat")?;
            eprintln!("study imutk: reading {} and {}", acc.display(), gyro.display());
            let rec = import_imutk(&acc, &gyro, None, &StaticDetection::default())?.recording;
            study_multi_pose(
                &rec,
                PoseKind::Unlabelled,
                IMUTK_GRAVITY_MPS2,
                "imutk",
                vec![acc.display().to_string(), gyro.display().to_string()],
                STUDY_SEED,
                &[],
            )
        }
    }
}

fn fmt3(v: [f64; 3], scale: f64, prec: usize) -> String {
    format!("[{:.p$}, {:.p$}, {:.p$}]", v[0] / scale, v[1] / scale, v[2] / scale, p = prec)
}

/// The human summary (Markdown; also printed to stdout). `figures` are the PNG file names to link.
pub fn summary_markdown(s: &Study, figures: &[String]) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "# sinscal study: {}\n", s.dataset);
    let _ = writeln!(o, "Measured data: {} ({} Hz).", s.sources.join(", "), s.rate_hz);
    let _ = writeln!(
        o,
        "Every SIMULATION below is seeded (seed {}) and uses the data's own sample times and poses; it is not \
         measured data.\n",
        s.seed
    );
    let _ = writeln!(o, "## 1. Base model\n");
    let _ = writeln!(
        o,
        "Each static pose: a constant mean per channel plus white noise. White-noise standard deviation per sample = \
         overlapping Allan deviation at one sample = RMS of first differences / sqrt 2, pooled over the static poses:"
    );
    for ch in &s.noise {
        let (u, name) = if ch.channel.starts_with('g') { (1f64.to_radians(), "deg/s") } else { (1.0, "m/s^2") };
        let _ = writeln!(o, "- {}: {:.4e} {name} per sample", ch.channel, ch.white_std / u);
    }
    if let Some(p) = &s.poses {
        let _ = writeln!(
            o,
            "\nPose means of the base model: accelerometer = g ({:.5} m/s^2) along the pose's up direction + one bias \
             (bias-only sensor, {}), gyro = one constant bias. Base accelerometer bias {} m/s^2.",
            p.gravity_mps2,
            if p.method.starts_with("labelled") { "labelled up axes" } else { "direction from the data, |f| = g" },
            fmt3(p.base_accel.bias_mps2, 1.0, 4)
        );
    }
    let _ = writeln!(o, "\n## 2.-3. Data against the base SIMULATION\n");
    let _ = writeln!(
        o,
        "Allan deviation ({}): ratio data / base SIMULATION at the longest tau with at least 9 clusters, and RMS over \
         tau of log10(ADEV SIMULATION / ADEV data):",
        if s.poses.is_some() { "longest static pose" } else { "whole record" }
    );
    let _ = writeln!(o, "\n| channel | tau [s] | data ADEV | base SIM ADEV | ratio | RMS log10 | quantisation step |");
    let _ = writeln!(o, "|---|---|---|---|---|---|---|");
    for ch in &s.noise {
        let (u, name) = unit_of(ch.channel);
        let li = ch.data.tau_s.iter().rposition(|t| *t <= ch.long_tau_s * 1.0001).unwrap_or(0);
        let q = ch.quantization_step.map_or("-".to_string(), |q| format!("{:.4} {name}", q / u));
        let _ = writeln!(
            o,
            "| {} | {:.2} | {:.4} {name} | {:.4} {name} | {:.2} | {:.3} | {q} |",
            ch.channel,
            ch.long_tau_s,
            ch.data.adev.get(li).copied().unwrap_or(f64::NAN) / u,
            ch.base_sim.adev.get(li).copied().unwrap_or(f64::NAN) / u,
            ch.ratio_at_long_tau,
            ch.rms_log10_base
        );
    }
    for sw in &s.sway {
        let _ = writeln!(
            o,
            "\nSway test {}: high-passed (61 s) 1-s means, correlation {:.3}, slope {:.2} m/s^2 per rad (a real tilt \
             gives g), accelerometer RMS {:.0} ug, tilt RMS {:.2} arcsec.",
            sw.pair,
            sw.correlation,
            sw.slope_mps2_per_rad,
            sw.accel_rms_mps2 / MICRO_G,
            sw.tilt_rms_rad * crate::io::calibration_result::ARCSEC_PER_RAD
        );
    }
    if let Some(p) = &s.poses {
        let _ = writeln!(
            o,
            "\nPer-pose |mean f - b| - g [m/s^2] (b = base bias): data, base SIMULATION, extended SIMULATION; white \
             noise std of the norm:"
        );
        let _ =
            writeln!(o, "\n| pose | samples | data | base SIM | extended SIM | noise std | extended-calibrated data |");
        let _ = writeln!(o, "|---|---|---|---|---|---|---|");
        for q in &p.poses {
            let _ = writeln!(
                o,
                "| {} | {} | {:+.4} | {:+.4} | {:+.4} | {:.1e} | {:+.4} |",
                q.name,
                q.samples,
                q.norm_minus_g_data_mps2,
                q.norm_minus_g_base_sim_mps2,
                q.norm_minus_g_extended_sim_mps2,
                q.norm_noise_std_mps2,
                q.norm_minus_g_extended_mps2
            );
        }
        let _ = writeln!(
            o,
            "\nRMS over poses: data {:.4} m/s^2 against {:.2e} m/s^2 of white noise ({:.0} x).",
            p.norm_rms_data_mps2,
            p.norm_rms_noise_mps2,
            p.norm_rms_data_mps2 / p.norm_rms_noise_mps2
        );
        let _ = writeln!(
            o,
            "Gyro per-pose means: RMS scatter {:.5} deg/s against {:.5} deg/s from white noise ({:.1} x).",
            p.gyro_spread_rms_radps.to_degrees(),
            p.gyro_spread_noise_radps.to_degrees(),
            p.gyro_spread_rms_radps / p.gyro_spread_noise_radps
        );
        for t in &p.turns {
            let _ = writeln!(
                o,
                "Turn {} ({:.2} s): gyro {} integrates {:.1} deg raw, {:.1} deg with the static bias removed.",
                t.label,
                t.duration_s,
                CHANNELS[t.axis],
                t.raw_angle_rad.to_degrees(),
                t.angle_rad.to_degrees()
            );
        }
    }
    let _ = writeln!(o, "\n## 4. Cause\n");
    if s.causes.is_empty() {
        let _ = writeln!(o, "None: the base model agrees with the data within the noise.");
    }
    for c in &s.causes {
        let _ = writeln!(o, "- **{}** ({}): {}", c.name, c.channels, c.evidence);
    }
    let _ = writeln!(o, "\n## 5. Extended model\n");
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            let t = &e.terms_all;
            let (gyro, (u, name)) = (ch.channel.starts_with('g'), unit_of(ch.channel));
            let _ = writeln!(
                o,
                "- {} IEEE 952 terms (whole record; SI): Q {:.3e} {}, N {:.3e} {}, B {:.3e} {} ({:.4} {name}), K {:.3e} \
                 {}, R {:.3e} {}; dominant at long tau: {}",
                ch.channel,
                t.quantization_q,
                if gyro { "rad" } else { "m/s" },
                t.random_walk_n,
                if gyro { "rad/sqrt(s)" } else { "m/s/sqrt(s)" },
                t.bias_instability_b,
                if gyro { "rad/s" } else { "m/s^2" },
                t.bias_instability_b / u,
                t.rate_random_walk_k,
                if gyro { "rad/s/sqrt(s)" } else { "m/s^2/sqrt(s)" },
                t.ramp_r,
                if gyro { "rad/s^2" } else { "m/s^3" },
                e.dominant_term
            );
            if let Some(x) = &e.extra_all {
                let _ = writeln!(o, "  plus {}", x.describe(if gyro { "rad/s" } else { "m/s^2" }));
            }
        }
    }
    if s.noise.iter().any(|c| c.extended.is_some()) {
        let _ = writeln!(
            o,
            "\nGenerator: quantisation as differenced white angle noise, white noise, bias instability as a sum of \
             Gauss-Markov processes (two per decade), rate random walk, ramp, and the band-limited term (Gauss-Markov \
             or sinusoid with random phase) where it lowers the weighted Allan residual by more than 20 %."
        );
    }
    if let Some(p) = &s.poses {
        let a = &p.extended_accel.matrix;
        let _ = writeln!(o, "Accelerometer, {}, fitted on all poses:", p.method);
        let _ = writeln!(o, "- bias {} m/s^2", fmt3(p.extended_accel.bias_mps2, 1.0, 4));
        let _ = writeln!(o, "- scale factors {} (dimensionless)", fmt3(p.extended_accel.scale_factors(), 1.0, 5));
        let _ = writeln!(
            o,
            "- A (f_meas = A f + b, dimensionless): [[{:.5}, {:+.5}, {:+.5}], [{:+.5}, {:.5}, {:+.5}], [{:+.5}, {:+.5}, \
             {:.5}]]",
            a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2]
        );
        if let Some(gs) = &p.gyro_g_sensitivity {
            let _ = writeln!(
                o,
                "- gyro g-sensitivity (fitted on all poses), (deg/s)/(m/s^2): [{}, {}, {}]",
                fmt3(gs[0], 1f64.to_radians(), 5),
                fmt3(gs[1], 1f64.to_radians(), 5),
                fmt3(gs[2], 1f64.to_radians(), 5)
            );
        }
        for t in &p.turns {
            let _ = writeln!(
                o,
                "- gyro scale factor {} from {}: {:+.4} (dimensionless)",
                CHANNELS[t.axis], t.label, t.scale_factor
            );
        }
    }
    let _ = writeln!(o, "\n## 6. Gain on data not used for the fit\n");
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            let _ = writeln!(
                o,
                "- {}: second half, RMS log10(ADEV SIMULATION / ADEV data): base {:.3}, extended {:.3} (dimensionless)",
                ch.channel, e.held_out_rms_log10_base, e.held_out_rms_log10_extended
            );
        }
    }
    if let Some(p) = &s.poses {
        let _ = writeln!(
            o,
            "- accelerometer, {}: RMS(|f calibrated| - g) base {:.4} m/s^2, extended {:.4} m/s^2 ({:.1} x smaller)",
            p.held_out_rule,
            p.held_out_norm_rms_base_mps2,
            p.held_out_norm_rms_extended_mps2,
            p.held_out_norm_rms_base_mps2 / p.held_out_norm_rms_extended_mps2
        );
        for (name, v) in &p.gyro_models_held_out_radps {
            let _ = writeln!(o, "- gyro per-pose means, odd poses, {name}: RMS residual {:.5} deg/s", v.to_degrees());
        }
        if !p.turns.is_empty() {
            let _ = writeln!(
                o,
                "- gyro scale factors: one turn per axis, so no held-out turn exists to test them (not measured)."
            );
        }
        if let Some(f) = &p.factory {
            let _ = writeln!(o, "\n## 7. imu_tk: fitted against the factory calibration\n");
            let _ = writeln!(
                o,
                "Both in the lower-triangular gauge K = L Q (counts = K f + offset; the rotation Q is not observable \
                 from |f| = g), g = {} m/s^2. The importer's nominal gains [415, 413, 415] counts/(m/s^2) are undone: \
                 counts = diag(nominal) A f + 32768 + nominal b.",
                p.gravity_mps2
            );
            let _ = writeln!(o, "\n| quantity | fitted | factory (diag(gain) M) | factory (diag(gain) M^-1) |");
            let _ = writeln!(o, "|---|---|---|---|");
            let _ = writeln!(
                o,
                "| gain x, y, z [counts/(m/s^2)] | {} | {} | |",
                fmt3(f.fitted_gain_counts_per_mps2, 1.0, 2),
                fmt3(f.factory_gain_counts_per_mps2, 1.0, 2)
            );
            let _ = writeln!(
                o,
                "| misalignment L10/L11, L20/L22, L21/L22 | {} | {} | {} |",
                fmt3(f.fitted_misalignment, 1.0, 4),
                fmt3(f.factory_misalignment, 1.0, 4),
                fmt3(f.factory_misalignment_inverse, 1.0, 4)
            );
            let _ = writeln!(o, "| offset [counts] | {} | not given | |", fmt3(f.fitted_offset_counts, 1.0, 1));
        }
    }
    if !figures.is_empty() {
        let _ = writeln!(o, "\n## Figures\n");
        for f in figures {
            let _ = writeln!(o, "- [{f}]({f})");
        }
    }
    o
}

fn curve_json(c: &Curve, unit: &str) -> Value {
    let mut m = Map::new();
    m.insert("tau_s".into(), json!(c.tau_s));
    m.insert(format!("adev_{unit}"), json!(c.adev));
    Value::Object(m)
}

fn terms_json(t: &NoiseTerms, gyro: bool) -> Value {
    if gyro {
        json!({"quantization_q_rad": t.quantization_q, "random_walk_n_rad_per_sqrt_s": t.random_walk_n,
               "bias_instability_b_radps": t.bias_instability_b, "rate_random_walk_k_radps_per_sqrt_s": t.rate_random_walk_k,
               "ramp_r_radps2": t.ramp_r})
    } else {
        json!({"quantization_q_mps": t.quantization_q, "random_walk_n_mps_per_sqrt_s": t.random_walk_n,
               "bias_instability_b_mps2": t.bias_instability_b, "rate_random_walk_k_mps2_per_sqrt_s": t.rate_random_walk_k,
               "ramp_r_mps3": t.ramp_r})
    }
}

/// The machine-readable study (schema [`SCHEMA`], SI units, unit-named keys).
pub fn study_json(s: &Study, figures: &[String]) -> Value {
    let unit = |c: &str| if c.starts_with('g') { "radps" } else { "mps2" };
    let mut base = Map::new();
    base.insert("model".into(), json!("per static pose: constant mean per channel + white noise (std = ADEV at one sample = RMS first difference / sqrt 2)"));
    base.insert("simulation".into(), json!(format!("SIMULATION, seed {}", s.seed)));
    for ch in &s.noise {
        base.insert(format!("{}_white_std_{}", ch.channel, unit(ch.channel)), json!(ch.white_std));
    }
    if let Some(p) = &s.poses {
        base.insert("gravity_mps2".into(), json!(p.gravity_mps2));
        base.insert("accel_bias_mps2".into(), json!(p.base_accel.bias_mps2));
    }
    let mut disagreement = Vec::new();
    for ch in &s.noise {
        let u = unit(ch.channel);
        let mut m = Map::new();
        m.insert("what".into(), json!("allan_deviation"));
        m.insert("channel".into(), json!(ch.channel));
        m.insert("long_tau_s".into(), json!(ch.long_tau_s));
        m.insert("ratio_data_over_base_sim_at_long_tau".into(), json!(ch.ratio_at_long_tau));
        m.insert("rms_log10_base_sim_over_data".into(), json!(ch.rms_log10_base));
        m.insert("data".into(), curve_json(&ch.data, u));
        m.insert("base_sim".into(), curve_json(&ch.base_sim, u));
        if let Some(q) = ch.quantization_step {
            m.insert(format!("quantization_step_{u}"), json!(q));
        }
        disagreement.push(Value::Object(m));
    }
    for sw in &s.sway {
        disagreement.push(json!({"what": "sway", "pair": sw.pair, "correlation": sw.correlation,
            "slope_mps2_per_rad": sw.slope_mps2_per_rad, "accel_rms_mps2": sw.accel_rms_mps2, "tilt_rms_rad": sw.tilt_rms_rad}));
    }
    let mut extended = Map::new();
    let mut gain = Map::new();
    for ch in &s.noise {
        if let Some(e) = &ch.extended {
            let g = ch.channel.starts_with('g');
            extended.insert(format!("{}_noise_terms", ch.channel), terms_json(&e.terms_all, g));
            extended.insert(format!("{}_noise_terms_first_half", ch.channel), terms_json(&e.terms_first_half, g));
            extended.insert(format!("{}_dominant_term", ch.channel), json!(e.dominant_term));
            let u = if g { "radps" } else { "mps2" };
            for (key, x) in [("", e.extra_all), ("_first_half", e.extra_first_half)] {
                let v = match x {
                    Some(ExtraTerm::GaussMarkov { sigma, tc_s }) => {
                        json!({"gauss_markov": {format!("sigma_{u}"): sigma, "tc_s": tc_s}})
                    }
                    Some(ExtraTerm::Sine { amplitude, frequency_hz }) => {
                        json!({"sine": {format!("amplitude_{u}"): amplitude, "frequency_hz": frequency_hz}})
                    }
                    None => Value::Null,
                };
                extended.insert(format!("{}_extra_term{key}", ch.channel), v);
            }
            gain.insert(
                format!("{}_held_out_rms_log10_adev", ch.channel),
                json!({"rule": "fit on the first half, evaluate on the second", "base": e.held_out_rms_log10_base,
                       "extended": e.held_out_rms_log10_extended}),
            );
        }
    }
    if let Some(p) = &s.poses {
        disagreement.push(json!({"what": "pose_norm_minus_g", "method": p.method,
            "poses": p.poses.iter().map(|q| json!({"pos": q.pos, "name": q.name, "samples": q.samples,
                "mean_force_mps2": q.mean_force_mps2, "mean_rate_radps": q.mean_rate_radps,
                "data_mps2": q.norm_minus_g_data_mps2, "base_sim_mps2": q.norm_minus_g_base_sim_mps2,
                "extended_sim_mps2": q.norm_minus_g_extended_sim_mps2, "noise_std_mps2": q.norm_noise_std_mps2,
                "extended_calibrated_mps2": q.norm_minus_g_extended_mps2})).collect::<Vec<_>>(),
            "rms_data_mps2": p.norm_rms_data_mps2, "rms_white_noise_mps2": p.norm_rms_noise_mps2}));
        disagreement.push(json!({"what": "gyro_pose_means", "rms_scatter_radps": p.gyro_spread_rms_radps,
            "rms_white_noise_radps": p.gyro_spread_noise_radps}));
        for t in &p.turns {
            disagreement
                .push(json!({"what": "turn", "label": t.label, "axis": CHANNELS[t.axis], "duration_s": t.duration_s,
                "raw_angle_rad": t.raw_angle_rad, "bias_removed_angle_rad": t.angle_rad}));
        }
        extended.insert(
            "accel".into(),
            json!({"method": p.method, "bias_mps2": p.extended_accel.bias_mps2,
            "scale_factors": p.extended_accel.scale_factors(), "matrix_a": p.extended_accel.matrix}),
        );
        if let Some(gs) = &p.gyro_g_sensitivity {
            extended.insert("gyro_g_sensitivity_radps_per_mps2".into(), json!(gs));
        }
        if !p.turns.is_empty() {
            extended.insert(
                "gyro_scale_factors".into(),
                Value::Object(p.turns.iter().map(|t| (CHANNELS[t.axis].to_string(), json!(t.scale_factor))).collect()),
            );
        }
        gain.insert(
            "accel_held_out_norm_rms_mps2".into(),
            json!({"rule": p.held_out_rule,
            "base": p.held_out_norm_rms_base_mps2, "extended": p.held_out_norm_rms_extended_mps2}),
        );
        if !p.gyro_models_held_out_radps.is_empty() {
            gain.insert(
                "gyro_pose_means_held_out_rms_radps".into(),
                Value::Object(p.gyro_models_held_out_radps.iter().map(|(n, v)| (n.to_string(), json!(v))).collect()),
            );
        }
        if let Some(f) = &p.factory {
            extended.insert(
                "factory_comparison".into(),
                json!({
                "gauge": "lower-triangular L of K = L Q, counts = K f + offset",
                "gravity_mps2": p.gravity_mps2,
                "fitted_gain_counts_per_mps2": f.fitted_gain_counts_per_mps2,
                "factory_gain_counts_per_mps2": f.factory_gain_counts_per_mps2,
                "fitted_misalignment": f.fitted_misalignment,
                "factory_misalignment": f.factory_misalignment,
                "factory_misalignment_inverse_convention": f.factory_misalignment_inverse,
                "fitted_offset_counts": f.fitted_offset_counts}),
            );
        }
    }
    json!({
        "schema": SCHEMA,
        "dataset": s.dataset,
        "sources": s.sources,
        "seed": s.seed,
        "rate_hz": s.rate_hz,
        "base": Value::Object(base),
        "disagreement": disagreement,
        "cause": s.causes.iter().map(|c| json!({"name": c.name, "channels": c.channels, "evidence": c.evidence})).collect::<Vec<_>>(),
        "extended": Value::Object(extended),
        "gain": Value::Object(gain),
        "figures": figures,
    })
}

/// Runs `sinscal study`: reads the data set, writes `summary.md` and the figures into `report_dir` and, with
/// `json`, the JSON ('-' = stdout, then the summary is not printed). Returns the study and the summary text.
pub fn run(
    dataset: Dataset,
    data_dir: Option<&Path>,
    report_dir: &Path,
    json_path: Option<&Path>,
) -> anyhow::Result<Study> {
    let data_dir: PathBuf = match data_dir {
        Some(d) => d.to_path_buf(),
        None => std::env::var_os("SINSCAL_DATA").map(PathBuf::from).ok_or_else(|| {
            InputError::file("sinscal study", "no data directory: give --data DIR or set SINSCAL_DATA")
        })?,
    };
    if !data_dir.is_dir() {
        return Err(InputError::file(&data_dir.display().to_string(), "not a directory (the data directory)").into());
    }
    let study = study_dataset(dataset, &data_dir)?;
    std::fs::create_dir_all(report_dir).map_err(|e| anyhow::anyhow!("cannot create {}: {e}", report_dir.display()))?;
    eprintln!("study {}: figures", study.dataset);
    let figures = write_figures(&study, report_dir)?;
    let text = summary_markdown(&study, &figures);
    let md = report_dir.join("summary.md");
    std::fs::write(&md, &text).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", md.display()))?;
    let to_stdout = json_path == Some(Path::new("-"));
    if !to_stdout {
        print!("{text}");
        println!("\nreport: {}", md.display());
    }
    if let Some(path) = json_path {
        let mut out = serde_json::to_string_pretty(&study_json(&study, &figures))?;
        out.push('\n');
        if to_stdout {
            print!("{out}");
        } else {
            std::fs::write(path, out).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        }
    }
    Ok(study)
}

// ---------------------------------------------------------------------------------------------------------------
// Figures

use plotters::prelude::*;

type Series = (String, RGBColor, Vec<(f64, f64)>);

fn plot_err(path: &Path, e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("plot {}: {e}", path.display())
}

/// Log-log panels (2 x 3).
fn loglog_panels(path: &Path, title: &str, panels: &[(String, String, Vec<Series>)]) -> anyhow::Result<()> {
    let root = BitMapBackend::new(path, (1500, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let root = root.titled(title, ("sans-serif", 24)).map_err(|e| plot_err(path, e))?;
    let areas = root.split_evenly((2, 3));
    for (area, (name, ylabel, series)) in areas.iter().zip(panels) {
        let pts = series.iter().flat_map(|s| s.2.iter()).filter(|p| p.0 > 0.0 && p.1 > 0.0);
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in pts {
            x0 = x0.min(p.0);
            x1 = x1.max(p.0);
            y0 = y0.min(p.1);
            y1 = y1.max(p.1);
        }
        if !(x0 < x1 && y0 < y1) {
            continue;
        }
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(70)
            .build_cartesian_2d((x0 / 1.2..x1 * 1.2).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())
            .map_err(|e| plot_err(path, e))?;
        chart.configure_mesh().x_desc("tau [s]").y_desc(ylabel.as_str()).draw().map_err(|e| plot_err(path, e))?;
        for (label, color, data) in series {
            let c = *color;
            chart
                .draw_series(LineSeries::new(data.iter().copied().filter(|p| p.1 > 0.0), c.stroke_width(2)))
                .map_err(|e| plot_err(path, e))?
                .label(label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3)));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Points per pose index (linear axes), one panel.
fn pose_plot(path: &Path, title: &str, ylabel: &str, series: &[Series]) -> anyhow::Result<()> {
    let root = BitMapBackend::new(path, (1200, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let all: Vec<(f64, f64)> = series.iter().flat_map(|s| s.2.iter().copied()).collect();
    let xmax = all.iter().map(|p| p.0).fold(1.0, f64::max) + 1.0;
    let ymax = all.iter().map(|p| p.1.abs()).fold(1e-9, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0f64..xmax, -ymax..ymax)
        .map_err(|e| plot_err(path, e))?;
    chart.configure_mesh().x_desc("pose (order in the record)").y_desc(ylabel).draw().map_err(|e| plot_err(path, e))?;
    for (label, color, data) in series {
        let c = *color;
        chart
            .draw_series(data.iter().map(|p| Circle::new(*p, 5, c.filled())))
            .map_err(|e| plot_err(path, e))?
            .label(label.clone())
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
        chart.draw_series(LineSeries::new(data.iter().copied(), c.mix(0.4))).map_err(|e| plot_err(path, e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

const BLACKISH: RGBColor = RGBColor(20, 20, 20);
const BLUE_: RGBColor = RGBColor(30, 80, 210);
const RED_: RGBColor = RGBColor(210, 40, 30);
const GREEN_: RGBColor = RGBColor(30, 150, 60);
const GREY_: RGBColor = RGBColor(140, 140, 140);

/// Writes the study's figures into `dir`; returns their file names.
pub fn write_figures(s: &Study, dir: &Path) -> anyhow::Result<Vec<String>> {
    let mut names = Vec::new();
    let scaled =
        |c: &Curve, u: f64| -> Vec<(f64, f64)> { c.tau_s.iter().zip(&c.adev).map(|(t, a)| (*t, a / u)).collect() };
    let panels: Vec<(String, String, Vec<Series>)> = s
        .noise
        .iter()
        .map(|ch| {
            let (u, name) = unit_of(ch.channel);
            let mut series = vec![
                ("data".to_string(), BLACKISH, scaled(&ch.data, u)),
                ("base SIMULATION (white)".to_string(), BLUE_, scaled(&ch.base_sim, u)),
            ];
            if let Some(e) = &ch.extended {
                series.push(("data, 2nd half".to_string(), GREY_, scaled(&e.held_out_data, u)));
                series.push(("extended SIMULATION, 2nd half".to_string(), RED_, scaled(&e.held_out_extended_sim, u)));
            }
            (
                format!("{}: ratio {:.1} at {:.0} s", ch.channel, ch.ratio_at_long_tau, ch.long_tau_s),
                format!("ADEV [{name}]"),
                series,
            )
        })
        .collect();
    let what = if s.poses.is_some() { "longest static pose" } else { "whole record" };
    loglog_panels(
        &dir.join("allan.png"),
        &format!("{}: overlapping Allan deviation, data vs SIMULATION ({what})", s.dataset),
        &panels,
    )?;
    names.push("allan.png".to_string());
    if let Some(p) = &s.poses {
        let idx = |f: &dyn Fn(&Pose) -> f64| -> Vec<(f64, f64)> {
            p.poses.iter().enumerate().map(|(k, q)| (k as f64 + 1.0, f(q))).collect()
        };
        pose_plot(
            &dir.join("pose_norm.png"),
            &format!("{}: |mean f - b| - g per pose (b: base bias)", s.dataset),
            "|f| - g [m/s^2]",
            &[
                ("data".to_string(), BLACKISH, idx(&|q| q.norm_minus_g_data_mps2)),
                ("base SIMULATION".to_string(), BLUE_, idx(&|q| q.norm_minus_g_base_sim_mps2)),
                ("extended SIMULATION".to_string(), RED_, idx(&|q| q.norm_minus_g_extended_sim_mps2)),
                ("data, extended calibration".to_string(), GREEN_, idx(&|q| q.norm_minus_g_extended_mps2)),
            ],
        )?;
        names.push("pose_norm.png".to_string());
        let n = p.poses.len() as f64;
        let colors = [RED_, GREEN_, BLUE_];
        let series: Vec<Series> = (0..3)
            .map(|i| {
                let m = p.poses.iter().map(|q| q.mean_rate_radps[i]).sum::<f64>() / n;
                (format!("{} data - mean", CHANNELS[i]), colors[i], idx(&|q| (q.mean_rate_radps[i] - m).to_degrees()))
            })
            .collect();
        pose_plot(
            &dir.join("gyro_pose_means.png"),
            &format!(
                "{}: gyro pose means less their mean (white noise gives {:.4} deg/s RMS)",
                s.dataset,
                p.gyro_spread_noise_radps.to_degrees()
            ),
            "deg/s",
            &series,
        )?;
        names.push("gyro_pose_means.png".to_string());
    }
    Ok(names)
}
