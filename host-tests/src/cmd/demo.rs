//! `sinscal demo`: writes the built-in example (a SIMULATION of the paper's Table 1 with known biases) and
//! calibrates it, with the truth printed beside the estimates.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;

use crate::calibration::{calibrate, Calibration, Options};
use crate::cmd::calibrate::finish;
use crate::io::error::InputError;
use crate::io::recording::Recording;
use crate::io::ARCSEC_PER_RAD;
use crate::model::synth::{Scenario, DEG_PER_HOUR, MICRO_G};

/// Arguments of `sinscal demo`.
#[derive(clap::Args)]
pub struct Args {
    /// Where to write the example recording.
    #[arg(long, default_value = "target/sinscal-example.csv")]
    out: PathBuf,
    /// Also write the calibration JSON here.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Runs `sinscal demo`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (out, json) = (args.out.as_path(), args.json.as_deref());
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let scenario = Scenario::example();
    let rec = scenario.recording(1, &out.display().to_string());
    rec.write(out)?;
    super::out(&format!(
        "Built-in example: {} (SIMULATION of the paper's Table 1, 60 s per position at 100 Hz, seed 1)\n\n",
        out.display()
    ))?;
    let rec = Recording::read(out)?;
    let cal = calibrate(&rec, &Options::default()).map_err(|e: InputError| anyhow::anyhow!(e))?;
    // The truth table is shown also when a check failed (exit 3 after it).
    let checked = finish(&cal, json);
    if checked.as_ref().is_err_and(|e| e.downcast_ref::<super::ChecksFailed>().is_none()) {
        return checked;
    }
    super::out(&truth_table(&scenario, &cal))?;
    checked
}

/// The truth of the simulation beside each estimate, and the error in standard errors.
fn truth_table(scenario: &Scenario, cal: &Calibration) -> String {
    let mut text = String::from("\nTruth of the simulation, and (estimate - truth) / standard error:\n");
    let e = &cal.estimates;
    let rows: [(&str, usize, f64, f64, &str); 9] = [
        ("gyro x", 0, scenario.gyro_bias_b_radps[0], DEG_PER_HOUR, "deg/h"),
        ("gyro y", 1, scenario.gyro_bias_b_radps[1], DEG_PER_HOUR, "deg/h"),
        ("gyro z", 2, scenario.gyro_bias_b_radps[2], DEG_PER_HOUR, "deg/h"),
        ("accel x", 3, scenario.accel_bias_b_mps2[0], MICRO_G, "ug"),
        ("accel y", 4, scenario.accel_bias_b_mps2[1], MICRO_G, "ug"),
        ("accel z", 5, scenario.accel_bias_b_mps2[2], MICRO_G, "ug"),
        ("offset e", 33, scenario.reference_offset_n_rad[0], 1.0 / ARCSEC_PER_RAD, "arcsec"),
        ("offset n", 34, scenario.reference_offset_n_rad[1], 1.0 / ARCSEC_PER_RAD, "arcsec"),
        ("offset u", 35, scenario.reference_offset_n_rad[2], 1.0 / ARCSEC_PER_RAD, "arcsec"),
    ];
    for (name, index, truth, unit, unit_name) in rows {
        let _ = match (e.value_si[index], e.std_si[index]) {
            (Some(v), Some(sd)) => writeln!(
                text,
                "  {name:<8} truth {:>+10.5} {unit_name:<6} estimate {:>+10.5}  ({:+.2} sigma)",
                truth / unit,
                v / unit,
                (v - truth) / sd
            ),
            _ if e.unobservable.contains(&index) => {
                writeln!(text, "  {name:<8} truth {:>+10.5} {unit_name:<6} unobservable", truth / unit)
            }
            _ => writeln!(text, "  {name:<8} truth {:>+10.5} {unit_name:<6} not in the model", truth / unit),
        };
    }
    text
}
