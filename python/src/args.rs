//! Integer arguments: each has the range the command line accepts (`day2night::bounds`), and
//! a value outside it (negative, too large, or beyond any machine integer) is a `ValueError`
//! naming the argument and the range (`seed: -1 is outside 0..=18446744073709551615`),
//! never an `OverflowError`. A value that is not an integer (a float, a string) is a
//! `TypeError` naming the argument. Any object with `__index__` is an integer (numpy's
//! integer scalars included).

use crate::errors::value_err;
use day2night::bounds::{
    EXR_ZIP_LEVEL_RANGE, ISO_RANGE, JOBS_RANGE, MAX_LIGHTS, SEED_RANGE, VARIANTS_RANGE,
};
use day2night::raw::crop::Crop;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// An integer argument: its name and its inclusive range.
#[derive(Debug, Clone, Copy)]
pub(crate) struct IntArg {
    pub name: &'static str,
    pub lo: u64,
    pub hi: u64,
}

/// `seed` (`--seed`).
pub(crate) const SEED: IntArg = IntArg {
    name: "seed",
    lo: SEED_RANGE.0,
    hi: SEED_RANGE.1,
};
/// `variant` (0-based: variant k is the `_v{k+1}` variant of `--variants k+1`).
pub(crate) const VARIANT: IntArg = IntArg {
    name: "variant",
    lo: VARIANTS_RANGE.0 as u64 - 1,
    hi: VARIANTS_RANGE.1 as u64 - 1,
};
/// `variants` (`--variants`).
pub(crate) const VARIANTS: IntArg = IntArg {
    name: "variants",
    lo: VARIANTS_RANGE.0 as u64,
    hi: VARIANTS_RANGE.1 as u64,
};
/// An ISO (`--iso`).
pub(crate) const ISO: IntArg = IntArg {
    name: "iso",
    lo: ISO_RANGE.0 as u64,
    hi: ISO_RANGE.1 as u64,
};
/// `bulbs` (`--bulbs`).
pub(crate) const BULBS: IntArg = IntArg {
    name: "bulbs",
    lo: 0,
    hi: MAX_LIGHTS as u64,
};
/// `lights` (`--lights`).
pub(crate) const LIGHTS: IntArg = IntArg {
    name: "lights",
    lo: 0,
    hi: MAX_LIGHTS as u64,
};
/// `exr_zip_level` (`--exr-zip-level`).
pub(crate) const EXR_ZIP_LEVEL: IntArg = IntArg {
    name: "exr_zip_level",
    lo: EXR_ZIP_LEVEL_RANGE.0 as u64,
    hi: EXR_ZIP_LEVEL_RANGE.1 as u64,
};
/// `set_threads(n)`: 0 (one per core) or `--jobs`'s range.
pub(crate) const THREADS: IntArg = IntArg {
    name: "n",
    lo: 0,
    hi: JOBS_RANGE.1 as u64,
};
/// `val` (`--val`: the last N inputs go to val; more than there are inputs is refused when
/// the inputs are listed).
pub(crate) const VAL: IntArg = IntArg {
    name: "val",
    lo: 0,
    hi: usize::MAX as u64,
};

/// Every argument of the table by its key in `day2night.BOUNDS`.
const ALL: [(&str, IntArg); 9] = [
    ("seed", SEED),
    ("variant", VARIANT),
    ("variants", VARIANTS),
    ("iso", ISO),
    ("bulbs", BULBS),
    ("lights", LIGHTS),
    ("exr_zip_level", EXR_ZIP_LEVEL),
    ("threads", THREADS),
    ("val", VAL),
];

impl IntArg {
    /// The value of this argument.
    pub fn get<T: TryFrom<u64>>(&self, v: &Bound<'_, PyAny>) -> PyResult<T> {
        self.get_as(v, self.name)
    }

    /// The value of this argument, called `label` in errors (`isos[1]`, `crop[2] (height)`).
    pub fn get_as<T: TryFrom<u64>>(&self, v: &Bound<'_, PyAny>, label: &str) -> PyResult<T> {
        in_range(v, label, self.lo, self.hi)
    }
}

/// `v` as an integer in `lo..=hi`, or the error naming `label` and the range.
pub(crate) fn in_range<T: TryFrom<u64>>(
    v: &Bound<'_, PyAny>,
    label: &str,
    lo: u64,
    hi: u64,
) -> PyResult<T> {
    let py = v.py();
    not_bool(v, label, "an integer")?;
    let int = py
        .import("operator")?
        .call_method1("index", (v,))
        .map_err(|_| {
            let ty = v
                .get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_else(|_| "?".into());
            PyTypeError::new_err(format!("{label} must be an integer (got {ty})"))
        })?;
    // Beyond i128 is out of every range: such an int does not extract.
    if let Ok(n) = int.extract::<i128>() {
        if n >= i128::from(lo) && n <= i128::from(hi) {
            if let Ok(t) = T::try_from(n as u64) {
                return Ok(t);
            }
        }
    }
    let mut shown = int.str().map(|s| s.to_string()).unwrap_or_default();
    if shown.len() > 40 {
        shown = format!("{}... ({} digits)", &shown[..20], shown.len());
    }
    Err(value_err(format!(
        "{label}: {shown} is outside {lo}..={hi}"
    )))
}

