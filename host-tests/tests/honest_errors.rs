//! Honest errors of a dwell mean (docs/method.md#honest-errors): the core's `DwellCollector` and
//! `pool_mean_noise` report for each channel the noise of a dwell mean from the dwells' own octave Allan
//! variance. Checked against
//! - the PSINS ring-laser-gyro record (real data): the record cut into consecutive dwells of 6, 60 and 300 s,
//!   the reported standard error of a dwell mean against the Allan deviation of the whole record at tau = T,
//!   on six dwell grids, with the ratio split into what the estimator measures and what the record's Allan
//!   curve does beyond it; with the HMM/KF prefilter also against the scatter of the filtered dwell values;
//! - the imu_tk Xsens poses (real data): the hand-placed poses pooled, against the poses' own scatter (the
//!   means of their two halves), and the long initial static interval cut into dwells, against its Allan
//!   deviation;
//! - a SIMULATION with coloured noise (quantisation, Gauss-Markov, rate random walk, white): the error of each
//!   dwell mean against the reported standard error, over 200 dwell sets per case.
//!
//! The real-data tests read the directory named by `SINSCAL_DATA` and report themselves skipped without it.
//! The tables they print are those of docs/method.md#honest-errors.

mod common;

use common::{data_dir, data_file};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use sinscal::calib::dwell::{
    allan_cluster_samples, allan_differences, pool_mean_noise, DwellCollector, DwellSummary, MeanNoise, Prefilter,
    ALLAN_LEVELS,
};
use sinscal::ImuSample;
use sinscal_host::io::import::{import_imutk, import_psins, StaticDetection};
use sinscal_host::io::recording::Row;
use sinscal_host::stats::noise::overlapping_allan_deviation;

const CHANNELS: [&str; 6] = ["gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z"];

fn channels(row: &Row) -> [f64; 6] {
    let (w, f) = (row.rate_b_radps, row.force_b_mps2);
    [w[0], w[1], w[2], f[0], f[1], f[2]]
}

/// One dwell through the core's collector.
fn summarise(collector: &mut DwellCollector, samples: &[[f64; 6]]) -> DwellSummary {
    collector.reset();
    for z in samples {
        let z = z.map(|v| v as f32);
        let sample = ImuSample { rate_b_radps: [z[0], z[1], z[2]], force_b_mps2: [z[3], z[4], z[5]] };
        collector.update(&sample).unwrap();
    }
    collector.summary().unwrap()
}

/// The dwell value (the mean of the filtered or raw channel) of channel `i`.
fn dwell_value(s: &DwellSummary, i: usize) -> f64 {
    (if i < 3 { s.rate_mean_b_radps[i] } else { s.force_mean_b_mps2[i - 3] }) as f64
}

/// The old white-noise standard error of a dwell mean: the pooled per-sample standard deviation / sqrt(N).
fn white_std_of_mean(summaries: &[DwellSummary], i: usize, n: f64) -> f64 {
    let var: f64 = summaries
        .iter()
        .map(|s| (if i < 3 { s.rate_sample_std_b_radps[i] } else { s.force_sample_std_b_mps2[i - 3] } as f64).powi(2))
        .sum::<f64>()
        / summaries.len() as f64;
    (var / n).sqrt()
}

/// Reported standard error of the mean of `n` samples.
fn reported(noise: &MeanNoise, n: f64) -> f64 {
    (noise.white_equivalent_var as f64 / n).sqrt()
}

/// Half the mean square difference of neighbouring values, square-rooted: for the values of consecutive dwells
/// the Allan deviation of the dwell values themselves at tau = the dwell length.
fn adjacent_deviation(values: &[f64]) -> f64 {
    let d = values.len() - 1;
    (values.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2 * d) as f64).sqrt()
}

fn prefilter_name(p: &Prefilter) -> &'static str {
    match p {
        Prefilter::None => "none",
        _ => "HMM/KF",
    }
}

