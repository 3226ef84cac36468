//! Least squares in square-root information form, f32, fixed size, no allocation.
//!
//! The normal equations square the condition number of a design (f32 then keeps half its digits); the
//! square-root form keeps it. Rows are folded one at a time into an upper-triangular `R` and a right-hand
//! side `z` by Givens rotations (Golub and Van Loan, Matrix Computations, 4th ed., section 5.1.8), so
//! that `||A x - y||^2 = ||R x - z||^2 + rss` for every `x` without ever holding `A`. Memory: `N (N + 1)`
//! floats, whatever the number of rows. Cost per row: about `2 N^2` multiplications in the worst case
//! (fewer for rows with leading zeros).
//!
//! A one-sided Jacobi singular value decomposition ([`jacobi_svd`], Hestenes' method; Demmel and Veselic,
//! SIAM J. Matrix Anal. Appl. 13 (1992)) of `R` gives the rank and the null directions to the relative
//! accuracy of f32, which the eigenvalues of `R^T R` would not.

/// Rows folded into an upper-triangular factor: `A^T A = R^T R`, `A^T y = R^T z`.
#[derive(Clone, Debug, PartialEq)]
pub struct SqrtInfo<const N: usize> {
    /// Upper-triangular factor (entries below the diagonal are zero).
    pub r: [[f32; N]; N],
    /// Transformed right-hand side.
    pub z: [f32; N],
    /// Sum of squares of the part of the right-hand side no column can explain.
    pub rss: f32,
    /// Columns in use (`<= N`).
    pub n: usize,
}

impl<const N: usize> SqrtInfo<N> {
    /// An empty factor of `n` columns (`n` is clamped to `N`).
    pub fn new(n: usize) -> SqrtInfo<N> {
        SqrtInfo { r: [[0.0; N]; N], z: [0.0; N], rss: 0.0, n: n.min(N) }
    }

    /// Folds in the row `a` (first `n` entries used) with right-hand side `y`.
    pub fn add_row(&mut self, a: &[f32; N], y: f32) {
        let mut x = *a;
        let mut rhs = y;
        for i in 0..self.n {
            if x[i] == 0.0 {
                continue;
            }
            let rii = self.r[i][i];
            let h = libm::hypotf(rii, x[i]);
            let (c, s) = (rii / h, x[i] / h);
            self.r[i][i] = h;
            x[i] = 0.0;
            for j in (i + 1)..self.n {
                let (rij, xj) = (self.r[i][j], x[j]);
                self.r[i][j] = c * rij + s * xj;
                x[j] = c * xj - s * rij;
            }
            let zi = self.z[i];
            self.z[i] = c * zi + s * rhs;
            rhs = c * rhs - s * zi;
        }
        self.rss += rhs * rhs;
    }
}

/// Solves `R x = z` for upper-triangular `R` of `n` columns. A zero diagonal gives a zero component.
pub fn solve_upper<const N: usize>(r: &[[f32; N]; N], z: &[f32; N], n: usize) -> [f32; N] {
    let mut x = [0.0f32; N];
    for i in (0..n.min(N)).rev() {
        let mut s = z[i];
        for j in (i + 1)..n {
            s -= r[i][j] * x[j];
        }
        x[i] = if r[i][i] != 0.0 { s / r[i][i] } else { 0.0 };
    }
    x
}

/// Solves `R^T x = b` for upper-triangular `R` of `n` columns (forward substitution).
pub fn solve_upper_transposed<const N: usize>(r: &[[f32; N]; N], b: &[f32; N], n: usize) -> [f32; N] {
    let mut x = [0.0f32; N];
    for i in 0..n.min(N) {
        let mut s = b[i];
        for k in 0..i {
            s -= r[k][i] * x[k];
        }
        x[i] = if r[i][i] != 0.0 { s / r[i][i] } else { 0.0 };
    }
    x
}

/// `(R^T R)^-1` for upper-triangular invertible `R` of `n` columns, written into `out`.
pub fn inverse_gram<const N: usize>(r: &[[f32; N]; N], n: usize, out: &mut [[f32; N]; N]) {
    // Columns of R^-1 one at a time: R^-1 e_j, then out = R^-1 R^-T.
    let mut rinv = [[0.0f32; N]; N];
    for j in 0..n {
        let mut e = [0.0f32; N];
        e[j] = 1.0;
        let col = solve_upper(r, &e, n);
        for i in 0..n {
            rinv[i][j] = col[i];
        }
    }
    for i in 0..n {
        for j in 0..n {
            let mut s = 0.0f32;
            for (k, rk) in rinv[i].iter().enumerate().take(n).skip(i.max(j)) {
                s += rk * rinv[j][k];
            }
            out[i][j] = s;
        }
    }
}

