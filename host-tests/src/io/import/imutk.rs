//! The imu_tk importer: accelerometer and gyro text counts without labels; static intervals detected and
//! levelled by their mean specific force.

use super::*;

/// Parameters of the static-interval detection of imu_tk data ([`detect_static_intervals`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticDetection {
    /// Length of the centred sliding window, s (default 1 s: 101 samples at 100 Hz).
    pub window_s: f64,
    /// Length of the static period at the start of the record that sets the noise level, s (default 50 s).
    pub init_static_s: f64,
    /// Threshold as a multiple of the initial period's variance (default 6; on the Xsens data any factor from 2 to
    /// 20 finds the same 37 to 38 poses).
    pub threshold_factor: f64,
    /// Shortest static interval kept, s (default 3 s).
    pub min_static_s: f64,
}

impl Default for StaticDetection {
    fn default() -> Self {
        StaticDetection { window_s: 1.0, init_static_s: 50.0, threshold_factor: 6.0, min_static_s: 3.0 }
    }
}

/// Static intervals found in a record, and the numbers that found them.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticIntervals {
    /// Sample index ranges (end exclusive), in time order.
    pub ranges: Vec<Range<usize>>,
    /// Variance of the initial static period (sum over the three axes), (m/s^2)^2.
    pub init_variance_mps2sq: f64,
    /// The threshold applied to the windowed variance, (m/s^2)^2.
    pub threshold_mps2sq: f64,
    /// Half-width of the sliding window, samples.
    pub half_window_samples: usize,
    /// Shortest run of static samples kept.
    pub min_samples: usize,
}

/// Finds static intervals in a specific-force record sampled at `rate_hz` (times `t_s`, one per sample).
///
/// Rule: for every sample k the windowed variance V_k is the sum over x, y, z of the population variance of the
/// specific force over the samples [k - h, k + h] (clipped at the ends), h = round(window_s * rate_hz / 2). The
/// reference V0 is the same sum over the initial static period (t - t_first < init_static_s). A sample is static
/// when V_k < threshold_factor * max(V0, floor_variance_mps2sq) (the floor is the quantisation variance, so that
/// noiseless data still have a usable threshold). Maximal runs of static samples of at least
/// round(min_static_s * rate_hz) samples are the static intervals. The error is the reason (record shorter than
/// the initial period, or too few samples).
pub fn detect_static_intervals(
    force_b_mps2: &[[f64; 3]],
    t_s: &[f64],
    rate_hz: f64,
    detection: &StaticDetection,
    floor_variance_mps2sq: f64,
) -> Result<StaticIntervals, String> {
    let n = force_b_mps2.len();
    if n < 2 || t_s.len() != n {
        return Err(format!("{n} samples: too few for static detection"));
    }
    let t_first = t_s[0];
    let duration_s = t_s[n - 1] - t_first;
    if duration_s < detection.init_static_s {
        return Err(format!(
            "the record lasts {duration_s:.2} s, shorter than the initial static period of {} s that sets the \
             detection threshold",
            detection.init_static_s
        ));
    }
    let init_count = t_s.iter().take_while(|t| **t - t_first < detection.init_static_s).count().max(2);
    let mut mean = [0.0; 3];
    for f in &force_b_mps2[..init_count] {
        for i in 0..3 {
            mean[i] += f[i] / init_count as f64;
        }
    }
    let init_variance_mps2sq: f64 =
        force_b_mps2[..init_count].iter().map(|f| (0..3).map(|i| (f[i] - mean[i]).powi(2)).sum::<f64>()).sum::<f64>()
            / init_count as f64;
    let threshold_mps2sq = detection.threshold_factor * init_variance_mps2sq.max(floor_variance_mps2sq);

    // Prefix sums of the force less the initial mean (small numbers: no cancellation in the variance).
    let mut sum = vec![[0.0f64; 3]; n + 1];
    let mut sum_sq = vec![[0.0f64; 3]; n + 1];
    for (k, f) in force_b_mps2.iter().enumerate() {
        for i in 0..3 {
            let d = f[i] - mean[i];
            sum[k + 1][i] = sum[k][i] + d;
            sum_sq[k + 1][i] = sum_sq[k][i] + d * d;
        }
    }
    let half_window_samples = ((detection.window_s * rate_hz / 2.0).round() as usize).max(1);
    let min_samples = ((detection.min_static_s * rate_hz).round() as usize).max(1);
    let is_static = |k: usize| -> bool {
        let lo = k.saturating_sub(half_window_samples);
        let hi = (k + half_window_samples + 1).min(n);
        let m = (hi - lo) as f64;
        let variance: f64 = (0..3)
            .map(|i| {
                let mean_i = (sum[hi][i] - sum[lo][i]) / m;
                ((sum_sq[hi][i] - sum_sq[lo][i]) / m - mean_i * mean_i).max(0.0)
            })
            .sum();
        variance < threshold_mps2sq
    };
    let mut ranges = Vec::new();
    let mut start: Option<usize> = None;
    for k in 0..=n {
        let quiet = k < n && is_static(k);
        match (quiet, start) {
            (true, None) => start = Some(k),
            (false, Some(s)) => {
                if k - s >= min_samples {
                    ranges.push(s..k);
                }
                start = None;
            }
            _ => {}
        }
    }
    Ok(StaticIntervals { ranges, init_variance_mps2sq, threshold_mps2sq, half_window_samples, min_samples })
}

