//! DNG reader: the real Canon file (compared with LibRaw through rawpy) and hand-built small
//! DNGs covering byte orders, packed bit depths, tiles, SubIFD raws, linearization and
//! per-site black levels.
use crate::common;
use crate::dngbuild;

use day2night::dng::read::{inspect_bytes, read_dng, read_dng_bytes};
use day2night::raw::meta::{ByteOrder, Layout};
use day2night::{Bayer, Rect};
use dngbuild::{Builder, Pixels};

const CANON: &str = "dng/canon_kissx4_magiclantern_rggb14_strips.dng";

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn canon_metadata() {
    let d = common::shared_data();
    let img = read_dng(&d.join(CANON)).unwrap();
    assert_eq!((img.width, img.height), (1888, 1182));
    let m = &img.meta;
    assert_eq!(
        m.active_area,
        Some(Rect {
            top: 26,
            left: 152,
            bottom: 1182,
            right: 1886
        })
    );
    assert_eq!(m.default_crop_origin, Some([0.0, 0.0]));
    assert_eq!(m.default_crop_size, Some([1734.0, 1156.0]));
    assert_eq!(img.bayer().unwrap(), Bayer::RGGB);
    assert_eq!(m.bits_per_sample, 14);
    assert_eq!(m.levels.black, vec![2056.0]);
    assert_eq!(m.levels.black_repeat, (1, 1));
    assert_eq!(m.levels.white, 15000.0);
    let n = m.as_shot_neutral.unwrap();
    assert!((n[0] - 1.0 / 2.477).abs() < 1e-9, "{n:?}");
    assert_eq!(n[1], 1.0);
    assert!((n[2] - 1.462 / 2.477).abs() < 1e-9, "{n:?}");
    assert_eq!(m.make.as_deref(), Some("Canon"));
    assert_eq!(m.model.as_deref(), Some("Canon EOS Kiss X4"));
    assert_eq!(m.unique_camera_model.as_deref(), Some("Canon EOS Kiss X4"));
    assert_eq!(m.dng_version, [1, 1, 0, 0]);
    let cm = m.color.color_matrix1.as_ref().unwrap();
    assert_eq!(cm.len(), 9);
    assert!((cm[0] - 0.6461).abs() < 1e-12);
    assert_eq!(m.color.analog_balance, Some(vec![1.0, 1.0, 1.0]));
    // ISO 0 and ExposureTime 0 mean "unknown".
    assert_eq!(m.exif.iso, None);
    assert_eq!(m.exif.exposure_time, None);
    assert_eq!(m.noise_profile, None);
    assert_eq!(m.orientation, 1);
    let st = m.storage.as_ref().unwrap();
    assert_eq!(st.byte_order, ByteOrder::Little);
    assert_eq!(st.sub_ifd, None);
    assert_eq!(st.compression, 1);
    assert_eq!(
        st.layout,
        Layout::Strips {
            rows_per_strip: 1182
        }
    );
    // Carried entries: Software, XResolution, BaselineNoise, ... but never structural ones.
    let tags: Vec<u16> = m.ifd0_extra.iter().map(|e| e.tag).collect();
    assert!(tags.contains(&305) && tags.contains(&50731), "{tags:?}");
    for s in [273u16, 279, 256, 257, 258, 259, 34665, 50714, 50728] {
        assert!(!tags.contains(&s), "tag {s} must not be carried");
    }
    assert!(!m.exif_extra.is_empty());
    img.validate().unwrap();
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn canon_pixels_match_libraw() {
    let d = common::shared_data();
    let py = common::python();
    let path = d.join(CANON);
    let img = read_dng(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let pix = dir.path().join("pix.u16");
    let bytes: Vec<u8> = img.data.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&pix, bytes).unwrap();
    let a = img.active_area();
    let exp = serde_json::json!({
        "width": img.width, "height": img.height,
        "active_area": [a.top, a.left, a.bottom, a.right],
        "bayer": img.bayer().unwrap().name(),
        "black": img.meta.levels.black[0], "white": img.meta.levels.white,
        "neutral": img.meta.as_shot_neutral,
    });
    let ej = dir.path().join("exp.json");
    std::fs::write(&ej, exp.to_string()).unwrap();
    let out = common::run_validator(
        &py,
        "read_compare.py",
        &[path.as_os_str(), pix.as_os_str(), ej.as_os_str()],
    );
    assert!(
        out.status.success(),
        "rawpy comparison failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn canon_info_cli() {
    let d = common::shared_data();
    let out = common::bin()
        .args(["info", "--json"])
        .arg(d.join(CANON))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let o = &v[0];
    assert_eq!(o["synth_ready"], true);
    assert_eq!(o["raw"]["cfa"], "RGGB");
    assert_eq!(o["raw"]["width"], 1888);
    assert_eq!(o["raw"]["meta"]["levels"]["white"], 15000.0);
    let out = common::bin()
        .arg("info")
        .arg(d.join(CANON))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("RGGB") && text.contains("26,152,1182,1886"),
        "{text}"
    );
    // The one warning: the real Canon has no NoiseProfile and no Exif ISO, so `synth`
    // would use another camera's noise table (issue 24).
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("warning[unknown-iso]: ")
            && err.contains(": noise: the input has no NoiseProfile and its ISO is unknown"),
        "{err}"
    );
}

