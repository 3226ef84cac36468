//! The ADIS driver over an embedded-hal 1.0 SPI device: initialisation, burst reads, the [`ImuSource`] implementation.

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

    /// Reads a 16-bit register: the address word, then the value in the following word.
    pub fn read_register(&mut self, register: u8) -> Result<u16, AdisError<SPI::Error>> {
        self.spi.write(&[register, 0x00]).map_err(AdisError::Spi)?;
        let mut value = [0u8; 2];
        self.spi.read(&mut value).map_err(AdisError::Spi)?;
        Ok(u16::from_be_bytes(value))
    }

    /// Writes a 16-bit register, low byte first.
    pub fn write_register(&mut self, register: u8, value: u16) -> Result<(), AdisError<SPI::Error>> {
        let [high, low] = value.to_be_bytes();
        self.spi.write(&[WRITE_FLAG | register, low]).map_err(AdisError::Spi)?;
        self.spi.write(&[WRITE_FLAG | (register + 1), high]).map_err(AdisError::Spi)
    }

    /// Checks PROD_ID, sets DEC_RATE for 100 Hz and, for ADIS1650x, the 32-bit burst.
    pub fn init(&mut self) -> Result<(), AdisError<SPI::Error>> {
        let found = self.read_register(reg::PROD_ID)?;
        let expected = self.model.product_id();
        if found != expected {
            return Err(AdisError::WrongProduct { expected, found });
        }
        self.write_register(reg::DEC_RATE, DEC_RATE_FOR_100HZ)?;
        if self.model.burst32() {
            let msc = self.read_register(reg::MSC_CTRL)?;
            self.write_register(reg::MSC_CTRL, msc | MSC_CTRL_BURST32)?;
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
