//! The IMU sample source abstraction: what the sampling code needs from any sensor driver.
//!
//! A driver turns the sensor's frames into [`ImuReading`]s in SI units, body frame (docs/conventions.md: x right,
//! y forward, z up; the sensor's axes must be mounted or remapped to it). Faults are classified into
//! [`ReadFault`] so that the sampling layer can count and report them without knowing the driver.

use crate::sensor::sample::ImuReading;

/// The kinds of read failure, as the sampling layer counts them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReadFault {
    /// The bus transfer failed.
    Bus,
    /// The frame's checksum did not match: corrupted transfer.
    Checksum,
    /// The sample counter did not advance: the same (old) sample was read again.
    StalledCounter,
    /// The sensor flagged a fault in its status word.
    StatusFlag,
    /// Every byte of the frame was zero: the data line stuck low (or a sensor that does not drive it). Such
    /// a frame passes a byte-sum checksum (0 = 0), so it is recognised on its own.
    DeadBus,
}

/// An error that knows its [`ReadFault`] class.
pub trait ClassifiedError: core::fmt::Debug {
    /// The class of this failure.
    fn fault(&self) -> ReadFault;
}

/// A source of IMU samples, one per data-ready event.
pub trait ImuSource {
    /// The driver's error.
    type Error: ClassifiedError;

    /// Reads the newest sample. Called once per data-ready event (100 Hz), from interrupt context.
    fn read(&mut self) -> Result<ImuReading, Self::Error>;
}
