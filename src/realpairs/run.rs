//! The driver of `real-pairs`: find the scenes, then on `jobs` threads hash each scene's
//! files, decide by the manifest whether it is up to date ([`crate::dataset::resume`]), and
//! if not plan, check and write it under its output lock; one `manifest.jsonl` record per
//! scene ([`crate::dataset::manifest`]), appended as each scene completes and rewritten sorted
//! at the end, as `dataset` does. A failing scene gets a `failed` record with its reason; the
//! other scenes are still done.

use super::discover::{find_scenes, hash_scene, plan_scene, Layout, SceneDir};
use super::outputs::{frames_field, write_scene};
use super::scene::prepare;
use super::PairOptions;
use crate::dataset::manifest::{self, Appender, Record, Status};
use crate::dataset::resume::{decide, Decision, Want};
use crate::dataset::run::{
    blank_record, check_out_dir, remove_replaced_outputs, remove_stale_temp_files_of,
};
use crate::dataset::{sha256_hex, Sink, Split, Unit};
use crate::diagnostics::{Diagnostics, Warning};
use crate::error::{Error, Result, ResultExt};
use crate::output::{stop_requested, OutputPolicy, OutputSetLock};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// What a run needs besides the pair options.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The captures.
    pub scenes_dir: PathBuf,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Worker threads = scenes in flight (>= 1).
    pub jobs: usize,
    /// Recompute every scene (and accept a non-empty OUT without a manifest).
    pub overwrite: bool,
    /// Called once per finished scene, for the caller's progress display (the library
    /// itself prints nothing); `None`: no progress.
    pub on_scene: Option<fn(&SceneDone<'_>)>,
}

/// One finished scene, as [`RunOptions::on_scene`] receives it.
#[derive(Debug)]
pub struct SceneDone<'a> {
    /// 1-based count of scenes finished so far.
    pub index: usize,
    /// Scenes in the run.
    pub total: usize,
    /// The scene's folder, relative to SCENES.
    pub scene: &'a str,
    /// "up to date", "done" or "FAILED (see the summary)".
    pub state: &'a str,
    /// The scene's warnings (about the scene's input).
    pub warnings: &'a [Warning],
    /// Seconds the scene took.
    pub secs: f64,
}

/// What a run did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Summary {
    /// Layout read.
    pub layout: String,
    /// Scenes found.
    pub scenes: usize,
    /// Scenes made in this run.
    pub done: usize,
    /// Scenes skipped (up to date).
    pub skipped: usize,
    /// Scenes that failed.
    pub failed: usize,
    /// Why scenes were (re)made: reason -> count.
    pub recomputed: BTreeMap<String, usize>,
    /// Failures: (scene input, error).
    pub failures: Vec<(String, String)>,
    /// Warnings, each about its scene's input (the subject), by scene.
    pub warnings: Vec<Warning>,
    /// Output files written in this run.
    pub outputs_written: usize,
    /// Manifest written.
    pub manifest: PathBuf,
    /// Wall time in seconds.
    pub seconds: f64,
}

impl Summary {
    /// Human summary for stderr.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "real-pairs: {} scenes ({} layout): {} made, {} skipped (up to date), {} failed; {} outputs written; {:.1} s",
            self.scenes, self.layout, self.done, self.skipped, self.failed,
            self.outputs_written, self.seconds
        );
        if !self.recomputed.is_empty() {
            let parts: Vec<String> = self
                .recomputed
                .iter()
                .map(|(k, v)| format!("{v} {k}"))
                .collect();
            s.push_str(&format!(
                "\nreal-pairs: work done, by reason: {}",
                parts.join(", ")
            ));
        }
        // Each error already starts with "scene <input>: ".
        for (_, e) in &self.failures {
            s.push_str(&format!("\nreal-pairs: FAILED {e}"));
        }
        s
    }
}

/// The outcome of one scene.
struct Outcome {
    record: Record,
    computed: Option<&'static str>,
    warnings: Diagnostics,
}

