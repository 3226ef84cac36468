//! Honest errors of a dwell mean (docs/method.md#honest-errors): the core's `DwellCollector` and
//! `pool_mean_noise` report for each channel the noise of a dwell mean from the dwells' own octave Allan
//! variance. Checked against
//! - the PSINS ring-laser-gyro record (real data): the record cut into consecutive dwells of 6, 60 and 300 s,
//!   the reported standard error of a dwell mean against the Allan deviation of the whole record at tau = T,
//!   on six dwell grids, with the ratio split into what the estimator measures and what the record's Allan
//!   curve does beyond it, and the slope the dwells show against the one beyond them; with the HMM/KF
//!   prefilter also against the scatter of the filtered dwell values;
//! - the imu_tk Xsens poses (real data): the hand-placed poses cut into their halves, which are the session's
//!   dwells, against the Allan deviation of the halves' means (two adjacent dwells at one attitude), and the
//!   long initial static interval cut into dwells, against its Allan deviation;
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
    ALLAN_LEVELS, MAX_NOISE_GROWTH,
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
    psins_consecutive_dwells(&data, &lengths);
    psins_six_grids(&data, &lengths);
    psins_prefilter_scatter(&data, &lengths[..2]);
}

/// Part 1, the record cut into consecutive dwells of T from its first sample, as the acceptance asks.
fn psins_consecutive_dwells(data: &Psins, lengths: &[usize]) {
    let (xs, rate_hz) = (&data.xs, data.rate_hz);
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
        for &n in lengths {
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
}

/// The slope of `log2 q`, `q = m AVAR(m)`, over the pooled level `top` and the two below it, weighted by their
/// differences as the core weighs them, per octave of cluster size, and its standard error: the rise or fall
/// that the dwells themselves show.
fn seen_slope(summaries: &[DwellSummary], i: usize, top: usize) -> (f64, f64) {
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for j in top.saturating_sub(2)..=top {
        let (avar, d) = pooled_allan(summaries, i, j);
        if d > 0.0 && avar > 0.0 {
            let w = d * std::f64::consts::LN_2.powi(2) / 2.0;
            let (x, y) = (j as f64, (allan_cluster_samples(j) as f64 * avar).log2());
            (sw, sx, sy, sxx, sxy) = (sw + w, sx + w * x, sy + w * y, sxx + w * x * x, sxy + w * x * y);
        }
    }
    let det = sw * sxx - sx * sx;
    ((sw * sxy - sx * sy) / det, (sw / det).sqrt())
}

/// Part 2, without prefilter on six dwell grids (the first dwell at 0, T/6, ..., 5T/6): how much of one grid's ratio
/// is the luck of where the vehicle's disturbances fall, and what the dwells can know of the rest. The ratio is
/// the product of four factors: estimation (the pooled within-dwell Allan deviation at the cluster size m
/// against the whole record's there), the factor `sqrt(1 + 2 / D)` for the estimate's noise, growth (the rise
/// carried on from m to T, 1 when none; as a factor on the standard error) and the record's curve between m and
/// T (`Psins::curve`). "seen" is the slope of `log2 q` that the pooled levels show up to m (`seen_slope`),
/// "beyond" the whole record's between m and T, both per octave of cluster size (0 for white noise).
fn psins_six_grids(data: &Psins, lengths: &[usize]) {
    let (xs, rate_hz) = (&data.xs, data.rate_hz);
    println!("six grids, the first dwell at k T / 6; geometric means over the grids (min..max of the ratio)");
    println!(
        "{:8} {:>4} {:>6} {:>6} {:>12} {:>6} {:>6} {:>6} {:>6} {:>11} {:>6}  verdict",
        "channel", "T s", "m", "ratio", "min..max", "estim", "noise", "growth", "curve", "seen", "beyond"
    );
    let mut collector = DwellCollector::new(&Prefilter::None).unwrap();
    for &n in lengths {
        let grids: Vec<Vec<DwellSummary>> =
            (0..6).map(|k| xs[k * n / 6..].chunks_exact(n).map(|d| summarise(&mut collector, d)).collect()).collect();
        for i in 0..6 {
            let (mut ratios, mut m) = (Vec::new(), 0);
            let (mut estimation, mut factor, mut growth, mut seen, mut seen_se) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for summaries in &grids {
                let noise = pool_mean_noise(summaries.iter().copied())[i];
                m = noise.cluster_samples as usize;
                let top = level_of(noise.cluster_samples);
                let (avar, d) = pooled_allan(summaries, i, top);
                let (slope, se) = seen_slope(summaries, i, top);
                ratios.push(reported(&noise, n as f64) / data.allan(i, n));
                estimation += (avar.sqrt() / data.allan(i, m)).ln() / 6.0;
                factor += (1.0 + 2.0 / d).sqrt().ln() / 6.0;
                growth += (noise.white_equivalent_var as f64 / (m as f64 * avar * (1.0 + 2.0 / d))).sqrt().ln() / 6.0;
                (seen, seen_se) = (seen + slope / 6.0, seen_se + se / 6.0);
            }
            let ratio = (ratios.iter().map(|r| r.ln()).sum::<f64>() / 6.0).exp();
            let (min, max) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
            let (estimation, factor, growth) = (estimation.exp(), factor.exp(), growth.exp());
            let curve = data.curve(i, m, n);
            let beyond = -2.0 * curve.log2() / (n as f64 / m as f64).log2();
            // The estimator measures what it claims: the record's own Allan deviation at the cluster size.
            assert!(in_band(estimation), "{} T = {n}: estimation factor {estimation:.2}", CHANNELS[i]);
            let verdict = psins_verdict(ratio, curve, growth, seen, seen_se, &format!("{} T = {n}", CHANNELS[i]));
            print!("{:8} {:>4} {:>6} {:>6.2} {:>5.2}..{:<5.2}", CHANNELS[i], n as f64 / rate_hz, m, ratio, min, max);
            print!(" {estimation:>6.2} {factor:>6.2} {growth:>6.2} {curve:>6.2}");
            println!(" {seen:>+5.2}+-{seen_se:<4.2} {beyond:>+6.2}  {verdict}");
        }
    }
}

/// What a six-grid ratio outside the band is. Above the band only where the record's curve falls beyond the
/// cluster size (white extrapolation conservative), below it only where it rises; and a case below the band
/// has either shown no significant rise inside the dwells or had its rise carried on to the cap: the rule did
/// with what the dwells show all it does.
fn psins_verdict(ratio: f64, curve: f64, growth: f64, seen: f64, seen_se: f64, case: &str) -> &'static str {
    if in_band(ratio) {
        "in band"
    } else if ratio > 1.0 {
        assert!(curve > 1.0, "{case}: ratio {ratio:.2} with a rising curve {curve:.2}");
        if seen < -2.0 * seen_se {
            "fall seen inside, extrapolated as white: conservative"
        } else {
            "fall beyond m, not seen inside: conservative"
        }
    } else {
        assert!(curve < 1.0, "{case}: ratio {ratio:.2} with a falling curve {curve:.2}");
        if growth > 0.97 * MAX_NOISE_GROWTH.sqrt() as f64 {
            "rise seen, carried on to the cap: LOW"
        } else if growth > 1.05 {
            "rise seen and carried on, steeper beyond m: LOW"
        } else {
            assert!(seen < 2.0 * seen_se, "{case}: a rise of {seen:.2} +- {seen_se:.2} seen and not carried on");
            "rise beyond m, not seen inside: LOW"
        }
    }
}

