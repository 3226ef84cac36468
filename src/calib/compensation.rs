//! Compensation of every sample on the device (docs/compensation.md): the inverse of the sensor model of
//! docs/conventions.md#sensor-model, in f32, with the inverses precomputed once.
//!
//! The model `w_meas = T_g w + b_g + G f`, `f_meas = T_a f + b_a`, `T = I + S + M`, is inverted as
//!
//! ```text
//! f = T_a^-1 (f_meas - b_a),        w = T_g^-1 (w_meas - b_g - G f)
//! ```
//!
//! with the compensated `f` in `G f`, exactly as the workstation's `sinscal apply` does it in f64
//! (docs/cli.md#apply). A term that was not estimated (or that the schedule could not determine) is the
//! identity (`T`) or zero (`b`, `G`). `T` is inverted once, when the compensation is made; a sample costs three
//! 3x3 matrix-vector products and nine subtractions, no division.
//!
//! Every constructor refuses what `sinscal apply` refuses: an entry of `S + M` beyond [`MAX_T_DEVIATION`], a
//! `det T` below [`MIN_T_DETERMINANT`], a bias or g-sensitivity beyond the plausible limits of any instrument,
//! and anything not finite. A compensation that exists therefore has finite, bounded coefficients.
//!
//! For the device's flash, [`Compensation::encode`] writes a fixed little-endian layout of [`ENCODED_BYTES`]
//! bytes (the layout version, then `b_g`, `b_a`, `T_a`, `T_g`, `G` as f32); [`Compensation::decode`] runs the
//! same checks and inverts `T` again, so a round trip is bit-exact (docs/compensation.md#encoding).

use crate::calib::angles::CalibrationResult;
use crate::calib::general::{
    g_sensitivity_radps_per_mps2, misalignment_index, parameter_name, sensor_matrix, ChannelSolution, Term, PARAMETERS,
};
use crate::math::linalg::{Mat3, Vec3};
use crate::sensor::sample::{ImuReading, ImuSample};

/// Largest accepted absolute value of an entry of `S + M` (a relative scale-factor error or a misalignment):
/// beyond it the calibration is not one of these axes (the limit of `sinscal apply`, docs/cli.md#apply).
pub const MAX_T_DEVIATION: f32 = 0.5;
/// Smallest accepted `det T`: below it `T` is singular, or (negative) reverses an axis.
pub const MIN_T_DETERMINANT: f32 = 1e-6;
/// Largest plausible gyro bias of any instrument, rad/s (the effect catalogue's limit, docs/cli.md#apply).
pub const MAX_GYRO_BIAS_RADPS: f32 = 0.1;
/// Largest plausible accelerometer bias, m/s^2.
pub const MAX_ACCEL_BIAS_MPS2: f32 = 2.0;
/// Largest plausible gyro g-sensitivity, (rad/s)/(m/s^2).
pub const MAX_G_SENSITIVITY_RADPS_PER_MPS2: f32 = 1e-3;

/// Version of the byte layout written by [`Compensation::encode`] (byte 0).
pub const LAYOUT_VERSION: u8 = 1;
/// Header bytes: the layout version and three reserved zero bytes (the values start 4-byte aligned).
const HEADER_BYTES: usize = 4;
/// f32 values stored: `b_g` 3, `b_a` 3, `T_a` 9, `T_g` 9, `G` 9.
const VALUES: usize = 33;
/// Length of the encoding, bytes.
pub const ENCODED_BYTES: usize = HEADER_BYTES + 4 * VALUES;

/// The sensor triad a matrix belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Triad {
    /// The gyros (`T_g`).
    Gyro,
    /// The accelerometers (`T_a`).
    Accel,
}

/// Why a compensation was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CompensationError {
    /// A parameter is not finite or beyond its plausible limit: a bias, a g-sensitivity, or an entry of
    /// `S + M` (a scale factor or misalignment: then `T` is far from the identity).
    Implausible {
        /// The parameter, as an index of the core's layout ([`parameter_name`]).
        parameter: usize,
        /// Its value, SI (for `S + M` the deviation from the identity).
        value: f32,
        /// The limit of its absolute value.
        limit: f32,
    },
    /// `det T` is below [`MIN_T_DETERMINANT`] (or not finite): `T` cannot be inverted.
    Singular {
        /// Which sensor's `T`.
        triad: Triad,
        /// Its determinant.
        det: f32,
    },
}

