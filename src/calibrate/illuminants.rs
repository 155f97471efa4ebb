//! Night illuminant dictionary from gray-card shots (docs/synthesis.md, "4. Night illuminants").
//!
//! Per gray-card DNG: over a region of interest (default: the central quarter-by-quarter of
//! the active area, i.e. `x = 3W/8, y = 3H/8, w = W/4, h = H/4`), the black-subtracted,
//! normalized samples of each CFA colour (both greens pooled) excluding saturated sites
//! (linearized value >= WhiteLevel), reduced with a 10 %-trimmed mean (robust to dust and
//! specular spots, no integer quantization as a median would have). Chromaticity
//! `[r/g, 1, b/g]`. Then a 2-D Gaussian over `[r/g, b/g]` by synth's own fit
//! (`synth::illuminant::Gaussian2::fit`): mean and covariance, unbiased (1/(M-1), default, as
//! the released code) or maximum-likelihood (1/M, the paper's eq. 2). A single illuminant gives
//! a zero covariance (documented fallback: synth then always draws that illuminant).
//!
//! Each card's light is also mapped to CIE 1931 xy through its capture's own colour matrices
//! (DNG chapter 6, [`CameraColor::neutral_to_xy`]), and the dictionary records the camera the
//! cards were shot with: `synth` uses the camera neutrals for that camera and the xy, through
//! the input's matrices, for any other (docs/calibration.md).

use super::format::{Gaussian2Fit, GrayCardMeasurement, IlluminantDictionary, ILLUMINANTS_FORMAT};
use super::stats::trimmed_mean;
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::isp::color::CameraColor;
use crate::normalize::Normalizer;
use crate::raw::camera::CameraId;
use crate::raw::RawImage;
use crate::synth::dictionaries::IlluminantDict;
use crate::synth::illuminant::{Covariance, Gaussian2};

/// Fraction trimmed at each end by the robust mean.
pub const TRIM: f64 = 0.1;
/// Saturated fraction of a colour above which a measurement carries a warning.
pub const SATURATION_WARN: f64 = 0.01;

/// A region of interest in active-area pixel coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Roi {
    /// First column.
    pub x: usize,
    /// First row.
    pub y: usize,
    /// Width.
    pub w: usize,
    /// Height.
    pub h: usize,
}

impl Roi {
    /// The default ROI: the central `W/4 x H/4` of a `W x H` active area (at least 2x2).
    pub fn central(w: usize, h: usize) -> Roi {
        let rw = (w / 4).max(2).min(w);
        let rh = (h / 4).max(2).min(h);
        Roi {
            x: (w - rw) / 2,
            y: (h - rh) / 2,
            w: rw,
            h: rh,
        }
    }
    /// Parse `X,Y,W,H`.
    pub fn parse(s: &str) -> Result<Roi> {
        let v: Vec<usize> = s
            .split(',')
            .map(|t| t.trim().parse::<usize>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| Error::invalid(format!("--roi {s:?}: expected X,Y,W,H (integers)")))?;
        match v.as_slice() {
            [x, y, w, h] if *w > 0 && *h > 0 => Ok(Roi {
                x: *x,
                y: *y,
                w: *w,
                h: *h,
            }),
            _ => Err(Error::invalid(format!(
                "--roi {s:?}: expected X,Y,W,H with W, H > 0"
            ))),
        }
    }
}

/// Which covariance normalisation to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Estimator {
    /// 1/(M-1) (released code; default).
    #[default]
    Unbiased,
    /// 1/M (paper eq. 2).
    Ml,
}

impl Estimator {
    /// synth's name for it.
    pub fn covariance(self) -> Covariance {
        match self {
            Estimator::Unbiased => Covariance::Unbiased,
            Estimator::Ml => Covariance::MaximumLikelihood,
        }
    }
    /// Name written in messages.
    pub fn covariance_name(self) -> &'static str {
        match self {
            Estimator::Unbiased => "unbiased",
            Estimator::Ml => "maximum_likelihood",
        }
    }
}

