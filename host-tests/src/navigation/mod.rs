//! Attitude and navigation of an IMU at rest: the coarse alignment of every dwell of `sinscal align`
//! ([`alignment`]), and the navigation check of `sinscal navigate`: a strapdown engine ([`strapdown`], f64, ENU)
//! and the static run of a recording with and without the calibration applied ([`check`]).

pub mod alignment;
pub mod check;
pub mod strapdown;
