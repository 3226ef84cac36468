//! Why the estimator refused the data ([`ChannelError`]), with the reason in words.

use crate::calib::general::estimator::MAX_DWELLS;
use crate::calib::general::terms::parameter_name;
use crate::calib::moves::MAX_MOVES;

/// Why the estimator refused the data (dwell indices count from 0 in the order added).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ChannelError {
    /// No dwell was added.
    NoDwells,
    /// More than [`MAX_DWELLS`] dwells.
    TooManyDwells,
    /// A mean, variance or attitude is NaN or infinite, or a variance is not positive.
    BadInput {
        /// Which dwell.
        dwell: usize,
    },
    /// |f| differs from g by more than the settings allow (an accelerometer scale error, or not at rest).
    ForceMagnitude {
        /// Which dwell.
        dwell: usize,
        /// |f| / g.
        ratio: f32,
    },
    /// Measured gravity points elsewhere than the reference attitude says (a wrong face down, wrong axes).
    GravityDirection {
        /// Which dwell.
        dwell: usize,
        /// Angle between the two, rad.
        angle_rad: f32,
    },
    /// The gyros see the Earth rate as if the heading were a quarter or half turn from the reference's.
    HeadingMismatch {
        /// Which dwell.
        dwell: usize,
        /// The reference heading, rad.
        given_rad: f32,
        /// The heading the Earth rate fits, rad.
        fits_rad: f32,
    },
    /// The model has no term the data can inform.
    NothingToEstimate,
    /// More than [`MAX_MOVES`] moves.
    TooManyMoves,
    /// A move joins a dwell that was not added, or a number of it is not finite.
    BadMove {
        /// Which move (from 0, in the order given).
        index: usize,
    },
    /// The fit did not converge and left the range any instrument could have (it ran away: a model these dwells
    /// cannot pin down); the first such parameter.
    Diverged {
        /// Its index (see [`parameter_name`]).
        parameter: usize,
        /// Its value, SI.
        value: f32,
    },
}

impl core::fmt::Display for ChannelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            ChannelError::NoDwells => f.write_str("no dwells to solve"),
            ChannelError::TooManyDwells => write!(f, "more than {MAX_DWELLS} dwells"),
            ChannelError::BadInput { dwell } => {
                write!(f, "dwell {}: a mean, variance or attitude is not finite or a variance not positive", dwell + 1)
            }
            ChannelError::ForceMagnitude { dwell, ratio } => write!(
                f,
                "dwell {}: |f| is {ratio:.4} g: an accelerometer scale error or a body not at rest",
                dwell + 1
            ),
            ChannelError::GravityDirection { dwell, angle_rad } => write!(
                f,
                "dwell {}: measured gravity is {:.1} deg from where the reference attitude puts it: a wrong face \
                 down, a wrong pitch/roll, or axes that are not x right, y forward, z up",
                dwell + 1,
                angle_rad.to_degrees()
            ),
            ChannelError::HeadingMismatch { dwell, given_rad, fits_rad } => write!(
                f,
                "dwell {}: the gyros see the Earth rate of heading {:.0} deg, not of the reference's {:.0} deg",
                dwell + 1,
                degrees_0_360(fits_rad),
                degrees_0_360(given_rad)
            ),
            ChannelError::NothingToEstimate => {
                f.write_str("the model has no term these data can inform: the schedule determines none of them")
            }
            ChannelError::TooManyMoves => write!(f, "more than {MAX_MOVES} moves"),
            ChannelError::BadMove { index } => write!(
                f,
                "move {}: it joins a dwell that was not added, or its rotation, duration or sums are not finite",
                index + 1
            ),
            ChannelError::Diverged { parameter, value } => write!(
                f,
                "the fit diverged: {} reached {value:e} (SI), beyond what any instrument has; fit fewer terms \
                 (--model) or add positions that determine them",
                parameter_name(parameter)
            ),
        }
    }
}

impl core::error::Error for ChannelError {}

/// An angle in degrees in [0, 360).
pub(super) fn degrees_0_360(angle_rad: f32) -> f32 {
    let d = angle_rad.to_degrees() % 360.0;
    if d < 0.0 {
        d + 360.0
    } else {
        d
    }
}
