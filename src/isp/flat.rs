//! Renders that come out constant: [`FlatCheck`] watches the bands of a render as they are
//! made (or a whole image) and tells whether a colour plane holds one value everywhere,
//! e.g. an all-black target after a GainMap of negative gains. It is fed from the band
//! sink, while each band is in cache; once every plane has shown two values it stops
//! looking, so on a normal image it costs the comparison of the first few pixels.
//!
//! The answer does not depend on the order in which bands arrive (any two different values
//! anywhere make a plane vary), so it is the same for any thread count.

use super::rgb::RgbImage;
use crate::diagnostics::{Code, Warning};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

/// No value seen yet in a plane.
const UNSET: u64 = u64::MAX;

/// Tracks, per R, G, B plane, whether every sample seen so far has one value.
#[derive(Debug)]
pub struct FlatCheck {
    /// The first value seen per plane (`f32` bits), [`UNSET`] before any.
    first: [AtomicU64; 3],
    /// A plane showed two different values (or NaN).
    varied: [AtomicBool; 3],
    /// Pixels seen (capped: only "at least 2" matters).
    pixels: AtomicU64,
}

impl Default for FlatCheck {
    fn default() -> Self {
        FlatCheck::new()
    }
}

impl FlatCheck {
    /// Nothing seen yet.
    pub fn new() -> FlatCheck {
        FlatCheck {
            first: [UNSET, UNSET, UNSET].map(AtomicU64::new),
            varied: [false, false, false].map(AtomicBool::new),
            pixels: AtomicU64::new(0),
        }
    }

    /// Look at interleaved RGB samples (a band of rows, any part of the image, from any
    /// thread).
    pub fn rows(&self, rows: &[f32]) {
        let n = (rows.len() / 3) as u64;
        if n == 0 {
            return;
        }
        if self.pixels.load(Ordering::Relaxed) < 2 {
            self.pixels.fetch_add(n.min(2), Ordering::Relaxed);
        }
        for c in 0..3 {
            if self.varied[c].load(Ordering::Relaxed) {
                continue;
            }
            let v0 = rows[c];
            // NaN != NaN: a plane with NaN is never called constant.
            let differs = rows.iter().skip(c).step_by(3).any(|&v| v != v0);
            if differs {
                self.varied[c].store(true, Ordering::Relaxed);
                continue;
            }
            // -0.0 and 0.0 are one value.
            let bits = u64::from((v0 + 0.0).to_bits());
            match self.first[c].compare_exchange(UNSET, bits, Ordering::Relaxed, Ordering::Relaxed)
            {
                Ok(_) => {}
                Err(seen) if seen == bits => {}
                Err(_) => self.varied[c].store(true, Ordering::Relaxed),
            }
        }
    }

    /// Look at a whole image.
    pub fn image(&self, img: &RgbImage) {
        self.rows(&img.data);
    }

    /// The value of each plane that held one value everywhere (`None` for a plane that
    /// varies); `None` when no plane is constant, or fewer than 2 pixels were seen (a
    /// single pixel says nothing).
    pub fn constant(&self) -> Option<[Option<f32>; 3]> {
        if self.pixels.load(Ordering::Relaxed) < 2 {
            return None;
        }
        let planes = [0, 1, 2].map(|c| {
            let bits = self.first[c].load(Ordering::Relaxed);
            (!self.varied[c].load(Ordering::Relaxed) && bits != UNSET)
                .then(|| f32::from_bits(bits as u32))
        });
        planes.iter().any(Option::is_some).then_some(planes)
    }

    /// The warning for `what` ("the target render", "the render") when a plane came out
    /// constant: "the render is constant: R, G and B are 0 in every pixel (all black)" or
    /// "the render's B plane is 0 in every pixel".
    pub fn warning(&self, what: &str) -> Option<Warning> {
        let planes = self.constant()?;
        let names = ["R", "G", "B"];
        let held: Vec<(usize, f32)> = planes
            .iter()
            .enumerate()
            .filter_map(|(c, v)| v.map(|v| (c, v)))
            .collect();
        let all_same = held.iter().all(|&(_, v)| v == held[0].1);
        let value = |v: f32| {
            if v == 0.0 {
                "0".to_string()
            } else {
                format!("{v}")
            }
        };
        let text = if held.len() == 3 && all_same {
            let v = held[0].1;
            let tail = if v <= 0.0 { " (all black)" } else { "" };
            format!(
                "{what} is constant: R, G and B are {} in every pixel{tail}",
                value(v)
            )
        } else if held.len() == 3 {
            format!(
                "{what} is constant: R {}, G {}, B {} in every pixel",
                value(held[0].1),
                value(held[1].1),
                value(held[2].1)
            )
        } else {
            let parts: Vec<String> = held
                .iter()
                .map(|&(c, v)| format!("{} is {}", names[c], value(v)))
                .collect();
            format!(
                "{what} has a constant plane: {} in every pixel",
                parts.join(", ")
            )
        };
        Some(Warning::new(Code::RenderConstant, text))
    }
}

