//! `sinscal study DATASET|RECORDING --report DIR`: a measured data set or any recording against a SIMULATION of
//! it: base model, disagreement, cause, extended model, gain on held-out data.

use std::path::PathBuf;

/// Arguments of `sinscal study`.
#[derive(clap::Args)]
pub struct Args {
    /// A recording file (an existing file wins), or a data set: psins, ferraris or imutk.
    #[arg(value_name = "DATASET|RECORDING")]
    target: String,
    /// The data directory of the data sets (default: $SINSCAL_DATA); not used for a recording.
    #[arg(long)]
    data: Option<PathBuf>,
    /// Directory for summary.md and the figures.
    #[arg(long)]
    report: PathBuf,
    /// Write the study as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `sinscal study`: status 3 (`ChecksFailed`) when the recording failed a check, the study written.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (_, failed) = crate::study::run(&args.target, args.data.as_deref(), &args.report, args.json.as_deref())?;
    if failed.is_empty() {
        Ok(())
    } else {
        Err(super::ChecksFailed(failed).into())
    }
}
