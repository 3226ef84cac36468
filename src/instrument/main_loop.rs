//! The instrument's main loop, written once for every board (target only): bytes from the link's receive queue
//! into frames, each frame to the [`Device`], its reply out of the board's transmitter; queued samples to the
//! device (the calibration sequence, the compensated stream); events and counters logged with defmt.
//!
//! A board brings only what is its own: the data-ready interrupt (it calls
//! [`on_data_ready`](crate::run::sampling::on_data_ready)), the receive interrupt (it fills the byte queue), a
//! transmitter ([`LinkTx`]), the flash, the watchdog, and the wait between two turns of the loop. QEMU's
//! `mps2-an386` (`src/board`) and the STM32F405 board package (`boards/stm32f405`) run this same loop.

use defmt_full as defmt;
use embedded_storage::nor_flash::NorFlash;
use heapless::spsc::Consumer;

use crate::instrument::device::{sample_frame, Action, Device};
use crate::instrument::link::{FrameReceiver, MAX_WIRE_BYTES};
use crate::instrument::message::DeviceState;
use crate::run::sampling::{process_next, QueueItem, SamplingStats};
use crate::run::sequence::Event;
use crate::sensor::adis::AdisError;
use crate::sensor::sample::ImuSample;

/// The transmitting half of a board's serial link.
pub trait LinkTx {
    /// Sends `bytes`; `false` if the transmitter stalled and the rest was not sent (a board bounds its waits).
    fn send(&mut self, bytes: &[u8]) -> bool;
}

/// The device's end of the link: the receive queue's consumer, the frame receiver, the transmitter and a reply
/// buffer.
pub struct LinkPort<T: LinkTx> {
    rx: Consumer<'static, u8>,
    tx: T,
    receiver: FrameReceiver,
    wire: [u8; MAX_WIRE_BYTES],
}

impl<T: LinkTx> LinkPort<T> {
    /// The link on the consumer of the receive interrupt's byte queue and the board's transmitter.
    pub fn new(rx: Consumer<'static, u8>, tx: T) -> LinkPort<T> {
        LinkPort { rx, tx, receiver: FrameReceiver::new(), wire: [0; MAX_WIRE_BYTES] }
    }

    /// Whether no byte waits.
    pub fn is_idle(&self) -> bool {
        self.rx.is_empty()
    }

    /// Handles every byte received so far: each whole frame goes to the device and its reply is sent. Returns
    /// `Action::Started` if a calibration started.
    pub fn pump<F: NorFlash>(&mut self, device: &mut Device<F>, sampling: &SamplingStats) -> Action {
        let mut action = Action::None;
        while let Some(byte) = self.rx.dequeue() {
            if let Some(frame) = self.receiver.push(byte) {
                let (n, a) = device.on_frame(frame, sampling, &mut self.wire);
                if !self.tx.send(&self.wire[..n]) {
                    defmt::warn!("link: transmit timed out");
                }
                if a == Action::Started {
                    action = a;
                }
            }
        }
        action
    }

    /// Sends a streamed sample.
    pub fn send_sample(&mut self, sample: &ImuSample) {
        let n = sample_frame(sample, &mut self.wire);
        let _ = self.tx.send(&self.wire[..n]);
    }
}

/// The instrument: the device (borrowed: it stays in the board's frame, where it was built, tens of kilobytes
/// that are never moved), its link, and whether the end of the last calibration was logged.
pub struct Instrument<'d, F: NorFlash, T: LinkTx> {
    /// The device behind the link.
    pub device: &'d mut Device<F>,
    /// The link.
    pub link: LinkPort<T>,
    reported: bool,
}

impl<'d, F: NorFlash, T: LinkTx> Instrument<'d, F, T> {
    /// The device on the link.
    pub fn new(device: &'d mut Device<F>, link: LinkPort<T>) -> Self {
        Instrument { device, link, reported: false }
    }

