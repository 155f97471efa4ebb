//! Mapping the raw image model back into tags: rationals, levels, the neutral (kept as the
//! source stored it while unchanged), the raw IFD, IFD0 and the EXIF IFD.

use super::*;

/// Best rational approximation of `x >= 0` with numerator and denominator <= `max`
/// (continued fractions; exact for values that were read from rationals).
pub(super) fn cf_rational(x: f64, max: u64) -> (u64, u64) {
    if !x.is_finite() || x <= 0.0 {
        return (0, 1);
    }
    if x >= max as f64 {
        return (max, 1);
    }
    let (mut h0, mut h1) = (0u64, 1u64);
    let (mut k0, mut k1) = (1u64, 0u64);
    let mut best = (0u64, 1u64);
    let mut r = x;
    for _ in 0..64 {
        let a = r.floor();
        if a > max as f64 {
            break;
        }
        let a = a as u64;
        let h = a.checked_mul(h1).and_then(|v| v.checked_add(h0));
        let k = a.checked_mul(k1).and_then(|v| v.checked_add(k0));
        let (h, k) = match (h, k) {
            (Some(h), Some(k)) if h <= max && k <= max => (h, k),
            _ => break,
        };
        best = (h, k);
        if h as f64 / k as f64 == x {
            break;
        }
        (h0, h1, k0, k1) = (h1, h, k1, k);
        let frac = r - a as f64;
        if frac <= 0.0 {
            break;
        }
        r = 1.0 / frac;
    }
    if best.1 == 0 {
        (0, 1)
    } else {
        best
    }
}

pub(super) fn urational(values: &[f64]) -> Value {
    Value::Rational(
        values
            .iter()
            .map(|&x| {
                let (n, d) = cf_rational(x, u32::MAX as u64);
                (n as u32, d as u32)
            })
            .collect(),
    )
}

pub(super) fn srational(values: &[f64]) -> Value {
    Value::SRational(
        values
            .iter()
            .map(|&x| {
                let (n, d) = cf_rational(x.abs(), i32::MAX as u64);
                let n = n as i32;
                (if x < 0.0 { -n } else { n }, d as i32)
            })
            .collect(),
    )
}

/// The source's stored entry of `tag` when it still decodes to `current` exactly (the value
/// was not changed): written back as the source stored it, type and value.
pub(super) fn kept(m: &RawMeta, tag: u16, current: &[f64]) -> Option<Value> {
    let v = m.stored_value(tag)?;
    (v.to_f64_vec()?.as_slice() == current).then(|| v.clone())
}

/// [`kept`] for AsShotNeutral, which the reader normalizes to green = 1.
pub(super) fn kept_neutral(m: &RawMeta, n: [f64; 3]) -> Option<Value> {
    let v = m.stored_value(t::AS_SHOT_NEUTRAL)?;
    match v.to_f64_vec()?.as_slice() {
        [r, g, b] if *g > 0.0 && [r / g, 1.0, b / g] == n => Some(v.clone()),
        _ => None,
    }
}

/// AsShotNeutral as RATIONALs that can never round to 0: green = 1 when every component is
/// representable within 1e-9 (the usual case), else the neutral rescaled by the geometric
/// mean of its extremes (AsShotNeutral is defined up to scale; readers divide by green),
/// which keeps ratios up to ~1.8e19 non-zero and finite.
pub fn neutral_value(n: [f64; 3]) -> Value {
    let close = |v: &Value, want: &[f64]| {
        v.to_f64_vec().is_some_and(|got| {
            got.iter()
                .zip(want)
                .all(|(g, w)| *g > 0.0 && ((g - w) / w).abs() <= 1e-9)
        })
    };
    let plain = urational(&n);
    if close(&plain, &n) || n.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return plain;
    }
    let (lo, hi) = n.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    });
    let s = (lo.sqrt()) * (hi.sqrt());
    let scaled = n.map(|x| x / s);
    let v = urational(&scaled);
    match &v {
        Value::Rational(r) if r.iter().all(|&(num, den)| num > 0 && den > 0) => v,
        // Beyond what RATIONAL holds: the smallest positive value instead of 0.
        Value::Rational(r) => Value::Rational(
            r.iter()
                .map(|&(num, den)| {
                    if num == 0 || den == 0 {
                        (1, u32::MAX)
                    } else {
                        (num, den)
                    }
                })
                .collect(),
        ),
        _ => v,
    }
}

