//! The data-ready side of sampling: read the sensor and push into a bounded queue, nothing else.
//!
//! [`on_data_ready`] runs in the data-ready interrupt (100 Hz). It never blocks and never drops anything
//! silently: a full queue, a read fault of each kind, and samples the sensor produced but nobody read
//! (data counter gaps) are counted in [`SamplingStats`]. Faults travel through the queue too, in order,
//! so the processing side knows which dwell they hit, and every item carries the turntable's signal as it
//! was when the sample was taken ([`QueueItem::table`]).

use heapless::spsc::{Consumer, Producer};

use crate::sensor::sample::ImuReading;
use crate::sensor::source::{ClassifiedError, ImuSource, ReadFault};

/// The turntable signal of a [`QueueItem`] from a board whose input only says "in position" (one GPIO
/// line), without saying which position: in position for whichever position the sequence expects. A
/// table that reports its position number uses 1 to 64 instead, and 0 means moving.
pub const TABLE_IN_POSITION: u8 = 255;

/// The turntable signals of a labelled full turn about body x, y and z (moving, back to where it started:
/// docs/method.md#moves). A table that reports its turns uses them instead of 0 while it makes one.
pub const TABLE_TURN: [u8; 3] = [252, 253, 254];

/// The body axis (0, 1, 2) of a turn signal, `None` for any other.
#[inline]
pub fn turn_axis_of(table: u8) -> Option<usize> {
    TABLE_TURN.iter().position(|t| *t == table)
}

/// What travels from the interrupt to the processing loop: a reading, or the fault that replaced it, with
/// the turntable's signal latched at the same moment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueueItem {
    /// The reading, or the kind of fault that replaced it.
    pub reading: Result<ImuReading, ReadFault>,
    /// The turntable's signal when the sample was taken: 0 = moving, k = in position k (1-based, as the
    /// replay file's table byte), [`TABLE_TURN`] = moving, a labelled full turn about body x, y or z,
    /// [`TABLE_IN_POSITION`] = in position (a board that does not say which).
    /// Latched in the interrupt with the sample, so that a processing loop running up to
    /// `QUEUE_SLOTS - 1` samples behind still sees the table as it was for this sample.
    pub table: u8,
}

/// Queue length (heapless 0.9: a `Queue<T, N>` holds N - 1 items): 15 samples = 150 ms of slack for the
/// processing loop.
pub const QUEUE_SLOTS: usize = 16;

/// Counters of the sampling side. Every counter saturates at `u32::MAX` instead of wrapping (at 100 Hz
/// that is after 497 days), so a count never silently restarts from zero.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SamplingStats {
    /// Data-ready events handled.
    pub events: u32,
    /// Good readings.
    pub readings: u32,
    /// Items (readings or faults) that did not fit into the queue.
    pub queue_full: u32,
    /// Bus failures.
    pub bus_errors: u32,
    /// Checksum mismatches.
    pub checksum_errors: u32,
    /// Stalled data counters.
    pub stalled_counters: u32,
    /// Status flags raised by the sensor.
    pub status_flags: u32,
    /// Frames of zero bytes only (the data line stuck low: [`ReadFault::DeadBus`]).
    pub dead_bus_frames: u32,
    /// Samples missed according to the sensor's counter.
    pub missed_samples: u32,
    /// The most items the queue held at once (its high-water mark; not part of a replay's outcome).
    pub queue_high_water: u32,
}

impl SamplingStats {
    /// Names of [`SamplingStats::counters`], in order.
    pub const COUNTER_NAMES: [&'static str; 10] = [
        "events",
        "readings",
        "queue_full",
        "bus_errors",
        "checksum_errors",
        "stalled_counters",
        "status_flags",
        "dead_bus_frames",
        "missed_samples",
        "queue_high_water",
    ];