/// Run `real-pairs`.
pub fn run(opts: &RunOptions, pairs: &PairOptions) -> Result<Summary> {
    let start = Instant::now();
    let out_dir = &opts.out_dir;
    let (layout, scenes) = find_scenes(
        &opts.scenes_dir,
        std::slice::from_ref(out_dir),
        pairs.layout,
    )?;
    let manifests = manifest::all_manifests(out_dir)?;
    check_out_dir(out_dir, &manifests, None, opts.overwrite)?;
    std::fs::create_dir_all(out_dir)
        .map_err(Error::Io)
        .in_file(out_dir)?;
    let own = out_dir.join(manifest::file_name(crate::dataset::Shard::ALL));
    let previous = manifest::latest(manifest::read(&own)?.records);
    let appender = Appender::open(&own)?;
    let ids: HashSet<String> = scenes.iter().map(|s| s.id.clone()).collect();
    remove_stale_temp_files_of(out_dir, &ids, &[Split::Real]);
    let options_sha = sha256_hex(pairs.fingerprint().as_bytes());
    let jobs = opts.jobs.max(1);
    let next = AtomicUsize::new(0);
    let count = AtomicUsize::new(0);
    let results: Mutex<Vec<Outcome>> = Mutex::new(Vec::new());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(|i| format!("real-pairs-{i}"))
        .build()
        .map_err(|e| Error::invalid(format!("cannot start {jobs} worker threads: {e}")))?;
    pool.scope(|s| {
        for _ in 0..jobs {
            s.spawn(|_| loop {
                if stop_requested().is_some() {
                    break;
                }
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(scene) = scenes.get(i) else { break };
                let t0 = Instant::now();
                let prev = previous.get(&(scene.rel.clone(), 1));
                let mut o = one_scene(scene, layout, pairs, prev, &options_sha, opts);
                if o.record.status != Status::Ok && stop_requested().is_some() {
                    break;
                }
                if o.computed.is_some() {
                    if let Err(e) = appender.append(&o.record) {
                        o.record.status = Status::Failed;
                        o.record.error = Some(format!("writing the manifest: {e}"));
                    }
                }
                let k = count.fetch_add(1, Ordering::SeqCst) + 1;
                if let Some(on_scene) = opts.on_scene {
                    on_scene(&SceneDone {
                        index: k,
                        total: scenes.len(),
                        scene: &scene.rel,
                        state: state(&o),
                        warnings: &o.warnings,
                        secs: t0.elapsed().as_secs_f64(),
                    });
                }
                results.lock().unwrap_or_else(|e| e.into_inner()).push(o);
            });
        }
    });
    drop(appender);
    if stop_requested().is_some() {
        return Err(Error::Interrupted.in_file(out_dir));
    }
    let results = results.into_inner().unwrap_or_else(|e| e.into_inner());
    let mut summary = Summary {
        layout: layout.name().to_string(),
        scenes: scenes.len(),
        manifest: own.clone(),
        ..Summary::default()
    };
    for o in &results {
        summary
            .warnings
            .extend(o.warnings.clone().about_owned(&o.record.input));
        match (o.computed, o.record.status) {
            (None, _) => summary.skipped += 1,
            (Some(reason), status) => {
                *summary.recomputed.entry(reason.to_string()).or_default() += 1;
                if status == Status::Ok {
                    summary.done += 1;
                    summary.outputs_written += o.record.outputs.len();
                } else {
                    summary.failed += 1;
                    summary.failures.push((
                        o.record.input.clone(),
                        o.record.error.clone().unwrap_or_default(),
                    ));
                }
            }
        }
    }
    summary.failures.sort();
    summary
        .warnings
        .sort_by(|a, b| (&a.subject, &a.message).cmp(&(&b.subject, &b.message)));
    manifest::write_compacted(&own, results.into_iter().map(|o| o.record))?;
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

fn state(o: &Outcome) -> &'static str {
    match (o.computed, o.record.status) {
        (None, _) => "up to date",
        (Some(_), Status::Ok) => "done",
        (Some(_), Status::Failed) => "FAILED (see the summary)",
    }
}

/// Hash, decide, and make one scene if needed.
fn one_scene(
    scene: &SceneDir,
    layout: Layout,
    pairs: &PairOptions,
    prev: Option<&Record>,
    options_sha: &str,
    opts: &RunOptions,
) -> Outcome {
    let unit = Unit {
        rel: scene.rel.clone(),
        path: scene.path.clone(),
        split: Split::Real,
        variant: 1,
        variants: 1,
        seed: 0,
        id: scene.id.clone(),
    };
    let mut rec = blank_record(&unit, "", options_sha);
    rec.kind = Some("real".into());
    rec.scene = Some(scene.id.clone());
    let failed = |mut rec: Record, e: Error, reason: &'static str| Outcome {
        record: {
            rec.error = Some(format!("scene {}: {e}", scene.rel));
            rec
        },
        computed: Some(reason),
        warnings: Diagnostics::new(),
    };
    let (hashes, input_sha) = match hash_scene(scene) {
        Ok(h) => h,
        Err(e) => return failed(rec, e, "input unreadable"),
    };
    rec.input_sha256 = input_sha.clone();
    let want = Want {
        split: Split::Real,
        input_sha256: &input_sha,
        seed: 0,
        options_sha256: options_sha,
    };
    let reason = match decide(prev, want, &opts.out_dir, opts.overwrite) {
        Decision::Skip => {
            if let Some(p) = prev {
                return Outcome {
                    record: p.clone(),
                    computed: None,
                    warnings: Diagnostics::new(),
                };
            }
            "new"
        }
        Decision::Redo(r) => r.describe(),
    };
    let plan = match plan_scene(scene, &hashes, layout, &pairs.release_isos) {
        Ok(p) => p,
        Err(e) => return failed(rec, e, reason),
    };
    rec.frames = Some(frames_field(&plan));
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };
    let sink = Sink::new(&opts.out_dir, Split::Real, &scene.id, policy);
    let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _lock = OutputSetLock::acquire(&opts.out_dir, &scene.id, false)?;
        let prep = prepare(&plan, pairs.max_motion_px)?;
        let info = write_scene(&plan, &prep, pairs, &sink)?;
        Ok::<_, Error>((info, prep.warnings))
    }));
    match res {
        Ok(Ok((info, warnings))) => {
            rec.status = Status::Ok;
            rec.outputs = sink.into_outputs();
            if let Some(p) = prev {
                remove_replaced_outputs(&opts.out_dir, p, &rec);
            }
            rec.iso = info.iso;
            rec.night_neutral = info.night_neutral;
            rec.stages = info.stages;
            Outcome {
                record: rec,
                computed: Some(reason),
                warnings,
            }
        }
        other => {
            // Nothing half-written: the files this attempt wrote go.
            for o in sink.into_outputs() {
                let _ = std::fs::remove_file(opts.out_dir.join(&o.path));
            }
            let e = match other {
                Ok(Err(e)) => e,
                _ => Error::invalid("internal error (panic) while processing"),
            };
            failed(rec, e, reason)
        }
    }
}
