//! SIMULATION: a Monte Carlo of the general estimator with the turntable's moves as observations of the gyro
//! terms, against a Cramer-Rao bound computed here in f64, independently of the core.
//!
//! The scenario ([`scenario`]) is a 14-position schedule (dwells of 20 s, moves of 90 deg in 6 s at constant
//! Euler-angle rates, 1 s of settling, 100 Hz) and a tactical MEMS IMU with every static term of
//! docs/conventions.md#sensor-model of both signs: gyro biases about 10 deg/h, scale factors about 1e-3,
//! misalignments about 5e-4, g-sensitivity about 1e-6 (rad/s)/(m/s^2); accelerometer biases about 1 mg, scale
//! factors and misalignments about 2e-4. The noise is WHITE ONLY: angle random walk 0.15 deg/sqrt(h),
//! velocity random walk 60 ug/sqrt(Hz), nothing else. Each run simulates the session with the simulator of
//! `sinscal simulate` (seed `s + i`), calibrates it as `sinscal calibrate --model full` does (the moves used,
//! docs/method.md#general-estimator) and compares every determined parameter with the truth.
//!
//! **The bound.** The data the estimator uses are the dwell means of the six channels and, per move, the
//! rotation the compensated gyros measure. Under white noise these are independent Gaussian observations, so
//! the Fisher information is the sum of a dwell part and a move part:
//! - dwell part: `sum_d J_d^T S_d^-1 J_d`, with `J_d` the design of the six dwell means at the truth
//!   ([`crate::bound::design`]) and `S_d = diag(sigma_c^2 / N_d)` (white noise of per-sample
//!   standard deviation `sigma_c`, `N_d` samples in the dwell);
//! - move part: `sum_m J_m^T S_m^-1 J_m`, with `J_m` the derivative of the rotation vector
//!   `log(R(theta) R(theta_true)^T)` (start frame of the move) by each gyro parameter, where `R(theta)` is the
//!   move's noise-free samples integrated here (one exact rotation per sample, f64) with the rates compensated
//!   by `theta` (`w = T_g^-1 (w_meas - b_g - G f)`, `f = T_a^-1 (f_meas - b_a)` at the true accelerometer
//!   terms), by central finite differences around the truth; and `S_m = sum_k C_k P diag(sigma^2) P^T C_k^T
//!   dt^2`, the covariance of the rotation vector from white gyro noise, `C_k` the true attitude at the middle
//!   of sample k relative to the move's start and `P = T_g^-1` (the compensation applied to the noise).
//!
//! The bound is `sqrt(diag((dwell + move)^-1))` over the parameters the estimator determines. It holds for
//! unbiased estimators that use the dwell means and the moves' end-to-end rotations (not the rate samples of a
//! move one by one, which the turntable's reference does not describe).
//!
//! **The reference estimator** ([`reference_errors`]): on each run, the generalised least squares of the same
//! data (raw dwell means, the moves' rotations integrated here at the truth) linearised at the truth. Its
//! covariance is the bound, so its RMS error over the runs is what the bound looks like through the Monte
//! Carlo's own scatter, and the estimator's RMS error over the reference's on the same runs is its RMS error /
//! bound with that scatter divided out.

use sinscal::calib::general::{misalignment_index, parameter_name, Model, PARAMETERS};
use sinscal::calib::moves::{MoveSums, MOVE_PARAMETERS};

use crate::bound::{channel_noises, design, dwell_spans, predict, Session};
use sinscal_host::calibration::{calibrate_channels, Options};
use sinscal_host::io::recording::Recording;
use sinscal_host::model::simulator::{simulate, ScenarioFile, ScheduleSpec, SiteSpec};
use sinscal_host::model::synth::{mul, mul_vec, rotation, rotation_vector, transpose, DEG_PER_HOUR, M3, MICRO_G};
use sinscal_host::stats::solve::solve_spd;

/// The schedule: pitch, roll, heading of each position, degrees (every quarter turn about each table axis).
pub const POSITIONS_DEG: [[f64; 3]; 14] = [
    [0.0, 0.0, 0.0],
    [0.0, 0.0, 90.0],
    [0.0, 0.0, 180.0],
    [0.0, 0.0, 270.0],
    [90.0, 0.0, 270.0],
    [90.0, 0.0, 0.0],
    [90.0, 0.0, 90.0],
    [90.0, 0.0, 180.0],
    [0.0, 90.0, 180.0],
    [0.0, 90.0, 270.0],
    [0.0, 90.0, 0.0],
    [0.0, 180.0, 0.0],
    [0.0, 270.0, 0.0],
    [180.0, 0.0, 0.0],
];
/// Site latitude, degrees north.
pub const LATITUDE_DEG: f64 = 45.7796;
/// Output rate, Hz.
pub const RATE_HZ: f64 = 100.0;
/// Dwell length, s.
pub const DWELL_S: f64 = 20.0;
/// Move length, s (90 deg in 6 s: 15 deg/s).
pub const MOVE_S: f64 = 6.0;
/// Stillness after a move, s.
pub const SETTLE_S: f64 = 1.0;
/// Gyro angle random walk, deg/sqrt(h).
pub const GYRO_ARW_DEG_PER_SQRT_H: f64 = 0.15;
/// Accelerometer velocity random walk, ug/sqrt(Hz).
pub const ACCEL_VRW_UG_PER_SQRT_HZ: f64 = 60.0;
/// Gyro biases, deg/h.
pub const GYRO_BIAS_DEG_PER_H: [f64; 3] = [10.0, -8.0, 12.0];
/// Gyro scale factors, 1.
pub const GYRO_SCALE_FACTOR: [f64; 3] = [1.2e-3, -0.8e-3, 1.0e-3];
/// Gyro misalignments (row i, column j: axis i's sensitivity to rate about j), 1.
pub const GYRO_MISALIGNMENT: M3 = [[0.0, 5e-4, -4e-4], [-6e-4, 0.0, 3e-4], [4e-4, -5e-4, 0.0]];
/// Gyro g-sensitivity (row i: gyro i; column j: force along j), (rad/s)/(m/s^2).
pub const GYRO_G_SENSITIVITY_RADPS_PER_MPS2: M3 =
    [[1.0e-6, -0.5e-6, 0.8e-6], [-1.2e-6, 0.6e-6, 1.0e-6], [0.7e-6, -1.0e-6, -0.9e-6]];
