//! Colour maths, at the bottom of the crate: 3x3 matrices, CIE XYZ and xy, the standard
//! whites, Bradford adaptation, the XYZ <-> sRGB matrices, the sRGB transfer curves, the
//! Planckian locus and correlated colour temperature (Robertson's, as the DNG SDK picks
//! matrices; and CCT/Duv from the locus, for judging lights).
//!
//! Pure functions of numbers: nothing here knows a file format, a raw image or an option.
//! Everything above uses it (the DNG reader's checks, the thumbnail, the renders, the
//! metrics, synthesis, the report, the Python package), so each formula and constant is
//! written once (docs/architecture.md, "Layers").
//!
//! * [`matrix3`]: products, determinant, inverse, condition number.
//! * [`xyz`]: xy <-> XYZ, D50/D65, Bradford, XYZ <-> linear sRGB.
//! * [`srgb`]: the sRGB OETF and its inverse, 8-bit encoding.
//! * [`cct`]: Robertson CCT and the EXIF LightSource temperatures (the DNG SDK's).
//! * [`planck`]: the Planckian locus, CCT and Duv.

pub mod cct;
pub mod matrix3;
pub mod planck;
pub mod srgb;
pub mod xyz;
