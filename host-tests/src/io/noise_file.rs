//! The noise file (`sinscal noise`, schema `sinscal-noise/1`, docs/formats.md#noise-file) read back as the
//! core's noise terms: what `calibrate --noise` weights the dwells by (docs/method.md#noise-model).

use std::io::Read as _;
use std::path::Path;

use serde_json::Value;
use sinscal::calib::noise_model::{ChannelNoiseTerms, NoiseModel};

use crate::io::error::InputError;

/// Largest noise file read, bytes: a file of six channels is a few tens of kilobytes; anything far larger is
/// not a noise file (and is not read whole).
pub const MAX_NOISE_FILE_BYTES: u64 = 1 << 20;

/// The channels' names in a noise file, in the core's order (gyro x, y, z, accelerometer x, y, z).
const CHANNELS: [&str; 6] = ["gx_radps", "gy_radps", "gz_radps", "ax_mps2", "ay_mps2", "az_mps2"];

/// A noise file: where it came from and its terms.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseFile {
    /// The file, for messages and the JSON.
    pub source: String,
    /// The terms.
    pub terms: NoiseTerms,
}

/// Each channel's noise terms (`None`: the file does not name that channel, as a file made from a recording
/// without gyros).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseTerms {
    /// Per channel (gyro x, y, z, accelerometer x, y, z).
    pub channels: [Option<ChannelNoiseTerms>; 6],
    /// Named from the calibration recording itself (`calibrate --noise recording`), not read from a file.
    pub from_recording: bool,
}

impl NoiseFile {
    /// Reads and checks a noise file.
    pub fn read(path: &Path) -> Result<NoiseFile, InputError> {
        let source = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|e| InputError::io(path, e))?;
        let mut text = String::new();
        file.take(MAX_NOISE_FILE_BYTES + 1).read_to_string(&mut text).map_err(|e| InputError::io(path, e))?;
        if text.len() as u64 > MAX_NOISE_FILE_BYTES {
            return Err(InputError::file(
                &source,
                format!("larger than {MAX_NOISE_FILE_BYTES} bytes: not a noise file (sinscal noise writes one)"),
            ));
        }
        Self::parse(&text, &source)
    }

    /// Parses the text of a noise file.
    pub fn parse(text: &str, source: &str) -> Result<NoiseFile, InputError> {
        let bad = |what: String| InputError::file(source, what);
        let v: Value = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
        if v.get("schema").and_then(Value::as_str) != Some("sinscal-noise/1") {
            return Err(bad("not a noise file: schema is not \"sinscal-noise/1\" (sinscal noise writes one)".into()));
        }
        let list = v.get("channels").and_then(Value::as_array).ok_or_else(|| bad("no \"channels\" list".into()))?;
        let mut channels = [None; 6];
        for c in list {
            let name = c.get("channel").and_then(Value::as_str).unwrap_or("");
            let i = CHANNELS
                .iter()
                .position(|n| *n == name)
                .ok_or_else(|| bad(format!("unknown channel \"{name}\" (expected one of {})", CHANNELS.join(", "))))?;
            if channels[i].is_some() {
                return Err(bad(format!("channel {name} given twice")));
            }
            channels[i] = Some(channel_terms(c, name).map_err(|e| bad(format!("channel {name}: {e}")))?);
        }
        if channels[3..].iter().any(Option::is_none) {
            return Err(bad("the three accelerometer channels are needed".into()));
        }
        Ok(NoiseFile { source: source.to_string(), terms: NoiseTerms { channels, from_recording: false } })
    }
}

impl NoiseTerms {
    /// The core's noise model for a calibration at `sample_interval_s`, `gyros`: whether it uses gyro data
    /// (the terms must then name them). The error says what is missing.
    pub fn model(&self, sample_interval_s: f64, gyros: bool) -> Result<NoiseModel, String> {
        if gyros && self.channels[..3].iter().any(Option::is_none) {
            return Err("the noise file has no gyro channels and the recording has gyros (make the file from a \
                        static run of this IMU with its gyros)"
                .into());
        }
        let channels = self.channels.map(Option::unwrap_or_default);
        let model = NoiseModel { sample_interval_s: sample_interval_s as f32, channels };
        if !model.is_valid(gyros) {
            return Err(format!("no usable noise model at a sample interval of {sample_interval_s} s"));
        }
        Ok(model)
    }
}

