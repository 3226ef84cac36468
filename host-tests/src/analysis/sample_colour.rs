//! The colour of a channel's noise at the scale of a few samples: the sensor's own filter (an anti-aliasing
//! or decimation filter) makes neighbouring samples correlated, which no Gauss-Markov process of a time
//! constant of two samples or more can describe. Measured on the shared records
//! (docs/analysis.md#the-noise-at-the-scale-of-a-few-samples): the Ferraris gyros' detrended samples
//! correlate +0.19 to +0.20 at one sample and -0.07 to -0.11 at two, nothing beyond.
//!
//! Modelled as a moving average of order two of the white noise, `w_t + theta_1 w_(t-1) + theta_2 w_(t-2)`,
//! fitted on the autocovariances (lags 0 to 3) of the sample DIFFERENCES within every dwell. A process slower
//! than a few samples (time constant `tau` samples, variance `s2`) hardly moves them: it adds `-s2
//! phi^(k-1) (1 - phi)^2` at lag `k` (`phi = exp(-1/tau)`), 0.24 % of its variance at `tau = 20`, and `2 s2
//! (1 - phi)` at lag 0, which reads as a little more white noise (10 % of its variance at `tau = 20`) and
//! pulls the coefficients slightly towards zero. The correlated-noise tests then run on the series passed through the inverse of that moving
//! average ([`SampleColour::whiten`]): the sensor's filter no longer stands in for, or masks, a process.
//! A process slower than the filter passes it with the filter's gain at zero frequency, `1 + theta_1 +
//! theta_2`, by which its fitted standard deviation is multiplied back ([`SampleColour::gain`]).

use super::correlated_noise::nelder_mead;

/// Lags of the differences' autocovariance fitted (0 to 3: the moving average of order two, differenced, is
/// one of order three).
const LAGS: usize = 4;

/// Within this of the edge of the invertible region the coefficients are held: the inverse filter's poles
/// stay at most this close to the unit circle.
const INVERTIBLE_MARGIN: f64 = 0.05;

/// The largest modulus of a root of the moving average that is removed (the inverse filter's slowest pole).
const MAX_ROOT: f64 = 0.8;

/// The gain at zero frequency of a colour removed is within this factor of 1.
const MAX_GAIN_FACTOR: f64 = 2.0;

/// Below this many differences the colour is not fitted (taken as white).
const MIN_DIFFERENCES: usize = 64;

/// A channel's noise colour at the sample scale: `w_t + theta[0] w_(t-1) + theta[1] w_(t-2)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct SampleColour {
    /// The moving-average coefficients (dimensionless).
    pub theta: [f64; 2],
}

/// The autocovariance of the differences of a unit-variance moving average `theta`, lags 0 to 3.
fn differenced_autocovariance(theta: [f64; 2]) -> [f64; LAGS] {
    let c = [1.0, theta[0] - 1.0, theta[1] - theta[0], -theta[1]];
    std::array::from_fn(|k| (0..LAGS - k).map(|i| c[i] * c[i + k]).sum())
}

/// `theta` inside the invertible region of a moving average of order two (`|theta_2| < 1`, `theta_2 +-
/// theta_1 > -1`), [`INVERTIBLE_MARGIN`] from its edge.
fn invertible(theta: [f64; 2]) -> [f64; 2] {
    let edge = 1.0 - INVERTIBLE_MARGIN;
    let t2 = theta[1].clamp(-edge, edge);
    let room = t2 + edge;
    [theta[0].clamp(-room, room), t2]
}

