//! The report's pictures from the real data: DNGs rendered by the software ISP, masks
//! re-evaluated from the synth sidecar's plan.

use super::build::{Illuminants, LightMark, Visuals};
use super::plot::Ellipse;
use super::thumb::{downscale, fit, Rgb8};
use crate::error::{Error, Result};
use crate::isp::color::CameraColor;
use crate::isp::render::DisplayGeometry;
use crate::isp::{RenderOptions, RgbImage};
use crate::synth::masks::PreparedMask;
use crate::synth::sidecar::Sidecar;
use crate::synth::LightKind;
use std::path::Path;

/// Visuals from DNG files and synth sidecars.
#[derive(Debug, Clone, Copy, Default)]
pub struct LibraryVisuals;

fn render(path: &Path) -> Result<RgbImage> {
    let raw = crate::dng::read::read_dng(path)?;
    crate::isp::render(&raw, &RenderOptions::default())
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

/// A sidecar of either version ([`Sidecar::from_value`]).
fn sidecar(v: &serde_json::Value) -> Result<Sidecar> {
    Sidecar::from_value(v.clone())
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

    fn masks(
        &self,
        v: &serde_json::Value,
        night_dng: Option<&Path>,
        max: usize,
    ) -> Result<Vec<(String, Rgb8)>> {
        let sc = sidecar(v)?;
        let plan = &sc.plan;
        let (aw, ah) = (plan.active_width, plan.active_height);
        if aw == 0 || ah == 0 {
            return Err(Error::malformed("sidecar plan has an empty active area"));
        }
        let geo = match night_dng {
            Some(p) => {
                let raw = crate::dng::read::read_dng(p)?;
                let a = raw.active_area();
                if (a.width(), a.height()) != (aw, ah) {
                    return Err(Error::invalid(format!(
                        "{}: active area {}x{} differs from the sidecar's {}x{}",
                        p.display(),
                        a.width(),
                        a.height(),
                        aw,
                        ah
                    )));
                }
                DisplayGeometry::new(&raw.meta, aw, ah)
            }
            None => DisplayGeometry::identity(aw, ah),
        };
        let (dw, dh) = geo.dims();
        let (tw, th) = fit(dw, dh, max);
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
                // Sample the full-resolution mask at the active-area site shown at the
                // thumbnail pixel's centre.
                let yo = ((r as f64 + 0.5) * dh as f64 / th as f64) as usize;
                let xo = ((c as f64 + 0.5) * dw as f64 / tw as f64) as usize;
                let (fc, fr) = geo.active_site(xo, yo);
                let m = prepared
                    .iter()
                    .map(|p| p.at(fr.min(ah - 1), fc.min(aw - 1)))
                    .fold(0f32, f32::max);
                [m, m, m]
            });
            for l in &lights {
                if kind != LightKind::Ambient {
                    // centre of site (row, col) in continuous coordinates
                    let shown = geo.display_point(l.center[1] + 0.5, l.center[0] + 0.5);
                    if let Some((x, y)) = shown {
                        // `mark` takes pixel-centred coordinates (pixel i is at i)
                        let (mx, my) = (x * tw as f64 / dw as f64, y * th as f64 / dh as f64);
                        img.mark(mx - 0.5, my - 0.5, 5, [255, 40, 40]);
                    }
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

    fn illuminants_xy(
        &self,
        v: &serde_json::Value,
        night_dng: Option<&Path>,
    ) -> Result<Illuminants> {
        let mut ill = self.illuminants(v)?;
        let dng = night_dng.ok_or_else(|| {
            Error::invalid("no clean night DNG: the xy plot needs the camera's colour matrices")
        })?;
        let raw = crate::dng::read::read_dng(dng)?;
        let color = CameraColor::new(&raw.meta.color).map_err(|e| e.in_file(dng))?;
        let plan = sidecar(v)?.plan;
        for (mark, light) in ill.lights.iter_mut().zip(&plan.lights) {
            let xy = color
                .neutral_to_xy(light.illuminant)
                .map_err(|e| e.in_file(dng))?;
            mark.chroma = xy;
        }
        ill.axes = ("x".into(), "y".into());
        ill.ellipse = None;
        Ok(ill)
    }

    fn dim_factor(&self, v: &serde_json::Value) -> Option<f64> {
        v.pointer("/run/dim_scale").and_then(|x| x.as_f64())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::OutputPolicy;
    use crate::synth::job::{DayInput, DirSink, SynthJob, Target};
    use crate::synth::SynthOptions;

    /// RGB of pixel (x, y).
    fn at(img: &Rgb8, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y * img.width + x);
        [img.data[i], img.data[i + 1], img.data[i + 2]]
    }

    #[test]
    fn lights_in_xy_go_through_the_files_matrices_and_lie_near_the_locus() {
        let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/day.dng");
        let day = DayInput::read(&fix).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let mut job = SynthJob::new(SynthOptions {
            isos: vec![],
            ..SynthOptions::default()
        })
        .unwrap();
        job.target = Target::None;
        let plan = job.plan(&day, "day.dng", 1, 0).unwrap();
        let policy = OutputPolicy::default();
        let sink = DirSink::new(dir.path(), job.base_name("day", &plan.plan), &policy);
        job.run_variant(&day, &plan, &sink).unwrap();
        let sc: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("day.json")).unwrap()).unwrap();
        let vis = LibraryVisuals;
        let clean = dir.path().join("day_clean.dng");
        let xy = vis.illuminants_xy(&sc, Some(&clean)).unwrap();
        assert_eq!(xy.lights.len(), plan.plan.lights.len());
        assert_eq!(xy.axes.0, "x");
        let color = CameraColor::new(&day.raw.meta.color).unwrap();
        for (m, l) in xy.lights.iter().zip(&plan.plan.lights) {
            let (cct, duv) = crate::color::planck::cct_duv(m.chroma).unwrap();
            assert!(
                (1500.0..8000.0).contains(&cct) && duv.abs() < 0.03,
                "{cct} {duv}"
            );
            // back to the same neutral through the day file's matrices
            let n = color.xy_to_neutral(m.chroma).unwrap();
            assert!((n[0] - l.illuminant[0]).abs() < 1e-6 && (n[2] - l.illuminant[2]).abs() < 1e-6);
        }
        assert!(vis.illuminants_xy(&sc, None).is_err());
    }

    #[test]
    fn masks_follow_the_night_render_geometry() {
        let fix = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/day.dng");
        let mut day = DayInput::read(&fix).unwrap();
        let a = day.raw.active_area();
        let (aw, ah) = (a.width(), a.height());
        let dir = tempfile::tempdir().unwrap();
        let mut job = SynthJob::new(SynthOptions {
            isos: vec![],
            ..SynthOptions::default()
        })
        .unwrap();
        job.target = Target::None;
        let vis = LibraryVisuals;
        let mut shapes = Vec::new();
        for orientation in [1u16, 6] {
            day.raw.meta.orientation = orientation;
            day.raw.meta.default_crop_origin = Some([8.0, 4.0]);
            day.raw.meta.default_crop_size = Some([(aw - 24) as f64, (ah - 12) as f64]);
            let plan = job.plan(&day, "day.dng", 3, 0).unwrap();
            let out = dir.path().join(format!("o{orientation}"));
            std::fs::create_dir_all(&out).unwrap();
            let policy = OutputPolicy::default();
            let sink = DirSink::new(&out, job.base_name("day", &plan.plan), &policy);
            job.run_variant(&day, &plan, &sink).unwrap();
            let sc: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("day.json")).unwrap()).unwrap();
            let clean = out.join("day_clean.dng");
            let night = vis.night(&clean, 64).unwrap();
            let masks = vis.masks(&sc, Some(&clean), 64).unwrap();
            let local = masks
                .iter()
                .find(|(n, _)| n.starts_with("local"))
                .map(|(_, m)| m)
                .expect("a local-light mask");
            // same thumbnail shape as the night render it is shown next to
            assert_eq!((local.width, local.height), (night.width, night.height));
            // the unrotated whole-active-area view keeps the sidecar's shape
            let plain = vis.masks(&sc, None, 64).unwrap();
            assert_eq!(plain[0].1.width.max(plain[0].1.height), 64);
            shapes.push((local.clone(), sc["plan"]["lights"].clone()));
            // a DNG of another size is refused
            let other = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/tiny_1x1.dng");
            if other.is_file() {
                assert!(vis.masks(&sc, Some(&other), 64).is_err());
            }
        }
        // Same lights (the plan does not depend on the orientation), so the orientation-6
        // mask is the orientation-1 mask turned clockwise: displayed (xo, yo) shows what
        // the unrotated thumbnail has at (yo, h1 - 1 - xo). The red centre marks are
        // (red, outlined in black) are drawn with rounding of their own: compare the other
        // pixels.
        let ((m1, l1), (m6, l6)) = (&shapes[0], &shapes[1]);
        assert_eq!(l1, l6);
        assert_eq!((m1.width, m1.height), (m6.height, m6.width));
        let (mut same, mut grey, mut levels) = (0, 0, std::collections::BTreeSet::new());
        for yo in 0..m6.height {
            for xo in 0..m6.width {
                let (a, b) = (at(m6, xo, yo), at(m1, yo, m1.height - 1 - xo));
                let plain = |p: [u8; 3]| p[0] == p[1] && p[1] == p[2] && p[0] > 0;
                if plain(a) && plain(b) {
                    grey += 1;
                    same += usize::from(a == b);
                    levels.insert(a[0]);
                }
            }
        }
        assert!(levels.len() > 8, "mask too flat to test: {levels:?}");
        assert!(
            grey > m6.width * m6.height / 2 && same == grey,
            "{same}/{grey}"
        );
    }
}
