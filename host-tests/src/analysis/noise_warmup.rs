//! The noise's own warm-up (docs/analysis.md#noise-warm-up): a channel whose noise is larger at the start of
//! the record than after it, as a ring-laser gyro's is in its first minutes. The correlated noise describes the
//! settled instrument, so it is fitted on the samples after the noise has settled; an estimate that mixed the
//! two would differ from one window of the record to the next.
//!
//! The test works on the logarithm of each block's sample variance (blocks of one second, at least
//! [`MIN_BLOCK_SAMPLES`] samples, within the dwells, in the record's time). The blocks before a time `T` are
//! set against those after it: the difference of their means over its standard error, each mean's variance
//! by Newey-West (Bartlett weights), so that noise bursts lasting many blocks do not pass as a step. `T` runs
//! over a grid of [`GRID`] times from [`FIRST_S`] after the start to half of what is left, and the test is
//! Bonferroni over the grid. Once a step passes, the test runs again on the blocks after it: the noise has
//! settled at the last step that passes.

use crate::stats::linfit::chi_square_upper;

/// Times tested per step.
const GRID: usize = 12;
/// The shortest warm-up tested, s.
const FIRST_S: f64 = 20.0;
/// Fewest blocks on either side of a step.
const MIN_SIDE_BLOCKS: usize = 10;
/// Fewest samples in a block (a block is one second, or this many samples when a second has fewer).
const MIN_BLOCK_SAMPLES: usize = 20;

/// One block: its time since the record's first sample (of its first sample, s) and its samples' variance
/// about their mean (channel unit squared).
#[derive(Clone, Copy, Debug)]
struct Block {
    t_s: f64,
    variance: f64,
}

/// One step of the noise level that passed: the time it ends, and its statistic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Step {
    /// Time since the record's first sample after which the level is lower, s.
    pub settled_s: f64,
    /// The one-sided statistic: the difference of the mean log-variances before and after over its standard
    /// error.
    pub z: f64,
    /// Times tested for this step (its Bonferroni factor).
    pub tested: usize,
    /// Blocks it was tested on.
    pub blocks: usize,
}

impl Step {
    /// One-sided p-value times the times tested.
    pub fn p_value(&self) -> f64 {
        (0.5 * chi_square_upper(self.z * self.z, 1.0) * self.tested as f64).min(1.0)
    }

    /// It passes at `p_value_limit` (alpha over the Bonferroni `m`) and lowers the BIC (two parameters, a time
    /// and a level, over the blocks it was tested on).
    fn passes(&self, p_value_limit: f64) -> bool {
        self.p_value() <= p_value_limit && self.z * self.z > 2.0 * (self.blocks as f64).ln()
    }
}

/// A channel's noise warm-up: the steps that pass at the level the search was run at, in time order, and
/// the blocks' variances to estimate its size at any of them.
#[derive(Clone, Debug, Default)]
pub(super) struct NoiseWarmup {
    steps: Vec<Step>,
    blocks: Vec<Block>,
}

/// The size of a noise warm-up settled at some time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Size {
    /// Time since the record's first sample at which the noise has settled, s.
    pub settled_s: f64,
    /// The standard deviation the warm-up adds to the settled noise (in quadrature), channel unit:
    /// `sqrt(mean variance before - mean variance after)` over the blocks.
    pub excess: f64,
    /// Its standard error (Newey-West on the block variances, the delta method), channel unit.
    pub std_error: f64,
    /// The settled noise's standard deviation (the root of the mean block variance after), channel unit.
    pub settled_rms: f64,
    /// The same over every block, channel unit.
    pub all_rms: f64,
    /// The steps that passed, in time order.
    pub steps: usize,
    /// Sum of the steps' squared statistics.
    pub statistic: f64,
    /// The largest of the steps' p-values (each with its Bonferroni factor over the times tested).
    pub p_value: f64,
    /// Blocks the test ran on.
    pub blocks: usize,
}

impl NoiseWarmup {
    /// Blocks of each dwell's `series` (the samples less the dwell's mean and line), whose first samples are at
    /// `t_s` (per dwell, the record's time, s; `t0_s` the record's first sample), sampled every `dt` s; the
    /// steps that pass at `p_value_limit` (alpha over the Bonferroni `m`).
    pub fn measure(series: &[Vec<f64>], t_s: &[&[f64]], t0_s: f64, dt: f64, p_value_limit: f64) -> NoiseWarmup {
        let blocks = blocks(series, t_s, t0_s, dt);
        let mut steps = Vec::new();
        let mut from = 0;
        while let Some(step) = best_step(&blocks[from..]) {
            if !step.passes(p_value_limit) {
                break;
            }
            steps.push(step);
            from = blocks.partition_point(|b| b.t_s < step.settled_s);
        }
        NoiseWarmup { steps, blocks }
    }

