//! The firmware path over a replay file: frames through the emulated device, the ADIS driver, the sampling
//! queue, the calibration sequence and the core.

use heapless::spsc::Queue;
use heapless::Vec;

use super::device::ReplayDevice;
use super::file::{read_header, ByteSource, ReplayError, ReplayHeader};
use crate::calib::calibration::PositionInput;
use crate::calib::solve::MAX_POSITIONS;
use crate::run::sampling::{on_data_ready, process_next, QueueItem, SamplingStats, QUEUE_SLOTS};
use crate::run::sequence::{CalibrationSequence, Event, SequenceFailure, SequenceSolution};
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
    imu.init().map_err(|_: AdisError<ReplayError>| ReplayError::Init)?;
    let mut sequence =
        CalibrationSequence::new(&header.schedule, header.site, settings).map_err(ReplayError::Sequence)?;
    let mut queue: Queue<QueueItem, QUEUE_SLOTS> = Queue::new();
    let (mut producer, mut consumer) = queue.split();
    let mut stats = SamplingStats::default();
    let mut failure = None;
    let mut aborted_dwells = 0;
    let mut record = [0u8; 1 + BURST32_LEN];
    let record_len = 1 + model.burst_len();
    let mut handle = |event: Event| {
        match event {
            Event::Failed(f) => failure = Some(f),
            Event::DwellAborted { .. } => aborted_dwells += 1,
            _ => {}
        }
        on_event(&event);
    };
    for _ in 0..header.frames {
        source.read_exact(&mut record[..record_len])?;
        let table = record[0];
        imu.spi_mut().load_frame(&record[1..record_len]);
        // What the data-ready interrupt does.
        on_data_ready(&mut imu, &mut producer, &mut stats);
        // What the processing loop does.
        while let Some(events) = process_next(&mut consumer, |item| {
            let in_position = table as usize == sequence.position() + 1;
            let first = sequence.on_sample(in_position, item);
            // Contiguous dwells (no sample between them): the sample that ends a dwell because the table
            // reports the next position is that position's first sample, not lost.
            let next = !in_position
                && matches!(first, Some(Event::DwellCompleted { .. }))
                && table as usize == sequence.position() + 1;
            let second = if next { sequence.on_sample(true, item) } else { None };
            [first, second]
        }) {
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