/// Accelerometer biases, ug.
pub const ACCEL_BIAS_UG: [f64; 3] = [1000.0, -800.0, 1200.0];
/// Accelerometer scale factors, 1.
pub const ACCEL_SCALE_FACTOR: [f64; 3] = [2e-4, -1.5e-4, 2.5e-4];
/// Accelerometer misalignments (row i, column j: axis i's sensitivity to force along j), 1.
pub const ACCEL_MISALIGNMENT: M3 = [[0.0, 2e-4, -1e-4], [-2e-4, 0.0, 1.5e-4], [1e-4, -2.5e-4, 0.0]];

/// The Monte Carlo's scenario (see the module's documentation): white noise only.
pub fn scenario() -> ScenarioFile {
    let mut s = ScenarioFile {
        site: SiteSpec { latitude_deg: LATITUDE_DEG, height_m: 0.0, gravity_mps2: None },
        schedule: ScheduleSpec {
            rate_hz: RATE_HZ,
            dwell_s: DWELL_S,
            move_s: MOVE_S,
            settle_s: SETTLE_S,
            positions_deg: POSITIONS_DEG.to_vec(),
            ..ScheduleSpec::default()
        },
        ..ScenarioFile::default()
    };
    s.gyro.bias_radps = GYRO_BIAS_DEG_PER_H.map(|b| b * DEG_PER_HOUR);
    s.gyro.scale_factor = GYRO_SCALE_FACTOR;
    s.gyro.misalignment = GYRO_MISALIGNMENT;
    s.gyro.g_sensitivity_radps_per_mps2 = GYRO_G_SENSITIVITY_RADPS_PER_MPS2;
    s.gyro.angle_random_walk_rad_per_sqrt_s = GYRO_ARW_DEG_PER_SQRT_H.to_radians() / 60.0;
    s.accel.bias_mps2 = ACCEL_BIAS_UG.map(|b| b * MICRO_G);
    s.accel.scale_factor = ACCEL_SCALE_FACTOR;
    s.accel.misalignment = ACCEL_MISALIGNMENT;
    s.accel.velocity_random_walk_mps_per_sqrt_s = ACCEL_VRW_UG_PER_SQRT_HZ * MICRO_G;
    s
}

/// The scenario with every noise switched off (the truth's own samples).
pub fn without_noise(s: &ScenarioFile) -> ScenarioFile {
    let mut quiet = s.clone();
    quiet.gyro.angle_random_walk_rad_per_sqrt_s = 0.0;
    quiet.gyro.rate_random_walk_radps_per_sqrt_s = 0.0;
    quiet.gyro.bias_instability = None;
    quiet.gyro.quantization_radps = [0.0; 3];
    quiet.gyro.vibration = None;
    quiet.accel.velocity_random_walk_mps_per_sqrt_s = 0.0;
    quiet.accel.acceleration_random_walk_mps2_per_sqrt_s = 0.0;
    quiet.accel.bias_instability = None;
    quiet.accel.quantization_mps2 = [0.0; 3];
    quiet.accel.vibration = None;
    quiet
}

/// The scenario's static terms in the core's parameter layout (docs/formats.md#calibration-json-version-2), SI.
pub fn truth_si(s: &ScenarioFile) -> [f64; PARAMETERS] {
    let mut theta = [0.0; PARAMETERS];
    for i in 0..3 {
        theta[i] = s.gyro.bias_radps[i];
        theta[3 + i] = s.accel.bias_mps2[i];
        theta[6 + i] = s.accel.scale_factor[i];
        theta[15 + i] = s.gyro.scale_factor[i];
        theta[33 + i] = s.schedule.reference_offset_enu_rad[i];
        for j in 0..3 {
            if i != j {
                theta[9 + misalignment_index(i, j)] = s.accel.misalignment[i][j];
                theta[18 + misalignment_index(i, j)] = s.gyro.misalignment[i][j];
            }
            theta[24 + 3 * i + j] = s.gyro.g_sensitivity_radps_per_mps2[i][j];
        }
    }
    theta
}

/// The gyro parameters (bias, scale factors, misalignments, g-sensitivity): the ones a move's rotation depends
/// on at first order.
pub fn gyro_parameters() -> Vec<usize> {
    (0..3).chain(15..33).collect()
}

/// One sample of a move: the outputs over its interval and the interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveSample {
    /// Gyro output, body, rad/s.
    pub rate_b_radps: [f64; 3],
    /// Accelerometer output, body, m/s^2.
    pub force_b_mps2: [f64; 3],
    /// Interval since the row before, s.
    pub dt_s: f64,
}