fn check_same(b: &Builder) -> day2night::RawImage {
    let bytes = b.build();
    let img = read_dng_bytes(&bytes).unwrap_or_else(|e| panic!("{b:?}: {e}"));
    assert_eq!((img.width, img.height), (b.width, b.height));
    assert!(img.data == b.pixels, "pixels differ for {:?}", b.layout);
    img
}

#[test]
fn byte_orders_and_bit_depths_strips_and_tiles() {
    for big in [false, true] {
        for bits in [8u16, 10, 12, 14, 16] {
            for layout in [
                Pixels::Strips { rows: 1 },
                Pixels::Strips { rows: 5 },
                Pixels::Tiles { w: 16, h: 16 },
                Pixels::Tiles { w: 32, h: 48 },
            ] {
                for (w, h) in [(37, 23), (64, 48), (1, 1), (7, 9)] {
                    let mut b = Builder::new(w, h, bits);
                    b.big_endian = big;
                    b.layout = layout;
                    let img = check_same(&b);
                    assert_eq!(img.meta.bits_per_sample, bits);
                    assert_eq!(img.meta.levels.white, ((1u32 << bits) - 1) as f64);
                    let want = if big {
                        ByteOrder::Big
                    } else {
                        ByteOrder::Little
                    };
                    assert_eq!(img.meta.storage.as_ref().unwrap().byte_order, want);
                }
            }
        }
    }
}

#[test]
fn lossless_jpeg_tiles_and_strips() {
    for bits in [10u16, 12, 14, 16] {
        for layout in [
            Pixels::LjpegTiles {
                w: 16,
                h: 16,
                two_components: false,
            },
            Pixels::LjpegTiles {
                w: 32,
                h: 16,
                two_components: true,
            },
            Pixels::LjpegStrips { rows: 8 },
            Pixels::LjpegStrips { rows: 100 },
        ] {
            let mut b = Builder::new(70, 35, bits);
            b.layout = layout;
            let img = check_same(&b);
            assert_eq!(img.meta.storage.as_ref().unwrap().compression, 7);
        }
    }
}

#[test]
fn raw_in_subifd() {
    let mut b = Builder::new(40, 30, 12).set(
        50829,
        day2night::tiff::value::Value::Long(vec![2, 4, 30, 40]),
    );
    b.raw_in_sub = true;
    b.big_endian = true;
    let img = check_same(&b);
    let st = img.meta.storage.as_ref().unwrap();
    assert_eq!(st.sub_ifd, Some(vec![0]));
    assert_eq!(
        img.meta.active_area,
        Some(Rect {
            top: 2,
            left: 4,
            bottom: 30,
            right: 40
        })
    );
    assert_eq!(img.meta.make.as_deref(), Some("TestMake"));
    // The preview IFD's structural tags are not carried; IFD0 DNG tags are modelled.
    assert!(img
        .meta
        .ifd0_extra
        .iter()
        .all(|e| e.tag != 273 && e.tag != 330));
    let info = inspect_bytes(&b.build()).unwrap();
    assert_eq!(info.raw_ifd.as_deref(), Some("IFD0/SubIFD0"));
    assert!(info.synth_ready);
    assert_eq!(info.ifds.len(), 2);
}

