//! The burst warp's interpolants compared on analytic scenes (docs/synthesis.md, "Bursts"):
//! RMS error (DN of a 14-bit range) of a moved frame against the scene evaluated at the
//! moved positions, (a) interpolating the exact RGB samples (the interpolant alone) and (b)
//! through the warp itself (MHC demosaic of the CFA mosaic, interpolant, mosaic back), over
//! 16 sub-pixel rigid motions (translations in [-2, 2] px, rotations in [-0.2, 0.2] degrees).
//!
//! cargo run --release --example burst_interp_error

use day2night::normalize::Normalizer;
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage};
use day2night::synth::burst::motion::{apply, invert, rigid};
use day2night::synth::burst::warp::{CleanSource, WarpLevels, Warper};
use day2night::synth::burst::Interp;

const BLACK: f64 = 64.0;
const WHITE: f64 = 16383.0;
const NEUTRAL: [f64; 3] = [0.5, 1.0, 0.7];

/// A colour scene whose finest detail has period about `period` samples.
fn scene(x: f64, y: f64, period: f64) -> [f64; 3] {
    let k = std::f64::consts::TAU / period;
    let t = 0.5
        + 0.15 * (x * k).sin() * (y * k * 0.8).cos()
        + 0.1 * (y * k * 0.37 + x * k * 0.21).sin()
        + 0.05 * (x * k * 0.13).cos();
    [0.8 * t + 0.05, t, 0.6 * t + 0.1]
}

fn dn(v: f64) -> f64 {
    v * (WHITE - BLACK) + BLACK
}

fn main() {
    let (w, h) = (160usize, 128usize);
    let centre = [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0];
    // 16 motions from a fixed LCG
    let mut s = 12345u64;
    let mut u = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let motions: Vec<[[f64; 3]; 2]> = (0..16)
        .map(|_| rigid(centre, 4.0 * u() - 2.0, 4.0 * u() - 2.0, 0.4 * u() - 0.2))
        .collect();
    println!("| scene (finest period) | interpolant | (a) interpolant alone: RMS DN | (b) the warp (MHC + interpolant): RMS DN |");
    println!("|---|---|---:|---:|");
    for period in [32.0, 12.0, 6.0] {
        let mut meta = RawMeta::new_bayer(Bayer::RGGB, 14, BLACK, WHITE);
        meta.as_shot_neutral = Some(NEUTRAL);
        let data: Vec<u16> = (0..w * h)
            .map(|i| {
                let (y, x) = (i / w, i % w);
                let c = Bayer::RGGB.color_at(y, x) as usize;
                dn(scene(x as f64, y as f64, period)[c]).round() as u16
            })
            .collect();
        let img = RawImage {
            width: w,
            height: h,
            data,
            meta,
        };
        let norm = Normalizer::new(&img).expect("levels");
        let levels = WarpLevels {
            norm: &norm,
            bayer: Bayer::RGGB,
            neutral: NEUTRAL,
            active: (w, h),
            keep_negative: false,
            truncate: false,
        };
        for interp in Interp::ALL {
            let r = interp.radius() as i64;
            let (mut sa, mut sb, mut n) = (0.0, 0.0, 0.0);
            for aff in &motions {
                let inv = invert(aff);
                let src = CleanSource {
                    data: &img.data,
                    stride: w,
                    offset: 0,
                    rows: 0..h,
                    cols: 0..w,
                };
                let warper = Warper::new(src, &levels, inv, interp);
                let mut out = vec![0u16; w * h];
                warper.fill(0..h, 0..w, &mut out, (w, 0));
                let mut wts = [0.0; 6];
                let mut wys = [0.0; 6];
                for y in 12..h - 12 {
                    for x in 12..w - 12 {
                        let (sx, sy) = apply(&inv, x as f64, y as f64);
                        let c = Bayer::RGGB.color_at(y, x) as usize;
                        let want = dn(scene(sx, sy, period)[c]);
                        // (a) the kernel on the exact samples of channel c
                        let (fx, fy) = (sx.floor(), sy.floor());
                        interp.weights(sx - fx, &mut wts);
                        interp.weights(sy - fy, &mut wys);
                        let mut v = 0.0;
                        for j in 0..2 * r {
                            for i in 0..2 * r {
                                let (px, py) = (fx as i64 - r + 1 + i, fy as i64 - r + 1 + j);
                                v += wys[j as usize]
                                    * wts[i as usize]
                                    * dn(scene(px as f64, py as f64, period)[c]);
                            }
                        }
                        sa += (v - want).powi(2);
                        sb += (out[y * w + x] as f64 - want).powi(2);
                        n += 1.0;
                    }
                }
            }
            println!(
                "| {period} px | {interp} | {:.2} | {:.2} |",
                (sa / n).sqrt(),
                (sb / n).sqrt()
            );
        }
    }
}
