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

use sinscal_host::analysis::{analyze_recording, Analysis};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::catalogue::{EffectKind, Sensor};
use sinscal_host::model::simulator::{
    clean_scenario, simulate, GaussMarkovSpec, PositionError, ScenarioFile, TemperatureSpec, VibrationSpec, WarmupSpec,
};

/// Per-channel axes as the trials name them (the sensor, then the axis).
const CHANNEL_AXES: &[&str] = &["gx", "gy", "gz", "ax", "ay", "az"];

/// See [`catalogue`].
const TRIALS: [(EffectKind, &[&str]); 13] = [
    (EffectKind::AccelScaleFactor, &["x", "z"]),
    (EffectKind::AccelMisalignment, &["xz", "yx", "yz", "zx"]),
    (EffectKind::GyroScaleFactor, &["x", "y"]),
    (EffectKind::GyroMisalignment, &["xy", "yx", "zx", "zy"]),
    (EffectKind::GyroGSensitivity, &["xx", "yx", "zx"]),
    (EffectKind::ReferenceOffset, &["e", "n", "u"]),
    (EffectKind::PositionError, &["e", "n", "u"]),
    (EffectKind::BiasDrift, CHANNEL_AXES),
    (EffectKind::BiasWarmup, CHANNEL_AXES),
    (EffectKind::TemperatureBias, CHANNEL_AXES),
    (EffectKind::CorrelatedNoise, CHANNEL_AXES),
    (EffectKind::Vibration, CHANNEL_AXES),
    (EffectKind::Quantization, CHANNEL_AXES),
];

/// Effects the trials hide (by catalogue name), with the axes each may take in the Table 1 schedule. Entries
/// that this schedule cannot see (body y is horizontal in every position, so nothing proportional to the
/// force along y) or cannot tell apart (the gyro's response to rate about z and to force along z have the
/// same pattern over the six positions: gyro_misalignment xz/yz, gyro_scale_factor z and gyro_g_sensitivity
/// xz/yz/zz; the accelerometers' nonlinearity, the same column as `accel_misalignment:xz` on x and as
/// `accel_scale_factor:z` on z, since no pose has z down) are left out; `sinscal analyze` lists them as
/// unobservable or as aliases.
pub fn catalogue() -> Vec<(&'static str, Vec<&'static str>)> {
    TRIALS.iter().map(|(effect, axes)| (effect.name(), axes.to_vec())).collect()
}

/// The truth of one trial.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    /// The catalogue entry.
    pub effect: EffectKind,
    /// Its sensor (for the per-channel effects, the channel's).
    pub sensor: Sensor,
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
    /// The time after the record's first sample at which a noise warm-up ends, s.
    pub settled_s: Option<f64>,
}

impl Hidden {
    /// An effect of `sensor` at `axes`, its value and extras not set yet.
    pub fn new(effect: EffectKind, sensor: Sensor, axes: &str) -> Hidden {
        Hidden {
            effect,
            sensor,
            axes: axes.to_string(),
            pos: None,
            value: 0.0,
            tau_s: None,
            frequency_hz: None,
            settled_s: None,
        }
    }
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
pub fn draw(effect: EffectKind, seed: u64, reference: &ReferenceErrors) -> (ScenarioFile, Hidden) {
    let mut d = Draw::new(effect, seed, reference);
    match effect {
        EffectKind::AccelScaleFactor | EffectKind::AccelMisalignment => d.accel_term(),
        // Not in `TRIALS` (see `catalogue`): `Draw::new` has refused it already.
        EffectKind::AccelNonlinearity => unreachable!("accel_nonlinearity is not a Table 1 trial"),
        // Not among the Table 1 trials: its size needs a unit of its own, which only the campaign in the
        // records' own poses has (`own_poses::Baseline::noise_warmup_excess`).
        EffectKind::NoiseWarmup => unreachable!("noise_warmup is not a Table 1 trial"),
        EffectKind::GyroScaleFactor | EffectKind::GyroMisalignment => d.gyro_term(),
        EffectKind::GyroGSensitivity => d.g_sensitivity(),
        EffectKind::ReferenceOffset => d.reference_offset(),
        EffectKind::PositionError => d.position_error(),
        EffectKind::BiasDrift => d.drift(),
        EffectKind::BiasWarmup => d.warmup(),
        EffectKind::TemperatureBias => d.temperature(),
        EffectKind::CorrelatedNoise => d.correlated_noise(),
        EffectKind::Vibration => d.vibration(),
        EffectKind::Quantization => d.quantization(),
    }
    (d.s, d.hidden)
}

/// One trial being drawn: the random stream, what is drawn first for every effect (axes, sign, signal to
/// noise), the scenario and the truth so far.
struct Draw<'a> {
    rng: ChaCha8Rng,
    reference: &'a ReferenceErrors,
    /// The axes drawn, as [`catalogue`] names them ("xz", "e", "gy").
    axes: &'static str,
    sign: f64,
    /// Magnitude in standard errors of the clean session.
    snr: f64,
    s: ScenarioFile,
    hidden: Hidden,
    /// Per-channel effects: a gyro channel, and its axis.
    gyro: bool,
    ax: usize,
    /// White noise per sample of the channel's sensor.
    noise: f64,
}

