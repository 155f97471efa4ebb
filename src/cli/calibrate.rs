//! `day2night calibrate illuminants|brightness|noise`: calibration files for a new camera.
use super::{usage, CmdResult};
use day2night::calibrate::{brightness, illuminants, noise, noise_image};
use day2night::dng::read_dng;
use day2night::error::ResultExt;
use day2night::output::{write_bytes_atomic, OutputPolicy};
use day2night::raw::camera::CameraId;
use day2night::raw::RawImage;
use day2night::{Code, Warning};
use std::path::{Path, PathBuf};

/// Calibration subcommands.
#[derive(Debug, clap::Subcommand)]
pub enum CalibrateCommand {
    /// Night illuminant dictionary from gray-card shots (and/or existing JSON lists to refit).
    #[command(after_help = "\
Per gray card: black-subtracted 10%-trimmed means of R, G, B over the ROI (default: the
central quarter x quarter of the active area), saturated sites excluded, chromaticity
[r/g, 1, b/g], and its CIE 1931 xy through the capture's own colour matrices (DNG
chapter 6). Then a 2-D Gaussian over [r/g, b/g] (unbiased covariance by default). The file
records the camera (Make, Model, UniqueCameraModel): synth uses the camera neutrals for that
camera and the xy, through its own matrices, for any other camera.
A .json input is a list of chromaticities to include (a day2night dictionary, with its xy
and camera, the shared s20fe file, or a bare [[r/g, 1, b/g], ...] list).

Example:
  day2night calibrate illuminants card_*.dng -o illuminants.json
  day2night calibrate illuminants card_01.dng --roi 1200,800,400,300 -o one_more.json")]
    Illuminants(IlluminantsArgs),
    /// Night brightness dictionary from real night raws.
    #[command(after_help = "\
Normalized mean intensity of each image's active area and the normal fit N(mean, std^2) that
`synth --brightness` samples target means from. One image: std = 0 (warning).

