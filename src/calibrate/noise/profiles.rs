//! Noise models read from the DNGs' own NoiseProfile tags ([`from_noise_profiles`]).

use super::iso_of;
use crate::calibrate::format::{IsoModel, PositionFit};
use crate::error::{Error, Result};
use crate::noise::model::NoiseParams;
use crate::raw::RawImage;
use std::collections::BTreeMap;

/// Models from the NoiseProfile tags of DNGs: one per ISO (files at the same ISO are
/// averaged). A profile with one (S, O) pair applies to all planes; with three, per colour.
pub fn from_noise_profiles(imgs: &[(String, &RawImage)]) -> Result<Vec<IsoModel>> {
    let mut by_iso: BTreeMap<u32, Vec<(String, &RawImage)>> = BTreeMap::new();
    for (name, img) in imgs {
        let iso = iso_of(img).map_err(|e| e.in_file(name))?;
        by_iso.entry(iso).or_default().push((name.clone(), img));
    }
    let mut out = vec![];
    for (iso, files) in by_iso {
        let mut sum = [[0.0f64; 2]; 4];
        let (mut black, mut white, mut bayer0) = (0.0, 0.0, None);
        for (name, img) in &files {
            let bayer = img.bayer().map_err(|e| e.in_file(name))?;
            if bayer0.is_some_and(|b| b != bayer) {
                return Err(Error::invalid(format!(
                    "CFA pattern {bayer} differs from the other files at ISO {iso}"
                ))
                .in_file(name));
            }
            bayer0 = Some(bayer);
            black = img.meta.levels.black_max();
            white = img.meta.levels.white;
            let np = img
                .meta
                .noise_profile
                .as_ref()
                .filter(|v| !v.is_empty())
                .ok_or_else(|| Error::invalid("the DNG has no NoiseProfile tag").in_file(name))?;
            let params = NoiseParams::from_dng_profile(np, bayer).map_err(|e| e.in_file(name))?;
            for (acc, so) in sum.iter_mut().zip(params.positions) {
                acc[0] += so[0];
                acc[1] += so[1];
            }
        }
        let bayer = bayer0.ok_or_else(|| Error::invalid("no files"))?;
        let k = files.len() as f64;
        let scale = white - black;
        let fits: Vec<PositionFit> = (0..4)
            .map(|p| {
                let (s, o) = (sum[p][0] / k, sum[p][1] / k);
                let beta1 = s * scale;
                PositionFit {
                    position: p,
                    color: ["R", "G", "B"][bayer.color_at(p / 2, p % 2) as usize % 3].into(),
                    s,
                    o,
                    s_stderr: None,
                    o_stderr: None,
                    beta1,
                    beta2: o * scale * scale - black * beta1,
                    r2: None,
                    chi2_reduced: None,
                    bins: 0,
                    pixels: 0,
                    clipped_pixels: 0,
                }
            })
            .collect();
        out.push(IsoModel {
            iso,
            positions: std::array::from_fn(|p| [fits[p].s, fits[p].o]),
            source: "noise_profile".into(),
            black,
            white,
            inputs: files.len(),
            quantization_variance_removed: 0.0,
            fits,
        });
    }
    Ok(out)
}