/// One-sided Jacobi SVD of the `n` leading columns of `a` (`n x n`): on return the columns of `a` are
/// `U Sigma` (mutually orthogonal), `v` holds `V`, and the singular values (column norms) are returned.
pub fn jacobi_svd<const N: usize>(a: &mut [[f32; N]; N], v: &mut [[f32; N]; N], n: usize) -> [f32; N] {
    let n = n.min(N);
    for (i, row) in v.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = if i == j { 1.0 } else { 0.0 };
        }
    }
    for _sweep in 0..40 {
        let mut rotated = false;
        for p in 0..n {
            for q in (p + 1)..n {
                let (mut alpha, mut beta, mut gamma) = (0.0f32, 0.0f32, 0.0f32);
                for row in a.iter().take(n) {
                    alpha += row[p] * row[p];
                    beta += row[q] * row[q];
                    gamma += row[p] * row[q];
                }
                if gamma == 0.0 || gamma.abs() <= 1e-7 * libm::sqrtf(alpha * beta) {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let sign = if zeta >= 0.0 { 1.0 } else { -1.0 };
                let t = sign / (zeta.abs() + libm::sqrtf(1.0 + zeta * zeta));
                let c = 1.0 / libm::sqrtf(1.0 + t * t);
                let s = c * t;
                for row in a.iter_mut().take(n) {
                    let (ap, aq) = (row[p], row[q]);
                    row[p] = c * ap - s * aq;
                    row[q] = s * ap + c * aq;
                }
                for row in v.iter_mut().take(n) {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
        if !rotated {
            break;
        }
    }
    let mut sigma = [0.0f32; N];
    for (j, s) in sigma.iter_mut().enumerate().take(n) {
        let mut sum = 0.0f32;
        for row in a.iter().take(n) {
            sum += row[j] * row[j];
        }
        *s = libm::sqrtf(sum);
    }
    sigma
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn givens_solves_an_overdetermined_system() {
        // y = 2 + 3 t at t = 0..5, plus one residual row.
        let mut s = SqrtInfo::<3>::new(2);
        for t in 0..6 {
            s.add_row(&[1.0, t as f32, 0.0], 2.0 + 3.0 * t as f32);
        }
        s.add_row(&[1.0, 0.0, 0.0], 3.0);
        let x = solve_upper(&s.r, &s.z, 2);
        // Least squares with the extra row: residuals must be orthogonal to the columns.
        let mut g = [0.0f32; 2];
        let rows: [(f32, f32, f32); 7] = [
            (1.0, 0.0, 2.0),
            (1.0, 1.0, 5.0),
            (1.0, 2.0, 8.0),
            (1.0, 3.0, 11.0),
            (1.0, 4.0, 14.0),
            (1.0, 5.0, 17.0),
            (1.0, 0.0, 3.0),
        ];
        let mut rss = 0.0;
        for (a, b, y) in rows {
            let r = y - a * x[0] - b * x[1];
            g[0] += a * r;
            g[1] += b * r;
            rss += r * r;
        }
        assert!(g[0].abs() < 1e-4 && g[1].abs() < 1e-4, "{g:?}");
        assert!((s.rss - rss).abs() < 1e-4, "{} vs {rss}", s.rss);
    }

    #[test]
    fn svd_finds_a_null_direction() {
        // Columns 0 and 1 are equal: one zero singular value, null vector (1, -1, 0)/sqrt 2.
        let mut a = [[1.0f32, 1.0, 0.0], [2.0, 2.0, 1.0], [0.0, 0.0, 3.0]];
        let mut v = [[0.0f32; 3]; 3];
        let s = jacobi_svd(&mut a, &mut v, 3);
        let k = (0..3).min_by(|&i, &j| s[i].total_cmp(&s[j])).unwrap_or(0);
        assert!(s[k] < 1e-6, "{s:?}");
        assert!((v[0][k].abs() - core::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
        assert!((v[0][k] + v[1][k]).abs() < 1e-6 && v[2][k].abs() < 1e-6);
    }

    #[test]
    fn inverse_gram_inverts() {
        let r = [[2.0f32, 1.0], [0.0, 4.0]];
        let mut p = [[0.0f32; 2]; 2];
        inverse_gram(&r, 2, &mut p);
        // R^T R = [[4, 2], [2, 17]]; its inverse = [[17, -2], [-2, 4]] / 64.
        let expect = [[17.0 / 64.0, -2.0 / 64.0], [-2.0 / 64.0, 4.0 / 64.0]];
        for i in 0..2 {
            for j in 0..2 {
                assert!((p[i][j] - expect[i][j]).abs() < 1e-7, "{p:?}");
            }
        }
        let x = solve_upper_transposed(&r, &[2.0, 9.0], 2);
        assert!((x[0] - 1.0).abs() < 1e-7 && (x[1] - 2.0).abs() < 1e-7, "{x:?}");
    }
}