/// Measure one gray card. `roi` in active-area coordinates; `None` = [`Roi::central`].
pub fn measure_gray_card(
    img: &RawImage,
    roi: Option<Roi>,
    file: &str,
) -> Result<GrayCardMeasurement> {
    let n = Normalizer::new(img)?;
    let bayer = img.bayer()?;
    let a = img.active_area();
    let (aw, ah) = (a.width(), a.height());
    let roi = roi.unwrap_or_else(|| Roi::central(aw, ah));
    if roi.x + roi.w > aw || roi.y + roi.h > ah {
        return Err(Error::invalid(format!(
            "ROI {},{},{},{} lies outside the {}x{} active area",
            roi.x, roi.y, roi.w, roi.h, aw, ah
        )));
    }
    let mut vals: [Vec<f64>; 3] = Default::default();
    let mut sat = [0usize; 3];
    for r in roi.y..roi.y + roi.h {
        let row0 = (r + a.top as usize) * img.width + a.left as usize;
        for c in roi.x..roi.x + roi.w {
            let x = img.data.get(row0 + c).copied().unwrap_or(0);
            let col = bayer.color_at(r, c) as usize;
            if n.linearize(x) >= n.white {
                sat[col] += 1;
            } else if let Some(v) = vals.get_mut(col) {
                v.push(n.normalize(x, r, c));
            }
        }
    }
    let names = ["red", "green", "blue"];
    let mut means = [0.0; 3];
    let mut pixels = [0usize; 3];
    let mut warnings = Diagnostics::new();
    for k in 0..3 {
        let total = vals[k].len() + sat[k];
        pixels[k] = vals[k].len();
        let m = trimmed_mean(&mut vals[k], TRIM).ok_or_else(|| {
            Error::invalid(format!(
                "gray card: all {} {} sites in the ROI are saturated (reduce exposure)",
                total, names[k]
            ))
        })?;
        if m <= 0.0 {
            return Err(Error::invalid(format!(
                "gray card: mean {} level {:.3e} is not above black (card too dark or ROI misses it)",
                names[k], m
            )));
        }
        if total > 0 && sat[k] as f64 > SATURATION_WARN * total as f64 {
            warnings.warn(
                Code::GrayCardSaturated,
                format!(
                    "{} of {} {} sites saturated: the {} mean is biased low",
                    sat[k], total, names[k], names[k]
                ),
            );
        }
        means[k] = m;
    }
    let chromaticity = [means[0] / means[1], 1.0, means[2] / means[1]];
    let xy = match CameraColor::new(&img.meta.color).and_then(|c| c.neutral_to_xy(chromaticity)) {
        Ok(xy) if crate::bounds::chromaticity_xy("xy", xy).is_ok() => Some(xy),
        Ok(xy) => {
            warnings.warn(
                Code::GrayCardNoXy,
                format!(
                    "the colour matrices map this light to xy {xy:?}, not a light's chromaticity: \
                 no xy (the dictionary serves this camera only)"
                ),
            );
            None
        }
        Err(e) => {
            warnings.warn(
                Code::GrayCardNoXy,
                format!(
                    "no xy ({}): the dictionary serves this camera only",
                    e.root()
                ),
            );
            None
        }
    };
    let camera = CameraId::of(&img.meta);
    Ok(GrayCardMeasurement {
        file: file.to_string(),
        roi: [roi.x, roi.y, roi.w, roi.h],
        means,
        pixels,
        saturated: sat,
        chromaticity,
        xy,
        camera: (!camera.is_unknown()).then_some(camera),
        warnings,
    })
}

/// Mean and covariance of `[r/g, b/g]` over `chroma` (`[r/g, 1, b/g]` entries), computed by
/// synth's own fit ([`Gaussian2::fit`]) so that calibration and sampling agree. One
/// illuminant: zero covariance (synth then always uses it; the CLI warns). Errors on an
/// empty list or a non-positive chromaticity.
pub fn fit_gaussian(chroma: &[[f64; 3]], est: Estimator) -> Result<Gaussian2Fit> {
    if let Some(bad) = chroma
        .iter()
        .find(|c| !(c[0] > 0.0 && c[2] > 0.0 && c[0].is_finite() && c[2].is_finite()))
    {
        return Err(Error::invalid(format!(
            "illuminant {bad:?} is not a positive finite [r/g, 1, b/g] chromaticity"
        )));
    }
    let dict = IlluminantDict {
        name: "calibrate illuminants".into(),
        source: String::new(),
        chromaticities: chroma.iter().map(|c| [c[0], c[2]]).collect(),
        weights: Vec::new(),
    };
    let g = Gaussian2::fit(&dict, est.covariance())?;
    Ok(Gaussian2Fit {
        mean: g.mean,
        covariance: g.cov,
        count: g.count,
        estimator: g.estimator,
    })
}

