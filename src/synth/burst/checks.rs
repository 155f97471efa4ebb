//! Every check of a burst, spelled once for every entry point (docs/synthesis.md, "Bursts"):
//! the options as the command line and Python give them ([`BurstRequest::resolve`]), the
//! shake step against the image size before the draw ([`check_step_fits`]), the frames'
//! valid areas after it ([`valid_area_warnings`]), and a replayed sidecar's transforms
//! ([`check_transform`]). Messages name the option in the caller's spelling ([`Names`]),
//! the value rounded ([`crate::bounds::short`]) and the allowed range.

use super::interp::Interp;
use super::motion::{rigid, valid_rect, BurstOptions, FrameTransform, Motion, MAX_FRAMES};
use super::motion::{MAX_ROLL_DEG, MAX_STEP_PX};
use crate::bounds::short;
use crate::diagnostics::{Code, Warning};
use crate::error::{Error, Result};

/// The shake step (px per frame) is at most this fraction of the active area's smaller side:
/// one step of a quarter side already moves a frame's expected valid area below about 80%,
/// and the walk adds a step per frame, so beyond it most frames of a burst would repeat the
/// image's edge.
pub const MAX_STEP_FRACTION: f64 = 0.25;
/// A frame whose valid area is under this fraction of the active area is reported in a
/// warning (the rest of the frame repeats the image's edge).
pub const MIN_VALID_FRACTION: f64 = 0.5;
/// Tolerance of a replayed transform's rotation part (orthonormality, consistency with
/// `theta_deg`): sampled transforms hold to rounding, about 1e-16.
pub const ROTATION_TOLERANCE: f64 = 1e-9;
/// Tolerance of a replayed translation against `dx`/`dy` and the centre, relative to the
/// image's extent (rounding of sampled transforms is about 1e-13 px).
pub const TRANSLATION_TOLERANCE: f64 = 1e-9;

/// How the caller spells the burst options in messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Names {
    /// Frames per ISO.
    pub burst: &'static str,
    /// The motion model.
    pub motion: &'static str,
    /// The walk's translation step.
    pub shake_step: &'static str,
    /// The walk's rotation step.
    pub shake_roll: &'static str,
    /// The warp's interpolant.
    pub warp_interp: &'static str,
}

impl Names {
    /// The command line's flags.
    pub const CLI: Names = Names {
        burst: "--burst",
        motion: "--motion",
        shake_step: "--shake-step",
        shake_roll: "--shake-roll",
        warp_interp: "--warp-interp",
    };
    /// Python's keyword arguments.
    pub const PYTHON: Names = Names {
        burst: "burst",
        motion: "motion",
        shake_step: "shake_step",
        shake_roll: "shake_roll",
        warp_interp: "warp_interp",
    };
    /// A sidecar's plan fields (`synth --replay`).
    pub const SIDECAR: Names = Names {
        burst: "plan field burst.frames",
        motion: "plan field burst.motion",
        shake_step: "plan field burst.shake.step_px",
        shake_roll: "plan field burst.shake.roll_deg",
        warp_interp: "plan field burst.interp",
    };
    /// Both spellings, for checks run where the caller is not known (the planner).
    pub const EITHER: Names = Names {
        burst: "--burst (Python burst)",
        motion: "--motion (Python motion)",
        shake_step: "--shake-step (Python shake_step)",
        shake_roll: "--shake-roll (Python shake_roll)",
        warp_interp: "--warp-interp (Python warp_interp)",
    };
}

/// The burst options as a caller gave them: `None` for an option not given.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BurstRequest {
    /// Frames per ISO (`None`: 1).
    pub frames: Option<i128>,
    /// Motion model by name.
    pub motion: Option<String>,
    /// Shake step, px.
    pub shake_step: Option<f64>,
    /// Shake roll, degrees.
    pub shake_roll: Option<f64>,
    /// Interpolant by name.
    pub warp_interp: Option<String>,
}

