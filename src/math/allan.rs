//! Online non-overlapping Allan variance at octave cluster sizes, in f32, without a sample buffer.
//!
//! Half the mean square difference of adjacent means of `m` samples is the Allan variance at `tau = m dt`
//! (IEEE Std 952-1997, Annex C, non-overlapping estimator):
//!
//! ```text
//! AVAR(m) = 1 / (2 D) * sum_i (ybar_{i+1} - ybar_i)^2,     ybar_i the mean of the i-th cluster of m samples
//! ```
//!
//! with `D` the number of differences (clusters minus one). [`OctaveAllan`] keeps it for the cluster sizes
//! `m_j = b 2^j`, `j = 0..K-1`, where each value fed is one cluster of level 0 (`b` samples: a single
//! sample, or the sum of a block of samples that the caller has already summed).
//!
//! **The cascade.** A cluster of level `j + 1` is two adjacent clusters of level `j`. Each level keeps the
//! sum of its last complete cluster; when cluster `i` of level `j` completes with sum `S_i`, the level adds
//! `(S_i - S_{i-1})^2` to its sum of squares and keeps `S_i`; when `i` is odd (the second of a pair) the sum
//! `S_{i-1} + S_i` is the next cluster of level `j + 1`, which is handled the same way. So level `j` works
//! once per `2^j` values: the amortised cost per value is two level steps (1 + 1/2 + 1/4 + ...), and no
//! level needs a separate running sum (the first half of a pending cluster is the previous cluster of the
//! level below). The number of differences of level `j` follows from the number of values fed `n`:
//! `(n >> j) - 1` once positive, so it is not stored either.
//!
//! **f32 care.** The first value fed is the shift: every cluster sum is a sum of deviations from it, so a
//! large constant (9.8 m/s^2, a gyro's Earth rate) never enters a sum. The cluster sums are formed
//! pairwise, whose rounding error grows with `log2` of the cluster size only (Higham, Accuracy and
//! Stability of Numerical Algorithms, 2nd ed., section 4.2), and the squared differences go into Kahan
//! sums ([`KahanSum`]), whose error does not grow with their number. Differences are taken of cluster
//! sums and divided by `m^2` only when the variance is read.
//!
//! Cost per value fed: amortised two level steps, each one subtraction, one multiplication, a Kahan
//! addition (four additions) and one addition towards the next level. RAM: `4 + 4 + 12 K` bytes (count,
//! shift, per level the previous cluster sum and a two-word Kahan sum).

use crate::math::accumulate::KahanSum;

/// Non-overlapping Allan variance at the `K` octave cluster sizes `b 2^j`, fed one level-0 cluster
/// (one sample, or the sum of `b` samples) at a time. See the [module documentation](self).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OctaveAllan<const K: usize> {
    /// Values fed so far.
    values: u32,
    /// The first value fed: every cluster sum is a sum of deviations from it.
    shift: f32,
    /// Per level, the sum (of deviations from the shift) of the last complete cluster.
    previous: [f32; K],
    /// Per level, the sum of the squared differences of adjacent cluster sums.
    sum_sq: [KahanSum; K],
}

impl<const K: usize> Default for OctaveAllan<K> {
    fn default() -> Self {
        OctaveAllan::new()
    }
}

impl<const K: usize> OctaveAllan<K> {
    /// An empty accumulator.
    pub const fn new() -> OctaveAllan<K> {
        OctaveAllan { values: 0, shift: 0.0, previous: [0.0; K], sum_sq: [KahanSum::new(); K] }
    }

    /// Feeds one level-0 cluster: a sample, or the sum of the `b` samples of one block (then every
    /// value fed must be a sum over the same number of samples).
    #[inline]
    pub fn add(&mut self, x: f32) {
        if self.values == 0 {
            self.shift = x;
        }
        self.values = self.values.wrapping_add(1);
        let n = self.values;
        // `s` is the sum of the cluster of level `j` that has just completed: the (n >> j)-th one.
        let mut s = x - self.shift;
        for j in 0..K {
            let before = self.previous[j];
            if (n >> j) >= 2 {
                let d = s - before;
                self.sum_sq[j].add(d * d);
            }
            self.previous[j] = s;
            if (n >> j) & 1 == 1 {
                // The first of a pair: the cluster of level j + 1 is not complete yet.
                break;
            }
            s += before;
        }
    }

