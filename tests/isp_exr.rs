//! The own EXR encoder (none/zips/zip): generated odd-size images, NaN/Inf included, decode
//! in OpenEXR and OpenImageIO to exactly the sanitized values written
//! (tests/validators/isp_exr_values.py).
mod common;

use day2night::exr::{write_exr, ExrCompression, ExrOptions, HALF_MAX};
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
fn own_encoder_output_decodes_exactly_in_openexr_and_oiio() {
    let Some(py) = common::python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (37, 21); // 21 lines: one full ZIP block of 16 and a partial one
    let img = image(w, h);
    for (comp, half, level) in [
        (ExrCompression::Zip, true, 1),
        (ExrCompression::Zip, true, 9),
        (ExrCompression::Zips, true, 1),
        (ExrCompression::None, true, 1),
        (ExrCompression::Zip, false, 1),
    ] {
        let kind = if half { "half" } else { "float" };
        let out = dir.path().join(format!("{comp}_{kind}_{level}.exr"));
        let exp = dir.path().join(format!("{comp}_{kind}_{level}.f32"));
        let opts = ExrOptions {
            half,
            compression: comp,
            zip_level: level,
        };
        let attrs = [("day2night:test".to_string(), "ünïcode ok".to_string())];
        write_exr(&img, &out, &opts, &attrs, &OutputPolicy::default()).unwrap();
        std::fs::write(&exp, expected(&img, half)).unwrap();
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
            "isp_exr_values.py {comp} {kind} level {level}: {stdout}\n{}",
            String::from_utf8_lossy(&r.stderr)
        );
        eprintln!("isp_exr_values.py {comp} {kind} level {level}: {stdout}");
    }
}
