#![no_std]
#![no_main]
use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use stm32f4xx_hal::gpio::{Edge, Input, PA0};
    use stm32f4xx_hal::prelude::*;

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        drdy: PA0<Input>,
        n: u32,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut exti = dp.EXTI;
        let mut rcc = dp.RCC.freeze(stm32f4xx_hal::rcc::Config::hse(8u32.MHz()).sysclk(168.MHz()));
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let mut drdy = gpioa.pa0.into_floating_input();
        drdy.make_interrupt_source(&mut syscfg);
        drdy.trigger_on_edge(&mut exti, Edge::Rising);
        drdy.enable_interrupt(&mut exti);
        (Shared {}, Local { drdy, n: 0 })
    }

    #[task(binds = EXTI0, local = [drdy, n])]
    fn data_ready(cx: data_ready::Context) {
        cx.local.drdy.clear_interrupt_pending_bit();
        *cx.local.n = cx.local.n.wrapping_add(1);
        defmt::info!("sample {}", *cx.local.n);
    }
}
