//! Hidden-effect trials: a SIMULATED Table 1 session (the clean scenario of `host-tests/scenarios/`) with one
//! effect of the catalogue hidden at a seeded random axis, sign and magnitude; `sinscal analyze` gets the
//! recording without the truth, and the trial checks its verdict, axes, sign and magnitude (within 30 %).
//!
//! Magnitudes are drawn in units of what the session can resolve: 10 to 20 standard errors of the
//! effect's estimate in the clean session (from the analysis of a clean recording, [`reference_errors`]),
//! so that the trials measure the analysis, not the luck of the draw. Time constants and frequencies are
//! drawn from the ranges the analysis claims to resolve (stated at each effect).

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::analysis::{analyze_recording, Analysis};
use crate::io::recording::Recording;
use crate::model::simulator::{
    simulate, GaussMarkovSpec, PositionError, ScenarioFile, TemperatureSpec, VibrationSpec, WarmupSpec,
};

/// The clean scenario every trial starts from (constant biases and white noise only).
pub const CLEAN_SCENARIO: &str = include_str!("../../scenarios/table1-clean.toml");

/// Effects the trials hide, with the axes each may take in the Table 1 schedule. Entries that this
/// schedule cannot see (body y is horizontal in every position, so nothing proportional to the force
/// along y) or cannot tell apart (the gyro's response to rate about z and to force along z have the same
/// pattern over the six positions: gyro_misalignment xz/yz, gyro_scale_factor z and gyro_g_sensitivity
/// xz/yz/zz) are left out; `sinscal analyze` lists them as unobservable or as aliases.
pub fn catalogue() -> Vec<(&'static str, Vec<&'static str>)> {
    vec![
        ("accel_scale_factor", vec!["x", "z"]),
        ("accel_misalignment", vec!["xz", "yx", "yz", "zx"]),
        ("gyro_scale_factor", vec!["x", "y"]),
        ("gyro_misalignment", vec!["xy", "yx", "zx", "zy"]),
        ("gyro_g_sensitivity", vec!["xx", "yx", "zx"]),
        ("reference_offset", vec!["e", "n", "u"]),
        ("position_error", vec!["e", "n", "u"]),
        ("bias_drift", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
        ("bias_warmup", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
        ("temperature_bias", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
        ("correlated_noise", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
        ("vibration", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
        ("quantization", vec!["gx", "gy", "gz", "ax", "ay", "az"]),
    ]
}

/// The truth of one trial.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    /// Catalogue name.
    pub effect: &'static str,
    /// "gyro", "accel" or "reference".
    pub sensor: &'static str,
    /// Axes as the analysis names them.
    pub axes: String,
    /// Position (position errors).
    pub pos: Option<u32>,
    /// True value, SI (the catalogue's estimate quantity).
    pub value: f64,
    /// Time constant, s (warm-up, correlated noise, the temperature profile).
    pub tau_s: Option<f64>,
    /// Frequency, Hz (vibration).
    pub frequency_hz: Option<f64>,
}

/// Standard errors of every linear candidate in a clean session, by the analysis's name
/// ("accel_scale_factor:x", "position_error:e:pos3", ...), and the white-noise standard deviation per
/// channel (gx..az).
#[derive(Clone, Debug)]
pub struct ReferenceErrors {
    /// Standard error per candidate name.
    pub std_error: BTreeMap<String, f64>,
    /// White noise per sample, gyro (rad/s) and accelerometer (m/s^2).
    pub noise: [f64; 2],
}

/// The clean scenario.
pub fn clean_scenario() -> ScenarioFile {
    ScenarioFile::parse(CLEAN_SCENARIO, "table1-clean.toml").expect("the built-in clean scenario parses")
}

/// Standard errors from the analysis of a clean recording (seed `seed`).
pub fn reference_errors(seed: u64) -> ReferenceErrors {
    let scenario = clean_scenario();
    let rec = simulate(&scenario, seed, "table1-clean.toml");
    let a = analyze_recording(&rec).expect("the clean recording analyses");
    let dt = 1.0 / scenario.schedule.rate_hz;
    ReferenceErrors {
        std_error: a.tested.iter().map(|t| (t.name.clone(), t.std_error)).collect(),
        noise: [
            scenario.gyro.angle_random_walk_rad_per_sqrt_s / dt.sqrt(),
            scenario.accel.velocity_random_walk_mps_per_sqrt_s / dt.sqrt(),
        ],
    }
}

fn axis(c: char) -> usize {
    match c {
        'x' | 'e' => 0,
        'y' | 'n' => 1,
        _ => 2,
    }
}

/// Draws the trial `seed` of `effect` (one of [`catalogue`]) and returns its scenario and truth.
pub fn draw(effect: &'static str, seed: u64, reference: &ReferenceErrors) -> (ScenarioFile, Hidden) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ effect.len() as u64);
    let axes_list =
        catalogue().into_iter().find(|(e, _)| *e == effect).map(|(_, a)| a).expect("effect in the catalogue");
    let axes = axes_list[rng.random_range(0..axes_list.len())];
    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
    let snr = rng.random_range(10.0..20.0);
    let mut s = clean_scenario();
    let positions = s.schedule.positions_deg.len() as u32;
    let mut hidden =
        Hidden { effect, sensor: "", axes: axes.to_string(), pos: None, value: 0.0, tau_s: None, frequency_hz: None };
    let se = |name: String| -> f64 {
        *reference.std_error.get(&name).unwrap_or_else(|| panic!("no reference standard error for {name}"))
    };
    // Sensor-channel effects: axes "gx".."az".
    let (gyro, ax) = (axes.starts_with('g'), axes.chars().last().map_or(0, axis));
    let noise = if gyro { reference.noise[0] } else { reference.noise[1] };
    match effect {
        "accel_scale_factor" | "accel_misalignment" => {
            let (i, j) = (axis(axes.as_bytes()[0] as char), axis(axes.chars().last().unwrap_or('x')));
            hidden.sensor = "accel";
            hidden.value = sign * snr * se(format!("{effect}:{axes}"));
            s.accel.misalignment[i][j] = if i == j { 0.0 } else { hidden.value };
            if i == j {
                s.accel.scale_factor[i] = hidden.value;
            }
        }
        "gyro_scale_factor" | "gyro_misalignment" => {
            let (i, j) = (axis(axes.as_bytes()[0] as char), axis(axes.chars().last().unwrap_or('x')));
            hidden.sensor = "gyro";
            hidden.value = sign * snr * se(format!("{effect}:{axes}"));
            if i == j {
                s.gyro.scale_factor[i] = hidden.value;
            } else {
                s.gyro.misalignment[i][j] = hidden.value;
            }
        }
        "gyro_g_sensitivity" => {
            let (i, j) = (axis(axes.as_bytes()[0] as char), axis(axes.as_bytes()[1] as char));
            hidden.sensor = "gyro";
            hidden.value = sign * snr * se(format!("{effect}:{axes}"));
            s.gyro.g_sensitivity_radps_per_mps2[i][j] = hidden.value;
        }
        "reference_offset" => {
            hidden.sensor = "reference";
            hidden.value = sign * snr * se(format!("{effect}:{axes}"));
            s.schedule.reference_offset_enu_rad[axis(axes.as_bytes()[0] as char)] = hidden.value;
        }
        "position_error" => {
            let pos = rng.random_range(1..=positions);
            hidden.sensor = "reference";
            hidden.pos = Some(pos);
            hidden.value = sign * snr * se(format!("{effect}:{axes}:pos{pos}"));
            let mut enu = [0.0; 3];
            enu[axis(axes.as_bytes()[0] as char)] = hidden.value;
            s.schedule.position_error.push(PositionError { pos, enu_rad: enu });
        }
        _ => {
            hidden.sensor = if gyro { "gyro" } else { "accel" };
            hidden.axes = ["x", "y", "z"][ax].to_string();
            let mut v = [0.0; 3];
            match effect {
                "bias_drift" => {
                    hidden.value = sign * snr * se(format!("bias_drift:{}", hidden.axes_of(gyro)));
                    v[ax] = hidden.value;
                    if gyro {
                        s.gyro.drift_radps_per_s = v;
                    } else {
                        s.accel.drift_mps2_per_s = v;
                    }
                }
                "bias_warmup" => {
                    // Time constants 20..100 s: curved within the session of about 390 s (a longer one is a
                    // drift to this session), and long against a block.
                    let tau = rng.random_range(20.0..100.0);
                    // Amplitude: 10..20 times its standard error from the block means (the shape's energy
                    // after the constant bias is removed), times 1.5 for the time constant being estimated.
                    let shape: Vec<f64> = block_times(&s).iter().map(|t| (-t / tau).exp()).collect();
                    hidden.value = sign * snr * 1.5 * block_noise(&s, noise) / centred_norm(&shape);
                    hidden.tau_s = Some(tau);
                    v[ax] = hidden.value;
                    let w = Some(WarmupSpec { amplitude: v, tau_s: tau });
                    if gyro {
                        s.gyro.warmup = w;
                    } else {
                        s.accel.warmup = w;
                    }
                }
                "temperature_bias" => {
                    // The sensor warms from 20 to 35 deg C with a 200 s time constant; the coefficient is
                    // 10..20 times its standard error from the block means.
                    let t = TemperatureSpec { start_c: 20.0, end_c: 35.0, tau_s: 200.0, reference_c: 20.0 };
                    let shape: Vec<f64> = block_times(&s).iter().map(|&x| t.at(x)).collect();
                    hidden.value = sign * snr * block_noise(&s, noise) / centred_norm(&shape);
                    hidden.tau_s = Some(200.0);
                    s.temperature = Some(t);
                    v[ax] = hidden.value;
                    if gyro {
                        s.gyro.temperature_coefficient_radps_per_k = v;
                    } else {
                        s.accel.temperature_coefficient_mps2_per_k = v;
                    }
                }
                "correlated_noise" => {
                    // Gauss-Markov of 0.2..2 s time constant and 1..3 times the white noise per sample.
                    let tau = rng.random_range(0.2..2.0);
                    hidden.value = rng.random_range(1.0..3.0) * noise;
                    hidden.tau_s = Some(tau);
                    v[ax] = hidden.value;
                    let gm = Some(GaussMarkovSpec { sigma: v, tau_s: tau });
                    if gyro {
                        s.gyro.bias_instability = gm;
                    } else {
                        s.accel.bias_instability = gm;
                    }
                }
                "vibration" => {
                    // 0.3..30 Hz, amplitude 10..20 standard errors of a sinusoid's amplitude in white noise.
                    let f = rng.random_range(0.3..30.0);
                    let samples = 6.0 * s.schedule.dwell_s * s.schedule.rate_hz;
                    hidden.value = snr * noise * (2.0 / samples).sqrt();
                    hidden.frequency_hz = Some(f);
                    v[ax] = hidden.value;
                    let vib = Some(VibrationSpec { amplitude: v, frequency_hz: f });
                    if gyro {
                        s.gyro.vibration = vib;
                    } else {
                        s.accel.vibration = vib;
                    }
                }
                "quantization" => {
                    // Output step 0.3..3 times the white noise per sample.
                    hidden.value = rng.random_range(0.3..3.0) * noise;
                    v[ax] = hidden.value;
                    if gyro {
                        s.gyro.quantization_radps = v;
                    } else {
                        s.accel.quantization_mps2 = v;
                    }
                }
                other => panic!("unknown effect {other}"),
            }
        }
    }
    (s, hidden)
}

/// Mid times of the analysis's blocks (6 s, ten per one-minute dwell) in the scenario's schedule, s.
fn block_times(s: &ScenarioFile) -> Vec<f64> {
    let sch = &s.schedule;
    let blocks = ((sch.dwell_s * sch.rate_hz) as usize / crate::analysis::BLOCK_SAMPLES).max(4);
    let mut times = Vec::new();
    for k in 0..sch.positions_deg.len() {
        let start = k as f64 * (sch.dwell_s + sch.settle_s + sch.move_s) + sch.settle_s;
        for b in 0..blocks {
            times.push(start + (b as f64 + 0.5) * sch.dwell_s / blocks as f64);
        }
    }
    times
}

/// White noise of a block mean.
fn block_noise(s: &ScenarioFile, per_sample: f64) -> f64 {
    let sch = &s.schedule;
    let blocks = ((sch.dwell_s * sch.rate_hz) as usize / crate::analysis::BLOCK_SAMPLES).max(4) as f64;
    per_sample / (sch.dwell_s * sch.rate_hz / blocks).sqrt()
}

/// Euclidean norm of `v` after its mean is removed.
fn centred_norm(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().map(|x| (x - m) * (x - m)).sum::<f64>().sqrt()
}

impl Hidden {
    fn axes_of(&self, gyro: bool) -> String {
        format!("{} ({})", self.axes, if gyro { "gyro" } else { "accel" })
    }
}

/// How one trial came out.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// The truth.
    pub hidden: Hidden,
    /// The analysis's verdict.
    pub verdict: String,
    /// Axes of the first effect found.
    pub axes: Option<String>,
    /// Its estimate.
    pub estimate: Option<f64>,
    /// Verdict, sensor, axes, position, sign right and magnitude within 30 %.
    pub correct: bool,
    /// Effects found, as "effect:sensor:axes".
    pub found: Vec<String>,
}

/// Runs the analysis on a recording and checks it against the truth.
pub fn judge(analysis: &Analysis, hidden: &Hidden) -> Outcome {
    let first = analysis.effects.first();
    let correct = first.is_some_and(|e| {
        e.effect == hidden.effect
            && e.sensor == hidden.sensor
            && e.axes == hidden.axes
            && e.pos == hidden.pos
            && e.estimate.signum() == hidden.value.signum()
            && ((e.estimate - hidden.value) / hidden.value).abs() <= 0.3
    });
    Outcome {
        hidden: hidden.clone(),
        verdict: analysis.verdict.clone(),
        axes: first.map(|e| e.axes.clone()),
        estimate: first.map(|e| e.estimate),
        correct,
        found: analysis.effects.iter().map(|e| format!("{}:{}:{}", e.effect, e.sensor, e.axes)).collect(),
    }
}

/// One trial: simulate, analyse, judge.
pub fn trial(effect: &'static str, seed: u64, reference: &ReferenceErrors) -> Outcome {
    let (scenario, hidden) = draw(effect, seed, reference);
    let rec: Recording = simulate(&scenario, seed, "hidden-effect trial");
    let analysis = analyze_recording(&rec).expect("a simulated recording analyses");
    judge(&analysis, &hidden)
}

/// A clean trial: the verdict must be "none".
pub fn clean_trial(seed: u64) -> Analysis {
    let rec = simulate(&clean_scenario(), seed, "clean trial");
    analyze_recording(&rec).expect("a simulated recording analyses")
}
