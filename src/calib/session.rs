//! A session's dwell statistics into the general estimator (docs/method.md#general-estimator): one function
//! that the workstation's `calibrate` and the firmware's calibration sequence both call, so that the same
//! dwells give the same estimator input, bit for bit, on either machine.
//!
//! Each dwell contributes its mean (or the prefilter's settled value) and the variance of that mean: with a
//! noise model ([`ChannelSettings::noise`], docs/method.md#noise-model) the model's at the dwell's length;
//! without, the session's pooled honest noise of the raw mean ([`pool_mean_noise`],
//! docs/method.md#honest-errors) over the dwell's number of samples. Either is never below the f32 resolution
//! of a mean (2^-23 of the Earth rate, of g), which keeps the weights finite on noise-free data. With a noise
//! model and each dwell's first sample, the estimator also takes the correlation between dwells into the
//! covariance.

use crate::calib::align::DwellValue;
use crate::calib::dwell::{pool_mean_noise, DwellSummary};
use crate::calib::general::{
    AttitudeKnowledge, ChannelDwell, ChannelError, ChannelEstimator, ChannelSettings, Model, Term, MAX_DWELLS,
};
use crate::calib::noise_model::Window;
use crate::nav::earth::{Site, EARTH_RATE_RADPS};
use crate::nav::frames::Attitude;

/// The general estimator's terms unless told otherwise, chosen by measurement
/// (docs/method.md#default-estimator): gyro and accelerometer biases and the accelerometer scale factors.
/// Under a real laboratory's errors the scale factor keeps the gravity model's error and the vertical scale
/// factor out of the vertical bias.
pub const DEFAULT_MODEL: Model = Model::BIASES.with(Term::AccelScaleFactor);

/// Whether gyros of per-sample noise variance `noise_var` (the pooled white-equivalent noise, gyro x, y, z first)
/// resolve the Earth rate in dwells of `samples` (at most [`MAX_DWELLS`] are counted): the standard error of the
/// median dwell's mean, on its worst axis, is below a third of the Earth rate.
pub fn gyros_resolve_earth_rate(noise_var: &[f32; 6], samples: impl Iterator<Item = u32>) -> bool {
    let mut counts = [0u32; MAX_DWELLS];
    let mut n = 0;
    for (slot, s) in counts.iter_mut().zip(samples) {
        *slot = s;
        n += 1;
    }
    if n == 0 {
        return false;
    }
    // Insertion sort: at most 64 counts, and a few dozen bytes of code where `sort_unstable` costs kilobytes.
    for k in 1..n {
        let mut j = k;
        while j > 0 && counts[j - 1] > counts[j] {
            counts.swap(j - 1, j);
            j -= 1;
        }
    }
    let median = counts[n / 2].max(1) as f32;
    let worst = noise_var[..3].iter().fold(0.0f32, |m, v| m.max(*v));
    libm::sqrtf(worst / median) < EARTH_RATE_RADPS / 3.0
}

/// The general estimator's settings with the default terms.
pub fn default_channel_settings() -> ChannelSettings {
    ChannelSettings { model: DEFAULT_MODEL, ..ChannelSettings::default() }
}

/// One dwell of a session.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SessionDwell<'a> {
    /// The reference attitude (its heading is ignored when `heading_known` is false).
    pub attitude: Attitude,
    /// Whether the reference gives the heading.
    pub heading_known: bool,
    /// The dwell's statistics.
    pub summary: &'a DwellSummary,
    /// The index of the dwell's first sample in the session (from its first sample); with a noise model, the
    /// dwells' windows give the correlation between them (docs/method.md#noise-model). `None`: not known.
    pub first_sample: Option<u32>,
}

/// Smallest variance of a dwell mean, (unit)^2: the f32 resolution of a mean of magnitude `scale`.
fn resolution_floor(scale: f32) -> f32 {
    (1.2e-7 * scale) * (1.2e-7 * scale)
}

/// The estimator loaded with a session's dwells, ready to solve: the pooled noise of the session over each
/// dwell's samples, the dwell value `dwell_value`. Errors are the estimator's refusals (with the dwell's
/// index in the order given).
pub fn session_estimator<'a, I>(
    dwells: I,
    site: Site,
    settings: ChannelSettings,
    dwell_value: DwellValue,
) -> Result<ChannelEstimator, ChannelError>
where
    I: Iterator<Item = SessionDwell<'a>> + Clone,
{
    // The pooled noise of the dwell mean (the raw mean of the used samples, with or without prefilter).
    let raw_q = pool_mean_noise(dwells.clone().map(|d| *d.summary)).map(|m| m.white_equivalent_var);
    let (rate_floor, force_floor) = (resolution_floor(EARTH_RATE_RADPS), resolution_floor(site.gravity_mps2));
    let mut settings = settings;
    // A heading the data would give only through the Earth rate (attitudes unknown, or a heading not given)
    // needs gyros that resolve it; otherwise the Earth rate is left out (docs/method.md#unknown-attitudes).
    let heading_from_earth_rate =
        settings.attitude == AttitudeKnowledge::Unknown || dwells.clone().any(|d| !d.heading_known);
    if settings.use_gyro && heading_from_earth_rate {
        settings.earth_rate_resolved &= gyros_resolve_earth_rate(&raw_q, dwells.clone().map(|d| d.summary.samples));
    }
    let mut estimator = ChannelEstimator::new(site, settings);
    for d in dwells {
        let s = d.summary;
        let (rate, force) = match dwell_value {
            DwellValue::Mean => (s.rate_mean_b_radps, s.force_mean_b_mps2),
            DwellValue::Settled => (s.rate_settled_b_radps, s.force_settled_b_mps2),
        };
        let n = s.samples.max(1) as f32;
        let variance = |i: usize| match &settings.noise {
            Some(model) => model.mean_variance(i, s.samples),
            None => raw_q[i] / n,
        };
        estimator.add(ChannelDwell {
            tilt: d.attitude.tilt(),
            heading_rad: d.heading_known.then_some(d.attitude.heading_rad),
            rate_mean_b_radps: rate,
            force_mean_b_mps2: force,
            rate_mean_var_b_radps2: [0, 1, 2].map(|i| variance(i).max(rate_floor)),
            force_mean_var_b_mps2sq: [0, 1, 2].map(|i| variance(3 + i).max(force_floor)),
            // The dwell's span: the samples used and those left out as spikes (saturating: a stored outcome read back
            // may carry any counts).
            window: d
                .first_sample
                .map(|first_sample| Window { first_sample, samples: s.samples.saturating_add(s.spikes) }),
        })?;
    }
    Ok(estimator)
}
