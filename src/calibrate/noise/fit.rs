//! The fits of the noise calibration (see the [module documentation](super)): `var = S y + O`
//! over one source's bins ([`fit_bins`]), one ISO from its sources ([`fit_iso`]), the laws
//! of S and O across ISOs ([`fit_iso_laws`]) and the model file ([`build_model`]).

use super::{BinStat, SourceStats, CLIP_MARGIN_SIGMAS, MIN_BIN_DOF, MIN_BIN_PIXELS};
use crate::calibrate::format::{
    IsoLaws, IsoModel, NoiseModelFile, PositionFit, NOISE_FORMAT, NOISE_UNITS,
};
use crate::calibrate::stats::{ls_through_origin, wls_line, LineFit};
use crate::diagnostics::{Code, Diagnostics};
use crate::error::{Error, Result};
use crate::raw::camera::CameraId;
use std::collections::BTreeMap;

/// Iteratively reweighted fit of `var = S mean + O` over bins (see module docs).
/// Returns the fit and the bins used.
pub fn fit_bins(bins: &[(BinStat, (f64, f64))]) -> Result<(LineFit, Vec<BinStat>)> {
    let usable: Vec<&(BinStat, (f64, f64))> = bins
        .iter()
        .filter(|(b, _)| b.pixels >= MIN_BIN_PIXELS && b.dof >= MIN_BIN_DOF)
        .collect();
    if usable.is_empty() {
        return Err(Error::invalid(format!(
            "no intensity bin has {MIN_BIN_PIXELS} unclipped pixels: the frames are too small or all clipped"
        )));
    }
    if usable.iter().all(|(b, _)| b.var <= 0.0) {
        return Err(Error::invalid(
            "zero variance across the frames at every intensity: identical frames or a noise-free source, nothing to fit",
        ));
    }
    let pos_mean = usable
        .iter()
        .map(|(b, _)| b.var)
        .filter(|v| *v > 0.0)
        .sum::<f64>()
        / usable.len() as f64;
    let floor = pos_mean * 1e-4;
    let mut sel: Vec<&(BinStat, (f64, f64))> = usable.clone();
    // First pass: weights from the measured variances themselves.
    let mut model: Option<LineFit> = None;
    for iter in 0..8 {
        if let Some(m) = model {
            // Drop bins too close to a clipping bound, by the current model.
            sel = usable
                .iter()
                .copied()
                .filter(|(b, (lo, hi))| {
                    let sd = (m.slope * b.mean + m.intercept).max(floor).sqrt();
                    b.mean - CLIP_MARGIN_SIGMAS * sd > *lo && b.mean + CLIP_MARGIN_SIGMAS * sd < *hi
                })
                .collect();
        }
        let x: Vec<f64> = sel.iter().map(|(b, _)| b.mean).collect();
        let y: Vec<f64> = sel.iter().map(|(b, _)| b.var).collect();
        let w: Vec<f64> = sel
            .iter()
            .map(|(b, _)| {
                let v = match model {
                    Some(m) => m.slope * b.mean + m.intercept,
                    None => b.var,
                }
                .max(floor);
                b.dof / (2.0 * v * v)
            })
            .collect();
        let f = wls_line(&x, &y, &w).map_err(|e| {
            Error::invalid(format!(
                "cannot fit the noise model ({e}): the scene needs a range of intensities (a ramp or textured scene, not a flat field)"
            ))
        })?;
        let done = model.is_some_and(|m| {
            (m.slope - f.slope).abs() <= 1e-9 * f.slope.abs().max(1e-30)
                && (m.intercept - f.intercept).abs() <= 1e-9 * f.intercept.abs().max(1e-30)
        });
        model = Some(f);
        if done && iter > 1 {
            break;
        }
    }
    let f = model.ok_or_else(|| Error::invalid("noise fit did not run"))?;
    Ok((f, sel.into_iter().map(|(b, _)| *b).collect()))
}