impl core::fmt::Display for CompensationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            CompensationError::Implausible { parameter, value, limit } => write!(
                f,
                "{} = {value:e} is not finite or beyond the plausible {limit:e} (SI units): not a calibration of \
                 this instrument",
                parameter_name(parameter)
            ),
            CompensationError::Singular { triad, det } => write!(
                f,
                "T_{} = I + S + M is singular (det {det:e}, at least {MIN_T_DETERMINANT:e} is needed): it cannot be \
                 inverted",
                match triad {
                    Triad::Gyro => "g",
                    Triad::Accel => "a",
                }
            ),
        }
    }
}

impl core::error::Error for CompensationError {}

/// The compensation of one IMU: the model's terms and the precomputed inverses, f32. Made only by the
/// constructors, which check every term; its coefficients are then finite and bounded.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Compensation {
    gyro_bias_b_radps: Vec3,
    accel_bias_b_mps2: Vec3,
    accel_t: Mat3,
    gyro_t: Mat3,
    accel_t_inv: Mat3,
    gyro_t_inv: Mat3,
    gyro_g_sensitivity_radps_per_mps2: Mat3,
}

impl Compensation {
    /// No compensation: zero biases and g-sensitivity, `T = I`. It returns every finite sample unchanged.
    pub const IDENTITY: Compensation = Compensation {
        gyro_bias_b_radps: [0.0; 3],
        accel_bias_b_mps2: [0.0; 3],
        accel_t: Mat3::IDENTITY,
        gyro_t: Mat3::IDENTITY,
        accel_t_inv: Mat3::IDENTITY,
        gyro_t_inv: Mat3::IDENTITY,
        gyro_g_sensitivity_radps_per_mps2: Mat3([[0.0; 3]; 3]),
    };

    /// The compensation of a sensor model: gyro bias `b_g` (body, rad/s), accelerometer bias `b_a` (body,
    /// m/s^2), `T_a` and `T_g` (`I + S + M`, row i, column j: axis i's output per unit input along j), and `G`
    /// (row i, column j: gyro i's rate error per unit specific force along j, (rad/s)/(m/s^2)). Inverts both
    /// `T` once; refuses what is not finite, beyond the plausible limits or singular.
    pub fn from_model(
        gyro_bias_b_radps: Vec3,
        accel_bias_b_mps2: Vec3,
        accel_t: &Mat3,
        gyro_t: &Mat3,
        gyro_g_sensitivity_radps_per_mps2: &Mat3,
    ) -> Result<Compensation, CompensationError> {
        let (gyro_bias, accel_bias) = (Term::GyroBias.parameters().0, Term::AccelBias.parameters().0);
        let g_first = Term::GyroGSensitivity.parameters().0;
        for i in 0..3 {
            check(gyro_bias + i, gyro_bias_b_radps[i], MAX_GYRO_BIAS_RADPS)?;
            check(accel_bias + i, accel_bias_b_mps2[i], MAX_ACCEL_BIAS_MPS2)?;
            for j in 0..3 {
                check(
                    g_first + 3 * i + j,
                    gyro_g_sensitivity_radps_per_mps2.0[i][j],
                    MAX_G_SENSITIVITY_RADPS_PER_MPS2,
                )?;
            }
        }
        let accel_t_inv = invert(accel_t, Triad::Accel)?;
        let gyro_t_inv = invert(gyro_t, Triad::Gyro)?;
        Ok(Compensation {
            gyro_bias_b_radps,
            accel_bias_b_mps2,
            accel_t: *accel_t,
            gyro_t: *gyro_t,
            accel_t_inv,
            gyro_t_inv,
            gyro_g_sensitivity_radps_per_mps2: *gyro_g_sensitivity_radps_per_mps2,
        })
    }

