//! Collection of one dwell (one turntable position): the prefilter bank and the per-channel statistics.
//!
//! Call rate: [`DwellCollector::update`] once per IMU sample (100 Hz), for the samples that belong to the
//! dwell; [`DwellCollector::summary`] once at its end. The collector keeps, per channel, the mean and
//! variance of the raw samples, the mean of the filtered samples (what the alignment consumes), the
//! filter's last state (the paper's "settled output"), and the octave Allan variance of the raw samples,
//! from which, with the prefilter's start term, [`MeanNoise`] gives the honest noise of the dwell mean
//! (docs/method.md#honest-errors); [`pool_mean_noise`] combines the dwells of one session.

use crate::calib::prefilter::{FixedGain, HmmKf, PrefilterError, PrefilterSettings};
use crate::math::accumulate::{BlockedSum, DwellStats, BLOCK_SAMPLES};
use crate::math::allan::OctaveAllan;
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

/// Octave levels of a dwell's Allan variance: cluster sizes `BLOCK_SAMPLES << j` samples, `j = 0..10`,
/// that is 64 to 32,768 samples (0.64 s to 328 s at 100 Hz). The levels start at the accumulators' block
/// of 64 samples, whose sums the collector has already formed, so that the Allan variance costs no work
/// per sample, only per block (docs/method.md#honest-errors says why); ten levels serve dwells up to 11
/// minutes, longer ones are extrapolated from 328 s.
pub const ALLAN_LEVELS: usize = 10;

/// Cluster size of the Allan level `level`, samples.
pub const fn allan_cluster_samples(level: usize) -> u32 {
    BLOCK_SAMPLES << level
}

/// Number of differences of adjacent clusters a dwell of `samples` samples has at Allan level `level` (0
/// beyond [`ALLAN_LEVELS`]): the collector feeds one value per complete block of [`BLOCK_SAMPLES`].
pub const fn allan_differences(samples: u32, level: usize) -> u32 {
    if level >= ALLAN_LEVELS {
        return 0;
    }
    ((samples / BLOCK_SAMPLES) >> level).saturating_sub(1)
}

/// The fewest differences of adjacent clusters an Allan level must rest on to be taken for
/// [`MeanNoise`] (per dwell and pooled); below it the longest level with any difference is taken, with
/// its few degrees of freedom. Chosen by simulation and on measured data (docs/method.md#honest-errors).
pub const MIN_ALLAN_DIFFERENCES: u32 = 16;

/// The noise of one channel's dwell mean, from the dwell's own Allan variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MeanNoise {
    /// White-equivalent sample variance q (unit of the channel squared): the dwell mean of N samples has variance q / N.
    /// From the Allan variance at the longest cluster size this dwell estimates well, times `1 + 2 / D` for
    /// the estimate's own noise (D differences), extrapolated as white noise beyond it. (Where `m AVAR(m)`
    /// measurably rises towards that cluster size, the rise is first carried on to the dwell length, at most
    /// 4-fold; the prefilter's start adds its part. docs/method.md#honest-errors.)
    pub white_equivalent_var: f32,
    /// Degrees of freedom of that estimate (number of cluster differences it rests on).
    pub dof: f32,
    /// Cluster size it was taken at, samples.
    pub cluster_samples: u32,
}

/// One channel's octave Allan variance over one dwell: what [`MeanNoise`] is taken from and what
/// [`pool_mean_noise`] pools.
///
/// It is the Allan variance of the **raw** samples, also when a prefilter runs. The mean of the filtered
/// dwell is exactly the raw mean plus a term from the filter's start and end
/// ([`HmmKf::start_transient_weight`]), so its noise is the raw mean's plus that term,
/// `prefilter_start_var`. The filtered samples themselves would count the start twice: the filter's
/// transient from the first sample lies in the first cluster of every level (measured on the PSINS
/// accelerometers, 6-s dwells: errors reported 1.5 to 1.7 times the scatter of the filtered dwell values),
/// and at the cluster sizes used (64 samples and more) the filter, with its DC gain of 1, leaves the Allan
/// variance otherwise unchanged.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DwellAllan {
    /// Allan variance at the cluster size [`allan_cluster_samples`]`(j)` (unit of the channel squared); 0
    /// where the dwell has no pair of clusters. The number of differences behind each entry is
    /// [`allan_differences`]`(samples, j)`.
    pub avar: [f32; ALLAN_LEVELS],
    /// Variance that the prefilter's start adds to the dwell mean (unit squared): `sigma^2 t / N^2` with
    /// `sigma` the raw sample standard deviation and `t` the filter's start weight
    /// ([`HmmKf::start_transient_weight`]); 0 without prefilter.
    pub prefilter_start_var: f32,
}

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
    /// Honest noise of each channel's mean (gyro x, y, z, accelerometer x, y, z).
    pub mean_noise: [MeanNoise; 6],
    /// Each channel's octave Allan variance over the dwell (gyro x, y, z, accelerometer x, y, z): the
    /// input of [`pool_mean_noise`].
    pub allan: [DwellAllan; 6],
}

