//! `sinscal simulate SCENARIO --out RECORDING`: a SIMULATION of a turntable session from a scenario file.

use std::path::PathBuf;

use crate::model::simulator::{simulate, ScenarioFile};

/// Arguments of `sinscal simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (docs/formats.md#scenario; examples in host-tests/scenarios/).
    scenario: PathBuf,
    /// Noise seed: the same seed gives the same recording.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output recording.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `sinscal simulate`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let Args { scenario, seed, out } = args;
    let file = ScenarioFile::read(&scenario)?;
    let rec = simulate(&file, seed, &scenario.display().to_string());
    rec.write(&out)?;
    let s = &file.schedule;
    super::out(&format!(
        "wrote {} ({} rows, {:.1} s at {} Hz, {} positions; SIMULATION of {}, seed {seed})\n",
        out.display(),
        rec.rows.len(),
        rec.rows.len() as f64 / s.rate_hz,
        s.rate_hz,
        s.positions_deg.len(),
        scenario.display()
    ))
}