/// The pooled Allan variance of channel `i` at `level` over the dwells, and its number of differences.
fn pooled_allan(summaries: &[DwellSummary], i: usize, level: usize) -> (f64, f64) {
    let (mut sum, mut count) = (0.0, 0.0);
    for s in summaries {
        let d = allan_differences(s.samples, level) as f64;
        sum += d * s.allan[i].avar[level] as f64;
        count += d;
    }
    (sum / count, count)
}

/// The Allan level of a cluster size.
fn level_of(cluster_samples: u32) -> usize {
    (0..ALLAN_LEVELS).find(|&j| allan_cluster_samples(j) == cluster_samples).unwrap()
}

/// In the acceptance band of a ratio of standard errors.
fn in_band(ratio: f64) -> bool {
    (0.8..=1.25).contains(&ratio)
}

/// The PSINS record, its rate and the whole record's overlapping Allan deviation of each channel at the octave
/// cluster sizes of the core and at the dwell lengths.
struct Psins {
    xs: Vec<[f64; 6]>,
    rate_hz: f64,
    sizes: Vec<usize>,
    adev: Vec<Vec<f64>>,
}

impl Psins {
    fn read(dir: &std::path::Path, lengths: &[usize]) -> Psins {
        let rec = import_psins(&data_file(dir, "psins-lasergyro/lasergyro.imu"), None).unwrap().recording;
        let rate_hz = rec.header.rate_hz.unwrap();
        let xs: Vec<[f64; 6]> = rec.rows.iter().map(channels).collect();
        let sizes: Vec<usize> =
            (0..ALLAN_LEVELS).map(|j| allan_cluster_samples(j) as usize).chain(lengths.iter().copied()).collect();
        let adev = (0..6)
            .map(|i| {
                let ch: Vec<f64> = xs.iter().map(|z| z[i]).collect();
                let points = overlapping_allan_deviation(&ch, rate_hz, &sizes);
                sizes
                    .iter()
                    .map(|&m| points.iter().find(|p| p.cluster_size == m).map_or(f64::NAN, |p| p.adev))
                    .collect()
            })
            .collect();
        Psins { xs, rate_hz, sizes, adev }
    }

    /// The whole record's Allan deviation of channel `i` at `m` samples.
    fn allan(&self, i: usize, m: usize) -> f64 {
        self.adev[i][self.sizes.iter().position(|&c| c == m).unwrap()]
    }

    /// How the whole record's white-equivalent variance `m AVAR(m)` changes from the cluster size `m` to the
    /// dwell length `n`, as a factor on a standard error: `sqrt(q(m) / q(n))`. 1 for white noise; above 1 when
    /// the Allan curve falls faster than white noise beyond `m` (white extrapolation is then conservative),
    /// below 1 when it rises (then it is low).
    fn curve(&self, i: usize, m: usize, n: usize) -> f64 {
        (m as f64 * self.allan(i, m).powi(2) / (n as f64 * self.allan(i, n).powi(2))).sqrt()
    }
}

