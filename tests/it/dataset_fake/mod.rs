//! A fake, fast, deterministic processor and helpers shared by the dataset tests.
#![allow(dead_code)]

use day2night::dataset::{
    self, Kind, Processor, RunOptions, Shard, Sink, SplitRule, Unit, UnitInfo,
};
use day2night::{Error, Result};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Fake synthesis: refuses inputs not starting with "DAY"; writes a clean raw, two noisy
/// raws and a sidecar whose bytes depend only on the input bytes, the seed and the options.
pub struct Fake {
    pub option: String,
    pub loads: AtomicUsize,
    pub units: AtomicUsize,
    /// Units given their input to use up ([`Processor::process_last`]; counted in `units`
    /// too).
    pub lasts: AtomicUsize,
}

impl Fake {
    pub fn new(option: &str) -> Fake {
        Fake {
            option: option.into(),
            loads: AtomicUsize::new(0),
            units: AtomicUsize::new(0),
            lasts: AtomicUsize::new(0),
        }
    }
}

impl Processor for Fake {
    type Loaded = Vec<u8>;
    fn fingerprint(&self) -> String {
        format!("fake option={}", self.option)
    }
    fn load(&self, _path: &Path, bytes: &[u8]) -> Result<Vec<u8>> {
        self.loads.fetch_add(1, Ordering::SeqCst);
        if !bytes.starts_with(b"DAY") {
            return Err(Error::malformed("not a fake day file"));
        }
        Ok(bytes.to_vec())
    }
    fn process_last(&self, input: Vec<u8>, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        self.lasts.fetch_add(1, Ordering::SeqCst);
        self.process(&input, unit, sink)
    }
    fn process(&self, input: &Vec<u8>, unit: &Unit, sink: &Sink) -> Result<UnitInfo> {
        self.units.fetch_add(1, Ordering::SeqCst);
        // Keyed like the real synthesis: (seed, relative path, variant), plus the content.
        let body = format!(
            "{}|{}|{}|{}|{}",
            dataset::sha256_hex(input),
            unit.seed,
            unit.rel,
            unit.variant,
            self.option
        );
        sink.write(Kind::CleanRaw, ".dng", |w| {
            for _ in 0..200 {
                w.write_all(body.as_bytes())?;
            }
            Ok(())
        })?;
        for iso in [1600, 3200] {
            sink.write(Kind::NoisyRaw, &format!("_iso{iso}.dng"), |w| {
                Ok(w.write_all(format!("{body}|{iso}").as_bytes())?)
            })?;
        }
        sink.write(Kind::Meta, ".json", |w| {
            let h = dataset::stable_u64(&[&body]);
            Ok(w.write_all(format!("{{\"seed\":{},\"h\":{h}}}", unit.seed).as_bytes())?)
        })?;
        Ok(UnitInfo {
            iso: vec![1600, 3200],
            night_neutral: Some([0.5, 1.0, 0.6]),
            stages: vec!["fake".into()],
        })
    }
}

pub fn make_day_dir(n: usize) -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    for i in 0..n {
        let sub = if i % 3 == 0 { "b" } else { "a/deep" };
        let p = d.path().join(sub).join(format!("img_{i:03}.dng"));
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, format!("DAY{i}").repeat(50)).unwrap();
    }
    d
}

pub fn opts(day: &Path, out: &Path) -> RunOptions {
    RunOptions {
        day_dir: day.to_path_buf(),
        out_dir: out.to_path_buf(),
        split: SplitRule::AllTrain,
        variants: 1,
        seed: 0,
        shard: Shard::ALL,
        jobs: 2,
        overwrite: false,
        progress: dataset::ProgressSink::silent(),
        wait: false,
    }
}

/// Every visible file under `dir` (relative path -> bytes), optionally without manifests.
pub fn tree(dir: &Path, with_manifests: bool) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, d: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(d).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                let rel = p
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    let mut m = BTreeMap::new();
    walk(dir, dir, &mut m);
    if !with_manifests {
        m.retain(|k, _| !k.starts_with("manifest"));
    }
    m
}

/// Load `page` headless; returns (console lines, screenshot bytes).
pub fn load_in_browser(chromium: &Path, page: &Path) -> (Vec<String>, Vec<u8>) {
    let profile = tempfile::tempdir().unwrap();
    let shot = profile.path().join("shot.png");
    let out = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--window-size=1400,1800",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!(
            "--user-data-dir={}",
            profile.path().join("profile").display()
        ))
        .arg(format!("--screenshot={}", shot.display()))
        .arg(format!("file://{}", page.canonicalize().unwrap().display()))
        .output()
        .expect("cannot start chromium");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let console: Vec<String> = stderr
        .lines()
        .filter(|l| l.contains(":CONSOLE"))
        .map(String::from)
        .collect();
    (console, std::fs::read(&shot).unwrap_or_default())
}
