//! SIMULATION of a turntable session from a scenario file (TOML): `sinscal simulate SCENARIO --seed N
//! --out RECORDING`. Every effect of the catalogue of docs/formats.md#effect-catalogue can be switched on.
//!
//! The model: the static sensor model of [`crate::model::sensor`] (docs/conventions.md#sensor-model,
//! `w_meas = T_g w + b_g + G f`, `f_meas = T_a f + b_a`) plus, per sensor, a time-varying bias `b(t)` and
//! white noise `n`, with the time-varying bias `b(t)`: drift `d t`, plus warm-up `A exp(-t/tau)`, plus temperature
//! `k (T(t) - T_ref)`, plus vibration `A sin(2 pi f t + phase)`, plus Gauss-Markov `x(t)`, plus rate random
//! walk; `n` is white noise; then the output is quantised.
//!
//! **Discretisation.** Every sample is the *average over its interval* `[t_k, t_k + dt)`, as an integrating
//! IMU delivers it, and each noise is discretised so that its Allan deviation is right at any sample rate:
//! - white noise of density `N` (rad/s/sqrt(Hz) = rad/sqrt(s); m/s/sqrt(s) for accelerometers): the
//!   interval average has standard deviation `N / sqrt(dt)`, so `ADEV(tau) = N / sqrt(tau)`;
//! - rate random walk `K` (rad/s/sqrt(s)): the walk `b` moves by `K sqrt(dt) xi1` over an interval, and the
//!   average over the interval is `b_k + K sqrt(dt) (xi1 / 2 + xi2 / sqrt(12))` with `xi2` independent:
//!   the exact interval average of Brownian motion, so `ADEV(tau) = K sqrt(tau / 3)` at every tau = m dt;
//! - Gauss-Markov of standard deviation `sigma` and correlation time `T`: the exact AR(1) transition
//!   `x_{k+1} = e^{-dt/T} x_k + sigma sqrt(1 - e^{-2 dt/T}) xi` (point values; for `T >> dt` the interval
//!   average differs by O(dt/T));
//! - vibration: the exact interval average of the sinusoid, so a vibration above the Nyquist frequency
//!   aliases as it would in a real sensor;
//! - quantisation with output step `q`: the *integrated* output is quantised, carrying the remainder from
//!   sample to sample (pulse output, as a ring-laser gyro or a counter delivers it); every output is a
//!   multiple of `q` and no increment is lost, giving the quantisation noise `ADEV(tau) = sqrt(3) Q / tau`
//!   with `Q = q dt / sqrt(12)` in the angle domain.
//!
//! Peers (gnss-ins-sim, the PSINS toolbox's error simulation) also draw white noise per sample from the
//! density and the sample rate; the interval average of the random walk and the quantisation of the
//! integrated output are what this simulator adds. They were not run side by side here.
//!
//! **Moves.** Between dwells the table turns from one attitude to the next at constant angle rates of its
//! pitch, roll and heading axes (`move_s`), then stays still for `settle_s`; those rows have `pos = 0`. The
//! body rate of each interval is the rotation vector of its attitude change, divided by dt.

use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::Deserialize;

use crate::io::dwell_tally::angle_step_deg;
use crate::io::error::InputError;
use crate::io::recording::{Header, Recording, Row, SimulationTruth};
use crate::model::sensor::Triad;
use crate::model::synth::{
    c_b_n, earth_rate_n_radps, mul, mul_t_vec, rotation, rotation_vector, transpose, M3, TABLE1_DEG,
};

/// A scenario file.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ScenarioFile {
    /// Where the table stands.
    pub site: SiteSpec,
    /// The turntable schedule and its errors.
    #[serde(default)]
    pub schedule: ScheduleSpec,
    /// Gyro errors.
    #[serde(default)]
    pub gyro: GyroSpec,
    /// Accelerometer errors.
    #[serde(default)]
    pub accel: AccelSpec,
    /// Sensor temperature profile (omitted: no temperature column, no temperature effect).
    pub temperature: Option<TemperatureSpec>,
}