impl BurstRequest {
    /// The options these values ask for, or the first error in `n`'s spelling: each value in
    /// its range; the motion options only with a burst of more than one frame; the shake step
    /// and roll only with `shake` motion (with `none` they would be ignored).
    pub fn resolve(&self, n: &Names) -> Result<BurstOptions> {
        let mut b = BurstOptions::default();
        if let Some(f) = self.frames {
            b.frames = u32::try_from(f)
                .ok()
                .filter(|f| (1..=MAX_FRAMES).contains(f))
                .ok_or_else(|| {
                    Error::invalid(format!(
                        "{}: {f} is outside 1..={MAX_FRAMES} (frames per ISO)",
                        n.burst
                    ))
                })?;
        }
        if let Some(m) = &self.motion {
            b.motion = m
                .parse()
                .map_err(|_| Error::invalid(format!("{}: {m:?} (use none or shake)", n.motion)))?;
        }
        if let Some(k) = &self.warp_interp {
            b.interp = k.parse::<Interp>().map_err(|_| {
                Error::invalid(format!(
                    "{}: {k:?} (use {})",
                    n.warp_interp,
                    Interp::ALL.map(|i| i.name()).join(", ")
                ))
            })?;
        }
        if let Some(v) = self.shake_step {
            b.shake.step_px = v;
        }
        if let Some(v) = self.shake_roll {
            b.shake.roll_deg = v;
        }
        b.check(n)?;
        let given = [
            (n.motion, self.motion.is_some()),
            (n.shake_step, self.shake_step.is_some()),
            (n.shake_roll, self.shake_roll.is_some()),
            (n.warp_interp, self.warp_interp.is_some()),
        ];
        let given: Vec<&str> = given.iter().filter(|g| g.1).map(|g| g.0).collect();
        if b.is_single() && !given.is_empty() {
            return Err(Error::invalid(format!(
                "{} need{} a burst ({} N with N > 1); {} is {}",
                given.join(", "),
                if given.len() == 1 { "s" } else { "" },
                n.burst,
                n.burst,
                b.frames
            )));
        }
        if b.motion == Motion::None {
            let shake = [
                (n.shake_step, self.shake_step.is_some()),
                (n.shake_roll, self.shake_roll.is_some()),
            ];
            if let Some((name, _)) = shake.iter().find(|g| g.1) {
                return Err(Error::invalid(format!(
                    "{name} has no effect with {} none (the frames do not move): drop it, or \
                     use {} shake",
                    n.motion, n.motion
                )));
            }
        }
        Ok(b)
    }
}

impl BurstOptions {
    /// Error on out-of-range values ([`BurstOptions::check`], naming both the flag and the
    /// Python argument).
    pub fn validate(&self) -> Result<()> {
        self.check(&Names::EITHER)
    }

    /// Error unless every value is in its range, naming the option in `n`'s spelling with
    /// the value rounded.
    pub fn check(&self, n: &Names) -> Result<()> {
        if !(1..=MAX_FRAMES).contains(&self.frames) {
            return Err(Error::invalid(format!(
                "{}: {} is outside 1..={MAX_FRAMES} (frames per ISO)",
                n.burst, self.frames
            )));
        }
        let s = &self.shake;
        crate::bounds::in_range(
            &format!("{} (px)", n.shake_step),
            s.step_px,
            0.0,
            MAX_STEP_PX,
        )?;
        crate::bounds::in_range(
            &format!("{} (degrees)", n.shake_roll),
            s.roll_deg,
            0.0,
            MAX_ROLL_DEG,
        )
    }
}

