//! `sinscal example --out FILE`: the built-in example recording (a SIMULATION of Table 1 with known biases).

use std::path::PathBuf;

use crate::model::synth::Scenario;

/// Arguments of `sinscal example`.
#[derive(clap::Args)]
pub struct Args {
    /// Output recording.
    #[arg(long)]
    out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs `sinscal example`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { out, seed } = args;
    let rec = Scenario::example().recording(seed, &out.display().to_string());
    rec.write(&out)?;
    super::out(&format!(
        "wrote {} ({} rows, SIMULATION of Table 1 with known biases, seed {seed})\n",
        out.display(),
        rec.rows.len()
    ))?;
    Ok(())
}
