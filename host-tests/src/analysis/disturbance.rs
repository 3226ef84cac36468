//! Disturbances (docs/analysis.md#disturbances): seconds in which a channel's noise stands far above its own
//! level, as a parked vehicle's gyros do when someone moves in it. They are a diagnostic, not an effect of the
//! catalogue: the analysis says where they are and how large, and that its noise terms include them. A
//! channel with a noise warm-up is tested after it has settled: the warm-up's blocks are its own.
//!
//! The test works on the logarithm of each block's sample variance (the noise warm-up's blocks,
//! [`samples_per_block`]: one second, within the dwells), each about its own straight line so that a process
//! slower than a block counts little. Each block is set against the channel's own level with robust
//! statistics: its distance from the median of the blocks over the spread of their lower half (the median
//! distance below the median, times 1.4826: the standard deviation of normal values). The disturbances, a
//! minority in the upper tail, move neither much. A block is disturbed when that distance passes the
//! one-sided normal quantile at `alpha / (m n)`, Bonferroni over the `n` blocks (and its square the BIC's
//! `ln n`), and its standard deviation is at least twice the median block's.

use crate::stats::linfit::{chi_square_quantile_upper, chi_square_upper};

use super::noise_warmup::{block_chunks, excess_in_quadrature, samples_per_block};

/// Fewest blocks for the test (the median and its deviation need a bulk).
const MIN_BLOCKS: usize = 20;
/// A disturbed block's standard deviation is at least this many times the median block's: the size that
/// makes a disturbance, beside the test (a process of a few seconds made a block pass the test alone; with
/// this, none did in the unit test's 30 seeds).
const MIN_RATIO: f64 = 2.0;
/// The normal standard deviation over the median distance of the lower half from the median (a quartile's).
const MAD_TO_SD: f64 = 1.4826;

/// One block: where it lies, its variance about its line (channel unit squared) and its robust distance.
#[derive(Clone, Copy, Debug)]
struct Block {
    /// Its dwell and its first sample there.
    dwell: usize,
    first: usize,
    /// Its first sample's time after the record's first sample, s.
    t_s: f64,
    variance: f64,
    z: f64,
}

/// A channel's blocks, in dwell order, and its level.
#[derive(Clone, Debug, Default)]
pub(super) struct BlockLevels {
    /// Samples per block.
    per_block: usize,
    /// Seconds per block.
    block_s: f64,
    /// The median of the blocks' variances (channel unit squared).
    median_variance: f64,
    blocks: Vec<Block>,
}

/// The disturbances at some level (a channel's diagnostic in the analysis JSON).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Disturbances {
    /// Disturbed blocks.
    pub blocks: usize,
    /// Runs of disturbed blocks (episodes).
    pub episodes: usize,
    /// Seconds disturbed (blocks times their length).
    pub disturbed_s: f64,
    /// Each episode's start and end, s after the record's first sample.
    pub episodes_s: Vec<[f64; 2]>,
    /// The standard deviation the disturbances add to the undisturbed noise (in quadrature), channel unit:
    /// `sqrt(mean variance of the disturbed blocks - mean of the others)`.
    pub excess: f64,
    /// Its standard error (channel unit).
    pub std_error: f64,
    /// The root of the mean block variance of the undisturbed blocks, channel unit.
    pub quiet_rms: f64,
    /// The largest block's one-sided p-value with the Bonferroni factor of the blocks.
    pub p_value: f64,
    /// Blocks tested.
    pub tested: usize,
}

impl BlockLevels {
    /// The blocks of each dwell's `series` (the samples less the dwell's mean and line), whose samples are at
    /// `t_s` (per dwell, the record's time; `t0_s` its first sample), `dt` s apart, that start at or after
    /// `from_s` after the first sample (where a noise warm-up has settled: its blocks are its own).
    pub fn measure(series: &[Vec<f64>], t_s: &[&[f64]], t0_s: f64, dt: f64, from_s: f64) -> BlockLevels {
        let per_block = samples_per_block(dt);
        let mut blocks: Vec<Block> = block_chunks(series, t_s, t0_s, dt)
            .filter(|&(_, _, t_s, _)| t_s >= from_s)
            .filter_map(|(dwell, first, t_s, chunk)| {
                let variance = variance_about_line(chunk);
                (variance > 0.0 && variance.is_finite()).then_some(Block { dwell, first, t_s, variance, z: 0.0 })
            })
            .collect();
        let mut median_variance = f64::INFINITY;
        if blocks.len() >= MIN_BLOCKS {
            let logs: Vec<f64> = blocks.iter().map(|b| b.variance.ln()).collect();
            let centre = median(logs.clone());
            median_variance = centre.exp();
            // The spread of the lower half (the distance of the lower quartile from the median over its
            // normal value): the disturbances, a minority in the upper tail, do not widen it.
            let lower: Vec<f64> = logs.iter().filter(|&&l| l <= centre).map(|l| centre - l).collect();
            let spread = MAD_TO_SD * median(lower);
            if spread > 0.0 {
                for (b, l) in blocks.iter_mut().zip(&logs) {
                    b.z = (l - centre) / spread;
                }
            }
        }
        BlockLevels { per_block, block_s: per_block as f64 * dt, median_variance, blocks }
    }

