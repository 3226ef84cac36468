//! Honest errors from a noise file (docs/method.md#noise-model), on real data: the noise file is made from one
//! part of a static record by the product (`sinscal noise`'s `characterise`, written as JSON and read back as
//! `calibrate --noise` reads it), and the standard error it gives a dwell mean (the core's
//! `NoiseModel::mean_variance`, what `session_estimator` weights a dwell by) is compared with the spread of
//! the means of consecutive dwells of another part of the record: the Allan deviation of the dwell means at
//! the dwell length, from the data alone.
//!
//! - PSINS ring-laser record: the noise file from one half, the dwells (6, 60 and 300 s) from the other, both
//!   ways round, the differences of both pooled.
//! - imu_tk Xsens: the noise file from the long first static interval, the dwells the halves of the
//!   hand-placed poses (two adjacent dwells at one attitude: one Allan difference per pose).
//!
//! The dwell means are the core's (`DwellCollector`, spike gate included, no prefilter: with the HMM/KF the
//! dwell value and its noise are the same, `honest_errors.rs` asserts it). The ratio's own uncertainty is
//! `1 / sqrt(2 d)` relative for `d` differences (each difference one chi-square degree of freedom).
//! Real-data tests: skipped, and saying so, without `SINSCAL_DATA`.

mod common;

use common::{data_dir, data_file};
use sinscal::calib::dwell::{DwellCollector, DwellSummary, Prefilter};
use sinscal::calib::noise_model::NoiseModel;
use sinscal::ImuSample;
use sinscal_host::cmd::noise::{characterise, DEFAULT_MIN_TAU_S};
use sinscal_host::io::import::{import_imutk, import_psins, StaticDetection};
use sinscal_host::io::noise_file::NoiseFile;
use sinscal_host::io::recording::{Recording, Row};

const CHANNELS: [&str; 6] = ["gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z"];

/// The noise model of `rows` as a calibration at `rate_hz` would read it: characterised, written, read back.
fn noise_model_of(rec: &Recording, rows: &[Row], rate_hz: f64) -> NoiseModel {
    let part = Recording { rows: rows.to_vec(), ..rec.clone() };
    let min_tau_s: f64 = std::env::var("MIN_TAU").ok().and_then(|v| v.parse().ok()).unwrap_or(DEFAULT_MIN_TAU_S);
    let file = characterise(&part, min_tau_s).expect("characterised");
    let text = serde_json::to_string(&file).unwrap();
    let terms = NoiseFile::parse(&text, "part").expect("a noise file the reader takes").terms;
    for (i, c) in file.channels.iter().enumerate() {
        println!("  {:8} {}", CHANNELS[i], c.named);
    }
    terms.model(1.0 / rate_hz, true).expect("a usable model")
}

/// The core's statistics of one dwell of `rows` (no prefilter).
fn dwell_summary(rows: &[Row]) -> DwellSummary {
    let mut c = DwellCollector::new(&Prefilter::None).unwrap();
    for r in rows {
        let s = ImuSample {
            rate_b_radps: r.rate_b_radps.map(|v| v as f32),
            force_b_mps2: r.force_b_mps2.map(|v| v as f32),
        };
        c.update(&s).unwrap();
    }
    c.summary().unwrap()
}

/// The core's dwell mean of each channel and its used samples.
fn dwell_means(rows: &[Row]) -> ([f64; 6], u32) {
    let s = dwell_summary(rows);
    let (w, f) = (s.rate_mean_b_radps, s.force_mean_b_mps2);
    ([w[0], w[1], w[2], f[0], f[1], f[2]].map(f64::from), s.samples)
}

/// Sums for one channel and dwell length: the squared differences of neighbouring dwell means over 2, the
/// reported variances of those dwells, and the number of differences.
#[derive(Default, Clone, Copy)]
struct Pooled {
    half_square_difference: f64,
    reported_var: f64,
    differences: usize,
}

impl Pooled {
    fn add(&mut self, a: (f64, f64), b: (f64, f64)) {
        self.half_square_difference += (b.0 - a.0).powi(2) / 2.0;
        self.reported_var += (a.1 + b.1) / 2.0;
        self.differences += 1;
    }

    /// Reported standard error over the measured spread, and the ratio's relative uncertainty.
    fn ratio(&self) -> (f64, f64) {
        ((self.reported_var / self.half_square_difference).sqrt(), 1.0 / (2.0 * self.differences as f64).sqrt())
    }
}

