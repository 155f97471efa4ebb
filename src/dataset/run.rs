//! The driver: discover, split, shard, decide (resume), then process the inputs in parallel
//! on `jobs` threads with at most `jobs` inputs in flight ([`super::pool`], the pool
//! `real-pairs` shares), appending a manifest record as each unit completes. One failing
//! input never stops the run.

use super::discover::{discover, sample_stem, Input};
use super::manifest::{self, Appender, Record, Status};
use super::progress::{InputDone, ProgressSink};
use super::resume::{decide, Decision, Reason, Want};
use super::split::{assign, Split, SplitRule};
use super::{sha256_hex, Processor, Shard, Sink, Unit};
use crate::error::{Error, Result, ResultExt};
use crate::output::{stop_requested, OutputPolicy, OutputSetLock};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// Everything a run needs besides the processor.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Folder searched (recursively) for day DNGs.
    pub day_dir: PathBuf,
    /// Output folder.
    pub out_dir: PathBuf,
    /// Train/val rule.
    pub split: SplitRule,
    /// Variants per input (>= 1).
    pub variants: u32,
    /// Run seed (unit seeds derive from it and the file).
    pub seed: u64,
    /// Which shard to process.
    pub shard: Shard,
    /// Worker threads = inputs in flight (>= 1).
    pub jobs: usize,
    /// Recompute everything, ignoring the manifest, and allow a non-empty OUT_DIR without
    /// a manifest.
    pub overwrite: bool,
    /// Receiver of the run's progress and per-input warnings (the library prints nothing).
    pub progress: ProgressSink,
    /// When another process is writing a unit's outputs (holds its
    /// [`OutputSetLock`]): wait for it (`true`) or fail the unit (`false`).
    pub wait: bool,
}

/// What a run did.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Summary {
    /// DNGs found under DAY_DIR.
    pub found: usize,
    /// Inputs in this shard.
    pub images: usize,
    /// Of which in train.
    pub train: usize,
    /// Of which in val.
    pub val: usize,
    /// Units (input x variant) in this shard.
    pub units: usize,
    /// Units computed in this run.
    pub done: usize,
    /// Units skipped because their outputs were up to date.
    pub skipped: usize,
    /// Units that failed.
    pub failed: usize,
    /// Output files written in this run.
    pub outputs_written: usize,
    /// Output files listed by the final manifest.
    pub outputs_total: usize,
    /// Why units were computed: reason -> count.
    pub recomputed: BTreeMap<String, usize>,
    /// Failures: (input, variant, error).
    pub failures: Vec<(String, u32, String)>,
    /// Records of units no longer in the dataset dropped from the manifest.
    pub stale_records_dropped: usize,
    /// Manifest written.
    pub manifest: PathBuf,
    /// Wall time in seconds.
    pub seconds: f64,
}

impl Summary {
    /// Human summary, several lines, for stderr.
    pub fn describe(&self) -> String {
        let mut s = format!(
            "dataset: {} images ({} train, {} val; {} found), {} units: {} computed, {} skipped (up to date), {} failed; {} outputs written ({} in manifest); {:.1} s",
            self.images, self.train, self.val, self.found, self.units, self.done,
            self.skipped, self.failed, self.outputs_written, self.outputs_total, self.seconds
        );
        s.push_str(&reasons_line("dataset", &self.recomputed));
        if self.stale_records_dropped > 0 {
            s.push_str(&format!(
                "\ndataset: dropped {} manifest records of inputs/variants no longer in the dataset (their files were left in place)",
                self.stale_records_dropped
            ));
        }
        for (input, v, e) in &self.failures {
            s.push_str(&format!("\ndataset: FAILED {input} variant {v}: {e}"));
        }
        s
    }
}

/// One input of the run: where it goes and under which name.
pub(super) struct Task {
    pub(super) input: Input,
    pub(super) split: Split,
    pub(super) stem: String,
}

impl Task {
    /// The (input, variant) units of this input, variants 1..=`variants`.
    pub(super) fn units(&self, variants: u32, seed: u64) -> Vec<Unit> {
        (1..=variants)
            .map(|variant| Unit {
                rel: self.input.rel.clone(),
                path: self.input.path.clone(),
                split: self.split,
                variant,
                variants,
                seed,
                id: unit_id(&self.stem, variant, variants),
            })
            .collect()
    }
}