    /// The robust distance a block must pass at `p_value_limit` (alpha over the Bonferroni `m`); infinite
    /// with too few blocks.
    fn limit(&self, p_value_limit: f64) -> f64 {
        let n = self.blocks.len();
        if n < MIN_BLOCKS {
            return f64::INFINITY;
        }
        // One-sided: P(z > limit) = p / n, so P(z^2 > limit^2) = 2 p / n.
        let z2 = chi_square_quantile_upper((2.0 * p_value_limit / n as f64).min(1.0), 1.0);
        z2.max((n as f64).ln()).sqrt()
    }

    /// The disturbances that pass at `p_value_limit`; `None` when no block does. A block is disturbed when its
    /// robust distance passes the limit and its standard deviation is at least [`MIN_RATIO`] times the median
    /// block's.
    pub fn at(&self, p_value_limit: f64) -> Option<Disturbances> {
        let limit = self.limit(p_value_limit);
        let floor = MIN_RATIO * MIN_RATIO * self.median_variance;
        let disturbed: Vec<bool> = self.blocks.iter().map(|b| b.z > limit && b.variance >= floor).collect();
        let count = disturbed.iter().filter(|&&d| d).count();
        let (excess, std_error) = excess(&self.blocks, &disturbed, self.per_block)?;
        let mean_quiet = mean_of(&self.blocks, &disturbed, false).0;
        let mut episodes_s: Vec<[f64; 2]> = Vec::new();
        let mut previous: Option<&Block> = None;
        for (b, _) in self.blocks.iter().zip(&disturbed).filter(|(_, &d)| d) {
            let next_to = |p: &Block| p.dwell == b.dwell && p.first + self.per_block == b.first;
            match (previous.filter(|p| next_to(p)), episodes_s.last_mut()) {
                (Some(_), Some(last)) => last[1] = b.t_s + self.block_s,
                _ => episodes_s.push([b.t_s, b.t_s + self.block_s]),
            }
            previous = Some(b);
        }
        let z = self.blocks.iter().map(|b| b.z).fold(f64::MIN, f64::max);
        let n = self.blocks.len() as f64;
        Some(Disturbances {
            blocks: count,
            episodes: episodes_s.len(),
            disturbed_s: count as f64 * self.block_s,
            episodes_s,
            excess,
            std_error,
            quiet_rms: mean_quiet.sqrt(),
            p_value: (0.5 * chi_square_upper(z * z, 1.0) * n).min(1.0),
            tested: self.blocks.len(),
        })
    }
}

