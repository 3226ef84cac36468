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
//!
//! Files: `terms` (the term table), `settings`, `error`, `correlation` (the covariance the noise model's
//! correlation between dwells adds), `estimator` (the dwells, the checks, Gauss-Newton),
//! `linearise` (the prediction and its rows), `nuisance` (unknown headings and tilts), `observability` (blind
//! spots and the gauge), `move_rows` (the moves' rows), `solution` (the solution and its statistics).

mod correlation;
mod error;
mod estimator;
mod linearise;
mod move_rows;
mod nuisance;
mod observability;
mod settings;
mod solution;
mod terms;

pub use error::ChannelError;
pub use estimator::{ChannelDwell, ChannelEstimator, MAX_DWELLS};
pub use linearise::{g_sensitivity_radps_per_mps2, sensor_matrix};
pub use observability::MIN_EXERCISE;
pub use settings::{AttitudeKnowledge, ChannelSettings};
pub use solution::ChannelSolution;
pub use terms::{
    implausible_parameter, misalignment_index, parameter_name, Axes, Model, Term, TermInfo, GAUGE_PARAMETERS,
    PARAMETERS, PLAUSIBLE_MAGNITUDE_SI, TERMS,
};
