//! The emulated ADIS: a device on the SPI bus that serves recorded burst frames to the real driver and
//! answers its start-up (software reset, self-test, product check, configuration written and read back) the
//! way the part does.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{self, Operation, SpiDevice};

use super::file::ReplayError;
use crate::sensor::adis::{
    reg, Model, BURST32_LEN, BURST_COMMAND, GLOB_CMD_SELF_TEST, GLOB_CMD_SOFTWARE_RESET, MSC_CTRL_DEFAULT, WRITE_FLAG,
};

/// A burst frame, word-aligned so that serving it is a word copy, as a DMA transfer would be.
#[derive(Clone, Debug)]
#[repr(align(4))]
struct Frame([u8; BURST32_LEN]);

/// A simulated ADIS device on the SPI bus that serves recorded burst frames and answers register reads.
///
/// Registers start at the part's power-on values (PROD_ID, MSC_CTRL as the data sheets give it, the others
/// 0). A software reset (GLOB_CMD bit 7) restores them; a self-test (GLOB_CMD bit 2) passes and leaves
/// DIAG_STAT at 0; both take effect at once, so the emulated device needs none of the part's waits (see
/// [`NoDelay`]). Delay operations in a transaction (the stall time between register words) are accepted and
/// take no time.
#[derive(Clone, Debug)]
pub struct ReplayDevice {
    model: Model,
    frame: Frame,
    pending: Option<u8>,
    registers: [u16; 64],
    resets: u32,
    self_tests: u32,
}

impl ReplayDevice {
    /// A device of `model` in its power-on state.
    pub fn new(model: Model) -> ReplayDevice {
        let mut device = ReplayDevice {
            model,
            frame: Frame([0; BURST32_LEN]),
            pending: None,
            registers: [0; 64],
            resets: 0,
            self_tests: 0,
        };
        device.power_on();
        device
    }

    /// The register file after power-on or a software reset.
    fn power_on(&mut self) {
        self.registers = [0; 64];
        self.registers[register_index(reg::PROD_ID)] = self.model.product_id();
        self.registers[register_index(reg::MSC_CTRL)] = MSC_CTRL_DEFAULT;
        self.pending = None;
    }

    /// Sets the burst the next burst read returns.
    pub fn load_frame(&mut self, bytes: &[u8]) {
        let n = self.model.burst_len().min(bytes.len());
        self.frame.0[..n].copy_from_slice(&bytes[..n]);
    }

    /// A register's value (as last written).
    pub fn register(&self, address: u8) -> u16 {
        self.registers[register_index(address)]
    }

    /// Software resets and self-tests commanded so far.
    pub fn commands(&self) -> (u32, u32) {
        (self.resets, self.self_tests)
    }

    /// One 16-bit word from the host outside a burst: a register write (byte by byte, GLOB_CMD's low byte
    /// runs the command) or the address of the register the next word reads.
    fn word(&mut self, address: u8, value: u8) {
        if address & WRITE_FLAG == 0 {
            self.pending = Some(address);
            return;
        }
        if address & !WRITE_FLAG == reg::GLOB_CMD {
            if value & GLOB_CMD_SOFTWARE_RESET != 0 {
                self.resets = self.resets.saturating_add(1);
                self.power_on();
            }
            if value & GLOB_CMD_SELF_TEST != 0 {
                self.self_tests = self.self_tests.saturating_add(1);
                self.registers[register_index(reg::DIAG_STAT)] = 0;
            }
            return;
        }
        let index = register_index(address);
        let current = self.registers[index].to_be_bytes();
        self.registers[index] = if address & 1 == 0 {
            u16::from_be_bytes([current[0], value])
        } else {
            u16::from_be_bytes([value, current[1]])
        };
    }
}

/// Index of a register in the device's register file: byte address without the write flag, in words.
fn register_index(address: u8) -> usize {
    ((address & !WRITE_FLAG) / 2) as usize
}

impl spi::ErrorType for ReplayDevice {
    type Error = ReplayError;
}

