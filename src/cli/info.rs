//! `day2night info FILE... [--json]`: describe DNG files, including ones synthesis cannot use.
use super::CmdResult;
use day2night::dng::read::{inspect, DngInfo};
use day2night::raw::camera::CameraId;
use day2night::synth::{Covariance, IlluminantChoice, IlluminantProvenance};
use day2night::RawImage;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `day2night info`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Example:\n  day2night info photo.dng\n  day2night info a.dng b.dng --json > info.json"
)]
pub struct InfoArgs {
    /// DNG files to describe.
    #[arg(required = true, value_name = "FILE.dng")]
    pub files: Vec<PathBuf>,
    /// Print a JSON array (one object per readable file) instead of text.
    #[arg(long)]
    pub json: bool,
}

/// What synthesis would make of the file's opcode lists (the ISP decides which opcodes it
/// can apply; the DNG layer's `inspect` cannot ask it): an optional opcode the renders skip,
/// an opcode that makes its samples constant and a TrimBounds that changes the target's
/// size are warnings, a mandatory one they cannot apply makes the file unusable, so
/// "ready" is said only when `synth` would run without a word.
fn opcode_verdict(info: &mut DngInfo, file: &Decoded) {
    let has_lists = info
        .raw
        .as_ref()
        .is_some_and(|r| !r.meta.opcode_lists().is_empty());
    if !info.synth_ready || !has_lists {
        return;
    }
    let verdict = file.get().and_then(|img| {
        use day2night::isp::opcodes::{check::check_render, OpcodeMode};
        check_render(img, OpcodeMode::Apply, true, true).map_err(|e| e.root().to_string())
    });
    match verdict {
        Ok(c) => info.warnings.extend(c.warnings),
        Err(e) => {
            info.synth_ready = false;
            info.reason = Some(e);
        }
    }
}

/// The file decoded once, on first need, for the verdicts that look past the tags.
struct Decoded<'a> {
    path: &'a std::path::Path,
    img: std::cell::OnceCell<Result<RawImage, String>>,
}

impl<'a> Decoded<'a> {
    fn new(path: &'a std::path::Path) -> Self {
        Decoded {
            path,
            img: std::cell::OnceCell::new(),
        }
    }

    fn get(&self) -> Result<&RawImage, String> {
        self.img
            .get_or_init(|| day2night::dng::read_dng(self.path).map_err(|e| e.root().to_string()))
            .as_ref()
            .map_err(Clone::clone)
    }
}

/// `synth`'s own checks with default options ([`day2night::synth::readiness`]): every item
/// that keeps the file from synthesis, listed at once, each with the flag that fixes it.
fn readiness_verdict(info: &mut DngInfo, file: &Decoded) {
    use day2night::synth::{readiness, Calibration, SynthOptions};
    if !info.synth_ready {
        return;
    }
    let opts = SynthOptions::default();
    let verdict = file.get().and_then(|img| {
        let cal = Calibration::embedded(&opts).map_err(|e| e.root().to_string())?;
        readiness::check(&img.meta, &opts, &cal, true).map_err(|e| e.root().to_string())
    });
    if let Err(why) = verdict {
        info.synth_ready = false;
        info.reason = Some(why);
    }
}

/// The night illuminant dictionary a default `synth` run samples for this file (its
/// provenance), or why it cannot (docs/synthesis.md, "Night lamps in CIE xy"; the
/// readiness verdict then says the file is not ready).
fn illuminant_verdict(info: &DngInfo) -> Option<Result<IlluminantProvenance, String>> {
    let raw = info.raw.as_ref()?;
    let camera = CameraId::new(
        info.make.clone(),
        info.model.clone(),
        info.unique_camera_model.clone(),
    );
    let r = IlluminantChoice::Auto.resolve(&camera, &raw.meta.meta.color, Covariance::Unbiased);
    Some(r.map(|r| r.provenance).map_err(|e| e.root().to_string()))
}

