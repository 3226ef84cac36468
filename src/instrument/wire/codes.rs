//! Every code of the wire formats as an enum with its byte: the IMU, the estimator, the prefilter, the dwell
//! value, why a configuration was refused, what an outcome holds. `wire_codes!` writes each enum with its
//! `code()` and `from_code()` from one list, so the two directions cannot disagree.

use crate::calib::align::DwellValue;
use crate::sensor::adis::Model;

/// An enum of codes: the list of variants and their codes, once; `code()`, `from_code()` and `ALL` from it.
macro_rules! wire_codes {
    ($(#[$meta:meta])* pub enum $name:ident : $repr:ty {
        $($(#[$vmeta:meta])* $variant:ident = $value:expr,)+
    }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        #[cfg_attr(feature = "defmt", derive(defmt::Format))]
        #[repr($repr)]
        pub enum $name {
            $($(#[$vmeta])* $variant = $value,)+
        }

        impl $name {
            /// Every code, in the order of the list.
            pub const ALL: &'static [$name] = &[$($name::$variant,)+];

            /// The code's value on the wire.
            pub const fn code(self) -> $repr {
                self as $repr
            }

            /// The code of a value on the wire; `None` for an unknown one.
            pub fn from_code(value: $repr) -> Option<$name> {
                Self::ALL.iter().copied().find(|c| c.code() == value)
            }
        }
    };
}
pub(crate) use wire_codes;

wire_codes! {
    /// The IMU whose frames a configuration describes.
    pub enum ImuCode: u8 {
        /// ADIS16470.
        Adis16470 = 0,
        /// ADIS16505-2.
        Adis16505_2 = 1,
    }
}

impl ImuCode {
    /// The code of a sensor model.
    pub fn of(model: Model) -> ImuCode {
        match model {
            Model::Adis16470 => ImuCode::Adis16470,
            Model::Adis16505_2 => ImuCode::Adis16505_2,
        }
    }

    /// The sensor model of the code.
    pub fn model(self) -> Model {
        match self {
            ImuCode::Adis16470 => Model::Adis16470,
            ImuCode::Adis16505_2 => Model::Adis16505_2,
        }
    }
}

wire_codes! {
    /// The estimator a configuration asks for.
    pub enum EstimatorCode: u8 {
        /// The paper's angle method.
        Angles = 0,
        /// The general estimator with gyro data.
        General = 1,
        /// The general estimator on the accelerometers only.
        GeneralWithoutGyros = 2,
    }
}

wire_codes! {
    /// The prefilter of the dwell collector.
    pub enum PrefilterCode: u8 {
        /// None: the dwell value is the plain mean.
        None = 0,
        /// The HMM/KF with the paper's Q and R and the configuration's `a`.
        HmmKf = 1,
    }
}

wire_codes! {
    /// The dwell value the solution uses.
    pub enum DwellValueCode: u8 {
        /// The mean of the dwell.
        Mean = 0,
        /// The prefilter's settled state.
        Settled = 1,
    }
}

impl DwellValueCode {
    /// The code of a dwell value.
    pub fn of(value: DwellValue) -> DwellValueCode {
        match value {
            DwellValue::Mean => DwellValueCode::Mean,
            DwellValue::Settled => DwellValueCode::Settled,
        }
    }

    /// The dwell value of the code.
    pub fn value(self) -> DwellValue {
        match self {
            DwellValueCode::Mean => DwellValue::Mean,
            DwellValueCode::Settled => DwellValue::Settled,
        }
    }
}

wire_codes! {
    /// Why the device refused a configuration (the detail of the error reply `Configuration`).
    pub enum ConfigurationRefusal: u32 {
        /// The body is shorter than the thresholds or longer than the longest configuration.
        Length = 1,
        /// The body does not decode: an unknown code, a schedule empty or longer than the core holds, a limit
        /// not positive, or bytes left over.
        Content = 2,
        /// The calibration sequence refused the schedule or the settings.
        Sequence = 3,
        /// The configuration names another IMU than the device's.
        Imu = 4,
    }
}

impl core::fmt::Display for ConfigurationRefusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            ConfigurationRefusal::Length => "its length is outside what a configuration can have",
            ConfigurationRefusal::Content => "it does not decode (an unknown code or a value out of range)",
            ConfigurationRefusal::Sequence => "the calibration sequence refused its schedule or settings",
            ConfigurationRefusal::Imu => "it names another IMU than the device's",
        })
    }
}

wire_codes! {
    /// What kind of solution an outcome holds.
    pub enum SolutionCode: u32 {
        /// None (the sequence failed or did not end).
        None = 0,
        /// The angle method's.
        Angles = 1,
        /// The general estimator's.
        General = 2,
    }
}

wire_codes! {
    /// What kind of failure an outcome holds.
    pub enum FailureKind: u32 {
        /// None.
        None = 0,
        /// A position was aborted too often.
        PositionAborted = 1,
        /// The angle method refused.
        Angles = 2,
        /// The general estimator refused.
        General = 3,
    }
}

wire_codes! {
    /// What the general estimator knew of the dwells' attitudes.
    pub enum AttitudeCode: u32 {
        /// The reference's attitudes.
        Reference = 0,
        /// Unknown (levelled from the data).
        Unknown = 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_decodes_to_itself_and_the_codes_are_the_documented_ones() {
        for c in ImuCode::ALL {
            assert_eq!(ImuCode::from_code(c.code()), Some(*c));
            assert_eq!(ImuCode::of(c.model()), *c);
        }
        assert_eq!(ImuCode::ALL.iter().map(|c| c.code()).collect::<heapless::Vec<u8, 4>>(), [0, 1]);
        assert_eq!(EstimatorCode::from_code(2), Some(EstimatorCode::GeneralWithoutGyros));
        assert_eq!(EstimatorCode::from_code(3), None);
        assert_eq!(ConfigurationRefusal::ALL.iter().map(|c| c.code()).collect::<heapless::Vec<u32, 4>>(), [1, 2, 3, 4]);
        assert_eq!(ConfigurationRefusal::from_code(0), None);
        for c in DwellValueCode::ALL {
            assert_eq!(DwellValueCode::of(c.value()), *c);
        }
        assert_eq!((PrefilterCode::HmmKf.code(), SolutionCode::General.code(), FailureKind::General.code()), (1, 2, 3));
        assert_eq!(AttitudeCode::from_code(1), Some(AttitudeCode::Unknown));
    }
}
