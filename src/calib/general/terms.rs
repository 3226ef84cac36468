//! The sensor model's terms: [`Term`], a set of them ([`Model`]), the parameters' names, order and plausible
//! magnitudes, the gauge parameters, and the bit of each term in a stored model.

/// How the parameters of a term are named after it (`<term>_<axes>`, docs/formats.md#calibration-json-version-2),
/// and how many it has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Axes {
    /// One per body axis: x, y, z.
    Body,
    /// The off-diagonal entries of a 3x3 matrix (axis i's sensitivity to j): xy, xz, yx, yz, zx, zy.
    OffDiagonal,
    /// Every entry of a 3x3 matrix, row by row: xx, xy, ..., zz.
    Matrix,
    /// One per navigation axis: e, n, u.
    Navigation,
}

impl Axes {
    /// The name suffix of each parameter, in parameter order.
    pub const fn suffixes(self) -> &'static [&'static str] {
        match self {
            Axes::Body => &["x", "y", "z"],
            Axes::OffDiagonal => &["xy", "xz", "yx", "yz", "zx", "zy"],
            Axes::Matrix => &["xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"],
            Axes::Navigation => &["e", "n", "u"],
        }
    }

    /// Number of parameters.
    pub const fn count(self) -> usize {
        self.suffixes().len()
    }
}

/// One row of the term table: everything the code knows of a term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TermInfo {
    /// The term.
    pub term: Term,
    /// The catalogue name (docs/formats.md#effect-catalogue), the prefix of its parameters' names.
    pub name: &'static str,
    /// How its parameters are named, and how many there are.
    pub axes: Axes,
    /// The largest magnitude of any of its parameters that any instrument could have, SI: a fit that did not
    /// converge and ends beyond it ran away ([`implausible_parameter`]).
    pub plausible_magnitude_si: f32,
    /// Its bit in a stored model ([`Model::stored_bits`]): replay and outcome files and the link carry it, so it
    /// never changes, whatever the order of the table or of the enum.
    pub stored_bit: u16,
    /// Whether the term describes the gyros (it cannot be estimated without gyro data).
    pub is_gyro: bool,
}

/// The term table, in parameter order: a term's parameters follow those of the terms before it. Names, parameter
/// counts and indices, plausible magnitudes, the gauge parameters and the stored bits are all derived from it.
pub const TERMS: [TermInfo; 8] = [
    TermInfo {
        term: Term::GyroBias,
        name: "gyro_bias",
        axes: Axes::Body,
        plausible_magnitude_si: 1.0, // 57 deg/s
        stored_bit: 0,
        is_gyro: true,
    },
    TermInfo {
        term: Term::AccelBias,
        name: "accel_bias",
        axes: Axes::Body,
        plausible_magnitude_si: 9.8, // 1 g
        stored_bit: 1,
        is_gyro: false,
    },
    TermInfo {
        term: Term::AccelScaleFactor,
        name: "accel_scale_factor",
        axes: Axes::Body,
        plausible_magnitude_si: 1.0, // 100 %
        stored_bit: 2,
        is_gyro: false,
    },
    TermInfo {
        term: Term::AccelMisalignment,
        name: "accel_misalignment",
        axes: Axes::OffDiagonal,
        plausible_magnitude_si: 1.0,
        stored_bit: 3,
        is_gyro: false,
    },
    TermInfo {
        term: Term::GyroScaleFactor,
        name: "gyro_scale_factor",
        axes: Axes::Body,
        plausible_magnitude_si: 1.0,
        stored_bit: 4,
        is_gyro: true,
    },
    TermInfo {
        term: Term::GyroMisalignment,
        name: "gyro_misalignment",
        axes: Axes::OffDiagonal,
        plausible_magnitude_si: 1.0,
        stored_bit: 5,
        is_gyro: true,
    },
    TermInfo {
        term: Term::GyroGSensitivity,
        name: "gyro_g_sensitivity",
        axes: Axes::Matrix,
        plausible_magnitude_si: 1e-2, // rad/s per m/s^2
        stored_bit: 6,
        is_gyro: true,
    },
    TermInfo {
        term: Term::ReferenceOffset,
        name: "reference_offset",
        axes: Axes::Navigation,
        plausible_magnitude_si: core::f32::consts::FRAC_PI_2,
        stored_bit: 7,
        is_gyro: false,
    },
];

