//! The burst's options and its planned motion: how many frames, which motion model, and each
//! frame's rigid transform relative to frame 00 (docs/synthesis.md, "Bursts").
//!
//! Coordinates are those of the **active area**: x to the right, y down, pixel (sample)
//! centres at integer coordinates, so sample (row r, column c) sits at (x, y) = (c, r) and
//! the centre of a `W x H` active area is `((W - 1) / 2, (H - 1) / 2)`. Frame k's transform
//! maps a scene point's frame-00 position `p0` to its frame-k position
//! `pk = R(theta) (p0 - centre) + centre + (dx, dy)`, written as the 2x3 affine
//! `pk = A p0 + b` (`affine = [[a, b, tx], [c, d, ty]]`). With y down, a positive `theta`
//! turns the scene clockwise on screen.
//!
//! The hand-held model (`shake`) is a random walk: frame 00 is the identity and frame k adds
//! an independent step to frame k-1's pose, `dx += step * z`, `dy += step * z`,
//! `theta += roll * z` (z ~ N(0, 1)). The draws come from the burst's own stream (SHA-256
//! of a tag and the variant's stream key), drawn only when the burst has more than one
//! frame, so the rest of the plan is the single-frame plan, draw for draw.

use super::interp::Interp;
use crate::error::{Error, Result};
use crate::synth::rng::{stream_key, SynthRng};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// The motion between the frames of a burst (`--motion`; its default is the option
/// table's, src/synth/options/table.rs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    /// A tripod: every frame is the identity (frames differ by their noise only).
    None,
    /// A hand-held camera: translation and roll as a random walk.
    Shake,
}

crate::choices! {
    Motion, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "motion {s:?} (use {})",
        crate::choice::listed::<Motion>(", ", " or ")
    )),
    None => "none": "A tripod: the frames differ by their noise only",
    Shake => "shake": "A hand-held camera: translation and roll as a random walk",
}

/// The hand-held walk's parameters (`--shake-step`, `--shake-roll`; docs/synthesis.md,
/// "Bursts": where the defaults come from).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Shake {
    /// Standard deviation of each frame's translation step, per axis, in pixels.
    pub step_px: f64,
    /// Standard deviation of each frame's rotation step, in degrees.
    pub roll_deg: f64,
}

/// What a burst is made of (`synth --burst N --motion ...`); part of
/// [`crate::synth::SynthOptions`], left out of serialized options for a single frame so
/// that single-frame sidecars and dataset fingerprints are unchanged. Its defaults, ranges
/// and choices are the option table's (src/synth/options/table.rs): the defaults are
/// [`crate::synth::options::burst_defaults`], and a field a serialized burst lacks takes its
/// default from there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default = "crate::synth::options::burst_defaults")]
pub struct BurstOptions {
    /// Frames per ISO (1 = one noisy raw per ISO, as without a burst).
    pub frames: u32,
    /// Motion between the frames.
    pub motion: Motion,
    /// The hand-held walk's parameters (used with [`Motion::Shake`]).
    pub shake: Shake,
    /// Interpolant of the warp.
    pub interp: Interp,
}

impl Default for BurstOptions {
    /// The blank that [`crate::synth::SynthOptions`]'s defaults start from (no frame, no
    /// motion), on which the option table sets its defaults; not the defaults themselves,
    /// which are [`crate::synth::options::burst_defaults`].
    fn default() -> BurstOptions {
        BurstOptions {
            frames: 0,
            motion: Motion::None,
            shake: Shake {
                step_px: 0.0,
                roll_deg: 0.0,
            },
            interp: Interp::Bilinear,
        }
    }
}

impl BurstOptions {
    /// True for a single frame (nothing of the burst is planned or recorded).
    pub fn is_single(&self) -> bool {
        self.frames <= 1
    }
}

/// A rectangle of a frame's active area: `top..top + height` x `left..left + width`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ValidRect {
    /// First row.
    pub top: usize,
    /// First column.
    pub left: usize,
    /// Rows (0 when no sample of the frame is valid).
    pub height: usize,
    /// Columns.
    pub width: usize,
}

