//! The synthesis options, in `--help` order: the one declaration of each (see the parent
//! module). A new option is one entry here (docs/architecture.md, "Adding a synthesis
//! option").

use super::{Choice, Constant, Kind, OptionDef, Python, Range, Value, Width};
use crate::bounds::{EXR_ZIP_LEVEL_RANGE, MAX_LIGHTS, SEED_RANGE};
use crate::encode::exr::ExrCompression;
use crate::error::{Error, Result};
use crate::synth::burst::motion::MAX_FRAMES;
use crate::synth::config::{parse_isos, parse_neutral};
use crate::synth::{Covariance, MaskEval, Mode, RelightFormula};
use std::path::PathBuf;

/// Every synthesis option, in the order `--help` lists them.
pub static OPTIONS: &[OptionDef] = &[
    OptionDef {
        name: "seed",
        value_name: "SEED",
        kind: Kind::Int {
            lo: SEED_RANGE.0,
            hi: SEED_RANGE.1,
            width: Width::U64,
            late: false,
        },
        default: Some("0"),
        help: "Master seed; each (input, variant) has its own random stream keyed by (seed, input \
name, variant), never by position or thread count (dataset: the name is the path relative to \
DAY_DIR)",
        python: Python::Absent(
            "a parameter of `synthesize`, `night_pair`, `NightPairs` and `dataset_units` (a unit \
carries its seed)",
        ),
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.seed = int(&v)? as u64;
            Ok(())
        },
    },
    OptionDef {
        name: "iso",
        value_name: "LIST|none",
        kind: Kind::Isos,
        default: Some("1600,3200"),
        help: "ISOs of the noisy outputs, comma-separated, or `none`",
        python: Python::Parameter,
        python_alias: None,
        synth_only: false,
        sidecar: Some("isos"),
        set: |d, v| {
            d.config.options.isos = match v {
                Value::Unset => Vec::new(),
                Value::Isos(list) => dedup(list)?,
                v => parse_isos(&text(&v)?)?,
            };
            Ok(())
        },
    },
    OptionDef {
        name: "mode",
        value_name: "MODE",
        kind: Kind::Choice(&[
            Choice {
                name: "local",
                help: "Several local lights (the paper's method)",
            },
            Choice {
                name: "global",
                help: "One night illuminant",
            },
            Choice {
                name: "dimmed",
                help: "Dimmed day image (baseline)",
            },
            Choice {
                name: "day",
                help: "The day image itself (baseline)",
            },
        ]),
        default: Some("local"),
        help: "Relighting mode",
        python: Python::Parameter,
        python_alias: None,
        synth_only: false,
        sidecar: Some("mode"),
        set: |d, v| {
            d.config.options.mode = text(&v)?.parse::<Mode>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "relight-formula",
        value_name: "RELIGHT_FORMULA",
        kind: Kind::Choice(&[
            Choice {
                name: "release",
                help: "The authors' released code",
            },
            Choice {
                name: "paper",
                help: "The paper's equation",
            },
        ]),
        default: Some("release"),
        help: "Local relighting formula",
        python: Python::Keyword,
        python_alias: Some("formula"),
        synth_only: false,
        sidecar: Some("formula"),
        set: |d, v| {
            d.config.options.formula = text(&v)?.parse::<RelightFormula>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "bulbs",
        value_name: "BULBS",
        kind: Kind::Int {
            lo: 0,
            hi: MAX_LIGHTS as u64,
            width: Width::U32,
            late: false,
        },
        default: None,
        help: "Saturated bulbs (default 5 with the release formula, 0 with the paper's)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("bulbs"),
        set: |d, v| {
            d.config.options.bulbs = opt_u32(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "lights",
        value_name: "LIGHTS",
        kind: Kind::Int {
            lo: 0,
            hi: MAX_LIGHTS as u64,
            width: Width::U32,
            late: false,
        },
        default: None,
        help: "Local lights besides the ambient (default 4 release; paper: 4 to 6 drawn)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("local_lights"),
        set: |d, v| {
            d.config.options.local_lights = opt_u32(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "ambient-gain",
        value_name: "G",
        kind: Kind::Float {
            range: Range::at_least(0.0),
            field: Some(|o| o.ambient_gain),
        },
        default: Some("0.05"),
        help: "Gain of the ambient light in the release formula's local relighting (the authors' \
released code)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("ambient_gain"),
        set: |d, v| {
            d.config.options.ambient_gain = float(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "bulb-gain",
        value_name: "LO,HI",
        kind: Kind::Pair {
            range: Range::at_least(0.0),
            field: Some(|o| o.bulb_gain),
        },
        default: Some("50,100"),
        help: "Range of the saturated bulbs' gain, each drawn uniformly (the authors' released \
code)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("bulb_gain"),
        set: |d, v| {
            d.config.options.bulb_gain = pair(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "illuminants",
        value_name: "paper|cie|FILE.json",
        kind: Kind::Path,
        default: None,
        help: "Night illuminant dictionary: `paper` (the paper phone's gray cards, its camera \
RGB), `cie` (CIE 015:2018 night lamps through each file's colour matrices) or a JSON file \
(camera neutrals, a Gaussian, xy lamps; `./paper` for a file named paper). Default: `paper` for \
the paper's phone (Samsung SM-G780*/SM-G781*) and under --compat release, `cie` for every other \
camera",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.illuminants = path(v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "covariance",
        value_name: "COVARIANCE",
        kind: Kind::Choice(&[
            Choice {
                name: "unbiased",
                help: "1/(M-1) (released code)",
            },
            Choice {
                name: "ml",
                help: "1/M (the paper's equation 2)",
            },
        ]),
        default: Some("unbiased"),
        help: "Illuminant covariance estimator",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("covariance"),
        set: |d, v| {
            d.config.options.covariance = text(&v)?.parse::<Covariance>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "brightness",
        value_name: "FILE.json",
        kind: Kind::Path,
        default: None,
        help: "Night brightness dictionary (JSON): dim to a drawn mean instead of U(0.55, 0.9)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.brightness = path(v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "dim-range",
        value_name: "LO,HI",
        kind: Kind::Pair {
            range: Range::above(0.0),
            field: Some(|o| o.dim_range),
        },
        default: Some("0.55,0.9"),
        help: "Range of the uniform dimming factor without a brightness dictionary (the paper's \
U(0.55, 0.9))",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("dim_range"),
        set: |d, v| {
            d.config.options.dim_range = pair(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "noise-model",
        value_name: "FILE.json",
        kind: Kind::Path,
        default: None,
        help: "Noise model (day2night-noise-model/1 JSON); default: the input's NoiseProfile, \
else (the paper's phone: its embedded table) an estimate from the image at its ISO, else the \
embedded paper phone table with a warning. See docs/noise.md",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.noise_model = path(v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "noise-gain",
        value_name: "K",
        kind: Kind::Float {
            range: Range::above(0.0),
            field: Some(|o| o.noise_gain),
        },
        default: Some("1"),
        help: "Factor on the noise model's standard deviation at every ISO (S and O times K^2; a \
Gaussian model only): noisier or cleaner inputs than the calibrated camera at the same Exif ISO, \
for a network robust to a noise calibration that is off",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("noise_gain"),
        set: |d, v| {
            d.config.options.noise_gain = float(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "replay",
        value_name: "SIDECAR.json",
        kind: Kind::Path,
        default: None,
        help: "Re-run a sidecar's plan on its input (one input): byte-identical outputs",
        python: Python::Absent("the command line's `synth` only: Python has no replay"),
        python_alias: None,
        synth_only: true,
        sidecar: None,
        set: |d, v| {
            d.replay = path(v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "day-neutral",
        value_name: "R,G,B",
        kind: Kind::Numbers(3),
        default: None,
        help: "Day neutral r,g,b overriding (or replacing a missing) AsShotNeutral",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("day_neutral"),
        set: |d, v| {
            d.config.options.day_neutral = match v {
                Value::Unset => None,
                Value::Numbers(n) => match n.as_slice() {
                    [r, g, b] => Some([*r, *g, *b]),
                    _ => return Err(Error::invalid("must be (r, g, b)")),
                },
                v => Some(parse_neutral(&text(&v)?)?),
            };
            Ok(())
        },
    },
    OptionDef {
        name: "mask-eval",
        value_name: "MASK_EVAL",
        kind: Kind::Text,
        default: Some("separable"),
        help: "Mask evaluation: separable (default), exact, truncated:K (K sigmas), or release \
(the authors' sampled kernel resized bilinearly)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("mask_eval"),
        set: |d, v| {
            d.config.options.mask_eval = text(&v)?.parse::<MaskEval>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "exr-compression",
        value_name: "KIND",
        kind: Kind::Text,
        default: Some("zip"),
        help: "EXR compression (lossless: zip (default, the fastest), piz (slower; larger on \
synth targets, smaller on noisy images), zips, rle, none; lossy for half: pxr24, b44, b44a). \
See docs/benchmarks.md",
        python: Python::Files,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.exr.compression = text(&v)?.parse::<ExrCompression>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "exr-zip-level",
        value_name: "N",
        kind: Kind::Int {
            lo: EXR_ZIP_LEVEL_RANGE.0 as u64,
            hi: EXR_ZIP_LEVEL_RANGE.1 as u64,
            width: Width::U8,
            late: false,
        },
        default: Some("1"),
        help: "Compression effort of zip/zips EXRs: 1 (default, fastest: day2night's run-length \
+ Huffman encoder) or 2 to 9 (miniz_oxide's zlib levels: 6 is 1.4 % smaller, 9 is 2 % smaller, \
at 18x and 50x the compression time). Lossless at every level. See docs/benchmarks.md",
        python: Python::Files,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            // in range: Draft::set checks the kind's
            let n = int(&v)?;
            d.config.exr.zip_level =
                u8::try_from(n).map_err(|_| Error::invalid(format!("{n} is not a level")))?;
            Ok(())
        },
    },
    OptionDef {
        name: "opcodes",
        value_name: "MODE",
        kind: Kind::Text,
        default: None,
        help: "DNG opcode lists of the input in the rendered targets and inputs: apply (default) \
or ignore (implied by --compat release). The night DNGs keep the lists either way",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("opcodes"),
        set: |d, v| {
            d.opcodes = match v {
                Value::Unset => None,
                v => Some(text(&v)?.parse()?),
            };
            Ok(())
        },
    },
    OptionDef {
        name: "burst",
        value_name: "N",
        kind: Kind::Int {
            lo: 1,
            hi: MAX_FRAMES as u64,
            width: Width::U32,
            late: true,
        },
        default: Some("1"),
        help: "Frames per ISO: a night burst of N noisy DNGs <stem>[_vK]_iso<ISO>_f<NN>.dng (1 = \
one noisy DNG per ISO, as without a burst). See docs/synthesis.md, \"Bursts\"",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.frames"),
        set: |d, v| {
            d.burst.frames = Some(int(&v)?);
            Ok(())
        },
    },
    OptionDef {
        name: "motion",
        value_name: "none|shake",
        kind: Kind::Text,
        default: None,
        help: "Motion between the frames of a burst: none (a tripod) or shake (a hand-held \
camera, the default)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.motion"),
        set: |d, v| {
            d.burst.motion = opt(v, |v| text(&v))?;
            Ok(())
        },
    },
    OptionDef {
        name: "shake-step",
        value_name: "PX",
        kind: Kind::Float {
            range: Range::ANY,
            field: None,
        },
        default: None,
        help: "Hand-held walk: standard deviation of each frame's translation step per axis, in \
pixels [default: 0.6]",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.shake.step_px"),
        set: |d, v| {
            d.burst.shake_step = opt(v, |v| float(&v))?;
            Ok(())
        },
    },
    OptionDef {
        name: "shake-roll",
        value_name: "DEG",
        kind: Kind::Float {
            range: Range::ANY,
            field: None,
        },
        default: None,
        help: "Hand-held walk: standard deviation of each frame's rotation step, in degrees \
[default: 0.015]",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.shake.roll_deg"),
        set: |d, v| {
            d.burst.shake_roll = opt(v, |v| float(&v))?;
            Ok(())
        },
    },
    OptionDef {
        name: "warp-interp",
        value_name: "KIND",
        kind: Kind::Text,
        default: None,
        help: "Interpolant of the burst warp: catmull-rom (default), lanczos3 or bilinear",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.interp"),
        set: |d, v| {
            d.burst.warp_interp = opt(v, |v| text(&v))?;
            Ok(())
        },
    },
    OptionDef {
        name: "target",
        value_name: "TARGET",
        kind: Kind::Choice(&[
            Choice {
                name: "exr",
                help: "Linear EXR",
            },
            Choice {
                name: "png",
                help: "sRGB PNG",
            },
            Choice {
                name: "both",
                help: "Both",
            },
            Choice {
                name: "none",
                help: "None",
            },
        ]),
        default: Some("exr"),
        help: "Targets to render from the clean night raw",
        python: Python::Files,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            // one of the choices (Draft::set checks the name)
            d.config.target = text(&v)?.parse()?;
            Ok(())
        },
    },
    OptionDef {
        name: "input-exr",
        value_name: "",
        kind: Kind::Switch,
        default: None,
        help: "Also write the network input (normalized, white-balanced, demosaiced noisy raw)",
        python: Python::Files,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.input_exr = switch(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "compression",
        value_name: "COMPRESSION",
        kind: Kind::Choice(&[
            Choice {
                name: "none",
                help: "Uncompressed",
            },
            Choice {
                name: "ljpeg",
                help: "Lossless JPEG",
            },
        ]),
        default: Some("none"),
        help: "DNG compression",
        python: Python::Files,
        python_alias: None,
        synth_only: false,
        sidecar: None,
        set: |d, v| {
            d.config.compression = text(&v)?.parse()?;
            Ok(())
        },
    },
    OptionDef {
        name: "truncate",
        value_name: "",
        kind: Kind::Switch,
        default: None,
        help: "Truncate instead of rounding when denormalizing (released code, -0.5 DN bias)",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("truncate"),
        set: |d, v| {
            d.config.options.truncate = switch(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "compat",
        value_name: "PRESET",
        kind: Kind::Choice(&[Choice {
            name: "release",
            help: "The authors' released code where it is deterministic",
        }]),
        default: None,
        help: "Reproduce the authors' released code where it is deterministic: implies \
--truncate and --mask-eval release, truncates the noisy raws too, divides by the day neutral as \
stored (not normalized to green = 1), does not cut illuminant draws at Mahalanobis 3 and samples \
every camera's lights from the paper phone's dictionary (unless --illuminants says otherwise). \
See docs/synthesis.md, \"Release compatibility\"",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("compat"),
        set: |d, v| {
            // the one preset (Draft::set checks the name), or None
            d.release = match v {
                Value::Unset => false,
                v => {
                    text(&v)?;
                    true
                }
            };
            Ok(())
        },
    },
];

/// The synthesis fields that are not options (docs/synthesis.md, "Options and constants").
pub static CONSTANTS: &[Constant] = &[
    Constant {
        field: "keep_negative",
        value: "false",
        why: "the method clips the normalized day raw to [0, 1] before relighting; keeping \
 negative values is a switch of the tests that check the clip, not a look",
    },
    Constant {
        field: "keep_highlights",
        value: "false",
        why: "as keep_negative, for white-balanced values above 1: the paper's clip",
    },
    Constant {
        field: "sampler",
        value: "floor 0.001, max_mahalanobis 3, max_tries 1000",
        why: "the paper's 3-sigma cut of the illuminant draws (--compat release removes it, \
as the released code has none); the floor and tries only keep the draw well defined",
    },
];

/// A value's text (a number is refused: the option takes a word or a list).
fn text(v: &Value) -> Result<String> {
    match v {
        Value::Text(s) => Ok(s.clone()),
        v => Err(Error::invalid(format!("{} is not text", shown(v)))),
    }
}

/// None for [`Value::Unset`] (the option's default), else the value `f` reads.
fn opt<T>(v: Value, f: impl FnOnce(Value) -> Result<T>) -> Result<Option<T>> {
    match v {
        Value::Unset => Ok(None),
        v => f(v).map(Some),
    }
}

/// A value's integer.
fn int(v: &Value) -> Result<i128> {
    match v {
        Value::Int(n) => Ok(*n),
        v => Err(Error::invalid(format!("{} is not an integer", shown(v)))),
    }
}

/// An optional count (None: the formula's default).
fn opt_u32(v: &Value) -> Result<Option<u32>> {
    match v {
        Value::Unset => Ok(None),
        v => {
            let n = int(v)?;
            u32::try_from(n)
                .map(Some)
                .map_err(|_| Error::invalid(format!("{n} is outside 0..={}", MAX_LIGHTS)))
        }
    }
}

/// A value's number (an integer is a number).
fn float(v: &Value) -> Result<f64> {
    match v {
        Value::Float(x) => Ok(*x),
        Value::Int(n) => Ok(*n as f64),
        Value::Text(s) => s
            .trim()
            .parse()
            .map_err(|_| Error::invalid(format!("{s:?} is not a number"))),
        v => Err(Error::invalid(format!("{} is not a number", shown(v)))),
    }
}

/// `lo,hi` (text or two numbers).
fn pair(v: &Value) -> Result<[f64; 2]> {
    let list = match v {
        Value::Numbers(n) => n.clone(),
        Value::Text(s) => s
            .split(',')
            .map(|p| p.trim().parse::<f64>())
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(|_| Error::invalid(format!("{s:?} is not lo,hi")))?,
        v => return Err(Error::invalid(format!("{} is not lo,hi", shown(v)))),
    };
    match list.as_slice() {
        [lo, hi] => Ok([*lo, *hi]),
        _ => Err(Error::invalid(format!(
            "{} values given (use lo,hi)",
            list.len()
        ))),
    }
}

/// A switch's state.
fn switch(v: &Value) -> Result<bool> {
    match v {
        Value::Switch(b) => Ok(*b),
        v => Err(Error::invalid(format!("{} is not a switch", shown(v)))),
    }
}

/// A path, or None.
fn path(v: Value) -> Result<Option<PathBuf>> {
    match v {
        Value::Unset => Ok(None),
        Value::Path(p) => Ok(Some(p)),
        Value::Text(s) => Ok(Some(PathBuf::from(s))),
        v => Err(Error::invalid(format!("{} is not a path", shown(&v)))),
    }
}

/// ISOs in order, duplicates dropped (each in the ISO range).
fn dedup(list: Vec<u32>) -> Result<Vec<u32>> {
    let mut v = Vec::new();
    for i in list {
        crate::bounds::iso("", i)?;
        if !v.contains(&i) {
            v.push(i);
        }
    }
    Ok(v)
}

/// A value as a message shows it.
fn shown(v: &Value) -> String {
    match v {
        Value::Unset => "None".into(),
        Value::Switch(b) => b.to_string(),
        Value::Int(n) => n.to_string(),
        Value::Float(x) => x.to_string(),
        Value::Text(s) => format!("{s:?}"),
        Value::Path(p) => format!("{:?}", p.display().to_string()),
        Value::Numbers(n) => format!("{n:?}"),
        Value::Isos(n) => format!("{n:?}"),
    }
}
