//! `sinscal analyze RECORDING|ANGLES`: what the base model (biases and white noise) gets wrong, which
//! effect of the catalogue explains it, with estimates, standard errors and the BIC gain; exit status 3 when
//! the analysis fails one of its checks (the final model leaves a channel unexplained, a candidate needs an
//! impossible value).

use std::path::PathBuf;

use crate::calibration::checks::failed_lines;
use crate::cmd::{json_to_stdout, write_json, ChecksFailed};

/// Arguments of `sinscal analyze`.
#[derive(clap::Args)]
pub struct Args {
    /// A recording (docs/formats.md#recording) or an angles file (docs/formats.md#angles, '# sinscal-angles: 1').
    input: PathBuf,
    /// Write the result as JSON (docs/formats.md#analysis-json) to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write a report (summary.md and figures) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
}

/// Runs `sinscal analyze`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { input, json, report } = args;
    let quiet = json_to_stdout(json.as_deref());
    eprintln!("sinscal analyze: reading {}", input.display());
    let analysis = crate::analysis::analyze_path(&input)?;
    if !quiet {
        super::out(&crate::analysis::summary(&analysis))?;
    }
    if let Some(dir) = report {
        let files = crate::analysis::report::write_report(&analysis, &dir)?;
        if !quiet {
            super::out(&format!("report: {} ({})\n", dir.display(), files.join(", ")))?;
        }
    }
    if let Some(path) = json {
        write_json(&path, &analysis)?;
    }
    let failed = failed_lines(&analysis.checks);
    if failed.is_empty() {
        Ok(())
    } else {
        Err(ChecksFailed(failed).into())
    }
}
