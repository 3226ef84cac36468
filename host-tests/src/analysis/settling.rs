//! Settling after a move (docs/analysis.md#settling-after-a-move): the first or last half-seconds of the
//! dwells that differ from the rest of their dwell beyond its noise, as a hand-placed unit's do while it
//! comes to rest. They are left out of every dwell before the analysis.
//!
//! The test works on the means of half-second segments of each dwell, per channel. At the start, the first
//! segment's mean less that of the segment [`DISTANCE`] segments later, squared and averaged over the
//! dwells, is set against the same difference of segments as far apart inside the dwells (away from both
//! ends), pooled over the dwells: an F test. Under a stationary noise, a slow wander of the bias (a random
//! walk's increments do not depend on where they start) or a straight line, such a difference does not
//! depend on where it lies, so only a change at the end itself passes. Once the first segment passes, the
//! second is tested the same way, up to [`MAX_SEGMENTS`]; the end of the dwells likewise, from their last
//! segment. Each test passes at `alpha / (2 c)` (Bonferroni over the two ends and the `c` channels). The
//! dwells settle at the most segments any channel passes, and every channel of every dwell long enough loses
//! them.

use serde::Serialize;

use crate::stats::noise::f_cdf;

use super::observations::Session;
use super::{ALPHA, CHANNELS, MIN_DWELL_SAMPLES};

/// One segment, s.
pub const SEGMENT_S: f64 = 0.5;
/// Most segments tested at each end.
const MAX_SEGMENTS: usize = 4;
/// Segments between the two of a difference: the first tested against the one just past the last tested.
const DISTANCE: usize = MAX_SEGMENTS + 1;
/// Fewest dwells with segments enough for the test.
const MIN_DWELLS: usize = 6;
/// Fewest differences inside the dwells for the noise they are set against (20 that do not overlap).
const MIN_INSIDE: usize = 20 * DISTANCE;
/// Fewest samples in a segment.
const MIN_SEGMENT_SAMPLES: usize = 5;

/// What the dwells lose at each end.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Settling {
    /// Seconds left out at the start of every dwell long enough (after a move).
    pub start_s: f64,
    /// Seconds left out at the end (before a move).
    pub end_s: f64,
    /// Dwells that lost them (those whose rest keeps at least the analysis's fewest samples of a dwell).
    pub dwells: usize,
    /// Dwells tested.
    pub tested_dwells: usize,
    /// The tests that passed.
    pub passed: Vec<SettlingTest>,
}

/// One test that passed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SettlingTest {
    /// The channel.
    pub channel: String,
    /// "start" or "end".
    pub end: String,
    /// The segment (0: the first from that end).
    pub segment: usize,
    /// The F statistic: the mean squared difference of that segment and the one [`DISTANCE`] segments on,
    /// over the same inside the dwells.
    pub f: f64,
    /// Its degrees of freedom (dwells; differences inside over [`DISTANCE`], as many as do not overlap).
    pub dof: [usize; 2],
    /// Its upper-tail p-value.
    pub p_value: f64,
}

/// The segment means of `y` (`per` samples each), from its start or, `from_end`, from its end.
fn segment_means(y: &[f64], per: usize, from_end: bool) -> Vec<f64> {
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
    if from_end {
        y.rchunks_exact(per).map(mean).collect()
    } else {
        y.chunks_exact(per).map(mean).collect()
    }
}

/// The segments of one channel's dwells (`dwells`, `per` samples a segment) that pass at one end
/// (`from_end`) at `p_value_limit`, and the tests that passed.
fn passing(dwells: &[&[f64]], per: usize, from_end: bool, p_value_limit: f64) -> Vec<(usize, f64, [usize; 2], f64)> {
    // Dwells with MAX_SEGMENTS at each end and at least two differences inside.
    let shortest = 2 * MAX_SEGMENTS + DISTANCE + 2;
    let means: Vec<Vec<f64>> =
        dwells.iter().map(|y| segment_means(y, per, from_end)).filter(|m| m.len() >= shortest).collect();
    if means.len() < MIN_DWELLS {
        return Vec::new();
    }
    let inside: Vec<f64> = means
        .iter()
        .flat_map(|m| (MAX_SEGMENTS..m.len() - MAX_SEGMENTS - DISTANCE).map(move |j| (m[j] - m[j + DISTANCE]).powi(2)))
        .collect();
    if inside.len() < MIN_INSIDE {
        return Vec::new();
    }
    let noise = inside.iter().sum::<f64>() / inside.len() as f64;
    if noise.is_nan() || noise <= 0.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for k in 0..MAX_SEGMENTS {
        let at_end = means.iter().map(|m| (m[k] - m[k + DISTANCE]).powi(2)).sum::<f64>() / means.len() as f64;
        let f = at_end / noise;
        // Differences inside that overlap share their noise: as many independent ones as do not overlap.
        let dof = [means.len(), inside.len() / DISTANCE];
        // The upper tail, as the lower one of the reciprocal (F(d2, d1)): no cancellation near zero.
        let p_value = f_cdf(1.0 / f, dof[1] as f64, dof[0] as f64);
        if p_value.is_nan() || p_value >= p_value_limit {
            break;
        }
        out.push((k, f, dof, p_value));
    }
    out
}

