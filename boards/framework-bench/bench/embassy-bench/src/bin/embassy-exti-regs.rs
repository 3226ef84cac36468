//! ExtiInput model that also replays embassy-stm32 0.6 exti.rs's register accesses and
//! critical sections for line 0 / port A, on QEMU's (stored-value) EXTI and SYSCFG registers.
//! Only difference to exti.rs: QEMU never sets EXTI_PR for a software trigger, so on_irq
//! ORs in bit 0 (the NVIC pend stands for an EXTI0 edge).
#![no_std]
#![no_main]

#[path = "../bench.rs"]
mod bench;
use bench::*;

const EXTI: usize = 0x4001_3C00;
const EXTI_IMR: *mut u32 = EXTI as *mut u32;
const EXTI_RTSR: *mut u32 = (EXTI + 0x08) as *mut u32;
const EXTI_FTSR: *mut u32 = (EXTI + 0x0C) as *mut u32;
const EXTI_PR: *mut u32 = (EXTI + 0x14) as *mut u32;
const EXTI_SWIER: *mut u32 = (EXTI + 0x10) as *mut u32;
const SYSCFG_EXTICR1: *mut u32 = (0x4001_3800 + 0x08) as *mut u32;
const LINE: u32 = 0;
const PORT_A: u32 = 0;

unsafe fn modify(reg: *mut u32, f: impl FnOnce(u32) -> u32) {
    reg.write_volatile(f(reg.read_volatile()));
}

struct ExtiRegsLine;
impl ExtiLine for ExtiRegsLine {
    // low_level::configure_and_enable_exti
    fn arm() {
        critical_section::with(|_| unsafe {
            // configure_exti_pin
            critical_section::with(|_| {
                let shift = 4 * (LINE % 4);
                modify(SYSCFG_EXTICR1, |w| (w & !(0xF << shift)) | (PORT_A << shift));
                modify(EXTI_RTSR, |w| w | (1 << LINE)); // rising
                modify(EXTI_FTSR, |w| w & !(1 << LINE)); // not falling
                critical_section::with(|_| EXTI_PR.write_volatile(1 << LINE)); // clear_exti_pending
            });
            // set_exti_interrupt_enabled
            critical_section::with(|_| modify(EXTI_IMR, |w| w | (1 << LINE)));
        });
    }
    // ExtiInputFuture::poll
    fn fired() -> bool {
        unsafe { EXTI_IMR.read_volatile() & (1 << LINE) == 0 }
    }
    // ExtiInputFuture::drop
    fn disarm() {
        critical_section::with(|_| unsafe { modify(EXTI_IMR, |w| w & !(1 << LINE)) });
    }
    // Shows why on_irq must OR in the line: a software trigger never reaches EXTI_PR in QEMU.
    fn setup() {
        unsafe {
            EXTI_RTSR.write_volatile(1 << LINE);
            EXTI_IMR.write_volatile(1 << LINE);
            EXTI_SWIER.write_volatile(1 << LINE);
            semihosting::println!(
                "embassy_exti_regs qemu EXTI probe: after RTSR=IMR=SWIER=1: imr={} rtsr={} swier={} pr={} (real STM32: pr=1)",
                EXTI_IMR.read_volatile(), EXTI_RTSR.read_volatile(), EXTI_SWIER.read_volatile(), EXTI_PR.read_volatile()
            );
            EXTI_SWIER.write_volatile(0);
            EXTI_IMR.write_volatile(0);
        }
    }
    // exti::on_irq
    fn on_irq() {
        unsafe {
            let bits = (EXTI_PR.read_volatile() | (1 << LINE)) & 0xFFFF; // QEMU: see header
            modify(EXTI_IMR, |w| w & !bits);
            let mut it = bits;
            while it != 0 {
                let pin = it.trailing_zeros();
                it &= !(1 << pin);
                let _ = pin; // EXTI_WAKERS[pin]; one line here
                DRDY_WAKER.wake();
            }
            EXTI_PR.write_volatile(bits);
        }
    }
}

embassy_bench!("embassy_exti_regs", ExtiRegsLine);
