//! Accuracy of the single-image noise estimate (`day2night::noise::estimate`) on synthetic
//! day frames with known Poisson-Gaussian noise `var(y) = a * y + b` (normalized units):
//! prints the error table of docs/noise.md, "Estimated from the day image".
//!
//! ```text
//! cargo run --release --example noise_estimate_accuracy [-- WIDTH HEIGHT [STEP...]]
//! ```
//!
//! Content (clean normalized signal per site, times a per-colour factor R 0.55, G 1, B 0.75):
//! `flat` (a 4x4 grid of flat patches), `ramp` (a horizontal ramp plus a gentle vertical
//! one), `texture` (the photograph behind fixtures/day.dng, `fixtures/source/astronaut.png`,
//! as linear grey, enlarged bilinearly so that it spans 2048 sites, centred, mirrored past
//! its edges: real edges and texture at the same scale in any frame size), `clipped`
//! (the same texture 1.5x brighter, about a third of the sites at white, and black 0 so that
//! dark sites clip at 0 too), `grainy` (the photograph not halved first, whose film grain
//! and 8-bit steps stay pixel-scale detail about as strong as the noise: the limit of any
//! single-image estimate). `texture` and `clipped` use the photograph halved (2x2 means)
//! before enlarging, so that like a raw behind a lens it is smooth at the pixel scale
//! except at edges. Every CFA phase, 10 to 16 bits. (Also used by
//! tests/it/noise_estimate.rs.)

#![allow(dead_code)]

use day2night::noise::estimate::{estimate, EstimateOptions, NoiseEstimate};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::path::Path;

/// Scene content of a synthetic frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Content {
    /// A 4x4 grid of flat patches from 0.03 to 0.93.
    Flat,
    /// A horizontal ramp 0.02..0.95 plus a gentle vertical one.
    Ramp,
    /// A real photograph (grey), enlarged bilinearly.
    Texture,
    /// The photograph 1.5x brighter with black 0: clipped at white and at 0.
    Clipped,
    /// The photograph not halved first (pass [`Grey::astronaut`]): its film grain and
    /// 8-bit steps stay pixel-scale detail about as strong as the noise.
    Grainy,
}

impl Content {
    /// All kinds.
    pub const ALL: [Content; 5] = [
        Content::Flat,
        Content::Ramp,
        Content::Texture,
        Content::Clipped,
        Content::Grainy,
    ];
    /// Table name.
    pub fn name(self) -> &'static str {
        match self {
            Content::Flat => "flat",
            Content::Ramp => "ramp",
            Content::Texture => "texture",
            Content::Clipped => "clipped",
            Content::Grainy => "grainy",
        }
    }
}

/// A grey image in [0, 1] (linear) with bilinear sampling.
pub struct Grey {
    w: usize,
    h: usize,
    v: Vec<f64>,
}

impl Grey {
    /// The photograph behind fixtures/day.dng as linear grey.
    pub fn astronaut() -> Grey {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/source/astronaut.png");
        let img = image::open(&p)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
            .to_rgb8();
        let lin = |c: u8| day2night::color::srgb::eotf_f64(c as f64 / 255.0);
        // luminance: the Y row of linear sRGB -> XYZ
        let y = day2night::color::xyz::SRGB_TO_XYZ[1];
        let (w, h) = (img.width() as usize, img.height() as usize);
        let v = img
            .pixels()
            .map(|p| y[0] * lin(p[0]) + y[1] * lin(p[1]) + y[2] * lin(p[2]))
            .collect();
        Grey { w, h, v }
    }
    /// Mean of each 2x2 block (half the size): a quarter of the film grain and 8-bit
    /// quantization variance.
    pub fn halved(&self) -> Grey {
        let (w, h) = (self.w / 2, self.h / 2);
        let g = |x: usize, y: usize| self.v[y * self.w + x];
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = (2 * (i % w), 2 * (i / w));
                (g(x, y) + g(x + 1, y) + g(x, y + 1) + g(x + 1, y + 1)) / 4.0
            })
            .collect();
        Grey { w, h, v }
    }
    /// Bilinear value at (x, y) in this image's pixels; outside, the image is mirrored
    /// (so that any frame size sees texture everywhere).
    pub fn at(&self, x: f64, y: f64) -> f64 {
        let mirror = |v: f64, n: usize| {
            let p = 2.0 * (n - 1) as f64;
            let m = v.rem_euclid(p);
            if m > (n - 1) as f64 {
                p - m
            } else {
                m
            }
        };
        let (x, y) = (mirror(x, self.w), mirror(y, self.h));
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.w - 1), (y0 + 1).min(self.h - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let g = |xx: usize, yy: usize| self.v[yy * self.w + xx];
        (g(x0, y0) * (1.0 - fx) + g(x1, y0) * fx) * (1.0 - fy)
            + (g(x0, y1) * (1.0 - fx) + g(x1, y1) * fx) * fy
    }
    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.w
    }
}