    /// Number of values fed.
    pub fn values(&self) -> u32 {
        self.values
    }

    /// Number of differences of adjacent clusters at level `level` (0 for a level beyond `K`).
    pub fn differences(&self, level: usize) -> u32 {
        if level >= K {
            return 0;
        }
        (self.values >> level).saturating_sub(1)
    }

    /// Sum of the squared differences of adjacent cluster **sums** at `level` (0 for a level beyond `K`).
    pub fn sum_sq_differences(&self, level: usize) -> f32 {
        self.sum_sq.get(level).map_or(0.0, |s| s.value())
    }

    /// The Allan variance at `level`, in the unit of the samples squared, when every value fed was the sum
    /// of `samples_per_value` samples (1 when the samples are fed one by one): the cluster size is
    /// `samples_per_value << level` samples. `None` when the level has no difference yet.
    pub fn allan_variance(&self, level: usize, samples_per_value: u32) -> Option<f32> {
        let d = self.differences(level);
        if d == 0 {
            return None;
        }
        let m = samples_per_value as f32 * (1u32 << level) as f32;
        // sum (S_{i+1} - S_i)^2 / (2 D m^2): the squared difference of cluster means is that of the sums
        // over m^2. Divided in two steps so that m^2 cannot overflow for any level.
        Some(self.sum_sq_differences(level) / m / m / (2.0 * d as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random sequence (xorshift32), so the tests need no RNG crate.
    struct Xorshift(u32);

    impl Xorshift {
        /// Uniform in [-1, 1).
        fn uniform(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            (self.0 as f64 / u32::MAX as f64 * 2.0 - 1.0) as f32
        }

        /// Approximately standard normal (sum of 12 uniforms on [-1, 1) has variance 4).
        fn normal(&mut self) -> f32 {
            (0..12).map(|_| self.uniform()).sum::<f32>() / 2.0
        }
    }

    /// The same estimator written out directly, in f64, from a buffer.
    fn reference(xs: &[f32], m: usize) -> Option<f64> {
        let means: Vec<f64> = xs.chunks_exact(m).map(|c| c.iter().map(|&x| x as f64).sum::<f64>() / m as f64).collect();
        (means.len() >= 2)
            .then(|| means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2.0 * (means.len() - 1) as f64))
    }

    #[test]
    fn matches_the_direct_estimator_with_a_large_offset() {
        let mut rng = Xorshift(0x2545_f491);
        let xs: Vec<f32> = (0..100_000).map(|_| 9.806_65 + 1e-3 * rng.normal()).collect();
        let mut a = OctaveAllan::<12>::new();
        for &x in &xs {
            a.add(x);
        }
        for j in 0..12 {
            let m = 1 << j;
            let want = reference(&xs, m).unwrap();
            let got = a.allan_variance(j, 1).unwrap() as f64;
            assert_eq!(a.differences(j) as usize, xs.len() / m - 1);
            assert!(((got - want) / want).abs() < 1e-4, "level {j}: {got:e} vs {want:e}");
        }
    }

    #[test]
    fn white_noise_gives_sigma_squared_over_m() {
        let sigma = 2e-3f32;
        let mut rng = Xorshift(0x1234_5678);
        let mut a = OctaveAllan::<14>::new();
        let n = 1 << 18;
        for _ in 0..n {
            a.add(0.5 + sigma * rng.normal());
        }
        for j in 0..14 {
            let m = (1u32 << j) as f64;
            let d = a.differences(j) as f64;
            let want = (sigma as f64).powi(2) / m;
            let got = a.allan_variance(j, 1).unwrap() as f64;
            // The estimate is a chi-square with D degrees of freedom / D: relative standard deviation
            // sqrt(2 / D) (adjacent differences share a cluster, which changes this little). Four of them.
            let tolerance = 4.0 * (2.0 / d).sqrt();
            assert!(((got - want) / want).abs() < tolerance, "level {j}: {got:e} vs {want:e} (D = {d})");
        }
    }

    #[test]
    fn constant_gives_exactly_zero() {
        let mut a = OctaveAllan::<10>::new();
        for _ in 0..5000 {
            a.add(9.806_65);
        }
        for j in 0..10 {
            assert_eq!(a.allan_variance(j, 1), Some(0.0), "level {j}");
        }
        assert_eq!(OctaveAllan::<10>::new().allan_variance(0, 1), None);
    }

    #[test]
    fn ramp_gives_half_the_squared_step_of_the_cluster_means() {
        // x_k = c + r k: adjacent means of m samples differ by r m exactly, so AVAR(m) = (r m)^2 / 2.
        let r = 1e-5f32;
        let mut a = OctaveAllan::<12>::new();
        for k in 0..(1u32 << 14) {
            a.add(9.8 + r * k as f32);
        }
        for j in 0..12 {
            let m = (1u32 << j) as f64;
            let want = (r as f64 * m).powi(2) / 2.0;
            let got = a.allan_variance(j, 1).unwrap() as f64;
            // The ramp's samples are rounded to f32 (9.8 has an ulp of 9.5e-7, r = 1e-5): the rounding
            // adds a white-noise-like term of about ulp^2 / 12 / m, relevant at the shortest clusters only.
            let rounding = (9.5e-7f64).powi(2) / 12.0 / m * 4.0;
            assert!((got - want).abs() < 1e-4 * want + rounding, "level {j}: {got:e} vs {want:e}");
        }
    }

    #[test]
    fn differenced_noise_falls_as_one_over_m_squared() {
        // x_k = e_k - e_{k-1} (quantisation-like, the increments of a bounded signal): a cluster mean is
        // (e_end - e_start) / m, so AVAR(m) = 3 sigma^2 / m^2 (three independent e in each difference).
        let sigma = 1e-2f32;
        let mut rng = Xorshift(0x0bad_cafe);
        let mut a = OctaveAllan::<12>::new();
        let mut previous = sigma * rng.normal();
        for _ in 0..(1u32 << 18) {
            let e = sigma * rng.normal();
            a.add(e - previous);
            previous = e;
        }
        for j in 0..12 {
            let m = (1u32 << j) as f64;
            let d = a.differences(j) as f64;
            let want = 3.0 * (sigma as f64).powi(2) / (m * m);
            let got = a.allan_variance(j, 1).unwrap() as f64;
            let tolerance = 5.0 * (2.0 / d).sqrt();
            assert!(((got - want) / want).abs() < tolerance, "level {j}: {got:e} vs {want:e} (D = {d})");
        }
        // The slope: from 2^4 to 2^10 samples the variance falls by 2^12 (not by 2^6, as white noise would).
        let ratio = a.allan_variance(4, 1).unwrap() / a.allan_variance(10, 1).unwrap();
        assert!((ratio / 4096.0 - 1.0).abs() < 0.3, "ratio {ratio}");
    }

    #[test]
    fn block_sums_give_the_allan_variance_of_the_samples() {
        // Feeding sums of 64 samples is the same estimator at cluster sizes 64 * 2^j.
        let mut rng = Xorshift(0x5eed_0001);
        let xs: Vec<f32> = (0..64 * 2000).map(|_| -3.0 + 0.1 * rng.normal()).collect();
        let mut a = OctaveAllan::<8>::new();
        for block in xs.chunks_exact(64) {
            a.add(block.iter().map(|&x| x - xs[0]).sum());
        }
        for j in 0..5 {
            let want = reference(&xs, 64 << j).unwrap();
            let got = a.allan_variance(j, 64).unwrap() as f64;
            assert!(((got - want) / want).abs() < 1e-4, "level {j}: {got:e} vs {want:e}");
        }
    }

    #[test]
    fn counts_and_levels_beyond_k() {
        let mut a = OctaveAllan::<3>::new();
        for k in 0..9 {
            a.add(k as f32);
        }
        assert_eq!((a.values(), a.differences(0), a.differences(1), a.differences(2)), (9, 8, 3, 1));
        assert_eq!((a.differences(3), a.sum_sq_differences(3), a.allan_variance(3, 1)), (0, 0.0, None));
    }
}
