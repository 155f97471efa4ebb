//! Tests of the safe output files (policy, deferred syncs, set locks, interrupt registry).

use super::*;
use crate::error::Error;
use std::fs;
use std::io::Write;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

#[test]
fn refuses_existing_and_inputs_and_cleans_up() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.bin");
    let pol = OutputPolicy::default();
    write_bytes_atomic(&p, &pol, b"one").unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"one");
    let err = write_bytes_atomic(&p, &pol, b"two").unwrap_err();
    assert!(err.to_string().contains("--overwrite"), "{err}");
    let pol2 = OutputPolicy {
        overwrite: true,
        inputs: vec![p.clone()],
        ..OutputPolicy::default()
    };
    assert!(write_bytes_atomic(&p, &pol2, b"two").is_err());
    let pol3 = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };
    write_bytes_atomic(&p, &pol3, b"two").unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"two");
    // A failing fill leaves nothing behind.
    let q = dir.path().join("b.bin");
    let r = write_atomic(&q, &pol, |w| {
        w.write_all(b"partial")?;
        Err(Error::invalid("boom"))
    });
    assert!(r.is_err());
    assert!(!q.exists());
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
}

fn tmp_files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    v.sort();
    v
}

#[test]
fn deferred_outputs_appear_on_finish_only() {
    let dir = tempfile::tempdir().unwrap();
    let queue = Arc::new(DeferredSyncs::default());
    let base = OutputPolicy::default();
    let pol = base.deferring(&queue);
    let (a, b) = (dir.path().join("a.bin"), dir.path().join("b.bin"));
    write_bytes_atomic(&a, &pol, b"one").unwrap();
    write_bytes_atomic(&b, &pol, b"two").unwrap();
    assert!(!a.exists() && !b.exists());
    assert_eq!(tmp_files(dir.path()).len(), 2);
    queue.finish(&base).unwrap();
    assert_eq!(fs::read(&a).unwrap(), b"one");
    assert_eq!(fs::read(&b).unwrap(), b"two");
    assert!(tmp_files(dir.path()).is_empty());
    // the queue is empty again: finishing twice is harmless
    queue.finish(&base).unwrap();
    // a failing fill under deferral leaves nothing and queues nothing
    let c = dir.path().join("c.bin");
    let r = write_atomic(&c, &pol, |w| {
        w.write_all(b"partial")?;
        Err(Error::invalid("boom"))
    });
    assert!(r.is_err() && !c.exists());
    assert!(tmp_files(dir.path()).is_empty());
    queue.finish(&base).unwrap();
}

#[test]
fn dropped_queue_removes_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("a.bin");
    {
        let queue = Arc::new(DeferredSyncs::default());
        let pol = OutputPolicy::default().deferring(&queue);
        write_bytes_atomic(&p, &pol, b"one").unwrap();
        assert_eq!(tmp_files(dir.path()).len(), 1);
    }
    assert!(!p.exists());
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn finish_rechecks_the_policy_and_cleans_up() {
    let dir = tempfile::tempdir().unwrap();
    let queue = Arc::new(DeferredSyncs::default());
    let base = OutputPolicy::default();
    let pol = base.deferring(&queue);
    let (a, b, c) = (
        dir.path().join("a.bin"),
        dir.path().join("b.bin"),
        dir.path().join("c.bin"),
    );
    for p in [&a, &b, &c] {
        write_bytes_atomic(p, &pol, b"new").unwrap();
    }
    // another writer creates b meanwhile: a is renamed, b refused, c removed
    fs::write(&b, b"theirs").unwrap();
    let err = queue.finish(&base).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("b.bin") && msg.contains("--overwrite"),
        "{msg}"
    );
    assert_eq!(fs::read(&a).unwrap(), b"new");
    assert_eq!(fs::read(&b).unwrap(), b"theirs");
    assert!(!c.exists());
    assert!(tmp_files(dir.path()).is_empty());
}

#[test]
fn atomic_file_across_calls_seeks_and_cleans_up() {
    use std::io::{Seek, SeekFrom};
    let dir = tempfile::tempdir().unwrap();
    let pol = OutputPolicy::default();
    let p = dir.path().join("a.bin");
    let mut f = AtomicFile::create(&p, &pol).unwrap();
    f.writer().unwrap().write_all(b"0000tail").unwrap();
    f.writer().unwrap().seek(SeekFrom::Start(0)).unwrap();
    f.writer().unwrap().write_all(b"head").unwrap();
    assert!(!p.exists());
    assert_eq!(tmp_files(dir.path()).len(), 1);
    f.finish().unwrap();
    assert_eq!(fs::read(&p).unwrap(), b"headtail");
    assert!(tmp_files(dir.path()).is_empty());
    // the policy is checked at creation
    assert!(AtomicFile::create(&p, &pol).is_err());
    // dropped unfinished: nothing appears, the temporary file goes
    let q = dir.path().join("b.bin");
    let mut f = AtomicFile::create(&q, &pol).unwrap();
    f.writer().unwrap().write_all(&[7; 3 << 20]).unwrap();
    drop(f);
    assert!(!q.exists() && tmp_files(dir.path()).is_empty());
    // deferred: appears on the queue's finish only; a dropped queue removes it
    let queue = Arc::new(DeferredSyncs::default());
    let dpol = pol.deferring(&queue);
    let mut f = AtomicFile::create(&q, &dpol).unwrap();
    f.writer().unwrap().write_all(b"late").unwrap();
    f.finish().unwrap();
    assert!(!q.exists());
    queue.finish(&pol).unwrap();
    assert_eq!(fs::read(&q).unwrap(), b"late");
    let r = dir.path().join("c.bin");
    {
        let queue = Arc::new(DeferredSyncs::default());
        let dpol = pol.deferring(&queue);
        let mut f = AtomicFile::create(&r, &dpol).unwrap();
        f.writer().unwrap().write_all(b"x").unwrap();
        f.finish().unwrap();
    }
    assert!(!r.exists() && tmp_files(dir.path()).is_empty());
}

