//! The provenance note the workstation sends with a calibration and the device keeps in its record: what the
//! workstation knows of the recording (its name, site, labels, lines, reference attitudes as written in the
//! file) and the calibration options, so that `device show` reports a stored record exactly as `device run`
//! reported it. JSON text; every number written to read back to the same bits.

use serde::{Deserialize, Serialize};
use sinscal::calib::align::DwellValue;

use crate::calibration::firmware_path::ReplayPlan;
use crate::calibration::{Coefficient, Method, Options, PrefilterKind};
use crate::io::recording::RowSource;

/// The provenance note.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// Note format.
    pub schema: String,
    /// The recording's name.
    pub source: String,
    /// Its latitude, degrees north.
    pub latitude_deg: f64,
    /// Its height, m.
    pub height_m: f64,
    /// Its gravity, m/s^2, if the header gives one.
    pub gravity_mps2: Option<f64>,
    /// Whether it has gyro columns.
    pub has_gyro: bool,
    /// The calibration options.
    pub options: OptionsNote,
    /// The dwells: labels, first lines, reference attitudes.
    pub plan: ReplayPlan,
}

/// The calibration options in the note.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptionsNote {
    /// "hmmkf" or "none".
    pub prefilter: String,
    /// The prefilter coefficient; `None` = identified from the first dwell.
    pub prefilter_a: Option<f32>,
    /// "mean" or "settled".
    pub dwell_value: String,
    /// Whether the reference offset is estimated.
    pub estimate_reference_offset: bool,
    /// Passes at most.
    pub max_passes: u32,
    /// "channels" or "angles".
    pub method: String,
    /// The general estimator's terms (bit i = the i-th term of the catalogue).
    pub terms: u16,
    /// Whether the attitudes are estimated.
    pub estimate_attitudes: bool,
    /// The firmware path's tolerance of rest, m/s^2.
    pub rest_force_tolerance_mps2: f32,
    /// The pose tolerance asked for, degrees (`None`: the recording's header or the default).
    #[serde(default)]
    pub pose_tolerance_deg: Option<f64>,
    /// Whether the noise model (carried in the device's configuration) was named from the recording itself.
    #[serde(default)]
    pub noise_from_recording: bool,
}

/// Note format written.
const SCHEMA: &str = "sinscal-device-note/1";

impl Provenance {
    /// The note of a calibration of `rec` with `options` over the dwells of `plan`.
    pub fn of(rec: &impl RowSource, options: &Options, plan: &ReplayPlan) -> Provenance {
        let h = rec.header();
        Provenance {
            schema: SCHEMA.into(),
            source: rec.source().to_string(),
            latitude_deg: h.latitude_deg,
            height_m: h.height_m,
            gravity_mps2: h.gravity_mps2,
            has_gyro: rec.has_gyro(),
            options: OptionsNote {
                prefilter: match options.prefilter {
                    PrefilterKind::HmmKf => "hmmkf",
                    PrefilterKind::None => "none",
                }
                .into(),
                prefilter_a: match options.coefficient {
                    Coefficient::Fixed(a) => Some(a),
                    Coefficient::Identify => None,
                },
                dwell_value: match options.dwell_value {
                    DwellValue::Mean => "mean",
                    DwellValue::Settled => "settled",
                }
                .into(),
                estimate_reference_offset: options.estimate_reference_offset,
                max_passes: options.max_passes,
                method: match options.method {
                    Method::Channels => "channels",
                    Method::Angles => "angles",
                }
                .into(),
                terms: options.model.stored_bits(),
                estimate_attitudes: options.estimate_attitudes,
                rest_force_tolerance_mps2: options.rest_force_tolerance_mps2,
                pose_tolerance_deg: options.pose_tolerance_deg,
                noise_from_recording: options.noise.is_some_and(|t| t.from_recording),
            },
            plan: plan.clone(),
        }
    }

    /// The note's bytes (compact JSON).
    pub fn to_bytes(&self) -> Vec<u8> {
        serde_json::to_vec(self).unwrap_or_default()
    }

    /// The note of its bytes.
    pub fn from_bytes(bytes: &[u8]) -> anyhow::Result<Provenance> {
        let note: Provenance =
            serde_json::from_slice(bytes).map_err(|e| anyhow::anyhow!("the record's provenance note: {e}"))?;
        if note.schema != SCHEMA {
            anyhow::bail!("the record's provenance note is '{}', this sinscal reads '{SCHEMA}'", note.schema);
        }
        Ok(note)
    }

    /// The calibration options of the note.
    pub fn options(&self) -> anyhow::Result<Options> {
        let o = &self.options;
        let bad = |what: &str, v: &str| anyhow::anyhow!("the record's provenance note: {what} '{v}'");
        Ok(Options {
            // The noise model travels in the device's configuration, not in the note: `device show` puts it back.
            noise: None,
            // The device's fit uses every move (the firmware path has no held-out moves).
            hold_out_moves: 0,
            prefilter: match o.prefilter.as_str() {
                "hmmkf" => PrefilterKind::HmmKf,
                "none" => PrefilterKind::None,
                v => return Err(bad("prefilter", v)),
            },
            coefficient: o.prefilter_a.map_or(Coefficient::Identify, Coefficient::Fixed),
            dwell_value: match o.dwell_value.as_str() {
                "mean" => DwellValue::Mean,
                "settled" => DwellValue::Settled,
                v => return Err(bad("dwell value", v)),
            },
            estimate_reference_offset: o.estimate_reference_offset,
            max_passes: o.max_passes,
            method: match o.method.as_str() {
                "channels" => Method::Channels,
                "angles" => Method::Angles,
                v => return Err(bad("method", v)),
            },
            model: sinscal::calib::general::Model::from_stored_bits(o.terms).ok_or_else(|| {
                anyhow::anyhow!("provenance note: terms {:#06x} name a term this version does not know", o.terms)
            })?,
            estimate_attitudes: o.estimate_attitudes,
            rest_force_tolerance_mps2: o.rest_force_tolerance_mps2,
            // The device's sequence does not integrate the moves.
            use_moves: false,
            pose_tolerance_deg: o.pose_tolerance_deg,
        })
    }
}
