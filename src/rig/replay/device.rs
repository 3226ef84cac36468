//! The emulated ADIS: a device on the SPI bus that serves recorded burst frames to the real driver and
//! answers its register reads and writes.

use embedded_hal::spi::{self, Operation, SpiDevice};

use super::file::ReplayError;
use crate::sensor::adis::{reg, Model, BURST32_LEN, BURST_COMMAND, WRITE_FLAG};

/// A burst frame, word-aligned so that serving it is a word copy, as a DMA transfer would be.
#[derive(Clone, Debug)]
#[repr(align(4))]
struct Frame([u8; BURST32_LEN]);

/// A simulated ADIS device on the SPI bus that serves recorded burst frames and answers register reads.
#[derive(Clone, Debug)]
pub struct ReplayDevice {
    model: Model,
    frame: Frame,
    pending: Option<u8>,
    registers: [u16; 64],
}

impl ReplayDevice {
    /// A device of `model` with its PROD_ID set.
    pub fn new(model: Model) -> ReplayDevice {
        let mut registers = [0u16; 64];
        registers[register_index(reg::PROD_ID)] = model.product_id();
        ReplayDevice { model, frame: Frame([0; BURST32_LEN]), pending: None, registers }
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
}

/// Index of a register in the device's register file: byte address without the write flag, in words.
fn register_index(address: u8) -> usize {
    ((address & !WRITE_FLAG) / 2) as usize
}

impl spi::ErrorType for ReplayDevice {
    type Error = ReplayError;
}

impl SpiDevice for ReplayDevice {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ReplayError> {
        match operations {
            [Operation::Write(cmd), Operation::Read(buf)] if *cmd == BURST_COMMAND => {
                let n = buf.len().min(self.model.burst_len());
                buf[..n].copy_from_slice(&self.frame.0[..n]);
                if n < buf.len() {
                    buf[n..].fill(0);
                }
            }
            [Operation::Write([address, value])] if address & WRITE_FLAG != 0 => {
                let index = register_index(*address);
                let current = self.registers[index].to_be_bytes();
                self.registers[index] = if address & 1 == 0 {
                    u16::from_be_bytes([current[0], *value])
                } else {
                    u16::from_be_bytes([*value, current[1]])
                };
            }
            [Operation::Write([address, _])] => self.pending = Some(*address),
            [Operation::Read(buf)] => {
                let value = self.pending.take().map_or(0, |a| self.registers[register_index(a)]);
                let bytes = value.to_be_bytes();
                for (i, b) in buf.iter_mut().enumerate() {
                    *b = bytes.get(i).copied().unwrap_or(0);
                }
            }
            _ => return Err(ReplayError::Format),
        }
        Ok(())
    }
}