/// The site.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SiteSpec {
    /// Geodetic latitude, degrees north.
    pub latitude_deg: f64,
    /// Height above the ellipsoid, m.
    #[serde(default)]
    pub height_m: f64,
    /// Local gravity, m/s^2; omitted: WGS-84 normal gravity at the latitude and height.
    pub gravity_mps2: Option<f64>,
}

/// The schedule: positions, times, and the table's own errors.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ScheduleSpec {
    /// Output rate, Hz.
    pub rate_hz: f64,
    /// Dwell length, s.
    pub dwell_s: f64,
    /// Table motion from one position to the next, s.
    pub move_s: f64,
    /// Stillness after a move (and before the first dwell) that is not part of a dwell, s.
    pub settle_s: f64,
    /// Positions (pitch, roll, heading), degrees; default the paper's Table 1.
    pub positions_deg: Vec<[f64; 3]>,
    /// Constant error of the table's reference, `phi0` (e, n, u), rad: the reported attitude is the true one
    /// seen through `C_ref = (I + [phi0 x]) C_true` to first order.
    pub reference_offset_enu_rad: [f64; 3],
    /// Attitude errors of single positions (in addition to the constant offset).
    pub position_error: Vec<PositionError>,
}

impl Default for ScheduleSpec {
    fn default() -> Self {
        ScheduleSpec {
            rate_hz: 100.0,
            dwell_s: 60.0,
            move_s: 5.0,
            settle_s: 1.0,
            positions_deg: TABLE1_DEG.to_vec(),
            reference_offset_enu_rad: [0.0; 3],
            position_error: Vec::new(),
        }
    }
}

/// The table's attitude error at one position.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PositionError {
    /// Position label (1-based).
    pub pos: u32,
    /// Error (e, n, u), rad, same sense as the reference offset.
    pub enu_rad: [f64; 3],
}

/// A first-order Gauss-Markov process per axis.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GaussMarkovSpec {
    /// Standard deviation per axis (rad/s for gyros, m/s^2 for accelerometers).
    #[serde(alias = "sigma_radps", alias = "sigma_mps2")]
    pub sigma: [f64; 3],
    /// Correlation time, s.
    pub tau_s: f64,
}

/// A sinusoid per axis (vibration or sway).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VibrationSpec {
    /// Amplitude per axis (rad/s for gyros, m/s^2 for accelerometers).
    #[serde(alias = "amplitude_radps", alias = "amplitude_mps2")]
    pub amplitude: [f64; 3],
    /// Frequency, Hz.
    pub frequency_hz: f64,
}

/// An exponential warm-up `A exp(-t / tau)` per axis.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WarmupSpec {
    /// Amplitude per axis at t = 0 (rad/s for gyros, m/s^2 for accelerometers).
    #[serde(alias = "amplitude_radps", alias = "amplitude_mps2")]
    pub amplitude: [f64; 3],
    /// Time constant, s.
    pub tau_s: f64,
}

/// Noise larger at the start (docs/analysis.md#noise-warm-up): white noise of `excess` per sample added to
/// every sample before `settled_s`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NoiseWarmupSpec {
    /// Standard deviation per sample added per axis (rad/s for gyros, m/s^2 for accelerometers).
    #[serde(alias = "excess_radps", alias = "excess_mps2")]
    pub excess: [f64; 3],
    /// Time after the session's start at which the noise has settled, s.
    pub settled_s: f64,
}

/// Gyro errors (rad, s).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct GyroSpec {
    /// Constant bias, body frame, rad/s.
    pub bias_radps: [f64; 3],
    /// Relative scale-factor errors (diagonal of S_g), 1.
    pub scale_factor: [f64; 3],
    /// Misalignment M_g (row i, column j: sensitivity of axis i to rate about j), 1; diagonal must be 0.
    pub misalignment: M3,
    /// g-sensitivity G (row i, column j: rate error of axis i per specific force along j), (rad/s)/(m/s^2).
    pub g_sensitivity_radps_per_mps2: M3,
    /// Angle random walk (white rate noise density), rad/s/sqrt(Hz) = rad/sqrt(s).
    pub angle_random_walk_rad_per_sqrt_s: f64,
    /// Rate random walk, rad/s/sqrt(s).
    pub rate_random_walk_radps_per_sqrt_s: f64,
    /// Bias instability as a Gauss-Markov process (`sigma_radps`, `tau_s`).
    pub bias_instability: Option<GaussMarkovSpec>,
    /// Output step, rad/s (0 = not quantised).
    pub quantization_radps: [f64; 3],
    /// Vibration or sway seen by the gyros (`amplitude_radps`, `frequency_hz`).
    pub vibration: Option<VibrationSpec>,
    /// Linear bias drift, rad/s per s.
    pub drift_radps_per_s: [f64; 3],
    /// Warm-up transient (`amplitude_radps`, `tau_s`).
    pub warmup: Option<WarmupSpec>,
    /// Noise larger at the start (`excess_radps`, `settled_s`).
    pub noise_warmup: Option<NoiseWarmupSpec>,
    /// Bias per kelvin of sensor temperature above the reference, (rad/s)/K.
    pub temperature_coefficient_radps_per_k: [f64; 3],
}

