//! Statistics in f64: weighted least squares with per-group variances and the likelihood the analysis
//! compares models by ([`linfit`]); the noise statistics of one channel ([`noise`]: Allan deviation, the
//! IEEE Std 952 terms, PSD, whiteness, quantisation).

pub mod linfit;
pub mod noise;
pub mod solve;