/// The rows of one move: every row with `pos = 0` between two dwells.
#[derive(Clone, Debug, PartialEq)]
pub struct Move {
    /// The dwell before it (index in the recording's order).
    pub from: usize,
    /// The dwell after it.
    pub to: usize,
    /// Its samples in order.
    pub samples: Vec<MoveSample>,
}

/// The moves of a recording: each run of rows with `pos = 0` between two dwells (not before the first dwell or
/// after the last).
pub fn moves_of(recording: &Recording) -> Vec<Move> {
    let mut moves = Vec::new();
    let mut current: Option<Move> = None;
    let (mut dwell, mut last_pos, mut previous_t_s) = (None::<usize>, 0u32, None::<f64>);
    for row in &recording.rows {
        let dt_s = previous_t_s.map_or(0.0, |t| row.t_s - t);
        previous_t_s = Some(row.t_s);
        if row.pos != 0 {
            if row.pos != last_pos {
                let next = dwell.map_or(0, |d| d + 1);
                if let Some(m) = current.take() {
                    moves.push(Move { to: next, ..m });
                }
                dwell = Some(next);
            }
        } else if let Some(from) = dwell {
            let m = current.get_or_insert_with(|| Move { from, to: from, samples: Vec::new() });
            m.samples.push(MoveSample { rate_b_radps: row.rate_b_radps, force_b_mps2: row.force_b_mps2, dt_s });
        }
        last_pos = row.pos;
    }
    moves
}

/// `T = I + S + M` of one sensor from the layout: scale factors from `scale`, misalignments from `misalignment`.
fn sensor_matrix(theta: &[f64; PARAMETERS], scale: usize, misalignment: usize) -> M3 {
    core::array::from_fn(|i| {
        core::array::from_fn(|j| {
            if i == j {
                1.0 + theta[scale + i]
            } else {
                theta[misalignment + misalignment_index(i, j)]
            }
        })
    })
}

/// The inverse of a 3x3 matrix (adjugate over determinant).
fn inverse3(m: &M3) -> M3 {
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    core::array::from_fn(|i| core::array::from_fn(|j| c(j, i) / det))
}

/// The inverse sensor model at `theta` (docs/conventions.md#sensor-model).
struct Compensation {
    gyro_inverse: M3,
    accel_inverse: M3,
    gyro_bias_radps: [f64; 3],
    accel_bias_mps2: [f64; 3],
    g_sensitivity: M3,
}

impl Compensation {
    fn new(theta: &[f64; PARAMETERS]) -> Compensation {
        Compensation {
            gyro_inverse: inverse3(&sensor_matrix(theta, 15, 18)),
            accel_inverse: inverse3(&sensor_matrix(theta, 6, 9)),
            gyro_bias_radps: [theta[0], theta[1], theta[2]],
            accel_bias_mps2: [theta[3], theta[4], theta[5]],
            g_sensitivity: core::array::from_fn(|i| core::array::from_fn(|j| theta[24 + 3 * i + j])),
        }
    }

    /// `w = T_g^-1 (w_meas - b_g - G f)` with `f = T_a^-1 (f_meas - b_a)`, rad/s.
    fn rate_b_radps(&self, s: &MoveSample) -> [f64; 3] {
        let f = mul_vec(&self.accel_inverse, [0, 1, 2].map(|i| s.force_b_mps2[i] - self.accel_bias_mps2[i]));
        let gf = mul_vec(&self.g_sensitivity, f);
        mul_vec(&self.gyro_inverse, [0, 1, 2].map(|i| s.rate_b_radps[i] - self.gyro_bias_radps[i] - gf[i]))
    }
}

/// The rotation of a move, `C_b(end)^b(start)`, from its samples with the rates compensated by `theta`: the
/// product of the exact rotations of the samples' angle increments `w dt`.
pub fn integrate(samples: &[MoveSample], theta: &[f64; PARAMETERS]) -> M3 {
    let comp = Compensation::new(theta);
    samples.iter().fold(rotation([0.0; 3]), |r, s| mul(&r, &rotation(comp.rate_b_radps(s).map(|w| w * s.dt_s))))
}

/// The finite-difference step of parameter `p`: small against the parameter's effect's nonlinearity, large
/// against f64 rounding of a move's rotation.
fn step_si(p: usize) -> f64 {
    match p {
        0..=2 => 1e-7,
        24..=32 => 1e-7,
        _ => 1e-5,
    }
}

/// The Jacobian of a move's rotation vector `log(R(theta) R(theta_0)^T)` (start frame, rad) by every parameter
/// of the layout at `theta_0`, by central differences over the gyro parameters ([`gyro_parameters`]); the other
/// columns are zero.
pub fn move_jacobian(samples: &[MoveSample], theta_0: &[f64; PARAMETERS]) -> [[f64; PARAMETERS]; 3] {
    let back = transpose(&integrate(samples, theta_0));
    let mut j = [[0.0; PARAMETERS]; 3];
    for p in gyro_parameters() {
        let h = step_si(p);
        let turned = |sign: f64| {
            let mut theta = *theta_0;
            theta[p] += sign * h;
            rotation_vector(&mul(&integrate(samples, &theta), &back))
        };
        let (plus, minus) = (turned(1.0), turned(-1.0));
        for a in 0..3 {
            j[a][p] = (plus[a] - minus[a]) / (2.0 * h);
        }
    }
    j
}