/// Largest factor by which [`MeanNoise`] carries a rising white-equivalent variance on from the cluster
/// size to the dwell length (a factor 2 on the standard error).
pub const MAX_NOISE_GROWTH: f32 = 4.0;

/// The noise of a mean of `n` samples from octave Allan variances with their numbers of differences
/// (`levels`: Allan variance and differences per level), the white-noise fallback (per-sample variance
/// and its degrees of freedom) and the white-equivalent variance that the prefilter's start adds.
///
/// The rule (docs/method.md#honest-errors): take the longest level with at least
/// [`MIN_ALLAN_DIFFERENCES`] differences (otherwise the longest with any) and its white-equivalent
/// variance `q(m) = m AVAR(m)`, times `1 + 2 / D` (D its differences: with a variance estimated from D
/// differences the mean square of error / reported standard error is `D / (D - 2)` for white noise, not 1;
/// the factor makes up for it to first order). If `ln q` rises with the level over that level and the two
/// below it (weighted least squares, weights D/2, the rise more than twice its standard error), the rise is
/// carried on to `n` samples as a power law, by at most [`MAX_NOISE_GROWTH`]; a flat or falling curve is
/// extrapolated as white noise (conservative when it falls). Then the start term is added. Without any
/// difference (a dwell shorter than two blocks) the per-sample variance, as for white noise.
#[inline(never)]
fn mean_noise_from_levels(
    levels: &[(f32, f32); ALLAN_LEVELS],
    fallback: (f32, f32),
    start_q: f32,
    n: f32,
) -> MeanNoise {
    let pick = |min: f32| (0..ALLAN_LEVELS).rev().find(|&j| levels[j].1 >= min && levels[j].1 > 0.0);
    let Some(top) = pick(MIN_ALLAN_DIFFERENCES as f32).or_else(|| pick(1.0)) else {
        return MeanNoise { white_equivalent_var: fallback.0 + start_q, dof: fallback.1, cluster_samples: 1 };
    };
    let m = allan_cluster_samples(top);
    // Weighted straight line through (j, log2 q_j), q_j = m_j AVAR_j: var(ln q_j) is about 2 / D_j, so
    // var(log2 q_j) = 2 / (D_j ln^2 2).
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for j in top.saturating_sub(2)..=top {
        let (avar, d) = levels[j];
        if avar > 0.0 && d > 0.0 {
            let w = d * (core::f32::consts::LN_2 * core::f32::consts::LN_2 / 2.0);
            let (x, y) = (j as f32, log2_approx(allan_cluster_samples(j) as f32 * avar));
            sw += w;
            sx += w * x;
            sy += w * y;
            sxx += w * x * x;
            sxy += w * x * y;
        }
    }
    let det = sw * sxx - sx * sx;
    let mut growth = 1.0;
    if det > 0.0 {
        // Rise per octave of cluster size, in octaves of q; significant when above twice its standard
        // error sqrt(sw / det).
        let slope = (sw * sxy - sx * sy) / det;
        if slope > 0.0 && slope * slope * det > 4.0 * sw {
            let octaves = log2_approx(n / m as f32).max(0.0);
            growth = exp2_capped(slope * octaves);
        }
    }
    let (avar, d) = levels[top];
    MeanNoise { white_equivalent_var: m as f32 * avar * (1.0 + 2.0 / d) * growth + start_q, dof: d, cluster_samples: m }
}

/// `log2 x` for a positive normal `x`, within 3e-5: the exponent plus `2 / ln 2 (t + t^3/3 + t^5/5 + t^7/7)`,
/// `t = (f - 1) / (f + 1)` of the mantissa `f` in [1, 2) (|t| <= 1/3). Enough for a slope whose noise is
/// tenths; libm's `log2f` would bring its tables and double-precision code into the firmware.
fn log2_approx(x: f32) -> f32 {
    let bits = x.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32 - 127;
    let f = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let t = (f - 1.0) / (f + 1.0);
    let t2 = t * t;
    exponent as f32
        + (2.0 / core::f32::consts::LN_2) * t * (1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0))))
}