/// One frame's pose relative to frame 00.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameTransform {
    /// Frame index (0 = the reference).
    pub frame: u32,
    /// Translation of the image centre, x (px).
    pub dx: f64,
    /// Translation of the image centre, y (px).
    pub dy: f64,
    /// Rotation about the image centre (degrees; clockwise on screen, y being down).
    pub theta_deg: f64,
    /// The 2x3 affine mapping frame-00 to frame-k active-area pixel coordinates (module
    /// documentation); the warp uses exactly these numbers.
    pub affine: [[f64; 3]; 2],
    /// The samples of this frame whose interpolation reads no sample from outside the
    /// image (outside it the edge is repeated: docs/synthesis.md, "Bursts").
    pub valid: ValidRect,
}

impl FrameTransform {
    /// True when the frame is exactly frame 00's geometry (its clean raw is the clean raw).
    pub fn is_identity(&self) -> bool {
        self.affine == IDENTITY
    }

    /// The inverse affine: frame-k coordinates to frame-00 coordinates.
    pub fn inverse(&self) -> [[f64; 3]; 2] {
        invert(&self.affine)
    }
}

/// The identity affine.
pub const IDENTITY: [[f64; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// The inverse of a 2x3 affine (its linear part invertible; a rigid one always is).
pub fn invert(m: &[[f64; 3]; 2]) -> [[f64; 3]; 2] {
    let [[a, b, tx], [c, d, ty]] = *m;
    let det = a * d - b * c;
    let (ia, ib, ic, id) = (d / det, -b / det, -c / det, a / det);
    [
        [ia, ib, -(ia * tx + ib * ty)],
        [ic, id, -(ic * tx + id * ty)],
    ]
}

/// Apply a 2x3 affine to (x, y).
#[inline]
pub fn apply(m: &[[f64; 3]; 2], x: f64, y: f64) -> (f64, f64) {
    (
        m[0][0] * x + m[0][1] * y + m[0][2],
        m[1][0] * x + m[1][1] * y + m[1][2],
    )
}

/// The affine of a rotation by `theta_deg` about `centre` followed by a translation.
pub fn rigid(centre: [f64; 2], dx: f64, dy: f64, theta_deg: f64) -> [[f64; 3]; 2] {
    if dx == 0.0 && dy == 0.0 && theta_deg == 0.0 {
        return IDENTITY;
    }
    let t = theta_deg.to_radians();
    let (s, c) = t.sin_cos();
    let [cx, cy] = centre;
    [
        [c, -s, cx - (c * cx - s * cy) + dx],
        [s, c, cy - (s * cx + c * cy) + dy],
    ]
}

/// The burst part of a plan: every frame's transform (present only for more than one frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BurstPlan {
    /// Frames per ISO.
    pub frames: u32,
    /// The motion model.
    pub motion: Motion,
    /// The walk's parameters (recorded with [`Motion::None`] too; unused then).
    pub shake: Shake,
    /// Interpolant of the warp.
    pub interp: Interp,
    /// The centre the rotations are about (x, y), `((W - 1) / 2, (H - 1) / 2)`.
    pub centre: [f64; 2],
    /// One transform per frame, frame 00 first (the identity).
    pub transforms: Vec<FrameTransform>,
}

/// The key of the burst's own random stream for (seed, input name, variant).
pub fn burst_key(seed: u64, input_name: &str, variant: u32) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(b"day2night burst motion v1\0");
    h.update(stream_key(seed, input_name, variant));
    h.finalize().into()
}

/// The noise seed of frame `frame` at an ISO whose plan seed is `seed`: frame 00 keeps the
/// single-frame seed (its noisy raw is the single-frame noisy raw), frame k > 0 draws from
/// `SHA-256("day2night burst frame noise v1" || seed || k)`.
pub fn frame_noise_seed(seed: u64, frame: u32) -> u64 {
    if frame == 0 {
        return seed;
    }
    let mut h = Sha256::new();
    h.update(b"day2night burst frame noise v1\0");
    h.update(seed.to_le_bytes());
    h.update(frame.to_le_bytes());
    let d: [u8; 32] = h.finalize().into();
    let mut b = [0u8; 8];
    b.copy_from_slice(&d[..8]);
    u64::from_le_bytes(b)
}