/// The covariance of a move's rotation vector (start frame, rad^2) from white gyro noise of per-sample variance
/// `sample_var_radps2` (per axis), the rates compensated at `theta`: `sum_k C_k P diag(var) P^T C_k^T dt^2`,
/// `C_k` the attitude at the middle of sample k relative to the start, `P = T_g^-1`.
pub fn move_covariance_rad2(samples: &[MoveSample], theta: &[f64; PARAMETERS], sample_var_radps2: [f64; 3]) -> M3 {
    let comp = Compensation::new(theta);
    let p = comp.gyro_inverse;
    let q: M3 = core::array::from_fn(|a| {
        core::array::from_fn(|b| (0..3).map(|i| p[a][i] * sample_var_radps2[i] * p[b][i]).sum())
    });
    let mut r = rotation([0.0; 3]);
    let mut cov = [[0.0; 3]; 3];
    for s in samples {
        let d = comp.rate_b_radps(s).map(|w| w * s.dt_s);
        let c = mul(&r, &rotation(d.map(|x| 0.5 * x)));
        let cqc = mul(&mul(&c, &q), &transpose(&c));
        for a in 0..3 {
            for b in 0..3 {
                cov[a][b] += cqc[a][b] * s.dt_s * s.dt_s;
            }
        }
        r = mul(&r, &rotation(d));
    }
    cov
}

/// One column of the core's Jacobian of a move against [`move_jacobian`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColumnAgreement {
    /// The parameter, in the core's layout.
    pub parameter: usize,
    /// The largest difference over the three components, rad per SI unit.
    pub difference_rad_per_si: f64,
    /// The largest component of the column here.
    pub column_scale_rad_per_si: f64,
    /// The largest component of any column of the parameter's kind (biases; scale factors and misalignments;
    /// g-sensitivities) here.
    pub kind_scale_rad_per_si: f64,
}

/// The kind of a gyro parameter: 0 bias, 1 scale factor or misalignment, 2 g-sensitivity.
fn kind_of(p: usize) -> usize {
    match p {
        0..=2 => 0,
        15..=23 => 1,
        _ => 2,
    }
}

/// The core's Jacobian of one move (`sinscal::calib::moves::MoveSums`, f32, its prior at `theta`) against
/// [`move_jacobian`], column by column, and the angle between the two integrated rotations, rad. Both
/// compensate the force the g-sensitivity sees with the accelerometer terms of `theta`.
pub fn core_jacobian_agreement(samples: &[MoveSample], theta: &[f64; PARAMETERS]) -> (Vec<ColumnAgreement>, f64) {
    let prior = theta.map(|x| x as f32);
    let mut sums = MoveSums::new(&prior).expect("a regular prior");
    for s in samples {
        sums.push(s.rate_b_radps.map(|x| x as f32), s.force_b_mps2.map(|x| x as f32), s.dt_s as f32);
    }
    let core = sums.finish(0, 1, [0.0; 3]);
    let mine = move_jacobian(samples, theta);
    let column_scale = |p: usize| (0..3).map(|a| mine[a][p].abs()).fold(0.0, f64::max);
    let kind_scale =
        |k: usize| MOVE_PARAMETERS.iter().filter(|&&p| kind_of(p) == k).map(|&p| column_scale(p)).fold(0.0, f64::max);
    let columns = MOVE_PARAMETERS
        .iter()
        .enumerate()
        .map(|(c, &p)| ColumnAgreement {
            parameter: p,
            difference_rad_per_si: (0..3).map(|a| (core.jacobian[a][c] as f64 - mine[a][p]).abs()).fold(0.0, f64::max),
            column_scale_rad_per_si: column_scale(p),
            kind_scale_rad_per_si: kind_scale(kind_of(p)),
        })
        .collect();
    let r_core: M3 = core::array::from_fn(|i| core::array::from_fn(|j| core.rotation.to_mat3().0[i][j] as f64));
    let between = rotation_vector(&mul(&r_core, &transpose(&integrate(samples, theta))));
    (columns, between.iter().map(|x| x * x).sum::<f64>().sqrt())
}

/// The inverse of a symmetric positive definite matrix; `None` when singular.
fn inverse_spd(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    solve_spd(a, &vec![0.0; a.len()]).map(|(_, inv)| inv)
}

/// One dwell as the bound sees it: its six channel means (gyro x, y, z, accelerometer x, y, z).
#[derive(Clone, Debug, PartialEq)]
pub struct DwellBound {
    /// The derivative of each mean by every parameter at the truth ([`crate::bound::design`]).
    pub design: [[f64; PARAMETERS]; 6],
    /// The means at the truth without noise, SI.
    pub predicted_si: [f64; 6],
    /// Their variances under white noise, `sigma^2 / N`, SI^2.
    pub variance_si2: [f64; 6],
}

/// One move as the bound sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct MoveBound {
    /// The dwell before it.
    pub from: usize,
    /// The dwell after it.
    pub to: usize,
    /// Its noise-free samples integrated at the truth, `C_b(end)^b(start)`.
    pub rotation: M3,
    /// [`move_jacobian`] at the truth.
    pub jacobian: [[f64; PARAMETERS]; 3],
    /// [`move_covariance_rad2`] at the truth, rad^2.
    pub covariance_rad2: M3,
    /// Its inverse.
    pub information_per_rad2: Vec<Vec<f64>>,
}

