//! The two-state HMM/KF prefilter of docs/method.md#step-1-prefilter, one instance per channel.
//!
//! State `X_k = [x_k, x_{k-1}]`, measurement `Z_k = [z_k, z_{k-1}]` (the raw channel now and one sample ago):
//!     X_{k+1} = F X_k + xi,   F = [[a, 1-a], [1, 0]],   Q = diag(q, q)
//!     Z_k     = H X_k + nu,   H = I,                    R = diag(r, r)
//! Every row of F and H is non-negative and sums to one, so a constant is a fixed point and the filter
//! passes DC unchanged. The Kalman gain is iterated to its steady value `K_off` (discrete Riccati
//! equation) once, at construction; each sample then costs one fixed-gain update
//!     X_pred = F X_{k-1},   X_k = X_pred + K_off (Z_k - H X_pred)
//! (with `Z_k`, not the printed paper's `X_k`, in the innovation). Call rate: once per sample of the channel.

use crate::math::accumulate::KahanSum;
use crate::nav::earth::STANDARD_GRAVITY_MPS2;

/// One degree per hour in rad/s.
pub const DEG_PER_HOUR_IN_RADPS: f32 = core::f32::consts::PI / 180.0 / 3600.0;

/// Settings of one channel's prefilter. `q` and `r` are per-sample variances in the channel's squared
/// unit ((rad/s)^2 for gyros, (m/s^2)^2 for accelerometers); only their ratio shapes the gain.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PrefilterSettings {
    /// Transition coefficient `a` of `F = [[a, 1-a], [1, 0]]`, in [0, 1]; 1 is the random-walk model.
    pub a: f32,
    /// Process noise variance per sample (both diagonal entries of Q), channel unit squared.
    pub q: f32,
    /// Measurement noise variance per sample (both diagonal entries of R), channel unit squared.
    pub r: f32,
}

impl PrefilterSettings {
    /// The paper's gyro setting: Q = (0.005 deg/h)^2, R = (0.1 deg/h)^2 per sample, with `a` = 1.
    pub fn paper_gyro() -> PrefilterSettings {
        let (q, r) = (0.005 * DEG_PER_HOUR_IN_RADPS, 0.1 * DEG_PER_HOUR_IN_RADPS);
        PrefilterSettings { a: 1.0, q: q * q, r: r * r }
    }

    /// The paper's accelerometer setting: Q = (5e-4 g)^2, R = (100e-4 g)^2 per sample, with `a` = 1
    /// (g = standard gravity 9.80665 m/s^2 as the unit).
    pub fn paper_accel() -> PrefilterSettings {
        let (q, r) = (5e-4 * STANDARD_GRAVITY_MPS2, 100e-4 * STANDARD_GRAVITY_MPS2);
        PrefilterSettings { a: 1.0, q: q * q, r: r * r }
    }

    /// The same noise setting with another transition coefficient.
    pub fn with_a(self, a: f32) -> PrefilterSettings {
        PrefilterSettings { a, ..self }
    }
}

/// Why a prefilter cannot be built.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum PrefilterError {
    /// `a` outside [0, 1] (F would not be row-stochastic with non-negative entries) or not finite.
    BadCoefficient,
    /// `q` or `r` not positive and finite.
    BadNoise,
    /// The Riccati iteration did not settle within its iteration limit.
    NotSettled,
}

impl core::fmt::Display for PrefilterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            PrefilterError::BadCoefficient => "prefilter coefficient a must be in [0, 1]",
            PrefilterError::BadNoise => "prefilter noise variances q and r must be positive and finite",
            PrefilterError::NotSettled => "prefilter Kalman gain did not settle",
        })
    }
}

impl core::error::Error for PrefilterError {}

/// A 2x2 matrix, row-major.
pub type Mat2 = [[f32; 2]; 2];

/// The settled gain of the Riccati iteration and how many iterations it took.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SteadyGain {
    /// `K_off`, dimensionless (row-major).
    pub gain: Mat2,
    /// Doubling steps until the solution stopped changing (step k covers 2^k samples of the recursion).
    pub iterations: u32,
}

/// Largest change of a gain entry that one ordinary Riccati step may still make at the returned
/// solution (a check that the doubling iteration converged to the fixed point).
pub const GAIN_TOLERANCE: f32 = 1e-6;
/// Iteration limit of the doubling recursion (it converges quadratically: about 2 log2(1/(1-rho)) steps).
pub const MAX_RICCATI_ITERATIONS: u32 = 64;