/// Accelerometer errors (m, s).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct AccelSpec {
    /// Constant bias, body frame, m/s^2.
    pub bias_mps2: [f64; 3],
    /// Relative scale-factor errors (diagonal of S_a), 1.
    pub scale_factor: [f64; 3],
    /// Misalignment M_a (row i, column j: sensitivity of axis i to force along j), 1; diagonal must be 0.
    pub misalignment: M3,
    /// Second-order nonlinearity K2 per axis: axis i reads `K2_i f_i^2` more, 1/(m/s^2).
    pub nonlinearity_per_mps2: [f64; 3],
    /// Velocity random walk (white force noise density), m/s^2/sqrt(Hz) = m/s/sqrt(s).
    pub velocity_random_walk_mps_per_sqrt_s: f64,
    /// Acceleration random walk, m/s^2/sqrt(s).
    pub acceleration_random_walk_mps2_per_sqrt_s: f64,
    /// Bias instability as a Gauss-Markov process (`sigma_mps2`, `tau_s`).
    pub bias_instability: Option<GaussMarkovSpec>,
    /// Output step, m/s^2 (0 = not quantised).
    pub quantization_mps2: [f64; 3],
    /// Vibration or sway seen by the accelerometers (`amplitude_mps2`, `frequency_hz`).
    pub vibration: Option<VibrationSpec>,
    /// Linear bias drift, m/s^2 per s.
    pub drift_mps2_per_s: [f64; 3],
    /// Warm-up transient (`amplitude_mps2`, `tau_s`).
    pub warmup: Option<WarmupSpec>,
    /// Noise larger at the start (`excess_mps2`, `settled_s`).
    pub noise_warmup: Option<NoiseWarmupSpec>,
    /// Bias per kelvin of sensor temperature above the reference, (m/s^2)/K.
    pub temperature_coefficient_mps2_per_k: [f64; 3],
}

/// Sensor temperature `T(t) = end + (start - end) exp(-t / tau)` (tau = 0: constant `start`).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TemperatureSpec {
    /// Temperature at t = 0, deg C.
    pub start_c: f64,
    /// Temperature approached, deg C.
    pub end_c: f64,
    /// Time constant, s.
    #[serde(default)]
    pub tau_s: f64,
    /// Temperature at which the constant biases hold, deg C.
    pub reference_c: f64,
}

impl TemperatureSpec {
    /// Temperature at `t_s`, deg C.
    pub fn at(&self, t_s: f64) -> f64 {
        if self.tau_s > 0.0 {
            self.end_c + (self.start_c - self.end_c) * (-t_s / self.tau_s).exp()
        } else {
            self.start_c
        }
    }
}

