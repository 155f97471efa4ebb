//! The banded warps of OpcodeList3: the image before each warp is made in strips of lines
//! (rows, or columns for the transposing orientations 5-8, whose bands are columns) on
//! demand, and a strip is dropped once no later band reaches it. So the render holds a
//! rolling window of source lines instead of the whole image (docs/isp.md, "DNG opcodes").
//!
//! * A chain of levels: level 0 is the image before the first warp (made by the caller's
//!   `pre`), level `j` the image after warp `j - 1` and the in-place opcodes that follow it
//!   (`after`). The output bands are warped by the last warp from the last level.
//! * Planning, before any pixel: the lines of a level that each band (or strip of the next
//!   level) reaches come from the warp's bounds (`super::warp_bounds::window`), so every
//!   strip knows how many readers it has; a strip is computed by the first reader that
//!   needs it and dropped when the last one has read it. Strips no reader reaches are never
//!   computed.
//! * The same planning simulates the bands in order and counts the lines held at once. Past
//!   `limit` (a pathological warp, whose bands reach far across the image, or fold it), or
//!   with more than `MAX_WARPS` warps, the chain falls back to the whole-image path: each
//!   level is made whole, in parallel, from the whole level below, which is then dropped
//!   (12 bytes per pixel for the image before the last warp, 24 while a level is made, as
//!   the whole-frame warps).
//!
//! Each strip is made by the same expressions whatever the strip height, and each band's
//! exact window (`super::warp::plan`) decides what it reads, so the output equals the
//! whole-frame warp bit for bit. A reader that reaches a strip outside its planned bound
//! (never seen; the bound is proved by a property test) gets it computed again, unshared.

use super::warp::{plan, resample_plan, Src, Warp};
use super::warp_bounds::window;
use super::StageRect;
use crate::error::{Error, Result};
use crate::limits::try_filled;
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};

/// The lines (rows, or columns) a window may hold at once before the chain falls back to
/// the whole-image path: an eighth of the image's lines, at least 256 (1.5 bytes per pixel
/// of the active area at most, at 12 bytes per line pixel, but on small images).
pub(crate) fn limit(lines: usize) -> usize {
    (lines / 8).max(256)
}

#[cfg(test)]
thread_local! {
    /// Chains made on this thread plan with too narrow a bound (tests).
    static NARROW: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The most warps a chain runs through windows (each level's strip is made by a reader of
/// the level above, so the depth of the calls grows with the warps); more take the
/// whole-image path.
pub(crate) const MAX_WARPS: usize = 8;

/// The direction the image is cut in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Axis {
    /// Strips of whole rows (orientations 1-4), stored row by row.
    Rows,
    /// Strips of whole columns (orientations 5-8), stored column by column.
    Cols,
}

enum Data {
    Empty,
    Busy,
    Ready(Arc<Vec<f32>>),
    Gone,
}

struct SlotState {
    /// Planned readers not yet done.
    users: usize,
    data: Data,
}

struct Slot {
    st: Mutex<SlotState>,
    changed: Condvar,
}

impl Slot {
    fn lock(&self) -> MutexGuard<'_, SlotState> {
        self.st.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// Puts a slot back to `Empty` (and wakes its waiters) if the computation unwinds.
struct EmptyOnUnwind<'a> {
    slot: &'a Slot,
    armed: bool,
}

impl Drop for EmptyOnUnwind<'_> {
    fn drop(&mut self) {
        if self.armed {
            self.slot.lock().data = Data::Empty;
            self.slot.changed.notify_all();
        }
    }
}

/// The image before the first warp over a rectangle (rows, columns): interleaved RGB, row
/// by row.
pub(crate) type PreFn<'a> = dyn Fn(Range<usize>, Range<usize>) -> Result<Vec<f32>> + Sync + 'a;

/// The in-place opcodes after warp `j` on a rectangle: `(j, data, rows, columns)`.
pub(crate) type AfterFn<'a> = dyn Fn(usize, &mut [f32], Range<usize>, Range<usize>) + Sync + 'a;

/// What the window did (tests, benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WindowStats {
    /// The planning found the window too wide: the whole-image path ran.
    pub fallback: bool,
    /// The most lines the planning expects to be held at once (all levels).
    pub planned_lines: usize,
    /// The most lines held at once in the run (all levels).
    pub peak_lines: usize,
    /// The lines of the image along the cut (rows or columns).
    pub lines: usize,
}

