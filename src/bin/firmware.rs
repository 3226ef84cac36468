//! The calibration instrument for an ADIS16505-2 on the SSP0 (PL022) SPI port of an MPS2 AN386 board
//! (Cortex-M4F), as QEMU's `mps2-an386` models it. No replay or test code: this is the binary whose flash and RAM
//! the budget measures.
//!
//! - TIMER0 (CMSDK APB timer, 25 MHz) interrupts at exactly 100 Hz: its hardware reload gives absolute
//!   deadlines. The interrupt only reads the IMU (burst read through the driver), latches the turntable's
//!   "in position" signal (GPIO0 pin 0) with it and enqueues both.
//! - UART0 is the host link (`sinscal device ... --port`): bytes in by interrupt, frames to the `Device`,
//!   replies out. The site, schedule and thresholds come over the link; nothing is compiled in.
//! - The main loop hands each queued sample to the device: the calibration sequence (when one runs) sees it raw,
//!   the stream (when on) gets it compensated with the stored calibration.
//! - The calibration record lives in the flash (on this board: the host file named by the first semihosting
//!   argument, `sinscal-flash.img` by default; QEMU models no flash controller here).
//! - The watchdog (CMSDK, NMI then reset): the main loop feeds it at every tick of TIMER0 (100 Hz, with or
//!   without an IMU), and so does the record store between its flash chunks; its NMI resets the system. Its
//!   period here is 0.5 s, not two sample periods: QEMU counts this watchdog in host time, and a loaded host
//!   stalls QEMU for tens of milliseconds. A board with a real oscillator uses two sample periods.
//! - Chip select of the IMU: GPIO0 pin 1, active low.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;
    use core::sync::atomic::{AtomicU32, Ordering};

    use cortex_m::interrupt::Mutex;
    use cortex_m_rt::{entry, exception};
    use defmt_full as defmt;
    use heapless::spsc::{Consumer, Producer, Queue};
    use sinscal::board::mps2_an386::{self as board, exit, CycleDelay, Pl022, TIMER0_IRQ};
    use sinscal::board::{uart, watchdog};
    use sinscal::instrument::device::Device;
    use sinscal::instrument::main_loop::{log_boot, log_init_error, Instrument, LinkPort};
    use sinscal::instrument::store::RecordStore;
    use sinscal::rig::semihost::{arg_path, CPath, HostFileFlash};
    use sinscal::run::sampling::{on_data_ready, QueueItem, SamplingStats, QUEUE_SLOTS, TABLE_IN_POSITION};
    use sinscal::sensor::adis::{Adis, Model, OUTPUT_RATE_HZ};

    /// The watchdog's period, microseconds (see the module's documentation for why not two sample periods).
    const WATCHDOG_PERIOD_US: u32 = 500_000;

    /// What the data-ready interrupt owns.
    struct Sampler {
        imu: Adis<Pl022>,
        queue: Producer<'static, QueueItem>,
        stats: SamplingStats,
    }

    static SAMPLER: Mutex<RefCell<Option<Sampler>>> = Mutex::new(RefCell::new(None));
    static RX: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
    static RX_LOST: AtomicU32 = AtomicU32::new(0);

    #[exception]
    unsafe fn DefaultHandler(irqn: i16) {
        if irqn == TIMER0_IRQ {
            board::clear_sample_timer();
            cortex_m::interrupt::free(|cs| {
                if let Some(s) = SAMPLER.borrow(cs).borrow_mut().as_mut() {
                    // The table's signal now, with the sample now: the processing loop may be up to 15
                    // samples behind.
                    let table = if board::in_position() { TABLE_IN_POSITION } else { 0 };
                    on_data_ready(&mut s.imu, &mut s.queue, &mut s.stats, table);
                }
            });
        } else if irqn == uart::UART0_RX_IRQ {
            cortex_m::interrupt::free(|cs| {
                if let Some(p) = RX.borrow(cs).borrow_mut().as_mut() {
                    if uart::on_receive(p) {
                        RX_LOST.fetch_add(1, Ordering::Relaxed);
                    }
                }
            });
        }
    }

    #[exception]
    unsafe fn NonMaskableInt() {
        // The watchdog: the main loop missed two sample periods.
        defmt::error!("watchdog: the main loop stalled; reset");
        cortex_m::peripheral::SCB::sys_reset();
    }

    /// Starts sampling: the IMU initialised, the data-ready timer at its output rate; `None` if the IMU does not
    /// start (the link still answers; the status shows no samples).
    fn start_sampling() -> Option<Consumer<'static, QueueItem>> {
        let mut imu = Adis::new(Pl022::init(), Model::Adis16505_2);
        if let Err(e) = imu.init(&mut CycleDelay) {
            log_init_error(&e);
            return None;
        }
        let queue: &'static mut Queue<QueueItem, QUEUE_SLOTS> =
            cortex_m::singleton!(: Queue<QueueItem, QUEUE_SLOTS> = Queue::new())?;
        let (producer, consumer) = queue.split();
        cortex_m::interrupt::free(|cs| {
            SAMPLER.borrow(cs).replace(Some(Sampler { imu, queue: producer, stats: SamplingStats::default() }));
        });
        Some(consumer)
    }

    #[entry]
    fn main() -> ! {
        let path = arg_path(1).or_else(|| CPath::new("sinscal-flash.img")).unwrap_or_else(|| exit(2));
        let Ok(store) = RecordStore::new(HostFileFlash::open(path), HostFileFlash::SECTOR_BYTES as u32) else {
            exit(3)
        };
        let mut device = Device::new(Model::Adis16505_2, store);
        device.set_busy_hook(watchdog::feed);
        defmt::info!("sinscal-firmware: ready");
        log_boot(&device);
        let rx: &'static mut Queue<u8, { uart::RX_QUEUE_SLOTS }> =
            cortex_m::singleton!(: Queue<u8, { uart::RX_QUEUE_SLOTS }> = Queue::new()).unwrap_or_else(|| exit(2));
        let (rx_producer, rx_consumer) = rx.split();
        cortex_m::interrupt::free(|cs| {
            RX.borrow(cs).replace(Some(rx_producer));
        });
        let mut instrument = Instrument::new(&mut device, LinkPort::new(rx_consumer, uart::Uart0));
        uart::init();
        let mut samples = start_sampling();
        // The data-ready timer at the IMU's output rate (100 Hz); without an IMU, the main loop's tick.
        board::start_sample_timer(OUTPUT_RATE_HZ as u32);
        if watchdog::present() {
            watchdog::start(WATCHDOG_PERIOD_US);
        }
        loop {
            watchdog::feed();
            let stats = cortex_m::interrupt::free(|cs| SAMPLER.borrow(cs).borrow().as_ref().map(|s| s.stats))
                .unwrap_or_default();
            instrument.turn(samples.as_mut(), &stats, RX_LOST.load(Ordering::Relaxed));
            cortex_m::asm::wfi();
        }
    }
}
