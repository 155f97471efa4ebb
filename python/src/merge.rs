//! `merge`: an aligned burst averaged as `day2night merge` and `day2night real-pairs`
//! average one (`day2night::calibrate::merge::Merger`), into a raw in memory.

use crate::convert::json_obj;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::raw::Raw;
use day2night::calibrate::merge::{repeated_frame, MergeReport, Merger};
use day2night::dng::read_dng;
use day2night::error::ResultExt;
use day2night::raw::RawImage;
use day2night::synth::job::DayInput;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

/// The frames' paths: each item through ``os.fsdecode`` (``str``, ``bytes`` or
/// ``os.PathLike``; anything else is its ``TypeError``), refused when one file comes twice.
fn frame_paths(py: Python<'_>, items: &[Bound<'_, PyAny>]) -> PyResult<Vec<PathBuf>> {
    let fsdecode = py.import("os")?.getattr("fsdecode")?;
    let paths = items
        .iter()
        .map(|item| fsdecode.call1((item,))?.extract::<PathBuf>())
        .collect::<PyResult<Vec<PathBuf>>>()?;
    match repeated_frame(&paths) {
        Some(why) => Err(value_err(why)),
        None => Ok(paths),
    }
}

/// Read the frames one at a time and merge them (the command line's `merge`).
fn merge_files(paths: &[PathBuf]) -> day2night::Result<(RawImage, MergeReport)> {
    let first = &paths[0];
    let mut merger = Merger::new(read_dng(first).in_file(first)?).in_file(first)?;
    for p in &paths[1..] {
        let img = read_dng(p).in_file(p)?;
        merger.add(&img).in_file(p)?;
    }
    merger.finish().in_file(first)
}

/// The mean of an aligned burst: the DNGs at ``paths`` (at least 2, read one at a time with
/// the GIL released) merged exactly as ``day2night merge FRAMES -o OUT.dng`` and
/// ``real-pairs``' clean raw merge them: with N frames and ``N * white <= 65535`` the
/// samples are the exact sums and the black and white levels are multiplied by N, else
/// ``round(sum * K / N)`` with ``K = floor(65535 / white)``; a site saturated in any frame is
/// white; NoiseProfile divided by N; the metadata is the first frame's. Frames of another
/// size, ActiveArea, CFA, level or ISO are a ``ValueError`` naming the file.
///
/// ``paths`` is a list (or other sequence) of ``str``, ``bytes`` or ``os.PathLike`` paths
/// (``os.fsdecode`` each). The same file twice (the same path after resolving ``.``, ``..``
/// and links) is a ``ValueError`` naming it: averaging a frame twice weights it double, so
/// duplicates are refused, not dropped.
///
/// Returns ``(raw, report)``: the merged ``Raw`` (in memory, named after the first frame)
/// and the merge's report, the dict ``merge --json`` prints (``frames``, ``scale_factor``,
/// ``exact``, ``white``, ``black``, ``saturated_sites``).
///
/// >>> raw, report = day2night.merge(["f0.dng", "f1.dng", "f2.dng"])
#[pyfunction]
pub(crate) fn merge<'py>(
    py: Python<'py>,
    paths: Vec<Bound<'py, PyAny>>,
) -> PyResult<(Raw, Bound<'py, PyAny>)> {
    let paths = frame_paths(py, &paths)?;
    if paths.len() < 2 {
        return Err(value_err(format!(
            "merge needs at least 2 frames, got {} (a single frame is already its own mean)",
            paths.len()
        )));
    }
    let (img, report) = py
        .detach(|| on_pool(|| merge_files(&paths)))
        .map_err(py_err)?;
    let first = &paths[0];
    let file_name = first
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| first.display().to_string());
    let name = first
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| file_name.clone());
    let day = py.detach(|| DayInput::in_memory(img, &file_name));
    let raw = Raw {
        day: Arc::new(day),
        name,
        file_name,
        from_file: false,
        data: OnceLock::new(),
    };
    Ok((raw, json_obj(py, &report)?))
}
