//! `Raw` (a raw in memory, read from a DNG or built from an array), `read_dng` and
//! `write_dng`. A LinearRaw DNG (already demosaiced) is read too, so that it can be
//! rendered; the synthesis refuses it with the command line's reason ([`Raw::cfa_day`]).

use crate::convert::meta_dict;
use crate::diagnostics::warn_meta;
use crate::errors::{py_err, value_err};
use crate::pool::on_pool;
use day2night::dng::write::{write_dng as lib_write_dng, Compression, WriteOptions};
use day2night::error::ResultExt;
use day2night::output::OutputPolicy;
use day2night::raw::meta::LINEAR_RAW_NOT_CFA;
use day2night::synth::job::DayInput;
use day2night::Error;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// A day DNG read into memory.
///
/// Attributes: ``data`` (uint16 ndarray of the whole stored plane, masked border
/// included: LibRaw's ``raw_image``; height x width x 3 for a LinearRaw DNG), ``meta``
/// (dict), ``name`` (file stem), ``file_name`` (the name the random streams are keyed by,
/// as in ``day2night synth``), ``path``.
///
/// >>> raw = day2night.read_dng("day.dng")
/// >>> raw.data.shape, raw.meta["cfa_pattern"]
/// ((3024, 4032), 'RGGB')
#[pyclass(module = "day2night", name = "Raw", frozen)]
pub(crate) struct Raw {
    pub(crate) day: Arc<DayInput>,
    pub(crate) name: String,
    pub(crate) file_name: String,
    /// Read from `day.source` (false: built in memory, e.g. `Raw.from_array`).
    pub(crate) from_file: bool,
    pub(crate) data: OnceLock<Py<PyAny>>,
}

impl Raw {
    /// The day input of a synthesis: a LinearRaw image is refused with the reason
    /// `day2night synth` gives (`<file>: unsupported: LinearRaw: ...`).
    pub(crate) fn cfa_day(&self) -> PyResult<Arc<DayInput>> {
        if self.day.raw.meta.linear_raw.is_some() {
            return Err(py_err(
                Error::unsupported(LINEAR_RAW_NOT_CFA).in_file(&self.day.source),
            ));
        }
        Ok(self.day.clone())
    }
}

#[pymethods]
impl Raw {
    /// The whole stored plane as a read-only uint16 array: height x width for a CFA
    /// mosaic, height x width x samples (3) for a LinearRaw image (samples interleaved as
    /// stored, before any black level or linearization).
    #[getter]
    fn data<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        if let Some(a) = self.data.get() {
            return Ok(a.bind(py).clone());
        }
        let raw = &self.day.raw;
        let err = |e: numpy::ndarray::ShapeError| value_err(e.to_string());
        let arr = match &raw.meta.linear_raw {
            None => {
                let a = Array2::from_shape_vec((raw.height, raw.width), raw.data.clone())
                    .map_err(err)?
                    .into_pyarray(py);
                a.readwrite().make_nonwriteable();
                a.into_any()
            }
            Some(lr) => {
                let spp = usize::from(lr.samples_per_pixel);
                let a = Array3::from_shape_vec((raw.height, raw.width, spp), raw.data.clone())
                    .map_err(err)?
                    .into_pyarray(py);
                a.readwrite().make_nonwriteable();
                a.into_any()
            }
        };
        let _ = self.data.set(arr.clone().unbind());
        Ok(self.data.get().map(|a| a.bind(py).clone()).unwrap_or(arr))
    }

    /// Metadata: cfa_pattern, black_level (BlackLevel pattern), black_level_repeat_dim,
    /// white_level, as_shot_neutral, iso, noise_profile, active_area [top, left, bottom,
    /// right], default_crop [top, left, height, width] (in active-area coordinates),
    /// orientation, make, model, width, height, bits_per_sample.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        meta_dict(py, &self.day.raw)
    }

    /// The file stem (``day`` for ``day.dng``).
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The file name (``day.dng``): the key of the random streams, as in ``day2night synth``.
    #[getter]
    fn file_name(&self) -> &str {
        &self.file_name
    }

    /// The path the DNG was read from (None for a raw built in memory).
    #[getter]
    fn path(&self) -> Option<String> {
        self.from_file
            .then(|| self.day.source.display().to_string())
    }

    /// A raw from a 2-D uint16 CFA array (the whole stored plane; any strides) and a
    /// metadata dict with the keys of ``Raw.meta`` (cfa_pattern, black_level and
    /// white_level required; missing colour metadata gets the documented defaults, each
    /// with a warning). ``name`` is the file stem the outputs and random streams are keyed
    /// by (``file_name`` is ``name + ".dng"``). Checked as the DNG reader checks a file.
    ///
    /// >>> r = day2night.read_dng("day.dng")
    /// >>> same = day2night.Raw.from_array(r.data, r.meta, name=r.name)
    #[staticmethod]
    fn from_array(
        py: Python<'_>,
        data: &Bound<'_, PyAny>,
        meta: &Bound<'_, PyAny>,
        name: &str,
    ) -> PyResult<Raw> {
        let (day, stem) = crate::raw_from::from_array(py, data, meta, name)?;
        let file_name = day.source.display().to_string();
        Ok(Raw {
            day: Arc::new(day),
            name: stem,
            file_name,
            from_file: false,
            data: OnceLock::new(),
        })
    }

    /// SHA-256 of the file's bytes (the sidecar's ``input.sha256``).
    #[getter]
    fn sha256(&self) -> &str {
        &self.day.sha256
    }

    fn __repr__(&self) -> String {
        let r = &self.day.raw;
        format!(
            "Raw({:?}, {}x{}, {})",
            self.file_name,
            r.width,
            r.height,
            match &r.meta.linear_raw {
                Some(lr) => format!("LinearRaw x{}", lr.samples_per_pixel),
                None => r
                    .bayer()
                    .map(|b| b.name())
                    .unwrap_or_else(|_| "non-Bayer".into()),
            }
        )
    }
}

