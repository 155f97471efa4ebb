//! Raw samples made row by row on demand: a [`RowSource`] is a CFA mosaic that need not be
//! held whole. The DNG writer packs and writes such a source strip by strip
//! ([`crate::dng::write_dng_rows`]), so a noisy night raw goes from its clean raw into the
//! file without a noisy plane ever existing (docs/benchmarks.md, "Peak memory at 109 MP").

use crate::error::Result;
use crate::raw::RawImage;
use rayon::prelude::*;

/// Rows of samples, whole rows at a time. `fill_rows` must give the same samples for a row
/// whatever rows it is asked for with and whatever thread asks (row-keyed random streams),
/// so any chunking gives the same image.
pub trait RowSource: Sync {
    /// Samples per row.
    fn width(&self) -> usize;
    /// Rows.
    fn height(&self) -> usize;
    /// An upper bound of every sample (the DNG writer chooses the stored bit depth from it
    /// before any row is made).
    fn max_bound(&self) -> u16;
    /// Fill `out` (whole rows: a multiple of [`RowSource::width`] samples) with the rows
    /// from `y0` on.
    fn fill_rows(&self, y0: usize, out: &mut [u16]);
    /// The samples, when they already exist as one row-major plane (no copy needed).
    fn plane(&self) -> Option<&[u16]> {
        None
    }
}

/// Rows per parallel task of [`to_plane`].
const ROWS_PER_TASK: usize = 16;

/// Every row of `src` as one row-major plane (made in parallel).
pub fn to_plane(src: &dyn RowSource) -> Result<Vec<u16>> {
    let (w, h) = (src.width(), src.height());
    let n = w
        .checked_mul(h)
        .ok_or_else(|| crate::error::Error::limits("image size overflows"))?;
    if let Some(p) = src.plane() {
        let mut v = crate::limits::try_with_capacity(n, "a raw plane")?;
        v.extend_from_slice(p);
        return Ok(v);
    }
    let mut v = crate::limits::try_filled(0u16, n, "a raw plane")?;
    if w > 0 {
        v.par_chunks_mut(w * ROWS_PER_TASK)
            .enumerate()
            .for_each(|(i, rows)| src.fill_rows(i * ROWS_PER_TASK, rows));
    }
    Ok(v)
}

/// The largest sample of `data` (0 when empty), computed in parallel.
pub fn plane_max(data: &[u16]) -> u16 {
    data.par_chunks(1 << 16)
        .map(|c| c.iter().copied().max().unwrap_or(0))
        .max()
        .unwrap_or(0)
}

/// A change of the active-area part of each active-area row of a raw (e.g. noise added to a
/// clean raw): [`MappedRows`] makes the changed raw row by row.
pub trait ActiveRowMap: Sync {
    /// Rewrite `seg`, the samples of active-area row `r` (all active-area columns);
    /// `scratch` is a buffer of the caller's that the map may use (any length).
    fn map_row(&self, r: usize, seg: &mut [u16], scratch: &mut Vec<f64>);
    /// An upper bound of every sample [`ActiveRowMap::map_row`] writes.
    fn bound(&self) -> u16;
}

/// A reference to a map is the map (so `&dyn ActiveRowMap` can drive [`MappedRows`]).
impl<M: ActiveRowMap + ?Sized> ActiveRowMap for &M {
    fn map_row(&self, r: usize, seg: &mut [u16], scratch: &mut Vec<f64>) {
        (**self).map_row(r, seg, scratch)
    }
    fn bound(&self) -> u16 {
        (**self).bound()
    }
}

/// The rows of `img` with an [`ActiveRowMap`] applied to their active-area part (the
/// samples outside the active area are `img`'s).
pub struct MappedRows<'a, M> {
    img: &'a RawImage,
    map: M,
}

impl<'a, M: ActiveRowMap> MappedRows<'a, M> {
    /// `img` changed by `map`.
    pub fn new(img: &'a RawImage, map: M) -> MappedRows<'a, M> {
        MappedRows { img, map }
    }
}

impl<M: ActiveRowMap> RowSource for MappedRows<'_, M> {
    fn width(&self) -> usize {
        self.img.width
    }
    fn height(&self) -> usize {
        self.img.height
    }
    fn max_bound(&self) -> u16 {
        plane_max(&self.img.data).max(self.map.bound())
    }
    fn fill_rows(&self, y0: usize, out: &mut [u16]) {
        let w = self.img.width;
        let a = self.img.active_area();
        let (top, left, aw) = (a.top as usize, a.left as usize, a.width());
        let mut scratch = Vec::new();
        for (i, row) in out.chunks_exact_mut(w).enumerate() {
            let sy = y0 + i;
            row.copy_from_slice(&self.img.data[sy * w..(sy + 1) * w]);
            if (top..a.bottom as usize).contains(&sy) {
                let seg = &mut row[left..left + aw];
                self.map.map_row(sy - top, seg, &mut scratch);
            }
        }
    }
}

/// A [`RawImage`]'s plane as a [`RowSource`] (its exact maximum is computed once).
pub struct PlaneRows<'a> {
    img: &'a RawImage,
    max: u16,
}

impl<'a> PlaneRows<'a> {
    /// The rows of `img`.
    pub fn new(img: &'a RawImage) -> PlaneRows<'a> {
        PlaneRows {
            img,
            max: plane_max(&img.data),
        }
    }
}

impl RowSource for PlaneRows<'_> {
    fn width(&self) -> usize {
        self.img.width
    }
    fn height(&self) -> usize {
        self.img.height
    }
    fn max_bound(&self) -> u16 {
        self.max
    }
    fn fill_rows(&self, y0: usize, out: &mut [u16]) {
        let start = y0 * self.img.width;
        out.copy_from_slice(&self.img.data[start..start + out.len()]);
    }
    fn plane(&self) -> Option<&[u16]> {
        Some(&self.img.data)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::Bayer;

    struct Ramp(usize, usize);
    impl RowSource for Ramp {
        fn width(&self) -> usize {
            self.0
        }
        fn height(&self) -> usize {
            self.1
        }
        fn max_bound(&self) -> u16 {
            u16::MAX
        }
        fn fill_rows(&self, y0: usize, out: &mut [u16]) {
            for (i, v) in out.iter_mut().enumerate() {
                *v = ((y0 * self.0 + i) * 7919 % 65521) as u16;
            }
        }
    }

    #[test]
    fn to_plane_is_the_rows_in_order_for_any_size() {
        for (w, h) in [(1, 1), (3, 17), (5, 16), (7, 33), (0, 4)] {
            let p = to_plane(&Ramp(w, h)).unwrap();
            let want: Vec<u16> = (0..w * h).map(|i| (i * 7919 % 65521) as u16).collect();
            assert_eq!(p, want, "{w}x{h}");
        }
    }

    #[test]
    fn plane_rows_give_the_plane_and_its_max() {
        let img = RawImage {
            width: 3,
            height: 2,
            data: vec![5, 9, 1, 0, 700, 2],
            meta: RawMeta::new_bayer(Bayer::RGGB, 10, 0.0, 1023.0),
        };
        let src = PlaneRows::new(&img);
        assert_eq!(src.max_bound(), 700);
        assert_eq!(to_plane(&src).unwrap(), img.data);
        let mut row = [0u16; 3];
        src.fill_rows(1, &mut row);
        assert_eq!(row, [0, 700, 2]);
    }
}
