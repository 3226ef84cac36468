//! The instrument: what makes the calibration firmware a device that a workstation configures and reads over a
//! serial link, that keeps its calibration across power loss, and that compensates its output.
//!
//! - [`crc`]: the CRC-32 of link frames and stored records.
//! - [`link`]: frames on the serial line (COBS, CRC, bounded).
//! - [`message`]: the messages in those frames (kinds, error codes, body fields).
//! - [`store`]: the power-safe A/B store of the calibration record in NOR flash (docs/storage.md).
//! - [`wire`]: the wire formats, each defined once with its encode and decode: the configuration, the
//!   outcome, the calibration record (compensation, configuration, note, outcome), and every code as an enum.
//! - [`device`]: the device behind the link (requests, the calibration, the record, compensation).
//! - `main_loop` (target only): the instrument's main loop and its link port, the same on every board.

pub mod crc;
pub mod device;
pub mod link;
#[cfg(target_os = "none")]
pub mod main_loop;
pub mod message;
pub mod store;
pub mod wire;
