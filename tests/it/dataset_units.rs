//! `dataset::units`: the dataset job as units for an external scheduler (Ray Data in the
//! Python package). Units written in any order, then the manifest, give `dataset`'s tree
//! byte for byte; a run killed before its manifest resumes, skipping the units it completed.

use crate::dataset_fake;

use dataset_fake::{make_day_dir, opts, tree, Fake};
use day2night::dataset::units::{self, Planned, UnitsOptions, WriteOptions, JOURNAL_DIR};
use day2night::dataset::{self, Record, Shard, SplitRule, Status};
use std::path::Path;
use std::sync::atomic::Ordering;

fn unit_opts(day: &Path, out: &Path) -> UnitsOptions {
    UnitsOptions {
        day_dir: day.to_path_buf(),
        out_dir: Some(out.to_path_buf()),
        split: SplitRule::LastN(2),
        variants: 2,
        seed: 3,
        shard: Shard::ALL,
        overwrite: false,
    }
}

fn write_all(planned: &[Planned], out: &Path, fake: &Fake) -> Vec<Record> {
    let w = WriteOptions {
        out_dir: out.to_path_buf(),
        overwrite: false,
        wait: false,
        progress: Default::default(),
    };
    planned
        .iter()
        .map(|p| {
            units::write_unit(&p.unit, p.previous.as_ref(), &w, fake)
                .unwrap()
                .0
        })
        .collect()
}

#[test]
fn units_in_any_order_equal_the_dataset_run() {
    let day = make_day_dir(7);
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut o = opts(day.path(), a.path());
    o.split = SplitRule::LastN(2);
    o.variants = 2;
    o.seed = 3;
    dataset::run(&o, &Fake::new("x")).unwrap();

    let mut planned = units::units(&unit_opts(day.path(), b.path())).unwrap();
    assert_eq!(planned.len(), 14);
    assert!(planned.iter().all(|p| p.previous.is_none()));
    assert_eq!(planned[0].unit.id, "a__deep__img_001_v1");
    planned.reverse();
    let records = write_all(&planned, b.path(), &Fake::new("x"));
    assert!(records.iter().all(|r| r.status == Status::Ok));
    assert!(b.path().join(JOURNAL_DIR).is_dir());
    units::write_manifest(b.path(), records, Shard::ALL).unwrap();
    assert!(!b.path().join(JOURNAL_DIR).exists());
    assert_eq!(tree(a.path(), true), tree(b.path(), true));

    // A shard's units are the shard's inputs.
    let mut so = unit_opts(day.path(), b.path());
    so.shard = Shard { index: 1, count: 3 };
    so.out_dir = None;
    let shard = units::units(&so).unwrap();
    assert!(!shard.is_empty() && shard.len() < 14);
    assert!(shard.iter().all(|p| so.shard.selects(&p.unit.rel)));
}

#[test]
fn a_killed_run_resumes_skipping_completed_units() {
    let day = make_day_dir(6);
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut o = opts(day.path(), a.path());
    o.split = SplitRule::LastN(2);
    o.variants = 2;
    o.seed = 3;
    dataset::run(&o, &Fake::new("x")).unwrap();

    // First run: 5 of 12 units done, then "killed" (no manifest), leaving a temporary file.
    let planned = units::units(&unit_opts(day.path(), b.path())).unwrap();
    write_all(&planned[..5], b.path(), &Fake::new("x"));
    let tmp = b.path().join("train/clean_raw/.b__img_000_v1.dng.tmp-4242");
    std::fs::create_dir_all(tmp.parent().unwrap()).unwrap();
    std::fs::write(&tmp, b"half").unwrap();

    // The rerun skips the 5 (their journal records) and removes the temporary file.
    let planned = units::units(&unit_opts(day.path(), b.path())).unwrap();
    assert!(!tmp.exists());
    let f = Fake::new("x");
    let w = WriteOptions {
        out_dir: b.path().to_path_buf(),
        overwrite: false,
        wait: false,
        progress: Default::default(),
    };
    let mut records = Vec::new();
    let mut skipped = 0;
    for p in &planned {
        let (r, why) = units::write_unit(&p.unit, p.previous.as_ref(), &w, &f).unwrap();
        skipped += usize::from(why.is_none());
        records.push(r);
    }
    assert_eq!((skipped, f.units.load(Ordering::SeqCst)), (5, 7));
    units::write_manifest(b.path(), records, Shard::ALL).unwrap();
    assert_eq!(tree(a.path(), true), tree(b.path(), true));

    // A finished tree: every unit skipped through the manifest; a deleted output redone.
    std::fs::remove_file(b.path().join("val/meta/b__img_003_v2.json")).unwrap();
    let planned = units::units(&unit_opts(day.path(), b.path())).unwrap();
    assert!(planned.iter().all(|p| p.previous.is_some()));
    let f = Fake::new("x");
    let records = write_all(&planned, b.path(), &f);
    assert_eq!(f.units.load(Ordering::SeqCst), 1);
    units::write_manifest(b.path(), records, Shard::ALL).unwrap();
    assert_eq!(tree(a.path(), true), tree(b.path(), true));
}