    /// The warm-up as the steps that pass at `p_value_limit` give it (a prefix of those measured); `None` when
    /// none does.
    pub fn at(&self, p_value_limit: f64) -> Option<Size> {
        let passing = self.steps.iter().take_while(|s| s.passes(p_value_limit)).count();
        let steps = &self.steps[..passing];
        let last = steps.last()?;
        let split = self.blocks.partition_point(|b| b.t_s < last.settled_s);
        let (before, after) = self.blocks.split_at(split);
        let variances = |b: &[Block]| b.iter().map(|b| b.variance).collect::<Vec<f64>>();
        let (before, after) = (variances(before), variances(after));
        let after = mean_and_variance(&after);
        let (excess, std_error) = excess_in_quadrature(mean_and_variance(&before), after)?;
        Some(Size {
            settled_s: last.settled_s,
            excess,
            std_error,
            settled_rms: after.0.sqrt(),
            all_rms: (self.blocks.iter().map(|b| b.variance).sum::<f64>() / self.blocks.len() as f64).sqrt(),
            steps: steps.len(),
            statistic: steps.iter().map(|s| s.z * s.z).sum(),
            p_value: steps.iter().map(Step::p_value).fold(0.0, f64::max),
            blocks: self.blocks.len(),
        })
    }

    /// Each block's time after the record's first sample (s) and standard deviation (channel unit), in time
    /// order.
    pub fn levels(&self) -> Vec<(f64, f64)> {
        self.blocks.iter().map(|b| (b.t_s, b.variance.sqrt())).collect()
    }
}

/// Samples in a block of the noise's level at `dt` s a sample: one second, or [`MIN_BLOCK_SAMPLES`] when a
/// second has fewer (the noise warm-up's blocks and the disturbances' are the same).
pub(super) fn samples_per_block(dt: f64) -> usize {
    ((1.0 / dt).round() as usize).max(MIN_BLOCK_SAMPLES)
}

