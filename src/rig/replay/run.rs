//! The firmware path over a replay file: frames through the emulated device, the ADIS driver, the sampling
//! queue, the calibration sequence and the core.

use heapless::spsc::Queue;
use heapless::Vec;

use super::device::{NoDelay, ReplayDevice};
use super::file::{read_header, ByteSource, ReplayError, ReplayHeader};
use crate::calib::angles::{PositionInput, MAX_POSITIONS};
use crate::run::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
use crate::run::sequence::{feed_sequence, CalibrationSequence, Event, SequenceFailure, SequenceSolution};
use crate::sensor::adis::{Adis, AdisError, BURST32_LEN};

/// What a replay produced.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplayOutcome {
    /// The header.
    pub header: ReplayHeader,
    /// Completed positions (attitude and dwell statistics).
    pub positions: Vec<PositionInput, MAX_POSITIONS>,
    /// The solution, if the sequence got there.
    pub result: Option<SequenceSolution>,
    /// The failure, if it failed.
    pub failure: Option<SequenceFailure>,
    /// Sampling counters.
    pub sampling: SamplingStats,
    /// Dwells aborted (and collected again).
    pub aborted_dwells: u32,
}

/// Replays a file: frames through the replay device, the ADIS driver, the sampling queue and the
/// calibration sequence. `on_event` sees every event of the sequence (the firmware logs them).
pub fn run_replay<R: ByteSource>(
    mut source: R,
    mut on_event: impl FnMut(&Event),
) -> Result<ReplayOutcome, ReplayError> {
    let header = read_header(&mut source)?;
    let settings = header.settings;
    let model = header.model;
    let mut imu = Adis::new(ReplayDevice::new(model), model);
    imu.init(&mut NoDelay).map_err(|_: AdisError<ReplayError>| ReplayError::Init)?;
    let mut sequence =
        CalibrationSequence::new(&header.schedule, header.site, settings).map_err(ReplayError::Sequence)?;
    let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
    let mut stats = SamplingStats::default();
    let mut failure = None;
    let mut aborted_dwells = 0u32;
    let mut record = [0u8; 1 + BURST32_LEN];
    let record_len = 1 + model.burst_len();
    let mut handle = |event: Event| {
        match event {
            Event::Failed(f) => failure = Some(f),
            Event::DwellAborted { .. } => aborted_dwells = u32::saturating_add(aborted_dwells, 1),
            _ => {}
        }
        on_event(&event);
    };
    for _ in 0..header.frames {
        source.read_exact(&mut record[..record_len])?;
        let table = record[0];
        imu.spi_mut().load_frame(&record[1..record_len]);
        // What the data-ready interrupt does: read, and latch the table's signal with the sample.
        on_data_ready(&mut imu, &mut producer, &mut stats, table);
        // What the processing loop does.
        while let Some(events) = process_next(&mut consumer, |item| feed_sequence(&mut sequence, item)) {
            for event in events.into_iter().flatten() {
                handle(event);
            }
        }
    }
    while let Some(event) = sequence.finish() {
        handle(event);
    }
    let result = sequence.result().cloned();
    let mut positions = Vec::new();
    for p in sequence.completed() {
        let _ = positions.push(*p);
    }
    Ok(ReplayOutcome { header, positions, result, failure, sampling: stats, aborted_dwells })
}
