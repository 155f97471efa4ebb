//! Writer round trips: every fixture and every real DNG in ../shared/data/dng, in every writer
//! mode: read -> write -> read gives identical pixels and metadata, a second write is a fixed
//! point, and independent tools (rawpy/LibRaw, the Adobe DNG SDK via dngpy, OpenImageIO,
//! tifffile: tests/validators/dng_check.py; exiftool -validate) accept the output.
//! Also the `convert` command: atomic, refuses existing outputs and inputs.

use crate::common;

use day2night::dng::read::{read_dng, read_dng_bytes};
use day2night::dng::write::{encode_dng, is_dropped, Compression, RawIfd, WriteOptions};
use day2night::raw::meta::RawMeta;
use day2night::raw::RawImage;
use day2night::tiff::value::Entry;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const MODES: [(Compression, RawIfd, &str); 4] = [
    (Compression::None, RawIfd::Main, "strips_main"),
    (Compression::Ljpeg, RawIfd::Main, "ljpeg_main"),
    (Compression::None, RawIfd::Sub, "strips_sub"),
    (Compression::Ljpeg, RawIfd::Sub, "ljpeg_sub"),
];

fn inputs() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(common::fixtures())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "dng"))
        .collect();
    // The real files too, unless they were absent at build time (build.rs; the tests
    // below then say so in their ignore reason).
    if !cfg!(d2n_missing = "shared-data") {
        let d = common::shared_data();
        for e in std::fs::read_dir(d.join("dng")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "dng") {
                v.push(p);
            }
        }
    }
    v.sort();
    assert!(v.len() >= 12, "fixtures missing: {v:?}");
    v
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12)
}

fn close_vec(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| close(*x, *y))
}

fn opt_close(a: &Option<Vec<f64>>, b: &Option<Vec<f64>>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => close_vec(a, b),
        _ => false,
    }
}

/// Tags this writer adds on its own (so they may appear in the output's extras).
const WRITER_ADDED: &[u16] = &[282, 283, 296, 305, 50781, 36864, 34864, 34867];

fn extras(m: &RawMeta) -> BTreeMap<u16, Entry> {
    m.ifd0_extra
        .iter()
        .chain(&m.raw_extra)
        .chain(&m.exif_extra)
        .map(|e| (e.tag, e.clone()))
        .collect()
}

