//! `sinscal montecarlo`: a SIMULATION of the estimators against the Cramer-Rao bound (Table 1, white noise).

use std::path::PathBuf;

use crate::calibration::montecarlo;
use crate::cmd::write_json;
use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::{Scenario, DEG_PER_HOUR, MICRO_G};

/// Arguments of `sinscal montecarlo`.
#[derive(clap::Args)]
pub struct Args {
    /// Number of runs (at least 2).
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u32).range(2..))]
    runs: u32,
    /// First seed (run i uses seed + i).
    #[arg(long, default_value_t = 1000)]
    seed: u64,
    /// Write the report as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Passes of the solution at most (1 = the paper's linear solution).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=50))]
    passes: u32,
}

/// Runs `sinscal montecarlo`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { runs, seed, json, passes } = args;
    let runs = runs as usize;
    let scenario = Scenario::example();
    let step = (runs / 10).max(1);
    let report = montecarlo::run(&scenario, runs, seed, passes, |done| {
        if done % step == 0 || done == runs {
            eprintln!("montecarlo: {done}/{runs} runs");
        }
    });
    super::out(&montecarlo_table(&report))?;
    if let Some(path) = json {
        write_json(&path, &report)?;
    }
    Ok(())
}

fn montecarlo_table(r: &montecarlo::Report) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Monte Carlo (SIMULATION): {} runs from seed {}, Table 1, {} samples per dwell at 100 Hz, white noise {:.3} deg/h (gyro) and {:.0} ug (accel) per sample",
        r.runs,
        r.seed,
        r.dwell_samples,
        r.gyro_noise_radps / DEG_PER_HOUR,
        r.accel_noise_mps2 / MICRO_G
    );
    let unit = |name: &str| -> (f64, &'static str) {
        if name.starts_with("gyro") {
            (DEG_PER_HOUR, "deg/h")
        } else if name.starts_with("accel") {
            (MICRO_G, "ug")
        } else {
            (1.0 / ARCSEC_PER_RAD, "arcsec")
        }
    };
    for e in &r.estimators {
        let _ = writeln!(out, "\nestimator: {}", e.estimator.name());
        let _ = writeln!(
            out,
            "  {:<20} {:>7} {:>11} {:>11} {:>11} {:>11} {:>9} {:>9}",
            "parameter", "unit", "mean err", "RMS err", "RMS SE", "CRB", "RMS/CRB", "RMS z"
        );
        for p in &e.parameters {
            let (u, name) = unit(p.parameter);
            let _ = writeln!(
                out,
                "  {:<20} {:>7} {:>11.5} {:>11.5} {:>11.5} {:>11.5} {:>9.3} {:>9.3}",
                p.parameter,
                name,
                p.mean_error / u,
                p.rms_error / u,
                p.rms_reported_std / u,
                p.crb_angles / u,
                p.efficiency_ratio,
                p.rms_normalised_error
            );
        }
    }
    let _ = writeln!(out, "\nCramer-Rao bounds (standard deviation): angle model vs. all six channels of every dwell");
    let _ = writeln!(
        out,
        "  {:<20} {:>7} {:>11} {:>14} {:>16} {:>12}",
        "parameter", "unit", "angles", "six channels", "channels, ref. exact", "angles/chan."
    );
    for (i, p) in sinscal::calib::angles::Parameter::ALL.iter().enumerate() {
        let (u, name) = unit(p.name());
        let known = r.crb_channels_known_reference.get(i).map_or("-".to_string(), |v| format!("{:.5}", v / u));
        let _ = writeln!(
            out,
            "  {:<20} {:>7} {:>11.5} {:>14.5} {:>16} {:>12.2}",
            p.name(),
            name,
            r.crb_angles[i] / u,
            r.crb_channels[i] / u,
            known,
            r.crb_angles[i] / r.crb_channels[i]
        );
    }
    let _ = writeln!(
        out,
        "\nSettled output: variance {:.4} (gyro) and {:.4} (accel) of one raw sample, against 1/{} = {:.2e} for the dwell mean: \
         std ratio {:.1} and {:.1}.",
        r.settled_noise_gain[0],
        r.settled_noise_gain[1],
        r.dwell_samples,
        1.0 / r.dwell_samples as f64,
        (r.settled_noise_gain[0] * r.dwell_samples as f64).sqrt(),
        (r.settled_noise_gain[1] * r.dwell_samples as f64).sqrt()
    );
    let _ = writeln!(out, "\nRMS/CRB: RMS error over the angle-model bound (1 = efficient). RMS z: RMS of error / reported standard error (1 = honest standard errors).");
    out
}
