//! `sinscal`: calibration of strapdown IMU biases on a turntable, on the workstation.
//! Exit status: 0 success, 1 bad input (one-line reason on stderr), 2 usage error.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use clap::{Parser, Subcommand, ValueEnum};
use sinscal::calib::align::DwellValue;
use sinscal_host::calibrate::{calibrate, Calibration, Coefficient, Options, PrefilterKind};
use sinscal_host::error::InputError;
use sinscal_host::montecarlo;
use sinscal_host::navcheck::{navigate, CalibrationBiases, NavOptions, NavReport};
use sinscal_host::output::{summary, CalibrationJson, ARCSEC_PER_RAD};
use sinscal_host::plot::navigation_plot;
use sinscal_host::qemu::calibrate_on_qemu;
use sinscal_host::recording::Recording;
use sinscal_host::replayfile::calibrate_on_host;
use sinscal_host::simulate::{simulate, ScenarioFile};
use sinscal_host::synth::{Scenario, DEG_PER_HOUR, MICRO_G};

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

#[derive(Clone, Copy, ValueEnum)]
enum PrefilterArg {
    /// The paper's two-state HMM/KF with its Q and R.
    Hmmkf,
    /// No prefilter.
    None,
}

#[derive(Clone, Copy, ValueEnum)]
enum DwellValueArg {
    /// Mean of the (filtered) dwell: minimum variance for white noise.
    Mean,
    /// The prefilter's settled output at the end of the dwell (the paper's alternative).
    Settled,
}

#[derive(Clone, Copy, ValueEnum)]
enum OnArg {
    /// Replay through the firmware path on x86 (device frames, driver, queue, sequence, core).
    Host,
    /// Replay through the firmware in QEMU (mps2-an386, Cortex-M4F).
    Qemu,
}

