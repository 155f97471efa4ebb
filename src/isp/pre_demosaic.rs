//! The fused pre-demosaic step of a CFA image, written once (the `Normalize` stage and the
//! sample stages up to the demosaic, as the driver made them: [`Pipe::cfa`]): a stored sample normalized
//! ([`Normalizer`], DNG chapter 5) and passed through the sample stages of
//! [`STAGES`](super::stages::STAGES) (white balance and clip), in the order of the list
//! ([`Samples::between`]). Every execution fills the demosaicer's input from here: the
//! whole frame, the bands, a crop's samples, and the opcode paths around OpcodeList2.

use super::drive::Pipe;
use super::opcodes::pin;
use super::stages::{Samples, Stage};
use crate::error::Result;
use crate::normalize::{Normalizer, SiteTable};
use crate::raw::Bayer;

impl Pipe<'_> {
    /// The normalization and the sample stages of the CFA samples (the `Normalize` and
    /// `Sample` stages of the list); `linearize: false` drops the LinearizationTable (a
    /// crop's samples are linear). Here, not in drive.rs: the driver does not know how an
    /// execution fills the demosaicer's input.
    pub(crate) fn cfa(&self, linearize: bool) -> Result<CfaSites> {
        let norm = Normalizer::new(self.img)?;
        let norm = if linearize {
            norm
        } else {
            norm.without_linearization()
        };
        CfaSites::new(self.img.bayer()?, norm, self.samples())
    }
}

/// The normalization and sample stages of one render's CFA samples (from [`Pipe::cfa`]).
pub(crate) struct CfaSites {
    bayer: Bayer,
    norm: Normalizer,
    samples: Samples,
    /// Every stored value up to white through [`CfaSites::site`], per 2x2 position, when
    /// the black level is 2x2-periodic (same bits, looked up).
    table: Option<SiteTable<f32>>,
}

impl CfaSites {
    pub(crate) fn new(bayer: Bayer, norm: Normalizer, samples: Samples) -> Result<CfaSites> {
        let mut s = CfaSites {
            bayer,
            norm,
            samples,
            table: None,
        };
        s.table = SiteTable::new(&s.norm, |r, c, x| s.site(x, r, c, s.norm.black_at(r, c)));
        Ok(s)
    }

    /// The stored sample `x` at active-area (r, c) of black level `black`, normalized and
    /// through every sample stage up to the demosaic (no OpcodeList2 applies): the
    /// demosaicer's input.
    #[inline]
    pub(crate) fn site(&self, x: u16, r: usize, c: usize, black: f64) -> f32 {
        let v = self.norm.normalize_with_black(x, black);
        let k = self.bayer.color_at(r, c) as usize;
        self.samples
            .between(Stage::Normalize, Stage::Demosaic, v, k) as f32
    }

    /// The samples `cs` of active-area row `r` into `out` through [`CfaSites::site`]:
    /// `src[c - offset]` is the stored value of column `c`, `w` the active area's width.
    /// Looked up when tabulated; wide rows take their black levels from
    /// [`Normalizer::black_row`] (bit-identical to `black_at`, without two integer divisions
    /// per sample) in `blacks`; narrow ones (orientations 5-8) ask per sample.
    #[inline]
    pub(crate) fn fill(&self, row: FillRow, cs: &[usize], out: &mut [f32]) {
        let FillRow {
            src,
            offset,
            r,
            w,
            blacks,
        } = row;
        let norm = &self.norm;
        if let Some(t) = &self.table {
            let (t0, t1) = t.row(r);
            for (o, &c) in out.iter_mut().zip(cs) {
                let x = src[c - offset];
                let tab = if c & 1 == 0 { t0 } else { t1 };
                *o = match tab.get(x as usize) {
                    Some(&v) => v,
                    None => self.site(x, r, c, norm.black_at(r, c)),
                };
            }
        } else if 2 * cs.len() >= w {
            blacks.resize(w, 0.0);
            norm.black_row(r, blacks);
            for (o, &c) in out.iter_mut().zip(cs) {
                *o = self.site(src[c - offset], r, c, blacks[c]);
            }
        } else {
            for (o, &c) in out.iter_mut().zip(cs) {
                *o = self.site(src[c - offset], r, c, norm.black_at(r, c));
            }
        }
    }

    /// The stored sample `x` at active-area (r, c) normalized, through the sample stages
    /// before OpcodeList2 and pinned into [0, 1] like the DNG SDK's 16-bit stage-2 image.
    #[inline]
    pub(crate) fn stage2(&self, x: u16, r: usize, c: usize) -> f32 {
        let v = self.norm.normalize(x, r, c);
        let k = self.bayer.color_at(r, c) as usize;
        pin(
            self.samples
                .between(Stage::Normalize, Stage::Opcodes2, v, k) as f32,
            1.0,
        )
    }

    /// The stage-2 value `v` at active-area (r, c) (OpcodeList2 applied) through the sample
    /// stages after OpcodeList2: the demosaicer's input on the opcode paths.
    #[inline]
    pub(crate) fn balanced(&self, v: f32, r: usize, c: usize) -> f32 {
        let k = self.bayer.color_at(r, c) as usize;
        self.samples.between(Stage::Opcodes2, Stage::Demosaic, v, k)
    }
}

/// One row's stored samples for [`CfaSites::fill`].
pub(crate) struct FillRow<'a> {
    /// The stored values, `src[c - offset]` for active-area column `c`.
    pub(crate) src: &'a [u16],
    /// The active-area column of `src[0]`.
    pub(crate) offset: usize,
    /// The active-area row.
    pub(crate) r: usize,
    /// The active area's width.
    pub(crate) w: usize,
    /// Scratch for a row's black levels.
    pub(crate) blacks: &'a mut Vec<f64>,
}
