//! Generate the committed DNG fixtures (deterministic: same code, same bytes).
//!
//! ```text
//! cargo run --release --example make_fixtures -- fixtures/ [SOURCE.png]
//! ```
//!
//! Writes every fixture listed in `fixtures/README.md`; the default day image `day.dng` is
//! mosaicked from `fixtures/source/astronaut.png` (NASA, public domain).

#[path = "common/scene.rs"]
mod scene;

use day2night::dng::write::{encode_dng, Compression, RawIfd, UniqueIdHash, WriteOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::{Bayer, RawImage, Rect};
use scene::{day_meta, hash01, mat_vec, synthetic_scene, CM1, SRGB_TO_XYZ};
use std::path::{Path, PathBuf};

/// Texture frequency of the fixtures' scene (radians per pixel, x and y).
const TEXTURE: [f64; 2] = [0.3, 0.2];

struct Spec {
    name: &'static str,
    width: usize,
    height: usize,
    bayer: Bayer,
    bits: u16,
    opts: WriteOptions,
    per_site_black: bool,
    black_deltas: bool,
    linearization: bool,
    border: Option<(u32, u32)>,
}

fn base_meta(bayer: Bayer, bits: u16) -> RawMeta {
    day_meta(bayer, bits, 0.0, ((1u32 << bits) - 1) as f64)
}

fn make_synthetic(s: &Spec) -> RawImage {
    let mut m = base_meta(s.bayer, s.bits);
    let code_max = ((1u32 << s.bits) - 1) as f64;
    // Linearized range: the LUT maps stored codes to 0..=16383 (14-bit linear).
    let lin_max = if s.linearization { 16383.0 } else { code_max };
    let black_base = (lin_max * 0.0625).round();
    m.levels.white = lin_max;
    if s.per_site_black {
        m.levels.black_repeat = (2, 2);
        m.levels.black = vec![
            black_base - 4.0,
            black_base,
            black_base + 2.0,
            black_base + 6.0,
        ];
    } else {
        m.levels.black = vec![black_base];
    }
    let (bt, bl) = s.border.unwrap_or((0, 0));
    let aw = s.width - bl as usize;
    let ah = s.height - bt as usize;
    if s.border.is_some() {
        m.active_area = Some(Rect {
            top: bt,
            left: bl,
            bottom: s.height as u32,
            right: s.width as u32,
        });
    }
    if aw >= 8 && ah >= 8 {
        // A 2-pixel margin for demosaicing (the DNG SDK warns without one).
        m.default_crop_origin = Some([2.0, 2.0]);
        m.default_crop_size = Some([(aw - 4) as f64, (ah - 4) as f64]);
    }
    if s.black_deltas {
        m.levels.black_delta_h = (0..aw).map(|c| ((c % 7) as f64) * 0.5).collect();
        m.levels.black_delta_v = (0..ah).map(|r| ((r % 5) as f64) * 0.25).collect();
    }
    let lut: Option<Vec<u16>> = s.linearization.then(|| {
        (0..=code_max as usize)
            .map(|i| (lin_max * (i as f64 / code_max).powi(2)).round() as u16)
            .collect()
    });
    m.linearization_table = lut.clone();
    let neutral = m.as_shot_neutral.unwrap_or([1.0; 3]);
    let mut data = vec![0u16; s.width * s.height];
    for y in 0..s.height {
        for x in 0..s.width {
            let lin = if (y as u32) < bt || (x as u32) < bl {
                // Masked border: black plus a little deterministic noise.
                black_base + (hash01(x as u64, y as u64, 7) * 8.0).floor()
            } else {
                let (ay, ax) = (y - bt as usize, x - bl as usize);
                let cam = synthetic_scene(ax, ay, aw, ah, neutral, TEXTURE);
                let ch = s.bayer.color_at(ay, ax) as usize;
                let black = m.levels.black_at(ay, ax);
                let noise = hash01(x as u64, y as u64, 1) - 0.5;
                black + (cam[ch] * 0.9).clamp(0.0, 1.0) * (lin_max - black) + noise * 2.0
            };
            let lin = lin.clamp(0.0, lin_max);
            data[y * s.width + x] = match &lut {
                // Invert the square-law table: the stored code whose value is closest.
                Some(_) => ((lin / lin_max).sqrt() * code_max).round() as u16,
                None => lin.round() as u16,
            };
        }
    }
    RawImage {
        width: s.width,
        height: s.height,
        data,
        meta: m,
    }
}

/// The inverse sRGB curve (the library's, in f64).
fn srgb_to_linear(c: f64) -> f64 {
    day2night::color::srgb::eotf_f64(c)
}

/// The default day image: astronaut.png -> linear sRGB -> XYZ -> camera (CM1) -> RGGB mosaic,
/// 12-bit, black 256, white 4095, masked border, DefaultCrop, D65, ISO 100.
fn make_day(source: &Path) -> Result<RawImage, Box<dyn std::error::Error>> {
    let rgb = image::open(source)?.to_rgb8();
    let (sw, sh) = (rgb.width() as usize & !1, rgb.height() as usize & !1);
    let (bt, bl) = (8usize, 16usize);
    let (w, h) = (sw + bl, sh + bt);
    let mut m = base_meta(Bayer::RGGB, 12);
    m.make = Some("day2night".into());
    m.model = Some("Fixture Camera".into());
    m.unique_camera_model = Some("day2night Fixture Camera".into());
    m.levels.black = vec![256.0];
    m.levels.white = 4095.0;
    m.active_area = Some(Rect {
        top: bt as u32,
        left: bl as u32,
        bottom: h as u32,
        right: w as u32,
    });
    m.default_crop_origin = Some([8.0, 8.0]);
    m.default_crop_size = Some([(sw - 16) as f64, (sh - 16) as f64]);
    m.exif.exposure_time = Some(1.0 / 250.0);
    m.exif.f_number = Some(8.0);
    // A plausible ISO-100 noise profile (variance = S*x + O on the 0..1 scale).
    m.noise_profile = Some(vec![(2.0e-5, 4.0e-7)]);
    let white_cam = mat_vec(&CM1, mat_vec(&SRGB_TO_XYZ, [1.0, 1.0, 1.0]));
    let neutral = [
        white_cam[0] / white_cam[1],
        1.0,
        white_cam[2] / white_cam[1],
    ];
    m.as_shot_neutral = Some(neutral);
    // Exposure: scene white lands at 0.8 of the range in the brightest raw channel.
    let maxc = white_cam.iter().cloned().fold(f64::MIN, f64::max);
    let gain = 0.8 / maxc;
    let (black, white) = (256.0, 4095.0);
    let mut data = vec![0u16; w * h];
    for y in 0..h {
        for x in 0..w {
            let n = hash01(x as u64, y as u64, 3) + hash01(y as u64, x as u64, 4) - 1.0;
            let v = if y < bt || x < bl {
                black + n * 3.0
            } else {
                let (ay, ax) = (y - bt, x - bl);
                let p = rgb.get_pixel(ax as u32, ay as u32).0;
                let lin = [
                    srgb_to_linear(p[0] as f64 / 255.0),
                    srgb_to_linear(p[1] as f64 / 255.0),
                    srgb_to_linear(p[2] as f64 / 255.0),
                ];
                let cam = mat_vec(&CM1, mat_vec(&SRGB_TO_XYZ, lin));
                let ch = Bayer::RGGB.color_at(ay, ax) as usize;
                let sig = (cam[ch] * gain).clamp(0.0, 1.0) * (white - black);
                // Shot + read noise, as a real capture at ISO 100 would have.
                black + sig + n * (0.5 + (sig * 0.02)).sqrt() * 2.0
            };
            data[y * w + x] = v.round().clamp(0.0, white) as u16;
        }
    }
    Ok(RawImage {
        width: w,
        height: h,
        data,
        meta: m,
    })
}

fn write(dir: &Path, name: &str, img: &RawImage, opts: &WriteOptions) -> std::io::Result<()> {
    // The fixtures keep their SHA-256 RawDataUniqueID (their bytes are the test inputs).
    let opts = WriteOptions {
        unique_id: UniqueIdHash::Sha256,
        ..opts.clone()
    };
    let bytes = encode_dng(img, &opts).map_err(std::io::Error::other)?;
    let path = dir.join(name);
    std::fs::write(&path, &bytes)?;
    println!("{} ({} bytes)", path.display(), bytes.len());
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "fixtures".to_string()),
    );
    let source = std::env::args()
        .nth(2)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/source/astronaut.png")
        });
    generate(&dir, &source)
}

