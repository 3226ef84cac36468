//! `sinscal study DATASET --report DIR`: a measured data set against a SIMULATION of it: base model,
//! disagreement, cause, extended model, gain on held-out data.

use std::path::PathBuf;

use crate::study::Dataset;

/// Arguments of `sinscal study`.
#[derive(clap::Args)]
pub struct Args {
    /// The data set.
    #[arg(value_enum)]
    dataset: Dataset,
    /// The data directory (default: $SINSCAL_DATA).
    #[arg(long)]
    data: Option<PathBuf>,
    /// Directory for summary.md and the figures.
    #[arg(long)]
    report: PathBuf,
    /// Write the study as JSON to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `sinscal study`.
pub fn run(args: Args) -> anyhow::Result<()> {
    crate::study::run(args.dataset, args.data.as_deref(), &args.report, args.json.as_deref()).map(|_| ())
}
