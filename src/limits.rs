//! Resource limits against hostile or absurd inputs: the largest image (in pixels) the readers
//! accept, and fallible allocation of large buffers (an allocation the system refuses is an
//! [`Error::Limits`] naming the size asked, never an abort). See docs/limits.md.
//!
//! The limits in force are process-wide: the defaults ([`DEFAULT_MAX_PIXELS`],
//! [`DEFAULT_OPCODE_BUDGET`]), or what the caller passed to [`Limits::install`]. The library
//! reads no environment variable: the CLI builds its [`Limits`] from `--max-pixels`,
//! `D2N_MAX_PIXELS` and `D2N_OPCODE_BUDGET` (src/cli/limits.rs) and installs them; a program
//! using the library installs its own.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicU64, Ordering};

/// Default largest image, in pixels (stored width x height): 2^28 = 268,435,456. That is
/// 1.8 times the largest single-shot camera sensor sold today (Phase One IQ4 150 MP,
/// 14204 x 10652), and its raw plane alone is 512 MiB of `u16`.
pub const DEFAULT_MAX_PIXELS: u64 = 1 << 28;

/// Environment variable from which the CLI sets the pixel limit when no option does (named in
/// the limit's error messages; the library does not read it).
pub const MAX_PIXELS_ENV: &str = "D2N_MAX_PIXELS";

/// Highest value the pixel limit can be raised to (65535 x 65535, the largest TIFF image the
/// readers accept per side).
pub const MAX_PIXELS_CEILING: u64 = 65535 * 65535;

/// 0 = not installed: the default applies.
static INSTALLED_MAX_PIXELS: AtomicU64 = AtomicU64::new(0);
/// 0 = not installed: the default applies.
static INSTALLED_OPCODE_BUDGET: AtomicU64 = AtomicU64::new(0);

/// Resource limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest image accepted, in pixels.
    pub max_pixels: u64,
    /// Budget of opcode work for one render, in pixel-passes ([`check_opcode_work`]).
    pub opcode_budget: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_pixels: DEFAULT_MAX_PIXELS,
            opcode_budget: DEFAULT_OPCODE_BUDGET,
        }
    }
}

impl Limits {
    /// Limits with `max_pixels`, checked to be in `1..=MAX_PIXELS_CEILING`.
    pub fn with_max_pixels(max_pixels: u64) -> Result<Limits> {
        if max_pixels == 0 || max_pixels > MAX_PIXELS_CEILING {
            return Err(Error::invalid(format!(
                "pixel limit {max_pixels} must be in 1..={MAX_PIXELS_CEILING}"
            )));
        }
        Ok(Limits {
            max_pixels,
            ..Limits::default()
        })
    }

    /// These limits with the opcode work budget `budget` (pixel-passes, at least 1).
    pub fn with_opcode_budget(self, budget: u64) -> Result<Limits> {
        if budget == 0 {
            return Err(Error::invalid(
                "opcode work budget must be a positive number of pixel-passes",
            ));
        }
        Ok(Limits {
            opcode_budget: budget,
            ..self
        })
    }

    /// Parse an opcode work budget: a positive integer of pixel-passes.
    pub fn parse_opcode_budget(s: &str) -> Result<u64> {
        match s.trim().parse::<u64>() {
            Ok(n) if n > 0 => Ok(n),
            _ => Err(Error::invalid(format!(
                "{s:?} is not a positive number of pixel-passes"
            ))),
        }
    }

    /// Parse a pixel count: digits, optionally with a `M` (10^6) or `G` (10^9) suffix
    /// ("300M", "1.5G", "400000000").
    pub fn parse_pixels(s: &str) -> Result<u64> {
        let t = s.trim();
        let (num, mul) = match t.chars().last() {
            Some('M' | 'm') => (&t[..t.len() - 1], 1e6),
            Some('G' | 'g') => (&t[..t.len() - 1], 1e9),
            _ => (t, 1.0),
        };
        let v: f64 = num
            .parse()
            .map_err(|_| Error::invalid(format!("{s:?} is not a pixel count (e.g. 300M)")))?;
        let px = v * mul;
        if !(px.is_finite() && px >= 1.0 && px <= MAX_PIXELS_CEILING as f64) {
            return Err(Error::invalid(format!(
                "pixel limit {s:?} must be in 1..={MAX_PIXELS_CEILING}"
            )));
        }
        Ok(px.round() as u64)
    }