#[derive(Subcommand)]
enum Command {
    /// Calibrate gyro and accelerometer biases from a recording (SPEC.md section 2).
    Calibrate {
        /// The recording (CSV).
        recording: PathBuf,
        /// Write the result as JSON (SPEC.md section 5) to this file ('-' = stdout).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Prefilter in front of the dwell statistics.
        #[arg(long, value_enum, default_value = "hmmkf")]
        prefilter: PrefilterArg,
        /// The prefilter's coefficient a in [0, 1], or 'auto' to identify it from the first dwell.
        #[arg(long, default_value = "1")]
        prefilter_a: String,
        /// Which dwell value the alignment uses.
        #[arg(long, value_enum, default_value = "mean")]
        dwell_value: DwellValueArg,
        /// Take the turntable reference as exact (do not estimate the constant offset phi0).
        #[arg(long)]
        no_reference_offset: bool,
        /// Passes of the solution at most: 1 = the paper's single linear solution; more remove its
        /// second-order error by realigning the bias-compensated dwells.
        #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=50))]
        passes: u32,
        /// Replay through the firmware path (device frames quantised by an ADIS16505-2, driver, sampling
        /// queue, calibration sequence) on this machine or in the emulated Cortex-M4F.
        #[arg(long, value_enum)]
        on: Option<OnArg>,
    },
    /// Write the built-in example recording (a SIMULATION of Table 1 with known biases).
    Example {
        /// Output recording.
        #[arg(long)]
        out: PathBuf,
        /// Noise seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// What the base model (biases + white noise) gets wrong: the effects of SPEC.md section 6 that a
    /// recording or an angles file shows, with estimates, standard errors and the BIC gain.
    Analyze {
        /// A recording (SPEC.md section 2) or an angles file (section 3, '# sinscal-angles: 1').
        input: PathBuf,
        /// Write the result as JSON (SPEC.md section 6) to this file ('-' = stdout).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write a report (summary.md and figures) into this directory.
        #[arg(long)]
        report: Option<PathBuf>,
    },
    /// SIMULATION of a turntable session from a scenario file (TOML; every effect of SPEC.md section 6).
    Simulate {
        /// Scenario file (see README, "Simulation"; examples in host-tests/scenarios/).
        scenario: PathBuf,
        /// Noise seed: the same seed gives the same recording.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output recording.
        #[arg(long)]
        out: PathBuf,
    },
    /// Write the built-in example and calibrate it, showing the truth beside the estimates.
    Demo {
        /// Where to write the example recording.
        #[arg(long, default_value = "target/sinscal-example.csv")]
        out: PathBuf,
        /// Also write the calibration JSON here.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Static pure-inertial navigation with and without the calibration's biases removed.
    Navigate {
        /// The recording: its longest static dwell is navigated, or, with --hours, a simulated static run of
        /// its IMU (for recordings written by sinscal's simulator).
        recording: PathBuf,
        /// The calibration result (JSON of `sinscal calibrate --json`).
        #[arg(long)]
        calibration: PathBuf,
        /// A second calibration to compare.
        #[arg(long)]
        compare: Option<PathBuf>,
        /// Length of a simulated static run, hours (needs a simulated recording).
        #[arg(long)]
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
    },
    /// Convert a measured data set (PSINS .imu, imucal Ferraris session, imu_tk counts) into a recording.
    Import(sinscal_host::import::ImportArgs),
    /// Study of a measured data set against a SIMULATION of it: base model, disagreement, cause, extended model,
    /// gain on held-out data (report with figures).
    Study {
        /// The data set.
        #[arg(value_enum)]
        dataset: sinscal_host::study::Dataset,
        /// The data directory (default: $SINSCAL_DATA).
        #[arg(long)]
        data: Option<PathBuf>,
        /// Directory for summary.md and the figures.
        #[arg(long)]
        report: PathBuf,
        /// Write the study as JSON to this file ('-' = stdout).
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// SIMULATION: Monte Carlo of the estimators against the Cramer-Rao bound (Table 1, white noise).
    Montecarlo {
        /// Number of runs.
        #[arg(long, default_value_t = 200)]
        runs: usize,
        /// First seed (run i uses seed + i).
        #[arg(long, default_value_t = 1000)]
        seed: u64,
        /// Write the report as JSON to this file ('-' = stdout).
        #[arg(long)]
        json: Option<PathBuf>,
        /// Passes of the solution at most (1 = the paper's linear solution).
        #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=50))]
        passes: u32,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Bad input and failures: one line on stderr, exit 1 (usage errors exit 2 through clap).
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("sinscal: {}", chain.join(": "));
            ExitCode::from(1)
        }
    }
}

fn write_output(path: &Path, text: &str) -> anyhow::Result<()> {
    if path == Path::new("-") {
        std::io::stdout().write_all(text.as_bytes())?;
        return Ok(());
    }
    std::fs::write(path, text).with_context(|| format!("cannot write {}", path.display()))
}

fn write_json(path: &Path, value: &impl serde::Serialize) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    write_output(path, &text)
}

fn run(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Calibrate {
            recording,
            json,
            prefilter,
            prefilter_a,
            dwell_value,
            no_reference_offset,
            passes,
            on,
        } => {
            let coefficient = if prefilter_a == "auto" {
                Coefficient::Identify
            } else {
                match prefilter_a.parse::<f32>() {
                    Ok(a) if (0.0..=1.0).contains(&a) => Coefficient::Fixed(a),
                    _ => anyhow::bail!("--prefilter-a: '{prefilter_a}' is neither 'auto' nor a number in [0, 1]"),
                }
            };
            let options = Options {
                prefilter: match prefilter {
                    PrefilterArg::Hmmkf => PrefilterKind::HmmKf,
                    PrefilterArg::None => PrefilterKind::None,
                },
                coefficient,
                dwell_value: match dwell_value {
                    DwellValueArg::Mean => DwellValue::Mean,
                    DwellValueArg::Settled => DwellValue::Settled,
                },
                estimate_reference_offset: !no_reference_offset,
                max_passes: passes,
            };
            let rec = Recording::read(&recording)?;
            let cal = match on {
                None => calibrate(&rec, &options)?,
                Some(OnArg::Host) => calibrate_on_host(&rec, &options)?,
                Some(OnArg::Qemu) => calibrate_on_qemu(&rec, &options)?,
            };
            finish(&cal, json.as_deref())
        }
        Command::Example { out, seed } => {
            let rec = Scenario::example().recording(seed, &out.display().to_string());
            rec.write(&out)?;
            println!(
                "wrote {} ({} rows, SIMULATION of Table 1 with known biases, seed {seed})",
                out.display(),
                rec.rows.len()
            );
            Ok(())
        }
        Command::Analyze { input, json, report } => {
            eprintln!("sinscal analyze: reading {}", input.display());
            let analysis = sinscal_host::analyze::analyze_path(&input)?;
            if json.as_deref() != Some(Path::new("-")) {
                print!("{}", sinscal_host::analyze::summary(&analysis));
            }
            if let Some(dir) = report {
                let files = sinscal_host::analysis_report::write_report(&analysis, &dir)?;
                if json.as_deref() != Some(Path::new("-")) {
                    println!("report: {} ({})", dir.display(), files.join(", "));
                }
            }
            if let Some(path) = json {
                write_json(&path, &analysis)?;
            }
            Ok(())
        }
        Command::Simulate { scenario, seed, out } => {
            let file = ScenarioFile::read(&scenario)?;
            let rec = simulate(&file, seed, &scenario.display().to_string());
            rec.write(&out)?;
            let s = &file.schedule;
            println!(
                "wrote {} ({} rows, {:.1} s at {} Hz, {} positions; SIMULATION of {}, seed {seed})",
                out.display(),
                rec.rows.len(),
                rec.rows.len() as f64 / s.rate_hz,
                s.rate_hz,
                s.positions_deg.len(),
                scenario.display()
            );
            Ok(())
        }
        Command::Demo { out, json } => demo(&out, json.as_deref()),
        Command::Navigate { recording, calibration, compare, hours, position, seed, json, plot } => {
            let rec = Recording::read(&recording)?;
            let cal = CalibrationBiases::read(&calibration)?;
            let second = compare.as_deref().map(CalibrationBiases::read).transpose()?;
            let options = NavOptions { hours, position, seed, ..NavOptions::default() };
            let started = std::time::Instant::now();
            let mut last_tenth = 0;
            let report = navigate(&rec, &cal, second.as_ref(), &options, |done, total| {
                let tenth = done * 10 / total.max(1);
                if tenth > last_tenth {
                    last_tenth = tenth;
                    eprintln!(
                        "navigate: {}0% ({:.2} of {:.2} h)",
                        tenth,
                        done as f64 / total as f64 * report_hours(hours, total),
                        report_hours(hours, total)
                    );
                }
            })?;
            let elapsed = started.elapsed().as_secs_f64();
            if json.as_deref() != Some(Path::new("-")) {
                print!("{}", navigation_summary(&report, elapsed));
            }
            if let Some(path) = plot {
                navigation_plot(&report, &path)?;
                if json.as_deref() != Some(Path::new("-")) {
                    println!("figure: {}", path.display());
                }
            }
            if let Some(path) = json {
                write_json(&path, &report)?;
            }
            Ok(())
        }
        Command::Study { dataset, data, report, json } => {
            sinscal_host::study::run(dataset, data.as_deref(), &report, json.as_deref()).map(|_| ())
        }
        Command::Import(args) => {
            if let Err(usage) = args.validate() {
                usage.exit();
            }
            print!("{}", sinscal_host::import::run(&args)?);
            Ok(())
        }
        Command::Montecarlo { runs, seed, json, passes } => {
            anyhow::ensure!(runs >= 2, "--runs must be at least 2");
            let scenario = Scenario::example();
            let step = (runs / 10).max(1);
            let report = montecarlo::run(&scenario, runs, seed, passes, |done| {
                if done % step == 0 || done == runs {
                    eprintln!("montecarlo: {done}/{runs} runs");
                }
            });
            print!("{}", montecarlo_table(&report));
            if let Some(path) = json {
                write_json(&path, &report)?;
            }
            Ok(())
        }
    }
}