/// `min(2^y, MAX_NOISE_GROWTH)` for `y >= 0`, within 2e-5 relative (the Taylor series of `e^(y ln 2)` to
/// the sixth power on the fraction of `y`).
fn exp2_capped(y: f32) -> f32 {
    // MAX_NOISE_GROWTH is 4 = 2^2.
    if y.is_nan() || y >= 2.0 {
        return MAX_NOISE_GROWTH;
    }
    let (whole, a) =
        if y >= 1.0 { (2.0, (y - 1.0) * core::f32::consts::LN_2) } else { (1.0, y * core::f32::consts::LN_2) };
    whole * (1.0 + a * (1.0 + a * (0.5 + a * (1.0 / 6.0 + a * (1.0 / 24.0 + a * (1.0 / 120.0 + a * (1.0 / 720.0)))))))
}

/// Combines the dwells of one session, channel by channel (the same sensor in every dwell), into one
/// noise per channel: the Allan sums of every level are pooled over the dwells (each dwell's variance
/// weighted by its number of differences), then the rule of [`MeanNoise`] picks the level, so that a
/// level too thin in one short dwell can rest on all of them, and a rising curve is carried on to the
/// dwells' mean length. The prefilter's start term is the dwells' average white-equivalent one; the
/// white fallback pools the per-sample variances. No allocation; an empty session gives zeros.
pub fn pool_mean_noise(summaries: impl Iterator<Item = DwellSummary>) -> [MeanNoise; 6] {
    pool(summaries, true)
}

/// [`pool_mean_noise`] without the prefilter's start term: the pooled noise of the raw dwell mean, for a caller
/// that adds each dwell's own start term ([`DwellAllan::prefilter_start_var`]).
pub fn pool_raw_mean_noise(summaries: impl Iterator<Item = DwellSummary>) -> [MeanNoise; 6] {
    pool(summaries, false)
}

/// The pooling of [`pool_mean_noise`], with the dwells' average start term or without it.
fn pool(summaries: impl Iterator<Item = DwellSummary>, with_start: bool) -> [MeanNoise; 6] {
    let mut avar_sum = [[0.0f32; ALLAN_LEVELS]; 6];
    let mut diffs = [0u32; ALLAN_LEVELS];
    let mut var_sum = [0.0f32; 6];
    let mut start_q_sum = [0.0f32; 6];
    let (mut dof, mut dwells, mut samples) = (0u32, 0u32, 0.0f32);
    for s in summaries {
        let n = s.samples;
        samples += n as f32;
        for j in 0..ALLAN_LEVELS {
            let d = allan_differences(n, j);
            diffs[j] = diffs[j].saturating_add(d);
            for i in 0..6 {
                avar_sum[i][j] += d as f32 * s.allan[i].avar[j];
            }
        }
        let free = n.saturating_sub(1);
        dof = dof.saturating_add(free);
        dwells += 1;
        let std = [s.rate_sample_std_b_radps, s.force_sample_std_b_mps2];
        for i in 0..6 {
            let sigma = std[i / 3][i % 3];
            var_sum[i] += free as f32 * sigma * sigma;
            start_q_sum[i] += s.allan[i].prefilter_start_var * n as f32;
        }
    }
    core::array::from_fn(|i| {
        if dwells == 0 {
            return MeanNoise::default();
        }
        let levels = core::array::from_fn(|j| {
            let d = diffs[j] as f32;
            (if d > 0.0 { avar_sum[i][j] / d } else { 0.0 }, d)
        });
        let fallback = (if dof > 0 { var_sum[i] / dof as f32 } else { 0.0 }, dof as f32);
        let dwells = dwells as f32;
        let start_q = if with_start { start_q_sum[i] / dwells } else { 0.0 };
        mean_noise_from_levels(&levels, fallback, start_q, samples / dwells)
    })
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
    /// The prefilter's start weight, gyro and accelerometer ([`HmmKf::start_transient_weight`]); 0
    /// without prefilter.
    start_weight: [f32; 2],
    /// Octave Allan variance of the dwell-value series per channel, fed one block sum at a time.
    allan: [OctaveAllan<ALLAN_LEVELS>; 6],
}

