//! The effect catalogue (docs/formats.md#effect-catalogue): the fifteen effects `sinscal analyze` tests and
//! `sinscal simulate` can switch on, each with its fixed name, its sensor and the SI unit of its estimate.
//! The names are part of the analysis JSON (docs/formats.md#analysis-json): [`EffectKind::name`] is what is
//! written, [`str::parse`] reads it back.

use std::fmt;
use std::str::FromStr;

/// What an effect belongs to: the reference (the table's attitude) or one of the two sensors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Sensor {
    /// The table attitude the recording states.
    Reference,
    /// The accelerometers.
    Accel,
    /// The gyros.
    Gyro,
}

impl Sensor {
    /// "reference", "accel" or "gyro", as the analysis JSON writes it.
    pub fn name(self) -> &'static str {
        match self {
            Sensor::Reference => "reference",
            Sensor::Accel => "accel",
            Sensor::Gyro => "gyro",
        }
    }

    /// The sensor of channel `c` of a recording (gx, gy, gz, ax, ay, az = 0..5).
    pub fn of_channel(c: usize) -> Sensor {
        if c < 3 {
            Sensor::Gyro
        } else {
            Sensor::Accel
        }
    }
}

impl fmt::Display for Sensor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One entry of the effect catalogue.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EffectKind {
    /// Constant table attitude error `phi0` (e, n, u), rad.
    ReferenceOffset,
    /// Table attitude error at one position (e, n, u), rad.
    PositionError,
    /// Accelerometer relative scale-factor error.
    AccelScaleFactor,
    /// Accelerometer axis i's sensitivity to force along j.
    AccelMisalignment,
    /// Accelerometer second-order nonlinearity K2: axis i reads `K2 f_i^2` more.
    AccelNonlinearity,
    /// Gyro relative scale-factor error.
    GyroScaleFactor,
    /// Gyro axis i's sensitivity to rate about j.
    GyroMisalignment,
    /// Gyro i error per specific force along j.
    GyroGSensitivity,
    /// Bias slope.
    BiasDrift,
    /// Amplitude of an exponential warm-up of the bias.
    BiasWarmup,
    /// First-order Gauss-Markov noise.
    CorrelatedNoise,
    /// Noise larger at the start of the record than once settled: the standard deviation it adds.
    NoiseWarmup,
    /// A sinusoid.
    Vibration,
    /// An output step.
    Quantization,
    /// Bias per kelvin.
    TemperatureBias,
}

impl EffectKind {
    /// The catalogue, in the order of docs/formats.md#effect-catalogue.
    pub const ALL: [EffectKind; 15] = [
        EffectKind::ReferenceOffset,
        EffectKind::PositionError,
        EffectKind::AccelScaleFactor,
        EffectKind::AccelMisalignment,
        EffectKind::AccelNonlinearity,
        EffectKind::GyroScaleFactor,
        EffectKind::GyroMisalignment,
        EffectKind::GyroGSensitivity,
        EffectKind::BiasDrift,
        EffectKind::BiasWarmup,
        EffectKind::CorrelatedNoise,
        EffectKind::NoiseWarmup,
        EffectKind::Vibration,
        EffectKind::Quantization,
        EffectKind::TemperatureBias,
    ];

    /// The fixed catalogue name ("reference_offset", ...).
    pub fn name(self) -> &'static str {
        match self {
            EffectKind::ReferenceOffset => "reference_offset",
            EffectKind::PositionError => "position_error",
            EffectKind::AccelScaleFactor => "accel_scale_factor",
            EffectKind::AccelMisalignment => "accel_misalignment",
            EffectKind::AccelNonlinearity => "accel_nonlinearity",
            EffectKind::GyroScaleFactor => "gyro_scale_factor",
            EffectKind::GyroMisalignment => "gyro_misalignment",
            EffectKind::GyroGSensitivity => "gyro_g_sensitivity",
            EffectKind::BiasDrift => "bias_drift",
            EffectKind::BiasWarmup => "bias_warmup",
            EffectKind::CorrelatedNoise => "correlated_noise",
            EffectKind::NoiseWarmup => "noise_warmup",
            EffectKind::Vibration => "vibration",
            EffectKind::Quantization => "quantization",
            EffectKind::TemperatureBias => "temperature_bias",
        }
    }

    /// The sensor the effect belongs to; `None` for the effects either sensor can have, one per channel
    /// (drift, warm-up, correlated noise, noise warm-up, vibration, quantisation, temperature).
    pub fn sensor(self) -> Option<Sensor> {
        match self {
            EffectKind::ReferenceOffset | EffectKind::PositionError => Some(Sensor::Reference),
            EffectKind::AccelScaleFactor | EffectKind::AccelMisalignment | EffectKind::AccelNonlinearity => {
                Some(Sensor::Accel)
            }
            EffectKind::GyroScaleFactor | EffectKind::GyroMisalignment | EffectKind::GyroGSensitivity => {
                Some(Sensor::Gyro)
            }
            _ => None,
        }
    }

    /// SI unit of the estimate, as the analysis JSON writes it. `sensor` picks the unit of the per-channel
    /// effects (gyro: rad/s based, accel: m/s^2 based); the others have one unit whatever it says.
    pub fn unit(self, sensor: Sensor) -> &'static str {
        let gyro = sensor == Sensor::Gyro;
        match self {
            EffectKind::ReferenceOffset | EffectKind::PositionError => "rad",
            EffectKind::AccelScaleFactor
            | EffectKind::AccelMisalignment
            | EffectKind::GyroScaleFactor
            | EffectKind::GyroMisalignment => "1",
            EffectKind::GyroGSensitivity => "(rad/s)/(m/s^2)",
            EffectKind::AccelNonlinearity => "1/(m/s^2)",
            EffectKind::BiasDrift if gyro => "(rad/s)/s",
            EffectKind::BiasDrift => "(m/s^2)/s",
            EffectKind::TemperatureBias if gyro => "(rad/s)/K",
            EffectKind::TemperatureBias => "(m/s^2)/K",
            EffectKind::BiasWarmup
            | EffectKind::CorrelatedNoise
            | EffectKind::NoiseWarmup
            | EffectKind::Vibration
            | EffectKind::Quantization => {
                if gyro {
                    "rad/s"
                } else {
                    "m/s^2"
                }
            }
        }
    }
}

