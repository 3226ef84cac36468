//! The ADIS on SPI1 as an embedded-hal `SpiDevice`: the HAL's SPI1 (mode 3, 8-bit frames, 656,250 Hz) moved a byte
//! at a time with bounded waits, and the chip select on a GPIO output (active low). The core's ADIS driver runs on
//! it unchanged.
//!
//! Every wait for the transmit buffer or the receive buffer gives up after [`SPI_WAIT_POLLS`] polls, at least four
//! byte times: a bus that has stopped makes the transfer fail with [`AdisSpiError::Timeout`] (a read fault counted
//! by the core), not a hang in the data-ready interrupt. The chip select is released whether the transaction
//! succeeds or not.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
use stm32f4xx_hal::gpio::{Output, PushPull, PA4};
use stm32f4xx_hal::pac::SPI1;
use stm32f4xx_hal::spi::{self, Spi};

use crate::clocks::{CycleDelay, PCLK2_HZ, SYSCLK_HZ};

/// SPI1's bit clock: PCLK2 (84 MHz) / 128 = 656,250 Hz, below the ADIS16505's 1 MHz limit for burst reads (the
/// HAL picks the divider 128 for a ratio of 96 to 191). The next divider, 64, gives 1.3125 MHz: too fast.
pub const SPI_CLOCK_HZ: u32 = PCLK2_HZ / 128;
const _: () = assert!(SPI_CLOCK_HZ <= 1_000_000 && PCLK2_HZ / 64 > 1_000_000);
/// Core cycles of one byte on the bus: 8 bits of 256 core cycles (168 MHz / 656.25 kHz).
const BYTE_CYCLES: u32 = 8 * (SYSCLK_HZ / SPI_CLOCK_HZ);
/// The most polls of a status flag for one byte: a poll takes at least one cycle, so this is at least four byte
/// times (49 us).
pub const SPI_WAIT_POLLS: u32 = 4 * BYTE_CYCLES;

/// Failures of a transfer on SPI1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum AdisSpiError {
    /// A flag did not come within [`SPI_WAIT_POLLS`] polls: the bus is stuck.
    Timeout,
    /// The SPI reported an overrun or a mode fault.
    Bus,
}

impl embedded_hal::spi::Error for AdisSpiError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// SPI1 with the ADIS's chip select.
pub struct AdisSpi {
    spi: Spi<SPI1>,
    cs: PA4<Output<PushPull>>,
}

impl ErrorType for AdisSpi {
    type Error = AdisSpiError;
}

impl AdisSpi {
    /// The device on a configured SPI1 and its chip select (set high: deselected).
    pub fn new(spi: Spi<SPI1>, mut cs: PA4<Output<PushPull>>) -> AdisSpi {
        cs.set_high();
        AdisSpi { spi, cs }
    }

    fn transfer_byte(&mut self, byte: u8) -> Result<u8, AdisSpiError> {
        let mut sent = false;
        for _ in 0..SPI_WAIT_POLLS {
            match self.spi.write_nonblocking(byte) {
                Ok(()) => {
                    sent = true;
                    break;
                }
                Err(nb::Error::WouldBlock) => {}
                Err(nb::Error::Other(_)) => return Err(AdisSpiError::Bus),
            }
        }
        if !sent {
            return Err(AdisSpiError::Timeout);
        }
        for _ in 0..SPI_WAIT_POLLS {
            match self.spi.read_nonblocking() {
                Ok(b) => return Ok(b),
                Err(nb::Error::WouldBlock) => {}
                Err(nb::Error::Other(_)) => return Err(AdisSpiError::Bus),
            }
        }
        Err(AdisSpiError::Timeout)
    }

    /// Empties the receive buffer (a byte left by a failed transfer must not start the next one).
    fn drain(&mut self) {
        for _ in 0..2 {
            if self.spi.read_nonblocking().is_err() {
                break;
            }
        }
    }

    fn run(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), AdisSpiError> {
        sinscal::sensor::spi::run_operations(operations, |b| self.transfer_byte(b), |ns| CycleDelay.delay_ns(ns))
    }
}

impl SpiDevice for AdisSpi {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), AdisSpiError> {
        self.drain();
        self.cs.set_low();
        let result = self.run(operations);
        // The last byte is received when its clock has ended: nothing is in flight when the chip select rises.
        self.cs.set_high();
        if result.is_err() {
            self.drain();
        }
        result
    }
}

/// SPI1's mode: mode 3 (clock idle high, data captured on the second edge), as the ADIS needs.
pub const MODE: spi::Mode =
    spi::Mode { polarity: spi::Polarity::IdleHigh, phase: spi::Phase::CaptureOnSecondTransition };
