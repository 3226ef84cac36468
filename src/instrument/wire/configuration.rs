//! The calibration's configuration: what the workstation asks of a calibration (the IMU, the estimator and its
//! terms, the site, the schedule with each position's label, the prefilter, the dwell value, the limits of rest)
//! and, on the device, the thresholds of its dwells. The replay file's header carries a [`Configuration`]; the
//! configure message and the record carry a [`DeviceConfiguration`]. Layout in the parent module.

use heapless::Vec;

use super::codes::{DwellValueCode, EstimatorCode, ImuCode, PrefilterCode};
use super::{Reader, WireError, Writer};
use crate::calib::align::DwellValue;
use crate::calib::angles::CalibrationSettings;
use crate::calib::angles::MAX_POSITIONS;
use crate::calib::dwell::{Prefilter, MIN_DWELL_SAMPLES};
use crate::calib::general::{ChannelSettings, Model as Terms};
use crate::calib::noise_model::{ChannelNoiseTerms, NoiseModel, TERM_VALUES};
use crate::calib::prefilter::PrefilterSettings;
use crate::nav::earth::Site;
use crate::nav::frames::Attitude;
pub use crate::run::sequence::RestLimits;
use crate::run::sequence::{Estimator, SequenceSettings};
use crate::sensor::adis::Model;

/// Bytes of a configuration's fixed part (IMU, estimator, site, positions, terms: 14; run settings: 12; rest
/// limits: 12; pose tolerance: 4; noise model: 4 + 6 x 9 x 4).
pub const FIXED_BYTES: usize = 14 + 12 + 12 + 4 + NOISE_BYTES;
/// Bytes of the noise model: the sample interval (0: no model) and each channel's terms.
pub const NOISE_BYTES: usize = 4 + 6 * TERM_VALUES * 4;
/// Bytes of each position of the schedule.
pub const POSITION_BYTES: usize = 16;
/// Bytes of the thresholds at the end of a device configuration.
pub const THRESHOLD_BYTES: usize = 12;
/// Longest configuration, bytes.
pub const MAX_BYTES: usize = FIXED_BYTES + POSITION_BYTES * MAX_POSITIONS;
/// Longest device configuration, bytes.
pub const MAX_DEVICE_BYTES: usize = MAX_BYTES + THRESHOLD_BYTES;

const _: () = assert!(MAX_POSITIONS <= 64, "unknown_headings holds one bit per position");
const _: () = assert!(
    MAX_DEVICE_BYTES <= crate::instrument::link::MAX_BODY_BYTES,
    "the configure message carries the longest device configuration"
);

/// The thresholds of a device's dwells, in samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Thresholds {
    /// Samples ignored after the table reports in position.
    pub settle_samples: u32,
    /// Samples of a full dwell.
    pub dwell_samples: u32,
    /// Fewest samples of a usable dwell.
    pub min_dwell_samples: u32,
}

impl Thresholds {
    /// A replayed sequence's: no settling (the recording's dwells are already the static parts), dwells as long
    /// as the table says, at least [`MIN_DWELL_SAMPLES`] samples.
    pub const REPLAY: Thresholds =
        Thresholds { settle_samples: 0, dwell_samples: u32::MAX, min_dwell_samples: MIN_DWELL_SAMPLES };

    /// A calibration on a real turntable: the sequence's defaults (2 s of settling, 60 s dwells, at least 10 s,
    /// at 100 Hz).
    pub fn table() -> Thresholds {
        let s = SequenceSettings::default();
        Thresholds {
            settle_samples: s.settle_samples,
            dwell_samples: s.dwell_samples,
            min_dwell_samples: s.min_dwell_samples,
        }
    }
}

