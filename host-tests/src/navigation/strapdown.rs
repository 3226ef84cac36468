//! Static pure-inertial navigation: the check a navigation engineer runs to accept a calibration.
//!
//! A strapdown mechanisation in f64 in the ENU frame (this is host-side verification code, not part of
//! the calibration core): attitude `C_b^n` updated by the body rates and the navigation-frame rate
//! `w_in = w_ie + w_en` (Earth rotation and transport rate), velocity by the specific force, Coriolis and
//! gravity, latitude and longitude on the WGS-84 ellipsoid. The vertical channel, unstable in pure inertial
//! navigation, is held at the reference height (as by a perfect altimeter): the check concerns the
//! horizontal channels and the attitude.
//!
//! Beside it, the closed-form solution of the linearised static error model (the psi-free phi-angle
//! equations, constant coefficients at rest), which gives the Schuler oscillation, the level error of
//! nabla/g, the latitude ramp and azimuth growth of the east gyro drift, and the Foucault modulation.

use sinscal::nav::earth::{WGS84_A_M, WGS84_E2};

use crate::io::calibration_model::CalibrationModel;
use crate::model::synth::{cross, mul, mul_vec, rotation, transpose, EARTH_RATE_RADPS, M3};

/// Meridian and prime-vertical radii of curvature of WGS-84 at a latitude, m.
pub fn radii_m(latitude_rad: f64) -> (f64, f64) {
    let s2 = latitude_rad.sin().powi(2);
    let w = 1.0 - WGS84_E2 * s2;
    (WGS84_A_M * (1.0 - WGS84_E2) / w.powf(1.5), WGS84_A_M / w.sqrt())
}

/// Misalignment `phi` (e, n, u), rad, of `c_hat` against `c`: `c_hat = (I - [phi x]) c` (docs/conventions.md#misalignment).
pub fn misalignment_rad(c_hat: &M3, c: &M3) -> [f64; 3] {
    let p = mul(c_hat, &transpose(c));
    [0.5 * (p[1][2] - p[2][1]), 0.5 * (p[2][0] - p[0][2]), 0.5 * (p[0][1] - p[1][0])]
}

/// Re-orthonormalises a direction cosine matrix (one symmetric correction step, C <- C (3I - C^T C) / 2).
fn orthonormalise(c: &M3) -> M3 {
    let ctc = mul(&transpose(c), c);
    let mut k = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            k[i][j] = 0.5 * ((if i == j { 3.0 } else { 0.0 }) - ctc[i][j]);
        }
    }
    mul(c, &k)
}

/// One navigation error sample against the static truth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct NavError {
    /// Time since the start, s.
    pub t_s: f64,
    /// Position error east, north, m.
    pub position_en_m: [f64; 2],
    /// Velocity error east, north, m/s.
    pub velocity_en_mps: [f64; 2],
    /// Attitude error phi (e, n, u), rad (docs/conventions.md#misalignment; phi_u is the heading error).
    pub attitude_n_rad: [f64; 3],
}

impl NavError {
    /// Horizontal position error, m.
    pub fn horizontal_position_m(&self) -> f64 {
        self.position_en_m[0].hypot(self.position_en_m[1])
    }

    /// Horizontal velocity error, m/s.
    pub fn horizontal_velocity_mps(&self) -> f64 {
        self.velocity_en_mps[0].hypot(self.velocity_en_mps[1])
    }
}

/// The navigator for a body at rest at a known place and attitude.
#[derive(Clone, Debug)]
pub struct StaticNavigator {
    c_b_n: M3,
    c_true: M3,
    velocity_n_mps: [f64; 3],
    latitude_rad: f64,
    longitude_rad: f64,
    latitude0_rad: f64,
    height_m: f64,
    gravity_mps2: f64,
    steps: u64,
}

