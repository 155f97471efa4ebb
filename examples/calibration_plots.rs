//! Draw the calibration figures of docs/calibration.md with the `image` crate:
//!
//! - `calibration_illuminants.png`: the 45 embedded gray-card chromaticities of the paper's
//!   phone, the Gaussian fitted by `calibrate illuminants` (1, 2, 3 sigma ellipses) and 30
//!   illuminants drawn by synth's sampler (seed 0);
//! - `calibration_noise.png`: per-bin variance vs mean of two synthetic bursts (ISO 1600 and
//!   3200 of the embedded paper-phone model, 16 frames of 512x256, 2x2 position 0) with the
//!   weighted least-squares lines `calibrate noise` fits, and the true model dashed.
//!
//! Run: `cargo run --example calibration_plots -- docs/img` (prints the fitted numbers).
use day2night::calibrate::illuminants::{fit_gaussian, Estimator};
use day2night::calibrate::noise::{fit_iso, BurstAccumulator};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use day2night::synth::dictionaries::embedded;
use day2night::synth::illuminant::{Gaussian2, SamplerRules};
use day2night::synth::rng::SynthRng;
use image::{Rgb, RgbImage};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use std::path::PathBuf;

const W: u32 = 900;
const H: u32 = 640;
const ML: f64 = 110.0;
const MR: f64 = 30.0;
const MT: f64 = 60.0;
const MB: f64 = 80.0;

fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_lowercase() {
        '0' => [14, 17, 19, 21, 25, 17, 14],
        '1' => [4, 12, 4, 4, 4, 4, 14],
        '2' => [14, 17, 1, 2, 4, 8, 31],
        '3' => [31, 2, 4, 2, 1, 17, 14],
        '4' => [2, 6, 10, 18, 31, 2, 2],
        '5' => [31, 16, 30, 1, 1, 17, 14],
        '6' => [6, 8, 16, 30, 17, 17, 14],
        '7' => [31, 1, 2, 4, 8, 8, 8],
        '8' => [14, 17, 17, 14, 17, 17, 14],
        '9' => [14, 17, 17, 15, 1, 2, 12],
        'a' => [0, 0, 14, 1, 15, 17, 15],
        'b' => [16, 16, 22, 25, 17, 17, 30],
        'c' => [0, 0, 14, 16, 16, 17, 14],
        'd' => [1, 1, 13, 19, 17, 17, 15],
        'e' => [0, 0, 14, 17, 31, 16, 14],
        'f' => [6, 9, 8, 28, 8, 8, 8],
        'g' => [0, 15, 17, 17, 15, 1, 14],
        'h' => [16, 16, 22, 25, 17, 17, 17],
        'i' => [4, 0, 12, 4, 4, 4, 14],
        'j' => [2, 0, 6, 2, 2, 18, 12],
        'k' => [16, 16, 18, 20, 24, 20, 18],
        'l' => [12, 4, 4, 4, 4, 4, 14],
        'm' => [0, 0, 26, 21, 21, 17, 17],
        'n' => [0, 0, 22, 25, 17, 17, 17],
        'o' => [0, 0, 14, 17, 17, 17, 14],
        'p' => [0, 0, 30, 17, 30, 16, 16],
        'q' => [0, 0, 13, 19, 15, 1, 1],
        'r' => [0, 0, 22, 25, 16, 16, 16],
        's' => [0, 0, 14, 16, 14, 1, 30],
        't' => [8, 8, 28, 8, 8, 9, 6],
        'u' => [0, 0, 17, 17, 17, 19, 13],
        'v' => [0, 0, 17, 17, 17, 10, 4],
        'w' => [0, 0, 17, 17, 21, 21, 10],
        'x' => [0, 0, 17, 10, 4, 10, 17],
        'y' => [0, 0, 17, 17, 15, 1, 14],
        'z' => [0, 0, 31, 2, 4, 8, 31],
        '.' => [0, 0, 0, 0, 0, 12, 12],
        '-' => [0, 0, 0, 31, 0, 0, 0],
        '/' => [0, 1, 2, 4, 8, 16, 0],
        '(' => [2, 4, 8, 8, 8, 4, 2],
        ')' => [8, 4, 2, 2, 2, 4, 8],
        ',' => [0, 0, 0, 0, 12, 4, 8],
        ':' => [0, 12, 12, 0, 12, 12, 0],
        '+' => [0, 4, 4, 31, 4, 4, 0],
        '=' => [0, 0, 31, 0, 31, 0, 0],
        '^' => [4, 10, 17, 0, 0, 0, 0],
        '*' => [0, 4, 21, 14, 21, 4, 0],
        _ => [0; 7],
    }
}

