//! Image quality metrics of `day2night eval`: PSNR, SSIM (scikit-image's default and the
//! Gaussian-window variant of Wang et al. 2004) and mean CIEDE2000 colour difference (and its
//! per-pixel map).
//!
//! All take two [`RgbImage`]s of the same size; a size mismatch is an
//! [`crate::Error::InvalidParam`] naming both sizes.

pub mod banded;
pub mod deltae;
pub mod psnr;
pub mod ssim;

pub use deltae::{ciede2000, delta_e_2000_map, mean_delta_e_2000, Lab};
pub use psnr::psnr;
pub use ssim::{ssim, SsimOptions, SsimWindow};

use crate::error::{Error, Result};
use crate::isp::RgbImage;

/// What `eval` does with NaN/Inf samples in either image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NonFinite {
    /// Refuse, naming the file and the count.
    #[default]
    Error,
    /// Replace them by 0, with a warning.
    Zero,
}

impl NonFinite {
    /// Both policies.
    pub const ALL: [NonFinite; 2] = [NonFinite::Error, NonFinite::Zero];
}

crate::choices! {
    NonFinite, ignore_case: true,
    unknown: |s| Error::invalid(format!(
        "nonfinite {s:?}: use {}",
        crate::choice::listed::<NonFinite>(", ", " or ")
    )),
    Error => "error": "Refuse, naming the file and the count",
    Zero => "zero": "Replace them by 0, with a warning",
}

/// Error unless `a` and `b` are valid images of the same size.
pub fn check_same_size(a: &RgbImage, b: &RgbImage) -> Result<()> {
    a.validate()?;
    b.validate()?;
    if a.width != b.width || a.height != b.height {
        return Err(Error::invalid(format!(
            "image sizes differ: {}x{} vs {}x{}",
            a.width, a.height, b.width, b.height
        )));
    }
    if a.width == 0 || a.height == 0 {
        return Err(Error::invalid("empty images"));
    }
    Ok(())
}
