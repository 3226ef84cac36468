//! Weighted linear least squares with per-group noise variances, the likelihood that `sinscal analyze`
//! compares its models by, and the chi-square quantile of its significance test.
//!
//! Observations `y_i = sum_j X_ij beta_j + e_i` with `e_i ~ N(0, s_g(i)^2)`: every observation belongs to a
//! variance group `g(i)` (a sensor channel, or the tilt and heading angles). With known standard
//! deviations the likelihood is the Gaussian one; otherwise each group's variance is estimated by maximum
//! likelihood together with `beta` (iteratively reweighted least squares, which converges to the joint
//! maximum because for fixed variances the `beta` step is exact and for fixed `beta` the variance step is),
//! and the log-likelihood is the profile one, `-n_g/2 (ln(2 pi s_g^2) + 1)` per group.

use crate::stats::noise::regularized_gamma_q;

pub use crate::stats::solve::solve_spd;

/// The observations of a linear problem.
#[derive(Clone, Debug)]
pub struct Observations {
    /// Observed values (residuals against the known part of the model), in each group's unit.
    pub y: Vec<f64>,
    /// Variance group of each observation.
    pub group: Vec<usize>,
    /// Number of groups.
    pub groups: usize,
    /// Known standard deviation of each observation; `None` = estimate one variance per group.
    pub sigma: Option<Vec<f64>>,
}

/// A fitted linear model.
#[derive(Clone, Debug)]
pub struct LinearFit {
    /// Estimated coefficients, one per column.
    pub beta: Vec<f64>,
    /// Their covariance (from the weighted normal equations with the fitted variances).
    pub covariance: Vec<Vec<f64>>,
    /// Residual `y - X beta` per observation.
    pub residual: Vec<f64>,
    /// Noise variance per group (fitted, or the mean of the known variances).
    pub variance: Vec<f64>,
    /// Root mean square residual per group, in the group's unit.
    pub rms: Vec<f64>,
    /// Log-likelihood of the fit (profile likelihood when the variances are estimated).
    pub log_likelihood: f64,
}

impl LinearFit {
    /// Standard error of coefficient `j`.
    pub fn std_error(&self, j: usize) -> f64 {
        self.covariance[j][j].max(0.0).sqrt()
    }
}

/// Fits `columns` (each of the length of `obs.y`) to the observations. `None` when the columns are
/// linearly dependent (with the weights) or there are no more observations than columns in a group
/// whose variance is estimated.
pub fn fit(obs: &Observations, columns: &[&[f64]]) -> Option<LinearFit> {
    let n = obs.y.len();
    let k = columns.len();
    let count = group_counts(obs);
    let mut variance = initial_variance(obs);
    // A group that the model fits exactly keeps a tiny variance, not zero (finite weights).
    let floor: Vec<f64> = variance.iter().map(|v| (v * 1e-24).max(1e-300)).collect();
    let iterations = if obs.sigma.is_some() { 1 } else { 30 };
    let mut result = None;
    let mut previous_ll = f64::NEG_INFINITY;
    for _ in 0..iterations {
        let (a, b) = normal_equations(obs, columns, &variance);
        let (beta, inverse) = if k == 0 { (Vec::new(), Vec::new()) } else { solve_spd(&a, &b)? };
        let residual: Vec<f64> =
            (0..n).map(|i| obs.y[i] - (0..k).map(|p| columns[p][i] * beta[p]).sum::<f64>()).collect();
        let mut ss = vec![0.0; obs.groups];
        for i in 0..n {
            ss[obs.group[i]] += residual[i] * residual[i];
        }
        let ll = match &obs.sigma {
            Some(s) => known_sigma_log_likelihood(s, &residual),
            None => update_variance(&mut variance, &ss, &count, &floor),
        };
        let rms: Vec<f64> =
            (0..obs.groups).map(|g| if count[g] > 0 { (ss[g] / count[g] as f64).sqrt() } else { 0.0 }).collect();
        let converged = (ll - previous_ll).abs() <= 1e-9 * ll.abs().max(1.0);
        previous_ll = ll;
        result = Some(LinearFit {
            beta,
            covariance: inverse,
            residual,
            variance: variance.clone(),
            rms,
            log_likelihood: ll,
        });
        if converged {
            break;
        }
    }
    let mut fit = result?;
    if let Some(s) = &obs.sigma {
        for g in 0..obs.groups {
            let v: Vec<f64> = (0..n).filter(|&i| obs.group[i] == g).map(|i| s[i] * s[i]).collect();
            fit.variance[g] = if v.is_empty() { 0.0 } else { v.iter().sum::<f64>() / v.len() as f64 };
        }
    }
    Some(fit)
}

/// Number of observations in each variance group.
fn group_counts(obs: &Observations) -> Vec<usize> {
    let mut count = vec![0usize; obs.groups];
    for &g in &obs.group {
        count[g] += 1;
    }
    count
}