/// How a [`Chain`] cuts its image: an active area of `dims` (stage image `extent`) cut along
/// `axis` in strips of `lines` lines.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Strips {
    /// The direction of the cut.
    pub(crate) axis: Axis,
    /// Active-area width and height.
    pub(crate) dims: (usize, usize),
    /// Lines per strip.
    pub(crate) lines: usize,
    /// The stage image (relative warp centres refer to it).
    pub(crate) extent: StageRect,
}

/// The warps of OpcodeList3 with their source windows (see the module documentation).
pub(crate) struct Chain<'a> {
    axis: Axis,
    /// Active-area width and height.
    dims: (usize, usize),
    /// Lines per strip.
    sb: usize,
    extent: StageRect,
    warps: Vec<Warp>,
    pre: &'a PreFn<'a>,
    after: &'a AfterFn<'a>,
    /// Per level, per strip.
    levels: Vec<Vec<Slot>>,
    keep: bool,
    #[cfg(test)]
    narrow: bool,
    live: AtomicUsize,
    peak: AtomicUsize,
    planned: usize,
}

/// `range` of lines as the strips of `sb` lines that hold it.
fn strips_of(range: &Range<usize>, sb: usize) -> Range<usize> {
    if range.is_empty() {
        0..0
    } else {
        range.start / sb..(range.end - 1) / sb + 1
    }
}

