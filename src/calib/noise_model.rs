//! A noise model per channel (docs/method.md#noise-model): the classic terms of IEEE Std 952-1997 Annex C
//! and a first-order Gauss-Markov process, named once from a static run (`sinscal noise`), and what they make
//! of the variance of a dwell's mean.
//!
//! The Allan variance of the model at averaging time `tau` is
//!
//! `AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln 2 / pi) B^2 + sigma^2 g(tau / T) + K^2 tau / 3 + R^2 tau^2 / 2`
//!
//! with `g(x) = (2 x - 3 + 4 e^-x - e^-2x) / x^2` for the Gauss-Markov process of standard deviation `sigma`
//! and correlation time `T`.
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
//! The model is fixed-size and f32, so that the device computes the same variances as the workstation: it is
//! part of the device's configuration (docs/formats.md#replay-file-ssrp-version-5).

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
        }
    }

    /// Every coefficient finite and >= 0, a Gauss-Markov term with a positive correlation time, and some term
    /// that makes the variance positive at every length.
    pub fn is_valid(&self) -> bool {
        let v = self.to_array();
        let finite = v.iter().all(|x| x.is_finite() && *x >= 0.0);
        let gm_ok = self.gauss_markov_u == 0.0 || self.gauss_markov_time_s > 0.0;
        let any = v.iter().enumerate().any(|(i, x)| i != 4 && *x > 0.0);
        finite && gm_ok && any
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

/// Values per channel on the wire.
pub const TERM_VALUES: usize = 7;

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
        m.sample_interval_s = 0.0;
        assert!(!m.is_valid(false));
    }
}
