//! Finding the scenes of SCENES and planning each one (docs/real-pairs.md, "Input layouts").
//!
//! [`find_scenes`] only lists names (cheap, done once); [`plan_scene`] reads and hashes a
//! scene's files and decides which frames are the clean burst and which are the noisy inputs
//! (done by the worker that processes the scene). A scene that cannot be planned (one frame,
//! no low-ISO burst, a missing ISO) is an error naming the scene and the file or pattern.

use super::{scene_id, RELEASE_LOW_ISO};
use crate::dataset::discover::is_dng_name;
use crate::dataset::{hash_file, sha256_hex};
use crate::error::{Error, Result, ResultExt};
use serde::Serialize;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

/// An input layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Layout {
    /// The authors' burst folders: one folder per scene, frames named `RAW_0_00<ISO>*`.
    Release,
    /// The authors' processed tree `night_real/{clean, clean_raw, dng/iso_<ISO>}/NNN.*`.
    ReleaseProcessed,
    /// A folder of DNGs per scene, the ISO read from each DNG.
    Simple,
}

impl Layout {
    /// Name as on the command line and in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            Layout::Release => "release",
            Layout::ReleaseProcessed => "release-processed",
            Layout::Simple => "simple",
        }
    }
}

/// `--layout`: detect or force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LayoutChoice {
    /// Detect from the folder (docs/real-pairs.md).
    Auto,
    /// This layout.
    Fixed(Layout),
}

impl std::str::FromStr for LayoutChoice {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Ok(match s {
            "auto" => LayoutChoice::Auto,
            "release" => LayoutChoice::Fixed(Layout::Release),
            "release-processed" => LayoutChoice::Fixed(Layout::ReleaseProcessed),
            "simple" => LayoutChoice::Fixed(Layout::Simple),
            _ => {
                return Err(Error::invalid(format!(
                    "unknown layout {s:?}: use auto, release, release-processed or simple"
                )))
            }
        })
    }
}

/// One file of a scene as listed (no content read yet).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Listed {
    /// Path relative to SCENES, `/`-separated.
    pub rel: String,
    /// Path to open.
    pub path: PathBuf,
}

/// A scene as found: its identity and its files, sorted by relative path (byte-wise, as
/// Python's `sorted(glob(...))` orders the release's frames).
#[derive(Debug, Clone)]
pub struct SceneDir {
    /// The scene's input name: its folder relative to SCENES (release, simple) or its
    /// number `NNN` (release-processed).
    pub rel: String,
    /// Output id ([`scene_id`]).
    pub id: String,
    /// The scene folder (release, simple) or SCENES (release-processed).
    pub path: PathBuf,
    /// Every file of the scene.
    pub files: Vec<Listed>,
}

/// A file of a planned scene, hashed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FileRef {
    /// Path relative to SCENES.
    pub name: String,
    /// Path to open.
    #[serde(skip)]
    pub path: PathBuf,
    /// ISO (from the name in the release layouts, from the DNG in the simple one).
    pub iso: u32,
    /// SHA-256 of the file.
    pub sha256: String,
}

/// The files of the processed tree for one scene.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcessedFiles {
    /// `clean_raw/NNN.png`: 16-bit PNG of the merged raw.
    pub clean_raw: FileRef,
    /// `clean/NNN.png`: the release's 8-bit target, if present.
    pub target: Option<FileRef>,
    /// `dng/iso_50/NNN.dng`: metadata of the clean raw.
    pub meta_dng: FileRef,
}

/// A planned scene: which frames are merged and which are the noisy inputs.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenePlan {
    /// Input name (see [`SceneDir::rel`]).
    pub rel: String,
    /// Output id.
    pub id: String,
    /// The scene folder (or SCENES).
    pub path: PathBuf,
    /// Layout it was read in.
    pub layout: Layout,
    /// ISO of the clean burst.
    pub low_iso: u32,
    /// The clean burst, sorted by name (empty for release-processed).
    pub clean: Vec<FileRef>,
    /// The first frame (by name) of each high-ISO burst, by ascending ISO.
    pub noisy: Vec<FileRef>,
    /// Frames found per ISO.
    pub frames: BTreeMap<u32, u32>,
    /// Release-processed files.
    pub processed: Option<ProcessedFiles>,
    /// Files of the scene that no rule uses (names).
    pub ignored: Vec<String>,
}

