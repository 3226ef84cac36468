//! `sinscal noise STATIC_RECORDING --out NOISE_FILE`: each channel's noise terms (quantisation, white noise,
//! bias instability, Gauss-Markov, rate random walk, rate ramp), named from its Allan variance, with standard
//! errors (docs/cli.md#noise). The noise file is JSON, schema `sinscal-noise/1`.

use std::path::PathBuf;

use serde::Serialize;

use crate::analysis::noise_terms::{noise_model_above, NoiseModel};
use crate::analysis::CHANNELS;
use crate::cmd::{json_to_stdout, write_json};
use crate::io::error::InputError;
use crate::io::recording::{RecordingFile, RowSource, TimeSteps};

/// Arguments of `sinscal noise`.
#[derive(clap::Args)]
pub struct Args {
    /// A static recording (docs/formats.md#recording): its longest dwell is characterised.
    recording: PathBuf,
    /// Write the noise file (JSON, schema sinscal-noise/1) to this file ('-' = stdout).
    #[arg(long)]
    out: PathBuf,
    /// Fit each channel's Allan variance at averaging times of at least this many seconds (default 1: a
    /// calibration's dwell means are seconds to minutes long; 0 fits every point, as `analyze` does).
    #[arg(long, default_value_t = DEFAULT_MIN_TAU_S, value_parser = parse_min_tau)]
    min_tau: f64,
}

/// The shortest averaging time a noise file is fitted at unless told otherwise, s: below it lie a ring-laser
/// gyro's dither and the filters of MEMS parts, which no term of the model describes and which a dwell mean of
/// seconds does not see (docs/method.md#noise-model, measured on the PSINS record).
pub const DEFAULT_MIN_TAU_S: f64 = 1.0;

/// `--min-tau`: a number of seconds >= 0 (a bad value is a usage error, exit 2).
fn parse_min_tau(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("'{text}' is not a number of seconds >= 0")),
    }
}

/// The noise file.
#[derive(Serialize)]
pub struct NoiseFile {
    /// "sinscal-noise/1".
    pub schema: &'static str,
    /// The recording characterised.
    pub source: String,
    /// The dwell characterised (the longest), its label.
    pub pos: u32,
    /// Its samples.
    pub samples: usize,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// The shortest averaging time fitted, s.
    pub min_tau_s: f64,
    /// Per channel (gyro x, y, z, accelerometer x, y, z; no gyros without gyro data): the named terms with their
    /// standard errors, the fit's statistics, and how far the white-noise error of the dwell's mean is off.
    pub channels: Vec<NoiseModel>,
}

/// Runs `sinscal noise`.
pub fn run(args: Args) -> anyhow::Result<()> {
    // Read in passes: only the longest dwell's samples are held.
    let rec = RecordingFile::open(&args.recording)?;
    let file = characterise(&rec, args.min_tau)?;
    if !json_to_stdout(Some(&args.out)) {
        super::out(&summary(&file))?;
    }
    write_json(&args.out, &file)
}

/// The noise file of a recording's longest dwell, fitted at averaging times of at least `min_tau_s`. Two
/// passes over the rows; only that dwell's samples are held.
pub fn characterise(rec: &impl RowSource, min_tau_s: f64) -> Result<NoiseFile, InputError> {
    let source = rec.source().to_string();
    let (pos, rows) = longest_dwell(rec)?
        .ok_or_else(|| InputError::at(&source, 1, "no dwell (no row with pos > 0) to characterise"))?;
    let median_step_s = || TimeSteps::of(rows.iter().map(|r| r.0)).median_s().unwrap_or(1.0);
    let rate_hz = rec.header().rate_hz.unwrap_or_else(|| 1.0 / median_step_s());
    let first = if rec.has_gyro() { 0 } else { 3 };
    let mut channels = Vec::new();
    for i in first..6 {
        let samples: Vec<f64> = rows.iter().map(|r| r.2[i]).collect();
        let model = noise_model_above(CHANNELS[i], i < 3, &samples, rate_hz, min_tau_s).ok_or_else(|| {
            InputError::at(
                &source,
                rows[0].1,
                format!(
                    "dwell {pos}: {} samples are too few to name {}'s noise (the Allan variance needs {} octaves)",
                    rows.len(),
                    CHANNELS[i],
                    crate::analysis::noise_terms::MIN_POINTS
                ),
            )
        })?;
        channels.push(model);
    }
    Ok(NoiseFile { schema: "sinscal-noise/1", source, pos, samples: rows.len(), rate_hz, min_tau_s, channels })
}

/// One row of the dwell characterised: its time, s, its line, and the six channels (SI).
type DwellRow = (f64, usize, [f64; 6]);

/// The longest dwell (the larger label of equally long ones): its label and rows, from two passes.
fn longest_dwell(rec: &impl RowSource) -> Result<Option<(u32, Vec<DwellRow>)>, InputError> {
    let mut counts: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    rec.for_each_row(&mut |r| {
        if r.pos > 0 {
            *counts.entry(r.pos).or_default() += 1;
        }
        Ok(())
    })?;
    let Some((&pos, _)) = counts.iter().max_by_key(|(p, n)| (**n, **p)) else { return Ok(None) };
    let mut rows = Vec::with_capacity(counts[&pos]);
    rec.for_each_row(&mut |r| {
        if r.pos == pos {
            let (w, f) = (r.rate_b_radps, r.force_b_mps2);
            rows.push((r.t_s, r.line, [w[0], w[1], w[2], f[0], f[1], f[2]]));
        }
        Ok(())
    })?;
    Ok(Some((pos, rows)))
}

/// The human summary: one line per channel.
pub fn summary(file: &NoiseFile) -> String {
    let mut out = format!(
        "sinscal noise: {} (dwell {}: {} samples at {} Hz, {:.0} s); each channel's noise terms from its Allan \
         variance (docs/analysis.md#noise-model)\n",
        file.source,
        file.pos,
        file.samples,
        file.rate_hz,
        file.samples as f64 / file.rate_hz
    );
    for m in &file.channels {
        out.push_str(&format!("  {}\n", m.text()));
        out.push_str(&format!(
            "  {:<9} white-noise error of this dwell's mean / the model's: {:.2}\n",
            "", m.white_error_factor
        ));
    }
    out
}