/// Error when a value of `opts` is out of its range, or its shake step is too large for a
/// `w x h` active area: above
/// [`MAX_STEP_FRACTION`] of its smaller side (for a burst that shakes). Called by the planner
/// before [`super::motion::plan_burst`] draws anything.
pub fn check_step_fits(opts: &BurstOptions, (w, h): (usize, usize)) -> Result<()> {
    opts.validate()?;
    if opts.is_single() || opts.motion != Motion::Shake {
        return Ok(());
    }
    let max = MAX_STEP_FRACTION * w.min(h) as f64;
    if opts.shake.step_px > max {
        return Err(Error::invalid(format!(
            "{}: {} px is too large for the {w}x{h} active area (at most {} px, a quarter of \
             its smaller side; docs/synthesis.md, \"Bursts\")",
            Names::EITHER.shake_step,
            short(opts.shake.step_px),
            short(max)
        )));
    }
    Ok(())
}

/// One warning for the frames whose valid area is under [`MIN_VALID_FRACTION`] of the
/// `w x h` active area (empty ones said so), or none.
pub fn valid_area_warnings(transforms: &[FrameTransform], (w, h): (usize, usize)) -> Vec<Warning> {
    let area = (w * h) as f64;
    let small: Vec<String> = transforms
        .iter()
        .filter(|t| ((t.valid.width * t.valid.height) as f64) < MIN_VALID_FRACTION * area)
        .map(|t| {
            let v = t.valid;
            if v.width == 0 || v.height == 0 {
                format!("f{:02} empty", t.frame)
            } else {
                format!("f{:02} {}x{}", t.frame, v.width, v.height)
            }
        })
        .collect();
    if small.is_empty() {
        return vec![];
    }
    let message = format!(
        "burst: {} of {} frames keep a valid area under half of the {w}x{h} active area ({}): \
         outside it a frame repeats the image's edge; lower {}",
        small.len(),
        transforms.len(),
        small.join(", "),
        Names::EITHER.shake_step
    );
    vec![Warning::new(Code::BurstValidArea, message)]
}

fn bad(field: &str, why: impl std::fmt::Display) -> Error {
    Error::invalid(format!("plan field {field}: {why}"))
}

