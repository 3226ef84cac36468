//! The general estimator of docs/method.md#general-estimator: every channel of every dwell against what the
//! reference predicts, with the sensor-model terms of the catalogue selectable.
//!
//! Per dwell `k`, with the reference attitude `C_k` (corrected by the constant reference offset `delta` when it
//! is in the model: `C_true = R(-delta) C_k`, to first order `(I - [delta x]) C_k`), the body vectors
//! `f_b = C_true^T f_n` and `w_b = C_true^T w_n` predict the dwell means
//!     f_meas = T_a f_b + b_a,        w_meas = T_g w_b + b_g + G f_b,        T = I + S + M
//! (docs/conventions.md#sensor-model). The unknowns are the model's terms (up to [`PARAMETERS`]) and, for each
//! dwell whose heading is unknown, that heading as a nuisance parameter: gravity does not depend on it, the Earth
//! rate's horizontal part does.
//!
//! Without reference attitudes ([`AttitudeKnowledge::Unknown`], hand-placed poses levelled from the data) the
//! direction of gravity in the body is two more nuisance angles per dwell (the tilt about east and north): the
//! accelerometers then constrain the sensor model only through `|T_a^-1 (f - b_a)| = g` (the imu_tk method).
//! The tilt is linearised about the direction of the calibrated measured gravity, `T_a^-1 (f - b_a)`, refined
//! with the dwell's heading by Gauss-Newton on its own rows, and eliminated like the heading. A common rotation
//! of every pose is then invisible: it moves the antisymmetric part of the misalignments (`T_a R`, and `T_g R`
//! with it), three blind spots of the structural design. With the accelerometer misalignments in the model, the
//! body frame is fixed to the accelerometer triad (x along accelerometer x, y in its x-y plane): the
//! misalignments xy, xz and yz are held at zero ([`ChannelSolution::gauge`]) and the others are estimated in
//! that frame (a lower-triangular `T_a`).
//!
//! The solution is Gauss-Newton on the dwell means weighted by their noise (the variance of each mean, which
//! the caller supplies, docs/method.md#how-it-solves). Each pass folds the
//! whitened rows into a square-root information factor ([`crate::math::lsq`]); a dwell's heading column is
//! removed by a Householder reflection of that dwell's rows before they are folded in, which is the Schur
//! complement of the nuisance in square-root form. Unknown headings are profiled exactly at the start of every
//! pass (a grid over the full circle, then one-dimensional Gauss-Newton), so the iteration cannot be caught on
//! the wrong side of the circle.
//!
//! Observability is structural: a second factor is built from the same rows at the reference attitudes,
//! unweighted, with gyro rows in units of the Earth rate and accelerometer rows in units of g, entries below
//! 1e-6 of those units set to zero, and columns scaled to unit norm. Its singular values below
//! [`ChannelSettings::rank_tolerance`] of the largest span the directions the schedule cannot see; a parameter
//! with a share in them is unobservable and is not estimated. Noise never makes a parameter unobservable: a
//! parameter that is determined but imprecise gets its (large) standard error.
//!
//! Memory: the problem holds [`MAX_DWELLS`] dwells (2.6 KB); a solution is 8.5 KB; solving uses about 30 KB of
//! stack (three 36 x 36 factors, the SVD's workspace and the attitude of every dwell).

use heapless::Vec;

use crate::calib::moves::{move_column, swing_about, ChannelMove, MAX_MOVES, MAX_MOVE_MISFIT_RAD, MOVE_PARAMETERS};
use crate::math::linalg::{cross, dot, norm, rotation, Mat3, Vec3};
use crate::math::lsq::{inverse_gram, jacobi_svd, solve_upper, solve_upper_transposed, SqrtInfo};
use crate::nav::earth::{Site, EARTH_RATE_RADPS};
use crate::nav::frames::{heading_rotation, Attitude};
use crate::nav::strapdown::Quat;

/// Most dwells one solution takes (a bit mask of `u64` marks suspect dwells).
pub const MAX_DWELLS: usize = 64;
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

    /// The model as stored in replay files, configurations and records: bit i is `Term::ALL[i]`.
    pub fn stored_bits(self) -> u16 {
        Term::ALL.iter().enumerate().fold(0, |bits, (i, t)| if self.contains(*t) { bits | 1 << i } else { bits })
    }

    /// The model of [`Model::stored_bits`]; `None` when a bit names no term.
    pub fn from_stored_bits(bits: u16) -> Option<Model> {
        let model = Term::ALL
            .iter()
            .enumerate()
            .fold(Model::EMPTY, |m, (i, t)| if bits & (1 << i) != 0 { m.with(*t) } else { m });
        (model.stored_bits() == bits).then_some(model)
    }

    /// Whether parameter `index` belongs to a term of the model.
    pub fn has_parameter(self, index: usize) -> bool {
        Term::ALL.iter().any(|t| {
            let (first, count) = t.parameters();
            self.contains(*t) && (first..first + count).contains(&index)
        })
    }
}

const NAMES: [&str; PARAMETERS] = [
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

/// One dwell as the estimator sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelDwell {
    /// The reference attitude without heading, `Rx(pitch) Ry(roll)` ([`crate::nav::frames::Attitude::tilt`]).
    pub tilt: Mat3,
    /// The reference heading, rad, clockwise from north; `None` when unknown.
    pub heading_rad: Option<f32>,
    /// Mean gyro output, body, rad/s (ignored without gyro data).
    pub rate_mean_b_radps: Vec3,
    /// Mean accelerometer output, body, m/s^2.
    pub force_mean_b_mps2: Vec3,
    /// Variance of each gyro mean, (rad/s)^2.
    pub rate_mean_var_b_radps2: Vec3,
    /// Variance of each accelerometer mean, (m/s^2)^2.
    pub force_mean_var_b_mps2sq: Vec3,
}

/// Settings of the estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSettings {
    /// The terms to estimate.
    pub model: Model,
    /// Whether the dwells carry gyro data; without, the gyro terms are dropped from the model.
    pub use_gyro: bool,
    /// Gauss-Newton passes at most.
    pub max_iterations: u32,
    /// Singular values of the structural design below this fraction of the largest are blind spots.
    pub rank_tolerance: f32,
    /// A parameter whose squared share in the blind spots exceeds this is unobservable.
    pub share_tolerance: f32,
    /// Largest relative difference between |f| and g accepted before the fit.
    pub max_force_magnitude_error: f32,
    /// Largest angle between measured gravity and the reference's accepted before the fit, rad.
    pub max_gravity_angle_rad: f32,
    /// Whether the dwells' tilts are a reference or unknown (then nuisance parameters).
    pub attitude: AttitudeKnowledge,
    /// Whether the gyros resolve the Earth rate (their dwell means and errors are well below it). Without, the
    /// gyro model leaves the Earth rate out: no heading is estimated or checked, and the gyro scale factors and
    /// misalignments, which a static pose sees only through the Earth rate, are not exercised.
    pub earth_rate_resolved: bool,
}

/// What the session knows of the dwells' attitudes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AttitudeKnowledge {
    /// Every dwell's tilt ([`ChannelDwell::tilt`]) is the reference's; its heading too unless `None`.
    #[default]
    Reference,
    /// No dwell's tilt is known (hand-placed poses): the direction of gravity in the body is two nuisance
    /// angles per dwell and [`ChannelDwell::tilt`] is ignored; a heading given is kept, an unknown one is a
    /// nuisance as well when gyro data are used.
    Unknown,
}

/// The parameters held at zero to fix the body frame when the attitudes are unknown: the accelerometer
/// misalignments xy, xz and yz (body x along accelerometer x, body y in the accelerometers' x-y plane).
pub const GAUGE_PARAMETERS: [usize; 3] = [9, 10, 12];

impl Default for ChannelSettings {
    fn default() -> ChannelSettings {
        ChannelSettings {
            model: Model::BIASES,
            use_gyro: true,
            max_iterations: 12,
            rank_tolerance: 1e-4,
            share_tolerance: 1e-3,
            max_force_magnitude_error: crate::calib::calibration::MAX_FORCE_MAGNITUDE_ERROR,
            max_gravity_angle_rad: 0.1745,
            attitude: AttitudeKnowledge::Reference,
            earth_rate_resolved: true,
        }
    }
}