/// The blocks of the noise's level in each dwell's `series` (samples at `t_s`, the record's time; `t0_s` its
/// first sample; `dt` s apart), dwell by dwell: (the dwell, the block's first sample in it, that sample's time
/// after the record's first sample in s, the block's samples).
pub(super) fn block_chunks<'a>(
    series: &'a [Vec<f64>],
    t_s: &'a [&'a [f64]],
    t0_s: f64,
    dt: f64,
) -> impl Iterator<Item = (usize, usize, f64, &'a [f64])> + 'a {
    let per_block = samples_per_block(dt);
    series.iter().zip(t_s).enumerate().flat_map(move |(dwell, (y, t))| {
        y.chunks_exact(per_block).enumerate().map(move |(k, chunk)| {
            let first = k * per_block;
            (dwell, first, t[first] - t0_s, chunk)
        })
    })
}

/// The blocks of each dwell's `series`, whose samples are at `t_s` (the record's time, `t0_s` its first
/// sample), `dt` s apart, in time order; each block's variance about its mean.
fn blocks(series: &[Vec<f64>], t_s: &[&[f64]], t0_s: f64, dt: f64) -> Vec<Block> {
    let mut blocks: Vec<Block> = block_chunks(series, t_s, t0_s, dt)
        .filter_map(|(_, _, t_s, chunk)| {
            let n = chunk.len() as f64;
            let mean = chunk.iter().sum::<f64>() / n;
            let variance = chunk.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (variance > 0.0 && variance.is_finite()).then_some(Block { t_s, variance })
        })
        .collect();
    blocks.sort_by(|a, b| a.t_s.total_cmp(&b.t_s));
    blocks
}

/// The standard deviation that a noise whose mean block variance is `larger` adds in quadrature to one whose
/// is `smaller`, each given as (mean variance, the variance of that mean), with its standard error by the
/// delta method (`d sqrt(v) = dv / (2 sqrt(v))`); `None` unless the first is the larger.
pub(super) fn excess_in_quadrature(larger: (f64, f64), smaller: (f64, f64)) -> Option<(f64, f64)> {
    let excess_variance = larger.0 - smaller.0;
    (excess_variance > 0.0).then(|| {
        let excess = excess_variance.sqrt();
        (excess, (larger.1 + smaller.1).sqrt() / (2.0 * excess))
    })
}

/// What a noise warm-up that settles at `settled_s` must exceed on a channel with these samples (as
/// [`NoiseWarmup::measure`] takes them): the standard error of the test's difference of mean log-variances
/// at that time, and the mean block variance after it (channel unit squared). `None` without
/// [`MIN_SIDE_BLOCKS`] blocks on either side.
pub(super) fn scale_at(series: &[Vec<f64>], t_s: &[&[f64]], t0_s: f64, dt: f64, settled_s: f64) -> Option<(f64, f64)> {
    let blocks = blocks(series, t_s, t0_s, dt);
    let split = blocks.partition_point(|b| b.t_s < settled_s);
    if split < MIN_SIDE_BLOCKS || blocks.len() - split < MIN_SIDE_BLOCKS {
        return None;
    }
    let logs: Vec<f64> = blocks.iter().map(|b| b.variance.ln()).collect();
    let (_, var_before) = mean_and_variance(&logs[..split]);
    let (_, var_after) = mean_and_variance(&logs[split..]);
    let settled_variance = blocks[split..].iter().map(|b| b.variance).sum::<f64>() / (blocks.len() - split) as f64;
    Some(((var_before + var_after).sqrt(), settled_variance))
}

/// The step of `blocks` (in time order) with the largest statistic over the grid of times, if any has blocks
/// enough on both sides and a positive statistic (the level before higher).
fn best_step(blocks: &[Block]) -> Option<Step> {
    let (first, last) = (blocks.first()?.t_s, blocks.last()?.t_s);
    let longest = (last - first) / 2.0;
    if longest <= FIRST_S {
        return None;
    }
    let logs: Vec<f64> = blocks.iter().map(|b| b.variance.ln()).collect();
    let ratio = (longest / FIRST_S).powf(1.0 / (GRID - 1) as f64);
    let mut best: Option<Step> = None;
    for g in 0..GRID {
        let settled_s = first + FIRST_S * ratio.powi(g as i32);
        let split = blocks.partition_point(|b| b.t_s < settled_s);
        if split < MIN_SIDE_BLOCKS || blocks.len() - split < MIN_SIDE_BLOCKS {
            continue;
        }
        let (before, after) = logs.split_at(split);
        let (mean_before, var_before) = mean_and_variance(before);
        let (mean_after, var_after) = mean_and_variance(after);
        let z = (mean_before - mean_after) / (var_before + var_after).sqrt().max(f64::MIN_POSITIVE);
        if z > 0.0 && best.is_none_or(|b| z > b.z) {
            best = Some(Step { settled_s, z, tested: GRID, blocks: blocks.len() });
        }
    }
    best
}

/// The mean of `x` and its variance by Newey-West with Bartlett weights over `2 n^(1/3)` lags, at least that of
/// independent values: serially correlated values (a noise burst over many blocks) count for less than
/// independent ones.
fn mean_and_variance(x: &[f64]) -> (f64, f64) {
    let n = x.len();
    let mean = x.iter().sum::<f64>() / n as f64;
    let d: Vec<f64> = x.iter().map(|v| v - mean).collect();
    let lags = ((2.0 * (n as f64).cbrt()).ceil() as usize).min(n.saturating_sub(1));
    let autocovariance = |l: usize| d[l..].iter().zip(&d).map(|(a, b)| a * b).sum::<f64>() / n as f64;
    let long_run = autocovariance(0)
        + 2.0 * (1..=lags).map(|l| (1.0 - l as f64 / (lags + 1) as f64) * autocovariance(l)).sum::<f64>();
    // Never below the variance of independent values: a negative sum of lags is the estimate's own noise.
    (mean, long_run.max(autocovariance(0)) / n as f64)
}

/// The samples of each dwell (at `t_s`, the record's time) that are kept once the noise has settled at
/// `settled_s` after `t0_s`, the record's first sample: (the dwell's index, its first sample kept). A dwell
/// whose rest would be shorter than the shortest dwell that keeps all its samples is left out whole, so that
/// no dwell is shorter than before (the slowest correlated noise resolved is set by the shortest dwell).
pub(super) fn settled(t_s: &[&[f64]], t0_s: f64, settled_s: f64) -> Vec<(usize, usize)> {
    let first_kept = |t: &[f64]| t.partition_point(|&t| t - t0_s < settled_s);
    let shortest_whole = t_s.iter().filter(|t| first_kept(t) == 0).map(|t| t.len()).min().unwrap_or(0);
    t_s.iter()
        .enumerate()
        .map(|(d, t)| (d, first_kept(t)))
        .filter(|&(d, from)| from == 0 || (from < t_s[d].len() && t_s[d].len() - from >= shortest_whole))
        .collect()
}

/// `series` (per dwell) reduced to the `kept` samples of [`settled`].
pub(super) fn keep(series: Vec<Vec<f64>>, kept: &[(usize, usize)]) -> Vec<Vec<f64>> {
    let mut series: Vec<Option<Vec<f64>>> = series.into_iter().map(Some).collect();
    // In place: the samples before are dropped from each kept dwell's own allocation.
    kept.iter()
        .filter_map(|&(d, from)| {
            series[d].take().map(|mut y| {
                y.drain(..from);
                y
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::model::simulator::normal;

    /// One dwell of `seconds` at 100 Hz: a Gauss-Markov process of 0.5 and 0.3 s, and white noise of 1 whose
    /// standard deviation is `boost` times larger before `until_s` (and twice as large in bursts of 30 s in
    /// every 300 s when `bursts`).
    fn record(seconds: f64, until_s: f64, boost: f64, bursts: bool, seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (dt, tau): (f64, f64) = (0.01, 0.3);
        let phi = (-dt / tau).exp();
        let n = (seconds / dt) as usize;
        let mut x = 0.0;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let y = t
            .iter()
            .map(|&t| {
                let burst = bursts && t % 300.0 > 150.0 && t % 300.0 < 180.0;
                let scale = if t < until_s {
                    boost
                } else if burst {
                    2.0
                } else {
                    1.0
                };
                x = phi * x + 0.5 * (1.0 - phi * phi).sqrt() * normal(&mut rng);
                scale * normal(&mut rng) + x
            })
            .collect();
        (t, y)
    }

    /// SIMULATION: a white noise three times larger in the first 100 s of 900 s is found settled within 25 s
    /// of 100 s in every seed (0 to 4), with the standard deviation it adds (sqrt(9 - 1) = 2.83) within three
    /// standard errors; without a warm-up, and with noise bursts through the record instead, no step passes
    /// at alpha / 18 in any seed.
    #[test]
    fn a_noise_larger_at_the_start_is_found_and_bursts_are_not() {
        let limit = super::super::ALPHA / 18.0;
        for seed in 0..5 {
            let (t, y) = record(900.0, 100.0, 3.0, false, seed);
            let w = NoiseWarmup::measure(&[y], &[&t], 0.0, 0.01, limit);
            let size = w.at(limit).unwrap_or_else(|| panic!("seed {seed}: no warm-up found"));
            assert!((size.settled_s - 100.0).abs() < 25.0, "seed {seed}: settled at {} s", size.settled_s);
            let truth = 8f64.sqrt();
            assert!((size.excess - truth).abs() < 3.0 * size.std_error, "seed {seed}: {size:?}");
            for (what, bursts) in [("white and a process", false), ("bursts", true)] {
                let (t, y) = record(900.0, 0.0, 1.0, bursts, seed + 10);
                let w = NoiseWarmup::measure(&[y], &[&t], 0.0, 0.01, limit);
                assert_eq!(w.at(limit), None, "seed {seed}: a warm-up in {what}: {:?}", w.steps);
            }
        }
    }

    /// The settled series: a dwell that starts before the noise has settled keeps its rest when that is no
    /// shorter than the shortest whole dwell, else it is left out.
    #[test]
    fn a_dwell_that_starts_before_the_noise_has_settled_keeps_its_rest_only_if_no_dwell_gets_shorter() {
        let dwell = |from: f64, n: usize| (0..n).map(|i| from + i as f64).collect::<Vec<f64>>();
        let t = [dwell(0.0, 10), dwell(20.0, 10), dwell(40.0, 4)];
        let times: Vec<&[f64]> = t.iter().map(|t| t.as_slice()).collect();
        // Settled at 25 s: the second dwell keeps 5 samples (>= 4, the third's), the first none.
        let kept = settled(&times, 0.0, 25.0);
        assert_eq!(kept, vec![(1, 5), (2, 0)]);
        assert_eq!(keep(t.to_vec(), &kept), vec![vec![25.0, 26.0, 27.0, 28.0, 29.0], t[2].clone()]);
        // Settled at 27 s: 3 samples would be left, fewer than 4: the dwell is left out.
        assert_eq!(settled(&times, 0.0, 27.0), vec![(2, 0)]);
        // Before the first sample: every dwell whole.
        assert_eq!(settled(&times, 0.0, -1.0), vec![(0, 0), (1, 0), (2, 0)]);
    }
}