/// Illuminants read from a JSON input of `calibrate illuminants`: their chromaticities and,
/// from a day2night dictionary, their xy (when it has one per chromaticity) and camera.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ListedIlluminants {
    /// `[r/g, 1, b/g]` each.
    pub chromaticities: Vec<[f64; 3]>,
    /// CIE 1931 xy, one per chromaticity, or empty.
    pub xy: Vec<[f64; 2]>,
    /// The camera the document says they were measured on.
    pub camera: Option<CameraId>,
}

/// [`parse_chromaticity_list`] plus a day2night dictionary's `xy` and `camera`.
pub fn parse_listed(text: &str) -> Result<ListedIlluminants> {
    let chromaticities = parse_chromaticity_list(text)?;
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| Error::malformed(format!("not valid JSON: {e}")))?;
    let xy = match v.get("xy") {
        Some(list) => {
            let xy: Vec<[f64; 2]> = serde_json::from_value(list.clone())
                .map_err(|e| Error::malformed(format!("xy: {e}")))?;
            if xy.len() != chromaticities.len() {
                return Err(Error::malformed(format!(
                    "{} xy for {} chromaticities",
                    xy.len(),
                    chromaticities.len()
                )));
            }
            for (i, p) in xy.iter().enumerate() {
                crate::bounds::chromaticity_xy(&format!("xy[{i}]"), *p)
                    .map_err(crate::bounds::malformed)?;
            }
            xy
        }
        None => vec![],
    };
    let camera = match v.get("camera") {
        Some(c) if !c.is_null() => {
            let c: CameraId = serde_json::from_value(c.clone())
                .map_err(|e| Error::malformed(format!("camera: {e}")))?;
            let c = CameraId::new(c.make, c.model, c.unique_camera_model);
            (!c.is_unknown()).then_some(c)
        }
        _ => None,
    };
    Ok(ListedIlluminants {
        chromaticities,
        xy,
        camera,
    })
}

/// Chromaticities from a JSON document: a day2night dictionary or the shared s20fe file
/// (key `illuminants_rgb_over_g`), or a bare list of `[r/g, 1, b/g]` or `[r/g, b/g]`.
pub fn parse_chromaticity_list(text: &str) -> Result<Vec<[f64; 3]>> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| Error::malformed(format!("not valid JSON: {e}")))?;
    let list = match &v {
        serde_json::Value::Array(_) => &v,
        serde_json::Value::Object(o) => o
            .get("illuminants_rgb_over_g")
            .ok_or_else(|| Error::malformed("JSON object has no `illuminants_rgb_over_g` list"))?,
        _ => return Err(Error::malformed("expected a list of chromaticities")),
    };
    let arr = list
        .as_array()
        .ok_or_else(|| Error::malformed("`illuminants_rgb_over_g` is not a list"))?;
    let max = crate::bounds::MAX_DICT_ENTRIES;
    if arr.len() > max {
        return Err(Error::limits(format!(
            "{} chromaticities (at most {max})",
            arr.len()
        )));
    }
    let big = crate::bounds::MAX_NEUTRAL_RATIO;
    let ok = |c: [f64; 3]| c.iter().all(|&x| x >= 1.0 / big && x <= big);
    arr.iter()
        .enumerate()
        .map(|(i, e)| {
            let nums: Option<Vec<f64>> = e
                .as_array()
                .map(|a| a.iter().map(|x| x.as_f64()).collect::<Option<Vec<f64>>>())
                .unwrap_or(None);
            match nums.as_deref() {
                Some([r, g, b]) if *g > 0.0 && ok([r / g, 1.0, b / g]) => Ok([r / g, 1.0, b / g]),
                Some([r, b]) if ok([*r, 1.0, *b]) => Ok([*r, 1.0, *b]),
                _ => Err(Error::malformed(format!(
                    "chromaticity #{i} is not [r/g, 1, b/g] or [r/g, b/g] numbers with \
                     ratios in [{}, {}]",
                    crate::bounds::short(1.0 / big),
                    crate::bounds::short(big)
                ))),
            }
        })
        .collect()
}