/// Frame sites per pixel of the grey image, so that the photograph spans 2048 sites
/// whatever the frame size: the halved photograph (256 wide) 8 sites per pixel, 4 per
/// pixel of each CFA position's plane; the whole one (512) 4 sites per pixel.
pub fn sites_per_pixel(grey: &Grey) -> f64 {
    2048.0 / grey.width() as f64
}

/// The clean normalized signal of content `c` at active (row, col) of a w x h frame.
pub fn clean(
    c: Content,
    grey: &Grey,
    bayer: Bayer,
    r: usize,
    col: usize,
    w: usize,
    h: usize,
) -> f64 {
    let u = col as f64 / w as f64;
    let v = r as f64 / h as f64;
    // The photograph centred on the frame, at a fixed scale.
    let k = sites_per_pixel(grey);
    let photo = || {
        let gw = grey.width() as f64;
        grey.at(
            (col as f64 - w as f64 / 2.0) / k + gw / 2.0,
            (r as f64 - h as f64 / 2.0) / k + gw / 2.0,
        )
    };
    let base = match c {
        Content::Flat => {
            let k = ((v * 4.0) as usize).min(3) * 4 + ((u * 4.0) as usize).min(3);
            0.03 + 0.06 * k as f64
        }
        Content::Ramp => 0.02 + 0.93 * u * (0.9 + 0.1 * v),
        Content::Texture | Content::Grainy => 0.02 + 0.93 * photo(),
        Content::Clipped => 1.5 * photo(),
    };
    let gain = [0.55, 1.0, 0.75][bayer.color_at(r, col) as usize];
    base * gain
}

/// A synthetic frame: content `c`, `bits` bits (white 2^bits - 1, black 2^(bits-4), or 0
/// for `Clipped`), Bayer `bayer`, noise `var(y) = a y + b` added before rounding, ISO 100.
#[allow(clippy::too_many_arguments)]
pub fn synthetic_frame(
    c: Content,
    grey: &Grey,
    bayer: Bayer,
    bits: u16,
    w: usize,
    h: usize,
    a: f64,
    b: f64,
    seed: u64,
) -> RawImage {
    let white = ((1u32 << bits) - 1) as f64;
    let black = if c == Content::Clipped {
        0.0
    } else {
        (1u32 << (bits - 4)) as f64
    };
    let scale = white - black;
    let mut meta = RawMeta::new_bayer(bayer, bits, black, white);
    meta.exif.iso = Some(100);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut data = Vec::with_capacity(w * h);
    for r in 0..h {
        for col in 0..w {
            let y = clean(c, grey, bayer, r, col, w, h);
            let var = (a * y + b).max(0.0) * scale * scale;
            let z: f64 = StandardNormal.sample(&mut rng);
            let x = black + y * scale + var.sqrt() * z;
            data.push(x.round().clamp(0.0, white) as u16);
        }
    }
    RawImage {
        width: w,
        height: h,
        data,
        meta,
    }
}

