//! The independent watchdog (IWDG) and what feeds it.
//!
//! The IWDG counts down at the LSI RC oscillator's clock over a prescaler (RM0090, "Independent watchdog"): 32 kHz
//! nominal, but 17 to 47 kHz over parts and temperature (STM32F405 data sheet, "LSI oscillator characteristics"),
//! so every period here is nominal and the bring-up checklist measures the real one (docs/board.md). Once started it
//! cannot be stopped; its prescaler and reload can be changed (after the unlock key, applied when SR clears).
//!
//! Who feeds it: the sample clock. Every data-ready interrupt (or, with no IMU, every 10 ms SysTick tick) calls
//! [`on_sample_clock`], which reloads the counter, so the watchdog's period is [`PERIOD_US`], two sample periods: a
//! sample clock that stops, or an interrupt that hangs, resets the board within two periods. The main loop is
//! watched through the same feed: it bumps a counter at every turn and at every flash chunk of a store
//! ([`main_loop_alive`], the device's busy hook), and the sample clock stops feeding when the counter has not moved
//! for [`MAIN_LOOP_DEADLINE_TICKS`] ticks. The deadline is long because one turn of the main loop solves the
//! calibration: 3.5 million instructions with the default model, 90.6 million with the full model (measured in
//! QEMU, `bash scripts/firmware-report`), 0.02 s and 0.54 s at 168 MHz at one instruction per cycle.
//!
//! A flash erase stalls every fetch from flash, interrupts included, for up to 500 ms per 16 KiB sector at x32
//! parallelism (data sheet, "Flash memory programming"): [`widen`] lengthens the period for it and [`restore`] sets
//! it back.

use core::sync::atomic::{AtomicU32, Ordering};

use stm32f4xx_hal::pac;

/// The LSI oscillator's nominal frequency, Hz.
pub const LSI_NOMINAL_HZ: u32 = 32_000;
/// The sample period of the ADIS at its output rate, microseconds.
pub const SAMPLE_PERIOD_US: u32 = 1_000_000 / sinscal::sensor::adis::OUTPUT_RATE_HZ as u32;
/// The watchdog's period in normal running: two sample periods (nominal LSI).
pub const PERIOD_US: u32 = 2 * SAMPLE_PERIOD_US;
/// The watchdog's period while the flash erases: eight times the longest 16 KiB sector erase (500 ms), so that
/// even at the fastest LSI (47 kHz, 0.68 of nominal) it exceeds the erase five times over.
pub const ERASE_PERIOD_US: u32 = 4_000_000;
/// Ticks of the sample clock (10 ms) without a turn of the main loop after which the watchdog is no longer fed:
/// 3 s, more than five times the full model's solve at 168 MHz and one instruction per cycle (0.54 s).
pub const MAIN_LOOP_DEADLINE_TICKS: u32 = 300;

const KEY_RELOAD: u16 = 0xAAAA;
const KEY_UNLOCK: u16 = 0x5555;
const KEY_START: u16 = 0xCCCC;
/// The largest reload value (12 bits).
const RELOAD_MAX: u32 = 0x0FFF;
/// Polls of SR while a new prescaler or reload is applied: it takes up to 5 LSI periods (at 17 kHz, 0.3 ms, about
/// 50,000 cycles at 168 MHz); a poll takes at least one cycle.
const UPDATE_WAIT_POLLS: u32 = 200_000;

/// A prescaler code (0 = /4 to 6 = /256) and a reload value for a period.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setting {
    /// PR: the prescaler is 4 << code.
    pub prescaler_code: u8,
    /// RLR: counts of the prescaled clock.
    pub reload: u16,
}

/// The finest setting for `period_us` at the nominal LSI: the smallest prescaler whose reload fits 12 bits.
pub const fn setting_for(period_us: u32) -> Setting {
    let mut code = 0;
    loop {
        let counts = (LSI_NOMINAL_HZ as u64 * period_us as u64) / (1_000_000 * (4u64 << code));
        if counts <= RELOAD_MAX as u64 || code == 6 {
            let reload = if counts > RELOAD_MAX as u64 {
                RELOAD_MAX
            } else if counts == 0 {
                1
            } else {
                counts as u32
            };
            return Setting { prescaler_code: code, reload: reload as u16 };
        }
        code += 1;
    }
}

/// The normal setting: 20 ms is /4 and a reload of 160.
pub const NORMAL: Setting = setting_for(PERIOD_US);
/// The setting while the flash erases.
pub const ERASE: Setting = setting_for(ERASE_PERIOD_US);
const _: () = assert!(NORMAL.prescaler_code == 0 && NORMAL.reload == 160);
// 4 s is prescaler 32 (code 3) and a reload of 4000.
const _: () = assert!(ERASE.prescaler_code == 3 && ERASE.reload == 4000);

fn iwdg() -> &'static pac::iwdg::RegisterBlock {
    // SAFETY: the IWDG's registers are only written here; each write is a single store.
    unsafe { &*pac::IWDG::ptr() }
}

fn key(k: u16) {
    // SAFETY: every 16-bit value is a valid KR write (only the three keys have an effect).
    iwdg().kr().write(|w| unsafe { w.key().bits(k) });
}

/// Applies `s` (unlock, prescaler, reload, wait for the update, reload the counter). `false` if the update did not
/// finish within its bound (the old setting then still counts; the counter is reloaded anyway).
fn apply(s: Setting) -> bool {
    key(KEY_UNLOCK);
    // SAFETY: the prescaler code is 0 to 6 and the reload 12 bits (`setting_for`).
    iwdg().pr().write(|w| unsafe { w.pr().bits(s.prescaler_code) });
    iwdg().rlr().write(|w| unsafe { w.rl().bits(s.reload) });
    let mut done = false;
    for _ in 0..UPDATE_WAIT_POLLS {
        if iwdg().sr().read().bits() & 0b11 == 0 {
            done = true;
            break;
        }
    }
    key(KEY_RELOAD);
    done
}

/// Starts the watchdog with the normal period. It cannot be stopped afterwards.
pub fn start() -> bool {
    key(KEY_START);
    apply(NORMAL)
}

/// Reloads the counter.
pub fn feed() {
    key(KEY_RELOAD);
}

/// Lengthens the period for a flash erase.
pub fn widen() -> bool {
    apply(ERASE)
}

/// Sets the normal period back (after an erase).
pub fn restore() -> bool {
    apply(NORMAL)
}

static MAIN_LOOP_TURNS: AtomicU32 = AtomicU32::new(0);
static TURNS_SEEN: AtomicU32 = AtomicU32::new(0);
static TICKS_WITHOUT_TURN: AtomicU32 = AtomicU32::new(0);

/// The main loop made progress (a turn, or a flash chunk of a store: the device's busy hook).
pub fn main_loop_alive() {
    MAIN_LOOP_TURNS.fetch_add(1, Ordering::Relaxed);
}

/// A tick of the sample clock: feeds the watchdog unless the main loop has not moved for
/// [`MAIN_LOOP_DEADLINE_TICKS`] ticks. Returns whether it fed.
pub fn on_sample_clock() -> bool {
    let turns = MAIN_LOOP_TURNS.load(Ordering::Relaxed);
    if TURNS_SEEN.swap(turns, Ordering::Relaxed) != turns {
        TICKS_WITHOUT_TURN.store(0, Ordering::Relaxed);
    } else if TICKS_WITHOUT_TURN.fetch_add(1, Ordering::Relaxed) >= MAIN_LOOP_DEADLINE_TICKS {
        return false;
    }
    feed();
    true
}
