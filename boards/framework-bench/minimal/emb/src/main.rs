#![no_std]
#![no_main]
use defmt_rtt as _;
use panic_probe as _;
use embassy_executor::Spawner;
use embassy_stm32::exti::{self, ExtiInput};
use embassy_stm32::gpio::Pull;
use embassy_stm32::{bind_interrupts, interrupt};

bind_interrupts!(struct Irqs {
    EXTI0 => exti::InterruptHandler<interrupt::typelevel::EXTI0>;
});

#[embassy_executor::main]
async fn main(_spawner: Spawner) {
    let p = embassy_stm32::init(Default::default());
    let mut drdy = ExtiInput::new(p.PA0, p.EXTI0, Pull::None, Irqs);
    let mut n: u32 = 0;
    loop {
        drdy.wait_for_rising_edge().await;
        n = n.wrapping_add(1);
        defmt::info!("sample {}", n);
    }
}