/// The bound of a scenario's calibration with moves, and what it rests on.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationBound {
    /// The parameters, in the core's layout.
    pub parameters: Vec<usize>,
    /// The dwells, in the session's order.
    pub dwells: Vec<DwellBound>,
    /// The moves, in the session's order.
    pub moves: Vec<MoveBound>,
    /// Fisher information of the dwell means over `parameters`, SI^-2.
    pub dwell_fisher_per_si2: Vec<Vec<f64>>,
    /// Fisher information of the moves' rotations over `parameters`.
    pub move_fisher_per_si2: Vec<Vec<f64>>,
    /// `(dwell + move)^-1`, SI^2.
    pub covariance_si: Vec<Vec<f64>>,
    /// The bound of the dwell means alone (standard deviation, SI) per parameter, `None` when the dwells alone
    /// do not determine the parameters.
    pub dwell_only_std_si: Option<Vec<f64>>,
}

impl RotationBound {
    /// The bound's standard deviation per parameter, SI.
    pub fn std_si(&self) -> Vec<f64> {
        (0..self.parameters.len()).map(|i| self.covariance_si[i][i].max(0.0).sqrt()).collect()
    }
}

/// The dwells of `quiet` (the session without noise) at `theta`: the design of their means and the white noise
/// of the scenario's per-sample variance over each dwell's samples.
pub fn dwell_bounds(scenario: &ScenarioFile, quiet: &Recording, theta: &[f64; PARAMETERS]) -> Vec<DwellBound> {
    let session = Session {
        latitude_rad: scenario.site.latitude_deg.to_radians(),
        gravity_mps2: scenario.gravity_mps2(),
        positions_deg: scenario.schedule.positions_deg.clone(),
    };
    let spans = dwell_spans(quiet).expect("a simulated recording has a rate");
    let noise = channel_noises(scenario);
    design(&session, theta)
        .into_iter()
        .zip(predict(&session, theta))
        .zip(&spans)
        .map(|((design, predicted), span)| DwellBound {
            design,
            predicted_si: predicted,
            variance_si2: noise.map(|c| c.white_sample_std_si.powi(2) / span.samples as f64),
        })
        .collect()
}

/// The moves of `quiet` at `theta`, with the white gyro noise of the scenario.
pub fn move_bounds(scenario: &ScenarioFile, quiet: &Recording, theta: &[f64; PARAMETERS]) -> Vec<MoveBound> {
    let var = channel_noises(scenario).map(|c| c.white_sample_std_si.powi(2));
    moves_of(quiet)
        .iter()
        .map(|m| {
            let covariance_rad2 = move_covariance_rad2(&m.samples, theta, [var[0], var[1], var[2]]);
            let rows: Vec<Vec<f64>> = covariance_rad2.iter().map(|r| r.to_vec()).collect();
            MoveBound {
                from: m.from,
                to: m.to,
                rotation: integrate(&m.samples, theta),
                jacobian: move_jacobian(&m.samples, theta),
                covariance_rad2,
                information_per_rad2: inverse_spd(&rows).expect("a positive covariance"),
            }
        })
        .collect()
}

/// One block of observations: the rows of its design (per row, the derivative by every parameter of the layout)
/// and its weight, the inverse of its covariance.
type Block<'a> = (Vec<&'a [f64; PARAMETERS]>, Vec<Vec<f64>>);

/// `sum_k A_k^T W_k A_k` over `parameters`, each `A_k` given by its rows.
fn information(blocks: &[Block<'_>], parameters: &[usize]) -> Vec<Vec<f64>> {
    let n = parameters.len();
    let mut fisher = vec![vec![0.0; n]; n];
    for (rows, weight) in blocks {
        for (a, &pa) in parameters.iter().enumerate() {
            for (b, &pb) in parameters.iter().enumerate() {
                for (r, wr) in weight.iter().enumerate() {
                    for (c, w) in wr.iter().enumerate() {
                        fisher[a][b] += rows[r][pa] * w * rows[c][pb];
                    }
                }
            }
        }
    }
    fisher
}

/// The bound over `parameters` for `scenario` at its truth; `None` when the information is singular.
pub fn rotation_bound(scenario: &ScenarioFile, parameters: &[usize]) -> Option<RotationBound> {
    let quiet = simulate(&without_noise(scenario), 0, "rotation-bound");
    let theta = truth_si(scenario);
    let dwells = dwell_bounds(scenario, &quiet, &theta);
    let moves = move_bounds(scenario, &quiet, &theta);
    let dwell_blocks: Vec<Block<'_>> = dwells
        .iter()
        .map(|d| {
            let weight = (0..6).map(|r| (0..6).map(|c| if r == c { 1.0 / d.variance_si2[r] } else { 0.0 }).collect());
            (d.design.iter().collect(), weight.collect())
        })
        .collect();
    let move_blocks: Vec<Block<'_>> =
        moves.iter().map(|m| (m.jacobian.iter().collect(), m.information_per_rad2.clone())).collect();
    let dwell_fisher = information(&dwell_blocks, parameters);
    let move_fisher = information(&move_blocks, parameters);
    let total: Vec<Vec<f64>> =
        dwell_fisher.iter().zip(&move_fisher).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x + y).collect()).collect();
    let covariance_si = inverse_spd(&total)?;
    let dwell_only_std_si =
        inverse_spd(&dwell_fisher).map(|inv| (0..inv.len()).map(|i| inv[i][i].max(0.0).sqrt()).collect());
    Some(RotationBound {
        parameters: parameters.to_vec(),
        dwells,
        moves,
        dwell_fisher_per_si2: dwell_fisher,
        move_fisher_per_si2: move_fisher,
        covariance_si,
        dwell_only_std_si,
    })
}

