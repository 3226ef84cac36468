//! The calibration firmware for an ADIS16505-2 on the SSP0 (PL022) SPI port of an MPS2 AN386 board
//! (Cortex-M4F), as QEMU's `mps2-an386` models it. No replay or test code: this is the binary whose flash
//! and RAM the budget measures.
//!
//! - TIMER0 (CMSDK APB timer, 25 MHz) interrupts at exactly 100 Hz: its hardware reload gives absolute
//!   deadlines. The interrupt only reads the IMU (burst read through the driver), latches the turntable's
//!   "in position" signal (GPIO0 pin 0) with it and enqueues both.
//! - The main loop owns the calibration sequence (prefilter bank and accumulators inside): it takes the
//!   items off the queue, feeds them to the sequence with the signal as it was at each sample
//!   (`feed_sequence`), and logs the events and the result with defmt.
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
    use heapless::spsc::{Consumer, Producer, Queue};
    use sinscal::board::mps2_an386::{self as board, exit, CycleDelay, Pl022, TIMER0_IRQ};
    use sinscal::calib::channels::parameter_name;
    use sinscal::calib::solve::TABLE1_POSITIONS_DEG;
    use sinscal::nav::earth::Site;
    use sinscal::nav::frames::Attitude;
    use sinscal::run::sampling::{
        on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS, TABLE_IN_POSITION,
    };
    use sinscal::run::sequence::{feed_sequence, CalibrationSequence, Event, SequenceSettings, SequenceSolution};
    use sinscal::sensor::adis::{Adis, AdisError, Model, OUTPUT_RATE_HZ};

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
            board::clear_sample_timer();
            cortex_m::interrupt::free(|cs| {
                if let Some(s) = SAMPLER.borrow(cs).borrow_mut().as_mut() {
                    // The table's signal now, with the sample now: the processing loop may be up to 15
                    // samples behind.
                    let table = if board::in_position() { TABLE_IN_POSITION } else { 0 };
                    on_data_ready(&mut s.imu, &mut s.queue, &mut s.stats, table);
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
            Event::Solved => match sequence.result() {
                Some(SequenceSolution::Channels(c)) => {
                    for i in 0..6 {
                        let (value, std) = c.estimate(i).unwrap_or((f32::NAN, f32::NAN));
                        defmt::info!("{=str}: {=f32} +- {=f32} (SI)", parameter_name(i), value, std);
                    }
                }
                Some(SequenceSolution::Angles(r)) => {
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
                None => {}
            },
            Event::Failed(_) => defmt::error!("calibration failed"),
        }
    }

    #[entry]
    fn main() -> ! {
        let mut imu = Adis::new(Pl022::init(), Model::Adis16505_2);
        if let Err(e) = imu.init(&mut CycleDelay) {
            match e {
                AdisError::WrongProduct { expected, found } => {
                    defmt::error!("IMU: PROD_ID {=u16}, expected {=u16}", found, expected)
                }
                AdisError::SelfTest { diag_stat } => {
                    defmt::error!("IMU: self-test failed, DIAG_STAT {=u16:#x}", diag_stat)
                }
                AdisError::ReadBack { register, written, read } => defmt::error!(
                    "IMU: register {=u8:#x} reads back {=u16:#x}, {=u16:#x} written",
                    register,
                    read,
                    written
                ),
                AdisError::Spi(_) => defmt::error!("IMU: SPI timeout"),
                _ => defmt::error!("IMU initialisation failed"),
            }
            exit(1);
        }
        let queue: &'static mut Queue<QueueItem, QUEUE_SLOTS> =
            cortex_m::singleton!(: Queue<QueueItem, QUEUE_SLOTS> = Queue::new()).unwrap_or_else(|| exit(2));
        let (producer, mut consumer): (_, Consumer<'static, QueueItem>) = queue.split();
        cortex_m::interrupt::free(|cs| {
            SAMPLER.borrow(cs).replace(Some(Sampler { imu, queue: producer, stats: SamplingStats::default() }));
        });
        let schedule = TABLE1_POSITIONS_DEG.map(|p| Attitude::from_degrees(p[0], p[1], p[2]));
        let site = Site::with_normal_gravity(45.7796f32.to_radians(), 0.0);
        let Ok(mut sequence) = CalibrationSequence::new(&schedule, site, SequenceSettings::default()) else { exit(3) };
        // The data-ready timer at the IMU's output rate (100 Hz).
        board::start_sample_timer(OUTPUT_RATE_HZ as u32);
        loop {
            while let Some(events) = process_next(&mut consumer, |item| feed_sequence(&mut sequence, item)) {
                for event in events.iter().flatten() {
                    log_event(event, &sequence);
                }
            }
            cortex_m::asm::wfi();
        }
    }
}
