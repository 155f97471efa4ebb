//! The dataset job as independent units, for a scheduler of the user's (Ray Data, Dask, a
//! queue): [`units`] lists the (input, split, variant) units that [`super::run()`] makes,
//! [`write_unit`] makes exactly one unit's files in the dataset layout and returns its
//! manifest record, [`write_manifest`] writes the manifest of a finished run. The three
//! together write the tree `day2night dataset` writes, byte for byte, whatever the order,
//! the process or the machine each unit runs on.
//!
//! Resume: [`units`] attaches to each unit its latest record from OUT_DIR's manifests, and
//! [`write_unit`] skips a unit whose record is up to date ([`super::resume::decide`], as
//! `dataset` decides). Until the manifest is written, each computed unit leaves its record
//! in `OUT_DIR/.day2night-units/<stem>.v<variant>.json` (one small file per unit, written
//! atomically after the unit's outputs: no shared file is appended to, so any number of
//! processes on any number of machines can write units into one shared folder);
//! [`write_unit`] reads its own unit's file first, so a rerun after a kill skips the units
//! completed before it, and [`write_manifest`] removes the files of the records it writes.
//! `dataset` ([`super::run()`]) reads those files too, so it can finish such a run.

use super::discover::sample_stem;
use super::manifest::{self, Record};
use super::progress::ProgressSink;
use super::resume::{decide, Decision, Reason};
use super::run::{
    blank_record, check_out_dir, compute_loaded, load_input, plan_tasks, remove_stale_temp_files,
    unit_id, want, Loaded, UnitOutput,
};
use super::{sha256_hex, Processor, Shard, Split, SplitRule, Unit};
use crate::error::{Error, Result, ResultExt};
use crate::output::{write_bytes_atomic, OutputPolicy};
use std::path::{Path, PathBuf};

use super::journal::read_journal;
pub use super::journal::{clear_journal, journal_path, journal_records, JOURNAL_DIR};

/// What [`units`] needs: `dataset`'s options that decide the units.
#[derive(Debug, Clone)]
pub struct UnitsOptions {
    /// Folder searched (recursively) for day DNGs.
    pub day_dir: PathBuf,
    /// Output folder: excluded from the search, its manifests give each unit's previous
    /// record, and temporary files a killed run left for these units are removed. None:
    /// just list the units.
    pub out_dir: Option<PathBuf>,
    /// Train/val rule.
    pub split: SplitRule,
    /// Variants per input (>= 1).
    pub variants: u32,
    /// Run seed.
    pub seed: u64,
    /// Which shard.
    pub shard: Shard,
    /// Accept a non-empty OUT_DIR that is not a dataset.
    pub overwrite: bool,
}

/// A unit with the latest record OUT_DIR's manifests hold for it.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The unit.
    pub unit: Unit,
    /// Its latest manifest record, if any.
    pub previous: Option<Record>,
}

/// A unit from its fields (the id is derived, as [`super::run()`] names it): `variant` in
/// `1..=variants`.
pub fn unit(
    rel: &str,
    path: PathBuf,
    split: Split,
    variant: u32,
    variants: u32,
    seed: u64,
) -> Result<Unit> {
    if variant == 0 || variant > variants {
        return Err(Error::invalid(format!(
            "unit variant {variant} is not within 1..={variants}"
        )));
    }
    Ok(Unit {
        rel: rel.to_string(),
        path,
        split,
        variant,
        variants,
        seed,
        id: unit_id(&sample_stem(rel), variant, variants),
    })
}

