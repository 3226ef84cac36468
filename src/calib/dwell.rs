//! Collection of one dwell (one turntable position): the prefilter bank and the per-channel statistics.
//!
//! Call rate: [`DwellCollector::update`] once per IMU sample (100 Hz), for the samples that belong to the
//! dwell; [`DwellCollector::summary`] once at its end. The collector gates spikes (docs/method.md#spikes)
//! and keeps, per channel, the mean and variance of the used raw samples (the dwell value the alignment
//! consumes), the filter's last state (the paper's "settled output"), and the octave Allan variance of the
//! raw samples, from which [`MeanNoise`] gives the honest noise of the dwell mean
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
    /// 4-fold. docs/method.md#honest-errors.)
    pub white_equivalent_var: f32,
    /// Degrees of freedom of that estimate (number of cluster differences it rests on).
    pub dof: f32,
    /// Cluster size it was taken at, samples.
    pub cluster_samples: u32,
}

/// One channel's octave Allan variance over one dwell: what [`MeanNoise`] is taken from and what
/// [`pool_mean_noise`] pools. It is the Allan variance of the used raw samples, also when a prefilter runs
/// (the dwell value is their mean).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DwellAllan {
    /// Allan variance at the cluster size [`allan_cluster_samples`]`(j)` (unit of the channel squared); 0
    /// where the dwell has no pair of clusters. The number of differences behind each entry is
    /// [`allan_differences`]`(samples, j)`.
    pub avar: [f32; ALLAN_LEVELS],
}