/// Why the estimator refused the data (dwell indices count from 0 in the order added).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ChannelError {
    /// No dwell was added.
    NoDwells,
    /// More than [`MAX_DWELLS`] dwells.
    TooManyDwells,
    /// A mean, variance or attitude is NaN or infinite, or a variance is not positive.
    BadInput {
        /// Which dwell.
        dwell: usize,
    },
    /// |f| differs from g by more than the settings allow (an accelerometer scale error, or not at rest).
    ForceMagnitude {
        /// Which dwell.
        dwell: usize,
        /// |f| / g.
        ratio: f32,
    },
    /// Measured gravity points elsewhere than the reference attitude says (a wrong face down, wrong axes).
    GravityDirection {
        /// Which dwell.
        dwell: usize,
        /// Angle between the two, rad.
        angle_rad: f32,
    },
    /// The gyros see the Earth rate as if the heading were a quarter or half turn from the reference's.
    HeadingMismatch {
        /// Which dwell.
        dwell: usize,
        /// The reference heading, rad.
        given_rad: f32,
        /// The heading the Earth rate fits, rad.
        fits_rad: f32,
    },
    /// The model has no term the data can inform.
    NothingToEstimate,
    /// More than [`MAX_MOVES`] moves.
    TooManyMoves,
    /// A move joins a dwell that was not added, or a number of it is not finite.
    BadMove {
        /// Which move (from 0, in the order given).
        index: usize,
    },
    /// The fit did not converge and left the range any instrument could have (it ran away: a model these dwells
    /// cannot pin down); the first such parameter.
    Diverged {
        /// Its index (see [`parameter_name`]).
        parameter: usize,
        /// Its value, SI.
        value: f32,
    },
}

/// The largest magnitude of each term that any instrument's parameter could have, SI, in the order of
/// [`Term::ALL`]: gyro bias 1 rad/s (57 deg/s), accelerometer bias 9.8 m/s^2 (1 g), scale factors and
/// misalignments 1 (100 %), g-sensitivity 1e-2 rad/s per m/s^2, reference offset pi/2 rad. A fit that did not
/// converge and ends beyond any of them ran away: it is refused ([`ChannelError::Diverged`]), never reported.
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

impl core::fmt::Display for ChannelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            ChannelError::NoDwells => f.write_str("no dwells to solve"),
            ChannelError::TooManyDwells => write!(f, "more than {MAX_DWELLS} dwells"),
            ChannelError::BadInput { dwell } => {
                write!(f, "dwell {}: a mean, variance or attitude is not finite or a variance not positive", dwell + 1)
            }
            ChannelError::ForceMagnitude { dwell, ratio } => write!(
                f,
                "dwell {}: |f| is {ratio:.4} g: an accelerometer scale error or a body not at rest",
                dwell + 1
            ),
            ChannelError::GravityDirection { dwell, angle_rad } => write!(
                f,
                "dwell {}: measured gravity is {:.1} deg from where the reference attitude puts it: a wrong face \
                 down, a wrong pitch/roll, or axes that are not x right, y forward, z up",
                dwell + 1,
                angle_rad.to_degrees()
            ),
            ChannelError::HeadingMismatch { dwell, given_rad, fits_rad } => write!(
                f,
                "dwell {}: the gyros see the Earth rate of heading {:.0} deg, not of the reference's {:.0} deg",
                dwell + 1,
                degrees_0_360(fits_rad),
                degrees_0_360(given_rad)
            ),
            ChannelError::NothingToEstimate => f.write_str("the model has no term these data can inform"),
            ChannelError::TooManyMoves => write!(f, "more than {MAX_MOVES} moves"),
            ChannelError::BadMove { index } => write!(
                f,
                "move {}: it joins a dwell that was not added, or its rotation, duration or sums are not finite",
                index + 1
            ),
            ChannelError::Diverged { parameter, value } => write!(
                f,
                "the fit diverged: {} reached {value:e} (SI), beyond what any instrument has; fit fewer terms \
                 (--model) or add positions that determine them",
                parameter_name(parameter)
            ),
        }
    }
}

impl core::error::Error for ChannelError {}

/// An angle in degrees in [0, 360).
fn degrees_0_360(angle_rad: f32) -> f32 {
    let d = angle_rad.to_degrees() % 360.0;
    if d < 0.0 {
        d + 360.0
    } else {
        d
    }
}

/// The solution.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ChannelSolution {
    /// The model estimated (without gyro terms when there were no gyro data).
    pub model: Model,
    /// Every parameter, SI units, in the order of [`parameter_name`]; 0 for those not estimated.
    pub parameters_si: [f32; PARAMETERS],
    /// Bit i: parameter i is in the model and determined by the schedule.
    pub observable: u64,
    /// Bit i: parameter i is in the model and the schedule cannot determine it.
    pub unobservable: u64,
    /// Covariance of the determined parameters, SI units; rows and columns of the others are zero.
    pub covariance_si: [[f32; PARAMETERS]; PARAMETERS],
    /// Number of dwells.
    pub dwells: usize,
    /// Heading of every dwell, rad: the reference's, or the estimate for unknown headings.
    pub heading_rad: [f32; MAX_DWELLS],
    /// Standard error of an estimated heading (given the sensor terms), rad; 0 for a given heading.
    pub heading_std_rad: [f32; MAX_DWELLS],
    /// Measured minus predicted gyro mean per dwell, rad/s.
    pub residual_rate_b_radps: [Vec3; MAX_DWELLS],
    /// Measured minus predicted accelerometer mean per dwell, m/s^2.
    pub residual_force_b_mps2: [Vec3; MAX_DWELLS],
    /// Per dwell: its whitened residual sum of squares scaled to the dwell's channel count by its degrees of
    /// freedom left after the fit (a chi-square of that many degrees of freedom when the model holds), or a
    /// negative value when the dwell has no freedom left to test.
    pub dwell_statistic: [f32; MAX_DWELLS],
    /// Bit k: dwell k's residuals exceed the 0.1 % level of that chi-square.
    pub suspect: u64,
    /// Sum of the squared whitened residuals.
    pub chi_square: f32,
    /// Residual degrees of freedom: channel means, less determined parameters, less estimated headings.
    pub degrees_of_freedom: u32,
    /// Gauss-Newton passes made.
    pub iterations: u32,
    /// Whether the last correction was below 1e-3 of every standard error, or stopped shrinking below 0.05 of
    /// them (f32 rounding).
    pub converged: bool,
    /// The attitude knowledge the solution assumed.
    pub attitude: AttitudeKnowledge,
    /// Whether the gyro model included the Earth rate ([`ChannelSettings::earth_rate_resolved`]).
    pub earth_rate_resolved: bool,
    /// Up (the direction of measured gravity) in the body of every dwell, a unit vector: the reference's, or
    /// the estimate when the attitudes are unknown.
    pub up_b: [Vec3; MAX_DWELLS],
    /// Number of blind spots of the structural design (singular values below the rank tolerance) before the
    /// body frame is fixed: three more than with reference attitudes when a common rotation of the poses is
    /// invisible.
    pub blind_spots: u32,
    /// Bit i: parameter i is held at zero to fix the body frame ([`GAUGE_PARAMETERS`]); it is also in
    /// `unobservable`, and the other parameters are estimated in that frame.
    pub gauge: u64,
    /// Moves used (docs/method.md#moves), in the order given.
    pub moves: usize,
    /// Per move: the rotation the calibrated gyros measured less the reference rotation, body frame at the
    /// start of the move, rad (without the part about up when a heading at either end is unknown).
    pub move_residual_rad: [Vec3; MAX_MOVES],
    /// Per move: its whitened residual sum of squares (a chi-square of [`ChannelSolution::move_rows`] degrees
    /// of freedom when the model holds); negative for a move left out.
    pub move_statistic: [f32; MAX_MOVES],
    /// Per move: its rows in the fit (3, or 2 without the part about up; 0 for a move left out).
    pub move_rows: [u8; MAX_MOVES],
    /// Bit k: move k was left out because its rotation at the start was further than
    /// [`crate::calib::moves::MAX_MOVE_MISFIT_RAD`] from the reference's.
    pub moves_refused: u64,
}

impl ChannelSolution {
    /// A solution of `model` over `dwells` dwells with nothing in it yet: every parameter, residual and
    /// statistic zero (the dwells' and moves' statistics -1: none), reference attitudes, the Earth rate resolved.
    pub fn empty(model: Model, dwells: usize) -> ChannelSolution {
        ChannelSolution {
            model,
            parameters_si: [0.0; PARAMETERS],
            observable: 0,
            unobservable: 0,
            covariance_si: [[0.0; PARAMETERS]; PARAMETERS],
            dwells,
            heading_rad: [0.0; MAX_DWELLS],
            heading_std_rad: [0.0; MAX_DWELLS],
            residual_rate_b_radps: [[0.0; 3]; MAX_DWELLS],
            residual_force_b_mps2: [[0.0; 3]; MAX_DWELLS],
            dwell_statistic: [-1.0; MAX_DWELLS],
            suspect: 0,
            chi_square: 0.0,
            degrees_of_freedom: 0,
            iterations: 0,
            converged: false,
            attitude: AttitudeKnowledge::Reference,
            earth_rate_resolved: true,
            up_b: [[0.0; 3]; MAX_DWELLS],
            blind_spots: 0,
            gauge: 0,
            moves: 0,
            move_residual_rad: [[0.0; 3]; MAX_MOVES],
            move_statistic: [-1.0; MAX_MOVES],
            move_rows: [0; MAX_MOVES],
            moves_refused: 0,
        }
    }

