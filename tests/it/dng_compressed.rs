//! Compressed DNGs written by an independent writer (tifffile + imagecodecs, through
//! tests/validators/make_compressed_dngs.py): lossless JPEG XL (52546) CFA tiles and strips,
//! LinearRaw JPEG XL tiles, lossy JPEG (34892) LinearRaw tiles. Lossless files decode to
//! exactly the generator's array; the Adobe DNG SDK reads the same files
//! (compressed_check.py); `info` and `render` work on each; `synth` works on the JPEG XL CFA
//! files (its night DNGs are written uncompressed and pass the validators) and refuses
//! LinearRaw; corrupt, truncated and wrongly sized tiles are clear errors.
use crate::common;

use day2night::dng::read::{read_dng, read_dng_bytes};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The generated files (made once per test run by the validator Python, with
/// imagecodecs); fails without them.
fn generated() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let py = common::python();
        let dir = tempfile::tempdir().unwrap().keep();
        let out = common::run_validator(&py, "make_compressed_dngs.py", &[dir.as_os_str()]);
        assert!(
            out.status.success(),
            "make_compressed_dngs.py failed (is imagecodecs installed? \
             tests/validators/requirements.txt):\n{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        dir
    })
}

const LOSSLESS: [&str; 3] = ["cfa_jxl_tiles", "cfa_jxl_strips", "linear_jxl_tiles"];
const GOOD: [&str; 5] = [
    "cfa_jxl_tiles",
    "cfa_jxl_strips",
    "linear_jxl_tiles",
    "linear_jxl_lossy",
    "linear_jpeg_tiles",
];
const LINEAR_RAW_REASON: &str =
    "LinearRaw: already demosaiced; the night synthesis works on the CFA mosaic";