/// Relative error of `S` (mean over positions of |S/a - 1|, worst position) and absolute
/// error of `O` (worst position), or the untrusted verdict.
pub struct Errors {
    /// Worst |S/a - 1| over the positions.
    pub s_rel: f64,
    /// Worst |O - b| over the positions.
    pub o_abs: f64,
    /// Worst |O/b - 1|.
    pub o_rel: f64,
    /// Why the fit was untrusted (None = trusted).
    pub untrusted: Option<String>,
}

/// Errors of an estimate against the truth (a, b).
pub fn errors(e: &NoiseEstimate, a: f64, b: f64) -> Errors {
    let mut out = Errors {
        s_rel: 0.0,
        o_abs: 0.0,
        o_rel: 0.0,
        untrusted: e.trusted().err(),
    };
    for p in &e.positions {
        out.s_rel = out.s_rel.max((p.s / a - 1.0).abs());
        out.o_abs = out.o_abs.max((p.o - b).abs());
        out.o_rel = out.o_rel.max((p.o / b - 1.0).abs());
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let w: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(2048);
    let h: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1536);
    let steps: Vec<usize> = if args.len() > 2 {
        args[2..].iter().filter_map(|s| s.parse().ok()).collect()
    } else {
        vec![1]
    };
    let full = Grey::astronaut();
    let halved = full.halved();
    let grid_a = [2e-5, 1e-4, 5e-4];
    let grid_b = [1e-7, 1e-6, 1e-5];
    println!("frame {w}x{h}; per cell: worst of 4 CFA phases x 4 positions; bits cycle 10,12,14,16 with the phase");
    // Per (content, a, b) and step: worst S error, O error, relative O error, untrusted.
    type Cell = (f64, f64, f64, usize, String);
    let mut rows: Vec<(Content, f64, f64, Vec<Cell>)> = vec![];
    for c in Content::ALL {
        for &a in &grid_a {
            for &b in &grid_b {
                let mut per_step =
                    vec![(0.0f64, 0.0f64, 0.0f64, 0usize, String::new()); steps.len()];
                for (i, bayer) in Bayer::ALL.into_iter().enumerate() {
                    let bits = [10u16, 12, 14, 16][i];
                    let grey = if c == Content::Grainy { &full } else { &halved };
                    let img = synthetic_frame(c, grey, bayer, bits, w, h, a, b, 7 + i as u64);
                    for (k, &step) in steps.iter().enumerate() {
                        let e = estimate(&img, &EstimateOptions { step: Some(step) })
                            .expect("estimate");
                        let er = errors(&e, a, b);
                        let r = &mut per_step[k];
                        r.0 = r.0.max(er.s_rel);
                        r.1 = r.1.max(er.o_abs);
                        r.2 = r.2.max(er.o_rel);
                        if let Some(u) = er.untrusted {
                            r.3 += 1;
                            r.4 = u;
                        }
                    }
                }
                rows.push((c, a, b, per_step));
            }
        }
    }
    for (k, step) in steps.iter().enumerate() {
        println!("\nstep {step} (one band of 4 rows in {step})");
        println!(
            "| content | a | b | max abs(S/a - 1) | max abs(O - b) | max abs(O/b - 1) | trusted |"
        );
        println!("|---|---:|---:|---:|---:|---:|---|");
        for (c, a, b, per_step) in &rows {
            let (s_rel, o_abs, o_rel, bad, why) = &per_step[k];
            println!(
                "| {} | {a:.0e} | {b:.0e} | {s_rel:.3} | {o_abs:.2e} | {o_rel:.2} | {} |",
                c.name(),
                if *bad == 0 {
                    "4/4".to_string()
                } else {
                    format!("{}/4 ({why})", 4 - bad)
                }
            );
        }
    }
}
