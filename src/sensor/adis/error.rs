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
    /// Every byte of the burst was zero (the data line stuck low): a frame the checksum cannot catch, since
    /// the sum of zero bytes is the zero checksum word.
    DeadBus,
    /// DIAG_STAT was not 0 after the self-test (bit 5: sensor failure; all ones: nothing drives the data line).
    SelfTest {
        /// The DIAG_STAT word read after the self-test.
        diag_stat: u16,
    },
    /// A configuration register read back another value than was written.
    ReadBack {
        /// The register's address.
        register: u8,
        /// The value written.
        written: u16,
        /// The value read back.
        read: u16,
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
            AdisError::DeadBus => f.write_str("burst of zero bytes only (data line stuck low)"),
            AdisError::SelfTest { diag_stat } => write!(f, "self-test failed: DIAG_STAT {diag_stat:#06x}"),
            AdisError::ReadBack { register, written, read } => {
                write!(f, "register {register:#04x} reads back {read:#06x}, {written:#06x} written")
            }
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for AdisError<E> {}

impl<E: core::fmt::Debug> ClassifiedError for AdisError<E> {
    fn fault(&self) -> ReadFault {
        match self {
            AdisError::Spi(_)
            | AdisError::WrongProduct { .. }
            | AdisError::ShortBurst { .. }
            | AdisError::ReadBack { .. } => ReadFault::Bus,
            AdisError::Checksum { .. } => ReadFault::Checksum,
            AdisError::StalledCounter { .. } => ReadFault::StalledCounter,
            AdisError::Status { .. } | AdisError::SelfTest { .. } => ReadFault::StatusFlag,
            AdisError::DeadBus => ReadFault::DeadBus,
        }
    }
}