#[test]
fn failures_and_a_foreign_out_dir() {
    let day = make_day_dir(3);
    std::fs::write(day.path().join("bad.dng"), b"not a day file").unwrap();
    let out = tempfile::tempdir().unwrap();
    let mut uo = unit_opts(day.path(), out.path());
    uo.variants = 1;
    uo.split = SplitRule::AllTrain;
    let planned = units::units(&uo).unwrap();
    let records = write_all(&planned, out.path(), &Fake::new("x"));
    let bad: Vec<&Record> = records
        .iter()
        .filter(|r| r.status == Status::Failed)
        .collect();
    assert_eq!(bad.len(), 1);
    assert!(bad[0].error.as_deref().unwrap().contains("bad.dng"));

    let foreign = tempfile::tempdir().unwrap();
    std::fs::write(foreign.path().join("notes.txt"), b"mine").unwrap();
    uo.out_dir = Some(foreign.path().to_path_buf());
    let e = units::units(&uo).unwrap_err().to_string();
    assert!(e.contains("not a dataset"), "{e}");
    uo.variants = 0;
    assert!(units::units(&uo).is_err());
}

#[test]
fn the_command_finishes_an_interrupted_unit_run() {
    let day = make_day_dir(5);
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut o = opts(day.path(), a.path());
    o.variants = 2;
    o.split = SplitRule::LastN(2);
    o.seed = 3;
    dataset::run(&o, &Fake::new("x")).unwrap();
    let planned = units::units(&unit_opts(day.path(), b.path())).unwrap();
    write_all(&planned[..4], b.path(), &Fake::new("x"));
    // `dataset` over the same folder: the 4 journaled units skipped, the journal cleared.
    let mut ob = o.clone();
    ob.out_dir = b.path().to_path_buf();
    let f = Fake::new("x");
    let s = dataset::run(&ob, &f).unwrap();
    assert_eq!(
        (s.skipped, s.done, f.units.load(Ordering::SeqCst)),
        (4, 6, 6)
    );
    assert!(!b.path().join(JOURNAL_DIR).exists());
    assert_eq!(tree(a.path(), true), tree(b.path(), true));
}

#[test]
fn write_units_loads_each_input_once_for_all_its_variants() {
    let day = make_day_dir(4);
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut uo = unit_opts(day.path(), a.path());
    uo.variants = 3;
    let w = |out: &Path| WriteOptions {
        out_dir: out.to_path_buf(),
        overwrite: false,
        wait: false,
        progress: Default::default(),
    };
    // One unit at a time: one load per unit.
    let planned = units::units(&uo).unwrap();
    let one = Fake::new("x");
    let records_a = write_all(&planned, a.path(), &one);
    assert_eq!(one.loads.load(Ordering::SeqCst), 12);
    // each unit is its input's last: it takes the decoded input
    assert_eq!(one.lasts.load(Ordering::SeqCst), 12);
    units::write_manifest(a.path(), records_a, Shard::ALL).unwrap();

    // Grouped by input: one load per input, the same tree.
    uo.out_dir = Some(b.path().to_path_buf());
    let planned = units::units(&uo).unwrap();
    let grouped = Fake::new("x");
    let mut records = Vec::new();
    for group in planned.chunk_by(|p, q| p.unit.path == q.unit.path) {
        let g: Vec<_> = group
            .iter()
            .map(|p| (p.unit.clone(), p.previous.clone()))
            .collect();
        let done = units::write_units(&g, &w(b.path()), &grouped).unwrap();
        assert_eq!(done.len(), 3);
        assert!(done
            .iter()
            .all(|(r, why)| r.status == Status::Ok && why.is_some()));
        records.extend(done.into_iter().map(|(r, _)| r));
    }
    assert_eq!(grouped.loads.load(Ordering::SeqCst), 4);
    assert_eq!(grouped.units.load(Ordering::SeqCst), 12);
    // the third variant of each input takes the decoded input, the first two borrow it
    assert_eq!(grouped.lasts.load(Ordering::SeqCst), 4);
    units::write_manifest(b.path(), records, Shard::ALL).unwrap();
    assert_eq!(tree(a.path(), true), tree(b.path(), true));

    // Up to date: nothing loaded. One variant's output deleted: one load, one unit.
    std::fs::remove_file(b.path().join("train/meta/a__deep__img_001_v2.json")).unwrap();
    let planned = units::units(&uo).unwrap();
    let again = Fake::new("x");
    for group in planned.chunk_by(|p, q| p.unit.path == q.unit.path) {
        let g: Vec<_> = group
            .iter()
            .map(|p| (p.unit.clone(), p.previous.clone()))
            .collect();
        units::write_units(&g, &w(b.path()), &again).unwrap();
    }
    assert_eq!(
        (
            again.loads.load(Ordering::SeqCst),
            again.units.load(Ordering::SeqCst),
            // the middle variant is the last one computed: it takes the input
            again.lasts.load(Ordering::SeqCst)
        ),
        (1, 1, 1)
    );

    // Units of two inputs in one call are refused.
    let mixed = [
        (planned[0].unit.clone(), None),
        (planned[3].unit.clone(), None),
    ];
    let e = units::write_units(&mixed, &w(b.path()), &again).unwrap_err();
    assert!(e.to_string().contains("group the units by input"), "{e}");
}
