//! `render --isp release`: the authors' release ISP reproduced. Against the release's own
//! renders of the fixtures (shared data, `release-isp/`: same size, at least 99.9 % of the
//! samples within 1 code), and on the fixtures alone: deterministic bytes, the release's
//! image window, and contradictory flags refused with the flag named.

use crate::common::{self, cli};
use std::path::{Path, PathBuf};

/// Decode an 8-bit RGB PNG: (width, height, bytes).
fn rgb8(p: &Path) -> (u32, u32, Vec<u8>) {
    let img = image::open(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .to_rgb8();
    (img.width(), img.height(), img.into_raw())
}

fn render_release(input: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["--isp", "release"];
    args.extend_from_slice(extra);
    cli("render", input, out, &args)
}

/// The DNG a reference was rendered from: the fixture of that name, else the DNG beside it.
fn source_of(refs: &Path, name: &str) -> PathBuf {
    let fixture = common::fixtures().join(format!("{name}.dng"));
    if fixture.is_file() {
        fixture
    } else {
        refs.join(format!("{name}.dng"))
    }
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the release's reference renders (absent at build time)"
)]
fn matches_the_release_renders() {
    let refs = common::shared_data().join("release-isp");
    let mut names: Vec<String> = std::fs::read_dir(&refs)
        .unwrap_or_else(|e| panic!("{}: {e}", refs.display()))
        .filter_map(|e| {
            let n = e.ok()?.file_name().into_string().ok()?;
            n.strip_suffix("_release.png").map(str::to_string)
        })
        .collect();
    names.sort();
    assert!(!names.is_empty(), "no *_release.png in {}", refs.display());
    let dir = tempfile::tempdir().unwrap();
    let mut report = Vec::new();
    for name in &names {
        let src = source_of(&refs, name);
        assert!(src.is_file(), "{}: no source DNG", src.display());
        let out = dir.path().join(format!("{name}.png"));
        let o = render_release(&src, &out, &[]);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (w, h, ours) = rgb8(&out);
        let (rw, rh, theirs) = rgb8(&refs.join(format!("{name}_release.png")));
        assert_eq!((w, h), (rw, rh), "{name}: image size");
        let off: Vec<u8> = ours
            .iter()
            .zip(&theirs)
            .map(|(a, b)| a.abs_diff(*b))
            .collect();
        let within = off.iter().filter(|d| **d <= 1).count() as f64 / off.len() as f64;
        let max = off.iter().copied().max().unwrap_or(0);
        report.push(format!(
            "{name}: {:.4} % within 1 code, max {max}",
            100.0 * within
        ));
        assert!(
            within >= 0.999,
            "{name}: only {:.3} % within 1 code",
            100.0 * within
        );
    }
    eprintln!("{}", report.join("\n"));
}

#[test]
fn deterministic_with_the_release_window() {
    let day = common::fixtures().join("day.dng");
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    for out in [&a, &b] {
        let o = render_release(&day, out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    // day.dng: a 512x512 active area at (8, 16) of the stored 528x520; the release crops
    // it again by ActiveArea's rows 8..520 and columns 16..528, clamped: 496 x 504.
    let (w, h, _) = rgb8(&a);
    assert_eq!((w, h), (496, 504));
    // The flags that mean what the release does are accepted, and change nothing.
    let c = dir.path().join("c.png");
    let same = [
        "--demosaic",
        "menon",
        "--tone",
        "release",
        "--opcodes",
        "ignore",
    ];
    let o = render_release(&day, &c, &same);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&c).unwrap());
    // A neutral changes the render; a linear EXR is written.
    let n = dir.path().join("n.png");
    assert!(render_release(&day, &n, &["--neutral", "0.6,1,0.5"])
        .status
        .success());
    assert_ne!(rgb8(&a).2, rgb8(&n).2);
    let exr = dir.path().join("x.exr");
    assert!(render_release(&day, &exr, &[]).status.success());
    assert!(exr.is_file());
}

