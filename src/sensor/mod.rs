//! Sensors: what a sample is ([`sample`]), what the sampling code needs from any driver ([`source`]), the
//! ADIS1647x/1650x driver over embedded-hal 1.0 SPI ([`adis`]), and an SPI transaction on a byte-at-a-time port
//! for the boards' SPI devices ([`spi`]). Depends on [`crate::math`] only.

pub mod adis;
pub mod sample;
pub mod source;
pub mod spi;
