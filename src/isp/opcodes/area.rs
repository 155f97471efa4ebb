//! The per-sample "area" opcodes (DNG 1.6 ch. 6: MapTable 7, MapPolynomial 8, DeltaPerRow 10,
//! DeltaPerColumn 11, ScalePerRow 12, ScalePerColumn 13) and the area walk they share with
//! GainMap: rows `top + k * row_pitch < bottom`, columns `left + k * col_pitch < right`,
//! planes `plane..plane + planes` (those the image has); an empty area means the whole image
//! (as in the SDK's `dng_area_spec::Overlap`).
//!
//! Units follow the Adobe DNG SDK: samples lie in `[0, range]` (stage 1: stored units,
//! range 65535; stages 2 and 3: [0, 1]) and every result is pinned into it.
//! * MapTable indexes the table with the 16-bit value (`round(x * 65535 / range)`); values
//!   past the table's end take its last entry.
//! * MapPolynomial evaluates `sum c_k x^k` on the stage's own values (stage 1: stored units,
//!   as the SDK's coefficient rescaling amounts to; stages 2-3: [0, 1]).
//! * Delta per row/column adds `delta * range / 65535`: the SDK scales deltas by 1/65535 on
//!   its 16-bit stage images, so deltas are in 16-bit units at every stage.
//! * Scale per row/column multiplies.

use super::pin;
use crate::dng::opcodes::{AreaSpec, OpcodeKind};

/// True when the area is empty (= the whole image).
fn is_empty(a: &AreaSpec) -> bool {
    a.top >= a.bottom || a.left >= a.right
}

/// The step index of stage row `r` in the area (`(r - top) / row_pitch`), or None when the
/// row is not touched.
pub fn row_step(a: &AreaSpec, r: usize) -> Option<usize> {
    if is_empty(a) {
        return Some(r);
    }
    let (t, b, p) = (
        a.top as usize,
        a.bottom as usize,
        a.row_pitch.max(1) as usize,
    );
    (r >= t && r < b && (r - t).is_multiple_of(p)).then(|| (r - t) / p)
}

/// The touched columns of a row segment `[left, left + width)`: (first column, end, pitch)
/// in stage coordinates, and the step index of the first.
pub fn col_span(a: &AreaSpec, left: usize, width: usize) -> Option<(usize, usize, usize, usize)> {
    let end_seg = left + width;
    if is_empty(a) {
        return (width > 0).then_some((left, end_seg, 1, left));
    }
    let (l, r, p) = (
        a.left as usize,
        a.right as usize,
        a.col_pitch.max(1) as usize,
    );
    let lo = left.max(l);
    let first = l + (lo - l).div_ceil(p) * p;
    let end = end_seg.min(r);
    (first < end).then(|| (first, end, p, (first - l) / p))
}

/// The planes of the area that an image with `planes` planes has.
pub fn plane_range(a: &AreaSpec, planes: usize) -> std::ops::Range<usize> {
    let p0 = (a.plane as usize).min(planes);
    let p1 = (a.plane as usize)
        .saturating_add(a.planes as usize)
        .min(planes);
    p0..p1
}

/// Call `f(sample, step_col)` for every touched sample of the row `row` (stage row `r`,
/// first pixel at stage column `left`, `planes` interleaved), `step_col` being the column's
/// step index in the area. Returns the row's step index (None: row untouched).
#[inline]
pub fn for_each_in_row(
    a: &AreaSpec,
    r: usize,
    left: usize,
    planes: usize,
    row: &mut [f32],
    mut f: impl FnMut(&mut f32, usize),
) -> Option<usize> {
    let rs = row_step(a, r)?;
    let width = row.len() / planes.max(1);
    let (first, end, pitch, k0) = col_span(a, left, width)?;
    let pr = plane_range(a, planes);
    for (k, c) in (first..end).step_by(pitch).enumerate() {
        let base = (c - left) * planes;
        for p in pr.clone() {
            f(&mut row[base + p], k0 + k);
        }
    }
    Some(rs)
}

/// One of the per-sample area opcodes, ready to run on rows.
#[derive(Debug, Clone)]
pub enum AreaOp {
    /// MapTable with the 16-bit index scale and the output scale.
    Table {
        /// Area.
        area: AreaSpec,
        /// Entries.
        table: Vec<u16>,
        /// `65535 / range`.
        to16: f32,
        /// `range / 65535`.
        from16: f32,
        /// Range.
        range: f32,
    },
    /// MapPolynomial.
    Poly {
        /// Area.
        area: AreaSpec,
        /// c0..cN.
        c: Vec<f64>,
        /// Range.
        range: f32,
    },
    /// Delta or scale per row (`per_row`) or per column; `add` for deltas.
    Table1d {
        /// Area.
        area: AreaSpec,
        /// Per step values (deltas already in the stage's units).
        values: Vec<f32>,
        /// Per row (else per column).
        per_row: bool,
        /// Add (delta) or multiply (scale).
        add: bool,
        /// Range.
        range: f32,
    },
}

