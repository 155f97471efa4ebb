//! The HTML report: built over a fake dataset with fake visuals, its PNGs decode, and it
//! loads in a real headless browser (Debian `chromium`, required) with no console errors
//! and produces a screenshot.

use crate::{common, dataset_fake};

use dataset_fake::{load_in_browser, make_day_dir, opts, Fake};
use day2night::dataset;
use day2night::report::{
    self, plot::Ellipse, thumb::Rgb8, Illuminants, LightMark, ReportOptions, Visuals,
};
use day2night::Result;
use std::path::Path;

struct FakeVisuals;

fn gradient(max: usize, tint: [f32; 3]) -> Rgb8 {
    let (w, h) = report::thumb::fit(300, 200, max);
    Rgb8::from_linear(w, h, |r, c| {
        let v = (r + c) as f32 / (w + h) as f32;
        [v * tint[0], v * tint[1], v * tint[2]]
    })
}

impl Visuals for FakeVisuals {
    fn day(&self, input: &Path, max: usize) -> Result<Rgb8> {
        assert!(input.is_file(), "{}", input.display());
        Ok(gradient(max, [1.0, 0.9, 0.7]))
    }
    fn night(&self, dng: &Path, max: usize) -> Result<Rgb8> {
        assert!(dng.is_file(), "{}", dng.display());
        Ok(gradient(max, [0.1, 0.1, 0.3]))
    }
    fn noisy_crop(&self, dng: &Path, size: usize) -> Result<Rgb8> {
        assert!(dng.is_file(), "{}", dng.display());
        Ok(Rgb8::from_linear(size, size, |r, c| {
            [((r * 7 + c * 13) % 17) as f32 / 40.0; 3]
        }))
    }
    fn masks(
        &self,
        _sc: &serde_json::Value,
        night: Option<&Path>,
        max: usize,
    ) -> Result<Vec<(String, Rgb8)>> {
        assert!(night.is_some_and(|p| p.is_file()), "{night:?}");
        let mut m = gradient(max, [1.0, 1.0, 1.0]);
        m.mark(50.0, 40.0, 6, [255, 0, 0]);
        Ok(vec![
            ("ambient".into(), gradient(max, [0.5; 3])),
            ("local lights".into(), m.clone()),
            ("bulbs".into(), m),
        ])
    }
    fn illuminants(&self, sc: &serde_json::Value) -> Result<Illuminants> {
        let seed = sc["h"].as_u64().unwrap_or(0);
        let f = (seed % 1000) as f64 / 10000.0;
        Ok(Illuminants {
            kinds: vec!["ambient".into(), "local".into(), "bulb".into()],
            axes: ("r/g".into(), "b/g".into()),
            ellipse: Some(Ellipse {
                mean: [0.6, 0.5],
                cov: [[0.004, 0.001], [0.001, 0.003]],
            }),
            lights: (0..3)
                .map(|k| LightMark {
                    kind: k,
                    centre: Some([0.3, 0.4]),
                    chroma: [0.55 + f, 0.45 + f * k as f64],
                })
                .collect(),
        })
    }
    fn illuminants_xy(&self, sc: &serde_json::Value, night: Option<&Path>) -> Result<Illuminants> {
        assert!(night.is_some_and(|p| p.is_file()), "{night:?}");
        let mut il = self.illuminants(sc)?;
        for l in &mut il.lights {
            l.chroma = [0.40 + l.chroma[0] / 10.0, 0.38 + l.chroma[1] / 50.0];
        }
        il.axes = ("x".into(), "y".into());
        il.ellipse = None;
        Ok(il)
    }
    fn dim_factor(&self, sc: &serde_json::Value) -> Option<f64> {
        Some((sc["h"].as_u64()? % 97) as f64 / 970.0)
    }
}

#[test]
#[cfg_attr(
    d2n_missing = "chromium",
    ignore = "needs chromium (D2N_ALLOW_MISSING)"
)]
fn report_builds_decodes_and_loads_headless() {
    let day = make_day_dir(14);
    std::fs::write(day.path().join("b/broken.dng"), b"bad").unwrap();
    let out = tempfile::tempdir().unwrap();
    let mut o = opts(day.path(), out.path());
    o.split = dataset::SplitRule::LastN(4);
    let s = dataset::run(&o, &Fake::new("x")).unwrap();
    assert_eq!(s.failed, 1);
    let ro = ReportOptions {
        out_dir: out.path().to_path_buf(),
        day_dir: Some(day.path().to_path_buf()),
        samples: 5,
        thumb: 240,
    };
    let rep = report::build(&ro, &FakeVisuals).unwrap();
    assert_eq!((rep.records, rep.samples), (15, 5));
    assert!(rep.warnings.is_empty(), "{:?}", rep.warnings);
    assert_eq!(rep.pngs.len(), 5 * 6);
    for p in &rep.pngs {
        let img = image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(img.width() > 0 && img.height() > 0);
    }
    let html = std::fs::read_to_string(&rep.page).unwrap();
    for needle in [
        "Dimming factor",
        "Night neutral r/g",
        "Night neutral b/g",
        "ISO",
        "Sampled illuminants",
        "Lights in CIE xy",
        "Planckian locus",
        "broken.dng",
        "Failures",
    ] {
        assert!(html.contains(needle), "page lacks {needle}");
    }
    assert!(
        !html.contains("http://")
            || html
                .matches("http://")
                .all(|_| html.contains("xmlns=\"http://www.w3.org/2000/svg\""))
    );
    assert!(!html.contains("https://"), "page refers to the network");

    let chromium = common::chromium();
    let (console, shot) = load_in_browser(&chromium, &rep.page);
    assert!(console.is_empty(), "console output: {console:#?}");
    if let Some(keep) = std::env::var_os("D2N_REPORT_SCREENSHOT") {
        std::fs::write(keep, &shot).unwrap();
    }
    let img = image::load_from_memory(&shot).expect("screenshot is not a PNG");
    let rgb = img.to_rgb8();
    let distinct: std::collections::HashSet<[u8; 3]> = rgb.pixels().map(|p| p.0).collect();
    assert!(
        distinct.len() > 50,
        "screenshot looks blank ({} colours)",
        distinct.len()
    );

    // The check can fail: a missing image is reported on the console.
    std::fs::remove_file(&rep.pngs[0]).unwrap();
    let (console, _) = load_in_browser(&chromium, &rep.page);
    assert!(
        console.iter().any(|l| l.contains("image failed to load")),
        "{console:#?}"
    );
}