    /// The limits in force: the installed ones ([`Limits::install`]), else the defaults.
    /// (A `Result` for the callers that once read the environment here; it is always `Ok`.)
    pub fn current() -> Result<Limits> {
        let d = Limits::default();
        let or = |v: u64, default: u64| if v == 0 { default } else { v };
        Ok(Limits {
            max_pixels: or(INSTALLED_MAX_PIXELS.load(Ordering::Relaxed), d.max_pixels),
            opcode_budget: or(
                INSTALLED_OPCODE_BUDGET.load(Ordering::Relaxed),
                d.opcode_budget,
            ),
        })
    }

    /// Make these the process-wide limits.
    pub fn install(self) {
        INSTALLED_MAX_PIXELS.store(self.max_pixels, Ordering::Relaxed);
        INSTALLED_OPCODE_BUDGET.store(self.opcode_budget, Ordering::Relaxed);
    }

    /// Error unless a `width` x `height` image (`what`: "raw image", "EXR data window", ...)
    /// is within the pixel limit.
    pub fn check_pixels(&self, what: &str, width: u64, height: u64) -> Result<()> {
        let n = width.saturating_mul(height);
        if n > self.max_pixels {
            return Err(Error::limits(format!(
                "{what} of {width}x{height} = {n} pixels exceeds the limit of {} pixels \
                 (raise it with --max-pixels or {MAX_PIXELS_ENV})",
                self.max_pixels
            )));
        }
        Ok(())
    }
}

/// [`Limits::current`]`.check_pixels(...)`.
pub fn check_pixels(what: &str, width: u64, height: u64) -> Result<()> {
    Limits::current()?.check_pixels(what, width, height)
}

/// Human-readable byte count ("512.0 MiB").
pub fn bytes_human(n: u128) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} bytes")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

fn alloc_error<T>(n: usize, what: &str) -> Error {
    let bytes = (n as u128) * (std::mem::size_of::<T>() as u128);
    Error::limits(format!(
        "cannot allocate {} for {what} ({n} elements): not enough memory",
        bytes_human(bytes)
    ))
}

/// An empty vector with room for `n` elements, or [`Error::Limits`] naming the size when the
/// allocator refuses (instead of aborting the process).
pub fn try_with_capacity<T>(n: usize, what: &str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| alloc_error::<T>(n, what))?;
    Ok(v)
}

/// `vec![value; n]`, or [`Error::Limits`] naming the size when the allocator refuses.
pub fn try_filled<T: Clone>(value: T, n: usize, what: &str) -> Result<Vec<T>> {
    let mut v = try_with_capacity(n, what)?;
    v.resize(n, value);
    Ok(v)
}

// ---- Opcode lists (DNG 1.6 chapter 6; see docs/dng-support.md) --------------------------------
// Checked by `dng::opcodes::parse_list` before anything is allocated: a hostile 4-byte count
// is refused, never reserved. Every list is also bounded by its own byte count (a count that
// does not fit the bytes is malformed), so these only cap what a well-formed list may ask.