impl DwellCollector {
    /// A collector with the given prefilter. The Riccati iteration runs here, once.
    pub fn new(prefilter: &Prefilter) -> Result<DwellCollector, PrefilterError> {
        let (gains, noise_gain, start_weight) = match prefilter {
            Prefilter::None => (None, [1.0, 1.0], [0.0, 0.0]),
            Prefilter::HmmKf { gyro, accel } => {
                let g = HmmKf::new(gyro)?;
                let a = HmmKf::new(accel)?;
                let noise = [g.impulse_response_sums().1, a.impulse_response_sums().1];
                let start = [g.start_transient_weight(), a.start_transient_weight()];
                (Some([g.fixed_gain(), a.fixed_gain()]), noise, start)
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
            start_weight,
            allan: [OctaveAllan::new(); 6],
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
        self.allan = [OctaveAllan::new(); 6];
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
            self.end_block();
        }
        Ok(())
    }

    /// The end of a block of [`BLOCK_SAMPLES`]: its sum of raw deviations goes to the Allan variance, and
    /// the blocked sums flush. Once per block, kept out of line so that the per-sample path stays small.
    #[inline(never)]
    fn end_block(&mut self) {
        for i in 0..6 {
            self.allan[i].add(self.raw_sum[i].block());
            self.raw_sum[i].flush();
            self.raw_sum_sq[i].flush();
            self.filtered_sum[i].flush();
        }
    }

    /// The summary of the dwell so far.
    #[inline(never)]
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
        let var = |i: usize| {
            DwellStats::shifted_variance(samples, self.raw_sum[i].value(), self.raw_sum_sq[i].value()).unwrap_or(0.0)
        };
        let std = |i: usize| libm::sqrtf(var(i));
        let n = samples as f32;
        let mut allan = [DwellAllan::default(); 6];
        let mut mean_noise = [MeanNoise::default(); 6];
        for i in 0..6 {
            let mut levels = [(0.0, 0.0); ALLAN_LEVELS];
            for j in 0..ALLAN_LEVELS {
                let avar = self.allan[i].allan_variance(j, BLOCK_SAMPLES).unwrap_or(0.0);
                allan[i].avar[j] = avar;
                levels[j] = (avar, allan_differences(samples, j) as f32);
            }
            let v = var(i);
            allan[i].prefilter_start_var = v * self.start_weight[i / 3] / n / n;
            mean_noise[i] = mean_noise_from_levels(&levels, (v, n - 1.0), allan[i].prefilter_start_var * n, n);
        }
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
            mean_noise,
            allan,
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

    /// A deterministic pseudo-random sequence, approximately standard normal (xorshift32, sum of 12 uniforms).
    fn normal(state: &mut u32) -> f32 {
        let mut s = 0.0;
        for _ in 0..12 {
            *state ^= *state << 13;
            *state ^= *state >> 17;
            *state ^= *state << 5;
            s += (*state as f64 / u32::MAX as f64) as f32;
        }
        s - 6.0
    }

    fn sample(z: [f32; 6]) -> ImuSample {
        ImuSample { rate_b_radps: [z[0], z[1], z[2]], force_b_mps2: [z[3], z[4], z[5]] }
    }

    #[test]
    fn allan_levels_are_those_of_the_raw_samples_with_and_without_prefilter() {
        // The levels equal the direct estimator over the complete blocks of the raw samples, with or without
        // prefilter. 100 blocks and 17 samples more (which the Allan levels do not use).
        let n = 64 * 100 + 17;
        let mut rng = 99u32;
        let xs: Vec<[f32; 6]> = (0..n)
            .map(|_| core::array::from_fn(|i| [1e-5, 2e-5, 7e-5, 0.1, -0.2, 9.8][i] + 1e-3 * normal(&mut rng)))
            .collect();
        for p in [Prefilter::None, Prefilter::paper()] {
            let mut c = DwellCollector::new(&p).unwrap();
            for z in &xs {
                c.update(&sample(*z)).unwrap();
            }
            let d = c.summary().unwrap();
            for i in 0..6 {
                for j in 0..ALLAN_LEVELS {
                    let m = allan_cluster_samples(j) as usize;
                    let means: Vec<f64> = xs[..6400]
                        .chunks_exact(m)
                        .map(|b| b.iter().map(|z| z[i] as f64).sum::<f64>() / m as f64)
                        .collect();
                    let diffs = means.len().saturating_sub(1);
                    assert_eq!(allan_differences(d.samples, j) as usize, diffs, "level {j}");
                    let want = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2 * diffs.max(1)) as f64;
                    let got = d.allan[i].avar[j] as f64;
                    assert!((got - want).abs() <= 1e-4 * want, "channel {i} level {j}: {got:e} vs {want:e}");
                }
                // 100 blocks: level 2 (256 samples) has 24 differences, level 3 has 11: level 2 is taken,
                // with the factor 1 + 2 / 24 for its estimate's noise.
                let noise = d.mean_noise[i];
                assert_eq!((noise.cluster_samples, noise.dof), (256, 24.0));
                let start = d.allan[i].prefilter_start_var;
                assert_eq!(start == 0.0, p == Prefilter::None);
                let q = 256.0 * d.allan[i].avar[2] * (1.0 + 2.0 / 24.0) + start * n as f32;
                assert!((noise.white_equivalent_var / q - 1.0).abs() < 1e-6, "{noise:?}");
            }
        }
    }

