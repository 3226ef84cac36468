//! stm32f4xx-hal 0.23 blocking SPI: instructions for one 20-byte transfer_in_place on SPI1
//! (mode 3, 8-bit). Under QEMU each byte completes instantly (no device, reads 0), so this
//! is the minimum instruction path: no RXNE/TXE polling iterations while bits shift out.
#![no_std]
#![no_main]

use bench_common::*;
use embedded_hal::spi::{SpiBus, MODE_3};
use stm32f4xx_hal::{pac, prelude::*, rcc::Config, spi::Spi};

const TRANSFERS: u32 = 100;
const BYTES_PER_TRANSFER: usize = 20;

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap();
    let dp = pac::Peripherals::take().unwrap();
    start_systick(&mut cp.SYST);
    let cal = calibrate();
    print_calibration("spi", &cal);

    // HSI, no PLL: freeze does not wait on any RCC ready flag (QEMU does not model them).
    let mut rcc = dp.RCC.freeze(Config::hsi());
    let gpioa = dp.GPIOA.split(&mut rcc);
    let mut spi = Spi::new(
        dp.SPI1,
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        MODE_3,
        1.MHz(),
        &mut rcc,
    );

    let mut buf = [0xA5u8; BYTES_PER_TRANSFER];
    let t0 = now_ticks();
    for _ in 0..TRANSFERS {
        SpiBus::transfer_in_place(&mut spi, core::hint::black_box(&mut buf)).unwrap();
    }
    let ticks = elapsed_ticks(t0, now_ticks());

    let x100 = cal.instructions_x100(ticks) as i64;
    let per_transfer_x100 = x100 / TRANSFERS as i64;
    semihosting::println!(
        "spi transfer_in_place: transfers={} bytes_per_transfer={} ticks={} instructions={} instructions_per_transfer={} instructions_per_byte={}",
        TRANSFERS,
        BYTES_PER_TRANSFER,
        ticks,
        Fixed2(x100),
        Fixed2(per_transfer_x100),
        Fixed2(per_transfer_x100 / BYTES_PER_TRANSFER as i64)
    );
    let ok = buf.iter().all(|&b| b == 0); // QEMU SPI with no device shifts in zeros
    semihosting::println!("spi check: rx_all_zero={} ok={}", ok, ok);
    exit(ok)
}
