//! Structural observability: the blind spots of the schedule, from the singular values of the structural
//! design, and the gauge that fixes the body frame when the attitudes are unknown.

use crate::calib::general::estimator::ChannelEstimator;
use crate::calib::general::settings::AttitudeKnowledge;
use crate::calib::general::terms::{Term, GAUGE_PARAMETERS, PARAMETERS};
use crate::math::lsq::jacobi_svd;

/// Smallest largest input of a proportional term, as a fraction of its full scale (g for the accelerometer
/// terms and the g-sensitivity, the Earth rate for the gyro scale factors and misalignments, 1 rad of offset),
/// for the schedule to exercise it.
pub const MIN_EXERCISE: f32 = 0.05;

impl ChannelEstimator {
    /// The structural rank of the (unit-column) structural factor `r`: which model columns are determined, the
    /// number of blind spots, and the gauge (parameter bits held at zero to fix the body frame). With unknown
    /// attitudes and the accelerometer misalignments in the model, the gauge columns are removed and the rank
    /// is taken again.
    pub(super) fn structural_rank(
        &self,
        r: &[[f32; PARAMETERS]; PARAMETERS],
        cols: &[usize; PARAMETERS],
        n: usize,
    ) -> ([bool; PARAMETERS], u32, u64) {
        let (mut determined, blind_spots) = self.determined_columns(r, n);
        let mut gauge = 0u64;
        if self.settings.attitude == AttitudeKnowledge::Unknown && self.model().contains(Term::AccelMisalignment) {
            // Zeroing a column of R zeroes the same column of the design (A = Q R).
            let mut fixed = *r;
            for c in 0..n {
                if GAUGE_PARAMETERS.contains(&cols[c]) {
                    gauge |= 1 << cols[c];
                    for row in fixed.iter_mut() {
                        row[c] = 0.0;
                    }
                }
            }
            determined = self.determined_columns(&fixed, n).0;
        }
        (determined, blind_spots, gauge)
    }

    /// SVD of a structural factor of `n` columns: whether each column is determined (its squared share in the
    /// blind spots at most the share tolerance), and the number of blind spots.
    pub(super) fn determined_columns(
        &self,
        r: &[[f32; PARAMETERS]; PARAMETERS],
        n: usize,
    ) -> ([bool; PARAMETERS], u32) {
        let mut a = *r;
        let mut v = [[0.0f32; PARAMETERS]; PARAMETERS];
        let sigma = jacobi_svd(&mut a, &mut v, n);
        let largest = sigma.iter().take(n).fold(0.0f32, |m, s| m.max(*s));
        let seen = |j: usize| sigma[j] > self.settings.rank_tolerance * largest;
        let mut determined = [false; PARAMETERS];
        for (c, slot) in determined.iter_mut().enumerate().take(n) {
            let share: f32 = (0..n).filter(|&j| !seen(j)).map(|j| v[c][j] * v[c][j]).sum();
            *slot = largest > 0.0 && share <= self.settings.share_tolerance;
        }
        (determined, (0..n).filter(|&j| !seen(j)).count() as u32)
    }
}
