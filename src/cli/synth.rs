//! `day2night synth`: clean and noisy night DNGs, targets and a sidecar per input and
//! variant (CLI.md). Inputs are processed one after another (each with rayon inside);
//! an input that cannot be used is reported and skipped, and the exit code is 1 at the end.

use super::{usage, CmdResult, Failure};
use day2night::dng::write::{write_dng, Compression, WriteOptions};
use day2night::error::Error;
use day2night::exr::{standard_attributes, write_exr, ExrOptions};
use day2night::isp::render::{render_input, render_linear, RenderOptions};
use day2night::noise::NoiseModel;
use day2night::output::{write_bytes_atomic, OutputPolicy};
use day2night::png::{write_png, PngOptions};
use day2night::synth::dictionaries::{self, embedded};
use day2night::synth::sidecar::{sha256_hex, CalibrationInfo, InputInfo, OutputInfo, Sidecar};
use day2night::synth::{
    self, night_meta, run_clean, run_noise, Calibration, Covariance, Gaussian2, MaskEval, Mode,
    Plan, RelightFormula, SynthOptions,
};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Relighting mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ModeArg {
    /// Several local lights (the paper's method).
    Local,
    /// One night illuminant.
    Global,
    /// Dimmed day image (baseline).
    Dimmed,
    /// The day image itself (baseline).
    Day,
}

/// Local relighting formula.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormulaArg {
    /// The authors' released code.
    Release,
    /// The paper's equation.
    Paper,
}

/// Targets to render.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TargetArg {
    /// Linear EXR.
    Exr,
    /// sRGB PNG.
    Png,
    /// Both.
    Both,
    /// None.
    None,
}

/// DNG compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CompressionArg {
    /// Uncompressed.
    None,
    /// Lossless JPEG.
    Ljpeg,
}

/// Covariance estimator of the illuminant fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum CovArg {
    /// 1/(M-1) (released code).
    Unbiased,
    /// 1/M (the paper's equation 2).
    Ml,
}

/// Arguments of `day2night synth`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:\n  \
  day2night synth day.dng -o night/                      # clean + ISO 1600/3200 + target.exr\n  \
  day2night synth a.dng b.dng -o out/ --seed 7 --variants 3 --iso 800,6400 --target both\n  \
  day2night synth day.dng -o again/ --replay night/day.json   # byte-identical outputs\n\n\
Outputs per input <stem> and variant K (the _vK part, K = 1.., only when --variants > 1):\n  \
<stem>[_vK]_clean.dng, <stem>[_vK]_iso<ISO>.dng, <stem>[_vK]_target.exr|png,\n  \
<stem>[_vK]_input.exr (--input-exr), <stem>[_vK].json (sidecar).")]
pub struct SynthArgs {
    /// Day DNG files.
    #[arg(required = true, value_name = "DAY.dng")]
    pub inputs: Vec<PathBuf>,
    /// Output directory (created if missing).
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    pub out: PathBuf,
    /// Master seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Variants per input.
    #[arg(long, default_value_t = 1)]
    pub variants: u32,
    /// ISOs of the noisy outputs, comma-separated, or `none`.
    #[arg(long, default_value = "1600,3200", value_name = "LIST|none")]
    pub iso: String,
    /// Relighting mode.
    #[arg(long, value_enum, default_value = "local")]
    pub mode: ModeArg,
    /// Local relighting formula.
    #[arg(long = "relight-formula", value_enum, default_value = "release")]
    pub relight_formula: FormulaArg,
    /// Saturated bulbs (default 5 with the release formula, 0 with the paper's).
    #[arg(long)]
    pub bulbs: Option<u32>,
    /// Calibration files and finer options (boxed to keep the subcommand enum small).
    #[command(flatten)]
    pub extra: Box<ExtraArgs>,
    /// Targets to render from the clean night raw.
    #[arg(long, value_enum, default_value = "exr")]
    pub target: TargetArg,
    /// Also write the network input (normalized, white-balanced, demosaiced noisy raw).
    #[arg(long = "input-exr")]
    pub input_exr: bool,
    /// DNG compression.
    #[arg(long, value_enum, default_value = "none")]
    pub compression: CompressionArg,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Replace existing outputs.
    #[arg(long)]
    pub overwrite: bool,
    /// Truncate instead of rounding when denormalizing (released code, -0.5 DN bias).
    #[arg(long)]
    pub truncate: bool,
}