/// The output id of a unit: the sample stem, plus `_vK` when more than one variant is made.
pub(super) fn unit_id(stem: &str, variant: u32, variants: u32) -> String {
    if variants > 1 {
        format!("{stem}_v{variant}")
    } else {
        stem.to_string()
    }
}

/// Discover the inputs under `day_dir` (skipping `out_dir`), refuse name clashes, split
/// them and keep `shard`'s: (inputs found, tasks of the shard).
pub(super) fn plan_tasks(
    day_dir: &Path,
    out_dir: Option<&Path>,
    split: SplitRule,
    shard: Shard,
) -> Result<(usize, Vec<Task>)> {
    let exclude: Vec<PathBuf> = out_dir.map(Path::to_path_buf).into_iter().collect();
    let inputs = discover(day_dir, &exclude)?;
    if inputs.is_empty() {
        return Err(Error::invalid(
            "no DNG file found (searched recursively for *.dng in any letter case)",
        )
        .in_file(day_dir));
    }
    // Two inputs must not map to the same output names.
    let mut stems: HashMap<String, &str> = HashMap::new();
    for inp in &inputs {
        let stem = sample_stem(&inp.rel);
        if let Some(other) = stems.insert(stem.clone(), &inp.rel) {
            return Err(Error::invalid(format!(
                "inputs {other} and {} would both be named {stem} in the dataset; rename one",
                inp.rel
            ))
            .in_file(day_dir));
        }
    }
    let splits = assign(&inputs, split)?;
    let found = inputs.len();
    let tasks = inputs
        .into_iter()
        .zip(splits)
        .filter(|(inp, _)| shard.selects(&inp.rel))
        .map(|(input, split)| Task {
            stem: sample_stem(&input.rel),
            input,
            split,
        })
        .collect();
    Ok((found, tasks))
}

/// Only reuse an OUT_DIR that is empty or already a dataset (it holds a manifest, or
/// `extra_marker` when given), unless `overwrite`.
pub fn check_out_dir(
    out_dir: &Path,
    manifests: &[PathBuf],
    extra_marker: Option<&Path>,
    overwrite: bool,
) -> Result<()> {
    let marked = !manifests.is_empty() || extra_marker.is_some_and(Path::exists);
    if !marked && !overwrite && dir_has_entries(out_dir) {
        return Err(Error::invalid(
            "output folder is not empty and holds no manifest*.jsonl (not a dataset); pass --overwrite to write into it anyway",
        )
        .in_file(out_dir));
    }
    Ok(())
}

/// Count one input's units into `st`; returns its (done, skipped, failed) counts.
fn tally(st: &mut Summary, outcome: &[(Record, Did)]) -> (usize, usize, usize) {
    let (mut done, mut skipped, mut failed) = (0, 0, 0);
    for (rec, what) in outcome {
        match what {
            Did::Skipped => {
                st.skipped += 1;
                skipped += 1;
            }
            Did::Computed(reason) => {
                *st.recomputed
                    .entry(reason.describe().to_string())
                    .or_default() += 1;
                if rec.status == Status::Ok {
                    st.done += 1;
                    done += 1;
                    st.outputs_written += rec.outputs.len();
                } else {
                    st.failed += 1;
                    failed += 1;
                    st.failures.push((
                        rec.input.clone(),
                        rec.variant,
                        rec.error.clone().unwrap_or_default(),
                    ));
                }
            }
        }
    }
    (done, skipped, failed)
}

/// The summary's "work done, by reason" line (with its leading newline) of `command`
/// (`dataset`, `real-pairs`); empty when nothing was (re)made.
pub fn reasons_line(command: &str, recomputed: &BTreeMap<String, usize>) -> String {
    if recomputed.is_empty() {
        return String::new();
    }
    let parts: Vec<String> = recomputed.iter().map(|(k, v)| format!("{v} {k}")).collect();
    format!("\n{command}: work done, by reason: {}", parts.join(", "))
}

