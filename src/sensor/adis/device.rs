//! The ADIS driver over an embedded-hal 1.0 SPI device: start-up (reset, self-test, product check, configuration
//! read back), register access with the stall time, burst reads, the [`ImuSource`] implementation.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use super::burst::*;
use super::error::AdisError;
use super::registers::*;
use crate::sensor::sample::ImuReading;
use crate::sensor::source::ImuSource;

/// The driver.
#[derive(Debug)]
pub struct Adis<SPI> {
    spi: SPI,
    model: Model,
    last_counter: Option<u16>,
}

impl<SPI: SpiDevice> Adis<SPI> {
    /// A driver for a device of the given model (no bus traffic yet).
    pub fn new(spi: SPI, model: Model) -> Adis<SPI> {
        Adis { spi, model, last_counter: None }
    }

    /// The model.
    pub fn model(&self) -> Model {
        self.model
    }

    /// The SPI device (for a replay device that is fed frame by frame).
    pub fn spi_mut(&mut self) -> &mut SPI {
        &mut self.spi
    }

    /// Gives the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// One 16-bit register word in its own chip-select cycle, followed by the stall time the device needs
    /// before the next word ([`STALL_NS`]). The delay is an [`Operation::DelayNs`] inside the transaction:
    /// embedded-hal delays run with the chip select asserted, so the chip select rises after the stall, and no
    /// clock edge of the next word comes sooner than the stall after this word's last one.
    fn word(&mut self, first: u8, second: u8) -> Result<(), AdisError<SPI::Error>> {
        self.spi
            .transaction(&mut [Operation::Write(&[first, second]), Operation::DelayNs(STALL_NS)])
            .map_err(AdisError::Spi)
    }

    /// Reads a 16-bit register: the address word, then the value in the following word, each followed by
    /// the stall time.
    pub fn read_register(&mut self, register: u8) -> Result<u16, AdisError<SPI::Error>> {
        self.word(register, 0x00)?;
        let mut value = [0u8; 2];
        self.spi
            .transaction(&mut [Operation::Read(&mut value), Operation::DelayNs(STALL_NS)])
            .map_err(AdisError::Spi)?;
        Ok(u16::from_be_bytes(value))
    }

    /// Writes a 16-bit register, low byte first, each word followed by the stall time.
    pub fn write_register(&mut self, register: u8, value: u16) -> Result<(), AdisError<SPI::Error>> {
        let [high, low] = value.to_be_bytes();
        self.word(WRITE_FLAG | register, low)?;
        self.word(WRITE_FLAG | (register + 1), high)
    }

    /// A global command: `bits` written to GLOB_CMD's low byte, one word (the data sheets' form, e.g. 0xE880
    /// for the software reset). The high byte is not written: the command starts with the low byte's write,
    /// and the device may already be busy with it.
    pub fn command(&mut self, bits: u8) -> Result<(), AdisError<SPI::Error>> {
        self.word(WRITE_FLAG | reg::GLOB_CMD, bits)
    }

    /// Writes a configuration register and reads it back: [`AdisError::ReadBack`] when the value differs.
    fn write_checked(&mut self, register: u8, value: u16) -> Result<(), AdisError<SPI::Error>> {
        self.write_register(register, value)?;
        let read = self.read_register(register)?;
        if read != value {
            return Err(AdisError::ReadBack { register, written: value, read });
        }
        Ok(())
    }

