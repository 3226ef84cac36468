//! The MPS2 board with the AN386 FPGA image (Cortex-M4F), as QEMU's `mps2-an386` models it: the PL022
//! SPI port SSP0 with a GPIO chip select, the CMSDK GPIO 0 pins, the CMSDK APB TIMER0, and exit through
//! semihosting. Register addresses and bits: ARM's MPS2 AN386 application note and the PL022 and CMSDK
//! technical reference manuals.

use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// Core and peripheral clock, Hz.
pub const CLOCK_HZ: u32 = 25_000_000;

/// PL022 SSP0 of the MPS2 FPGA image (AN386).
const SSP0: usize = 0x4002_0000;
const SSP_CR0: usize = 0x00;
const SSP_CR1: usize = 0x04;
const SSP_DR: usize = 0x08;
const SSP_SR: usize = 0x0C;
const SSP_CPSR: usize = 0x10;
/// SSP_CR0: 8-bit frames (DSS = 7), SPO = 1 (CPOL), SPH = 1 (CPHA): SPI mode 3, as the ADIS needs.
const SSP_CR0_MODE3_8BIT: u32 = 0x7 | (1 << 6) | (1 << 7);
/// SSP_CR1: SSE, the port enabled.
const SSP_CR1_SSE: u32 = 1 << 1;
/// Clock prescaler: 25 MHz / (2 * 13) < 1 MHz, the ADIS burst limit.
const SSP_CPSR_BELOW_1MHZ: u32 = 26;
const SSP_SR_TNF: u32 = 1 << 1;
const SSP_SR_RNE: u32 = 1 << 2;

/// CMSDK AHB GPIO 0.
const GPIO0: usize = 0x4001_0000;
const GPIO_DATA: usize = 0x00;
const GPIO_DATAOUT: usize = 0x04;
const GPIO_OUTENSET: usize = 0x10;
/// GPIO 0 pin 0: the turntable's "in position" signal (input).
const PIN_IN_POSITION: u32 = 1 << 0;
/// GPIO 0 pin 1: chip select of the IMU, active low.
const PIN_IMU_CS: u32 = 1 << 1;

/// CMSDK APB TIMER0 and its interrupt number on MPS2.
const TIMER0: usize = 0x4000_0000;
const TIMER_CTRL: usize = 0x00;
const TIMER_RELOAD: usize = 0x08;
const TIMER_INTCLEAR: usize = 0x0C;
/// TIMER_CTRL: enable (bit 0) and interrupt enable (bit 3).
const TIMER_CTRL_ENABLE_IRQ: u32 = 0b1001;
/// TIMER0's interrupt number.
pub const TIMER0_IRQ: i16 = 8;

fn write(addr: usize, value: u32) {
    // SAFETY: `addr` is one of the memory-mapped peripheral registers above.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

fn read(addr: usize) -> u32 {
    // SAFETY: as in `write`.
    unsafe { core::ptr::read_volatile(addr as *const u32) }
}

/// Ends the program with `code` as QEMU's exit status (semihosting).
pub fn exit(code: i32) -> ! {
    semihosting::process::exit(code)
}

/// Whether the turntable reports "in position" (GPIO 0 pin 0).
pub fn in_position() -> bool {
    read(GPIO0 + GPIO_DATA) & PIN_IN_POSITION != 0
}

/// Starts TIMER0 as a periodic interrupt at `rate_hz` (hardware reload: absolute deadlines) and unmasks
/// its interrupt.
pub fn start_sample_timer(rate_hz: u32) {
    write(TIMER0 + TIMER_RELOAD, CLOCK_HZ / rate_hz - 1);
    write(TIMER0 + TIMER_CTRL, TIMER_CTRL_ENABLE_IRQ);
    // SAFETY: the interrupt's handler is installed by the binary (`DefaultHandler`) before this is called.
    unsafe { cortex_m::peripheral::NVIC::unmask(Irq(TIMER0_IRQ as u16)) };
}

/// Acknowledges TIMER0's interrupt.
pub fn clear_sample_timer() {
    write(TIMER0 + TIMER_INTCLEAR, 1);
}

/// An interrupt number of the board.
#[derive(Clone, Copy)]
struct Irq(u16);

// SAFETY: the numbers are the board's external interrupt lines.
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// The PL022 SSP0 as an embedded-hal SPI device, with GPIO 0 pin 1 as its chip select.
pub struct Pl022;

/// The PL022 reports no errors; the type exists for embedded-hal.
#[derive(Debug)]
pub struct SpiError;

impl embedded_hal::spi::Error for SpiError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

impl ErrorType for Pl022 {
    type Error = SpiError;
}

impl Pl022 {
    /// Configures SSP0 (8-bit frames, mode 3, below 1 MHz) and the chip select (high: deselected).
    pub fn init() -> Pl022 {
        write(SSP0 + SSP_CR0, SSP_CR0_MODE3_8BIT);
        write(SSP0 + SSP_CPSR, SSP_CPSR_BELOW_1MHZ);
        write(SSP0 + SSP_CR1, SSP_CR1_SSE);
        write(GPIO0 + GPIO_OUTENSET, PIN_IMU_CS);
        write(GPIO0 + GPIO_DATAOUT, PIN_IMU_CS);
        Pl022
    }

    fn transfer_byte(byte: u8) -> u8 {
        while read(SSP0 + SSP_SR) & SSP_SR_TNF == 0 {}
        write(SSP0 + SSP_DR, byte as u32);
        while read(SSP0 + SSP_SR) & SSP_SR_RNE == 0 {}
        read(SSP0 + SSP_DR) as u8
    }
}

impl SpiDevice for Pl022 {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
        write(GPIO0 + GPIO_DATAOUT, 0);
        for op in operations.iter_mut() {
            match op {
                Operation::Write(bytes) => bytes.iter().for_each(|&b| {
                    Self::transfer_byte(b);
                }),
                Operation::Read(bytes) => bytes.iter_mut().for_each(|b| *b = Self::transfer_byte(0)),
                Operation::Transfer(r, w) => {
                    for (i, rb) in r.iter_mut().enumerate() {
                        *rb = Self::transfer_byte(w.get(i).copied().unwrap_or(0));
                    }
                }
                Operation::TransferInPlace(bytes) => bytes.iter_mut().for_each(|b| *b = Self::transfer_byte(*b)),
                // One loop iteration of `delay` per 40 ns at 25 MHz.
                Operation::DelayNs(ns) => cortex_m::asm::delay(*ns / 40 + 1),
            }
        }
        write(GPIO0 + GPIO_DATAOUT, PIN_IMU_CS);
        Ok(())
    }
}