/// A `TypeError` for a bool given as `label` (`True` is an `int` to Python, but
/// `burst=True` is a mistake, not one frame).
fn not_bool(v: &Bound<'_, PyAny>, label: &str, want: &str) -> PyResult<()> {
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(PyTypeError::new_err(format!(
            "{label} must be {want} (got bool)"
        )));
    }
    Ok(())
}

/// An integer argument `label` whose range the library checks (it names `lo..=hi` only for
/// values beyond any machine integer): a bool or a non-integer is a `TypeError`.
pub(crate) fn integer(v: &Bound<'_, PyAny>, label: &str, lo: u64, hi: u64) -> PyResult<i128> {
    not_bool(v, label, "an integer")?;
    let int = v.py().import("operator")?.call_method1("index", (v,));
    match int.and_then(|i| i.extract::<i128>()) {
        Ok(n) => Ok(n),
        // Not an integer (TypeError) or beyond i128 (ValueError naming the range).
        Err(_) => in_range::<u64>(v, label, lo, hi).map(i128::from),
    }
}

/// A float argument `label` (an int is taken as a float; a bool or anything else is a
/// `TypeError`). Its range is the library's check.
pub(crate) fn float(v: &Bound<'_, PyAny>, label: &str) -> PyResult<f64> {
    not_bool(v, label, "a number")?;
    v.extract::<f64>().map_err(|_| {
        PyTypeError::new_err(format!("{label} must be a number (got {})", type_name(v)))
    })
}

/// A str argument `label` (anything else is a `TypeError`).
pub(crate) fn string(v: &Bound<'_, PyAny>, label: &str) -> PyResult<String> {
    v.extract::<String>()
        .map_err(|_| PyTypeError::new_err(format!("{label} must be a str (got {})", type_name(v))))
}

fn type_name(v: &Bound<'_, PyAny>) -> String {
    v.get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "?".into())
}

/// ``value`` as an int within ``BOUNDS[key]``, else the ``ValueError`` (``TypeError`` for
/// a non-integer) the native functions raise for that argument, called ``label`` (default:
/// ``key``). For checks in Python code (``NightPairs``).
///
/// >>> day2night.check_int("seed", -1)
/// ValueError: seed: -1 is outside 0..=18446744073709551615
#[pyfunction]
#[pyo3(signature = (key, value, label=None))]
pub(crate) fn check_int(key: &str, value: &Bound<'_, PyAny>, label: Option<&str>) -> PyResult<u64> {
    let (_, arg) = ALL.iter().find(|(k, _)| *k == key).ok_or_else(|| {
        value_err(format!(
            "unknown argument {key:?} (known: {})",
            ALL.map(|(k, _)| k).join(", ")
        ))
    })?;
    arg.get_as(value, label.unwrap_or(key))
}

/// `day2night.BOUNDS`: each integer argument's (lowest, highest) value.
pub(crate) fn bounds_dict(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for (key, a) in ALL {
        d.set_item(key, (a.lo, a.hi))?;
    }
    Ok(d)
}

/// An argument type whose Python value is checked against an [`IntArg`] when the call's
/// arguments are extracted (so a signature keeps its default, e.g. `seed=Seed(0)`).
macro_rules! int_type {
    ($(#[$doc:meta])* $ty:ident($inner:ty) = $arg:expr) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy)]
        pub(crate) struct $ty(pub $inner);

        impl<'a, 'py> FromPyObject<'a, 'py> for $ty {
            type Error = PyErr;
            fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
                $arg.get(&obj).map($ty)
            }
        }
    };
}

int_type!(
    /// A `seed` argument.
    Seed(u64) = SEED
);
int_type!(
    /// A 0-based `variant` argument.
    Variant(u32) = VARIANT
);
int_type!(
    /// A `variants` argument.
    Variants(u32) = VARIANTS
);
int_type!(
    /// One `iso` argument.
    Iso(u32) = ISO
);
int_type!(
    /// The `n` of `set_threads`.
    Threads(usize) = THREADS
);
int_type!(
    /// A `val` argument.
    Val(usize) = VAL
);

