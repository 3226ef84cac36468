//! The boards the firmware runs on (target only): register-level code, and what every firmware binary
//! shares, written once: the defmt logger, the panic handler and the exit path.
//!
//! Today one board: QEMU's `mps2-an386` (ARM MPS2 with the AN386 Cortex-M4F image), see [`mps2_an386`].

// The defmt logger of every firmware binary: defmt frames through semihosting to QEMU's stdout.
use defmt_full as defmt;
use defmt_semihosting as _;

pub mod mps2_an386;
pub mod uart;
pub mod watchdog;

pub use mps2_an386::exit;

/// Exit status of a firmware that panicked.
pub const PANIC_EXIT_CODE: i32 = 101;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    exit(PANIC_EXIT_CODE)
}
