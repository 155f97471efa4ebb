//! The one table of value bounds: every range a number read from a file or an option must
//! lie in (ISOs, noise parameters, neutrals and illuminant ratios, gains, colour-matrix
//! conditioning, NoiseProfile entries, calibration files), with why each value, and the small
//! check helpers that turn a violation into an error naming the field and the value in short
//! number form (`ColorMatrix1 [...] is ill-conditioned: condition number 4.61169e18 is
//! above 10000`).
//!
//! Everything that samples such a value (the synthesis planner, the CLI's option parsing) and
//! everything that reads one back (the sidecar reader of `synth --replay`, the calibration-file
//! readers, the DNG metadata checks of [`crate::dng::check`]) uses these constants, so a
//! sampled plan always passes the replay check. Resource limits (pixels, allocations) are in
//! [`crate::limits`]. The rules are listed in docs/limits.md ("Value bounds").

use crate::color::matrix3::{condition_number, determinant, from_row_major};
use crate::color::xyz::{xy_to_xyz, D50_XY};
use crate::error::{Error, Result};

// ---------------------------------------------------------------------------------------
// ISO and noise.

/// ISO range accepted everywhere (`--iso`, Exif ISO, noise models, sidecars): the highest ISO
/// of any camera sold is 3,280,000 (Nikon D5, Hi 5).
pub const ISO_RANGE: (u32, u32) = (1, 4_000_000);
/// Most noisy outputs (ISOs) per plan, and the most ISOs `--iso` takes.
pub const MAX_NOISE_ENTRIES: usize = 64;
/// Most ISO points in a noise model file.
pub const MAX_ISO_POINTS: usize = 1000;
/// Largest magnitude of a Gaussian noise parameter S or O (variance of the normalized
/// signal): a variance of 1e3 is already 30 times the full signal range as a standard
/// deviation.
pub const MAX_NOISE_PARAM: f64 = 1e3;
/// Largest DNG NoiseProfile entry S or O (variance of the normalized signal at full scale):
/// above 1 the noise standard deviation at white exceeds the whole signal range. Real
/// cameras: S about 1e-5..1e-2, O about 1e-9..1e-3.
pub const MAX_NOISE_PROFILE: f64 = 1.0;
/// Physics noise model: DN per electron K (a sensor with 1e6 DN per electron or 1e6
/// electrons per DN does not exist).
pub const K_RANGE: (f64, f64) = (1e-6, 1e6);
/// Physics noise model: largest read or row noise sigma, in DN (the full 16-bit range).
pub const MAX_SIGMA_DN: f64 = 65535.0;

// ---------------------------------------------------------------------------------------
// Colour.

/// A neutral (AsShotNeutral, `--day-neutral`) or an illuminant of a calibration file may have
/// no channel more than this many times above or below green: a white-balance gain of 1000
/// is beyond any real light or sensor (tungsten on a phone sensor: about 3).
pub const MAX_NEUTRAL_RATIO: f64 = 1e3;
/// Illuminants and neutrals of a plan (channel / green) lie within `[1/MAX_RATIO, MAX_RATIO]`:
/// [`MAX_NEUTRAL_RATIO`] squared, since a night neutral is a day neutral times an
/// illuminant ratio.
pub const MAX_RATIO: f64 = MAX_NEUTRAL_RATIO * MAX_NEUTRAL_RATIO;
/// Gaussian illuminant files: mean and covariance entries within +-this (chromaticity
/// ratios; [`MAX_NEUTRAL_RATIO`] bounds the ratios themselves).
pub const MAX_CHROMA: f64 = MAX_NEUTRAL_RATIO;
/// Largest condition number (2-norm) of a ColorMatrix or CameraCalibration. The Adobe DNG SDK
/// normalizes a ColorMatrix (D50 maps to at most 1) and rounds it to 4 decimals before
/// inverting it, so beyond about 2e4 its smallest direction rounds away and the SDK refuses
/// the file ("ColorMatrix1 is not invertible"); camera matrices are below 100.
pub const MAX_MATRIX_CONDITION: f64 = 1e4;
/// The DNG SDK's own test after that normalization: |determinant| below this is "not
/// invertible" (dng_matrix.cpp, `kNearZero`).
pub const SDK_MIN_DETERMINANT: f64 = 1e-10;
/// Decimal places the DNG SDK rounds a normalized ColorMatrix to.
pub const SDK_MATRIX_ROUNDING: f64 = 1e4;
/// Each of x, y and z = 1 - x - y of a lamp in an xy illuminant dictionary is at least
/// this: a light with no X, Y or Z at all is not a lamp, and xy -> XYZ divides by y.
pub const MIN_XYZ_CHROMATICITY: f64 = 1e-3;
/// Largest weight of a lamp in an xy illuminant dictionary (a count of gray cards, like
/// [`MAX_DICT_ENTRIES`]).
pub const MAX_LAMP_WEIGHT: f64 = 1e6;