/// The error (estimate - truth, SI, per parameter of the bound) of the efficient reference estimator on a
/// recording of the bound's session: the generalised least squares of the model linearised at the truth, from
/// the raw dwell means and the moves' rotations integrated here at the truth. Its covariance is the bound
/// exactly (linear model, Gaussian noise), so its RMS error over the runs shows what the Monte Carlo's own
/// scatter makes of the bound. A dwell mean `y = y(theta_0) + J_d dtheta + e`; a move's misfit at the truth
/// `e_m = log(R_meas(theta_0) R(theta_0)^T)` is undone by `dtheta` when `e_m + J_m dtheta = 0`, so
/// `dtheta = (F)^-1 (sum J_d^T S_d^-1 (y - y(theta_0)) - sum J_m^T S_m^-1 e_m)`.
pub fn reference_errors(bound: &RotationBound, truth: &[f64; PARAMETERS], recording: &Recording) -> Vec<f64> {
    let n = bound.parameters.len();
    let mut g = vec![0.0; n];
    let dwells = recording.dwells();
    assert_eq!(dwells.len(), bound.dwells.len(), "the recording is not of the bound's session");
    for (d, b) in dwells.iter().zip(&bound.dwells) {
        let count = d.rows.len() as f64;
        for c in 0..6 {
            let mean =
                d.rows.iter().map(|r| if c < 3 { r.rate_b_radps[c] } else { r.force_b_mps2[c - 3] }).sum::<f64>()
                    / count;
            let weighted = (mean - b.predicted_si[c]) / b.variance_si2[c];
            for (a, &p) in bound.parameters.iter().enumerate() {
                g[a] += b.design[c][p] * weighted;
            }
        }
    }
    let moves = moves_of(recording);
    assert_eq!(moves.len(), bound.moves.len(), "the recording is not of the bound's session");
    for (m, b) in moves.iter().zip(&bound.moves) {
        let e = rotation_vector(&mul(&integrate(&m.samples, truth), &transpose(&b.rotation)));
        let w: Vec<f64> = (0..3).map(|r| (0..3).map(|c| b.information_per_rad2[r][c] * e[c]).sum()).collect();
        for (a, &p) in bound.parameters.iter().enumerate() {
            g[a] -= (0..3).map(|r| b.jacobian[r][p] * w[r]).sum::<f64>();
        }
    }
    (0..n).map(|i| (0..n).map(|j| bound.covariance_si[i][j] * g[j]).sum()).collect()
}

/// The calibration the Monte Carlo runs: `sinscal calibrate --model full` (every term, the moves used, the
/// default prefilter and dwell value).
pub fn options() -> Options {
    Options { model: Model::FULL, ..Options::default() }
}

/// What a Monte Carlo needs once: the scenario, its truth, the determined parameters and the bound.
#[derive(Clone, Debug)]
pub struct Setup {
    /// The scenario.
    pub scenario: ScenarioFile,
    /// Its static terms, SI.
    pub truth_si: [f64; PARAMETERS],
    /// The parameters the schedule determines (those of the calibration of the noise-free session).
    pub parameters: Vec<usize>,
    /// The bound over them.
    pub bound: RotationBound,
}

/// The setup of `scenario` calibrated with [`options`].
pub fn setup(scenario: ScenarioFile) -> Setup {
    let quiet = simulate(&without_noise(&scenario), 0, "rotation-mc-quiet");
    let parameters = calibrate_channels(&quiet, &options()).expect("the noise-free session").estimates.determined;
    let bound = rotation_bound(&scenario, &parameters).expect("the determined parameters have a bound");
    Setup { truth_si: truth_si(&scenario), scenario, parameters, bound }
}

/// One run's outcome: per determined parameter (setup order) the error and the reported standard error, SI;
/// the move passes; or why the calibration failed.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOutcome {
    /// Seed of the run.
    pub seed: u64,
    /// Per parameter: (estimate - truth, reported standard error), `None` when the run left it undetermined.
    pub errors_si: Vec<Option<(f64, f64)>>,
    /// Passes of move integration and solution.
    pub move_passes: u32,
    /// The fit scale of the gyro terms and of the others (docs/method.md#fit-scale).
    pub std_scale: [f64; 6],
    /// Per parameter: the error of the reference estimator on the same run ([`reference_errors`]), SI.
    pub reference_errors_si: Vec<f64>,
}

/// One run: simulate with `seed`, calibrate, compare; `Err` with the reason when the calibration fails.
pub fn run_once(setup: &Setup, seed: u64) -> Result<RunOutcome, String> {
    let recording = simulate(&setup.scenario, seed, "rotation-mc");
    let c = calibrate_channels(&recording, &options()).map_err(|e| format!("seed {seed}: {e}"))?;
    let e = &c.estimates;
    let errors = setup
        .parameters
        .iter()
        .map(|&p| match (e.value_si[p], e.std_si[p]) {
            (Some(v), Some(sd)) => Some((v - setup.truth_si[p], sd)),
            _ => None,
        })
        .collect();
    let reference_errors_si = reference_errors(&setup.bound, &setup.truth_si, &recording);
    Ok(RunOutcome { seed, errors_si: errors, move_passes: c.move_passes, std_scale: e.std_scale, reference_errors_si })
}

