//! The target files of a banded render (EXR and/or 8-bit PNG), written while the target is
//! rendered: `synth` and `render` never hold the encoded target whole.
//!
//! [`TargetFiles::create`] opens the files (header first: [`ExrFile`], [`PngFile`], each an
//! [`crate::output::AtomicFile`]) once the output size is known; [`TargetFiles::band`]
//! encodes one band of [`BAND`] rows, from any thread, and appends it to each file as soon
//! as every band above it is written (a band that comes early waits in a small reorder
//! buffer; the render makes bands nearly in order and at most a few ahead:
//! [`crate::isp::render::render_bands`]); [`TargetFiles::finish`] completes
//! the files (the EXR offset table, the PNG's IEND) and hands them to the output policy
//! (sync and rename, or deferred). The bytes are those of the whole-image writers
//! ([`crate::encode::exr::write_exr`], [`crate::encode::png::write_png`]); on any error,
//! or when dropped unfinished, no file appears and the temporary files are removed.

use crate::deflate::Encoder;
use crate::encode::exr::{encode_exr_rows, ExrFile, ExrOptions};
use crate::encode::png::{encode_u8_slice, PngOptions};
use crate::encode::png_rows::{PngFile, PngRows};
use crate::error::{Error, Result};
use crate::isp::render::BAND;
use crate::isp::tone::DisplayTone;
use crate::output::OutputPolicy;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The stored EXR blocks of one band.
type Blocks = Vec<Vec<u8>>;

/// The open target files of one render.
#[derive(Debug)]
pub struct TargetFiles<'p> {
    exr: Option<InOrder<Blocks, ExrFile<'p>>>,
    exr_opts: ExrOptions,
    png: Option<InOrder<PngRows, PngFile<'p>>>,
    tone: DisplayTone,
}

impl<'p> TargetFiles<'p> {
    /// Open the EXR at `exr` (with options `exr_opts` and header attributes `attrs`)
    /// and/or the 8-bit PNG (display encoding `tone`) at `png`, for a `width` x `height`
    /// render.
    pub fn create(
        (width, height): (usize, usize),
        exr: Option<&Path>,
        (exr_opts, attrs): (&ExrOptions, &[(String, String)]),
        png: Option<(&Path, DisplayTone)>,
        policy: &'p OutputPolicy,
    ) -> Result<TargetFiles<'p>> {
        let exr = match exr {
            Some(path) => Some(InOrder::new(ExrFile::create(
                path, width, height, exr_opts, attrs, policy,
            )?)),
            None => None,
        };
        let tone = png.map_or(PngOptions::default().tone, |(_, t)| t);
        let png = match png {
            Some((path, tone)) => Some(InOrder::new(PngFile::create(
                path, width, height, tone, policy,
            )?)),
            None => None,
        };
        Ok(TargetFiles {
            exr,
            exr_opts: *exr_opts,
            png,
            tone,
        })
    }

    /// Encode the band of rows from output row `y0` (a multiple of [`BAND`]; `width`
    /// interleaved linear RGB pixels per row) and write it to each file once the bands
    /// above it are written.
    pub fn band(&self, y0: usize, width: usize, rows: &[f32]) -> Result<()> {
        if !y0.is_multiple_of(BAND) {
            return Err(Error::invalid(format!(
                "target band from row {y0}: not a multiple of {BAND} rows"
            )));
        }
        let bi = y0 / BAND;
        if let Some(exr) = &self.exr {
            let blocks = encode_exr_rows(rows, width, y0, &self.exr_opts)?;
            exr.submit(bi, blocks, |f, i, b| f.push_rows(i * BAND, &b))?;
        }
        if let Some(png) = &self.png {
            let rgb8 = encode_u8_slice(rows, self.tone);
            let group = PngRows::encode(&rgb8, width, &mut Encoder::new())?;
            png.submit(bi, group, |f, _, g| f.push(&g))?;
        }
        Ok(())
    }

    /// Complete the files (every band must have been written) and hand them to the
    /// output policy; the EXR's error first.
    pub fn finish(&self) -> Result<()> {
        let exr = self.exr.as_ref().map(InOrder::take).transpose();
        let png = self.png.as_ref().map(InOrder::take).transpose();
        // Both files are taken first, so that on an error neither is left open.
        let (exr, png) = (exr?, png?);
        if let Some(f) = exr {
            f.finish()?;
        }
        if let Some(f) = png {
            f.finish()?;
        }
        Ok(())
    }
}

/// Items numbered 0, 1, 2, ... written into `file` in that order, whatever the order in
/// which they arrive: an item that comes early waits until the ones before it are written.
/// After a failed write the file is dropped (an [`crate::output::AtomicFile`] then removes
/// its temporary file) and later items are refused.
#[derive(Debug)]
struct InOrder<T, F> {
    state: Mutex<InOrderState<T, F>>,
}

#[derive(Debug)]
struct InOrderState<T, F> {
    /// The next item to write.
    next: usize,
    /// Items that came before their turn.
    early: BTreeMap<usize, T>,
    /// None after a failed write or once taken.
    file: Option<F>,
}