/// Same meaning: every typed field equal (floats to 1e-9 relative, they travel as
/// rationals), every carried extra entry preserved, nothing new but the writer's own tags.
fn assert_same_meta(a: &RawMeta, b: &RawMeta, what: &str) {
    assert_eq!(a.make, b.make, "{what}: make");
    assert_eq!(a.model, b.model, "{what}: model");
    assert_eq!(a.unique_camera_model, b.unique_camera_model, "{what}");
    assert_eq!(a.bits_per_sample, b.bits_per_sample, "{what}: bits");
    assert_eq!(a.active_area, b.active_area, "{what}: active area");
    assert_eq!(a.default_crop_origin, b.default_crop_origin, "{what}");
    assert_eq!(a.default_crop_size, b.default_crop_size, "{what}");
    assert_eq!(a.cfa, b.cfa, "{what}: cfa");
    assert_eq!(a.linearization_table, b.linearization_table, "{what}");
    let (la, lb) = (&a.levels, &b.levels);
    assert_eq!(la.black_repeat, lb.black_repeat, "{what}");
    assert!(close_vec(&la.black, &lb.black), "{what}: black");
    assert!(
        close_vec(&la.black_delta_h, &lb.black_delta_h),
        "{what}: dh"
    );
    assert!(
        close_vec(&la.black_delta_v, &lb.black_delta_v),
        "{what}: dv"
    );
    assert!(close(la.white, lb.white), "{what}: white");
    assert!(
        opt_close(
            &a.as_shot_neutral.map(|v| v.to_vec()),
            &b.as_shot_neutral.map(|v| v.to_vec())
        ),
        "{what}: neutral {:?} {:?}",
        a.as_shot_neutral,
        b.as_shot_neutral
    );
    let (ca, cb) = (&a.color, &b.color);
    assert!(
        opt_close(&ca.color_matrix1, &cb.color_matrix1),
        "{what}: cm1"
    );
    assert!(
        opt_close(&ca.color_matrix2, &cb.color_matrix2),
        "{what}: cm2"
    );
    assert!(opt_close(&ca.camera_calibration1, &cb.camera_calibration1));
    assert!(opt_close(&ca.camera_calibration2, &cb.camera_calibration2));
    assert!(opt_close(&ca.forward_matrix1, &cb.forward_matrix1));
    assert!(opt_close(&ca.forward_matrix2, &cb.forward_matrix2));
    assert!(opt_close(&ca.analog_balance, &cb.analog_balance), "{what}");
    assert!(opt_close(
        &ca.baseline_exposure.map(|v| vec![v]),
        &cb.baseline_exposure.map(|v| vec![v])
    ));
    assert_eq!(ca.calibration_illuminant1, cb.calibration_illuminant1);
    assert_eq!(ca.calibration_illuminant2, cb.calibration_illuminant2);
    assert_eq!(a.noise_profile, b.noise_profile, "{what}: noise profile");
    assert_eq!(a.orientation, b.orientation, "{what}");
    assert_eq!(a.exif.iso, b.exif.iso, "{what}: iso");
    assert!(opt_close(
        &a.exif.exposure_time.map(|v| vec![v]),
        &b.exif.exposure_time.map(|v| vec![v])
    ));
    assert!(opt_close(
        &a.exif.f_number.map(|v| vec![v]),
        &b.exif.f_number.map(|v| vec![v])
    ));
    assert_eq!(a.exif.date_time_original, b.exif.date_time_original);
    assert_eq!(a.opcode_lists, b.opcode_lists, "{what}: opcodes");
    let (ea, eb) = (extras(a), extras(b));
    for (tag, e) in &ea {
        if WRITER_ADDED.contains(tag) {
            continue; // regenerated by the writer (checked below)
        } else if is_dropped(*tag) {
            assert!(!eb.contains_key(tag), "{what}: dropped tag {tag} written");
        } else {
            assert_eq!(eb.get(tag), Some(e), "{what}: carried tag {tag} changed");
        }
    }
    assert_eq!(
        eb.get(&305).map(|e| e.value.as_string()),
        Some(Some(day2night::software_name())),
        "{what}: Software"
    );
    for tag in eb.keys() {
        assert!(
            ea.contains_key(tag) || WRITER_ADDED.contains(tag),
            "{what}: unexpected new tag {tag}"
        );
    }
}

/// Pixels as LibRaw reports them: LinearizationTable applied.
fn libraw_view(img: &RawImage) -> Vec<u8> {
    let lut = img.meta.linearization_table.as_deref();
    img.data
        .iter()
        .flat_map(|&s| {
            let v = match lut {
                Some(t) => t[(s as usize).min(t.len() - 1)],
                None => s,
            };
            v.to_le_bytes()
        })
        .collect()
}

/// `exiftool -validate` warnings of several files in one exiftool run (perl start-up is
/// the slow part), normalised so that the same problem in IFD0 or a SubIFD compares equal.
fn exiftool_warnings(exiftool: &Path, files: &[PathBuf]) -> Vec<Vec<String>> {
    let out = std::process::Command::new(exiftool)
        .args(["-validate", "-warning", "-a", "-s3"])
        .args(files)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let mut per_file: Vec<Vec<String>> = vec![];
    for line in text.lines() {
        if line.starts_with("======== ") {
            per_file.push(vec![]);
        } else if let Some(cur) = per_file.last_mut() {
            if line.starts_with('[') {
                cur.push(line.replace("SubIFD ", "IFD ").replace("IFD0 ", "IFD "));
            }
        } else if files.len() == 1 {
            // A single file gets no "========" header.
            per_file.push(vec![]);
            if line.starts_with('[') {
                per_file[0].push(line.replace("SubIFD ", "IFD ").replace("IFD0 ", "IFD "));
            }
        }
    }
    assert_eq!(per_file.len(), files.len(), "exiftool output: {text}");
    per_file
}

