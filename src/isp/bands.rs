//! Bands computed in parallel and nearly in order, for consumers that write them out as
//! they come (the streamed EXR and PNG targets of `synth`).
//!
//! [`in_order`] runs one worker per thread of the current rayon pool; each takes the lowest
//! band nobody has taken yet (a shared counter), so bands finish roughly top to bottom
//! (a plain `into_par_iter` splits the range in halves and finishes them far out of order).
//! A worker does not take band `i` until every band below `i - window` has finished
//! (`window` = 2 x workers + 1), so a consumer that writes bands in order buffers at most
//! `window` of them, whatever the scheduling. Each band is computed on its own: the results
//! do not depend on the thread count or on which worker computed which band.

use crate::error::{Error, Result};
use std::sync::{Condvar, Mutex, MutexGuard, PoisonError};

/// Bands taken beyond the lowest unfinished one, for `workers` workers.
pub(crate) fn window(workers: usize) -> usize {
    2 * workers.max(1) + 1
}

struct State<T> {
    /// Next band to take.
    next: usize,
    /// Bands `0..done` have finished.
    done: usize,
    results: Vec<Option<T>>,
    /// The error of the lowest failed band.
    err: Option<(usize, Error)>,
    /// Take no more bands (an error, or a panic in a worker).
    stop: bool,
}

struct Shared<T> {
    state: Mutex<State<T>>,
    changed: Condvar,
}

impl<T> Shared<T> {
    fn lock(&self) -> MutexGuard<'_, State<T>> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// Sets `stop` (and wakes the waiting workers) if a band's computation unwinds.
struct StopOnUnwind<'a, T> {
    shared: &'a Shared<T>,
    armed: bool,
}

impl<T> Drop for StopOnUnwind<'_, T> {
    fn drop(&mut self) {
        if self.armed {
            self.shared.lock().stop = true;
            self.shared.changed.notify_all();
        }
    }
}

/// `work(band, scratch)` for every band in `0..nb` (see the module documentation), the
/// results in band order; `scratch` is a per-worker buffer. On errors, the error of the
/// lowest band that failed (no new band is started after the first error).
///
/// `work` runs while other workers may wait for its band to finish: it must not wait for
/// other rayon work itself (no `join`, `scope` or parallel iterator inside), or a waiting
/// worker stolen by it could wait for it forever.
pub(crate) fn in_order<T, F>(nb: usize, work: F) -> Result<Vec<T>>
where
    T: Send,
    F: Fn(usize, &mut Vec<f32>) -> Result<T> + Sync,
{
    let workers = rayon::current_num_threads().clamp(1, nb.max(1));
    let window = window(workers);
    let shared = Shared {
        state: Mutex::new(State {
            next: 0,
            done: 0,
            results: (0..nb).map(|_| None).collect(),
            err: None,
            stop: false,
        }),
        changed: Condvar::new(),
    };
    let worker = || {
        let mut scratch = Vec::new();
        loop {
            let bi = {
                let mut st = shared.lock();
                loop {
                    if st.stop || st.next >= nb {
                        return;
                    }
                    if st.next < st.done + window {
                        break;
                    }
                    st = shared
                        .changed
                        .wait(st)
                        .unwrap_or_else(PoisonError::into_inner);
                }
                st.next += 1;
                st.next - 1
            };
            let mut guard = StopOnUnwind {
                shared: &shared,
                armed: true,
            };
            let r = work(bi, &mut scratch);
            guard.armed = false;
            let mut st = shared.lock();
            match r {
                Ok(t) => {
                    st.results[bi] = Some(t);
                    while st.done < nb && st.results[st.done].is_some() {
                        st.done += 1;
                    }
                }
                Err(e) => {
                    if st.err.as_ref().is_none_or(|(i, _)| bi < *i) {
                        st.err = Some((bi, e));
                    }
                    st.stop = true;
                }
            }
            drop(st);
            shared.changed.notify_all();
        }
    };
    if workers == 1 {
        worker();
    } else {
        rayon::scope(|s| {
            for _ in 0..workers {
                s.spawn(|_| worker());
            }
        });
    }
    let st = shared
        .state
        .into_inner()
        .unwrap_or_else(PoisonError::into_inner);
    if let Some((_, e)) = st.err {
        return Err(e);
    }
    st.results
        .into_iter()
        .map(|r| r.ok_or_else(|| Error::invalid("a band of the render was not computed")))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    }

    #[test]
    fn results_are_in_band_order_for_any_thread_count() {
        for threads in [1, 2, 3, 8] {
            for nb in [0, 1, 2, 7, 100] {
                let got = pool(threads)
                    .install(|| in_order(nb, |bi, scratch| Ok((bi, scratch.len()))))
                    .unwrap();
                let want: Vec<(usize, usize)> = (0..nb).map(|i| (i, 0)).collect();
                assert_eq!(got, want, "{threads} threads, {nb} bands");
            }
        }
    }

    #[test]
    fn bands_in_flight_stay_within_the_window() {
        // Band 0 is slow: the other workers may run ahead by the window only.
        for threads in [2, 4] {
            let max_ahead = AtomicUsize::new(0);
            let done0 = AtomicUsize::new(0);
            pool(threads)
                .install(|| {
                    in_order(60, |bi, _| {
                        if bi == 0 {
                            std::thread::sleep(std::time::Duration::from_millis(50));
                            done0.store(1, Ordering::SeqCst);
                        } else if done0.load(Ordering::SeqCst) == 0 {
                            max_ahead.fetch_max(bi, Ordering::SeqCst);
                        }
                        Ok(())
                    })
                })
                .unwrap();
            let ahead = max_ahead.load(Ordering::SeqCst);
            assert!(ahead < window(threads), "{threads} threads: band {ahead}");
        }
    }

    #[test]
    fn the_lowest_failing_band_is_reported_and_later_ones_do_not_start() {
        for threads in [1, 2, 4] {
            let started = AtomicUsize::new(0);
            let e = pool(threads)
                .install(|| {
                    in_order(1000, |bi, _| {
                        started.fetch_add(1, Ordering::SeqCst);
                        if bi == 5 || bi == 9 {
                            return Err(Error::invalid(format!("band {bi}")));
                        }
                        Ok(bi)
                    })
                })
                .unwrap_err();
            assert_eq!(e.to_string(), "invalid parameter: band 5", "{threads}");
            assert!(started.load(Ordering::SeqCst) < 5 + 2 * window(threads));
        }
    }

    #[test]
    fn a_panicking_band_does_not_hang_the_others() {
        let r = std::panic::catch_unwind(|| {
            pool(3).install(|| {
                in_order(100, |bi, _| {
                    if bi == 2 {
                        panic!("band 2");
                    }
                    Ok(bi)
                })
            })
        });
        assert!(r.is_err());
    }
}
