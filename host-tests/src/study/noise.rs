//! The noise of one channel against the BASE model: white noise whose standard deviation per sample is the
//! Allan deviation at one sample, its seeded SIMULATION, and where the two Allan deviation curves disagree. The
//! Allan deviation helpers (cluster sizes, curves, the longest reliable tau, the RMS log10 disagreement) live
//! here too; the IEEE 952 extension is [`super::noise_extension`].

use super::generate::white;
use super::noise_extension::held_out_noise_extension;
use super::{rms, ChannelNoise, Curve};
use crate::stats::noise::{
    detect_quantization, is_print_step, log_spaced_clusters, overlapping_allan_deviation, print_step,
};

/// RMS of first differences / sqrt 2 of several segments pooled, SI: the ADEV at one sample.
pub(crate) fn white_std(segments: &[&[f64]]) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for seg in segments {
        for w in seg.windows(2) {
            s += (w[1] - w[0]).powi(2);
            n += 1;
        }
    }
    (s / (2.0 * n.max(1) as f64)).sqrt()
}

/// Cluster sizes for a record of `n` samples: about 6 per decade, up to n / 3.
pub(crate) fn clusters(n: usize) -> Vec<usize> {
    log_spaced_clusters(n, 6).into_iter().filter(|m| *m * 3 <= n).collect()
}

/// The overlapping Allan deviation of `samples` at the cluster sizes `m`.
pub(crate) fn curve(samples: &[f64], rate_hz: f64, m: &[usize]) -> Curve {
    let p = overlapping_allan_deviation(samples, rate_hz, m);
    Curve { tau_s: p.iter().map(|q| q.tau_s).collect(), adev: p.iter().map(|q| q.adev).collect() }
}

/// The largest tau with K = N / m >= 9 clusters (relative uncertainty <= 0.25), as an index into `m`.
pub(crate) fn long_index(n: usize, m: &[usize]) -> usize {
    m.iter().rposition(|&c| c * 9 <= n).unwrap_or(0)
}

/// RMS over the points with K >= 9 of log10(sim / data).
pub(crate) fn rms_log10(sim: &Curve, data: &Curve, n: usize, rate_hz: f64) -> f64 {
    rms(sim
        .tau_s
        .iter()
        .zip(&sim.adev)
        .zip(&data.adev)
        .filter(|((t, _), _)| (*t * rate_hz).round() as usize * 9 <= n)
        .map(|((_, s), d)| (s / d).log10()))
}

/// The noise study of one channel of a single static record: base white SIMULATION, ADEV disagreement, and the
/// IEEE 952 extension fitted on the first half and evaluated on the second (records of at least 2000 samples).
pub fn channel_noise(channel: &'static str, samples: &[f64], rate_hz: f64, seed: u64, stream: u64) -> ChannelNoise {
    let n = samples.len();
    let m = clusters(n);
    let sigma = white_std(&[samples]);
    let data = curve(samples, rate_hz, &m);
    let base_sim = curve(&white(n, sigma, seed, stream), rate_hz, &m);
    let li = long_index(n, &m).min(data.adev.len().saturating_sub(1));
    let ratio = data.adev.get(li).copied().unwrap_or(f64::NAN) / base_sim.adev.get(li).copied().unwrap_or(f64::NAN);
    let extended = (n / 2 >= 1000).then(|| held_out_noise_extension(samples, rate_hz, &m, seed, stream));
    // A lattice at the file's printed digits is not the sensor's step.
    let printed = print_step(&[samples]);
    let quantization_step =
        detect_quantization(samples).ok().filter(|q| q.quantized && !is_print_step(q.step, printed)).map(|q| q.step);
    ChannelNoise {
        channel,
        white_std: sigma,
        rate_hz,
        rms_log10_base: rms_log10(&base_sim, &data, n, rate_hz),
        long_tau_s: m.get(li).map_or(f64::NAN, |c| *c as f64 / rate_hz),
        ratio_at_long_tau: ratio,
        data,
        base_sim,
        quantization_step,
        extended,
    }
}