fn finish_validator(src: &Path, child: std::process::Child) -> String {
    let o = child.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "dng_check.py failed for {}:\n{text}\n{}",
        src.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    text
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn round_trip_every_input_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let py = common::python();
    let mut report = vec![];
    let mut pending = vec![];
    for src in inputs() {
        let stem = src.file_stem().unwrap().to_string_lossy().to_string();
        let r1 = read_dng(&src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
        let mut outs = vec![];
        for (compression, raw_ifd, name) in MODES {
            let what = format!("{stem} {name}");
            let opts = WriteOptions {
                compression,
                raw_ifd,
                ..Default::default()
            };
            let b1 = encode_dng(&r1, &opts).unwrap_or_else(|e| panic!("{what}: {e}"));
            let r2 = read_dng_bytes(&b1).unwrap_or_else(|e| panic!("{what}: re-read: {e}"));
            assert_eq!((r2.width, r2.height), (r1.width, r1.height), "{what}");
            assert!(r2.data == r1.data, "{what}: pixels differ after round trip");
            assert_same_meta(&r1.meta, &r2.meta, &what);
            // Second generation: a fixed point, byte for byte.
            let b2 = encode_dng(&r2, &opts).unwrap();
            let r3 = read_dng_bytes(&b2).unwrap();
            assert!(
                r3.data == r2.data,
                "{what}: second round trip changed pixels"
            );
            // RawDataUniqueID hashes the metadata, whose floats may move by an ulp in the
            // first generation (rationals); from the second generation on all is fixed.
            let no_id = |m: &RawMeta| {
                let mut m = m.clone();
                m.ifd0_extra.retain(|e| e.tag != 50781);
                m
            };
            assert!(
                no_id(&r3.meta) == no_id(&r2.meta),
                "{what}: second round trip changed metadata:\n{:?}\n{:?}",
                r2.meta,
                r3.meta
            );
            assert_eq!(
                encode_dng(&r3, &opts).unwrap(),
                b2,
                "{what}: not a fixed point"
            );
            let out = dir.path().join(format!("{stem}__{name}.dng"));
            std::fs::write(&out, &b1).unwrap();
            outs.push(out);
        }
        {
            let pix = dir.path().join(format!("{stem}.u16"));
            std::fs::write(&pix, libraw_view(&r1)).unwrap();
            let mut args: Vec<std::ffi::OsString> = vec![src.clone().into()];
            args.extend(outs.iter().map(|o| o.clone().into_os_string()));
            for a in [
                "--pixels".into(),
                pix.into_os_string(),
                "--width".into(),
                r1.width.to_string().into(),
                "--height".into(),
                r1.height.to_string().into(),
            ] {
                args.push(a);
            }
            // Validators run in the background (a few at a time) while the next input is
            // written; results are checked below.
            if pending.len() >= 3 {
                let (src, child): (PathBuf, std::process::Child) = pending.remove(0);
                report.push(finish_validator(&src, child));
            }
            let child = std::process::Command::new(&py)
                .arg(common::root().join("tests/validators/dng_check.py"))
                .args(&args)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("failed to start validator python");
            pending.push((src.clone(), child));
        }
    }
    for (src, child) in pending {
        report.push(finish_validator(&src, child));
    }
    println!("{}", report.join(""));
}

/// `exiftool -validate` finds nothing in the written files that it does not find in the
/// source, in every mode.
#[test]
#[cfg_attr(
    d2n_missing = "exiftool",
    ignore = "needs exiftool (D2N_ALLOW_MISSING)"
)]
fn exiftool_validate_accepts_every_written_mode() {
    let dir = tempfile::tempdir().unwrap();
    let et = common::exiftool();
    for src in inputs() {
        let stem = src.file_stem().unwrap().to_string_lossy().to_string();
        let r1 = read_dng(&src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
        let mut outs = vec![];
        for (compression, raw_ifd, name) in MODES {
            let opts = WriteOptions {
                compression,
                raw_ifd,
                ..Default::default()
            };
            let out = dir.path().join(format!("{stem}__{name}.dng"));
            std::fs::write(&out, encode_dng(&r1, &opts).unwrap()).unwrap();
            outs.push(out);
        }
        {
            let mut files = vec![src.clone()];
            files.extend(outs.iter().cloned());
            let warns = exiftool_warnings(&et, &files);
            // exiftool expects ceil(w*h*bits/8) bytes; TIFF pads every packed row to a
            // byte (libtiff, the DNG SDK and LibRaw agree), so odd-width packed rows are
            // "oversized" to exiftool. Only that exact case is tolerated, only for strips.
            let row_padded = !(r1.width * r1.meta.bits_per_sample as usize).is_multiple_of(8);
            for ((out, w_out), (_, _, name)) in outs.iter().zip(&warns[1..]).zip(MODES) {
                for w in w_out {
                    if row_padded
                        && !name.starts_with("ljpeg")
                        && w.starts_with("[minor] Oversized IFD StripByteCounts")
                    {
                        continue;
                    }
                    assert!(
                        warns[0].contains(w),
                        "{}: exiftool -validate warning the source lacks: {w}",
                        out.display()
                    );
                }
            }
        }
    }
}

#[test]
fn writer_output_is_deterministic_across_thread_counts() {
    let src = common::fixtures().join("day.dng");
    let img = read_dng(&src).unwrap();
    let opts = WriteOptions {
        compression: Compression::Ljpeg,
        raw_ifd: RawIfd::Sub,
        ..Default::default()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| encode_dng(&img, &opts).unwrap());
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap()
        .install(|| encode_dng(&img, &opts).unwrap());
    assert_eq!(one, many);
}

#[test]
fn convert_cli_is_atomic_and_refuses_overwrites() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("in.dng");
    std::fs::copy(common::fixtures().join("day.dng"), &src).unwrap();
    let src_bytes = std::fs::read(&src).unwrap();
    let out = dir.path().join("out.dng");
    let run = |args: &[&std::ffi::OsStr]| common::bin().arg("convert").args(args).output().unwrap();

    let o = run(&[
        src.as_os_str(),
        out.as_os_str(),
        "--compression".as_ref(),
        "ljpeg".as_ref(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stdout.is_empty(), "convert printed on stdout");
    let first = std::fs::read(&out).unwrap();
    let back = read_dng(&out).unwrap();
    assert_eq!(back.data, read_dng(&src).unwrap().data);

    // Existing output: refused, untouched.
    let o = run(&[src.as_os_str(), out.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("day2night: ") && err.contains("--overwrite"),
        "{err}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), first);

    // --overwrite replaces it; same options give identical bytes.
    let o = run(&[
        src.as_os_str(),
        out.as_os_str(),
        "--overwrite".as_ref(),
        "--compression".as_ref(),
        "ljpeg".as_ref(),
    ]);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), first);

    // The input is never overwritten, even with --overwrite (also via another path).
    let alias = dir.path().join(".").join("in.dng");
    let o = run(&[src.as_os_str(), alias.as_os_str(), "--overwrite".as_ref()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("input"));
    assert_eq!(std::fs::read(&src).unwrap(), src_bytes);

    // Bad usage -> 2; unreadable input -> 1 naming the file; no temp files left behind.
    let o = run(&[
        src.as_os_str(),
        "x.dng".as_ref(),
        "--compression".as_ref(),
        "zip".as_ref(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let junk = dir.path().join("junk.dng");
    std::fs::write(&junk, b"II*\0garbage").unwrap();
    let o2 = dir.path().join("o2.dng");
    let o = run(&[junk.as_os_str(), o2.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("junk.dng"));
    assert!(!o2.exists());
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");

    // --raw-ifd sub writes a thumbnail IFD0 and the raw in a SubIFD.
    let sub = dir.path().join("sub.dng");
    let o = run(&[
        src.as_os_str(),
        sub.as_os_str(),
        "--raw-ifd".as_ref(),
        "sub".as_ref(),
    ]);
    assert!(o.status.success());
    let info = day2night::dng::read::inspect(&sub).unwrap();
    let json = serde_json::to_string(&info).unwrap();
    assert!(json.contains("sub_ifd"), "{json}");
    assert_eq!(read_dng(&sub).unwrap().data, back.data);
}
