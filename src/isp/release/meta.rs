//! What the release's pipeline reads from a DNG (its `get_metadata`), in the project's terms:
//! the values of the tags as stored, with the release's fallbacks, and its image window.

use crate::error::{Error, Result};
use crate::raw::RawImage;

/// AsShotNeutral's tag number (the stored, un-normalized values are what the release divides
/// by).
const AS_SHOT_NEUTRAL: u16 = 50728;

/// The black level as the release subtracts it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Black {
    /// One value for every sample (float32 arithmetic in the release).
    Scalar(f64),
    /// One value per 2x2 site, row-major from the image's top-left corner (float64
    /// arithmetic in the release).
    Sites([f64; 4]),
}

/// The metadata the release's target render uses.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseMeta {
    /// BlackLevel (0 when absent).
    pub black: Black,
    /// WhiteLevel.
    pub white: f64,
    /// CFAPattern colours (0 red, 1 green, 2 blue), row-major, applied from the top-left
    /// corner of the release's image whatever its offset in the active area.
    pub cfa: [u8; 4],
    /// The neutral that white-balances and picks the colour matrix: the caller's, else
    /// AsShotNeutral as stored, else AsShotWhiteXY converted (green = 1).
    pub neutral: [f64; 3],
    /// ColorMatrix1, row-major (all ones when absent, as the release does).
    pub cm1: [f64; 9],
    /// ColorMatrix2, row-major (all ones when absent, as the release does).
    pub cm2: [f64; 9],
    /// Orientation (1..=8).
    pub orientation: u16,
    /// The release's own second crop: the ActiveArea rectangle (top, left, bottom, right)
    /// applied again to the active area, when its reader sees the tag (raw in IFD0).
    pub second_crop: Option<[usize; 4]>,
}

impl ReleaseMeta {
    /// The release's view of `raw`'s metadata; `neutral` replaces the file's AsShotNeutral
    /// (the release's night targets use the synthetic neutral). Without either, AsShotWhiteXY
    /// is converted through the colour matrices as the project's ISP converts it
    /// ([`resolve_neutral`](crate::isp::render_parts::resolve_neutral)); with none of the
    /// three the render is refused with that ISP's error.
    pub fn of(raw: &RawImage, neutral: Option<[f64; 3]>) -> Result<ReleaseMeta> {
        let m = &raw.meta;
        if m.linear_raw.is_some() {
            return Err(Error::unsupported(
                "--isp release: a LinearRaw DNG has no CFA mosaic to render",
            ));
        }
        let cfa = m.bayer()?.0;
        let black = match m.levels.black.as_slice() {
            [] => Black::Scalar(0.0),
            [b] => Black::Scalar(*b),
            [a, b, c, d] => Black::Sites([*a, *b, *c, *d]),
            v => {
                return Err(Error::unsupported(format!(
                    "--isp release: BlackLevel has {} values; the release reads 1 or 4",
                    v.len()
                )))
            }
        };
        // The release divides by AsShotNeutral as stored (it requires the tag). Without
        // one, the white balance is what the project's ISP uses (docs/isp.md): AsShotWhiteXY
        // through the colour matrices, else the same refusal.
        let neutral = match (neutral, stored_neutral(raw).or(m.as_shot_neutral)) {
            (Some(n), _) | (None, Some(n)) => n,
            (None, None) => crate::isp::render_parts::resolve_neutral(m, None)?,
        };
        if neutral.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(Error::invalid(format!(
                "neutral {neutral:?}: need 3 positive finite components"
            )));
        }
        let matrix = |v: &Option<Vec<f64>>, name: &str| -> Result<[f64; 9]> {
            match v {
                None => Ok([1.0; 9]),
                Some(v) => v.as_slice().try_into().map_err(|_| {
                    Error::unsupported(format!(
                        "--isp release: {name} has {} values; the release reads 3x3",
                        v.len()
                    ))
                }),
            }
        };
        // The release's tag reader looks in IFD0 only for ActiveArea: a raw in a SubIFD
        // gets no second crop. An image without a stored layout is written by day2night's
        // writer, which puts the raw in IFD0.
        let in_ifd0 = m.storage.as_ref().is_none_or(|s| s.sub_ifd.is_none());
        let second_crop = match (m.active_area, in_ifd0) {
            (Some(a), true) => Some([a.top, a.left, a.bottom, a.right].map(|v| v as usize)),
            _ => None,
        };
        Ok(ReleaseMeta {
            black,
            white: m.levels.white,
            cfa,
            neutral,
            cm1: matrix(&m.color.color_matrix1, "ColorMatrix1")?,
            cm2: matrix(&m.color.color_matrix2, "ColorMatrix2")?,
            orientation: m.orientation,
            second_crop,
        })
    }
}

/// AsShotNeutral as the file stored it (not normalized to green = 1).
fn stored_neutral(raw: &RawImage) -> Option<[f64; 3]> {
    let v = raw.meta.stored_value(AS_SHOT_NEUTRAL)?.to_f64_vec()?;
    v.as_slice().try_into().ok()
}