struct Plot {
    img: RgbImage,
    x: (f64, f64),
    y: (f64, f64),
}

impl Plot {
    fn new(x: (f64, f64), y: (f64, f64)) -> Plot {
        Plot {
            img: RgbImage::from_pixel(W, H, Rgb([255, 255, 255])),
            x,
            y,
        }
    }
    fn px(&self, x: f64, y: f64) -> (f64, f64) {
        let u = ML + (x - self.x.0) / (self.x.1 - self.x.0) * (W as f64 - ML - MR);
        let v = H as f64 - MB - (y - self.y.0) / (self.y.1 - self.y.0) * (H as f64 - MT - MB);
        (u, v)
    }
    fn dot(&mut self, u: f64, v: f64, r: f64, c: Rgb<u8>) {
        let ri = r.ceil() as i64;
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                if ((dx * dx + dy * dy) as f64) <= r * r {
                    self.put(u as i64 + dx, v as i64 + dy, c);
                }
            }
        }
    }
    fn put(&mut self, x: i64, y: i64, c: Rgb<u8>) {
        if x >= 0 && y >= 0 && (x as u32) < W && (y as u32) < H {
            self.img.put_pixel(x as u32, y as u32, c);
        }
    }
    fn line_px(&mut self, a: (f64, f64), b: (f64, f64), width: f64, c: Rgb<u8>, dash: bool) {
        let n = ((b.0 - a.0).hypot(b.1 - a.1)).ceil().max(1.0) as usize;
        for i in 0..=n {
            if dash && (i / 8) % 2 == 1 {
                continue;
            }
            let t = i as f64 / n as f64;
            self.dot(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1), width / 2.0, c);
        }
    }
    /// Data-space polyline clipped to the plot box (point-wise).
    fn polyline(&mut self, pts: &[(f64, f64)], width: f64, c: Rgb<u8>, dash: bool) {
        for w in pts.windows(2) {
            let (a, b) = (self.px(w[0].0, w[0].1), self.px(w[1].0, w[1].1));
            let inside = |p: (f64, f64)| {
                p.0 >= ML && p.0 <= W as f64 - MR && p.1 >= MT && p.1 <= H as f64 - MB
            };
            if inside(a) && inside(b) {
                self.line_px(a, b, width, c, dash);
            }
        }
    }
    fn text(&mut self, x: f64, y: f64, s: &str, scale: i64, c: Rgb<u8>) {
        for (k, ch) in s.chars().enumerate() {
            let g = glyph(ch);
            for (r, bits) in g.iter().enumerate() {
                for col in 0..5 {
                    if bits & (16 >> col) != 0 {
                        for sy in 0..scale {
                            for sx in 0..scale {
                                self.put(
                                    x as i64 + (k as i64 * 6 + col) * scale + sx,
                                    y as i64 + r as i64 * scale + sy,
                                    c,
                                );
                            }
                        }
                    }
                }
            }
        }
    }
    fn text_width(s: &str, scale: i64) -> f64 {
        (s.chars().count() as i64 * 6 * scale) as f64
    }
    fn axes(
        &mut self,
        title: &str,
        xl: &str,
        yl: &str,
        xt: &[f64],
        yt: &[f64],
        yfmt: &dyn Fn(f64) -> String,
    ) {
        let k = Rgb([0, 0, 0]);
        let grey = Rgb([225, 225, 225]);
        for &t in xt {
            let (u, _) = self.px(t, self.y.0);
            self.line_px((u, MT), (u, H as f64 - MB), 1.0, grey, false);
            let s = format!("{t}");
            self.text(
                u - Self::text_width(&s, 2) / 2.0,
                H as f64 - MB + 10.0,
                &s,
                2,
                k,
            );
        }
        for &t in yt {
            let (_, v) = self.px(self.x.0, t);
            self.line_px((ML, v), (W as f64 - MR, v), 1.0, grey, false);
            let s = yfmt(t);
            self.text(ML - 10.0 - Self::text_width(&s, 2), v - 7.0, &s, 2, k);
        }
        let (l, r, t, b) = (ML, W as f64 - MR, MT, H as f64 - MB);
        self.line_px((l, t), (r, t), 2.0, k, false);
        self.line_px((l, b), (r, b), 2.0, k, false);
        self.line_px((l, t), (l, b), 2.0, k, false);
        self.line_px((r, t), (r, b), 2.0, k, false);
        self.text(
            (W as f64 - Self::text_width(title, 2)) / 2.0,
            8.0,
            title,
            2,
            k,
        );
        self.text(
            (W as f64 - Self::text_width(xl, 2)) / 2.0,
            H as f64 - 35.0,
            xl,
            2,
            k,
        );
        self.text(10.0, MT - 24.0, yl, 2, k);
    }
    fn legend(&mut self, items: &[(&str, Rgb<u8>)], left: bool) {
        for (i, (s, c)) in items.iter().enumerate() {
            let y = MT + 15.0 + 24.0 * i as f64;
            let x = if left {
                ML + 15.0
            } else {
                W as f64 - MR - 20.0 - Self::text_width(s, 2) - 25.0
            };
            self.dot(x + 6.0, y + 7.0, 5.0, *c);
            self.text(x + 20.0, y, s, 2, Rgb([0, 0, 0]));
        }
    }
}