fn mat2_mul(a: &Mat2, b: &Mat2) -> Mat2 {
    [
        [a[0][0] * b[0][0] + a[0][1] * b[1][0], a[0][0] * b[0][1] + a[0][1] * b[1][1]],
        [a[1][0] * b[0][0] + a[1][1] * b[1][0], a[1][0] * b[0][1] + a[1][1] * b[1][1]],
    ]
}

fn mat2_add(a: &Mat2, b: &Mat2) -> Mat2 {
    [[a[0][0] + b[0][0], a[0][1] + b[0][1]], [a[1][0] + b[1][0], a[1][1] + b[1][1]]]
}

fn mat2_transpose(a: &Mat2) -> Mat2 {
    [[a[0][0], a[1][0]], [a[0][1], a[1][1]]]
}

fn mat2_symmetrise(a: &Mat2) -> Mat2 {
    let off = 0.5 * (a[0][1] + a[1][0]);
    [[a[0][0], off], [off, a[1][1]]]
}

fn mat2_inverse(a: &Mat2) -> Option<Mat2> {
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some([[a[1][1] / det, -a[0][1] / det], [-a[1][0] / det, a[0][0] / det]])
}

const I2: Mat2 = [[1.0, 0.0], [0.0, 1.0]];

/// The gain `K = P_pred (P_pred + R)^-1` for a predicted covariance in units of `r` (R = I).
fn gain_from_predicted(p_pred: &Mat2) -> Option<Mat2> {
    Some(mat2_mul(p_pred, &mat2_inverse(&mat2_add(p_pred, &I2))?))
}

/// Solves the filter Riccati equation for the steady gain `K_off`.
///
/// In units of `r` (R = I, Q = (q/r) I, H = I) the predicted covariance is the fixed point of
///     P = F P F^T - F P (P + I)^-1 P F^T + Q
/// and `K_off = P (P + I)^-1`. The plain recursion contracts at about `(1 - K)^2` per step, slowly for the
/// paper's gyro setting (K about 0.035), and in f32 its rounding accumulates over the hundreds of steps to
/// about 1e-5 of the gain. The structure-preserving doubling algorithm (Chu, Fan, Lin, Wang, "Structure-
/// preserving algorithms for periodic discrete-time algebraic Riccati equations", Int. J. Control 77,
/// 2004) runs the same recursion in steps of 2^k samples, with the dual data A = F^T, G = H^T R^-1 H, H = Q:
///     W = I + G_k H_k,  A_{k+1} = A_k W^-1 A_k,  G_{k+1} = G_k + A_k W^-1 G_k A_k^T,
///     H_{k+1} = H_k + A_k^T H_k W^-1 A_k,      H_k -> P
/// and converges quadratically. The result is checked with one ordinary Riccati step.
pub fn steady_gain(settings: &PrefilterSettings) -> Result<SteadyGain, PrefilterError> {
    let PrefilterSettings { a, q, r } = *settings;
    if !(0.0..=1.0).contains(&a) {
        return Err(PrefilterError::BadCoefficient);
    }
    if !(q > 0.0 && r > 0.0 && q.is_finite() && r.is_finite()) {
        return Err(PrefilterError::BadNoise);
    }
    let q_rel = q / r;
    let f: Mat2 = [[a, 1.0 - a], [1.0, 0.0]];
    let mut big_a = mat2_transpose(&f);
    let mut big_g = I2;
    let mut big_h: Mat2 = [[q_rel, 0.0], [0.0, q_rel]];
    for iteration in 1..=MAX_RICCATI_ITERATIONS {
        let w_inv = mat2_inverse(&mat2_add(&I2, &mat2_mul(&big_g, &big_h))).ok_or(PrefilterError::NotSettled)?;
        let a_w = mat2_mul(&big_a, &w_inv);
        let next_a = mat2_mul(&a_w, &big_a);
        let next_g = mat2_symmetrise(&mat2_add(&big_g, &mat2_mul(&mat2_mul(&a_w, &big_g), &mat2_transpose(&big_a))));
        let next_h = mat2_symmetrise(&mat2_add(
            &big_h,
            &mat2_mul(&mat2_mul(&mat2_transpose(&big_a), &big_h), &mat2_mul(&w_inv, &big_a)),
        ));
        let change = (0..4).map(|m| (next_h[m / 2][m % 2] - big_h[m / 2][m % 2]).abs()).fold(0.0f32, f32::max);
        let size = (0..4).map(|m| next_h[m / 2][m % 2].abs()).fold(0.0f32, f32::max);
        big_a = next_a;
        big_g = next_g;
        big_h = next_h;
        if !size.is_finite() {
            return Err(PrefilterError::NotSettled);
        }
        if change <= 4.0 * f32::EPSILON * size {
            let gain = gain_from_predicted(&big_h).ok_or(PrefilterError::NotSettled)?;
            // One ordinary Riccati step from the solution must give the same gain.
            let p_post = gain; // for R = I the a-posteriori covariance equals the gain
            let mut p_pred = mat2_mul(&mat2_mul(&f, &p_post), &mat2_transpose(&f));
            p_pred[0][0] += q_rel;
            p_pred[1][1] += q_rel;
            let check = gain_from_predicted(&mat2_symmetrise(&p_pred)).ok_or(PrefilterError::NotSettled)?;
            let step = (0..4).map(|m| (check[m / 2][m % 2] - gain[m / 2][m % 2]).abs()).fold(0.0f32, f32::max);
            if step > GAIN_TOLERANCE {
                return Err(PrefilterError::NotSettled);
            }
            return Ok(SteadyGain { gain, iterations: iteration });
        }
    }
    Err(PrefilterError::NotSettled)
}

