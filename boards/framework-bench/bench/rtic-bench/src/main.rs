//! RTIC 2 bench: hardware tasks bound to EXTI interrupts (as the real firmware's data-ready
//! handler), pended by software from idle N times.
#![no_std]
#![no_main]

use bench_common as _; // panic handler (semihosting), memory.x

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use bench_common::*;
    use cortex_m::peripheral::NVIC;
    use stm32f4xx_hal::gpio::{Edge, Input, PA0};
    use stm32f4xx_hal::pac::Interrupt;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::Config;

    #[shared]
    struct Shared {
        /// Stand-in for the firmware's shared sample queue: written by the tasks, read by idle.
        samples: u32,
    }

    #[local]
    struct Local {
        drdy: PA0<Input>,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut syst = cx.core.SYST;
        start_systick(&mut syst);
        // Same EXTI setup as minimal/rtic, but HSI clocks: HSE/PLL would spin on RCC ready
        // flags, which QEMU does not model. (QEMU stores EXTI/SYSCFG register values but
        // never raises EXTI from GPIO, so the interrupts are pended via the NVIC.)
        let dp = cx.device;
        let mut exti = dp.EXTI;
        let mut rcc = dp.RCC.freeze(Config::hsi());
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let mut drdy = gpioa.pa0.into_floating_input();
        drdy.make_interrupt_source(&mut syscfg);
        drdy.trigger_on_edge(&mut exti, Edge::Rising);
        drdy.enable_interrupt(&mut exti);
        (Shared { samples: 0 }, Local { drdy })
    }

    fn pend_loop_ticks(irq: Interrupt) -> u32 {
        let t0 = now_ticks();
        for _ in 0..N_SAMPLES {
            NVIC::pend(irq);
        }
        elapsed_ticks(t0, now_ticks())
    }

    #[idle(shared = [samples])]
    fn idle(mut cx: idle::Context) -> ! {
        let cal = calibrate();
        print_calibration("rtic", &cal);
        let direct_ticks = direct_loop_ticks(N_SAMPLES);

        // 1. framework only: task = lock + sample work (EXTI1, no EXTI register access)
        let min_ticks = pend_loop_ticks(Interrupt::EXTI1);
        // 2. as the firmware: task also clears the EXTI pending bit through the HAL (EXTI0)
        let fw_ticks = pend_loop_ticks(Interrupt::EXTI0);
        // 3. as 2, plus idle locks the shared resource once per sample (consumer side)
        let mut seen = 0;
        let t0 = now_ticks();
        for _ in 0..N_SAMPLES {
            NVIC::pend(Interrupt::EXTI0);
            seen = cx.shared.samples.lock(|s| *s);
        }
        let fw_lock_ticks = elapsed_ticks(t0, now_ticks());

        print_result("rtic", "task_min", &cal, N_SAMPLES, direct_ticks, min_ticks);
        print_result("rtic", "task_firmware", &cal, N_SAMPLES, direct_ticks, fw_ticks);
        print_result("rtic", "task_firmware+idle_lock", &cal, N_SAMPLES, direct_ticks, fw_lock_ticks);
        let ok = seen == 3 * N_SAMPLES && samples_done() == 4 * N_SAMPLES;
        semihosting::println!("rtic check: task_runs={} sample_work_calls={} ok={}", seen, samples_done(), ok);
        exit(ok)
    }

    /// The firmware's data-ready task (as minimal/rtic, minus defmt).
    #[task(binds = EXTI0, shared = [samples], local = [drdy], priority = 1)]
    fn data_ready(mut cx: data_ready::Context) {
        cx.local.drdy.clear_interrupt_pending_bit();
        cx.shared.samples.lock(|s| *s += 1);
        sample_work();
    }

    /// Framework-only variant: no EXTI register access.
    #[task(binds = EXTI1, shared = [samples], priority = 1)]
    fn data_ready_min(mut cx: data_ready_min::Context) {
        cx.shared.samples.lock(|s| *s += 1);
        sample_work();
    }
}