fn illuminant_plot(out: &std::path::Path) {
    let dict = embedded::illuminants();
    let chroma: Vec<[f64; 3]> = dict
        .chromaticities
        .iter()
        .map(|c| [c[0], 1.0, c[1]])
        .collect();
    let fit = fit_gaussian(&chroma, Estimator::Unbiased).expect("fit");
    println!(
        "illuminants: {} points, mean [{:.6}, {:.6}], unbiased covariance [[{:.6e}, {:.6e}], [{:.6e}, {:.6e}]]",
        fit.count, fit.mean[0], fit.mean[1], fit.covariance[0][0], fit.covariance[0][1],
        fit.covariance[1][0], fit.covariance[1][1]
    );
    let g = Gaussian2 {
        name: "embedded".into(),
        mean: fit.mean,
        cov: fit.covariance,
        count: fit.count,
        estimator: fit.estimator,
    };
    let mut p = Plot::new((0.3, 1.3), (0.1, 0.55));
    p.axes(
        "45 night gray cards, fitted gaussian (1-3 sigma), 30 draws",
        "r/g",
        "b/g",
        &[0.3, 0.5, 0.7, 0.9, 1.1, 1.3],
        &[0.1, 0.2, 0.3, 0.4, 0.5],
        &|v| format!("{v:.1}"),
    );
    let a = g.sqrt_cov();
    for k in [1.0, 2.0, 3.0] {
        let pts: Vec<(f64, f64)> = (0..=360)
            .map(|i| {
                let t = (i as f64).to_radians();
                let z = [k * t.cos(), k * t.sin()];
                (
                    g.mean[0] + a[0][0] * z[0] + a[0][1] * z[1],
                    g.mean[1] + a[1][0] * z[0] + a[1][1] * z[1],
                )
            })
            .collect();
        p.polyline(&pts, 2.0, Rgb([40, 150, 60]), k > 1.5);
    }
    for c in &chroma {
        let (u, v) = p.px(c[0], c[2]);
        p.dot(u, v, 5.0, Rgb([30, 80, 200]));
    }
    let mut rng = SynthRng::new(0, "calibration_plots", 0);
    for _ in 0..30 {
        let s = g
            .sample(&mut rng, &SamplerRules::default())
            .expect("sample");
        let (u, v) = p.px(s[0], s[2]);
        p.dot(u, v, 4.0, Rgb([220, 40, 40]));
    }
    let (u, v) = p.px(g.mean[0], g.mean[1]);
    p.dot(u, v, 6.0, Rgb([0, 0, 0]));
    p.legend(
        &[
            ("gray cards", Rgb([30, 80, 200])),
            ("sampled", Rgb([220, 40, 40])),
            ("mean, 1-3 sigma", Rgb([40, 150, 60])),
        ],
        false,
    );
    p.img.save(out).expect("save png");
}

