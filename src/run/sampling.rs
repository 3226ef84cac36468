//! The data-ready side of sampling: read the sensor and push into a bounded queue, nothing else.
//!
//! [`on_data_ready`] runs in the data-ready interrupt (100 Hz). It never blocks and never drops anything
//! silently: a full queue, a read fault of each kind, and samples the sensor produced but nobody read
//! (data counter gaps) are counted in [`SamplingStats`]. Faults travel through the queue too, in order,
//! so the processing side knows which dwell they hit.

use heapless::spsc::{Consumer, Producer};

use crate::sensor::sample::ImuReading;
use crate::sensor::source::{ClassifiedError, ImuSource, ReadFault};

/// What travels from the interrupt to the processing loop: a reading or the fault that replaced it.
pub type QueueItem = Result<ImuReading, ReadFault>;

/// Queue length (heapless 0.9: a `Queue<T, N>` holds N - 1 items): 15 samples = 150 ms of slack for the
/// processing loop.
pub const QUEUE_SLOTS: usize = 16;

/// Counters of the sampling side.
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
    /// Samples missed according to the sensor's counter.
    pub missed_samples: u32,
}

impl SamplingStats {
    /// Faults of every kind.
    pub fn faults(&self) -> u32 {
        self.bus_errors + self.checksum_errors + self.stalled_counters + self.status_flags
    }
}

/// Handles one data-ready event: one read, one enqueue attempt, counters updated.
#[inline]
pub fn on_data_ready<S: ImuSource>(imu: &mut S, queue: &mut Producer<'_, QueueItem>, stats: &mut SamplingStats) {
    stats.events = stats.events.wrapping_add(1);
    let item = match imu.read() {
        Ok(reading) => {
            stats.readings += 1;
            stats.missed_samples += reading.missed as u32;
            Ok(reading)
        }
        Err(e) => {
            let fault = e.fault();
            match fault {
                ReadFault::Bus => stats.bus_errors += 1,
                ReadFault::Checksum => stats.checksum_errors += 1,
                ReadFault::StalledCounter => stats.stalled_counters += 1,
                ReadFault::StatusFlag => stats.status_flags += 1,
            }
            Err(fault)
        }
    };
    if queue.enqueue(item).is_err() {
        stats.queue_full += 1;
    }
}

/// Hands the oldest queued item to `f` by reference, then removes it: the item is read in place, never
/// copied out of the queue (a copy of the 36-byte item costs more instructions than its checks). Returns
/// `f`'s result, or `None` when the queue is empty.
#[inline]
pub fn process_next<R>(queue: &mut Consumer<'_, QueueItem>, f: impl FnOnce(&QueueItem) -> R) -> Option<R> {
    let result = f(queue.peek()?);
    // The value just processed; nothing reads it, so the compiler drops the copy.
    let _ = queue.dequeue();
    Some(result)
}
