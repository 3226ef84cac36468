//! Dwell statistics in f32 without loss of precision over 60,000+ samples.
//!
//! A plain f32 running sum of 60,000 samples of 9.8 m/s^2 loses about 12 bits: each addition rounds at
//! the scale of the sum (2^-24 * 6e5 = 0.035 m/s^2 per step in the worst case). Two measures keep the
//! result at the precision of a single sample:
//! 1. the samples are shifted by the dwell's first sample, so the summands are the small deviations;
//! 2. the sums of the deviations and of their squares use Kahan's compensated summation, whose error
//!    does not grow with the number of samples (Higham, Accuracy and Stability of Numerical Algorithms,
//!    2nd ed., section 4.3: |error| <= (2u + O(n u^2)) sum |x_i|).
//!
//! To keep the per-sample cost at one addition per sum, the sums are blocked: a plain f32 partial sum over
//! [`BLOCK_SAMPLES`] samples, added into the Kahan sum at the end of each block (Higham, section 4.2,
//! blocked summation). The error bound becomes about (BLOCK_SAMPLES u + 2u) sum |x_i|: with shifted data
//! and 64-sample blocks, 4e-6 of the deviations, far below any noise the mean is meant to average out.
//!
//! Cost per sample and channel: 1 subtraction, 1 multiplication and 2 additions.

/// Kahan compensated sum.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KahanSum {
    sum: f32,
    compensation: f32,
}

impl KahanSum {
    /// An empty sum.
    pub const fn new() -> KahanSum {
        KahanSum { sum: 0.0, compensation: 0.0 }
    }

    /// Adds `x`. (The compiler does not reassociate floating-point additions, so the compensation
    /// survives optimisation.)
    #[inline]
    pub fn add(&mut self, x: f32) {
        let y = x - self.compensation;
        let t = self.sum + y;
        self.compensation = (t - self.sum) - y;
        self.sum = t;
    }

    /// The sum.
    #[inline]
    pub fn value(&self) -> f32 {
        self.sum
    }
}

/// Samples per block of a blocked sum.
pub const BLOCK_SAMPLES: u32 = 64;

/// A blocked sum: a plain f32 partial sum, flushed into a Kahan sum every block.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BlockedSum {
    block: f32,
    total: KahanSum,
}

impl BlockedSum {
    /// An empty sum.
    pub const fn new() -> BlockedSum {
        BlockedSum { block: 0.0, total: KahanSum::new() }
    }

    /// Adds `x` to the current block.
    #[inline(always)]
    pub fn add(&mut self, x: f32) {
        self.block += x;
    }

    /// The sum of the open block (what [`BlockedSum::flush`] will add to the total).
    #[inline(always)]
    pub fn block(&self) -> f32 {
        self.block
    }

    /// Ends the block: its sum goes into the compensated total.
    #[inline]
    pub fn flush(&mut self) {
        self.total.add(self.block);
        self.block = 0.0;
    }

    /// The sum (total plus the open block).
    pub fn value(&self) -> f32 {
        let mut t = self.total;
        t.add(self.block);
        t.value()
    }
}

/// Mean and variance of one channel over one dwell (shifted data, blocked compensated sums).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DwellStats {
    count: u32,
    shift: f32,
    sum: BlockedSum,
    sum_sq: BlockedSum,
}

impl DwellStats {
    /// An empty accumulator.
    pub const fn new() -> DwellStats {
        DwellStats { count: 0, shift: 0.0, sum: BlockedSum::new(), sum_sq: BlockedSum::new() }
    }

    /// Adds one sample. The first sample becomes the shift.
    #[inline]
    pub fn add(&mut self, x: f32) {
        if self.count == 0 {
            self.shift = x;
        }
        let d = x - self.shift;
        self.sum.add(d);
        self.sum_sq.add(d * d);
        self.count += 1;
        if self.count % BLOCK_SAMPLES == 0 {
            self.sum.flush();
            self.sum_sq.flush();
        }
    }

    /// Mean from a count, a shift and the sum of deviations from the shift; `None` when empty.
    /// (Shared with the dwell collector, which keeps its sums itself.)
    pub fn shifted_mean(count: u32, shift: f32, sum: f32) -> Option<f32> {
        (count > 0).then(|| shift + sum / count as f32)
    }

    /// Unbiased variance (divisor n - 1) from a count and the sums of deviations and squared deviations;
    /// `None` with fewer than two samples.
    pub fn shifted_variance(count: u32, sum: f32, sum_sq: f32) -> Option<f32> {
        let n = count as f32;
        // sum (d - mean_d)^2 = sum d^2 - (sum d)^2 / n; with shifted data the two terms are of the order
        // of the spread, not of the offset, so the difference does not cancel catastrophically.
        (count > 1).then(|| ((sum_sq - sum * (sum / n)) / (n - 1.0)).max(0.0))
    }

    /// Number of samples.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Mean of the samples; `None` when empty.
    pub fn mean(&self) -> Option<f32> {
        DwellStats::shifted_mean(self.count, self.shift, self.sum.value())
    }

    /// Unbiased sample variance (divisor n - 1); `None` with fewer than two samples.
    pub fn variance(&self) -> Option<f32> {
        DwellStats::shifted_variance(self.count, self.sum.value(), self.sum_sq.value())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random sequence in [-1, 1) (xorshift32), so the test needs no RNG crate.
    fn noise(state: &mut u32) -> f32 {
        *state ^= *state << 13;
        *state ^= *state >> 17;
        *state ^= *state << 5;
        (*state as f32 / u32::MAX as f32) * 2.0 - 1.0
    }

    #[test]
    fn matches_f64_over_a_long_dwell_with_a_large_offset() {
        // 72,000 samples (12 minutes at 100 Hz) of 9.8 m/s^2 + 1e-3 noise + a slow ramp.
        let mut acc = DwellStats::new();
        let mut seed = 0x1234_5678u32;
        let xs: Vec<f32> = (0..72_000).map(|k| 9.806_65 + 1e-3 * noise(&mut seed) + 2e-9 * k as f32).collect();
        for &x in &xs {
            acc.add(x);
        }
        let n = xs.len() as f64;
        let mean64 = xs.iter().map(|&x| x as f64).sum::<f64>() / n;
        let var64 = xs.iter().map(|&x| (x as f64 - mean64).powi(2)).sum::<f64>() / (n - 1.0);
        let mean = acc.mean().unwrap() as f64;
        let var = acc.variance().unwrap() as f64;
        // Mean to within one f32 ulp of 9.8 (9.5e-7), variance to 1e-5 relative.
        assert!((mean - mean64).abs() < 1e-6, "mean {mean} vs {mean64}");
        assert!(((var - var64) / var64).abs() < 1e-5, "var {var} vs {var64}");

        // The naive f32 running sum is far worse: that is why this type exists.
        let naive: f32 = xs.iter().sum::<f32>() / xs.len() as f32;
        assert!((naive as f64 - mean64).abs() > 10.0 * (mean - mean64).abs().max(1e-8));
    }

    #[test]
    fn empty_and_single_sample() {
        let mut acc = DwellStats::new();
        assert_eq!(acc.mean(), None);
        acc.add(3.5);
        assert_eq!(acc.mean(), Some(3.5));
        assert_eq!(acc.variance(), None);
        acc.add(3.5);
        assert_eq!(acc.variance(), Some(0.0));
    }
}