/// The starting variance of each group: its mean square observation (1 for an empty group).
fn initial_variance(obs: &Observations) -> Vec<f64> {
    (0..obs.groups)
        .map(|g| {
            let (s, c) = obs
                .y
                .iter()
                .zip(&obs.group)
                .filter(|(_, &gi)| gi == g)
                .fold((0.0, 0usize), |(s, c), (y, _)| (s + y * y, c + 1));
            if c > 0 {
                (s / c as f64).max(1e-300)
            } else {
                1.0
            }
        })
        .collect()
}

/// Weight of observation `i`: its inverse known variance, or the inverse of its group's current variance.
fn weight(obs: &Observations, i: usize, variance: &[f64]) -> f64 {
    match &obs.sigma {
        Some(s) => 1.0 / (s[i] * s[i]),
        None => 1.0 / variance[obs.group[i]],
    }
}

/// The weighted normal equations `A beta = b` of the columns (A filled in full from its lower triangle).
fn normal_equations(obs: &Observations, columns: &[&[f64]], variance: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let k = columns.len();
    let mut a = vec![vec![0.0; k]; k];
    let mut b = vec![0.0; k];
    for i in 0..obs.y.len() {
        let w = weight(obs, i, variance);
        for p in 0..k {
            let xp = columns[p][i];
            if xp == 0.0 {
                continue;
            }
            b[p] += w * xp * obs.y[i];
            for q in 0..=p {
                a[p][q] += w * xp * columns[q][i];
            }
        }
    }
    for p in 0..k {
        for q in 0..p {
            a[q][p] = a[p][q];
        }
    }
    (a, b)
}

/// The Gaussian log-likelihood of the residuals with known standard deviations `s`.
fn known_sigma_log_likelihood(s: &[f64], residual: &[f64]) -> f64 {
    (0..residual.len())
        .map(|i| -0.5 * ((2.0 * std::f64::consts::PI * s[i] * s[i]).ln() + residual[i] * residual[i] / (s[i] * s[i])))
        .sum()
}

/// Sets each non-empty group's variance to its mean square residual (at least `floor`) and returns the profile
/// log-likelihood.
fn update_variance(variance: &mut [f64], ss: &[f64], count: &[usize], floor: &[f64]) -> f64 {
    for g in 0..variance.len() {
        if count[g] > 0 {
            variance[g] = (ss[g] / count[g] as f64).max(floor[g]);
        }
    }
    (0..variance.len())
        .filter(|&g| count[g] > 0)
        .map(|g| -0.5 * count[g] as f64 * ((2.0 * std::f64::consts::PI * variance[g]).ln() + 1.0))
        .sum::<f64>()
}

/// Upper tail probability of the chi-square distribution with `dof` degrees of freedom at `x`.
pub fn chi_square_upper(x: f64, dof: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    regularized_gamma_q(0.5 * dof, 0.5 * x)
}

/// The `x` whose upper chi-square tail probability is `p` (bisection; relative accuracy 1e-10).
pub fn chi_square_quantile_upper(p: f64, dof: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, dof.max(1.0));
    while chi_square_upper(hi, dof) > p {
        hi *= 2.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi_square_upper(mid, dof) > p {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo <= 1e-10 * hi {
            break;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chi_square_quantiles_match_tables() {
        // Tables: chi2_1(0.95) = 3.841459, chi2_2(0.99) = 9.210340, chi2_10(0.999) = 29.588298.
        assert!((chi_square_quantile_upper(0.05, 1.0) - 3.841459).abs() < 1e-5);
        assert!((chi_square_quantile_upper(0.01, 2.0) - 9.210340).abs() < 1e-5);
        assert!((chi_square_quantile_upper(0.001, 10.0) - 29.588298).abs() < 1e-4);
    }

    #[test]
    fn exact_line_and_group_variances() {
        // y = 2 + 3 x exactly in group 0, plus a group 1 with known scatter +-1 around 5.
        let x: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let mut y: Vec<f64> = x.iter().map(|x| 2.0 + 3.0 * x).collect();
        let mut group = vec![0; 20];
        let mut one = vec![1.0; 20];
        let mut slope = x.clone();
        let mut other = vec![0.0; 20];
        for i in 0..10 {
            y.push(5.0 + if i % 2 == 0 { 1.0 } else { -1.0 });
            group.push(1);
            one.push(0.0);
            slope.push(0.0);
            other.push(1.0);
        }
        let obs = Observations { y, group, groups: 2, sigma: None };
        let f = fit(&obs, &[&one, &slope, &other]).unwrap();
        assert!((f.beta[0] - 2.0).abs() < 1e-9 && (f.beta[1] - 3.0).abs() < 1e-9 && (f.beta[2] - 5.0).abs() < 1e-12);
        assert!((f.rms[1] - 1.0).abs() < 1e-12);
        // Dependent columns are refused.
        let twice: Vec<f64> = one.iter().map(|v| 2.0 * v).collect();
        assert!(fit(&obs, &[&one, &twice]).is_none());
    }
}