/// Run the dataset generation with `processor`.
pub fn run<P: Processor>(opts: &RunOptions, processor: &P) -> Result<Summary> {
    let start = Instant::now();
    if opts.variants == 0 {
        return Err(Error::invalid("--variants must be at least 1"));
    }
    let jobs = opts.jobs.max(1);
    let out_dir = &opts.out_dir;
    let (found, tasks) = plan_tasks(&opts.day_dir, Some(out_dir), opts.split, opts.shard)?;

    // Safety: only reuse an OUT_DIR that is empty or already a dataset.
    let manifests = manifest::all_manifests(out_dir)?;
    let journal = out_dir.join(super::journal::JOURNAL_DIR);
    check_out_dir(out_dir, &manifests, Some(&journal), opts.overwrite)?;
    std::fs::create_dir_all(out_dir)
        .map_err(Error::Io)
        .in_file(out_dir)?;
    let own_manifest = out_dir.join(manifest::file_name(opts.shard));
    // Previous records from every manifest; this shard's own file read last so it wins.
    let mut previous = Vec::new();
    for m in manifests.iter().filter(|m| **m != own_manifest) {
        previous.extend(manifest::read(m)?.records);
    }
    let own_loaded = manifest::read(&own_manifest)?;
    let own_keys: Vec<(String, u32)> = own_loaded.records.iter().map(|r| r.key()).collect();
    previous.extend(own_loaded.records);
    // Units written by `dataset::units` (a Ray run) since the last manifest: newer.
    previous.extend(super::journal::journal_records(out_dir));
    let previous = manifest::latest(previous);
    let appender = Appender::open(&own_manifest)?;
    remove_stale_temp_files(out_dir, &tasks, opts.variants);

    let options_sha = sha256_hex(processor.fingerprint().as_bytes());
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };

    let n_units = tasks.len() * opts.variants as usize;
    let final_records: Mutex<Vec<Record>> = Mutex::new(Vec::with_capacity(n_units));
    let stats = Mutex::new(Summary::default());
    let progress = &opts.progress;
    progress.start(tasks.len());
    let finished = AtomicUsize::new(0);
    super::pool::for_each(&tasks, jobs, "dataset", |task| {
        let t0 = Instant::now();
        let outcome = process_input(
            task,
            opts,
            processor,
            &previous,
            &options_sha,
            &policy,
            &appender,
        );
        let (done, skipped, failed) = tally(
            &mut stats.lock().unwrap_or_else(|e| e.into_inner()),
            &outcome,
        );
        progress.input_done(&InputDone {
            index: finished.fetch_add(1, Ordering::SeqCst) + 1,
            total: tasks.len(),
            split: task.split.name(),
            input: &task.input.rel,
            done,
            skipped,
            failed,
            secs: t0.elapsed().as_secs_f64(),
        });
        final_records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .extend(outcome.into_iter().map(|(r, _)| r));
        ControlFlow::Continue(())
    })?;
    progress.finish();
    drop(appender);
    if stop_requested().is_some() {
        // The manifest holds every unit completed (appended as each one finished); keep it
        // as it is, uncompacted, so the records of the inputs not reached stay for the
        // rerun that resumes.
        return Err(Error::Interrupted.in_file(out_dir));
    }

    let final_records = final_records
        .into_inner()
        .unwrap_or_else(|e| e.into_inner());
    let keep: std::collections::HashSet<(String, u32)> =
        final_records.iter().map(|r| r.key()).collect();
    let stale = own_keys
        .into_iter()
        .collect::<std::collections::HashSet<_>>()
        .into_iter()
        .filter(|k| !keep.contains(k))
        .count();
    let mut summary = stats.into_inner().unwrap_or_else(|e| e.into_inner());
    summary.outputs_total = final_records.iter().map(|r| r.outputs.len()).sum();
    let keys: Vec<(String, u32)> = final_records.iter().map(|r| r.key()).collect();
    manifest::write_compacted(&own_manifest, final_records)?;
    super::journal::clear_journal(out_dir, &keys);
    summary.failures.sort();
    summary.found = found;
    summary.images = tasks.len();
    summary.train = tasks.iter().filter(|t| t.split == Split::Train).count();
    summary.val = summary.images - summary.train;
    summary.units = n_units;
    summary.stale_records_dropped = stale;
    summary.manifest = own_manifest;
    summary.seconds = start.elapsed().as_secs_f64();
    Ok(summary)
}

