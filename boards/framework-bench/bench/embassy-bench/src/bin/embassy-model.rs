//! Minimal ExtiInput model: the armed flag is a RAM atomic, no EXTI register accesses
//! and no critical sections besides the AtomicWaker's own.
#![no_std]
#![no_main]

#[path = "../bench.rs"]
mod bench;
use bench::*;
use core::sync::atomic::{AtomicBool, Ordering};

static DRDY_ARMED: AtomicBool = AtomicBool::new(false);

struct RamFlagLine;
impl ExtiLine for RamFlagLine {
    fn arm() {
        DRDY_ARMED.store(true, Ordering::Relaxed);
    }
    fn fired() -> bool {
        !DRDY_ARMED.load(Ordering::Relaxed)
    }
    fn disarm() {
        DRDY_ARMED.store(false, Ordering::Relaxed);
    }
    fn on_irq() {
        DRDY_ARMED.store(false, Ordering::Relaxed);
        DRDY_WAKER.wake();
    }
}

embassy_bench!("embassy_model", RamFlagLine);
