//! Correlated colour temperature (CCT) the way the DNG SDK computes it: Robertson's 1968
//! isotemperature lines (`dng_temperature`), and the temperatures the SDK assigns to the EXIF
//! LightSource codes of CalibrationIlluminant1/2. These pick and interpolate a camera's
//! colour matrices; [`super::planck`] measures light colours (CCT and Duv from the locus).
//! [`release_xyz_to_cct`] is the authors' release's own walk along the same lines (its
//! target ISP, docs/isp.md).

/// Correlated colour temperature (kelvin) of an EXIF LightSource code, as the DNG SDK
/// assigns them; `None` for unknown/other codes.
pub fn light_source_temperature(code: u16) -> Option<f64> {
    Some(match code {
        17 | 3 => 2850.0,              // Standard light A, Tungsten
        24 => 3200.0,                  // ISO studio tungsten
        23 => 5000.0,                  // D50
        20 | 1 | 9 | 4 | 18 => 5500.0, // D55, Daylight, Fine weather, Flash, Standard B
        21 | 19 | 10 => 6500.0,        // D65, Standard C, Cloudy
        22 | 11 => 7500.0,             // D75, Shade
        12 => 6430.0,                  // Daylight fluorescent (D 5700-7100K)
        13 => 5000.0,                  // Day white fluorescent (N 4600-5500K)
        14 | 2 => 4150.0,              // Cool white fluorescent (W 3800-4500K), Fluorescent
        15 => 3450.0,                  // White fluorescent (WW 3250-3800K)
        16 => 2940.0,                  // Warm white fluorescent (L 2600-3250K)
        _ => return None,
    })
}

/// Robertson (1968) isotemperature lines: (mired, u, v, slope), CIE 1960 UCS.
const ROBERTSON: [[f64; 4]; 31] = [
    [0.0, 0.18006, 0.26352, -0.24341],
    [10.0, 0.18066, 0.26589, -0.25479],
    [20.0, 0.18133, 0.26846, -0.26876],
    [30.0, 0.18208, 0.27119, -0.28539],
    [40.0, 0.18293, 0.27407, -0.30470],
    [50.0, 0.18388, 0.27709, -0.32675],
    [60.0, 0.18494, 0.28021, -0.35156],
    [70.0, 0.18611, 0.28342, -0.37915],
    [80.0, 0.18740, 0.28668, -0.40955],
    [90.0, 0.18880, 0.28997, -0.44278],
    [100.0, 0.19032, 0.29326, -0.47888],
    [125.0, 0.19462, 0.30141, -0.58204],
    [150.0, 0.19962, 0.30921, -0.70471],
    [175.0, 0.20525, 0.31647, -0.84901],
    [200.0, 0.21142, 0.32312, -1.0182],
    [225.0, 0.21807, 0.32909, -1.2168],
    [250.0, 0.22511, 0.33439, -1.4512],
    [275.0, 0.23247, 0.33904, -1.7298],
    [300.0, 0.24010, 0.34308, -2.0637],
    [325.0, 0.24792, 0.34655, -2.4681],
    [350.0, 0.25591, 0.34951, -2.9641],
    [375.0, 0.26400, 0.35200, -3.5814],
    [400.0, 0.27218, 0.35407, -4.3633],
    [425.0, 0.28039, 0.35577, -5.3762],
    [450.0, 0.28863, 0.35714, -6.7262],
    [475.0, 0.29685, 0.35823, -8.5955],
    [500.0, 0.30505, 0.35907, -11.324],
    [525.0, 0.31320, 0.35968, -15.628],
    [550.0, 0.32129, 0.36011, -23.325],
    [575.0, 0.32931, 0.36038, -40.770],
    [600.0, 0.33724, 0.36051, -116.45],
];

/// Correlated colour temperature of an xy chromaticity (Robertson's method, as in the DNG
/// SDK's `dng_temperature`), clamped to [1e6 / 600, 1e9] kelvin.
pub fn xy_to_cct(xy: [f64; 2]) -> f64 {
    let den = 1.5 - xy[0] + 6.0 * xy[1];
    let (u, v) = (2.0 * xy[0] / den, 3.0 * xy[1] / den);
    let (mut last_dt, mut last_du, mut last_dv) = (0.0, 0.0, 0.0);
    for index in 1..ROBERTSON.len() {
        let [_, tu, tv, slope] = ROBERTSON[index];
        let len = (1.0 + slope * slope).sqrt();
        let (du, dv) = (1.0 / len, slope / len);
        let dt = -(u - tu) * dv + (v - tv) * du;
        if dt <= 0.0 || index == ROBERTSON.len() - 1 {
            let dt = -dt.min(0.0);
            let f = if index == 1 { 0.0 } else { dt / (last_dt + dt) };
            let mired = ROBERTSON[index - 1][0] * f + ROBERTSON[index][0] * (1.0 - f);
            let _ = (last_du, last_dv);
            return 1.0e6 / mired.max(1e-3);
        }
        (last_dt, last_du, last_dv) = (dt, du, dv);
    }
    5000.0
}

