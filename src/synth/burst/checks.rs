//! Every check of a burst, spelled once for every entry point (docs/synthesis.md, "Bursts"):
//! the rules between its options ([`check_rules`]; each option's range and choices are the
//! option table's, src/synth/options/table.rs, checked there), the shake step against the
//! image size before the draw ([`check_step_fits`]), the frames' valid areas after it
//! ([`valid_area_warnings`]), and a replayed sidecar's transforms ([`check_transform`]).
//! Messages name the option in the caller's spelling, the value rounded
//! ([`crate::bounds::short`]) and the allowed range.

use super::interp::Interp;
use super::motion::{rigid, valid_rect, BurstOptions, FrameTransform, Motion};
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

/// An option as a message names it where the caller is not known (the planner): both the
/// flag and the Python keyword, `--shake-step (Python shake_step)`.
pub fn either(flag: &str) -> String {
    format!("--{flag} (Python {})", flag.replace('-', "_"))
}

/// The rules between the burst options, which the option table's checks of each value
/// (range, choice) cannot make: the motion options only with a burst of more than one
/// frame, the shake step and roll only with `shake` motion (with `none` they would be
/// ignored). An option at its default (`defaults`, the table's) changes nothing and is not
/// refused. `spell` names an option (by its table name) as the caller spells it.
pub fn check_rules(
    b: &BurstOptions,
    defaults: &BurstOptions,
    spell: &dyn Fn(&str) -> String,
) -> Result<()> {
    let set = [
        ("motion", b.motion != defaults.motion),
        ("shake-step", b.shake.step_px != defaults.shake.step_px),
        ("shake-roll", b.shake.roll_deg != defaults.shake.roll_deg),
        ("warp-interp", b.interp != defaults.interp),
    ];
    let set: Vec<String> = set.iter().filter(|g| g.1).map(|g| spell(g.0)).collect();
    let burst = spell("burst");
    if b.is_single() && !set.is_empty() {
        return Err(Error::invalid(format!(
            "{} need{} a burst ({burst} N with N > 1); {burst} is {}",
            set.join(", "),
            if set.len() == 1 { "s" } else { "" },
            b.frames
        )));
    }
    if b.motion == Motion::None {
        let shake = [
            ("shake-step", b.shake.step_px != defaults.shake.step_px),
            ("shake-roll", b.shake.roll_deg != defaults.shake.roll_deg),
        ];
        if let Some((name, _)) = shake.iter().find(|g| g.1) {
            let motion = spell("motion");
            return Err(Error::invalid(format!(
                "{} has no effect with {motion} none (the frames do not move): drop it, or \
                 use {motion} shake",
                spell(name)
            )));
        }
    }
    Ok(())
}

/// Error when the shake step of `opts` (each value already in its range:
/// [`crate::synth::SynthOptions::validate`]) is too large for a `w x h` active area: above
/// [`MAX_STEP_FRACTION`] of its smaller side (for a burst that shakes). Called by the planner
/// before [`super::motion::plan_burst`] draws anything.
pub fn check_step_fits(opts: &BurstOptions, (w, h): (usize, usize)) -> Result<()> {
    if opts.is_single() || opts.motion != Motion::Shake {
        return Ok(());
    }
    let max = MAX_STEP_FRACTION * w.min(h) as f64;
    if opts.shake.step_px > max {
        return Err(Error::invalid(format!(
            "{}: {} px is too large for the {w}x{h} active area (at most {} px, a quarter of \
             its smaller side; docs/synthesis.md, \"Bursts\")",
            either("shake-step"),
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
        either("shake-step")
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
            ..crate::synth::options::burst_defaults()
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
    fn the_rules_between_the_options_name_them_as_the_caller_does() {
        let d = crate::synth::options::burst_defaults();
        let python = |n: &str| n.replace('-', "_");
        let cli = |n: &str| format!("--{n}");
        let e = |b: BurstOptions, spell: &dyn Fn(&str) -> String| {
            check_rules(&b, &d, spell).unwrap_err().to_string()
        };
        let none = BurstOptions {
            motion: Motion::None,
            ..d
        };
        let m = e(none, &python);
        assert!(
            m.contains("motion needs a burst (burst N with N > 1)"),
            "{m}"
        );
        let mut stepped = d;
        stepped.shake.step_px = 2.0;
        let m = e(stepped, &cli);
        assert!(m.contains("--shake-step needs a burst"), "{m}");
        let m = e(
            BurstOptions {
                frames: 3,
                ..BurstOptions {
                    motion: Motion::None,
                    ..stepped
                }
            },
            &cli,
        );
        assert!(
            m.contains("--shake-step has no effect with --motion none"),
            "{m}"
        );
        // a value at its default changes nothing: not refused
        check_rules(&d, &d, &cli).unwrap();
        check_rules(&BurstOptions { frames: 3, ..none }, &d, &cli).unwrap();
    }

    #[test]
    fn the_step_is_bounded_by_the_image_and_small_valid_areas_are_reported() {
        let o = BurstOptions {
            frames: 3,
            shake: super::super::motion::Shake {
                step_px: 50.0,
                roll_deg: 0.0,
            },
            ..crate::synth::options::burst_defaults()
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
