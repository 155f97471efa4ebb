//! 3x3 matrices, row-major (`m[row][column]`): products, the determinant, the inverse, and the
//! 2-norm condition number. Colour matrices (DNG ColorMatrix, ForwardMatrix, XYZ <-> RGB) are
//! all 3x3; this is the one place their algebra is written.
//!
//! The arithmetic is spelled out term by term on purpose: every caller's outputs depend on
//! the exact order of the floating-point operations, and moving a product or an inverse here
//! must not change a bit.

/// A 3x3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// The identity matrix.
pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// The matrix of 9 row-major values (a DNG matrix tag), or `None` for another count.
pub fn from_row_major(v: &[f64]) -> Option<Mat3> {
    match v {
        [a, b, c, d, e, f, g, h, i] => Some([[*a, *b, *c], [*d, *e, *f], [*g, *h, *i]]),
        _ => None,
    }
}

/// Matrix product `a * b`.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// Matrix times column vector, `a * v`.
pub fn mul_vec(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    ]
}

/// The diagonal matrix of `v`.
pub fn diag(v: [f64; 3]) -> Mat3 {
    [[v[0], 0.0, 0.0], [0.0, v[1], 0.0], [0.0, 0.0, v[2]]]
}

/// The determinant (cofactor expansion along the first row).
pub fn determinant(m: &Mat3) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The inverse by the adjugate, given `det = determinant(m)`: each cofactor times `1 / det`.
/// No check: the caller has decided that `det` is large enough for its purpose (see
/// [`inverse`] for the checked form). A zero `det` gives infinities or NaNs.
pub fn inverse_with_determinant(m: &Mat3, det: f64) -> Mat3 {
    let inv = 1.0 / det;
    [
        [
            (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * inv,
            (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * inv,
            (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * inv,
        ],
        [
            (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * inv,
            (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * inv,
            (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * inv,
        ],
        [
            (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * inv,
            (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * inv,
            (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * inv,
        ],
    ]
}

/// Why [`inverse`] refused a matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NotInvertible {
    /// Zero (or not finite) determinant, or all entries zero.
    Singular,
    /// Not singular but ill-conditioned: the determinant relative to the largest entry
    /// cubed (`relative_determinant`) is below 1e-12 (e.g. diag(2^31, 1, 2^-31), whose
    /// determinant is 1).
    IllConditioned {
        /// `determinant / max|entry|^3`.
        relative_determinant: f64,
    },
}

/// The inverse, or why not: singular, not finite, or ill-conditioned (the determinant
/// below 1e-12 times the largest entry cubed; scale-free, so tiny well-conditioned matrices
/// are inverted).
pub fn inverse(m: &Mat3) -> Result<Mat3, NotInvertible> {
    let det = determinant(m);
    let scale = max_abs(m);
    if !det.is_finite() || scale == 0.0 || det == 0.0 {
        return Err(NotInvertible::Singular);
    }
    if det.abs() < 1e-12 * scale.powi(3) {
        return Err(NotInvertible::IllConditioned {
            relative_determinant: det / scale.powi(3),
        });
    }
    Ok(inverse_with_determinant(m, det))
}

fn max_abs(m: &Mat3) -> f64 {
    m.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()))
}

/// Singular values, largest first: square roots of the eigenvalues of `M^T M`, by cyclic
/// Jacobi rotations (exact to rounding for 3x3).
pub fn singular_values(m: &Mat3) -> [f64; 3] {
    // A = M^T M, symmetric positive semi-definite. Scale first so that huge or tiny entries
    // do not overflow or underflow the products.
    let scale = max_abs(m);
    if scale == 0.0 || !scale.is_finite() {
        return [scale, 0.0, 0.0];
    }
    let n: Vec<[f64; 3]> = m.iter().map(|r| r.map(|v| v / scale)).collect();
    let mut a = [[0.0f64; 3]; 3];
    for (i, row) in a.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| n[k][i] * n[k][j]).sum();
        }
    }
    for _ in 0..64 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off <= 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() <= 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in a.iter_mut() {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
        }
    }
    let mut s = [a[0][0], a[1][1], a[2][2]].map(|e| e.max(0.0).sqrt() * scale);
    s.sort_by(|x, y| y.total_cmp(x));
    s
}

/// 2-norm condition number (largest over smallest singular value; infinite when singular).
pub fn condition_number(m: &Mat3) -> f64 {
    let s = singular_values(m);
    if s[2] == 0.0 {
        f64::INFINITY
    } else {
        s[0] / s[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn frobenius(m: &Mat3) -> f64 {
        m.iter().flatten().map(|v| v * v).sum::<f64>().sqrt()
    }

    fn max_diff(a: &Mat3, b: &Mat3) -> f64 {
        (0..9).fold(0.0, |d, k| d.max((a[k / 3][k % 3] - b[k / 3][k % 3]).abs()))
    }

    #[test]
    fn known_products_and_inverse() {
        let m = [[2.0, 0.0, 1.0], [1.0, 3.0, 0.0], [0.0, 1.0, 4.0]];
        assert_eq!(determinant(&m), 25.0);
        assert_eq!(mul(&m, &IDENTITY), m);
        assert_eq!(mul_vec(&m, [1.0, 1.0, 1.0]), [3.0, 4.0, 5.0]);
        assert_eq!(mul(&diag([1.0, 2.0, 3.0]), &IDENTITY)[2][2], 3.0);
        let inv = inverse(&m).unwrap();
        assert!(max_diff(&mul(&m, &inv), &IDENTITY) < 1e-15);
        assert_eq!(inv[0][0], 12.0 / 25.0);
        assert_eq!(
            from_row_major(&[1., 2., 3., 4., 5., 6., 7., 8., 9.]).unwrap()[2][0],
            7.0
        );
        assert!(from_row_major(&[1.0; 8]).is_none());
    }

    #[test]
    fn singular_and_ill_conditioned_are_told_apart() {
        let rank2 = [[1., 2., 3.], [2., 4., 6.], [0., 0., 1.]];
        assert_eq!(inverse(&rank2), Err(NotInvertible::Singular));
        assert_eq!(inverse(&[[0.0; 3]; 3]), Err(NotInvertible::Singular));
        let nan = [[f64::NAN, 0., 0.], [0., 1., 0.], [0., 0., 1.]];
        assert_eq!(inverse(&nan), Err(NotInvertible::Singular));
        let t = 2f64.powi(31);
        let skew = diag([t, 1.0, 1.0 / t]);
        assert_eq!(determinant(&skew), 1.0);
        assert!(matches!(
            inverse(&skew),
            Err(NotInvertible::IllConditioned { .. })
        ));
        assert_eq!(condition_number(&skew), 2f64.powi(62));
        // Tiny but well conditioned: inverted.
        assert!(inverse(&diag([1e-5; 3])).is_ok());
        assert_eq!(condition_number(&rank2), f64::INFINITY);
    }

    proptest! {
        /// m * inverse(m) = I for every well-conditioned matrix, and inverting twice gives m.
        #[test]
        fn inverse_round_trips(v in proptest::array::uniform9(-10.0f64..10.0)) {
            let m = from_row_major(&v).unwrap();
            prop_assume!(condition_number(&m) < 1e6);
            let inv = inverse(&m).unwrap();
            let tol = 1e-9 * condition_number(&m);
            prop_assert!(max_diff(&mul(&m, &inv), &IDENTITY) < tol);
            prop_assert!(max_diff(&mul(&inv, &m), &IDENTITY) < tol);
            let back = inverse(&inv).unwrap();
            prop_assert!(max_diff(&back, &m) < tol * frobenius(&m).max(1.0));
        }

        /// The SVD-free bound: cond_2 <= ||M||_F ||M^-1||_F <= 3 cond_2.
        #[test]
        fn condition_number_within_the_frobenius_bound(v in proptest::array::uniform9(-10.0f64..10.0)) {
            let m = from_row_major(&v).unwrap();
            let d = determinant(&m);
            if d != 0.0 && d.is_finite() {
                let inv = inverse_with_determinant(&m, d);
                let cf = frobenius(&m) * frobenius(&inv);
                let c2 = condition_number(&m);
                prop_assume!(cf < 1e8);
                prop_assert!(c2 <= cf * (1.0 + 1e-9), "cond2 {} > condF {}", c2, cf);
                prop_assert!(cf <= 3.0 * c2 * (1.0 + 1e-9), "condF {} > 3 cond2 {}", cf, c2);
            }
        }

        /// Scaling a matrix changes neither its condition number nor the verdict.
        #[test]
        fn condition_is_scale_free(v in proptest::array::uniform9(-10.0f64..10.0), e in -6i32..6) {
            let k = 10f64.powi(e);
            let m = from_row_major(&v).unwrap();
            let mk = m.map(|r| r.map(|x| x * k));
            let (a, b) = (condition_number(&m), condition_number(&mk));
            prop_assert!(a == b || (a - b).abs() <= 1e-6 * a.max(b));
        }
    }
}