#[test]
fn set_lock_excludes_a_second_holder_and_is_removed_on_release() {
    let dir = tempfile::tempdir().unwrap();
    let a = OutputSetLock::acquire(dir.path(), "day", false).unwrap();
    assert!(a.path().ends_with(".day.lock") && a.path().exists());
    // A second open file description (as another process would have) is refused...
    let err = OutputSetLock::acquire(dir.path(), "day", false).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("output set day_* is being written by another day2night process"),
        "{msg}"
    );
    assert!(matches!(err.root(), Error::Busy(_)));
    // ...while another set is independent.
    let b = OutputSetLock::acquire(dir.path(), "day_v2", false).unwrap();
    drop(a);
    #[cfg(unix)]
    assert!(!dir.path().join(".day.lock").exists());
    let again = OutputSetLock::acquire(dir.path(), "day", false).unwrap();
    drop((again, b));
    #[cfg(unix)]
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn set_lock_waiters_take_turns() {
    use std::sync::atomic::AtomicUsize;
    let dir = tempfile::tempdir().unwrap();
    let inside = AtomicUsize::new(0);
    let max_inside = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                for _ in 0..25 {
                    let _g = OutputSetLock::acquire(dir.path(), "x", true).unwrap();
                    let n = inside.fetch_add(1, Ordering::SeqCst) + 1;
                    max_inside.fetch_max(n, Ordering::SeqCst);
                    std::thread::yield_now();
                    inside.fetch_sub(1, Ordering::SeqCst);
                }
            });
        }
    });
    assert_eq!(max_inside.load(Ordering::SeqCst), 1);
    #[cfg(unix)]
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn closed_registry_removes_live_files_and_refuses_new_ones() {
    let dir = tempfile::tempdir().unwrap();
    let reg = TempRegistry::new();
    let (t1, t2) = (dir.path().join(".a.tmp-1"), dir.path().join(".b.tmp-1"));
    let mut f = reg.create(&t1).unwrap();
    f.write_all(b"x").unwrap();
    reg.create(&t2).unwrap();
    assert_eq!(reg.live(), [t1.clone(), t2.clone()]);
    // one committed: no longer live
    let out = dir.path().join("b.bin");
    reg.commit_all(vec![(t2.clone(), out.clone())], |_| Ok(()))
        .unwrap();
    assert_eq!(reg.live(), std::slice::from_ref(&t1));
    assert_eq!(reg.close_and_remove(), 1);
    assert!(!t1.exists() && out.exists());
    assert!(matches!(
        reg.create(&dir.path().join(".c.tmp-1")),
        Err(Error::Interrupted)
    ));
    assert!(!dir.path().join(".c.tmp-1").exists());
    // a rename after the close is refused and its file removed
    let t3 = dir.path().join(".d.tmp-1");
    fs::write(&t3, b"late").unwrap();
    let err = reg
        .commit_all(vec![(t3.clone(), dir.path().join("d.bin"))], |_| Ok(()))
        .unwrap_err();
    assert!(matches!(err.root(), Error::Interrupted), "{err}");
    assert!(!t3.exists() && !dir.path().join("d.bin").exists());
}

#[test]
fn close_waits_for_an_open_set_until_it_completes() {
    let dir = tempfile::tempdir().unwrap();
    let reg = Arc::new(TempRegistry::new());
    reg.open_set().unwrap();
    let side = dir.path().join("s.json");
    let (tmp, side2, reg2) = (dir.path().join(".s.json.tmp-1"), side.clone(), reg.clone());
    // The set's last file (its sidecar) is written only once the close is waiting.
    let (go, started) = std::sync::mpsc::channel::<()>();
    let mut writer = Some(std::thread::spawn(move || {
        started.recv().unwrap();
        reg2.create(&tmp).unwrap();
        reg2.commit_all(vec![(tmp, side2)], |_| Ok(())).unwrap();
        reg2.close_set();
    }));
    let mut waits = 0;
    reg.close_and_remove_after(|| {
        waits += 1;
        if let Some(w) = writer.take() {
            go.send(()).unwrap();
            // the registry stayed open for the set: its file was created and renamed
            w.join().unwrap();
        }
        true
    });
    assert_eq!(waits, 1);
    assert!(side.exists());
    // then the close refuses new sets and files
    assert!(matches!(reg.open_set(), Err(Error::Interrupted)));
}

#[test]
fn close_stops_waiting_for_a_set_that_never_completes() {
    let dir = tempfile::tempdir().unwrap();
    let reg = TempRegistry::new();
    reg.open_set().unwrap();
    let t = dir.path().join(".a.tmp-1");
    reg.create(&t).unwrap();
    let mut waits = 0;
    let removed = reg.close_and_remove_after(|| {
        waits += 1;
        waits < 3
    });
    assert_eq!((waits, removed), (3, 1));
    assert!(!t.exists());
    assert!(matches!(
        reg.create(&dir.path().join(".b.tmp-1")),
        Err(Error::Interrupted)
    ));
    // the grace as a clock: none at all does not wait for the open set
    let reg = TempRegistry::new();
    reg.open_set().unwrap();
    assert_eq!(reg.close_and_remove_within(Duration::ZERO), 0);
    assert!(matches!(reg.open_set(), Err(Error::Interrupted)));
}