/// One imu_tk file: (line, t_s, counts x y z) per sample.
fn parse_imutk_counts(text: &str, source: &str) -> Result<Vec<(usize, f64, [f64; 3])>, InputError> {
    let mut samples: Vec<(usize, f64, [f64; 3])> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('%') || line.starts_with('#') {
            continue;
        }
        let v = whitespace_numbers(line, 4, "sample line (t_s x y z)").map_err(|r| InputError::at(source, n, r))?;
        if let Some((_, previous_t_s, _)) = samples.last() {
            if v[0] <= *previous_t_s {
                return Err(InputError::at(
                    source,
                    n,
                    format!("time {} s does not increase (previous sample: {previous_t_s} s)", v[0]),
                ));
            }
        }
        let counts = [v[1], v[2], v[3]];
        if let Some(c) = counts.iter().find(|c| !(0.0..=65535.0).contains(*c)) {
            return Err(InputError::at(source, n, format!("count {c} is outside the unsigned 16-bit range 0..65535")));
        }
        samples.push((n, v[0], counts));
    }
    if samples.len() < 2 {
        return Err(InputError::file(source, format!("{} samples: too few", samples.len())));
    }
    Ok(samples)
}

/// Reads imu_tk's accelerometer and gyro files; see [`parse_imutk`].
pub fn import_imutk(
    acc: &Path,
    gyro: &Path,
    latitude_deg: Option<f64>,
    detection: &StaticDetection,
) -> Result<Imported, InputError> {
    parse_imutk(
        &read_text(acc)?,
        &acc.display().to_string(),
        &read_text(gyro)?,
        &gyro.display().to_string(),
        latitude_deg,
        detection,
    )
}

/// Largest relative distance of the accelerometer file's median |f| (at the nominal gains) from gravity: a
/// hand-held session rests most of the time, so its median specific force is g.
pub const IMUTK_MAX_MEDIAN_FORCE_ERROR_RELATIVE: f64 = 0.2;