impl<T, F> InOrder<T, F> {
    fn new(file: F) -> InOrder<T, F> {
        InOrder {
            state: Mutex::new(InOrderState {
                next: 0,
                early: BTreeMap::new(),
                file: Some(file),
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, InOrderState<T, F>> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Hand over item `i`; writes it (`write(file, index, item)`) and every early item
    /// after it if its turn has come.
    fn submit(
        &self,
        i: usize,
        item: T,
        write: impl Fn(&mut F, usize, T) -> Result<()>,
    ) -> Result<()> {
        let mut st = self.lock();
        let InOrderState { next, early, file } = &mut *st;
        let Some(f) = file.as_mut() else {
            return Err(Error::invalid(
                "the target file was abandoned after an earlier error",
            ));
        };
        if i < *next || early.contains_key(&i) {
            return Err(Error::invalid(format!("target band {i} given twice")));
        }
        early.insert(i, item);
        while let Some(item) = early.remove(next) {
            if let Err(e) = write(f, *next, item) {
                early.clear();
                *file = None;
                return Err(e);
            }
            *next += 1;
        }
        Ok(())
    }

    /// The file, once every item handed over has been written (none waits).
    fn take(&self) -> Result<F> {
        let mut st = self.lock();
        let waiting = st.early.keys().next().copied();
        let file = st.file.take();
        st.early.clear();
        match (file, waiting) {
            (Some(f), None) => Ok(f),
            (Some(_), Some(i)) => Err(Error::invalid(format!(
                "target band {} is missing (band {i} came)",
                st.next
            ))),
            (None, _) => Err(Error::invalid(
                "the target file was abandoned after an earlier error",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::exr::write_exr;
    use crate::encode::png::write_png;
    use crate::isp::RgbImage;

    fn image(w: usize, h: usize) -> RgbImage {
        let mut img = RgbImage::new(w, h);
        for (i, v) in img.data.iter_mut().enumerate() {
            *v = match i % 17 {
                0 => f32::NAN,
                1 => 3.0,
                2 => -0.5,
                _ => ((i * 7919) % 1000) as f32 / 997.0,
            };
        }
        img
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// Bands handed over in `order` give the whole-image writers' bytes.
    #[test]
    fn bands_in_any_order_give_the_whole_image_files() {
        let dir = tempfile::tempdir().unwrap();
        let policy = OutputPolicy::default();
        let attrs = [("day2night:synth".to_string(), "x=1".to_string())];
        for (k, (w, h)) in [(1, 1), (5, 31), (7, 32), (3, 33), (9, 200)]
            .into_iter()
            .enumerate()
        {
            let img = image(w, h);
            let nb = h.div_ceil(BAND);
            for opts in [
                ExrOptions::default(),
                ExrOptions {
                    half: false,
                    compression: crate::encode::exr::ExrCompression::Zips,
                    ..ExrOptions::default()
                },
            ] {
                let (a, b) = (dir.path().join("a.exr"), dir.path().join("a.png"));
                write_exr(&img, &a, &opts, &attrs, &policy).unwrap();
                write_png(&img, &b, &PngOptions::default(), &policy).unwrap();
                // reversed, and even bands first
                let orders: [Vec<usize>; 2] = [
                    (0..nb).rev().collect(),
                    (0..nb).step_by(2).chain((1..nb).step_by(2)).collect(),
                ];
                for order in orders {
                    let (c, d) = (dir.path().join("c.exr"), dir.path().join("c.png"));
                    let t = TargetFiles::create(
                        (w, h),
                        Some(&c),
                        (&opts, &attrs),
                        Some((&d, PngOptions::default().tone)),
                        &policy,
                    )
                    .unwrap();
                    for &bi in &order {
                        let rows = &img.data
                            [3 * w * BAND * bi..(3 * w * BAND * (bi + 1)).min(img.data.len())];
                        t.band(bi * BAND, w, rows).unwrap();
                    }
                    t.finish().unwrap();
                    assert_eq!(
                        std::fs::read(&a).unwrap(),
                        std::fs::read(&c).unwrap(),
                        "case {k}"
                    );
                    assert_eq!(
                        std::fs::read(&b).unwrap(),
                        std::fs::read(&d).unwrap(),
                        "case {k}"
                    );
                    std::fs::remove_file(&c).unwrap();
                    std::fs::remove_file(&d).unwrap();
                }
                std::fs::remove_file(&a).unwrap();
                std::fs::remove_file(&b).unwrap();
            }
        }
        assert!(names(dir.path()).is_empty());
    }

    #[test]
    fn missing_or_repeated_bands_and_drops_leave_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let policy = OutputPolicy::default();
        let (w, h) = (4, 100);
        let img = image(w, h);
        let (e, p) = (dir.path().join("t.exr"), dir.path().join("t.png"));
        let band =
            |bi: usize| &img.data[3 * w * BAND * bi..(3 * w * BAND * (bi + 1)).min(img.data.len())];
        let open = || {
            TargetFiles::create(
                (w, h),
                Some(&e),
                (&ExrOptions::default(), &[]),
                Some((&p, PngOptions::default().tone)),
                &policy,
            )
            .unwrap()
        };
        // a missing band: finish fails, nothing appears
        let t = open();
        for bi in [0, 1, 3] {
            t.band(bi * BAND, w, band(bi)).unwrap();
        }
        let err = t.finish().unwrap_err().to_string();
        assert!(err.contains("band 2 is missing"), "{err}");
        drop(t);
        assert!(names(dir.path()).is_empty());
        // a band given twice is refused; dropped unfinished, nothing appears
        let t = open();
        t.band(0, w, band(0)).unwrap();
        assert!(t.band(0, w, band(0)).is_err());
        assert!(t.band(5, w, band(1)).is_err(), "a misaligned band");
        assert_eq!(names(dir.path()).len(), 2, "two temporary files while open");
        drop(t);
        assert!(names(dir.path()).is_empty());
        // a band that cannot be encoded (a partial row)
        let t = open();
        assert!(t.band(0, w, &band(0)[1..]).is_err());
        assert!(t.finish().is_err());
        drop(t);
        assert!(names(dir.path()).is_empty());
    }
}
