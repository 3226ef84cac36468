//! Fixed-size f32 vectors and 3x3 matrices: just what the alignment and the bias solution need.
//!
//! A [`Vec3`] carries no frame or unit by itself; every variable that holds one says both in its name
//! (`force_b_mps2`, `phi_n_rad`). A [`Mat3`] is row-major: `m.0[row][col]`.

/// A 3-vector. The frame and unit are in the name of the variable that holds it.
pub type Vec3 = [f32; 3];

/// Dot product.
#[inline]
pub fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product `a x b` (right-handed).
#[inline]
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Euclidean norm.
#[inline]
pub fn norm(a: Vec3) -> f32 {
    libm::sqrtf(dot(a, a))
}

/// `s * a`.
#[inline]
pub fn scale(a: Vec3, s: f32) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// A 3x3 matrix, row-major (`m.0[row][col]`). Direction cosine matrices are named `c_b_n`
/// (transforms body-frame components into navigation-frame components: `v_n = c_b_n * v_b`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mat3(pub [[f32; 3]; 3]);

impl Mat3 {
    /// The identity.
    pub const IDENTITY: Mat3 = Mat3([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);

    /// The matrix whose columns are `a`, `b`, `c`.
    pub fn from_cols(a: Vec3, b: Vec3, c: Vec3) -> Mat3 {
        Mat3([[a[0], b[0], c[0]], [a[1], b[1], c[1]], [a[2], b[2], c[2]]])
    }

    /// The matrix whose rows are `a`, `b`, `c`.
    pub fn from_rows(a: Vec3, b: Vec3, c: Vec3) -> Mat3 {
        Mat3([a, b, c])
    }

    /// Row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> Vec3 {
        self.0[i]
    }

    /// Column `j`.
    #[inline]
    pub fn col(&self, j: usize) -> Vec3 {
        [self.0[0][j], self.0[1][j], self.0[2][j]]
    }

    /// Transpose (for a direction cosine matrix: the inverse, `c_n_b = c_b_n.transpose()`).
    pub fn transpose(&self) -> Mat3 {
        Mat3::from_cols(self.0[0], self.0[1], self.0[2])
    }

    /// Matrix product `self * rhs`.
    pub fn mul(&self, rhs: &Mat3) -> Mat3 {
        let mut out = [[0.0f32; 3]; 3];
        for (i, row) in out.iter_mut().enumerate() {
            for (j, cell) in row.iter_mut().enumerate() {
                *cell = dot(self.0[i], rhs.col(j));
            }
        }
        Mat3(out)
    }

    /// Matrix-vector product `self * v`.
    pub fn mul_vec(&self, v: Vec3) -> Vec3 {
        [dot(self.0[0], v), dot(self.0[1], v), dot(self.0[2], v)]
    }

    /// Determinant (the triple product of the columns).
    pub fn det(&self) -> f32 {
        dot(self.col(0), cross(self.col(1), self.col(2)))
    }

    /// Inverse by the adjugate: the rows of `M^-1` are `(c1 x c2)/det`, `(c2 x c0)/det`, `(c0 x c1)/det`
    /// for the columns `c0, c1, c2` of `M`. `None` when the determinant is zero or not finite.
    pub fn inverse(&self) -> Option<Mat3> {
        let (c0, c1, c2) = (self.col(0), self.col(1), self.col(2));
        let r0 = cross(c1, c2);
        let det = dot(c0, r0);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_det = 1.0 / det;
        Some(Mat3::from_rows(scale(r0, inv_det), scale(cross(c2, c0), inv_det), scale(cross(c0, c1), inv_det)))
    }

    /// Elementwise finiteness.
    pub fn is_finite(&self) -> bool {
        self.0.iter().flatten().all(|x| x.is_finite())
    }
}

/// The skew-symmetric matrix `[v x]`, such that `[v x] w = v x w`.
pub fn skew(v: Vec3) -> Mat3 {
    Mat3([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
}

/// Right-handed rotation by the angle `|v|` about `v` (Rodrigues), f32.
pub fn rotation(v: Vec3) -> Mat3 {
    let t2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if t2 == 0.0 {
        return Mat3::IDENTITY;
    }
    let t = libm::sqrtf(t2);
    let k = [v[0] / t, v[1] / t, v[2] / t];
    let (s, c) = (libm::sinf(t), libm::cosf(t));
    let mut m = [[0.0f32; 3]; 3];
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            m[i][j] = id * c + s * kx[i][j] + (1.0 - c) * k[i] * k[j];
        }
    }
    Mat3(m)
}

/// The lower Cholesky factor of the leading `n` x `n` block (`n` at most 3) of a symmetric 3x3 matrix, or `None` when it is not
/// positive definite.
pub fn cholesky3(s: &[[f32; 3]; 3], n: usize) -> Option<[[f32; 3]; 3]> {
    let mut l = [[0.0f32; 3]; 3];
    for i in 0..n {
        for j in 0..=i {
            let mut v = s[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k];
            }
            if i == j {
                // NaN is refused too.
                if v.is_nan() || v <= 0.0 {
                    return None;
                }
                l[i][i] = libm::sqrtf(v);
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    Some(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_is_rodrigues() {
        let r = rotation([0.0, 0.0, core::f32::consts::FRAC_PI_2]);
        let x = r.mul_vec([1.0, 0.0, 0.0]);
        assert!((x[1] - 1.0).abs() < 1e-6 && x[0].abs() < 1e-6);
        assert_eq!(rotation([0.0; 3]), Mat3::IDENTITY);
    }

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m = Mat3([[2.0, -1.0, 0.5], [0.25, 3.0, -2.0], [1.0, 0.0, 4.0]]);
        let p = m.mul(&m.inverse().unwrap());
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((p.0[i][j] - want).abs() < 1e-6, "{p:?}");
            }
        }
    }

    #[test]
    fn singular_matrix_has_no_inverse() {
        let m = Mat3::from_cols([1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 0.0]);
        assert!(m.inverse().is_none());
    }

    #[test]
    fn skew_matches_cross_product() {
        let (v, w) = ([0.3, -1.2, 2.0], [-0.7, 0.4, 1.1]);
        assert_eq!(skew(v).mul_vec(w), cross(v, w));
    }
}
