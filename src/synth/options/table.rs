//! The synthesis options, in `--help` order: the one declaration of each (see the parent
//! module). A new option is one entry here (docs/architecture.md, "Adding a synthesis
//! option").

use super::{Constant, Kind, OptDefault, OptionDef, Python, Range, Value, Width};
use crate::bounds::{EXR_ZIP_LEVEL_RANGE, MAX_LIGHTS, SEED_RANGE};
use crate::choice::Choice;
use crate::dng::write::Compression;
use crate::encode::exr::ExrCompression;
use crate::error::{Error, Result};
use crate::isp::opcodes::OpcodeMode;
use crate::synth::burst::{Interp, Motion};
use crate::synth::config::{parse_isos, parse_neutral, Preset};
use crate::synth::outputs::Target;
use crate::synth::{Covariance, MaskEval, Mode, RelightFormula};
use std::path::PathBuf;

/// Most frames of a burst (`--burst`).
pub const MAX_FRAMES: u32 = 64;
/// Largest step of the hand-held walk's translation (`--shake-step`, px per frame).
pub const MAX_STEP_PX: f64 = 1000.0;
/// Largest step of the hand-held walk's rotation (`--shake-roll`, degrees per frame).
pub const MAX_ROLL_DEG: f64 = 5.0;

/// Every synthesis option, in the order `--help` lists them.
pub static OPTIONS: &[OptionDef] = &[
    OptionDef {
        name: "seed",
        value_name: "SEED",
        kind: Kind::Int {
            lo: SEED_RANGE.0,
            hi: SEED_RANGE.1,
            width: Width::U64,
            field: None,
        },
        default: OptDefault::Value("0"),
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
        default: OptDefault::Value("1600,3200"),
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
        kind: Kind::Choice(Mode::NAMES),
        default: OptDefault::Value(Mode::Local.name()),
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
        kind: Kind::Choice(RelightFormula::NAMES),
        default: OptDefault::Value(RelightFormula::Release.name()),
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
            field: Some(|o| o.bulbs.map_or(0, u64::from)),
        },
        default: OptDefault::Derived("5 with the release formula, 0 with the paper's"),
        help: "Saturated bulbs",
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
            field: Some(|o| o.local_lights.map_or(0, u64::from)),
        },
        default: OptDefault::Derived("4 with the release formula; the paper's draws 4 to 6"),
        help: "Local lights besides the ambient",
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
        default: OptDefault::Value("0.05"),
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
        default: OptDefault::Value("50,100"),
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
        default: OptDefault::Derived(
            "`paper` for the paper's phone (Samsung SM-G780*/SM-G781*) and under --compat \
release, `cie` for every other camera",
        ),
        help: "Night illuminant dictionary: `paper` (the paper phone's gray cards, its camera \
RGB), `cie` (CIE 015:2018 night lamps through each file's colour matrices) or a JSON file \
(camera neutrals, a Gaussian, xy lamps; `./paper` for a file named paper)",
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
        kind: Kind::Choice(Covariance::NAMES),
        default: OptDefault::Value(Covariance::Unbiased.name()),
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
        default: OptDefault::Off,
        help: "Night brightness dictionary (JSON): dim to a drawn mean instead of by --dim-range",
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
        default: OptDefault::Value("0.55,0.9"),
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
        default: OptDefault::Derived(
            "the input's NoiseProfile, else (the paper's phone: its embedded table) an estimate \
from the image at its ISO, else the embedded paper phone table with a warning",
        ),
        help: "Noise model (day2night-noise-model/1 JSON). See docs/noise.md",
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
        default: OptDefault::Value("1"),
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
        default: OptDefault::Off,
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
        default: OptDefault::Derived("the input's AsShotNeutral"),
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
        kind: Kind::Choice(MaskEval::NAMES),
        default: OptDefault::Value(MaskEval::NAMES[0].name),
        help: "Mask evaluation",
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
        kind: Kind::Choice(ExrCompression::NAMES),
        default: OptDefault::Value(ExrCompression::Zip.name()),
        help: "EXR compression. See docs/benchmarks.md",
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
            field: None,
        },
        default: OptDefault::Value("1"),
        help: "Compression effort of zip/zips EXRs: 1 (the fastest: day2night's run-length + \
Huffman encoder) or 2 to 9 (miniz_oxide's zlib levels: 6 is 1.4 % smaller, 9 is 2 % smaller, \
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
        kind: Kind::Choice(OpcodeMode::NAMES),
        default: OptDefault::Derived("apply; ignore under --compat release"),
        help: "DNG opcode lists of the input in the rendered targets and inputs. The night DNGs \
keep the lists either way",
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
            field: Some(|o| u64::from(o.burst.frames)),
        },
        default: OptDefault::Value("1"),
        help: "Frames per ISO: a night burst of N noisy DNGs <stem>[_vK]_iso<ISO>_f<NN>.dng (1 = \
one noisy DNG per ISO, as without a burst). See docs/synthesis.md, \"Bursts\"",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.frames"),
        set: |d, v| {
            // in range: Draft::set checks the kind's
            let n = int(&v)?;
            d.config.options.burst.frames =
                u32::try_from(n).map_err(|_| Error::invalid(format!("{n} is not a count")))?;
            Ok(())
        },
    },
    OptionDef {
        name: "motion",
        value_name: "MOTION",
        kind: Kind::Choice(Motion::NAMES),
        default: OptDefault::Value(Motion::Shake.name()),
        help: "Motion between the frames of a burst",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.motion"),
        set: |d, v| {
            d.config.options.burst.motion = text(&v)?.parse::<Motion>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "shake-step",
        value_name: "PX",
        kind: Kind::Float {
            range: Range::between(0.0, MAX_STEP_PX),
            field: Some(|o| o.burst.shake.step_px),
        },
        default: OptDefault::Value("0.6"),
        help: "Hand-held walk: standard deviation of each frame's translation step per axis, in \
pixels",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.shake.step_px"),
        set: |d, v| {
            d.config.options.burst.shake.step_px = float(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "shake-roll",
        value_name: "DEG",
        kind: Kind::Float {
            range: Range::between(0.0, MAX_ROLL_DEG),
            field: Some(|o| o.burst.shake.roll_deg),
        },
        default: OptDefault::Value("0.015"),
        help: "Hand-held walk: standard deviation of each frame's rotation step, in degrees",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.shake.roll_deg"),
        set: |d, v| {
            d.config.options.burst.shake.roll_deg = float(&v)?;
            Ok(())
        },
    },
    OptionDef {
        name: "warp-interp",
        value_name: "KIND",
        kind: Kind::Choice(Interp::NAMES),
        default: OptDefault::Value(Interp::CatmullRom.name()),
        help: "Interpolant of the burst warp",
        python: Python::Keyword,
        python_alias: None,
        synth_only: false,
        sidecar: Some("burst.interp"),
        set: |d, v| {
            d.config.options.burst.interp = text(&v)?.parse::<Interp>()?;
            Ok(())
        },
    },
    OptionDef {
        name: "target",
        value_name: "TARGET",
        kind: Kind::Choice(Target::NAMES),
        default: OptDefault::Value(Target::Exr.name()),
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
        default: OptDefault::Off,
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
        kind: Kind::Choice(Compression::NAMES),
        default: OptDefault::Value(Compression::None.name()),
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
        default: OptDefault::Off,
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
        kind: Kind::Choice(Preset::NAMES),
        default: OptDefault::Off,
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
                v => text(&v)?.parse::<Preset>()? == Preset::Release,
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