/// What the workstation asks of a calibration.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    /// The IMU whose frames the calibration reads.
    pub imu: Model,
    /// The estimator.
    pub estimator: EstimatorCode,
    /// The general estimator's terms (carried with every estimator; the angle method ignores them).
    pub terms: Terms,
    /// The site.
    pub site: Site,
    /// The schedule: the turntable's attitudes (an unknown heading is carried as 0).
    pub schedule: Vec<Attitude, MAX_POSITIONS>,
    /// Each position's label in the recording, in schedule order.
    pub labels: Vec<u16, MAX_POSITIONS>,
    /// Bit k: the heading of position k is unknown.
    pub unknown_headings: u64,
    /// The prefilter of the dwell collector.
    pub prefilter: Prefilter,
    /// The dwell value the solution uses.
    pub dwell_value: DwellValue,
    /// Passes of the angle method at most.
    pub max_passes: u8,
    /// Whether the angle method estimates the reference offset.
    pub estimate_reference_offset: bool,
    /// The limits of rest of the sequence's checks.
    pub rest: RestLimits,
    /// How well the schedule's attitudes are known, rad (one standard deviation, each axis; 0: exact): the
    /// general estimator's [`ChannelSettings::pose_tolerance_rad`].
    pub pose_tolerance_rad: f32,
    /// The channels' noise model (docs/method.md#noise-model); `None`: the session's own dwell noise.
    pub noise: Option<NoiseModel>,
}

/// Largest pose tolerance a configuration carries, rad (10 deg).
pub const MAX_POSE_TOLERANCE_RAD: f32 = 0.174_532_93;

impl Configuration {
    /// The configuration of the sequence's defaults (the general estimator with its default terms, the paper's
    /// prefilter, the dwell means, the angle method's passes and reference offset, the limits of rest) for an
    /// IMU at a site, with no position yet: a caller sets what it asks for and takes the rest from here
    /// (`Configuration { schedule, ..Configuration::new(imu, site) }`).
    pub fn new(imu: Model, site: Site) -> Configuration {
        let s = SequenceSettings::default();
        let (estimator, terms) = match s.estimator {
            Estimator::Angles => (EstimatorCode::Angles, Terms::BIASES),
            Estimator::Channels(c) if c.use_gyro => (EstimatorCode::General, c.model),
            Estimator::Channels(c) => (EstimatorCode::GeneralWithoutGyros, c.model),
        };
        Configuration {
            imu,
            estimator,
            terms,
            site,
            schedule: Vec::new(),
            labels: Vec::new(),
            unknown_headings: 0,
            prefilter: s.prefilter,
            dwell_value: s.calibration.dwell_value,
            max_passes: s.calibration.max_passes.min(255) as u8,
            estimate_reference_offset: s.calibration.solver.estimate_reference_offset,
            rest: RestLimits::default(),
            pose_tolerance_rad: 0.0,
            noise: None,
        }
    }

    /// The sequence's estimator of the configuration.
    pub fn sequence_estimator(&self) -> Estimator {
        let general = |use_gyro| {
            Estimator::Channels(ChannelSettings {
                model: self.terms,
                use_gyro,
                pose_tolerance_rad: self.pose_tolerance_rad,
                noise: self.noise,
                ..Default::default()
            })
        };
        match self.estimator {
            EstimatorCode::Angles => Estimator::Angles,
            EstimatorCode::General => general(true),
            EstimatorCode::GeneralWithoutGyros => general(false),
        }
    }

    /// The settings of a sequence that runs the configuration with these thresholds.
    pub fn sequence_settings(&self, thresholds: Thresholds) -> SequenceSettings {
        let mut calibration = CalibrationSettings {
            dwell_value: self.dwell_value,
            max_passes: u32::from(self.max_passes),
            ..CalibrationSettings::default()
        };
        calibration.solver.estimate_reference_offset = self.estimate_reference_offset;
        SequenceSettings {
            settle_samples: thresholds.settle_samples,
            dwell_samples: thresholds.dwell_samples,
            min_dwell_samples: thresholds.min_dwell_samples,
            rest: self.rest,
            prefilter: self.prefilter,
            estimator: self.sequence_estimator(),
            calibration,
            unknown_headings: self.unknown_headings,
            ..SequenceSettings::default()
        }
    }