/// What one dwell gives the alignment, per channel (body frame).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DwellSummary {
    /// Samples used.
    pub samples: u32,
    /// Samples rejected as not finite.
    pub rejected: u32,
    /// Samples not used as spikes: some channel beyond the gate ([`GATE_WIDTH_SIGMA`]).
    pub spikes: u32,
    /// Mean of the used raw gyro samples, rad/s (with or without prefilter: the filtered mean without its
    /// boundary term).
    pub rate_mean_b_radps: Vec3,
    /// Mean of the used raw accelerometer samples, m/s^2.
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
/// (`levels`: Allan variance and differences per level) and the white-noise fallback (per-sample variance
/// and its degrees of freedom).
///
/// The rule (docs/method.md#honest-errors): take the longest level with at least
/// [`MIN_ALLAN_DIFFERENCES`] differences (otherwise the longest with any) and its white-equivalent
/// variance `q(m) = m AVAR(m)`, times `1 + 2 / D` (D its differences: with a variance estimated from D
/// differences the mean square of error / reported standard error is `D / (D - 2)` for white noise, not 1;
/// the factor makes up for it to first order). If `ln q` rises with the level over that level and the two
/// below it (weighted least squares, weights D/2, the rise more than twice its standard error), the rise is
/// carried on to `n` samples as a power law, by at most [`MAX_NOISE_GROWTH`]; a flat or falling curve is
/// extrapolated as white noise (conservative when it falls). Without any
/// difference (a dwell shorter than two blocks) the per-sample variance, as for white noise.
#[inline(never)]
fn mean_noise_from_levels(levels: &[(f32, f32); ALLAN_LEVELS], fallback: (f32, f32), n: f32) -> MeanNoise {
    let pick = |min: f32| (0..ALLAN_LEVELS).rev().find(|&j| levels[j].1 >= min && levels[j].1 > 0.0);
    let Some(top) = pick(MIN_ALLAN_DIFFERENCES as f32).or_else(|| pick(1.0)) else {
        return MeanNoise { white_equivalent_var: fallback.0, dof: fallback.1, cluster_samples: 1 };
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
    MeanNoise { white_equivalent_var: m as f32 * avar * (1.0 + 2.0 / d) * growth, dof: d, cluster_samples: m }
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
/// dwells' mean length. The white fallback pools the per-sample variances. No allocation; an empty session
/// gives zeros.
pub fn pool_mean_noise(summaries: impl Iterator<Item = DwellSummary>) -> [MeanNoise; 6] {
    let mut avar_sum = [[0.0f32; ALLAN_LEVELS]; 6];
    let mut diffs = [0u32; ALLAN_LEVELS];
    let mut var_sum = [0.0f32; 6];
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
        mean_noise_from_levels(&levels, fallback, samples / dwells as f32)
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

/// Samples a dwell starts with before its spike gate opens (one block): their median per channel is the
/// dwell's level (and the shift of its sums), their spread the gate's first width (docs/method.md#spikes).
pub const GATE_START_SAMPLES: usize = BLOCK_SAMPLES as usize;

/// Least width of the spike gate in standard deviations of one sample: a sample of any channel further than
/// the gate's width from the dwell's level is a spike, not used and counted. Wide enough for the heavy tails
/// of real sensors (a ring-laser gyro's samples reach 18 standard deviations in 30,000, docs/method.md#spikes;
/// Gaussian noise never reaches it); a spike just inside moves a dwell mean of `N` white-noise samples by at
/// most `20 / sqrt(N)` of its standard error (0.8 for a 6-s dwell at 100 Hz, 0.26 for 60 s).
pub const GATE_WIDTH_SIGMA: f32 = 20.0;

/// The gate widens with the samples used, `n`, to [`GATE_GROWTH`]` sqrt(n)` standard deviations where that is
/// more than [`GATE_WIDTH_SIGMA`] (beyond 6,400 samples): a sample just inside still moves the mean by at most
/// a quarter of its standard error, and longer dwells, which reach further into a heavy tail, keep it.
pub const GATE_GROWTH: f32 = 0.25;

/// Largest deviations left out of the gate's first width: up to this many spikes among the held samples do
/// not widen it.
const GATE_START_TRIMMED: usize = 4;

/// Samples beyond the gate, each within [`GATE_RUN_WINDOW`] samples of the last, that are not spikes but a
/// level that moved (a dwell that is not static, a disturbance): the gate opens for the rest of the dwell,
/// and they are used and not counted as spikes.
pub const GATE_RUN_MAX: u32 = 3;

/// Used samples after which the samples held beyond the gate were spikes (isolated, not a run).
pub const GATE_RUN_WINDOW: u32 = 8;

/// The gate's width while the dwell's first samples are held: negative, so that every sample takes the
/// out-of-line path that holds it (the per-sample path tests nothing else).
const GATE_CLOSED: f32 = -1.0;

/// Median of the held values and the root mean square of their deviations from it without the
/// [`GATE_START_TRIMMED`] largest: the dwell's level and a first width of its noise (for Gaussian noise 0.9
/// of its standard deviation). A width of 0 (a constant or coarsely quantised start) means "not known yet".
/// A dwell that ends before its gate opened holds fewer values: then one is left out per 16.
fn robust_level(values: &[f32]) -> (f32, f32) {
    let n = values.len().min(GATE_START_SAMPLES);
    let mut v = [0.0f32; GATE_START_SAMPLES];
    v[..n].copy_from_slice(&values[..n]);
    let half = n / 2;
    let upper = select(&mut v[..n], half);
    // The middle values: `select` left the lower half below `half`; its largest is the lower middle value.
    let lower = if n % 2 == 0 { v[..half].iter().fold(f32::NEG_INFINITY, |m, &x| m.max(x)) } else { upper };
    let median = 0.5 * (lower + upper);
    let mut dev = [0.0f32; GATE_START_SAMPLES];
    for k in 0..n {
        dev[k] = (values[k] - median).abs();
    }
    let kept = n - n * GATE_START_TRIMMED / GATE_START_SAMPLES;
    if kept < n {
        select(&mut dev[..n], kept);
    }
    let sum_sq: f32 = dev[..kept].iter().map(|d| d * d).sum();
    (median, libm::sqrtf(sum_sq / kept.max(1) as f32))
}

/// Hoare's selection: reorders `v` so that `v[k]` is the value a sort would put there, every value before it
/// no larger and every value after it no smaller; returns `v[k]`. NaN-free input (the collector refuses
/// non-finite samples before); expected time linear, no allocation.
fn select(v: &mut [f32], k: usize) -> f32 {
    let (mut lo, mut hi) = (0usize, v.len() - 1);
    while lo < hi {
        let pivot = v[lo + (hi - lo) / 2];
        let (mut i, mut j) = (lo, hi);
        while i <= j {
            while v[i] < pivot {
                i += 1;
            }
            while v[j] > pivot {
                j -= 1;
            }
            if i <= j {
                v.swap(i, j);
                i += 1;
                if j == 0 {
                    break;
                }
                j -= 1;
            }
        }
        if k <= j {
            hi = j;
        } else if k >= i {
            lo = i;
        } else {
            break;
        }
    }
    v[k]
}

/// The prefilter bank and statistics for the six channels of one dwell (gyro x, y, z, accel x, y, z).
///
/// A dwell starts by holding its first [`GATE_START_SAMPLES`] samples; their median per channel is the
/// shift of the sums (and where the filters start), their spread the first width of the spike gate. From
/// then on, per sample: a sample any of whose channels lies further than the gate's width (at least
/// [`GATE_WIDTH_SIGMA`] standard deviations) from that median is a spike (not used, counted); otherwise, per
/// channel, blocked sums of raw deviations and their squares, and the filter's state. The width follows the
/// used samples at every block end; a level that moves further than the gate is a run, which opens it. The
/// dwell value is the mean of the used raw samples: the mean of the filtered samples is that mean plus a
/// boundary term of the filter's start and end (docs/method.md#step-1-prefilter), which would make the dwell
/// value depend on where the dwell starts. The filter constants are held once per
/// sensor ([`FixedGain`]), the states channel by channel.
#[derive(Clone, Debug)]
pub struct DwellCollector {
    /// Gyro and accelerometer filter constants; `None` without prefilter.
    gains: Option<[FixedGain; 2]>,
    /// Filter states `[x_k, x_{k-1}]` per channel.
    state: [[f32; 2]; 6],
    /// The previous used raw sample `z_{k-1}` per channel (with or without prefilter).
    previous_raw: [f32; 6],
    /// The dwell's first samples, held until the gate opens.
    start: [[f32; 6]; GATE_START_SAMPLES],
    /// Samples held in `start`.
    held: usize,
    count: u32,
    shift: [f32; 6],
    raw_sum: [BlockedSum; 6],
    raw_sum_sq: [BlockedSum; 6],
    /// The gate's half width per channel (infinite while the noise is not known, [`GATE_CLOSED`] while the
    /// dwell's first samples are held).
    gate: [f32; 6],
    rejected: u32,
    spikes: u32,
    /// Samples beyond the gate with fewer than [`GATE_RUN_WINDOW`] used ones between them.
    run: u32,
    /// Samples used when the last one beyond the gate came.
    last_beyond: u32,
    /// Those samples, held until the run ends or reaches [`GATE_RUN_MAX`].
    pending: [[f32; 6]; GATE_RUN_MAX as usize],
    /// The gate opened for the rest of the dwell ([`GATE_RUN_MAX`]).
    open: bool,
    noise_gain: [f32; 2],
    /// Octave Allan variance of the dwell-value series per channel, fed one block sum at a time.
    allan: [OctaveAllan<ALLAN_LEVELS>; 6],
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
            start: [[0.0; 6]; GATE_START_SAMPLES],
            held: 0,
            count: 0,
            shift: [0.0; 6],
            raw_sum: [BlockedSum::new(); 6],
            raw_sum_sq: [BlockedSum::new(); 6],
            gate: [GATE_CLOSED; 6],
            rejected: 0,
            spikes: 0,
            run: 0,
            last_beyond: 0,
            pending: [[0.0; 6]; GATE_RUN_MAX as usize],
            open: false,
            noise_gain,
            allan: [OctaveAllan::new(); 6],
        })
    }

    /// Output variance of the settled prefilter per unit raw white-noise variance, gyro and accelerometer
    /// (1 without prefilter).
    pub fn noise_gain(&self) -> [f32; 2] {
        self.noise_gain
    }

    /// Starts a new dwell: statistics cleared; the gate closes until the dwell's first samples are held.
    pub fn reset(&mut self) {
        self.held = 0;
        self.count = 0;
        self.raw_sum = [BlockedSum::new(); 6];
        self.raw_sum_sq = [BlockedSum::new(); 6];
        self.gate = [GATE_CLOSED; 6];
        self.rejected = 0;
        self.spikes = 0;
        self.run = 0;
        self.last_beyond = 0;
        self.open = false;
        self.allan = [OctaveAllan::new(); 6];
    }

    /// Samples used so far in this dwell (held ones included).
    pub fn samples(&self) -> u32 {
        if self.held < GATE_START_SAMPLES {
            self.held as u32
        } else {
            self.count
        }
    }

    /// Samples of this dwell not used as spikes so far.
    pub fn spikes(&self) -> u32 {
        self.spikes
    }

    /// Feeds one sample. A sample with a non-finite value is counted and not used (an error); a spike is
    /// counted and not used (not an error: the dwell goes on).
    #[inline]
    pub fn update(&mut self, sample: &ImuSample) -> Result<(), DwellError> {
        let r = sample.rate_b_radps;
        let f = sample.force_b_mps2;
        let z = [r[0], r[1], r[2], f[0], f[1], f[2]];
        if !all_finite(&z) {
            self.rejected = self.rejected.saturating_add(1);
            return Err(DwellError::NotFinite);
        }
        // While the dwell's first samples are held the gate is closed (a negative width): every sample goes to
        // the out-of-line path, which holds it.
        self.gated(&z);
        Ok(())
    }

    /// The dwell's first samples are all held: level, shift and first width from them; filters started at the
    /// level; then the held samples go through the gate like any other. Once per dwell, out of line.
    #[inline(never)]
    fn open_gate(&mut self) {
        let held = self.held;
        for i in 0..6 {
            let mut column = [0.0f32; GATE_START_SAMPLES];
            for k in 0..held {
                column[k] = self.start[k][i];
            }
            let (median, width) = robust_level(&column[..held]);
            self.shift[i] = median;
            self.state[i] = [median, median];
            self.previous_raw[i] = median;
            self.gate[i] = if width > 0.0 { GATE_WIDTH_SIGMA * width } else { f32::INFINITY };
        }
        self.held = GATE_START_SAMPLES;
        for k in 0..held {
            let z = self.start[k];
            self.gated(&z);
        }
    }

    /// One sample through the gate: counted as a spike, or used. Written out channel by channel, with `|` (no
    /// short circuit) over the six tests: size optimisation keeps loops rolled and recomputes their addresses
    /// (docs/firmware.md: the per-sample budget).
    #[inline(always)]
    fn gated(&mut self, z: &[f32; 6]) {
        let (s, g) = (&self.shift, &self.gate);
        let d = [z[0] - s[0], z[1] - s[1], z[2] - s[2], z[3] - s[3], z[4] - s[4], z[5] - s[5]];
        let beyond = (d[0].abs() > g[0])
            | (d[1].abs() > g[1])
            | (d[2].abs() > g[2])
            | (d[3].abs() > g[3])
            | (d[4].abs() > g[4])
            | (d[5].abs() > g[5]);
        if beyond {
            self.beyond_gate(z);
            return;
        }
        self.used(z, &d);
    }

    /// A sample beyond the gate, or any while the gate is closed (held for its start). Beyond the open gate: a
    /// spike, held until the run of such samples says otherwise. Samples beyond the gate each within
    /// [`GATE_RUN_WINDOW`] used samples of the last are a run; a run of [`GATE_RUN_MAX`] is not spikes but a
    /// level that moved: the gate opens for the rest of the dwell and the held samples are used after all, so that
    /// nothing is lost. Out of line: rare.
    #[inline(never)]
    fn beyond_gate(&mut self, z: &[f32; 6]) {
        if self.held < GATE_START_SAMPLES {
            self.start[self.held] = *z;
            self.held += 1;
            if self.held == GATE_START_SAMPLES {
                self.open_gate();
            }
            return;
        }
        if self.run != 0 && self.count.wrapping_sub(self.last_beyond) >= GATE_RUN_WINDOW {
            // The samples held before were isolated: spikes.
            self.run = 0;
        }
        self.spikes = self.spikes.saturating_add(1);
        self.pending[self.run as usize] = *z;
        self.run += 1;
        self.last_beyond = self.count;
        if self.run >= GATE_RUN_MAX {
            self.spikes -= self.run;
            self.gate = [f32::INFINITY; 6];
            self.open = true;
            for k in 0..self.run as usize {
                let z = self.pending[k];
                let d: [f32; 6] = core::array::from_fn(|i| z[i] - self.shift[i]);
                self.used(&z, &d);
            }
            self.run = 0;
        }
    }

    /// A used sample `z` (`d` its deviation from the shift): sums, filter, block.
    #[inline(always)]
    fn used(&mut self, z: &[f32; 6], d: &[f32; 6]) {
        let (sum, sq) = (&mut self.raw_sum, &mut self.raw_sum_sq);
        sum[0].add(d[0]);
        sq[0].add(d[0] * d[0]);
        sum[1].add(d[1]);
        sq[1].add(d[1] * d[1]);
        sum[2].add(d[2]);
        sq[2].add(d[2] * d[2]);
        sum[3].add(d[3]);
        sq[3].add(d[3] * d[3]);
        sum[4].add(d[4]);
        sq[4].add(d[4] * d[4]);
        sum[5].add(d[5]);
        sq[5].add(d[5] * d[5]);
        match self.gains {
            Some([gyro, accel]) => {
                // Written out channel by channel: constant indices are constant offsets, and the gains stay
                // in registers (a loop, which size optimisation keeps rolled, recomputes addresses).
                gyro.step(&mut self.state[0], &mut self.previous_raw[0], z[0]);
                gyro.step(&mut self.state[1], &mut self.previous_raw[1], z[1]);
                gyro.step(&mut self.state[2], &mut self.previous_raw[2], z[2]);
                accel.step(&mut self.state[3], &mut self.previous_raw[3], z[3]);
                accel.step(&mut self.state[4], &mut self.previous_raw[4], z[4]);
                accel.step(&mut self.state[5], &mut self.previous_raw[5], z[5]);
            }
            None => self.previous_raw = *z,
        }
        self.count += 1;
        if self.count % BLOCK_SAMPLES == 0 {
            self.end_block();
        }
    }

    /// The end of a block of [`BLOCK_SAMPLES`]: its sum of raw deviations goes to the Allan variance, the
    /// blocked sums flush, and the gate's width follows the used samples' standard deviation. Once per block,
    /// kept out of line so that the per-sample path stays small.
    #[inline(never)]
    fn end_block(&mut self) {
        for i in 0..6 {
            self.allan[i].add(self.raw_sum[i].block());
            self.raw_sum[i].flush();
            self.raw_sum_sq[i].flush();
            let (sum, sum_sq) = (self.raw_sum[i].value(), self.raw_sum_sq[i].value());
            let var = DwellStats::shifted_variance(self.count, sum, sum_sq).unwrap_or(0.0);
            if var > 0.0 && !self.open {
                let width = GATE_WIDTH_SIGMA.max(GATE_GROWTH * libm::sqrtf(self.count as f32));
                self.gate[i] = width * libm::sqrtf(var);
            }
        }
    }

    /// The summary of the dwell so far.
    #[inline(never)]
    pub fn summary(&self) -> Result<DwellSummary, DwellError> {
        if self.held < GATE_START_SAMPLES {
            // A dwell shorter than the gate's start: its held samples through the gate, on a copy.
            if self.held < MIN_DWELL_SAMPLES as usize {
                return Err(DwellError::TooFewSamples { samples: self.samples() });
            }
            let mut opened = self.clone();
            opened.open_gate();
            return opened.summary();
        }
        let samples = self.count;
        if samples < MIN_DWELL_SAMPLES {
            return Err(DwellError::TooFewSamples { samples });
        }
        let filtered = self.gains.is_some();
        let last = if filtered { self.state.map(|x| x[0]) } else { self.previous_raw };
        let mean = |i: usize| {
            DwellStats::shifted_mean(samples, self.shift[i], self.raw_sum[i].value()).unwrap_or(self.shift[i])
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
            mean_noise[i] = mean_noise_from_levels(&levels, (var(i), n - 1.0), n);
        }
        Ok(DwellSummary {
            samples,
            rejected: self.rejected,
            spikes: self.spikes,
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
                let q = 256.0 * d.allan[i].avar[2] * (1.0 + 2.0 / 24.0);
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
        // scatter (2048-sample clusters, one difference per dwell: relative standard deviation 0.26), with or
        // without prefilter (the dwell value is the raw mean either way).
        for p in [Prefilter::None, Prefilter::paper()] {
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
            let want = 1.0 + 2.0 / 30.0;
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
        assert_eq!((d.mean_noise[0].dof, d.mean_noise[0].cluster_samples), (99.0, 1));
        assert!((d.mean_noise[0].white_equivalent_var / (sigma * sigma) - 1.0).abs() < 1e-6);
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

    /// A dwell of white noise (standard deviation 1e-3 on every channel), with `spike` added to channel
    /// `channel` of sample `at`; its summary.
    fn dwell_with_spike(p: &Prefilter, n: usize, at: usize, channel: usize, spike: f32) -> DwellSummary {
        let mut rng = 7u32;
        let mut c = DwellCollector::new(p).unwrap();
        for k in 0..n {
            let mut z: [f32; 6] =
                core::array::from_fn(|i| [1e-5, 2e-5, 7e-5, 0.1, -0.2, 9.8][i] + 1e-3 * normal(&mut rng));
            if k == at {
                z[channel] += spike;
            }
            c.update(&sample(z)).unwrap();
        }
        c.summary().unwrap()
    }

    #[test]
    fn one_spike_anywhere_is_not_used_and_counted() {
        // 600 samples (6 s at 100 Hz): the standard error of the mean is 1e-3 / sqrt(600) = 4.1e-5. A spike of
        // 0.03 (30 sigma) or 35 (a gyro's range in rad/s) at the first sample, inside the held block, at its
        // end and later: one spike, 599 samples, every mean within 0.1 standard error of the clean dwell's.
        for p in [Prefilter::None, Prefilter::paper()] {
            let clean = dwell_with_spike(&p, 600, usize::MAX, 0, 0.0);
            assert_eq!((clean.samples, clean.spikes), (600, 0));
            for at in [0, 1, 17, 63, 64, 65, 300, 599] {
                for (channel, spike) in [(0, 0.03), (0, -35.0), (4, 0.03), (5, 150.0)] {
                    let d = dwell_with_spike(&p, 600, at, channel, spike);
                    assert_eq!((d.samples, d.spikes), (599, 1), "at {at} channel {channel} {spike}");
                    for i in 0..3 {
                        let dr = (d.rate_mean_b_radps[i] - clean.rate_mean_b_radps[i]).abs();
                        let df = (d.force_mean_b_mps2[i] - clean.force_mean_b_mps2[i]).abs();
                        assert!(dr < 0.1 * 4.1e-5 && df < 0.1 * 4.1e-5, "at {at}: {dr:e} {df:e}");
                        let ratio = d.force_sample_std_b_mps2[i] / clean.force_sample_std_b_mps2[i];
                        assert!((ratio - 1.0).abs() < 0.05, "at {at}: std ratio {ratio}");
                    }
                }
            }
        }
    }

    #[test]
    fn noise_alone_is_never_a_spike_and_a_moved_level_opens_the_gate() {
        // 200 dwells of 3000 samples of white noise: no spike.
        let mut rng = 3u32;
        let mut c = DwellCollector::new(&Prefilter::paper()).unwrap();
        for _ in 0..200 {
            c.reset();
            for _ in 0..3000 {
                c.update(&sample(core::array::from_fn(|_| normal(&mut rng)))).unwrap();
            }
            assert_eq!(c.summary().unwrap().spikes, 0);
        }
        // A step of 50 sigma after 1000 samples is not a spike: after GATE_RUN_MAX samples beyond the gate, the
        // gate opens; those samples are used after all, and not counted.
        c.reset();
        for k in 0..3000 {
            let step = if k >= 1000 { 50.0 } else { 0.0 };
            c.update(&sample(core::array::from_fn(|_| step + normal(&mut rng)))).unwrap();
        }
        let d = c.summary().unwrap();
        assert_eq!((d.samples, d.spikes), (3000, 0));
    }

    #[test]
    fn the_dwell_value_does_not_depend_on_the_prefilter_or_where_the_dwell_starts() {
        // The same samples with and without prefilter give the same mean (the raw mean of the used samples); a
        // dwell started k samples later differs by exactly the k samples left out.
        let mut rng = 11u32;
        let xs: Vec<[f32; 6]> =
            (0..3000).map(|_| core::array::from_fn(|i| 9.8 * (i / 5) as f32 + normal(&mut rng))).collect();
        let mean_of = |p: &Prefilter, from: usize| {
            let mut c = DwellCollector::new(p).unwrap();
            for z in &xs[from..] {
                c.update(&sample(*z)).unwrap();
            }
            c.summary().unwrap()
        };
        for k in 0..=5 {
            let (none, kf) = (mean_of(&Prefilter::None, k), mean_of(&Prefilter::paper(), k));
            for i in 0..3 {
                let want: f64 = xs[k..].iter().map(|z| z[i] as f64).sum::<f64>() / (3000 - k) as f64;
                assert!((none.rate_mean_b_radps[i] as f64 - want).abs() < 1e-5, "k {k}");
                assert!((kf.rate_mean_b_radps[i] - none.rate_mean_b_radps[i]).abs() <= 1e-6, "k {k}");
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
