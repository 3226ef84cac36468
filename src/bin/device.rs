//! Firmware: the calibration instrument in the emulated Cortex-M4F (QEMU mps2-an386), with the ADIS emulated by
//! the replay device on the SPI bus. `sinscal device run|show --qemu --flash IMAGE` boots it:
//!     qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -serial unix:SOCKET \
//!       -semihosting-config enable=on,target=native,arg=sinscal-device,arg=IMAGE,arg=REPLAY -kernel ELF
//! - UART0 is the host link (frames and messages of `sinscal::instrument`), received by interrupt.
//! - IMAGE is the flash (two 16 KiB sectors, a host file through semihosting, kept across boots): the calibration
//!   record is loaded from it at boot and compensates every sample.
//! - REPLAY (`-` for none) holds the IMU's frames and the turntable's position signal: when a calibration starts,
//!   each frame is served by the emulated ADIS to the real driver, as fast as the main loop takes them, and the
//!   data-ready handler latches the position signal with the sample. The site, schedule and settings come over
//!   the link, not from the file.
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
    use sinscal::board::{exit, uart};
    use sinscal::instrument::device::{Action, Device};
    use sinscal::instrument::main_loop::{log_boot, log_counters, log_event, LinkPort};
    use sinscal::instrument::store::RecordStore;
    use sinscal::rig::replay::{read_header, ByteSource, ReplayDevice};
    use sinscal::rig::semihost::{arg_path, FileSource, HostFileFlash};
    use sinscal::run::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
    use sinscal::sensor::adis::{Adis, Model, BURST32_LEN};

    static RX: Mutex<RefCell<Option<Producer<'static, u8>>>> = Mutex::new(RefCell::new(None));
    static RX_LOST: AtomicU32 = AtomicU32::new(0);
    /// The idle loop's wake-up tick, Hz.
    const IDLE_TICK_HZ: u32 = 100;

    #[exception]
    unsafe fn DefaultHandler(irqn: i16) {
        if irqn == sinscal::board::mps2_an386::TIMER0_IRQ {
            // The wake-up tick of the idle loop.
            sinscal::board::mps2_an386::clear_sample_timer();
        }
        if irqn == uart::UART0_RX_IRQ {
            cortex_m::interrupt::free(|cs| {
                if let Some(p) = RX.borrow(cs).borrow_mut().as_mut() {
                    if uart::on_receive(p) {
                        RX_LOST.fetch_add(1, Ordering::Relaxed);
                    }
                }
            });
        }
    }

    fn fail(what: &str) -> ! {
        defmt::error!("sinscal-device: {=str}", what);
        exit(1)
    }

    /// The replay's frames: the file, its model and the frames left.
    struct Frames {
        source: FileSource,
        model: Model,
        left: u32,
    }

    fn open_frames() -> Option<Frames> {
        let path = arg_path(2).filter(|p| p.as_c_str().to_bytes() != b"-")?;
        let mut source = FileSource::open(&path).unwrap_or_else(|| fail("cannot open the replay file"));
        let header = read_header(&mut source).unwrap_or_else(|_| fail("replay file unreadable"));
        Some(Frames { source, model: header.configuration.imu, left: header.frames })
    }

    /// What the data-ready interrupt would do for one frame: serve it, read it, latch the table signal.
    fn sample_frame(
        frames: &mut Frames,
        imu: &mut Adis<ReplayDevice>,
        queue: &mut Producer<'_, QueueItem>,
        stats: &mut SamplingStats,
    ) -> bool {
        let mut record = [0u8; 1 + BURST32_LEN];
        let len = 1 + frames.model.burst_len();
        if frames.left == 0 || frames.source.read_exact(&mut record[..len]).is_err() {
            return false;
        }
        frames.left -= 1;
        imu.spi_mut().load_frame(&record[1..len]);
        on_data_ready(imu, queue, stats, record[0]);
        true
    }

    #[entry]
    fn main() -> ! {
        let flash_path = arg_path(1).unwrap_or_else(|| fail("usage: sinscal-device FLASH REPLAY"));
        let flash = HostFileFlash::open(flash_path);
        let store =
            RecordStore::new(flash, HostFileFlash::SECTOR_BYTES as u32).unwrap_or_else(|_| fail("flash layout"));
        let mut frames = open_frames();
        let model = frames.as_ref().map_or(Model::Adis16505_2, |f| f.model);
        let mut imu = Adis::new(ReplayDevice::new(model), model);
        if imu.init(&mut sinscal::rig::replay::NoDelay).is_err() {
            fail("IMU initialisation failed");
        }
        let mut device = Device::new(model, store);
        defmt::info!("sinscal-device: ready");
        log_boot(&device);
        let rx: &'static mut Queue<u8, { uart::RX_QUEUE_SLOTS }> =
            cortex_m::singleton!(: Queue<u8, { uart::RX_QUEUE_SLOTS }> = Queue::new()).unwrap_or_else(|| exit(2));
        let (rx_producer, rx_consumer): (_, Consumer<'static, u8>) = rx.split();
        cortex_m::interrupt::free(|cs| {
            RX.borrow(cs).replace(Some(rx_producer));
        });
        let mut link = LinkPort::new(rx_consumer, uart::Uart0);
        uart::init();
        sinscal::board::mps2_an386::start_sample_timer(IDLE_TICK_HZ);
        let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
        let (mut producer, mut consumer) = queue.split();
        let mut stats = SamplingStats::default();
        loop {
            device.link.rx_overruns = RX_LOST.load(Ordering::Relaxed);
            if link.pump(&mut device, &stats) == Action::Started {
                // A calibration starts: the replay starts from its first frame.
                frames = open_frames();
            }
            if !device.running() {
                // Sleep until a byte arrives or the next tick. (The tick bounds the wait of a byte that arrives
                // between the check and the WFI: QEMU does not wake a WFI for an interrupt masked by PRIMASK, so
                // the usual masked check-then-wait would sleep for ever there.)
                if link.is_idle() {
                    cortex_m::asm::wfi();
                }
                continue;
            }
            let sampled = frames.as_mut().is_some_and(|f| sample_frame(f, &mut imu, &mut producer, &mut stats));
            while let Some(out) = process_next(&mut consumer, |item| device.on_sample(item, &stats, log_event)) {
                if let Some(sample) = out {
                    link.send_sample(&sample);
                }
            }
            if !sampled {
                device.end_of_samples(&stats, log_event);
                log_counters(&stats, &device);
            }
        }
    }
}
