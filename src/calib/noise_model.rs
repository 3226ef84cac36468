//! A noise model per channel (docs/method.md#noise-model): the classic terms of IEEE Std 952-1997 Annex C
//! and a first-order Gauss-Markov process, named once from a static run (`sinscal noise`), and what they make
//! of the variance of a dwell's mean.
//!
//! The Allan variance of the model at averaging time `tau` is
//!
//! `AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + sigma^2 g(tau / T) + K^2 tau / 3 + R^2 tau^2 / 2`
//! `          + S^2 h(tau / T_S) / tau^2`
//!
//! with `g(x) = (2 x - 3 + 4 e^-x - e^-2x) / x^2` for the Gauss-Markov process of standard deviation `sigma`
//! and correlation time `T`, and `h(x) = 3 - 4 e^-x + e^-2x` for **sway**: a channel whose integral (the angle
//! of a gyro, the velocity of an accelerometer) is a first-order Gauss-Markov process of standard deviation `S`
//! and correlation time `T_S`, as a vehicle's or a building's sway leaves a bounded tilt. Averaged over much
//! less than `T_S` it is white noise (`N^2 = 2 S^2 / T_S`); over much more its mean falls as `1 / tau`, like
//! quantisation (`Q = S`), because the angle it integrates to stays bounded.
//!
//! **The variance of a dwell mean** is the model's Allan variance at the dwell's length `T_d`: half the mean
//! square difference of the means of two adjacent dwells of that length. For white noise it is the familiar
//! `N^2 / T_d = sigma^2 / samples`; for quantisation of an integrated output it is `3 Q^2 / T_d^2`, falling
//! with the square of the length (where `sigma / sqrt(samples)` would be far too large); for noise slower than
//! the dwell (bias instability, Gauss-Markov of long correlation time, rate random walk) it is the wander
//! between dwells that a single dwell cannot see in its own scatter. The sensor terms a calibration estimates
//! refer to the span of its dwells (the stated epoch): a bias with a rate random walk is the bias over the
//! session, and its standard error is what a second session of the same schedule right after it would differ
//! by, over the square root of two.
//!
//! **Between dwells** ([`NoiseModel::repeat_covariance`]): the errors of two dwells' means are correlated by
//! the noise slower than a dwell. Their covariance, with the same epoch as the variance above, is
//! `E[(e_a - e'_a)(e_b - e'_b)] / 2`, `e'` the errors of the same session repeated right after it: for a dwell
//! alone in its session exactly the Allan variance at its length. For the stationary terms it is
//! `C(a, b) - C(a, b + L) / 2 - C(b, a + L) / 2` (`C` the covariance of window means, `L` the session's span);
//! for the rate random walk `K^2 (L - mean |t - s|) / 2` over the two windows, for the ramp `R^2 L^2 / 2`.
//! Bias instability (flicker) has no finite covariance; it is taken as eight Gauss-Markov processes of
//! correlation times 0.01 s to 1e5 s, each of variance `B^2 ln 10 / pi`, whose Allan variance is
//! `(2 ln 2 / pi) B^2` within 2 % for averaging times of 1 s to 1e4 s.
//!
//! The model is fixed-size and f32, so that the device computes the same variances as the workstation: it is
//! part of the device's configuration (docs/formats.md#replay-file-ssrp-version-6).

/// ln 2 / pi * 2: the Allan variance of unit bias instability.
const BIAS_INSTABILITY_AVAR: f32 = 2.0 * core::f32::consts::LN_2 / core::f32::consts::PI;