    #[test]
    fn constant_has_no_mean_noise_and_white_noise_its_variance() {
        let s = ImuSample { rate_b_radps: [1e-5, -2e-5, 7e-5], force_b_mps2: [0.01, -0.02, 9.8] };
        for p in [Prefilter::None, Prefilter::paper()] {
            let mut c = DwellCollector::new(&p).unwrap();
            for _ in 0..6000 {
                c.update(&s).unwrap();
            }
            let d = c.summary().unwrap();
            for m in d.mean_noise {
                assert_eq!((m.white_equivalent_var, m.dof, m.cluster_samples), (0.0, 22.0, 256));
            }
        }
        // White noise of variance 1: 30 dwells of 60 s pooled give q = 1 + 2 / 30 within the estimate's
        // scatter (2048-sample clusters, one difference per dwell: relative standard deviation 0.26), and the
        // prefilter's start adds its 207 / 6000 on top.
        for (p, start) in [(Prefilter::None, 0.0), (Prefilter::paper(), 207.1 / 6000.0)] {
            let mut rng = 5u32;
            let mut c = DwellCollector::new(&p).unwrap();
            let mut dwells = [None; 30];
            for dwell in dwells.iter_mut() {
                c.reset();
                for _ in 0..6000 {
                    c.update(&sample(core::array::from_fn(|_| normal(&mut rng)))).unwrap();
                }
                *dwell = Some(c.summary().unwrap());
            }
            let pooled = pool_mean_noise(dwells.iter().flatten().copied());
            let want = 1.0 + 2.0 / 30.0 + start;
            for m in pooled {
                assert_eq!((m.cluster_samples, m.dof), (2048, 30.0));
                assert!(m.white_equivalent_var > 0.0 && m.white_equivalent_var < 2.1 * want, "{m:?}");
            }
            // The six channels are independent: their average rests on 180 differences (0.105 relative).
            let average = pooled.iter().map(|m| m.white_equivalent_var).sum::<f32>() / 6.0;
            assert!((average / want - 1.0).abs() < 4.0 * (2.0f32 / 180.0).sqrt(), "{average} vs {want}");
        }
    }

    #[test]
    fn a_rising_curve_is_carried_on_to_the_dwell_length_and_a_falling_one_is_not() {
        // A random walk: m AVAR(m) grows as m^2, the rise is clear over 64..256 samples, and carried on
        // from 256 samples to the 6000 of the dwell it would be 550-fold: capped at 4. Differenced noise
        // (quantisation-like) falls as 1 / m: white extrapolation, q = 256 AVAR(256). Both with the factor
        // 1 + 2 / 22 of the level's 22 differences.
        let mut rng = 23u32;
        let (mut walk, mut previous) = ([0.0f32; 6], [0.0f32; 6]);
        let mut rising = DwellCollector::new(&Prefilter::None).unwrap();
        let mut falling = DwellCollector::new(&Prefilter::None).unwrap();
        for _ in 0..6000 {
            let e: [f32; 6] = core::array::from_fn(|_| normal(&mut rng));
            walk = core::array::from_fn(|i| walk[i] + 1e-3 * e[i]);
            rising.update(&sample(core::array::from_fn(|i| 9.8 + walk[i]))).unwrap();
            falling.update(&sample(core::array::from_fn(|i| e[i] - previous[i]))).unwrap();
            previous = e;
        }
        let (r, f) = (rising.summary().unwrap(), falling.summary().unwrap());
        for i in 0..6 {
            assert_eq!((r.mean_noise[i].cluster_samples, f.mean_noise[i].cluster_samples), (256, 256));
            let factor = 1.0 + 2.0 / 22.0;
            let q = r.mean_noise[i].white_equivalent_var / (256.0 * r.allan[i].avar[2] * factor);
            assert!((q / MAX_NOISE_GROWTH - 1.0).abs() < 1e-6, "{q}");
            let q = f.mean_noise[i].white_equivalent_var / (256.0 * f.allan[i].avar[2] * factor);
            assert!((q - 1.0).abs() < 1e-6, "{q}");
        }
    }

