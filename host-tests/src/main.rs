//! `sinscal`: calibration of a strapdown IMU on a turntable, on the workstation (docs/cli.md).
//! Exit status: 0 success, 1 bad input (one-line reason on stderr), 2 usage error, 3 a result was written but
//! fails one of its checks (`calibrate`, and `apply` of such a result: each failed check one line on stderr,
//! `sinscal: check failed: NAME: DETAIL`, docs/cli.md#checks). A pipeline can trust exit 0.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sinscal_host::cmd;

#[derive(Parser)]
#[command(
    name = "sinscal",
    version,
    about = "Fast six-position bias calibration of a strapdown IMU (HMM/KF prefilter, analytic coarse alignment, least squares)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Calibrate gyro and accelerometer biases from a recording (docs/formats.md#recording).
    Calibrate(cmd::calibrate::Args),
    /// Write the built-in example recording (a SIMULATION of Table 1 with known biases).
    Example(cmd::example::Args),
    /// What the base model (biases + white noise) gets wrong: the effects of the catalogue
    /// (docs/formats.md#effect-catalogue) that a recording or an angles file shows, with estimates,
    /// standard errors and the BIC gain.
    Analyze(cmd::analyze::Args),
    /// SIMULATION of a turntable session from a scenario file (TOML; every effect of the catalogue).
    Simulate(cmd::simulate::Args),
    /// Write the built-in example and calibrate it, showing the truth beside the estimates.
    Demo(cmd::demo::Args),
    /// Compensate a recording with a calibration result (JSON version 1 or 2): f = T_a^-1 (f_meas - b_a),
    /// w = T_g^-1 (w_meas - b_g - G f).
    Apply(cmd::apply::Args),
    /// Per dwell, the attitude of the analytic coarse alignment with standard errors, against the reference.
    Align(cmd::align::Args),
    /// Each channel's noise terms (quantisation, white noise, bias instability, Gauss-Markov, rate random walk),
    /// with standard errors, from a static recording's longest dwell (a noise file, JSON).
    Noise(cmd::noise::Args),
    /// Static pure-inertial navigation with and without the calibration's biases removed.
    Navigate(cmd::navigate::Args),
    /// Convert a measured data set (PSINS .imu, imucal Ferraris session, imu_tk counts) into a recording.
    Import(cmd::import::Args),
    /// Study of a measured data set against a SIMULATION of it: base model, disagreement, cause, extended model,
    /// gain on held-out data (report with figures).
    Study(cmd::study::Args),
    /// SIMULATION: Monte Carlo of the estimators against the Cramer-Rao bound (Table 1, white noise).
    Montecarlo(cmd::montecarlo::Args),
    /// The calibration firmware as an instrument over its serial link (QEMU or a board): run a calibration and
    /// store it, or show the stored record.
    Device(cmd::device::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Calibrate(args) => cmd::calibrate::run(args),
        Command::Example(args) => cmd::example::run(args),
        Command::Analyze(args) => cmd::analyze::run(args),
        Command::Simulate(args) => cmd::simulate::run(args),
        Command::Demo(args) => cmd::demo::run(args),
        Command::Apply(args) => cmd::apply::run(args),
        Command::Align(args) => cmd::align::run(args),
        Command::Navigate(args) => cmd::navigate::run(args),
        Command::Noise(args) => cmd::noise::run(args),
        Command::Import(args) => cmd::import::run(args),
        Command::Study(args) => cmd::study::run(args),
        Command::Montecarlo(args) => cmd::montecarlo::run(args),
        Command::Device(args) => cmd::device::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of standard output closed it (`sinscal ... | head`): it wanted no more.
        Err(e)
            if e.downcast_ref::<cmd::StdoutError>().is_some_and(|o| o.0.kind() == std::io::ErrorKind::BrokenPipe) =>
        {
            ExitCode::SUCCESS
        }
        Err(e) if e.downcast_ref::<cmd::ChecksFailed>().is_some() => {
            // The result was written; each failed check is one line (no generic error line).
            for line in e.downcast_ref::<cmd::ChecksFailed>().map_or(&[][..], |c| &c.0[..]) {
                eprintln!("sinscal: {line}");
            }
            ExitCode::from(3)
        }
        Err(e) => {
            // Bad input and failures: one line on stderr, exit 1 (usage errors exit 2 through clap).
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("sinscal: {}", chain.join(": "));
            ExitCode::from(1)
        }
    }
}
