//! Tests of the EXR writer: both encoders, rows and blocks against whole images, determinism
//! across runs and thread counts, attributes, compression names.

use super::*;
use crate::error::Error;
use exr::prelude::*;

#[test]
fn rows_and_blocks_give_the_whole_image_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (13usize, 70usize);
    let mut img = RgbImage::new(w, h);
    for (i, v) in img.data.iter_mut().enumerate() {
        *v = match i % 13 {
            0 => f32::NAN,
            1 => 1e9,
            _ => ((i * 7919) % 1000) as f32 / 997.0,
        };
    }
    let attrs = [("day2night:x".to_string(), "y".to_string())];
    let policy = OutputPolicy::default();
    for compression in [
        ExrCompression::None,
        ExrCompression::Zips,
        ExrCompression::Zip,
    ] {
        for half in [true, false] {
            let opts = ExrOptions {
                half,
                compression,
                ..ExrOptions::default()
            };
            assert!(encodes_rows(&opts));
            let a = dir.path().join(format!("a{compression}{half}.exr"));
            write_exr(&img, &a, &opts, &attrs, &policy).unwrap();
            // bands of 32 rows (the render's), the last one short
            let mut blocks = Vec::new();
            for (k, rows) in img.data.chunks(3 * w * 32).enumerate() {
                blocks.extend(encode_exr_rows(rows, w, 32 * k, &opts).unwrap());
            }
            let b = dir.path().join(format!("b{compression}{half}.exr"));
            write_exr_blocks(w, h, &blocks, &b, &opts, &attrs, &policy).unwrap();
            assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
            // a missing block and a misaligned band are errors, not bad files
            let c = dir.path().join(format!("c{compression}{half}.exr"));
            assert!(write_exr_blocks(w, h, &blocks[1..], &c, &opts, &attrs, &policy).is_err());
            assert!(!c.exists());
        }
    }
    let zip = ExrOptions::default();
    assert!(encode_exr_rows(&img.data[..3 * w * 16], w, 8, &zip).is_err());
    assert!(encode_exr_rows(&img.data[..3 * w * 16 + 1], w, 0, &zip).is_err());
    assert!(!encodes_rows(&ExrOptions {
        compression: ExrCompression::Piz,
        ..ExrOptions::default()
    }));
}
use std::io::Cursor;

#[test]
fn writes_and_reads_back_sanitized() {
    let mut img = RgbImage::new(5, 3);
    img.data[0] = f32::NAN;
    img.data[1] = f32::INFINITY;
    img.data[2] = -1e9;
    img.data[3] = 0.25;
    for c in ExrCompression::ALL {
        for half in [true, false] {
            let mut buf = Cursor::new(Vec::new());
            let opts = ExrOptions {
                half,
                compression: c,
                ..ExrOptions::default()
            };
            encode_exr(&img, &mut buf, &opts, &[("a:b".into(), "x".into())]).unwrap();
            let bytes = buf.into_inner();
            let image = exr::prelude::read()
                .no_deep_data()
                .largest_resolution_level()
                .rgba_channels(
                    |r, _| vec![[0f32; 3]; r.area()],
                    |v: &mut Vec<[f32; 3]>, p: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                        v[p.1 * 5 + p.0] = [r, g, b]
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(Cursor::new(bytes))
                .unwrap();
            let px = &image.layer_data.channel_data.pixels;
            let lim = if half { HALF_MAX } else { f32::MAX };
            assert_eq!(px[0][0], 0.0, "{c}");
            if c == ExrCompression::Pxr24 && !half {
                // 24-bit floats: finite and near the limit
                assert!(px[0][1].is_finite() && px[0][1] > 3.0e38, "{c}");
                continue;
            }
            assert_eq!(px[0][1], lim, "{c}");
            assert_eq!(px[0][2], if half { -lim } else { -1e9 }, "{c}");
            if !matches!(c, ExrCompression::B44 | ExrCompression::B44a) || !half {
                assert_eq!(px[1][0], 0.25, "{c}");
            }
            assert!(image.attributes.chromaticities.is_some());
        }
    }
}

#[test]
fn header_is_deterministic_with_many_attributes() {
    let img = RgbImage::new(3, 2);
    let attrs: Vec<(String, String)> = (0..12)
        .map(|i| (format!("k{i}"), format!("v{i}")))
        .collect();
    let enc = || {
        let mut buf = Cursor::new(Vec::new());
        encode_exr(&img, &mut buf, &ExrOptions::default(), &attrs).unwrap();
        buf.into_inner()
    };
    let first = enc();
    // HashMap order is random per map: many encodings in one process must still agree
    for _ in 0..20 {
        assert_eq!(enc(), first);
    }
    let back = exr::meta::MetaData::read_from_buffered(Cursor::new(&first), true).unwrap();
    assert_eq!(back.headers[0].own_attributes.other.len(), 12);
}

#[test]
fn parallel_compression_is_deterministic() {
    let mut img = RgbImage::new(97, 83);
    for (i, v) in img.data.iter_mut().enumerate() {
        *v = ((i * 7919) % 1000) as f32 / 997.0;
    }
    let enc = || {
        let mut buf = Cursor::new(Vec::new());
        encode_exr(&img, &mut buf, &ExrOptions::default(), &[]).unwrap();
        buf.into_inner()
    };
    let a = enc();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(enc);
    assert_eq!(a, b);
    assert_eq!(a, enc());
}

/// Decode EXR bytes with the `exr` crate: (width, height, RGB samples as f32).
fn read_back(bytes: &[u8]) -> (usize, usize, Vec<[f32; 3]>) {
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |r, _| (r.0, vec![[0f32; 3]; r.area()]),
            |v: &mut (usize, Vec<[f32; 3]>),
             p: Vec2<usize>,
             (r, g, b, _a): (f32, f32, f32, f32)| { v.1[p.1 * v.0 + p.0] = [r, g, b] },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes.to_vec()))
        .unwrap();
    let size = image.layer_data.size;
    (size.0, size.1, image.layer_data.channel_data.pixels.1)
}