/// The noise terms of one channel, SI: for a gyro the unit is rad/s, for an accelerometer m/s^2 (written
/// `U` below). Every coefficient is >= 0; a term absent from the model is 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelNoiseTerms {
    /// Quantisation Q, U s (rad for a gyro, m/s for an accelerometer).
    pub quantisation_u_s: f32,
    /// White noise N (angle or velocity random walk), U sqrt(s).
    pub white_u_sqrt_s: f32,
    /// Bias instability B, U.
    pub instability_u: f32,
    /// Gauss-Markov standard deviation sigma, U.
    pub gauss_markov_u: f32,
    /// Gauss-Markov correlation time T, s (> 0 when sigma is).
    pub gauss_markov_time_s: f32,
    /// Rate random walk K, U / sqrt(s).
    pub random_walk_u_per_sqrt_s: f32,
    /// Rate ramp R, U / s.
    pub ramp_u_per_s: f32,
    /// Sway S: the standard deviation of the channel's bounded integral, U s (rad for a gyro, m/s for an
    /// accelerometer).
    pub sway_u_s: f32,
    /// Sway's correlation time T_S, s (> 0 when S is).
    pub sway_time_s: f32,
}

impl ChannelNoiseTerms {
    /// The terms as the wire carries them, in this order.
    pub fn to_array(&self) -> [f32; TERM_VALUES] {
        [
            self.quantisation_u_s,
            self.white_u_sqrt_s,
            self.instability_u,
            self.gauss_markov_u,
            self.gauss_markov_time_s,
            self.random_walk_u_per_sqrt_s,
            self.ramp_u_per_s,
            self.sway_u_s,
            self.sway_time_s,
        ]
    }

    /// The terms from [`ChannelNoiseTerms::to_array`]'s order.
    pub fn from_array(v: [f32; TERM_VALUES]) -> ChannelNoiseTerms {
        ChannelNoiseTerms {
            quantisation_u_s: v[0],
            white_u_sqrt_s: v[1],
            instability_u: v[2],
            gauss_markov_u: v[3],
            gauss_markov_time_s: v[4],
            random_walk_u_per_sqrt_s: v[5],
            ramp_u_per_s: v[6],
            sway_u_s: v[7],
            sway_time_s: v[8],
        }
    }

    /// Every coefficient finite and >= 0, a Gauss-Markov term and sway with positive correlation times, and
    /// some term that makes the variance positive at every length.
    pub fn is_valid(&self) -> bool {
        let v = self.to_array();
        let finite = v.iter().all(|x| x.is_finite() && *x >= 0.0);
        let gm_ok = self.gauss_markov_u == 0.0 || self.gauss_markov_time_s > 0.0;
        let sway_ok = self.sway_u_s == 0.0 || self.sway_time_s > 0.0;
        let any = v.iter().enumerate().any(|(i, x)| i != 4 && i != 8 && *x > 0.0);
        finite && gm_ok && sway_ok && any
    }

    /// The model's Allan variance at `tau_s` (> 0), U^2.
    pub fn allan_variance(&self, tau_s: f32) -> f32 {
        let sq = |x: f32| x * x;
        let tau = tau_s;
        let mut v = 3.0 * sq(self.quantisation_u_s) / (tau * tau)
            + sq(self.white_u_sqrt_s) / tau
            + BIAS_INSTABILITY_AVAR * sq(self.instability_u)
            + sq(self.random_walk_u_per_sqrt_s) * tau / 3.0
            + sq(self.ramp_u_per_s) * tau * tau / 2.0;
        if self.gauss_markov_u > 0.0 && self.gauss_markov_time_s > 0.0 {
            v += sq(self.gauss_markov_u) * gauss_markov_shape(tau / self.gauss_markov_time_s);
        }
        if self.sway_u_s > 0.0 && self.sway_time_s > 0.0 {
            v += sq(self.sway_u_s) * sway_shape(tau / self.sway_time_s) / (tau * tau);
        }
        v
    }

    /// The variance of the mean of a dwell `duration_s` long (> 0), U^2: the Allan variance at that length
    /// (module documentation).
    pub fn mean_variance(&self, duration_s: f32) -> f32 {
        self.allan_variance(duration_s)
    }
}