Example:
  day2night calibrate brightness night/*.dng -o brightness.json")]
    Brightness(BrightnessArgs),
    /// Per-ISO noise model from bursts, clean/noisy pairs, NoiseProfile tags or ordinary day
    /// images (--from-image), or the physics-based model from dark and flat frames
    /// (--physics).
    #[command(after_help = "\
Per ISO (Exif ISO of the frames) and 2x2 CFA position: var(y) = S*y + O on normalized data,
fitted by weighted least squares over intensity bins (split-half burst statistics or pair
residuals), clipped pixels excluded, rounding variance removed from O. Several ISOs in one
file; S = c*ISO and O = a + b*ISO^2 fitted across them. A burst needs >= 4 frames; 16 frames
of 1024x512 pixels measure S and O to about 1 %.

--from-image: the noise of each day image estimated from the image itself (smooth regions,
Poisson-Gaussian fit per 2x2 position, clipping aware): what synth does for an input without
NoiseProfile. Less exact than a burst (docs/noise.md gives its accuracy); --assume-iso N for
images without an Exif ISO.

--physics: per ISO, K (DN per electron) from flat-pair differences against the dark point,
sigma_row from dark row means, sigma_read and the Tukey lambda (PPCC) from row-corrected dark
residuals; >= 2 darks and >= 2 flats (pairs of equal exposure) per ISO. See docs/noise.md.

Examples:
  day2night calibrate noise --burst iso1600_*.dng --burst iso3200_*.dng -o noise.json
  day2night calibrate noise --pair merged_iso50.dng iso3200_01.dng -o noise.json
  day2night calibrate noise --from-noise-profile shots/*.dng -o noise.json
  day2night calibrate noise --from-image day_*.dng --assume-iso 100 -o noise.json
  day2night calibrate noise --physics --dark dark_*.dng --flat flat_*.dng -o physics.json --plot fit.svg")]
    Noise(NoiseArgs),
}

/// Options shared by every calibrate command.
#[derive(Debug, clap::Args)]
pub struct OutArgs {
    /// Output JSON file.
    #[arg(short, long, visible_alias = "out", value_name = "FILE.json")]
    output: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    overwrite: bool,
    /// Also print the written document on stdout.
    #[arg(long)]
    json: bool,
}

/// Arguments of `calibrate illuminants`.
#[derive(Debug, clap::Args)]
pub struct IlluminantsArgs {
    /// Gray-card DNGs (and/or .json chromaticity lists).
    #[arg(required = true, value_name = "GRAYCARD.dng")]
    inputs: Vec<PathBuf>,
    /// Region of interest X,Y,W,H in active-area pixels (default: the central 1/4 x 1/4).
    #[arg(long, value_name = "X,Y,W,H")]
    roi: Option<String>,
    /// Covariance estimator: unbiased 1/(M-1) (released code) or ml 1/M (paper eq. 2).
    #[arg(long, value_enum, default_value = "unbiased")]
    estimator: EstimatorArg,
    #[command(flatten)]
    out: OutArgs,
}

#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum EstimatorArg {
    Unbiased,
    Ml,
}

/// Arguments of `calibrate brightness`.
#[derive(Debug, clap::Args)]
pub struct BrightnessArgs {
    /// Real night DNGs.
    #[arg(required = true, value_name = "NIGHT.dng")]
    inputs: Vec<PathBuf>,
    #[command(flatten)]
    out: OutArgs,
}

/// Arguments of `calibrate noise` (hand-written clap impls: `--burst` groups need
/// per-occurrence values, which clap's derive only offers behind an unstable feature).
#[derive(Debug)]
pub struct NoiseArgs {
    burst: Vec<Vec<PathBuf>>,
    pair: Vec<Vec<PathBuf>>,
    from_noise_profile: Vec<PathBuf>,
    from_image: Vec<PathBuf>,
    assume_iso: Option<u32>,
    physics: bool,
    dark: Vec<PathBuf>,
    flat: Vec<PathBuf>,
    plot: Option<PathBuf>,
    poisson_max_electrons: Option<f64>,
    out: OutArgs,
}

impl clap::FromArgMatches for NoiseArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let occ = |id: &str| -> Vec<Vec<PathBuf>> {
            m.get_occurrences::<PathBuf>(id)
                .map(|o| o.map(|g| g.cloned().collect()).collect())
                .unwrap_or_default()
        };
        Ok(NoiseArgs {
            burst: occ("burst"),
            pair: occ("pair"),
            from_noise_profile: occ("from_noise_profile").into_iter().flatten().collect(),
            from_image: occ("from_image").into_iter().flatten().collect(),
            assume_iso: m.get_one::<u32>("assume_iso").copied(),
            physics: m.get_flag("physics"),
            dark: occ("dark").into_iter().flatten().collect(),
            flat: occ("flat").into_iter().flatten().collect(),
            plot: m.get_one::<PathBuf>("plot").cloned(),
            poisson_max_electrons: m.get_one::<f64>("poisson_max_electrons").copied(),
            out: OutArgs::from_arg_matches(m)?,
        })
    }
    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for NoiseArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        use clap::{value_parser, Arg, ArgAction};
        let cmd = cmd
            .arg(
                Arg::new("burst")
                    .long("burst")
                    .num_args(1..)
                    .action(ArgAction::Append)
                    .value_parser(value_parser!(PathBuf))
                    .value_name("FRAME.dng")
                    .help("An aligned burst of one static scene at one ISO (>= 4 frames); repeatable"),
            )
            .arg(
                Arg::new("pair")
                    .long("pair")
                    .num_args(2)
                    .action(ArgAction::Append)
                    .value_parser(value_parser!(PathBuf))
                    .value_names(["CLEAN.dng", "NOISY.dng"])
                    .help("A clean (e.g. merged) frame and a noisy frame of the same scene; repeatable"),
            )
            .arg(
                Arg::new("from_noise_profile")
                    .long("from-noise-profile")
                    .num_args(1..)
                    .action(ArgAction::Append)
                    .value_parser(value_parser!(PathBuf))
                    .value_name("DNG")
                    .help("DNGs whose NoiseProfile tags (and Exif ISO) give the model"),
            )
            .arg(
                Arg::new("from_image")
                    .long("from-image")
                    .num_args(1..)
                    .action(ArgAction::Append)
                    .value_parser(value_parser!(PathBuf))
                    .value_name("DAY.dng")
                    .help("Ordinary day images: the noise estimated from each image itself (one ISO point per input ISO; docs/noise.md)"),
            )
            .arg(
                Arg::new("assume_iso")
                    .long("assume-iso")
                    .value_parser(parse_iso)
                    .value_name("ISO")
                    .visible_alias("iso")
                    .help("ISO of input frames without an Exif ISO (missing or 0); frames with one keep theirs"),
            )
            .arg(
                Arg::new("physics")
                    .long("physics")
                    .action(ArgAction::SetTrue)
                    .conflicts_with_all(["burst", "pair", "from_noise_profile", "from_image"])
                    .requires_all(["dark", "flat"])
                    .help("Fit the physics-based model (shot, Tukey-lambda read, row noise) from --dark and --flat frames"),
            )
            .arg(
                Arg::new("dark")
                    .long("dark")
                    .num_args(1..)
                    .action(ArgAction::Append)
                    .requires("physics")
                    .value_parser(value_parser!(PathBuf))
                    .value_name("DARK.dng")
                    .help("Dark frames (no light), >= 2 per ISO (--physics)"),
            )
            .arg(
                Arg::new("flat")
                    .long("flat")
                    .num_args(1..)
                    .action(ArgAction::Append)
                    .requires("physics")
                    .value_parser(value_parser!(PathBuf))
                    .value_name("FLAT.dng")
                    .help("Flat frames (uniform, unsaturated), in pairs of equal exposure, >= 2 per ISO (--physics)"),
            )
            .arg(
                Arg::new("plot")
                    .long("plot")
                    .requires("physics")
                    .value_parser(value_parser!(PathBuf))
                    .value_name("FIT.svg")
                    .help("Also write an SVG plot of the mean-variance fit (--physics)"),
            )
            .arg(
                Arg::new("poisson_max_electrons")
                    .long("poisson-max-electrons")
                    .requires("physics")
                    .value_parser(value_parser!(f64))
                    .value_name("N")
                    .help("Exact Poisson shot noise up to N electrons, normal approximation above (--physics; default 1000)"),
            );
        <OutArgs as clap::Args>::augment_args(cmd)
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// Run a calibration subcommand.
pub fn run(cmd: CalibrateCommand) -> CmdResult {
    match cmd {
        CalibrateCommand::Illuminants(a) => run_illuminants(a),
        CalibrateCommand::Brightness(a) => run_brightness(a),
        CalibrateCommand::Noise(a) => run_noise(a),
    }
}

fn read(path: &Path) -> day2night::Result<RawImage> {
    read_dng(path).in_file(path)
}

/// A progress bar over `len` files on stderr, hidden unless stderr is a terminal.
pub(super) fn progress(len: usize) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() || len < 2 {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(len as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} files {msg}") {
        pb.set_style(style);
    }
    pb
}

fn write_json<T: serde::Serialize>(out: &OutArgs, inputs: &[PathBuf], doc: &T) -> CmdResult {
    let mut bytes = serde_json::to_vec_pretty(doc)?;
    bytes.push(b'\n');
    let policy = OutputPolicy {
        overwrite: out.overwrite,
        inputs: inputs.to_vec(),
        ..OutputPolicy::default()
    };
    write_bytes_atomic(&out.output, &policy, &bytes)?;
    if out.json {
        print!("{}", String::from_utf8_lossy(&bytes));
    }
    eprintln!("wrote {}", out.output.display());
    Ok(())
}

fn run_illuminants(a: IlluminantsArgs) -> CmdResult {
    let roi = match &a.roi {
        Some(s) => Some(illuminants::Roi::parse(s).map_err(usage)?),
        None => None,
    };
    let est = match a.estimator {
        EstimatorArg::Unbiased => illuminants::Estimator::Unbiased,
        EstimatorArg::Ml => illuminants::Estimator::Ml,
    };
    let mut files = vec![];
    let mut extra = vec![];
    for p in &a.inputs {
        let is_json = p
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        if is_json {
            let text = day2night::synth::dictionaries::read_calibration_text(p)?;
            let list = illuminants::parse_listed(&text).in_file(p)?;
            eprintln!(
                "{}: {} chromaticities{}",
                p.display(),
                list.chromaticities.len(),
                if list.xy.is_empty() { "" } else { " with xy" }
            );
            extra.push(list);
        } else {
            let img = read(p)?;
            let m =
                illuminants::measure_gray_card(&img, roi, &p.display().to_string()).in_file(p)?;
            let xy = m.xy.map_or(String::new(), |xy| {
                let cct = day2night::color::planck::cct_duv(xy)
                    .map_or(String::new(), |(t, d)| format!(", {t:.0} K, Duv {d:+.4}"));
                format!("  xy {:.4} {:.4}{cct}", xy[0], xy[1])
            });
            eprintln!(
                "{}: r/g {:.5}  b/g {:.5}{xy}  (R/G/B means {:.5} {:.5} {:.5}, {}/{}/{} px, {} saturated)",
                p.display(),
                m.chromaticity[0],
                m.chromaticity[2],
                m.means[0],
                m.means[1],
                m.means[2],
                m.pixels[0],
                m.pixels[1],
                m.pixels[2],
                m.saturated.iter().sum::<usize>()
            );
            super::warn_all(p, &m.warnings);
            files.push(m);
        }
    }
    let (dict, notes) = illuminants::build_dictionary(files, extra, est)?;
    for n in &notes {
        super::warn(n, "");
    }
    if let Some(c) = &dict.camera {
        eprintln!(
            "camera: {c}: synth uses the camera neutrals for it{}",
            if dict.xy.is_empty() {
                ""
            } else {
                ", the xy through their own colour matrices for other cameras"
            }
        );
    }
    let f = &dict.fit;
    eprintln!(
        "fit over {} illuminants ({} covariance): mean [{:.6}, {:.6}]  covariance [[{:.6e}, {:.6e}], [{:.6e}, {:.6e}]]",
        f.count,
        est.covariance_name(),
        f.mean[0],
        f.mean[1],
        f.covariance[0][0],
        f.covariance[0][1],
        f.covariance[1][0],
        f.covariance[1][1]
    );
    let degenerate = match f.count {
        1 => {
            Some("one illuminant: zero covariance, synth will always use it; shoot more gray cards")
        }
        2 => Some("2 illuminants give a degenerate (line) covariance; shoot more gray cards"),
        _ => None,
    };
    if let Some(m) = degenerate {
        super::warn(&Warning::new(Code::IlluminantsDegenerate, m), "");
    }
    write_json(&a.out, &a.inputs, &dict)
}

fn run_brightness(a: BrightnessArgs) -> CmdResult {
    let mut files = vec![];
    for p in &a.inputs {
        let img = read(p)?;
        let m = brightness::measure(&img, &p.display().to_string()).in_file(p)?;
        eprintln!("{}: mean {:.6}", p.display(), m.mean);
        files.push(m);
    }
    let dict = brightness::build_dictionary(files)?;
    let f = &dict.fit;
    eprintln!(
        "normal fit over {} images: mean {:.6} std {:.6} (range {:.6}..{:.6})",
        f.count, f.mean, f.std, f.min, f.max
    );
    if f.count == 1 {
        let m = "one image: std = 0, synth will always use this brightness";
        super::warn(&Warning::new(Code::BrightnessSingleImage, m), "");
    }
    write_json(&a.out, &a.inputs, &dict)
}

/// An ISO within [`day2night::bounds::ISO_RANGE`], the range `synth` takes (a model at
/// another ISO could not be used).
fn parse_iso(s: &str) -> Result<u32, String> {
    let iso: u32 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not an ISO (a whole number)"))?;
    day2night::bounds::iso("", iso).map_err(|e| match e {
        day2night::Error::InvalidParam(m) => m,
        e => e.to_string(),
    })?;
    Ok(iso)
}

/// The fits of a noise calibration, per ISO and position, and its ISO laws (stderr).
fn print_fits(model: &day2night::calibrate::format::NoiseModelFile) {
    for m in &model.isos {
        eprintln!(
            "ISO {} ({}, {} input(s), black {} white {}):",
            m.iso, m.source, m.inputs, m.black, m.white
        );
        for f in &m.fits {
            let fit = match (f.r2, f.chi2_reduced) {
                (Some(r2), Some(c2)) => format!(
                    "  R^2 {:.4}  chi2/dof {:.2}  {} bins  {} px  ({} clipped px excluded)",
                    r2, c2, f.bins, f.pixels, f.clipped_pixels
                ),
                _ => String::new(),
            };
            eprintln!(
                "  position {} ({}): S {:.4e}  O {:.4e}  (beta1 {:.4} DN, beta2 {:.3} DN^2){}",
                f.position, f.color, f.s, f.o, f.beta1, f.beta2, fit
            );
        }
    }
    if let Some(l) = &model.iso_laws {
        eprintln!(
            "ISO laws over {:?}: S = {:.4e} * ISO, O = {:.4e} + {:.4e} * ISO^2 (position 0)",
            l.isos, l.s_per_iso[0], l.o_at_iso0[0], l.o_per_iso2[0]
        );
    }
}

/// `calibrate noise` without any input is a usage error that lists the kinds of input.
fn need_some_input(a: &NoiseArgs) -> CmdResult {
    if a.burst.is_empty()
        && a.pair.is_empty()
        && a.from_noise_profile.is_empty()
        && a.from_image.is_empty()
    {
        return Err(usage(
            "give at least one --burst FRAMES..., --pair CLEAN NOISY, --from-noise-profile DNG..., --from-image DAY.dng... or --physics --dark ... --flat ...",
        ));
    }
    Ok(())
}

fn run_noise(a: NoiseArgs) -> CmdResult {
    if a.physics {
        return run_noise_physics(a);
    }
    // Frames without an Exif ISO get --assume-iso (noted once), the others keep theirs.
    let noted = std::cell::Cell::new(false);
    let read = |p: &Path| -> day2night::Result<RawImage> {
        let mut img = read(p)?;
        if let Some(iso) = a.assume_iso {
            if img.meta.exif.iso.filter(|&i| i > 0).is_none() {
                img.meta.exif.iso = Some(iso);
                if !noted.replace(true) {
                    eprintln!(
                        "day2night: {}: no Exif ISO, using --assume-iso {iso} (and for any other such frame)",
                        p.display()
                    );
                }
            }
        }
        Ok(img)
    };
    need_some_input(&a)?;
    let mut inputs: Vec<PathBuf> = vec![];
    let mut sources = vec![];
    // The camera of the first input; inputs of other cameras are said.
    let mut camera: Option<CameraId> = None;
    let mut note_camera = |p: &Path, img: &RawImage| {
        let c = CameraId::of(&img.meta);
        match &camera {
            None if !c.is_unknown() => camera = Some(c),
            Some(first) if first.same_camera(&c) == Some(false) => super::warn_all(
                p,
                &[Warning::new(
                    Code::CalibrateMixedCameras,
                    format!(
                        "another camera ({}) than the first input's ({}): the model records {}",
                        c.label(),
                        first.label(),
                        first.label()
                    ),
                )],
            ),
            _ => {}
        }
    };
    let total = a.burst.iter().map(Vec::len).sum::<usize>()
        + 2 * a.pair.len()
        + a.from_noise_profile.len()
        + a.from_image.len();
    let pb = progress(total);
    for burst in &a.burst {
        inputs.extend(burst.iter().cloned());
        let mut it = burst.iter();
        let Some(first) = it.next() else { continue };
        let img = read(first)?;
        pb.inc(1);
        note_camera(first, &img);
        let mut acc = noise::BurstAccumulator::new(img).in_file(first)?;
        for p in it {
            let img = read(p)?;
            acc.add(&img).in_file(p)?;
            pb.inc(1);
        }
        let st = acc.finish().in_file(first)?;
        eprintln!(
            "burst of {} frames from {}: ISO {}",
            st.frames,
            first.display(),
            st.iso
        );
        sources.push(st);
    }
    for pair in &a.pair {
        let [clean, noisy] = pair.as_slice() else {
            return Err(usage("--pair takes exactly two files: CLEAN NOISY"));
        };
        inputs.extend([clean.clone(), noisy.clone()]);
        let (c, n) = (read(clean)?, read(noisy)?);
        pb.inc(2);
        note_camera(noisy, &n);
        let st = noise::pair_stats(&c, &n).in_file(noisy)?;
        eprintln!(
            "pair {} / {}: ISO {}",
            clean.display(),
            noisy.display(),
            st.iso
        );
        sources.push(st);
    }
    let mut profiled = vec![];
    for p in &a.from_noise_profile {
        inputs.push(p.clone());
        let img = read(p)?;
        pb.inc(1);
        note_camera(p, &img);
        // Keep metadata only: pixels are not needed.
        profiled.push((
            p.display().to_string(),
            RawImage {
                data: vec![],
                ..img
            },
        ));
    }
    let mut estimates = vec![];
    for p in &a.from_image {
        inputs.push(p.clone());
        let img = read(p)?;
        pb.inc(1);
        note_camera(p, &img);
        let name = p.display().to_string();
        let e = noise_image::estimate_image(&name, &img, &Default::default()).in_file(p)?;
        eprintln!(
            "{}: ISO {}, noise estimated from the image ({} smooth 2x2 blocks, one band in {}){}",
            p.display(),
            e.iso,
            e.estimate.smooth_blocks(),
            e.estimate.step,
            match e.estimate.trusted() {
                Ok(_) => String::new(),
                Err(why) => format!(": cannot be trusted: {why}"),
            }
        );
        estimates.push(e);
    }
    pb.finish_and_clear();
    let refs: Vec<(String, &RawImage)> = profiled.iter().map(|(n, i)| (n.clone(), i)).collect();
    let mut profiles = noise::from_noise_profiles(&refs)?;
    let mut est_warnings = day2night::Diagnostics::new();
    if !estimates.is_empty() {
        let (models, w) = noise_image::from_image_estimates(&estimates)?;
        profiles.extend(models);
        est_warnings = w;
    }
    let (model, warnings) = noise::build_model(sources, profiles, camera)?;
    est_warnings.extend(warnings);
    let warnings = est_warnings;
    print_fits(&model);
    for w in &warnings {
        super::warn(w, "");
    }
    write_json(&a.out, &inputs, &model)
}

fn run_noise_physics(a: NoiseArgs) -> CmdResult {
    use day2night::calibrate::physics;
    let read_all = |paths: &[PathBuf]| -> day2night::Result<Vec<(String, RawImage)>> {
        let mut v = vec![];
        for p in paths {
            let mut img = read(p)?;
            if let Some(iso) = a.assume_iso {
                if img.meta.exif.iso.filter(|&i| i > 0).is_none() {
                    img.meta.exif.iso = Some(iso);
                }
            }
            v.push((p.display().to_string(), img));
        }
        Ok(v)
    };
    let darks = read_all(&a.dark)?;
    let flats = read_all(&a.flat)?;
    let dr: Vec<physics::Named> = darks.iter().map(|(n, i)| (n.as_str(), i)).collect();
    let fr: Vec<physics::Named> = flats.iter().map(|(n, i)| (n.as_str(), i)).collect();
    let camera_id = darks
        .first()
        .map(|(_, i)| CameraId::of(&i.meta))
        .filter(|c| !c.is_unknown());
    let camera = camera_id
        .as_ref()
        .map(|c| c.label())
        .unwrap_or_else(|| "unknown camera".into());
    let source = format!(
        "{camera}: physics noise calibration from {} dark and {} flat frames (day2night calibrate noise --physics)",
        darks.len(),
        flats.len()
    );
    let mut cal = physics::fit_physics(&dr, &fr, &source)?;
    cal.model.camera = camera_id;
    if let Some(n) = a.poisson_max_electrons {
        cal.model = cal.model.with_poisson_max(n)?;
    }
    eprintln!(
        "{:>6}  {:>10}  {:>10}  {:>8}  {:>6}  {:>10}  {:>6}  {:>6}",
        "ISO", "K DN/e-", "read DN", "lambda", "gauss", "row DN", "darks", "pairs"
    );
    for (p, f) in cal.model.isos.iter().zip(&cal.fits) {
        eprintln!(
            "{:>6}  {:>10.4}  {:>10.4}  {:>8.3}  {:>6}  {:>10.4}  {:>6}  {:>6}",
            p.iso,
            p.k,
            p.sigma_read,
            p.lambda,
            if p.gaussian_read { "yes" } else { "no" },
            p.sigma_row,
            f.dark.frames,
            f.flats.len()
        );
    }
    let j = &cal.model.joint;
    eprintln!(
        "joint fit: ln sigma_read = {:.4} + {:.4} ln K (residual {:.4}); ln sigma_row = {:.4} + {:.4} ln K (residual {:.4})",
        j.read.intercept, j.read.slope, j.read.residual_std, j.row.intercept, j.row.slope, j.row.residual_std
    );
    for w in &cal.warnings {
        super::warn(w, "");
    }
    let inputs: Vec<PathBuf> = a.dark.iter().chain(&a.flat).cloned().collect();
    if let Some(plot) = &a.plot {
        let svg = physics::plot_svg(&cal)?;
        let policy = OutputPolicy {
            overwrite: a.out.overwrite,
            inputs: inputs.clone(),
            ..OutputPolicy::default()
        };
        write_bytes_atomic(plot, &policy, svg.as_bytes())?;
        eprintln!("wrote {}", plot.display());
    }
    write_json(&a.out, &inputs, &cal)
}
