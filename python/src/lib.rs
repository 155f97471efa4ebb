//! Python bindings of day2night (`day2night._native`): a thin shell that converts types.
//! Every computation is the Rust library's (`day2night::synth::night::synthesize`, the same
//! path `day2night synth` runs), with the GIL released while it runs.
//!
//! Conversions: `errors` (the one mapping of library errors to Python exceptions), `args`
//! (integer arguments checked against the command line's bounds), `convert` (numpy arrays,
//! JSON values, `Raw.meta`), `synth_options` (keyword options to a job), `raw_from` (a
//! metadata dict to a raw). Entry points: `raw` (`Raw`, `read_dng`),
//! `synthesize` (`synthesize`, `write_outputs`), `render`, `metrics`, `pairs`
//! (`NightPairs` items), `patches` (`fresh_pair`: `FreshPatches` items), `dataset_units`,
//! `network_input` (`release_codes`, `demosaic_bilinear`: the release's network input),
//! `png` (`png_bytes`), `png_decode` (`png_decode`), `release_noise` (`release_noise`,
//! `RELEASE_NOISE_TABLE`: the release's noise), `pool` (`set_threads`, `threads`), `merge` (a
//! burst's mean).
#![forbid(unsafe_code)]

mod args;
mod burst;
mod convert;
mod dataset_units;
mod diagnostics;
mod errors;
mod merge;
mod metrics;
mod network_input;
mod option_default;
mod pairs;
mod patches;
mod png;
mod png_decode;
mod pool;
mod raw;
mod raw_from;
mod release_noise;
mod render;
mod synth_options;
mod synthesize;

use pyo3::prelude::*;

/// The library version.
#[pyfunction]
fn version() -> &'static str {
    day2night::VERSION
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<raw::Raw>()?;
    m.add_class::<synthesize::Synthesis>()?;
    m.add_function(wrap_pyfunction!(raw::read_dng, m)?)?;
    m.add_function(wrap_pyfunction!(synthesize::synthesize, m)?)?;
    m.add_function(wrap_pyfunction!(synthesize::write_outputs, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::encode_u8, m)?)?;
    m.add_function(wrap_pyfunction!(render::render_release_u8, m)?)?;
    m.add_function(wrap_pyfunction!(render::release_conflicts, m)?)?;
    m.add_function(wrap_pyfunction!(render::release_window, m)?)?;
    m.add_function(wrap_pyfunction!(network_input::release_codes, m)?)?;
    m.add_function(wrap_pyfunction!(network_input::demosaic_bilinear, m)?)?;
    m.add_function(wrap_pyfunction!(png::png_bytes, m)?)?;
    m.add_function(wrap_pyfunction!(png_decode::png_decode, m)?)?;
    m.add_function(wrap_pyfunction!(release_noise::release_noise, m)?)?;
    m.add("RELEASE_NOISE_TABLE", release_noise::table_dict(m.py())?)?;
    m.add_function(wrap_pyfunction!(metrics::psnr, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::ssim, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::delta_e2000, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::delta_e2000_map, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(pool::set_threads, m)?)?;
    m.add_function(wrap_pyfunction!(pool::threads, m)?)?;
    m.add_function(wrap_pyfunction!(raw::write_dng, m)?)?;
    m.add_function(wrap_pyfunction!(merge::merge, m)?)?;
    m.add("BOUNDS", args::bounds_dict(m.py())?)?;
    m.add("SYNTH_OPTIONS", synth_options::table_dict(m.py())?)?;
    m.add("KEYWORDS", synth_options::keywords_dict(m.py())?)?;
    m.add("SYNTH_CONSTANTS", synth_options::constants_list(m.py())?)?;
    // The parameters of the functions that bind their arguments themselves (the others'
    // are in their text signatures): python/pysrc/day2night/signatures.py.
    let params = pyo3::types::PyDict::new(m.py());
    for (name, required, list) in [
        ("synthesize", &["raw"][..], synthesize::PARAMS),
        ("fresh_pair", &["raw", "crop", "iso"][..], patches::PARAMS),
        ("dataset_units", &["day_dir"][..], dataset_units::PARAMS),
    ] {
        params.set_item(name, args::signature_list(m.py(), required, list)?)?;
    }
    m.add("PARAMETERS", params)?;
    // Every warning code with its summary (day2night.diagnostics makes a class of each).
    let codes: Vec<(&str, &str)> = day2night::Code::ALL
        .iter()
        .map(|c| (c.as_str(), c.summary()))
        .collect();
    m.add("WARNING_CODES", codes)?;
    // XYZ (D65) -> linear sRGB, three rows: day2night::color::xyz::XYZ_TO_SRGB, the one
    // definition (rawpy_meta.py undoes LibRaw's camera -> sRGB matrix with it).
    let xyz_to_srgb: Vec<Vec<f64>> = day2night::color::xyz::XYZ_TO_SRGB
        .chunks(3)
        .map(<[f64]>::to_vec)
        .collect();
    m.add("XYZ_TO_SRGB", xyz_to_srgb)?;
    m.add_function(wrap_pyfunction!(args::check_int, m)?)?;
    m.add_function(wrap_pyfunction!(pairs::night_pair, m)?)?;
    m.add_function(wrap_pyfunction!(patches::fresh_pair, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::dataset_units, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::write_unit, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::write_units, m)?)?;
    m.add_function(wrap_pyfunction!(dataset_units::write_manifest, m)?)?;
    Ok(())
}