    /// The compensation of parameters in the core's layout ([`parameter_name`], SI units): biases, scale
    /// factors, misalignments and g-sensitivity; the reference offset (a property of the turntable, not of the
    /// sensor) is not used.
    pub fn from_parameters(theta: &[f32; PARAMETERS]) -> Result<Compensation, CompensationError> {
        let (gb, ab) = (Term::GyroBias.parameters().0, Term::AccelBias.parameters().0);
        let triad = |v: usize| [theta[v], theta[v + 1], theta[v + 2]];
        Compensation::from_model(
            triad(gb),
            triad(ab),
            &sensor_matrix(theta, Term::AccelScaleFactor.parameters().0, Term::AccelMisalignment.parameters().0),
            &sensor_matrix(theta, Term::GyroScaleFactor.parameters().0, Term::GyroMisalignment.parameters().0),
            &g_sensitivity_radps_per_mps2(theta),
        )
    }

    /// The compensation of a general-estimator solution: every parameter it determined; a term not in its
    /// model, and a parameter the schedule could not determine, are the identity or zero (as `sinscal apply`
    /// takes a `null` of the calibration JSON).
    pub fn from_channels(solution: &ChannelSolution) -> Result<Compensation, CompensationError> {
        let mut theta = [0.0f32; PARAMETERS];
        for (i, x) in theta.iter_mut().enumerate() {
            if solution.observable & (1 << i) != 0 {
                *x = solution.parameters_si[i];
            }
        }
        Compensation::from_parameters(&theta)
    }

    /// The compensation of an angle-method calibration: its biases (an undetermined one is zero), `T = I`,
    /// `G = 0`.
    pub fn from_angles(result: &CalibrationResult) -> Result<Compensation, CompensationError> {
        let s = &result.solution;
        let value = |e: Option<crate::calib::angles::Estimate>| e.map_or(0.0, |e| e.value);
        Compensation::from_model(
            s.gyro_bias_b_radps.map(value),
            s.accel_bias_b_mps2.map(value),
            &Mat3::IDENTITY,
            &Mat3::IDENTITY,
            &Mat3([[0.0; 3]; 3]),
        )
    }

    /// The compensated sample: `f = T_a^-1 (f_meas - b_a)`, then `w = T_g^-1 (w_meas - b_g - G f)` with that
    /// `f`. Body frame, SI units; no division.
    #[inline]
    pub fn apply(&self, sample: &ImuSample) -> ImuSample {
        let (f_meas, w_meas) = (sample.force_b_mps2, sample.rate_b_radps);
        let (b_a, b_g) = (self.accel_bias_b_mps2, self.gyro_bias_b_radps);
        let force_b_mps2 = mul_vec(&self.accel_t_inv, [f_meas[0] - b_a[0], f_meas[1] - b_a[1], f_meas[2] - b_a[2]]);
        let gf = mul_vec(&self.gyro_g_sensitivity_radps_per_mps2, force_b_mps2);
        let rate_b_radps = mul_vec(
            &self.gyro_t_inv,
            [w_meas[0] - b_g[0] - gf[0], w_meas[1] - b_g[1] - gf[1], w_meas[2] - b_g[2] - gf[2]],
        );
        ImuSample { rate_b_radps, force_b_mps2 }
    }

    /// A reading with its sample compensated ([`Compensation::apply`]); counter, missed samples and temperature
    /// are copied unchanged.
    pub fn apply_reading(&self, reading: &ImuReading) -> ImuReading {
        ImuReading { sample: self.apply(&reading.sample), ..*reading }
    }

    /// Gyro bias `b_g`, body, rad/s.
    pub fn gyro_bias_b_radps(&self) -> Vec3 {
        self.gyro_bias_b_radps
    }

    /// Accelerometer bias `b_a`, body, m/s^2.
    pub fn accel_bias_b_mps2(&self) -> Vec3 {
        self.accel_bias_b_mps2
    }

    /// `T_a = I + S_a + M_a`.
    pub fn accel_t(&self) -> Mat3 {
        self.accel_t
    }

    /// `T_g = I + S_g + M_g`.
    pub fn gyro_t(&self) -> Mat3 {
        self.gyro_t
    }

    /// `T_a^-1`, computed once by the adjugate.
    pub fn accel_t_inv(&self) -> Mat3 {
        self.accel_t_inv
    }

    /// `T_g^-1`.
    pub fn gyro_t_inv(&self) -> Mat3 {
        self.gyro_t_inv
    }

    /// `G`, (rad/s)/(m/s^2), row i = gyro i.
    pub fn gyro_g_sensitivity_radps_per_mps2(&self) -> Mat3 {
        self.gyro_g_sensitivity_radps_per_mps2
    }