/// Less common `synth` options.
#[derive(Debug, clap::Args)]
pub struct ExtraArgs {
    /// Local lights besides the ambient (default 4 release; paper: 4 to 6 drawn).
    #[arg(long)]
    pub lights: Option<u32>,
    /// Night illuminant dictionary (JSON); default: the embedded paper phone's.
    #[arg(long, value_name = "FILE.json")]
    pub illuminants: Option<PathBuf>,
    /// Illuminant covariance estimator.
    #[arg(long, value_enum, default_value = "unbiased")]
    pub covariance: CovArg,
    /// Night brightness dictionary (JSON): dim to a drawn mean instead of U(0.55, 0.9).
    #[arg(long, value_name = "FILE.json")]
    pub brightness: Option<PathBuf>,
    /// Noise model (day2night-noise-model/1 JSON); default: the input's NoiseProfile, else
    /// the embedded paper phone table.
    #[arg(long = "noise-model", value_name = "FILE.json")]
    pub noise_model: Option<PathBuf>,
    /// Re-run a sidecar's plan on its input (one input): byte-identical outputs.
    #[arg(long, value_name = "SIDECAR.json")]
    pub replay: Option<PathBuf>,
    /// Day neutral r,g,b overriding (or replacing a missing) AsShotNeutral.
    #[arg(long = "day-neutral", value_name = "R,G,B")]
    pub day_neutral: Option<String>,
    /// Mask evaluation: separable (default), exact, or truncated:K (K sigmas).
    #[arg(long = "mask-eval", default_value = "separable")]
    pub mask_eval: String,
    /// EXR compression (lossless: zip (default), piz (faster, smaller on renders), zips,
    /// rle, none; lossy for half: pxr24, b44, b44a). See docs/benchmarks.md.
    #[arg(long = "exr-compression", default_value = "zip", value_name = "KIND")]
    pub exr_compression: String,
}

pub(super) fn parse_isos(s: &str) -> Result<Vec<u32>, Failure> {
    if s.trim().eq_ignore_ascii_case("none") {
        return Ok(vec![]);
    }
    let mut v = Vec::new();
    for part in s.split(',') {
        let iso: u32 = part.trim().parse().map_err(|_| {
            usage(format!(
                "--iso: {:?} is not an ISO (use e.g. 1600,3200 or none)",
                part
            ))
        })?;
        if iso == 0 {
            return Err(usage("--iso: ISO 0"));
        }
        if !v.contains(&iso) {
            v.push(iso);
        }
    }
    Ok(v)
}

pub(super) fn parse_neutral(s: &str) -> Result<[f64; 3], Failure> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| usage(format!("--day-neutral: {:?} is not r,g,b", s)))?;
    match v.as_slice() {
        [r, g, b] => Ok([*r, *g, *b]),
        _ => Err(usage(format!("--day-neutral: {:?} is not r,g,b", s))),
    }
}

pub(super) fn parse_mask_eval(s: &str) -> Result<MaskEval, Failure> {
    match s {
        "separable" => Ok(MaskEval::Separable),
        "exact" => Ok(MaskEval::Exact),
        _ => match s
            .strip_prefix("truncated:")
            .and_then(|k| k.parse::<f64>().ok())
        {
            Some(k) if k > 0.0 && k.is_finite() => Ok(MaskEval::Truncated { k }),
            _ => Err(usage(format!(
                "--mask-eval: {:?} (use separable, exact or truncated:K)",
                s
            ))),
        },
    }
}

fn target_name(t: TargetArg) -> &'static str {
    match t {
        TargetArg::Exr => "exr",
        TargetArg::Png => "png",
        TargetArg::Both => "both",
        TargetArg::None => "none",
    }
}

fn target_from_name(s: &str) -> Result<TargetArg, Failure> {
    Ok(match s {
        "exr" => TargetArg::Exr,
        "png" => TargetArg::Png,
        "both" => TargetArg::Both,
        "none" => TargetArg::None,
        _ => {
            return Err(Failure::from(Error::malformed(format!(
                "sidecar target {:?}",
                s
            ))))
        }
    })
}

