//! `calibrate --on qemu`: the replay file through the firmware in QEMU (mps2-an386, Cortex-M4F).

use crate::calibrate::{Calibration, Options};
use crate::error::InputError;
use crate::recording::Recording;

/// Runs the firmware's replay in QEMU.
pub fn calibrate_on_qemu(rec: &Recording, _options: &Options) -> Result<Calibration, InputError> {
    Err(InputError::file(&rec.source, "--on qemu: the QEMU firmware is not built yet"))
}