/// Find the scenes of `root` in the layout asked for (or detected); `exclude` (the output
/// folder) is skipped. Errors when nothing usable is found.
pub fn find_scenes(
    root: &Path,
    exclude: &[PathBuf],
    choice: LayoutChoice,
) -> Result<(Layout, Vec<SceneDir>)> {
    if !root.is_dir() {
        return Err(Error::invalid("not a directory").in_file(root));
    }
    let processed_tree = root.join("clean_raw").is_dir() && root.join("dng").is_dir();
    let layout = match choice {
        LayoutChoice::Fixed(l) => l,
        LayoutChoice::Auto if processed_tree => Layout::ReleaseProcessed,
        LayoutChoice::Auto => Layout::Simple, // refined below from the frame names
    };
    if layout == Layout::ReleaseProcessed {
        let scenes = processed_scenes(root)?;
        check_unique_ids(root, &scenes)?;
        check_id_lengths(&scenes)?;
        return Ok((layout, scenes));
    }
    let scenes = scene_folders(root, exclude)?;
    check_unique_ids(root, &scenes)?;
    check_id_lengths(&scenes)?;
    let named = scenes
        .iter()
        .flat_map(|s| &s.files)
        .any(|f| release_iso(file_name(&f.rel)).is_some());
    let layout = match choice {
        LayoutChoice::Auto if named => Layout::Release,
        _ => layout,
    };
    Ok((layout, scenes))
}

/// Error when two scenes would write the same output id ([`scene_id`]: `a/b` and `a__b`
/// both give `a__b`), or ids that differ only in letter case (one file on a case-insensitive
/// file system): checked before anything is written, naming both folders.
fn check_unique_ids(root: &Path, scenes: &[SceneDir]) -> Result<()> {
    let mut seen: BTreeMap<String, &SceneDir> = BTreeMap::new();
    for s in scenes {
        if let Some(first) = seen.insert(s.id.to_lowercase(), s) {
            let how = if first.id == s.id {
                format!("both map to the output id {:?}", s.id)
            } else {
                format!(
                    "their output ids {:?} and {:?} differ only in letter case",
                    first.id, s.id
                )
            };
            return Err(Error::invalid(format!(
                "scenes {:?} and {:?}: {how} ('/' becomes '__'), so one would overwrite the other: rename one of the folders",
                first.rel, s.rel
            ))
            .in_file(root));
        }
    }
    Ok(())
}

/// Longest scene id, in bytes: a file name holds at most 255 bytes, and the longest name
/// made from an id is the temporary name of a noisy input, `.<id>_iso<ISO>.dng.tmp-<pid>`
/// (an ISO of up to 10 digits, a process id of up to 7: 31 bytes besides the id).
pub const ID_MAX_BYTES: usize = 255 - ".tmp-".len() - 1 - 7 - "_iso".len() - 10 - ".dng".len();

/// Error ([`Error::Limits`]) when a scene's output id ([`scene_id`]) is longer than
/// [`ID_MAX_BYTES`]: its files could not be written (the file system's name limit). Checked
/// before anything is written, naming the folder.
fn check_id_lengths(scenes: &[SceneDir]) -> Result<()> {
    match scenes.iter().find(|s| s.id.len() > ID_MAX_BYTES) {
        Some(s) => Err(Error::Limits(format!(
            "scene {:?}: its output id is {} bytes, longer than the {ID_MAX_BYTES} its file names allow (255 bytes per name, with the temporary suffix): rename the folder or file to a shorter name",
            s.rel,
            s.id.len()
        ))
        .in_file(&s.path)),
        None => Ok(()),
    }
}

fn file_name(rel: &str) -> &str {
    rel.rsplit('/').next().unwrap_or(rel)
}

/// The ISO in a release frame name `RAW_0_00<ISO zero-padded to 4 digits>...`: the digits
/// after `RAW_0_00` (4, or more when a fifth digit follows an ISO of 10000 or more is not
/// distinguishable, so exactly 4 are read: docs/real-pairs.md).
pub fn release_iso(name: &str) -> Option<u32> {
    let rest = name.strip_prefix("RAW_0_00")?;
    let digits = rest.get(..4)?;
    if digits.bytes().all(|b| b.is_ascii_digit()) {
        digits.parse().ok()
    } else {
        None
    }
}

/// The release's pattern for an ISO: `RAW_0_00` + the ISO zero-padded to 4 digits.
pub fn release_prefix(iso: u32) -> String {
    format!("RAW_0_00{iso:04}")
}