impl SampleColour {
    /// The colour of `series` (each dwell's samples, mean and line removed).
    pub fn of(series: &[Vec<f64>]) -> SampleColour {
        let mut sums = [0.0; LAGS];
        let mut counts = [0usize; LAGS];
        for d in series {
            // The differences read from the samples in place (no copy of a dwell).
            let diffs = d.len().saturating_sub(1);
            let diff = |i: usize| d[i + 1] - d[i];
            for k in 0..LAGS {
                for i in k..diffs {
                    sums[k] += diff(i) * diff(i - k);
                }
                counts[k] += diffs.saturating_sub(k);
            }
        }
        if counts[0] < MIN_DIFFERENCES || sums[0] <= 0.0 {
            return SampleColour::default();
        }
        let g: [f64; LAGS] = std::array::from_fn(|k| sums[k] / counts[k].max(1) as f64 / (sums[0] / counts[0] as f64));
        // Least squares of the normalised autocovariances, the white variance profiled out; in units of 1e-6
        // (the simplex stops when its values agree within 1e-6, and the misfits are of the order of 1e-4).
        let misfit = |theta: [f64; 2]| {
            let m = differenced_autocovariance(theta);
            let s2 = g.iter().zip(&m).map(|(a, b)| a * b).sum::<f64>() / m.iter().map(|b| b * b).sum::<f64>();
            -1e6 * g.iter().zip(&m).map(|(a, b)| (a - s2 * b).powi(2)).sum::<f64>()
        };
        let (start, _) = nelder_mead(misfit, invertible, [0.0, 0.0], [0.1, 0.1], 400);
        let (theta, _) = nelder_mead(misfit, invertible, start, [0.02, 0.02], 400);
        let colour = SampleColour { theta };
        if colour.is_a_filter() {
            colour
        } else {
            SampleColour::default()
        }
    }

    /// Whether the colour is a sensor's low-pass filter that the tests can be freed of: it passes zero
    /// frequency at least as well as half the sample rate (`theta_1 >= 0`: `1 + theta_1 + theta_2 >= 1 -
    /// theta_1 + theta_2`), its gain at zero frequency is within [`MAX_GAIN_FACTOR`] of 1, and every root of
    /// its moving average is at most [`MAX_ROOT`] from the origin. A colour that stresses the high frequencies
    /// is a differenced white noise, such as the quantisation of a counter that carries its remainder (the
    /// PSINS laser gyros y and z: gains at zero frequency of 0.05 and 0.68; x: a root 0.97 from the origin):
    /// its inverse would multiply every slow process 1 / gain times, and it is left in the samples.
    fn is_a_filter(&self) -> bool {
        let [a, b] = self.theta;
        // The roots of z^2 + a z + b: complex ones have modulus sqrt(b).
        let disc = a * a - 4.0 * b;
        let largest_root = if disc < 0.0 { b.sqrt() } else { (a.abs() + disc.sqrt()) / 2.0 };
        let gain = self.gain();
        a >= 0.0 && largest_root <= MAX_ROOT && (1.0 / MAX_GAIN_FACTOR..=MAX_GAIN_FACTOR).contains(&gain)
    }

    /// `series` passed through the inverse of the moving average in place: `v_t = y_t - theta_1 v_(t-1) -
    /// theta_2 v_(t-2)`, each dwell from rest (no copy of the samples; nothing to do for white noise).
    pub fn whiten(&self, mut series: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
        let [a, b] = self.theta;
        if self.theta == [0.0, 0.0] {
            return series;
        }
        for d in series.iter_mut() {
            let (mut v1, mut v2) = (0.0, 0.0);
            for y in d.iter_mut() {
                let v = *y - a * v1 - b * v2;
                (v2, v1) = (v1, v);
                *y = v;
            }
        }
        series
    }

    /// The density of the moving average at `f_hz` (samples `rate_hz` apart) over that of white noise of the
    /// same variance: `|1 + theta_1 e^(-i w) + theta_2 e^(-2 i w)|^2 / (1 + theta_1^2 + theta_2^2)`, `w = 2 pi
    /// f / rate`; dimensionless.
    pub fn relative_density(&self, f_hz: f64, rate_hz: f64) -> f64 {
        let [a, b] = self.theta;
        let w = std::f64::consts::TAU * f_hz / rate_hz;
        let re = 1.0 + a * w.cos() + b * (2.0 * w).cos();
        let im = a * w.sin() + b * (2.0 * w).sin();
        (re * re + im * im) / (1.0 + a * a + b * b)
    }

