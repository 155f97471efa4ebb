//! TrimBounds (opcode 6) on the stage-3 image (OpcodeList3): the image keeps only the
//! rectangle (top, left, bottom, right), in the same coordinates (the SDK's
//! `dng_image::Trim`): later opcodes see the trimmed extent, and DefaultCrop (relative to
//! the active area) is intersected with them. A rectangle that is empty or not inside the
//! image is an error, as in the SDK.

use super::StageRect;
use crate::error::{Error, Result};

/// Cut `data` (`planes` interleaved samples per pixel, covering `extent`) to `rect`
/// (top, left, bottom, right). Returns the new samples and extent.
pub fn trim(
    data: &[f32],
    planes: usize,
    extent: StageRect,
    rect: [u32; 4],
) -> Result<(Vec<f32>, StageRect)> {
    let nb = StageRect {
        t: rect[0] as i64,
        l: rect[1] as i64,
        b: rect[2] as i64,
        r: rect[3] as i64,
    };
    if nb.h() <= 0
        || nb.w() <= 0
        || nb.t < extent.t
        || nb.l < extent.l
        || nb.b > extent.b
        || nb.r > extent.r
    {
        return Err(Error::malformed(format!(
            "OpcodeList3: TrimBounds {rect:?} is empty or not inside the image ({}, {}, {}, {})",
            extent.t, extent.l, extent.b, extent.r
        )));
    }
    let w = extent.w() as usize;
    let nw = nb.w() as usize;
    let mut out = Vec::with_capacity(nw * nb.h() as usize * planes);
    for r in nb.t..nb.b {
        let y = (r - extent.t) as usize;
        let x0 = (nb.l - extent.l) as usize;
        out.extend_from_slice(&data[(y * w + x0) * planes..(y * w + x0 + nw) * planes]);
    }
    Ok((out, nb))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trims_in_the_same_coordinates() {
        let data: Vec<f32> = (0..20).map(|i| i as f32).collect(); // 5x4, one plane
        let (d, b) = trim(&data, 1, StageRect::of_size(5, 4), [1, 2, 3, 5]).unwrap();
        assert_eq!(
            b,
            StageRect {
                t: 1,
                l: 2,
                b: 3,
                r: 5
            }
        );
        assert_eq!(d, vec![7.0, 8.0, 9.0, 12.0, 13.0, 14.0]);
        // trimming again inside the new extent
        let (d2, _) = trim(&d, 1, b, [2, 3, 3, 4]).unwrap();
        assert_eq!(d2, vec![13.0]);
        assert!(trim(&data, 1, StageRect::of_size(5, 4), [0, 0, 5, 5]).is_err());
        assert!(trim(&data, 1, StageRect::of_size(5, 4), [2, 2, 2, 3]).is_err());
    }
}