impl SpiDevice for ReplayDevice {
    /// In line: the burst is the per-sample path, a copy of the frame into the driver's buffer (the register
    /// accesses of the start-up stay out of line).
    #[inline(always)]
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ReplayError> {
        // The burst first, in line: it is the per-sample path.
        if let [Operation::Write(cmd), Operation::Read(buf)] = &mut *operations {
            if *cmd == BURST_COMMAND {
                let n = buf.len().min(self.model.burst_len());
                buf[..n].copy_from_slice(&self.frame.0[..n]);
                if n < buf.len() {
                    buf[n..].fill(0);
                }
                return Ok(());
            }
        }
        self.register_access(operations)
    }
}

impl ReplayDevice {
    /// Register words, their answers and delays (start-up only: kept out of the burst path's code).
    #[inline(never)]
    fn register_access(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ReplayError> {
        for operation in operations.iter_mut() {
            match operation {
                Operation::Write([address, value]) => self.word(*address, *value),
                Operation::Read(buf) => {
                    let value = self.pending.take().map_or(0, |a| self.registers[register_index(a)]);
                    let bytes = value.to_be_bytes();
                    for (i, b) in buf.iter_mut().enumerate() {
                        *b = bytes.get(i).copied().unwrap_or(0);
                    }
                }
                Operation::DelayNs(_) => {}
                _ => return Err(ReplayError::Format),
            }
        }
        Ok(())
    }
}

/// The delay of a replay: none. The emulated device is ready at once after a reset or a self-test (they take
/// effect on the register write), and a replay feeds its frames as fast as it reads them, not at 100 Hz, so
/// there is nothing to wait for.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoDelay;

impl DelayNs for NoDelay {
    fn delay_ns(&mut self, _ns: u32) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::adis::{Adis, DEC_RATE_FOR_100HZ, MSC_CTRL_BURST32};

    #[test]
    fn the_driver_starts_the_emulated_device_as_it_starts_the_part() {
        let mut imu = Adis::new(ReplayDevice::new(Model::Adis16505_2), Model::Adis16505_2);
        // A configuration left over from before: the software reset must clear it.
        imu.write_register(reg::DEC_RATE, 7).unwrap();
        imu.spi_mut().registers[register_index(reg::DIAG_STAT)] = 0x0020;
        imu.init(&mut NoDelay).unwrap();
        let device = imu.release();
        assert_eq!(device.commands(), (1, 1));
        assert_eq!(device.register(reg::DEC_RATE), DEC_RATE_FOR_100HZ);
        assert_eq!(device.register(reg::MSC_CTRL), MSC_CTRL_DEFAULT | MSC_CTRL_BURST32);
        assert_eq!(device.register(reg::DIAG_STAT), 0);
        assert_eq!(device.register(reg::PROD_ID), 16505);
    }

    #[test]
    fn a_reset_restores_the_power_on_registers_and_a_16_bit_model_keeps_its_burst() {
        let mut imu = Adis::new(ReplayDevice::new(Model::Adis16470), Model::Adis16470);
        imu.init(&mut NoDelay).unwrap();
        assert_eq!(imu.read_register(reg::MSC_CTRL).unwrap(), MSC_CTRL_DEFAULT);
        assert_eq!(imu.read_register(reg::DEC_RATE).unwrap(), DEC_RATE_FOR_100HZ);
        imu.command(GLOB_CMD_SOFTWARE_RESET).unwrap();
        assert_eq!(imu.read_register(reg::DEC_RATE).unwrap(), 0);
        assert_eq!(imu.read_register(reg::PROD_ID).unwrap(), 16470);
        // A device of another model is refused after its self-test passed.
        let mut imu = Adis::new(ReplayDevice::new(Model::Adis16470), Model::Adis16505_2);
        assert!(matches!(
            imu.init(&mut NoDelay),
            Err(crate::sensor::adis::AdisError::WrongProduct { expected: 16505, found: 16470 })
        ));
        assert_eq!(imu.release().commands(), (1, 1));
    }
}
