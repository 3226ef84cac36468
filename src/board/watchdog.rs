//! The CMSDK APB watchdog of the MPS2 AN386 board (base 0x4000_8000, clocked at the 25 MHz peripheral clock): it
//! counts down from its load value; at zero with the interrupt enabled it raises its interrupt (the NMI on this
//! board) and reloads; at zero again with the interrupt still pending and reset enabled, it resets the system.
//! Registers: ARM's CMSDK technical reference manual.

use super::mps2_an386::{read, write, CLOCK_HZ};

const WDOG: usize = 0x4000_8000;
const WDOG_LOAD: usize = 0x000;
const WDOG_VALUE: usize = 0x004;
const WDOG_CONTROL: usize = 0x008;
const WDOG_INTCLR: usize = 0x00C;
const WDOG_LOCK: usize = 0xC00;
const WDOG_PERIPH_ID0: usize = 0xFE0;
/// LOCK: the key that unlocks the other registers (any other value locks them).
const LOCK_KEY: u32 = 0x1ACC_E551;
/// CONTROL: interrupt enable (bit 0), reset enable (bit 1).
const CONTROL_INT_RESET: u32 = 0b11;
/// The CMSDK watchdog's peripheral ID 0.
const PERIPH_ID0: u32 = 0x24;

/// Whether the board has the watchdog (its peripheral ID reads back).
pub fn present() -> bool {
    read(WDOG + WDOG_PERIPH_ID0) & 0xFF == PERIPH_ID0
}

/// Starts the watchdog with a period of `period_us` microseconds: its interrupt (the NMI) after one period
/// without [`feed`], the reset after two.
pub fn start(period_us: u32) {
    write(WDOG + WDOG_LOCK, LOCK_KEY);
    write(WDOG + WDOG_LOAD, (CLOCK_HZ / 1_000_000).saturating_mul(period_us));
    write(WDOG + WDOG_CONTROL, CONTROL_INT_RESET);
    write(WDOG + WDOG_LOCK, 0);
}

/// Restarts the count from the load value and clears a pending interrupt.
pub fn feed() {
    write(WDOG + WDOG_LOCK, LOCK_KEY);
    write(WDOG + WDOG_INTCLR, 1);
    write(WDOG + WDOG_LOCK, 0);
}

/// The count now (clock cycles left of the period).
pub fn value() -> u32 {
    read(WDOG + WDOG_VALUE)
}

/// Stops the watchdog.
pub fn stop() {
    write(WDOG + WDOG_LOCK, LOCK_KEY);
    write(WDOG + WDOG_CONTROL, 0);
    write(WDOG + WDOG_LOCK, 0);
}