/// Runs with seeds `seed .. seed + runs`, on the machine's threads; outcomes in seed order.
pub fn run_all(setup: &Setup, runs: usize, seed: u64) -> Vec<Result<RunOutcome, String>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, runs.max(1));
    let mut out: Vec<(u64, Result<RunOutcome, String>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    (t..runs).step_by(threads).map(|i| (i as u64, run_once(setup, seed + i as u64))).collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().expect("a run panicked")).collect()
    });
    out.sort_by_key(|(i, _)| *i);
    out.into_iter().map(|(_, r)| r).collect()
}

/// The Monte Carlo's figures of one parameter, SI.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterFigures {
    /// Index in the core's layout.
    pub parameter: usize,
    /// True value.
    pub truth_si: f64,
    /// Runs that determined it.
    pub runs: usize,
    /// Mean of estimate - truth.
    pub mean_error_si: f64,
    /// RMS of estimate - truth.
    pub rms_error_si: f64,
    /// RMS of the reported standard error.
    pub rms_reported_std_si: f64,
    /// RMS of (estimate - truth) / reported standard error.
    pub rms_z: f64,
    /// The bound's standard deviation.
    pub bound_si: f64,
    /// The bound of the dwell means alone, when they determine the parameters.
    pub dwell_only_bound_si: Option<f64>,
    /// RMS error of the reference estimator ([`reference_errors`]) on the same runs.
    pub reference_rms_error_si: f64,
}

impl ParameterFigures {
    /// RMS error over the bound.
    pub fn rms_over_bound(&self) -> f64 {
        self.rms_error_si / self.bound_si
    }

    /// RMS error over the reference estimator's on the same runs: RMS error / bound with the scatter of the
    /// runs themselves divided out (1 in expectation for an efficient estimator).
    pub fn rms_over_reference(&self) -> f64 {
        self.rms_error_si / self.reference_rms_error_si
    }
}

/// The figures of every determined parameter over the successful runs.
pub fn figures(setup: &Setup, outcomes: &[Result<RunOutcome, String>]) -> Vec<ParameterFigures> {
    let ok: Vec<&RunOutcome> = outcomes.iter().filter_map(|o| o.as_ref().ok()).collect();
    let bound = setup.bound.std_si();
    setup
        .parameters
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let pairs: Vec<(f64, f64)> = ok.iter().filter_map(|o| o.errors_si[i]).collect();
            let reference = ok.iter().map(|o| o.reference_errors_si[i].powi(2)).sum::<f64>() / ok.len().max(1) as f64;
            let n = pairs.len().max(1) as f64;
            let mean = |f: &dyn Fn(&(f64, f64)) -> f64| pairs.iter().map(f).sum::<f64>() / n;
            ParameterFigures {
                parameter: p,
                truth_si: setup.truth_si[p],
                runs: pairs.len(),
                mean_error_si: mean(&|(e, _)| *e),
                rms_error_si: mean(&|(e, _)| e * e).sqrt(),
                rms_reported_std_si: mean(&|(_, s)| s * s).sqrt(),
                rms_z: mean(&|(e, s)| (e / s).powi(2)).sqrt(),
                bound_si: bound[i],
                dwell_only_bound_si: setup.bound.dwell_only_std_si.as_ref().map(|d| d[i]),
                reference_rms_error_si: reference.sqrt(),
            }
        })
        .collect()
}

/// The unit a parameter is shown in and its size in SI.
pub fn display_unit(p: usize) -> (&'static str, f64) {
    match p {
        0..=2 => ("deg/h", DEG_PER_HOUR),
        3..=5 => ("ug", MICRO_G),
        6..=23 => ("ppm", 1e-6),
        24..=32 => ("deg/h/g", DEG_PER_HOUR / 9.80665),
        _ => ("arcsec", 1.0 / 206_264.806_247_096_36),
    }
}