/// The error model of one sensor triad in SI, whatever the sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct TriadModel {
    /// The static terms: constant bias, `T = I + S + M`, and the cross-coupling to the other sensor's true
    /// quantity (the gyros' g-sensitivity; zero for accelerometers).
    pub statics: Triad,
    /// White noise density, unit * sqrt(s).
    pub white_density: f64,
    /// Random walk of the bias, unit / sqrt(s).
    pub random_walk: f64,
    /// Gauss-Markov sigma per axis and correlation time, s.
    pub gauss_markov: Option<([f64; 3], f64)>,
    /// Output step per axis (0 = off).
    pub quantization: [f64; 3],
    /// Vibration amplitude per axis and frequency, Hz.
    pub vibration: Option<([f64; 3], f64)>,
    /// Drift per second.
    pub drift_per_s: [f64; 3],
    /// Warm-up amplitude per axis and time constant, s.
    pub warmup: Option<([f64; 3], f64)>,
    /// Noise warm-up: (standard deviation per sample added, s until it settles).
    pub noise_warmup: Option<([f64; 3], f64)>,
    /// Bias per kelvin.
    pub temperature_coefficient_per_k: [f64; 3],
    /// Second-order nonlinearity per axis: axis i reads `K2_i q_i^2` more (`q` its own interval-averaged true
    /// quantity), 1/unit.
    pub nonlinearity_per_unit: [f64; 3],
}

/// Most rows a scenario may ask for (about 1 GB in memory; 2.8 hours at 1 kHz).
pub const MAX_SIMULATED_ROWS: f64 = 1e7;

/// Smallest quantisation step, SI: a finer step divides samples into more steps than f64 counts exactly.
pub const MIN_QUANTIZATION_STEP_SI: f64 = 1e-15;

/// The dotted key of the first number in `value` that is not finite (`inf`, `nan`), if any.
fn non_finite(key: &str, value: &toml::Value) -> Option<String> {
    match value {
        toml::Value::Float(x) if !x.is_finite() => Some(key.to_string()),
        toml::Value::Array(items) => items.iter().enumerate().find_map(|(i, v)| non_finite(&format!("{key}[{i}]"), v)),
        toml::Value::Table(t) => t.iter().find_map(|(k, v)| {
            let key = if key.is_empty() { k.clone() } else { format!("{key}.{k}") };
            non_finite(&key, v)
        }),
        _ => None,
    }
}

fn check_offdiagonal(m: &M3, what: &str) -> Result<(), String> {
    if (0..3).any(|i| m[i][i] != 0.0) {
        return Err(format!("{what}: the diagonal must be 0 (scale factors go in scale_factor)"));
    }
    Ok(())
}

/// The clean scenario (`host-tests/scenarios/table1-clean.toml`: constant biases and white noise only), the one
/// the hidden-effect trials and the analysis tests start from.
pub const CLEAN_SCENARIO: &str = include_str!("../../scenarios/table1-clean.toml");

/// The clean scenario, parsed.
pub fn clean_scenario() -> ScenarioFile {
    ScenarioFile::parse(CLEAN_SCENARIO, "table1-clean.toml").expect("the built-in clean scenario parses")
}

