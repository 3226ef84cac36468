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
    /// The workstation's UTC time when it started the run (ISO 8601, seconds); what `device show` reports as
    /// when the record was made.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub run_started_utc: Option<String>,
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
            run_started_utc: Some(utc_iso8601(std::time::SystemTime::now())),
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

/// `time` as ISO 8601 UTC to the second (`2026-11-28T03:04:05Z`); the epoch for a time before it.
pub fn utc_iso8601(time: std::time::SystemTime) -> String {
    let seconds = time.duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, of_day) = (seconds / 86_400, seconds % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    format!("{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z", of_day / 3600, of_day / 60 % 60, of_day % 60)
}

/// The proleptic Gregorian date of `days` since 1970-01-01 (the era-based conversion of H. Hinnant's
/// "chrono-compatible low-level date algorithms").
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let day_of_era = z.rem_euclid(146_097);
    let year_of_era = (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let mp = (5 * day_of_year + 2) / 153;
    let day = (day_of_year - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, UNIX_EPOCH};

    #[test]
    fn utc_times_of_known_instants() {
        assert_eq!(utc_iso8601(UNIX_EPOCH), "1970-01-01T00:00:00Z");
        // 2000-02-29 (a leap day of a century divisible by 400) 12:34:56 UTC.
        assert_eq!(utc_iso8601(UNIX_EPOCH + Duration::from_secs(951_827_696)), "2000-02-29T12:34:56Z");
        // 2026-11-28 00:00:00 UTC, and the last second of 2100-02-28 (2100 is not a leap year).
        assert_eq!(utc_iso8601(UNIX_EPOCH + Duration::from_secs(1_795_824_000)), "2026-11-28T00:00:00Z");
        assert_eq!(utc_iso8601(UNIX_EPOCH + Duration::from_secs(4_107_542_399)), "2100-02-28T23:59:59Z");
    }
}