/// The table of [`figures`], one line per parameter, in display units.
pub fn table(figures: &[ParameterFigures]) -> String {
    let mut out = format!(
        "{:<22} {:>7} {:>9} {:>8} {:>9} {:>9} {:>9} {:>6} {:>7} {:>7} {:>7} {:>10} {:>4}\n",
        "parameter",
        "unit",
        "truth",
        "mean err",
        "RMS err",
        "RMS SE",
        "CRB",
        "RMS z",
        "RMS/CRB",
        "GLS/CRB",
        "RMS/GLS",
        "dwells CRB",
        "runs"
    );
    for f in figures {
        let (unit, scale) = display_unit(f.parameter);
        let dwells = f.dwell_only_bound_si.map_or("-".to_string(), |d| format!("{:.4e}", d / scale));
        out.push_str(&format!(
            "{:<22} {:>7} {:>9.2} {:>8.3} {:>9.3} {:>9.3} {:>9.3} {:>6.3} {:>7.3} {:>7.3} {:>7.3} {:>10} {:>4}\n",
            parameter_name(f.parameter),
            unit,
            f.truth_si / scale,
            f.mean_error_si / scale,
            f.rms_error_si / scale,
            f.rms_reported_std_si / scale,
            f.bound_si / scale,
            f.rms_z,
            f.rms_over_bound(),
            f.reference_rms_error_si / f.bound_si,
            f.rms_over_reference(),
            dwells,
            f.runs
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    /// A pure quarter turn about z in `MOVE_S` at 100 Hz, gravity along z: no Earth rate, exact samples.
    fn quarter_turn_about_z() -> Vec<MoveSample> {
        let n = (MOVE_S * RATE_HZ) as usize;
        let dt_s = 1.0 / RATE_HZ;
        let sample = MoveSample { rate_b_radps: [0.0, 0.0, FRAC_PI_2 / MOVE_S], force_b_mps2: [0.0, 0.0, 9.8], dt_s };
        vec![sample; n]
    }

    #[test]
    fn a_quarter_turn_about_z_has_the_jacobian_by_hand() {
        let samples = quarter_turn_about_z();
        let theta = [0.0; PARAMETERS];
        let r = integrate(&samples, &theta);
        // x goes to y.
        assert!((r[1][0] - 1.0).abs() < 1e-12 && r[0][0].abs() < 1e-12, "{r:?}");
        let j = move_jacobian(&samples, &theta);
        let column = |p: usize| [j[0][p], j[1][p], j[2][p]];
        let close = |p: usize, expected: [f64; 3], tol: f64| {
            let got = column(p);
            assert!(
                (0..3).all(|a| (got[a] - expected[a]).abs() < tol),
                "{}: {got:?} vs {expected:?}",
                parameter_name(p)
            );
        };
        // A scale factor s on z: the gyro reads (1 + s) times the rate, the compensated turn is pi/2 / (1 + s):
        // d rotation / d s = -pi/2 about z.
        close(17, [0.0, 0.0, -FRAC_PI_2], 1e-8);
        // Other scale factors: nothing turns about x or y.
        close(15, [0.0; 3], 1e-8);
        close(16, [0.0; 3], 1e-8);
        // A bias on z: -T about z.
        close(2, [0.0, 0.0, -MOVE_S], 1e-7);
        // A bias on x, seen in the start frame while the body turns: -int (cos a, sin a, 0) dt = -(T / (pi/2))
        // (1, 1, 0); the misalignment xz (x's sensitivity to rate about z): -int (cos a, sin a, 0) da = -(1, 1, 0).
        let k = MOVE_S / FRAC_PI_2;
        close(0, [-k, -k, 0.0], 1e-5);
        close(18 + misalignment_index(0, 2), [-1.0, -1.0, 0.0], 1e-5);
        // y's sensitivity to rate about z: -int (-sin a, cos a, 0) da = -(-1, 1, 0).
        close(18 + misalignment_index(1, 2), [1.0, -1.0, 0.0], 1e-5);
        // g-sensitivity zz: a rate 9.8 G_zz on z over T: -9.8 T about z.
        close(24 + 8, [0.0, 0.0, -9.8 * MOVE_S], 1e-6);
        // No accelerometer or offset column.
        assert!((3..15).chain(33..36).all(|p| column(p) == [0.0; 3]));
    }

    #[test]
    fn a_quarter_turn_about_z_has_the_covariance_by_hand() {
        let samples = quarter_turn_about_z();
        let var = [1e-6, 4e-6, 9e-6];
        let cov = move_covariance_rad2(&samples, &[0.0; PARAMETERS], var);
        let dt_t = MOVE_S / RATE_HZ;
        // About z the noise of z alone; x and y share their variances as the body turns about z; the average of
        // cos^2 over a quarter turn is 1/2.
        assert!((cov[2][2] / (var[2] * dt_t) - 1.0).abs() < 1e-12, "{cov:?}");
        assert!(((cov[0][0] + cov[1][1]) / ((var[0] + var[1]) * dt_t) - 1.0).abs() < 1e-12);
        assert!((cov[0][0] / ((var[0] + var[1]) * dt_t / 2.0) - 1.0).abs() < 1e-3, "{cov:?}");
        assert!(cov[0][2].abs() < 1e-20 && cov[1][2].abs() < 1e-20);
    }

    #[test]
    fn moves_are_found_between_dwells_only() {
        let s = without_noise(&scenario());
        let rec = simulate(&s, 0, "moves");
        let moves = moves_of(&rec);
        assert_eq!(moves.len(), POSITIONS_DEG.len() - 1);
        for (k, m) in moves.iter().enumerate() {
            assert_eq!((m.from, m.to), (k, k + 1));
            assert_eq!(m.samples.len(), ((MOVE_S + SETTLE_S) * RATE_HZ) as usize);
        }
        // Each move integrates, at the truth, to the reference rotation C_from^T E C_to (E: the Earth's turn).
        let theta = truth_si(&s);
        let w_n = sinscal_host::model::synth::earth_rate_n_radps(LATITUDE_DEG.to_radians());
        for m in &moves {
            let (a, b) = (POSITIONS_DEG[m.from], POSITIONS_DEG[m.to]);
            let t_s: f64 = m.samples.iter().map(|x| x.dt_s).sum();
            let c_from = sinscal_host::model::synth::c_b_n(a[0], a[1], a[2]);
            let c_to = sinscal_host::model::synth::c_b_n(b[0], b[1], b[2]);
            let reference = mul(&mul(&transpose(&c_from), &rotation(w_n.map(|w| w * t_s))), &c_to);
            let miss = rotation_vector(&mul(&integrate(&m.samples, &theta), &transpose(&reference)));
            assert!(miss.iter().all(|x| x.abs() < 1e-9), "move {} -> {}: {miss:?}", m.from, m.to);
        }
    }

    #[test]
    fn inverse3_inverts() {
        let m = [[1.001, 2e-4, -3e-4], [5e-4, 0.998, 1e-4], [-2e-4, 4e-4, 1.002]];
        let p = mul(&m, &inverse3(&m));
        for i in 0..3 {
            for j in 0..3 {
                assert!((p[i][j] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
    }
}
