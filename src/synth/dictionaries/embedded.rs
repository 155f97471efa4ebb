//! Embedded calibration: the cameras whose night illuminants and noise ship inside the
//! binary, as data files read by the same readers as a user's calibration files
//! (`synth --illuminants FILE`: [`super::xy::parse_illuminant_file`]; `--noise-model FILE`:
//! [`NoiseModel::from_json`]).
//!
//! One camera today: the capture phone of the CVPR 2022 day-to-night paper, a Samsung
//! Galaxy S20 FE (10-bit, black 64, white 1023), `calibration/samsung-s20fe/` in the
//! repository. Its figures derive from the public release of the paper's code and data
//! ("CVPR 2022 day-to-night release, CC BY-NC 4.0", Punnappurath, Abuolaim, Abdelhamed,
//! Levinshtein, Brown; Samsung Electronics): `utils/gray_card_illum_dict.mat` (night_dict:
//! 45 gray-card chromaticities) and `noise_profiler/h-gauss-s20-v1/model_params.npy`
//! (heteroscedastic Gaussian betas in DN per ISO and 2x2 position, kept in the noise file's
//! `dn_table` beside their normalized form). The release is licensed CC BY-NC 4.0 by its
//! authors: these figures carry that licence's attribution and non-commercial terms.
//!
//! Which camera an input is: [`for_camera`], the one lookup (Make, and a Model prefix,
//! compared as [`CameraId::make_and_model_prefix`] does).

use super::xy::parse_illuminant_file;
use super::{IlluminantDict, IlluminantSource};
use crate::error::{Error, Result};
use crate::noise::release::DnTable;
use crate::noise::NoiseModel;
use crate::raw::camera::CameraId;
use std::sync::OnceLock;

/// One camera's embedded calibration, decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraCalibration {
    /// Short name: the folder under `calibration/` (`samsung-s20fe`).
    pub key: &'static str,
    /// The night illuminant dictionary (camera RGB neutrals of this camera).
    pub illuminants: IlluminantDict,
    /// The camera the illuminant file names (its provenance's `camera`).
    pub illuminants_camera: CameraId,
    /// The noise model (its `camera` is the noise provenance's).
    pub noise: NoiseModel,
}

/// A registered camera: how to recognize it, and its files.
struct Entry {
    key: &'static str,
    /// Make, compared as [`CameraId::make_and_model_prefix`] does.
    make: &'static str,
    /// Model prefixes (any one), compared the same way.
    model_prefixes: &'static [&'static str],
    illuminants_json: &'static str,
    noise_json: &'static str,
}

/// The paper's phone: Make `samsung`, Model `SM-G780*` (4G) or `SM-G781*` (5G).
const PAPER_PHONE: Entry = Entry {
    key: "samsung-s20fe",
    make: "samsung",
    model_prefixes: &["SM-G780", "SM-G781"],
    illuminants_json: include_str!("../../../calibration/samsung-s20fe/illuminants.json"),
    noise_json: include_str!("../../../calibration/samsung-s20fe/noise.json"),
};

/// Every embedded camera; the first is the paper's phone ([`paper`]).
const CAMERAS: [Entry; 1] = [PAPER_PHONE];

fn decode(e: &Entry) -> Result<CameraCalibration> {
    let what = |part: &str| format!("embedded calibration {}/{part}.json", e.key);
    let v: serde_json::Value = serde_json::from_str(e.illuminants_json)
        .map_err(|err| Error::malformed(format!("{}: {err}", what("illuminants"))))?;
    let name = v.get("name").and_then(|n| n.as_str()).unwrap_or(e.key);
    let file = parse_illuminant_file(name, &v)?;
    let (Some(IlluminantSource::Dict(illuminants)), Some(camera)) = (file.rgb, file.camera) else {
        return Err(Error::malformed(format!(
            "{}: needs camera neutrals and a camera",
            what("illuminants")
        )));
    };
    let noise = NoiseModel::from_json(e.noise_json)?;
    Ok(CameraCalibration {
        key: e.key,
        illuminants,
        illuminants_camera: camera,
        noise,
    })
}

/// Every embedded camera's calibration, decoded once.
fn all() -> &'static [CameraCalibration] {
    static DECODED: OnceLock<Vec<CameraCalibration>> = OnceLock::new();
    DECODED.get_or_init(|| {
        CAMERAS
            .iter()
            .map(|e| match decode(e) {
                Ok(c) => c,
                // Data compiled into the binary, decoded by a unit test on every build.
                Err(err) => unreachable!("embedded calibration {} invalid: {err}", e.key),
            })
            .collect()
    })
}

/// The embedded calibration measured on `camera`'s model, if any.
pub fn for_camera(camera: &CameraId) -> Option<&'static CameraCalibration> {
    CAMERAS
        .iter()
        .position(|e| camera.make_and_model_prefix(e.make, e.model_prefixes))
        .map(|i| &all()[i])
}

/// The paper's phone's calibration: `--illuminants paper`, `--compat release`, and the noise
/// table of last resort.
pub fn paper() -> &'static CameraCalibration {
    &all()[0]
}

/// Attribution of the paper phone's figures (the illuminant file's `source`).
pub fn attribution() -> &'static str {
    &paper().illuminants.source
}

/// The paper phone's illuminant dictionary.
pub fn illuminants() -> IlluminantDict {
    paper().illuminants.clone()
}

/// The paper phone's noise model, in the portable normalized form.
pub fn noise_model() -> NoiseModel {
    paper().noise.clone()
}

/// The paper phone's noise table in DN as the release holds it (the noise file's
/// `dn_table`): the figures of the release's noise ([`crate::noise::release`]).
pub fn paper_dn_table() -> &'static DnTable {
    static TABLE: OnceLock<DnTable> = OnceLock::new();
    TABLE.get_or_init(|| match parse_dn_table(PAPER_PHONE.noise_json) {
        Ok(t) => t,
        // Data compiled into the binary, decoded by a unit test on every build.
        Err(err) => unreachable!("embedded calibration samsung-s20fe/noise.json: {err}"),
    })
}

/// A noise file's `dn_table` (`black`, `white`, `rows` of [ISO, position, beta1, beta2]).
fn parse_dn_table(json: &str) -> Result<DnTable> {
    #[derive(serde::Deserialize)]
    struct File {
        dn_table: Table,
    }
    #[derive(serde::Deserialize)]
    struct Table {
        black: f64,
        white: f64,
        rows: Vec<(u32, usize, f64, f64)>,
    }
    let f: File = serde_json::from_str(json)
        .map_err(|e| Error::malformed(format!("noise file dn_table: {e}")))?;
    Ok(DnTable {
        black: f.dn_table.black,
        white: f.dn_table.white,
        rows: f.dn_table.rows,
    })
}

#[cfg(test)]
#[path = "embedded_tests.rs"]
mod tests;
