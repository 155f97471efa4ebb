//! `day2night.dataset_units`, `write_unit`, `write_manifest`: the dataset job as units for a
//! scheduler of the user's (Ray Data: python/examples/ray_dataset.py). The library's
//! `day2night::dataset::units` does the work; this file converts Python values (the CLI's
//! option names and values, in snake case) to the library's types and back.

use crate::args::{self, Param, ParamDefault, Seed, Val, Variants, SEED, VARIANTS};
use crate::convert::json_obj;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use crate::synth_options::{self, Scope};
use day2night::dataset::resume::Reason;
use day2night::dataset::synthesis::SynthProcessor;
use day2night::dataset::units::{self as lib, UnitsOptions, WriteOptions};
use day2night::dataset::{Record, Shard, Split, SplitRule, Unit};
use day2night::synth::config::JobConfig;
use day2night::synth::options::Draft;
use day2night::{Error, Warning};
use pyo3::prelude::*;

/// The per-input warnings of a unit's decode (metadata corrections), collected on the worker
/// threads and raised as Python warnings ([`Collected::raise`]) once the call has the GIL
/// again: the library itself prints nothing.
#[derive(Clone, Default)]
struct Collected(Arc<Mutex<Vec<(PathBuf, Warning)>>>);

impl day2night::dataset::Progress for Collected {
    fn warning(&self, path: &std::path::Path, warning: &Warning) {
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner());
        v.push((path.to_path_buf(), warning.clone()));
    }
}

impl Collected {
    /// The run's progress sink, collecting into `self`.
    fn sink(&self) -> day2night::dataset::ProgressSink {
        day2night::dataset::ProgressSink::new(self.clone())
    }

    /// Raise every collected warning, in the order they came, about its input.
    fn raise(&self, py: Python<'_>) -> PyResult<()> {
        let all = std::mem::take(&mut *self.0.lock().unwrap_or_else(|e| e.into_inner()));
        for (path, w) in all {
            crate::diagnostics::warn_lines(py, &path.display().to_string(), &[w])?;
        }
        Ok(())
    }
}
use pyo3::types::{PyDict, PyList, PyTuple};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

fn parse_split_rule(
    val: Option<usize>,
    val_fraction: Option<f64>,
    seed: u64,
) -> PyResult<SplitRule> {
    match (val, val_fraction) {
        (Some(_), Some(_)) => Err(value_err("give val or val_fraction, not both")),
        (Some(n), None) => Ok(SplitRule::LastN(n)),
        (None, Some(f)) => {
            if !(0.0..=1.0).contains(&f) {
                return Err(value_err(format!("val_fraction {f} is not within [0, 1]")));
            }
            Ok(SplitRule::Fraction { fraction: f, seed })
        }
        (None, None) => Ok(SplitRule::AllTrain),
    }
}

fn parse_shard(shard: Option<&str>) -> PyResult<Shard> {
    match shard {
        None => Ok(Shard::ALL),
        Some(s) => Shard::parse(s).map_err(py_err),
    }
}

/// `dataset_units`' parameters after `day_dir`: `out_dir`, then the keyword-only ones,
/// with their defaults (their one spelling).
pub(crate) const PARAMS: &[Param] = &[
    Param::pos("out_dir", ParamDefault::None),
    Param::kw("variants", ParamDefault::Int(1)),
    Param::kw("val", ParamDefault::None),
    Param::kw("val_fraction", ParamDefault::None),
    Param::kw("seed", ParamDefault::Table("seed")),
    Param::kw("shard", ParamDefault::None),
    Param::kw("overwrite", ParamDefault::Bool(false)),
];