/// Plan the burst of a `w x h` active area: `None` for a single frame. The caller checks
/// `opts` first ([`super::checks::check_step_fits`]: the ranges and the step against the
/// image).
pub fn plan_burst(
    opts: &BurstOptions,
    (w, h): (usize, usize),
    (seed, input_name, variant): (u64, &str, u32),
) -> Result<Option<BurstPlan>> {
    if opts.is_single() {
        return Ok(None);
    }
    let centre = [(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0];
    let mut rng = SynthRng::from_key(burst_key(seed, input_name, variant));
    let (mut dx, mut dy, mut th) = (0.0f64, 0.0f64, 0.0f64);
    let mut transforms = Vec::with_capacity(opts.frames as usize);
    for k in 0..opts.frames {
        if k > 0 && opts.motion == Motion::Shake {
            dx += opts.shake.step_px * rng.normal();
            dy += opts.shake.step_px * rng.normal();
            th += opts.shake.roll_deg * rng.normal();
        }
        let affine = rigid(centre, dx, dy, th);
        transforms.push(FrameTransform {
            frame: k,
            dx,
            dy,
            theta_deg: th,
            valid: valid_rect(&affine, (w, h), opts.interp.radius()),
            affine,
        });
    }
    Ok(Some(BurstPlan {
        frames: opts.frames,
        motion: opts.motion,
        shake: opts.shake,
        interp: opts.interp,
        centre,
        transforms,
    }))
}

/// True when frame-k point (x, y) maps to a frame-00 point whose `radius`-tap interpolation
/// reads inside the `w x h` image: `radius - 1 <= x0 <= w - 1 - radius` (and the same in y).
fn inside(inv: &[[f64; 3]; 2], (w, h): (usize, usize), r: usize, x: f64, y: f64) -> bool {
    let (x0, y0) = apply(inv, x, y);
    let lo = r as f64 - 1.0;
    x0 >= lo && y0 >= lo && x0 <= (w - 1) as f64 - r as f64 && y0 <= (h - 1) as f64 - r as f64
}

/// The rectangle of frame-k samples whose source lies wholly inside the image for a
/// `radius`-tap interpolant: the frame-00 box `[r - 1, W - 1 - r] x [r - 1, H - 1 - r]`
/// mapped into frame k (a rotated rectangle), the axis-aligned rectangle inside it, its
/// corners checked through the inverse map (a convex set holds the whole rectangle when it
/// holds the corners) and shrunk until they are inside.
pub fn valid_rect(affine: &[[f64; 3]; 2], (w, h): (usize, usize), r: usize) -> ValidRect {
    let empty = ValidRect {
        top: 0,
        left: 0,
        height: 0,
        width: 0,
    };
    if *affine == IDENTITY {
        return ValidRect {
            top: 0,
            left: 0,
            height: h,
            width: w,
        };
    }
    if w < 2 * r || h < 2 * r {
        return empty;
    }
    let inv = invert(affine);
    let (lo, hx, hy) = (r as f64 - 1.0, (w - 1 - r) as f64, (h - 1 - r) as f64);
    let c = [(lo, lo), (hx, lo), (lo, hy), (hx, hy)].map(|(x, y)| apply(affine, x, y));
    // corners: top-left, top-right, bottom-left, bottom-right of the source box
    let left = c[0].0.max(c[2].0).ceil();
    let right = c[1].0.min(c[3].0).floor();
    let top = c[0].1.max(c[1].1).ceil();
    let bottom = c[2].1.min(c[3].1).floor();
    let clampi = |v: f64, n: usize| v.clamp(0.0, (n - 1) as f64) as usize;
    if !(left <= right && top <= bottom) || right < 0.0 || bottom < 0.0 {
        return empty;
    }
    let (mut x0, mut x1) = (clampi(left, w), clampi(right, w));
    let (mut y0, mut y1) = (clampi(top, h), clampi(bottom, h));
    // shrink until every corner's source is inside (rounding, or a large rotation)
    for _ in 0..(w + h) {
        let ok = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
            .iter()
            .all(|&(x, y)| inside(&inv, (w, h), r, x as f64, y as f64));
        if ok {
            return ValidRect {
                top: y0,
                left: x0,
                height: y1 - y0 + 1,
                width: x1 - x0 + 1,
            };
        }
        if x1 <= x0 || y1 <= y0 {
            break;
        }
        x0 += 1;
        x1 -= 1;
        y0 += 1;
        y1 -= 1;
    }
    empty
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn affine_maps_the_centre_by_the_translation_and_inverts() {
        let c = [99.5, 49.5];
        let m = rigid(c, 3.25, -1.5, 0.7);
        let (x, y) = apply(&m, c[0], c[1]);
        assert!((x - 102.75).abs() < 1e-12 && (y - 48.0).abs() < 1e-12);
        let inv = invert(&m);
        for (px, py) in [(0.0, 0.0), (199.0, 0.0), (13.5, 77.25)] {
            let (qx, qy) = apply(&m, px, py);
            let (rx, ry) = apply(&inv, qx, qy);
            assert!((rx - px).abs() < 1e-9 && (ry - py).abs() < 1e-9);
        }
        // a positive angle turns (x right, y down) clockwise on screen: +x goes to +y
        let m = rigid([0.0, 0.0], 0.0, 0.0, 90.0);
        let (x, y) = apply(&m, 1.0, 0.0);
        assert!(x.abs() < 1e-12 && (y - 1.0).abs() < 1e-12);
        assert_eq!(rigid(c, 0.0, 0.0, 0.0), IDENTITY);
    }

    #[test]
    fn valid_rects_hold_only_inside_sources() {
        for (dx, dy, th) in [
            (0.0, 0.0, 0.0),
            (2.5, -3.0, 0.0),
            (-7.0, 1.0, 0.4),
            (0.3, 0.2, -2.0),
            (500.0, 0.0, 0.0),
        ] {
            let (w, h) = (120usize, 80usize);
            let m = rigid([59.5, 39.5], dx, dy, th);
            let v = valid_rect(&m, (w, h), 2);
            let inv = invert(&m);
            let mut inside_count = 0;
            for y in 0..h {
                for x in 0..w {
                    let ok = inside(&inv, (w, h), 2, x as f64, y as f64) || m == IDENTITY;
                    let in_rect = (v.top..v.top + v.height).contains(&y)
                        && (v.left..v.left + v.width).contains(&x);
                    if in_rect {
                        assert!(ok, "{dx} {dy} {th}: ({x},{y}) in {v:?}");
                    }
                    inside_count += ok as usize;
                }
            }
            // the rectangle is most of the valid set for small motions
            if dx.abs() < 100.0 {
                assert!(
                    v.width * v.height * 10 >= inside_count * 8,
                    "{v:?} {inside_count}"
                );
            } else {
                assert_eq!(v.width * v.height, 0);
            }
        }
    }

    #[test]
    fn the_walk_is_seeded_and_none_is_identity() {
        let o = BurstOptions {
            frames: 8,
            ..crate::synth::options::burst_defaults()
        };
        let a = plan_burst(&o, (400, 300), (1, "a.dng", 0))
            .unwrap()
            .unwrap();
        let b = plan_burst(&o, (400, 300), (1, "a.dng", 0))
            .unwrap()
            .unwrap();
        assert_eq!(a, b);
        assert!(a.transforms[0].is_identity());
        assert!(a.transforms[1..].iter().all(|t| !t.is_identity()));
        let c = plan_burst(&o, (400, 300), (1, "a.dng", 1))
            .unwrap()
            .unwrap();
        assert_ne!(a.transforms[3], c.transforms[3]);
        let n = BurstOptions {
            motion: Motion::None,
            ..o
        };
        let p = plan_burst(&n, (400, 300), (1, "a.dng", 0))
            .unwrap()
            .unwrap();
        assert!(p.transforms.iter().all(|t| t.is_identity()));
        assert!(plan_burst(
            &crate::synth::options::burst_defaults(),
            (4, 4),
            (0, "x", 0)
        )
        .unwrap()
        .is_none());
        assert_eq!(frame_noise_seed(77, 0), 77);
        assert_ne!(frame_noise_seed(77, 1), frame_noise_seed(77, 2));
        // a count out of the table's range is refused with the options (not here)
        let bad = crate::synth::SynthOptions {
            burst: BurstOptions { frames: 65, ..o },
            ..Default::default()
        };
        assert!(bad.validate().is_err());
    }
}
