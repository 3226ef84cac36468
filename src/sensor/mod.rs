//! Sensors: what a sample is ([`sample`]), what the sampling code needs from any driver ([`source`]), and
//! the ADIS1647x/1650x driver over embedded-hal 1.0 SPI ([`adis`]). Depends on [`crate::math`] only.

pub mod adis;
pub mod sample;
pub mod source;
