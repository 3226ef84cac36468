//! SIMULATION: multi-position turntable data with known biases, for the built-in example, the tests and
//! the Monte Carlo. The truth is computed in f64 with its own rotation code, written from docs/conventions.md
//! independently of the core's f32 implementation, so that a test of the core against it is a
//! test of the conventions, not of the code against itself.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::io::recording::{Header, Recording, Row, SimulationTruth};
use crate::model::sensor::Triad;

/// Earth rotation rate, rad/s (docs/conventions.md).
pub const EARTH_RATE_RADPS: f64 = 7.292115e-5;

/// Earth rate in the navigation frame (East-North-Up) at latitude `latitude_rad`, rad/s:
/// `[0, W cos L, W sin L]` (docs/conventions.md).
pub fn earth_rate_n_radps(latitude_rad: f64) -> [f64; 3] {
    [0.0, EARTH_RATE_RADPS * latitude_rad.cos(), EARTH_RATE_RADPS * latitude_rad.sin()]
}
/// 1 deg/h in rad/s.
pub const DEG_PER_HOUR: f64 = std::f64::consts::PI / 180.0 / 3600.0;
/// 1 ug in m/s^2 (docs/conventions.md#units: 1 ug = 9.80665e-6 m/s^2).
pub const MICRO_G: f64 = 9.80665e-6;

/// A 3x3 matrix, row-major, f64.
pub type M3 = [[f64; 3]; 3];

/// `a * b`.
pub fn mul(a: &M3, b: &M3) -> M3 {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// `a^T`.
pub fn transpose(a: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| a[j][i]))
}

/// `a x b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `a * v`.
pub fn mul_vec(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

/// `a^T * v`.
pub fn mul_t_vec(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[k][i] * v[k]).sum())
}

/// Right-handed rotation of vectors by the angle `|v|` about the axis `v` (Rodrigues).
pub fn rotation(v: [f64; 3]) -> M3 {
    let t = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if t == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let k = [v[0] / t, v[1] / t, v[2] / t];
    let (s, c) = t.sin_cos();
    let mut r = [[0.0; 3]; 3];
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            r[i][j] = id * c + s * kx[i][j] + (1.0 - c) * k[i] * k[j];
        }
    }
    r
}

/// The rotation vector of `r` (inverse of [`rotation`]), any angle below pi.
pub fn rotation_vector(r: &M3) -> [f64; 3] {
    let v = [r[2][1] - r[1][2], r[0][2] - r[2][0], r[1][0] - r[0][1]];
    let s = 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let c = 0.5 * (r[0][0] + r[1][1] + r[2][2] - 1.0);
    let angle = s.atan2(c);
    let k = if s > 1e-300 { angle / (2.0 * s) } else { 0.5 };
    v.map(|x| x * k)
}

/// `C_b^n` from turntable angles in degrees: heading clockwise from north is a rotation by -heading about
/// up, pitch a rotation about body x, roll about body y (docs/conventions.md).
///
/// At multiples of 90 degrees (where turntable positions usually are) the sines and cosines are exact, as in
/// the core's frames: roll 270 and roll -90 give the same matrix, with exact zeros, not `cos = -1.8e-16`.
pub fn c_b_n(pitch_deg: f64, roll_deg: f64, heading_deg: f64) -> M3 {
    let about = |axis: usize, deg: f64| -> M3 {
        let (s, c) = sin_cos_deg(deg);
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut r = [[0.0; 3]; 3];
        r[axis][axis] = 1.0;
        r[i][i] = c;
        r[j][j] = c;
        r[i][j] = -s;
        r[j][i] = s;
        r
    };
    mul(&mul(&about(2, -heading_deg), &about(0, pitch_deg)), &about(1, roll_deg))
}

/// sin and cos of an angle in degrees, exact at multiples of 90 degrees.
pub fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let quarter = deg / 90.0;
    let nearest = quarter.round();
    if (quarter - nearest).abs() < 1e-12 {
        match (nearest as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        deg.to_radians().sin_cos()
    }
}

/// A simulated multi-position session with constant biases and white noise.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Latitude, degrees north.
    pub latitude_deg: f64,
    /// Height, m.
    pub height_m: f64,
    /// Magnitude of gravity, m/s^2 (written to the header).
    pub gravity_mps2: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Dwell length, s.
    pub dwell_s: f64,
    /// Rows with `pos = 0` between dwells (turntable moving or settling), s. They carry the attitude of
    /// the next position and are ignored by calibration.
    pub settle_s: f64,
    /// Turntable positions (pitch, roll, heading), degrees.
    pub positions_deg: Vec<[f64; 3]>,
    /// Gyro bias, body frame, rad/s.
    pub gyro_bias_b_radps: [f64; 3],
    /// Accelerometer bias, body frame, m/s^2.
    pub accel_bias_b_mps2: [f64; 3],
    /// White noise, standard deviation of one gyro sample, rad/s.
    pub gyro_noise_radps: f64,
    /// White noise, standard deviation of one accelerometer sample, m/s^2.
    pub accel_noise_mps2: f64,
    /// Constant error of the turntable reference `phi0` (e, n, u), rad: the reported attitude is the true
    /// one seen through `C_ref = (I + [phi0 x]) C_true` to first order, so alignment shows `+phi0`.
    pub reference_offset_n_rad: [f64; 3],
}