/// Integers as SHORT/LONG when exact, otherwise RATIONAL.
pub(super) fn levels_value(values: &[f64]) -> Value {
    let ints = values
        .iter()
        .all(|&v| v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64);
    if ints && values.iter().all(|&v| v <= u16::MAX as f64) {
        Value::Short(values.iter().map(|&v| v as u16).collect())
    } else if ints {
        Value::Long(values.iter().map(|&v| v as u32).collect())
    } else {
        urational(values)
    }
}

pub(super) fn ascii_or_default(s: &Option<String>, default: &str) -> Value {
    match s.as_deref().map(str::trim) {
        Some(s) if !s.is_empty() => Value::ascii(s),
        _ => Value::ascii(default),
    }
}

/// Tags that describe the raw image (raw IFD).
pub(super) fn set_raw_tags(ifd: &mut Ifd, m: &RawMeta) {
    let c = &m.cfa;
    ifd.set(
        t::CFA_REPEAT_PATTERN_DIM,
        Value::Short(vec![c.rows as u16, c.cols as u16]),
    );
    ifd.set(t::CFA_PATTERN, Value::Byte(c.pattern.clone()));
    let planes = if c.plane_color.is_empty() {
        vec![0, 1, 2]
    } else {
        c.plane_color.clone()
    };
    ifd.set(t::CFA_PLANE_COLOR, Value::Byte(planes));
    ifd.set(t::CFA_LAYOUT, Value::Short(vec![c.layout.max(1)]));
    if let Some(lt) = &m.linearization_table {
        ifd.set(t::LINEARIZATION_TABLE, Value::Short(lt.clone()));
    }
    let l = &m.levels;
    if l.black_repeat != (1, 1) {
        ifd.set(
            t::BLACK_LEVEL_REPEAT_DIM,
            Value::Short(vec![l.black_repeat.0 as u16, l.black_repeat.1 as u16]),
        );
    }
    ifd.set(t::BLACK_LEVEL, levels_value(&l.black));
    if !l.black_delta_h.is_empty() {
        ifd.set(t::BLACK_LEVEL_DELTA_H, srational(&l.black_delta_h));
    }
    if !l.black_delta_v.is_empty() {
        ifd.set(t::BLACK_LEVEL_DELTA_V, srational(&l.black_delta_v));
    }
    let white = if l.white.fract() == 0.0 && l.white >= 0.0 && l.white <= u32::MAX as f64 {
        Value::Long(vec![l.white as u32])
    } else {
        urational(&[l.white])
    };
    ifd.set(t::WHITE_LEVEL, white);
    if let Some(a) = m.active_area {
        ifd.set(
            t::ACTIVE_AREA,
            Value::Long(vec![a.top, a.left, a.bottom, a.right]),
        );
    }
    if let Some(o) = m.default_crop_origin {
        ifd.set(t::DEFAULT_CROP_ORIGIN, levels_value(&o));
    }
    if let Some(s) = m.default_crop_size {
        ifd.set(t::DEFAULT_CROP_SIZE, levels_value(&s));
    }
    for (i, tag) in [t::OPCODE_LIST1, t::OPCODE_LIST2, t::OPCODE_LIST3]
        .into_iter()
        .enumerate()
    {
        if let Some(Some(bytes)) = m.opcode_lists.get(i) {
            ifd.set(tag, Value::Undefined(bytes.clone()));
        }
    }
    if let Some(np) = &m.noise_profile {
        ifd.set(
            t::NOISE_PROFILE,
            Value::Double(np.iter().flat_map(|&(s, o)| [s, o]).collect()),
        );
    }
}

