//! The sinscal calibration instrument on an STM32F405 navigation computer (Cortex-M4F, 168 MHz): the board layer.
//!
//! Everything the instrument does is the core's, the same code that QEMU's `mps2-an386` board runs
//! (`sinscal::instrument::main_loop`): the ADIS driver, the sampling queue, the calibration sequence, the link's
//! frames and messages, the record store and the compensation. This file and its modules bring only the board:
//!
//! | what | where | pins |
//! |---|---|---|
//! | ADIS16505-2 on SPI1, mode 3, 656,250 Hz | [`adis_spi`] | PA5 SCK, PA6 MISO (DOUT), PA7 MOSI (DIN), PA4 CS (active low) |
//! | data ready: the sample clock (the IMU's own 100 Hz, not an MCU timer) | EXTI4, rising edge | PC4 |
//! | the turntable's "in position" (high = in position; pulled down) | read with each sample | PC0 |
//! | the host link, 115200 baud 8N1 | [`link`], USART1 | PA9 TX, PA10 RX |
//! | the calibration record, sectors 1 and 2 | [`flash`] | |
//! | the watchdog, two sample periods | [`watchdog`], IWDG | |
//! | the log: defmt over RTT (probe-rs) | defmt-rtt | SWD |
//!
//! RTIC 2 maps the firmware's structure one to one: the data-ready interrupt is the highest-priority hardware task
//! (it reads the burst, latches the table's signal and enqueues, nothing more), the USART's receive interrupt the
//! next, and `idle` is the main loop. The choice over embassy-stm32, by flash and instructions per sample, is in
//! docs/board.md.
#![no_std]
#![no_main]

mod adis_spi;
mod clocks;
mod flash;
mod link;
mod watchdog;

