//! Shared pieces of both benches: the sample work, SysTick timing, calibration, reporting.
#![no_std]

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;

/// Number of data-ready events per measured loop.
pub const N_SAMPLES: u32 = 1000;

/// Counts calls of `sample_work` (lets each bench verify the handler really ran).
pub static SAMPLES_DONE: AtomicU32 = AtomicU32::new(0);

/// The fixed "sample" work, identical in both benches: one out-of-line call doing
/// a load + store of a global counter.
#[inline(never)]
pub fn sample_work() {
    // load + store (no ldrex/strex): same cost wherever it is called from
    SAMPLES_DONE.store(SAMPLES_DONE.load(Ordering::Relaxed) + 1, Ordering::Relaxed);
}

pub fn samples_done() -> u32 {
    SAMPLES_DONE.load(Ordering::Relaxed)
}

const SYSTICK_MASK: u32 = 0x00FF_FFFF;

/// SysTick free-running on the core clock (168 MHz on QEMU netduinoplus2), no interrupt.
pub fn start_systick(syst: &mut SYST) {
    syst.disable_interrupt();
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSTICK_MASK);
    syst.clear_current();
    syst.enable_counter();
}

#[inline(always)]
pub fn now_ticks() -> u32 {
    SYST::get_current()
}

/// SysTick counts down; 24-bit wrap-around.
#[inline(always)]
pub fn elapsed_ticks(start: u32, end: u32) -> u32 {
    start.wrapping_sub(end) & SYSTICK_MASK
}

/// `iterations` x {subs; bne} = exactly 2*iterations instructions.
#[inline(always)]
fn counted_loop(iterations: u32) {
    unsafe {
        core::arch::asm!(
            "1:",
            "subs {0}, #1",
            "bne 1b",
            inout(reg) iterations => _,
            options(nomem, nostack),
        );
    }
}

fn time_counted_loop(iterations: u32) -> u32 {
    let t0 = now_ticks();
    counted_loop(iterations);
    let t1 = now_ticks();
    elapsed_ticks(t0, t1)
}

/// Ticks per known number of instructions, from the difference of two counted loops
/// (cancels the timing overhead).
pub struct Calibration {
    pub instructions: u64,
    pub ticks: u64,
}

pub fn calibrate() -> Calibration {
    const SHORT: u32 = 100_000;
    const LONG: u32 = 600_000;
    let short = time_counted_loop(SHORT);
    let long = time_counted_loop(LONG);
    Calibration { instructions: 2 * (LONG - SHORT) as u64, ticks: (long - short) as u64 }
}

impl Calibration {
    /// instructions * 100 (for two decimals without floats)
    pub fn instructions_x100(&self, ticks: u32) -> u64 {
        (ticks as u64 * self.instructions * 100 + self.ticks / 2) / self.ticks
    }
}

/// N direct calls of the sample work: the no-framework baseline.
pub fn direct_loop_ticks(n: u32) -> u32 {
    let t0 = now_ticks();
    for _ in 0..n {
        sample_work();
    }
    let t1 = now_ticks();
    elapsed_ticks(t0, t1)
}

pub struct Fixed2(pub i64);
impl core::fmt::Display for Fixed2 {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let sign = if self.0 < 0 { "-" } else { "" };
        let a = self.0.unsigned_abs();
        write!(f, "{}{}.{:02}", sign, a / 100, a % 100)
    }
}

pub fn print_calibration(bench: &str, cal: &Calibration) {
    semihosting::println!(
        "{} calibration: {} instructions = {} systick_ticks -> ticks_per_instruction={}.{:06} (expected 0.168000)",
        bench,
        cal.instructions,
        cal.ticks,
        cal.ticks / cal.instructions,
        (cal.ticks * 1_000_000 / cal.instructions) % 1_000_000
    );
}

/// Prints raw ticks, instructions and per-sample overhead over the direct baseline.
pub fn print_result(bench: &str, variant: &str, cal: &Calibration, n: u32, direct_ticks: u32, ticks: u32) {
    let direct_x100 = cal.instructions_x100(direct_ticks) as i64;
    let total_x100 = cal.instructions_x100(ticks) as i64;
    let per_sample_x100 = (total_x100 - direct_x100) / n as i64;
    semihosting::println!(
        "{} {}: n_samples={} direct_ticks={} direct_instructions={} framework_ticks={} framework_instructions={} overhead_instructions_per_sample={}",
        bench,
        variant,
        n,
        direct_ticks,
        Fixed2(direct_x100),
        ticks,
        Fixed2(total_x100),
        Fixed2(per_sample_x100)
    );
}

/// Exit QEMU through semihosting.
pub fn exit(ok: bool) -> ! {
    semihosting::process::exit(if ok { 0 } else { 1 })
}