    /// Value and standard error of parameter `index`, or `None` when it is not in the model or undetermined.
    pub fn estimate(&self, index: usize) -> Option<(f32, f32)> {
        if index < PARAMETERS && self.observable & (1 << index) != 0 {
            Some((self.parameters_si[index], libm::sqrtf(self.covariance_si[index][index].max(0.0))))
        } else {
            None
        }
    }
}

/// Smallest largest input of a proportional term, as a fraction of its full scale (g for the accelerometer
/// terms and the g-sensitivity, the Earth rate for the gyro scale factors and misalignments, 1 rad of offset),
/// for the schedule to exercise it.
pub const MIN_EXERCISE: f32 = 0.05;

/// Chi-square quantiles at 0.999 for 1 to 6 degrees of freedom.
const CHI2_999: [f32; 6] = [10.828, 13.816, 16.266, 18.467, 20.515, 22.458];

/// The estimator: dwells collected, solved on demand.
#[derive(Clone, Debug)]
pub struct ChannelEstimator {
    site: Site,
    settings: ChannelSettings,
    dwells: Vec<ChannelDwell, MAX_DWELLS>,
}

/// The prediction of one dwell and its derivatives: rows 0-2 gyro x, y, z, rows 3-5 accelerometer x, y, z;
/// `d_attitude[row][m]`: by a rotation of the dwell's attitude about navigation axis m (e, n, u; u is the
/// heading), `C' = R(-phi) C`.
struct Linearised {
    pred: [f32; 6],
    jac: [[f32; PARAMETERS]; 6],
    d_attitude: [[f32; 3]; 6],
}