/// Error unless transform `t` (frame `i` of a burst about `centre` on a `w x h` active area,
/// warped with `interp`, translations within `extent` px) is what the planner would write:
/// finite; frame 00 the identity; a rotation part that is orthonormal and turns by
/// `theta_deg`; a translation that moves the centre by (`dx`, `dy`); a valid rectangle
/// inside the active area (overflow-safe) and inside the one the transform allows.
pub fn check_transform(
    i: usize,
    t: &FrameTransform,
    (centre, interp): ([f64; 2], Interp),
    (w, h): (usize, usize),
    extent: f64,
) -> Result<()> {
    let n = |f: &str| format!("burst.transforms[{i}].{f}");
    if t.frame as usize != i {
        return Err(bad(&n("frame"), format!("{} (expected {i})", t.frame)));
    }
    let pf = |f: &str| format!("plan field {}", n(f));
    crate::bounds::in_range(&pf("dx"), t.dx, -extent, extent)?;
    crate::bounds::in_range(&pf("dy"), t.dy, -extent, extent)?;
    crate::bounds::in_range(&pf("theta_deg"), t.theta_deg, -360.0, 360.0)?;
    for (r, row) in t.affine.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            let lim = if c == 2 {
                4.0 * extent
            } else {
                1.0 + ROTATION_TOLERANCE
            };
            crate::bounds::in_range(&pf(&format!("affine[{r}][{c}]")), v, -lim, lim)?;
        }
    }
    if i == 0 && t.affine != super::motion::IDENTITY {
        return Err(bad(&n("affine"), "frame 00 must be the identity"));
    }
    let [[a, b, tx], [c, d, ty]] = t.affine;
    // Orthonormal with determinant 1: a rotation [[cos, -sin], [sin, cos]].
    let off = [
        (a - d).abs(),
        (b + c).abs(),
        (a * a + c * c - 1.0).abs(),
        (a * d - b * c - 1.0).abs(),
    ];
    if off.iter().any(|&e| e > ROTATION_TOLERANCE) {
        return Err(bad(
            &n("affine"),
            format!(
                "[[{}, {}], [{}, {}]] is not a rotation (a burst frame moves rigidly: \
                 orthonormal, determinant 1)",
                short(a),
                short(b),
                short(c),
                short(d)
            ),
        ));
    }
    let want = rigid(centre, t.dx, t.dy, t.theta_deg);
    let rot_off = (0..2)
        .flat_map(|r| (0..2).map(move |c| (r, c)))
        .map(|(r, c)| (t.affine[r][c] - want[r][c]).abs())
        .fold(0.0, f64::max);
    if rot_off > ROTATION_TOLERANCE {
        return Err(bad(
            &n("affine"),
            format!(
                "turns by {} degrees, theta_deg says {}",
                short(c.atan2(a).to_degrees()),
                short(t.theta_deg)
            ),
        ));
    }
    let tol = TRANSLATION_TOLERANCE * extent.max(1.0);
    if (tx - want[0][2]).abs() > tol || (ty - want[1][2]).abs() > tol {
        return Err(bad(
            &n("affine"),
            format!(
                "translation ({}, {}) does not move the centre ({}, {}) by dx {}, dy {} \
                 (expected ({}, {}))",
                short(tx),
                short(ty),
                short(centre[0]),
                short(centre[1]),
                short(t.dx),
                short(t.dy),
                short(want[0][2]),
                short(want[1][2])
            ),
        ));
    }
    let v = &t.valid;
    let end = |o: usize, l: usize| o.checked_add(l);
    match (end(v.top, v.height), end(v.left, v.width)) {
        (Some(b), Some(r)) if b <= h && r <= w => {}
        _ => {
            return Err(bad(
                &n("valid"),
                format!(
                    "rows {}+{}, columns {}+{} lie outside the {w}x{h} active area",
                    v.top, v.height, v.left, v.width
                ),
            ))
        }
    }
    if v.width > 0 && v.height > 0 {
        let a = valid_rect(&t.affine, (w, h), interp.radius());
        let inside = v.top >= a.top
            && v.left >= a.left
            && v.top + v.height <= a.top + a.height
            && v.left + v.width <= a.left + a.width;
        if !inside {
            return Err(bad(
                &n("valid"),
                format!(
                    "{}x{} at ({}, {}) claims samples the transform takes from outside the \
                     image (its valid area is {}x{} at ({}, {}))",
                    v.width, v.height, v.left, v.top, a.width, a.height, a.left, a.top
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::motion::{plan_burst, ValidRect};
    use super::*;

    fn shaken() -> (super::super::motion::BurstPlan, (usize, usize)) {
        let o = BurstOptions {
            frames: 6,
            shake: super::super::motion::Shake {
                step_px: 3.0,
                roll_deg: 0.5,
            },
            ..BurstOptions::default()
        };
        let wh = (120, 80);
        (plan_burst(&o, wh, (9, "a.dng", 0)).unwrap().unwrap(), wh)
    }

    fn check(t: &FrameTransform, i: usize, wh: (usize, usize)) -> Result<()> {
        let c = [(wh.0 as f64 - 1.0) / 2.0, (wh.1 as f64 - 1.0) / 2.0];
        check_transform(i, t, (c, Interp::CatmullRom), wh, 12000.0)
    }

    #[test]
    fn sampled_transforms_pass() {
        let (p, wh) = shaken();
        for (i, t) in p.transforms.iter().enumerate() {
            check(t, i, wh).unwrap();
        }
    }

    #[test]
    fn a_shear_an_inconsistent_pose_and_an_overflowing_rectangle_fail() {
        let (p, wh) = shaken();
        let mut t = p.transforms[2].clone();
        t.affine = [[1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let e = check(&t, 2, wh).unwrap_err().to_string();
        assert!(e.contains("not a rotation"), "{e}");

        let mut t = p.transforms[2].clone();
        t.theta_deg += 1.0;
        let e = check(&t, 2, wh).unwrap_err().to_string();
        assert!(e.contains("theta_deg says"), "{e}");

        let mut t = p.transforms[2].clone();
        t.dx += 0.5;
        let e = check(&t, 2, wh).unwrap_err().to_string();
        assert!(e.contains("does not move the centre"), "{e}");

        let mut t = p.transforms[2].clone();
        t.valid.top = usize::MAX;
        let e = check(&t, 2, wh).unwrap_err().to_string();
        assert!(e.contains("outside the 120x80 active area"), "{e}");
    }

    #[test]
    fn a_valid_rectangle_the_transform_does_not_allow_fails() {
        let c = [59.5, 39.5];
        let affine = rigid(c, 5000.0, 0.0, 0.0);
        let t = FrameTransform {
            frame: 1,
            dx: 5000.0,
            dy: 0.0,
            theta_deg: 0.0,
            affine,
            valid: ValidRect {
                top: 10,
                left: 10,
                height: 60,
                width: 44,
            },
        };
        let e = check(&t, 1, (120, 80)).unwrap_err().to_string();
        assert!(
            e.contains("44x60") && e.contains("valid area is 0x0"),
            "{e}"
        );
    }

    #[test]
    fn a_rotation_entry_just_above_one_is_rounding() {
        let (p, wh) = shaken();
        let mut t = p.transforms[0].clone();
        t.affine[0][0] = 1.0 + 1e-15;
        t.affine[1][1] = 1.0 + 1e-15;
        // Within the tolerance of a rotation, but frame 00 must be exactly the identity.
        assert!(check(&t, 0, wh)
            .unwrap_err()
            .to_string()
            .contains("identity"));
        let mut t = p.transforms[1].clone();
        t.affine[0][0] += 1e-15;
        check(&t, 1, wh).unwrap();
    }

    #[test]
    fn requests_follow_the_command_line_rules() {
        let r = |f: Option<i128>, m: Option<&str>, s: Option<f64>| BurstRequest {
            frames: f,
            motion: m.map(String::from),
            shake_step: s,
            ..BurstRequest::default()
        };
        let e = |q: BurstRequest, n: &Names| q.resolve(n).unwrap_err().to_string();
        let m = e(r(Some(1), Some("shake"), None), &Names::PYTHON);
        assert!(
            m.contains("motion needs a burst (burst N with N > 1)"),
            "{m}"
        );
        let m = e(r(None, None, Some(2.0)), &Names::CLI);
        assert!(m.contains("--shake-step needs a burst"), "{m}");
        let m = e(r(Some(-1), None, None), &Names::PYTHON);
        assert!(m.contains("burst: -1 is outside 1..=64"), "{m}");
        let m = e(r(Some(3), Some("none"), Some(5.0)), &Names::CLI);
        assert!(
            m.contains("--shake-step has no effect with --motion none"),
            "{m}"
        );
        let m = e(r(Some(3), None, Some(1e308)), &Names::CLI);
        assert!(
            m.contains("--shake-step (px): 1e308 is outside [0, 1000]"),
            "{m}"
        );
        assert!(r(Some(3), Some("none"), None).resolve(&Names::CLI).is_ok());
    }

    #[test]
    fn the_step_is_bounded_by_the_image_and_small_valid_areas_are_reported() {
        let o = BurstOptions {
            frames: 3,
            shake: super::super::motion::Shake {
                step_px: 50.0,
                roll_deg: 0.0,
            },
            ..BurstOptions::default()
        };
        let e = check_step_fits(&o, (64, 48)).unwrap_err().to_string();
        assert!(e.contains("64x48") && e.contains("at most 12 px"), "{e}");
        assert!(check_step_fits(&o, (400, 300)).is_ok());
        let mut far = shaken().0.transforms;
        far[3].valid = ValidRect {
            top: 0,
            left: 0,
            height: 0,
            width: 0,
        };
        let w = valid_area_warnings(&far, (120, 80));
        assert_eq!(w.len(), 1);
        assert!(w[0].message.contains("f03 empty"), "{w:?}");
        assert_eq!(w[0].code, Code::BurstValidArea);
        assert!(valid_area_warnings(&shaken().0.transforms, (120, 80)).is_empty());
    }
}