/// The DNG at `path` as [`DayInput::read`] decodes it, LinearRaw images included (that
/// function refuses them: a day input of the synthesis is a CFA mosaic).
fn read_input(path: &Path) -> Result<DayInput, Error> {
    let bytes = std::fs::read(path).map_err(Error::Io).in_file(path)?;
    let (sha256, raw) = rayon::join(
        || day2night::synth::sidecar::sha256_hex(&bytes),
        || day2night::dng::read::read_dng_bytes(&bytes),
    );
    Ok(DayInput::new(
        raw.in_file(path)?,
        sha256,
        path.to_path_buf(),
    ))
}

/// Read a DNG into memory (the GIL is released while it is read and decoded). A LinearRaw
/// DNG (already demosaiced) is read for ``render``; ``synthesize`` refuses it.
///
/// >>> raw = day2night.read_dng("day.dng")
#[pyfunction]
pub(crate) fn read_dng(py: Python<'_>, path: PathBuf) -> PyResult<Raw> {
    let day = py
        .detach(|| on_pool(|| read_input(&path)))
        .map_err(py_err)?;
    let file_name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    let name = path
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| file_name.clone());
    warn_meta(py, &path, &day.raw.meta)?;
    Ok(Raw {
        day: Arc::new(day),
        name,
        file_name,
        from_file: true,
        data: OnceLock::new(),
    })
}

/// Write ``raw`` as a DNG at ``path`` through the library's DNG writer (the one
/// ``day2night synth`` uses): uncompressed strips (``compression="none"``) or lossless
/// JPEG tiles (``"ljpeg"``), every modelled tag (levels, CFA, colour matrices, neutral,
/// ISO, noise profile, crop, orientation, opcode lists; for a read DNG also the tags it
/// carried). Written to a temporary file, synced and renamed into place; an existing
/// ``path`` is refused unless ``overwrite=True``.
///
/// >>> day2night.write_dng(day2night.from_rawpy(rawpy.imread("a.nef"), "a"), "a.dng")
#[pyfunction]
#[pyo3(signature = (raw, path, overwrite=false, compression="none"))]
pub(crate) fn write_dng(
    py: Python<'_>,
    raw: &Bound<'_, Raw>,
    path: PathBuf,
    overwrite: bool,
    compression: &str,
) -> PyResult<()> {
    let compression = match compression {
        "none" => Compression::None,
        "ljpeg" => Compression::Ljpeg,
        c => {
            return Err(value_err(format!(
                "compression {c:?}: use \"none\" or \"ljpeg\""
            )))
        }
    };
    let r = raw.get();
    let day = r.day.clone();
    let policy = OutputPolicy {
        overwrite,
        inputs: if r.from_file {
            vec![day.source.clone()]
        } else {
            Vec::new()
        },
        ..OutputPolicy::default()
    };
    let opts = WriteOptions {
        compression,
        ..WriteOptions::default()
    };
    py.detach(move || on_pool(move || lib_write_dng(&day.raw, &path, &opts, &policy)))
        .map_err(py_err)
}
