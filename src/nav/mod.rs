//! Navigation frames and the Earth: the one home of every sign convention (docs/conventions.md).
//!
//! [`frames`]: the turntable attitude (pitch, roll, heading) to `C_b^n` (East-North-Up navigation frame,
//! body x right, y forward, z up) and the misalignment `phi` of a computed attitude,
//! `C_hat_b^n = (I - [phi x]) C_b^n`. [`earth`]: Earth rate, WGS-84 normal gravity, the site. [`strapdown`]: the
//! body's rotation over a move from its gyro rates (quaternion, coning-corrected two-sample update).

pub mod earth;
pub mod frames;
pub mod strapdown;
