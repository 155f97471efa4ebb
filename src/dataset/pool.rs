//! The worker pool and stop loop of `dataset` and `real-pairs`: `jobs` threads each take the
//! next item only when they have finished the previous one (at most `jobs` items in
//! flight, so at most `jobs` images in memory), and none takes a new item once a stop has
//! been requested ([`crate::output::request_stop`]).

use crate::error::{Error, Result};
use crate::output::stop_requested;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Run `work` once per item of `items` on `jobs` (>= 1) threads named `<name>-<i>`, in the
/// order of `items` (each worker takes the lowest item not yet taken). A worker stops
/// when a stop is requested or when `work` returns [`ControlFlow::Break`]; the others
/// go on until they see the stop themselves. Returns when every worker has stopped;
/// the caller checks [`stop_requested`] for an interrupted run.
pub fn for_each<T, F>(items: &[T], jobs: usize, name: &'static str, work: F) -> Result<()>
where
    T: Sync,
    F: Fn(&T) -> ControlFlow<()> + Sync,
{
    let jobs = jobs.max(1);
    let next = AtomicUsize::new(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .thread_name(move |i| format!("{name}-{i}"))
        .build()
        .map_err(|e| Error::invalid(format!("cannot start {jobs} worker threads: {e}")))?;
    pool.scope(|s| {
        for _ in 0..jobs {
            s.spawn(|_| loop {
                // Interrupted: start no new item (see crate::output::request_stop).
                if stop_requested().is_some() {
                    break;
                }
                let i = next.fetch_add(1, Ordering::SeqCst);
                let Some(item) = items.get(i) else { break };
                if work(item).is_break() {
                    break;
                }
            });
        }
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn every_item_once_on_any_number_of_workers() {
        let items: Vec<usize> = (0..37).collect();
        for jobs in [0, 1, 3, 64] {
            let seen = Mutex::new(Vec::new());
            for_each(&items, jobs, "test", |&i| {
                seen.lock().unwrap().push(i);
                ControlFlow::Continue(())
            })
            .unwrap();
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable();
            assert_eq!(seen, items, "jobs {jobs}");
        }
    }

    #[test]
    fn a_break_stops_that_worker() {
        let items: Vec<usize> = (0..10).collect();
        let seen = Mutex::new(Vec::new());
        for_each(&items, 1, "test", |&i| {
            seen.lock().unwrap().push(i);
            if i == 4 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .unwrap();
        assert_eq!(seen.into_inner().unwrap(), [0, 1, 2, 3, 4]);
    }
}