/// Each channel's pooled ratio printed; the number in the band, and the cases outside the band widened by two
/// of the ratio's own uncertainties (`failures`).
fn check(pooled: &[Pooled; 6], case: &str, failures: &mut Vec<String>) -> usize {
    let mut inside = 0;
    for (i, p) in pooled.iter().enumerate() {
        let (ratio, rel) = p.ratio();
        let in_band = (0.7..=1.4).contains(&ratio);
        inside += in_band as usize;
        println!(
            "  {:8} {case:>10} differences {:>4}  ratio {ratio:.2} +- {:.2}  {}",
            CHANNELS[i],
            p.differences,
            ratio * rel,
            if in_band { "in [0.7, 1.4]" } else { "OUT" }
        );
        // Outside the band only by the data's own scatter: within two of the ratio's uncertainties.
        let low = 0.7 * (1.0 - 2.0 * rel);
        let high = 1.4 * (1.0 + 2.0 * rel);
        if !(low..=high).contains(&ratio) {
            failures.push(format!("{} {case}: ratio {ratio:.2} (+- {:.2})", CHANNELS[i], ratio * rel));
        }
    }
    inside
}

#[test]
fn psins_noise_file_from_one_half_gives_honest_errors_on_the_other() {
    let Some(dir) = data_dir() else { return };
    let rec = import_psins(&data_file(&dir, "psins-lasergyro/lasergyro.imu"), None).unwrap().recording;
    let rate_hz = rec.header.rate_hz.unwrap();
    // The record's first rows are spikes (the importer keeps them); the halves after them.
    let rows = &rec.rows[16..];
    let (a, b) = rows.split_at(rows.len() / 2);
    println!("REAL DATA psins-lasergyro, {} + {} samples at {rate_hz} Hz", a.len(), b.len());
    println!(" noise file from the first half:");
    let model_a = noise_model_of(&rec, a, rate_hz);
    println!(" noise file from the second half:");
    let model_b = noise_model_of(&rec, b, rate_hz);
    let (mut total, mut failures, mut ratios) = (0, Vec::new(), Vec::new());
    for seconds in [6.0, 60.0, 300.0] {
        let n = (seconds * rate_hz) as usize;
        let mut pooled = [Pooled::default(); 6];
        for (model, eval) in [(&model_a, b), (&model_b, a)] {
            let dwells: Vec<([f64; 6], u32)> = eval.chunks_exact(n).map(dwell_means).collect();
            for w in dwells.windows(2) {
                for (i, p) in pooled.iter_mut().enumerate() {
                    let reported = |d: &([f64; 6], u32)| (d.0[i], model.mean_variance(i, d.1) as f64);
                    p.add(reported(&w[0]), reported(&w[1]));
                }
            }
        }
        total += check(&pooled, &format!("T = {seconds} s"), &mut failures);
        ratios.push(pooled.map(|p| p.ratio().0));
    }
    println!("in [0.7, 1.4]: {total} of 18 channel-lengths");
    // Every channel in the band at 6 s, and the gyro x and the accelerometers at 60 s too (the ratio's own
    // uncertainty there is 13 %). Beyond: the y and z gyros' model is conservative, never optimistic (their
    // Q + N models stay twice the measured Allan deviation at 64 s, and the first half's disturbances are twice
    // the second's; the first half names sway for the y gyro, which brings its ratio from 1.92 to 1.60); at
    // 300 s four differences say little (+- 35 %), so there only the band widened by two of the ratio's
    // uncertainties is asserted.
    let conservative = ["gyro y T = 60 s", "gyro z T = 60 s", "gyro y T = 300 s", "gyro z T = 300 s"];
    for f in &failures {
        assert!(conservative.iter().any(|c| f.starts_with(c)), "outside the band: {f}");
    }
    for (i, r) in ratios[1].iter().enumerate().filter(|(i, _)| [1, 2].contains(i)) {
        assert!(*r > 1.0 && *r < 3.0, "{} at 60 s: {r:.2}, not conservative", CHANNELS[i]);
    }
}

#[test]
fn imutk_noise_file_from_the_first_interval_gives_honest_errors_on_the_hand_placed_poses() {
    let Some(dir) = data_dir() else { return };
    let acc = data_file(&dir, "imu-tk-xsens/xsens_acc.mat");
    let gyro = data_file(&dir, "imu-tk-xsens/xsens_gyro.mat");
    let rec = import_imutk(&acc, &gyro, None, &StaticDetection::default()).unwrap().recording;
    let rate_hz = rec.header.rate_hz.unwrap();
    let dwells = rec.dwells();
    let (first, poses) = dwells.split_first().unwrap();
    let first_rows: Vec<Row> = first.rows.iter().map(|r| (*r).clone()).collect();
    println!("REAL DATA imu-tk-xsens: noise file from the first interval ({} samples)", first_rows.len());
    let model = noise_model_of(&rec, &first_rows, rate_hz);
    let mut pooled = [Pooled::default(); 6];
    for pose in poses {
        let rows: Vec<Row> = pose.rows.iter().map(|r| (*r).clone()).collect();
        let h = rows.len() / 2;
        let (x, y) = (dwell_means(&rows[..h]), dwell_means(&rows[h..2 * h]));
        for (i, p) in pooled.iter_mut().enumerate() {
            let reported = |d: &([f64; 6], u32)| (d.0[i], model.mean_variance(i, d.1) as f64);
            p.add(reported(&x), reported(&y));
        }
    }
    println!(" {} hand-placed poses, each cut into two halves:", poses.len());
    let mut failures = Vec::new();
    let inside = check(&pooled, "half poses", &mut failures);
    println!("in [0.7, 1.4]: {inside} of 6 channels");
    // The gyros are honest. The accelerometers of the hand-placed poses scatter about twice as much as the
    // quiet first interval says (a hand-held session is not a static run): the noise file of a quiet run
    // understates them by that factor, and the calibration's fit check, which takes the file's noise as
    // known, is what tells. Asserted as measured, so that a change in either shows.
    for (i, p) in pooled.iter().enumerate() {
        let (ratio, _) = p.ratio();
        let expected = if i < 3 { 0.7..=1.4 } else { 0.4..=0.7 };
        assert!(expected.contains(&ratio), "{}: ratio {ratio:.2} outside {expected:?}", CHANNELS[i]);
    }
}