/// Fit one ISO from its sources (bursts and/or pairs of the same camera levels and CFA).
pub fn fit_iso(sources: &[SourceStats]) -> Result<IsoModel> {
    let first = sources
        .first()
        .ok_or_else(|| Error::invalid("no burst or pair to fit"))?;
    for s in sources {
        if s.bayer != first.bayer || s.black != first.black || s.white != first.white {
            return Err(Error::invalid(format!(
                "inputs at ISO {} disagree in CFA pattern or levels ({} black {} white {} vs {} black {} white {})",
                first.iso, s.bayer, s.black, s.white, first.bayer, first.black, first.white
            )));
        }
    }
    let scale = first.scale();
    let q = 1.0 / (12.0 * scale * scale);
    let mut positions = Vec::with_capacity(4);
    for p in 0..4 {
        let bins: Vec<(BinStat, (f64, f64))> = sources
            .iter()
            .flat_map(|s| s.bins[p].iter().map(move |b| (*b, s.bounds())))
            .collect();
        let (f, used) = fit_bins(&bins).map_err(|e| {
            Error::invalid(format!("ISO {} position {}: {}", first.iso, p, e.root()))
        })?;
        let s = f.slope;
        let o = f.intercept - q;
        let beta1 = s * scale;
        let beta2 = o * scale * scale - first.black * beta1;
        let color = match first.bayer.color_at(p / 2, p % 2) {
            0 => "R",
            1 => "G",
            _ => "B",
        };
        positions.push(PositionFit {
            position: p,
            color: color.into(),
            s,
            o,
            s_stderr: Some(f.slope_se),
            o_stderr: Some(f.intercept_se),
            beta1,
            beta2,
            r2: Some(f.r2),
            chi2_reduced: Some(if f.dof > 0 {
                f.chi2 / f.dof as f64
            } else {
                0.0
            }),
            bins: used.len(),
            pixels: used.iter().map(|b| b.pixels).sum(),
            clipped_pixels: sources.iter().map(|s| s.clipped[p]).sum(),
        });
    }
    let kinds: std::collections::BTreeSet<&str> = sources.iter().map(|s| s.kind).collect();
    Ok(IsoModel {
        iso: first.iso,
        positions: std::array::from_fn(|p| [positions[p].s, positions[p].o]),
        source: kinds.into_iter().collect::<Vec<_>>().join("+"),
        black: first.black,
        white: first.white,
        inputs: sources.len(),
        quantization_variance_removed: q,
        fits: positions,
    })
}

/// `S = c ISO` (least squares through the origin) and `O = a + b ISO^2` (least squares)
/// per position across ISO models; `None` with fewer than two distinct ISOs.
pub fn fit_iso_laws(models: &[IsoModel]) -> Option<IsoLaws> {
    if models.len() < 2 {
        return None;
    }
    let isos: Vec<f64> = models.iter().map(|m| m.iso as f64).collect();
    let iso2: Vec<f64> = isos.iter().map(|i| i * i).collect();
    let mut laws = IsoLaws {
        s_per_iso: [0.0; 4],
        o_at_iso0: [0.0; 4],
        o_per_iso2: [0.0; 4],
        isos: models.iter().map(|m| m.iso).collect(),
    };
    for p in 0..4 {
        let s: Vec<f64> = models.iter().map(|m| m.positions[p][0]).collect();
        let o: Vec<f64> = models.iter().map(|m| m.positions[p][1]).collect();
        laws.s_per_iso[p] = ls_through_origin(&isos, &s)?;
        let f = wls_line(&iso2, &o, &vec![1.0; o.len()]).ok()?;
        laws.o_at_iso0[p] = f.intercept;
        laws.o_per_iso2[p] = f.slope;
    }
    Some(laws)
}

/// Assemble the model file from measured sources and other models (NoiseProfile tags, image
/// estimates), recording `camera`. Measured ISOs take precedence over the others at the
/// same ISO, and earlier others over later ones (returned as warnings).
pub fn build_model(
    sources: Vec<SourceStats>,
    profiles: Vec<IsoModel>,
    camera: Option<CameraId>,
) -> Result<(NoiseModelFile, Diagnostics)> {
    let mut by_iso: BTreeMap<u32, Vec<SourceStats>> = BTreeMap::new();
    for s in sources {
        by_iso.entry(s.iso).or_default().push(s);
    }
    let mut models: BTreeMap<u32, IsoModel> = BTreeMap::new();
    for (iso, srcs) in &by_iso {
        models.insert(*iso, fit_iso(srcs)?);
    }
    let mut warnings = Diagnostics::new();
    for p in profiles {
        match models.entry(p.iso) {
            std::collections::btree_map::Entry::Occupied(o) => warnings.warn(
                Code::CalibrateIsoOverlap,
                format!(
                    "ISO {}: the {} model takes precedence over the {} one",
                    p.iso,
                    o.get().source,
                    p.source
                ),
            ),
            std::collections::btree_map::Entry::Vacant(v) => {
                v.insert(p);
            }
        }
    }
    if models.is_empty() {
        return Err(Error::invalid(
            "nothing to calibrate: give --burst, --pair, --from-noise-profile or --from-image",
        ));
    }
    let isos: Vec<IsoModel> = models.into_values().collect();
    for m in &isos {
        for f in &m.fits {
            if f.o < 0.0 || f.s < 0.0 {
                warnings.warn(Code::CalibrateNegativeParameter, format!(
                    "ISO {} position {}: negative parameter (S {:.3e}, O {:.3e}); synth clamps variances at 0",
                    m.iso, f.position, f.s, f.o
                ));
            }
        }
    }
    Ok((
        NoiseModelFile {
            format: NOISE_FORMAT.into(),
            units: NOISE_UNITS.into(),
            source: format!(
                "day2night {} calibrate noise{}",
                crate::VERSION,
                camera
                    .as_ref()
                    .map(|c| format!(" ({})", c.label()))
                    .unwrap_or_default()
            ),
            camera,
            iso_laws: fit_iso_laws(&isos),
            isos,
        },
        warnings,
    ))
}