#[test]
fn psins_ring_laser_gyro_reported_errors_against_the_allan_deviation() {
    let Some(dir) = data_dir() else { return };
    let lengths = [600usize, 6000, 30000];
    let data = Psins::read(&dir, &lengths);
    let (xs, rate_hz) = (&data.xs, data.rate_hz);

    // 1. The record cut into consecutive dwells of T from its first sample, as the acceptance asks.
    println!(
        "REAL DATA psins-lasergyro: {} samples at {rate_hz} Hz, consecutive dwells of T from the first sample",
        xs.len()
    );
    println!(
        "{:8} {:>4} {:>7} {:>6} {:>6} {:>5} {:>10} {:>10} {:>6} {:>4} {:>10} {:>6} {:>6}",
        "channel",
        "T s",
        "filter",
        "dwells",
        "m",
        "dof",
        "reported",
        "Allan(T)",
        "ratio",
        "band",
        "old white",
        "old/A",
        "curve"
    );
    let mut in_band_count = [0usize; 2];
    let mut range = [(f64::INFINITY, 0.0f64); 2];
    for (k, prefilter) in [Prefilter::None, Prefilter::paper()].into_iter().enumerate() {
        let mut collector = DwellCollector::new(&prefilter).unwrap();
        for &n in &lengths {
            let summaries: Vec<DwellSummary> = xs.chunks_exact(n).map(|d| summarise(&mut collector, d)).collect();
            let pooled = pool_mean_noise(summaries.iter().copied());
            for i in 0..6 {
                let rep = reported(&pooled[i], n as f64);
                let allan = data.allan(i, n);
                let old = white_std_of_mean(&summaries, i, n as f64);
                let m = pooled[i].cluster_samples as usize;
                let ratio = rep / allan;
                in_band_count[k] += in_band(ratio) as usize;
                range[k] = (range[k].0.min(ratio), range[k].1.max(ratio));
                println!(
                    "{:8} {:>4} {:>7} {:>6} {:>6} {:>5} {:>10.3e} {:>10.3e} {:>6.2} {:>4} {:>10.3e} {:>6.2} {:>6.2}",
                    CHANNELS[i],
                    n as f64 / rate_hz,
                    prefilter_name(&prefilter),
                    summaries.len(),
                    m,
                    pooled[i].dof,
                    rep,
                    allan,
                    ratio,
                    if in_band(ratio) { "in" } else { "OUT" },
                    old,
                    old / allan,
                    data.curve(i, m, n)
                );
            }
        }
    }
    println!(
        "in [0.8, 1.25]: {} of 18 without prefilter (ratios {:.2}..{:.2}), {} of 18 with HMM/KF (ratios {:.2}..{:.2}; \
         against the raw record, which does not contain the prefilter's start, see part 3)",
        in_band_count[0], range[0].0, range[0].1, in_band_count[1], range[1].0, range[1].1
    );
    // The acceptance band is not met on this record (docs/method.md#honest-errors says where and why); what
    // holds on this grid: every channel and length within a factor 3 (the white-noise formula: 0.17 to 18).
    assert!(range[0].0 > 1.0 / 3.0 && range[0].1 < 3.0, "ratios {:?}", range[0]);

    // 2. Without prefilter on six dwell grids (the first dwell at 0, T/6, ..., 5T/6): how much of one grid's
    // ratio is the luck of where the vehicle's disturbances fall. The ratio is the product of three factors:
    // estimation (the pooled within-dwell Allan deviation at the cluster size m against the whole record's
    // there), growth (the rise carried on from m to T, 1 when none; as a factor on the standard error) and
    // the record's curve between m and T (`Psins::curve`).
    println!("six grids, the first dwell at k T / 6; geometric means over the grids (min..max of the ratio)");
    println!(
        "{:8} {:>4} {:>6} {:>6} {:>12} {:>6} {:>6} {:>6}  verdict",
        "channel", "T s", "m", "ratio", "min..max", "estim", "growth", "curve"
    );
    let mut collector = DwellCollector::new(&Prefilter::None).unwrap();
    for &n in &lengths {
        let grids: Vec<Vec<DwellSummary>> =
            (0..6).map(|k| xs[k * n / 6..].chunks_exact(n).map(|d| summarise(&mut collector, d)).collect()).collect();
        for i in 0..6 {
            let (mut ratios, mut estimation, mut growth, mut m) = (Vec::new(), 0.0, 0.0, 0);
            for summaries in &grids {
                let noise = pool_mean_noise(summaries.iter().copied())[i];
                m = noise.cluster_samples as usize;
                let (avar, _) = pooled_allan(summaries, i, level_of(noise.cluster_samples));
                ratios.push(reported(&noise, n as f64) / data.allan(i, n));
                estimation += (avar.sqrt() / data.allan(i, m)).ln() / 6.0;
                growth += (noise.white_equivalent_var as f64 / (m as f64 * avar)).sqrt().ln() / 6.0;
            }
            let ratio = (ratios.iter().map(|r| r.ln()).sum::<f64>() / 6.0).exp();
            let (min, max) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
            let (estimation, growth) = (estimation.exp(), growth.exp());
            let curve = data.curve(i, m, n);
            // The estimator measures what it claims: the record's own Allan deviation at the cluster size.
            assert!(in_band(estimation), "{} T = {n}: estimation factor {estimation:.2}", CHANNELS[i]);
            // And a ratio outside the band is the record's curve beyond the cluster size: above the band only
            // where the curve falls (white extrapolation conservative), below it only where it rises.
            let verdict = if in_band(ratio) {
                "in band"
            } else if ratio > 1.0 {
                assert!(curve > 1.0, "{} T = {n}: ratio {ratio:.2} with a rising curve {curve:.2}", CHANNELS[i]);
                "curve falls beyond m: conservative"
            } else {
                assert!(curve < 1.0, "{} T = {n}: ratio {ratio:.2} with a falling curve {curve:.2}", CHANNELS[i]);
                "curve rises beyond m: LOW"
            };
            println!(
                "{:8} {:>4} {:>6} {:>6.2} {:>5.2}..{:<5.2} {:>6.2} {:>6.2} {:>6.2}  {verdict}",
                CHANNELS[i],
                n as f64 / rate_hz,
                m,
                ratio,
                min,
                max,
                estimation,
                growth,
                curve
            );
        }
    }

    // 3. With the HMM/KF prefilter the dwell value is the filtered mean: the raw mean plus the term of the
    // filter's start, which the raw record's Allan deviation does not contain. Its honest reference is the
    // scatter of the filtered dwell values themselves, for dwells separated by 1 s (as on a turntable, so that
    // one dwell's end and the next one's start are not neighbouring samples).
    println!("HMM/KF: dwells of T separated by 1 s; reported against the scatter of the filtered dwell values");
    println!(
        "{:8} {:>4} {:>6} {:>10} {:>10} {:>6} {:>10} {:>10}",
        "channel", "T s", "dwells", "reported", "scatter", "ratio", "start part", "Allan(T)"
    );
    let mut collector = DwellCollector::new(&Prefilter::paper()).unwrap();
    let gap = rate_hz as usize;
    for &n in &lengths[..2] {
        let summaries: Vec<DwellSummary> =
            xs.chunks_exact(n + gap).map(|d| summarise(&mut collector, &d[..n])).collect();
        let pooled = pool_mean_noise(summaries.iter().copied());
        for i in 0..6 {
            let rep = reported(&pooled[i], n as f64);
            let values: Vec<f64> = summaries.iter().map(|s| dwell_value(s, i)).collect();
            let scatter = adjacent_deviation(&values);
            let start_var =
                summaries.iter().map(|s| s.allan[i].prefilter_start_var as f64).sum::<f64>() / summaries.len() as f64;
            // Where the start dominates and the reference rests on hundreds of dwells (the 6-s accelerometers:
            // the accelerometer counts are 0.12 m/s^2 steps), the start term must be right.
            if start_var > 0.5 * rep * rep && summaries.len() >= 100 {
                assert!(in_band(rep / scatter), "{} T = {n}: {rep:.3e} vs scatter {scatter:.3e}", CHANNELS[i]);
            }
            println!(
                "{:8} {:>4} {:>6} {:>10.3e} {:>10.3e} {:>6.2} {:>10.3e} {:>10.3e}",
                CHANNELS[i],
                n as f64 / rate_hz,
                summaries.len(),
                rep,
                scatter,
                rep / scatter,
                start_var.sqrt(),
                data.allan(i, n)
            );
        }
    }
}

