//! Collection of one dwell (one turntable position): the prefilter bank and the per-channel statistics.
//!
//! Call rate: [`DwellCollector::update`] once per IMU sample (100 Hz), for the samples that belong to the
//! dwell; [`DwellCollector::summary`] once at its end. The collector keeps, per channel, the mean and
//! variance of the raw samples (the variance gives the standard errors), the mean of the filtered
//! samples (what the alignment consumes), and the filter's last state (the paper's "settled output").

use crate::calib::prefilter::{FixedGain, HmmKf, PrefilterError, PrefilterSettings};
use crate::math::accumulate::{BlockedSum, DwellStats, BLOCK_SAMPLES};
use crate::math::linalg::Vec3;
use crate::sensor::sample::ImuSample;

/// Which prefilter the collector runs in front of the statistics.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Prefilter {
    /// No prefilter: the dwell value is the plain mean of the raw samples.
    None,
    /// The HMM/KF of docs/method.md#step-1-prefilter with one setting for the three gyros and one for the accelerometers.
    HmmKf {
        /// Gyro channels, (rad/s)^2.
        gyro: PrefilterSettings,
        /// Accelerometer channels, (m/s^2)^2.
        accel: PrefilterSettings,
    },
}

impl Prefilter {
    /// The HMM/KF with the paper's Q and R and `a` = 1.
    pub fn paper() -> Prefilter {
        Prefilter::HmmKf { gyro: PrefilterSettings::paper_gyro(), accel: PrefilterSettings::paper_accel() }
    }
}

/// Why a dwell cannot be summarised, or a sample not used.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DwellError {
    /// Fewer samples than [`MIN_DWELL_SAMPLES`].
    TooFewSamples {
        /// Samples collected.
        samples: u32,
    },
    /// A sample had a NaN or infinite value; it was not used (counted in the summary).
    NotFinite,
}

impl core::fmt::Display for DwellError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DwellError::TooFewSamples { samples } => {
                write!(f, "dwell has {samples} samples, at least {MIN_DWELL_SAMPLES} are needed")
            }
            DwellError::NotFinite => f.write_str("sample is NaN or infinite"),
        }
    }
}

impl core::error::Error for DwellError {}

/// The smallest dwell the collector summarises (a variance needs some samples to mean anything).
pub const MIN_DWELL_SAMPLES: u32 = 10;

/// What one dwell gives the alignment, per channel (body frame).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DwellSummary {
    /// Samples used.
    pub samples: u32,
    /// Samples rejected as not finite.
    pub rejected: u32,
    /// Mean of the (prefiltered, if a prefilter runs) gyro channels, rad/s.
    pub rate_mean_b_radps: Vec3,
    /// Mean of the (prefiltered) accelerometer channels, m/s^2.
    pub force_mean_b_mps2: Vec3,
    /// Standard deviation of one raw gyro sample, rad/s.
    pub rate_sample_std_b_radps: Vec3,
    /// Standard deviation of one raw accelerometer sample, m/s^2.
    pub force_sample_std_b_mps2: Vec3,
    /// The prefilter's state after the last sample (the raw last sample without prefilter), rad/s.
    pub rate_settled_b_radps: Vec3,
    /// The prefilter's state after the last sample (the raw last sample without prefilter), m/s^2.
    pub force_settled_b_mps2: Vec3,
    /// Output variance of the settled prefilter per unit raw white-noise variance (sum of the squared
    /// impulse response): gyro and accelerometer. 1 without prefilter.
    pub settled_noise_gain: [f32; 2],
}

/// Whether all six values are finite, branch-free: `x - x` is +0 for every finite x and NaN for NaN and
/// the infinities, so the sum of the six differences is 0 exactly when all are finite (unlike a sum of the
/// values themselves, it cannot overflow).
#[inline(always)]
#[allow(clippy::eq_op, reason = "x - x is the finiteness test, not a mistake")]
fn all_finite(z: &[f32; 6]) -> bool {
    (z[0] - z[0]) + (z[1] - z[1]) + (z[2] - z[2]) + (z[3] - z[3]) + (z[4] - z[4]) + (z[5] - z[5]) == 0.0
}

