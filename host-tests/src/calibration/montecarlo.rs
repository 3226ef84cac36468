//! SIMULATION: Monte Carlo of the calibration against the Cramer-Rao bound.
//!
//! Each run draws a fresh white-noise session of the scenario, feeds it sample by sample through the
//! core (dwell collector, alignment, solver) with three estimators, and compares the estimates with the
//! truth. The bounds are computed in f64 from the core's own design rows and angle covariance at the
//! TRUE noise level:
//! - the angle-model bound `(sum_k A_k^T Sigma_k^-1 A_k)^-1`, which the least-squares estimator on the
//!   alignment angles reaches when it works as designed (its own model's bound);
//! - the six-channel bound: the same unknowns estimated from all six channel means of every dwell
//!   (`w_b = C^T w_n + eps`, `f_b = C^T f_n + nabla`, reference offset in both), which is what the data
//!   could give at best.

use serde::Serialize;
use sinscal::calib::align::{angle_covariance_rad2, DwellValue};
use sinscal::calib::angles::{
    calibrate_positions, design_rows_si, BiasSolution, CalibrationSettings, Parameter, PositionInput, MAX_PARAMETERS,
};
use sinscal::calib::dwell::{DwellCollector, DwellSummary, Prefilter};
use sinscal::nav::earth::Site;
use sinscal::nav::frames::Attitude;
use sinscal::sensor::sample::ImuSample;

use crate::model::synth::{c_b_n as c_b_n_f64, earth_rate_n_radps, mul_t_vec, Scenario};

/// The estimators compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Estimator {
    /// No prefilter, dwell mean.
    NoneMean,
    /// HMM/KF prefilter, mean of the filtered dwell.
    HmmkfMean,
    /// HMM/KF prefilter, the filter's settled output at the end of the dwell (the paper's alternative).
    HmmkfSettled,
}

impl Estimator {
    /// All, in report order.
    pub const ALL: [Estimator; 3] = [Estimator::NoneMean, Estimator::HmmkfMean, Estimator::HmmkfSettled];

    /// Name in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Estimator::NoneMean => "none, dwell mean",
            Estimator::HmmkfMean => "hmmkf, dwell mean",
            Estimator::HmmkfSettled => "hmmkf, settled output",
        }
    }
}

/// Statistics of one parameter under one estimator (SI units).
#[derive(Clone, Debug, Serialize)]
pub struct ParameterStats {
    /// Parameter name.
    pub parameter: &'static str,
    /// True value.
    pub truth: f64,
    /// Mean of (estimate - truth).
    pub mean_error: f64,
    /// RMS of (estimate - truth).
    pub rms_error: f64,
    /// RMS of the reported standard error.
    pub rms_reported_std: f64,
    /// RMS of (estimate - truth) / reported standard error: 1 when the standard errors are right.
    pub rms_normalised_error: f64,
    /// Angle-model Cramer-Rao bound (standard deviation).
    pub crb_angles: f64,
    /// rms_error / crb_angles.
    pub efficiency_ratio: f64,
}

/// Results of one estimator.
#[derive(Clone, Debug, Serialize)]
pub struct EstimatorStats {
    /// Which.
    pub estimator: Estimator,
    /// Per parameter, in the core's order.
    pub parameters: Vec<ParameterStats>,
}

/// The whole Monte Carlo report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// "sinscal-montecarlo/1".
    pub schema: &'static str,
    /// Runs.
    pub runs: usize,
    /// First seed (run i uses seed + i).
    pub seed: u64,
    /// Passes of the solution at most.
    pub max_passes: u32,
    /// Gyro white noise per sample, rad/s.
    pub gyro_noise_radps: f64,
    /// Accelerometer white noise per sample, m/s^2.
    pub accel_noise_mps2: f64,
    /// Samples per dwell.
    pub dwell_samples: usize,
    /// Results per estimator.
    pub estimators: Vec<EstimatorStats>,
    /// Angle-model bound per parameter (standard deviation, SI).
    pub crb_angles: Vec<f64>,
    /// Six-channel bound per parameter, with the reference offset unknown (standard deviation, SI).
    pub crb_channels: Vec<f64>,
    /// Six-channel bound per parameter with the reference attitude taken as exact (6 parameters).
    pub crb_channels_known_reference: Vec<f64>,
    /// Output variance of the settled HMM/KF per raw sample variance, gyro and accelerometer (the dwell
    /// mean's is 1 / samples).
    pub settled_noise_gain: [f64; 2],
}

