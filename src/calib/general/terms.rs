//! The sensor model's terms: [`Term`], a set of them ([`Model`]), the parameters' names, order and plausible
//! magnitudes, the gauge parameters, and the bit of each term in a stored model.

/// Parameters of the full model: gyro bias 3, accelerometer bias 3, accelerometer scale factor 3 and
/// misalignment 6, gyro scale factor 3 and misalignment 6, gyro g-sensitivity 9, reference offset 3.
pub const PARAMETERS: usize = 36;

/// A term of the sensor model (docs/conventions.md#sensor-model), named as in the effect catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Term {
    /// Gyro bias `b_g`, rad/s (x, y, z).
    GyroBias,
    /// Accelerometer bias `b_a`, m/s^2.
    AccelBias,
    /// Accelerometer scale factors (diagonal of `S_a`), 1.
    AccelScaleFactor,
    /// Accelerometer misalignments (off-diagonal `M_a`: axis i's sensitivity to force along j), 1.
    AccelMisalignment,
    /// Gyro scale factors, 1.
    GyroScaleFactor,
    /// Gyro misalignments, 1.
    GyroMisalignment,
    /// Gyro g-sensitivity `G`, (rad/s)/(m/s^2), all nine entries.
    GyroGSensitivity,
    /// Constant reference (turntable base) offset `delta` about e, n, u, rad.
    ReferenceOffset,
}

impl Term {
    /// Every term in parameter order.
    pub const ALL: [Term; 8] = [
        Term::GyroBias,
        Term::AccelBias,
        Term::AccelScaleFactor,
        Term::AccelMisalignment,
        Term::GyroScaleFactor,
        Term::GyroMisalignment,
        Term::GyroGSensitivity,
        Term::ReferenceOffset,
    ];

    /// The catalogue name (docs/formats.md#effect-catalogue).
    pub fn name(self) -> &'static str {
        match self {
            Term::GyroBias => "gyro_bias",
            Term::AccelBias => "accel_bias",
            Term::AccelScaleFactor => "accel_scale_factor",
            Term::AccelMisalignment => "accel_misalignment",
            Term::GyroScaleFactor => "gyro_scale_factor",
            Term::GyroMisalignment => "gyro_misalignment",
            Term::GyroGSensitivity => "gyro_g_sensitivity",
            Term::ReferenceOffset => "reference_offset",
        }
    }

    /// First parameter index and number of parameters.
    pub fn parameters(self) -> (usize, usize) {
        match self {
            Term::GyroBias => (0, 3),
            Term::AccelBias => (3, 3),
            Term::AccelScaleFactor => (6, 3),
            Term::AccelMisalignment => (9, 6),
            Term::GyroScaleFactor => (15, 3),
            Term::GyroMisalignment => (18, 6),
            Term::GyroGSensitivity => (24, 9),
            Term::ReferenceOffset => (33, 3),
        }
    }

    /// Whether the term describes the gyros (it cannot be estimated without gyro data).
    pub fn is_gyro(self) -> bool {
        matches!(self, Term::GyroBias | Term::GyroScaleFactor | Term::GyroMisalignment | Term::GyroGSensitivity)
    }

    const fn bit(self) -> u16 {
        1 << (self as u16)
    }
}

/// A set of terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Model(u16);

impl Model {
    /// No term.
    pub const EMPTY: Model = Model(0);
    /// Gyro and accelerometer biases.
    pub const BIASES: Model = Model(0b11);
    /// Every static term.
    pub const FULL: Model = Model(0xff);

    /// The model with `term` added.
    #[must_use]
    pub const fn with(self, term: Term) -> Model {
        Model(self.0 | term.bit())
    }

    /// The model with `term` removed.
    #[must_use]
    pub const fn without(self, term: Term) -> Model {
        Model(self.0 & !term.bit())
    }

    /// Whether `term` is in the model.
    pub const fn contains(self, term: Term) -> bool {
        self.0 & term.bit() != 0
    }

    /// The model without its gyro terms.
    #[must_use]
    pub fn accelerometer_only(self) -> Model {
        Term::ALL.iter().filter(|t| t.is_gyro()).fold(self, |m, t| m.without(*t))
    }

    /// Whether parameter `index` belongs to a term of the model.
    pub fn has_parameter(self, index: usize) -> bool {
        Term::ALL.iter().any(|t| {
            let (first, count) = t.parameters();
            self.contains(*t) && (first..first + count).contains(&index)
        })
    }
}