/// Tests every channel of `session` at both ends of its dwells and cuts what passes from every dwell whose
/// rest keeps at least [`MIN_DWELL_SAMPLES`]; `None` when nothing passes.
pub(super) fn settle(session: &mut Session) -> Option<Settling> {
    let per = (SEGMENT_S / session.dt).round() as usize;
    if per < MIN_SEGMENT_SAMPLES {
        return None;
    }
    let channels: Vec<usize> = session.channels().collect();
    let limit = ALPHA / (2 * channels.len()) as f64;
    let mut passed = Vec::new();
    let mut cut = [0usize; 2];
    let mut tested_dwells = 0;
    for &c in &channels {
        let dwells: Vec<&[f64]> = session.dwells.iter().map(|d| &d.y[c][..]).collect();
        tested_dwells =
            tested_dwells.max(dwells.iter().filter(|y| y.len() / per >= 2 * MAX_SEGMENTS + DISTANCE + 2).count());
        for (e, from_end) in [false, true].into_iter().enumerate() {
            for (segment, f, dof, p_value) in passing(&dwells, per, from_end, limit) {
                cut[e] = cut[e].max(segment + 1);
                let end = if from_end { "end" } else { "start" };
                passed.push(SettlingTest { channel: CHANNELS[c].into(), end: end.into(), segment, f, dof, p_value });
            }
        }
    }
    if passed.is_empty() {
        return None;
    }
    let (start, end) = (cut[0] * per, cut[1] * per);
    let mut dwells = 0;
    for d in session.dwells.iter_mut().filter(|d| d.t.len() >= start + end + MIN_DWELL_SAMPLES) {
        let keep = start..d.t.len() - end;
        d.t = d.t[keep.clone()].to_vec();
        for y in d.y.iter_mut() {
            if !y.is_empty() {
                *y = y[keep.clone()].to_vec();
            }
        }
        if let Some(temp) = d.temp.as_mut() {
            *temp = temp[keep.clone()].to_vec();
        }
        dwells += 1;
    }
    let seconds = |n: usize| n as f64 * session.dt;
    Some(Settling { start_s: seconds(start), end_s: seconds(end), dwells, tested_dwells, passed })
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::model::simulator::normal;

    /// Twenty dwells of 10 s at 100 Hz: white noise of 1, a random walk of 0.02 a sample, a slope of 0.01 a
    /// second, and `start` times a decay of 0.3 s (a random sign per dwell) from each dwell's first sample.
    fn dwells(start: f64, seed: u64) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..20)
            .map(|_| {
                let sign = if normal(&mut rng) > 0.0 { 1.0 } else { -1.0 };
                let mut walk = 0.0;
                (0..1000)
                    .map(|i| {
                        let t = i as f64 / 100.0;
                        walk += 0.02 * normal(&mut rng);
                        normal(&mut rng) + walk + 0.01 * t + sign * start * (-t / 0.3).exp()
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn a_decay_after_each_move_is_found_at_the_start_and_wander_and_slopes_are_not() {
        let limit = ALPHA / 12.0;
        for seed in 0..5 {
            // A decay of 2 from each start: 0.74 over the first half-second's mean (against a segment's noise
            // of 0.14 and the walk's 0.45 over 2.5 s), 0.14 over the second's.
            let series = dwells(2.0, seed);
            let refs: Vec<&[f64]> = series.iter().map(|y| &y[..]).collect();
            let start = passing(&refs, 50, false, limit);
            assert!(!start.is_empty() && start.len() <= 2, "seed {seed}: {start:?}");
            assert!(start[0].3 < 1e-4, "seed {seed}: {start:?}");
            assert!(passing(&refs, 50, true, limit).is_empty(), "seed {seed}: the ends settled");
        }
        for seed in 0..30 {
            let series = dwells(0.0, 100 + seed);
            let refs: Vec<&[f64]> = series.iter().map(|y| &y[..]).collect();
            for from_end in [false, true] {
                assert!(passing(&refs, 50, from_end, limit).is_empty(), "seed {seed}: {from_end}");
            }
        }
    }
}
