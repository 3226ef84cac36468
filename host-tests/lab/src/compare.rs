//! SIMULATION: the estimators side by side on the same runs, with the errors of a real laboratory
//! (docs/method.md#default-estimator).
//!
//! Each run draws the sensor's biases, its misalignments, the turntable's position errors and the noise of
//! every dwell mean, and builds the dwell means exactly (f64, the host's model: `model::sensor::Triad`).
//! The same means go to the paper's angle method and to the general estimator with several models. The
//! dwell means are drawn directly (Gaussian, with the standard error of a white-noise mean of the dwell
//! length), which is what every estimator here consumes.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::Serialize;
use sinscal::calib::angles::{calibrate_positions, CalibrationSettings, PositionInput};
use sinscal::calib::dwell::{DwellAllan, DwellSummary, MeanNoise};
use sinscal::calib::general::{ChannelDwell, ChannelEstimator, ChannelSettings, Model, Term};
use sinscal::nav::earth::Site;
use sinscal::nav::frames::Attitude;

use sinscal_host::calibration::estimates::Estimates;
use sinscal_host::model::sensor::Triad;
use sinscal_host::model::synth::{
    c_b_n, earth_rate_n_radps, mul, mul_t_vec, rotation, DEG_PER_HOUR, MICRO_G, TABLE1_DEG,
};

/// Arcseconds in a radian.
const ARCSEC_RAD: f64 = 4.848_136_811_095_36e-6;

/// The laboratory: its errors and the sensor's noise.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Lab {
    /// Latitude, degrees.
    pub latitude_deg: f64,
    /// True local gravity, m/s^2.
    pub gravity_mps2: f64,
    /// The gravity the calibration is told minus the true one, m/s^2 (a gravity model's error).
    pub gravity_error_mps2: f64,
    /// Standard deviation of each gyro bias drawn, rad/s.
    pub gyro_bias_std_radps: f64,
    /// Standard deviation of each accelerometer bias drawn, m/s^2.
    pub accel_bias_std_mps2: f64,
    /// Vertical (z) accelerometer scale factor, 1.
    pub accel_scale_factor_z: f64,
    /// Standard deviation of each misalignment (accelerometer and gyro), rad.
    pub misalignment_std_rad: f64,
    /// Standard deviation of each turntable position error per axis and dwell, rad.
    pub table_error_std_rad: f64,
    /// Gyro angle random walk, rad/s per sqrt(Hz) (standard error of a mean of T seconds: this / sqrt(T)).
    pub gyro_arw_radps_per_rthz: f64,
    /// Accelerometer white noise, m/s^2 per sqrt(Hz).
    pub accel_noise_mps2_per_rthz: f64,
    /// Dwell length, s.
    pub dwell_s: f64,
    /// Turntable positions (pitch, roll, heading), degrees.
    pub positions_deg: Vec<[f64; 3]>,
}

impl Lab {
    /// A fibre-optic-gyro IMU on Table 1, 1 min per position, no laboratory error: angle random walk
    /// 0.005 deg/sqrt(h), 10 ug/sqrt(Hz).
    pub fn fog_table1() -> Lab {
        Lab {
            latitude_deg: 45.7796,
            gravity_mps2: 9.8063,
            gravity_error_mps2: 0.0,
            gyro_bias_std_radps: 0.05 * DEG_PER_HOUR,
            accel_bias_std_mps2: 100.0 * MICRO_G,
            accel_scale_factor_z: 0.0,
            misalignment_std_rad: 0.0,
            table_error_std_rad: 0.0,
            // 0.005 deg/sqrt(h) = 0.005 * 3600 deg/h / sqrt(3600 s) = 0.3 deg/h per sqrt(Hz).
            gyro_arw_radps_per_rthz: 0.3 * DEG_PER_HOUR,
            accel_noise_mps2_per_rthz: 10.0 * MICRO_G,
            dwell_s: 60.0,
            positions_deg: TABLE1_DEG.to_vec(),
        }
    }

    /// The same with a real laboratory's errors: the gravity model 20 ug off, a vertical accelerometer scale
    /// factor of 100 ppm, misalignments of 50 arcsec, turntable positions good to 3 arcsec.
    pub fn fog_table1_lab() -> Lab {
        Lab {
            gravity_error_mps2: 20.0 * MICRO_G,
            accel_scale_factor_z: 100e-6,
            misalignment_std_rad: 50.0 * ARCSEC_RAD,
            table_error_std_rad: 3.0 * ARCSEC_RAD,
            ..Lab::fog_table1()
        }
    }
}