impl<'a> Draw<'a> {
    fn new(effect: EffectKind, seed: u64, reference: &'a ReferenceErrors) -> Draw<'a> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ effect.name().len() as u64);
        let axes_list = TRIALS.iter().find(|(e, _)| *e == effect).map(|(_, a)| *a).expect("effect in the catalogue");
        let axes = axes_list[rng.random_range(0..axes_list.len())];
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        let snr = rng.random_range(10.0..20.0);
        // Sensor-channel effects: axes "gx".."az".
        let (gyro, ax) = (axes.starts_with('g'), axes.chars().last().map_or(0, axis));
        let sensor = effect.sensor().unwrap_or(if gyro { Sensor::Gyro } else { Sensor::Accel });
        let hidden_axes = if effect.sensor().is_none() { ["x", "y", "z"][ax] } else { axes };
        let hidden = Hidden::new(effect, sensor, hidden_axes);
        let noise = if gyro { reference.noise[0] } else { reference.noise[1] };
        Draw { rng, reference, axes, sign, snr, s: clean_scenario(), hidden, gyro, ax, noise }
    }

    /// The clean session's standard error of the candidate `name`.
    fn se(&self, name: String) -> f64 {
        *self.reference.std_error.get(&name).unwrap_or_else(|| panic!("no reference standard error for {name}"))
    }

    /// `sign * snr` standard errors of the candidate named by the effect and the axes drawn.
    fn linear_value(&self) -> f64 {
        self.sign * self.snr * self.se(format!("{}:{}", self.hidden.effect, self.axes))
    }

    /// The (i, j) of an axis pair ("xz") or axis ("x" = (0, 0)).
    fn pair(&self) -> (usize, usize) {
        (axis(self.axes.as_bytes()[0] as char), axis(self.axes.chars().last().unwrap_or('x')))
    }

    fn accel_term(&mut self) {
        let (i, j) = self.pair();
        self.hidden.value = self.linear_value();
        self.s.accel.misalignment[i][j] = if i == j { 0.0 } else { self.hidden.value };
        if i == j {
            self.s.accel.scale_factor[i] = self.hidden.value;
        }
    }

    fn gyro_term(&mut self) {
        let (i, j) = self.pair();
        self.hidden.value = self.linear_value();
        if i == j {
            self.s.gyro.scale_factor[i] = self.hidden.value;
        } else {
            self.s.gyro.misalignment[i][j] = self.hidden.value;
        }
    }

    fn g_sensitivity(&mut self) {
        let (i, j) = (axis(self.axes.as_bytes()[0] as char), axis(self.axes.as_bytes()[1] as char));
        self.hidden.value = self.linear_value();
        self.s.gyro.g_sensitivity_radps_per_mps2[i][j] = self.hidden.value;
    }

    fn reference_offset(&mut self) {
        self.hidden.value = self.linear_value();
        self.s.schedule.reference_offset_enu_rad[axis(self.axes.as_bytes()[0] as char)] = self.hidden.value;
    }

    fn position_error(&mut self) {
        let positions = self.s.schedule.positions_deg.len() as u32;
        let pos = self.rng.random_range(1..=positions);
        self.hidden.pos = Some(pos);
        self.hidden.value = self.sign * self.snr * self.se(format!("{}:{}:pos{pos}", self.hidden.effect, self.axes));
        let mut enu = [0.0; 3];
        enu[axis(self.axes.as_bytes()[0] as char)] = self.hidden.value;
        self.s.schedule.position_error.push(PositionError { pos, enu_rad: enu });
    }

    /// `[0, 0, 0]` with the hidden value on the channel's axis.
    fn on_axis(&self) -> [f64; 3] {
        let mut v = [0.0; 3];
        v[self.ax] = self.hidden.value;
        v
    }

    fn drift(&mut self) {
        let name = format!("{}:{} ({})", self.hidden.effect, self.hidden.axes, self.hidden.sensor);
        self.hidden.value = self.sign * self.snr * self.se(name);
        let v = self.on_axis();
        if self.gyro {
            self.s.gyro.drift_radps_per_s = v;
        } else {
            self.s.accel.drift_mps2_per_s = v;
        }
    }

    fn warmup(&mut self) {
        // Time constants 20..100 s: curved within the session of about 390 s (a longer one is a drift to
        // this session), and long against a block.
        let tau = self.rng.random_range(20.0..100.0);
        // Amplitude: 10..20 times its standard error from the block means (the shape's energy after the
        // constant bias is removed), times 1.5 for the time constant being estimated.
        let shape: Vec<f64> = block_times(&self.s).iter().map(|t| (-t / tau).exp()).collect();
        self.hidden.value = self.sign * self.snr * 1.5 * block_noise(&self.s, self.noise) / centred_norm(&shape);
        self.hidden.tau_s = Some(tau);
        let w = Some(WarmupSpec { amplitude: self.on_axis(), tau_s: tau });
        if self.gyro {
            self.s.gyro.warmup = w;
        } else {
            self.s.accel.warmup = w;
        }
    }

    fn temperature(&mut self) {
        // The sensor warms from 20 to 35 deg C with a 200 s time constant; the coefficient is 10..20 times
        // its standard error from the block means.
        let t = TemperatureSpec { start_c: 20.0, end_c: 35.0, tau_s: 200.0, reference_c: 20.0 };
        let shape: Vec<f64> = block_times(&self.s).iter().map(|&x| t.at(x)).collect();
        self.hidden.value = self.sign * self.snr * block_noise(&self.s, self.noise) / centred_norm(&shape);
        self.hidden.tau_s = Some(200.0);
        self.s.temperature = Some(t);
        let v = self.on_axis();
        if self.gyro {
            self.s.gyro.temperature_coefficient_radps_per_k = v;
        } else {
            self.s.accel.temperature_coefficient_mps2_per_k = v;
        }
    }

    fn correlated_noise(&mut self) {
        // Gauss-Markov of 0.2..2 s time constant and 1..3 times the white noise per sample.
        let tau = self.rng.random_range(0.2..2.0);
        self.hidden.value = self.rng.random_range(1.0..3.0) * self.noise;
        self.hidden.tau_s = Some(tau);
        let gm = Some(GaussMarkovSpec { sigma: self.on_axis(), tau_s: tau });
        if self.gyro {
            self.s.gyro.bias_instability = gm;
        } else {
            self.s.accel.bias_instability = gm;
        }
    }

    fn vibration(&mut self) {
        // 0.3..30 Hz, amplitude 10..20 standard errors of a sinusoid's amplitude in white noise.
        let f = self.rng.random_range(0.3..30.0);
        let samples = 6.0 * self.s.schedule.dwell_s * self.s.schedule.rate_hz;
        self.hidden.value = self.snr * self.noise * (2.0 / samples).sqrt();
        self.hidden.frequency_hz = Some(f);
        let vib = Some(VibrationSpec { amplitude: self.on_axis(), frequency_hz: f });
        if self.gyro {
            self.s.gyro.vibration = vib;
        } else {
            self.s.accel.vibration = vib;
        }
    }

    fn quantization(&mut self) {
        // Output step 0.3..3 times the white noise per sample.
        self.hidden.value = self.rng.random_range(0.3..3.0) * self.noise;
        let v = self.on_axis();
        if self.gyro {
            self.s.gyro.quantization_radps = v;
        } else {
            self.s.accel.quantization_mps2 = v;
        }
    }
}

/// Mid times of the analysis's blocks (6 s, ten per one-minute dwell) in the scenario's schedule, s.
fn block_times(s: &ScenarioFile) -> Vec<f64> {
    let sch = &s.schedule;
    let blocks = ((sch.dwell_s * sch.rate_hz) as usize / sinscal_host::analysis::BLOCK_SAMPLES).max(4);
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
    let blocks = ((sch.dwell_s * sch.rate_hz) as usize / sinscal_host::analysis::BLOCK_SAMPLES).max(4) as f64;
    per_sample / (sch.dwell_s * sch.rate_hz / blocks).sqrt()
}

/// Euclidean norm of `v` after its mean is removed.
fn centred_norm(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().map(|x| (x - m) * (x - m)).sum::<f64>().sqrt()
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
            && e.sensor == hidden.sensor.name()
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

/// One trial of the effect named `effect` (a name of [`catalogue`]): simulate, analyse, judge.
pub fn trial(effect: &str, seed: u64, reference: &ReferenceErrors) -> Outcome {
    let effect: EffectKind = effect.parse().unwrap_or_else(|e| panic!("{e}"));
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
