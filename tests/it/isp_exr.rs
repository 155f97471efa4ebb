//! The own EXR encoder (none/zips/zip): generated odd-size images, NaN/Inf included, decode
//! in OpenEXR and OpenImageIO to exactly the sanitized values written
//! (tests/validators/isp_exr_values.py).
use crate::common;

use day2night::encode::exr::{write_exr, ExrCompression, ExrOptions, HALF_MAX};
use day2night::isp::RgbImage;
use day2night::output::OutputPolicy;

/// Varied values over several magnitudes, negative ones, and non-finite ones.
fn image(w: usize, h: usize) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    let mut s = 12345u32;
    for (i, v) in img.data.iter_mut().enumerate() {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let u = (s >> 8) as f32 / (1u32 << 24) as f32;
        *v = match i % 11 {
            0 => u * 1e-3,
            1 => -u,
            2 => u * 7e4,
            _ => u * 2.0,
        };
    }
    img.data[0] = f32::NAN;
    img.data[4] = f32::INFINITY;
    img.data[8] = f32::NEG_INFINITY;
    img.data[10] = 1e30;
    img
}

/// A compressible image (smooth ramps, flat runs, a little texture) large enough that one ZIP
/// block spans several chunks of the level-1 encoder (`day2night::deflate`).
fn smooth(w: usize, h: usize) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            for k in 0..3 {
                let v = if x < w / 3 {
                    0.18 // a flat run
                } else {
                    (x as f32 / w as f32) * (0.5 + 0.25 * k as f32)
                        + ((x * 7 + y * 13) % 5) as f32 * 1e-3
                };
                img.data[3 * (y * w + x) + k] = v;
            }
        }
    }
    img
}

/// What a reader must see: NaN -> 0, clamped, rounded to half when `half`.
fn expected(img: &RgbImage, half: bool) -> Vec<u8> {
    let lim = if half { HALF_MAX } else { f32::MAX };
    img.data
        .iter()
        .map(|&v| {
            let v = if v.is_nan() { 0.0 } else { v.clamp(-lim, lim) };
            if half {
                exr::prelude::f16::from_f32(v).to_f32()
            } else {
                v
            }
        })
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn own_encoder_output_decodes_exactly_in_openexr_and_oiio() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    // 21 lines: one full ZIP block of 16 and a partial one
    let noisy = image(37, 21);
    let smooth = smooth(1500, 21);
    for (name, img, comp, half, level) in [
        ("noisy", &noisy, ExrCompression::Zip, true, 1),
        ("noisy", &noisy, ExrCompression::Zip, true, 9),
        ("noisy", &noisy, ExrCompression::Zips, true, 1),
        ("noisy", &noisy, ExrCompression::None, true, 1),
        ("noisy", &noisy, ExrCompression::Zip, false, 1),
        ("smooth", &smooth, ExrCompression::Zip, true, 1),
        ("smooth", &smooth, ExrCompression::Zip, true, 2),
        ("smooth", &smooth, ExrCompression::Zips, true, 1),
        ("smooth", &smooth, ExrCompression::Zip, false, 1),
    ] {
        let (w, h) = (img.width, img.height);
        let kind = if half { "half" } else { "float" };
        let out = dir.path().join(format!("{name}_{comp}_{kind}_{level}.exr"));
        let exp = dir.path().join(format!("{name}_{comp}_{kind}_{level}.f32"));
        let opts = ExrOptions {
            half,
            compression: comp,
            zip_level: level,
        };
        let attrs = [("day2night:test".to_string(), "ünïcode ok".to_string())];
        write_exr(img, &out, &opts, &attrs, &OutputPolicy::default()).unwrap();
        std::fs::write(&exp, expected(img, half)).unwrap();
        if name == "smooth" {
            // really compressed, not stored raw (float mantissas are noisier than halves)
            let raw = w * h * 3 * if half { 2 } else { 4 };
            let most = if half { raw / 2 } else { raw * 9 / 10 };
            let len = std::fs::metadata(&out).unwrap().len() as usize;
            assert!(
                len < most,
                "{comp} {kind} level {level}: {len} of {raw} bytes"
            );
        }
        let (ws, hs) = (w.to_string(), h.to_string());
        let args: Vec<&std::ffi::OsStr> = vec![
            out.as_os_str(),
            exp.as_os_str(),
            kind.as_ref(),
            ws.as_ref(),
            hs.as_ref(),
            comp.name().as_ref(),
        ];
        let r = common::run_validator(&py, "isp_exr_values.py", &args);
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(
            r.status.success(),
            "isp_exr_values.py {name} {comp} {kind} level {level}: {stdout}\n{}",
            String::from_utf8_lossy(&r.stderr)
        );
        eprintln!("isp_exr_values.py {name} {comp} {kind} level {level}: {stdout}");
    }
}