/// Inverse of a symmetric positive definite matrix (Gauss-Jordan with partial pivoting), f64.
fn invert(mut a: Vec<Vec<f64>>) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut inv: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect()).collect();
    for col in 0..n {
        let pivot = (col..n).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        inv.swap(col, pivot);
        let p = a[col][col];
        for j in 0..n {
            a[col][j] /= p;
            inv[col][j] /= p;
        }
        for row in 0..n {
            if row != col {
                let f = a[row][col];
                if f != 0.0 {
                    for j in 0..n {
                        a[row][j] -= f * a[col][j];
                        inv[row][j] -= f * inv[col][j];
                    }
                }
            }
        }
    }
    Some(inv)
}

fn bound_from_fisher(fisher: Vec<Vec<f64>>) -> Vec<f64> {
    match invert(fisher) {
        Some(cov) => (0..cov.len()).map(|i| cov[i][i].max(0.0).sqrt()).collect(),
        None => vec![f64::INFINITY; MAX_PARAMETERS],
    }
}

fn site_of(s: &Scenario) -> Site {
    Site { latitude_rad: (s.latitude_deg as f32).to_radians(), gravity_mps2: s.gravity_mps2 as f32 }
}

/// The angle-model Cramer-Rao bound for the scenario's noise (standard deviation per parameter, SI).
pub fn crb_angles(s: &Scenario) -> Vec<f64> {
    let site = site_of(s);
    let n = s.dwell_samples() as f32;
    let wv = [(s.gyro_noise_radps * s.gyro_noise_radps) as f32 / n; 3];
    let fv = [(s.accel_noise_mps2 * s.accel_noise_mps2) as f32 / n; 3];
    let mut fisher = vec![vec![0.0f64; MAX_PARAMETERS]; MAX_PARAMETERS];
    for p in &s.positions_deg {
        let c = Attitude::from_degrees(p[0] as f32, p[1] as f32, p[2] as f32).c_b_n();
        let rows = design_rows_si(&c, &site);
        let cov = angle_covariance_rad2(&c, fv, wv, &site);
        let cov64: Vec<Vec<f64>> = (0..3).map(|i| (0..3).map(|j| cov.0[i][j] as f64).collect()).collect();
        let w = invert(cov64).expect("angle covariance is positive definite");
        for a in 0..MAX_PARAMETERS {
            for b in 0..MAX_PARAMETERS {
                let mut sum = 0.0;
                for i in 0..3 {
                    for j in 0..3 {
                        sum += rows[i][a] as f64 * w[i][j] * rows[j][b] as f64;
                    }
                }
                fisher[a][b] += sum;
            }
        }
    }
    bound_from_fisher(fisher)
}

/// The six-channel Cramer-Rao bound; with `known_reference` the offset is not a parameter.
pub fn crb_channels(s: &Scenario, known_reference: bool) -> Vec<f64> {
    let params = if known_reference { 6 } else { MAX_PARAMETERS };
    let n = s.dwell_samples() as f64;
    let var = [s.gyro_noise_radps.powi(2) / n, s.accel_noise_mps2.powi(2) / n];
    let lat = s.latitude_deg.to_radians();
    let w_n = earth_rate_n_radps(lat);
    let f_n = [0.0, 0.0, s.gravity_mps2];
    let mut fisher = vec![vec![0.0f64; params]; params];
    for p in &s.positions_deg {
        let c = c_b_n_f64(p[0], p[1], p[2]);
        // v_b = C^T (I + [phi0 x]) v_n  =>  d v_b / d phi0 = -C^T [v_n x].
        for (sensor, v_n) in [w_n, f_n].iter().enumerate() {
            for axis in 0..3 {
                let mut row = vec![0.0; params];
                row[3 * sensor + axis] = 1.0;
                if !known_reference {
                    for k in 0..3 {
                        let mut e = [0.0; 3];
                        e[k] = 1.0;
                        // column k of -[v_n x] is -(v_n x e_k)
                        let col = [
                            -(v_n[1] * e[2] - v_n[2] * e[1]),
                            -(v_n[2] * e[0] - v_n[0] * e[2]),
                            -(v_n[0] * e[1] - v_n[1] * e[0]),
                        ];
                        row[6 + k] = mul_t_vec(&c, col)[axis];
                    }
                }
                for a in 0..params {
                    for b in 0..params {
                        fisher[a][b] += row[a] * row[b] / var[sensor];
                    }
                }
            }
        }
    }
    bound_from_fisher(fisher)
}

fn summarise(collector: &DwellCollector) -> DwellSummary {
    collector.summary().expect("simulated dwells are long enough")
}

