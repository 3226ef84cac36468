//! The f64 solvers of the host, in one place: symmetric positive definite systems (Cholesky after
//! equilibration), square systems (Gaussian elimination) and the 3 x 3 inverse, least squares by Householder QR
//! or by the normal equations, non-linear least squares (Gauss-Newton), and non-negative least squares by
//! enumerating the supports. Small dense problems (tens of unknowns): clarity over speed.

/// Solves the symmetric positive definite system `a x = b` after equilibration; `None` when `a` is
/// singular to working precision (a column that the others explain). Returns `x` and `a^-1`.
pub fn solve_spd(a: &[Vec<f64>], b: &[f64]) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let k = b.len();
    let d: Vec<f64> = (0..k).map(|i| if a[i][i] > 0.0 { 1.0 / a[i][i].sqrt() } else { 0.0 }).collect();
    if d.iter().any(|&v| v == 0.0 || !v.is_finite()) {
        return None;
    }
    // Cholesky of D A D.
    let mut l = vec![vec![0.0; k]; k];
    for i in 0..k {
        for j in 0..=i {
            let mut s = a[i][j] * d[i] * d[j];
            for p in 0..j {
                s -= l[i][p] * l[j][p];
            }
            if i == j {
                if s <= 1e-11 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let solve = |rhs: &[f64]| -> Vec<f64> {
        let mut z = vec![0.0; k];
        for i in 0..k {
            z[i] = (rhs[i] - (0..i).map(|p| l[i][p] * z[p]).sum::<f64>()) / l[i][i];
        }
        let mut x = vec![0.0; k];
        for i in (0..k).rev() {
            x[i] = (z[i] - ((i + 1)..k).map(|p| l[p][i] * x[p]).sum::<f64>()) / l[i][i];
        }
        x
    };
    let scaled: Vec<f64> = (0..k).map(|i| b[i] * d[i]).collect();
    let x: Vec<f64> = solve(&scaled).iter().zip(&d).map(|(x, d)| x * d).collect();
    let mut inverse = vec![vec![0.0; k]; k];
    for j in 0..k {
        let mut e = vec![0.0; k];
        e[j] = 1.0;
        let col = solve(&e);
        for i in 0..k {
            inverse[i][j] = col[i] * d[i] * d[j];
        }
    }
    Some((x, inverse))
}

/// Non-negative least squares min |A c - y|, c >= 0, for five unknowns, by enumerating the supports
/// (every subset of the columns, solved by [`least_squares_subset`]; the best feasible one wins).
///
/// It differs from [`nnls_normal`] only in the subset solver: Householder QR on the columns scaled to unit norm
/// (robust for the Allan-variance design of [`crate::stats::noise`], whose columns span many decades); the loop
/// over the supports is [`nnls_by_supports`] for both.
pub fn nnls_by_enumeration(rows: &[([f64; 5], f64)]) -> Option<[f64; 5]> {
    let ss_of = |c: &[f64]| -> f64 {
        rows.iter()
            .map(|(a, y)| {
                let r = a.iter().zip(c).map(|(a, c)| a * c).sum::<f64>() - y;
                r * r
            })
            .sum()
    };
    let solve_subset = |cols: &[usize]| -> Option<Vec<f64>> {
        let x = least_squares_subset(rows, cols)?;
        (!x.iter().any(|&v| v < 0.0 || !v.is_finite())).then_some(x)
    };
    let (c, _) = nnls_by_supports(5, ss_of, solve_subset)?;
    Some([c[0], c[1], c[2], c[3], c[4]])
}

/// Non-negative least squares min |A c - y|, c >= 0, by enumerating the supports: each subset of the columns
/// scaled to unit norm and solved by the normal equations ([`least_squares_normal`]); the best feasible one
/// wins. Returns the coefficients and the residual sum of squares; `None` without rows or without a feasible
/// support.
///
/// It differs from [`nnls_by_enumeration`] in the subset solver (normal equations instead of QR) and in taking
/// any number of columns: the study's extended noise fits (six unknowns, rows already weighted) were made with
/// it, and QR would change their last bits. The loop over the supports is [`nnls_by_supports`] for both.
pub fn nnls_normal(rows: &[Vec<f64>], y: &[f64]) -> Option<(Vec<f64>, f64)> {
    let p = rows.first()?.len();
    let ss_of = |c: &[f64]| -> f64 {
        rows.iter().zip(y).map(|(r, yv)| (r.iter().zip(c).map(|(a, b)| a * b).sum::<f64>() - yv).powi(2)).sum()
    };
    let solve_subset = |cols: &[usize]| -> Option<Vec<f64>> {
        let norms: Vec<f64> = cols.iter().map(|&j| rows.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt()).collect();
        if norms.iter().any(|v| v.is_nan() || *v <= 0.0) {
            return None;
        }
        let sub_rows: Vec<Vec<f64>> =
            rows.iter().map(|r| cols.iter().zip(&norms).map(|(&j, n)| r[j] / n).collect()).collect();
        let x = least_squares_normal(&sub_rows, y)?;
        if x.iter().any(|v| *v < 0.0) {
            return None;
        }
        Some(x.iter().zip(&norms).map(|(v, n)| v / n).collect())
    };
    nnls_by_supports(p, ss_of, solve_subset)
}

/// The loop of the enumerating NNLS solvers: for every non-empty subset of the `p` columns (in the order of the
/// bit masks 1 .. 2^p), `solve_subset` gives the coefficients of those columns (`None`: singular or infeasible),
/// the others are zero, and the coefficients with the smallest `ss_of` (the first on ties) win. Returns them
/// with their `ss_of`.
pub fn nnls_by_supports(
    p: usize,
    ss_of: impl Fn(&[f64]) -> f64,
    solve_subset: impl Fn(&[usize]) -> Option<Vec<f64>>,
) -> Option<(Vec<f64>, f64)> {
    let mut best: Option<(Vec<f64>, f64)> = None;
    for mask in 1u32..(1 << p) {
        let cols: Vec<usize> = (0..p).filter(|j| mask & (1 << j) != 0).collect();
        let Some(x) = solve_subset(&cols) else { continue };
        let mut c = vec![0.0; p];
        for (&j, &v) in cols.iter().zip(&x) {
            c[j] = v;
        }
        let ss = ss_of(&c);
        if best.as_ref().is_none_or(|b| ss < b.1) {
            best = Some((c, ss));
        }
    }
    best
}

/// Unconstrained least squares on the columns `cols` of the rows, by Householder QR with the columns
/// scaled to unit norm. `None` if rank-deficient.
pub fn least_squares_subset(rows: &[([f64; 5], f64)], cols: &[usize]) -> Option<Vec<f64>> {
    let (m, p) = (rows.len(), cols.len());
    if m < p {
        return None;
    }
    let mut a: Vec<Vec<f64>> = (0..p).map(|j| rows.iter().map(|r| r.0[cols[j]]).collect()).collect();
    let mut y: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let mut scale = vec![0.0; p];
    for j in 0..p {
        let norm = a[j].iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        scale[j] = norm;
        a[j].iter_mut().for_each(|v| *v /= norm);
    }
    // Householder QR, column-major a[j][i].
    let mut rdiag = vec![0.0; p];
    for k in 0..p {
        let norm = a[k][k..].iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm < 1e-12 {
            return None;
        }
        let alpha = if a[k][k] > 0.0 { -norm } else { norm };
        let mut v: Vec<f64> = a[k][k..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|x| x * x).sum();
        if vnorm2 > 0.0 {
            for j in k..p {
                let d: f64 = v.iter().zip(&a[j][k..]).map(|(v, x)| v * x).sum::<f64>() * 2.0 / vnorm2;
                a[j][k..].iter_mut().zip(&v).for_each(|(x, v)| *x -= d * v);
            }
            let d: f64 = v.iter().zip(&y[k..]).map(|(v, x)| v * x).sum::<f64>() * 2.0 / vnorm2;
            y[k..].iter_mut().zip(&v).for_each(|(x, v)| *x -= d * v);
        }
        rdiag[k] = a[k][k];
    }
    let mut x = vec![0.0; p];
    for k in (0..p).rev() {
        let s: f64 = ((k + 1)..p).map(|j| a[j][k] * x[j]).sum();
        x[k] = (y[k] - s) / rdiag[k];
    }
    Some(x.iter().zip(&scale).map(|(x, s)| x / s).collect())
}

/// The inverse of a 3 x 3 matrix by cofactors; `None` when the determinant is not finite or not above 1e-300 in
/// magnitude.
pub fn inverse3(a: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if !(det.is_finite() && det.abs() > 1e-300) {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (r0, r1) = ((j + 1) % 3, (j + 2) % 3);
            let (c0, c1) = ((i + 1) % 3, (i + 2) % 3);
            inv[i][j] = (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / det;
        }
    }
    Some(inv)
}

/// Solves the square system `a x = b` by Gaussian elimination with partial pivoting; `None` if singular (a pivot
/// not above 1e-300 in magnitude) or if the solution is not finite.
pub fn solve_square(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for k in 0..n {
        let p = (k..n).max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))?;
        if a[p][k].is_nan() || a[p][k].abs() <= 1e-300 {
            return None;
        }
        a.swap(k, p);
        b.swap(k, p);
        for i in (k + 1)..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = ((k + 1)..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / a[k][k];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Linear least squares min |X beta - y| by the normal equations, solved by [`solve_square`] (small,
/// well-conditioned designs; [`least_squares_subset`] is the QR alternative). `None` without rows, with fewer
/// rows than unknowns, or when the normal matrix is singular.
pub fn least_squares_normal(rows: &[Vec<f64>], y: &[f64]) -> Option<Vec<f64>> {
    let p = rows.first()?.len();
    if rows.len() < p {
        return None;
    }
    let mut ata = vec![vec![0.0; p]; p];
    let mut aty = vec![0.0; p];
    for (r, &yv) in rows.iter().zip(y) {
        for i in 0..p {
            aty[i] += r[i] * yv;
            for j in 0..p {
                ata[i][j] += r[i] * r[j];
            }
        }
    }
    solve_square(ata, aty)
}

/// Gauss-Newton with a numerical (central-difference) Jacobian and step halving: minimises sum r_k(p)^2 from
/// the start `p`. Stops after 100 steps, when a step is negligible (every component at most 1e-12 of its
/// parameter, or of 1e-6), or when no halving (30 at most) lowers the cost.
pub fn gauss_newton(mut p: Vec<f64>, residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> Vec<f64> {
    let cost = |p: &[f64]| residuals(p).iter().map(|r| r * r).sum::<f64>();
    let mut c = cost(&p);
    for _ in 0..100 {
        let r = residuals(&p);
        let jac = central_jacobian(&p, r.len(), residuals);
        let neg: Vec<f64> = r.iter().map(|v| -v).collect();
        let Some(step) = least_squares_normal(&jac, &neg) else { break };
        let Some((q, cq, small)) = halved_step(&p, &step, c, &cost) else { break };
        let improved = cq < c;
        p = q;
        c = cq;
        if small {
            return p;
        }
        if !improved {
            break;
        }
    }
    p
}

/// The Jacobian of `residuals` (`m` of them) at `p` by central differences, step 1e-6 of each parameter (or of
/// 1e-3 for small ones); row k, column j: d r_k / d p_j.
fn central_jacobian(p: &[f64], m: usize, residuals: &dyn Fn(&[f64]) -> Vec<f64>) -> Vec<Vec<f64>> {
    let n = p.len();
    let mut jac = vec![vec![0.0; n]; m];
    for j in 0..n {
        let h = 1e-6 * p[j].abs().max(1e-3);
        let mut a = p.to_vec();
        let mut b = p.to_vec();
        a[j] += h;
        b[j] -= h;
        let (ra, rb) = (residuals(&a), residuals(&b));
        for k in 0..m {
            jac[k][j] = (ra[k] - rb[k]) / (2.0 * h);
        }
    }
    jac
}

/// The first of `p + t step`, t = 1, 1/2, ... (30 tries), whose cost is at most `c`: the point, its cost, and
/// whether the step taken was negligible. `None` if no try is accepted.
fn halved_step(p: &[f64], step: &[f64], c: f64, cost: &dyn Fn(&[f64]) -> f64) -> Option<(Vec<f64>, f64, bool)> {
    let mut t = 1.0;
    for _ in 0..30 {
        let q: Vec<f64> = p.iter().zip(step).map(|(a, s)| a + t * s).collect();
        let cq = cost(&q);
        if cq <= c {
            let small = step.iter().zip(p).all(|(s, a)| (t * s).abs() <= 1e-12 * a.abs().max(1e-6));
            return Some((q, cq, small));
        }
        t *= 0.5;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse3_times_the_matrix_is_the_identity() {
        let a = [[2.0, 0.5, -1.0], [0.1, 3.0, 0.2], [-0.3, 0.4, 1.5]];
        let inv = inverse3(&a).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i][k] * inv[k][j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12, "{i} {j}: {p}");
            }
        }
        assert!(inverse3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]]).is_none());
    }

    #[test]
    fn normal_equations_are_exact_on_consistent_data() {
        let beta = [0.5, -2.0, 3.0];
        let rows: Vec<Vec<f64>> = (0..10).map(|k| vec![1.0, k as f64, (k * k) as f64 / 10.0]).collect();
        let y: Vec<f64> = rows.iter().map(|r| r.iter().zip(&beta).map(|(a, b)| a * b).sum()).collect();
        let x = least_squares_normal(&rows, &y).unwrap();
        for (x, b) in x.iter().zip(&beta) {
            assert!((x - b).abs() < 1e-10, "{x} vs {b}");
        }
        assert!(least_squares_normal(&rows[..2], &y[..2]).is_none(), "fewer rows than unknowns");
        assert!(solve_square(vec![vec![1.0, 2.0], vec![2.0, 4.0]], vec![1.0, 2.0]).is_none(), "singular");
    }

    #[test]
    fn gauss_newton_finds_the_centre_of_a_sphere() {
        let centre = [0.3, -0.2, 0.1];
        let points: Vec<[f64; 3]> =
            [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
                .iter()
                .map(|u| [0, 1, 2].map(|i| centre[i] + 9.8 * u[i]))
                .collect();
        let residuals = |p: &[f64]| -> Vec<f64> {
            points.iter().map(|m| (0..3).map(|i| (m[i] - p[i]).powi(2)).sum::<f64>().sqrt() - 9.8).collect()
        };
        let p = gauss_newton(vec![0.0; 3], &residuals);
        for (p, c) in p.iter().zip(&centre) {
            assert!((p - c).abs() < 1e-9, "{p} vs {c}");
        }
    }

    #[test]
    fn both_nnls_solvers_clip_a_negative_coefficient_and_agree() {
        // y = 2 x0 + 1 x2 - 0.5 x4 + noise-free: the best non-negative fit leaves x4 out.
        let rows5: Vec<([f64; 5], f64)> = (0..12)
            .map(|k| {
                let t = 1.0 + k as f64;
                let a = [1.0, t, t.sqrt(), t * t / 10.0, 1.0 / t];
                (a, 2.0 * a[0] + a[2] - 0.5 * a[4])
            })
            .collect();
        let qr = nnls_by_enumeration(&rows5).unwrap();
        let rows: Vec<Vec<f64>> = rows5.iter().map(|r| r.0.to_vec()).collect();
        let y: Vec<f64> = rows5.iter().map(|r| r.1).collect();
        let (normal, ss) = nnls_normal(&rows, &y).unwrap();
        assert_eq!(qr[4], 0.0);
        assert_eq!(normal[4], 0.0);
        assert!(qr.iter().all(|v| *v >= 0.0) && normal.iter().all(|v| *v >= 0.0));
        assert!(ss.is_finite() && ss > 0.0);
        for (a, b) in qr.iter().zip(&normal) {
            assert!((a - b).abs() < 1e-6 * (1.0 + a.abs()), "{qr:?} vs {normal:?}");
        }
    }
}