/// Most opcodes in one list. Phones write up to about ten (four GainMaps, a warp, bad pixels).
pub const MAX_OPCODES_PER_LIST: u32 = 4096;
/// Most gains in one GainMap (`MapPointsV * MapPointsH * MapPlanes`): 2^22 (16 MiB of `f32`);
/// phones write 17 x 13 x 1 to 51 x 39 x 4.
pub const MAX_GAIN_MAP_POINTS: u64 = 1 << 22;
/// Longest MapTable: 65536 entries (every 16-bit value; the Adobe SDK's limit too).
pub const MAX_MAP_TABLE_LEN: u32 = 1 << 16;
/// Most bad points plus bad rectangles in one FixBadPixelsList: 2^22.
pub const MAX_BAD_PIXEL_ENTRIES: u64 = 1 << 22;
/// Most entries in one DeltaPerRow/Column or ScalePerRow/Column (one per row or column step:
/// the readers' largest side is 65535).
pub const MAX_PER_LINE_ENTRIES: u64 = 1 << 16;
/// Most planes a WarpRectilinear or WarpFisheye may describe (the DNG SDK's kMaxColorPlanes).
pub const MAX_WARP_PLANES: u32 = 4;
/// Highest MapPolynomial degree (DNG 1.6, MapPolynomial: "Degree ... from 0 to 8").
pub const MAX_POLYNOMIAL_DEGREE: u32 = 8;

// ---- Opcode work (docs/limits.md, "Opcode work") ------------------------------------------
// The work of the lists a render applies is counted at planning, before any pixel is touched:
// each opcode costs its weight (below) times the pixels of the stage image it acts on (the
// stored image for OpcodeList1, the active area for lists 2 and 3; an area opcode counts the
// pixels of its area and pitch). Opcodes that change nothing are dropped first and cost
// nothing (`isp::opcodes::budget`). One unit is about one pointwise pass over one pixel
// (4 ns on the 2-core benchmark machine, docs/benchmarks.md "DNG opcodes").

/// Default budget of opcode work, in pixel-passes: 2^34 (about a minute of opcode work on the
/// benchmark machine). A 150 MP frame with four GainMaps and a warp costs about 2^32.7.
pub const DEFAULT_OPCODE_BUDGET: u64 = 1 << 34;
/// Environment variable from which the CLI sets the opcode work budget (pixel-passes; named
/// in the budget's error messages, the library does not read it).
pub const OPCODE_BUDGET_ENV: &str = "D2N_OPCODE_BUDGET";
/// Weight of a per-sample area opcode (MapTable, MapPolynomial, Delta/Scale per row/column).
pub const COST_POINTWISE: u64 = 1;
/// Weight of a GainMap and of a FixVignetteRadial (a bilinear gain or a polynomial per pixel).
pub const COST_GAIN: u64 = 2;
/// Weight of a bad-pixel pass (a mask of the pixels, then the repairs).
pub const COST_BAD_PIXELS: u64 = 2;
/// Weight of a repeated identical FixBadPixelsConstant (it only revisits the pixels still bad).
pub const COST_BAD_PIXELS_REPEAT: u64 = 1;
/// Weight of a rectilinear warp (WarpRectilinear, WarpRectilinear2: 4x4 bicubic per sample).
pub const COST_WARP: u64 = 32;
/// Weight of a fisheye warp (an `atan` per pixel more).
pub const COST_WARP_FISHEYE: u64 = 40;
/// Weight of a TrimBounds (one copy).
pub const COST_TRIM: u64 = 1;

/// The opcode work budget in force: the installed one ([`Limits::install`]), else
/// [`DEFAULT_OPCODE_BUDGET`].
pub fn opcode_budget() -> Result<u64> {
    Ok(Limits::current()?.opcode_budget)
}

/// The cost of one opcode: its list's tag name, its description ("WarpRectilinear (opcode
/// 3 of 4)") and its pixel-passes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OpcodeCost {
    /// "OpcodeList1" ...
    pub list: &'static str,
    /// Name and position in its list.
    pub what: String,
    /// Pixel-passes.
    pub cost: u64,
}

