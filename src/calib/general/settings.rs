//! The estimator's settings ([`ChannelSettings`]) and what it knows of the dwells' attitudes
//! ([`AttitudeKnowledge`]).

use crate::calib::general::terms::Model;
use crate::calib::limits::{FORCE_MAGNITUDE_ERROR_MAX_RELATIVE, POSE_GRAVITY_ANGLE_MAX_RAD};
use crate::calib::noise_model::NoiseModel;

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
    /// (Default [`FORCE_MAGNITUDE_ERROR_MAX_RELATIVE`].)
    pub force_magnitude_error_max_relative: f32,
    /// Largest angle between measured gravity and the reference's accepted before the fit, rad.
    /// (Default [`POSE_GRAVITY_ANGLE_MAX_RAD`].)
    pub pose_gravity_angle_max_rad: f32,
    /// Whether the dwells' tilts are a reference or unknown (then nuisance parameters).
    pub attitude: AttitudeKnowledge,
    /// How well the reference attitudes are known, rad (one standard deviation, each axis): with
    /// [`AttitudeKnowledge::Reference`] and a tolerance above 0, each dwell's attitude error (the tilt about
    /// east and north, and the heading where the gyros resolve the Earth rate) is a nuisance parameter with the
    /// prior N(0, tolerance^2) (docs/method.md#poses-known-to-a-tolerance). 0: the labels are exact.
    pub pose_tolerance_rad: f32,
    /// Whether the gyros resolve the Earth rate (their dwell means and errors are well below it). Without, the
    /// gyro model leaves the Earth rate out: no heading is estimated or checked, and the gyro scale factors and
    /// misalignments, which a static pose sees only through the Earth rate, are not exercised.
    pub earth_rate_resolved: bool,
    /// The channels' noise model, named once from a static run (docs/method.md#noise-model): with it, the
    /// variance of each dwell mean is the model's at the dwell's length; without, the session's own pooled
    /// dwell noise (docs/method.md#honest-errors). The estimator itself reads the dwells' variances only;
    /// [`session_estimator`](crate::calib::session::session_estimator) sets them from this.
    pub noise: Option<NoiseModel>,
}

/// What the session knows of the dwells' attitudes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AttitudeKnowledge {
    /// Every dwell's tilt ([`ChannelDwell::tilt`](crate::calib::general::ChannelDwell::tilt)) is the reference's; its heading too unless `None`.
    #[default]
    Reference,
    /// No dwell's tilt is known (hand-placed poses): the direction of gravity in the body is two nuisance
    /// angles per dwell and [`ChannelDwell::tilt`](crate::calib::general::ChannelDwell::tilt) is ignored; a heading given is kept, an unknown one is a
    /// nuisance as well when gyro data are used.
    Unknown,
}

impl Default for ChannelSettings {
    fn default() -> ChannelSettings {
        ChannelSettings {
            model: Model::BIASES,
            use_gyro: true,
            max_iterations: 12,
            rank_tolerance: 1e-4,
            share_tolerance: 1e-3,
            force_magnitude_error_max_relative: FORCE_MAGNITUDE_ERROR_MAX_RELATIVE,
            pose_gravity_angle_max_rad: POSE_GRAVITY_ANGLE_MAX_RAD,
            attitude: AttitudeKnowledge::Reference,
            pose_tolerance_rad: 0.0,
            earth_rate_resolved: true,
            noise: None,
        }
    }
}