/// Longest impulse response [`HmmKf::impulse_response_sums`] follows (it stops once the state is below 1e-9).
pub const MAX_IMPULSE_SAMPLES: u32 = 1_000_000;

/// The constants of a settled filter: `a` and the gain `K_off`. Shared by the channels of one sensor, so
/// that a filter bank keeps them in registers and only the per-channel state in memory.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedGain {
    /// The HMM coefficient `a` of `F = [[a, 1-a], [1, 0]]`.
    pub a: f32,
    /// The settled gain `K_off`.
    pub gain: Mat2,
}

impl FixedGain {
    /// One step of the fixed-gain recursion on a channel's state `[x_k, x_{k-1}]` and previous raw sample
    /// `z_{k-1}`; returns the new `x_k`. `a x0 + (1-a) x1` is written `x1 + a (x0 - x1)` so that a
    /// constant state predicts exactly itself in floating point (zero innovation, bit-exact DC
    /// pass-through). The one definition of the recursion: [`HmmKf`] and the dwell collector's bank both
    /// call it.
    #[inline(always)]
    pub fn step(&self, state: &mut [f32; 2], previous_raw: &mut f32, raw: f32) -> f32 {
        let [x0, x1] = *state;
        let pred = [x1 + self.a * (x0 - x1), x0];
        let innov = [raw - pred[0], *previous_raw - pred[1]];
        let k = &self.gain;
        let x = pred[0] + k[0][0] * innov[0] + k[0][1] * innov[1];
        *state = [x, pred[1] + k[1][0] * innov[0] + k[1][1] * innov[1]];
        *previous_raw = raw;
        x
    }
}

/// One channel's fixed-gain HMM/KF filter.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HmmKf {
    constants: FixedGain,
    /// `[x_k, x_{k-1}]` in the channel's unit.
    state: [f32; 2],
    /// The previous raw sample `z_{k-1}`.
    previous_raw: f32,
    started: bool,
}

impl HmmKf {
    /// A filter with the settled gain of `settings`. Not started: the first sample initialises the
    /// state to `[z_0, z_0]`.
    pub fn new(settings: &PrefilterSettings) -> Result<HmmKf, PrefilterError> {
        let SteadyGain { gain, .. } = steady_gain(settings)?;
        Ok(HmmKf::with_gain(settings.a, gain))
    }

    /// A filter with a given gain (for example one computed once and shared by three channels).
    pub fn with_gain(a: f32, gain: Mat2) -> HmmKf {
        HmmKf { constants: FixedGain { a, gain }, state: [0.0; 2], previous_raw: 0.0, started: false }
    }

    /// The gain `K_off` in use.
    pub fn gain(&self) -> Mat2 {
        self.constants.gain
    }

    /// The filter's constants (`a` and `K_off`).
    pub fn fixed_gain(&self) -> FixedGain {
        self.constants
    }

    /// Forgets the state; the next sample starts the filter again.
    pub fn reset(&mut self) {
        self.started = false;
    }