/// The six positions of the paper's Table 1 (pitch, roll, heading), degrees.
pub const TABLE1_DEG: [[f64; 3]; 6] =
    [[0.0, 0.0, 0.0], [0.0, 0.0, 180.0], [0.0, 0.0, 90.0], [0.0, 0.0, 270.0], [0.0, 90.0, 0.0], [0.0, 270.0, 0.0]];

impl Scenario {
    /// Table 1 at the paper's site (45.7796 N), 1 minute per position at 100 Hz, no noise, no biases.
    pub fn table1_exact() -> Scenario {
        let latitude_deg = 45.7796;
        Scenario {
            latitude_deg,
            height_m: 0.0,
            gravity_mps2: sinscal::nav::earth::normal_gravity_mps2((latitude_deg as f32).to_radians(), 0.0) as f64,
            rate_hz: 100.0,
            dwell_s: 60.0,
            settle_s: 2.0,
            positions_deg: TABLE1_DEG.to_vec(),
            gyro_bias_b_radps: [0.0; 3],
            accel_bias_b_mps2: [0.0; 3],
            gyro_noise_radps: 0.0,
            accel_noise_mps2: 0.0,
            reference_offset_n_rad: [0.0; 3],
        }
    }

    /// The built-in example: Table 1 with biases of both signs, white noise at the level of a
    /// navigation-grade IMU (gyro 0.1 deg/h, accelerometer 1 mg per 100 Hz sample), and a small
    /// turntable base error.
    pub fn example() -> Scenario {
        Scenario {
            gyro_bias_b_radps: [0.05 * DEG_PER_HOUR, -0.03 * DEG_PER_HOUR, 0.02 * DEG_PER_HOUR],
            accel_bias_b_mps2: [100.0 * MICRO_G, -80.0 * MICRO_G, 50.0 * MICRO_G],
            gyro_noise_radps: 0.1 * DEG_PER_HOUR,
            accel_noise_mps2: 1000.0 * MICRO_G,
            reference_offset_n_rad: [3.0 / 206_264.8, -2.0 / 206_264.8, 10.0 / 206_264.8],
            ..Scenario::table1_exact()
        }
    }

    /// Samples per dwell.
    pub fn dwell_samples(&self) -> usize {
        (self.dwell_s * self.rate_hz).round() as usize
    }

    /// The exact (noise-free) measurement at a position: `(rate_b_radps, force_b_mps2)`.
    pub fn exact_sample(&self, position_deg: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let [p, r, h] = position_deg;
        let c_ref = c_b_n(p, r, h);
        // C_true = R(-phi0) C_ref, so that C_ref = (I + [phi0 x]) C_true to first order.
        let offset = self.reference_offset_n_rad.map(|x| -x);
        let c_true = mul(&rotation(offset), &c_ref);
        let lat = self.latitude_deg.to_radians();
        let w_n = earth_rate_n_radps(lat);
        let f_n = [0.0, 0.0, self.gravity_mps2];
        let w_b = mul_t_vec(&c_true, w_n);
        let f_b = mul_t_vec(&c_true, f_n);
        // Biases only: T = I, no g-sensitivity (the sensor model of crate::model::sensor).
        let zero = [[0.0; 3]; 3];
        let gyro = Triad::new(self.gyro_bias_b_radps, [0.0; 3], &zero, zero);
        let accel = Triad::new(self.accel_bias_b_mps2, [0.0; 3], &zero, zero);
        (gyro.measure(w_b, f_b), accel.measure(f_b, [0.0; 3]))
    }