    /// Starts the device as the data sheets and the Linux IIO driver do:
    ///
    /// 1. software reset (GLOB_CMD bit 7), then `delay` waits [`Model::reset_recovery_ms`];
    /// 2. self-test (GLOB_CMD bit 2), then `delay` waits [`Model::self_test_ms`], and DIAG_STAT must read 0
    ///    ([`AdisError::SelfTest`] with the flags otherwise);
    /// 3. PROD_ID must be the model's ([`AdisError::WrongProduct`]);
    /// 4. DEC_RATE = 19 (100 Hz) and, for ADIS1650x, MSC_CTRL with the 32-bit burst bit (read, modified,
    ///    written), each read back and compared ([`AdisError::ReadBack`]).
    ///
    /// Every register word is followed by the stall time ([`STALL_NS`]) as an SPI delay operation; the
    /// millisecond waits go through `delay` (the board's clock-based delay; a replay's emulated device is
    /// ready at once and takes a no-op delay).
    pub fn init(&mut self, delay: &mut impl DelayNs) -> Result<(), AdisError<SPI::Error>> {
        self.command(GLOB_CMD_SOFTWARE_RESET)?;
        delay.delay_ms(self.model.reset_recovery_ms());
        self.command(GLOB_CMD_SELF_TEST)?;
        delay.delay_ms(self.model.self_test_ms());
        let diag_stat = self.read_register(reg::DIAG_STAT)?;
        if diag_stat != 0 {
            return Err(AdisError::SelfTest { diag_stat });
        }
        let found = self.read_register(reg::PROD_ID)?;
        let expected = self.model.product_id();
        if found != expected {
            return Err(AdisError::WrongProduct { expected, found });
        }
        self.write_checked(reg::DEC_RATE, DEC_RATE_FOR_100HZ)?;
        if self.model.burst32() {
            let msc = self.read_register(reg::MSC_CTRL)?;
            self.write_checked(reg::MSC_CTRL, msc | MSC_CTRL_BURST32)?;
        }
        self.last_counter = None;
        Ok(())
    }

    /// The burst transaction: the command word, then the model's burst into `buf`, in one chip-select
    /// cycle. Returns the bytes received.
    #[inline(always)]
    fn transfer<'b>(&mut self, buf: &'b mut [u8; BURST32_LEN]) -> Result<&'b [u8], AdisError<SPI::Error>> {
        let len = self.model.burst_len();
        self.spi
            .transaction(&mut [Operation::Write(&BURST_COMMAND), Operation::Read(&mut buf[..len])])
            .map_err(AdisError::Spi)?;
        Ok(&buf[..len])
    }

    /// One burst read, decoded but without the counter and status checks.
    #[inline(always)]
    pub fn read_burst(&mut self) -> Result<Burst, AdisError<SPI::Error>> {
        let mut buf = [0u8; BURST32_LEN];
        let bytes = self.transfer(&mut buf)?;
        decode_burst(self.model, bytes)
    }

    /// Everything after the bus transfer: checksum, decode, counter and status checks, conversion to SI.
    /// [`ImuSource::read`] is one burst transaction followed by this; with a DMA transfer, call it on the
    /// received bytes.
    #[inline(always)]
    pub fn decode_reading(&mut self, burst_bytes: &[u8]) -> Result<ImuReading, AdisError<SPI::Error>> {
        let burst = decode_burst(self.model, burst_bytes)?;
        let missed = match self.last_counter {
            Some(last) if burst.data_counter == last => {
                return Err(AdisError::StalledCounter { counter: last });
            }
            Some(last) => burst.data_counter.wrapping_sub(last).wrapping_sub(1),
            None => 0,
        };
        self.last_counter = Some(burst.data_counter);
        if burst.diag_stat != 0 {
            return Err(AdisError::Status { diag_stat: burst.diag_stat });
        }
        Ok(ImuReading {
            sample: burst.to_sample(self.model),
            counter: burst.data_counter,
            missed,
            temperature_c: burst.temp_raw as f32 * TEMP_C_PER_LSB,
        })
    }
}

impl<SPI: SpiDevice> ImuSource for Adis<SPI> {
    type Error = AdisError<SPI::Error>;

    /// Burst read, then [`Adis::decode_reading`].
    fn read(&mut self) -> Result<ImuReading, Self::Error> {
        let mut buf = [0u8; BURST32_LEN];
        let bytes = self.transfer(&mut buf)?;
        self.decode_reading(bytes)
    }
}
