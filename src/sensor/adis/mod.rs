//! Driver for the Analog Devices ADIS1647x / ADIS1650x IMU family over SPI (embedded-hal 1.0).
//!
//! Register map, burst format, checksum and scale factors: ADIS16470 and ADIS16505 data sheets (Analog
//! Devices, Rev. C / Rev. A), as implemented in the Linux IIO driver `drivers/iio/imu/adis16475.c`:
//! - registers are 16-bit, big-endian on the wire; reading register `r` sends the word `[r, 0x00]` and
//!   returns the value in the next word; writing sends `[0x80 | r, low byte]`, `[0x80 | (r+1), high byte]`;
//!   outside burst mode each word is its own chip-select cycle and is followed by the stall time
//!   (t_STALL >= 16 us, [`STALL_NS`]);
//! - start-up: software reset (GLOB_CMD bit 7) and its recovery time, self-test (GLOB_CMD bit 2) and its
//!   time, DIAG_STAT = 0, PROD_ID, then the configuration written and read back ([`Adis::init`]);
//! - a burst read sends the word `[GLOB_CMD, 0x00]` = 0x6800 and then clocks out the burst:
//!   16-bit burst (ADIS1647x, and ADIS1650x with BURST_SEL = 0): DIAG_STAT, X/Y/Z_GYRO_OUT,
//!   X/Y/Z_ACCL_OUT, TEMP_OUT, DATA_CNTR, checksum (10 words);
//!   32-bit burst (ADIS1650x with MSC_CTRL bit 9 set): DIAG_STAT, then for each of the six channels its
//!   _LOW and _OUT words, TEMP_OUT, DATA_CNTR, checksum (16 words);
//! - the checksum is the 16-bit sum of all preceding bytes of the burst (not the command); a burst of zero
//!   bytes only passes it and is refused on its own ([`AdisError::DeadBus`]);
//! - the internal sample rate is 2000 SPS; DEC_RATE = 19 decimates to the 100 Hz output rate;
//! - bursts are read at an SPI clock of at most 1 MHz.
//!
//! The 32-bit outputs are fixed-point values in units of the 16-bit LSB: `OUT` is the integer part and
//! `LOW` the fraction (`I16F16`).
//!
//! Split by role: [`registers`] (addresses, constants, models and scale factors), [`burst`] (the burst frame:
//! checksum, decoding, encoding), [`error`] (the driver's errors and their fault classes), [`device`] (the
//! driver over an embedded-hal [`SpiDevice`](embedded_hal::spi::SpiDevice)).

pub mod burst;
pub mod device;
pub mod error;
pub mod registers;

pub use burst::*;
pub use device::*;
pub use error::*;
pub use registers::*;