/// An `isos` argument: a sequence of ISOs, each in [`ISO`]'s range (`isos[i]` in errors).
#[derive(Debug, Clone)]
pub(crate) struct Isos(pub Vec<u32>);

impl<'a, 'py> FromPyObject<'a, 'py> for Isos {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        isos(&obj, "isos").map(Isos)
    }
}

/// A sequence of ISOs called `label` (`label[i]` in errors).
pub(crate) fn isos(v: &Bound<'_, PyAny>, label: &str) -> PyResult<Vec<u32>> {
    if v.is_instance_of::<pyo3::types::PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{label} must be a sequence of integers (got a string)"
        )));
    }
    let items = v
        .try_iter()
        .map_err(|_| PyTypeError::new_err(format!("{label} must be a sequence of integers")))?;
    let mut out = Vec::new();
    for (i, item) in items.enumerate() {
        out.push(ISO.get_as(&item?, &format!("{label}[{i}]"))?);
    }
    Ok(out)
}

/// A `crop=(top, left, height, width)` argument within an active area of `aw` x `ah`
/// samples: top and left from 0 to the last even row and column, height and width from 1
/// to what is left of the area. Odd offsets are refused by [`Crop::check`].
pub(crate) fn crop(v: &Bound<'_, PyAny>, aw: usize, ah: usize) -> PyResult<Crop> {
    let items: Vec<Bound<'_, PyAny>> = v
        .try_iter()
        .and_then(|it| it.collect::<PyResult<Vec<_>>>())
        .map_err(|_| PyTypeError::new_err("crop must be (top, left, height, width)"))?;
    if items.len() != 4 {
        return Err(value_err(format!(
            "crop must be (top, left, height, width): got {} values",
            items.len()
        )));
    }
    let at = |i: usize, what: &str, lo: usize, hi: usize| -> PyResult<usize> {
        if hi < lo {
            return Err(value_err(format!(
                "crop[{i}] ({what}): no value fits a {aw}x{ah} active area"
            )));
        }
        in_range(
            &items[i],
            &format!("crop[{i}] ({what})"),
            lo as u64,
            hi as u64,
        )
    };
    // Offsets are even (they keep the CFA phase): the last even row and column.
    let top = at(0, "top", 0, ah.saturating_sub(1) & !1)?;
    let left = at(1, "left", 0, aw.saturating_sub(1) & !1)?;
    let height = at(2, "height", 1, ah - top)?;
    let width = at(3, "width", 1, aw - left)?;
    Ok(Crop {
        top,
        left,
        height,
        width,
    })
}

/// A bound parameter's value, None when the call did not give it.
pub(crate) type Given<'py> = Option<Bound<'py, PyAny>>;

/// A default of a [`Param`].
#[derive(Debug, Clone, Copy)]
pub(crate) enum ParamDefault {
    /// None.
    None,
    /// An int.
    Int(u64),
    /// A str.
    Str(&'static str),
    /// A bool.
    Bool(bool),
    /// The Python default of the table's option of that name
    /// ([`crate::option_default::python_default`]).
    Table(&'static str),
}

/// A parameter of a function that binds its arguments itself ([`bind_params`]): its name,
/// its default and whether it is keyword-only. The one spelling of both: the binding
/// applies the default, and `day2night._native.PARAMETERS` gives them to the signature
/// Python shows (python/pysrc/day2night/signatures.py).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Param {
    pub name: &'static str,
    pub default: ParamDefault,
    pub keyword_only: bool,
}

impl Param {
    /// A positional-or-keyword parameter.
    pub const fn pos(name: &'static str, default: ParamDefault) -> Param {
        Param {
            name,
            default,
            keyword_only: false,
        }
    }

    /// A keyword-only parameter.
    pub const fn kw(name: &'static str, default: ParamDefault) -> Param {
        Param {
            name,
            default,
            keyword_only: true,
        }
    }

    /// The default as a Python value.
    pub fn default_value<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(match self.default {
            ParamDefault::None => py.None().into_bound(py),
            ParamDefault::Int(n) => n.into_pyobject(py)?.into_any(),
            ParamDefault::Str(s) => s.into_pyobject(py)?.into_any(),
            ParamDefault::Bool(b) => pyo3::types::PyBool::new(py, b).to_owned().into_any(),
            ParamDefault::Table(name) => {
                let d = day2night::synth::options::find(name)
                    .ok_or_else(|| value_err(format!("no option {name:?}")))?;
                crate::option_default::python_default(py, d)?
            }
        })
    }
}