/// Sessions of two dwells (REAL DATA, PSINS): each session two 30-s dwells 5 s apart at the record's one
/// attitude, calibrated by the core (`session_estimator`, biases) with the noise file of the other half, with
/// and without the dwells' windows (the correlation between them, docs/method.md#noise-model); the reported
/// standard error of each bias against the spread of the biases of consecutive sessions.
#[test]
fn psins_two_dwell_sessions_need_the_correlation_between_dwells() {
    use sinscal::calib::general::{ChannelSettings, Model};
    use sinscal::calib::session::{session_estimator, SessionDwell};
    use sinscal::nav::frames::Attitude;
    let Some(dir) = data_dir() else { return };
    let rec = import_psins(&data_file(&dir, "psins-lasergyro/lasergyro.imu"), None).unwrap().recording;
    let rate_hz = rec.header.rate_hz.unwrap();
    let rows = &rec.rows[16..];
    let (a, b) = rows.split_at(rows.len() / 2);
    let (site, _) = sinscal_host::calibration::site_of(&rec.header);
    let r0 = &rows[0];
    let attitude =
        Attitude::from_degrees(r0.pitch_deg as f32, r0.roll_deg as f32, r0.heading_deg.unwrap_or(0.0) as f32);
    let (dwell, gap) = ((30.0 * rate_hz) as usize, (5.0 * rate_hz) as usize);
    let session = 2 * dwell + gap;
    let mut rows_of = Vec::new();
    // [with windows, without] x channel.
    let mut pooled = [[Pooled::default(); 6]; 2];
    println!("REAL DATA psins-lasergyro: sessions of two 30-s dwells 5 s apart, noise file of the other half");
    for (fit, eval) in [(a, b), (b, a)] {
        let model = noise_model_of(&rec, fit, rate_hz);
        for with_windows in [true, false] {
            let settings = ChannelSettings { model: Model::BIASES, noise: Some(model), ..ChannelSettings::default() };
            let mut estimates: Vec<[(f64, f64); 6]> = Vec::new();
            for s in eval.chunks_exact(session) {
                let summaries = [&s[..dwell], &s[dwell + gap..]].map(dwell_summary);
                let starts = [0u32, (dwell + gap) as u32];
                let dwells = (0..2).map(|k| SessionDwell {
                    attitude,
                    heading_known: true,
                    summary: &summaries[k],
                    first_sample: with_windows.then_some(starts[k]),
                });
                let solution = session_estimator(dwells, site, settings, sinscal::calib::align::DwellValue::Mean)
                    .unwrap()
                    .solve()
                    .unwrap();
                // gyro_bias x, y, z then accel_bias x, y, z: parameters 0..6.
                estimates.push(core::array::from_fn(|i| {
                    let (v, se) = solution.estimate(i).unwrap();
                    (v as f64, (se as f64).powi(2))
                }));
            }
            rows_of.push(estimates.len());
            for w in estimates.windows(2) {
                for (i, p) in pooled[usize::from(!with_windows)].iter_mut().enumerate() {
                    p.add(w[0][i], w[1][i]);
                }
            }
        }
    }
    let mut failures = Vec::new();
    println!(" with the correlation between the two dwells:");
    let with = check(&pooled[0], "with", &mut failures);
    println!(" without (each dwell independent):");
    let mut ignored = Vec::new();
    let without = check(&pooled[1], "without", &mut ignored);
    println!("in [0.7, 1.4]: {with} of 6 with the correlation, {without} of 6 without ({:?} sessions)", rows_of);
    for (i, (x, y)) in pooled[0].iter().zip(&pooled[1]).enumerate() {
        println!("  {:8} ratio with {:.2}, without {:.2}", CHANNELS[i], x.ratio().0, y.ratio().0);
    }
    // The accelerometers, whose noise is slower than a dwell, are honest only with the correlation.
    for i in 3..6 {
        let (with, without) = (pooled[0][i].ratio().0, pooled[1][i].ratio().0);
        assert!((0.7..=1.4).contains(&with), "{}: with the correlation {with:.2}", CHANNELS[i]);
        assert!(without < with, "{}: without {without:.2}, with {with:.2}", CHANNELS[i]);
    }
}
