//! Assembling the report page from the manifest(s), the sidecars and the outputs.

use super::html::escape;
use super::plot::{self, Ellipse};
use super::thumb::Rgb8;
use crate::dataset::{manifest, Kind, Record, Status};
use crate::error::{Error, Result, ResultExt};
use crate::output::{write_bytes_atomic, OutputPolicy};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Options of `day2night report`.
#[derive(Debug, Clone)]
pub struct ReportOptions {
    /// The dataset folder (holds manifest*.jsonl).
    pub out_dir: PathBuf,
    /// DAY_DIR the dataset was made from (for the day renders); when `None`, the day
    /// column says it is not available.
    pub day_dir: Option<PathBuf>,
    /// Samples shown in detail (spread evenly over the dataset).
    pub samples: usize,
    /// Longest side of thumbnails, pixels.
    pub thumb: usize,
}

/// A light drawn on the report (centre in thumbnail-independent relative coordinates).
#[derive(Debug, Clone, PartialEq)]
pub struct LightMark {
    /// Class index into [`Illuminants::kinds`].
    pub kind: usize,
    /// Centre as a fraction of (width, height) of the active area, if the light has one.
    pub centre: Option<[f64; 2]>,
    /// Chromaticity of its illuminant in the plot's axes.
    pub chroma: [f64; 2],
}

/// Illuminant plot data of one sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Illuminants {
    /// Names of the light classes (e.g. ambient, local, bulb).
    pub kinds: Vec<String>,
    /// The plot's axis names.
    pub axes: (String, String),
    /// The sampling distribution (dictionary fit), if known.
    pub ellipse: Option<Ellipse>,
    /// The lights.
    pub lights: Vec<LightMark>,
}

/// Where the pictures and sampled values come from: the real synthesis/ISP in the CLI,
/// fakes in tests.
pub trait Visuals {
    /// Day render thumbnail of an input DNG.
    fn day(&self, input: &Path, max: usize) -> Result<Rgb8>;
    /// Render thumbnail of a night DNG.
    fn night(&self, dng: &Path, max: usize) -> Result<Rgb8>;
    /// Full-resolution centre crop (`size` x `size`) of the render of a noisy DNG.
    fn noisy_crop(&self, dng: &Path, size: usize) -> Result<Rgb8>;
    /// Light masks (name, thumbnail) from a sidecar, at a thumbnail of longest side `max`,
    /// in the geometry (DefaultCrop, orientation) of the render of `night_dng` (the clean
    /// night DNG of the same unit) so they line up with the night thumbnail; the whole
    /// active area, unrotated, when `None`.
    fn masks(
        &self,
        sidecar: &serde_json::Value,
        night_dng: Option<&Path>,
        max: usize,
    ) -> Result<Vec<(String, Rgb8)>>;
    /// Sampled illuminants and light centres from a sidecar.
    fn illuminants(&self, sidecar: &serde_json::Value) -> Result<Illuminants>;
    /// The same lights in CIE 1931 xy (axes `x`, `y`, no ellipse): each light's camera
    /// neutral through the colour matrices of `night_dng` (the clean night DNG, which keeps
    /// the day file's).
    fn illuminants_xy(
        &self,
        sidecar: &serde_json::Value,
        night_dng: Option<&Path>,
    ) -> Result<Illuminants>;
    /// Dimming factor from a sidecar.
    fn dim_factor(&self, sidecar: &serde_json::Value) -> Option<f64>;
}

/// What the report contains.
#[derive(Debug, Clone, Default)]
pub struct ReportSummary {
    /// The page.
    pub page: PathBuf,
    /// Records in the manifest(s).
    pub records: usize,
    /// Samples shown in detail.
    pub samples: usize,
    /// PNG files written.
    pub pngs: Vec<PathBuf>,
    /// Things that could not be shown, with why (the subject is the sample's id).
    pub warnings: crate::diagnostics::Diagnostics,
}

/// A report warning about sample `id`: something that could not be shown.
fn not_available(id: &str, message: String) -> crate::diagnostics::Warning {
    crate::diagnostics::Warning::new(crate::diagnostics::Code::ReportNotAvailable, message)
        .about(id)
}

struct Cell {
    title: String,
    html: String,
}

