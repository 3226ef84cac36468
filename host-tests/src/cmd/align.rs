//! `sinscal align RECORDING`: per dwell, the attitude of the analytic coarse alignment with standard errors and
//! its difference from the recording's reference attitude (docs/cli.md#align).

use std::path::PathBuf;

use crate::cmd::{json_to_stdout, write_json};
use crate::io::recording::RecordingFile;
use crate::navigation::alignment::{align, summary};

/// Arguments of `sinscal align`.
#[derive(clap::Args)]
pub struct Args {
    /// The recording (docs/formats.md#recording); accelerometer-only data give pitch and roll only.
    recording: PathBuf,
    /// Write the result as JSON (docs/formats.md#alignment-json) to this file ('-' = stdout).
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `sinscal align`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { recording, json } = args;
    let rec = RecordingFile::open(&recording)?;
    let report = align(&rec)?;
    if !json_to_stdout(json.as_deref()) {
        super::out(&summary(&report))?;
    }
    if let Some(path) = json {
        write_json(&path, &report)?;
    }
    Ok(())
}