    /// Calls `sink(position_index, rate_b_radps, force_b_mps2)` for every sample of every dwell, with
    /// white Gaussian noise drawn from a ChaCha8 generator seeded with `seed`.
    pub fn for_each_sample(&self, seed: u64, mut sink: impl FnMut(usize, [f64; 3], [f64; 3])) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let unit = Normal::new(0.0, 1.0).expect("unit normal");
        for (k, &position) in self.positions_deg.iter().enumerate() {
            let (w, f) = self.exact_sample(position);
            for _ in 0..self.dwell_samples() {
                let mut noisy_w = w;
                let mut noisy_f = f;
                for i in 0..3 {
                    noisy_w[i] += self.gyro_noise_radps * unit.sample(&mut rng);
                    noisy_f[i] += self.accel_noise_mps2 * unit.sample(&mut rng);
                }
                sink(k, noisy_w, noisy_f);
            }
        }
    }

    /// The true errors, as written into a recording's header.
    pub fn truth(&self, seed: u64) -> SimulationTruth {
        SimulationTruth {
            seed,
            gyro_bias_b_radps: self.gyro_bias_b_radps,
            accel_bias_b_mps2: self.accel_bias_b_mps2,
            gyro_noise_radps: self.gyro_noise_radps,
            accel_noise_mps2: self.accel_noise_mps2,
            reference_offset_n_rad: self.reference_offset_n_rad,
        }
    }

    /// The session as a recording: dwells labelled 1..n, `settle_s` of `pos = 0` rows before each.
    pub fn recording(&self, seed: u64, source: &str) -> Recording {
        let dt = 1.0 / self.rate_hz;
        let settle = (self.settle_s * self.rate_hz).round() as usize;
        let mut rows = Vec::new();
        let mut tick = 0u64;
        let mut push = |rows: &mut Vec<Row>, pos: u32, position: [f64; 3], w: [f64; 3], f: [f64; 3]| {
            rows.push(Row {
                t_s: tick as f64 * dt,
                pos,
                pitch_deg: position[0],
                roll_deg: position[1],
                heading_deg: Some(position[2]),
                rate_b_radps: w,
                force_b_mps2: f,
                temp_c: None,
                turn_axis: None,
                line: 0,
            });
            tick += 1;
        };
        let mut current = usize::MAX;
        self.for_each_sample(seed, |k, w, f| {
            let position = self.positions_deg[k];
            if k != current {
                current = k;
                let (w0, f0) = self.exact_sample(position);
                for _ in 0..settle {
                    push(&mut rows, 0, position, w0, f0);
                }
            }
            push(&mut rows, k as u32 + 1, position, w, f);
        });
        Recording {
            source: source.to_string(),
            header: Header {
                latitude_deg: self.latitude_deg,
                height_m: self.height_m,
                rate_hz: Some(self.rate_hz),
                gravity_mps2: Some(self.gravity_mps2),
                comments: vec![format!(
                    "SIMULATION by sinscal (seed {seed}), not measured data; truth_* keys give its errors"
                )],
                truth: Some(self.truth(seed)),
                pose_tolerance_deg: None,
            },
            rows,
            has_gyro: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_check_values_in_f64() {
        let c = c_b_n(0.0, 0.0, 90.0);
        let y = mul_vec(&c, [0.0, 1.0, 0.0]);
        assert!((y[0] - 1.0).abs() < 1e-15 && y[1].abs() < 1e-15);
        let c = c_b_n(0.0, 90.0, 0.0);
        let x = mul_vec(&c, [1.0, 0.0, 0.0]);
        let z = mul_vec(&c, [0.0, 0.0, 1.0]);
        assert!((x[2] + 1.0).abs() < 1e-15 && (z[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn quarter_turns_are_exact_and_agree_with_the_axis_angle_rotation() {
        // Roll 270 and roll -90 are one attitude: the same matrix, bit for bit, with exact zeros.
        assert_eq!(c_b_n(0.0, 270.0, 0.0), c_b_n(0.0, -90.0, 0.0));
        assert_eq!(c_b_n(0.0, 270.0, 0.0)[0][0], 0.0);
        assert_eq!(c_b_n(180.0, 0.0, 450.0), c_b_n(-180.0, 0.0, 90.0));
        // Elsewhere the matrix is the product of axis-angle rotations (heading -psi about up).
        for [p, r, h] in [[12.5, -33.0, 250.0], [90.0, 45.0, 10.0], [0.3, 179.9, -0.1]] {
            let about = |axis: usize, deg: f64| {
                let mut v = [0.0; 3];
                v[axis] = deg.to_radians();
                rotation(v)
            };
            let want = mul(&mul(&about(2, -h), &about(0, p)), &about(1, r));
            let got = c_b_n(p, r, h);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((got[i][j] - want[i][j]).abs() < 1e-15, "{p} {r} {h}");
                }
            }
        }
    }

    #[test]
    fn truth_round_trips_through_the_header() {
        let s = Scenario { dwell_s: 0.2, ..Scenario::example() };
        let rec = s.recording(9, "a");
        let back = Recording::parse(&rec.to_csv(), "a").unwrap();
        assert_eq!(back.header.truth, Some(s.truth(9)));
        let broken = rec.to_csv().replace("# truth_accel_noise_mps2", "# truth_accel_noisy");
        let e = Recording::parse(&broken, "a").unwrap_err().to_string();
        assert!(e.contains("no 'truth_accel_noise_mps2'"), "{e}");
    }

    #[test]
    fn recording_is_reproducible_from_the_seed() {
        let s = Scenario { dwell_s: 1.0, ..Scenario::example() };
        assert_eq!(s.recording(5, "a").to_csv(), s.recording(5, "a").to_csv());
        assert_ne!(s.recording(5, "a").to_csv(), s.recording(6, "a").to_csv());
    }
}