/// Build `OUT_DIR/report/index.html` (+ `report/img/*.png`).
pub fn build(opts: &ReportOptions, vis: &dyn Visuals) -> Result<ReportSummary> {
    let out = &opts.out_dir;
    if !out.is_dir() {
        let why = if out.exists() {
            "not a folder (give the folder `day2night dataset` wrote)"
        } else {
            "no such folder"
        };
        return Err(Error::invalid(why).in_file(out));
    }
    let records = latest_records(out)?;
    let report_dir = out.join("report");
    let img_dir = report_dir.join("img");
    std::fs::create_dir_all(&img_dir)
        .map_err(Error::Io)
        .in_file(&img_dir)?;
    let mut summary = ReportSummary {
        page: report_dir.join("index.html"),
        records: records.len(),
        ..Default::default()
    };

    let ok: Vec<&Record> = records.iter().filter(|r| r.status == Status::Ok).collect();
    let failed: Vec<&Record> = records.iter().filter(|r| r.status != Status::Ok).collect();
    let sidecars: Vec<Option<serde_json::Value>> =
        ok.iter().map(|r| read_sidecar(out, r)).collect();

    let plots = dataset_plots(&ok, &sidecars, vis)?;

    // Samples spread evenly.
    let n = opts.samples.min(ok.len());
    let picks: Vec<usize> = if n == 0 {
        vec![]
    } else {
        let mut v: Vec<usize> = (0..n).map(|i| i * ok.len() / n).collect();
        v.dedup();
        v
    };
    let mut sample_html = String::new();
    for &i in &picks {
        let (Some(r), Some(sc)) = (ok.get(i), sidecars.get(i)) else {
            continue;
        };
        sample_html.push_str(&sample_section(opts, vis, r, sc, &img_dir, &mut summary));
        summary.samples += 1;
    }

    let train = records
        .iter()
        .filter(|r| r.split == crate::dataset::Split::Train)
        .count();
    let fail_html = failures_html(&failed);
    let page = format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>day2night dataset report</title>
<link rel="icon" href="data:,">
<style>
body {{ font-family: sans-serif; margin: 1.5em; background: #fafafa; color: #222; }}
.row {{ display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; }}
figure {{ margin: 0; background: #fff; padding: 6px; border: 1px solid #ddd; }}
figcaption {{ font-size: 12px; color: #555; }}
.na {{ width: 240px; color: #a33; font-size: 12px; }}
section.sample {{ border-top: 1px solid #ccc; margin-top: 1em; }}
h3 small {{ font-weight: normal; color: #666; }}
table {{ border-collapse: collapse; }} td, th {{ border: 1px solid #ccc; padding: 2px 6px; font-size: 13px; }}
</style>
<script>
// Self-check for headless tests: report images that failed to load on the console.
window.addEventListener('load', function () {{
  for (const img of document.images) {{
    if (!img.complete || img.naturalWidth === 0) console.error('image failed to load: ' + img.getAttribute('src'));
  }}
}});
</script></head><body>
<h1>day2night dataset report</h1>
<p>{records} units ({ok} ok, {nfail} failed; {train} train, {val} val), {nsamples} samples shown. Generated by {software}.</p>
<h2>Dataset</h2>
<div class="row">{p0}{p1}{p2}{p3}</div>
{fail_html}
<h2>Samples</h2>
{sample_html}
</body></html>
"#,
        records = records.len(),
        ok = ok.len(),
        nfail = failed.len(),
        train = train,
        val = records.len() - train,
        nsamples = summary.samples,
        software = escape(&crate::software_name()),
        p0 = plots[0],
        p1 = plots[1],
        p2 = plots[2],
        p3 = plots[3],
    );
    let policy = OutputPolicy {
        overwrite: true,
        inputs: vec![],
        ..OutputPolicy::default()
    };
    write_bytes_atomic(&summary.page, &policy, page.as_bytes())?;
    Ok(summary)
}

/// The latest record of every unit in the manifests of `out`.
fn latest_records(out: &Path) -> Result<Vec<Record>> {
    let manifests = manifest::all_manifests(out)?;
    if manifests.is_empty() {
        return Err(Error::invalid("no manifest*.jsonl here: not a dataset folder").in_file(out));
    }
    let mut all = Vec::new();
    for m in &manifests {
        all.extend(manifest::read(m)?.records);
    }
    Ok(manifest::latest(all).into_values().collect())
}

/// The dataset-level plots: dimming factors, night neutrals, noisy outputs per ISO.
fn dataset_plots(
    ok: &[&Record],
    sidecars: &[Option<serde_json::Value>],
    vis: &dyn Visuals,
) -> Result<[String; 4]> {
    let dims: Vec<f64> = sidecars
        .iter()
        .flatten()
        .filter_map(|s| vis.dim_factor(s))
        .collect();
    let rg: Vec<f64> = ok
        .iter()
        .filter_map(|r| r.night_neutral.map(|n| n[0] / n[1]))
        .collect();
    let bg: Vec<f64> = ok
        .iter()
        .filter_map(|r| r.night_neutral.map(|n| n[2] / n[1]))
        .collect();
    let mut isos: BTreeMap<u32, usize> = BTreeMap::new();
    for r in ok {
        for i in &r.iso {
            *isos.entry(*i).or_default() += 1;
        }
    }
    let iso_bars: Vec<(String, usize)> = isos.iter().map(|(k, v)| (k.to_string(), *v)).collect();
    Ok([
        plot::histogram("Dimming factor", "factor", &dims, 20)?,
        plot::histogram("Night neutral r/g", "r/g", &rg, 20)?,
        plot::histogram("Night neutral b/g", "b/g", &bg, 20)?,
        plot::bars("Noisy outputs per ISO", "ISO", &iso_bars)?,
    ])
}

/// One sample's section of the page: its renders (PNGs written to `img_dir`), masks and
/// illuminant plots; what cannot be made is said in the page and in `summary.warnings`.
fn sample_section(
    opts: &ReportOptions,
    vis: &dyn Visuals,
    r: &Record,
    sc: &Option<serde_json::Value>,
    img_dir: &Path,
    summary: &mut ReportSummary,
) -> String {
    let out = &opts.out_dir;
    let id = sample_id(r);
    let mut cells: Vec<Cell> = Vec::new();
    let mut png = |name: &str, title: &str, res: Result<Rgb8>, summary: &mut ReportSummary| {
        let file = format!("{}_{name}.png", safe(&id));
        let html = match res.and_then(|img| {
            img.write_png(&img_dir.join(&file))?;
            Ok(img)
        }) {
            Ok(img) => {
                summary.pngs.push(img_dir.join(&file));
                format!(
                    "<img src=\"img/{}\" width=\"{}\" height=\"{}\" alt=\"{}\">",
                    escape(&file),
                    img.width,
                    img.height,
                    escape(title)
                )
            }
            Err(e) => {
                summary
                    .warnings
                    .push(not_available(&id, format!("{title}: {e}")));
                format!(
                    "<p class=\"na\">not available: {}</p>",
                    escape(&e.to_string())
                )
            }
        };
        cells.push(Cell {
            title: title.to_string(),
            html,
        });
    };
    let day = match &opts.day_dir {
        Some(d) => vis.day(&d.join(&r.input), opts.thumb),
        None => Err(Error::invalid("DAY_DIR unknown (pass --day-dir)")),
    };
    png("day", "Day render", day, summary);
    let clean_path = first_output(r, Kind::CleanRaw).map(|p| out.join(p));
    let clean = clean_path
        .as_deref()
        .ok_or_else(|| Error::invalid("no clean raw output"))
        .and_then(|p| vis.night(p, opts.thumb));
    png("night", "Clean night render", clean, summary);
    let noisy = noisy_output(r)
        .ok_or_else(|| Error::invalid("no noisy output"))
        .and_then(|p| vis.noisy_crop(&out.join(p), 256));
    let noisy_title = format!(
        "Noisy crop (ISO {})",
        r.iso
            .last()
            .map(|i| i.to_string())
            .unwrap_or_else(|| "?".into())
    );
    png("noisy", &noisy_title, noisy, summary);
    fn missing<T>() -> Result<T> {
        Err(Error::invalid("sidecar missing or unreadable"))
    }
    let (masks, ill, ill_xy) = match sc {
        Some(sc) => (
            vis.masks(sc, clean_path.as_deref(), opts.thumb),
            vis.illuminants(sc),
            vis.illuminants_xy(sc, clean_path.as_deref()),
        ),
        None => (missing(), missing(), missing()),
    };
    match masks {
        Ok(ms) => {
            for (name, img) in ms {
                let title = format!("Mask: {name}");
                let file_name = name.split(" (").next().unwrap_or(&name).to_string();
                png(
                    &format!("mask_{}", safe(&file_name)),
                    &title,
                    Ok(img),
                    summary,
                );
            }
        }
        Err(e) => png("mask", "Light masks", Err(e), summary),
    }
    cells.extend(plot_cells(ill, ill_xy, &id, summary));
    let nn = r
        .night_neutral
        .map(|n| format!("{:.3}, {:.3}, {:.3}", n[0], n[1], n[2]))
        .unwrap_or_else(|| "-".into());
    let mut html = format!(
            "<section class=\"sample\"><h3>{} <small>({}, variant {}, seed {}, ISO {:?}, night neutral {})</small></h3><div class=\"row\">",
            escape(&r.input),
            r.split.name(),
            r.variant,
            r.seed,
            r.iso,
            escape(&nn)
        );
    for c in cells {
        html.push_str(&format!(
            "<figure>{}<figcaption>{}</figcaption></figure>",
            c.html,
            escape(&c.title)
        ));
    }
    html.push_str("</div></section>\n");
    html
}

/// The points and kinds of the plotted lights.
fn light_points(il: &Illuminants) -> (Vec<(f64, f64, usize)>, Vec<&str>) {
    let pts = il
        .lights
        .iter()
        .map(|l| (l.chroma[0], l.chroma[1], l.kind))
        .collect();
    let kinds = il.kinds.iter().map(|s| s.as_str()).collect();
    (pts, kinds)
}

/// A plot's SVG, or "not available" in the page and in `summary.warnings` (about `id`,
/// naming `what`).
fn svg_or_na(plot: Result<String>, id: &str, what: &str, summary: &mut ReportSummary) -> String {
    plot.unwrap_or_else(|e| {
        summary
            .warnings
            .push(not_available(id, format!("{what}: {e}")));
        format!(
            "<p class=\"na\">not available: {}</p>",
            escape(&e.to_string())
        )
    })
}

/// The sampled illuminants over the dictionary ellipse, and in CIE xy.
fn plot_cells(
    ill: Result<Illuminants>,
    ill_xy: Result<Illuminants>,
    id: &str,
    summary: &mut ReportSummary,
) -> [Cell; 2] {
    let ill_plot = ill.and_then(|il| {
        let (pts, kinds) = light_points(&il);
        plot::chromaticity(
            "Sampled illuminants",
            (&il.axes.0, &il.axes.1),
            &pts,
            &kinds,
            il.ellipse,
        )
    });
    let ill_cell = Cell {
        title: "Illuminants (over the dictionary ellipse, 1-3 sigma)".into(),
        html: svg_or_na(ill_plot, id, "illuminants", summary),
    };
    let xy_plot = ill_xy.and_then(|il| {
        let (pts, kinds) = light_points(&il);
        super::plot_xy::planckian("Lights in CIE xy", &pts, &kinds)
    });
    let xy_cell = Cell {
        title: "Lights in CIE 1931 xy through the camera's colour matrices, against the \
                    Planckian locus (ticks: CCT; grey: Duv +-0.01)"
            .into(),
        html: svg_or_na(xy_plot, id, "illuminants in xy", summary),
    };
    [ill_cell, xy_cell]
}

/// The failures table (empty without failures).
fn failures_html(failed: &[&Record]) -> String {
    let mut fail_html = String::new();
    if !failed.is_empty() {
        fail_html.push_str(
            "<h2>Failures</h2><table><tr><th>input</th><th>variant</th><th>error</th></tr>",
        );
        for r in failed {
            fail_html.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
                escape(&r.input),
                r.variant,
                escape(r.error.as_deref().unwrap_or(""))
            ));
        }
        fail_html.push_str("</table>");
    }
    fail_html
}

/// Output id of a record (its sidecar's file stem).
fn sample_id(r: &Record) -> String {
    first_output(r, Kind::Meta)
        .and_then(|p| p.rsplit('/').next())
        .map(|n| n.trim_end_matches(".json").to_string())
        .unwrap_or_else(|| format!("{}_v{}", r.input.replace('/', "__"), r.variant))
}

fn safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn first_output(r: &Record, kind: Kind) -> Option<&str> {
    r.outputs
        .iter()
        .find(|o| o.kind == kind)
        .map(|o| o.path.as_str())
}

/// The noisy output of the highest ISO.
fn noisy_output(r: &Record) -> Option<&str> {
    let noisy = || r.outputs.iter().filter(|o| o.kind == Kind::NoisyRaw);
    r.iso
        .iter()
        .max()
        .and_then(|iso| {
            let tag = format!("_iso{iso}.");
            noisy().find(|o| o.path.contains(&tag))
        })
        .or_else(|| noisy().next_back())
        .map(|o| o.path.as_str())
}

fn read_sidecar(out: &Path, r: &Record) -> Option<serde_json::Value> {
    let p = out.join(first_output(r, Kind::Meta)?);
    let bytes = std::fs::read(p).ok()?;
    serde_json::from_slice(&bytes).ok()
}