/// The first parameter of each term of [`TERMS`].
const FIRST: [usize; TERMS.len()] = {
    let mut first = [0; TERMS.len()];
    let mut i = 1;
    while i < TERMS.len() {
        first[i] = first[i - 1] + TERMS[i - 1].axes.count();
        i += 1;
    }
    first
};

/// Parameters of the full model: the parameters of every term of [`TERMS`] (gyro bias 3, accelerometer bias 3,
/// accelerometer scale factor 3 and misalignment 6, gyro scale factor 3 and misalignment 6, gyro g-sensitivity 9,
/// reference offset 3).
pub const PARAMETERS: usize = FIRST[TERMS.len() - 1] + TERMS[TERMS.len() - 1].axes.count();

/// A term of the sensor model (docs/conventions.md#sensor-model), named as in the effect catalogue; its row of
/// [`TERMS`] says the rest.
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
    /// Every term in parameter order (the order of [`TERMS`]).
    pub const ALL: [Term; TERMS.len()] = {
        let mut all = [Term::GyroBias; TERMS.len()];
        let mut i = 0;
        while i < TERMS.len() {
            all[i] = TERMS[i].term;
            i += 1;
        }
        all
    };

    /// The term's row of [`TERMS`] (the enum is in the table's order: a unit test checks it).
    pub const fn info(self) -> &'static TermInfo {
        &TERMS[self as usize]
    }

    /// The catalogue name (docs/formats.md#effect-catalogue).
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// First parameter index and number of parameters.
    pub const fn parameters(self) -> (usize, usize) {
        (FIRST[self as usize], self.info().axes.count())
    }

    /// Whether the term describes the gyros (it cannot be estimated without gyro data).
    pub fn is_gyro(self) -> bool {
        self.info().is_gyro
    }

    /// The index of entry `(i, j)` of the term (row i, column j of a matrix term; `j` is ignored for a term of
    /// one parameter per axis), or `None` when the term has no such entry (a diagonal of misalignments).
    pub fn parameter_index(self, i: usize, j: usize) -> Option<usize> {
        let first = self.parameters().0;
        match self.info().axes {
            Axes::Body | Axes::Navigation => (i < 3).then_some(first + i),
            Axes::OffDiagonal => (i < 3 && j < 3 && i != j).then(|| first + misalignment_index(i, j)),
            Axes::Matrix => (i < 3 && j < 3).then_some(first + 3 * i + j),
        }
    }

    const fn bit(self) -> u16 {
        1 << self.info().stored_bit
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
    pub const BIASES: Model = Model::EMPTY.with(Term::GyroBias).with(Term::AccelBias);
    /// Every static term.
    pub const FULL: Model = {
        let mut model = Model::EMPTY;
        let mut i = 0;
        while i < TERMS.len() {
            model = model.with(TERMS[i].term);
            i += 1;
        }
        model
    };

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

    /// The model as stored (replay and outcome files, the link): bit [`TermInfo::stored_bit`] of each term in it.
    pub const fn stored_bits(self) -> u16 {
        self.0
    }

    /// The model of stored bits, or `None` when a bit is set that no term has.
    pub const fn from_stored_bits(bits: u16) -> Option<Model> {
        if bits & !Model::FULL.0 == 0 {
            Some(Model(bits))
        } else {
            None
        }
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
pub const fn misalignment_index(i: usize, j: usize) -> usize {
    2 * i + if j < i { j } else { j.saturating_sub(1) }
}

/// The parameters held at zero to fix the body frame when the attitudes are unknown: the accelerometer
/// misalignments xy, xz and yz (body x along accelerometer x, body y in the accelerometers' x-y plane).
pub const GAUGE_PARAMETERS: [usize; 3] = {
    let first = Term::AccelMisalignment.parameters().0;
    [first + misalignment_index(0, 1), first + misalignment_index(0, 2), first + misalignment_index(1, 2)]
};

/// The largest magnitude of each term that any instrument's parameter could have, SI, in the order of
/// [`Term::ALL`] ([`TermInfo::plausible_magnitude_si`]): gyro bias 1 rad/s (57 deg/s), accelerometer bias
/// 9.8 m/s^2 (1 g), scale factors and misalignments 1 (100 %), g-sensitivity 1e-2 rad/s per m/s^2, reference
/// offset pi/2 rad. A fit that did not converge and ends beyond any of them ran away: it is refused
/// ([`ChannelError::Diverged`](crate::calib::general::ChannelError::Diverged)), never reported. (An imprecise
/// estimate inside them stays, with its standard error.)
pub const PLAUSIBLE_MAGNITUDE_SI: [f32; TERMS.len()] = {
    let mut out = [0.0; TERMS.len()];
    let mut i = 0;
    while i < TERMS.len() {
        out[i] = TERMS[i].plausible_magnitude_si;
        i += 1;
    }
    out
};

/// The first parameter of `theta` beyond [`PLAUSIBLE_MAGNITUDE_SI`] (or not finite).
pub fn implausible_parameter(theta: &[f32; PARAMETERS]) -> Option<usize> {
    for (t, limit) in Term::ALL.iter().zip(PLAUSIBLE_MAGNITUDE_SI) {
        let (first, count) = t.parameters();
        for p in first..first + count {
            if !theta[p].is_finite() || theta[p].abs() > limit {
                return Some(p);
            }
        }
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
        for (t, term) in Term::ALL.iter().enumerate() {
            let p = term.parameters().0;
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

    #[test]
    fn the_table_is_in_the_order_of_the_enum() {
        for (i, info) in TERMS.iter().enumerate() {
            assert_eq!(info.term as usize, i, "{}", info.name);
            assert_eq!(Term::ALL[i], info.term);
            assert_eq!(info.term.info(), info);
        }
    }

    #[test]
    fn parameter_names_are_derived_from_the_table_and_unique() {
        let mut derived = std::vec::Vec::new();
        for info in &TERMS {
            let (first, count) = info.term.parameters();
            assert_eq!(first, derived.len(), "{}: its parameters follow those of the terms before it", info.name);
            assert_eq!(count, info.axes.count());
            derived.extend(info.axes.suffixes().iter().map(|axes| std::format!("{}_{axes}", info.name)));
        }
        assert_eq!(derived.len(), PARAMETERS, "the counts sum to PARAMETERS");
        assert_eq!(NAMES.len(), PARAMETERS);
        for (p, name) in derived.iter().enumerate() {
            assert_eq!(parameter_name(p), name, "parameter {p}");
        }
        let unique: std::collections::BTreeSet<&str> = NAMES.iter().copied().collect();
        assert_eq!(unique.len(), PARAMETERS, "names are unique");
        assert_eq!(parameter_name(PARAMETERS), "");
    }

    #[test]
    fn parameter_index_names_each_entry() {
        assert_eq!(Term::GyroBias.parameter_index(2, 0).map(parameter_name), Some("gyro_bias_z"));
        assert_eq!(Term::AccelMisalignment.parameter_index(2, 1).map(parameter_name), Some("accel_misalignment_zy"));
        assert_eq!(Term::AccelMisalignment.parameter_index(1, 1), None);
        assert_eq!(Term::GyroGSensitivity.parameter_index(1, 2).map(parameter_name), Some("gyro_g_sensitivity_yz"));
        assert_eq!(Term::ReferenceOffset.parameter_index(2, 0).map(parameter_name), Some("reference_offset_u"));
        let gauge = GAUGE_PARAMETERS.map(parameter_name);
        assert_eq!(gauge, ["accel_misalignment_xy", "accel_misalignment_xz", "accel_misalignment_yz"]);
    }

    /// The stored bits are in flash, in replay and outcome files and on the link: written out here, so that any
    /// change of them fails.
    #[test]
    fn stored_bits_are_the_documented_ones() {
        let expected = [
            (Term::GyroBias, 0),
            (Term::AccelBias, 1),
            (Term::AccelScaleFactor, 2),
            (Term::AccelMisalignment, 3),
            (Term::GyroScaleFactor, 4),
            (Term::GyroMisalignment, 5),
            (Term::GyroGSensitivity, 6),
            (Term::ReferenceOffset, 7),
        ];
        assert_eq!(expected.len(), TERMS.len(), "a new term needs its stored bit here");
        for (term, bit) in expected {
            assert_eq!(term.info().stored_bit, bit, "{}", term.name());
            assert_eq!(Model::EMPTY.with(term).stored_bits(), 1 << bit, "{}", term.name());
        }
        assert_eq!(Model::BIASES.stored_bits(), 0b11);
        assert_eq!(Model::FULL.stored_bits(), 0xff);
    }

    #[test]
    fn stored_bits_round_trip() {
        for bits in 0..=Model::FULL.stored_bits() {
            let model = Model::from_stored_bits(bits).expect("every combination of terms");
            assert_eq!(model.stored_bits(), bits);
            for t in Term::ALL {
                assert_eq!(model.contains(t), bits & (1 << t.info().stored_bit) != 0);
            }
        }
        assert_eq!(Model::from_stored_bits(0x100), None, "a bit no term has");
    }
}