/// The EXIF LightSource codes (EXIF 2.32 table; DNG CalibrationIlluminant1/2 use them):
/// 0 unknown, 1-4 daylight, fluorescent, tungsten, flash, 9-24 the named weathers, standard
/// lights and D50-D75, 255 other. A code outside it has no colour temperature: matrices
/// tagged with it are not interpolated (ColorMatrix1 alone is used).
pub const EXIF_LIGHT_SOURCES: [u16; 22] = [
    0, 1, 2, 3, 4, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 255,
];

// ---------------------------------------------------------------------------------------
// Lights and plans.

/// Largest gain or weight of a light (released bulbs: 50 to 100).
pub const MAX_GAIN: f64 = 1e6;
/// Sigmas, windows and centres are bounded by this many times the image's larger side.
pub const MAX_EXTENT_FACTOR: f64 = 100.0;
/// Most stages or warnings listed in a plan.
pub const MAX_LIST: usize = 1000;

// ---------------------------------------------------------------------------------------
// Integer arguments (the command line's flags and the Python package's arguments).

/// Master seed (`--seed`, Python `seed`): any 64-bit unsigned value (the random streams are
/// keyed by all of its bits).
pub const SEED_RANGE: (u64, u64) = (0, u64::MAX);
/// Variants per input (`--variants`): at least one. Python's 0-based `variant` is variant
/// `variant + 1` of `--variants variant + 1`, so it is at most `VARIANTS_RANGE.1 - 1`.
pub const VARIANTS_RANGE: (u32, u32) = (1, u32::MAX);
/// Most local lights and most bulbs (`--lights`, `--bulbs`): each costs a pass over its
/// window (the paper draws 4 to 6 lights, the release adds 5 bulbs).
pub const MAX_LIGHTS: u32 = 256;
/// EXR zip levels (`--exr-zip-level`): 1 (day2night's encoder) to 9 (zlib's largest).
pub const EXR_ZIP_LEVEL_RANGE: (u8, u8) = (1, 9);
/// Worker threads or inputs in parallel (`--jobs`; Python `set_threads`, where 0 means one
/// per core): each is an OS thread with its own stack and, for `dataset`, an image in
/// memory, and more of them than cores do not help (docs/dataset.md); 4096 is above the
/// hardware threads of any one machine day2night runs on.
pub const JOBS_RANGE: (usize, usize) = (1, 4096);

/// Error unless `n` is in [`JOBS_RANGE`]; the message names `field`.
pub fn jobs(field: &str, n: usize) -> Result<()> {
    let (lo, hi) = JOBS_RANGE;
    if (lo..=hi).contains(&n) {
        return Ok(());
    }
    Err(Error::invalid(format!(
        "{field}: {n} is outside {lo}..={hi}"
    )))
}

// ---------------------------------------------------------------------------------------
// Calibration files.

/// Largest calibration JSON file read (calibration files are kilobytes).
pub const MAX_CALIBRATION_FILE_BYTES: u64 = 64 << 20;
/// Most entries in an illuminant or brightness list.
pub const MAX_DICT_ENTRIES: usize = 1_000_000;

// ---------------------------------------------------------------------------------------
// Helpers.

/// A number in short form: integers as integers up to 1e6, others with at most 6
/// significant digits, scientific notation outside [1e-3, 1e6) (`1e6`, `4.61e18`, `0.001`,
/// `3.2e-4`).
pub fn short(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e6).contains(&a) {
        let s = format!("{:.*}", (5 - a.log10().floor() as i32).max(0) as usize, x);
        if s.contains('.') {
            return s.trim_end_matches('0').trim_end_matches('.').to_string();
        }
        return s;
    }
    let s = format!("{x:.5e}");
    match s.split_once('e') {
        Some((m, e)) => {
            let m = if m.contains('.') {
                m.trim_end_matches('0').trim_end_matches('.')
            } else {
                m
            };
            format!("{m}e{e}")
        }
        None => s,
    }
}

/// Numbers in short form, space separated.
pub fn short_list(v: &[f64]) -> String {
    v.iter().map(|&x| short(x)).collect::<Vec<_>>().join(" ")
}

/// The same error as a malformed-input error (for bounds on values read from files).
pub fn malformed(e: Error) -> Error {
    match e {
        Error::InvalidParam(m) => Error::Malformed(m),
        e => e,
    }
}