#[test]
fn contradictory_flags_are_refused() {
    let day = common::fixtures().join("day.dng");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    // `--opcodes` has no value that contradicts the release (apply is the default, ignore
    // its own): a value outside both is clap's refusal, exit 2, naming the option.
    let o = render_release(&day, &out, &["--opcodes", "warn"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "--opcodes warn: {err}");
    assert!(err.contains("--opcodes"), "--opcodes warn: {err}");
    assert!(!out.exists(), "--opcodes warn wrote an output");
    let cases: [(&[&str], &str); 5] = [
        (&["--demosaic", "bilinear"], "--demosaic"),
        (&["--tone", "gamma22"], "--tone"),
        (&["--no-crop"], "--no-crop"),
        (&["--camera-rgb"], "--camera-rgb"),
        (&["--bits", "16"], "--bits 16"),
    ];
    for (extra, flag) in cases {
        let o = render_release(&day, &out, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains(flag) && err.contains("--isp release"),
            "{extra:?}: {err}"
        );
        assert!(!out.exists(), "{extra:?} wrote an output");
    }
    let tif = dir.path().join("x.tif");
    let o = render_release(&day, &tif, &[]);
    assert!(o.status.code() == Some(2) && !tif.exists());
    let o = cli("render", &day, &out, &["--isp", "libraw"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("'libraw'") && err.contains("--isp") && err.contains("release"));
}

/// The release's fixed options are compared as typed, as Python's keywords are: an alias
/// or another case of the default (`--demosaic malvar`, `--opcodes APPLY`) names a choice
/// that is not the release's and is refused, exit 2, with the message naming it; the
/// default's and the release's own names pass.
#[test]
fn fixed_options_are_compared_as_typed() {
    let day = common::fixtures().join("day.dng");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let cases: [(&str, &str, &str); 5] = [
        ("--demosaic", "malvar", "menon"),
        ("--demosaic", "MENON", "menon"),
        ("--tone", "gamma", "release"),
        ("--opcodes", "APPLY", "ignore"),
        ("--opcodes", "Ignore", "ignore"),
    ];
    for (flag, value, own) in cases {
        let o = render_release(&day, &out, &[flag, value]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {err}");
        let want = format!("{flag} {value}: --isp release uses {flag} {own} (leave it out)");
        assert!(err.contains(&want), "{flag} {value}: {err}");
        assert!(!out.exists(), "{flag} {value} wrote an output");
    }
    for given in [
        ["--demosaic", "mhc", "--tone", "srgb", "--opcodes", "apply"],
        [
            "--demosaic",
            "menon",
            "--tone",
            "release",
            "--opcodes",
            "ignore",
        ],
    ] {
        let o = render_release(&day, &out, &[&given[..], &["--overwrite"]].concat());
        assert!(
            o.status.success(),
            "{given:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// Every file under `dir` whose name ends with `suffix`.
fn files_ending(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(files_ending(&p, suffix));
        } else if p.to_string_lossy().ends_with(suffix) {
            out.push(p);
        }
    }
    out
}

/// `real-pairs --isp release`: the target is `render --isp release` of the clean raw it
/// wrote (same neutral), byte for byte in its pixels; the default ISP's target differs.
#[test]
fn real_pairs_render_targets_with_the_release_isp() {
    use crate::real_pairs::{ok, real_pairs, simple_scene, synth};
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("synth");
    synth(&s, 2, &["--motion", "none"]);
    let scenes = d.path().join("scenes");
    simple_scene(&scenes.join("night/a"), &s);
    let (rel, own) = (d.path().join("rel"), d.path().join("own"));
    ok(&real_pairs(&scenes, &rel, &["--isp", "release"]));
    ok(&real_pairs(&scenes, &own, &[]));
    let targets = files_ending(&rel, ".png");
    assert_eq!(targets.len(), 1, "{targets:?}");
    let clean = files_ending(&rel, ".dng")
        .into_iter()
        .find(|p| !p.to_string_lossy().contains("iso"))
        .expect("the clean raw");
    let again = d.path().join("again.png");
    ok(&render_release(&clean, &again, &[]));
    assert_eq!(rgb8(&targets[0]), rgb8(&again));
    let theirs = files_ending(&own, ".png");
    assert_ne!(rgb8(&targets[0]), rgb8(&theirs[0]));
    let o = real_pairs(&scenes, &d.path().join("x"), &["--isp", "libraw"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--isp"));
}