impl StaticNavigator {
    /// Starts at the reference attitude `c_b_n`, zero velocity, at the given place; `gravity_mps2` is the
    /// magnitude used for the vertical specific force.
    pub fn new(c_b_n: M3, latitude_rad: f64, height_m: f64, gravity_mps2: f64) -> StaticNavigator {
        StaticNavigator {
            c_b_n,
            c_true: c_b_n,
            velocity_n_mps: [0.0; 3],
            latitude_rad,
            longitude_rad: 0.0,
            latitude0_rad: latitude_rad,
            height_m,
            gravity_mps2,
            steps: 0,
        }
    }

    /// One step of `dt_s` with the measured body rate (rad/s) and specific force (m/s^2).
    pub fn step(&mut self, rate_b_radps: [f64; 3], force_b_mps2: [f64; 3], dt_s: f64) {
        let (r_m, r_n) = radii_m(self.latitude_rad);
        let (rm_h, rn_h) = (r_m + self.height_m, r_n + self.height_m);
        let [ve, vn, _] = self.velocity_n_mps;
        let (sl, cl) = self.latitude_rad.sin_cos();
        let w_ie = [0.0, EARTH_RATE_RADPS * cl, EARTH_RATE_RADPS * sl];
        let w_en = [-vn / rm_h, ve / rn_h, ve * sl / cl / rn_h];
        let w_in = [0, 1, 2].map(|i| w_ie[i] + w_en[i]);

        // Attitude: C <- R(-w_in dt) C R(w_ib dt) (exact for rates constant over the step).
        let c_old = self.c_b_n;
        let c_new = mul(&mul(&rotation(w_in.map(|x| -x * dt_s)), &c_old), &rotation(rate_b_radps.map(|x| x * dt_s)));
        self.c_b_n = c_new;
        self.steps += 1;
        if self.steps.is_multiple_of(1000) {
            self.c_b_n = orthonormalise(&self.c_b_n);
        }

        // Velocity: specific force through the mean attitude of the step, Coriolis and transport, gravity.
        let f_old = mul_vec(&c_old, force_b_mps2);
        let f_new = mul_vec(&c_new, force_b_mps2);
        let f_n = [0, 1, 2].map(|i| 0.5 * (f_old[i] + f_new[i]));
        let coriolis = cross([0, 1, 2].map(|i| 2.0 * w_ie[i] + w_en[i]), self.velocity_n_mps);
        let g_n = [0.0, 0.0, -self.gravity_mps2];
        let v_old = self.velocity_n_mps;
        let mut v_new = [0, 1, 2].map(|i| v_old[i] + (f_n[i] - coriolis[i] + g_n[i]) * dt_s);
        v_new[2] = 0.0; // vertical channel held at the reference height
        self.velocity_n_mps = v_new;

        // Position: trapezoidal velocity.
        let ve_mid = 0.5 * (v_old[0] + v_new[0]);
        let vn_mid = 0.5 * (v_old[1] + v_new[1]);
        self.latitude_rad += vn_mid / rm_h * dt_s;
        self.longitude_rad += ve_mid / (rn_h * cl) * dt_s;
    }

    /// The error against the static truth at time `t_s`.
    pub fn error(&self, t_s: f64) -> NavError {
        let (r_m, r_n) = radii_m(self.latitude0_rad);
        NavError {
            t_s,
            position_en_m: [
                self.longitude_rad * (r_n + self.height_m) * self.latitude0_rad.cos(),
                (self.latitude_rad - self.latitude0_rad) * (r_m + self.height_m),
            ],
            velocity_en_mps: [self.velocity_n_mps[0], self.velocity_n_mps[1]],
            attitude_n_rad: misalignment_rad(&self.c_b_n, &self.c_true),
        }
    }
}

