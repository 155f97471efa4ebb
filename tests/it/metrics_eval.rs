//! `day2night eval`: PSNR, SSIM and Delta E 2000 against scikit-image and colour-science on
//! whole images; EXR/PNG/TIFF inputs including the OpenEXR reference images; clean refusals.
use crate::common;

use std::path::{Path, PathBuf};

fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let day = common::fixtures().join("day.dng");
    let out = dir.join(name);
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "render".as_ref(),
        day.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let o = common::bin().args(&args).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

fn eval_json(a: &Path, b: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "eval".as_ref(),
        a.as_os_str(),
        b.as_os_str(),
        "--json".as_ref(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let o = common::bin().args(&args).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn reference(a: &Path, b: &Path) -> serde_json::Value {
    let py = common::python();
    let o = common::run_validator(
        &py,
        "isp_metrics.py",
        &[a.as_os_str(), b.as_os_str(), "1".as_ref()],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn f(v: &serde_json::Value, k: &str) -> f64 {
    v[k].as_f64()
        .unwrap_or_else(|| panic!("{k} missing in {v}"))
}

#[test]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn metrics_match_scikit_image_and_colour_science() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pairs = [
        // 8-bit PNGs, two demosaics
        (
            render(d, "mhc.png", &[]),
            render(d, "bil.png", &["--demosaic", "bilinear"]),
        ),
        // 16-bit TIFFs with different tones
        (
            render(d, "a.tif", &["--demosaic", "menon"]),
            render(d, "b.tif", &["--tone", "gamma22"]),
        ),
        // linear float EXRs
        (
            render(d, "a.exr", &["--float", "--demosaic", "menon"]),
            render(d, "b.exr", &["--float", "--neutral", "0.45,1,0.7"]),
        ),
    ];
    for (a, b) in &pairs {
        let ours = eval_json(a, b, &[]);
        let gauss = eval_json(a, b, &["--ssim-window", "gaussian"]);
        let r = reference(a, b);
        eprintln!("{}: ours {ours}\nreference {r}", a.display());
        assert!(
            (f(&ours, "psnr") - f(&r, "psnr")).abs() < 1e-4,
            "psnr {ours} {r}"
        );
        assert!(
            (f(&ours, "ssim") - f(&r, "ssim")).abs() < 0.002,
            "ssim {ours} {r}"
        );
        assert!(
            (f(&gauss, "ssim") - f(&r, "ssim_gaussian")).abs() < 0.002,
            "gaussian ssim {gauss} {r}"
        );
        let de = (f(&ours, "delta_e_2000") - f(&r, "delta_e_2000")).abs();
        assert!(
            de < 1e-3 * f(&r, "delta_e_2000").max(1.0),
            "delta E {ours} {r}"
        );
        assert!(f(&ours, "psnr") > 20.0 && f(&ours, "ssim") < 1.0);
    }
}

#[test]
fn text_output_and_identical_images() {
    let dir = tempfile::tempdir().unwrap();
    let a = render(dir.path(), "a.png", &[]);
    let o = common::bin()
        .args(["eval".as_ref(), a.as_os_str(), a.as_os_str()])
        .output()
        .unwrap();
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(
        s.contains("psnr: inf")
            && s.contains("ssim: 1.000000")
            && s.contains("delta_e_2000: 0.0000"),
        "{s}"
    );
    let j = eval_json(&a, &a, &[]);
    assert!(j["psnr"].is_null() && f(&j, "ssim") == 1.0 && f(&j, "delta_e_2000") == 0.0);
}

#[test]
fn size_mismatch_and_bad_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let a = render(dir.path(), "a.png", &[]);
    let b = render(dir.path(), "b.png", &["--no-crop"]);
    let o = common::bin()
        .args(["eval".as_ref(), a.as_os_str(), b.as_os_str()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.starts_with("day2night: ") && e.contains("496x496") && e.contains("512x512"),
        "{e}"
    );
    assert!(o.stdout.is_empty());
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let o = common::bin()
        .args(["eval".as_ref(), junk.as_os_str(), a.as_os_str()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("junk.png"));
    let o = common::bin()
        .args([
            "eval".as_ref(),
            a.as_os_str(),
            a.as_os_str(),
            "--ssim-window".as_ref(),
            "box".as_ref(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
#[cfg_attr(
    d2n_missing = "shared-data",
    ignore = "needs the real-camera files (absent at build time)"
)]
#[cfg_attr(
    d2n_missing = "validators",
    ignore = "needs the validators (D2N_ALLOW_MISSING)"
)]
fn openexr_reference_images_are_read_and_damaged_ones_refused() {
    let d = common::shared_data();
    let mut n = 0;
    for e in std::fs::read_dir(d.join("exr")).unwrap() {
        let p = e.unwrap().path();
        let img = day2night::encode::read::read_image(&p).unwrap_or_else(|e| panic!("{e}"));
        assert!(img.linear && img.image.width > 0, "{}", p.display());
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.contains("naninf") {
            assert!(img.non_finite > 0, "{name}: NaN/Inf not seen");
        }
        if name.contains("stripes_rgba") {
            assert_eq!((img.image.width, img.image.height), (100, 50));
        }
        // eval of a file against itself works (NaN/Inf replaced by 0 with --nonfinite zero)
        let j = eval_json(&p, &p, &["--nonfinite", "zero"]);
        assert_eq!(f(&j, "ssim"), 1.0, "{name}");
        n += 1;
    }
    assert!(n >= 6);
    // Cross-check pixel values with OpenImageIO-free numpy reading where possible
    {
        let py = common::python();
        let script = "import sys,OpenEXR,numpy as np\nwith OpenEXR.File(sys.argv[1]) as f:\n ch=f.channels()\n px=ch['RGB'].pixels if 'RGB' in ch else ch[list(ch)[0]].pixels\n print(float(np.nansum(np.where(np.isfinite(px),px,0).astype(np.float64))))";
        let p = d.join("exr/openexr_cannon_rgb_half_b44_photo.exr");
        let o = std::process::Command::new(py)
            .arg("-c")
            .arg(script)
            .arg(&p)
            .output()
            .unwrap();
        let want: f64 = String::from_utf8_lossy(&o.stdout).trim().parse().unwrap();
        let img = day2night::encode::read::read_image(&p).unwrap();
        let got: f64 = img.image.data.iter().map(|&v| v as f64).sum();
        assert!(
            (got - want).abs() <= 1e-6 * want.abs().max(1.0),
            "{got} vs {want}"
        );
    }
    for e in std::fs::read_dir(d.join("exr-bad")).unwrap() {
        let p = e.unwrap().path();
        let a = common::fixtures().join("day.dng");
        let o = common::bin()
            .args(["eval".as_ref(), p.as_os_str(), a.as_os_str()])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", p.display());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.starts_with("day2night: ") && err.contains("EXR"),
            "{err}"
        );
    }
}