/// Error unless the opcodes' total cost is within `budget`. The error names the list in which
/// the total passes the budget, and the opcode when that opcode alone costs more than it.
pub fn check_opcode_work(costs: &[OpcodeCost], budget: u64) -> Result<()> {
    let mut total = 0u64;
    for c in costs {
        if c.cost > budget {
            return Err(Error::limits(format!(
                "{}: {} alone costs {} pixel-passes of opcode work, more than the budget of \
                 {budget} (docs/limits.md, \"Opcode work\"; raise it with {OPCODE_BUDGET_ENV}, \
                 or render with --opcodes ignore)",
                c.list, c.what, c.cost
            )));
        }
        total = total.saturating_add(c.cost);
        if total > budget {
            let n = costs.iter().filter(|d| d.list == c.list).count();
            return Err(Error::limits(format!(
                "{}: its {n} opcodes bring the opcode work to {total} pixel-passes, more than \
                 the budget of {budget} (docs/limits.md, \"Opcode work\"; raise it with \
                 {OPCODE_BUDGET_ENV}, or render with --opcodes ignore)",
                c.list
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_check() {
        assert_eq!(Limits::parse_pixels("300M").unwrap(), 300_000_000);
        assert_eq!(Limits::parse_pixels("1.5G").unwrap(), 1_500_000_000);
        assert_eq!(Limits::parse_pixels(" 1000 ").unwrap(), 1000);
        for bad in ["", "x", "0", "-5", "1e30", "NaN", "5G"] {
            assert!(Limits::parse_pixels(bad).is_err(), "{bad}");
        }
        let l = Limits::with_max_pixels(100).unwrap();
        assert!(l.check_pixels("raw image", 10, 10).is_ok());
        let e = l.check_pixels("raw image", 11, 10).unwrap_err().to_string();
        assert!(
            e.contains("11x10 = 110 pixels exceeds the limit of 100"),
            "{e}"
        );
        assert!(e.contains("--max-pixels"), "{e}");
        assert!(l.check_pixels("x", u64::MAX, u64::MAX).is_err());
        assert!(Limits::with_max_pixels(0).is_err());
        assert_eq!(l.opcode_budget, DEFAULT_OPCODE_BUDGET);
        assert_eq!(l.with_opcode_budget(7).unwrap().opcode_budget, 7);
        assert!(l.with_opcode_budget(0).is_err());
        assert_eq!(Limits::parse_opcode_budget(" 1000 ").unwrap(), 1000);
        for bad in ["", "0", "-1", "1.5", "lots"] {
            assert!(Limits::parse_opcode_budget(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn opcode_work_names_the_list_or_the_opcode() {
        let c = |list, what: &str, cost| OpcodeCost {
            list,
            what: what.into(),
            cost,
        };
        let costs = [
            c("OpcodeList2", "GainMap (opcode 1 of 1)", 40),
            c("OpcodeList3", "WarpRectilinear (opcode 1 of 2)", 50),
            c("OpcodeList3", "WarpRectilinear (opcode 2 of 2)", 50),
        ];
        assert!(check_opcode_work(&costs, 140).is_ok());
        let e = check_opcode_work(&costs, 100).unwrap_err().to_string();
        assert!(
            e.starts_with("limit exceeded: OpcodeList3: its 2 opcodes bring"),
            "{e}"
        );
        assert!(
            e.contains("140 pixel-passes") && e.contains(OPCODE_BUDGET_ENV),
            "{e}"
        );
        let e = check_opcode_work(&costs, 45).unwrap_err().to_string();
        assert!(
            e.contains("OpcodeList3: WarpRectilinear (opcode 1 of 2) alone costs 50"),
            "{e}"
        );
        assert!(check_opcode_work(&[], 1).is_ok());
    }

    #[test]
    fn refused_allocation_is_an_error_naming_the_size() {
        let e = try_filled(0u16, usize::MAX / 2, "the raw plane").unwrap_err();
        let s = e.to_string();
        assert!(matches!(e, Error::Limits(_)), "{s}");
        assert!(s.contains("the raw plane") && s.contains("TiB"), "{s}");
        let v = try_filled(7u8, 5, "x").unwrap();
        assert_eq!(v, vec![7; 5]);
        assert_eq!(bytes_human(512 << 20), "512.0 MiB");
    }
}
