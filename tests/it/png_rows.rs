//! The own 8-bit PNG encoder (src/encode/png_rows.rs): files of several sizes, tones and
//! row-group heights decode in OpenImageIO and scikit-image (tests/validators/png_rows.py) to
//! exactly the samples written, with the colour-space chunk readers expect.
use crate::common;

use day2night::deflate::Encoder;
use day2night::encode::png_rows::{write_png_groups, write_png_rgb8, PngRows};
use day2night::isp::tone::DisplayTone;
use day2night::output::OutputPolicy;

/// Smooth ramps, a flat region, saturated stripes and a little noise.
fn image(w: usize, h: usize) -> Vec<u8> {
    let mut s = 0x2545_F491u32;
    let mut v = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for x in 0..w {
            for k in 0..3 {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                v.push(if x < w / 5 {
                    17
                } else if y % 9 == 0 {
                    255
                } else {
                    ((x * (k + 1) + y * 2) as u32 + (s >> 30)) as u8
                });
            }
        }
    }
    v
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn own_png_decodes_exactly_in_openimageio_and_skimage() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    for (w, h, tone, group) in [
        (1, 1, DisplayTone::Srgb, 32),
        (3, 70, DisplayTone::Gamma22, 32),
        (257, 33, DisplayTone::Srgb, 1),
        (1000, 100, DisplayTone::Srgb, 32),
        (999, 64, DisplayTone::Release, 7),
    ] {
        let img = image(w, h);
        let name = format!("{w}x{h}_{tone:?}_{group}");
        let out = dir.path().join(format!("{name}.png"));
        let exp = dir.path().join(format!("{name}.rgb8"));
        if group == 32 {
            write_png_rgb8(&img, w, h, tone, &out, &OutputPolicy::default()).unwrap();
        } else {
            let mut enc = Encoder::new();
            let groups: Vec<PngRows> = img
                .chunks(3 * w * group)
                .map(|r| PngRows::encode(r, w, &mut enc).unwrap())
                .collect();
            write_png_groups(&groups, w, h, tone, &out, &OutputPolicy::default()).unwrap();
        }
        std::fs::write(&exp, &img).unwrap();
        let tone_name = match tone {
            DisplayTone::Srgb => "srgb",
            DisplayTone::Gamma22 => "gamma22",
            DisplayTone::Release => "release",
        };
        let (ws, hs) = (w.to_string(), h.to_string());
        let args: Vec<&std::ffi::OsStr> = vec![
            out.as_os_str(),
            exp.as_os_str(),
            ws.as_ref(),
            hs.as_ref(),
            tone_name.as_ref(),
        ];
        let r = common::run_validator(&py, "png_rows.py", &args);
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(
            r.status.success(),
            "png_rows.py {name}: {stdout}\n{}",
            String::from_utf8_lossy(&r.stderr)
        );
        eprintln!("png_rows.py {name}: {stdout}");
    }
}