    /// The positions encoded: those with both an attitude and a label (the two lists are meant to be as long).
    pub fn positions(&self) -> usize {
        self.schedule.len().min(self.labels.len())
    }

    /// The encoding's length, bytes.
    pub fn encoded_bytes(&self) -> usize {
        FIXED_BYTES + POSITION_BYTES * self.positions()
    }

    /// Writes the encoding.
    pub fn encode(&self, w: &mut Writer<'_>) {
        let (prefilter, [a_gyro, a_accel]) = match self.prefilter {
            Prefilter::None => (PrefilterCode::None, [1.0, 1.0]),
            Prefilter::HmmKf { gyro, accel } => (PrefilterCode::HmmKf, [gyro.a, accel.a]),
        };
        w.u8(ImuCode::of(self.imu).code()).u8(self.estimator.code());
        w.f32(self.site.latitude_rad).f32(self.site.gravity_mps2);
        w.u16(self.positions() as u16).u16(self.terms.stored_bits());
        w.u8(prefilter.code()).u8(DwellValueCode::of(self.dwell_value).code());
        w.u8(self.max_passes).u8(self.estimate_reference_offset as u8).f32(a_gyro).f32(a_accel);
        w.f32(self.rest.force_error_max_mps2).f32(self.rest.gravity_angle_max_rad).f32(self.rest.rate_max_radps);
        w.f32(self.pose_tolerance_rad);
        let noise = self.noise.unwrap_or_default();
        w.f32(noise.sample_interval_s);
        for c in &noise.channels {
            for v in c.to_array() {
                w.f32(v);
            }
        }
        for (k, (a, label)) in self.schedule.iter().zip(&self.labels).enumerate() {
            let heading_unknown = self.unknown_headings >> k & 1 != 0;
            w.f32(a.pitch_rad).f32(a.roll_rad).f32(a.heading_rad).u16(*label).u16(heading_unknown as u16);
        }
    }

    /// The number of positions a configuration's fixed part announces (its first [`FIXED_BYTES`] bytes), to
    /// read the rest of it from a stream; `None` for too few bytes or a count the core does not hold.
    pub fn positions_announced(fixed: &[u8]) -> Option<usize> {
        let count = Reader::new(fixed.get(10..12)?).u16()? as usize;
        (1..=MAX_POSITIONS).contains(&count).then_some(count)
    }

    /// Reads a configuration.
    pub fn decode(r: &mut Reader<'_>) -> Result<Configuration, WireError> {
        Self::decode_fields(r).ok_or(WireError)?
    }

