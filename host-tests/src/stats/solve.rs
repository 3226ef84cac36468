//! The f64 solvers of the host, in one place: symmetric positive definite systems (Cholesky after
//! equilibration), least squares by Householder QR, and non-negative least squares by enumerating the
//! supports. Small dense problems (tens of unknowns): clarity over speed.

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
pub fn nnls_by_enumeration(rows: &[([f64; 5], f64)]) -> Option<[f64; 5]> {
    let mut best: Option<([f64; 5], f64)> = None;
    for mask in 1u32..32 {
        let cols: Vec<usize> = (0..5).filter(|j| mask & (1 << j) != 0).collect();
        let Some(x) = least_squares_subset(rows, &cols) else { continue };
        if x.iter().any(|&v| v < 0.0 || !v.is_finite()) {
            continue;
        }
        let mut c = [0.0; 5];
        for (&j, &v) in cols.iter().zip(&x) {
            c[j] = v;
        }
        let ss: f64 = rows
            .iter()
            .map(|(a, y)| {
                let r = a.iter().zip(&c).map(|(a, c)| a * c).sum::<f64>() - y;
                r * r
            })
            .sum();
        if best.as_ref().is_none_or(|b| ss < b.1) {
            best = Some((c, ss));
        }
    }
    best.map(|b| b.0)
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