fn expected(dir: &Path, name: &str) -> Vec<u16> {
    std::fs::read(dir.join(format!("{name}.bin")))
        .unwrap()
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect()
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn lossless_jpeg_xl_decodes_to_the_written_pixels() {
    let dir = generated();
    for name in LOSSLESS {
        let img = read_dng(&dir.join(format!("{name}.dng"))).unwrap();
        assert_eq!((img.width, img.height), (400, 300), "{name}");
        assert_eq!(img.meta.bits_per_sample, 16, "{name}");
        let st = img.meta.storage.as_ref().unwrap();
        assert_eq!(st.compression, 52546, "{name}");
        let exp = expected(dir, name);
        assert_eq!(img.data.len(), exp.len(), "{name}");
        assert!(
            img.data == exp,
            "{name}: decoded samples differ from the written array"
        );
        let linear = name.starts_with("linear");
        assert_eq!(img.meta.linear_raw.is_some(), linear, "{name}");
        if let Some(l) = &img.meta.linear_raw {
            assert_eq!(l.samples_per_pixel, 3);
            assert_eq!(l.black, vec![100.0, 200.0, 300.0]);
            assert_eq!(l.white, vec![60000.0, 61000.0, 62000.0]);
        } else {
            assert_eq!(img.bayer().unwrap().name(), "RGGB");
        }
    }
}

/// (max, mean) absolute difference between our decode of NAME.dng and NAME.bin.
fn decode_error(dir: &Path, name: &str) -> (i32, f64) {
    let img = read_dng(&dir.join(format!("{name}.dng"))).unwrap();
    let exp = expected(dir, name);
    assert_eq!(img.data.len(), exp.len());
    let diffs: Vec<i32> = img
        .data
        .iter()
        .zip(&exp)
        .map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs())
        .collect();
    let max = diffs.iter().copied().max().unwrap();
    let mean = diffs.iter().map(|&d| f64::from(d)).sum::<f64>() / diffs.len() as f64;
    (max, mean)
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn lossy_jpeg_decodes_within_a_few_codes_of_libjpeg() {
    let dir = generated();
    let (max, mean) = decode_error(dir, "linear_jpeg_tiles");
    assert!(max <= 4 && mean < 0.05, "max {max} mean {mean}");
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn lossy_jpeg_xl_decodes_close_to_libjxl() {
    let dir = generated();
    let (max, mean) = decode_error(dir, "linear_jxl_lossy");
    eprintln!("lossy JPEG XL vs libjxl: max {max} mean {mean} (16-bit codes)");
    assert!(max <= 2 && mean < 0.1, "max {max} mean {mean}");
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn adobe_sdk_and_libraw_read_the_same_files() {
    let dir = generated();
    let py = common::python();
    let mut args: Vec<&std::ffi::OsStr> = vec![dir.as_os_str()];
    args.extend(GOOD.iter().map(std::ffi::OsStr::new));
    let out = common::run_validator(&py, "compressed_check.py", &args);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        text.matches("SDK reads it, no warning").count(),
        GOOD.len(),
        "{text}"
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn info_and_render_work_on_each() {
    let dir = generated();
    for name in GOOD {
        let p = dir.join(format!("{name}.dng"));
        let out = common::bin().arg("info").arg(&p).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "{name}: {text}");
        if name.starts_with("linear") {
            assert!(text.contains("LinearRaw, 3 samples per pixel"), "{text}");
            assert!(text.contains("per sample:"), "{text}");
            assert!(text.contains(LINEAR_RAW_REASON), "{text}");
        } else {
            assert!(text.contains("synthesis:     ready"), "{text}");
        }
        let png = dir.join(format!("{name}.render.png"));
        let out = common::bin()
            .arg("render")
            .arg(&p)
            .arg("-o")
            .arg(&png)
            .arg("--overwrite")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        // DefaultCropSize 384x288 of the 392x296 active area.
        let img = image::open(&png).unwrap();
        assert_eq!((img.width(), img.height()), (384, 288), "{name}");
    }
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn linear_raw_render_normalizes_per_sample() {
    let dir = generated();
    // A flat mid-grey LinearRaw would be flat after rendering; here: the render of the
    // 16-bit file equals the one computed from its samples by the DNG formulas.
    let img = read_dng(&dir.join("linear_jxl_tiles.dng")).unwrap();
    let n = [0.55, 1.0, 0.7];
    let cam = day2night::isp::render_linear_raw::camera_rgb(&img, n).unwrap();
    let (black, white) = ([100.0, 200.0, 300.0], [60000.0, 61000.0, 62000.0]);
    let (r, c) = (40usize, 50usize);
    for s in 0..3 {
        let x = f64::from(img.data[((r + 2) * 400 + c + 4) * 3 + s]);
        let want = (((x - black[s]) / (white[s] - black[s])).clamp(0.0, 1.0) / n[s]).min(1.0);
        let got = f64::from(cam.data[(r * cam.width + c) * 3 + s]);
        assert!((got - want).abs() < 1e-6, "sample {s}: {got} vs {want}");
    }
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn synth_works_on_jpeg_xl_cfa_and_refuses_linear_raw() {
    let dir = generated();
    let py = common::python();
    for name in ["cfa_jxl_tiles", "cfa_jxl_strips"] {
        let src = dir.join(format!("{name}.dng"));
        let out_dir = tempfile::tempdir().unwrap();
        let out = common::bin()
            .arg("synth")
            .arg(&src)
            .arg("-o")
            .arg(out_dir.path())
            .args(["--iso", "1600"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        // Night DNGs are written with today's writer (uncompressed strips by default).
        let clean = out_dir.path().join(format!("{name}_clean.dng"));
        let night = read_dng(&clean).unwrap();
        assert_eq!(night.meta.storage.as_ref().unwrap().compression, 1);
        assert_eq!((night.width, night.height), (400, 300));
        let sidecar = out_dir.path().join(format!("{name}.json"));
        let v = common::run_validator(
            &py,
            "synth_check.py",
            &[
                src.as_os_str(),
                sidecar.as_os_str(),
                out_dir.path().as_os_str(),
            ],
        );
        assert!(
            v.status.success(),
            "{name}: {}\n{}",
            String::from_utf8_lossy(&v.stdout),
            String::from_utf8_lossy(&v.stderr)
        );
    }
    for name in ["linear_jxl_tiles", "linear_jpeg_tiles"] {
        let out_dir = tempfile::tempdir().unwrap();
        let out = common::bin()
            .arg("synth")
            .arg(dir.join(format!("{name}.dng")))
            .arg("-o")
            .arg(out_dir.path())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(LINEAR_RAW_REASON) && err.contains(name),
            "{err}"
        );
        assert_eq!(std::fs::read_dir(out_dir.path()).unwrap().count(), 0);
    }
}

/// IFD0's (offsets, counts) entry value positions for tiles or strips: (tag 324/273 values,
/// tag 325/279 values) as file offsets of each u32 (little-endian files only).
fn block_entries(bytes: &[u8]) -> (Vec<usize>, Vec<usize>) {
    let u16_at = |o: usize| u16::from_le_bytes([bytes[o], bytes[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    let ifd = u32_at(4);
    let mut offs = Vec::new();
    let mut counts = Vec::new();
    for i in 0..u16_at(ifd) {
        let e = ifd + 2 + 12 * i;
        let (tag, n) = (u16_at(e), u32_at(e + 4));
        let at = if n == 1 { e + 8 } else { u32_at(e + 8) };
        let list: Vec<usize> = (0..n).map(|k| at + 4 * k).collect();
        match tag {
            273 | 324 => offs = list,
            279 | 325 => counts = list,
            _ => {}
        }
    }
    (offs, counts)
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn corrupt_truncated_and_missized_tiles_are_clear_errors() {
    let dir = generated();
    for (name, codec) in [
        ("cfa_jxl_tiles", "JPEG XL tile 0"),
        ("cfa_jxl_strips", "JPEG XL strip 0"),
        ("linear_jxl_tiles", "JPEG XL tile 0"),
        ("linear_jpeg_tiles", "lossy JPEG tile 0"),
    ] {
        let good = std::fs::read(dir.join(format!("{name}.dng"))).unwrap();
        let (offs, counts) = block_entries(&good);
        let u32_at = |b: &[u8], o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
        let (off0, len0) = (u32_at(&good, offs[0]) as usize, u32_at(&good, counts[0]));
        // Truncated block: its byte count halved.
        let mut b = good.clone();
        b[counts[0]..counts[0] + 4].copy_from_slice(&(len0 / 2).to_le_bytes());
        let e = read_dng_bytes(&b).expect_err(name).to_string();
        assert!(e.contains(codec), "{name} truncated: {e}");
        // Garbage header.
        let mut b = good.clone();
        b[off0..off0 + 16].fill(0xAB);
        let e = read_dng_bytes(&b).expect_err(name).to_string();
        assert!(
            e.contains(codec) && e.contains("cannot decode"),
            "{name}: {e}"
        );
        // Flipped bytes inside the entropy-coded data: an error naming the block, or
        // (no checksum in either format) other pixels; never a panic.
        for k in 0..24usize {
            let mut b = good.clone();
            let at = off0 + 20 + (k * 7919) % (len0 as usize - 24);
            b[at] ^= 1 << (k % 8);
            b[at + 1] = b[at + 1].wrapping_add((k as u8).wrapping_mul(37).wrapping_add(1));
            if let Err(e) = read_dng_bytes(&b) {
                assert!(e.to_string().contains(codec), "{name}: {e}");
            }
        }
    }
    let e = read_dng(&dir.join("bad_jxl_tile_size.dng"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("JPEG XL tile 1: decodes to 64x64 pixels") && e.contains("needs 128x128"),
        "{e}"
    );
    let e = read_dng(&dir.join("bad_cfa_jpeg.dng"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("lossy JPEG (34892) in a CFA raw"), "{e}");
    for bad in ["bad_jxl_tile_size", "bad_cfa_jpeg"] {
        let out = common::bin()
            .arg("info")
            .arg(dir.join(format!("{bad}.dng")))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(1), "{bad}");
        assert!(String::from_utf8_lossy(&out.stderr).starts_with("day2night: "));
    }
}