/// The units `day2night dataset` makes with these options, in its order (inputs sorted by
/// relative path, then variants), each with its previous record.
pub fn units(o: &UnitsOptions) -> Result<Vec<Planned>> {
    if o.variants == 0 {
        return Err(Error::invalid("--variants must be at least 1"));
    }
    let (_found, tasks) = plan_tasks(&o.day_dir, o.out_dir.as_deref(), o.split, o.shard)?;
    let mut previous = std::collections::BTreeMap::new();
    if let Some(out_dir) = &o.out_dir {
        let manifests = manifest::all_manifests(out_dir)?;
        check_out_dir(
            out_dir,
            &manifests,
            Some(&out_dir.join(JOURNAL_DIR)),
            o.overwrite,
        )?;
        // Every manifest, this shard's own file last (it wins), as `dataset` reads them.
        let own = out_dir.join(manifest::file_name(o.shard));
        let mut records = Vec::new();
        for m in manifests.iter().filter(|m| **m != own) {
            records.extend(manifest::read(m)?.records);
        }
        records.extend(manifest::read(&own)?.records);
        previous = manifest::latest(records);
        remove_stale_temp_files(out_dir, &tasks, o.variants);
    }
    Ok(tasks
        .iter()
        .flat_map(|t| t.units(o.variants, o.seed))
        .map(|u| Planned {
            previous: previous.remove(&(u.rel.clone(), u.variant)),
            unit: u,
        })
        .collect())
}

/// Options of [`write_unit`] besides the processor.
#[derive(Debug, Clone)]
pub struct WriteOptions {
    /// Output folder.
    pub out_dir: PathBuf,
    /// Recompute even when the unit is up to date.
    pub overwrite: bool,
    /// Wait for another process writing the unit instead of failing it.
    pub wait: bool,
    /// Receiver of the per-input warnings (metadata corrections), said once per decode;
    /// the library prints nothing.
    pub progress: ProgressSink,
}

/// Make one unit's outputs in OUT_DIR (every file atomic, under the unit's lock) unless its
/// latest record (`previous`, or the journal's, which is newer) is up to date. Returns the
/// unit's manifest record and why it was computed (None: skipped, the record is the
/// previous one). A unit that fails returns a `failed` record with the error, as `dataset`
/// records it; `Err` only for an OUT_DIR that cannot be created. [`write_units`] of one.
pub fn write_unit<P: Processor>(
    unit: &Unit,
    previous: Option<&Record>,
    o: &WriteOptions,
    processor: &P,
) -> Result<(Record, Option<Reason>)> {
    let mut done = write_units(&[(unit.clone(), previous.cloned())], o, processor)?;
    done.pop()
        .ok_or_else(|| Error::invalid("write_unit: no record was made"))
}

