//! `sinscal study RECORDING`: the study of any sinscal recording (docs/formats.md#recording), not only the three
//! built-in data sets. Everything the study needs comes from the recording itself:
//! - one static pose (one non-zero `pos`): the single-pose noise study of that pose's rows ([`study_single_pose`]);
//!   at least 6: the pose study ([`study_multi_pose`]); 0 or 2 to 5 are refused with the reason;
//! - the poses' orientations are labelled ([`PoseKind::Labelled`], up = the dwell's pitch and roll) unless the
//!   header says they were levelled from the recording's own accelerometers (`# attitude_source:
//!   accelerometer-levelled`: [`PoseKind::Unlabelled`], only |f| = g is known);
//! - gravity: the header's `gravity_mps2`, else normal gravity at the header's latitude and height;
//! - the sample rate: the header's `rate_hz`, else 1 / the median time step;
//! - the labelled turns: the rows of the `turn` column (docs/formats.md#turns);
//! - an accelerometer-only recording is refused (`no gyro columns: study needs gyros`): the study's noise,
//!   sway and pose parts are built on six channels.

use std::path::Path;

use super::multi_pose::{study_multi_pose, PoseKind};
use super::psins::study_single_pose;
use super::{Dataset, LabelledTurn, Study, MIN_SINGLE_POSE_SAMPLES, STUDY_SEED};
use crate::calibration::attitude_knowledge;
use crate::io::error::InputError;
use crate::io::import::FERRARIS_ROTATIONS;
use crate::io::recording::{Recording, RowSource, TimeSteps};
use sinscal::calib::general::AttitudeKnowledge;

/// What `sinscal study` was asked to study.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// One of the built-in data sets, read from the data directory.
    Dataset(Dataset),
    /// A sinscal recording file.
    Recording(std::path::PathBuf),
}

/// The target named by the command line's argument: an existing file is a recording (even when its name is a
/// data set's); otherwise `psins`, `ferraris` or `imutk` is that data set; anything else is refused.
pub fn target_of(arg: &str) -> Result<Target, InputError> {
    let path = Path::new(arg);
    if path.is_file() {
        return Ok(Target::Recording(path.to_path_buf()));
    }
    if let Some(d) = [Dataset::Psins, Dataset::Ferraris, Dataset::Imutk].into_iter().find(|d| d.name() == arg) {
        return Ok(Target::Dataset(d));
    }
    let why = if path.exists() { "not a file" } else { "no such file" };
    Err(InputError::file(arg, format!("{why}, and not a data set (psins, ferraris, imutk): nothing to study")))
}

/// Gravity of a recording, m/s^2: the header's `gravity_mps2`, else normal gravity at its latitude and height.
pub fn gravity_of(rec: &Recording) -> f64 {
    rec.header.gravity_mps2.unwrap_or_else(|| {
        sinscal::nav::earth::normal_gravity_mps2(
            (rec.header.latitude_deg as f32).to_radians(),
            rec.header.height_m as f32,
        ) as f64
    })
}

/// The labelled turns of a recording's `turn` column as (label `x_rot`/`y_rot`/`z_rot`, body axis, row range):
/// each run of consecutive rows with the same axis, plus one row past its end (so that the last turn row's
/// interval is integrated, as for the built-in Ferraris study).
pub fn recording_turns(rec: &Recording) -> Vec<LabelledTurn> {
    let mut turns: Vec<LabelledTurn> = Vec::new();
    let mut k = 0;
    while k < rec.rows.len() {
        let Some(axis) = rec.rows[k].turn_axis else {
            k += 1;
            continue;
        };
        let start = k;
        while k < rec.rows.len() && rec.rows[k].turn_axis == Some(axis) {
            k += 1;
        }
        let label = FERRARIS_ROTATIONS.get(axis).map_or(format!("turn {axis}"), |s| s.to_string());
        turns.push((label, axis, start..(k + 1).min(rec.rows.len())));
    }
    turns
}

/// Reads the recording at `path` and studies it (no files written). The study's name is the file's name.
pub fn study_recording(path: &Path) -> Result<Study, InputError> {
    study_of(read_recording(path)?, path)
}

/// Reads the recording at `path` for a study: it needs gyros; a rate the header does not give is 1 / the median
/// time step.
pub fn read_recording(path: &Path) -> Result<Recording, InputError> {
    eprintln!("study: reading the recording {}", path.display());
    let mut rec = Recording::read(path)?;
    rec.require_gyro("study")?;
    if rec.header.rate_hz.is_none() {
        rec.header.rate_hz = TimeSteps::of(rec.rows.iter().map(|r| r.t_s)).median_s().map(|dt| 1.0 / dt);
    }
    Ok(rec)
}

/// The study of `rec`, read from `path` ([`read_recording`]).
pub fn study_of(mut rec: Recording, path: &Path) -> Result<Study, InputError> {
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let sources = vec![path.display().to_string()];
    let poses = rec.dwells().len();
    match poses {
        1 => {
            rec.rows.retain(|r| r.pos != 0);
            if rec.rows.len() < MIN_SINGLE_POSE_SAMPLES {
                return Err(InputError::file(
                    &rec.source,
                    format!(
                        "one static pose of {} samples: the noise study needs at least {MIN_SINGLE_POSE_SAMPLES}",
                        rec.rows.len()
                    ),
                ));
            }
            eprintln!("study {name}: one static pose, {} samples: the noise study", rec.rows.len());
            Ok(study_single_pose(&rec, &name, sources, STUDY_SEED))
        }
        n if n >= 6 => {
            let kind = match attitude_knowledge(&rec.header) {
                AttitudeKnowledge::Reference => PoseKind::Labelled,
                AttitudeKnowledge::Unknown => PoseKind::Unlabelled,
            };
            let g = gravity_of(&rec);
            let turns = recording_turns(&rec);
            eprintln!("study {name}: {n} static poses ({kind:?}), g {g:.5} m/s^2, {} labelled turns", turns.len());
            study_multi_pose(&rec, kind, g, &name, sources, STUDY_SEED, &turns)
        }
        n => Err(InputError::file(
            &rec.source,
            format!(
                "{n} static poses (non-zero pos): a study needs one pose (the noise study) or at least 6 (the pose \
                 study)"
            ),
        )),
    }
}