    /// Every counter, in the order of [`SamplingStats::COUNTER_NAMES`] (the device's status reply).
    pub fn counters(&self) -> [u32; 10] {
        [
            self.events,
            self.readings,
            self.queue_full,
            self.bus_errors,
            self.checksum_errors,
            self.stalled_counters,
            self.status_flags,
            self.dead_bus_frames,
            self.missed_samples,
            self.queue_high_water,
        ]
    }

    /// The counters of [`SamplingStats::counters`]' order.
    pub fn from_counters(c: [u32; 10]) -> SamplingStats {
        let [events, readings, queue_full, bus_errors, checksum_errors, stalled_counters, status_flags, dead_bus_frames, missed_samples, queue_high_water] =
            c;
        SamplingStats {
            events,
            readings,
            queue_full,
            bus_errors,
            checksum_errors,
            stalled_counters,
            status_flags,
            dead_bus_frames,
            missed_samples,
            queue_high_water,
        }
    }

    /// The counts since `start` (an earlier snapshot of the same counters); the high-water mark is this one's.
    pub fn since(&self, start: &SamplingStats) -> SamplingStats {
        SamplingStats {
            events: self.events.saturating_sub(start.events),
            readings: self.readings.saturating_sub(start.readings),
            queue_full: self.queue_full.saturating_sub(start.queue_full),
            bus_errors: self.bus_errors.saturating_sub(start.bus_errors),
            checksum_errors: self.checksum_errors.saturating_sub(start.checksum_errors),
            stalled_counters: self.stalled_counters.saturating_sub(start.stalled_counters),
            status_flags: self.status_flags.saturating_sub(start.status_flags),
            dead_bus_frames: self.dead_bus_frames.saturating_sub(start.dead_bus_frames),
            missed_samples: self.missed_samples.saturating_sub(start.missed_samples),
            queue_high_water: self.queue_high_water,
        }
    }

    /// Faults of every kind (saturating).
    pub fn faults(&self) -> u32 {
        self.bus_errors
            .saturating_add(self.checksum_errors)
            .saturating_add(self.stalled_counters)
            .saturating_add(self.status_flags)
            .saturating_add(self.dead_bus_frames)
    }
}

/// Handles one data-ready event: one read, one enqueue attempt with the turntable signal `table` latched
/// with it ([`QueueItem::table`]), counters updated (saturating).
#[inline]
pub fn on_data_ready<S: ImuSource>(
    imu: &mut S,
    queue: &mut Producer<'_, QueueItem>,
    stats: &mut SamplingStats,
    table: u8,
) {
    stats.events = stats.events.saturating_add(1);
    let reading = match imu.read() {
        Ok(reading) => {
            stats.readings = stats.readings.saturating_add(1);
            stats.missed_samples = stats.missed_samples.saturating_add(reading.missed as u32);
            Ok(reading)
        }
        Err(e) => {
            let fault = e.fault();
            let counter = match fault {
                ReadFault::Bus => &mut stats.bus_errors,
                ReadFault::Checksum => &mut stats.checksum_errors,
                ReadFault::StalledCounter => &mut stats.stalled_counters,
                ReadFault::StatusFlag => &mut stats.status_flags,
                ReadFault::DeadBus => &mut stats.dead_bus_frames,
            };
            *counter = counter.saturating_add(1);
            Err(fault)
        }
    };
    if queue.enqueue(QueueItem { reading, table }).is_err() {
        stats.queue_full = stats.queue_full.saturating_add(1);
    }
    stats.queue_high_water = stats.queue_high_water.max(queue.len() as u32);
}

/// Hands the oldest queued item to `f` by reference, then removes it: the item is read in place, never
/// copied out of the queue (a copy of the 40-byte item costs more instructions than its checks). Returns
/// `f`'s result, or `None` when the queue is empty.
#[inline]
pub fn process_next<R>(queue: &mut Consumer<'_, QueueItem>, f: impl FnOnce(&QueueItem) -> R) -> Option<R> {
    let result = f(queue.peek()?);
    // The value just processed; nothing reads it, so the compiler drops the copy.
    let _ = queue.dequeue();
    Some(result)
}
