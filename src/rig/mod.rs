//! What only emulation and tests use: the replay of a recording through the firmware path ([`replay`]:
//! the replay file, the emulated ADIS, the run) and, in the emulated Cortex-M4F, host files through
//! semihosting (`semihost`, target only, QEMU's board).

pub mod exact;
pub mod replay;
#[cfg(all(target_os = "none", feature = "mps2-an386"))]
pub mod semihost;