/// The prefilter bank and statistics for the six channels of one dwell (gyro x, y, z, accel x, y, z).
///
/// Per channel: the shift (the dwell's first raw sample, which is also the filter's first output), blocked
/// sums of raw deviations and their squares, and of filtered deviations; the filter's state. The filter
/// constants are held once per sensor ([`FixedGain`]), the states channel by channel.
#[derive(Clone, Debug)]
pub struct DwellCollector {
    /// Gyro and accelerometer filter constants; `None` without prefilter.
    gains: Option<[FixedGain; 2]>,
    /// Filter states `[x_k, x_{k-1}]` per channel.
    state: [[f32; 2]; 6],
    /// The previous raw sample `z_{k-1}` per channel (with or without prefilter).
    previous_raw: [f32; 6],
    count: u32,
    shift: [f32; 6],
    raw_sum: [BlockedSum; 6],
    raw_sum_sq: [BlockedSum; 6],
    filtered_sum: [BlockedSum; 6],
    rejected: u32,
    noise_gain: [f32; 2],
}

impl DwellCollector {
    /// A collector with the given prefilter. The Riccati iteration runs here, once.
    pub fn new(prefilter: &Prefilter) -> Result<DwellCollector, PrefilterError> {
        let (gains, noise_gain) = match prefilter {
            Prefilter::None => (None, [1.0, 1.0]),
            Prefilter::HmmKf { gyro, accel } => {
                let g = HmmKf::new(gyro)?;
                let a = HmmKf::new(accel)?;
                let noise = [g.impulse_response_sums().1, a.impulse_response_sums().1];
                (Some([g.fixed_gain(), a.fixed_gain()]), noise)
            }
        };
        Ok(DwellCollector {
            gains,
            state: [[0.0; 2]; 6],
            previous_raw: [0.0; 6],
            count: 0,
            shift: [0.0; 6],
            raw_sum: [BlockedSum::new(); 6],
            raw_sum_sq: [BlockedSum::new(); 6],
            filtered_sum: [BlockedSum::new(); 6],
            rejected: 0,
            noise_gain,
        })
    }

    /// Output variance of the settled prefilter per unit raw white-noise variance, gyro and accelerometer
    /// (1 without prefilter).
    pub fn noise_gain(&self) -> [f32; 2] {
        self.noise_gain
    }

    /// Starts a new dwell: statistics cleared; the filters restart at the dwell's first sample.
    pub fn reset(&mut self) {
        self.count = 0;
        self.raw_sum = [BlockedSum::new(); 6];
        self.raw_sum_sq = [BlockedSum::new(); 6];
        self.filtered_sum = [BlockedSum::new(); 6];
        self.rejected = 0;
    }

    /// Samples used so far in this dwell.
    pub fn samples(&self) -> u32 {
        self.count
    }

    /// One channel with its filter: raw statistics, one fixed-gain step, filtered sum.
    #[inline(always)]
    fn filtered_channel(&mut self, i: usize, x: f32, gain: &FixedGain) {
        let d = x - self.shift[i];
        self.raw_sum[i].add(d);
        self.raw_sum_sq[i].add(d * d);
        let y = gain.step(&mut self.state[i], &mut self.previous_raw[i], x);
        self.filtered_sum[i].add(y - self.shift[i]);
    }

    /// Feeds one sample. A sample with a non-finite value is counted and not used.
    #[inline]
    pub fn update(&mut self, sample: &ImuSample) -> Result<(), DwellError> {
        let r = sample.rate_b_radps;
        let f = sample.force_b_mps2;
        let z = [r[0], r[1], r[2], f[0], f[1], f[2]];
        if !all_finite(&z) {
            self.rejected = self.rejected.saturating_add(1);
            return Err(DwellError::NotFinite);
        }
        if self.count == 0 {
            // The first sample: it is the shift, its deviations are zero, and it starts the filters.
            self.shift = z;
            self.state = z.map(|x| [x, x]);
            self.previous_raw = z;
            self.count = 1;
            return Ok(());
        }
        match self.gains {
            Some([gyro, accel]) => {
                // Written out channel by channel: constant indices are constant offsets, and the gains stay
                // in registers (a loop, which size optimisation keeps rolled, recomputes addresses).
                self.filtered_channel(0, z[0], &gyro);
                self.filtered_channel(1, z[1], &gyro);
                self.filtered_channel(2, z[2], &gyro);
                self.filtered_channel(3, z[3], &accel);
                self.filtered_channel(4, z[4], &accel);
                self.filtered_channel(5, z[5], &accel);
            }
            None => {
                for i in 0..6 {
                    let d = z[i] - self.shift[i];
                    self.raw_sum[i].add(d);
                    self.raw_sum_sq[i].add(d * d);
                }
                self.previous_raw = z;
            }
        }
        self.count += 1;
        if self.count % BLOCK_SAMPLES == 0 {
            for i in 0..6 {
                self.raw_sum[i].flush();
                self.raw_sum_sq[i].flush();
                self.filtered_sum[i].flush();
            }
        }
        Ok(())
    }