/// Tags of IFD0 (camera, colour, version, provenance).
pub(super) fn set_ifd0_tags(ifd: &mut Ifd, m: &RawMeta, unique_id: Vec<u8>, raw_in_sub: bool) {
    let has_opcodes = m.opcode_lists.iter().any(|o| o.is_some());
    ifd.set(t::DNG_VERSION, Value::Byte(vec![1, 4, 0, 0]));
    ifd.set(
        t::DNG_BACKWARD_VERSION,
        Value::Byte(if has_opcodes {
            vec![1, 3, 0, 0]
        } else {
            vec![1, 1, 0, 0]
        }),
    );
    let ucm = m
        .unique_camera_model
        .clone()
        .filter(|s| !s.trim().is_empty())
        .or_else(|| match (&m.make, &m.model) {
            (Some(a), Some(b)) => Some(format!("{a} {b}")),
            (None, Some(b)) => Some(b.clone()),
            _ => None,
        });
    ifd.set(t::UNIQUE_CAMERA_MODEL, ascii_or_default(&ucm, "Unknown"));
    ifd.set(t::MAKE, ascii_or_default(&m.make, "Unknown"));
    ifd.set(t::MODEL, ascii_or_default(&m.model, "Unknown"));
    ifd.set(
        t::ORIENTATION,
        Value::Short(vec![m.orientation.clamp(1, 8)]),
    );
    ifd.set(t::SOFTWARE, Value::ascii(&crate::software_name()));
    let c = &m.color;
    // ColorMatrix1 is required: an identity-like default only when the source had none.
    let cm1 = c
        .color_matrix1
        .clone()
        .unwrap_or_else(|| vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    ifd.set(
        t::COLOR_MATRIX1,
        kept(m, t::COLOR_MATRIX1, &cm1).unwrap_or_else(|| srational(&cm1)),
    );
    let mats = [
        (t::COLOR_MATRIX2, &c.color_matrix2),
        (t::CAMERA_CALIBRATION1, &c.camera_calibration1),
        (t::CAMERA_CALIBRATION2, &c.camera_calibration2),
        (t::FORWARD_MATRIX1, &c.forward_matrix1),
        (t::FORWARD_MATRIX2, &c.forward_matrix2),
    ];
    for (tag, v) in mats {
        if let Some(v) = v {
            ifd.set(tag, kept(m, tag, v).unwrap_or_else(|| srational(v)));
        }
    }
    if let Some(i) = c.calibration_illuminant1 {
        ifd.set(t::CALIBRATION_ILLUMINANT1, Value::Short(vec![i]));
    }
    if let Some(i) = c.calibration_illuminant2 {
        ifd.set(t::CALIBRATION_ILLUMINANT2, Value::Short(vec![i]));
    }
    if let Some(ab) = &c.analog_balance {
        ifd.set(
            t::ANALOG_BALANCE,
            kept(m, t::ANALOG_BALANCE, ab).unwrap_or_else(|| urational(ab)),
        );
    }
    if let Some(be) = c.baseline_exposure {
        ifd.set(
            t::BASELINE_EXPOSURE,
            kept(m, t::BASELINE_EXPOSURE, &[be]).unwrap_or_else(|| srational(&[be])),
        );
    }
    if let Some(n) = m.as_shot_neutral {
        ifd.set(
            t::AS_SHOT_NEUTRAL,
            kept_neutral(m, n).unwrap_or_else(|| neutral_value(n)),
        );
    } else if let Some(xy) = m.as_shot_white_xy {
        ifd.set(
            t::AS_SHOT_WHITE_XY,
            kept(m, t::AS_SHOT_WHITE_XY, &xy).unwrap_or_else(|| urational(&xy)),
        );
    }
    ifd.set(t::RAW_DATA_UNIQUE_ID, Value::Byte(unique_id));
    for e in &m.ifd0_extra {
        let belongs_to_raw = raw_in_sub && RAW_IFD_TAGS.contains(&e.tag);
        if !is_dropped(e.tag) && !belongs_to_raw {
            ifd.set_if_absent(e.tag, e.value.clone());
        }
    }
    ifd.set_if_absent(t::X_RESOLUTION, Value::Rational(vec![(72, 1)]));
    ifd.set_if_absent(t::Y_RESOLUTION, Value::Rational(vec![(72, 1)]));
    ifd.set_if_absent(t::RESOLUTION_UNIT, Value::Short(vec![2]));
}

pub(super) fn exif_ifd(m: &RawMeta) -> Ifd {
    let mut ifd = Ifd::new();
    ifd.set(t::EXIF_VERSION, Value::Undefined(b"0230".to_vec()));
    let e = &m.exif;
    if let Some(iso) = e.iso.filter(|&i| i > 0) {
        ifd.set(
            t::ISO_SPEED_RATINGS,
            Value::Short(vec![iso.min(65535) as u16]),
        );
        ifd.set(t::SENSITIVITY_TYPE, Value::Short(vec![3]));
        ifd.set(t::ISO_SPEED, Value::Long(vec![iso]));
    }
    if let Some(et) = e.exposure_time.filter(|&x| x > 0.0 && x.is_finite()) {
        ifd.set(t::EXPOSURE_TIME, urational(&[et]));
    }
    if let Some(f) = e.f_number.filter(|&x| x > 0.0 && x.is_finite()) {
        ifd.set(t::F_NUMBER, urational(&[f]));
    }
    if let Some(d) = &e.date_time_original {
        ifd.set(t::DATE_TIME_ORIGINAL, Value::ascii(d));
    }
    for en in &m.exif_extra {
        if !is_dropped(en.tag) {
            ifd.set_if_absent(en.tag, en.value.clone());
        }
    }
    ifd
}
