//! The clock tree and a delay counted in core cycles.
//!
//! HSE (the board's crystal, [`HSE_HZ`]) through the PLL to SYSCLK = 168 MHz, AHB 168 MHz, APB1 42 MHz, APB2
//! 84 MHz (the STM32F405's maxima). SPI1 and USART1 are on APB2.

use embedded_hal::delay::DelayNs;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc;

/// The board's crystal, Hz: 8 MHz on most STM32F405 boards (flight controllers, Olimex STM32-H405); change it for a
/// board with another crystal (the bring-up checklist, docs/board.md, checks the resulting clocks).
pub const HSE_HZ: u32 = 8_000_000;
/// The core clock, Hz.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// APB1, Hz.
pub const PCLK1_HZ: u32 = 42_000_000;
/// APB2, Hz.
pub const PCLK2_HZ: u32 = 84_000_000;

/// The clock configuration: the tree above; built for QEMU's model (feature `qemu-netduinoplus2`), the 16 MHz HSI
/// alone, since QEMU models no RCC ready flags.
pub fn config() -> rcc::Config {
    if cfg!(feature = "qemu-netduinoplus2") {
        rcc::Config::hsi()
    } else {
        rcc::Config::hse(HSE_HZ.Hz()).sysclk(SYSCLK_HZ.Hz()).pclk1(PCLK1_HZ.Hz()).pclk2(PCLK2_HZ.Hz())
    }
}

/// A delay counted in core cycles at [`SYSCLK_HZ`] (`cortex_m::asm::delay` runs at least the given number of
/// cycles). Interrupts taken meanwhile lengthen it, never shorten it. The ADIS driver's start-up waits and stall
/// times go through it.
#[derive(Clone, Copy, Debug, Default)]
pub struct CycleDelay;

impl DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        let cycles = (ns as u64 * SYSCLK_HZ as u64).div_ceil(1_000_000_000);
        cortex_m::asm::delay(cycles.min(u32::MAX as u64) as u32);
    }
}

/// The core's cycle counter (DWT CYCCNT, started at boot): durations on the board's own clock, for the bring-up
/// readings (a flash erase, the longest turn of the main loop). It wraps every 2^32 cycles (25.6 s at 168 MHz).
pub fn cycles_now() -> u32 {
    cortex_m::peripheral::DWT::cycle_count()
}

/// Microseconds from `start` (a [`cycles_now`]) to now, for spans shorter than 25.6 s.
pub fn us_since(start: u32) -> u32 {
    cycles_now().wrapping_sub(start) / (SYSCLK_HZ / 1_000_000)
}