#[test]
fn imutk_xsens_reported_errors_against_the_scatter_of_the_data() {
    let Some(dir) = data_dir() else { return };
    let acc = data_file(&dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = data_file(&dir, "imu-tk-xsens/xsens_gyro.mat");
    let rec = import_imutk(&acc, &gyro, None, &StaticDetection::default()).unwrap().recording;
    let rate_hz = rec.header.rate_hz.unwrap();
    let poses: Vec<Vec<[f64; 6]>> = rec.dwells().iter().map(|d| d.rows.iter().map(|r| channels(r)).collect()).collect();
    let (first, rest) = poses.split_first().unwrap();
    let mut lengths: Vec<usize> = rest.iter().map(|p| p.len()).collect();
    lengths.sort_unstable();
    let median = lengths[lengths.len() / 2];
    println!(
        "REAL DATA imu-tk-xsens, no prefilter: {} poses; the first {} samples, the {} hand-placed ones {}..{} samples \
         (median {median})",
        poses.len(),
        first.len(),
        rest.len(),
        lengths[0],
        lengths[lengths.len() - 1],
    );
    println!(
        "{:8} {:>5} {:>4} {:>10} {:>10} {:>6} {:>10} {:>6} {:>24} | {:>10} {:>10} {:>6}",
        "channel",
        "m",
        "dof",
        "reported",
        "halves",
        "ratio",
        "old white",
        "old/h",
        "q(m)/q(64), m = 128, 256",
        "first",
        "Allan(N)",
        "ratio"
    );
    let mut collector = DwellCollector::new(&Prefilter::None).unwrap();
    let summaries: Vec<DwellSummary> = rest.iter().map(|p| summarise(&mut collector, p)).collect();
    let pooled = pool_mean_noise(summaries.iter().copied());
    // The first (long) static interval cut into dwells of the median pose length, as a session of its own.
    let quiet: Vec<DwellSummary> = first.chunks_exact(median).map(|d| summarise(&mut collector, d)).collect();
    let quiet_pooled = pool_mean_noise(quiet.iter().copied());
    for i in 0..6 {
        // The poses' own scatter at their length: the difference of the means of the two halves of a pose,
        // over 2, has the variance of the pose mean's error for white noise (it is the Allan deviation at half
        // the pose length over sqrt 2). RMS over the poses, against the RMS of the reported standard errors
        // at each pose's length and of the white-noise formula.
        let (mut halves, mut rep, mut old) = (0.0, 0.0, 0.0);
        for (p, s) in rest.iter().zip(&summaries) {
            let h = p.len() / 2;
            let mean = |xs: &[[f64; 6]]| xs.iter().map(|z| z[i]).sum::<f64>() / xs.len() as f64;
            halves += ((mean(&p[h..2 * h]) - mean(&p[..h])) / 2.0).powi(2);
            rep += reported(&pooled[i], p.len() as f64).powi(2);
            old += white_std_of_mean(std::slice::from_ref(s), i, p.len() as f64).powi(2);
        }
        let count = rest.len() as f64;
        let (halves, rep, old) = ((halves / count).sqrt(), (rep / count).sqrt(), (old / count).sqrt());
        // How the pooled white-equivalent variance of the poses runs with the cluster size.
        let q = |j: usize| allan_cluster_samples(j) as f64 * pooled_allan(&summaries, i, j).0;
        let (q1, q2) = (q(1) / q(0), q(2) / q(0));
        let ch: Vec<f64> = first.iter().map(|z| z[i]).collect();
        let first_allan = overlapping_allan_deviation(&ch, rate_hz, &[median])[0].adev;
        let quiet_rep = reported(&quiet_pooled[i], median as f64);
        println!(
            "{:8} {:>5} {:>4} {:>10.3e} {:>10.3e} {:>6.2} {:>10.3e} {:>6.2} {:>14.2} {:>9.2} | {:>10.3e} {:>10.3e} {:>6.2}",
            CHANNELS[i],
            pooled[i].cluster_samples,
            pooled[i].dof,
            rep,
            halves,
            rep / halves,
            old,
            old / halves,
            q1,
            q2,
            quiet_rep,
            first_allan,
            quiet_rep / first_allan,
        );
        // The quiet start: in the band on every channel.
        assert!(in_band(quiet_rep / first_allan), "{} first interval: {:.2}", CHANNELS[i], quiet_rep / first_allan);
        if q2 < 4.0 {
            assert!(in_band(rep / halves), "{} poses: {:.2}", CHANNELS[i], rep / halves);
        } else {
            // The hand-placed poses of accelerometer z are not still: m AVAR(m) grows more than 4-fold from
            // 0.64 s to 2.56 s. The rise is carried on to the pose length (at most 4-fold), above the halves,
            // which assume white noise from half the pose to the whole: conservative against them, by at
            // most the cap's factor 2.
            assert!((1.0..2.0).contains(&(rep / halves)), "{} poses: {:.2}", CHANNELS[i], rep / halves);
        }
    }
}

/// SIMULATION: per-sample noise of one channel, in units of the white noise: white, quantisation (`e_k -
/// e_{k-1}`, the increments of a quantised integral), Gauss-Markov (standard deviation, correlation time in
/// samples) and rate random walk (step per sample).
#[derive(Clone, Copy, Debug)]
struct ColouredNoise {
    white: f64,
    quantisation: f64,
    markov_sigma: f64,
    markov_samples: f64,
    random_walk: f64,
}

/// A continuous record of `len` samples of six independent channels with `noise`, about realistic offsets (9.8
/// m/s^2 on accelerometer z) and scales (gyro 1e-4 rad/s, accelerometer 1e-3 m/s^2 per unit), Gauss-Markov
/// started in its stationary distribution, the random walk at 0.
fn simulate(noise: &ColouredNoise, len: usize, rng: &mut ChaCha8Rng) -> Vec<[f64; 6]> {
    const OFFSET: [f64; 6] = [1e-5, 2e-5, 7e-5, 0.1, -0.2, 9.8];
    const SCALE: [f64; 6] = [1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3];
    let phi = (-1.0 / noise.markov_samples).exp();
    let drive = noise.markov_sigma * (1.0 - phi * phi).sqrt();
    let mut normal = move || -> f64 { StandardNormal.sample(rng) };
    let mut markov: [f64; 6] = std::array::from_fn(|_| noise.markov_sigma * normal());
    let mut previous: [f64; 6] = std::array::from_fn(|_| noise.quantisation * normal());
    let mut walk = [0.0f64; 6];
    (0..len)
        .map(|_| {
            std::array::from_fn(|i| {
                let e = noise.quantisation * normal();
                markov[i] = phi * markov[i] + drive * normal();
                walk[i] += noise.random_walk * normal();
                let v = noise.white * normal() + (e - previous[i]) + markov[i] + walk[i];
                previous[i] = e;
                OFFSET[i] + SCALE[i] * v
            })
        })
        .collect()
}

/// SIMULATION: `sets` sessions of `dwells` dwells of `n` samples, separated by 100 samples (a turntable move),
/// each pooled; the RMS over the 6 channels and all dwells of (error of a dwell mean / reported standard
/// error), without prefilter and with HMM/KF, then the same with the old white-noise standard error. The
/// error of a dwell mean is taken against its neighbour, in the Allan sense: (ybar_k - ybar_{k-1}) / sqrt 2,
/// whose variance is the Allan variance at the dwell length for any of these noises (for white noise and the
/// other stationary ones it is the variance of the error against the truth).
fn simulate_sessions(noise: &ColouredNoise, n: usize, dwells: usize, sets: usize, seed: u64) -> [f64; 4] {
    let gap = 100;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut collectors =
        [DwellCollector::new(&Prefilter::None).unwrap(), DwellCollector::new(&Prefilter::paper()).unwrap()];
    let (mut sum, mut count) = ([0.0f64; 4], 0.0);
    for _ in 0..sets {
        let xs = simulate(noise, (n + gap) * dwells, &mut rng);
        for (k, collector) in collectors.iter_mut().enumerate() {
            let summaries: Vec<DwellSummary> =
                xs.chunks_exact(n + gap).map(|d| summarise(collector, &d[..n])).collect();
            let pooled = pool_mean_noise(summaries.iter().copied());
            for i in 0..6 {
                let rep = reported(&pooled[i], n as f64);
                let old = white_std_of_mean(&summaries, i, n as f64);
                for w in summaries.windows(2) {
                    let error = (dwell_value(&w[1], i) - dwell_value(&w[0], i)) / 2f64.sqrt();
                    sum[k] += (error / rep).powi(2);
                    sum[k + 2] += (error / old).powi(2);
                    count += (k == 0) as u8 as f64;
                }
            }
        }
    }
    sum.map(|s| (s / count).sqrt())
}

#[test]
fn simulation_coloured_noise_reported_errors_are_honest() {
    // SIMULATION (no real data). "mix": quantisation dominates the sample-to-sample scatter, a Gauss-Markov term
    // of 0.5 s dominates the dwell means, a rate random walk adds a fifth to the variance of a 60-s mean, white
    // noise as much as the Gauss-Markov's per-sample sigma. "quantised": a ring-laser-gyro-like channel, the
    // per-sample scatter ten times the white noise that the means see; with the HMM/KF prefilter the filter's
    // start then dominates a 6-s mean. "white": the control.
    let mix =
        ColouredNoise { white: 1.0, quantisation: 3.0, markov_sigma: 1.0, markov_samples: 50.0, random_walk: 1.3e-3 };
    let quantised =
        ColouredNoise { white: 1.0, quantisation: 10.0, markov_sigma: 0.0, markov_samples: 1.0, random_walk: 0.0 };
    let white =
        ColouredNoise { white: 1.0, quantisation: 0.0, markov_sigma: 0.0, markov_samples: 1.0, random_walk: 0.0 };
    println!("SIMULATION: RMS of (error of a dwell mean / reported standard error), 6 channels, 200 sessions per case");
    println!(
        "{:10} {:>6} {:>6} {:>8} {:>8} {:>10} {:>10}",
        "noise", "N", "dwells", "none", "HMM/KF", "old none", "old HMM/KF"
    );
    for (name, noise, n, dwells, seed) in [
        ("mix", mix, 6000, 6, 952),
        ("mix", mix, 600, 10, 953),
        ("quantised", quantised, 600, 10, 954),
        ("white", white, 6000, 6, 955),
    ] {
        let rms = simulate_sessions(&noise, n, dwells, 200, seed);
        println!("{name:10} {n:>6} {dwells:>6} {:>8.3} {:>8.3} {:>10.3} {:>10.3}", rms[0], rms[1], rms[2], rms[3]);
        for (k, filter) in ["none", "HMM/KF"].iter().enumerate() {
            if name == "quantised" && k == 0 {
                // Quantisation noise falls as 1 / m^2 in Allan variance: white extrapolation from 128 samples
                // to 600 overstates the mean's noise (conservative, the documented side of the limit).
                assert!((0.5..1.0).contains(&rms[k]), "{name} N = {n} {filter}: RMS {:.3}", rms[k]);
            } else {
                assert!((0.8..=1.2).contains(&rms[k]), "{name} N = {n} {filter}: RMS {:.3}", rms[k]);
            }
        }
    }
    // The limits (docs/method.md#honest-errors), printed, not in the band: noise whose white-equivalent variance
    // rises between the cluster size and the dwell length without showing it below the cluster size.
    let walk =
        ColouredNoise { white: 1.0, quantisation: 0.0, markov_sigma: 0.0, markov_samples: 1.0, random_walk: 3e-4 };
    let slow =
        ColouredNoise { white: 1.0, quantisation: 0.0, markov_sigma: 0.1, markov_samples: 1000.0, random_walk: 0.0 };
    for (name, noise, n, dwells, seed) in [("walk", walk, 6000, 6, 956), ("markov 10s", slow, 600, 10, 957)] {
        let rms = simulate_sessions(&noise, n, dwells, 100, seed);
        println!(
            "{name:10} {n:>6} {dwells:>6} {:>8.3} {:>8.3} {:>10.3} {:>10.3}  (limit, not asserted)",
            rms[0], rms[1], rms[2], rms[3]
        );
    }
}