/// The mean variance of the `blocks` whose flag in `disturbed` is `want`, and the mean's variance from the
/// blocks' scatter.
fn mean_of(blocks: &[Block], disturbed: &[bool], want: bool) -> (f64, f64) {
    let v: Vec<f64> = blocks.iter().zip(disturbed).filter(|(_, &d)| d == want).map(|(b, _)| b.variance).collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let scatter = if v.len() > 1 { v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    (m, scatter / n)
}

/// The standard deviation the `disturbed` blocks add to the others' (in quadrature) and its standard error
/// (each mean's variance at least that of Gaussian blocks' variances, `2 v^2 / (samples - 1)` each, so that
/// one disturbed block still has one); `None` when either set is empty or the disturbed blocks' mean
/// variance is not the larger.
fn excess(blocks: &[Block], disturbed: &[bool], per_block: usize) -> Option<(f64, f64)> {
    let count = disturbed.iter().filter(|&&d| d).count();
    if count == 0 || count == blocks.len() {
        return None;
    }
    let (mean_disturbed, scatter_disturbed) = mean_of(blocks, disturbed, true);
    let (mean_quiet, scatter_quiet) = mean_of(blocks, disturbed, false);
    let gaussian = |m: f64, n: usize| 2.0 * m * m / (per_block as f64 - 1.0) / n as f64;
    let var_disturbed = scatter_disturbed.max(gaussian(mean_disturbed, count));
    let var_quiet = scatter_quiet.max(gaussian(mean_quiet, blocks.len() - count));
    excess_in_quadrature((mean_disturbed, var_disturbed), (mean_quiet, var_quiet))
}

/// The variance of `y` about its own straight line (least squares on the sample index, `n - 2` degrees of
/// freedom): a process slower than the block bends it little, so only noise within the block counts.
fn variance_about_line(y: &[f64]) -> f64 {
    let n = y.len() as f64;
    let (mean_i, mean_y) = ((n - 1.0) / 2.0, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in y.iter().enumerate() {
        let di = i as f64 - mean_i;
        sxy += di * (v - mean_y);
        sxx += di * di;
    }
    let slope = sxy / sxx;
    y.iter().enumerate().map(|(i, v)| (v - mean_y - slope * (i as f64 - mean_i)).powi(2)).sum::<f64>() / (n - 2.0)
}

/// The median of `x` (not empty).
fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::model::simulator::normal;

    /// `seconds` at 100 Hz of white noise of 1 and, when `bursts`, ten bursts of 5 s with a standard deviation
    /// of 4 (every 90 s from 20 s).
    fn record(seconds: usize, bursts: bool, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..seconds * 100)
            .map(|i| {
                let t = i as f64 / 100.0;
                let burst = bursts && t >= 20.0 && ((t - 20.0) % 90.0) < 5.0 && t < 20.0 + 90.0 * 10.0;
                normal(&mut rng) * if burst { 4.0 } else { 1.0 }
            })
            .collect()
    }

    /// The samples' times at 100 Hz, s.
    fn times(y: &[f64]) -> Vec<f64> {
        (0..y.len()).map(|i| i as f64 / 100.0).collect()
    }

    #[test]
    fn bursts_of_noise_are_found_and_stationary_noise_white_or_coloured_has_none() {
        let limit = 0.01 / 24.0;
        for seed in 0..5 {
            let y = record(900, true, seed);
            let d = BlockLevels::measure(std::slice::from_ref(&y), &[&times(&y)], 0.0, 0.01, 0.0);
            let found = d.at(limit).expect("bursts found");
            // Fifty disturbed seconds in ten episodes; a block that straddles a burst's edge may pass or not.
            assert!((50..=60).contains(&found.blocks), "seed {seed}: {found:?}");
            assert_eq!(found.episodes, 10, "seed {seed}: {found:?}");
            // Each episode within a block of its burst (20 s, then every 90 s, for 5 s).
            for (k, [from, to]) in found.episodes_s.iter().enumerate() {
                let burst = 20.0 + 90.0 * k as f64;
                assert!((from - burst).abs() <= 1.0 && (to - (burst + 5.0)).abs() <= 1.0, "seed {seed}: {found:?}");
            }
            assert!((found.disturbed_s - found.blocks as f64).abs() < 1e-9, "seed {seed}: one-second blocks");
            // Variance 16 against 1: an excess of sqrt(15) = 3.87.
            assert!((found.excess - 15f64.sqrt()).abs() < 3.0 * found.std_error + 0.3, "seed {seed}: {found:?}");
            assert!((found.quiet_rms - 1.0).abs() < 0.05, "seed {seed}: {found:?}");
        }
        for seed in 0..30 {
            let y = record(900, false, 100 + seed);
            let d = BlockLevels::measure(std::slice::from_ref(&y), &[&times(&y)], 0.0, 0.01, 0.0);
            assert_eq!(d.at(limit), None, "seed {seed}: white noise");
            // A Gauss-Markov process of 2 s (standard deviation 3) beside the white noise: its blocks' variances
            // scatter more, and the robust spread takes that from the bulk.
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
            let phi = (-0.01f64 / 2.0).exp();
            let mut x = 0.0;
            let coloured: Vec<f64> = y
                .iter()
                .map(|w| {
                    x = phi * x + 3.0 * (1.0 - phi * phi).sqrt() * normal(&mut rng);
                    x + w
                })
                .collect();
            let d = BlockLevels::measure(std::slice::from_ref(&coloured), &[&times(&coloured)], 0.0, 0.01, 0.0);
            assert_eq!(d.at(limit), None, "seed {seed}: coloured noise");
        }
    }
}