/// The (input, split, variant) units ``day2night dataset DAY_DIR -o OUT_DIR`` makes with
/// the same options, in its order, as dicts: ``input`` (path relative to ``day_dir``, the
/// unit's identity), ``path``, ``split`` ("train" | "val"), ``variant`` (1-based),
/// ``variants``, ``seed``, ``id`` (output name) and ``previous`` (the unit's latest
/// manifest record in ``out_dir`` as a JSON string, or None).
///
/// With ``out_dir``, as ``dataset`` does when it starts: the folder is excluded from the
/// search, must be empty, missing or a dataset (unless ``overwrite``), and temporary files a
/// killed run left for these units are removed. ``val``, ``val_fraction``, ``shard``
/// ("I/N") and ``seed`` are the command's flags.
///
/// >>> units = day2night.dataset_units("day/", "night/", variants=2, val=10, seed=1)
#[pyfunction]
#[pyo3(signature = (day_dir, out_dir=None, **kwargs))]
pub fn dataset_units<'py>(
    py: Python<'py>,
    day_dir: PathBuf,
    out_dir: Option<PathBuf>,
    kwargs: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    // The keyword-only parameters, bound by name (Python's errors for an unknown one);
    // `out_dir` comes from the signature above, so only its default is bound here.
    let (p, _) = args::bind_params("dataset_units", PARAMS, &PyTuple::empty(py), kwargs, false)?;
    let variants = p.extract::<Variants>("variants")?.0;
    let val = p.extract::<Option<Val>>("val")?.map(|v| v.0);
    let val_fraction = p.extract::<Option<f64>>("val_fraction")?;
    let seed = p.extract::<Seed>("seed")?.0;
    let shard = p.extract::<Option<String>>("shard")?;
    let overwrite = p.extract::<bool>("overwrite")?;
    let opts = UnitsOptions {
        day_dir,
        out_dir,
        split: parse_split_rule(val, val_fraction, seed)?,
        variants,
        seed,
        shard: parse_shard(shard.as_deref())?,
        overwrite,
    };
    let planned = py.detach(move || lib::units(&opts)).map_err(py_err)?;
    let list = PyList::empty(py);
    for p in planned {
        let u = &p.unit;
        let d = PyDict::new(py);
        d.set_item("input", &u.rel)?;
        d.set_item("path", u.path.display().to_string())?;
        d.set_item("split", u.split.name())?;
        d.set_item("variant", u.variant)?;
        d.set_item("variants", u.variants)?;
        d.set_item("seed", u.seed)?;
        d.set_item("id", &u.id)?;
        let prev = match &p.previous {
            Some(r) => Some(serde_json::to_string(r).map_err(|e| value_err(e.to_string()))?),
            None => None,
        };
        d.set_item("previous", prev)?;
        list.append(d)?;
    }
    Ok(list)
}

/// A record given as a dict or a JSON string.
fn record_from(v: &Bound<'_, PyAny>, what: &str) -> PyResult<Record> {
    let text: String = if let Ok(s) = v.extract::<String>() {
        s
    } else {
        v.py()
            .import("json")?
            .call_method1("dumps", (v,))?
            .extract()?
    };
    serde_json::from_str(&text)
        .map_err(|e| value_err(format!("{what}: not a manifest record: {e}")))
}

fn unit_from(d: &Bound<'_, PyAny>) -> PyResult<(Unit, Option<Record>)> {
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)
            .map_err(|_| value_err(format!("unit has no {k:?}: pass a dict from dataset_units")))
    };
    let rel: String = get("input")?.extract()?;
    let path: PathBuf = get("path")?.extract()?;
    let split = match get("split")?.extract::<String>()?.as_str() {
        "train" => Split::Train,
        "val" => Split::Val,
        s => return Err(value_err(format!("unit split {s:?}: train or val"))),
    };
    let variants: u32 = VARIANTS.get_as(&get("variants")?, "unit[\"variants\"]")?;
    let variant: u32 = args::in_range(
        &get("variant")?,
        "unit[\"variant\"]",
        1,
        u64::from(variants),
    )?;
    let seed: u64 = SEED.get_as(&get("seed")?, "unit[\"seed\"]")?;
    let unit = lib::unit(&rel, path, split, variant, variants, seed).map_err(py_err)?;
    if let Ok(id) = d.get_item("id") {
        if !id.is_none() && id.extract::<String>()? != unit.id {
            return Err(value_err(format!(
                "unit id {id} is not the id of {rel} variant {variant} ({})",
                unit.id
            )));
        }
    }
    let previous = match d.get_item("previous") {
        Ok(p) if !p.is_none() => Some(record_from(&p, "unit[\"previous\"]")?),
        _ => None,
    };
    Ok((unit, previous))
}