// The plausible limits of any instrument are the calibration model's (io::calibration_model): the reader of a
// calibration refuses values beyond them, and the catalogue holds its effects to them.
pub use crate::io::calibration_model::{
    MAX_ACCEL_BIAS_MPS2, MAX_GYRO_BIAS_RADPS, MAX_G_SENSITIVITY_RADPS_PER_MPS2, MAX_LEVEL_ERROR_RAD,
    MAX_SCALE_OR_MISALIGNMENT,
};
/// Largest accelerometer second-order nonlinearity K2, 1/(m/s^2): 1e-3, about 10 mg/g^2 (a consumer MEMS
/// accelerometer's is of the order of 1 mg/g^2, a navigation-grade one's 10 ug/g^2).
pub const MAX_ACCEL_NONLINEARITY_PER_MPS2: f64 = 1e-3;
/// Largest heading error of a reference attitude, rad (29 degrees).
pub const MAX_HEADING_ERROR_RAD: f64 = 0.5;

impl EffectKind {
    /// The largest magnitude of this effect's estimate that a plausible instrument and turntable show
    /// (docs/analysis.md#plausibility), SI; `None` for the noise effects, whose size the data themselves
    /// show. Time effects are bounded by what they add to the bias over the session: a drift by the largest
    /// bias over `span_s`, a temperature coefficient by the largest bias over `temperature_span_k`.
    pub fn plausible_limit(self, sensor: Sensor, axes: &str, span_s: f64, temperature_span_k: f64) -> Option<f64> {
        let bias = if sensor == Sensor::Gyro { MAX_GYRO_BIAS_RADPS } else { MAX_ACCEL_BIAS_MPS2 };
        match self {
            EffectKind::ReferenceOffset | EffectKind::PositionError if axes == "u" => Some(MAX_HEADING_ERROR_RAD),
            EffectKind::ReferenceOffset | EffectKind::PositionError => Some(MAX_LEVEL_ERROR_RAD),
            EffectKind::AccelScaleFactor
            | EffectKind::AccelMisalignment
            | EffectKind::GyroScaleFactor
            | EffectKind::GyroMisalignment => Some(MAX_SCALE_OR_MISALIGNMENT),
            EffectKind::GyroGSensitivity => Some(MAX_G_SENSITIVITY_RADPS_PER_MPS2),
            EffectKind::AccelNonlinearity => Some(MAX_ACCEL_NONLINEARITY_PER_MPS2),
            EffectKind::BiasDrift => Some(bias / span_s.max(1.0)),
            EffectKind::BiasWarmup => Some(bias),
            EffectKind::TemperatureBias => Some(bias / temperature_span_k.max(1.0)),
            EffectKind::CorrelatedNoise
            | EffectKind::NoiseWarmup
            | EffectKind::Vibration
            | EffectKind::Quantization => None,
        }
    }

    /// A function of time (drift, warm-up, temperature): what it explains across dwells is confounded with
    /// the order of the poses unless poses repeat or it shows within the dwells.
    pub fn is_time_term(self) -> bool {
        matches!(self, EffectKind::BiasDrift | EffectKind::BiasWarmup | EffectKind::TemperatureBias)
    }
}

impl fmt::Display for EffectKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not in the catalogue.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownEffect(pub String);

impl fmt::Display for UnknownEffect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown effect '{}' (not in the catalogue)", self.0)
    }
}

impl std::error::Error for UnknownEffect {}

impl FromStr for EffectKind {
    type Err = UnknownEffect;

    fn from_str(s: &str) -> Result<EffectKind, UnknownEffect> {
        EffectKind::ALL.into_iter().find(|k| k.name() == s).ok_or_else(|| UnknownEffect(s.to_string()))
    }
}

/// A name (an analysis verdict, an effect's `effect` field) against a catalogue entry.
impl PartialEq<EffectKind> for String {
    fn eq(&self, other: &EffectKind) -> bool {
        self == other.name()
    }
}

/// A name against a catalogue entry.
impl PartialEq<EffectKind> for str {
    fn eq(&self, other: &EffectKind) -> bool {
        self == other.name()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_and_are_distinct() {
        for k in EffectKind::ALL {
            assert_eq!(k.name().parse::<EffectKind>(), Ok(k));
            assert_eq!(EffectKind::ALL.iter().filter(|o| o.name() == k.name()).count(), 1);
        }
        assert!("bias".parse::<EffectKind>().is_err());
    }
}