/// Remove the hidden temporary files (`.<name>.tmp-<pid>`, see `crate::output`) that a
/// killed run left for the outputs of this run's units: each unit belongs to exactly one
/// shard, so only another run of the same shard could own them, and the files of a unit
/// whose [`OutputSetLock`] is held (being written now) are left alone. Other shards' files
/// are left alone.
pub(super) fn remove_stale_temp_files(out_dir: &Path, tasks: &[Task], variants: u32) {
    let mut ids = std::collections::HashSet::new();
    for t in tasks {
        for v in 1..=variants {
            ids.insert(unit_id(&t.stem, v, variants));
        }
    }
    remove_stale_temp_files_of(out_dir, &ids, &[Split::Train, Split::Val]);
}

/// `remove_stale_temp_files` for the output ids `ids` in the folders of `splits` (shared
/// with `real-pairs`, whose units are scenes).
pub fn remove_stale_temp_files_of(
    out_dir: &Path,
    ids: &std::collections::HashSet<String>,
    splits: &[Split],
) {
    for &split in splits {
        for kind in super::ALL_KINDS {
            let dir = out_dir.join(split.name()).join(kind.dir());
            let Ok(rd) = std::fs::read_dir(&dir) else {
                continue;
            };
            for e in rd.flatten() {
                let name = e.file_name();
                let Some(name) = name.to_str() else { continue };
                if let Some(id) = temp_file_id(name) {
                    if ids.contains(id) {
                        if let Ok(_unit) = OutputSetLock::acquire(out_dir, id, false) {
                            let _ = std::fs::remove_file(e.path());
                        }
                    }
                }
            }
        }
    }
}

/// The output id a temporary file `.<id><suffix>.tmp-<pid>` belongs to, where the suffix is
/// an extension optionally preceded by `_iso<N>`.
fn temp_file_id(name: &str) -> Option<&str> {
    let rest = name.strip_prefix('.')?;
    let (out_name, pid) = rest.rsplit_once(".tmp-")?;
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let (base, _ext) = out_name.rsplit_once('.')?;
    if let Some((id, iso)) = base.rsplit_once("_iso") {
        if !iso.is_empty() && iso.bytes().all(|b| b.is_ascii_digit()) {
            return Some(id);
        }
    }
    Some(base)
}

fn dir_has_entries(p: &Path) -> bool {
    std::fs::read_dir(p)
        .map(|mut rd| rd.next().is_some())
        .unwrap_or(false)
}

enum Did {
    Skipped,
    Computed(Reason),
}