/// `g(x) = (2 x - 3 + 4 e^-x - e^-2x) / x^2`, the Allan variance of a unit Gauss-Markov process at
/// `tau = x T`. Below `x = 1` the closed form cancels away f32's digits; there its power series
/// `sum_{k >= 3} (4 (-1)^k - (-2)^k) / k! x^(k-2)` (`2x/3 - x^2/2 + 7x^3/30 - ...`), 14 terms: the first
/// left out is below 1e-9 of the sum.
fn gauss_markov_shape(x: f32) -> f32 {
    if x >= 1.0 {
        return (2.0 * x - 3.0 + 4.0 * libm::expf(-x) - libm::expf(-2.0 * x)) / (x * x);
    }
    // k = 3: x^1 / 3!, with the alternating signs carried in `minus_one` and `minus_two`.
    let (mut power, mut factorial, mut minus_one, mut minus_two) = (x, 6.0f32, -1.0f32, -8.0f32);
    let mut sum = 0.0f32;
    for k in 3..17 {
        sum += (4.0 * minus_one - minus_two) / factorial * power;
        power *= x;
        factorial *= (k + 1) as f32;
        minus_one = -minus_one;
        minus_two *= -2.0;
    }
    sum
}

/// The time between two disjoint windows `[start, end)` in seconds, in either order (0 when they touch).
fn gap_s(x: (f32, f32), y: (f32, f32)) -> f32 {
    if x.0 <= y.0 { y.0 - x.1 } else { x.0 - y.1 }.max(0.0)
}

/// `h(x) = 3 - 4 e^-x + e^-2x`: `tau^2` times the Allan variance of unit sway at `tau = x T_S` (the angle
/// `theta` Gauss-Markov: `(3 R(0) - 4 R(tau) + R(2 tau)) / tau^2` with `R` its autocovariance). Below `x = 1`
/// its power series `sum_{k >= 1} (-1)^k (2^k - 4) / k! x^k` (`2x - 2x^3/3 + x^4/2 - ...`), 16 terms: the
/// first left out is below 1e-9 of the sum.
fn sway_shape(x: f32) -> f32 {
    if x >= 1.0 {
        return 3.0 - 4.0 * libm::expf(-x) + libm::expf(-2.0 * x);
    }
    let (mut power, mut factorial, mut two_k, mut sign) = (x, 1.0f32, 2.0f32, -1.0f32);
    let mut sum = 0.0f32;
    for k in 1..17 {
        sum += sign * (two_k - 4.0) / factorial * power;
        power *= x;
        factorial *= (k + 1) as f32;
        two_k *= 2.0;
        sign = -sign;
    }
    sum
}

/// The covariance of the means of two windows of sway of variance `var` (of the integral) and correlation time
/// `tc_s`: `[start, end)` in seconds, the same window or disjoint ones. A window's mean is the change of the
/// integral over it divided by its length: `2 var (1 - e^-T/T_S) / T^2` alone; disjoint windows share no sample
/// but the integral's memory, `-var e^-gap/T_S (1 - e^-T_x/T_S) (1 - e^-T_y/T_S) / (T_x T_y)`: negative, as what
/// one window's angle gains the next gives back.
fn sway_windows(var: f32, tc_s: f32, x: (f32, f32), y: (f32, f32), same: bool) -> f32 {
    let (tx, ty) = (x.1 - x.0, y.1 - y.0);
    let fx = -libm::expm1f(-tx / tc_s);
    if same {
        return 2.0 * var * fx / (tx * tx);
    }
    let gap_s = gap_s(x, y);
    let fy = -libm::expm1f(-ty / tc_s);
    -var * fx * fy * libm::expf(-gap_s / tc_s) / (tx * ty)
}

/// A dwell's samples in its session: the index of its first sample (from the session's first) and its number
/// of samples (those used and those left out as spikes: the dwell's span).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Window {
    /// The index of the dwell's first sample.
    pub first_sample: u32,
    /// Its samples.
    pub samples: u32,
}

impl Window {
    /// The window `shift` samples later.
    fn later(self, shift: u64) -> (u64, u64) {
        let first = self.first_sample as u64 + shift;
        (first, first + self.samples as u64)
    }
}

/// Correlation times of the Gauss-Markov processes that stand for bias instability, s.
const FLICKER_TIMES_S: [f32; 8] = [0.01, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5];
/// The variance of each of them per unit `B^2`: `ln 10 / pi` (module documentation).
const FLICKER_VARIANCE: f32 = core::f32::consts::LN_10 / core::f32::consts::PI;

