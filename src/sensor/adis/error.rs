//! Errors of the ADIS driver and their fault classes.

use crate::sensor::source::{ClassifiedError, ReadFault};

/// Errors of the driver. `E` is the SPI device's error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AdisError<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// Checksum mismatch.
    Checksum {
        /// Sum of the received bytes.
        computed: u16,
        /// Checksum word received.
        received: u16,
    },
    /// DATA_CNTR did not advance since the last burst.
    StalledCounter {
        /// The counter value read twice.
        counter: u16,
    },
    /// DIAG_STAT reported a fault.
    Status {
        /// The DIAG_STAT word.
        diag_stat: u16,
    },
    /// The buffer is shorter than the model's burst.
    ShortBurst {
        /// Bytes given.
        len: usize,
    },
    /// PROD_ID is not the configured model's.
    WrongProduct {
        /// Expected PROD_ID.
        expected: u16,
        /// PROD_ID read.
        found: u16,
    },
}

impl<E: core::fmt::Debug> core::fmt::Display for AdisError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AdisError::Spi(e) => write!(f, "SPI error: {e:?}"),
            AdisError::Checksum { computed, received } => {
                write!(f, "burst checksum {received:#06x} does not match the data ({computed:#06x})")
            }
            AdisError::StalledCounter { counter } => write!(f, "data counter stalled at {counter}"),
            AdisError::Status { diag_stat } => write!(f, "DIAG_STAT flags {diag_stat:#06x}"),
            AdisError::WrongProduct { expected, found } => write!(f, "PROD_ID {found}, expected {expected}"),
            AdisError::ShortBurst { len } => write!(f, "burst of {len} bytes is too short"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for AdisError<E> {}

impl<E: core::fmt::Debug> ClassifiedError for AdisError<E> {
    fn fault(&self) -> ReadFault {
        match self {
            AdisError::Spi(_) | AdisError::WrongProduct { .. } | AdisError::ShortBurst { .. } => ReadFault::Bus,
            AdisError::Checksum { .. } => ReadFault::Checksum,
            AdisError::StalledCounter { .. } => ReadFault::StalledCounter,
            AdisError::Status { .. } => ReadFault::StatusFlag,
        }
    }
}