/// Error unless `v` is finite and in `[lo, hi]`; the message names `field`.
pub fn in_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if v.is_finite() && v >= lo && v <= hi {
        return Ok(());
    }
    let (l, h) = (short(lo), short(hi));
    // A value just past a bound is printed with every digit it needs: "1 is outside
    // [-1, 1]" would not say what is wrong with 1 + 1e-15.
    let mut shown = short(v);
    if shown == l || shown == h {
        shown = format!("{v}");
    }
    Err(Error::invalid(format!(
        "{field}: {shown} is outside [{l}, {h}]"
    )))
}

/// Error unless `iso` is in [`ISO_RANGE`] (the message starts with `field: ` unless `field`
/// is empty).
pub fn iso(field: &str, iso: u32) -> Result<()> {
    if (ISO_RANGE.0..=ISO_RANGE.1).contains(&iso) {
        return Ok(());
    }
    let at = if field.is_empty() {
        String::new()
    } else {
        format!("{field}: ")
    };
    Err(Error::invalid(format!(
        "{at}ISO {iso} is outside {}..={}",
        ISO_RANGE.0, ISO_RANGE.1
    )))
}

/// Error unless every component is finite and within `[1/max, max]`.
pub fn ratios(field: &str, v: &[f64], max: f64) -> Result<()> {
    for (i, &x) in v.iter().enumerate() {
        in_range(&format!("{field}[{i}]"), x, 1.0 / max, max)?;
    }
    Ok(())
}

/// Error unless `xy` is a chromaticity of a light: finite, with x, y and z = 1 - x - y each
/// at least [`MIN_XYZ_CHROMATICITY`].
pub fn chromaticity_xy(field: &str, xy: [f64; 2]) -> Result<()> {
    let z = 1.0 - xy[0] - xy[1];
    let hi = 1.0 - 2.0 * MIN_XYZ_CHROMATICITY;
    in_range(&format!("{field} x"), xy[0], MIN_XYZ_CHROMATICITY, hi)?;
    in_range(&format!("{field} y"), xy[1], MIN_XYZ_CHROMATICITY, hi)?;
    if z < MIN_XYZ_CHROMATICITY {
        return Err(Error::invalid(format!(
            "{field}: x + y = {} leaves z = 1 - x - y below {} (not a light's chromaticity)",
            short(xy[0] + xy[1]),
            short(MIN_XYZ_CHROMATICITY)
        )));
    }
    Ok(())
}

/// Error unless `n <= max` (a count of entries).
pub fn count(field: &str, n: usize, max: usize) -> Result<()> {
    if n <= max {
        return Ok(());
    }
    Err(Error::limits(format!(
        "{field}: {n} entries (at most {max})"
    )))
}

/// Error unless the 3x3 matrix `m` (row-major, 9 values) can be inverted by every DNG reader:
/// finite; not singular; condition number at most [`MAX_MATRIX_CONDITION`]; and, for a
/// ColorMatrix (`sdk_normalized`), still invertible after the Adobe DNG SDK's normalization
/// (scaled so that D50 maps to at most 1, rounded to 4 decimals, |det| >= 1e-10).
pub fn matrix3(field: &str, v: &[f64], sdk_normalized: bool) -> Result<()> {
    let Some(m) = from_row_major(v) else {
        return Ok(()); // Not a 3x3 matrix (non-RGB CFA): its size is checked by the reader.
    };
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(Error::malformed(format!(
            "{field}: {} is not finite",
            short(*x)
        )));
    }
    let cond = condition_number(&m);
    if !cond.is_finite() || determinant(&m) == 0.0 {
        return Err(Error::malformed(format!(
            "{field} [{}] is singular (rank below 3): colours cannot be mapped back",
            short_list(v)
        )));
    }
    if cond > MAX_MATRIX_CONDITION {
        return Err(Error::malformed(format!(
            "{field} [{}] is ill-conditioned: condition number {} is above {} \
             (DNG readers round it away; camera matrices are below 100)",
            short_list(v),
            short(cond),
            short(MAX_MATRIX_CONDITION)
        )));
    }
    if sdk_normalized {
        // dng_camera_profile::NormalizeColorMatrix, then Invert's determinant test.
        // D50 as XYZ with Y = 1, the SDK's PCS white.
        let d50 = xy_to_xyz(D50_XY);
        let max = m
            .iter()
            .map(|r| r[0] * d50[0] + r[1] * d50[1] + r[2] * d50[2])
            .fold(f64::NEG_INFINITY, f64::max);
        let k = if max > 0.0 && !(0.99..=1.01).contains(&max) {
            1.0 / max
        } else {
            1.0
        };
        let r =
            m.map(|row| row.map(|x| (x * k * SDK_MATRIX_ROUNDING).round() / SDK_MATRIX_ROUNDING));
        let det = determinant(&r);
        if det.abs() < SDK_MIN_DETERMINANT {
            return Err(Error::malformed(format!(
                "{field} [{}] is not invertible once normalized and rounded to 4 decimals \
                 as the DNG SDK does (determinant {})",
                short_list(v),
                short(det)
            )));
        }
    }
    Ok(())
}

