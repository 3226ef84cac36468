//! The calibration firmware for an ADIS16505-2 on the SSP0 (PL022) SPI port of an MPS2 AN386 board
//! (Cortex-M4F), as QEMU's `mps2-an386` models it. No replay or test code: this is the binary whose flash
//! and RAM the budget measures.
//!
//! - TIMER0 (CMSDK APB timer, 25 MHz) interrupts at exactly 100 Hz: its hardware reload gives absolute
//!   deadlines. The interrupt only reads the IMU (burst read through the driver) and enqueues the reading.
//! - The main loop owns the calibration sequence (prefilter bank and accumulators inside): it takes the
//!   readings off the queue with the turntable's "in position" signal (GPIO0 pin 0) and logs the events
//!   and the result with defmt.
//! - Chip select of the IMU: GPIO0 pin 1, active low.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::RefCell;

    use cortex_m::interrupt::Mutex;
    use cortex_m_rt::{entry, exception};
    use defmt_full as defmt;
    use defmt_semihosting as _;
    use embedded_hal::spi::{ErrorKind, ErrorType, Operation, SpiDevice};
    use heapless::spsc::{Consumer, Producer, Queue};
    use sinscal::adis::{Adis, Model};
    use sinscal::earth::Site;
    use sinscal::frames::Attitude;
    use sinscal::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
    use sinscal::sequence::{CalibrationSequence, Event, SequenceSettings};
    use sinscal::solve::TABLE1_POSITIONS_DEG;

    /// PL022 SSP0 of the MPS2 FPGA image (AN386).
    const SSP0: usize = 0x4002_0000;
    const SSP_CR0: usize = 0x00;
    const SSP_CR1: usize = 0x04;
    const SSP_DR: usize = 0x08;
    const SSP_SR: usize = 0x0C;
    const SSP_CPSR: usize = 0x10;
    const SSP_SR_TNF: u32 = 1 << 1;
    const SSP_SR_RNE: u32 = 1 << 2;
    /// CMSDK AHB GPIO 0.
    const GPIO0: usize = 0x4001_0000;
    const GPIO_DATA: usize = 0x00;
    const GPIO_DATAOUT: usize = 0x04;
    const GPIO_OUTENSET: usize = 0x10;
    const PIN_IN_POSITION: u32 = 1 << 0;
    const PIN_IMU_CS: u32 = 1 << 1;
    /// CMSDK APB TIMER0 and its interrupt number on MPS2.
    const TIMER0: usize = 0x4000_0000;
    const TIMER_CTRL: usize = 0x00;
    const TIMER_RELOAD: usize = 0x08;
    const TIMER_INTCLEAR: usize = 0x0C;
    const TIMER0_IRQ: i16 = 8;
    /// Core and peripheral clock, Hz.
    const CLOCK_HZ: u32 = 25_000_000;

    fn write(addr: usize, value: u32) {
        // Memory-mapped peripheral registers of the board.
        unsafe { core::ptr::write_volatile(addr as *mut u32, value) }
    }

    fn read(addr: usize) -> u32 {
        unsafe { core::ptr::read_volatile(addr as *const u32) }
    }

    /// The PL022 as an embedded-hal SPI device, with a GPIO chip select.
    struct Pl022;

    #[derive(Debug)]
    struct SpiError;

    impl embedded_hal::spi::Error for SpiError {
        fn kind(&self) -> ErrorKind {
            ErrorKind::Other
        }
    }

    impl ErrorType for Pl022 {
        type Error = SpiError;
    }

    impl Pl022 {
        fn init() -> Pl022 {
            // 8-bit frames, SPI mode 3 (CPOL = 1, CPHA = 1, as the ADIS needs), 25 MHz / (2 * 13) < 1 MHz.
            write(SSP0 + SSP_CR0, 0x7 | (1 << 6) | (1 << 7));
            write(SSP0 + SSP_CPSR, 26);
            write(SSP0 + SSP_CR1, 1 << 1);
            write(GPIO0 + GPIO_OUTENSET, PIN_IMU_CS);
            write(GPIO0 + GPIO_DATAOUT, PIN_IMU_CS);
            Pl022
        }

        fn transfer_byte(byte: u8) -> u8 {
            while read(SSP0 + SSP_SR) & SSP_SR_TNF == 0 {}
            write(SSP0 + SSP_DR, byte as u32);
            while read(SSP0 + SSP_SR) & SSP_SR_RNE == 0 {}
            read(SSP0 + SSP_DR) as u8
        }
    }

    impl SpiDevice for Pl022 {
        fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), SpiError> {
            write(GPIO0 + GPIO_DATAOUT, 0);
            for op in operations.iter_mut() {
                match op {
                    Operation::Write(bytes) => bytes.iter().for_each(|&b| {
                        Self::transfer_byte(b);
                    }),
                    Operation::Read(bytes) => bytes.iter_mut().for_each(|b| *b = Self::transfer_byte(0)),
                    Operation::Transfer(r, w) => {
                        for (i, rb) in r.iter_mut().enumerate() {
                            *rb = Self::transfer_byte(w.get(i).copied().unwrap_or(0));
                        }
                    }
                    Operation::TransferInPlace(bytes) => bytes.iter_mut().for_each(|b| *b = Self::transfer_byte(*b)),
                    Operation::DelayNs(ns) => cortex_m::asm::delay(*ns / 40 + 1),
                }
            }
            write(GPIO0 + GPIO_DATAOUT, PIN_IMU_CS);
            Ok(())
        }
    }

    /// What the data-ready interrupt owns.
    struct Sampler {
        imu: Adis<Pl022>,
        queue: Producer<'static, QueueItem>,
        stats: SamplingStats,
    }

    static SAMPLER: Mutex<RefCell<Option<Sampler>>> = Mutex::new(RefCell::new(None));

    #[exception]
    unsafe fn DefaultHandler(irqn: i16) {
        if irqn == TIMER0_IRQ {
            write(TIMER0 + TIMER_INTCLEAR, 1);
            cortex_m::interrupt::free(|cs| {
                if let Some(s) = SAMPLER.borrow(cs).borrow_mut().as_mut() {
                    on_data_ready(&mut s.imu, &mut s.queue, &mut s.stats);
                }
            });
        }
    }

    fn log_event(e: &Event, sequence: &CalibrationSequence) {
        match e {
            Event::Settling { index } => defmt::info!("position {=usize}: in position, settling", index + 1),
            Event::DwellStarted { index } => defmt::info!("position {=usize}: collecting", index + 1),
            Event::DwellAborted { index, at_sample, .. } => {
                defmt::warn!("position {=usize}: dwell aborted at sample {=u32}", index + 1, at_sample)
            }
            Event::DwellCompleted { index, samples, faults } => {
                defmt::info!("position {=usize}: {=u32} samples, {=u32} faults", index + 1, samples, faults)
            }
            Event::Solved => {
                if let Some(r) = sequence.result() {
                    let s = &r.solution;
                    for i in 0..3 {
                        let (g, a) = (s.gyro_bias_b_radps[i], s.accel_bias_b_mps2[i]);
                        defmt::info!(
                            "axis {=usize}: gyro bias {=f32} +- {=f32} rad/s, accel bias {=f32} +- {=f32} m/s^2",
                            i,
                            g.map_or(f32::NAN, |e| e.value),
                            g.map_or(f32::NAN, |e| e.std_error),
                            a.map_or(f32::NAN, |e| e.value),
                            a.map_or(f32::NAN, |e| e.std_error)
                        );
                    }
                }
            }
            Event::Failed(_) => defmt::error!("calibration failed"),
        }
    }

    #[entry]
    fn main() -> ! {
        let mut imu = Adis::new(Pl022::init(), Model::Adis16505_2);
        if let Err(e) = imu.init() {
            match e {
                sinscal::adis::AdisError::WrongProduct { expected, found } => {
                    defmt::error!("IMU: PROD_ID {=u16}, expected {=u16}", found, expected)
                }
                _ => defmt::error!("IMU initialisation failed"),
            }
            semihosting::process::exit(1);
        }
        let queue: &'static mut Queue<QueueItem, QUEUE_SLOTS> =
            cortex_m::singleton!(: Queue<QueueItem, QUEUE_SLOTS> = Queue::new())
                .unwrap_or_else(|| semihosting::process::exit(2));
        let (producer, mut consumer): (_, Consumer<'static, QueueItem>) = queue.split();
        cortex_m::interrupt::free(|cs| {
            SAMPLER.borrow(cs).replace(Some(Sampler { imu, queue: producer, stats: SamplingStats::default() }));
        });
        let schedule = TABLE1_POSITIONS_DEG.map(|p| Attitude::from_degrees(p[0], p[1], p[2]));
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let Ok(mut sequence) = CalibrationSequence::new(&schedule, site, SequenceSettings::default()) else {
            semihosting::process::exit(3)
        };
        // 100 Hz data-ready timer.
        write(TIMER0 + TIMER_RELOAD, CLOCK_HZ / 100 - 1);
        write(TIMER0 + TIMER_CTRL, 0b1001);
        unsafe { cortex_m::peripheral::NVIC::unmask(Irq(TIMER0_IRQ as u16)) };
        loop {
            while let Some(event) = process_next(&mut consumer, |item| {
                let in_position = read(GPIO0 + GPIO_DATA) & PIN_IN_POSITION != 0;
                sequence.on_sample(in_position, item)
            }) {
                if let Some(event) = event {
                    log_event(&event, &sequence);
                }
            }
            cortex_m::asm::wfi();
        }
    }

    #[derive(Clone, Copy)]
    struct Irq(u16);

    unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
        fn number(self) -> u16 {
            self.0
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        defmt::error!("panic");
        semihosting::process::exit(101)
    }
}