fn finish(cal: &Calibration, json: Option<&Path>) -> anyhow::Result<()> {
    match json {
        Some(path) if path == Path::new("-") => write_json(path, &CalibrationJson::new(cal)),
        Some(path) => {
            print!("{}", summary(cal));
            write_json(path, &CalibrationJson::new(cal))
        }
        None => {
            print!("{}", summary(cal));
            Ok(())
        }
    }
}

fn demo(out: &Path, json: Option<&Path>) -> anyhow::Result<()> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let scenario = Scenario::example();
    let rec = scenario.recording(1, &out.display().to_string());
    rec.write(out)?;
    println!(
        "Built-in example: {} (SIMULATION of the paper's Table 1, 60 s per position at 100 Hz, seed 1)\n",
        out.display()
    );
    let rec = Recording::read(out)?;
    let cal = calibrate(&rec, &Options::default()).map_err(|e: InputError| anyhow::anyhow!(e))?;
    finish(&cal, json)?;
    println!("\nTruth of the simulation, and (estimate - truth) / standard error:");
    let s = &cal.solution;
    let rows: [(&str, Option<sinscal::calib::solve::Estimate>, f64, f64, &str); 9] = [
        ("gyro x", s.gyro_bias_b_radps[0], scenario.gyro_bias_b_radps[0], DEG_PER_HOUR, "deg/h"),
        ("gyro y", s.gyro_bias_b_radps[1], scenario.gyro_bias_b_radps[1], DEG_PER_HOUR, "deg/h"),
        ("gyro z", s.gyro_bias_b_radps[2], scenario.gyro_bias_b_radps[2], DEG_PER_HOUR, "deg/h"),
        ("accel x", s.accel_bias_b_mps2[0], scenario.accel_bias_b_mps2[0], MICRO_G, "ug"),
        ("accel y", s.accel_bias_b_mps2[1], scenario.accel_bias_b_mps2[1], MICRO_G, "ug"),
        ("accel z", s.accel_bias_b_mps2[2], scenario.accel_bias_b_mps2[2], MICRO_G, "ug"),
        ("offset e", s.reference_offset_n_rad[0], scenario.reference_offset_n_rad[0], 1.0 / ARCSEC_PER_RAD, "arcsec"),
        ("offset n", s.reference_offset_n_rad[1], scenario.reference_offset_n_rad[1], 1.0 / ARCSEC_PER_RAD, "arcsec"),
        ("offset u", s.reference_offset_n_rad[2], scenario.reference_offset_n_rad[2], 1.0 / ARCSEC_PER_RAD, "arcsec"),
    ];
    for (name, est, truth, unit, unit_name) in rows {
        match est {
            Some(e) => println!(
                "  {name:<8} truth {:>+10.5} {unit_name:<6} estimate {:>+10.5}  ({:+.2} sigma)",
                truth / unit,
                e.value as f64 / unit,
                (e.value as f64 - truth) / e.std_error as f64
            ),
            None => println!("  {name:<8} truth {:>+10.5} {unit_name:<6} unobservable", truth / unit),
        }
    }
    Ok(())
}

/// Hours of a run for progress messages (the sample count is known before the rate when not simulating).
fn report_hours(hours: Option<f64>, total: usize) -> f64 {
    hours.unwrap_or(total as f64 / 100.0 / 3600.0)
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
            "  the calibration's standard errors predict for the calibrated run (bias uncertainty only, RMS): \
             {:.2} m at the end, {:.2} m at most; heading {:.2} arcsec at the end",
            p.rms_final_horizontal_position_error_m,
            p.max_rms_horizontal_position_error_m,
            p.rms_final_heading_error_rad * ARCSEC_PER_RAD
        );
    }
    let _ = writeln!(out, "  computed in {elapsed_s:.2} s");
    out
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
    for (i, p) in sinscal::calib::solve::Parameter::ALL.iter().enumerate() {
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
