//! Small maths: fixed-size 3-vectors and 3x3 matrices in f32 ([`linalg`]), the dwell accumulators
//! (shifted, blocked, compensated sums: [`accumulate`]) and the online octave Allan variance ([`allan`]).
//! No units here; the callers' names carry them.

pub mod accumulate;
pub mod allan;
pub mod linalg;
pub mod lsq;