impl ScenarioFile {
    /// Reads and checks a scenario file.
    pub fn read(path: &Path) -> Result<ScenarioFile, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, e))?;
        ScenarioFile::parse(&text, &path.display().to_string())
    }

    /// Parses and checks the text of a scenario; `source` names it in errors.
    pub fn parse(text: &str, source: &str) -> Result<ScenarioFile, InputError> {
        let scenario: ScenarioFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
            let message = e.message().to_string();
            match line {
                Some(line) => InputError::at(source, line, message),
                None => InputError::file(source, message),
            }
        })?;
        if let Ok(table) = text.parse::<toml::Table>() {
            non_finite("", &toml::Value::Table(table))
                .map_or(Ok(()), |key| Err(InputError::file(source, format!("{key} is not a finite number"))))?;
        }
        scenario.check().map_err(|reason| InputError::file(source, reason))?;
        Ok(scenario)
    }

    fn check(&self) -> Result<(), String> {
        use crate::io::recording::{gravity_ok, latitude_ok, rate_ok, shown, MAX_LATITUDE_DEG, MAX_RATE_HZ};
        let s = &self.schedule;
        // What the recording reader accepts, so that simulate never writes a file it refuses.
        if !latitude_ok(self.site.latitude_deg) {
            return Err(format!(
                "site.latitude_deg {} is not in [-{MAX_LATITUDE_DEG}, {MAX_LATITUDE_DEG}]",
                shown(self.site.latitude_deg)
            ));
        }
        if let Some(g) = self.site.gravity_mps2.filter(|&g| !gravity_ok(g)) {
            return Err(format!("site.gravity_mps2 {} is not a gravity on Earth (9.7..9.9)", shown(g)));
        }
        if !rate_ok(s.rate_hz) {
            return Err(format!("schedule.rate_hz {} is not a rate in (0, {MAX_RATE_HZ}] Hz", shown(s.rate_hz)));
        }
        let rows = s.positions_deg.len() as f64 * (s.dwell_s + s.settle_s + s.move_s) * s.rate_hz;
        if rows > MAX_SIMULATED_ROWS {
            return Err(format!(
                "the schedule is {} rows: at most {MAX_SIMULATED_ROWS:e} are simulated (shorter dwells or a lower \
                 rate)",
                shown(rows)
            ));
        }
        if s.dwell_s.is_nan() || s.dwell_s * s.rate_hz < 10.0 {
            return Err(format!("schedule.dwell_s {} s gives fewer than 10 samples", s.dwell_s));
        }
        if s.move_s.is_nan() || s.settle_s.is_nan() || s.move_s < 0.0 || s.settle_s < 0.0 {
            return Err("schedule.move_s and settle_s must not be negative".into());
        }
        if s.positions_deg.is_empty() {
            return Err("schedule.positions_deg is empty".into());
        }
        for e in &s.position_error {
            if e.pos == 0 || e.pos as usize > s.positions_deg.len() {
                return Err(format!("schedule.position_error: pos {} is not a position of the schedule", e.pos));
            }
        }
        check_offdiagonal(&self.gyro.misalignment, "gyro.misalignment")?;
        check_offdiagonal(&self.accel.misalignment, "accel.misalignment")?;
        let taus = [
            self.gyro.bias_instability.as_ref().map(|g| g.tau_s),
            self.accel.bias_instability.as_ref().map(|g| g.tau_s),
            self.gyro.warmup.as_ref().map(|w| w.tau_s),
            self.accel.warmup.as_ref().map(|w| w.tau_s),
        ];
        if taus.iter().flatten().any(|&t| t.is_nan() || t <= 0.0) {
            return Err("every tau_s of bias_instability and warmup must be positive".into());
        }
        for (name, w) in [("gyro", &self.gyro.noise_warmup), ("accel", &self.accel.noise_warmup)] {
            if w.as_ref().is_some_and(|w| [w.settled_s].iter().chain(&w.excess).any(|v| v.is_nan() || *v < 0.0)) {
                return Err(format!("{name}.noise_warmup: settled_s and excess must not be negative"));
            }
        }
        let densities = [
            self.gyro.angle_random_walk_rad_per_sqrt_s,
            self.gyro.rate_random_walk_radps_per_sqrt_s,
            self.accel.velocity_random_walk_mps_per_sqrt_s,
            self.accel.acceleration_random_walk_mps2_per_sqrt_s,
        ];
        if densities.iter().any(|&d| d.is_nan() || d < 0.0) {
            return Err("noise densities must not be negative".into());
        }
        if self
            .gyro
            .quantization_radps
            .iter()
            .chain(&self.accel.quantization_mps2)
            .any(|&q| q.is_nan() || q < 0.0 || (q > 0.0 && q < MIN_QUANTIZATION_STEP_SI))
        {
            return Err(format!("quantization steps must be 0 (off) or at least {MIN_QUANTIZATION_STEP_SI:e}"));
        }
        Ok(())
    }

    /// Gravity used: the file's, or WGS-84 normal gravity.
    pub fn gravity_mps2(&self) -> f64 {
        self.site.gravity_mps2.unwrap_or_else(|| {
            sinscal::nav::earth::normal_gravity_mps2(
                (self.site.latitude_deg as f32).to_radians(),
                self.site.height_m as f32,
            ) as f64
        })
    }

    /// The gyro triad in SI.
    pub fn gyro_model(&self) -> TriadModel {
        let g = &self.gyro;
        TriadModel {
            statics: Triad::new(g.bias_radps, g.scale_factor, &g.misalignment, g.g_sensitivity_radps_per_mps2),
            white_density: g.angle_random_walk_rad_per_sqrt_s,
            random_walk: g.rate_random_walk_radps_per_sqrt_s,
            gauss_markov: g.bias_instability.as_ref().map(|b| (b.sigma, b.tau_s)),
            quantization: g.quantization_radps,
            vibration: g.vibration.as_ref().map(|v| (v.amplitude, v.frequency_hz)),
            drift_per_s: g.drift_radps_per_s,
            warmup: g.warmup.as_ref().map(|w| (w.amplitude, w.tau_s)),
            noise_warmup: g.noise_warmup.as_ref().map(|w| (w.excess, w.settled_s)),
            temperature_coefficient_per_k: g.temperature_coefficient_radps_per_k,
            nonlinearity_per_unit: [0.0; 3],
        }
    }

    /// The accelerometer triad in SI.
    pub fn accel_model(&self) -> TriadModel {
        let a = &self.accel;
        TriadModel {
            statics: Triad::new(a.bias_mps2, a.scale_factor, &a.misalignment, [[0.0; 3]; 3]),
            white_density: a.velocity_random_walk_mps_per_sqrt_s,
            random_walk: a.acceleration_random_walk_mps2_per_sqrt_s,
            gauss_markov: a.bias_instability.as_ref().map(|b| (b.sigma, b.tau_s)),
            quantization: a.quantization_mps2,
            vibration: a.vibration.as_ref().map(|v| (v.amplitude, v.frequency_hz)),
            drift_per_s: a.drift_mps2_per_s,
            warmup: a.warmup.as_ref().map(|w| (w.amplitude, w.tau_s)),
            noise_warmup: a.noise_warmup.as_ref().map(|w| (w.excess, w.settled_s)),
            temperature_coefficient_per_k: a.temperature_coefficient_mps2_per_k,
            nonlinearity_per_unit: a.nonlinearity_per_mps2,
        }
    }
}