/// Part 3, with the HMM/KF prefilter: the dwell value is the mean of the used raw samples (the filtered mean
/// without its boundary term), so the dwell values and their reported errors are exactly those without prefilter,
/// for dwells separated by 1 s (as on a turntable). Before, the filter's start dominated the 6-s accelerometer
/// means of this record.
fn psins_prefilter_scatter(data: &Psins, lengths: &[usize]) {
    let (xs, rate_hz) = (&data.xs, data.rate_hz);
    println!("HMM/KF: dwells of T separated by 1 s; reported against the scatter of the dwell values");
    println!("{:8} {:>4} {:>6} {:>10} {:>10} {:>6}", "channel", "T s", "dwells", "reported", "scatter", "ratio");
    let mut filtered = DwellCollector::new(&Prefilter::paper()).unwrap();
    let mut plain = DwellCollector::new(&Prefilter::None).unwrap();
    let gap = rate_hz as usize;
    for &n in lengths {
        let summaries: Vec<DwellSummary> =
            xs.chunks_exact(n + gap).map(|d| summarise(&mut filtered, &d[..n])).collect();
        let without: Vec<DwellSummary> = xs.chunks_exact(n + gap).map(|d| summarise(&mut plain, &d[..n])).collect();
        let pooled = pool_mean_noise(summaries.iter().copied());
        assert_eq!(pooled, pool_mean_noise(without.iter().copied()), "T = {n}: the prefilter changed the noise");
        for (a, b) in summaries.iter().zip(&without) {
            assert_eq!((a.rate_mean_b_radps, a.force_mean_b_mps2), (b.rate_mean_b_radps, b.force_mean_b_mps2));
        }
        for i in 0..6 {
            let rep = reported(&pooled[i], n as f64);
            let values: Vec<f64> = summaries.iter().map(|s| dwell_value(s, i)).collect();
            let scatter = adjacent_deviation(&values);
            println!(
                "{:8} {:>4} {:>6} {:>10.3e} {:>10.3e} {:>6.2}",
                CHANNELS[i],
                n as f64 / rate_hz,
                summaries.len(),
                rep,
                scatter,
                rep / scatter
            );
        }
    }
}