/// The job `dataset`'s flags spell, from keyword options named like the flags (`--iso` is
/// `iso`, `--noise-model` is `noise_model`, ...), with the same values and defaults: the
/// option table's (python/src/synth_options.rs).
fn dataset_config(variants: u32, options: Option<&Bound<'_, PyDict>>) -> PyResult<JobConfig> {
    let mut draft = Draft::new(variants);
    synth_options::apply(
        &mut draft,
        options,
        Scope::Files,
        "; seed, variants, val and shard are dataset_units'",
    )?;
    synth_options::finish(draft)
}

/// Processors already built (calibration files loaded), by configuration: a worker writes
/// many units with the same options.
fn processor_for(cfg: &JobConfig) -> Result<Arc<SynthProcessor>, Error> {
    static CACHE: OnceLock<Mutex<HashMap<String, Arc<SynthProcessor>>>> = OnceLock::new();
    let key = format!("{cfg:?}");
    let cache = CACHE.get_or_init(Default::default);
    if let Some(p) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(p.clone());
    }
    let p = Arc::new(SynthProcessor { job: cfg.build()? });
    let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
    if map.len() > 16 {
        map.clear();
    }
    map.insert(key, p.clone());
    Ok(p)
}

/// Write exactly one unit's files (a dict from ``dataset_units``) into the dataset layout
/// in ``out_dir``, as ``day2night dataset`` writes them with the same options, and return
/// its manifest record (a dict, the line ``manifest.jsonl`` holds for the unit).
///
/// Every file is written atomically under the unit's lock. A unit whose record (the unit's
/// ``previous``, or the one a killed run of this function left) is up to date is skipped:
/// its record is returned and nothing is written. A unit that fails returns a record with
/// ``status`` "failed" and the ``error``, as ``dataset`` records it.
///
/// Options are ``dataset``'s synthesis and output flags in snake case, same values and
/// defaults: every option of the table but the seed (a unit carries it), as the signature
/// lists them (``inspect.signature(day2night.write_unit)``; docs/python.md, generated from
/// it, gives each one's values). ``overwrite`` recomputes an up-to-date
/// unit, ``wait`` waits for another process writing the same unit. With ``reason=True``
/// returns ``(record, reason)``: why the unit was computed ("new", "outputs missing or
/// altered", ...) or None when it was skipped.
///
/// >>> rec = day2night.write_unit(units[0], "night/", iso="800,3200", target="both")
#[pyfunction]
#[pyo3(signature = (unit, out_dir, *, overwrite=false, wait=false, reason=false, **options))]
pub fn write_unit<'py>(
    py: Python<'py>,
    unit: &Bound<'py, PyAny>,
    out_dir: PathBuf,
    overwrite: bool,
    wait: bool,
    reason: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (unit, previous) = unit_from(unit)?;
    let cfg = dataset_config(unit.variants, options)?;
    let said = Collected::default();
    let w = WriteOptions {
        out_dir,
        overwrite,
        wait,
        progress: said.sink(),
    };
    let done = py.detach(move || {
        on_pool(move || {
            let p = processor_for(&cfg)?;
            lib::write_unit(&unit, previous.as_ref(), &w, p.as_ref())
        })
    });
    said.raise(py)?;
    let (rec, why) = done.map_err(py_err)?;
    let rec = json_obj(py, &rec)?;
    if reason {
        Ok((rec, why.map(|r| r.describe()))
            .into_pyobject(py)?
            .into_any())
    } else {
        Ok(rec)
    }
}