/// Reciprocal temperatures (1/K) of the [`ROBERTSON`] lines as the authors' release lists
/// them (its first is the smallest positive double instead of 0).
const RELEASE_RECIPROCAL_K: [f64; 31] = [
    f64::MIN_POSITIVE,
    10.0e-6,
    20.0e-6,
    30.0e-6,
    40.0e-6,
    50.0e-6,
    60.0e-6,
    70.0e-6,
    80.0e-6,
    90.0e-6,
    100.0e-6,
    125.0e-6,
    150.0e-6,
    175.0e-6,
    200.0e-6,
    225.0e-6,
    250.0e-6,
    275.0e-6,
    300.0e-6,
    325.0e-6,
    350.0e-6,
    375.0e-6,
    400.0e-6,
    425.0e-6,
    450.0e-6,
    475.0e-6,
    500.0e-6,
    525.0e-6,
    550.0e-6,
    575.0e-6,
    600.0e-6,
];

/// Correlated colour temperature of an XYZ triple as the authors' release computes it (the
/// `XYZtoCCT` of Lindbloom's C code on the same Robertson lines, in its own arithmetic): the
/// signed distances to the lines are walked until they change sign; when they never do, the
/// last two lines are used anyway (an extrapolation). `None` for XYZ all below 1e-20 (the
/// release's -1).
pub fn release_xyz_to_cct(xyz: [f64; 3]) -> Option<f64> {
    if xyz.iter().all(|v| *v < 1.0e-20) {
        return None;
    }
    let den = xyz[0] + 15.0 * xyz[1] + 3.0 * xyz[2];
    let us = (4.0 * xyz[0]) / den;
    let vs = (6.0 * xyz[1]) / den;
    let (mut di, mut dm) = (0.0, 0.0);
    let mut i = 0;
    while i < ROBERTSON.len() {
        let [_, u, v, t] = ROBERTSON[i];
        di = (vs - v) - t * (us - u);
        if i > 0 && ((di < 0.0 && dm >= 0.0) || (di >= 0.0 && dm < 0.0)) {
            break;
        }
        dm = di;
        i += 1;
    }
    // A walk with no sign change leaves the last line (the release's loop variable).
    let i = i.min(ROBERTSON.len() - 1).max(1);
    let di = di / (1.0 + ROBERTSON[i][3] * ROBERTSON[i][3]).sqrt();
    let dm = dm / (1.0 + ROBERTSON[i - 1][3] * ROBERTSON[i - 1][3]).sqrt();
    let p = dm / (dm - di);
    let (a, b) = (RELEASE_RECIPROCAL_K[i - 1], RELEASE_RECIPROCAL_K[i]);
    Some(1.0 / ((b - a) * p + a))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::xyz::{D50_XY, D65_XY};

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn cct_of_standard_whites() {
        // D65 ~ 6504 K, D50 ~ 5003 K, illuminant A (0.44757, 0.40745) ~ 2856 K.
        assert!(
            close(xy_to_cct(D65_XY), 6504.0, 5.0),
            "{}",
            xy_to_cct(D65_XY)
        );
        assert!(
            close(xy_to_cct(D50_XY), 5003.0, 5.0),
            "{}",
            xy_to_cct(D50_XY)
        );
        assert!(close(xy_to_cct([0.44757, 0.40745]), 2856.0, 5.0));
        assert!(xy_to_cct([0.25, 0.25]).is_finite());
        assert!(xy_to_cct([0.6, 0.35]).is_finite());
    }

    #[test]
    fn light_sources() {
        assert_eq!(light_source_temperature(21), Some(6500.0));
        assert_eq!(light_source_temperature(17), Some(2850.0));
        assert_eq!(light_source_temperature(255), None);
    }

    #[test]
    fn cct_falls_as_the_white_warms() {
        // Along the Planckian locus, Robertson's CCT follows the locus temperature.
        let mut last = f64::INFINITY;
        for t in [12000.0, 8000.0, 6500.0, 5000.0, 4000.0, 3000.0, 2000.0] {
            let c = xy_to_cct(crate::color::planck::planck_xy(t));
            assert!(c < last && close(c, t, 0.01 * t), "{t}: {c}");
            last = c;
        }
    }

    #[test]
    fn release_cct_of_standard_whites() {
        // D65 and illuminant A as XYZ with Y = 1: within a few kelvin of their CCTs.
        let xyz = |xy: [f64; 2]| [xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]];
        let d65 = release_xyz_to_cct(xyz(D65_XY)).unwrap();
        assert!(close(d65, 6504.0, 5.0), "{d65}");
        let a = release_xyz_to_cct(xyz([0.44757, 0.40745])).unwrap();
        assert!(close(a, 2856.0, 5.0), "{a}");
        assert_eq!(release_xyz_to_cct([0.0; 3]), None);
        // Far beyond the last line (bluer than any): extrapolated, still finite.
        assert!(release_xyz_to_cct([0.2, 0.1, 2.0]).unwrap().is_finite());
    }
}