    /// The stored values in layout order: `b_g`, `b_a`, `T_a` (row-major), `T_g`, `G`.
    fn values(&self) -> [f32; VALUES] {
        let mut v = [0.0f32; VALUES];
        let all = self
            .gyro_bias_b_radps
            .iter()
            .chain(&self.accel_bias_b_mps2)
            .chain(self.accel_t.0.iter().flatten())
            .chain(self.gyro_t.0.iter().flatten())
            .chain(self.gyro_g_sensitivity_radps_per_mps2.0.iter().flatten());
        for (slot, x) in v.iter_mut().zip(all) {
            *slot = *x;
        }
        v
    }

    /// Writes the fixed little-endian layout (docs/compensation.md#encoding): byte 0 the layout version
    /// ([`LAYOUT_VERSION`]), bytes 1 to 3 zero, then 33 f32 values, 4 bytes each: `b_g` (x, y, z), `b_a`,
    /// `T_a` row by row, `T_g`, `G`. The inverses are not stored: [`Compensation::decode`] computes them again.
    pub fn encode(&self, out: &mut [u8; ENCODED_BYTES]) {
        let (header, body) = out.split_at_mut(HEADER_BYTES);
        header.copy_from_slice(&[LAYOUT_VERSION, 0, 0, 0]);
        for (chunk, x) in body.chunks_exact_mut(4).zip(self.values()) {
            chunk.copy_from_slice(&x.to_le_bytes());
        }
    }

    /// Reads the layout of [`Compensation::encode`]: exactly [`ENCODED_BYTES`] bytes, the current layout
    /// version, zero reserved bytes, and values that pass every check of [`Compensation::from_model`] (finite,
    /// plausible, `T` invertible). `None` otherwise. The encoding carries no checksum: the stored record that
    /// holds it does.
    pub fn decode(bytes: &[u8]) -> Option<Compensation> {
        let [LAYOUT_VERSION, 0, 0, 0, body @ ..] = bytes else { return None };
        if body.len() != 4 * VALUES {
            return None;
        }
        let mut v = [0.0f32; VALUES];
        for (x, chunk) in v.iter_mut().zip(body.chunks_exact(4)) {
            *x = f32::from_le_bytes(<[u8; 4]>::try_from(chunk).ok()?);
        }
        let matrix = |first: usize| Mat3(core::array::from_fn(|i| core::array::from_fn(|j| v[first + 3 * i + j])));
        Compensation::from_model([v[0], v[1], v[2]], [v[3], v[4], v[5]], &matrix(6), &matrix(15), &matrix(24)).ok()
    }
}

/// `m v`, the sums in the order of [`Mat3::mul_vec`] (bit-identical to it), always inlined: the per-sample path
/// keeps the values in registers instead of passing arrays through memory to a call.
#[inline(always)]
fn mul_vec(m: &Mat3, v: Vec3) -> Vec3 {
    let r = &m.0;
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2],
    ]
}

/// Refuses a value that is not finite or whose magnitude exceeds `limit`.
fn check(parameter: usize, value: f32, limit: f32) -> Result<(), CompensationError> {
    // NaN fails the comparison too.
    if value.abs() <= limit {
        Ok(())
    } else {
        Err(CompensationError::Implausible { parameter, value, limit })
    }
}