/// A deterministic image with distinct, varied values (some negative, some large).
fn ramp(w: usize, h: usize) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    let mut s = 0x9e37_79b9_u32;
    for v in img.data.iter_mut() {
        s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        *v = ((s >> 8) as f32 / (1u32 << 24) as f32 - 0.1) * 3.0;
    }
    img
}

/// (first line, data size) of every block, parsed from the offset table.
fn chunks(bytes: &[u8]) -> Vec<(i32, usize)> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), true).unwrap();
    let h = &meta.headers[0];
    let n = h.chunk_count;
    // header end: the offset table is the n u64 before the first chunk
    let first = {
        let mut pos = 8;
        while bytes[pos] != 0 {
            let name_end = pos + bytes[pos..].iter().position(|&b| b == 0).unwrap();
            let ty_end = name_end + 1 + bytes[name_end + 1..].iter().position(|&b| b == 0).unwrap();
            let size = i32::from_le_bytes(bytes[ty_end + 1..ty_end + 5].try_into().unwrap());
            pos = ty_end + 5 + size as usize;
        }
        pos + 1
    };
    (0..n)
        .map(|i| {
            let o = u64::from_le_bytes(bytes[first + 8 * i..first + 8 * i + 8].try_into().unwrap())
                as usize;
            let y = i32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
            let len = i32::from_le_bytes(bytes[o + 4..o + 8].try_into().unwrap());
            assert!(o + 8 + len as usize <= bytes.len());
            (y, len as usize)
        })
        .collect()
}

#[test]
fn own_encoder_round_trips_odd_sizes() {
    for (w, h) in [(1, 1), (1, 7), (9, 1), (17, 33), (5, 16), (4, 17)] {
        let img = ramp(w, h);
        for c in [
            ExrCompression::None,
            ExrCompression::Zips,
            ExrCompression::Zip,
        ] {
            for half in [true, false] {
                for zip_level in [1, 6, 9] {
                    let opts = ExrOptions {
                        half,
                        compression: c,
                        zip_level,
                    };
                    let mut buf = Cursor::new(Vec::new());
                    encode_exr(&img, &mut buf, &opts, &[("k".into(), "v".into())]).unwrap();
                    let bytes = buf.into_inner();
                    let (rw, rh, px) = read_back(&bytes);
                    assert_eq!((rw, rh), (w, h));
                    for (i, p) in px.iter().enumerate() {
                        for (k, &got) in p.iter().enumerate() {
                            let v = img.data[3 * i + k];
                            let want = if half { f16::from_f32(v).to_f32() } else { v };
                            assert_eq!(got, want, "{c} half={half} {w}x{h} at {i}/{k}");
                        }
                    }
                    let lpb = if c == ExrCompression::Zip { 16 } else { 1 };
                    let ch = chunks(&bytes);
                    assert_eq!(ch.len(), h.div_ceil(lpb));
                    for (b, (y, _)) in ch.iter().enumerate() {
                        assert_eq!(*y as usize, b * lpb);
                    }
                    let meta =
                        exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes), true).unwrap();
                    assert_eq!(meta.headers[0].compression, c.to_exr());
                }
            }
        }
    }
}