impl AreaOp {
    /// The area opcode of `kind` for samples in `[0, range]`; None for other kinds.
    pub fn new(kind: &OpcodeKind, range: f32) -> Option<AreaOp> {
        let unit = range / 65535.0;
        Some(match kind {
            OpcodeKind::MapTable { area, table } if !table.is_empty() => AreaOp::Table {
                area: *area,
                table: table.clone(),
                to16: 65535.0 / range,
                from16: unit,
                range,
            },
            OpcodeKind::MapPolynomial { area, coefficients } => AreaOp::Poly {
                area: *area,
                c: coefficients.clone(),
                range,
            },
            OpcodeKind::DeltaPerRow { area, deltas }
            | OpcodeKind::DeltaPerColumn { area, deltas } => AreaOp::Table1d {
                area: *area,
                values: deltas.iter().map(|d| d * unit).collect(),
                per_row: matches!(kind, OpcodeKind::DeltaPerRow { .. }),
                add: true,
                range,
            },
            OpcodeKind::ScalePerRow { area, scales }
            | OpcodeKind::ScalePerColumn { area, scales } => AreaOp::Table1d {
                area: *area,
                values: scales.clone(),
                per_row: matches!(kind, OpcodeKind::ScalePerRow { .. }),
                add: false,
                range,
            },
            _ => return None,
        })
    }