    /// The summary of the dwell so far.
    pub fn summary(&self) -> Result<DwellSummary, DwellError> {
        let samples = self.count;
        if samples < MIN_DWELL_SAMPLES {
            return Err(DwellError::TooFewSamples { samples });
        }
        let filtered = self.gains.is_some();
        let last = if filtered { self.state.map(|x| x[0]) } else { self.previous_raw };
        let mean = |i: usize| {
            let sum = if filtered { self.filtered_sum[i].value() } else { self.raw_sum[i].value() };
            DwellStats::shifted_mean(samples, self.shift[i], sum).unwrap_or(self.shift[i])
        };
        let std = |i: usize| {
            let var = DwellStats::shifted_variance(samples, self.raw_sum[i].value(), self.raw_sum_sq[i].value());
            libm::sqrtf(var.unwrap_or(0.0))
        };
        Ok(DwellSummary {
            samples,
            rejected: self.rejected,
            rate_mean_b_radps: [mean(0), mean(1), mean(2)],
            force_mean_b_mps2: [mean(3), mean(4), mean(5)],
            rate_sample_std_b_radps: [std(0), std(1), std(2)],
            force_sample_std_b_mps2: [std(3), std(4), std(5)],
            rate_settled_b_radps: [last[0], last[1], last[2]],
            force_settled_b_mps2: [last[3], last[4], last[5]],
            settled_noise_gain: self.noise_gain,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_input_gives_exact_means_with_and_without_prefilter() {
        let s = ImuSample { rate_b_radps: [1e-5, -2e-5, 7e-5], force_b_mps2: [0.01, -0.02, 9.8] };
        for p in [Prefilter::None, Prefilter::paper()] {
            let mut c = DwellCollector::new(&p).unwrap();
            for _ in 0..6000 {
                c.update(&s).unwrap();
            }
            let d = c.summary().unwrap();
            assert_eq!(d.samples, 6000);
            assert_eq!(d.rate_mean_b_radps, s.rate_b_radps);
            assert_eq!(d.force_mean_b_mps2, s.force_b_mps2);
            assert_eq!(d.force_settled_b_mps2, s.force_b_mps2);
            assert_eq!(d.rate_sample_std_b_radps, [0.0; 3]);
        }
    }

    #[test]
    fn non_finite_samples_are_counted_not_used() {
        let mut c = DwellCollector::new(&Prefilter::None).unwrap();
        let good = ImuSample { rate_b_radps: [0.0; 3], force_b_mps2: [0.0, 0.0, 9.8] };
        let bad = ImuSample { rate_b_radps: [f32::NAN, 0.0, 0.0], ..good };
        for _ in 0..20 {
            c.update(&good).unwrap();
        }
        assert_eq!(c.update(&bad), Err(DwellError::NotFinite));
        let d = c.summary().unwrap();
        assert_eq!((d.samples, d.rejected), (20, 1));
        assert_eq!(d.force_mean_b_mps2, [0.0, 0.0, 9.8]);
    }

    #[test]
    fn finiteness_test_catches_every_non_finite_value_and_no_finite_one() {
        let finite = [0.0, -0.0, 1.0, -1.0, f32::MAX, f32::MIN, f32::MIN_POSITIVE, 1e-45];
        for &x in &finite {
            for i in 0..6 {
                let mut z = [f32::MAX; 6];
                z[i] = x;
                assert!(all_finite(&z), "{x} at {i}");
                for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    z[i] = bad;
                    assert!(!all_finite(&z), "{bad} at {i}");
                }
            }
        }
    }

    #[test]
    fn short_dwell_is_an_error() {
        let mut c = DwellCollector::new(&Prefilter::None).unwrap();
        c.update(&ImuSample::default()).unwrap();
        assert_eq!(c.summary(), Err(DwellError::TooFewSamples { samples: 1 }));
    }
}
