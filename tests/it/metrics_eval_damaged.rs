//! `eval` of damaged EXRs (docs/isp.md, "Metrics"): the error names the file whose data is
//! broken (never the other one), says what is wrong in plain words (which chunk, rows and
//! compression; no internal name of the decoder such as "DWAB(None)" or "line order
//! attribute value"), and a decoder panic is an error, not a backtrace. Checked on broken
//! chunks of every compression day2night writes, truncations, header byte flips, and the
//! shared fuzz reproducers.
use crate::common;
use std::path::{Path, PathBuf};

/// Shapes of the decoder's internals and of panics that must not reach the user.
fn internal(s: &str) -> Option<&'static str> {
    [
        "DWAB(",
        "DWAA(",
        "ZIP16",
        "ZIP1 ",
        "Vec2",
        "attribute value",
        "invalid:",
        "not supported:",
        "`",
        "None)",
        "panicked",
        "RUST_BACKTRACE",
        "reference to missing bytes",
    ]
    .into_iter()
    .find(|w| s.contains(w))
}

/// `eval a b`: (exit code, stderr).
fn eval(a: &Path, b: &Path) -> (Option<i32>, String) {
    let r = common::bin().arg("eval").arg(a).arg(b).output().unwrap();
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

/// The failure of `eval` with `bad` on either side names `bad` (first thing on the line)
/// and not `good`, in plain words; returns the message.
fn refused(good: &Path, bad: &Path) -> String {
    let mut last = String::new();
    for (a, b) in [(good, bad), (bad, good)] {
        let (code, err) = eval(a, b);
        assert_eq!(code, Some(1), "{} vs {}: {err}", a.display(), b.display());
        let line = err.lines().last().unwrap_or_default().to_string();
        if line.contains(" differs from ") {
            // A flip in the data window: a readable file of another size; both are named.
            assert!(line.contains(&*bad.display().to_string()), "{err}");
            last = "(another size)".into();
            continue;
        }
        assert!(
            line.starts_with(&format!("day2night: {}: ", bad.display())),
            "the broken file is not named first: {err}"
        );
        assert!(!line.contains(&*good.display().to_string()), "{err}");
        assert!(internal(&err).is_none(), "{:?} in {err}", internal(&err));
        last = line;
    }
    last
}

fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let r = common::cli("render", &common::fixtures().join("day.dng"), &out, extra);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    out
}

#[test]
fn a_broken_chunk_is_named_with_its_file_rows_and_compression() {
    let t = tempfile::tempdir().unwrap();
    let good = render(t.path(), "good.exr", &[]);
    for (comp, extra) in [
        ("ZIP", &["--exr-compression", "zip"][..]),
        ("ZIPS", &["--exr-compression", "zips"][..]),
        ("PIZ", &["--exr-compression", "piz"][..]),
        ("B44", &["--exr-compression", "b44"][..]),
        ("PXR24", &["--exr-compression", "pxr24"][..]),
        ("RLE", &["--exr-compression", "rle"][..]),
    ] {
        let src = render(t.path(), &format!("{comp}.exr"), extra);
        let bytes = std::fs::read(&src).unwrap();
        let mut broken = bytes.clone();
        let mid = bytes.len() / 2;
        for b in &mut broken[mid..mid + 64] {
            *b ^= 0x5a;
        }
        let bad = t.path().join(format!("{comp}_bad.exr"));
        std::fs::write(&bad, &broken).unwrap();
        let (code, _) = eval(&good, &bad);
        if code == Some(0) {
            // Some formats have no check: flipped bytes are other pixels. Never a panic.
            continue;
        }
        let msg = refused(&good, &bad);
        assert!(
            msg.contains("chunk") && msg.contains(&format!("{comp} compression")),
            "{comp}: {msg}"
        );
    }
    // The ZIP case in full: which chunk, its rows, what is wrong.
    let bytes = std::fs::read(&good).unwrap();
    let mut broken = bytes.clone();
    let mid = bytes.len() / 2;
    for b in &mut broken[mid..mid + 200] {
        *b ^= 0x5a;
    }
    let bad = t.path().join("zip_bad.exr");
    std::fs::write(&bad, &broken).unwrap();
    let msg = refused(&good, &bad);
    assert!(
        msg.contains("malformed input: EXR: chunk ")
            && msg.contains("rows ")
            && msg.contains("ZIP compression) is damaged: its zlib stream does not decode"),
        "{msg}"
    );
}

#[test]
fn truncations_and_header_flips_give_plain_errors_naming_the_file() {
    let t = tempfile::tempdir().unwrap();
    let good = render(t.path(), "good.exr", &[]);
    let bytes = std::fs::read(&good).unwrap();
    let bad = t.path().join("bad.exr");
    let mut seen = std::collections::BTreeSet::new();
    for cut in [5, 9, 40, 120, 300, 800, bytes.len() / 3, bytes.len() - 1] {
        std::fs::write(&bad, &bytes[..cut]).unwrap();
        seen.insert(refused(&good, &bad));
    }
    // Byte flips over the header and the offset table: refused in plain words, or (a flip
    // in a value the reader does not use) read.
    let header_end = bytes.len().min(1200);
    for (k, at) in (4..header_end).step_by(7).enumerate() {
        let mut m = bytes.clone();
        m[at] ^= [0xff, 0x01, 0x80, 0x20][k % 4];
        std::fs::write(&bad, &m).unwrap();
        let (code, err) = eval(&good, &bad);
        assert!(internal(&err).is_none(), "flip at {at}: {err}");
        if code != Some(0) {
            seen.insert(refused(&good, &bad));
        }
    }
    assert!(seen.len() >= 5, "{seen:#?}");
    eprintln!(
        "{} distinct messages:\n{}",
        seen.len(),
        seen.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
fn the_shared_fuzz_reproducers_are_named_in_plain_words() {
    let t = tempfile::tempdir().unwrap();
    let good = render(t.path(), "good.exr", &[]);
    for name in [
        "exr-bad/openexr_damaged_scanlines_fuzzer_5087823085174784.bin",
        "exr-bad/openexr_damaged_tiles_fuzzer_5131789849591808.bin",
    ] {
        let bad = common::shared_file(name);
        let msg = refused(&good, &bad);
        assert!(
            msg.contains("EXR: the file ends early (truncated?)"),
            "{msg}"
        );
    }
}