/// One estimator of the comparison.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Candidate {
    /// The paper's angle method (refined, reference offset estimated: `--method angles`).
    Angles,
    /// The general estimator with a model.
    Channels(Model),
}

impl Candidate {
    /// The name in reports.
    pub fn name(&self) -> String {
        match self {
            Candidate::Angles => "angles".to_string(),
            Candidate::Channels(m) => {
                let terms: Vec<&str> = Term::ALL.iter().filter(|t| m.contains(**t)).map(|t| t.name()).collect();
                format!("channels: {}", terms.join(","))
            }
        }
    }
}

/// One run's dwell means and the true biases.
struct Run {
    inputs: Vec<PositionInput>,
    dwells: Vec<ChannelDwell>,
    truth: [f64; 6],
}

fn draw(lab: &Lab, rng: &mut ChaCha8Rng) -> Run {
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let mut n = || unit.sample(rng);
    let gyro_bias = [0; 3].map(|_| n() * lab.gyro_bias_std_radps);
    let accel_bias = [0; 3].map(|_| n() * lab.accel_bias_std_mps2);
    let mut accel_m = [[0.0; 3]; 3];
    let mut gyro_m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            if i != j {
                accel_m[i][j] = n() * lab.misalignment_std_rad;
                gyro_m[i][j] = n() * lab.misalignment_std_rad;
            }
        }
    }
    let accel = Triad::new(accel_bias, [0.0, 0.0, lab.accel_scale_factor_z], &accel_m, [[0.0; 3]; 3]);
    let gyro = Triad::new(gyro_bias, [0.0; 3], &gyro_m, [[0.0; 3]; 3]);
    let rate_mean_std_radps = lab.gyro_arw_radps_per_rthz / lab.dwell_s.sqrt();
    let force_mean_std_mps2 = lab.accel_noise_mps2_per_rthz / lab.dwell_s.sqrt();
    let w_n = earth_rate_n_radps(lab.latitude_deg.to_radians());
    let samples = (lab.dwell_s * 100.0) as u32;
    let mut run = Run { inputs: Vec::new(), dwells: Vec::new(), truth: [0.0; 6] };
    run.truth[..3].copy_from_slice(&gyro_bias);
    run.truth[3..].copy_from_slice(&accel_bias);
    for p in &lab.positions_deg {
        let error = [0; 3].map(|_| n() * lab.table_error_std_rad);
        let c_true = mul(&rotation(error), &c_b_n(p[0], p[1], p[2]));
        let f_b = mul_t_vec(&c_true, [0.0, 0.0, lab.gravity_mps2]);
        let w_b = mul_t_vec(&c_true, w_n);
        let f = accel.measure(f_b, [0.0; 3]).map(|x| (x + n() * force_mean_std_mps2) as f32);
        let w = gyro.measure(w_b, f_b).map(|x| (x + n() * rate_mean_std_radps) as f32);
        let attitude = Attitude::from_degrees(p[0] as f32, p[1] as f32, p[2] as f32);
        let rate_sample_std_radps = (rate_mean_std_radps * (samples as f64).sqrt()) as f32;
        let force_sample_std_mps2 = (force_mean_std_mps2 * (samples as f64).sqrt()) as f32;
        let summary = DwellSummary {
            samples,
            rejected: 0,
            spikes: 0,
            rate_mean_b_radps: w,
            force_mean_b_mps2: f,
            rate_sample_std_b_radps: [rate_sample_std_radps; 3],
            force_sample_std_b_mps2: [force_sample_std_mps2; 3],
            rate_settled_b_radps: w,
            force_settled_b_mps2: f,
            settled_noise_gain: [1.0, 1.0],
            // White noise of known size: what the dwell's own Allan variance would give, exactly.
            mean_noise: [
                rate_sample_std_radps,
                rate_sample_std_radps,
                rate_sample_std_radps,
                force_sample_std_mps2,
                force_sample_std_mps2,
                force_sample_std_mps2,
            ]
            .map(|s| MeanNoise { white_equivalent_var: s * s, dof: samples as f32, cluster_samples: 1 }),
            allan: [DwellAllan::default(); 6],
        };
        run.inputs.push(PositionInput { c_b_n: attitude.c_b_n(), summary });
        run.dwells.push(ChannelDwell {
            tilt: attitude.tilt(),
            heading_rad: Some(attitude.heading_rad),
            rate_mean_b_radps: w,
            force_mean_b_mps2: f,
            rate_mean_var_b_radps2: [(rate_mean_std_radps * rate_mean_std_radps) as f32; 3],
            force_mean_var_b_mps2sq: [(force_mean_std_mps2 * force_mean_std_mps2) as f32; 3],
            window: None,
        });
    }
    run
}

