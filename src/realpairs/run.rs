//! The driver of `real-pairs`: find the scenes, then on `jobs` threads (the pool
//! `dataset` uses, [`crate::dataset::pool`]) hash each scene's
//! files, decide by the manifest whether it is up to date ([`crate::dataset::resume`]), and
//! if not plan, check and write it under its output lock; one `manifest.jsonl` record per
//! scene ([`crate::dataset::manifest`]), appended as each scene completes and rewritten sorted
//! at the end, as `dataset` does. A failing scene gets a `failed` record with its reason; the
//! other scenes are still done.

use super::discover::{find_scenes, hash_scene, plan_scene, Layout, SceneDir, ScenePlan};
use super::outputs::{commit_scene, frames_field, write_scene};
use super::scene::prepare;
use super::PairOptions;
use crate::dataset::manifest::{self, Appender, Record, Status};
use crate::dataset::resume::{decide, Decision, Want};
use crate::dataset::run::{
    blank_record, check_out_dir, reasons_line, remove_replaced_outputs, remove_stale_temp_files_of,
};
use crate::dataset::{sha256_hex, Kind, Sink, Split, Unit};
use crate::diagnostics::{Diagnostics, Warning};
use crate::error::{Error, Result, ResultExt};
use crate::output::{stop_requested, DeferredSyncs, OutputPolicy, OutputSetLock};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
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
    /// Called with the scene's id at each [`Checkpoint`] of its writing (a seam for tests
    /// that interrupt a run at a known point); `None` in the command.
    pub checkpoint: Option<fn(&str, Checkpoint)>,
}

/// A point of a scene's writing, told to [`RunOptions::checkpoint`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Checkpoint {
    /// Every file of the scene is written to its temporary file; none is in place.
    Staged,
    /// Every file of the scene is in place; its manifest record is not yet appended.
    Committed,
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
    /// Scenes (inputs) the previous manifest recorded that SCENES no longer holds: their
    /// records are dropped, their files left in place (as `dataset` does).
    pub dropped: Vec<String>,
}

impl Summary {
    /// Human summary for stderr.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "real-pairs: {} scenes ({} layout): {} made, {} skipped (up to date), {} failed; {} outputs written; {:.1} s",
            self.scenes, self.layout, self.done, self.skipped, self.failed,
            self.outputs_written, self.seconds
        );
        s.push_str(&reasons_line("real-pairs", &self.recomputed));
        if !self.dropped.is_empty() {
            s.push_str(&format!(
                "\nreal-pairs: dropped the manifest records of {} scenes no longer in SCENES (their files were left in place): {}",
                self.dropped.len(),
                self.dropped.join(", ")
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
    /// The scene's committed files, held open for an interrupt until the record is
    /// appended (dropped then).
    set: Option<Arc<DeferredSyncs>>,
}

/// Run `real-pairs`.
pub fn run(opts: &RunOptions, pairs: &PairOptions) -> Result<Summary> {
    let start = Instant::now();
    let out_dir = &opts.out_dir;
    let canon = |p: &std::path::Path| std::fs::canonicalize(p).ok();
    if canon(out_dir).is_some() && canon(out_dir) == canon(&opts.scenes_dir) {
        return Err(Error::invalid(
            "the output folder is the scenes folder SCENES: give OUT a folder of its own (outside the scenes)",
        )
        .in_file(out_dir));
    }
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
    let count = AtomicUsize::new(0);
    let results: Mutex<Vec<Outcome>> = Mutex::new(Vec::new());
    crate::dataset::pool::for_each(&scenes, opts.jobs, "real-pairs", |scene| {
        let t0 = Instant::now();
        let prev = previous.get(&(scene.rel.clone(), 1));
        let mut o = one_scene(scene, layout, pairs, prev, &options_sha, opts);
        if o.record.status != Status::Ok && stop_requested().is_some() {
            return ControlFlow::Break(());
        }
        if o.computed.is_some() {
            if let Err(e) = appender.append(&o.record) {
                o.record.status = Status::Failed;
                o.record.error = Some(format!("writing the manifest: {e}"));
            }
        }
        // The set is whole on disk and recorded: an interrupt need not wait for it.
        drop(o.set.take());
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
        ControlFlow::Continue(())
    })?;
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
    let here: HashSet<&str> = scenes.iter().map(|s| s.rel.as_str()).collect();
    summary.dropped = previous
        .keys()
        .filter(|(rel, _)| !here.contains(rel.as_str()))
        .map(|(rel, _)| rel.clone())
        .collect();
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
    let failed = |mut rec: Record, e: Error, reason: &'static str| {
        if let Some(p) = prev {
            if stop_requested().is_none() {
                // A failed scene lists no files: those of its last good run go (docs).
                if let Ok(_lock) = OutputSetLock::acquire(&opts.out_dir, &scene.id, false) {
                    remove_replaced_outputs(&opts.out_dir, p, &rec);
                }
            }
        }
        rec.error = Some(format!("scene {}: {e}", scene.rel));
        Outcome {
            record: rec,
            computed: Some(reason),
            warnings: Diagnostics::new(),
            set: None,
        }
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
                    set: None,
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
    let syncs = Arc::new(DeferredSyncs::default());
    let sink = Sink::new(
        &opts.out_dir,
        Split::Real,
        &scene.id,
        policy.deferring(&syncs),
    );
    let committing = std::cell::Cell::new(false);
    let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _lock = OutputSetLock::acquire(&opts.out_dir, &scene.id, false)?;
        let prep = prepare(&plan, pairs.max_motion_px)?;
        let info = write_scene(&plan, &prep, pairs, &sink)?;
        if let Some(f) = opts.checkpoint {
            f(&scene.id, Checkpoint::Staged);
        }
        let copied = prep.target_png.is_some();
        committing.set(true);
        commit_scene(&sink, &syncs, &policy, pairs.target, copied)?;
        if let Some(f) = opts.checkpoint {
            f(&scene.id, Checkpoint::Committed);
        }
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
                set: Some(syncs),
            }
        }
        other => {
            // Nothing half-written: staged files were never renamed into place (dropping
            // the queue removes them); a commit that failed part way removes the scene's
            // files.
            drop(syncs);
            if committing.get() {
                for p in scene_paths(&sink, &plan) {
                    let _ = std::fs::remove_file(p);
                }
            }
            let e = match other {
                Ok(Err(e)) => e,
                _ => Error::invalid("internal error (panic) while processing"),
            };
            failed(rec, e, reason)
        }
    }
}

/// Every file a scene may have in OUT.
fn scene_paths(sink: &Sink, plan: &ScenePlan) -> Vec<PathBuf> {
    let mut v = vec![
        sink.path(Kind::CleanRaw, ".dng"),
        sink.path(Kind::Target, ".png"),
        sink.path(Kind::Target, ".exr"),
        sink.path(Kind::Meta, ".json"),
    ];
    for f in &plan.noisy {
        v.push(sink.path(Kind::NoisyRaw, &format!("_iso{}.dng", f.iso)));
    }
    v
}
