//! `release_noise`: the release's noise on a clean plane (`day2night::noise::release`), with
//! the draws of a `numpy.random.RandomState` whose state is passed in and given back, and
//! `RELEASE_NOISE_TABLE`, the S20 FE table in DN (the embedded calibration's one copy).

use crate::errors::{py_err, value_err};
use day2night::noise::numpy_legacy::LegacyState;
use day2night::noise::release::release_noise as noise;
use day2night::synth::dictionaries::embedded::paper_dn_table;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The legacy generator's state as `RandomState.get_state()` lists it after its name.
type State<'py> = (Bound<'py, PyAny>, usize, i64, f64);

/// The release's noisy uint16 plane of the clean float32 ``plane`` (2-D, DN, the visible
/// raw) at ``iso``, with the draws of the ``numpy.random.RandomState`` whose state is
/// ``state`` (``get_state()[1:]``: key, pos, has_gauss, cached_gaussian). Returns
/// ``(noisy, state after the draws)``, for ``set_state(("MT19937", *state))``.
#[pyfunction]
pub(crate) fn release_noise<'py>(
    py: Python<'py>,
    plane: PyReadonlyArray2<'py, f32>,
    iso: u32,
    state: State<'py>,
) -> PyResult<(Bound<'py, PyAny>, State<'py>)> {
    let (key, pos, has_gauss, gauss) = state;
    let key: PyReadonlyArray1<'py, u32> = key
        .extract()
        .map_err(|_| value_err("release noise: the state's key must be a uint32 array"))?;
    let mut rng =
        LegacyState::new(key.as_array().to_vec(), pos, has_gauss != 0, gauss).map_err(py_err)?;
    let v = plane.as_array();
    let (h, w) = v.dim();
    let samples: Vec<f32> = v.iter().copied().collect();
    let (out, rng) = py
        .detach(move || noise(&samples, w, iso, paper_dn_table(), &mut rng).map(|o| (o, rng)))
        .map_err(py_err)?;
    let out = Array2::from_shape_vec((h, w), out).map_err(|e| value_err(e.to_string()))?;
    let key = rng.key.into_pyarray(py).into_any();
    let state = (key, rng.pos, i64::from(rng.has_gauss), rng.gauss);
    Ok((out.into_pyarray(py).into_any(), state))
}

/// ``{"black", "white", "rows": [(iso, position, beta1, beta2), ...]}``: the S20 FE table.
pub(crate) fn table_dict(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let t = paper_dn_table();
    let d = PyDict::new(py);
    d.set_item("black", t.black)?;
    d.set_item("white", t.white)?;
    d.set_item("rows", t.rows.clone())?;
    Ok(d)
}