/// Everything decided once per run.
struct Job {
    opts: SynthOptions,
    cal: Calibration,
    variants: u32,
    target: TargetArg,
    input_exr: bool,
    compression: CompressionArg,
    exr: ExrOptions,
    seed: u64,
    out: PathBuf,
    policy: OutputPolicy,
    replay: Option<Sidecar>,
}

/// Run `day2night synth`.
pub fn run(args: SynthArgs) -> CmdResult {
    if args.variants == 0 {
        return Err(usage("--variants must be at least 1"));
    }
    if args.jobs == Some(0) {
        return Err(usage("--jobs must be at least 1"));
    }
    let replay = match &args.extra.replay {
        Some(p) => {
            if args.inputs.len() != 1 {
                return Err(usage(
                    "--replay takes exactly one input (the sidecar's day DNG)",
                ));
            }
            Some(synth::sidecar::Sidecar::read(p)?)
        }
        None => None,
    };
    let job = match replay {
        Some(sc) => Job {
            opts: sc.options.clone(),
            cal: Calibration {
                illuminants: sc.calibration.illuminants.clone(),
                brightness: sc.calibration.brightness.clone(),
                noise: None,
            },
            variants: sc.outputs.variants,
            target: target_from_name(&sc.outputs.target)?,
            input_exr: sc.outputs.input_exr,
            compression: if sc.outputs.compression == "ljpeg" {
                CompressionArg::Ljpeg
            } else {
                CompressionArg::None
            },
            exr: ExrOptions {
                compression: sc.outputs.exr_compression.parse()?,
                ..ExrOptions::default()
            },
            seed: sc.plan.seed,
            out: args.out.clone(),
            policy: OutputPolicy {
                overwrite: args.overwrite,
                inputs: args.inputs.clone(),
            },
            replay: Some(sc),
        },
        None => {
            let opts = SynthOptions {
                mode: match args.mode {
                    ModeArg::Local => Mode::Local,
                    ModeArg::Global => Mode::Global,
                    ModeArg::Dimmed => Mode::Dimmed,
                    ModeArg::Day => Mode::Day,
                },
                formula: match args.relight_formula {
                    FormulaArg::Release => RelightFormula::Release,
                    FormulaArg::Paper => RelightFormula::Paper,
                },
                bulbs: args.bulbs,
                local_lights: args.extra.lights,
                isos: parse_isos(&args.iso)?,
                truncate: args.truncate,
                covariance: match args.extra.covariance {
                    CovArg::Unbiased => Covariance::Unbiased,
                    CovArg::Ml => Covariance::MaximumLikelihood,
                },
                day_neutral: args
                    .extra
                    .day_neutral
                    .as_deref()
                    .map(parse_neutral)
                    .transpose()?,
                mask_eval: parse_mask_eval(&args.extra.mask_eval)?,
                ..SynthOptions::default()
            };
            opts.validate().map_err(usage)?;
            let illuminants = match &args.extra.illuminants {
                Some(p) => {
                    Gaussian2::from_source(&dictionaries::load_illuminants(p)?, opts.covariance)
                        .map_err(|e| e.in_file(p))?
                }
                None => Gaussian2::fit(&embedded::illuminants(), opts.covariance)?,
            };
            let brightness = args
                .extra
                .brightness
                .as_deref()
                .map(dictionaries::load_brightness)
                .transpose()?;
            let noise = args
                .extra
                .noise_model
                .as_deref()
                .map(NoiseModel::from_file)
                .transpose()?;
            Job {
                opts,
                cal: Calibration {
                    illuminants,
                    brightness,
                    noise,
                },
                variants: args.variants,
                target: args.target,
                input_exr: args.input_exr,
                compression: args.compression,
                exr: ExrOptions {
                    compression: args
                        .extra
                        .exr_compression
                        .parse()
                        .map_err(|e: Error| usage(format!("--exr-compression: {}", e)))?,
                    ..ExrOptions::default()
                },
                seed: args.seed,
                out: args.out.clone(),
                policy: OutputPolicy {
                    overwrite: args.overwrite,
                    inputs: args.inputs.clone(),
                },
                replay: None,
            }
        }
    };
    std::fs::create_dir_all(&job.out).map_err(|e| Error::from(e).in_file(&job.out))?;
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = args.jobs {
        builder = builder.num_threads(n);
    }
    let pool = builder.build().map_err(|e| {
        Failure::from(anyhow::anyhow!(
            "cannot start {} worker threads: {e}",
            args.jobs.unwrap_or(0)
        ))
    })?;

    let total = args.inputs.len() as u64 * job.variants as u64;
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(total);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{bar:30} {pos}/{len} {msg} [{elapsed_precise}]",
        ) {
            b.set_style(style);
        }
        Some(b)
    } else {
        None
    };
    let mut failed = 0usize;
    for input in &args.inputs {
        if let Some(b) = &bar {
            b.set_message(input.display().to_string());
        }
        let r = pool.install(|| process_input(input, &job, bar.as_ref()));
        if let Err(e) = r {
            failed += 1;
            let msg = format!("day2night: {}", e.in_file(input));
            match &bar {
                Some(b) => b.println(msg),
                None => eprintln!("{msg}"),
            }
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if failed > 0 {
        return Err(Failure::from(anyhow::anyhow!(
            "{} of {} inputs failed",
            failed,
            args.inputs.len()
        )));
    }
    Ok(())
}

fn process_input(
    input: &Path,
    job: &Job,
    bar: Option<&indicatif::ProgressBar>,
) -> day2night::Result<()> {
    let bytes = std::fs::read(input)?;
    // Hash (for the sidecar) and decode at the same time: both only read `bytes`.
    let (sha, img) = rayon::join(
        || sha256_hex(&bytes),
        || day2night::dng::read::read_dng_bytes(&bytes),
    );
    let img = img?;
    drop(bytes);
    let name = input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| input.display().to_string());
    let stem = input
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| name.clone());
    let variants: Vec<u32> = match &job.replay {
        Some(sc) => {
            if sc.input.sha256 != sha {
                return Err(Error::invalid(format!(
                    "input does not match the sidecar (sha256 {} expected {})",
                    sha, sc.input.sha256
                )));
            }
            vec![sc.plan.variant]
        }
        None => (0..job.variants).collect(),
    };
    for v in variants {
        let plan = match &job.replay {
            Some(sc) => sc.plan.clone(),
            None => synth::plan(&img, &name, job.seed, v, &job.opts, &job.cal)?,
        };
        for w in &plan.warnings {
            let msg = format!("day2night: {}: warning: {}", input.display(), w);
            match bar {
                Some(b) => b.println(msg),
                None => eprintln!("{msg}"),
            }
        }
        process_variant(input, &img, &plan, &stem, &sha, job)?;
        if let Some(b) = bar {
            b.inc(1);
        }
    }
    Ok(())
}