/// Process every variant of one input; returns the final record of each unit.
fn process_input<P: Processor>(
    task: &Task,
    opts: &RunOptions,
    processor: &P,
    previous: &BTreeMap<(String, u32), Record>,
    options_sha: &str,
    policy: &OutputPolicy,
    appender: &Appender,
) -> Vec<(Record, Did)> {
    let units = task.units(opts.variants, opts.seed);
    let blank = |u: &Unit, input_sha256: &str| blank_record(u, input_sha256, options_sha);
    let finish = |mut rec: Record, what: Did| -> (Record, Did) {
        if !matches!(what, Did::Skipped) {
            if let Err(e) = appender.append(&rec) {
                // The manifest itself failed: report it on the unit.
                rec.status = Status::Failed;
                rec.error = Some(format!("writing the manifest: {e}"));
            }
        }
        (rec, what)
    };

    let bytes = match std::fs::read(&task.input.path) {
        Ok(b) => b,
        Err(e) => {
            let msg = Error::Io(e).in_file(&task.input.path).to_string();
            return units
                .iter()
                .map(|u| {
                    let prev = previous.get(&(u.rel.clone(), u.variant));
                    let reason = match decide(
                        prev,
                        want(u, "", options_sha),
                        &opts.out_dir,
                        opts.overwrite,
                    ) {
                        Decision::Redo(r) => r,
                        Decision::Skip => Reason::InputChanged,
                    };
                    let mut r = blank(u, "");
                    r.error = Some(msg.clone());
                    finish(r, Did::Computed(reason))
                })
                .collect();
        }
    };
    let input_sha = sha256_hex(&bytes);
    let decisions: Vec<Decision> = units
        .iter()
        .map(|u| {
            let prev = previous.get(&(u.rel.clone(), u.variant));
            decide(
                prev,
                want(u, &input_sha, options_sha),
                &opts.out_dir,
                opts.overwrite,
            )
        })
        .collect();
    let mut out = Vec::with_capacity(units.len());
    let mut loaded: Option<std::result::Result<P::Loaded, String>> = None;
    // The last unit computed from this input may use the decoded input up.
    let last = decisions
        .iter()
        .rposition(|d| matches!(d, Decision::Redo(_)));
    for (i, (u, d)) in units.iter().zip(decisions).enumerate() {
        if stop_requested().is_some() {
            break;
        }
        let reason = match d {
            Decision::Skip => {
                if let Some(prev) = previous.get(&(u.rel.clone(), u.variant)) {
                    out.push((prev.clone(), Did::Skipped));
                }
                continue;
            }
            Decision::Redo(r) => r,
        };
        if loaded.is_none() {
            loaded = Some(load_input(processor, &task.input.path, &bytes));
            if let Some(Ok(input)) = &loaded {
                for w in processor.warnings(input) {
                    opts.progress.warning(&task.input.path, &w);
                }
            }
        }
        let prev = previous.get(&(u.rel.clone(), u.variant));
        let to = UnitOutput {
            out_dir: &opts.out_dir,
            policy,
            wait: opts.wait,
        };
        let at = Loaded {
            last: Some(i) == last,
            blank: blank(u, &input_sha),
            to,
        };
        let rec = compute_loaded(processor, &mut loaded, u, prev, at);
        if rec.status != Status::Ok && stop_requested().is_some() {
            // Stopped by an interrupt: no record, the rerun computes the unit.
            break;
        }
        out.push(finish(rec, Did::Computed(reason)));
    }
    out
}

/// The record of a unit not (yet) made: status failed, no outputs.
pub fn blank_record(u: &Unit, input_sha256: &str, options_sha256: &str) -> Record {
    Record {
        input: u.rel.clone(),
        variant: u.variant,
        split: u.split,
        status: Status::Failed,
        input_sha256: input_sha256.to_string(),
        seed: u.seed,
        options_sha256: options_sha256.to_string(),
        outputs: vec![],
        iso: vec![],
        night_neutral: None,
        stages: vec![],
        error: None,
        kind: None,
        scene: None,
        frames: None,
    }
}

/// Load a unit's input from its bytes, a panic caught as an error message.
pub(super) fn load_input<P: Processor>(
    processor: &P,
    path: &Path,
    bytes: &[u8],
) -> std::result::Result<P::Loaded, String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| processor.load(path, bytes))) {
        Ok(Ok(x)) => Ok(x),
        Ok(Err(e)) => Err(e.in_file(path).to_string()),
        Err(_) => Err(format!(
            "{}: internal error (panic) while loading",
            path.display()
        )),
    }
}

/// Where and how a unit's outputs are written: the output directory, the write policy, and
/// whether to wait for another process's lock on the unit (`--wait`).
#[derive(Debug, Clone, Copy)]
pub struct UnitOutput<'a> {
    /// The output directory.
    pub out_dir: &'a Path,
    /// How files are written.
    pub policy: &'a OutputPolicy,
    /// Wait for a lock another process holds, instead of failing.
    pub wait: bool,
}

/// How [`compute_loaded`] makes a unit: whether it is the last unit computed from its input,
/// its blank record, and where its outputs go.
pub struct Loaded<'a> {
    /// The last unit of its input that is computed: it takes the decoded input.
    pub last: bool,
    /// The unit's blank record ([`compute_unit`]'s `rec`).
    pub blank: Record,
    /// Where its outputs go.
    pub to: UnitOutput<'a>,
}

