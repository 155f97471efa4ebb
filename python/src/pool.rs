//! The worker threads computations run on: one rayon pool per Python thread and process
//! (`set_threads`, `threads`).

use crate::args::Threads;
use crate::errors::py_err;
use day2night::Error;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// The worker threads of a Python thread: each Python thread that computes gets its own
/// rayon pool (so two Python threads with `set_threads(1)` compute on two cores at once,
/// instead of queueing on one shared worker), owned by the process that made it. A process
/// forked from one that had already computed (a `DataLoader` worker) inherits the pool's
/// bookkeeping but none of its threads, so a pool is only used in the process that built
/// it; a child builds its own (and forgets the parent's).
struct Pool {
    pid: u32,
    threads: usize,
    pool: Arc<rayon::ThreadPool>,
}

thread_local! {
    static POOL: std::cell::RefCell<Option<Pool>> = const { std::cell::RefCell::new(None) };
}
static THREADS: AtomicUsize = AtomicUsize::new(0);

fn pool() -> Result<Arc<rayon::ThreadPool>, Error> {
    POOL.with(|slot| {
        let mut slot = slot.borrow_mut();
        let want = THREADS.load(Ordering::Relaxed);
        let pid = std::process::id();
        if let Some(p) = slot.as_ref() {
            if p.pid == pid && (want == 0 || want == p.threads) {
                return Ok(p.pool.clone());
            }
        }
        let mut b = rayon::ThreadPoolBuilder::new();
        if want > 0 {
            b = b.num_threads(want);
        }
        let pool = Arc::new(
            b.build()
                .map_err(|e| Error::invalid(format!("cannot start worker threads: {e}")))?,
        );
        if let Some(old) = slot.take() {
            if old.pid != pid {
                // Its threads live in the parent process only: never join or drop them here.
                std::mem::forget(old);
            }
        }
        *slot = Some(Pool {
            pid,
            threads: pool.current_num_threads(),
            pool: pool.clone(),
        });
        Ok(pool)
    })
}

/// Run `f` on the calling thread's worker threads.
pub(crate) fn on_pool<T: Send>(f: impl FnOnce() -> Result<T, Error> + Send) -> Result<T, Error> {
    pool()?.install(f)
}

/// Set the number of worker threads each computation uses: 0 (one per core, the default;
/// the ``RAYON_NUM_THREADS`` environment variable also sets it) to 4096 (``--jobs``'s
/// limit; more is a ``ValueError``). Every Python thread that computes has its own workers:
/// with several ``DataLoader`` workers or Python threads, about cores / workers each avoids
/// oversubscription.
///
/// >>> day2night.set_threads(1)
#[pyfunction]
pub(crate) fn set_threads(n: Threads) {
    THREADS.store(n.0, Ordering::Relaxed);
}

/// The number of worker threads computations of the calling thread use.
#[pyfunction]
pub(crate) fn threads() -> PyResult<usize> {
    Ok(pool().map_err(py_err)?.current_num_threads())
}