    /// The filtered value `x_k` (0 before the first sample).
    pub fn value(&self) -> f32 {
        self.state[0]
    }

    /// Feeds the raw sample `z_k` and returns the filtered value `x_k`.
    #[inline]
    pub fn update(&mut self, raw: f32) -> f32 {
        if !self.started {
            self.state = [raw, raw];
            self.previous_raw = raw;
            self.started = true;
            return raw;
        }
        self.step(raw)
    }

    /// The fixed-gain recursion ([`FixedGain::step`]); returns `x_k`.
    #[inline(always)]
    fn step(&mut self, raw: f32) -> f32 {
        self.constants.step(&mut self.state, &mut self.previous_raw, raw)
    }

    /// Response of the settled filter to raw white noise: returns `(sum h_k, sum h_k^2)` of its impulse
    /// response `h` (output `x` per unit raw sample, which enters twice: as `z_k` and one step later as
    /// `z_{k-1}`). The first is the DC gain (1 for a row-stochastic F); the second is the ratio of the
    /// output variance to the raw per-sample variance, used for the standard error of the settled output.
    pub fn impulse_response_sums(&self) -> (f32, f32) {
        // `step` runs the recursion whether or not the filter was started: state and previous raw are zero.
        let mut probe = HmmKf::with_gain(self.constants.a, self.constants.gain);
        let mut sum = KahanSum::new();
        let mut sum_sq = KahanSum::new();
        let mut raw = 1.0;
        for k in 0..MAX_IMPULSE_SAMPLES {
            probe.step(raw);
            raw = 0.0;
            let h = probe.state[0];
            sum.add(h);
            sum_sq.add(h * h);
            if k > 8 && probe.state[0].abs() < 1e-9 && probe.state[1].abs() < 1e-9 {
                break;
            }
        }
        (sum.value(), sum_sq.value())
    }

    /// What the filter's start adds to the mean of its outputs over a dwell, per unit raw white-noise
    /// variance and times `N^2`: returns `w0^2 + sum d_i^2`.
    ///
    /// The filter starts at the dwell's first sample (state `[z_0, z_0]`), so the sum of its `N` outputs
    /// weighs `z_0` by `1 + w0` (the start state's response summed), every later sample by the cumulative
    /// impulse response `H(i)` up to the end of the dwell (`i` samples later), that is by `1 - d_i` with
    /// `d_i = 1 - H(i)`; since the DC gain is 1, `sum d_i = w0`. The mean of the filtered dwell is then the
    /// raw mean plus `(w0 z_0 - sum_i d_i z_{N-1-i}) / N`, whose variance for white raw noise of variance
    /// `sigma^2` is `sigma^2 (w0^2 + sum d_i^2) / N^2` (for `N` longer than the response). For the paper's
    /// setting `w0` is 14.1 and the result 207: a 6-s dwell mean at 100 Hz has 1.35 times the variance
    /// of the raw mean, a 60-s one 1.03 times.
    pub fn start_transient_weight(&self) -> f32 {
        // The start state's response: z_0 = 1 sets the state and the previous raw sample to 1, then zeros.
        let mut start = HmmKf::with_gain(self.constants.a, self.constants.gain);
        start.update(1.0);
        let mut weight = KahanSum::new();
        for k in 0..MAX_IMPULSE_SAMPLES {
            let y = start.update(0.0);
            weight.add(y);
            if k > 8 && start.state[0].abs() < 1e-9 && start.state[1].abs() < 1e-9 {
                break;
            }
        }
        // The deficit of the cumulative impulse response of the settled filter.
        let mut probe = HmmKf::with_gain(self.constants.a, self.constants.gain);
        let mut cumulative = KahanSum::new();
        let mut deficit_sq = KahanSum::new();
        let mut raw = 1.0;
        for k in 0..MAX_IMPULSE_SAMPLES {
            probe.step(raw);
            raw = 0.0;
            cumulative.add(probe.state[0]);
            let d = 1.0 - cumulative.value();
            deficit_sq.add(d * d);
            if k > 8 && probe.state[0].abs() < 1e-9 && probe.state[1].abs() < 1e-9 {
                break;
            }
        }
        let w0 = weight.value();
        w0 * w0 + deficit_sq.value()
    }
}