/// Assemble the dictionary file from gray-card measurements and listed illuminants (JSON
/// inputs), with what the user should know: the xy list is written when every illuminant
/// has one, the camera when every illuminant comes from the same known camera.
pub fn build_dictionary(
    files: Vec<GrayCardMeasurement>,
    extra: Vec<ListedIlluminants>,
    est: Estimator,
) -> Result<(IlluminantDictionary, Diagnostics)> {
    let mut all: Vec<[f64; 3]> = vec![];
    let mut xy: Vec<Option<[f64; 2]>> = vec![];
    let mut cameras: Vec<Option<CameraId>> = vec![];
    for l in &extra {
        all.extend(&l.chromaticities);
        xy.extend((0..l.chromaticities.len()).map(|i| l.xy.get(i).copied()));
        cameras.extend(l.chromaticities.iter().map(|_| l.camera.clone()));
    }
    for m in &files {
        all.push(m.chromaticity);
        xy.push(m.xy);
        cameras.push(m.camera.clone());
    }
    let fit = fit_gaussian(&all, est)?;
    let mut notes = Diagnostics::new();
    let xy: Vec<[f64; 2]> = match xy.iter().copied().collect::<Option<Vec<_>>>() {
        Some(v) => v,
        None => {
            let n = xy.iter().filter(|p| p.is_none()).count();
            notes.warn(
                Code::IlluminantsDictionary,
                format!(
                    "{n} of {} illuminants have no xy (no colour matrices, or a listed dictionary \
                 without them): the dictionary holds camera neutrals only, for this camera",
                    xy.len()
                ),
            );
            vec![]
        }
    };
    let first = cameras.first().cloned().flatten();
    let camera = match &first {
        Some(c)
            if cameras
                .iter()
                .all(|o| o.as_ref().and_then(|o| o.same_camera(c)) == Some(true)) =>
        {
            Some(c.clone())
        }
        _ => {
            let mut names: Vec<String> = cameras
                .iter()
                .map(|c| c.as_ref().map_or("an unknown camera".into(), |c| c.label()))
                .collect();
            names.sort();
            names.dedup();
            notes.warn(
                Code::IlluminantsDictionary,
                format!(
                    "the illuminants come from {}: the camera is not recorded, so synth uses the \
                 camera neutrals as they are for every camera{}",
                    names.join(", "),
                    if xy.is_empty() {
                        ""
                    } else {
                        " unless it uses the xy"
                    }
                ),
            );
            None
        }
    };
    let dict = IlluminantDictionary {
        format: ILLUMINANTS_FORMAT.into(),
        what: "Night illuminant dictionary: gray-card chromaticities [r/g, 1, b/g] in the raw colours of `camera`, their CIE 1931 xy through the captures' own colour matrices, and the 2-D Gaussian over [r/g, b/g] that synth samples illuminants from (for `camera`; other cameras use the xy through their own matrices)".into(),
        count: all.len(),
        illuminants_rgb_over_g: all,
        camera,
        observer: (!xy.is_empty()).then(|| "CIE 1931 2 degree".to_string()),
        xy,
        fit,
        files,
    };
    Ok((dict, notes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::meta::RawMeta;
    use crate::raw::{Bayer, Rect};

    fn card(bayer: Bayer, rgb: [f64; 3], w: usize, h: usize) -> RawImage {
        let meta = RawMeta::new_bayer(bayer, 12, 256.0, 4095.0);
        let mut data = vec![0u16; w * h];
        for r in 0..h {
            for c in 0..w {
                let v = rgb[bayer.color_at(r, c) as usize];
                // Deterministic +-3 DN pattern with zero mean over each 2x2 phase.
                let d = [-3.0, 3.0, 1.0, -1.0][(r / 2 + c / 2) % 4];
                data[r * w + c] = (256.0 + v + d).round() as u16;
            }
        }
        RawImage {
            width: w,
            height: h,
            data,
            meta,
        }
    }

    #[test]
    fn recovers_chromaticity_any_phase() {
        for b in Bayer::ALL {
            let img = card(b, [800.0, 1600.0, 400.0], 64, 48);
            let m = measure_gray_card(&img, None, "x").unwrap();
            assert!((m.chromaticity[0] - 0.5).abs() < 1e-3, "{b}: {m:?}");
            assert!((m.chromaticity[2] - 0.25).abs() < 1e-3, "{b}: {m:?}");
            assert_eq!(m.roi, [24, 18, 16, 12]);
        }
    }

    #[test]
    fn outliers_and_saturation_are_excluded() {
        let mut img = card(Bayer::RGGB, [800.0, 1600.0, 400.0], 64, 64);
        // A few hot pixels and saturated sites inside the ROI.
        for i in 0..6 {
            let idx = (24 + i) * 64 + 24 + 2 * i;
            img.data[idx] = 4095;
        }
        img.data[30 * 64 + 31] = 4000;
        let m = measure_gray_card(&img, None, "x").unwrap();
        assert!((m.chromaticity[0] - 0.5).abs() < 2e-3, "{m:?}");
        assert!(m.saturated.iter().sum::<usize>() == 6, "{m:?}");
    }

    #[test]
    fn all_saturated_and_bad_roi_are_errors() {
        let mut img = card(Bayer::RGGB, [800.0, 1600.0, 400.0], 16, 16);
        img.data.iter_mut().for_each(|v| *v = 4095);
        let e = measure_gray_card(&img, None, "x").unwrap_err().to_string();
        assert!(e.contains("saturated"), "{e}");
        let img = card(Bayer::RGGB, [800.0, 1600.0, 400.0], 16, 16);
        let e = measure_gray_card(&img, Some(Roi::parse("10,10,8,8").unwrap()), "x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("outside"), "{e}");
        assert!(Roi::parse("1,2,3").is_err() && Roi::parse("1,2,0,4").is_err());
    }

    #[test]
    fn roi_is_relative_to_active_area() {
        // Data laid out with RGGB starting at stored (1, 1) = the active area's origin.
        let (w, h) = (41, 41);
        let mut img = card(Bayer::RGGB, [800.0, 1600.0, 400.0], w, h);
        let rgb = [800.0, 1600.0, 400.0];
        for r in 0..h {
            for c in 0..w {
                let col = Bayer::RGGB.color_at(r + 1, c + 1) as usize;
                img.data[r * w + c] = (256.0 + rgb[col]) as u16;
            }
        }
        img.meta.active_area = Some(Rect {
            top: 1,
            left: 1,
            bottom: 41,
            right: 41,
        });
        let m = measure_gray_card(&img, Some(Roi::parse("3,3,20,20").unwrap()), "x").unwrap();
        assert!((m.chromaticity[0] - 0.5).abs() < 1e-9, "{m:?}");
        assert!((m.chromaticity[2] - 0.25).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn gaussian_fit_matches_definition() {
        let pts = [[0.5, 1.0, 0.3], [0.7, 1.0, 0.2], [0.9, 1.0, 0.4]];
        let f = fit_gaussian(&pts, Estimator::Unbiased).unwrap();
        assert!((f.mean[0] - 0.7).abs() < 1e-12 && (f.mean[1] - 0.3).abs() < 1e-12);
        assert!((f.covariance[0][0] - 0.04).abs() < 1e-12);
        assert!((f.covariance[0][1] - 0.01).abs() < 1e-12);
        assert!((f.covariance[1][1] - 0.01).abs() < 1e-12);
        let g = fit_gaussian(&pts, Estimator::Ml).unwrap();
        assert!((g.covariance[0][0] - 0.04 * 2.0 / 3.0).abs() < 1e-12);
        let one = fit_gaussian(&pts[..1], Estimator::Unbiased).unwrap();
        assert_eq!((one.covariance, one.count), ([[0.0; 2]; 2], 1));
        assert!(fit_gaussian(&[], Estimator::Unbiased).is_err());
        assert!(fit_gaussian(&[[0.0, 1.0, 0.3]], Estimator::Unbiased).is_err());
    }

    #[test]
    fn cards_record_their_camera_and_xy() {
        // A card lit by illuminant A, as the test camera's own matrices see it.
        let a = [0.44758, 0.40745];
        let meta = RawMeta::new_bayer(Bayer::RGGB, 12, 256.0, 4095.0);
        let n = CameraColor::new(&meta.color)
            .unwrap()
            .xy_to_neutral(a)
            .unwrap();
        let img = card(Bayer::GRBG, [1600.0 * n[0], 1600.0, 1600.0 * n[2]], 64, 48);
        let m = measure_gray_card(&img, None, "a").unwrap();
        let xy = m.xy.unwrap();
        assert!(
            (xy[0] - a[0]).abs() < 2e-3 && (xy[1] - a[1]).abs() < 2e-3,
            "{xy:?}"
        );
        assert_eq!(m.camera.as_ref().unwrap().label(), "day2night Synthetic");
        let (d, notes) =
            build_dictionary(vec![m.clone(), m.clone()], vec![], Estimator::Unbiased).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!(
            (d.xy.len(), d.camera, d.observer.is_some()),
            (2, m.camera.clone(), true)
        );
        // A listed dictionary without xy or camera: neutrals only, camera unknown, said.
        let listed = ListedIlluminants {
            chromaticities: vec![[0.5, 1.0, 0.3]],
            ..Default::default()
        };
        let (d, notes) =
            build_dictionary(vec![m.clone()], vec![listed], Estimator::Unbiased).unwrap();
        assert!(d.xy.is_empty() && d.camera.is_none() && d.observer.is_none());
        assert!(
            notes[0].message.contains("1 of 2 illuminants have no xy"),
            "{notes:?}"
        );
        assert!(notes[1].message.contains("an unknown camera"), "{notes:?}");
        // Another camera's cards: camera not recorded, xy kept.
        let mut other = m.clone();
        other.camera = Some(CameraId::new(Some("Nikon".into()), Some("D3".into()), None));
        let (d, notes) = build_dictionary(vec![m, other], vec![], Estimator::Unbiased).unwrap();
        assert!(d.camera.is_none() && d.xy.len() == 2);
        assert!(
            notes[0].message.contains("Nikon D3")
                && notes[0].message.contains("day2night Synthetic")
        );
        // No colour matrices: no xy, a warning on the card.
        let mut bare = card(Bayer::RGGB, [800.0, 1600.0, 400.0], 64, 48);
        bare.meta.color = Default::default();
        let m = measure_gray_card(&bare, None, "b").unwrap();
        assert!(
            m.xy.is_none() && m.warnings[0].message.contains("no ColorMatrix1"),
            "{m:?}"
        );
        // Round trip through JSON and parse_listed.
        let one = measure_gray_card(&img, None, "a").unwrap();
        let (d, _) = build_dictionary(vec![one], vec![], Estimator::Unbiased).unwrap();
        assert!(build_dictionary(vec![], vec![], Estimator::Unbiased).is_err());
        let l = parse_listed(&serde_json::to_string(&d).unwrap()).unwrap();
        assert_eq!((l.xy, l.camera), (d.xy.clone(), d.camera.clone()));
    }

    #[test]
    fn parses_lists_and_dictionaries() {
        let a = parse_chromaticity_list("[[0.5, 1, 0.3], [0.6, 0.2]]").unwrap();
        assert_eq!(a, vec![[0.5, 1.0, 0.3], [0.6, 1.0, 0.2]]);
        let b =
            parse_chromaticity_list(r#"{"illuminants_rgb_over_g": [[1.0, 2.0, 0.5]]}"#).unwrap();
        assert_eq!(b, vec![[0.5, 1.0, 0.25]]);
        assert!(parse_chromaticity_list("{}").is_err());
        assert!(parse_chromaticity_list("[[1]]").is_err());
    }
}