fn burst(iso: u32, s: f64, o: f64, seed: u64) -> Vec<RawImage> {
    let (w, h, black, white) = (512usize, 256usize, 64.0, 1023.0);
    let scale = white - black;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let clean: Vec<f64> = (0..w * h)
        .map(|i| {
            let t = (i % w) as f64 / w as f64;
            ((0.9 * t * t) * scale + black).round()
        })
        .collect();
    (0..16)
        .map(|_| {
            let mut meta = RawMeta::new_bayer(Bayer::RGGB, 10, black, white);
            meta.exif.iso = Some(iso);
            let data = clean
                .iter()
                .map(|&x| {
                    let y = (x - black) / scale;
                    let z: f64 = StandardNormal.sample(&mut rng);
                    (x + z * (s * y + o).max(0.0).sqrt() * scale)
                        .round()
                        .clamp(0.0, white) as u16
                })
                .collect();
            RawImage {
                width: w,
                height: h,
                data,
                meta,
            }
        })
        .collect()
}

fn noise_plot(out: &std::path::Path) {
    let model = embedded::noise_model();
    let mut p = Plot::new((0.0, 0.9), (0.0, 45.0));
    p.axes(
        "variance vs mean per bin, position 0, 16-frame bursts",
        "mean y (normalized)",
        "variance (1e-4)",
        &[0.0, 0.2, 0.4, 0.6, 0.8],
        &[0.0, 10.0, 20.0, 30.0, 40.0],
        &|v| format!("{v:.0}"),
    );
    let colours = [Rgb([30, 80, 200]), Rgb([220, 40, 40])];
    for (k, iso) in [1600u32, 3200].into_iter().enumerate() {
        let [s, o] = model.at(iso).expect("model").params.positions[0];
        let frames = burst(iso, s, o, iso as u64);
        let mut it = frames.into_iter();
        let mut acc = BurstAccumulator::new(it.next().expect("frame")).expect("acc");
        for f in it {
            acc.add(&f).expect("add");
        }
        let st = acc.finish().expect("finish");
        let m = fit_iso(std::slice::from_ref(&st)).expect("fit");
        let f = &m.fits[0];
        println!(
            "ISO {iso} position 0: true S {s:.4e} O {o:.4e}; fitted S {:.4e} O {:.4e} (R^2 {:.4}, chi2/dof {:.2}, {} bins, {} px)",
            f.s, f.o, f.r2.unwrap_or(0.0), f.chi2_reduced.unwrap_or(0.0), f.bins, f.pixels
        );
        for b in &st.bins[0] {
            let (u, v) = p.px(b.mean, b.var * 1e4);
            // The fit's clip rule: bins within 4 predicted sigmas of white are dropped.
            let near_white = b.mean + 4.0 * (f.s * b.mean + f.o).max(0.0).sqrt() >= 1.0;
            let c = if near_white {
                Rgb([170, 170, 170])
            } else {
                colours[k]
            };
            p.dot(u, v, 3.0, c);
        }
        let q = m.quantization_variance_removed;
        let fitted: Vec<(f64, f64)> = (0..=90)
            .map(|i| i as f64 / 100.0)
            .map(|y| (y, (f.s * y + f.o + q) * 1e4))
            .collect();
        p.polyline(&fitted, 2.0, Rgb([0, 0, 0]), false);
        let truth: Vec<(f64, f64)> = (0..=90)
            .map(|i| i as f64 / 100.0)
            .map(|y| (y, (s * y + o + q) * 1e4))
            .collect();
        p.polyline(&truth, 2.0, Rgb([40, 150, 60]), true);
    }
    p.legend(
        &[
            ("iso 1600 bins", colours[0]),
            ("iso 3200 bins", colours[1]),
            ("wls fit", Rgb([0, 0, 0])),
            ("true model (dashed)", Rgb([40, 150, 60])),
            ("bins near white, excluded", Rgb([170, 170, 170])),
        ],
        true,
    );
    p.img.save(out).expect("save png");
}

fn main() {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs/img".into()));
    std::fs::create_dir_all(&dir).expect("create output dir");
    illuminant_plot(&dir.join("calibration_illuminants.png"));
    noise_plot(&dir.join("calibration_noise.png"));
    println!("wrote {}", dir.display());
}
