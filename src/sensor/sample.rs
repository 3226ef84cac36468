//! What a sensor delivers: one sample in the body frame, SI units ([`ImuSample`]), and a reading with
//! the sensor's counter and temperature ([`ImuReading`]).

use crate::math::linalg::Vec3;

/// One IMU sample in the body frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuSample {
    /// Angular rate measured by the gyros, body frame, rad/s.
    pub rate_b_radps: Vec3,
    /// Specific force measured by the accelerometers, body frame, m/s^2.
    pub force_b_mps2: Vec3,
}

/// One sample from the sensor.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ImuReading {
    /// Angular rate and specific force, body frame, SI.
    pub sample: ImuSample,
    /// The sensor's sample counter (wraps).
    pub counter: u16,
    /// Samples the sensor produced but the host never read, from the counter gap since the last reading.
    pub missed: u16,
    /// Sensor temperature, deg C.
    pub temperature_c: f32,
}