/// Identifies the coefficient `a` from a static window of one channel's raw samples.
///
/// The model implies for the differences `d_k = x_k - x_{k-1}`:  `d_{k+1} = (a - 1) d_k + xi`, so the
/// constrained AR(2) fit of the data (`z_{k+1} = a z_k + (1-a) z_{k-1}`, row sum one) is the least-squares
/// AR(1) coefficient `rho` of the first differences, `a = 1 + rho`, projected onto [0, 1]. Pure white
/// noise about a constant gives rho = -1/2, so a = 1/2. Runs incrementally (no sample buffer).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CoefficientIdentifier {
    count: u32,
    previous_raw: f32,
    previous_difference: f32,
    lagged_products: KahanSum,
    lagged_squares: KahanSum,
}

impl CoefficientIdentifier {
    /// An empty identifier.
    pub const fn new() -> CoefficientIdentifier {
        CoefficientIdentifier {
            count: 0,
            previous_raw: 0.0,
            previous_difference: 0.0,
            lagged_products: KahanSum::new(),
            lagged_squares: KahanSum::new(),
        }
    }

    /// Feeds one raw sample.
    pub fn update(&mut self, raw: f32) {
        if self.count >= 1 {
            let d = raw - self.previous_raw;
            if self.count >= 2 {
                self.lagged_products.add(d * self.previous_difference);
                self.lagged_squares.add(self.previous_difference * self.previous_difference);
            }
            self.previous_difference = d;
        }
        self.previous_raw = raw;
        self.count = self.count.saturating_add(1);
    }