/// Where `synth` (no `--noise-model`, default options) would take this file's noise model
/// from, and which camera's it is (issue 24): the noise chain of
/// `day2night::synth::noise_source`, its warnings joining the file's. The pixels are read
/// only when the chain gets to the estimate from the image.
fn noise_verdict(info: &mut DngInfo, file: &Decoded) -> Option<day2night::noise::NoiseProvenance> {
    use day2night::synth::{noise_source::choose_noise_model, Calibration, SynthOptions};
    if !info.synth_ready {
        return None;
    }
    let img = file.get().ok()?;
    let bayer = img.bayer().ok()?;
    let opts = SynthOptions::default();
    let cal = Calibration::embedded(&opts).ok()?;
    let est = || day2night::noise::estimate(img, &Default::default());
    match choose_noise_model(img, &cal, &opts, bayer, &est) {
        Ok(c) => {
            info.warnings.extend(c.warnings);
            Some(c.provenance)
        }
        Err(e) => {
            info.warnings.warn(
                day2night::Code::NoiseUnavailable,
                format!("noise: {}", e.root()),
            );
            None
        }
    }
}

/// Run `day2night info`.
pub fn run(args: InfoArgs) -> CmdResult {
    let mut failed = 0usize;
    let mut objects = Vec::new();
    let mut text = String::new();
    for f in &args.files {
        match inspect(f) {
            Ok(mut info) => {
                let file = Decoded::new(f);
                opcode_verdict(&mut info, &file);
                readiness_verdict(&mut info, &file);
                let ill = illuminant_verdict(&info);
                let noise = noise_verdict(&mut info, &file);
                // Every warning of `info` is about this file.
                info.warnings.about(&f.display().to_string());
                super::warn_all(f, &info.warnings);
                if let Some(e) = &info.error {
                    eprintln!("day2night: {}: {e}", f.display());
                    failed += 1;
                }
                if args.json {
                    let mut v = serde_json::to_value(&info)?;
                    if let Some(o) = v.as_object_mut() {
                        o.insert("file".into(), f.display().to_string().into());
                        if let Some(ill) = &ill {
                            let j = match ill {
                                Ok(p) => serde_json::to_value(p)?,
                                Err(e) => serde_json::json!({ "error": e }),
                            };
                            o.insert("night_illuminants".into(), j);
                        }
                        if let Some(n) = &noise {
                            o.insert("noise_model".into(), serde_json::to_value(n)?);
                        }
                    }
                    objects.push(v);
                } else {
                    describe(&mut text, f, &info, &ill, noise.as_ref());
                }
            }
            Err(e) => {
                match sniff(f) {
                    Some(kind) => eprintln!(
                        "day2night: {}: not a DNG: this is {kind} (info describes DNG files)",
                        f.display()
                    ),
                    // `inspect` already names the file.
                    None => eprintln!("day2night: {e}"),
                }
                failed += 1;
            }
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&objects)?);
    } else {
        print!("{text}");
    }
    if failed > 0 && args.files.len() == 1 {
        // The file's own line said why.
        return Err(super::reported(1));
    }
    if failed > 0 {
        return Err(super::Failure {
            code: 1,
            error: anyhow::anyhow!("{failed} of {} files could not be read", args.files.len()),
        });
    }
    Ok(())
}

/// The kind of a file that is not TIFF-based, from its first bytes (None for TIFF, which
/// `inspect`'s own error then describes, and for unknown contents).
fn sniff(path: &std::path::Path) -> Option<&'static str> {
    use std::io::Read;
    let mut head = [0u8; 12];
    let mut f = std::fs::File::open(path).ok()?;
    let n = f.read(&mut head).ok()?;
    let h = &head[..n];
    let kinds: [(&[u8], usize, &str); 9] = [
        (b"\x76\x2f\x31\x01", 0, "an OpenEXR image"),
        (b"\x89PNG\r\n\x1a\n", 0, "a PNG image"),
        (b"\xff\xd8\xff", 0, "a JPEG image"),
        (b"II\x2b\x00", 0, "a BigTIFF file"),
        (b"MM\x00\x2b", 0, "a BigTIFF file"),
        (b"ftyp", 4, "an ISO media file (HEIF, AVIF, CR3 or MP4)"),
        (b"RIFF", 0, "a RIFF file (e.g. WebP)"),
        (b"GIF8", 0, "a GIF image"),
        (b"%PDF", 0, "a PDF document"),
    ];
    kinds
        .iter()
        .find(|(magic, at, _)| h.get(*at..at + magic.len()) == Some(*magic))
        .map(|k| k.2)
}

/// A number in its shortest form at 6 significant digits: `3.2e-4` rather than
/// `3.1999999999999997e-4` (the binary value of a NoiseProfile double).
fn short_sci(x: f64) -> String {
    let s = format!("{x:.5e}");
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => s,
    }
}

fn opt<T: std::fmt::Display>(v: &Option<T>) -> String {
    v.as_ref().map_or("-".to_string(), |x| x.to_string())
}