impl<'a> Chain<'a> {
    /// The chain of `warps` over the image `strips` cuts. `pre(rows, cols)`: the image before the first warp
    /// over a rectangle (interleaved RGB, row by row); `after(j, data, rows, cols)`: the
    /// in-place opcodes after warp `j` on a rectangle. `finals`: the rectangle of every
    /// output band, in the order they are made; `limit`: the lines held at once past which
    /// the whole-image path runs (default [`limit`]).
    pub(crate) fn new(
        strips: Strips,
        warps: Vec<Warp>,
        pre: &'a PreFn<'a>,
        after: &'a AfterFn<'a>,
        finals: &[(Range<usize>, Range<usize>)],
        limit_lines: Option<usize>,
    ) -> Result<Chain<'a>> {
        if warps.is_empty() {
            return Err(Error::invalid("a warp chain without a warp"));
        }
        let Strips {
            axis,
            dims,
            lines: sb,
            extent,
        } = strips;
        let sb = sb.max(1);
        let mut c = Chain {
            axis,
            dims,
            sb,
            extent,
            warps,
            pre,
            after,
            levels: Vec::new(),
            keep: false,
            #[cfg(test)]
            narrow: NARROW.with(|n| n.get()),
            live: AtomicUsize::new(0),
            peak: AtomicUsize::new(0),
            planned: 0,
        };
        let n = c.lines().div_ceil(sb);
        let nl = c.warps.len();
        // Readers and first/last time of use of every strip, top level down (none past
        // MAX_WARPS warps: the whole-image path runs anyway, unplanned).
        let planned_finals = if nl > MAX_WARPS { &finals[..0] } else { finals };
        let mut users = vec![vec![0usize; n]; nl];
        let mut when = vec![vec![(usize::MAX, 0usize); n]; nl];
        let note = |users: &mut [usize], when: &mut [(usize, usize)], ks: Range<usize>, t| {
            for k in ks {
                users[k] += 1;
                when[k] = (when[k].0.min(t), when[k].1.max(t));
            }
        };
        for (t, (rows, cols)) in planned_finals.iter().enumerate() {
            let ks = c.need(nl - 1, rows, cols);
            note(&mut users[nl - 1], &mut when[nl - 1], ks, t);
        }
        for j in (1..nl).rev() {
            for k in 0..n {
                if users[j][k] > 0 {
                    let (rows, cols) = c.strip(k);
                    let (t, ks) = (when[j][k].0, c.need(j - 1, &rows, &cols));
                    note(&mut users[j - 1], &mut when[j - 1], ks, t);
                }
            }
        }
        // Lines held at once, bands made in order.
        let mut delta = vec![0i64; finals.len() + 1];
        for j in 0..nl {
            for k in 0..n {
                if users[j][k] > 0 {
                    let len = c.strip_len(k) as i64;
                    delta[when[j][k].0] += len;
                    delta[when[j][k].1 + 1] -= len;
                }
            }
        }
        let mut held = 0i64;
        for d in &delta {
            held += d;
            c.planned = c.planned.max(held.max(0) as usize);
        }
        c.keep = c.planned > limit_lines.unwrap_or_else(|| limit(c.lines())) || nl > MAX_WARPS;
        c.levels = users
            .into_iter()
            .map(|u| {
                u.into_iter()
                    .map(|users| Slot {
                        st: Mutex::new(SlotState {
                            users,
                            data: Data::Empty,
                        }),
                        changed: Condvar::new(),
                    })
                    .collect()
            })
            .collect();
        if c.keep {
            // The whole-image path: each level made whole in parallel from the one before,
            // which is then dropped (two whole images at a time, as the whole-frame warps).
            for j in 0..nl {
                (0..n)
                    .into_par_iter()
                    .try_for_each(|k| c.get(j, k..k + 1).map(drop))?;
                if j > 0 {
                    c.drop_level(j - 1);
                }
            }
        }
        Ok(c)
    }

    /// What the window did so far.
    pub(crate) fn stats(&self) -> WindowStats {
        WindowStats {
            fallback: self.keep,
            planned_lines: self.planned,
            peak_lines: self.peak.load(Ordering::Relaxed),
            lines: self.lines(),
        }
    }

    fn lines(&self) -> usize {
        match self.axis {
            Axis::Rows => self.dims.1,
            Axis::Cols => self.dims.0,
        }
    }

    fn strip_len(&self, k: usize) -> usize {
        (self.lines() - k * self.sb).min(self.sb)
    }

    /// The rectangle (rows, columns) of strip `k`.
    fn strip(&self, k: usize) -> (Range<usize>, Range<usize>) {
        let (w, h) = self.dims;
        let along = k * self.sb..k * self.sb + self.strip_len(k);
        match self.axis {
            Axis::Rows => (along, 0..w),
            Axis::Cols => (0..h, along),
        }
    }

    /// The strips of level `j` that warp `j` may read for the destination rectangle.
    fn need(&self, j: usize, rows: &Range<usize>, cols: &Range<usize>) -> Range<usize> {
        let (r, c) = window(
            &self.warps[j],
            self.extent,
            self.dims,
            rows.clone(),
            cols.clone(),
        );
        let ks = strips_of(
            match self.axis {
                Axis::Rows => &r,
                Axis::Cols => &c,
            },
            self.sb,
        );
        #[cfg(test)]
        if self.narrow {
            // A bound that misses the window (tests of the unplanned reads).
            return ks.start..ks.start + ks.len() / 2;
        }
        ks
    }

    /// Strip `k` of level `j`; `planned`: computed for the planned readers (its own reads
    /// of the level below are then planned too).
    fn make(&self, j: usize, k: usize, planned: bool) -> Result<Vec<f32>> {
        let (rows, cols) = self.strip(k);
        let rgb = if j == 0 {
            (self.pre)(rows.clone(), cols.clone())?
        } else {
            let mut out = self.warp(j - 1, &rows, &cols)?;
            if planned {
                self.release(j - 1, self.need(j - 1, &rows, &cols));
            }
            (self.after)(j - 1, &mut out, rows.clone(), cols.clone());
            out
        };
        Ok(match self.axis {
            Axis::Rows => rgb,
            Axis::Cols => {
                // Stored column by column.
                let (rw, rh) = (cols.len(), rows.len());
                let mut t = try_filled(0.0f32, rgb.len(), "a strip of the image before a warp")?;
                for (y, row) in rgb.chunks_exact(3 * rw.max(1)).enumerate() {
                    for (x, px) in row.chunks_exact(3).enumerate() {
                        t[3 * (x * rh + y)..][..3].copy_from_slice(px);
                    }
                }
                t
            }
        })
    }

    /// The destination rectangle of warp `j` (interleaved RGB, row by row), read from the
    /// strips of level `j` its exact window reaches.
    fn warp(&self, j: usize, rows: &Range<usize>, cols: &Range<usize>) -> Result<Vec<f32>> {
        let (w, h) = self.dims;
        let dims = (w, h, 3);
        let p = plan(
            &self.warps[j],
            dims,
            self.extent,
            rows.clone(),
            cols.clone(),
        );
        let ks = strips_of(
            match self.axis {
                Axis::Rows => &p.win_rows,
                Axis::Cols => &p.win_cols,
            },
            self.sb,
        );
        let held = self.get(j, ks.clone())?;
        let first = ks.start * self.sb;
        let src = match self.axis {
            Axis::Rows => Src::Rows {
                first,
                rows: held.iter().flat_map(|s| s.chunks_exact(3 * w)).collect(),
            },
            Axis::Cols => Src::Cols {
                first,
                cols: held.iter().flat_map(|s| s.chunks_exact(3 * h)).collect(),
            },
        };
        let mut out = try_filled(0.0f32, 3 * rows.len() * cols.len(), "a band of the warp")?;
        resample_plan(&p, dims, self.extent, &src, &mut out);
        Ok(out)
    }

    /// The output rectangle `rows x cols`: the last warp and the in-place opcodes after it
    /// (interleaved RGB, row by row).
    pub(crate) fn render(&self, rows: Range<usize>, cols: Range<usize>) -> Result<Vec<f32>> {
        let last = self.warps.len() - 1;
        let mut out = self.warp(last, &rows, &cols)?;
        self.release(last, self.need(last, &rows, &cols));
        (self.after)(last, &mut out, rows, cols);
        Ok(out)
    }

    /// Every strip of level `j` let go (the whole-image path, once the next level is whole).
    fn drop_level(&self, j: usize) {
        for (k, slot) in self.levels[j].iter().enumerate() {
            let mut st = slot.lock();
            if let Data::Ready(_) = st.data {
                self.live.fetch_sub(self.strip_len(k), Ordering::Relaxed);
            }
            st.data = Data::Gone;
        }
    }

    /// One planned reader of strips `ks` of level `j` is done with them. A strip whose
    /// readers are all done before it was ever computed lets go of its own reads of the
    /// level below.
    fn release(&self, j: usize, ks: Range<usize>) {
        if self.keep {
            return;
        }
        for k in ks {
            let slot = &self.levels[j][k];
            let mut st = slot.lock();
            if st.users == 0 {
                continue;
            }
            st.users -= 1;
            if st.users > 0 {
                continue;
            }
            match st.data {
                Data::Busy => {} // its maker sees no reader left and drops it
                Data::Ready(_) => {
                    self.live.fetch_sub(self.strip_len(k), Ordering::Relaxed);
                    st.data = Data::Gone;
                }
                Data::Gone => {}
                Data::Empty => {
                    st.data = Data::Gone;
                    drop(st);
                    if j > 0 {
                        let (rows, cols) = self.strip(k);
                        self.release(j - 1, self.need(j - 1, &rows, &cols));
                    }
                }
            }
        }
    }

    /// Strips `ks` of level `j`, computing those nobody has (the free ones first, then
    /// waiting for those another thread is computing).
    fn get(&self, j: usize, ks: Range<usize>) -> Result<Vec<Arc<Vec<f32>>>> {
        let mut got: Vec<Option<Arc<Vec<f32>>>> = vec![None; ks.len()];
        loop {
            let mut waiting = None;
            let mut progress = false;
            for (i, k) in ks.clone().enumerate() {
                if got[i].is_some() {
                    continue;
                }
                let slot = &self.levels[j][k];
                let mut st = slot.lock();
                match &st.data {
                    Data::Ready(a) => {
                        got[i] = Some(a.clone());
                        progress = true;
                    }
                    Data::Busy => {
                        waiting.get_or_insert(k);
                    }
                    Data::Empty | Data::Gone => {
                        let planned = matches!(st.data, Data::Empty) && (self.keep || st.users > 0);
                        if planned {
                            st.data = Data::Busy;
                        }
                        drop(st);
                        let mut guard = EmptyOnUnwind {
                            slot,
                            armed: planned,
                        };
                        let r = self.make(j, k, planned);
                        guard.armed = false;
                        let a = match r {
                            Ok(v) => Arc::new(v),
                            Err(e) => {
                                if planned {
                                    slot.lock().data = Data::Empty;
                                    slot.changed.notify_all();
                                }
                                return Err(e);
                            }
                        };
                        if planned {
                            let mut st = slot.lock();
                            if self.keep || st.users > 0 {
                                st.data = Data::Ready(a.clone());
                                let live =
                                    self.live.fetch_add(self.strip_len(k), Ordering::Relaxed);
                                self.peak
                                    .fetch_max(live + self.strip_len(k), Ordering::Relaxed);
                            } else {
                                st.data = Data::Gone;
                            }
                            drop(st);
                            slot.changed.notify_all();
                        }
                        got[i] = Some(a);
                        progress = true;
                    }
                }
            }
            if got.iter().all(Option::is_some) {
                return Ok(got.into_iter().flatten().collect());
            }
            if !progress {
                if let Some(k) = waiting {
                    let slot = &self.levels[j][k];
                    let mut st = slot.lock();
                    while matches!(st.data, Data::Busy) {
                        st = slot
                            .changed
                            .wait(st)
                            .unwrap_or_else(PoisonError::into_inner);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::warp::{apply, Model};
    use super::*;

    fn image(w: usize, h: usize) -> Vec<f32> {
        (0..3 * w * h)
            .map(|i| ((i * 7919 + 13) % 1009) as f32 / 1008.0)
            .collect()
    }

    fn warps(b: StageRect) -> Vec<Warp> {
        let rect = Model::Rectilinear {
            kr: [1.0, -0.15, 0.03, 0.0],
            kt: [0.004, -0.003],
        };
        let fish = |k0| Model::Fisheye {
            kr: [k0, 0.08, 0.0, 0.0],
        };
        vec![
            Warp::new(vec![rect], [0.4, 0.6], b, 3).unwrap(),
            Warp::new(vec![fish(1.0), fish(1.03), fish(0.97)], [0.5, 0.5], b, 3).unwrap(),
        ]
    }

    /// The chain's bands of `band` lines, made in `order` (on a pool of `threads`), against
    /// the whole warps; the strips all dropped at the end.
    fn run(axis: Axis, sb: usize, nw: usize, order: &[usize], threads: usize, band: usize) {
        let (w, h) = (23, 41);
        let b = StageRect::of_size(w, h);
        let data = image(w, h);
        let ws = warps(b)[..nw].to_vec();
        let mut whole = data.clone();
        for (j, warp) in ws.iter().enumerate() {
            whole = apply(warp, &whole, w, h, 3, b);
            whole
                .iter_mut()
                .for_each(|v| *v = v.mul_add(0.5, 0.1 * j as f32));
        }
        let pre = |rows: Range<usize>, cols: Range<usize>| -> Result<Vec<f32>> {
            let mut out = Vec::new();
            for r in rows {
                out.extend_from_slice(&data[3 * (r * w + cols.start)..3 * (r * w + cols.end)]);
            }
            Ok(out)
        };
        let after = |j: usize, d: &mut [f32], _: Range<usize>, _: Range<usize>| {
            d.iter_mut()
                .for_each(|v| *v = v.mul_add(0.5, 0.1 * j as f32));
        };
        let lines = if axis == Axis::Rows { h } else { w };
        let rect = |i: usize| {
            let along = i * band..((i + 1) * band).min(lines);
            match axis {
                Axis::Rows => (along, 0..w),
                Axis::Cols => (0..h, along),
            }
        };
        let finals: Vec<_> = order.iter().map(|&i| rect(i)).collect();
        let strips = Strips {
            axis,
            dims: (w, h),
            lines: sb,
            extent: b,
        };
        let chain = Chain::new(strips, ws, &pre, &after, &finals, Some(usize::MAX)).unwrap();
        let bands: Vec<Vec<f32>> = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                finals
                    .par_iter()
                    .map(|(r, c)| chain.render(r.clone(), c.clone()).unwrap())
                    .collect()
            });
        let what = format!("{axis:?}, strips of {sb}, {nw} warps, {threads} threads");
        for ((rows, cols), got) in finals.iter().zip(&bands) {
            let mut want = Vec::new();
            for r in rows.clone() {
                want.extend_from_slice(&whole[3 * (r * w + cols.start)..3 * (r * w + cols.end)]);
            }
            assert_eq!(got, &want, "{what}: band {rows:?} x {cols:?}");
        }
        let st = chain.stats();
        assert!(!st.fallback && st.peak_lines > 0, "{what}: {st:?}");
        assert_eq!(chain.live.load(Ordering::Relaxed), 0, "{what}: strips left");
        for level in &chain.levels {
            for slot in level {
                let st = slot.lock();
                assert!(matches!(st.data, Data::Gone | Data::Empty), "{what}");
            }
        }
    }

    #[test]
    fn a_chain_equals_the_whole_warps_in_any_band_order() {
        for axis in [Axis::Rows, Axis::Cols] {
            let n = if axis == Axis::Rows { 41usize } else { 23 }.div_ceil(5);
            let forward: Vec<usize> = (0..n).collect();
            let backward: Vec<usize> = (0..n).rev().collect();
            let mixed: Vec<usize> = (0..n).map(|i| (i * 5 + 2) % n).collect();
            for sb in [1, 3, 8, 64] {
                for nw in [1, 2] {
                    for order in [&forward, &backward, &mixed] {
                        for threads in [1, 3] {
                            run(axis, sb, nw, order, threads, 5);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn reads_outside_the_planned_bound_are_computed_again_and_still_match() {
        NARROW.with(|n| n.set(true));
        for axis in [Axis::Rows, Axis::Cols] {
            for nw in [1, 2] {
                let order: Vec<usize> = (0..5).collect();
                run(axis, 4, nw, &order, 1, 5);
            }
        }
        NARROW.with(|n| n.set(false));
    }
}