/// Summary of one navigation run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct RunSummary {
    /// Which run ("uncompensated", "calibrated", ...).
    pub name: String,
    /// Gyro bias subtracted, body frame, rad/s.
    pub gyro_bias_removed_radps: [f64; 3],
    /// Accelerometer bias subtracted, body frame, m/s^2.
    pub accel_bias_removed_mps2: [f64; 3],
    /// The terms of the sensor model the run compensates (`gyro_bias`, `accel_scale_factor`, ...).
    pub terms_applied: Vec<&'static str>,
    /// Largest horizontal position error, m.
    pub max_horizontal_position_error_m: f64,
    /// Horizontal position error at the end, m.
    pub final_horizontal_position_error_m: f64,
    /// Largest horizontal velocity error, m/s.
    pub max_horizontal_velocity_error_mps: f64,
    /// Horizontal velocity error at the end, m/s.
    pub final_horizontal_velocity_error_mps: f64,
    /// Largest |heading error| (phi_u), rad.
    pub max_heading_error_rad: f64,
    /// Heading error at the end, rad.
    pub final_heading_error_rad: f64,
}

/// One run: its name, the sensor model it compensates every sample with, and its error history.
#[derive(Clone, Debug)]
pub struct Run {
    /// Name.
    pub name: String,
    /// The compensation (docs/conventions.md#sensor-model): `f = T_a^-1 (f_meas - b_a)`,
    /// `w = T_g^-1 (w_meas - b_g - G f)`.
    pub compensation: CalibrationModel,
    /// Errors at the recording interval.
    pub history: Vec<NavError>,
}

impl Run {
    /// A run that removes biases only (zero biases: the uncompensated run).
    pub fn with_biases(name: &str, gyro_bias_radps: [f64; 3], accel_bias_mps2: [f64; 3]) -> Run {
        Run {
            name: name.to_string(),
            compensation: CalibrationModel::biases_only(name, gyro_bias_radps, accel_bias_mps2),
            history: Vec::new(),
        }
    }

    /// The summary figures.
    pub fn summary(&self) -> RunSummary {
        let last = self.history.last().copied().unwrap_or(NavError {
            t_s: 0.0,
            position_en_m: [0.0; 2],
            velocity_en_mps: [0.0; 2],
            attitude_n_rad: [0.0; 3],
        });
        let max = |f: &dyn Fn(&NavError) -> f64| self.history.iter().map(f).fold(0.0, f64::max);
        RunSummary {
            name: self.name.clone(),
            gyro_bias_removed_radps: self.compensation.gyro_bias_radps,
            accel_bias_removed_mps2: self.compensation.accel_bias_mps2,
            terms_applied: self.compensation.terms.iter().map(|t| t.name()).collect(),
            max_horizontal_position_error_m: max(&|e| e.horizontal_position_m()),
            final_horizontal_position_error_m: last.horizontal_position_m(),
            max_horizontal_velocity_error_mps: max(&|e| e.horizontal_velocity_mps()),
            final_horizontal_velocity_error_mps: last.horizontal_velocity_mps(),
            max_heading_error_rad: max(&|e| e.attitude_n_rad[2].abs()),
            final_heading_error_rad: last.attitude_n_rad[2],
        }
    }
}

/// Where and how the static run happens.
#[derive(Clone, Copy, Debug)]
pub struct StaticSetup {
    /// Attitude of the body (and initial attitude of the navigator).
    pub c_b_n: M3,
    /// Latitude, rad.
    pub latitude_rad: f64,
    /// Height, m.
    pub height_m: f64,
    /// Gravity magnitude, m/s^2.
    pub gravity_mps2: f64,
    /// Sample interval, s.
    pub dt_s: f64,
    /// Errors are recorded every this many samples.
    pub record_every: usize,
}

/// Navigates several runs in lockstep over one stream of samples: each run compensates with its own model.
/// `next_sample(k)` gives sample k as (rate_b_radps, force_b_mps2); `progress(done, total)` is called
/// at every recorded point.
pub fn navigate_runs(
    setup: &StaticSetup,
    samples: usize,
    mut next_sample: impl FnMut(usize) -> ([f64; 3], [f64; 3]),
    runs: &mut [Run],
    mut progress: impl FnMut(usize, usize),
) {
    let mut lockstep = Lockstep::new(setup, runs, samples);
    for k in 0..samples {
        let (w, f) = next_sample(k);
        lockstep.step(runs, w, f, &mut progress);
    }
}

