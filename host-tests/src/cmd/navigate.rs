//! `sinscal navigate RECORDING --calibration CAL.json`: static pure-inertial navigation with and without
//! the calibration's sensor model compensated.

use std::path::PathBuf;

use crate::cmd::{json_to_stdout, write_json};
use crate::io::recording::RecordingFile;
use crate::io::ARCSEC_PER_RAD;
use crate::navigation::check::{navigate, NavCalibration, NavOptions, NavReport};
use crate::plot::navigation_plot;

/// Arguments of `sinscal navigate`.
#[derive(clap::Args)]
pub struct Args {
    /// The recording: its longest static dwell is navigated, or, with --hours, a simulated static run of
    /// its IMU (for recordings written by sinscal's simulator).
    recording: PathBuf,
    /// The calibration result (JSON of `sinscal calibrate --json`).
    #[arg(long)]
    calibration: PathBuf,
    /// A second calibration to compare.
    #[arg(long)]
    compare: Option<PathBuf>,
    /// Length of a simulated static run, hours, in (0, 48] (needs a simulated recording).
    #[arg(long, value_parser = parse_hours)]
    hours: Option<f64>,
    /// The dwell (pos label) whose attitude and samples are used.
    #[arg(long)]
    position: Option<u32>,
    /// Noise seed of the simulated run (default: the recording's seed + 1).
    #[arg(long)]
    seed: Option<u64>,
    /// Write the summary as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write a PNG figure of the runs.
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// Runs `sinscal navigate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { recording, calibration, compare, hours, position, seed, json, plot } = args;
    let quiet = json_to_stdout(json.as_deref());
    // The rows are read in passes, never held (docs/formats.md#speed-and-memory).
    let rec = RecordingFile::open(&recording)?;
    let cal = NavCalibration::read(&calibration)?;
    let second = compare.as_deref().map(NavCalibration::read).transpose()?;
    let options = NavOptions { hours, position, seed, ..NavOptions::default() };
    let started = std::time::Instant::now();
    let mut last_tenth = 0;
    let report = navigate(&rec, &cal, second.as_ref(), &options, |done_h, total_h| {
        let tenth = (done_h / total_h * 10.0).floor() as u32;
        if tenth > last_tenth {
            last_tenth = tenth;
            eprintln!("navigate: {tenth}0% ({done_h:.2} of {total_h:.2} h)");
        }
    })?;
    let elapsed = started.elapsed().as_secs_f64();
    if !quiet {
        super::out(&navigation_summary(&report, elapsed))?;
    }
    if let Some(path) = plot {
        navigation_plot(&report, &path)?;
        if !quiet {
            super::out(&format!("figure: {}\n", path.display()))?;
        }
    }
    if let Some(path) = json {
        write_json(&path, &report)?;
    }
    Ok(())
}

fn navigation_summary(r: &NavReport, elapsed_s: f64) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "sinscal navigate: {} ({}), {:.2} h at {} Hz, latitude {} deg, attitude ({}, {}, {}) deg, height held",
        r.source,
        if r.simulated { "SIMULATED static run of the recording's IMU" } else { "recorded static dwell" },
        r.hours,
        r.rate_hz,
        r.latitude_deg,
        r.attitude_deg[0],
        r.attitude_deg[1],
        r.attitude_deg[2]
    );
    let _ = writeln!(
        out,
        "\n  {:<44} {:>12} {:>12} {:>11} {:>11} {:>12} {:>12}",
        "run", "max pos [m]", "end pos [m]", "max v [m/s]", "end v [m/s]", "max hdg [\"]", "end hdg [\"]"
    );
    for s in &r.runs {
        let _ = writeln!(
            out,
            "  {:<44} {:>12.2} {:>12.2} {:>11.4} {:>11.4} {:>12.2} {:>12.2}",
            s.name,
            s.max_horizontal_position_error_m,
            s.final_horizontal_position_error_m,
            s.max_horizontal_velocity_error_mps,
            s.final_horizontal_velocity_error_mps,
            s.max_heading_error_rad * ARCSEC_PER_RAD,
            s.final_heading_error_rad * ARCSEC_PER_RAD
        );
    }
    if r.runs.len() >= 2 && r.runs[1].max_horizontal_position_error_m > 0.0 {
        let _ = writeln!(
            out,
            "\n  largest horizontal error: uncompensated / calibrated = {:.1}",
            r.runs[0].max_horizontal_position_error_m / r.runs[1].max_horizontal_position_error_m
        );
    }
    if let Some(p) = &r.predicted_from_std_errors {
        let _ = writeln!(
            out,
            "  the calibration's covariance ({} parameters) predicts for the calibrated run (RMS): \
             {:.2} m at the end, {:.2} m at most; heading {:.2} arcsec at the end",
            p.parameters,
            p.rms_final_horizontal_position_error_m,
            p.max_rms_horizontal_position_error_m,
            p.rms_final_heading_error_rad * ARCSEC_PER_RAD
        );
    }
    let _ = writeln!(out, "  computed in {elapsed_s:.2} s");
    out
}

/// `--hours`: a finite number in (0, 48] (otherwise a usage error, exit 2).
fn parse_hours(text: &str) -> Result<f64, String> {
    use crate::navigation::check::MAX_HOURS;
    match text.parse::<f64>() {
        Ok(h) if h > 0.0 && h <= MAX_HOURS => Ok(h),
        _ => Err(format!("'{text}' is not a number of hours in (0, {MAX_HOURS}]")),
    }
}