/// One run: the three estimators' solutions, each with at most `max_passes` passes.
pub fn run_once(s: &Scenario, seed: u64, max_passes: u32) -> [BiasSolution; 3] {
    let site = site_of(s);
    let mut plain = DwellCollector::new(&Prefilter::None).expect("no prefilter");
    let mut filtered = DwellCollector::new(&Prefilter::paper()).expect("paper prefilter");
    let mut summaries: Vec<(usize, DwellSummary, DwellSummary)> = Vec::new();
    let per_dwell = s.dwell_samples();
    s.for_each_sample(seed, |k, w, f| {
        let sample = ImuSample { rate_b_radps: w.map(|x| x as f32), force_b_mps2: f.map(|x| x as f32) };
        plain.update(&sample).expect("finite");
        filtered.update(&sample).expect("finite");
        if plain.samples() as usize == per_dwell {
            summaries.push((k, summarise(&plain), summarise(&filtered)));
            plain.reset();
            filtered.reset();
        }
    });
    Estimator::ALL.map(|e| {
        let (use_filtered, dwell_value) = match e {
            Estimator::NoneMean => (false, DwellValue::Mean),
            Estimator::HmmkfMean => (true, DwellValue::Mean),
            Estimator::HmmkfSettled => (true, DwellValue::Settled),
        };
        let inputs: Vec<PositionInput> = summaries
            .iter()
            .map(|(k, plain, filtered)| {
                let p = s.positions_deg[*k];
                let c_b_n = Attitude::from_degrees(p[0] as f32, p[1] as f32, p[2] as f32).c_b_n();
                PositionInput { c_b_n, summary: if use_filtered { *filtered } else { *plain } }
            })
            .collect();
        let settings = CalibrationSettings { dwell_value, max_passes, ..CalibrationSettings::default() };
        calibrate_positions(&inputs, &site, &settings).expect("calibration").solution
    })
}

/// Runs the Monte Carlo; `progress(done)` is called after each run.
pub fn run(s: &Scenario, runs: usize, seed: u64, max_passes: u32, mut progress: impl FnMut(usize)) -> Report {
    let truth: Vec<f64> = s
        .gyro_bias_b_radps
        .iter()
        .chain(s.accel_bias_b_mps2.iter())
        .chain(s.reference_offset_n_rad.iter())
        .copied()
        .collect();
    // sums per estimator and parameter: error, error^2, std^2, (error/std)^2
    let mut sums = [[[0.0f64; 4]; MAX_PARAMETERS]; 3];
    for r in 0..runs {
        let solutions = run_once(s, seed.wrapping_add(r as u64), max_passes);
        for (e, sol) in solutions.iter().enumerate() {
            for (i, p) in Parameter::ALL.iter().enumerate() {
                let est = sol.get(*p).expect("Table 1 with the offset determines every parameter");
                let err = est.value as f64 - truth[i];
                let sd = est.std_error as f64;
                let acc = &mut sums[e][i];
                acc[0] += err;
                acc[1] += err * err;
                acc[2] += sd * sd;
                acc[3] += (err / sd).powi(2);
            }
        }
        progress(r + 1);
    }
    let crb = crb_angles(s);
    let n = runs as f64;
    let estimators = Estimator::ALL
        .iter()
        .enumerate()
        .map(|(e, &estimator)| EstimatorStats {
            estimator,
            parameters: Parameter::ALL
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    let acc = sums[e][i];
                    let rms_error = (acc[1] / n).sqrt();
                    ParameterStats {
                        parameter: p.name(),
                        truth: truth[i],
                        mean_error: acc[0] / n,
                        rms_error,
                        rms_reported_std: (acc[2] / n).sqrt(),
                        rms_normalised_error: (acc[3] / n).sqrt(),
                        crb_angles: crb[i],
                        efficiency_ratio: rms_error / crb[i],
                    }
                })
                .collect(),
        })
        .collect();
    Report {
        schema: "sinscal-montecarlo/1",
        runs,
        seed,
        max_passes,
        gyro_noise_radps: s.gyro_noise_radps,
        accel_noise_mps2: s.accel_noise_mps2,
        dwell_samples: s.dwell_samples(),
        estimators,
        crb_angles: crb,
        crb_channels: crb_channels(s, false),
        crb_channels_known_reference: crb_channels(s, true),
        settled_noise_gain: DwellCollector::new(&Prefilter::paper())
            .expect("paper prefilter")
            .noise_gain()
            .map(|g| g as f64),
    }
}