/// ``write_unit`` for several units (dicts from ``dataset_units``), each input read,
/// hashed and decoded once for all of its units (its variants), as ``day2night dataset``
/// does; units of several inputs are grouped by input (``group_units`` gives the groups, one
/// per scheduler task). Returns the records (or ``(record, reason)`` pairs with
/// ``reason=True``) in the order of ``units``. Same options as ``write_unit``.
///
/// >>> for group in day2night.group_units(units):
/// ...     records += day2night.write_units(group, "night/", iso="800,3200")
#[pyfunction]
#[pyo3(signature = (units, out_dir, *, overwrite=false, wait=false, reason=false, **options))]
pub fn write_units<'py>(
    py: Python<'py>,
    units: &Bound<'py, PyAny>,
    out_dir: PathBuf,
    overwrite: bool,
    wait: bool,
    reason: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyList>> {
    let mut parsed = Vec::new();
    for (i, u) in units.try_iter()?.enumerate() {
        let u = u?;
        parsed.push(unit_from(&u).map_err(|e| {
            let msg = e.value(py).to_string();
            if e.is_instance_of::<pyo3::exceptions::PyValueError>(py) {
                value_err(format!("units[{i}]: {msg}"))
            } else {
                e
            }
        })?);
    }
    let list = PyList::empty(py);
    let Some((first, _)) = parsed.first() else {
        return Ok(list);
    };
    let cfg = dataset_config(first.variants, options)?;
    // Groups by input, in the order each input first appears.
    let mut groups: Vec<(PathBuf, Vec<usize>)> = Vec::new();
    for (i, (u, _)) in parsed.iter().enumerate() {
        match groups.iter_mut().find(|(p, _)| *p == u.path) {
            Some((_, idx)) => idx.push(i),
            None => groups.push((u.path.clone(), vec![i])),
        }
    }
    let said = Collected::default();
    let w = WriteOptions {
        out_dir,
        overwrite,
        wait,
        progress: said.sink(),
    };
    let n = parsed.len();
    let done = py.detach(move || {
        on_pool(move || {
            let p = processor_for(&cfg)?;
            let mut done: Vec<Option<(Record, Option<Reason>)>> = vec![None; n];
            for (_, idx) in &groups {
                let group: Vec<(Unit, Option<Record>)> =
                    idx.iter().map(|&i| parsed[i].clone()).collect();
                for (&i, r) in idx.iter().zip(lib::write_units(&group, &w, p.as_ref())?) {
                    done[i] = Some(r);
                }
            }
            Ok(done)
        })
    });
    said.raise(py)?;
    let done = done.map_err(py_err)?;
    for (rec, why) in done.into_iter().flatten() {
        let rec = json_obj(py, &rec)?;
        if reason {
            list.append((rec, why.map(|r| r.describe())))?;
        } else {
            list.append(rec)?;
        }
    }
    Ok(list)
}

/// Write the manifest of a run (``manifest.jsonl``, or ``manifest.shard-I-of-N.jsonl``
/// with ``shard="I/N"``) into ``out_dir`` from the records ``write_unit`` returned (dicts
/// or JSON strings; the latest record of each unit is kept), lines sorted as ``dataset``
/// writes them, and remove the per-unit records of those units. Returns the path.
///
/// >>> day2night.write_manifest(records, "night/")
#[pyfunction]
#[pyo3(signature = (records, out_dir, shard=None))]
pub fn write_manifest(
    py: Python<'_>,
    records: &Bound<'_, PyAny>,
    out_dir: PathBuf,
    shard: Option<&str>,
) -> PyResult<String> {
    let shard = parse_shard(shard)?;
    let mut recs = Vec::new();
    for (i, r) in records.try_iter()?.enumerate() {
        recs.push(record_from(&r?, &format!("records[{i}]"))?);
    }
    let path = py
        .detach(move || lib::write_manifest(&out_dir, recs, shard))
        .map_err(py_err)?;
    Ok(path.display().to_string())
}
