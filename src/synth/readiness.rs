//! Everything that keeps an input from synthesis with given options, found at once
//! (issue 24 point 4): `synth` refuses an input listing every missing or refused item with
//! the flag that fixes it, and `day2night info` runs the same checks, so "ready" means that
//! `synth` with default options runs.

use super::{Calibration, Mode, SynthOptions};
use crate::error::{Error, Result};
use crate::raw::meta::RawMeta;

/// The items that keep an input with metadata `meta` from synthesis with `opts` and `cal`
/// (`renders`: a target or the network input is rendered), each an error naming the flag
/// that fixes it, in the order the synthesis needs them: the day neutral, the night
/// illuminant dictionary (modes that sample lights), the colour matrices of the renders.
pub fn problems(
    meta: &RawMeta,
    opts: &SynthOptions,
    cal: &Calibration,
    renders: bool,
) -> Vec<Error> {
    let mut out = Vec::new();
    let neutral = match super::neutral::day_neutral_for(meta, opts) {
        Ok((n, _)) => Some(n),
        Err(e) => {
            out.push(e);
            None
        }
    };
    if matches!(opts.mode, Mode::Global | Mode::Local) {
        if let Err(e) = cal.illuminants_for(meta, opts) {
            out.push(e);
        }
    }
    if renders {
        // The render's own matrix ([`crate::isp::render::color_matrix`], what `render` and
        // the target render build): the colour tags parse, and they map a neutral to a
        // positive luminance (an all-zero or negated ForwardMatrix does not).
        let color = match neutral {
            Some(n) => crate::isp::render::color_matrix(meta, n).map(|_| ()),
            None => crate::isp::color::CameraColor::new(&meta.color).map(|_| ()),
        };
        if let Err(e) = color {
            out.push(Error::unsupported(format!(
                "the target render needs usable colour matrices ({}): pass --target none \
                 (and no --input-exr), or use a DNG with valid ColorMatrix1/ForwardMatrix1",
                text(&e)
            )));
        }
    }
    out
}

/// An error's message without its kind ("unsupported: ", ...), for a list of them.
fn text(e: &Error) -> String {
    match e.root() {
        Error::Unsupported(m) | Error::InvalidParam(m) | Error::Malformed(m) | Error::Limits(m) => {
            m.clone()
        }
        e => e.to_string(),
    }
}

/// `Ok` when [`problems`] finds nothing; one problem is returned as it is, several as one
/// error listing them all (`3 problems: (1) ...; (2) ...; (3) ...`).
pub fn check(meta: &RawMeta, opts: &SynthOptions, cal: &Calibration, renders: bool) -> Result<()> {
    let mut p = problems(meta, opts, cal, renders);
    match p.len() {
        0 => Ok(()),
        1 => Err(p.remove(0)),
        n => Err(Error::unsupported(format!(
            "{n} problems: {}",
            p.iter()
                .enumerate()
                .map(|(i, e)| format!("({}) {}", i + 1, text(e)))
                .collect::<Vec<_>>()
                .join("; ")
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raw::Bayer;

    fn pidng_like() -> RawMeta {
        // Neither AsShotNeutral nor AsShotWhiteXY nor ColorMatrix1, as a PiDNG file.
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        m.as_shot_neutral = None;
        m.as_shot_white_xy = None;
        m.color.color_matrix1 = None;
        m
    }

    fn opts(mode: Mode) -> SynthOptions {
        SynthOptions {
            mode,
            ..SynthOptions::default()
        }
    }

    #[test]
    fn every_problem_is_listed_with_its_flag() {
        let m = pidng_like();
        let o = opts(Mode::Local);
        let cal = Calibration::embedded(&o).unwrap();
        let p = problems(&m, &o, &cal, true);
        assert_eq!(p.len(), 3, "{p:?}");
        let e = check(&m, &o, &cal, true).unwrap_err().to_string();
        for flag in ["--day-neutral", "--illuminants paper", "--target none"] {
            assert!(e.contains(flag), "{flag} missing from: {e}");
        }
        assert!(e.contains("3 problems: (1) "), "{e}");
    }

    #[test]
    fn each_flag_removes_its_item() {
        let m = pidng_like();
        let mut o = opts(Mode::Local);
        o.day_neutral = Some([0.5, 1.0, 0.6]);
        let paper = Calibration {
            illuminants: super::super::IlluminantChoice::Paper,
            ..Calibration::embedded(&o).unwrap()
        };
        assert!(check(&m, &o, &paper, false).is_ok());
        // One problem left: the error is that problem's own.
        let e = check(&m, &o, &paper, true).unwrap_err().to_string();
        assert!(
            e.contains("--target none") && !e.contains("problems"),
            "{e}"
        );
        // The modes without lights need no dictionary.
        let d = opts(Mode::Dimmed);
        let cal = Calibration::embedded(&d).unwrap();
        assert_eq!(problems(&m, &d, &cal, false).len(), 1);
    }

    #[test]
    fn a_forward_matrix_mapping_white_to_no_light_is_a_problem() {
        let fm = [0.6, 0.3, 0.1, 0.25, 0.7, 0.05, 0.0, 0.1, 0.75];
        for bad in [vec![0.0; 9], fm.iter().map(|v| -v).collect()] {
            let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
            m.as_shot_neutral = Some([0.5, 1.0, 0.6]);
            m.color.color_matrix1 = Some(vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
            m.color.forward_matrix1 = Some(fm.to_vec());
            let o = opts(Mode::Dimmed);
            let cal = Calibration::embedded(&o).unwrap();
            assert!(problems(&m, &o, &cal, true).is_empty());
            m.color.forward_matrix1 = Some(bad);
            let e = check(&m, &o, &cal, true).unwrap_err().to_string();
            assert!(e.contains("non-positive luminance"), "{e}");
            assert!(e.contains("--target none"), "{e}");
            // Without a render the matrices are not used.
            assert!(problems(&m, &o, &cal, false).is_empty());
        }
    }

    #[test]
    fn a_complete_input_has_none() {
        let mut m = RawMeta::new_bayer(Bayer::RGGB, 12, 0.0, 4095.0);
        m.as_shot_neutral = Some([0.5, 1.0, 0.6]);
        m.color.color_matrix1 = Some(vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
        let o = opts(Mode::Local);
        let cal = Calibration::embedded(&o).unwrap();
        assert!(problems(&m, &o, &cal, true).is_empty());
    }
}