/// Per candidate and bias (gyro x, y, z, accelerometer x, y, z): RMS error, RMS z, and how often the bias was
/// reported unobservable.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateStats {
    /// The candidate's name.
    pub name: String,
    /// RMS of estimate - truth, SI.
    pub rms_error_si: [f64; 6],
    /// RMS of (estimate - truth) / reported standard error.
    pub rms_z: [f64; 6],
    /// Runs in which the bias was reported unobservable.
    pub unobservable_runs: [usize; 6],
}

/// Runs `runs` draws of the lab through every candidate.
pub fn compare(lab: &Lab, candidates: &[Candidate], runs: usize, seed: u64) -> Vec<CandidateStats> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let told = Site {
        latitude_rad: (lab.latitude_deg as f32).to_radians(),
        gravity_mps2: (lab.gravity_mps2 + lab.gravity_error_mps2) as f32,
    };
    let mut sq = vec![[0.0f64; 6]; candidates.len()];
    let mut zsq = vec![[0.0f64; 6]; candidates.len()];
    let mut count = vec![[0usize; 6]; candidates.len()];
    let mut unobservable = vec![[0usize; 6]; candidates.len()];
    for _ in 0..runs {
        let run = draw(lab, &mut rng);
        for (c, candidate) in candidates.iter().enumerate() {
            let estimates = match candidate {
                Candidate::Angles => {
                    let settings = CalibrationSettings::default();
                    let r = calibrate_positions(&run.inputs, &told, &settings).expect("angle method");
                    Estimates::from_angles(&r.solution)
                }
                Candidate::Channels(model) => {
                    let mut est =
                        ChannelEstimator::new(told, ChannelSettings { model: *model, ..ChannelSettings::default() });
                    for d in &run.dwells {
                        est.add(*d).expect("dwell");
                    }
                    // As `calibrate` reports them: with the fit scale of each sensor.
                    Estimates::from_session(&est, &est.solve().expect("general estimator"), 0)
                }
            };
            for i in 0..6 {
                match (estimates.value_si[i], estimates.std_si[i]) {
                    (Some(v), Some(sd)) => {
                        let e = v - run.truth[i];
                        sq[c][i] += e * e;
                        zsq[c][i] += (e / sd) * (e / sd);
                        count[c][i] += 1;
                    }
                    _ => unobservable[c][i] += 1,
                }
            }
        }
    }
    candidates
        .iter()
        .enumerate()
        .map(|(c, candidate)| CandidateStats {
            name: candidate.name(),
            rms_error_si: [0, 1, 2, 3, 4, 5].map(|i| (sq[c][i] / count[c][i].max(1) as f64).sqrt()),
            rms_z: [0, 1, 2, 3, 4, 5].map(|i| (zsq[c][i] / count[c][i].max(1) as f64).sqrt()),
            unobservable_runs: unobservable[c],
        })
        .collect()
}

/// The comparison as a text table: RMS errors in deg/h and ug, RMS z.
pub fn table(stats: &[CandidateStats]) -> String {
    let mut out = String::from(
        "estimator                                    | RMS error gyro x, y, z [deg/h] | RMS error accel x, y, z [ug] | RMS z (6 biases)\n",
    );
    for s in stats {
        let g = [0, 1, 2].map(|i| s.rms_error_si[i] / DEG_PER_HOUR);
        let a = [3, 4, 5].map(|i| s.rms_error_si[i] / MICRO_G);
        let z: Vec<String> = s.rms_z.iter().map(|z| format!("{z:.2}")).collect();
        out.push_str(&format!(
            "{:<44} | {:>8.5} {:>8.5} {:>8.5}   | {:>7.2} {:>7.2} {:>7.2}     | {}\n",
            s.name,
            g[0],
            g[1],
            g[2],
            a[0],
            a[1],
            a[2],
            z.join(" ")
        ));
    }
    out
}