/// Write every fixture into `dir`; `source` is the photograph behind `day.dng`.
/// (Also used by tests/it/fixtures_reproducible.rs.)
pub fn generate(dir: &Path, source: &Path) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let order = |big: bool| WriteOptions {
        big_endian: big,
        ..Default::default()
    };
    let specs = vec![
        Spec {
            name: "rggb_16bit_le_strips.dng",
            width: 320,
            height: 240,
            bayer: Bayer::RGGB,
            bits: 16,
            opts: WriteOptions {
                rows_per_strip: Some(16),
                ..Default::default()
            },
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "rggb_12bit_in16_le_strips.dng",
            width: 320,
            height: 240,
            bayer: Bayer::RGGB,
            bits: 12,
            opts: WriteOptions {
                unpacked16: true,
                ..Default::default()
            },
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "grbg_12bit_packed_be_strips.dng",
            width: 320,
            height: 240,
            bayer: Bayer::GRBG,
            bits: 12,
            opts: order(true),
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: Some((4, 8)),
        },
        Spec {
            name: "gbrg_10bit_packed_le_tiles.dng",
            width: 328,
            height: 248,
            bayer: Bayer::GBRG,
            bits: 10,
            opts: WriteOptions {
                uncompressed_tiles: Some((64, 48)),
                ..Default::default()
            },
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "bggr_14bit_packed_le_subifd_black2x2.dng",
            width: 320,
            height: 240,
            bayer: Bayer::BGGR,
            bits: 14,
            opts: WriteOptions {
                raw_ifd: RawIfd::Sub,
                ..Default::default()
            },
            per_site_black: true,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "rggb_12bit_ljpeg_tiles_deltas.dng",
            width: 336,
            height: 250,
            bayer: Bayer::RGGB,
            bits: 12,
            opts: WriteOptions {
                compression: Compression::Ljpeg,
                ..Default::default()
            },
            per_site_black: true,
            black_deltas: true,
            linearization: false,
            border: Some((2, 4)),
        },
        Spec {
            name: "grbg_16bit_be_ljpeg_subifd.dng",
            width: 320,
            height: 240,
            bayer: Bayer::GRBG,
            bits: 16,
            opts: WriteOptions {
                compression: Compression::Ljpeg,
                raw_ifd: RawIfd::Sub,
                big_endian: true,
                ..Default::default()
            },
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "gbrg_10bit_linearization_be.dng",
            width: 320,
            height: 240,
            bayer: Bayer::GBRG,
            bits: 10,
            opts: order(true),
            per_site_black: false,
            black_deltas: false,
            linearization: true,
            border: None,
        },
        Spec {
            name: "edge_1x1.dng",
            width: 1,
            height: 1,
            bayer: Bayer::RGGB,
            bits: 16,
            opts: WriteOptions::default(),
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "edge_7x9_12bit_packed.dng",
            width: 7,
            height: 9,
            bayer: Bayer::BGGR,
            bits: 12,
            opts: order(false),
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
        Spec {
            name: "edge_7x9_ljpeg.dng",
            width: 7,
            height: 9,
            bayer: Bayer::GRBG,
            bits: 14,
            opts: WriteOptions {
                compression: Compression::Ljpeg,
                ..Default::default()
            },
            per_site_black: false,
            black_deltas: false,
            linearization: false,
            border: None,
        },
    ];
    for s in &specs {
        let img = make_synthetic(s);
        img.validate()?;
        write(dir, s.name, &img, &s.opts)?;
    }
    let day = make_day(source)?;
    day.validate()?;
    write(dir, "day.dng", &day, &order(false))?;
    Ok(())
}