/// The running state of one triad's random processes.
struct TriadState {
    model: TriadModel,
    /// One generator per process and axis family, so that switching one effect on does not change the
    /// random numbers of the others.
    white: ChaCha8Rng,
    walk: ChaCha8Rng,
    markov: ChaCha8Rng,
    noise_warmup: ChaCha8Rng,
    walk_b: [f64; 3],
    markov_x: [f64; 3],
    vibration_phase: [f64; 3],
    /// Integrated output not yet delivered by the quantiser, in output steps * samples.
    quantizer_carry: [f64; 3],
}

/// The seeded random stream `stream` of `seed` (ChaCha8), shared by the simulations.
pub(crate) fn rng(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream(stream);
    r
}

/// A standard normal draw.
pub fn normal(r: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(r)
}

impl TriadState {
    fn new(model: TriadModel, seed: u64, base_stream: u64) -> TriadState {
        let mut phase_rng = rng(seed, base_stream + 3);
        let mut markov = rng(seed, base_stream + 2);
        // The Gauss-Markov process starts in its stationary distribution.
        let markov_x = match model.gauss_markov {
            Some((sigma, _)) => [0, 1, 2].map(|i| sigma[i] * normal(&mut markov)),
            None => [0.0; 3],
        };
        TriadState {
            vibration_phase: [0, 1, 2].map(|_| rand::Rng::random::<f64>(&mut phase_rng) * std::f64::consts::TAU),
            model,
            white: rng(seed, base_stream),
            walk: rng(seed, base_stream + 1),
            markov,
            noise_warmup: rng(seed, base_stream + 4),
            walk_b: [0.0; 3],
            markov_x,
            quantizer_carry: [0.0; 3],
        }
    }