#[test]
fn linearization_and_per_site_black_and_deltas() {
    use day2night::tiff::value::Value;
    let (w, h) = (20, 10);
    let table: Vec<u16> = (0..4096u32).map(|i| (i * 3 / 2) as u16).collect();
    let dh: Vec<(i32, i32)> = (0..w).map(|i| (i as i32, 4)).collect();
    let dv: Vec<(i32, i32)> = (0..h).map(|i| (-(i as i32), 2)).collect();
    let b = Builder::new(w, h, 12)
        .set(50712, Value::Short(table.clone()))
        .set(50713, Value::Short(vec![2, 2]))
        .set(
            50714,
            Value::Rational(vec![(200, 1), (201, 1), (405, 2), (203, 1)]),
        )
        .set(50715, Value::SRational(dh))
        .set(50716, Value::SRational(dv))
        .set(50717, Value::Long(vec![6000]));
    let img = check_same(&b);
    let l = &img.meta.levels;
    assert_eq!(img.meta.linearization_table.as_deref(), Some(&table[..]));
    assert_eq!(l.black_repeat, (2, 2));
    assert_eq!(l.black, vec![200.0, 201.0, 202.5, 203.0]);
    assert_eq!(l.black_delta_h.len(), w);
    assert_eq!(l.black_delta_h[3], 0.75);
    assert_eq!(l.black_delta_v[4], -2.0);
    assert_eq!(l.white, 6000.0);
    assert_eq!(l.black_at(1, 3), 203.0 + 0.75 - 0.5);
}

#[test]
fn other_phases_and_non_bayer_cfa_still_read() {
    use day2night::tiff::value::Value;
    for bayer in Bayer::ALL {
        let b = Builder::new(8, 8, 12).set(33422, Value::Byte(bayer.0.to_vec()));
        assert_eq!(check_same(&b).bayer().unwrap(), bayer);
    }
    // 2x4 pattern: readable, but not a Bayer mosaic.
    let b = Builder::new(8, 8, 12)
        .set(33421, Value::Short(vec![2, 4]))
        .set(33422, Value::Byte(vec![0, 1, 0, 1, 1, 2, 1, 2]));
    let img = check_same(&b);
    let e = img.bayer().unwrap_err().to_string();
    assert!(e.contains("2x4"), "{e}");
    let info = inspect_bytes(&b.build()).unwrap();
    assert!(!info.synth_ready && info.error.is_none());
    assert!(info.reason.unwrap().contains("2x4"));
}

#[test]
fn exif_and_colour_fields() {
    use day2night::tiff::value::Value;
    let mut b = Builder::new(8, 8, 12)
        .set(51041, Value::Double(vec![1e-4, 2e-6]))
        .set(50730, Value::SRational(vec![(-1, 2)]))
        .set(50728, Value::Rational(vec![(1, 2), (2, 1), (3, 2)]))
        .set(51009, Value::Undefined(vec![0, 0, 0, 0]));
    b.exif = vec![
        (34855, Value::Short(vec![800])),
        (33434, Value::Rational(vec![(1, 50)])),
        (33437, Value::Rational(vec![(28, 10)])),
        (36867, Value::ascii("2024:01:02 03:04:05")),
        (37386, Value::Rational(vec![(50, 1)])),
    ];
    let m = check_same(&b).meta;
    assert_eq!(m.exif.iso, Some(800));
    assert_eq!(m.exif.exposure_time, Some(0.02));
    assert_eq!(m.exif.f_number, Some(2.8));
    assert_eq!(
        m.exif.date_time_original.as_deref(),
        Some("2024:01:02 03:04:05")
    );
    assert_eq!(m.exif_extra.len(), 1);
    assert_eq!(m.noise_profile, Some(vec![(1e-4, 2e-6)]));
    assert_eq!(m.color.baseline_exposure, Some(-0.5));
    assert_eq!(m.as_shot_neutral, Some([0.25, 1.0, 0.75]));
    assert_eq!(m.opcode_lists[1].as_deref(), Some(&[0u8, 0, 0, 0][..]));
    assert_eq!(m.color.calibration_illuminant1, Some(21));
}