/// The mean of channel `i` over `xs`.
fn channel_mean(xs: &[[f64; 6]], i: usize) -> f64 {
    xs.iter().map(|z| z[i]).sum::<f64>() / xs.len() as f64
}

#[test]
fn imutk_xsens_reported_errors_against_the_allan_deviation() {
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
    // 1. Each hand-placed pose cut into its two halves: two adjacent dwells at one attitude, so the difference
    // of their means over sqrt 2 is one Allan difference at the half-pose length T, whatever the attitude. The
    // halves are the session's dwells (pooled, as a calibration pools its dwells); the reference is the RMS of
    // those differences over the poses, the Allan deviation at T from the data alone (one difference per pose),
    // against the RMS over the poses of the reported standard error of a half.
    let halves: Vec<&[[f64; 6]]> = rest
        .iter()
        .flat_map(|p| {
            let h = p.len() / 2;
            [&p[..h], &p[h..2 * h]]
        })
        .collect();
    let mut collector = DwellCollector::new(&Prefilter::None).unwrap();
    let summaries: Vec<DwellSummary> = halves.iter().map(|h| summarise(&mut collector, h)).collect();
    let pooled = pool_mean_noise(summaries.iter().copied());
    // 2. The first (long, quiet) interval cut into dwells of the median pose length, as a session of its own,
    // against its own overlapping Allan deviation at that length.
    let quiet: Vec<DwellSummary> = first.chunks_exact(median).map(|d| summarise(&mut collector, d)).collect();
    let quiet_pooled = pool_mean_noise(quiet.iter().copied());
    println!(
        "REAL DATA imu-tk-xsens, no prefilter: {} static intervals; the first {} samples ({} dwells of {median}), \
         the {} hand-placed poses {}..{} samples (median {median}) as {} half-pose dwells",
        poses.len(),
        first.len(),
        quiet.len(),
        rest.len(),
        lengths[0],
        lengths[lengths.len() - 1],
        halves.len(),
    );
    println!(
        "{:8} {:>4} {:>4} {:>10} {:>10} {:>6} {:>10} {:>6} {:>13} {:>5} {:>2} {:>6} | {:>4} {:>4} {:>10} {:>10} {:>6}",
        "channel",
        "m",
        "dof",
        "reported",
        "Allan(T)",
        "ratio",
        "old white",
        "old/A",
        "q128,q256/q64",
        "max|z|",
        ">4",
        "calm",
        "m",
        "dof",
        "first",
        "Allan(T)",
        "ratio"
    );
    for i in 0..6 {
        let h = HalvesRow::new(&halves, &summaries, &pooled[i], i);
        // How the pooled white-equivalent variance of the halves runs with the cluster size.
        let q = |j: usize| allan_cluster_samples(j) as f64 * pooled_allan(&summaries, i, j).0;
        let ch: Vec<f64> = first.iter().map(|z| z[i]).collect();
        let first_allan = overlapping_allan_deviation(&ch, rate_hz, &[median])[0].adev;
        let quiet_rep = reported(&quiet_pooled[i], median as f64);
        print!(
            "{:8} {:>4} {:>4} {:>10.3e} {:>10.3e} {:>6.2} {:>10.3e} {:>6.2} {:>6.2},{:>6.2} {:>5.1} {:>2} {:>6.2}",
            CHANNELS[i],
            pooled[i].cluster_samples,
            pooled[i].dof,
            h.reported,
            h.allan,
            h.reported / h.allan,
            h.old,
            h.old / h.allan,
            q(1) / q(0),
            q(2) / q(0),
            h.largest_z,
            h.beyond_4,
            h.calm_ratio,
        );
        let (m, dof) = (quiet_pooled[i].cluster_samples, quiet_pooled[i].dof);
        println!(" | {m:>4} {dof:>4} {quiet_rep:>10.3e} {first_allan:>10.3e} {:>6.2}", quiet_rep / first_allan);
        // The quiet start: in the band on every channel.
        assert!(in_band(quiet_rep / first_allan), "{} first interval: {:.2}", CHANNELS[i], quiet_rep / first_allan);
        // The poses: in the band, or low because a pose moved between its halves (a difference of more than 4
        // reported standard errors; among 36 standard normal values one beyond 4 has a chance of 0.2 %), which
        // nothing inside a half shows.
        let ratio = h.reported / h.allan;
        assert!(in_band(ratio) || h.largest_z > 4.0, "{} poses: {ratio:.2}", CHANNELS[i]);
    }
}