    fn decode_fields(r: &mut Reader<'_>) -> Option<Result<Configuration, WireError>> {
        let imu = ImuCode::from_code(r.u8()?);
        let estimator = EstimatorCode::from_code(r.u8()?);
        let site = Site { latitude_rad: r.f32()?, gravity_mps2: r.f32()? };
        let count = r.u16()? as usize;
        let terms = Terms::from_stored_bits(r.u16()?);
        let prefilter = PrefilterCode::from_code(r.u8()?);
        let dwell_value = DwellValueCode::from_code(r.u8()?);
        let (max_passes, estimate_reference_offset) = (r.u8()?, r.u8()? != 0);
        let (a_gyro, a_accel) = (r.f32()?, r.f32()?);
        let rest =
            RestLimits { force_error_max_mps2: r.f32()?, gravity_angle_max_rad: r.f32()?, rate_max_radps: r.f32()? };
        let pose_tolerance_rad = r.f32()?;
        let noise = Self::decode_noise(r)?;
        let (Some(imu), Some(estimator), Some(terms), Some(prefilter), Some(dwell_value)) =
            (imu, estimator, terms, prefilter, dwell_value)
        else {
            return Some(Err(WireError));
        };
        let positive = |x: f32| x.is_finite() && x > 0.0;
        let limits_ok = positive(rest.force_error_max_mps2) && positive(rest.gravity_angle_max_rad);
        let tolerance_ok = (0.0..=MAX_POSE_TOLERANCE_RAD).contains(&pose_tolerance_rad);
        let gyros = estimator != EstimatorCode::GeneralWithoutGyros;
        let noise_ok = noise.is_none_or(|m| m.is_valid(gyros));
        let settings_ok = limits_ok && positive(rest.rate_max_radps) && tolerance_ok && noise_ok;
        if count == 0 || count > MAX_POSITIONS || !settings_ok {
            return Some(Err(WireError));
        }
        let (mut schedule, mut labels, mut unknown_headings) = (Vec::new(), Vec::new(), 0u64);
        for k in 0..count {
            let attitude = Attitude { pitch_rad: r.f32()?, roll_rad: r.f32()?, heading_rad: r.f32()? };
            // count <= MAX_POSITIONS: both pushes fit.
            let _ = schedule.push(attitude);
            let _ = labels.push(r.u16()?);
            if r.u16()? & 1 != 0 {
                unknown_headings |= 1u64 << k;
            }
        }
        let prefilter = match prefilter {
            PrefilterCode::None => Prefilter::None,
            PrefilterCode::HmmKf => Prefilter::HmmKf {
                gyro: PrefilterSettings::paper_gyro().with_a(a_gyro),
                accel: PrefilterSettings::paper_accel().with_a(a_accel),
            },
        };
        Some(Ok(Configuration {
            imu: imu.model(),
            estimator,
            terms,
            site,
            schedule,
            labels,
            unknown_headings,
            prefilter,
            dwell_value: dwell_value.value(),
            max_passes,
            estimate_reference_offset,
            rest,
            pose_tolerance_rad,
            noise,
        }))
    }

    /// The noise model's bytes: `None` inside when the sample interval is 0 (no model).
    fn decode_noise(r: &mut Reader<'_>) -> Option<Option<NoiseModel>> {
        let sample_interval_s = r.f32()?;
        let mut channels = [ChannelNoiseTerms::default(); 6];
        for c in &mut channels {
            let mut v = [0.0f32; TERM_VALUES];
            for x in &mut v {
                *x = r.f32()?;
            }
            *c = ChannelNoiseTerms::from_array(v);
        }
        Some((sample_interval_s != 0.0).then_some(NoiseModel { sample_interval_s, channels }))
    }
}

/// The configure message's body and the record's configuration: a configuration and the device's thresholds.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceConfiguration {
    /// What the calibration is.
    pub configuration: Configuration,
    /// The thresholds of its dwells.
    pub thresholds: Thresholds,
}

impl DeviceConfiguration {
    /// The sequence settings it asks for.
    pub fn sequence_settings(&self) -> SequenceSettings {
        self.configuration.sequence_settings(self.thresholds)
    }

    /// Writes the encoding.
    pub fn encode(&self, w: &mut Writer<'_>) {
        self.configuration.encode(w);
        let t = &self.thresholds;
        w.u32(t.settle_samples).u32(t.dwell_samples).u32(t.min_dwell_samples);
    }

    /// Reads a device configuration that fills `bytes` exactly.
    pub fn decode(bytes: &[u8]) -> Result<DeviceConfiguration, WireError> {
        let mut r = Reader::new(bytes);
        let configuration = Configuration::decode(&mut r)?;
        let thresholds = Thresholds {
            settle_samples: r.u32().ok_or(WireError)?,
            dwell_samples: r.u32().ok_or(WireError)?,
            min_dwell_samples: r.u32().ok_or(WireError)?,
        };
        if !r.is_empty() {
            return Err(WireError);
        }
        Ok(DeviceConfiguration { configuration, thresholds })
    }
}