/// A function's signature as `day2night._native.PARAMETERS` lists it: the required
/// positional parameters, then `params`; each as (name, "POSITIONAL_OR_KEYWORD" or
/// "KEYWORD_ONLY", default, or no default when required).
pub(crate) fn signature_list<'py>(
    py: Python<'py>,
    required: &[&str],
    params: &[Param],
) -> PyResult<Bound<'py, pyo3::types::PyList>> {
    let list = pyo3::types::PyList::empty(py);
    for r in required {
        list.append((*r, "POSITIONAL_OR_KEYWORD", false, py.None()))?;
    }
    for p in params {
        let kind = if p.keyword_only {
            "KEYWORD_ONLY"
        } else {
            "POSITIONAL_OR_KEYWORD"
        };
        list.append((p.name, kind, true, p.default_value(py)?))?;
    }
    Ok(list)
}

/// The values of a function's [`Param`]s, each given or its default, read by name: a
/// parameter list can be reordered without rebinding anything (tests/tidy.rs refuses a
/// positional read such as `p[0]`).
pub(crate) struct BoundParams<'py> {
    func: String,
    values: Vec<(&'static str, Bound<'py, PyAny>)>,
}

impl<'py> BoundParams<'py> {
    /// The value of the parameter `name` (an internal error names it if the function's
    /// `PARAMS` has no such parameter).
    pub fn get(&self, name: &str) -> PyResult<&Bound<'py, PyAny>> {
        self.values
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v)
            .ok_or_else(|| {
                pyo3::exceptions::PyRuntimeError::new_err(format!(
                    "internal error: {}() has no parameter {name:?}",
                    self.func
                ))
            })
    }

    /// The value of `name`, extracted (a TypeError as PyO3 words it otherwise).
    pub fn extract<T: for<'a> pyo3::FromPyObject<'a, 'py>>(&self, name: &str) -> PyResult<T> {
        self.get(name)?.extract::<T>().map_err(Into::into)
    }
}

/// [`bind`] with `params`' names (their positions allowed while positional), each value
/// given or its default, by name; the other keyword arguments when `rest`.
pub(crate) fn bind_params<'py>(
    func: &str,
    params: &[Param],
    args: &Bound<'py, pyo3::types::PyTuple>,
    kwargs: Option<&Bound<'py, PyDict>>,
    rest: bool,
) -> PyResult<(BoundParams<'py>, Bound<'py, PyDict>)> {
    let names: Vec<&str> = params.iter().map(|p| p.name).collect();
    let positional = params.iter().take_while(|p| !p.keyword_only).count();
    if args.len() > positional {
        return Err(PyTypeError::new_err(format!(
            "{func}() takes at most {positional} positional arguments after the first but {} were given",
            args.len()
        )));
    }
    let (given, others) = bind(func, &names, args, kwargs, rest)?;
    let mut values = Vec::with_capacity(params.len());
    for (g, p) in given.into_iter().zip(params) {
        let v = match g {
            Some(v) => v,
            None => p.default_value(args.py())?,
        };
        values.push((p.name, v));
    }
    let bound = BoundParams {
        func: func.to_string(),
        values,
    };
    Ok((bound, others))
}

/// The parameters `names` of the Python function `func`, bound from its positional `args`
/// (in order) and its keyword arguments `kwargs`, as Python binds a signature of
/// positional-or-keyword parameters (a value given twice, or too many positional values,
/// is a `TypeError` with Python's own words). Returns each parameter's value (None when
/// not given: the caller applies the default) and the other keyword arguments: with
/// `rest`, the `**options` the caller parses; without, an unexpected keyword is a
/// `TypeError`. Lets a function with many parameters take them as one value.
pub(crate) fn bind<'py>(
    func: &str,
    names: &[&str],
    args: &Bound<'py, pyo3::types::PyTuple>,
    kwargs: Option<&Bound<'py, PyDict>>,
    rest: bool,
) -> PyResult<(Vec<Given<'py>>, Bound<'py, PyDict>)> {
    if args.len() > names.len() {
        return Err(PyTypeError::new_err(format!(
            "{func}() takes at most {} positional arguments after the first but {} were given",
            names.len(),
            args.len()
        )));
    }
    let mut values: Vec<Given<'py>> = vec![None; names.len()];
    for (slot, a) in values.iter_mut().zip(args.iter()) {
        *slot = Some(a);
    }
    let others = PyDict::new(args.py());
    if let Some(kw) = kwargs {
        for (k, v) in kw.iter() {
            let key: String = k.extract()?;
            match names.iter().position(|n| *n == key) {
                Some(i) if values[i].is_some() => {
                    return Err(PyTypeError::new_err(format!(
                        "{func}() got multiple values for argument '{key}'"
                    )))
                }
                Some(i) => values[i] = Some(v),
                None if rest => others.set_item(k, v)?,
                None => {
                    return Err(PyTypeError::new_err(format!(
                        "{func}() got an unexpected keyword argument '{key}'"
                    )))
                }
            }
        }
    }
    Ok((values, others))
}