    /// Apply to one row (stage row `r`, first pixel at stage column `left`).
    pub fn row(&self, r: usize, left: usize, planes: usize, row: &mut [f32]) {
        match self {
            AreaOp::Table {
                area,
                table,
                to16,
                from16,
                range,
            } => {
                let last = table.len() - 1;
                for_each_in_row(area, r, left, planes, row, |v, _| {
                    let i = (pin(*v, *range) * to16).round() as usize;
                    *v = table[i.min(last)] as f32 * from16;
                });
            }
            AreaOp::Poly { area, c, range } => {
                for_each_in_row(area, r, left, planes, row, |v, _| {
                    let x = *v as f64;
                    let y = c.iter().rev().fold(0.0f64, |acc, &k| acc * x + k);
                    *v = pin(y as f32, *range);
                });
            }
            AreaOp::Table1d {
                area,
                values,
                per_row,
                add,
                range,
            } => {
                let Some(rs) = row_step(area, r) else { return };
                let row_value = if *per_row {
                    match values.get(rs) {
                        Some(&v) => Some(v),
                        None => return,
                    }
                } else {
                    None
                };
                for_each_in_row(area, r, left, planes, row, |v, k| {
                    let Some(t) = row_value.or_else(|| values.get(k).copied()) else {
                        return;
                    };
                    *v = pin(if *add { *v + t } else { *v * t }, *range);
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(top: u32, left: u32, bottom: u32, right: u32, rp: u32, cp: u32) -> AreaSpec {
        AreaSpec {
            top,
            left,
            bottom,
            right,
            plane: 0,
            planes: 1,
            row_pitch: rp,
            col_pitch: cp,
        }
    }

    /// Apply `op` to a `w x h` single-plane image starting at stage (top, left).
    fn run(op: &AreaOp, img: &mut [f32], w: usize, top: usize, left: usize) {
        for (i, row) in img.chunks_mut(w).enumerate() {
            op.row(top + i, left, 1, row);
        }
    }

    #[test]
    fn pitch_and_area_walk_like_the_sdk() {
        // 6x5 image, area rows 1..5 step 2, cols 1..6 step 2: (1,1) (1,3) (1,5) (3,1) ...
        let a = area(1, 1, 5, 6, 2, 2);
        let op = AreaOp::new(
            &OpcodeKind::ScalePerRow {
                area: a,
                scales: vec![2.0, 3.0],
            },
            1.0,
        )
        .unwrap();
        let mut img = vec![0.25f32; 30];
        run(&op, &mut img, 6, 0, 0);
        for r in 0..5 {
            for c in 0..6 {
                let want = match (r, c % 2) {
                    (1, 1) => 0.5,
                    (3, 1) => 0.75,
                    _ => 0.25,
                };
                assert_eq!(img[r * 6 + c], want, "({r},{c})");
            }
        }
        // the same image processed as two segments (a crop) gives the same samples
        let mut a2 = vec![0.25f32; 30];
        for r in 0..5 {
            let (x, y) = a2[r * 6..r * 6 + 6].split_at_mut(3);
            op.row(r, 0, 1, x);
            op.row(r, 3, 1, y);
        }
        assert_eq!(a2, img);
    }

    #[test]
    fn delta_per_column_in_16_bit_units_and_pinned() {
        let a = area(0, 0, 2, 3, 1, 1);
        let k = OpcodeKind::DeltaPerColumn {
            area: a,
            deltas: vec![655.35, -65535.0, 65535.0],
        };
        let mut img = vec![0.5f32; 6];
        run(&AreaOp::new(&k, 1.0).unwrap(), &mut img, 3, 0, 0);
        assert!((img[0] - 0.51).abs() < 1e-6 && img[1] == 0.0 && img[2] == 1.0);
        // stage 1: stored units
        let mut img = vec![1000.0f32; 6];
        run(&AreaOp::new(&k, 65535.0).unwrap(), &mut img, 3, 0, 0);
        assert!((img[3] - 1655.35).abs() < 1e-2 && img[4] == 0.0 && img[5] == 65535.0);
    }

    #[test]
    fn delta_per_row_and_scale_per_column() {
        let a = area(0, 0, 3, 2, 1, 1);
        let mut img = vec![0.5f32; 6];
        let d = OpcodeKind::DeltaPerRow {
            area: a,
            deltas: vec![0.0, 6553.5, 65535.0],
        };
        run(&AreaOp::new(&d, 1.0).unwrap(), &mut img, 2, 0, 0);
        assert_eq!(img[0], 0.5);
        assert!((img[2] - 0.6).abs() < 1e-6);
        assert_eq!(img[4], 1.0);
        let s = OpcodeKind::ScalePerColumn {
            area: a,
            scales: vec![0.5, f32::NAN],
        };
        run(&AreaOp::new(&s, 1.0).unwrap(), &mut img, 2, 0, 0);
        assert_eq!(img[0], 0.25);
        assert_eq!(img[1], 0.0, "NaN scale gives 0, not NaN");
    }

    #[test]
    fn map_table_indexes_16_bit_values_and_repeats_the_last_entry() {
        let a = area(0, 0, 1, 3, 1, 1);
        let k = OpcodeKind::MapTable {
            area: a,
            table: vec![10, 20, 30],
        };
        let mut img = vec![0.0, 1.0, 65535.0];
        run(&AreaOp::new(&k, 65535.0).unwrap(), &mut img, 3, 0, 0);
        assert_eq!(img, vec![10.0, 20.0, 30.0]);
        let mut img = vec![1.0 / 65535.0, 0.0, 0.5];
        run(&AreaOp::new(&k, 1.0).unwrap(), &mut img, 3, 0, 0);
        assert!((img[0] - 20.0 / 65535.0).abs() < 1e-9);
        assert!((img[2] - 30.0 / 65535.0).abs() < 1e-9);
    }

    #[test]
    fn map_polynomial_on_stage_values() {
        let a = area(0, 0, 1, 2, 1, 1);
        let k = OpcodeKind::MapPolynomial {
            area: a,
            coefficients: vec![0.1, 0.5, 0.25],
        };
        let mut img = vec![0.0, 0.8];
        run(&AreaOp::new(&k, 1.0).unwrap(), &mut img, 2, 0, 0);
        assert!((img[0] - 0.1).abs() < 1e-7);
        assert!((img[1] - (0.1 + 0.4 + 0.16)).abs() < 1e-6);
        let k = OpcodeKind::MapPolynomial {
            area: a,
            coefficients: vec![-5.0, 2.0],
        };
        let mut img = vec![1.0, 40000.0];
        run(&AreaOp::new(&k, 65535.0).unwrap(), &mut img, 2, 0, 0);
        assert_eq!(img, vec![0.0, 65535.0]);
    }

    #[test]
    fn planes_and_empty_area() {
        let mut a = area(0, 0, 0, 0, 1, 1);
        a.plane = 1;
        a.planes = 5;
        let k = OpcodeKind::ScalePerColumn {
            area: a,
            scales: vec![0.5; 4],
        };
        // empty area = whole image; planes 1.. of a 3-plane image
        let mut row = vec![1.0f32; 6];
        AreaOp::new(&k, 1.0).unwrap().row(7, 0, 3, &mut row);
        assert_eq!(row, vec![1.0, 0.5, 0.5, 1.0, 0.5, 0.5]);
    }
}
