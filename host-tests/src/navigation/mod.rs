//! The navigation check of `sinscal navigate`: a strapdown engine ([`strapdown`], f64, ENU) and the static
//! run of a recording with and without the calibration applied ([`check`]).

pub mod check;
pub mod strapdown;