#[test]
fn incompressible_blocks_are_stored_raw() {
    // a 1x1 block (6 or 12 bytes) cannot shrink under zlib's 6-byte framing + deflate
    for half in [true, false] {
        let mut img = RgbImage::new(1, 1);
        img.data.copy_from_slice(&[0.5, -2.0, 7.25]);
        let opts = ExrOptions {
            half,
            ..ExrOptions::default()
        };
        let mut buf = Cursor::new(Vec::new());
        encode_exr(&img, &mut buf, &opts, &[]).unwrap();
        let bytes = buf.into_inner();
        assert_eq!(chunks(&bytes), vec![(0, if half { 6 } else { 12 })]);
        assert_eq!(read_back(&bytes).2, vec![[0.5, -2.0, 7.25]]);
    }
    // a compressible image is compressed
    let img = RgbImage::new(64, 16);
    let mut buf = Cursor::new(Vec::new());
    encode_exr(&img, &mut buf, &ExrOptions::default(), &[]).unwrap();
    assert!(chunks(buf.get_ref())[0].1 < 64 * 16 * 6 / 10);
}

#[test]
fn zip_levels_trade_size_and_are_checked() {
    // a smooth image with texture: higher levels find more matches
    let mut img = RgbImage::new(64, 48);
    for (i, v) in img.data.iter_mut().enumerate() {
        *v = (i / 3 % 64 + i / 192) as f32 * 0.01 + ((i * 7) % 5) as f32 * 0.001;
    }
    let size = |zip_level| {
        let mut buf = Cursor::new(Vec::new());
        let opts = ExrOptions {
            zip_level,
            ..ExrOptions::default()
        };
        encode_exr(&img, &mut buf, &opts, &[]).map(|_| buf.into_inner().len())
    };
    let (s1, s9) = (size(1).unwrap(), size(9).unwrap());
    assert!(s9 < s1, "level 9: {s9} bytes, level 1: {s1}");
    assert!(size(0).is_err());
    assert!(size(10).is_err());
}

#[test]
fn reserved_and_duplicate_attributes_are_rejected() {
    let img = RgbImage::new(2, 2);
    for c in [ExrCompression::Zip, ExrCompression::Piz] {
        let opts = ExrOptions {
            compression: c,
            ..ExrOptions::default()
        };
        for bad in [
            vec![("software".to_string(), "x".to_string())],
            vec![("a".into(), "1".into()), ("a".into(), "2".into())],
            vec![("".into(), "1".into())],
        ] {
            let r = encode_exr(&img, Cursor::new(Vec::new()), &opts, &bad);
            assert!(matches!(r, Err(Error::InvalidParam(_))), "{c} {bad:?}");
        }
    }
}

#[test]
fn own_encoder_is_deterministic_across_thread_counts() {
    let img = ramp(97, 83);
    for c in [
        ExrCompression::None,
        ExrCompression::Zips,
        ExrCompression::Zip,
    ] {
        let opts = ExrOptions {
            compression: c,
            ..ExrOptions::default()
        };
        let enc = || {
            let mut buf = Cursor::new(Vec::new());
            encode_exr(
                &img,
                &mut buf,
                &opts,
                &[("z".into(), "1".into()), ("a".into(), "2".into())],
            )
            .unwrap();
            buf.into_inner()
        };
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        let one = pool(1).install(enc);
        let two = pool(2).install(enc);
        assert_eq!(one, two, "{c}");
        assert_eq!(one, enc(), "{c}");
    }
}

#[test]
fn compression_names_parse() {
    for c in ExrCompression::ALL {
        assert_eq!(c.name().parse::<ExrCompression>().unwrap(), c);
    }
    assert!("dwaa".parse::<ExrCompression>().is_err());
}
