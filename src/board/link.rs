//! What every instrument firmware's main loop does with the link and the device, written once: bytes from the
//! receive queue into frames, each frame to the [`Device`], its reply out of UART0; events and the device's
//! samples logged or streamed.

use defmt_full as defmt;
use embedded_storage::nor_flash::NorFlash;
use heapless::spsc::Consumer;

use super::uart;
use crate::instrument::device::{sample_frame, Action, Device};
use crate::instrument::link::{FrameReceiver, MAX_WIRE_BYTES};
use crate::run::sampling::SamplingStats;
use crate::run::sequence::Event;
use crate::sensor::sample::ImuSample;

/// The device's end of the link: the receive queue's consumer, the frame receiver and a reply buffer.
pub struct LinkPort {
    rx: Consumer<'static, u8>,
    receiver: FrameReceiver,
    wire: [u8; MAX_WIRE_BYTES],
}

impl LinkPort {
    /// The link on the consumer of UART0's receive queue.
    pub fn new(rx: Consumer<'static, u8>) -> LinkPort {
        LinkPort { rx, receiver: FrameReceiver::new(), wire: [0; MAX_WIRE_BYTES] }
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
                if !uart::send(&self.wire[..n]) {
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
        let _ = uart::send(&self.wire[..n]);
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