    /// The output over `[t0, t0 + dt)` for the interval-averaged true quantity `own` and the other
    /// sensor's `other`, at sensor temperature `temp_c` relative to the reference.
    fn sample(&mut self, t0: f64, dt: f64, own: [f64; 3], other: [f64; 3], delta_temp_k: f64) -> [f64; 3] {
        let m = &self.model;
        let mut out = [0.0; 3];
        let t_mid = t0 + 0.5 * dt;
        for i in 0..3 {
            let mut y = m.statics.measure_axis(i, own, other);
            y += m.nonlinearity_per_unit[i] * own[i] * own[i];
            y += m.drift_per_s[i] * t_mid;
            if let Some((a, tau)) = m.warmup {
                // Exact interval average of A exp(-t/tau).
                y += a[i] * tau / dt * ((-t0 / tau).exp() - (-(t0 + dt) / tau).exp());
            }
            y += m.temperature_coefficient_per_k[i] * delta_temp_k;
            if let Some((a, f)) = m.vibration {
                let w = std::f64::consts::TAU * f;
                let p = self.vibration_phase[i];
                y += a[i] / (w * dt) * ((w * t0 + p).cos() - (w * (t0 + dt) + p).cos());
            }
            if m.random_walk > 0.0 {
                let step = m.random_walk * dt.sqrt();
                let (xi1, xi2) = (normal(&mut self.walk), normal(&mut self.walk));
                y += self.walk_b[i] + step * (0.5 * xi1 + xi2 / 12f64.sqrt());
                self.walk_b[i] += step * xi1;
            }
            if let Some((sigma, tau)) = m.gauss_markov {
                y += self.markov_x[i];
                let phi = (-dt / tau).exp();
                self.markov_x[i] =
                    phi * self.markov_x[i] + sigma[i] * (1.0 - phi * phi).sqrt() * normal(&mut self.markov);
            }
            if m.white_density > 0.0 {
                y += m.white_density / dt.sqrt() * normal(&mut self.white);
            }
            if let Some((excess, _)) = m.noise_warmup.filter(|&(_, settled_s)| t0 < settled_s) {
                y += excess[i] * normal(&mut self.noise_warmup);
            }
            out[i] = y;
        }
        for i in 0..3 {
            let q = m.quantization[i];
            if q > 0.0 {
                let total = self.quantizer_carry[i] + out[i] / q;
                let steps = total.round();
                self.quantizer_carry[i] = total - steps;
                out[i] = steps * q;
            }
        }
        out
    }
}

/// The true body rate and specific force of the interval from attitude `c0` to `c1` (`C_b^n`) over `dt`: the
/// rotation vector of `C0^T C1` over dt plus the Earth rate at mid-interval, and the force at mid-interval.
fn interval_truth(c0: &M3, c1: &M3, dt: f64, w_ie_n: [f64; 3], f_n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let relative = mul(&transpose(c0), c1);
    let turn = rotation_vector(&relative);
    let c_mid = mul(c0, &rotation(turn.map(|x| 0.5 * x)));
    let earth_b = mul_t_vec(&c_mid, w_ie_n);
    ([0, 1, 2].map(|i| turn[i] / dt + earth_b[i]), mul_t_vec(&c_mid, f_n))
}

/// One sample boundary of a simulated session: reported attitude (deg), pos label of the interval that starts
/// there, and the table's attitude error (e, n, u; rad) there.
type Boundary = ([f64; 3], u32, [f64; 3]);

/// The table's attitude error (e, n, u) at position index `k`: the constant offset plus that position's own.
fn table_error_at(s: &ScheduleSpec, k: usize) -> [f64; 3] {
    let mut err = s.reference_offset_enu_rad;
    for e in s.position_error.iter().filter(|e| e.pos as usize == k + 1) {
        for i in 0..3 {
            err[i] += e.enu_rad[i];
        }
    }
    err
}

/// One entry per sample boundary of the schedule (moves, settles and dwells in turn), the table's error
/// interpolated during moves so that it never jumps, and a final boundary closing the last interval.
fn schedule_boundaries(s: &ScheduleSpec) -> Vec<Boundary> {
    let samples = |secs: f64| (secs * s.rate_hz).round() as usize;
    let mut boundaries: Vec<Boundary> = Vec::new();
    for (k, &p) in s.positions_deg.iter().enumerate() {
        let err = table_error_at(s, k);
        if k > 0 {
            let (from, from_err) = (s.positions_deg[k - 1], table_error_at(s, k - 1));
            let n = samples(s.move_s);
            let steps = [0, 1, 2].map(|i| angle_step_deg(from[i], p[i]));
            for j in 0..n {
                let x = j as f64 / n as f64;
                let att = [0, 1, 2].map(|i| from[i] + x * steps[i]);
                boundaries.push((att, 0, [0, 1, 2].map(|i| (1.0 - x) * from_err[i] + x * err[i])));
            }
        }
        for _ in 0..samples(s.settle_s) {
            boundaries.push((p, 0, err));
        }
        for _ in 0..samples(s.dwell_s) {
            boundaries.push((p, k as u32 + 1, err));
        }
    }
    if let Some(&(att, _, err)) = boundaries.last() {
        boundaries.push((att, 0, err));
    }
    boundaries
}

