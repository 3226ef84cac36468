//! The MPS2 board with the AN386 FPGA image (Cortex-M4F), as QEMU's `mps2-an386` models it: the PL022
//! SPI port SSP0 with a GPIO chip select, the CMSDK GPIO 0 pins, the CMSDK APB TIMER0, and exit through
//! semihosting. Register addresses and bits: ARM's MPS2 AN386 application note and the PL022 and CMSDK
//! technical reference manuals.

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};

/// Core and peripheral clock, Hz.
pub const CLOCK_HZ: u32 = 25_000_000;
/// Nanoseconds per core cycle at [`CLOCK_HZ`]: 40.
const NS_PER_CYCLE: u32 = 1_000_000_000 / CLOCK_HZ;

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
/// SSP0's bit clock, Hz: the peripheral clock / (CPSDVSR * (1 + SCR)) with SCR = 0 (PL022 TRM): 961,538 Hz.
pub const SPI_CLOCK_HZ: u32 = CLOCK_HZ / SSP_CPSR_BELOW_1MHZ;
/// Core cycles of one 8-bit frame on SSP0: 8 bits of 26 peripheral (= core) cycles, 208 cycles (8.3 us).
const SSP_BYTE_CYCLES: u32 = 8 * SSP_CPSR_BELOW_1MHZ;
/// Most polls of the SSP status register while waiting for one byte: a poll takes at least one core cycle,
/// so this is at least four byte times (832 cycles, 33 us); a byte that has not moved by then will not, and
/// the transfer fails with [`SpiError::Timeout`] instead of hanging the data-ready interrupt.
pub const SSP_WAIT_POLLS_MAX: u32 = 4 * SSP_BYTE_CYCLES;
/// Entries of the PL022's receive FIFO (PL022 TRM): the most stale bytes to drain after a failed transfer.
const SSP_FIFO_DEPTH: u32 = 8;
/// SSP_SR: transmit FIFO not full.
const SSP_SR_TNF: u32 = 1 << 1;
/// SSP_SR: receive FIFO not empty.
const SSP_SR_RNE: u32 = 1 << 2;
/// SSP_SR: the port is busy (a frame is being sent or received).
const SSP_SR_BSY: u32 = 1 << 4;

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

/// Writes a memory-mapped register of the board's peripherals (this file's, UART0's, the watchdog's).
pub(crate) fn write(addr: usize, value: u32) {
    // SAFETY: every caller passes the address of one of the board's memory-mapped peripheral registers.
    unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
}

/// Reads a memory-mapped register of the board's peripherals.
pub(crate) fn read(addr: usize) -> u32 {
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
    unmask_irq(TIMER0_IRQ as u16);
}

/// Unmasks the board's external interrupt `irq`.
pub(crate) fn unmask_irq(irq: u16) {
    // SAFETY: the binary installs the interrupts' handler (`DefaultHandler`) before it starts a peripheral.
    unsafe { cortex_m::peripheral::NVIC::unmask(Irq(irq)) };
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

/// A delay counted in core cycles at [`CLOCK_HZ`] (`cortex_m::asm::delay` runs at least the given number of
/// cycles: 40 ns each at 25 MHz; rounded up). Interrupts taken meanwhile lengthen it, never shorten it. The
/// driver's start-up waits (reset recovery, self-test) go through it.
#[derive(Clone, Copy, Debug, Default)]
pub struct CycleDelay;

impl DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        cortex_m::asm::delay(ns.div_ceil(NS_PER_CYCLE));
    }
}

/// The PL022 SSP0 as an embedded-hal SPI device, with GPIO 0 pin 1 as its chip select.
pub struct Pl022;

/// Failures of a PL022 transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum SpiError {
    /// A status flag (transmit FIFO not full, receive FIFO not empty) did not come within
    /// [`SSP_WAIT_POLLS_MAX`] polls: the port or its clock is stuck. The transaction was abandoned and the
    /// chip select released.
    Timeout,
}

impl embedded_hal::spi::Error for SpiError {
    /// embedded-hal has no kind for a timeout: [`ErrorKind::Other`].
    fn kind(&self) -> ErrorKind {
        match self {
            SpiError::Timeout => ErrorKind::Other,
        }
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

    /// Disables the port (SSE cleared): transfers stall until [`Pl022::enable`]. The on-target test stalls
    /// the bus this way to show that a transfer then fails with [`SpiError::Timeout`] instead of hanging.
    pub fn disable(&mut self) {
        write(SSP0 + SSP_CR1, 0);
    }

    /// Enables the port again (as [`Pl022::init`] left it).
    pub fn enable(&mut self) {
        write(SSP0 + SSP_CR1, SSP_CR1_SSE);
    }

    /// Waits until `flag` is set in SSP_SR, at most [`SSP_WAIT_POLLS_MAX`] polls.
    fn wait_for(flag: u32) -> Result<(), SpiError> {
        for _ in 0..SSP_WAIT_POLLS_MAX {
            if read(SSP0 + SSP_SR) & flag != 0 {
                return Ok(());
            }
        }
        Err(SpiError::Timeout)
    }

    fn transfer_byte(byte: u8) -> Result<u8, SpiError> {
        Self::wait_for(SSP_SR_TNF)?;
        write(SSP0 + SSP_DR, byte as u32);
        Self::wait_for(SSP_SR_RNE)?;
        Ok(read(SSP0 + SSP_DR) as u8)
    }

    /// Empties the receive FIFO (at most its depth): a byte that arrived after its transfer was given up
    /// must not be taken for the first byte of the next transaction. One status read when it is empty.
    fn drain_receive_fifo() {
        for _ in 0..SSP_FIFO_DEPTH {
            if read(SSP0 + SSP_SR) & SSP_SR_RNE == 0 {
                break;
            }
            let _ = read(SSP0 + SSP_DR);
        }
    }

    /// After a failed transfer: waits (bounded) for the port to finish the frame in flight, then drains the
    /// receive FIFO.
    fn recover() {
        for _ in 0..SSP_WAIT_POLLS_MAX {
            if read(SSP0 + SSP_SR) & SSP_SR_BSY == 0 {
                break;
            }
        }
        Self::drain_receive_fifo();
    }

    /// The operations of one transaction, stopping at the first failure.
    fn run(operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
        crate::sensor::spi::run_operations(operations, Self::transfer_byte, |ns| CycleDelay.delay_ns(ns))
    }
}

impl SpiDevice for Pl022 {
    /// The operations with the chip select low, from an empty receive FIFO; the chip select is released
    /// whether they succeed or not.
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
        Self::drain_receive_fifo();
        write(GPIO0 + GPIO_DATAOUT, 0);
        let result = Self::run(operations);
        write(GPIO0 + GPIO_DATAOUT, PIN_IMU_CS);
        if result.is_err() {
            Self::recover();
        }
        result
    }
}