/// The median |f| of counts read with the accelerometer's nominal gains, m/s^2.
fn median_force_mps2(counts: &[ImutkCounts]) -> f64 {
    let mut norms: Vec<f64> = counts
        .iter()
        .map(|(_, _, c)| {
            let f = [0, 1, 2].map(|i| (c[i] - IMUTK_OFFSET_COUNTS) / IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2[i]);
            (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt()
        })
        .collect();
    norms.sort_by(f64::total_cmp);
    norms.get(norms.len() / 2).copied().unwrap_or(0.0)
}

/// The accelerometer file reads as gravity: its median |f| within [`IMUTK_MAX_MEDIAN_FORCE_ERROR_RELATIVE`] of g; when it
/// does not and the gyro file does, the two are swapped.
fn check_accelerometer_file(
    acc: &[ImutkCounts],
    gyro: &[ImutkCounts],
    acc_source: &str,
    gyro_source: &str,
) -> Result<(), InputError> {
    let near_g = |f: f64| (f / IMUTK_GRAVITY_MPS2 - 1.0).abs() <= IMUTK_MAX_MEDIAN_FORCE_ERROR_RELATIVE;
    let (acc_f, gyro_f) = (median_force_mps2(acc), median_force_mps2(gyro));
    if near_g(acc_f) {
        return Ok(());
    }
    let shown = crate::io::recording::shown;
    let reason = if near_g(gyro_f) {
        format!(
            "the accelerometer and gyro files seem swapped: this file's median |f| is {} m/s^2 at the \
             accelerometer's nominal gains, {gyro_source}'s is {}, near g ({IMUTK_GRAVITY_MPS2})",
            shown(acc_f),
            shown(gyro_f)
        )
    } else {
        format!(
            "its median |f| is {} m/s^2 at the accelerometer's nominal gains, not within {} % of g \
             ({IMUTK_GRAVITY_MPS2}): not imu_tk accelerometer counts",
            shown(acc_f),
            IMUTK_MAX_MEDIAN_FORCE_ERROR_RELATIVE * 100.0
        )
    };
    Err(InputError::file(acc_source, reason))
}

/// Parses imu_tk text counts: an accelerometer file and a gyro file (`xsens_acc.mat`, `xsens_gyro.mat`: plain
/// text despite the name), each with lines `t_s x y z`, x, y, z in unsigned 16-bit counts. The two files must have
/// the same number of samples at the same times (within [`IMUTK_MAX_TIME_MISMATCH_S`]).
///
/// Conversion with the nominal factory gains: force_mps2 = (count - 32768) / [`IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2`],
/// rate_radps = (count - 32768) / [`IMUTK_GYRO_GAIN_COUNTS_PER_RADPS`] (no misalignment, no measured offsets; the
/// header says so). The rate is 1 / median(dt). There are no labels: static intervals are found by
/// [`detect_static_intervals`] on the specific force with `detection` (quantisation floor: the sum over the axes
/// of (1 count / gain)^2 / 12), and interval k becomes position k = 1, 2, ... with the pitch and roll of its mean
/// specific force ([`level_attitude_deg`]) and an empty heading; samples between intervals get pos = 0 (pitch 0,
/// roll 0, heading empty). Gravity is [`IMUTK_GRAVITY_MPS2`] (imu_tk's example value); the latitude is
/// `latitude_deg` or [`IMUTK_DEFAULT_LATITUDE_DEG`] (unknown).
pub fn parse_imutk(
    acc_text: &str,
    acc_source: &str,
    gyro_text: &str,
    gyro_source: &str,
    latitude_deg: Option<f64>,
    detection: &StaticDetection,
) -> Result<Imported, InputError> {
    let latitude = option_latitude(latitude_deg, "--latitude-deg")?;
    let (acc, gyro) = paired_counts(acc_text, acc_source, gyro_text, gyro_source)?;
    let mut dt_s: Vec<f64> = acc.windows(2).map(|w| w[1].1 - w[0].1).collect();
    dt_s.sort_by(f64::total_cmp);
    let median_dt_s = dt_s[dt_s.len() / 2];
    let rate_hz = (100.0 / median_dt_s).round() / 100.0;

    let force: Vec<[f64; 3]> = acc
        .iter()
        .map(|(_, _, c)| [0, 1, 2].map(|i| (c[i] - IMUTK_OFFSET_COUNTS) / IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2[i]))
        .collect();
    let rate: Vec<[f64; 3]> = gyro
        .iter()
        .map(|(_, _, c)| [0, 1, 2].map(|i| (c[i] - IMUTK_OFFSET_COUNTS) / IMUTK_GYRO_GAIN_COUNTS_PER_RADPS[i]))
        .collect();
    check_accelerometer_file(&acc, &gyro, acc_source, gyro_source)?;
    let t_s: Vec<f64> = acc.iter().map(|(_, t, _)| *t).collect();
    let floor_variance_mps2sq: f64 = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2.iter().map(|g| 1.0 / (g * g) / 12.0).sum();
    let intervals = detect_static_intervals(&force, &t_s, rate_hz, detection, floor_variance_mps2sq)
        .map_err(|r| InputError::file(acc_source, r))?;
    let rows = levelled_rows(&acc, &force, &rate, &intervals, acc_source)?;
    let sources = [acc_source, gyro_source];
    let (recording, notes) = imutk_recording(rows, sources, latitude, rate_hz, detection, &intervals);
    let summary = summarise(&recording, "imu_tk text counts", &notes, &|_| String::new());
    Ok(Imported { recording, summary })
}

/// The accelerometer and gyro counts, read and checked to be sample for sample at the same times.
fn paired_counts(
    acc_text: &str,
    acc_source: &str,
    gyro_text: &str,
    gyro_source: &str,
) -> Result<(Vec<ImutkCounts>, Vec<ImutkCounts>), InputError> {
    let acc = parse_imutk_counts(acc_text, acc_source)?;
    let gyro = parse_imutk_counts(gyro_text, gyro_source)?;
    if acc.len() != gyro.len() {
        return Err(InputError::file(
            gyro_source,
            format!("{} samples, the accelerometer file {acc_source} has {}", gyro.len(), acc.len()),
        ));
    }
    for ((_, t_acc_s, _), (n, t_gyro_s, _)) in acc.iter().zip(&gyro) {
        if (t_acc_s - t_gyro_s).abs() > IMUTK_MAX_TIME_MISMATCH_S {
            return Err(InputError::at(
                gyro_source,
                *n,
                format!("time {t_gyro_s} s differs from the accelerometer's {t_acc_s} s at the same sample"),
            ));
        }
    }
    Ok((acc, gyro))
}

/// One imu_tk sample: line number, time (s) and the three counts.
type ImutkCounts = (usize, f64, [f64; 3]);

/// The rows in SI units, each static interval a position levelled by its mean specific force.
fn levelled_rows(
    acc: &[ImutkCounts],
    force: &[[f64; 3]],
    rate: &[[f64; 3]],
    intervals: &StaticIntervals,
    acc_source: &str,
) -> Result<Vec<Row>, InputError> {
    let mut rows: Vec<Row> = acc
        .iter()
        .zip(force.iter().zip(rate))
        .map(|((n, t, _), (f, w))| Row {
            t_s: *t,
            pos: 0,
            pitch_deg: 0.0,
            roll_deg: 0.0,
            heading_deg: None,
            rate_b_radps: *w,
            force_b_mps2: *f,
            temp_c: None,
            turn_axis: None,
            line: *n,
        })
        .collect();
    level_intervals(&mut rows, &intervals.ranges, acc_source)?;
    Ok(rows)
}

/// The recording with its header (sources, scales, latitude, detection rule) and the summary's notes.
fn imutk_recording(
    rows: Vec<Row>,
    [acc_source, gyro_source]: [&str; 2],
    latitude: Option<f64>,
    rate_hz: f64,
    detection: &StaticDetection,
    intervals: &StaticIntervals,
) -> (Recording, Vec<String>) {
    let (latitude_deg, latitude_source) = match latitude {
        Some(lat) => (lat, "command line (--latitude-deg)".to_string()),
        None => (
            IMUTK_DEFAULT_LATITUDE_DEG,
            format!(
                "unknown, {IMUTK_DEFAULT_LATITUDE_DEG} assumed (inferred: not stated in the data; set --latitude-deg)"
            ),
        ),
    };
    let [ax, ay, az] = IMUTK_ACCEL_GAIN_COUNTS_PER_MPS2;
    let [gx, gy, gz] = IMUTK_GYRO_GAIN_COUNTS_PER_RADPS;
    let gains = format!(
        "nominal factory gains: accel diag [{ax}, {ay}, {az}] counts/(m/s^2), gyro diag [{gx}, {gy}, {gz}] \
         counts/(rad/s), offset {IMUTK_OFFSET_COUNTS} counts, no misalignment"
    );
    let rule = format!(
        "sliding {} s window ({} samples each side), sum of the 3 accel variances < {} x initial {} s variance \
         ({:.3e} (m/s^2)^2, threshold {:.3e}), at least {} s",
        detection.window_s,
        intervals.half_window_samples,
        detection.threshold_factor,
        detection.init_static_s,
        intervals.init_variance_mps2sq,
        intervals.threshold_mps2sq,
        detection.min_static_s
    );
    let comments = vec![
        format!("source: {acc_source} + {gyro_source}"),
        "source_format: imu_tk text counts (t_s x y z, unsigned 16-bit counts, accelerometer and gyro files)"
            .to_string(),
        format!("scale: {gains}"),
        format!("latitude_source: {latitude_source}"),
        format!("gravity_source: imu_tk example value {IMUTK_GRAVITY_MPS2} m/s^2"),
        format!("attitude_source: {ATTITUDE_SOURCE_LEVELLED}"),
        format!("static_detection: {rule}"),
    ];
    let recording = Recording {
        source: acc_source.to_string(),
        header: Header {
            latitude_deg,
            height_m: 0.0,
            rate_hz: Some(rate_hz),
            gravity_mps2: Some(IMUTK_GRAVITY_MPS2),
            comments,
            truth: None,
            pose_tolerance_deg: None,
        },
        rows,
        has_gyro: true,
    };
    let notes = vec![
        format!(
            "latitude {latitude_deg} deg ({latitude_source}), g {IMUTK_GRAVITY_MPS2} m/s^2 (imu_tk's example value)"
        ),
        format!("counts converted with the {gains}"),
        format!("static intervals: {rule}; {} found", intervals.ranges.len()),
        "pitch and roll of each interval: levelled from its mean specific force (nominal gains: errors of degrees); \
         heading unknown (empty)"
            .to_string(),
    ];
    (recording, notes)
}