fn nums(v: &[f64]) -> String {
    v.iter()
        .map(|x| {
            format!("{x:.6}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// One line per opcode list and per opcode, below the "opcode lists" line.
fn describe_opcodes(out: &mut String, lists: &[day2night::dng::opcodes::describe::OpcodeListInfo]) {
    for l in lists {
        match &l.error {
            Some(e) => {
                let _ = writeln!(out, "    {} ({} bytes): {e}", l.list, l.bytes);
            }
            None => {
                let _ = writeln!(
                    out,
                    "    {} ({} bytes, {} opcodes):",
                    l.list,
                    l.bytes,
                    l.opcodes.len()
                );
                for (i, op) in l.opcodes.iter().enumerate() {
                    let _ = writeln!(out, "      {}. {}", i + 1, op.text());
                }
            }
        }
    }
}

/// The raw image's lines of [`describe`].
fn describe_raw(out: &mut String, r: &day2night::dng::read::RawSummary) {
    let summary = &r.meta;
    let m = &summary.meta;
    let _ = writeln!(
        out,
        "  raw size:      {}x{}, {}-bit",
        r.width, r.height, m.bits_per_sample
    );
    if let Some(a) = m.active_area {
        let _ = writeln!(
            out,
            "  active area:   {},{},{},{} ({}x{})",
            a.top,
            a.left,
            a.bottom,
            a.right,
            a.width(),
            a.height()
        );
    }
    if let (Some(o), Some(s)) = (m.default_crop_origin, m.default_crop_size) {
        let _ = writeln!(
            out,
            "  default crop:  origin {} size {}",
            nums(&o),
            nums(&s)
        );
    }
    let _ = writeln!(out, "  CFA:           {}", r.cfa);
    if let Some(st) = &m.storage {
        let layout = match st.layout {
            day2night::raw::meta::Layout::Strips { rows_per_strip } => {
                format!("strips of {rows_per_strip} rows")
            }
            day2night::raw::meta::Layout::Tiles { width, height } => {
                format!("tiles {width}x{height}")
            }
        };
        let _ = writeln!(
            out,
            "  storage:       {layout}, compression {} ({})",
            st.compression,
            day2night::dng::read::compression_name(st.compression)
        );
    }
    describe_levels(out, summary);
    let e = &m.exif;
    let _ = writeln!(
        out,
        "  exposure:      ISO {}, {} s, f/{}, {}",
        opt(&e.iso),
        opt(&e.exposure_time),
        opt(&e.f_number),
        opt(&e.date_time_original)
    );
    let _ = writeln!(
        out,
        "  noise profile: {}",
        m.noise_profile.as_ref().map_or("-".into(), |p| p
            .iter()
            .map(|(s, o)| format!("S={} O={}", short_sci(*s), short_sci(*o)))
            .collect::<Vec<_>>()
            .join("; "))
    );
    let _ = writeln!(out, "  orientation:   {}", m.orientation);
    if summary.gps_entries() > 0 {
        let _ = writeln!(
            out,
            "  GPS:           {} entries (carried)",
            summary.gps_entries()
        );
    }
    let _ = writeln!(
        out,
        "  opcode lists:  {}",
        if summary.opcode_lists().is_empty() {
            "none".to_string()
        } else {
            summary
                .opcode_lists()
                .iter()
                .map(|i| format!("OpcodeList{i}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    describe_opcodes(out, &summary.opcodes);
}

/// Levels, neutral and colour tags of [`describe_raw`].
fn describe_levels(out: &mut String, summary: &day2night::dng::read::MetaSummary) {
    let m = &summary.meta;
    let l = &m.levels;
    let _ = writeln!(
        out,
        "  black level:   {} (repeat {}x{}){}{}",
        nums(&l.black),
        l.black_repeat.0,
        l.black_repeat.1,
        if l.black_delta_h.is_empty() {
            ""
        } else {
            ", DeltaH"
        },
        if l.black_delta_v.is_empty() {
            ""
        } else {
            ", DeltaV"
        }
    );
    let _ = writeln!(out, "  white level:   {}", nums(&[l.white]));
    if let Some(lr) = &m.linear_raw {
        let _ = writeln!(
            out,
            "  per sample:    black {}, white {} (LinearRaw, {} samples)",
            nums(&lr.black),
            nums(&lr.white),
            lr.samples_per_pixel
        );
    }
    if let Some(n) = summary.linearization_table_len() {
        let _ = writeln!(out, "  linearization: table of {n} entries");
    }
    let _ = writeln!(
        out,
        "  as-shot neutral: {}",
        m.as_shot_neutral.map_or("-".into(), |n| nums(&n))
    );
    if let Some(xy) = m.as_shot_white_xy {
        let _ = writeln!(out, "  as-shot white xy: {}", nums(&xy));
    }
    let c = &m.color;
    for (name, mat, ill) in [
        ("ColorMatrix1", &c.color_matrix1, c.calibration_illuminant1),
        ("ColorMatrix2", &c.color_matrix2, c.calibration_illuminant2),
    ] {
        if let Some(mx) = mat {
            let _ = writeln!(out, "  {name}:  {} (illuminant {})", nums(mx), opt(&ill));
        }
    }
    for (name, mat) in [
        ("ForwardMatrix1", &c.forward_matrix1),
        ("ForwardMatrix2", &c.forward_matrix2),
        ("CameraCalibration1", &c.camera_calibration1),
        ("CameraCalibration2", &c.camera_calibration2),
        ("AnalogBalance", &c.analog_balance),
    ] {
        if let Some(mx) = mat {
            let _ = writeln!(out, "  {name}: {}", nums(mx));
        }
    }
    if let Some(b) = c.baseline_exposure {
        let _ = writeln!(out, "  baseline exposure: {} EV", nums(&[b]));
    }
}

fn describe(
    out: &mut String,
    file: &std::path::Path,
    i: &DngInfo,
    ill: &Option<Result<IlluminantProvenance, String>>,
    noise: Option<&day2night::noise::NoiseProvenance>,
) {
    let _ = writeln!(out, "{}", file.display());
    let _ = writeln!(
        out,
        "  camera:        {} {} ({})",
        opt(&i.make),
        opt(&i.model),
        opt(&i.unique_camera_model)
    );
    let _ = writeln!(
        out,
        "  format:        DNG {}, {}",
        opt(&i.dng_version),
        i.byte_order
    );
    for s in &i.ifds {
        let _ = writeln!(
            out,
            "  {:<14} type {} {}x{} {}-bit x{} {} ({}), {}, {}",
            format!("{}:", s.path),
            s.new_subfile_type,
            opt(&s.width),
            opt(&s.height),
            opt(&s.bits_per_sample),
            s.samples_per_pixel,
            s.photometric_name,
            opt(&s.photometric),
            s.compression_name,
            s.layout
        );
    }
    let _ = writeln!(out, "  raw IFD:       {}", opt(&i.raw_ifd));
    if let Some(r) = &i.raw {
        describe_raw(out, r);
    }
    match ill {
        Some(Ok(p)) => {
            let _ = writeln!(out, "  night illuminants: {}", p.summary());
        }
        Some(Err(e)) => {
            let _ = writeln!(out, "  night illuminants: not available: {e}");
        }
        None => {}
    }
    if let Some(n) = noise {
        let _ = writeln!(
            out,
            "  noise model:   {} ({}): {}",
            n.source.name(),
            n.camera
                .as_ref()
                .map_or("camera unknown".to_string(), |c| format!(
                    "camera {}",
                    c.label()
                )),
            n.note
        );
    }
    let _ = writeln!(
        out,
        "  synthesis:     {}",
        if i.synth_ready && i.warnings.is_empty() {
            "ready".to_string()
        } else if i.synth_ready {
            format!("ready, with warnings: {}", i.warnings.messages().join("; "))
        } else {
            format!("not usable: {}", opt(&i.reason))
        }
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_numbers_are_short() {
        assert_eq!(short_sci(3.1999999999999997e-4), "3.2e-4");
        assert_eq!(short_sci(1.0239999999999998e-4), "1.024e-4");
        assert_eq!(short_sci(2e-5), "2e-5");
        assert_eq!(short_sci(0.0), "0e0");
        assert_eq!(short_sci(1.234567e-3), "1.23457e-3");
    }

    #[test]
    fn sniffs_non_tiff_files() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.exr");
        std::fs::write(&p, b"\x76\x2f\x31\x01\x02\0\0\0").unwrap();
        assert_eq!(sniff(&p), Some("an OpenEXR image"));
        std::fs::write(&p, b"II*\0\x08\0\0\0").unwrap();
        assert_eq!(sniff(&p), None);
        std::fs::write(&p, b"").unwrap();
        assert_eq!(sniff(&p), None);
    }
}
