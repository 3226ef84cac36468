//! Small maths: fixed-size 3-vectors and 3x3 matrices in f32 ([`linalg`]) and the dwell accumulators
//! (shifted, blocked, compensated sums: [`accumulate`]). No units here; the callers' names carry them.

pub mod accumulate;
pub mod linalg;
pub mod lsq;