    /// The identified `a` in [0, 1]; `None` before 10 samples or when the window is exactly constant.
    pub fn coefficient(&self) -> Option<f32> {
        let sxx = self.lagged_squares.value();
        if self.count < 10 || sxx <= 0.0 {
            return None;
        }
        let rho = self.lagged_products.value() / sxx;
        Some((1.0 + rho).clamp(0.0, 1.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook Riccati recursion in f64 with the full Q and R (no normalisation, no shortcut).
    fn riccati_f64(a: f64, q: f64, r: f64) -> [[f64; 2]; 2] {
        let f = [[a, 1.0 - a], [1.0, 0.0]];
        let mut p = [[r, 0.0], [0.0, r]];
        let mut k = [[0.0; 2]; 2];
        for _ in 0..1_000_000 {
            // P_pred = F P F' + Q
            let mut fp = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    fp[i][j] = (0..2).map(|m| f[i][m] * p[m][j]).sum();
                }
            }
            let mut pp = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    pp[i][j] = (0..2).map(|m| fp[i][m] * f[j][m]).sum::<f64>() + if i == j { q } else { 0.0 };
                }
            }
            // S = P_pred + R, K = P_pred S^-1
            let s = [[pp[0][0] + r, pp[0][1]], [pp[1][0], pp[1][1] + r]];
            let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
            let si = [[s[1][1] / det, -s[0][1] / det], [-s[1][0] / det, s[0][0] / det]];
            let mut kn = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    kn[i][j] = (0..2).map(|m| pp[i][m] * si[m][j]).sum();
                }
            }
            // P = (I - K) P_pred
            for i in 0..2 {
                for j in 0..2 {
                    p[i][j] = pp[i][j] - (0..2).map(|m| kn[i][m] * pp[m][j]).sum::<f64>();
                }
            }
            let change = (0..4).map(|m| (kn[m / 2][m % 2] - k[m / 2][m % 2]).abs()).fold(0.0, f64::max);
            k = kn;
            if change < 1e-15 {
                break;
            }
        }
        k
    }

    #[test]
    fn steady_gain_matches_f64_riccati_for_the_paper_settings() {
        for (settings, name) in [
            (PrefilterSettings::paper_gyro(), "gyro"),
            (PrefilterSettings::paper_accel(), "accel"),
            (PrefilterSettings::paper_gyro().with_a(0.5), "gyro a=0.5"),
            (PrefilterSettings::paper_accel().with_a(0.0), "accel a=0"),
        ] {
            let got = steady_gain(&settings).unwrap();
            let want = riccati_f64(settings.a as f64, settings.q as f64, settings.r as f64);
            for i in 0..2 {
                for j in 0..2 {
                    // f32 fixed point of the recursion: within 1e-5 relative of the f64 solution.
                    let err = (got.gain[i][j] as f64 - want[i][j]).abs();
                    assert!(err < 1e-5 * want[i][j].abs().max(1e-2), "{name}: K[{i}][{j}] {:?} vs {want:?}", got.gain);
                }
            }
        }
    }

    #[test]
    fn constant_passes_bit_exactly() {
        for settings in [PrefilterSettings::paper_gyro(), PrefilterSettings::paper_accel().with_a(0.37)] {
            let mut f = HmmKf::new(&settings).unwrap();
            for &c in &[9.806_65f32, -7.292_115e-5, 0.0, 1.0e-30] {
                f.reset();
                for _ in 0..5000 {
                    assert_eq!(f.update(c), c);
                }
            }
        }
    }

    #[test]
    fn dc_gain_is_one_and_a_step_is_followed() {
        let f = HmmKf::new(&PrefilterSettings::paper_gyro()).unwrap();
        let (dc, noise_gain) = f.impulse_response_sums();
        assert!((dc - 1.0).abs() < 1e-4, "DC gain {dc}");
        assert!(noise_gain > 0.0 && noise_gain < 0.2, "noise gain {noise_gain}");
        let mut f = f;
        f.update(0.0);
        let mut y = 0.0;
        for _ in 0..2000 {
            y = f.update(1.0);
        }
        assert!((y - 1.0).abs() < 1e-5, "{y}");
    }

    #[test]
    fn bad_settings_are_rejected() {
        let s = PrefilterSettings::paper_gyro();
        assert_eq!(steady_gain(&s.with_a(1.5)), Err(PrefilterError::BadCoefficient));
        assert_eq!(steady_gain(&s.with_a(f32::NAN)), Err(PrefilterError::BadCoefficient));
        assert_eq!(steady_gain(&PrefilterSettings { q: 0.0, ..s }), Err(PrefilterError::BadNoise));
    }

    fn lcg_gauss(state: &mut u64) -> f32 {
        // Sum of 12 uniforms minus 6: a unit-variance, near-Gaussian deviate (good enough for this test).
        let mut s = 0.0;
        for _ in 0..12 {
            *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            s += (*state >> 40) as f32 / (1u64 << 24) as f32;
        }
        s - 6.0
    }

    #[test]
    fn start_transient_weight_is_the_excess_variance_of_the_filtered_mean() {
        let f = HmmKf::new(&PrefilterSettings::paper_gyro()).unwrap();
        let t = f.start_transient_weight();
        assert!((t - 207.1).abs() < 0.5, "{t}");
        // The filtered mean of a dwell differs from the raw mean by exactly the start and end terms: for
        // white noise its variance is sigma^2 (1 / N + t / N^2). 2000 dwells of 600 samples.
        let (n, runs) = (600usize, 2000);
        let mut rng = 11u64;
        let (mut filtered_sq, mut raw_sq) = (0.0f64, 0.0f64);
        for _ in 0..runs {
            let mut g = f;
            g.reset();
            let (mut sf, mut sr) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let z = lcg_gauss(&mut rng);
                sf += g.update(z) as f64;
                sr += z as f64;
            }
            filtered_sq += (sf / n as f64).powi(2);
            raw_sq += (sr / n as f64).powi(2);
        }
        let want = 1.0 + t as f64 / n as f64;
        let got = filtered_sq / raw_sq;
        // Each mean square has a relative standard deviation of sqrt(2 / 2000) = 0.032; they are correlated.
        assert!((got / want - 1.0).abs() < 0.06, "{got} vs {want}");
    }

    #[test]
    fn coefficient_is_identified_from_model_data() {
        // Data from the model itself with a = 0.3 (no measurement noise): x_{k+1} = a x_k + (1-a) x_{k-1} + xi.
        let mut rng = 7u64;
        let mut id = CoefficientIdentifier::new();
        let (mut x0, mut x1) = (0.0f32, 0.0f32);
        for _ in 0..60_000 {
            let x = 0.3 * x0 + 0.7 * x1 + 1e-3 * lcg_gauss(&mut rng);
            x1 = x0;
            x0 = x;
            id.update(x);
        }
        let a = id.coefficient().unwrap();
        assert!((a - 0.3).abs() < 0.02, "a = {a}");

        // White noise about a constant: a = 1/2.
        let mut id = CoefficientIdentifier::new();
        for _ in 0..60_000 {
            id.update(9.8 + 1e-3 * lcg_gauss(&mut rng));
        }
        let a = id.coefficient().unwrap();
        assert!((a - 0.5).abs() < 0.02, "a = {a}");
    }
}