/// [`write_unit`] for several units of one input (its variants), as `dataset` processes an
/// input: the file is read and hashed once, and decoded once (only if some unit is not up
/// to date) for all of them. Returns each unit's record and reason, in order. Units of
/// different inputs are refused (group them by input first).
pub fn write_units<P: Processor>(
    units: &[(Unit, Option<Record>)],
    o: &WriteOptions,
    processor: &P,
) -> Result<Vec<(Record, Option<Reason>)>> {
    let Some((first, _)) = units.first() else {
        return Ok(Vec::new());
    };
    if let Some((other, _)) = units.iter().find(|(u, _)| u.path != first.path) {
        return Err(Error::invalid(format!(
            "units of two inputs ({} and {}) in one call: group the units by input",
            first.rel, other.rel
        )));
    }
    let out_dir = &o.out_dir;
    let options_sha = sha256_hex(processor.fingerprint().as_bytes());
    let read =
        std::fs::read(&first.path).map_err(|e| Error::Io(e).in_file(&first.path).to_string());
    let input_sha = read.as_ref().map(|b| sha256_hex(b)).unwrap_or_default();
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };
    let mut loaded: Option<std::result::Result<P::Loaded, String>> = None;
    let mut done = Vec::with_capacity(units.len());
    // Every unit's latest record and decision first: the last unit that is computed may
    // take the decoded input (relighting in place, as `dataset` does).
    let decided: Vec<(PathBuf, Option<Record>, Decision)> = units
        .iter()
        .map(|(unit, previous)| {
            let journal = journal_path(out_dir, &unit.rel, unit.variant);
            let journaled = read_journal(&journal);
            let decision = decide(
                journaled.as_ref().or(previous.as_ref()),
                want(unit, &input_sha, &options_sha),
                out_dir,
                o.overwrite,
            );
            (journal, journaled, decision)
        })
        .collect();
    let last = decided
        .iter()
        .rposition(|(_, _, d)| matches!(d, Decision::Redo(_)));
    for (i, ((unit, previous), (journal, journaled, decision))) in
        units.iter().zip(decided).enumerate()
    {
        let prev = journaled.as_ref().or(previous.as_ref());
        let (rec, reason) = match &read {
            Err(msg) => {
                let reason = match decision {
                    Decision::Redo(r) => r,
                    Decision::Skip => Reason::InputChanged,
                };
                let mut r = blank_record(unit, "", &options_sha);
                r.error = Some(msg.clone());
                (r, reason)
            }
            Ok(bytes) => {
                let reason = match decision {
                    Decision::Skip => {
                        if let Some(p) = prev {
                            done.push((p.clone(), None));
                            continue;
                        }
                        Reason::New
                    }
                    Decision::Redo(r) => r,
                };
                std::fs::create_dir_all(out_dir)
                    .map_err(Error::Io)
                    .in_file(out_dir)?;
                let blank = blank_record(unit, &input_sha, &options_sha);
                if loaded.is_none() {
                    let l = load_input(processor, &unit.path, bytes);
                    if let Ok(input) = &l {
                        for w in processor.warnings(input) {
                            o.progress.warning(&unit.path, &w);
                        }
                    }
                    loaded = Some(l);
                }
                let at = Loaded {
                    last: Some(i) == last,
                    blank,
                    to: UnitOutput {
                        out_dir,
                        policy: &policy,
                        wait: o.wait,
                    },
                };
                (
                    compute_loaded(processor, &mut loaded, unit, prev, at),
                    reason,
                )
            }
        };
        let mut rec = rec;
        let saved = super::ensure_parent(&journal)
            .and_then(|_| write_bytes_atomic(&journal, &policy, rec.to_line()?.as_bytes()));
        if let Err(e) = saved {
            rec.status = manifest::Status::Failed;
            rec.error = Some(format!("writing the unit's record: {e}"));
        }
        done.push((rec, Some(reason)));
    }
    Ok(done)
}

/// Write the manifest of a run from its records (one per unit, the latest of each key
/// kept; lines sorted, as `dataset` writes it) into OUT_DIR (`manifest.jsonl`, or the
/// shard's file), then remove the journal files of these records. Returns the path.
pub fn write_manifest(
    out_dir: &Path,
    records: impl IntoIterator<Item = Record>,
    shard: Shard,
) -> Result<PathBuf> {
    let records = manifest::latest(records);
    std::fs::create_dir_all(out_dir)
        .map_err(Error::Io)
        .in_file(out_dir)?;
    let path = out_dir.join(manifest::file_name(shard));
    let keys: Vec<(String, u32)> = records.keys().cloned().collect();
    manifest::write_compacted(&path, records.into_values())?;
    clear_journal(out_dir, &keys);
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_ids_and_journal_names() {
        let u = unit("a/b.dng", "x/a/b.dng".into(), Split::Val, 2, 3, 7).unwrap();
        assert_eq!(u.id, "a__b_v2");
        assert_eq!(u.split, Split::Val);
        assert_eq!(
            unit("a.dng", "a.dng".into(), Split::Train, 1, 1, 0)
                .unwrap()
                .id,
            "a"
        );
        assert!(unit("a.dng", "a.dng".into(), Split::Train, 0, 1, 0).is_err());
        assert!(unit("a.dng", "a.dng".into(), Split::Train, 2, 1, 0).is_err());
        assert_eq!(
            journal_path(Path::new("o"), "a/b.dng", 2),
            Path::new("o/.day2night-units/a__b.v2.json")
        );
    }
}