    /// The moving average's gain at zero frequency, `1 + theta_1 + theta_2`: a process slower than the
    /// filter is divided by it in the whitened series.
    pub fn gain(&self) -> f64 {
        1.0 + self.theta[0] + self.theta[1]
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::model::simulator::normal;

    /// `dwells` dwells of `len` samples of the moving average `theta` of unit white noise.
    fn moving_average(theta: [f64; 2], dwells: usize, len: usize, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..dwells)
            .map(|_| {
                let w: Vec<f64> = (0..len + 2).map(|_| normal(&mut rng)).collect();
                (2..len + 2).map(|i| w[i] + theta[0] * w[i - 1] + theta[1] * w[i - 2]).collect()
            })
            .collect()
    }

    #[test]
    fn a_moving_average_is_found_and_whitened() {
        let theta = [0.25, -0.12];
        let series = moving_average(theta, 20, 2000, 3);
        let c = SampleColour::of(&series);
        for k in 0..2 {
            assert!((c.theta[k] - theta[k]).abs() < 0.02, "theta {:?} against {theta:?}", c.theta);
        }
        let white = c.whiten(series.clone());
        let n: f64 = white.iter().map(|d| d.len() as f64).sum();
        let var = white.iter().flatten().map(|v| v * v).sum::<f64>() / n;
        for lag in 1..4 {
            let r = white.iter().map(|d| d.windows(lag + 1).map(|w| w[0] * w[lag]).sum::<f64>()).sum::<f64>() / n / var;
            assert!(r.abs() < 0.02, "lag {lag}: {r}");
        }
    }

    #[test]
    fn a_differenced_white_noise_is_no_filter_and_is_left_in_the_samples() {
        // The quantisation error of a counter that carries its remainder: w_t - w_(t-1), gain 0 at zero
        // frequency. Fitted, it sits at the edge of the invertible region; it is not removed.
        let series = moving_average([-1.0, 0.0], 10, 4000, 7);
        assert_eq!(SampleColour::of(&series), SampleColour::default());
        assert!(!SampleColour { theta: [0.17, 0.95] }.is_a_filter());
        assert!(!SampleColour { theta: [-0.24, -0.08] }.is_a_filter());
        assert!(SampleColour { theta: [0.25, -0.1] }.is_a_filter());
    }

    #[test]
    fn the_relative_density_averages_one_and_is_the_gain_squared_at_zero_frequency() {
        let c = SampleColour { theta: [0.25, -0.1] };
        let norm = 1.0 + 0.25 * 0.25 + 0.1 * 0.1;
        assert!((c.relative_density(0.0, 100.0) - c.gain().powi(2) / norm).abs() < 1e-12);
        let mean = (0..1000).map(|i| c.relative_density((i as f64 + 0.5) * 0.05, 100.0)).sum::<f64>() / 1000.0;
        assert!((mean - 1.0).abs() < 1e-9, "{mean}");
    }

    #[test]
    fn white_noise_keeps_its_colour_near_nothing() {
        let c = SampleColour::of(&moving_average([0.0, 0.0], 10, 4000, 5));
        assert!(c.theta.iter().all(|t| t.abs() < 0.02), "{:?}", c.theta);
        assert!((c.gain() - 1.0).abs() < 0.04);
    }

    #[test]
    fn a_slow_process_passes_with_the_gain_at_zero_frequency() {
        // A ramp (the slowest signal) beside the filtered noise, not through it: once whitened, its slope is
        // divided by the gain at zero frequency.
        let c = SampleColour { theta: [0.3, -0.1] };
        let ramp: Vec<f64> = (0..5000).map(|i| i as f64 * 1e-3).collect();
        let white = c.whiten(vec![ramp]);
        let slope = (white[0][4999] - white[0][4000]) / 999.0;
        assert!((slope * c.gain() - 1e-3).abs() < 1e-12, "{slope}");
    }
}