fn read_dir_sorted(dir: &Path) -> Result<Vec<(String, PathBuf, bool)>> {
    let mut v = Vec::new();
    for e in fs::read_dir(dir).map_err(Error::Io).in_file(dir)? {
        let e = e.map_err(Error::Io).in_file(dir)?;
        let path = e.path();
        let name = e.file_name();
        let Some(name) = name.to_str() else {
            return Err(Error::unsupported("file name is not valid UTF-8").in_file(&path));
        };
        if name.starts_with('.') {
            continue;
        }
        let is_dir = e.file_type().map_err(Error::Io).in_file(&path)?.is_dir();
        v.push((name.to_string(), path, is_dir));
    }
    v.sort_by(|a, b| a.0.as_bytes().cmp(b.0.as_bytes()));
    Ok(v)
}

/// Every folder under `root` that directly holds DNG files is a scene.
fn scene_folders(root: &Path, exclude: &[PathBuf]) -> Result<Vec<SceneDir>> {
    let exclude: Vec<PathBuf> = exclude
        .iter()
        .filter_map(|p| fs::canonicalize(p).ok())
        .collect();
    let mut out = Vec::new();
    let mut stack = vec![(root.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        if fs::canonicalize(&dir).is_ok_and(|c| exclude.contains(&c)) {
            continue;
        }
        let mut files = Vec::new();
        for (name, path, is_dir) in read_dir_sorted(&dir)? {
            let rel = if prefix.is_empty() {
                name.clone()
            } else {
                format!("{prefix}/{name}")
            };
            if is_dir {
                stack.push((path, rel));
            } else if is_dng_name(&name) && path.is_file() {
                files.push(Listed { rel, path });
            }
        }
        if files.is_empty() {
            continue;
        }
        if prefix.is_empty() {
            return Err(Error::invalid(format!(
                "holds DNG files directly ({} ...): put the frames of each scene in a folder of their own",
                files[0].rel
            ))
            .in_file(root));
        }
        out.push(SceneDir {
            id: scene_id(&prefix),
            rel: prefix,
            path: dir,
            files,
        });
    }
    if out.is_empty() {
        return Err(Error::invalid(
            "no scene found: no folder under it holds a DNG file (*.dng in any letter case)",
        )
        .in_file(root));
    }
    out.sort_by(|a, b| a.rel.as_bytes().cmp(b.rel.as_bytes()));
    Ok(out)
}

/// The scenes of the processed tree: every `NNN` of a `clean_raw/NNN.png`, a `clean/NNN.png`
/// or a `dng/<folder>/NNN.dng`, with every such file of it; [`plan_scene`] decides what each
/// file is for (a scene without its clean raw fails there, as a burst folder without its
/// low-ISO frames does) and lists the files no rule uses as ignored.
fn processed_scenes(root: &Path) -> Result<Vec<SceneDir>> {
    let mut scenes: BTreeMap<String, Vec<Listed>> = BTreeMap::new();
    let mut add = |sub: &str, ext: &str| -> Result<()> {
        let dir = root.join(sub);
        if !dir.is_dir() {
            return Ok(());
        }
        for (name, path, is_dir) in read_dir_sorted(&dir)? {
            let lower = name.to_ascii_lowercase();
            let Some(stem) = lower.strip_suffix(ext).map(|s| &name[..s.len()]) else {
                continue;
            };
            if is_dir || stem.is_empty() {
                continue;
            }
            scenes.entry(stem.to_string()).or_default().push(Listed {
                rel: format!("{sub}/{name}"),
                path,
            });
        }
        Ok(())
    };
    add("clean_raw", ".png")?;
    add("clean", ".png")?;
    for (name, _, is_dir) in read_dir_sorted(&root.join("dng"))? {
        if is_dir {
            add(&format!("dng/{name}"), ".dng")?;
        }
    }
    if scenes.is_empty() {
        return Err(Error::invalid(
            "no scene found: no clean_raw/*.png, clean/*.png or dng/<folder>/*.dng",
        )
        .in_file(root));
    }
    Ok(scenes
        .into_iter()
        .map(|(stem, mut files)| {
            files.sort_by(|a, b| a.rel.as_bytes().cmp(b.rel.as_bytes()));
            SceneDir {
                id: scene_id(&stem),
                rel: stem,
                path: root.to_path_buf(),
                files,
            }
        })
        .collect())
}

/// The ISO of a processed-tree folder `iso_<N>`.
fn processed_iso(dir_name: &str) -> Option<u32> {
    let n = dir_name.strip_prefix("iso_")?;
    if n.is_empty() || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    n.parse().ok().filter(|&i| i > 0)
}

/// SHA-256 of every file of the scene, and the scene's input hash: the SHA-256 of the files'
/// hex hashes concatenated in name order.
pub fn hash_scene(scene: &SceneDir) -> Result<(Vec<String>, String)> {
    let mut hashes = Vec::with_capacity(scene.files.len());
    for f in &scene.files {
        hashes.push(hash_file(&f.path).in_file(&f.path)?.1);
    }
    let joined = hashes.concat();
    Ok((hashes, sha256_hex(joined.as_bytes())))
}

/// Plan a hashed scene (`hashes` from [`hash_scene`]): which frames are merged and which are
/// the noisy inputs. `release_isos`: the noisy ISOs of the release layout.
pub fn plan_scene(
    scene: &SceneDir,
    hashes: &[String],
    layout: Layout,
    release_isos: &[u32],
) -> Result<ScenePlan> {
    let mut refs = Vec::new();
    for (f, h) in scene.files.iter().zip(hashes) {
        let iso = match layout {
            Layout::Release => release_iso(file_name(&f.rel)).unwrap_or(0),
            Layout::Simple => dng_iso(&f.path)?,
            Layout::ReleaseProcessed => f
                .rel
                .split('/')
                .find_map(processed_iso)
                .unwrap_or(RELEASE_LOW_ISO),
        };
        refs.push(FileRef {
            name: f.rel.clone(),
            path: f.path.clone(),
            iso,
            sha256: h.clone(),
        });
    }
    let mut plan = ScenePlan {
        rel: scene.rel.clone(),
        id: scene.id.clone(),
        path: scene.path.clone(),
        layout,
        low_iso: RELEASE_LOW_ISO,
        clean: vec![],
        noisy: vec![],
        frames: BTreeMap::new(),
        processed: None,
        ignored: vec![],
    };
    match layout {
        Layout::Release => plan_release(&mut plan, refs, release_isos)?,
        Layout::Simple => plan_simple(&mut plan, refs)?,
        Layout::ReleaseProcessed => plan_processed(&mut plan, refs, release_isos)?,
    }
    Ok(plan)
}

/// The ISO of a DNG (Exif ISOSpeedRatings), from its metadata only.
fn dng_iso(path: &Path) -> Result<u32> {
    let bytes = fs::read(path).map_err(Error::Io).in_file(path)?;
    let info = crate::dng::read::inspect_bytes(&bytes).in_file(path)?;
    // The real reason a frame is unusable (e.g. WhiteLevel below BlackLevel, an all-zero
    // AsShotNeutral), not a missing ISO.
    let refused = match (&info.error, &info.raw, &info.reason) {
        (Some(e), _, _) | (None, None, Some(e)) => Some(e),
        _ => None,
    };
    if let Some(e) = refused {
        return Err(Error::invalid(format!("not a usable raw DNG: {e}")).in_file(path));
    }
    info.raw.and_then(|r| r.meta.meta.exif.iso).ok_or_else(|| {
        Error::invalid(
            "no ISO in the DNG (Exif ISOSpeedRatings): the simple layout groups frames by it",
        )
        .in_file(path)
    })
}

fn plan_release(plan: &mut ScenePlan, refs: Vec<FileRef>, isos: &[u32]) -> Result<()> {
    let low = release_prefix(RELEASE_LOW_ISO);
    let prefixes: Vec<(u32, String)> = isos.iter().map(|&i| (i, release_prefix(i))).collect();
    let mut noisy: BTreeMap<u32, Vec<FileRef>> = BTreeMap::new();
    for mut r in refs {
        let name = file_name(&r.name).to_string();
        if name.starts_with(&low) {
            r.iso = RELEASE_LOW_ISO;
            plan.clean.push(r);
        } else if let Some((iso, _)) = prefixes.iter().find(|(_, p)| name.starts_with(p)) {
            r.iso = *iso;
            noisy.entry(*iso).or_default().push(r);
        } else {
            plan.ignored.push(r.name);
        }
    }
    plan.frames.insert(RELEASE_LOW_ISO, plan.clean.len() as u32);
    check_burst(
        plan,
        &format!("no frame named {low}* (the ISO {RELEASE_LOW_ISO} burst)"),
    )?;
    for &iso in isos {
        let Some(v) = noisy.remove(&iso) else {
            return Err(Error::invalid(format!(
                "no frame named {}* (the ISO {iso} burst; --iso lists the noisy ISOs expected)",
                release_prefix(iso)
            )));
        };
        plan.frames.insert(iso, v.len() as u32);
        if let Some(first) = v.into_iter().next() {
            plan.noisy.push(first);
        }
    }
    Ok(())
}

fn check_burst(plan: &ScenePlan, none: &str) -> Result<()> {
    match plan.clean.as_slice() {
        [] => Err(Error::invalid(format!("no low-ISO burst: {none}"))),
        [one] => Err(Error::invalid(format!(
            "the low-ISO (ISO {}) burst has one frame ({}): merging needs at least 2",
            plan.low_iso, one.name
        ))),
        _ => Ok(()),
    }
}

fn plan_simple(plan: &mut ScenePlan, refs: Vec<FileRef>) -> Result<()> {
    let mut by_iso: BTreeMap<u32, Vec<FileRef>> = BTreeMap::new();
    for r in refs {
        by_iso.entry(r.iso).or_default().push(r);
    }
    for (iso, v) in &by_iso {
        plan.frames.insert(*iso, v.len() as u32);
    }
    let mut it = by_iso.into_iter();
    let Some((low, clean)) = it.next() else {
        return Err(Error::invalid("no DNG frame"));
    };
    plan.low_iso = low;
    plan.clean = clean;
    check_burst(plan, "no DNG frame")?;
    for (_, v) in it {
        if let Some(first) = v.into_iter().next() {
            plan.noisy.push(first);
        }
    }
    Ok(())
}

fn plan_processed(plan: &mut ScenePlan, refs: Vec<FileRef>, isos: &[u32]) -> Result<()> {
    let (mut clean_raw, mut target, mut meta_dng): (Option<FileRef>, _, _) = (None, None, None);
    let mut noisy: BTreeMap<u32, FileRef> = BTreeMap::new();
    for r in refs {
        let folder = r.name.rsplit_once('/').map_or("", |(d, _)| d);
        let iso = folder.strip_prefix("dng/").and_then(processed_iso);
        let slot = match (folder, iso) {
            ("clean_raw", _) => &mut clean_raw,
            ("clean", _) => &mut target,
            (_, Some(RELEASE_LOW_ISO)) => &mut meta_dng,
            (_, Some(i)) if isos.contains(&i) => match noisy.entry(i) {
                std::collections::btree_map::Entry::Vacant(v) => {
                    v.insert(r);
                    continue;
                }
                std::collections::btree_map::Entry::Occupied(o) => {
                    return Err(two_files(&o.get().name, &r.name));
                }
            },
            _ => {
                // dng/iso_<ISO not in --iso>, dng/<not iso_N>: no rule uses it.
                plan.ignored.push(r.name);
                continue;
            }
        };
        if let Some(prev) = slot.as_ref() {
            return Err(two_files(&prev.name, &r.name));
        }
        *slot = Some(r);
    }
    let Some(clean_raw) = clean_raw else {
        return Err(Error::invalid(format!(
            "no clean_raw/{}.png (the merged raw of the scene)",
            plan.rel
        )));
    };
    let Some(meta_dng) = meta_dng else {
        return Err(Error::invalid(format!(
            "no dng/iso_{RELEASE_LOW_ISO}/{}.dng (the metadata of the clean raw)",
            plan.rel
        )));
    };
    plan.frames.insert(RELEASE_LOW_ISO, 1);
    for &iso in isos {
        let Some(mut r) = noisy.remove(&iso) else {
            return Err(Error::invalid(format!(
                "no dng/iso_{iso}/{}.dng (the ISO {iso} input; --iso lists the noisy ISOs expected)",
                plan.rel
            )));
        };
        r.iso = iso;
        plan.frames.insert(iso, 1);
        plan.noisy.push(r);
    }
    plan.noisy.sort_by_key(|r| r.iso);
    plan.processed = Some(ProcessedFiles {
        clean_raw,
        target,
        meta_dng,
    });
    Ok(())
}

/// Two files of a processed scene for one role (e.g. `clean/007.png` and `clean/007.PNG`).
fn two_files(a: &str, b: &str) -> Error {
    Error::invalid(format!(
        "{a} and {b} are both this scene's file for one role: keep one"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn release_names() {
        assert_eq!(release_iso("RAW_0_000050_0001.dng"), Some(50));
        assert_eq!(release_iso("RAW_0_001600x.dng"), Some(1600));
        assert_eq!(release_iso("RAW_0_0x1600.dng"), None);
        assert_eq!(release_iso("IMG_1.dng"), None);
        assert_eq!(release_prefix(50), "RAW_0_000050");
        assert_eq!(release_prefix(3200), "RAW_0_003200");
        assert_eq!(processed_iso("iso_1600"), Some(1600));
        assert_eq!(processed_iso("iso_"), None);
        assert_eq!(processed_iso("x_50"), None);
        assert!(matches!(
            "release-processed".parse::<LayoutChoice>(),
            Ok(LayoutChoice::Fixed(Layout::ReleaseProcessed))
        ));
        assert!("nope".parse::<LayoutChoice>().is_err());
    }
}