fn process_variant(
    input: &Path,
    img: &day2night::RawImage,
    plan: &Plan,
    stem: &str,
    sha: &str,
    job: &Job,
) -> day2night::Result<()> {
    let base = if job.variants > 1 {
        format!("{}_v{}", stem, plan.variant + 1)
    } else {
        stem.to_string()
    };
    let wopts = WriteOptions {
        compression: match job.compression {
            CompressionArg::None => Compression::None,
            CompressionArg::Ljpeg => Compression::Ljpeg,
        },
        ..WriteOptions::default()
    };
    let mut stages = plan.stages.clone();
    let (mut clean, report) = run_clean(img, plan)?;
    clean.meta = night_meta(&img.meta, plan, plan.clean_iso, &plan.clean_noise);
    let clean = clean;
    let clean_name = format!("{}_clean.dng", base);
    let noisy_names: Vec<String> = plan
        .noise
        .iter()
        .map(|np| format!("{}_iso{}.dng", base, np.iso))
        .collect();
    let neutral = plan.night_neutral;
    // One attribute only: the exr crate keeps custom attributes in a HashMap, so several
    // would be written in a per-process random order (non-deterministic bytes).
    let summary = standard_attributes(input, neutral)
        .into_iter()
        .map(|(k, v)| format!("{}={}", k.trim_start_matches("day2night:"), v))
        .chain([
            format!("seed={}", plan.seed),
            format!("variant={}", plan.variant),
        ])
        .collect::<Vec<_>>()
        .join("; ");
    let attrs = vec![("day2night:synth".to_string(), summary)];
    let want_exr = matches!(job.target, TargetArg::Exr | TargetArg::Both);
    let want_png = matches!(job.target, TargetArg::Png | TargetArg::Both);
    let exr_name = format!("{}_target.exr", base);
    let png_name = format!("{}_target.png", base);

    // The clean DNG write, the noisy raws (computed and written one ISO after the other) and
    // the target render run as concurrent rayon tasks: each output is computed exactly as
    // before (same bytes), only the order in which files appear changes. With --jobs 1 the
    // tasks run one after another on the single worker.
    let mut clean_res: Option<day2night::Result<()>> = None;
    let mut noisy_res: Option<day2night::Result<Option<day2night::RawImage>>> = None;
    let mut target_res: Option<day2night::Result<()>> = None;
    rayon::scope(|s| {
        let (clean, wopts) = (&clean, &wopts);
        let (clean_name, noisy_names) = (&clean_name, &noisy_names);
        let (exr_name, png_name, attrs) = (&exr_name, &png_name, &attrs);
        let (clean_res, noisy_res) = (&mut clean_res, &mut noisy_res);
        s.spawn(move |_| {
            *clean_res = Some(write_dng(
                clean,
                &job.out.join(clean_name),
                wopts,
                &job.policy,
            ));
        });
        s.spawn(move |_| {
            *noisy_res = Some((|| {
                let mut first_noisy = None;
                for (i, n) in noisy_names.iter().enumerate() {
                    let (_, noisy) = run_noise(clean, plan, i)?;
                    write_dng(&noisy, &job.out.join(n), wopts, &job.policy)?;
                    if first_noisy.is_none() && job.input_exr {
                        first_noisy = Some(noisy);
                    }
                }
                Ok(first_noisy)
            })());
        });
        if want_exr || want_png {
            target_res = Some((|| {
                let ropts = RenderOptions {
                    neutral: Some(neutral),
                    ..RenderOptions::default()
                };
                let rgb = render_linear(clean, &ropts)?;
                let (e, p) = rayon::join(
                    || {
                        if want_exr {
                            write_exr(&rgb, &job.out.join(exr_name), &job.exr, attrs, &job.policy)
                        } else {
                            Ok(())
                        }
                    },
                    || {
                        if want_png {
                            write_png(
                                &rgb,
                                &job.out.join(png_name),
                                &PngOptions::default(),
                                &job.policy,
                            )
                        } else {
                            Ok(())
                        }
                    },
                );
                e.and(p)
            })());
        }
    });
    // Errors in a fixed order (clean, noisy, target), whatever finished first.
    clean_res.unwrap_or(Ok(()))?;
    let first_noisy = noisy_res.unwrap_or(Ok(None))?;
    target_res.unwrap_or(Ok(()))?;
    let mut files = vec![clean_name];
    stages.push("write_clean_dng".into());
    files.extend(noisy_names);
    if !plan.noise.is_empty() {
        stages.push("write_noisy_dng".into());
    }
    if want_exr {
        files.push(exr_name);
        stages.push("target_exr".into());
    }
    if want_png {
        files.push(png_name);
        stages.push("target_png".into());
    }
    if job.input_exr {
        let src = first_noisy.as_ref().unwrap_or(&clean);
        let rgb = render_input(src, Some(neutral), Default::default())?;
        let n = format!("{}_input.exr", base);
        write_exr(&rgb, &job.out.join(&n), &job.exr, &attrs, &job.policy)?;
        files.push(n);
        stages.push("input_exr".into());
    }
    let sidecar_name = format!("{}.json", base);
    files.push(sidecar_name.clone());
    let sc = Sidecar {
        format: synth::sidecar::SIDECAR_FORMAT.into(),
        tool: "day2night".into(),
        version: day2night::VERSION.into(),
        input: InputInfo {
            name: plan.input_name.clone(),
            sha256: sha.to_string(),
        },
        options: job.opts.clone(),
        calibration: CalibrationInfo {
            illuminants: job.cal.illuminants.clone(),
            brightness: job.cal.brightness.clone(),
            noise_model: plan.noise_model_source.clone(),
        },
        plan: plan.clone(),
        run: report,
        stages,
        outputs: OutputInfo {
            variants: job.variants,
            compression: match job.compression {
                CompressionArg::None => "none".into(),
                CompressionArg::Ljpeg => "ljpeg".into(),
            },
            target: target_name(job.target).into(),
            input_exr: job.input_exr,
            files,
            exr_compression: job.exr.compression.name().into(),
        },
    };
    write_bytes_atomic(
        &job.out.join(&sidecar_name),
        &job.policy,
        sc.to_json()?.as_bytes(),
    )
}