/// One channel's terms from its `terms` list (`term`, `value_si`, and `tau_c_s` for the Gauss-Markov term and
/// sway).
fn channel_terms(c: &Value, name: &str) -> Result<ChannelNoiseTerms, String> {
    let terms = c.get("terms").and_then(Value::as_array).ok_or("no \"terms\" list")?;
    let mut t = ChannelNoiseTerms::default();
    let mut seen = Vec::new();
    for term in terms {
        let kind = term.get("term").and_then(Value::as_str).unwrap_or("");
        let value = term.get("value_si").and_then(Value::as_f64).ok_or(format!("term {kind}: no value_si"))?;
        if !(value.is_finite() && value >= 0.0) {
            return Err(format!("term {kind}: value_si {value} is not a non-negative number"));
        }
        if seen.contains(&kind) {
            return Err(format!("term {kind} given twice"));
        }
        seen.push(kind);
        let value = value as f32;
        match kind {
            "quantization" => t.quantisation_u_s = value,
            "white" => t.white_u_sqrt_s = value,
            "bias_instability" => t.instability_u = value,
            "rate_random_walk" => t.random_walk_u_per_sqrt_s = value,
            "rate_ramp" => t.ramp_u_per_s = value,
            "gauss_markov" | "sway" => {
                let tau = term.get("tau_c_s").and_then(Value::as_f64).unwrap_or(0.0);
                if !(tau.is_finite() && tau > 0.0) {
                    return Err(format!("term {kind}: tau_c_s {tau} is not a positive number of seconds"));
                }
                if kind == "sway" {
                    (t.sway_u_s, t.sway_time_s) = (value, tau as f32);
                } else {
                    (t.gauss_markov_u, t.gauss_markov_time_s) = (value, tau as f32);
                }
            }
            other => return Err(format!("unknown term \"{other}\"")),
        }
    }
    if !t.is_valid() {
        return Err(format!("no term makes {name}'s noise positive"));
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(channels: &str) -> String {
        format!(r#"{{"schema": "sinscal-noise/1", "channels": [{channels}]}}"#)
    }

    fn accel() -> String {
        ["ax_mps2", "ay_mps2", "az_mps2"]
            .map(|n| format!(r#"{{"channel": "{n}", "terms": [{{"term": "white", "value_si": 1e-4}}]}}"#))
            .join(",")
    }

    #[test]
    fn reads_the_terms_into_the_cores_fields() {
        let gx = r#"{"channel": "gx_radps", "terms": [{"term": "quantization", "value_si": 2e-6},
            {"term": "gauss_markov", "value_si": 3e-5, "tau_c_s": 0.05}, {"term": "rate_random_walk", "value_si": 1e-7},
            {"term": "sway", "value_si": 4e-4, "tau_c_s": 3.5}]}"#;
        let f = NoiseFile::parse(&file(&format!("{gx},{}", accel())), "f").unwrap().terms;
        let g = f.channels[0].unwrap();
        assert_eq!((g.quantisation_u_s, g.gauss_markov_u, g.gauss_markov_time_s), (2e-6, 3e-5, 0.05));
        assert_eq!((g.sway_u_s, g.sway_time_s), (4e-4, 3.5));
        assert_eq!((g.white_u_sqrt_s, g.random_walk_u_per_sqrt_s), (0.0, 1e-7));
        assert_eq!(f.channels[4].unwrap().white_u_sqrt_s, 1e-4);
        assert!(f.channels[1].is_none());
        // Gyro data need the gyro channels; accelerometer-only data do not.
        assert!(f.model(0.01, true).is_err());
        let m = f.model(0.01, false).unwrap();
        assert_eq!(m.sample_interval_s, 0.01);
    }

    #[test]
    fn refuses_what_is_not_a_noise_model() {
        for (text, says) in [
            (r#"{"schema": "sinscal/2"}"#.to_string(), "not a noise file"),
            (file(r#"{"channel": "ax_mps2", "terms": []}"#), "no term makes"),
            (file(&format!(r#"{},{{"channel": "ax_mps2", "terms": []}}"#, accel())), "given twice"),
            (file(r#"{"channel": "bx", "terms": []}"#), "unknown channel"),
            (file(r#"{"channel": "ax_mps2", "terms": [{"term": "white", "value_si": -1}]}"#), "non-negative"),
            (file(r#"{"channel": "ax_mps2", "terms": [{"term": "gauss_markov", "value_si": 1}]}"#), "tau_c_s"),
            (file(r#"{"channel": "ax_mps2", "terms": [{"term": "sway", "value_si": 1}]}"#), "term sway: tau_c_s"),
            (file(r#"{"channel": "ax_mps2", "terms": [{"term": "pink", "value_si": 1}]}"#), "unknown term"),
            (file(r#"{"channel": "ax_mps2", "terms": [{"term": "white", "value_si": 1}]}"#), "three accelerometer"),
        ] {
            let e = NoiseFile::parse(&text, "f").unwrap_err().to_string();
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}
