//! LinearRaw raw IFDs (PhotometricInterpretation 34892: already demosaiced, e.g. Apple
//! ProRAW, Adobe lossy DNG): the sample layout they may have and their per-sample levels.
//! CFA IFDs never reach this module's level code (`spp == 1` passes through unchanged).

use super::*;
use crate::raw::meta::LinearRaw;

/// Error unless a LinearRaw IFD has 3 chunky samples per pixel.
pub(super) fn check_layout(raw: &Ifd, spp: u32) -> Result<()> {
    if spp != 3 {
        return Err(Error::unsupported(format!(
            "LinearRaw with {spp} samples per pixel (3 supported)"
        )));
    }
    if let Some(pc) = raw.u32(PLANAR_CONFIGURATION) {
        if pc != 1 {
            return Err(Error::unsupported(format!(
                "LinearRaw with PlanarConfiguration {pc} (separate planes; chunky, 1, supported)"
            )));
        }
    }
    if let Some(b) = raw.get(BITS_PER_SAMPLE).and_then(|v| v.to_u32_vec()) {
        if b.windows(2).any(|p| p[0] != p[1]) {
            return Err(Error::unsupported(format!(
                "LinearRaw with different BitsPerSample per sample ({b:?})"
            )));
        }
    }
    Ok(())
}

/// The empty CFA description of a LinearRaw image: no pattern, `spp` planes R, G, B.
pub(super) fn no_cfa(spp: u16) -> CfaPattern {
    CfaPattern {
        rows: 0,
        cols: 0,
        pattern: Vec::new(),
        plane_color: (0..spp.min(255) as u8).collect(),
        layout: 1,
    }
}

/// " x N samples" for an error message about a LinearRaw BlackLevel count ("" for CFA).
pub(super) fn times_samples(spp: usize) -> String {
    if spp == 1 {
        String::new()
    } else {
        format!(" x {spp} samples")
    }
}

/// The levels of the model from the file's: unchanged for CFA (`spp == 1`). For LinearRaw,
/// `black` holds `rows x cols x spp` values and WhiteLevel one per sample (one value is
/// taken for all samples); returns sample 0's black per repeat cell and white, and the
/// per-sample values in a [`LinearRaw`].
pub(super) fn split_levels(
    raw: &Ifd,
    black: Vec<f64>,
    white: f64,
    repeat: (usize, usize),
    spp: usize,
) -> Result<(Vec<f64>, f64, Option<LinearRaw>)> {
    if spp == 1 {
        return Ok((black, white, None));
    }
    let whites = match raw.get(WHITE_LEVEL) {
        Some(v) => {
            let w = tags::floats(v, WHITE_LEVEL)?;
            match w.len() {
                1 => vec![w[0]; spp],
                n if n == spp => w,
                n => {
                    return Err(Error::malformed(format!(
                        "WhiteLevel has {n} values for {spp} samples per pixel"
                    )))
                }
            }
        }
        None => vec![white; spp],
    };
    // The model's CFA-shaped levels hold sample 0's (each sample is validated on its own by
    // LinearRaw::validate; a max/min over samples could refuse valid files).
    let cells = repeat.0 * repeat.1;
    let per_cell: Vec<f64> = (0..cells).map(|c| black[c * spp]).collect();
    let first_white = whites[0];
    Ok((
        per_cell,
        first_white,
        Some(LinearRaw {
            samples_per_pixel: spp as u16,
            black,
            white: whites,
        }),
    ))
}