/// Runs navigated in lockstep, one sample at a time ([`navigate_runs`] gives the samples by index; a reader
/// that keeps no rows gives them as they come).
pub struct Lockstep<'s> {
    setup: &'s StaticSetup,
    navs: Vec<StaticNavigator>,
    samples: usize,
    done: usize,
}

impl<'s> Lockstep<'s> {
    /// The runs at rest at the start of `samples` samples (their histories restart).
    pub fn new(setup: &'s StaticSetup, runs: &mut [Run], samples: usize) -> Lockstep<'s> {
        let navs: Vec<StaticNavigator> = runs
            .iter()
            .map(|_| StaticNavigator::new(setup.c_b_n, setup.latitude_rad, setup.height_m, setup.gravity_mps2))
            .collect();
        for (run, nav) in runs.iter_mut().zip(&navs) {
            run.history.clear();
            run.history.push(nav.error(0.0));
        }
        Lockstep { setup, navs, samples, done: 0 }
    }

    /// The next sample, (rate_b_radps, force_b_mps2), through every run.
    pub fn step(&mut self, runs: &mut [Run], w: [f64; 3], f: [f64; 3], progress: &mut impl FnMut(usize, usize)) {
        let (setup, k, samples) = (self.setup, self.done, self.samples);
        for (run, nav) in runs.iter_mut().zip(self.navs.iter_mut()) {
            let fc = run.compensation.compensate_force(f);
            let wc = run.compensation.compensate_rate(w, fc);
            nav.step(wc, fc, setup.dt_s);
            if (k + 1) % setup.record_every == 0 || k + 1 == samples {
                run.history.push(nav.error((k + 1) as f64 * setup.dt_s));
            }
        }
        if (k + 1) % setup.record_every == 0 {
            progress(k + 1, samples);
        }
        self.done += 1;
    }
}

/// Closed-form solution of the linearised static error model.
///
/// States `x = [phi_e, phi_n, phi_u, dv_e, dv_n, dp_e, dp_n]` (rad, m/s, m) with constant inputs
/// `eps_n = C_b^n eps_b` and `nabla_n = C_b^n nabla_b`; at rest, height held, with `Omega_N = W cos L`,
/// `Omega_U = W sin L`, `R_M`, `R_N` the radii (derived from `C_hat = (I - [phi x]) C`):
///     phi_e' =  Omega_U phi_n - Omega_N phi_u - dv_n / R_M                    - eps_e
///     phi_n' = -Omega_U phi_e - Omega_U dp_n / R_M + dv_e / R_N               - eps_n
///     phi_u' =  Omega_N phi_e + Omega_N dp_n / R_M + tan L dv_e / R_N         - eps_u
///     dv_e'  = -g phi_n + 2 Omega_U dv_n + nabla_e
///     dv_n'  =  g phi_e - 2 Omega_U dv_e + nabla_n
///     dp_e'  =  dv_e,   dp_n' = dv_n
/// The solution is `x(t) = expm(A t)` of the system augmented with the constant inputs, evaluated at the
/// times given (the matrix exponential by scaling and squaring of its Taylor series, f64).
pub fn linear_error_model(
    latitude_rad: f64,
    height_m: f64,
    gravity_mps2: f64,
    gyro_bias_n_radps: [f64; 3],
    accel_bias_n_mps2: [f64; 3],
    step_s: f64,
    steps: usize,
) -> Vec<NavError> {
    const N: usize = 13;
    let (r_m, r_n) = radii_m(latitude_rad);
    let (rm, rn) = (r_m + height_m, r_n + height_m);
    let (sl, cl) = latitude_rad.sin_cos();
    let (on, ou) = (EARTH_RATE_RADPS * cl, EARTH_RATE_RADPS * sl);
    let g = gravity_mps2;
    let mut a = [[0.0f64; N]; N];
    // phi_e
    a[0][1] = ou;
    a[0][2] = -on;
    a[0][4] = -1.0 / rm;
    a[0][7] = -1.0;
    // phi_n
    a[1][0] = -ou;
    a[1][6] = -ou / rm;
    a[1][3] = 1.0 / rn;
    a[1][8] = -1.0;
    // phi_u
    a[2][0] = on;
    a[2][6] = on / rm;
    a[2][3] = sl / cl / rn;
    a[2][9] = -1.0;
    // dv_e, dv_n
    a[3][1] = -g;
    a[3][4] = 2.0 * ou;
    a[3][10] = 1.0;
    a[4][0] = g;
    a[4][3] = -2.0 * ou;
    a[4][11] = 1.0;
    // dp_e, dp_n
    a[5][3] = 1.0;
    a[6][4] = 1.0;
    // states 7..12: eps_n (e, n, u), nabla_n (e, n, u), constant; nabla_u (12) has no effect at height held.

    let phi = expm(&a, step_s);
    let mut x = [0.0f64; N];
    x[7..10].copy_from_slice(&gyro_bias_n_radps);
    x[10..13].copy_from_slice(&accel_bias_n_mps2);
    let mut out = Vec::with_capacity(steps + 1);
    for k in 0..=steps {
        out.push(NavError {
            t_s: k as f64 * step_s,
            position_en_m: [x[5], x[6]],
            velocity_en_mps: [x[3], x[4]],
            attitude_n_rad: [x[0], x[1], x[2]],
        });
        let mut next = [0.0; N];
        for i in 0..N {
            next[i] = (0..N).map(|j| phi[i][j] * x[j]).sum();
        }
        x = next;
    }
    out
}

/// `expm(A t)` by scaling and squaring of the Taylor series (f64).
fn expm<const N: usize>(a: &[[f64; N]; N], t: f64) -> [[f64; N]; N] {
    let norm: f64 = a.iter().map(|row| row.iter().map(|x| (x * t).abs()).sum::<f64>()).fold(0.0, f64::max);
    let squarings = if norm > 0.5 { (norm / 0.5).log2().ceil() as u32 } else { 0 };
    let scale = t / 2f64.powi(squarings as i32);
    let mut result = [[0.0; N]; N];
    let mut term = [[0.0; N]; N];
    for i in 0..N {
        result[i][i] = 1.0;
        term[i][i] = 1.0;
    }
    for k in 1..30 {
        let mut next = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                next[i][j] = (0..N).map(|m| term[i][m] * a[m][j] * scale).sum::<f64>() / k as f64;
            }
        }
        term = next;
        for i in 0..N {
            for j in 0..N {
                result[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        let mut sq = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                sq[i][j] = (0..N).map(|m| result[i][m] * result[m][j]).sum();
            }
        }
        result = sq;
    }
    result
}

/// Schuler period at a latitude and height, s: `2 pi sqrt(R / g)` with `R = sqrt(R_M R_N) + h`.
pub fn schuler_period_s(latitude_rad: f64, height_m: f64, gravity_mps2: f64) -> f64 {
    let (r_m, r_n) = radii_m(latitude_rad);
    2.0 * std::f64::consts::PI * (((r_m * r_n).sqrt() + height_m) / gravity_mps2).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expm_of_a_rotation_generator_is_the_rotation() {
        let a = [[0.0, -1.0], [1.0, 0.0]];
        let e = expm(&a, 2.0);
        assert!((e[0][0] - 2f64.cos()).abs() < 1e-13 && (e[1][0] - 2f64.sin()).abs() < 1e-13);
    }

    #[test]
    fn radii_at_equator_and_pole() {
        let (m, n) = radii_m(0.0);
        assert!((n - WGS84_A_M).abs() < 1e-6 && (m - 6_335_439.327).abs() < 1e-2);
        let (m, n) = radii_m(std::f64::consts::FRAC_PI_2);
        assert!((m - n).abs() < 1e-6);
    }
}
