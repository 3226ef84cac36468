//! The firmware's run time, free of any board: the data-ready handler that reads the IMU and queues the
//! readings ([`sampling`]), and the calibration sequence that consumes them ([`sequence`]).

pub mod sampling;
pub mod sequence;