/// Read a calibration text file (illuminant, brightness or noise model JSON), refusing files
/// over [`MAX_CALIBRATION_FILE_BYTES`].
pub fn read_calibration_text(path: &std::path::Path) -> Result<String> {
    let len = std::fs::metadata(path)
        .map_err(|e| Error::from(e).in_file(path))?
        .len();
    if len > MAX_CALIBRATION_FILE_BYTES {
        return Err(Error::limits(format!(
            "calibration file of {len} bytes (at most {MAX_CALIBRATION_FILE_BYTES})"
        ))
        .in_file(path));
    }
    std::fs::read_to_string(path).map_err(|e| Error::from(e).in_file(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_numbers() {
        assert_eq!(short(1e6), "1e6");
        assert_eq!(short(4_000_001.0), "4e6");
        assert_eq!(short(1e-3), "0.001");
        assert_eq!(short(3.2e-4), "3.2e-4");
        assert_eq!(short(2f64.powi(62)), "4.61169e18");
        assert_eq!(short(65535.0), "65535");
        assert_eq!(short(-700.0), "-700");
        assert_eq!(short(0.5), "0.5");
        assert_eq!(short(1.0 / 3.0), "0.333333");
        assert_eq!(short(0.0), "0");
    }

    #[test]
    fn a_value_just_past_a_bound_shows_its_digits() {
        let e = in_range("x", 1.0 + 1e-15, -1.0, 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("x: 1.000000000000001 is outside [-1, 1]"), "{e}");
        let e = in_range("x", 1e308, 0.0, 1000.0).unwrap_err().to_string();
        assert!(e.contains("x: 1e308 is outside [0, 1000]"), "{e}");
    }

    #[test]
    fn iso_bounds_at_and_past_the_edge() {
        assert!(iso("x", ISO_RANGE.1).is_ok());
        let e = iso("--iso", ISO_RANGE.1 + 1).unwrap_err().to_string();
        assert!(e.contains("--iso") && e.contains("4000001"), "{e}");
        assert!(iso("x", 0).is_err());
    }

    #[test]
    fn jobs_at_and_past_the_edges() {
        assert!(jobs("--jobs", JOBS_RANGE.0).is_ok() && jobs("--jobs", JOBS_RANGE.1).is_ok());
        let e = jobs("--jobs", JOBS_RANGE.1 + 1).unwrap_err().to_string();
        assert!(e.contains("--jobs: 4097 is outside 1..=4096"), "{e}");
        assert!(jobs("--jobs", 0).is_err());
    }

    #[test]
    fn huge_but_unit_determinant_is_ill_conditioned_not_singular() {
        let t = 2f64.powi(31);
        let v = [t, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0 / t];
        let e = matrix3("ColorMatrix1", &v, true).unwrap_err().to_string();
        assert!(e.contains("condition number 4.61169e18"), "{e}");
        assert!(!e.contains("singular"), "{e}");
        let e = matrix3("ColorMatrix1", &[1., 2., 3., 2., 4., 6., 0., 0., 1.], true)
            .unwrap_err()
            .to_string();
        assert!(e.contains("singular"), "{e}");
    }

    #[test]
    fn sdk_normalization_matches_the_measured_limit() {
        // Measured with dngpy (SDK 1.7.1): diag(1e4, 1, 1) accepted, diag(10^4.5, 1, 1)
        // refused; a tiny but well-conditioned matrix is accepted (it is normalized first).
        let d = |a: f64, b: f64, c: f64| [a, 0., 0., 0., b, 0., 0., 0., c];
        assert!(matrix3("CM", &d(1e4, 1.0, 1.0), true).is_ok());
        assert!(matrix3("CM", &d(1e-4, 1e-4, 1e-4), true).is_ok());
        assert!(matrix3("CM", &d(10f64.powf(4.5), 1.0, 1.0), true).is_err());
        assert!(matrix3("CM", &crate::color::xyz::XYZ_TO_SRGB, true).is_ok());
    }
}
