//! The instrument: what makes the calibration firmware a device that a workstation configures and reads over a
//! serial link, that keeps its calibration across power loss, and that compensates its output.
//!
//! - [`crc`]: the CRC-32 of link frames and stored records.
//! - [`store`]: the power-safe A/B store of the calibration record in NOR flash (docs/storage.md).

pub mod crc;
pub mod store;
