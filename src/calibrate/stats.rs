//! Small numerical helpers shared by the calibration commands: robust means and a weighted
//! straight-line least-squares fit with standard errors and goodness of fit.

use crate::error::{Error, Result};

/// Symmetric trimmed mean: sorts `v` and averages after dropping `trim` (0..0.5) of the
/// samples at each end. Robust to outliers (dust, specular spots) without the 1-DN
/// quantization of a median of integer data. `None` for an empty slice.
pub fn trimmed_mean(v: &mut [f64], trim: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let k = ((v.len() as f64) * trim.clamp(0.0, 0.49)).floor() as usize;
    let kept = &v[k..v.len() - k];
    Some(kept.iter().sum::<f64>() / kept.len() as f64)
}

/// Result of a weighted least-squares line fit `y = slope * x + intercept`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineFit {
    /// Fitted slope.
    pub slope: f64,
    /// Fitted intercept.
    pub intercept: f64,
    /// Standard error of the slope (weights taken as inverse variances).
    pub slope_se: f64,
    /// Standard error of the intercept.
    pub intercept_se: f64,
    /// Weighted coefficient of determination.
    pub r2: f64,
    /// Weighted sum of squared residuals (chi-square when weights are 1/variance).
    pub chi2: f64,
    /// Degrees of freedom of the residuals (points - 2).
    pub dof: usize,
}

/// Weighted least squares of `y = a x + b` (weights = inverse variances of `y`).
/// Errors when fewer than two points have positive weight or all `x` coincide.
pub fn wls_line(x: &[f64], y: &[f64], w: &[f64]) -> Result<LineFit> {
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut n = 0usize;
    for ((&xi, &yi), &wi) in x.iter().zip(y).zip(w) {
        if !(wi > 0.0 && wi.is_finite() && xi.is_finite() && yi.is_finite()) {
            continue;
        }
        n += 1;
        sw += wi;
        sx += wi * xi;
        sy += wi * yi;
        sxx += wi * xi * xi;
        sxy += wi * xi * yi;
    }
    if n < 2 {
        return Err(Error::invalid(format!(
            "a line fit needs at least 2 usable points, got {n}"
        )));
    }
    // Centre for numerical stability.
    let xm = sx / sw;
    let ym = sy / sw;
    let cxx = sxx - sw * xm * xm;
    let cxy = sxy - sw * xm * ym;
    if cxx <= 1e-300 * sw.max(1.0) {
        return Err(Error::invalid(
            "a line fit needs points at two or more different x values",
        ));
    }
    let slope = cxy / cxx;
    let intercept = ym - slope * xm;
    let (mut chi2, mut tot) = (0.0, 0.0);
    for ((&xi, &yi), &wi) in x.iter().zip(y).zip(w) {
        if !(wi > 0.0 && wi.is_finite() && xi.is_finite() && yi.is_finite()) {
            continue;
        }
        let r = yi - slope * xi - intercept;
        chi2 += wi * r * r;
        tot += wi * (yi - ym) * (yi - ym);
    }
    let r2 = if tot > 0.0 { 1.0 - chi2 / tot } else { 1.0 };
    Ok(LineFit {
        slope,
        intercept,
        slope_se: (1.0 / cxx).sqrt(),
        intercept_se: (1.0 / sw + xm * xm / cxx).sqrt(),
        r2,
        chi2,
        dof: n - 2,
    })
}

/// Ordinary least squares of `y = c x` through the origin; `None` when all x are 0.
pub fn ls_through_origin(x: &[f64], y: &[f64]) -> Option<f64> {
    let sxx: f64 = x.iter().map(|v| v * v).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| a * b).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trimmed_mean_ignores_outliers() {
        let mut v: Vec<f64> = (0..100).map(|i| 10.0 + (i % 5) as f64).collect();
        v[3] = 1e6;
        v[7] = -1e6;
        let m = trimmed_mean(&mut v, 0.1).unwrap();
        assert!((m - 12.0).abs() < 0.2, "{m}");
        assert!(trimmed_mean(&mut [], 0.1).is_none());
    }

    #[test]
    fn wls_exact_line_and_errors() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y = [1.0, 3.0, 5.0, 7.0];
        let f = wls_line(&x, &y, &[1.0, 2.0, 1.0, 5.0]).unwrap();
        assert!((f.slope - 2.0).abs() < 1e-12 && (f.intercept - 1.0).abs() < 1e-12);
        assert!((f.r2 - 1.0).abs() < 1e-12 && f.chi2 < 1e-20 && f.dof == 2);
        assert!(wls_line(&[1.0, 1.0], &[1.0, 2.0], &[1.0, 1.0]).is_err());
        assert!(wls_line(&[1.0], &[1.0], &[1.0]).is_err());
        assert_eq!(ls_through_origin(&[1.0, 2.0], &[2.0, 4.0]), Some(2.0));
    }

    #[test]
    fn wls_matches_closed_form_standard_errors() {
        // Unit weights: SE(slope) = sqrt(1 / Sxx) for known unit variance.
        let x = [0.0, 1.0, 2.0];
        let f = wls_line(&x, &[0.0, 1.0, 2.0], &[1.0; 3]).unwrap();
        assert!((f.slope_se - (0.5f64).sqrt()).abs() < 1e-12);
        assert!((f.intercept_se - (1.0 / 3.0 + 1.0 / 2.0f64).sqrt()).abs() < 1e-12);
    }
}
