//! Resume: decide, per unit, whether the previous record still describes valid outputs.
//! A unit is skipped only when its latest record is `ok`, for the same input bytes
//! (SHA-256), options fingerprint, seed and split, and every output it lists exists with the
//! recorded size. Anything else is recomputed, with the reason counted and reported.

use super::manifest::{Record, Status};
use super::split::Split;
use std::path::Path;

/// Why a unit is (re)computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Reason {
    /// No previous record.
    New,
    /// `--overwrite`: everything is recomputed.
    Forced,
    /// The previous attempt failed.
    PreviouslyFailed,
    /// The input file's content changed.
    InputChanged,
    /// Processing options changed.
    OptionsChanged,
    /// The seed changed (run seed or variant count).
    SeedChanged,
    /// The input moved to the other split.
    SplitChanged,
    /// An output is missing or has another size.
    OutputsMissing,
}

impl Reason {
    /// Short description for the summary.
    pub fn describe(self) -> &'static str {
        match self {
            Reason::New => "new",
            Reason::Forced => "forced by --overwrite",
            Reason::PreviouslyFailed => "failed before",
            Reason::InputChanged => "input changed",
            Reason::OptionsChanged => "options changed",
            Reason::SeedChanged => "seed changed",
            Reason::SplitChanged => "split changed",
            Reason::OutputsMissing => "outputs missing or altered",
        }
    }
}

/// Skip or redo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Outputs exist and match: nothing to do.
    Skip,
    /// Work needed, and why.
    Redo(Reason),
}

/// What the current run wants for a unit.
#[derive(Debug, Clone, Copy)]
pub struct Want<'a> {
    /// Current split.
    pub split: Split,
    /// Current input SHA-256.
    pub input_sha256: &'a str,
    /// Current unit seed.
    pub seed: u64,
    /// Current options SHA-256.
    pub options_sha256: &'a str,
}

/// Decide for one unit given its latest previous record.
pub fn decide(prev: Option<&Record>, want: Want<'_>, out_dir: &Path, force: bool) -> Decision {
    if force {
        return Decision::Redo(Reason::Forced);
    }
    let Some(r) = prev else {
        return Decision::Redo(Reason::New);
    };
    let reason = if r.status != Status::Ok {
        Some(Reason::PreviouslyFailed)
    } else if r.input_sha256 != want.input_sha256 {
        Some(Reason::InputChanged)
    } else if r.options_sha256 != want.options_sha256 {
        Some(Reason::OptionsChanged)
    } else if r.seed != want.seed {
        Some(Reason::SeedChanged)
    } else if r.split != want.split {
        Some(Reason::SplitChanged)
    } else if r.outputs.is_empty()
        || !r.outputs.iter().all(|o| {
            std::fs::metadata(out_dir.join(&o.path))
                .map(|m| m.is_file() && m.len() == o.bytes)
                .unwrap_or(false)
        })
    {
        Some(Reason::OutputsMissing)
    } else {
        None
    };
    match reason {
        Some(r) => Decision::Redo(r),
        None => Decision::Skip,
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Kind, OutputFile};
    use super::*;

    #[test]
    fn decisions() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(d.path().join("train/meta")).unwrap();
        std::fs::write(d.path().join("train/meta/a.json"), b"{}").unwrap();
        let r = Record {
            input: "a.dng".into(),
            variant: 1,
            split: Split::Train,
            status: Status::Ok,
            input_sha256: "i".into(),
            seed: 5,
            options_sha256: "o".into(),
            outputs: vec![OutputFile {
                kind: Kind::Meta,
                path: "train/meta/a.json".into(),
                bytes: 2,
                sha256: String::new(),
            }],
            iso: vec![],
            night_neutral: None,
            stages: vec![],
            error: None,
            kind: None,
            scene: None,
            frames: None,
        };
        let w = Want {
            split: Split::Train,
            input_sha256: "i",
            seed: 5,
            options_sha256: "o",
        };
        let p = d.path();
        assert_eq!(decide(Some(&r), w, p, false), Decision::Skip);
        assert_eq!(decide(Some(&r), w, p, true), Decision::Redo(Reason::Forced));
        assert_eq!(decide(None, w, p, false), Decision::Redo(Reason::New));
        let cases = [
            (
                Want {
                    input_sha256: "x",
                    ..w
                },
                Reason::InputChanged,
            ),
            (
                Want {
                    options_sha256: "x",
                    ..w
                },
                Reason::OptionsChanged,
            ),
            (Want { seed: 6, ..w }, Reason::SeedChanged),
            (
                Want {
                    split: Split::Val,
                    ..w
                },
                Reason::SplitChanged,
            ),
        ];
        for (want, reason) in cases {
            assert_eq!(decide(Some(&r), want, p, false), Decision::Redo(reason));
        }
        let mut failed = r.clone();
        failed.status = Status::Failed;
        assert_eq!(
            decide(Some(&failed), w, p, false),
            Decision::Redo(Reason::PreviouslyFailed)
        );
        std::fs::write(p.join("train/meta/a.json"), b"{ }").unwrap();
        assert_eq!(
            decide(Some(&r), w, p, false),
            Decision::Redo(Reason::OutputsMissing)
        );
        std::fs::remove_file(p.join("train/meta/a.json")).unwrap();
        assert_eq!(
            decide(Some(&r), w, p, false),
            Decision::Redo(Reason::OutputsMissing)
        );
    }
}