/// [`compute_unit`] from an input's load (`loaded`, filled by `load_input` before the
/// first unit that is computed): the last unit takes the decoded input out
/// ([`UnitInput::Last`]), the others borrow it; a load that failed gives each unit a
/// failed record with its message.
pub fn compute_loaded<P: Processor>(
    processor: &P,
    loaded: &mut Option<std::result::Result<P::Loaded, String>>,
    u: &Unit,
    prev: Option<&Record>,
    at: Loaded<'_>,
) -> Record {
    let Loaded { last, blank, to } = at;
    match loaded.take() {
        Some(Ok(input)) if last => {
            compute_unit(processor, UnitInput::Last(input), u, prev, blank, to)
        }
        Some(Ok(input)) => {
            let rec = compute_unit(processor, UnitInput::Shared(&input), u, prev, blank, to);
            *loaded = Some(Ok(input));
            rec
        }
        Some(Err(msg)) => {
            let rec = Record {
                error: Some(msg.clone()),
                ..blank
            };
            *loaded = Some(Err(msg));
            rec
        }
        None => Record {
            error: Some("not loaded".into()),
            ..blank
        },
    }
}

/// The decoded input a unit is computed from: shared while later units of the same input
/// still need it, handed over to the last one ([`Processor::process_last`]).
pub enum UnitInput<'a, L> {
    /// Borrowed: more units of this input follow.
    Shared(&'a L),
    /// Owned: the input's last unit.
    Last(L),
}

/// Make one unit's outputs under its [`OutputSetLock`] and return its record (`rec`, the
/// blank record, filled in): `ok` with the files written, or `failed` with the error (a
/// panic is caught). Files the previous record listed that are no longer made are removed.
pub fn compute_unit<P: Processor>(
    processor: &P,
    input: UnitInput<'_, P::Loaded>,
    u: &Unit,
    prev: Option<&Record>,
    mut rec: Record,
    to: UnitOutput,
) -> Record {
    let UnitOutput {
        out_dir,
        policy,
        wait,
    } = to;
    let sink = Sink::new(out_dir, u.split, &u.id, policy.clone());
    // One process at a time writes a unit's outputs (docs/concurrency.md).
    let res = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _unit = OutputSetLock::acquire(out_dir, &u.id, wait)?;
        match input {
            UnitInput::Shared(input) => processor.process(input, u, &sink),
            UnitInput::Last(input) => processor.process_last(input, u, &sink),
        }
    }));
    match res {
        Ok(Ok(info)) => {
            rec.status = Status::Ok;
            rec.outputs = sink.into_outputs();
            if let Some(prev) = prev {
                remove_replaced_outputs(out_dir, prev, &rec);
            }
            rec.iso = info.iso;
            rec.night_neutral = info.night_neutral;
            rec.stages = info.stages;
        }
        Ok(Err(e)) => rec.error = Some(e.in_file(&u.path).to_string()),
        Err(_) => {
            rec.error = Some(format!(
                "{}: internal error (panic) while processing",
                u.path.display()
            ))
        }
    }
    rec
}

/// Delete the files a unit's previous record listed that its new outputs no longer include
/// (e.g. `.exr` targets after switching to `--target png`, or outputs under the other split),
/// so a recomputed unit leaves exactly its current files. Only plain relative paths inside
/// OUT_DIR are touched.
pub fn remove_replaced_outputs(out_dir: &Path, prev: &Record, now: &Record) {
    for o in &prev.outputs {
        let p = Path::new(&o.path);
        let plain = p
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        if plain && !now.outputs.iter().any(|n| n.path == o.path) {
            let _ = std::fs::remove_file(out_dir.join(p));
        }
    }
}

pub(super) fn want<'a>(u: &Unit, input_sha: &'a str, options_sha: &'a str) -> Want<'a> {
    Want {
        split: u.split,
        input_sha256: input_sha,
        seed: u.seed,
        options_sha256: options_sha,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_file_ids() {
        assert_eq!(temp_file_id(".a_v2_iso1600.dng.tmp-123"), Some("a_v2"));
        assert_eq!(temp_file_id(".a__b.json.tmp-9"), Some("a__b"));
        assert_eq!(temp_file_id(".a_isox.exr.tmp-9"), Some("a_isox"));
        assert_eq!(temp_file_id("a.dng"), None);
        assert_eq!(temp_file_id(".a.dng.tmp-"), None);
    }
}