/// The model's parameter indices in order, and their count.
fn columns(model: Model) -> ([usize; PARAMETERS], usize) {
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

/// `T = I + S + M` of one sensor from the parameters: scale factors from index `scale_first`, misalignments
/// (order xy, xz, yx, yz, zx, zy) from `misalignment_first`.
pub fn sensor_matrix(theta: &[f32; PARAMETERS], scale_first: usize, misalignment_first: usize) -> Mat3 {
    let mut t = Mat3::IDENTITY;
    for i in 0..3 {
        t.0[i][i] += theta[scale_first + i];
        for j in 0..3 {
            if i != j {
                t.0[i][j] += theta[misalignment_first + misalignment_index(i, j)];
            }
        }
    }
    t
}

/// The gyro g-sensitivity `G` from the parameters, (rad/s)/(m/s^2), row i = gyro i.
pub fn g_sensitivity_radps_per_mps2(theta: &[f32; PARAMETERS]) -> Mat3 {
    Mat3([[theta[24], theta[25], theta[26]], [theta[27], theta[28], theta[29]], [theta[30], theta[31], theta[32]]])
}

/// Prediction and Jacobian of one dwell at the parameters `theta` and the attitude `c_ref` (`C_b^n`).
/// Without `earth_rate` the gyros are predicted without the Earth rate.
fn linearise(theta: &[f32; PARAMETERS], c_ref: &Mat3, site: &Site, model: Model, earth_rate: bool) -> Linearised {
    let c_ref = *c_ref;
    let offset = [theta[33], theta[34], theta[35]];
    let c_true = if model.contains(Term::ReferenceOffset) {
        rotation([-offset[0], -offset[1], -offset[2]]).mul(&c_ref)
    } else {
        c_ref
    };
    let f_n = site.force_at_rest_n_mps2();
    let w_n = if earth_rate { site.earth_rate_n_radps() } else { [0.0; 3] };
    let ct = c_true.transpose();
    let f_b = ct.mul_vec(f_n);
    let w_b = ct.mul_vec(w_n);
    let t_a = sensor_matrix(theta, 6, 9);
    let t_g = sensor_matrix(theta, 15, 18);
    let g_mat =
        Mat3([[theta[24], theta[25], theta[26]], [theta[27], theta[28], theta[29]], [theta[30], theta[31], theta[32]]]);
    let fa = t_a.mul_vec(f_b);
    let wg = t_g.mul_vec(w_b);
    let gf = g_mat.mul_vec(f_b);
    let mut out = Linearised { pred: [0.0; 6], jac: [[0.0; PARAMETERS]; 6], d_attitude: [[0.0; 3]; 6] };
    for i in 0..3 {
        out.pred[i] = wg[i] + theta[i] + gf[i];
        out.pred[3 + i] = fa[i] + theta[3 + i];
        let (g, a) = (i, 3 + i);
        out.jac[g][i] = 1.0;
        out.jac[a][3 + i] = 1.0;
        out.jac[a][6 + i] = f_b[i];
        out.jac[g][15 + i] = w_b[i];
        for j in 0..3 {
            if i != j {
                out.jac[a][9 + misalignment_index(i, j)] = f_b[j];
                out.jac[g][18 + misalignment_index(i, j)] = w_b[j];
            }
            out.jac[g][24 + 3 * i + j] = f_b[j];
        }
    }
    // Reference offset: d(C_true^T v)/d(delta_m) = C_true^T (e_m x v) to first order.
    let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for (m, e) in axes.iter().enumerate() {
        let dfb = ct.mul_vec(cross(*e, f_n));
        let dwb = ct.mul_vec(cross(*e, w_n));
        let (da, dg, dgf) = (t_a.mul_vec(dfb), t_g.mul_vec(dwb), g_mat.mul_vec(dfb));
        for i in 0..3 {
            out.jac[i][33 + m] = dg[i] + dgf[i];
            out.jac[3 + i][33 + m] = da[i];
        }
    }
    // Attitude (tilt about e and n, heading about u): d(C_true^T v)/d(phi_m) = C_ref^T (e_m x (C_ref v_b)) with
    // v_b = C_true^T v (exact); the heading psi is phi_u.
    for (m, e) in axes.iter().enumerate() {
        let dfb = c_ref.transpose().mul_vec(cross(*e, c_ref.mul_vec(f_b)));
        let dwb = c_ref.transpose().mul_vec(cross(*e, c_ref.mul_vec(w_b)));
        let (da, dg, dgf) = (t_a.mul_vec(dfb), t_g.mul_vec(dwb), g_mat.mul_vec(dfb));
        for i in 0..3 {
            out.d_attitude[i][m] = dg[i] + dgf[i];
            out.d_attitude[3 + i][m] = da[i];
        }
    }
    out
}

/// Whitened rows of one dwell: channel rows (`rows` of them), their right-hand sides and the columns of its
/// nuisance attitude angles (e, n, u; zero for the angles that are not nuisances).
struct DwellRows {
    a: [[f32; PARAMETERS]; 6],
    y: [f32; 6],
    h: [[f32; 3]; 6],
    rows: usize,
}

/// Removes the nuisance columns from a dwell's rows by Householder reflections, one column at a time: the
/// first rows then carry all the nuisance information and are dropped (their number is returned); the rest are
/// orthogonal to the nuisance directions. This is the Schur complement of the nuisances in square-root form.
fn eliminate_nuisances(d: &mut DwellRows, n: usize) -> usize {
    let m = d.rows;
    let mut top = 0;
    for col in 0..3 {
        if top >= m {
            break;
        }
        let h_norm = libm::sqrtf(d.h[top..m].iter().map(|x| x[col] * x[col]).sum());
        if h_norm == 0.0 {
            continue;
        }
        let alpha = if d.h[top][col] >= 0.0 { -h_norm } else { h_norm };
        let mut u = [0.0f32; 6];
        for r in top..m {
            u[r] = d.h[r][col];
        }
        u[top] -= alpha;
        let uu: f32 = u[top..m].iter().map(|x| x * x).sum();
        if uu == 0.0 {
            continue;
        }
        // Reflect every column: the parameters', the right-hand side and the later nuisance columns.
        for c in 0..n + 4 {
            let value = |d: &DwellRows, r: usize| match c {
                c if c < n => d.a[r][c],
                c if c == n => d.y[r],
                c => d.h[r][c - n - 1],
            };
            let s: f32 = (top..m).map(|r| u[r] * value(d, r)).sum();
            let k = 2.0 * s / uu;
            for r in top..m {
                match c {
                    c if c < n => d.a[r][c] -= k * u[r],
                    c if c == n => d.y[r] -= k * u[r],
                    c => d.h[r][c - n - 1] -= k * u[r],
                }
            }
        }
        top += 1;
    }
    top
}

/// The tilt (`Rx(pitch) Ry(roll)`) that puts body direction `up_b` (any length) up.
fn tilt_of_up(up_b: Vec3) -> Mat3 {
    let pitch_rad = libm::atan2f(up_b[1], libm::hypotf(up_b[0], up_b[2]));
    let roll_rad = libm::atan2f(-up_b[0], up_b[2]);
    Attitude { pitch_rad, roll_rad, heading_rad: 0.0 }.tilt()
}

impl ChannelEstimator {
    /// An estimator for one site.
    pub fn new(site: Site, settings: ChannelSettings) -> ChannelEstimator {
        ChannelEstimator { site, settings, dwells: Vec::new() }
    }

    /// The settings.
    pub fn settings(&self) -> &ChannelSettings {
        &self.settings
    }

    /// Dwells added.
    pub fn dwells(&self) -> &[ChannelDwell] {
        &self.dwells
    }

    /// Adds a dwell.
    pub fn add(&mut self, dwell: ChannelDwell) -> Result<(), ChannelError> {
        let index = self.dwells.len();
        let finite = |v: Vec3| v.iter().all(|x| x.is_finite());
        let positive = |v: Vec3| v.iter().all(|x| x.is_finite() && *x > 0.0);
        let gyro_ok =
            !self.settings.use_gyro || (finite(dwell.rate_mean_b_radps) && positive(dwell.rate_mean_var_b_radps2));
        let heading_ok = dwell.heading_rad.is_none_or(|h| h.is_finite());
        let tilt_ok = self.settings.attitude == AttitudeKnowledge::Unknown || dwell.tilt.is_finite();
        if !(gyro_ok
            && heading_ok
            && tilt_ok
            && finite(dwell.force_mean_b_mps2)
            && positive(dwell.force_mean_var_b_mps2sq))
        {
            return Err(ChannelError::BadInput { dwell: index });
        }
        self.dwells.push(dwell).map_err(|_| ChannelError::TooManyDwells)
    }

    fn model(&self) -> Model {
        if self.settings.use_gyro {
            self.settings.model
        } else {
            self.settings.model.accelerometer_only()
        }
    }

    /// The checks before any fit: |f| against g, and the direction of measured gravity against the reference
    /// (when the attitudes are a reference).
    fn check_plausible(&self) -> Result<(), ChannelError> {
        let g = self.site.gravity_mps2;
        for (dwell, d) in self.dwells.iter().enumerate() {
            let f = d.force_mean_b_mps2;
            let ratio = norm(f) / g;
            // NaN fails the test too.
            let within = (ratio - 1.0).abs() <= self.settings.max_force_magnitude_error;
            if !within {
                return Err(ChannelError::ForceMagnitude { dwell, ratio });
            }
            if self.settings.attitude == AttitudeKnowledge::Unknown {
                continue;
            }
            let up_b = d.tilt.transpose().mul_vec([0.0, 0.0, 1.0]);
            let cos = (dot(f, up_b) / norm(f)).clamp(-1.0, 1.0);
            let angle_rad = libm::acosf(cos);
            let within = angle_rad <= self.settings.max_gravity_angle_rad;
            if !within {
                return Err(ChannelError::GravityDirection { dwell, angle_rad });
            }
        }
        Ok(())
    }

    /// Solves with every dwell, after the plausibility checks; a dwell whose residuals fit a heading a quarter
    /// or half turn from its reference heading is refused.
    pub fn solve(&self) -> Result<ChannelSolution, ChannelError> {
        self.solve_with(&[])
    }

    /// [`ChannelEstimator::solve`] with the moves between dwells as observations of the gyro terms as well
    /// (docs/method.md#moves).
    pub fn solve_with(&self, moves: &[ChannelMove]) -> Result<ChannelSolution, ChannelError> {
        self.check_plausible()?;
        let solution = self.solve_excluding_with(0, moves)?;
        self.check_headings(&solution, moves)?;
        Ok(solution)
    }

    /// Each move joins two dwells that were added, and its numbers are finite.
    fn check_moves(&self, moves: &[ChannelMove]) -> Result<(), ChannelError> {
        if moves.len() > MAX_MOVES {
            return Err(ChannelError::TooManyMoves);
        }
        for (index, m) in moves.iter().enumerate() {
            let finite = m.rotation.0.iter().all(|x| x.is_finite())
                && m.duration_s.is_finite()
                && m.duration_s > 0.0
                && m.jacobian.iter().flatten().all(|x| x.is_finite())
                && m.prior_si.iter().all(|x| x.is_finite())
                && m.covariance_rad2.is_finite();
            let ends = match m.turn {
                Some(t) => {
                    let up = t.up_b;
                    let finite = up.iter().chain(&t.angle_b_rad).chain(&t.angle_sum_b_rad).all(|x| x.is_finite());
                    finite && (norm(up) - 1.0).abs() < 1e-3
                }
                None => m.from < self.dwells.len() && m.to < self.dwells.len(),
            };
            if !ends || !finite {
                return Err(ChannelError::BadMove { index });
            }
        }
        Ok(())
    }

    /// Suspect dwells with a known heading and tilt: refit without the dwell and test whether its gyro means
    /// fit a heading 90, 180 or 270 deg off far better than the reference's.
    fn check_headings(&self, solution: &ChannelSolution, moves: &[ChannelMove]) -> Result<(), ChannelError> {
        let unknown_tilt = self.settings.attitude == AttitudeKnowledge::Unknown;
        if !self.settings.use_gyro || !self.settings.earth_rate_resolved || unknown_tilt || solution.suspect == 0 {
            return Ok(());
        }
        for (k, d) in self.dwells.iter().enumerate() {
            let Some(given) = d.heading_rad else { continue };
            if solution.suspect & (1 << k) == 0 {
                continue;
            }
            let without = self.solve_excluding_with(1 << k, moves)?;
            let cost = |heading: f32| self.heading_cost(d, &d.tilt, &without.parameters_si, heading, without.model);
            let at_given = cost(given);
            for quarter in 1..4 {
                let other = given + quarter as f32 * core::f32::consts::FRAC_PI_2;
                let c = cost(other);
                if c < CHI2_999[2] && at_given > CHI2_999[2] && c < 0.1 * at_given {
                    return Err(ChannelError::HeadingMismatch { dwell: k, given_rad: given, fits_rad: other });
                }
            }
        }
        Ok(())
    }

    /// The weighted cost of one dwell at `heading` over the tilt `tilt` (gyro rows only: gravity does not see
    /// the heading).
    fn heading_cost(
        &self,
        d: &ChannelDwell,
        tilt: &Mat3,
        theta: &[f32; PARAMETERS],
        heading: f32,
        model: Model,
    ) -> f32 {
        let lin = self.linearise(theta, &heading_rotation(heading).mul(tilt), model);
        let mut c = 0.0;
        for i in 0..3 {
            let r = d.rate_mean_b_radps[i] - lin.pred[i];
            c += r * r / d.rate_mean_var_b_radps2[i];
        }
        c
    }

    /// The heading that fits dwell `d` over `tilt` best given `theta`: a 5 deg grid, then Gauss-Newton in one
    /// dimension.
    fn profile_heading(&self, d: &ChannelDwell, tilt: &Mat3, theta: &[f32; PARAMETERS], model: Model) -> f32 {
        let step = core::f32::consts::PI / 36.0;
        let mut best = (f32::INFINITY, 0.0f32);
        for i in 0..72 {
            let h = i as f32 * step;
            let c = self.heading_cost(d, tilt, theta, h, model);
            if c < best.0 {
                best = (c, h);
            }
        }
        let mut heading = best.1;
        for _ in 0..6 {
            let lin = self.linearise(theta, &heading_rotation(heading).mul(tilt), model);
            let (mut num, mut den) = (0.0f32, 0.0f32);
            for i in 0..3 {
                let r = d.rate_mean_b_radps[i] - lin.pred[i];
                let w = 1.0 / d.rate_mean_var_b_radps2[i];
                num += lin.d_attitude[i][2] * r * w;
                den += lin.d_attitude[i][2] * lin.d_attitude[i][2] * w;
            }
            if den <= 0.0 {
                break;
            }
            let delta = (num / den).clamp(-step, step);
            heading += delta;
            if delta.abs() < 1e-7 {
                break;
            }
        }
        heading
    }

    /// Prediction and Jacobian of one dwell (the Earth rate only when the gyros resolve it).
    fn linearise(&self, theta: &[f32; PARAMETERS], c_ref: &Mat3, model: Model) -> Linearised {
        linearise(theta, c_ref, &self.site, model, self.settings.earth_rate_resolved)
    }

    /// Which attitude angles of dwell `d` are nuisance parameters: tilt about e and n (unknown attitudes),
    /// heading (unknown heading, gyro data used and resolving the Earth rate).
    fn nuisances(&self, d: &ChannelDwell) -> [bool; 3] {
        let tilt = self.settings.attitude == AttitudeKnowledge::Unknown;
        let heading = self.settings.use_gyro && self.settings.earth_rate_resolved && d.heading_rad.is_none();
        [tilt, tilt, heading]
    }

    /// The attitude of dwell `d` that fits its means best given `theta`, with its heading: the tilt that puts
    /// the calibrated measured gravity `T_a^-1 (f - b_a)` up, the heading profiled over it when unknown, then
    /// Gauss-Newton on every nuisance angle with all of the dwell's rows.
    fn profile_attitude(&self, d: &ChannelDwell, theta: &[f32; PARAMETERS], model: Model) -> (Mat3, f32) {
        let b_a = [theta[3], theta[4], theta[5]];
        let f = [0, 1, 2].map(|i| d.force_mean_b_mps2[i] - b_a[i]);
        let t_a = sensor_matrix(theta, 6, 9);
        let up_b = t_a.inverse().map_or(f, |t| t.mul_vec(f));
        let tilt = tilt_of_up(up_b);
        let active = self.nuisances(d);
        let mut heading = match d.heading_rad {
            Some(h) => h,
            None if active[2] => self.profile_heading(d, &tilt, theta, model),
            None => 0.0,
        };
        let mut c = heading_rotation(heading).mul(&tilt);
        let first = if self.settings.use_gyro { 0 } else { 3 };
        for _ in 0..4 {
            let lin = self.linearise(theta, &c, model);
            let mut normal = Mat3::IDENTITY;
            let mut rhs = [0.0f32; 3];
            for ch in first..6 {
                let (measured, var) = if ch < 3 {
                    (d.rate_mean_b_radps[ch], d.rate_mean_var_b_radps2[ch])
                } else {
                    (d.force_mean_b_mps2[ch - 3], d.force_mean_var_b_mps2sq[ch - 3])
                };
                let r = measured - lin.pred[ch];
                let j = [0, 1, 2].map(|m| if active[m] { lin.d_attitude[ch][m] } else { 0.0 });
                for a in 0..3 {
                    rhs[a] += j[a] * r / var;
                    for b in 0..3 {
                        normal.0[a][b] += j[a] * j[b] / var;
                    }
                }
            }
            // Equilibrated solve (the tilt and heading rows differ by orders of magnitude); an inactive angle
            // keeps its unit diagonal and a zero step.
            let scale = [0, 1, 2].map(|a| if normal.0[a][a] > 0.0 { 1.0 / libm::sqrtf(normal.0[a][a]) } else { 0.0 });
            let mut scaled = normal;
            for a in 0..3 {
                for b in 0..3 {
                    scaled.0[a][b] *= scale[a] * scale[b];
                }
                if scale[a] == 0.0 {
                    scaled.0[a][a] = 1.0;
                }
            }
            let Some(inverse) = scaled.inverse() else { break };
            let step = inverse.mul_vec([0, 1, 2].map(|a| rhs[a] * scale[a]));
            let mut phi = [0, 1, 2].map(|a| step[a] * scale[a]);
            let size = norm(phi);
            if !size.is_finite() {
                break;
            }
            if size > 0.1 {
                phi = phi.map(|x| x * 0.1 / size);
            }
            c = rotation([-phi[0], -phi[1], -phi[2]]).mul(&c);
            heading += phi[2];
            if size < 1e-7 {
                break;
            }
        }
        (c, heading)
    }

    /// Whitened rows of dwell `d` for the model's columns `cols` (`n` of them), scaled by `scale`, with the
    /// columns of the nuisance angles `nuisance`.
    #[allow(clippy::too_many_arguments, reason = "one call site; a struct would only rename the arguments")]
    fn rows(
        &self,
        d: &ChannelDwell,
        lin: &Linearised,
        cols: &[usize; PARAMETERS],
        n: usize,
        scale: &[f32; PARAMETERS],
        structural: bool,
        nuisance: [bool; 3],
    ) -> DwellRows {
        let mut out = DwellRows { a: [[0.0; PARAMETERS]; 6], y: [0.0; 6], h: [[0.0; 3]; 6], rows: 0 };
        let first = if self.settings.use_gyro { 0 } else { 3 };
        let g = self.site.gravity_mps2;
        for ch in first..6 {
            let (measured, var) = if ch < 3 {
                (d.rate_mean_b_radps[ch], d.rate_mean_var_b_radps2[ch])
            } else {
                (d.force_mean_b_mps2[ch - 3], d.force_mean_var_b_mps2sq[ch - 3])
            };
            let weight = if structural {
                if ch < 3 {
                    1.0 / EARTH_RATE_RADPS
                } else {
                    1.0 / g
                }
            } else {
                1.0 / libm::sqrtf(var)
            };
            let r = out.rows;
            for (c, &p) in cols.iter().enumerate().take(n) {
                let mut x = lin.jac[ch][p] * weight;
                if structural && x.abs() < 1e-6 {
                    x = 0.0;
                }
                out.a[r][c] = x * scale[c];
            }
            out.y[r] = (measured - lin.pred[ch]) * weight;
            for m in 0..3 {
                let mut h = if nuisance[m] { lin.d_attitude[ch][m] * weight } else { 0.0 };
                if structural && h.abs() < 1e-6 {
                    h = 0.0;
                }
                out.h[r][m] = h;
            }
            out.rows += 1;
        }
        out
    }

    /// Solves without the dwells marked in `exclude` (bit k = dwell k); no plausibility checks.
    pub fn solve_excluding(&self, exclude: u64) -> Result<ChannelSolution, ChannelError> {
        self.solve_excluding_with(exclude, &[])
    }

    /// [`ChannelEstimator::solve_excluding`] with moves; a move to or from a dwell left out is left out too.
    pub fn solve_excluding_with(&self, exclude: u64, moves: &[ChannelMove]) -> Result<ChannelSolution, ChannelError> {
        if self.dwells.is_empty() {
            return Err(ChannelError::NoDwells);
        }
        // Each move's dwells exist (an index beyond them would otherwise panic in its rows).
        self.check_moves(moves)?;
        let model = self.model();
        let (cols, n) = columns(model);
        if n == 0 {
            return Err(ChannelError::NothingToEstimate);
        }
        let used = |k: usize| exclude & (1u64 << k) == 0;
        let unknown_tilt = self.settings.attitude == AttitudeKnowledge::Unknown;
        let mut theta = [0.0f32; PARAMETERS];
        let mut heading = [0.0f32; MAX_DWELLS];
        let mut attitude = [Mat3::IDENTITY; MAX_DWELLS];
        for (k, d) in self.dwells.iter().enumerate() {
            heading[k] = d.heading_rad.unwrap_or(0.0);
            attitude[k] = heading_rotation(heading[k]).mul(&d.tilt);
        }
        let mut pass = Pass::default();
        let mut iterations = 0;
        let mut converged = false;
        let mut previous = f32::INFINITY;
        let mut refused = 0u64;
        while iterations < self.settings.max_iterations.max(1) {
            iterations += 1;
            // Every dwell's nuisance angles, the left-out ones too (their residuals are reported).
            for (k, d) in self.dwells.iter().enumerate() {
                if unknown_tilt {
                    (attitude[k], heading[k]) = self.profile_attitude(d, &theta, model);
                } else if self.nuisances(d)[2] {
                    heading[k] = self.profile_heading(d, &d.tilt, &theta, model);
                    attitude[k] = heading_rotation(heading[k]).mul(&d.tilt);
                }
            }
            if iterations == 1 {
                refused = self.gross_misfits(moves, &attitude);
            }
            pass = self.pass(&theta, &attitude, &cols, n, used, UsedMoves { all: moves, refused });
            let mut largest = 0.0f32;
            for c in 0..n {
                let p = cols[c];
                let step = pass.step_si[c];
                theta[p] += step;
                let std = libm::sqrtf(pass.cov_scaled[c][c].max(0.0)) * pass.scale[c];
                if std > 0.0 {
                    largest = largest.max(step.abs() / std);
                }
            }
            // Converged when the step is negligible against the standard errors, or when it has stopped
            // shrinking at a small level (the rounding of f32 on data far more precise than its errors).
            if largest < 1e-3 || (largest < 0.05 && largest > 0.5 * previous) {
                converged = true;
                break;
            }
            previous = largest;
        }
        // A fit that did not converge and left every instrument's range ran away: refused. (A converged fit
        // keeps its estimate, however imprecise: its standard error says so.)
        if let Some(parameter) = implausible_parameter(&theta).filter(|_| !converged) {
            return Err(ChannelError::Diverged { parameter, value: theta[parameter] });
        }
        let state = State { theta: &theta, heading: &heading, attitude: &attitude, cols: &cols, n, model, refused };
        Ok(self.finish(&state, &pass, used, iterations, converged, moves))
    }

    /// One Gauss-Newton pass at `theta` and the dwells' `attitude`: structural rank, weighted solution of the
    /// determined parameters.
    fn pass(
        &self,
        theta: &[f32; PARAMETERS],
        attitude: &[Mat3; MAX_DWELLS],
        cols: &[usize; PARAMETERS],
        n: usize,
        used: impl Fn(usize) -> bool,
        moves: UsedMoves<'_>,
    ) -> Pass {
        let UsedMoves { all: moves, refused } = moves;
        let model = self.model();
        let zero = [0.0f32; PARAMETERS];
        let ones = [1.0f32; PARAMETERS];
        let none = [false; 3];
        // Column norms of the weighted and the structural designs, for equilibration.
        let mut norm_w = [0.0f32; PARAMETERS];
        let mut norm_s = [0.0f32; PARAMETERS];
        let mut peak_s = [0.0f32; PARAMETERS];
        for (k, d) in self.dwells.iter().enumerate().filter(|(k, _)| used(*k)) {
            let lin = self.linearise(theta, &attitude[k], model);
            let lin_s = self.linearise(&zero, &attitude[k], model);
            let w = self.rows(d, &lin, cols, n, &ones, false, none);
            let s = self.rows(d, &lin_s, cols, n, &ones, true, none);
            for c in 0..n {
                for r in 0..w.rows {
                    norm_w[c] += w.a[r][c] * w.a[r][c];
                    norm_s[c] += s.a[r][c] * s.a[r][c];
                    peak_s[c] = peak_s[c].max(s.a[r][c].abs());
                }
            }
        }
        let use_gyro = self.settings.use_gyro;
        let used = &used;
        let moves_used = || {
            moves
                .iter()
                .enumerate()
                .filter(move |(k, m)| use_gyro && move_used(m, used) && (*k >= 64 || refused & (1 << k) == 0))
        };
        for (_, m) in moves_used() {
            let w = self.move_rows(m, theta, attitude, cols, n, &ones, false);
            let s = self.move_rows(m, theta, attitude, cols, n, &ones, true);
            for c in 0..n {
                for r in 0..w.rows {
                    norm_w[c] += w.a[r][c] * w.a[r][c];
                    norm_s[c] += s.a[r][c] * s.a[r][c];
                    peak_s[c] = peak_s[c].max(s.a[r][c].abs());
                }
            }
        }
        // A proportional term whose input never reaches 5 % of full scale in any dwell (an axis tilted by less
        // than 3 deg from horizontal for a scale factor) is not exercised by the schedule: absent, whatever a
        // fit would make of it (a 0.05 deg tilt would otherwise "determine" a scale factor from 9e-4 g).
        // A dwell whose heading is neither given nor estimated leaves the reference offset undefined: its axes
        // are navigation axes, and that dwell's are not known.
        let offset_undefined =
            self.dwells.iter().enumerate().any(|(k, d)| used(k) && d.heading_rad.is_none() && !self.nuisances(d)[2]);
        for c in 0..n {
            let p = cols[c];
            let full_scale = match p {
                33..=35 if offset_undefined => f32::INFINITY,
                6..=23 | 33..=35 => 1.0,
                24..=32 => self.site.gravity_mps2 / EARTH_RATE_RADPS,
                _ => continue,
            };
            if peak_s[c] < MIN_EXERCISE * full_scale {
                norm_s[c] = 0.0;
            }
        }
        let mut scale = [1.0f32; PARAMETERS];
        let mut scale_s = [1.0f32; PARAMETERS];
        for c in 0..n {
            if norm_w[c] > 0.0 {
                scale[c] = 1.0 / libm::sqrtf(norm_w[c]);
            }
            if norm_s[c] > 0.0 {
                scale_s[c] = 1.0 / libm::sqrtf(norm_s[c]);
            } else {
                scale_s[c] = 0.0;
            }
        }
        let mut weighted = SqrtInfo::<PARAMETERS>::new(n);
        let mut structure = SqrtInfo::<PARAMETERS>::new(n);
        for (k, d) in self.dwells.iter().enumerate().filter(|(k, _)| used(*k)) {
            let lin = self.linearise(theta, &attitude[k], model);
            let lin_s = self.linearise(&zero, &attitude[k], model);
            let nuisance = self.nuisances(d);
            let mut w = self.rows(d, &lin, cols, n, &scale, false, nuisance);
            let mut s = self.rows(d, &lin_s, cols, n, &scale_s, true, nuisance);
            let skip_w = eliminate_nuisances(&mut w, n);
            let skip_s = eliminate_nuisances(&mut s, n);
            for r in skip_w..w.rows {
                weighted.add_row(&w.a[r], w.y[r]);
            }
            for r in skip_s..s.rows {
                structure.add_row(&s.a[r], 0.0);
            }
        }
        for (_, m) in moves_used() {
            let w = self.move_rows(m, theta, attitude, cols, n, &scale, false);
            let s = self.move_rows(m, theta, attitude, cols, n, &scale_s, true);
            for r in 0..w.rows {
                weighted.add_row(&w.a[r], w.y[r]);
                structure.add_row(&s.a[r], 0.0);
            }
        }
        let (determined, blind_spots, gauge) = self.structural_rank(&structure.r, cols, n);
        // The determined columns of the weighted factor, triangularised again.
        let mut kept = [0usize; PARAMETERS];
        let mut m = 0;
        for (c, &d) in determined.iter().enumerate().take(n) {
            if d {
                kept[m] = c;
                m += 1;
            }
        }
        let mut restricted = SqrtInfo::<PARAMETERS>::new(m);
        for i in 0..n {
            let mut row = [0.0f32; PARAMETERS];
            for (slot, &c) in row.iter_mut().zip(kept.iter()).take(m) {
                *slot = weighted.r[i][c];
            }
            restricted.add_row(&row, weighted.z[i]);
        }
        let x = solve_upper(&restricted.r, &restricted.z, m);
        let mut cov_kept = [[0.0f32; PARAMETERS]; PARAMETERS];
        inverse_gram(&restricted.r, m, &mut cov_kept);
        let mut pass = Pass { scale, determined, blind_spots, gauge, ..Pass::default() };
        for (i, &ci) in kept.iter().enumerate().take(m) {
            pass.step_si[ci] = x[i] * scale[ci];
            for (j, &cj) in kept.iter().enumerate().take(m) {
                pass.cov_scaled[ci][cj] = cov_kept[i][j];
            }
        }
        pass.restricted = restricted.r;
        pass.kept = kept;
        pass.kept_count = m;
        pass
    }

    /// The structural rank of the (unit-column) structural factor `r`: which model columns are determined, the
    /// number of blind spots, and the gauge (parameter bits held at zero to fix the body frame). With unknown
    /// attitudes and the accelerometer misalignments in the model, the gauge columns are removed and the rank
    /// is taken again.
    fn structural_rank(
        &self,
        r: &[[f32; PARAMETERS]; PARAMETERS],
        cols: &[usize; PARAMETERS],
        n: usize,
    ) -> ([bool; PARAMETERS], u32, u64) {
        let (mut determined, blind_spots) = self.determined_columns(r, n);
        let mut gauge = 0u64;
        if self.settings.attitude == AttitudeKnowledge::Unknown && self.model().contains(Term::AccelMisalignment) {
            // Zeroing a column of R zeroes the same column of the design (A = Q R).
            let mut fixed = *r;
            for c in 0..n {
                if GAUGE_PARAMETERS.contains(&cols[c]) {
                    gauge |= 1 << cols[c];
                    for row in fixed.iter_mut() {
                        row[c] = 0.0;
                    }
                }
            }
            determined = self.determined_columns(&fixed, n).0;
        }
        (determined, blind_spots, gauge)
    }

    /// SVD of a structural factor of `n` columns: whether each column is determined (its squared share in the
    /// blind spots at most the share tolerance), and the number of blind spots.
    fn determined_columns(&self, r: &[[f32; PARAMETERS]; PARAMETERS], n: usize) -> ([bool; PARAMETERS], u32) {
        let mut a = *r;
        let mut v = [[0.0f32; PARAMETERS]; PARAMETERS];
        let sigma = jacobi_svd(&mut a, &mut v, n);
        let largest = sigma.iter().take(n).fold(0.0f32, |m, s| m.max(*s));
        let seen = |j: usize| sigma[j] > self.settings.rank_tolerance * largest;
        let mut determined = [false; PARAMETERS];
        for (c, slot) in determined.iter_mut().enumerate().take(n) {
            let share: f32 = (0..n).filter(|&j| !seen(j)).map(|j| v[c][j] * v[c][j]).sum();
            *slot = largest > 0.0 && share <= self.settings.share_tolerance;
        }
        (determined, (0..n).filter(|&j| !seen(j)).count() as u32)
    }

    fn finish(
        &self,
        state: &State<'_>,
        pass: &Pass,
        used: impl Fn(usize) -> bool,
        iterations: u32,
        converged: bool,
        moves: &[ChannelMove],
    ) -> ChannelSolution {
        let State { theta, heading, attitude, cols, n, model, .. } = *state;
        let mut sol = ChannelSolution::empty(model, self.dwells.len());
        sol.heading_rad = *heading;
        sol.iterations = iterations;
        sol.converged = converged;
        sol.attitude = self.settings.attitude;
        sol.earth_rate_resolved = self.settings.earth_rate_resolved;
        sol.blind_spots = pass.blind_spots;
        sol.gauge = pass.gauge;
        sol.moves_refused = state.refused;
        for c in 0..n {
            let p = cols[c];
            if pass.determined[c] {
                sol.observable |= 1 << p;
                sol.parameters_si[p] = theta[p];
                for d in 0..n {
                    if pass.determined[d] {
                        sol.covariance_si[p][cols[d]] = pass.cov_scaled[c][d] * pass.scale[c] * pass.scale[d];
                    }
                }
            } else {
                sol.unobservable |= 1 << p;
            }
        }
        let first = if self.settings.use_gyro { 0 } else { 3 };
        let mut channels = 0u32;
        let mut nuisances = 0u32;
        for (k, d) in self.dwells.iter().enumerate() {
            sol.up_b[k] = attitude[k].row(2);
            let lin = self.linearise(theta, &attitude[k], model);
            let nuisance = self.nuisances(d);
            let mut rows = self.rows(d, &lin, cols, n, &pass.scale, false, nuisance);
            for i in 0..3 {
                sol.residual_rate_b_radps[k][i] = if first == 0 { d.rate_mean_b_radps[i] - lin.pred[i] } else { 0.0 };
                sol.residual_force_b_mps2[k][i] = d.force_mean_b_mps2[i] - lin.pred[3 + i];
            }
            if !used(k) {
                continue;
            }
            let h_norm2: f32 = rows.h[..rows.rows].iter().map(|h| h[2] * h[2]).sum();
            if nuisance[2] && h_norm2 > 0.0 {
                sol.heading_std_rad[k] = 1.0 / libm::sqrtf(h_norm2);
            }
            // The dwell's own freedom: its nuisance angles take one row each (the residuals are at the
            // profiled optimum, so the reflection leaves the residual sum of squares unchanged).
            let skip = eliminate_nuisances(&mut rows, n);
            // Leverage of the dwell's remaining rows: h = |R^-T a|^2 over the determined columns.
            let mut chi2 = 0.0f32;
            let mut leverage = skip as f32;
            for r in 0..rows.rows {
                chi2 += rows.y[r] * rows.y[r];
                if r < skip {
                    continue;
                }
                let mut a = [0.0f32; PARAMETERS];
                for (slot, &c) in a.iter_mut().zip(pass.kept.iter()).take(pass.kept_count) {
                    *slot = rows.a[r][c];
                }
                let b = solve_upper_transposed(&pass.restricted, &a, pass.kept_count);
                leverage += b.iter().take(pass.kept_count).map(|x| x * x).sum::<f32>();
            }
            nuisances += skip as u32;
            channels += rows.rows as u32;
            sol.chi_square += chi2;
            let free = rows.rows as f32 - leverage;
            if free >= 0.5 {
                let statistic = chi2 * rows.rows as f32 / free;
                sol.dwell_statistic[k] = statistic;
                if statistic > CHI2_999[rows.rows - 1] {
                    sol.suspect |= 1 << k;
                }
            }
        }
        if self.settings.use_gyro {
            channels += self.finish_moves(&mut sol, state, pass, &used, moves);
        }
        sol.degrees_of_freedom = channels.saturating_sub(pass.kept_count as u32 + nuisances);
        sol
    }

    /// Each move's residual, and the statistics of those used: their chi-square is added to the solution's;
    /// returns their rows.
    fn finish_moves(
        &self,
        sol: &mut ChannelSolution,
        state: &State<'_>,
        pass: &Pass,
        used: &impl Fn(usize) -> bool,
        moves: &[ChannelMove],
    ) -> u32 {
        let State { theta, attitude, cols, n, refused, .. } = *state;
        let mut channels = 0;
        for (k, m) in moves.iter().enumerate().take(MAX_MOVES) {
            let rows = self.move_rows(m, theta, attitude, cols, n, &pass.scale, false);
            sol.move_residual_rad[k] = rows.residual_rad;
            sol.moves += 1;
            if !move_used(m, used) || refused & (1 << k) != 0 {
                continue;
            }
            let chi2: f32 = rows.y[..rows.rows].iter().map(|y| y * y).sum();
            sol.move_statistic[k] = chi2;
            sol.move_rows[k] = rows.rows as u8;
            sol.chi_square += chi2;
            channels += rows.rows as u32;
        }
        channels
    }

    /// The moves whose rotation at their prior is further than [`MAX_MOVE_MISFIT_RAD`] from the reference's at
    /// the dwells' `attitude` (bit k: move k).
    fn gross_misfits(&self, moves: &[ChannelMove], attitude: &[Mat3; MAX_DWELLS]) -> u64 {
        let mut refused = 0u64;
        for (k, m) in moves.iter().enumerate().take(MAX_MOVES) {
            if m.turn.is_some() || m.from >= self.dwells.len() || m.to >= self.dwells.len() {
                continue;
            }
            let e = self.rotation_misfit(m, attitude).e_rad;
            // NaN is refused too.
            if norm(e).is_nan() || norm(e) > MAX_MOVE_MISFIT_RAD {
                refused |= 1 << k;
            }
        }
        refused
    }

    /// The rotation error of each of `moves` (at most [`MAX_MOVES`]) at the parameters `parameters_si`, with the
    /// dwells' attitudes of `solution` (body frame at the start of each move, rad; without the part about up
    /// when a heading at either end is unknown): moves held out of the fit, checked against a calibration.
    pub fn move_residuals(
        &self,
        parameters_si: &[f32; PARAMETERS],
        solution: &ChannelSolution,
        moves: &[ChannelMove],
    ) -> [Vec3; MAX_MOVES] {
        let mut attitude = [Mat3::IDENTITY; MAX_DWELLS];
        for (k, d) in self.dwells.iter().enumerate() {
            let tilt = if self.settings.attitude == AttitudeKnowledge::Unknown {
                tilt_of_up(solution.up_b[k])
            } else {
                d.tilt
            };
            attitude[k] = heading_rotation(solution.heading_rad[k]).mul(&tilt);
        }
        let (cols, n) = columns(solution.model);
        let ones = [1.0f32; PARAMETERS];
        let mut out = [[0.0f32; 3]; MAX_MOVES];
        for (slot, m) in out.iter_mut().zip(moves) {
            *slot = self.move_rows(m, parameters_si, &attitude, &cols, n, &ones, false).residual_rad;
        }
        out
    }

    /// The rotation error of a move between two dwells at its prior (start frame, rad), the basis of its rows
    /// (three, or two without the part about up when a heading at either end is unknown), the number of rows,
    /// and whether the horizontal Earth rate's direction is unknown.
    fn rotation_misfit(&self, m: &ChannelMove, attitude: &[Mat3; MAX_DWELLS]) -> Misfit {
        let w_n = self.site.earth_rate_n_radps();
        let (c_from, c_to) = (attitude[m.from], attitude[m.to]);
        // The body's rotation relative to inertial space: the navigation frame turns with the Earth.
        let earth = rotation(w_n.map(|w| w * m.duration_s));
        let (from, to) = (&self.dwells[m.from], &self.dwells[m.to]);
        let unresolved = [from, to].iter().any(|d| d.heading_rad.is_none() && !self.nuisances(d)[2]);
        let twist_free = from.heading_rad.is_none() || to.heading_rad.is_none();
        let reference = c_from.transpose().mul(&earth).mul(&c_to);
        let up = c_from.row(2);
        let q_ref = Quat::from_mat3(&reference);
        let misfit = m.rotation.mul(&q_ref.conjugate());
        if twist_free {
            // Two directions at right angles to up.
            let helper = if up[0].abs() < 0.9 { [1.0, 0.0, 0.0] } else { [0.0, 1.0, 0.0] };
            let b1 = cross(up, helper);
            let b1 = b1.map(|x| x / norm(b1));
            let (swing, twist) = swing_about(&misfit, up);
            let basis = [b1, cross(up, b1), [0.0; 3]];
            // A change of the move's rotation (start frame) reaches the swing turned back by the twist.
            let frame = twist.conjugate().to_mat3();
            Misfit { e_rad: swing.to_rotation_vector(), basis, rows: 2, unresolved, frame }
        } else {
            Misfit {
                e_rad: misfit.to_rotation_vector(),
                basis: IDENTITY_BASIS,
                rows: 3,
                unresolved,
                frame: Mat3::IDENTITY,
            }
        }
    }

    /// The rows of one move at `theta` and the dwells' `attitude`: whitened by its covariance, or, `structural`,
    /// in units of the Earth rate over the move with entries below 1e-6 of it set to zero; model columns `cols`
    /// scaled by `scale`. Without a heading at either end the part about up at the start is left out (two
    /// rows): the reference does not say how far the body turned about the vertical.
    #[allow(clippy::too_many_arguments, reason = "the same arguments as the dwells' rows")]
    fn move_rows(
        &self,
        m: &ChannelMove,
        theta: &[f32; PARAMETERS],
        attitude: &[Mat3; MAX_DWELLS],
        cols: &[usize; PARAMETERS],
        n: usize,
        scale: &[f32; PARAMETERS],
        structural: bool,
    ) -> MoveRows {
        let w_n = self.site.earth_rate_n_radps();
        let Misfit { e_rad: misfit, basis, rows, unresolved, frame } = match m.turn {
            // The integral of the rate against the turns made and the Earth's rotation about up (its horizontal
            // part turns with the body and is added as noise below).
            Some(t) => {
                let vertical = w_n[2] * m.duration_s;
                let e_rad = [0, 1, 2].map(|i| t.angle_sum_b_rad[i] - t.angle_b_rad[i] - t.up_b[i] * vertical);
                Misfit { e_rad, basis: IDENTITY_BASIS, rows: 3, unresolved: true, frame: Mat3::IDENTITY }
            }
            None => self.rotation_misfit(m, attitude),
        };
        // The Jacobian in the residual's frame.
        let mut jacobian = [[0.0f32; MOVE_PARAMETERS.len()]; 3];
        for (c, _) in MOVE_PARAMETERS.iter().enumerate() {
            let column = frame.mul_vec([m.jacobian[0][c], m.jacobian[1][c], m.jacobian[2][c]]);
            for a in 0..3 {
                jacobian[a][c] = column[a];
            }
        }
        // The error at theta: the prior's plus the linear change since the prior.
        let mut e = misfit;
        for (c, &p) in MOVE_PARAMETERS.iter().enumerate() {
            let delta = theta[p] - m.prior_si[c];
            for (a, slot) in e.iter_mut().enumerate() {
                *slot += jacobian[a][c] * delta;
            }
        }
        // The covariance in the basis; an unknown heading also leaves the horizontal Earth rate's direction
        // unknown when it is not estimated: its angle over the move is added as noise.
        let mut cov = frame.mul(&m.covariance_rad2).mul(&frame.transpose());
        if unresolved {
            let horizontal = self.site.earth_rate_north_radps() * m.duration_s;
            for i in 0..3 {
                cov.0[i][i] += horizontal * horizontal;
            }
        }
        let mut out = MoveRows { a: [[0.0; PARAMETERS]; 3], y: [0.0; 3], rows, residual_rad: e };
        let unit = if structural { 1.0 / (EARTH_RATE_RADPS * m.duration_s) } else { 1.0 };
        for (r, b) in basis.iter().enumerate().take(rows) {
            out.y[r] = if structural { 0.0 } else { -dot(*b, e) };
            for (c, &p) in cols.iter().enumerate().take(n) {
                let Some(mc) = move_column(p) else { continue };
                let x = (0..3).map(|k| b[k] * jacobian[k][mc]).sum::<f32>() * unit;
                out.a[r][c] = if structural && x.abs() < 1e-6 { 0.0 } else { x * scale[c] };
            }
        }
        if structural {
            return out;
        }
        // Whitening: rows times the inverse of the Cholesky factor of B cov B^T.
        let mut s = [[0.0f32; 3]; 3];
        for i in 0..rows {
            for j in 0..rows {
                s[i][j] = dot(basis[i], cov.mul_vec(basis[j]));
            }
        }
        let Some(l) = cholesky3(&s, rows) else {
            out.rows = 0;
            return out;
        };
        for c in 0..n + 1 {
            // Forward substitution on column c (c == n: the right-hand side).
            let mut x = [0.0f32; 3];
            for i in 0..rows {
                let mut v = if c < n { out.a[i][c] } else { out.y[i] };
                for (j, xj) in x.iter().enumerate().take(i) {
                    v -= l[i][j] * xj;
                }
                x[i] = v / l[i][i];
            }
            for (i, xi) in x.iter().enumerate().take(rows) {
                if c < n {
                    out.a[i][c] = *xi;
                } else {
                    out.y[i] = *xi;
                }
            }
        }
        out
    }
}

/// The moves of a pass: all of them, and those left out as gross misfits (bit k: move k).
#[derive(Clone, Copy)]
struct UsedMoves<'a> {
    all: &'a [ChannelMove],
    refused: u64,
}

