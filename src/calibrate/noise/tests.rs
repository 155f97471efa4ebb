//! Tests of the noise calibration: S and O recovered from synthetic bursts and pairs, the
//! refusals, the ISO laws and NoiseProfile models.

use super::*;
use crate::raw::meta::RawMeta;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// A ramp scene with heteroscedastic noise `var(y) = s y + o` per frame.
pub(crate) fn burst(s: f64, o: f64, frames: usize, w: usize, h: usize, seed: u64) -> Vec<RawImage> {
    let (black, white) = (64.0, 1023.0);
    let scale = white - black;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let clean: Vec<f64> = (0..w * h)
        .map(|i| {
            let t = (i % w) as f64 / w as f64;
            (0.9 * t * t + rng.random::<f64>() * 0.01) * scale + black
        })
        .map(|v: f64| v.round())
        .collect();
    (0..frames)
        .map(|_| {
            let mut meta = RawMeta::new_bayer(Bayer::RGGB, 10, black, white);
            meta.exif.iso = Some(1600);
            let data = clean
                .iter()
                .map(|&x| {
                    let y = (x - black) / scale;
                    let sd = (s * y + o).max(0.0).sqrt() * scale;
                    let v = x + Normal::new(0.0, sd).unwrap().sample(&mut rng);
                    v.round().clamp(0.0, white) as u16
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

fn run_burst(frames: Vec<RawImage>) -> Result<SourceStats> {
    let mut it = frames.into_iter();
    let mut acc = BurstAccumulator::new(it.next().unwrap())?;
    for f in it {
        acc.add(&f)?;
    }
    acc.finish()
}

#[test]
fn burst_recovers_s_and_o() {
    let (s, o) = (2.3 / 959.0, 1.03e-5);
    let st = run_burst(burst(s, o, 8, 512, 256, 1)).unwrap();
    let m = fit_iso(&[st]).unwrap();
    for f in &m.fits {
        assert!((f.s / s - 1.0).abs() < 0.02, "{f:?}");
        // O's standard error is about 2.6 % at this size: allow 3 of them.
        assert!((f.o - o).abs() < 3.0 * f.o_stderr.unwrap(), "{f:?}");
        assert!(f.o_stderr.unwrap() < 0.03 * o, "{f:?}");
        assert!(f.chi2_reduced.unwrap() < 1.5, "{f:?}");
    }
    assert_eq!(m.iso, 1600);
}

#[test]
fn pair_recovers_s_and_o() {
    let (s, o) = (2.3 / 959.0, 1.03e-5);
    let mut b = burst(s, o, 1, 1024, 512, 2);
    let noisy = b.pop().unwrap();
    // A noise-free clean frame from the same generator.
    let mut clean = burst(0.0, 0.0, 1, 1024, 512, 2).pop().unwrap();
    clean.meta.exif.iso = Some(50);
    let st = pair_stats(&clean, &noisy).unwrap();
    let m = fit_iso(&[st]).unwrap();
    for f in &m.fits {
        // Within 3 standard errors (about 3 % for S, 5 % for O at this size).
        assert!((f.s - s).abs() < 3.0 * f.s_stderr.unwrap(), "{f:?}");
        assert!((f.o - o).abs() < 3.0 * f.o_stderr.unwrap(), "{f:?}");
        assert!(f.s_stderr.unwrap() < 0.02 * s && f.o_stderr.unwrap() < 0.05 * o);
    }
}

#[test]
fn degenerate_bursts() {
    let b = burst(1e-3, 1e-5, 3, 32, 32, 3);
    let e = run_burst(b).unwrap_err().to_string();
    assert!(e.contains("at least 4 frames"), "{e}");
    let b = burst(1e-3, 1e-5, 2, 32, 32, 3);
    let mut acc = BurstAccumulator::new(b[0].clone()).unwrap();
    let e = acc.add(&b[0]).unwrap_err().to_string();
    assert!(e.contains("identical"), "{e}");
    let mut other = b[1].clone();
    other.meta.exif.iso = Some(3200);
    let e = acc.add(&other).unwrap_err().to_string();
    assert!(e.contains("ISO 3200"), "{e}");
    // Zero variance: two frames that are the same scene without noise, differing only
    // in a single clipped pixel.
    let mut z = burst(0.0, 0.0, 4, 64, 64, 4);
    for (k, f) in z.iter_mut().enumerate() {
        f.data[k] = 1023;
    }
    let e = fit_iso(&[run_burst(z).unwrap()]).unwrap_err().to_string();
    assert!(e.contains("zero variance"), "{e}");
}

#[test]
fn iso_laws_and_profiles() {
    let mk = |iso: u32, s: f64, o: f64| {
        let mut meta = RawMeta::new_bayer(Bayer::GRBG, 10, 64.0, 1023.0);
        meta.exif.iso = Some(iso);
        meta.noise_profile = Some(vec![(s, o)]);
        RawImage {
            width: 2,
            height: 2,
            data: vec![100; 4],
            meta,
        }
    };
    let a = mk(800, 8e-4, 1e-6 + 1e-12 * 640000.0);
    let b = mk(1600, 16e-4, 1e-6 + 1e-12 * 2560000.0);
    let models = from_noise_profiles(&[("a".into(), &a), ("b".into(), &b)]).unwrap();
    assert_eq!(models.len(), 2);
    assert_eq!(models[0].fits[0].color, "G");
    let laws = fit_iso_laws(&models).unwrap();
    assert!((laws.s_per_iso[0] - 1e-6).abs() < 1e-15);
    assert!((laws.o_at_iso0[2] - 1e-6).abs() < 1e-12);
    assert!((laws.o_per_iso2[3] - 1e-12).abs() < 1e-18);
    let mut c = mk(100, 1.0, 1.0);
    c.meta.noise_profile = None;
    let e = from_noise_profiles(&[("c.dng".into(), &c)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("c.dng") && e.contains("NoiseProfile"), "{e}");
}
