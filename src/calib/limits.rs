//! The thresholds that decide whether a dwell is at rest and whether its pose is plausible: each default defined
//! once, with its unit (or `relative`) in its name. The calibration sequence checks every sample against the rest
//! thresholds (`run::sequence::SequenceSettings`); the estimators check every dwell's mean against the
//! pose thresholds before a fit ([`crate::calib::general::ChannelSettings`], [`crate::calib::angles`]).

/// Largest angle between a sample's specific force and the announced up direction, rad, while a dwell is
/// sampled (`run::sequence::RestLimits::gravity_angle_max_rad`): 0.1 rad (5.7 deg) lets
/// vibration and a tilted table through, not a wrong face down.
pub const REST_GRAVITY_ANGLE_MAX_RAD: f32 = 0.1;

/// Largest | |f| - g | of one sample of a body at rest, m/s^2
/// (`run::sequence::RestLimits::force_error_max_mps2`): 0.5 m/s^2 (51 mg) passes vibration
/// and scale errors, and aborts a dwell whose body is moved.
pub const REST_FORCE_ERROR_MAX_MPS2: f32 = 0.5;

/// Largest angular rate magnitude of one sample of a body at rest, rad/s
/// (`run::sequence::RestLimits::rate_max_radps`): 2 deg/s, far above any gyro bias and the
/// Earth rate, far below a table that turns.
pub const REST_RATE_MAX_RADPS: f32 = 2.0f32.to_radians();

/// Largest angle between a dwell's mean specific force and the up direction of its reference attitude, rad,
/// before a fit ([`crate::calib::general::ChannelSettings::pose_gravity_angle_max_rad`]): 0.1745 rad (10 deg)
/// catches a wrong face down, wrong axes or a wrong pitch/roll, and passes misalignments and poses placed by hand.
pub const POSE_GRAVITY_ANGLE_MAX_RAD: f32 = 0.1745;

/// Largest relative difference between a dwell's mean |f| and g accepted before a fit, 1 (not %): 0.2, beyond
/// any accelerometer scale error; more means a body not at rest or wrong units. The angle method uses it as it
/// is; the general estimator's default
/// ([`crate::calib::general::ChannelSettings::force_magnitude_error_max_relative`]).
pub const FORCE_MAGNITUDE_ERROR_MAX_RELATIVE: f32 = 0.2;