    /// One turn of the main loop: every received frame answered, every queued sample handed to the device (and
    /// streamed when the stream is on), the counters logged once when a calibration ends. `sampling` is the
    /// data-ready interrupt's counters now, `rx_overruns` the bytes the receive interrupt lost so far.
    pub fn turn(
        &mut self,
        samples: Option<&mut Consumer<'static, QueueItem>>,
        sampling: &SamplingStats,
        rx_overruns: u32,
    ) {
        self.device.link.rx_overruns = rx_overruns;
        self.link.pump(self.device, sampling);
        if let Some(consumer) = samples {
            let device = &mut *self.device;
            while let Some(out) = process_next(consumer, |item| device.on_sample(item, sampling, log_event)) {
                if let Some(sample) = out {
                    self.link.send_sample(&sample);
                }
            }
        }
        let done = !self.device.running() && self.device.state() != DeviceState::Idle;
        if done && !self.reported {
            log_counters(sampling, self.device);
        }
        self.reported = done;
    }
}

/// Logs an event of the calibration sequence (defmt).
pub fn log_event(e: &Event) {
    match e {
        Event::Settling { index } => defmt::info!("position {=usize}: in position, settling", index + 1),
        Event::DwellStarted { index } => defmt::info!("position {=usize}: collecting", index + 1),
        Event::DwellAborted { index, at_sample, .. } => {
            defmt::warn!("position {=usize}: dwell aborted at sample {=u32}", index + 1, at_sample)
        }
        Event::DwellCompleted { index, samples, faults } => {
            defmt::info!("position {=usize}: {=u32} samples, {=u32} faults", index + 1, samples, faults)
        }
        Event::Solved => defmt::info!("all positions collected: solved"),
        Event::Failed(_) => defmt::error!("calibration failed"),
    }
}

/// Logs, at boot, which record the device loaded (its sequence number and slot) and, in one warning, a damaged
/// record newer than it: the device then compensates with the older record, or with none.
pub fn log_boot<F: NorFlash>(device: &Device<F>) {
    match device.stored_record() {
        Some(r) => defmt::info!(
            "stored calibration: record {=u32} (slot {=u8}); compensates: {=bool}",
            r.sequence,
            r.slot,
            device.compensating()
        ),
        None => defmt::info!("no stored calibration: samples leave uncompensated"),
    }
    if let Some(d) = device.damaged_record() {
        defmt::warn!("the newest record ({=u32}, slot {=u8}) is damaged (CRC mismatch): not used", d.sequence, d.slot);
    }
}

/// Logs every counter of the sampling side and of the link (defmt).
pub fn log_counters<F: NorFlash>(sampling: &SamplingStats, device: &Device<F>) {
    let s = sampling.counters();
    for (name, value) in SamplingStats::COUNTER_NAMES.iter().zip(s) {
        defmt::info!("sampling {=str}: {=u32}", name, value);
    }
    let l = &device.link;
    defmt::info!(
        "link: {=u32} requests, {=u32} CRC errors, {=u32} frame errors, {=u32} version errors, {=u32} refused, {=u32} overruns",
        l.requests,
        l.crc_errors,
        l.frame_errors,
        l.version_errors,
        l.refused,
        l.rx_overruns
    );
}

/// Logs why the IMU did not start (defmt).
pub fn log_init_error<E>(e: &AdisError<E>) {
    match e {
        AdisError::WrongProduct { expected, found } => {
            defmt::error!("IMU: PROD_ID {=u16}, expected {=u16}", found, expected)
        }
        AdisError::SelfTest { diag_stat } => defmt::error!("IMU: self-test failed, DIAG_STAT {=u16:#x}", diag_stat),
        AdisError::ReadBack { register, written, read } => {
            defmt::error!("IMU: register {=u8:#x} reads back {=u16:#x}, {=u16:#x} written", register, read, written)
        }
        AdisError::Spi(_) => defmt::error!("IMU: SPI transfer failed"),
        _ => defmt::error!("IMU initialisation failed"),
    }
}