/// The warning of [`FlatCheck::warning`] for a whole image.
pub fn warning(img: &RgbImage, what: &str) -> Option<Warning> {
    let f = FlatCheck::new();
    f.image(img);
    f.warning(what)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn img(w: usize, h: usize, f: impl Fn(usize, usize, usize) -> f32) -> RgbImage {
        let mut i = RgbImage::new(w, h);
        for (k, v) in i.data.iter_mut().enumerate() {
            *v = f(k / 3 / w, k / 3 % w, k % 3);
        }
        i
    }

    #[test]
    fn finds_constant_planes_and_only_them() {
        let black = img(5, 4, |_, _, _| 0.0);
        assert_eq!(black.data.len(), 60);
        let w = warning(&black, "the render").unwrap();
        assert_eq!(w.code, Code::RenderConstant);
        let w = w.message;
        assert!(
            w.contains("R, G and B are 0 in every pixel (all black)"),
            "{w}"
        );
        let grey = img(5, 4, |_, _, c| [0.25, 0.5, 0.75][c]);
        let w = warning(&grey, "the render").unwrap().message;
        assert!(w.contains("R 0.25, G 0.5, B 0.75"), "{w}");
        let no_blue = img(
            5,
            4,
            |r, x, c| if c == 2 { 0.0 } else { (r * 5 + x) as f32 },
        );
        let w = warning(&no_blue, "the target render").unwrap().message;
        assert_eq!(
            w,
            "the target render has a constant plane: B is 0 in every pixel"
        );
        // One differing sample anywhere (last pixel, any plane) is enough.
        for c in 0..3 {
            let mut i = black.clone();
            let n = i.data.len();
            i.data[n - 3 + c] = 1e-30;
            let got = FlatCheck::new();
            got.image(&i);
            let planes = got.constant().unwrap();
            assert_eq!(planes[c], None);
            assert_eq!(planes.iter().filter(|p| p.is_some()).count(), 2);
        }
        let varied = img(5, 4, |r, x, c| (r + x + c) as f32);
        assert!(warning(&varied, "the render").is_none());
        // -0 and 0 are one value; NaN varies; one pixel says nothing.
        let mut z = black.clone();
        z.data[0] = -0.0;
        assert!(warning(&z, "x").is_some());
        let mut n = black.clone();
        n.data[4] = f32::NAN;
        assert_eq!(FlatCheck::new().constant(), None);
        let f = FlatCheck::new();
        f.image(&n);
        assert_eq!(f.constant().unwrap()[1], None);
        assert!(warning(&img(1, 1, |_, _, _| 0.0), "x").is_none());
        assert!(warning(&img(2, 1, |_, _, _| 0.0), "x").is_some());
    }

    #[test]
    fn bands_in_any_order_on_any_thread_give_the_whole_image_answer() {
        for (k, case) in [
            img(7, 40, |_, _, _| 0.0),
            img(7, 40, |r, _, c| if r == 39 && c == 1 { 0.5 } else { 0.0 }),
            img(7, 40, |r, _, _| if r < 20 { 0.1 } else { 0.2 }),
        ]
        .into_iter()
        .enumerate()
        {
            let whole = FlatCheck::new();
            whole.image(&case);
            for band in [1, 3, 32] {
                let f = FlatCheck::new();
                let mut bands: Vec<&[f32]> = case.data.chunks(3 * 7 * band).collect();
                bands.reverse();
                bands.par_iter().for_each(|b| f.rows(b));
                assert_eq!(f.constant(), whole.constant(), "case {k} band {band}");
            }
        }
    }
}