/// `T^-1` after the checks of `sinscal apply`: every entry of `S + M` within [`MAX_T_DEVIATION`], `det T` at
/// least [`MIN_T_DETERMINANT`], and a finite inverse.
fn invert(t: &Mat3, triad: Triad) -> Result<Mat3, CompensationError> {
    let (scale_first, misalignment_first) = match triad {
        Triad::Gyro => (Term::GyroScaleFactor.parameters().0, Term::GyroMisalignment.parameters().0),
        Triad::Accel => (Term::AccelScaleFactor.parameters().0, Term::AccelMisalignment.parameters().0),
    };
    for i in 0..3 {
        for j in 0..3 {
            let (parameter, deviation) = if i == j {
                (scale_first + i, t.0[i][j] - 1.0)
            } else {
                (misalignment_first + misalignment_index(i, j), t.0[i][j])
            };
            check(parameter, deviation, MAX_T_DEVIATION)?;
        }
    }
    let det = t.det();
    let singular = CompensationError::Singular { triad, det };
    if det.is_nan() || det < MIN_T_DETERMINANT {
        return Err(singular);
    }
    // Entries within 0.5 of the identity and det >= 1e-6 bound the inverse's entries by 4.5e6: it is finite.
    t.inverse().filter(Mat3::is_finite).ok_or(singular)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model with every term non-zero, of both signs.
    fn model() -> (Vec3, Vec3, Mat3, Mat3, Mat3) {
        (
            [3.0e-5, -2.0e-5, 1.0e-5],
            [2.5e-3, -1.7e-3, 4.1e-3],
            Mat3([[1.0003, 2.0e-4, -3.0e-4], [-1.5e-4, 0.9995, 4.0e-4], [2.5e-4, -3.5e-4, 1.0008]]),
            Mat3([[0.9994, -1.0e-3, 5.0e-4], [7.0e-4, 1.0004, -2.0e-4], [-4.0e-4, 9.0e-4, 1.0002]]),
            Mat3([[1.0e-5, -2.0e-5, 3.0e-5], [-4.0e-5, 5.0e-6, 6.0e-5], [2.0e-5, -7.0e-5, -1.0e-5]]),
        )
    }

    fn full() -> Compensation {
        let (b_g, b_a, t_a, t_g, g) = model();
        Compensation::from_model(b_g, b_a, &t_a, &t_g, &g).unwrap()
    }

    fn bits(c: &Compensation) -> [u32; VALUES] {
        c.values().map(f32::to_bits)
    }

    #[test]
    fn identity_returns_the_sample() {
        let s = ImuSample { rate_b_radps: [0.3, -1.2e-4, 7.0], force_b_mps2: [-0.5, 9.81, -30.0] };
        assert_eq!(Compensation::IDENTITY.apply(&s), s);
        let none = Compensation::from_parameters(&[0.0; PARAMETERS]).unwrap();
        assert_eq!(none, Compensation::IDENTITY);
        let r = ImuReading { sample: s, counter: 7, missed: 2, temperature_c: 31.5 };
        let out = full().apply_reading(&r);
        assert_eq!((out.counter, out.missed, out.temperature_c), (7, 2, 31.5));
        assert_eq!(out.sample, full().apply(&s));
    }

    #[test]
    fn inverse_is_the_inverse() {
        let c = full();
        for (t, t_inv) in [(c.accel_t(), c.accel_t_inv()), (c.gyro_t(), c.gyro_t_inv())] {
            let p = t.mul(&t_inv);
            for i in 0..3 {
                for j in 0..3 {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((p.0[i][j] - want).abs() < 2.5e-7, "{p:?}");
                }
            }
        }
    }

    #[test]
    fn round_trip_is_bit_exact() {
        let c = full();
        let mut bytes = [0u8; ENCODED_BYTES];
        c.encode(&mut bytes);
        assert_eq!(&bytes[..4], &[LAYOUT_VERSION, 0, 0, 0]);
        // b_g x at bytes 4..8, little-endian.
        assert_eq!(bytes[4..8], 3.0e-5f32.to_le_bytes());
        let back = Compensation::decode(&bytes).unwrap();
        assert_eq!(bits(&back), bits(&c));
        for (a, b) in [(back.accel_t_inv, c.accel_t_inv), (back.gyro_t_inv, c.gyro_t_inv)] {
            assert_eq!(a.0.map(|r| r.map(f32::to_bits)), b.0.map(|r| r.map(f32::to_bits)));
        }
        let mut again = [0u8; ENCODED_BYTES];
        back.encode(&mut again);
        assert_eq!(again, bytes);
        let mut id = [0u8; ENCODED_BYTES];
        Compensation::IDENTITY.encode(&mut id);
        assert_eq!(Compensation::decode(&id), Some(Compensation::IDENTITY));
    }

    #[test]
    fn decode_refuses_bad_bytes() {
        let mut good = [0u8; ENCODED_BYTES];
        full().encode(&mut good);
        assert!(Compensation::decode(&good[..ENCODED_BYTES - 1]).is_none(), "short");
        assert!(Compensation::decode(&[]).is_none(), "empty");
        let mut long = [0u8; ENCODED_BYTES + 1];
        long[..ENCODED_BYTES].copy_from_slice(&good);
        assert!(Compensation::decode(&long).is_none(), "long");
        let corrupt = |at: usize, bytes: [u8; 4]| {
            let mut b = good;
            b[at..at + 4].copy_from_slice(&bytes);
            Compensation::decode(&b)
        };
        assert!(corrupt(0, [LAYOUT_VERSION + 1, 0, 0, 0]).is_none(), "version");
        assert!(corrupt(0, [LAYOUT_VERSION, 0, 1, 0]).is_none(), "reserved");
        // Every value position refuses NaN and infinity.
        for k in 0..VALUES {
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                assert!(corrupt(HEADER_BYTES + 4 * k, bad.to_le_bytes()).is_none(), "value {k}: {bad}");
            }
        }
        // A bias whose exponent is flipped, a scale factor far from 1, a singular T_a.
        assert!(corrupt(4, 3.0e25f32.to_le_bytes()).is_none());
        assert!(corrupt(HEADER_BYTES + 4 * 6, 1.6f32.to_le_bytes()).is_none());
        let mut singular = good;
        for (k, x) in [0.5f32, 0.5, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 1.0].iter().enumerate() {
            let at = HEADER_BYTES + 4 * (6 + k);
            singular[at..at + 4].copy_from_slice(&x.to_le_bytes());
        }
        assert!(Compensation::decode(&singular).is_none(), "singular");
        assert!(Compensation::decode(&good).is_some());
    }

    #[test]
    fn constructors_refuse_what_apply_refuses() {
        let (b_g, b_a, t_a, t_g, g) = model();
        let mut bad_bias = b_g;
        bad_bias[1] = f32::NAN;
        let e = Compensation::from_model(bad_bias, b_a, &t_a, &t_g, &g).unwrap_err();
        assert!(matches!(e, CompensationError::Implausible { parameter: 1, .. }), "{e:?}");
        let mut far = t_g;
        far.0[2][0] = -0.6;
        let e = Compensation::from_model(b_g, b_a, &t_a, &far, &g).unwrap_err();
        assert!(
            matches!(e, CompensationError::Implausible { parameter, .. } if parameter_name(parameter) == "gyro_misalignment_zx")
        );
        let mut big_scale = t_a;
        big_scale.0[1][1] = 1.5001;
        let e = Compensation::from_model(b_g, b_a, &big_scale, &t_g, &g).unwrap_err();
        assert!(
            matches!(e, CompensationError::Implausible { parameter, .. } if parameter_name(parameter) == "accel_scale_factor_y")
        );
        // Singular (det 0) although every entry is within 0.5 of the identity.
        let singular = Mat3([[0.5, 0.5, 0.0], [0.5, 0.5, 0.0], [0.0, 0.0, 1.0]]);
        let e = Compensation::from_model(b_g, b_a, &singular, &t_g, &g).unwrap_err();
        assert!(matches!(e, CompensationError::Singular { triad: Triad::Accel, .. }), "{e:?}");
        let mut big_g = g;
        big_g.0[1][2] = 2e-3;
        let e = Compensation::from_model(b_g, b_a, &t_a, &t_g, &big_g).unwrap_err();
        assert!(
            matches!(e, CompensationError::Implausible { parameter, .. } if parameter_name(parameter) == "gyro_g_sensitivity_yz")
        );
        let mut big_accel = b_a;
        big_accel[2] = -2.5;
        assert!(Compensation::from_model(b_g, big_accel, &t_a, &t_g, &g).is_err());
    }

    #[test]
    fn parameters_enter_where_the_layout_says() {
        // accel_misalignment_xy is T_a[0][1]; gyro_g_sensitivity_zx is G[2][0]; the offset is ignored.
        let mut theta = [0.0f32; PARAMETERS];
        theta[9] = 1e-3;
        theta[30] = -2e-5;
        theta[33] = 0.4;
        let c = Compensation::from_parameters(&theta).unwrap();
        assert_eq!(c.accel_t().0[0][1], 1e-3);
        assert_eq!(c.accel_t().0[1][0], 0.0);
        assert_eq!(c.gyro_g_sensitivity_radps_per_mps2().0[2][0], -2e-5);
        assert_eq!(c.gyro_t(), Mat3::IDENTITY);
    }
}