/// `u - 1 + e^-u` without cancellation: its power series `u^2/2 - u^3/6 + ...` below 1.
fn u_minus_one_plus_exp(u: f32) -> f32 {
    if u >= 1.0 {
        return u - 1.0 + libm::expf(-u);
    }
    let (mut term, mut sum) = (u * u / 2.0, 0.0f32);
    for k in 3..14 {
        sum += term;
        term *= -u / k as f32;
    }
    sum
}

/// The covariance of the means of two windows of a first-order Gauss-Markov process of variance `var` and
/// correlation time `tc_s`: `[start, end)` in seconds, the same window or disjoint ones.
fn gauss_markov_windows(var: f32, tc_s: f32, x: (f32, f32), y: (f32, f32), same: bool) -> f32 {
    let (tx, ty) = (x.1 - x.0, y.1 - y.0);
    if same {
        return 2.0 * var * tc_s * tc_s * u_minus_one_plus_exp(tx / tc_s) / (tx * tx);
    }
    let gap_s = gap_s(x, y);
    let fx = -libm::expm1f(-tx / tc_s);
    let fy = -libm::expm1f(-ty / tc_s);
    var * tc_s * tc_s * fx * fy * libm::expf(-gap_s / tc_s) / (tx * ty)
}

/// Values per channel on the wire.
pub const TERM_VALUES: usize = 9;

/// The noise model of the six channels (gyro x, y, z in rad/s, accelerometer x, y, z in m/s^2) and the sample
/// interval of the calibration it is applied to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoiseModel {
    /// The calibration's sample interval, s: a dwell of `n` samples lasts `n` times it.
    pub sample_interval_s: f32,
    /// Per channel.
    pub channels: [ChannelNoiseTerms; 6],
}

impl NoiseModel {
    /// A positive finite sample interval and every channel valid; `gyros`: whether the gyro channels are used
    /// (without, theirs may be all zero).
    pub fn is_valid(&self, gyros: bool) -> bool {
        let first = if gyros { 0 } else { 3 };
        let interval_ok = self.sample_interval_s.is_finite() && self.sample_interval_s > 0.0;
        interval_ok && self.channels[first..].iter().all(ChannelNoiseTerms::is_valid)
    }

    /// The variance of channel `channel`'s mean over a dwell of `samples` samples, U^2.
    pub fn mean_variance(&self, channel: usize, samples: u32) -> f32 {
        let duration_s = samples.max(1) as f32 * self.sample_interval_s;
        self.channels[channel].mean_variance(duration_s)
    }