/// Our decode of builder-made DNGs (LJ92 tiles with 2 components, LJ92 strips, packed
/// big-endian, SubIFD raw) compared with LibRaw's, sample by sample.
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn builder_files_match_libraw() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let mut cases = Vec::new();
    let mut b = Builder::new(320, 240, 14);
    b.layout = Pixels::LjpegTiles {
        w: 64,
        h: 64,
        two_components: true,
    };
    cases.push(("lj92_tiles_2c", b));
    let mut b = Builder::new(320, 240, 12);
    b.layout = Pixels::LjpegTiles {
        w: 128,
        h: 96,
        two_components: false,
    };
    b.big_endian = true;
    cases.push(("lj92_tiles_1c_be", b));
    let mut b = Builder::new(320, 240, 16);
    b.layout = Pixels::LjpegStrips { rows: 240 };
    cases.push(("lj92_strip", b));
    let mut b = Builder::new(320, 240, 12);
    b.big_endian = true;
    b.raw_in_sub = true;
    cases.push(("packed12_be_subifd", b));
    let mut b = Builder::new(320, 240, 10);
    b.layout = Pixels::Tiles { w: 64, h: 64 };
    cases.push(("packed10_tiles", b));
    for (name, b) in cases {
        let path = dir.path().join(format!("{name}.dng"));
        std::fs::write(&path, b.build()).unwrap();
        let img = read_dng(&path).unwrap();
        assert_eq!(img.data, b.pixels, "{name}");
        let pix = dir.path().join(format!("{name}.u16"));
        let bytes: Vec<u8> = img.data.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&pix, bytes).unwrap();
        let exp = serde_json::json!({
            "width": img.width, "height": img.height, "active_area": null,
            "bayer": img.bayer().unwrap().name(),
            "black": img.meta.levels.black[0], "white": img.meta.levels.white,
            "neutral": img.meta.as_shot_neutral,
        });
        let ej = dir.path().join(format!("{name}.json"));
        std::fs::write(&ej, exp.to_string()).unwrap();
        let out = common::run_validator(
            &py,
            "read_compare.py",
            &[path.as_os_str(), pix.as_os_str(), ej.as_os_str()],
        );
        assert!(
            out.status.success(),
            "{name}: rawpy comparison failed:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// Every committed fixture (made by the writer's generator) decodes to the same samples as
/// LibRaw's, with the same pattern, levels and white balance.
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn fixtures_match_libraw() {
    let py = common::python();
    let dir = tempfile::tempdir().unwrap();
    let mut n = 0;
    let mut entries: Vec<_> = std::fs::read_dir(common::fixtures())
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    entries.sort();
    for path in entries {
        if path.extension().is_none_or(|x| x != "dng") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let img = read_dng(&path).unwrap_or_else(|e| panic!("{e}"));
        if img.width < 22 || img.height < 22 {
            eprintln!("{name}: not compared (LibRaw refuses images under 22 pixels a side)");
            continue;
        }
        compare_with_libraw(&py, dir.path(), &path, &img, &name);
        n += 1;
    }
    assert!(n > 0, "no fixtures/*.dng compared with LibRaw");
}

fn compare_with_libraw(
    py: &std::path::Path,
    dir: &std::path::Path,
    path: &std::path::Path,
    img: &day2night::RawImage,
    name: &str,
) {
    let pix = dir.join(format!("{name}.u16"));
    let bytes: Vec<u8> = img.data.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&pix, bytes).unwrap();
    let l = &img.meta.levels;
    let simple_black = l.black.iter().all(|&b| b == l.black[0])
        && l.black_delta_h.is_empty()
        && l.black_delta_v.is_empty()
        && img.meta.linearization_table.is_none();
    let a = img.active_area();
    let exp = serde_json::json!({
        "width": img.width, "height": img.height,
        "active_area": img.meta.active_area.map(|_| [a.top, a.left, a.bottom, a.right]),
        "bayer": img.bayer().unwrap().name(),
        "black": if simple_black { Some(l.black[0]) } else { None },
        "white": if img.meta.linearization_table.is_none() { Some(l.white) } else { None },
        "neutral": img.meta.as_shot_neutral,
        "linearization": img.meta.linearization_table,
    });
    let ej = dir.join(format!("{name}.json"));
    std::fs::write(&ej, exp.to_string()).unwrap();
    let out = common::run_validator(
        py,
        "read_compare.py",
        &[path.as_os_str(), pix.as_os_str(), ej.as_os_str()],
    );
    assert!(
        out.status.success(),
        "{name}: rawpy comparison failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The writer's lossless JPEG output read back by our decoder and by LibRaw: the real
/// Canon file re-encoded as LJ92 tiles (raw in IFD0 and in a SubIFD).
#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn writer_ljpeg_output_matches_libraw() {
    use day2night::dng::write::{encode_dng, Compression, RawIfd, WriteOptions};
    let d = common::shared_data();
    let py = common::python();
    let src = read_dng(&d.join(CANON)).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for raw_ifd in [RawIfd::Main, RawIfd::Sub] {
        let opts = WriteOptions {
            compression: Compression::Ljpeg,
            raw_ifd,
            ..Default::default()
        };
        let bytes = encode_dng(&src, &opts).unwrap_or_else(|e| panic!("LJ92 {raw_ifd:?}: {e}"));
        let back = read_dng_bytes(&bytes).unwrap();
        assert_eq!(back.meta.storage.as_ref().unwrap().compression, 7);
        assert!(back.data == src.data, "LJ92 round trip changed pixels");
        let name = format!("canon_lj92_{raw_ifd:?}.dng");
        let path = dir.path().join(&name);
        std::fs::write(&path, &bytes).unwrap();
        compare_with_libraw(&py, dir.path(), &path, &back, &name);
    }
}

/// The writer's LJ92 encoder against our decoder on awkward inputs: all precisions,
/// 1-4 components, extreme values and noise.
#[test]
fn writer_encoder_round_trips_through_our_decoder() {
    use day2night::dng::{ljpeg, ljpeg_encode};
    let mut s = 0x1234_5678u32;
    for p in [2u8, 8, 10, 12, 14, 15, 16] {
        for nc in 1..=4usize {
            let (w, h) = (17, 9);
            let max = (1u32 << p) - 1;
            let samples: Vec<u16> = (0..w * h * nc)
                .map(|i| {
                    s ^= s << 13;
                    s ^= s >> 17;
                    s ^= s << 5;
                    match i % 5 {
                        0 => 0,
                        1 => max as u16,
                        _ => (s % (max + 1)) as u16,
                    }
                })
                .collect();
            let enc = match ljpeg_encode::encode(&samples, w, h, nc, p) {
                Ok(e) => e,
                Err(e) => panic!("encoder refused p={p} nc={nc}: {e}"),
            };
            let d = ljpeg::decode(&enc).unwrap();
            assert_eq!((d.width, d.height, d.components), (w, h, nc));
            assert!(d.data == samples, "p={p} nc={nc}");
        }
    }
}

/// When IFD0 (an RGB preview) also claims NewSubFileType 0, the CFA SubIFD is still chosen.
#[test]
fn cfa_subifd_preferred_over_main_preview() {
    use day2night::tiff::value::Value;
    let mut b = Builder::new(24, 16, 12);
    b.raw_in_sub = true;
    b.ifd0_set = vec![(254, Value::Long(vec![0]))];
    let img = check_same(&b);
    assert_eq!(img.meta.storage.unwrap().sub_ifd, Some(vec![0]));
}