pub(super) const NAMES: [&str; PARAMETERS] = [
    "gyro_bias_x",
    "gyro_bias_y",
    "gyro_bias_z",
    "accel_bias_x",
    "accel_bias_y",
    "accel_bias_z",
    "accel_scale_factor_x",
    "accel_scale_factor_y",
    "accel_scale_factor_z",
    "accel_misalignment_xy",
    "accel_misalignment_xz",
    "accel_misalignment_yx",
    "accel_misalignment_yz",
    "accel_misalignment_zx",
    "accel_misalignment_zy",
    "gyro_scale_factor_x",
    "gyro_scale_factor_y",
    "gyro_scale_factor_z",
    "gyro_misalignment_xy",
    "gyro_misalignment_xz",
    "gyro_misalignment_yx",
    "gyro_misalignment_yz",
    "gyro_misalignment_zx",
    "gyro_misalignment_zy",
    "gyro_g_sensitivity_xx",
    "gyro_g_sensitivity_xy",
    "gyro_g_sensitivity_xz",
    "gyro_g_sensitivity_yx",
    "gyro_g_sensitivity_yy",
    "gyro_g_sensitivity_yz",
    "gyro_g_sensitivity_zx",
    "gyro_g_sensitivity_zy",
    "gyro_g_sensitivity_zz",
    "reference_offset_e",
    "reference_offset_n",
    "reference_offset_u",
];

/// The report name of parameter `index` (docs/formats.md#calibration-json-version-2): `<term>_<axes>`.
pub fn parameter_name(index: usize) -> &'static str {
    NAMES.get(index).copied().unwrap_or("")
}

/// Index of the misalignment entry `(i, j)`, `i != j`, within its term (order xy, xz, yx, yz, zx, zy).
pub fn misalignment_index(i: usize, j: usize) -> usize {
    2 * i + if j < i { j } else { j.saturating_sub(1) }
}

/// The parameters held at zero to fix the body frame when the attitudes are unknown: the accelerometer
/// misalignments xy, xz and yz (body x along accelerometer x, body y in the accelerometers' x-y plane).
pub const GAUGE_PARAMETERS: [usize; 3] = [9, 10, 12];

/// The largest magnitude of each term that any instrument's parameter could have, SI, in the order of
/// [`Term::ALL`]: gyro bias 1 rad/s (57 deg/s), accelerometer bias 9.8 m/s^2 (1 g), scale factors and
/// misalignments 1 (100 %), g-sensitivity 1e-2 rad/s per m/s^2, reference offset pi/2 rad. A fit that did not
/// converge and ends beyond any of them ran away: it is refused ([`ChannelError::Diverged`](crate::calib::general::ChannelError::Diverged)), never reported.
/// (An imprecise estimate inside them stays, with its standard error.)
pub const PLAUSIBLE_MAGNITUDE_SI: [f32; 8] = [1.0, 9.8, 1.0, 1.0, 1.0, 1.0, 1e-2, core::f32::consts::FRAC_PI_2];

/// The first parameter of `theta` beyond [`PLAUSIBLE_MAGNITUDE_SI`] (or not finite).
pub fn implausible_parameter(theta: &[f32; PARAMETERS]) -> Option<usize> {
    // Parameters per term, in the order of Term::ALL.
    const COUNTS: [usize; 8] = [3, 3, 3, 6, 3, 6, 9, 3];
    let mut start = 0;
    for (count, limit) in COUNTS.iter().zip(PLAUSIBLE_MAGNITUDE_SI) {
        for p in start..start + count {
            if !theta[p].is_finite() || theta[p].abs() > limit {
                return Some(p);
            }
        }
        start += count;
    }
    None
}

/// The model's parameter indices in order, and their count.
pub(super) fn columns(model: Model) -> ([usize; PARAMETERS], usize) {
    let mut cols = [0usize; PARAMETERS];
    let mut n = 0;
    for (i, _) in NAMES.iter().enumerate() {
        if model.has_parameter(i) {
            cols[n] = i;
            n += 1;
        }
    }
    (cols, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implausible_parameters_are_found_at_each_terms_bound() {
        let zero = [0.0f32; PARAMETERS];
        assert_eq!(implausible_parameter(&zero), None);
        // One parameter of each term, just inside and just beyond its bound, of both signs.
        let first_of_term = [0, 3, 6, 9, 15, 18, 24, 33];
        for (t, &p) in first_of_term.iter().enumerate() {
            let limit = PLAUSIBLE_MAGNITUDE_SI[t];
            for sign in [1.0f32, -1.0] {
                let mut theta = zero;
                theta[p] = sign * limit;
                assert_eq!(implausible_parameter(&theta), None, "{} at its bound", parameter_name(p));
                theta[p] = sign * limit * 1.01;
                assert_eq!(implausible_parameter(&theta), Some(p), "{} beyond its bound", parameter_name(p));
            }
        }
        let mut theta = zero;
        theta[35] = f32::NAN;
        assert_eq!(implausible_parameter(&theta), Some(35), "not finite");
    }
}