    /// The covariance of the errors of channel `channel`'s means over dwells `a` and `b` of a session spanning
    /// `span_samples` samples, U^2, with the session as the epoch (module documentation): for one dwell alone
    /// in its session the Allan variance at its length.
    pub fn repeat_covariance(&self, channel: usize, a: Window, b: Window, span_samples: u32) -> f32 {
        let t = &self.channels[channel];
        let dt = self.sample_interval_s;
        let same = a == b;
        let span = span_samples as u64;
        let seconds = |w: (u64, u64)| (w.0 as f32 * dt, w.1 as f32 * dt);
        let (wa, wb) = (a.later(0), b.later(0));
        let (wa_later, wb_later) = (a.later(span), b.later(span));
        // A stationary term's covariance C of window means: C(a, b) - C(a, b + L) / 2 - C(b, a + L) / 2.
        let stationary = |c: &dyn Fn((u64, u64), (u64, u64), bool) -> f32| {
            c(wa, wb, same) - 0.5 * c(wa, wb_later, false) - 0.5 * c(wb, wa_later, false)
        };
        let mut v = 0.0f32;
        if same {
            v += t.white_u_sqrt_s * t.white_u_sqrt_s / (a.samples.max(1) as f32 * dt);
        }
        if t.quantisation_u_s > 0.0 {
            // The carry model: a window's mean error is (carry before - carry at its end) q / T, carries of
            // variance Q^2 (IEEE Q): 2 Q^2 / T^2 alone, -Q^2 / (T_x T_y) for windows that share a carry.
            let q2 = t.quantisation_u_s * t.quantisation_u_s;
            v += stationary(&|x, y, same| {
                let (tx, ty) = ((x.1 - x.0) as f32 * dt, (y.1 - y.0) as f32 * dt);
                if same {
                    2.0 * q2 / (tx * tx)
                } else if x.1 == y.0 || y.1 == x.0 {
                    -q2 / (tx * ty)
                } else {
                    0.0
                }
            });
        }
        if t.gauss_markov_u > 0.0 && t.gauss_markov_time_s > 0.0 {
            let (var, tc) = (t.gauss_markov_u * t.gauss_markov_u, t.gauss_markov_time_s);
            v += stationary(&|x, y, same| gauss_markov_windows(var, tc, seconds(x), seconds(y), same));
        }
        if t.sway_u_s > 0.0 && t.sway_time_s > 0.0 {
            let (var, tc) = (t.sway_u_s * t.sway_u_s, t.sway_time_s);
            v += stationary(&|x, y, same| sway_windows(var, tc, seconds(x), seconds(y), same));
        }
        if t.instability_u > 0.0 {
            let var = FLICKER_VARIANCE * t.instability_u * t.instability_u;
            for tc in FLICKER_TIMES_S {
                v += stationary(&|x, y, same| gauss_markov_windows(var, tc, seconds(x), seconds(y), same));
            }
        }
        let span_s = span as f32 * dt;
        if t.random_walk_u_per_sqrt_s > 0.0 {
            // The mean of |t - s| over the two windows: T / 3 within one, the distance of the middles between two.
            let mean_abs_s = if same {
                a.samples as f32 * dt / 3.0
            } else {
                let mid = |w: (u64, u64)| (w.0 + w.1) as f32 * 0.5 * dt;
                (mid(wa) - mid(wb)).abs()
            };
            let k2 = t.random_walk_u_per_sqrt_s * t.random_walk_u_per_sqrt_s;
            v += 0.5 * k2 * (span_s - mean_abs_s);
        }
        v + 0.5 * t.ramp_u_per_s * t.ramp_u_per_s * span_s * span_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn white(n: f32) -> ChannelNoiseTerms {
        ChannelNoiseTerms { white_u_sqrt_s: n, ..Default::default() }
    }

    #[test]
    fn white_noise_gives_sigma_squared_over_samples() {
        // N = sigma sqrt(dt): sigma = 0.01 at 100 Hz is N = 0.001; 6000 samples: sigma^2 / 6000.
        let m = NoiseModel { sample_interval_s: 0.01, channels: [white(0.001); 6] };
        let v = m.mean_variance(2, 6000);
        assert!((v / (1e-4 / 6000.0) - 1.0).abs() < 1e-5, "{v}");
    }

    #[test]
    fn quantisation_falls_with_the_square_of_the_length() {
        let q = ChannelNoiseTerms { quantisation_u_s: 1e-5, ..Default::default() };
        let (a, b) = (q.mean_variance(10.0), q.mean_variance(100.0));
        assert!((a / b - 100.0).abs() < 1e-3, "{}", a / b);
        assert!((a - 3.0 * 1e-10 / 100.0).abs() < 1e-16, "{a}");
    }

    #[test]
    fn slow_terms_do_not_fall() {
        let b = ChannelNoiseTerms { instability_u: 1e-4, ..Default::default() };
        assert_eq!(b.mean_variance(1.0), b.mean_variance(1000.0));
        let k = ChannelNoiseTerms { random_walk_u_per_sqrt_s: 1e-5, ..Default::default() };
        assert!((k.mean_variance(300.0) / k.mean_variance(30.0) - 10.0).abs() < 1e-4);
    }

    #[test]
    fn gauss_markov_shape_matches_its_limits_and_is_continuous_at_the_switch() {
        // Long averaging: 2 T / tau. Short: 2 tau / (3 T).
        assert!((gauss_markov_shape(1000.0) * 1000.0 / 2.0 - 1.0).abs() < 3e-3);
        assert!((gauss_markov_shape(1e-3) / (2e-3 / 3.0) - 1.0).abs() < 1e-3);
        let (below, above) = (gauss_markov_shape(0.999_999), gauss_markov_shape(1.0));
        assert!((below / above - 1.0).abs() < 1e-5, "{below} {above}");
        // Against f64's closed form where it keeps its digits: g(0.1), g(0.5).
        let closed = |x: f64| (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp()) / (x * x);
        for x in [0.1f64, 0.5, 0.9] {
            assert!((gauss_markov_shape(x as f32) as f64 / closed(x) - 1.0).abs() < 1e-5, "{x}");
        }
        // The hump: the largest value near x = 1.89.
        let peak =
            (1..400).map(|i| i as f32 * 0.01).max_by(|a, b| gauss_markov_shape(*a).total_cmp(&gauss_markov_shape(*b)));
        assert!((peak.unwrap() - 1.89).abs() < 0.02, "{peak:?}");
    }

    /// One dwell alone in its session: its covariance with itself is the Allan variance at its length, term by
    /// term (bias instability within the 2 % of its Gauss-Markov stand-in).
    #[test]
    fn a_dwell_alone_has_the_allan_variance() {
        let dt = 0.01;
        let terms = [
            ChannelNoiseTerms { white_u_sqrt_s: 1e-3, ..Default::default() },
            ChannelNoiseTerms { quantisation_u_s: 1e-4, ..Default::default() },
            ChannelNoiseTerms { gauss_markov_u: 1e-3, gauss_markov_time_s: 20.0, ..Default::default() },
            ChannelNoiseTerms { gauss_markov_u: 1e-3, gauss_markov_time_s: 0.05, ..Default::default() },
            ChannelNoiseTerms { random_walk_u_per_sqrt_s: 1e-5, ..Default::default() },
            ChannelNoiseTerms { ramp_u_per_s: 1e-7, ..Default::default() },
            ChannelNoiseTerms { instability_u: 1e-4, ..Default::default() },
            ChannelNoiseTerms { sway_u_s: 1e-4, sway_time_s: 2.0, ..Default::default() },
            ChannelNoiseTerms { sway_u_s: 1e-4, sway_time_s: 500.0, ..Default::default() },
        ];
        for (k, t) in terms.iter().enumerate() {
            let m = NoiseModel { sample_interval_s: dt, channels: [*t; 6] };
            for samples in [100u32, 6000, 30_000] {
                let w = Window { first_sample: 0, samples };
                let (cov, avar) = (m.repeat_covariance(0, w, w, samples), t.allan_variance(samples as f32 * dt));
                let tolerance = if k == 6 { 0.025 } else { 2e-3 };
                assert!((cov / avar - 1.0).abs() < tolerance, "term {k}, {samples} samples: {cov:e} against {avar:e}");
            }
        }
    }

    /// Two dwells: white noise does not correlate them; a slow Gauss-Markov process does, positively, and the
    /// covariance is symmetric.
    #[test]
    fn slow_noise_correlates_two_dwells() {
        let white = NoiseModel { sample_interval_s: 0.01, channels: [white(1e-3); 6] };
        let (a, b) = (Window { first_sample: 0, samples: 6000 }, Window { first_sample: 7000, samples: 6000 });
        assert_eq!(white.repeat_covariance(0, a, b, 13_000), 0.0);
        let slow = ChannelNoiseTerms { gauss_markov_u: 1e-3, gauss_markov_time_s: 1000.0, ..Default::default() };
        let m = NoiseModel { sample_interval_s: 0.01, channels: [slow; 6] };
        let (ab, ba) = (m.repeat_covariance(0, a, b, 13_000), m.repeat_covariance(0, b, a, 13_000));
        let (aa, bb) = (m.repeat_covariance(0, a, a, 13_000), m.repeat_covariance(0, b, b, 13_000));
        assert!((ab / ba - 1.0).abs() < 1e-5, "{ab:e} {ba:e}");
        assert!(ab > 0.0 && ab < aa.sqrt() * bb.sqrt(), "{ab:e} {aa:e} {bb:e}");
        // Nearly the whole Allan variance of the pair is common: the correlation is high.
        assert!(ab / (aa * bb).sqrt() > 0.5, "{}", ab / (aa * bb).sqrt());
    }

    /// Sway: white noise of `N^2 = 2 S^2 / T_S` averaged over much less than its correlation time, quantisation
    /// of `Q = S` over much more; the series and the closed form agree at the switch and with f64.
    #[test]
    fn sway_is_white_when_short_and_quantisation_when_long() {
        let (s, tc) = (1e-4f32, 10.0f32);
        let sway = ChannelNoiseTerms { sway_u_s: s, sway_time_s: tc, ..Default::default() };
        let white = ChannelNoiseTerms { white_u_sqrt_s: (2.0 * s * s / tc).sqrt(), ..Default::default() };
        let quantisation = ChannelNoiseTerms { quantisation_u_s: s, ..Default::default() };
        assert!((sway.allan_variance(0.01) / white.allan_variance(0.01) - 1.0).abs() < 1e-3);
        assert!((sway.allan_variance(1e4) / quantisation.allan_variance(1e4) - 1.0).abs() < 1e-3);
        let closed = |x: f64| 3.0 - 4.0 * (-x).exp() + (-2.0 * x).exp();
        for x in [1e-3f64, 0.1, 0.5, 0.999_999] {
            assert!((sway_shape(x as f32) as f64 / closed(x) - 1.0).abs() < 1e-5, "{x}");
        }
    }

    /// Two adjacent dwells of sway anticorrelate (the angle one gains the next gives back); far apart they do not
    /// correlate.
    #[test]
    fn sway_anticorrelates_adjacent_dwells() {
        let sway = ChannelNoiseTerms { sway_u_s: 1e-4, sway_time_s: 5.0, ..Default::default() };
        let m = NoiseModel { sample_interval_s: 0.01, channels: [sway; 6] };
        let (a, b) = (Window { first_sample: 0, samples: 1000 }, Window { first_sample: 1000, samples: 1000 });
        let far = Window { first_sample: 100_000, samples: 1000 };
        let (ab, aa) = (m.repeat_covariance(0, a, b, 2000), m.repeat_covariance(0, a, a, 2000));
        assert!(ab < 0.0 && -ab < aa, "{ab:e} {aa:e}");
        // A session of 2,000 s: the dwells and their repeats all hundreds of correlation times apart.
        let af = m.repeat_covariance(0, a, far, 200_000);
        assert!(af.abs() < 1e-6 * aa, "{af:e} {aa:e}");
    }

    #[test]
    fn the_series_of_u_minus_one_plus_exp_matches_f64() {
        for u in [1e-4f64, 1e-2, 0.3, 0.999, 1.0, 5.0] {
            let exact = u - 1.0 + (-u).exp();
            let got = u_minus_one_plus_exp(u as f32) as f64;
            assert!((got / exact - 1.0).abs() < 1e-4, "{u}: {got:e} against {exact:e}");
        }
    }

    #[test]
    fn invalid_models_are_refused() {
        let mut m = NoiseModel { sample_interval_s: 0.01, channels: [white(1e-3); 6] };
        assert!(m.is_valid(true));
        m.channels[0].white_u_sqrt_s = f32::NAN;
        assert!(!m.is_valid(true));
        assert!(m.is_valid(false), "gyros unused");
        m.channels[4] = ChannelNoiseTerms::default();
        assert!(!m.is_valid(false), "all zero: no variance");
        m.channels[4] = ChannelNoiseTerms { gauss_markov_u: 1e-3, ..Default::default() };
        assert!(!m.is_valid(false), "Gauss-Markov without its time");
        m.channels[4].gauss_markov_time_s = 10.0;
        assert!(m.is_valid(false));
        m.channels[4] = ChannelNoiseTerms { sway_u_s: 1e-3, ..Default::default() };
        assert!(!m.is_valid(false), "sway without its time");
        m.channels[4].sway_time_s = 10.0;
        assert!(m.is_valid(false));
        m.sample_interval_s = 0.0;
        assert!(!m.is_valid(false));
    }
}