use defmt_rtt as _;
use panic_probe as _;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use heapless::spsc::{Consumer, Producer, Queue};
    use sinscal::instrument::device::Device;
    use sinscal::instrument::main_loop::{log_boot, log_init_error, Instrument, LinkPort};
    use sinscal::instrument::store::RecordStore;
    use sinscal::run::sampling::{on_data_ready, QueueItem, SamplingStats, QUEUE_SLOTS, TABLE_IN_POSITION};
    use sinscal::sensor::adis::{Adis, Model};
    use stm32f4xx_hal::gpio::{Edge, Input, PC0, PC4};
    use stm32f4xx_hal::pac::{self, USART1};
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::serial::{self, Rx, Serial, Tx};
    use stm32f4xx_hal::spi::Spi;

    use crate::adis_spi::{self, AdisSpi};
    use crate::clocks::{cycles_now, us_since, CycleDelay};
    use crate::flash::{RecordFlash, SECTOR_BYTES};
    use crate::link::{self, UsartTx, LINK_BAUD, RX_QUEUE_SLOTS};
    use crate::watchdog;

    /// The IMU on the board.
    const IMU_MODEL: Model = Model::Adis16505_2;

    /// A turn of the main loop longer than this is logged (a solve, a store), microseconds.
    const LONG_TURN_US: u32 = 10_000;

    /// Logs why the board reset (RCC_CSR's flags, RM0090 "RCC clock control & status register"): a watchdog reset
    /// means the sample clock stopped or the main loop missed its deadline.
    fn log_reset_cause(csr: u32) {
        const CAUSES: [(u32, &str); 7] = [
            (25, "brown-out"),
            (26, "reset pin"),
            (27, "power-on"),
            (28, "software"),
            (29, "independent watchdog"),
            (30, "window watchdog"),
            (31, "low-power"),
        ];
        for (bit, cause) in CAUSES {
            if csr & (1 << bit) != 0 {
                defmt::info!("reset cause: {=str}", cause);
            }
        }
    }

    /// What the data-ready interrupt owns.
    pub struct Sampler {
        imu: Adis<AdisSpi>,
        queue: Producer<'static, QueueItem>,
        data_ready: PC4<Input>,
        in_position: PC0<Input>,
    }

    #[shared]
    struct Shared {
        /// The sampling side's counters (the data-ready interrupt writes them, the main loop reads a copy).
        stats: SamplingStats,
    }

    #[local]
    struct Local {
        sampler: Option<Sampler>,
        rx: Rx<USART1>,
        rx_queue: Producer<'static, u8>,
        main: Option<MainLoopParts>,
    }

    /// What the main loop owns.
    pub struct MainLoopParts {
        tx: Tx<USART1>,
        rx_queue: Consumer<'static, u8>,
        samples: Option<Consumer<'static, QueueItem>>,
        flash: pac::FLASH,
    }

    #[init(local = [
        samples: Queue<QueueItem, QUEUE_SLOTS> = Queue::new(),
        bytes: Queue<u8, RX_QUEUE_SLOTS> = Queue::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut core = cx.core;
        // A debugger keeps its access to RAM (RTT) while the core sleeps in WFI, and a halted core stops the
        // watchdog (DBGMCU_CR DBG_SLEEP, DBGMCU_APB1_FZ DBG_IWDG_STOP); without a debugger these do nothing.
        dp.DBGMCU.cr().modify(|_, w| w.dbg_sleep().set_bit());
        dp.DBGMCU.apb1_fz().modify(|_, w| w.dbg_iwdg_stop().set_bit());
        log_reset_cause(dp.RCC.csr().read().bits());
        // Clear the reset flags (RMVF), so that the next boot reports only its own cause.
        dp.RCC.csr().modify(|_, w| w.rmvf().set_bit());
        core.DCB.enable_trace();
        core.DWT.enable_cycle_counter();
        let mut rcc = dp.RCC.freeze(crate::clocks::config());
        defmt::info!(
            "sinscal-stm32f405: SYSCLK {=u32} Hz, PCLK1 {=u32} Hz, PCLK2 {=u32} Hz",
            rcc.clocks.sysclk().raw(),
            rcc.clocks.pclk1().raw(),
            rcc.clocks.pclk2().raw()
        );
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let mut exti = dp.EXTI;
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);

        let config = serial::Config::default().baudrate(LINK_BAUD.bps());
        let Ok(usart) = Serial::new(dp.USART1, (gpioa.pa9, gpioa.pa10), config, &mut rcc) else {
            defmt::panic!("USART1: {=u32} baud cannot be set from PCLK2", LINK_BAUD)
        };
        let (tx, mut rx) = usart.split();
        rx.listen();
        let (rx_producer, rx_consumer) = cx.local.bytes.split();

        let spi = Spi::new(
            dp.SPI1,
            (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
            adis_spi::MODE,
            adis_spi::SPI_CLOCK_HZ.Hz(),
            &mut rcc,
        );
        let cs = gpioa.pa4.into_push_pull_output();
        let mut imu = Adis::new(AdisSpi::new(spi, cs), IMU_MODEL);
        let sampler = match imu.init(&mut CycleDelay) {
            Ok(()) => {
                let mut data_ready = gpioc.pc4.into_floating_input();
                data_ready.make_interrupt_source(&mut syscfg);
                data_ready.trigger_on_edge(&mut exti, Edge::Rising);
                data_ready.enable_interrupt(&mut exti);
                let in_position = gpioc.pc0.into_pull_down_input();
                let (queue, consumer) = cx.local.samples.split();
                defmt::info!("IMU started: data ready on PC4 is the sample clock");
                Some((Sampler { imu, queue, data_ready, in_position }, consumer))
            }
            Err(e) => {
                log_init_error(&e);
                None
            }
        };
        let (sampler, samples) = sampler.unzip();
        if sampler.is_none() {
            // No IMU, no data ready: SysTick ticks at the sample rate instead, for the watchdog and the main loop
            // (the link still answers; the status shows no samples).
            core.SYST.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
            core.SYST.set_reload(rcc.clocks.sysclk().raw() / sinscal::sensor::adis::OUTPUT_RATE_HZ as u32 - 1);
            core.SYST.clear_current();
            core.SYST.enable_interrupt();
            core.SYST.enable_counter();
        }
        if !watchdog::start() {
            defmt::warn!("watchdog: the prescaler and reload were not applied within the bound");
        }
        let main = MainLoopParts { tx, rx_queue: rx_consumer, samples, flash: dp.FLASH };
        (Shared { stats: SamplingStats::default() }, Local { sampler, rx, rx_queue: rx_producer, main: Some(main) })
    }

    /// The main loop: the core's instrument, one turn per wake-up (every sample, every received byte).
    #[idle(shared = [stats], local = [main])]
    fn idle(mut cx: idle::Context) -> ! {
        let Some(MainLoopParts { tx, rx_queue, mut samples, flash }) = cx.local.main.take() else {
            defmt::panic!("the main loop's parts were taken before it started")
        };
        let Some(flash) = RecordFlash::new(flash) else {
            defmt::panic!("memory.x and src/flash.rs disagree on the record's sectors")
        };
        let Ok(store) = RecordStore::new(flash, SECTOR_BYTES) else {
            defmt::panic!("the record's flash does not hold two slots")
        };
        let mut device = Device::new(IMU_MODEL, store);
        device.set_busy_hook(watchdog::main_loop_alive);
        log_boot(&device);
        let mut instrument = Instrument::new(&mut device, LinkPort::new(rx_queue, UsartTx(tx)));
        let mut longest_turn_us = 0;
        loop {
            watchdog::main_loop_alive();
            let start = cycles_now();
            let stats = cx.shared.stats.lock(|s| *s);
            instrument.turn(samples.as_mut(), &stats, link::RX_LOST.load(core::sync::atomic::Ordering::Relaxed));
            // A bring-up reading (docs/board.md#bring-up-checklist): the solve's turn against the watchdog's
            // main-loop deadline.
            let turn_us = us_since(start);
            if turn_us > longest_turn_us && turn_us > LONG_TURN_US {
                longest_turn_us = turn_us;
                defmt::info!("main loop: longest turn so far {=u32} us", turn_us);
            }
            cortex_m::asm::wfi();
        }
    }

    /// Data ready (PC4, EXTI4): one sample read, the table's signal latched with it, both enqueued; then the
    /// watchdog fed (the sample clock is alive; the main loop is checked by `watchdog::on_sample_clock`).
    #[task(binds = EXTI4, priority = 3, shared = [stats], local = [sampler])]
    fn data_ready(mut cx: data_ready::Context) {
        if let Some(s) = cx.local.sampler.as_mut() {
            s.data_ready.clear_interrupt_pending_bit();
            let table = if s.in_position.is_high() { TABLE_IN_POSITION } else { 0 };
            cx.shared.stats.lock(|stats| on_data_ready(&mut s.imu, &mut s.queue, stats, table));
        }
        watchdog::on_sample_clock();
    }

    /// The link's receive interrupt (USART1): every byte into the main loop's queue.
    #[task(binds = USART1, priority = 2, local = [rx, rx_queue])]
    fn link_receive(cx: link_receive::Context) {
        link::on_receive(cx.local.rx, cx.local.rx_queue);
    }

    /// Without an IMU: the sample clock's stand-in (SysTick at 100 Hz) for the watchdog; it also wakes the main loop.
    #[task(binds = SysTick, priority = 1)]
    fn tick(_: tick::Context) {
        watchdog::on_sample_clock();
    }
}