/// The true attitude `C_b^n` at a boundary: the reported attitude turned by the table's error.
fn true_attitude((att, _, err): Boundary) -> M3 {
    mul(&rotation(err.map(|x| -x)), &c_b_n(att[0], att[1], att[2]))
}

/// The simulated rows, one per interval between boundaries: the true rate and force through the sensor models.
/// `g` is the site's gravity (m/s^2).
fn simulated_rows(scenario: &ScenarioFile, seed: u64, boundaries: &[Boundary], dt: f64, g: f64) -> Vec<Row> {
    let lat = scenario.site.latitude_deg.to_radians();
    let w_ie_n = earth_rate_n_radps(lat);
    let f_n = [0.0, 0.0, g];
    let mut gyro = TriadState::new(scenario.gyro_model(), seed, 0);
    let mut accel = TriadState::new(scenario.accel_model(), seed, 16);
    let mut rows = Vec::with_capacity(boundaries.len());
    // The attitude at a boundary and an interval's truth are computed where they change (bit-identical).
    let mut c1 = boundaries.first().map_or([[0.0; 3]; 3], |&b| true_attitude(b));
    let mut truth = ([0.0; 3], [0.0; 3]);
    for k in 0..boundaries.len().saturating_sub(1) {
        let (att0, pos, _) = boundaries[k];
        let c0 = c1;
        let moved = boundaries[k + 1] != boundaries[k];
        if moved {
            c1 = true_attitude(boundaries[k + 1]);
        }
        let t0 = k as f64 * dt;
        if k == 0 || moved || boundaries[k] != boundaries[k - 1] {
            truth = interval_truth(&c0, &c1, dt, w_ie_n, f_n);
        }
        let (w_b, f_b) = truth;
        let (temp_c, delta_temp) = match &scenario.temperature {
            Some(t) => {
                let c = t.at(t0 + 0.5 * dt);
                (Some(c), c - t.reference_c)
            }
            None => (None, 0.0),
        };
        let w = gyro.sample(t0, dt, w_b, f_b, delta_temp);
        let f = accel.sample(t0, dt, f_b, w_b, delta_temp);
        rows.push(Row {
            t_s: t0,
            pos,
            pitch_deg: att0[0],
            roll_deg: att0[1],
            heading_deg: Some(att0[2].rem_euclid(360.0)),
            rate_b_radps: w,
            force_b_mps2: f,
            temp_c,
            turn_axis: None,
            line: 0,
        });
    }
    rows
}

/// The simulated session as a recording, reproducible from `seed`.
pub fn simulate(scenario: &ScenarioFile, seed: u64, source: &str) -> Recording {
    let s = &scenario.schedule;
    let dt = 1.0 / s.rate_hz;
    let g = scenario.gravity_mps2();
    let boundaries = schedule_boundaries(s);
    let rows = simulated_rows(scenario, seed, &boundaries, dt, g);
    let truth = SimulationTruth {
        seed,
        gyro_bias_b_radps: scenario.gyro.bias_radps,
        accel_bias_b_mps2: scenario.accel.bias_mps2,
        gyro_noise_radps: scenario.gyro.angle_random_walk_rad_per_sqrt_s / dt.sqrt(),
        accel_noise_mps2: scenario.accel.velocity_random_walk_mps_per_sqrt_s / dt.sqrt(),
        reference_offset_n_rad: s.reference_offset_enu_rad,
    };
    Recording {
        source: source.to_string(),
        header: Header {
            latitude_deg: scenario.site.latitude_deg,
            height_m: scenario.site.height_m,
            rate_hz: Some(s.rate_hz),
            gravity_mps2: Some(g),
            comments: vec![format!("SIMULATION by sinscal simulate (seed {seed}) of {source}, not measured data")],
            truth: Some(truth),
            pose_tolerance_deg: None,
        },
        rows,
        has_gyro: true,
    }
}
