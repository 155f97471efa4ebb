//! `--compat release` means the release's noise for every input (issue 42; docs/noise.md,
//! "Where the model comes from", case 3): on a DNG with a NoiseProfile and an ISO
//! (`fixtures/day.dng`: 2e-5, 4e-7 at ISO 100) the noisy raw is the one the release's
//! table gives, the same as for that file without its NoiseProfile (the input the release
//! path always had), and the sidecar says where the noise came from.

use crate::common;
use crate::synth_cli::{ok, synth};
use day2night::dng::read_dng;
use day2night::dng::write::write_dng;
use day2night::noise::NoiseSource;
use day2night::synth::dictionaries::embedded;
use day2night::synth::sidecar::Sidecar;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `synth IN -o OUT --compat release --seed 5 --iso 800 --target none`.
fn release_run(input: &Path, out: &Path) {
    ok(&synth(&[
        s(input),
        "-o",
        s(out),
        "--compat",
        "release",
        "--seed",
        "5",
        "--iso",
        "800",
        "--target",
        "none",
    ]));
}

#[test]
fn compat_release_noise_is_the_release_table_whatever_the_input_says() {
    let t = tempfile::tempdir().unwrap();
    let day = read_dng(&common::fixtures().join("day.dng")).unwrap();
    assert!(day.meta.noise_profile.is_some() && day.meta.exif.iso == Some(100));
    // The same frame written twice by one writer, with and without its NoiseProfile (same
    // file name: the random streams are keyed by it).
    let mut bare = day.clone();
    bare.meta.noise_profile = None;
    let mut ins = vec![];
    for (dir, img) in [("with", &day), ("without", &bare)] {
        let p = t.path().join(dir).join("day.dng");
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        write_dng(img, &p, &Default::default(), &Default::default()).unwrap();
        let out = t.path().join(format!("{dir}-out"));
        release_run(&p, &out);
        ins.push(out);
    }
    let raw = |dir: &Path, name: &str| read_dng(&dir.join(name)).unwrap();
    let (a, b) = (
        raw(&ins[0], "day_iso800.dng"),
        raw(&ins[1], "day_iso800.dng"),
    );
    assert_eq!(
        raw(&ins[0], "day_clean.dng").data,
        raw(&ins[1], "day_clean.dng").data
    );
    let max = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap();
    assert!(max <= 1, "noisy raws {max} DN apart");
    // Both plans hold the release's table at ISO 800, and the sidecar says why.
    let table = embedded::noise_model().at(800).unwrap().params;
    for out in &ins {
        let sc = Sidecar::read(&out.join("day.json")).unwrap();
        assert_eq!(sc.plan.noise[0].params, table);
        let p = sc.calibration.provenance.unwrap().noise.unwrap();
        assert_eq!(p.source, NoiseSource::EmbeddedS20Fe);
        assert!(
            p.note.starts_with("--compat release: the release's table"),
            "{}",
            p.note
        );
    }
    let sc = Sidecar::read(&ins[0].join("day.json")).unwrap();
    let note = sc.calibration.provenance.unwrap().noise.unwrap().note;
    assert!(
        note.contains("not the input's NoiseProfile (at ISO 100)"),
        "{note}"
    );
    let said = sc.report.warnings.iter().any(|w| {
        w.message
            .contains("rather than the input's NoiseProfile (at ISO 100)")
    });
    assert!(said, "{:?}", sc.report.warnings);
    // The noise has the table's size, not the NoiseProfile's (2e-5 at ISO 100 is S 1.6e-4
    // at ISO 800, about 7 times less than the table's): the variance of noisy - clean
    // over the variance the table predicts, on unclipped samples.
    let clean = raw(&ins[0], "day_clean.dng");
    let (black, white) = (clean.meta.levels.black[0], clean.meta.levels.white);
    let range = white - black;
    let area = clean.active_area();
    let (mut got, mut want) = (0.0, 0.0);
    for r in 0..area.height() {
        for c in 0..area.width() {
            let (y, x0) = (area.top as usize + r, area.left as usize + c);
            let (n, v) = (a.get(y, x0), clean.get(y, x0));
            let x = (f64::from(v) - black) / range;
            if !(0.05..0.9).contains(&x) {
                continue;
            }
            let [sp, op] = table.positions[2 * (r % 2) + c % 2];
            got += ((f64::from(n) - f64::from(v)) / range).powi(2);
            want += sp * x + op;
        }
    }
    let ratio = got / want;
    assert!(
        (0.8..1.25).contains(&ratio),
        "noise variance / table's: {ratio}"
    );
}