/// One channel of the imu_tk poses cut into halves: RMS over the poses of the Allan difference of the two
/// halves (the Allan deviation at the half-pose length), of the reported standard error of a half and of the
/// white-noise one; per pose `z`, the difference over its reported standard error (about standard normal when
/// the reported error is right): the largest `|z|`, the number beyond 4 and the ratio without those.
struct HalvesRow {
    allan: f64,
    reported: f64,
    old: f64,
    largest_z: f64,
    beyond_4: usize,
    calm_ratio: f64,
}

impl HalvesRow {
    fn new(halves: &[&[[f64; 6]]], summaries: &[DwellSummary], noise: &MeanNoise, i: usize) -> HalvesRow {
        let (mut allan, mut rep, mut old, mut z) = (0.0, 0.0, 0.0, Vec::new());
        for (pair, s) in halves.chunks_exact(2).zip(summaries.chunks_exact(2)) {
            let n = pair[0].len() as f64;
            let difference = (channel_mean(pair[1], i) - channel_mean(pair[0], i)) / 2f64.sqrt();
            allan += difference.powi(2);
            rep += reported(noise, n).powi(2);
            old += white_std_of_mean(s, i, n).powi(2);
            z.push(difference / reported(noise, n));
        }
        let count = z.len() as f64;
        let calm: Vec<f64> = z.iter().copied().filter(|v| v.abs() <= 4.0).collect();
        HalvesRow {
            allan: (allan / count).sqrt(),
            reported: (rep / count).sqrt(),
            old: (old / count).sqrt(),
            largest_z: z.iter().fold(0.0f64, |a, v| a.max(v.abs())),
            beyond_4: z.len() - calm.len(),
            calm_ratio: (calm.len() as f64 / calm.iter().map(|v| v * v).sum::<f64>()).sqrt(),
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
    // per-sample scatter ten times the white noise that the means see (the filter's start dominated a 6-s mean
    // before the dwell value was the raw mean with or without the HMM/KF). "white": the control.
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
            if name == "quantised" {
                // Quantisation noise falls as 1 / m^2 in Allan variance: white extrapolation from 128 samples
                // to 600 overstates the mean's noise (conservative, the documented side of the limit). With the
                // HMM/KF the dwell value is the same raw mean (the filter's boundary term removed), so the same.
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
