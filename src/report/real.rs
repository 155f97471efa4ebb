//! The report's pictures from the real data: DNGs rendered by the software ISP, masks
//! re-evaluated from the synth sidecar's plan.

use super::build::{Illuminants, LightMark, Visuals};
use super::plot::Ellipse;
use super::thumb::{downscale, fit, Rgb8};
use crate::error::{Error, Result};
use crate::isp::{render_linear, RenderOptions, RgbImage};
use crate::synth::masks::PreparedMask;
use crate::synth::sidecar::Sidecar;
use crate::synth::LightKind;
use std::path::Path;

/// Visuals from DNG files and synth sidecars.
#[derive(Debug, Clone, Copy, Default)]
pub struct LibraryVisuals;

fn render(path: &Path) -> Result<RgbImage> {
    let raw = crate::dng::read::read_dng(path)?;
    render_linear(&raw, &RenderOptions::default())
}

fn px(img: &RgbImage, r: usize, c: usize) -> [f32; 3] {
    img.pixel(c, r).unwrap_or([0.0; 3])
}

fn thumbnail(img: &RgbImage, max: usize) -> Rgb8 {
    let (tw, th) = fit(img.width, img.height, max);
    let small = downscale(img.width, img.height, tw, th, |r, c| px(img, r, c));
    Rgb8::from_linear(tw, th, |r, c| {
        small.get(r * tw + c).copied().unwrap_or([0.0; 3])
    })
}

fn sidecar(v: &serde_json::Value) -> Result<Sidecar> {
    serde_json::from_value(v.clone()).map_err(|e| Error::malformed(format!("sidecar: {e}")))
}

impl Visuals for LibraryVisuals {
    fn day(&self, input: &Path, max: usize) -> Result<Rgb8> {
        Ok(thumbnail(&render(input)?, max))
    }

    fn night(&self, dng: &Path, max: usize) -> Result<Rgb8> {
        // Night renders are dark: show them as rendered (no exposure boost), so the page
        // shows what the dataset holds.
        Ok(thumbnail(&render(dng)?, max))
    }

    fn noisy_crop(&self, dng: &Path, size: usize) -> Result<Rgb8> {
        let img = render(dng)?;
        let (w, h) = (size.min(img.width), size.min(img.height));
        let (r0, c0) = ((img.height - h) / 2, (img.width - w) / 2);
        Ok(Rgb8::from_linear(w, h, |r, c| px(&img, r0 + r, c0 + c)))
    }

    fn masks(&self, v: &serde_json::Value, max: usize) -> Result<Vec<(String, Rgb8)>> {
        let sc = sidecar(v)?;
        let plan = &sc.plan;
        let (aw, ah) = (plan.active_width, plan.active_height);
        if aw == 0 || ah == 0 {
            return Err(Error::malformed("sidecar plan has an empty active area"));
        }
        let (tw, th) = fit(aw, ah, max);
        let mut out = Vec::new();
        for (kind, name) in [
            (LightKind::Ambient, "ambient"),
            (LightKind::Local, "local lights"),
            (LightKind::Bulb, "bulbs"),
        ] {
            let lights: Vec<_> = plan.lights.iter().filter(|l| l.kind == kind).collect();
            if lights.is_empty() {
                continue;
            }
            let prepared: Vec<PreparedMask> = lights
                .iter()
                .map(|l| PreparedMask::new(l, aw, ah, plan.mask_eval))
                .collect();
            let mut img = Rgb8::from_linear(tw, th, |r, c| {
                if kind == LightKind::Ambient {
                    return [1.0; 3];
                }
                // Sample the full-resolution mask at the thumbnail pixel's centre.
                let fr = ((r as f64 + 0.5) * ah as f64 / th as f64) as usize;
                let fc = ((c as f64 + 0.5) * aw as f64 / tw as f64) as usize;
                let m = prepared
                    .iter()
                    .map(|p| p.at(fr.min(ah - 1), fc.min(aw - 1)))
                    .fold(0f32, f32::max);
                [m, m, m]
            });
            for l in &lights {
                if kind != LightKind::Ambient {
                    let x = l.center[1] * tw as f64 / aw as f64;
                    let y = l.center[0] * th as f64 / ah as f64;
                    img.mark(x, y, 5, [255, 40, 40]);
                }
            }
            out.push((format!("{name} ({})", lights.len()), img));
        }
        Ok(out)
    }

    fn illuminants(&self, v: &serde_json::Value) -> Result<Illuminants> {
        let sc = sidecar(v)?;
        let g = &sc.calibration.illuminants;
        let plan = &sc.plan;
        let lights = plan
            .lights
            .iter()
            .map(|l| LightMark {
                kind: match l.kind {
                    LightKind::Ambient => 0,
                    LightKind::Local => 1,
                    LightKind::Bulb => 2,
                },
                centre: (l.kind != LightKind::Ambient).then(|| {
                    [
                        l.center[1] / plan.active_width.max(1) as f64,
                        l.center[0] / plan.active_height.max(1) as f64,
                    ]
                }),
                chroma: [l.illuminant[0], l.illuminant[2]],
            })
            .collect();
        Ok(Illuminants {
            kinds: vec!["ambient".into(), "local".into(), "bulb".into()],
            axes: ("r/g".into(), "b/g".into()),
            ellipse: Some(Ellipse {
                mean: g.mean,
                cov: g.cov,
            }),
            lights,
        })
    }

    fn dim_factor(&self, v: &serde_json::Value) -> Option<f64> {
        v.pointer("/run/dim_scale").and_then(|x| x.as_f64())
    }
}
