//! Structural observability: the blind spots of the schedule, from the singular values of the structural
//! design, and the gauge that fixes the body frame when the attitudes are unknown.

use crate::calib::general::estimator::{ChannelEstimator, Design};
use crate::calib::general::settings::AttitudeKnowledge;
use crate::calib::general::terms::{Term, GAUGE_PARAMETERS, PARAMETERS};
use crate::math::lsq::{jacobi_svd, SqrtInfo};
use crate::nav::earth::EARTH_RATE_RADPS;

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

    /// The columns solved for: the determined ones, then, in model order, each undetermined column that the
    /// schedule exercises (a structural norm above zero), that is not held by the gauge, and that is independent
    /// of the columns taken before it: its distance from their span, in the unit-column structural factor,
    /// above ten times the rank tolerance. The factor is triangularised again with the determined columns first;
    /// a column's distance from the span of those before it is then its diagonal entry.
    pub(super) fn completion(
        &self,
        r: &[[f32; PARAMETERS]; PARAMETERS],
        determined: &[bool; PARAMETERS],
        scale_s: &[f32; PARAMETERS],
        gauge: u64,
        cols: &[usize; PARAMETERS],
        n: usize,
    ) -> [bool; PARAMETERS] {
        let mut solved = *determined;
        let mut order = [0usize; PARAMETERS];
        let mut m = 0;
        for first in [true, false] {
            for c in 0..n {
                let candidate = !determined[c] && scale_s[c] > 0.0 && gauge & (1 << cols[c]) == 0;
                if (first && determined[c]) || (!first && candidate) {
                    order[m] = c;
                    m += 1;
                }
            }
        }
        let mut permuted = SqrtInfo::<PARAMETERS>::new(m);
        for row in r.iter().take(n) {
            let mut p = [0.0f32; PARAMETERS];
            for (slot, &c) in p.iter_mut().zip(order.iter()).take(m) {
                *slot = row[c];
            }
            permuted.add_row(&p, 0.0);
        }
        let tolerance = 10.0 * self.settings.rank_tolerance;
        for (k, &c) in order.iter().enumerate().take(m) {
            if !determined[c] && permuted.r[k][k].abs() > tolerance {
                solved[c] = true;
            }
        }
        solved
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

    /// Sets to zero the structural norm `norm_s` of every proportional term's column whose largest entry `peak_s`
    /// is below [`MIN_EXERCISE`] of its full scale: the schedule does not exercise it. A proportional term whose
    /// input never reaches 5 % of full scale in any dwell (an axis tilted by less than 3 deg from horizontal for a
    /// scale factor) is absent, whatever a fit would make of it (a 0.05 deg tilt would otherwise "determine" a
    /// scale factor from 9e-4 g). A dwell whose heading is neither given nor estimated leaves the reference offset
    /// undefined: its axes are navigation axes, and that dwell's are not known.
    pub(super) fn drop_unexercised(
        &self,
        design: &Design<'_>,
        used: &impl Fn(usize) -> bool,
        peak_s: &[f32; PARAMETERS],
        norm_s: &mut [f32; PARAMETERS],
    ) {
        let (cols, n) = (design.cols, design.n);
        let offset_undefined =
            self.dwells.iter().enumerate().any(|(k, d)| used(k) && d.heading_rad.is_none() && !self.nuisances(d)[2]);
        for c in 0..n {
            let p = cols[c];
            let full_scale = match p {
                33..=35 if offset_undefined => f32::INFINITY,
                6..=23 | 33..=35 => 1.0,
                24..=32 => self.site.gravity_mps2 / EARTH_RATE_RADPS,
                _ => continue,
            };
            if peak_s[c] < MIN_EXERCISE * full_scale {
                norm_s[c] = 0.0;
            }
        }
    }
}