    #[test]
    fn a_thin_level_with_its_factor_keeps_white_noise_errors_honest() {
        // Sessions of sixteen 256-sample dwells of white noise of variance 1 (mean 0): pooled, level 1 has one
        // difference per dwell (16, the fewest taken), level 0 three (48). With a variance from 16 differences the
        // mean square of (dwell mean / reported standard error) is 16 / 14 = 1.14; the factor 1 + 2 / 16 brings
        // it to 1.02. 300 sessions, 6 channels: the mean square rests on 1800 variances (standard deviation
        // about 0.015).
        let mut rng = 41u32;
        let mut c = DwellCollector::new(&Prefilter::None).unwrap();
        let (mut sum_sq, mut count) = (0.0f64, 0.0f64);
        for _ in 0..300 {
            let mut dwells = [None; 16];
            for dwell in dwells.iter_mut() {
                c.reset();
                for _ in 0..256 {
                    c.update(&sample(core::array::from_fn(|_| normal(&mut rng)))).unwrap();
                }
                *dwell = Some(c.summary().unwrap());
            }
            let pooled = pool_mean_noise(dwells.iter().flatten().copied());
            for (i, m) in pooled.iter().enumerate() {
                assert_eq!((m.cluster_samples, m.dof), (128, 16.0));
                let var_of_mean = (m.white_equivalent_var / 256.0) as f64;
                for d in dwells.iter().flatten() {
                    let mean = if i < 3 { d.rate_mean_b_radps[i] } else { d.force_mean_b_mps2[i - 3] } as f64;
                    sum_sq += mean * mean / var_of_mean;
                    count += 1.0;
                }
            }
        }
        let mean_square = sum_sq / count;
        assert!((0.95..1.08).contains(&mean_square), "{mean_square}");
    }

    #[test]
    fn pooling_one_dwell_gives_its_own_noise_and_short_dwells_fall_back_to_white() {
        let mut rng = 17u32;
        let mut c = DwellCollector::new(&Prefilter::paper()).unwrap();
        for _ in 0..3000 {
            c.update(&sample(core::array::from_fn(|_| normal(&mut rng)))).unwrap();
        }
        let d = c.summary().unwrap();
        let pooled = pool_mean_noise(core::iter::once(d));
        for i in 0..6 {
            assert_eq!(pooled[i].cluster_samples, d.mean_noise[i].cluster_samples);
            assert_eq!(pooled[i].dof, d.mean_noise[i].dof);
            let rel = pooled[i].white_equivalent_var / d.mean_noise[i].white_equivalent_var - 1.0;
            assert!(rel.abs() < 1e-5, "{rel}");
        }
        assert_eq!(pool_mean_noise(core::iter::empty()), [MeanNoise::default(); 6]);
        // 100 samples: one block, no difference. The per-sample variance, as for white noise.
        c = DwellCollector::new(&Prefilter::None).unwrap();
        for _ in 0..100 {
            c.update(&sample(core::array::from_fn(|_| normal(&mut rng)))).unwrap();
        }
        let d = c.summary().unwrap();
        let sigma = d.rate_sample_std_b_radps[0];
        assert_eq!(d.mean_noise[0], MeanNoise { white_equivalent_var: sigma * sigma, dof: 99.0, cluster_samples: 1 });
    }

    #[test]
    fn the_compact_log2_and_exp2_are_accurate_enough() {
        let mut x = 1.0e-30f32;
        while x < 1.0e30 {
            assert!((log2_approx(x) - x.log2()).abs() < 3e-5, "{x}");
            x *= 1.37;
        }
        for k in 0..200 {
            let y = k as f32 * 0.01;
            assert!((exp2_capped(y) / y.exp2() - 1.0).abs() < 2e-5, "{y}");
        }
        assert_eq!((exp2_capped(2.0), exp2_capped(7.5), exp2_capped(f32::INFINITY)), (4.0, 4.0, 4.0));
    }

    #[test]
    fn short_dwell_is_an_error() {
        let mut c = DwellCollector::new(&Prefilter::None).unwrap();
        c.update(&ImuSample::default()).unwrap();
        assert_eq!(c.summary(), Err(DwellError::TooFewSamples { samples: 1 }));
    }
}