/// The rows of x, y and z.
const IDENTITY_BASIS: [Vec3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A move's error at its prior, in the frame of its residual.
struct Misfit {
    /// The error, rad.
    e_rad: Vec3,
    /// The directions of its rows (the first `rows`).
    basis: [Vec3; 3],
    rows: usize,
    /// Whether the horizontal Earth rate's direction over the move is unknown.
    unresolved: bool,
    /// From a change of the move's rotation (start frame) to the residual's frame.
    frame: Mat3,
}

/// Whether a move is used when the dwells `used` are: a closed move always, another when both its dwells are.
fn move_used(m: &ChannelMove, used: &impl Fn(usize) -> bool) -> bool {
    m.turn.is_some() || (used(m.from) && used(m.to))
}

/// The rows of one move (up to three), its residual and its number of rows.
struct MoveRows {
    a: [[f32; PARAMETERS]; 3],
    y: [f32; 3],
    rows: usize,
    /// The rotation error at the parameters, start frame, rad.
    residual_rad: Vec3,
}

/// The lower Cholesky factor of the leading `n` x `n` block of a symmetric matrix, or `None` when it is not
/// positive definite.
fn cholesky3(s: &[[f32; 3]; 3], n: usize) -> Option<[[f32; 3]; 3]> {
    let mut l = [[0.0f32; 3]; 3];
    for i in 0..n {
        for j in 0..=i {
            let mut v = s[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k];
            }
            if i == j {
                // NaN is refused too.
                if v.is_nan() || v <= 0.0 {
                    return None;
                }
                l[i][i] = libm::sqrtf(v);
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    Some(l)
}

/// The state of one solve that [`ChannelEstimator::finish`] reports.
#[derive(Clone, Copy)]
struct State<'a> {
    theta: &'a [f32; PARAMETERS],
    heading: &'a [f32; MAX_DWELLS],
    attitude: &'a [Mat3; MAX_DWELLS],
    cols: &'a [usize; PARAMETERS],
    n: usize,
    model: Model,
    /// Moves left out as gross misfits (bit k: move k).
    refused: u64,
}

/// What one Gauss-Newton pass leaves for the next and for the final statistics.
struct Pass {
    /// The step, SI units, by model column.
    step_si: [f32; PARAMETERS],
    /// Covariance of the equilibrated parameters, by model column.
    cov_scaled: [[f32; PARAMETERS]; PARAMETERS],
    /// The equilibration, by model column: the design's columns are multiplied by it, so it is also the SI
    /// units per equilibrated unit of each parameter.
    scale: [f32; PARAMETERS],
    /// Whether each model column is determined by the schedule.
    determined: [bool; PARAMETERS],
    /// The weighted factor of the determined columns.
    restricted: [[f32; PARAMETERS]; PARAMETERS],
    /// Model columns of the determined parameters, and their number.
    kept: [usize; PARAMETERS],
    kept_count: usize,
    /// Blind spots of the structural design before the gauge, and the gauge's parameter bits.
    blind_spots: u32,
    gauge: u64,
}

impl Default for Pass {
    fn default() -> Pass {
        Pass {
            step_si: [0.0; PARAMETERS],
            cov_scaled: [[0.0; PARAMETERS]; PARAMETERS],
            scale: [0.0; PARAMETERS],
            determined: [false; PARAMETERS],
            restricted: [[0.0; PARAMETERS]; PARAMETERS],
            kept: [0; PARAMETERS],
            kept_count: 0,
            blind_spots: 0,
            gauge: 0,
        }
    }
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
