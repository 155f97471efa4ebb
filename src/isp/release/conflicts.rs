//! The options `--isp release` fixes (docs/isp.md, "The release's ISP"): each may be left
//! at its default or name what the release does, and any other value is refused. One rule
//! for the command line (`render --isp release`), the Python `render(isp="release")` and
//! the trainer's targets (`render_target(isp="release")`), each naming the option its own
//! way.

use crate::error::Error;
use crate::isp::demosaic::Demosaic;
use crate::isp::opcodes::OpcodeMode;
use crate::isp::tone::DisplayTone;

/// Which ISP renders (`render --isp`, `real-pairs --isp`, Python's `isp=`): day2night's
/// own or the release's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Isp {
    /// day2night's ISP (docs/isp.md).
    #[default]
    Day2night,
    /// The authors' release's target render reproduced (docs/isp.md).
    Release,
}

crate::choices! {
    Isp, ignore_case: false,
    unknown: |s| Error::invalid(format!(
        "isp {s:?}: use {}",
        crate::choice::listed::<Isp>(", ", " or ")
    )),
    Day2night => "day2night": "day2night's ISP",
    Release => "release": "The authors' release's target render reproduced",
}

/// An option the release fixes: its name (`demosaic`, `tone`, `opcodes`), its default
/// and the release's own value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fixed {
    /// The option's name, without dashes.
    pub option: &'static str,
    /// Its default (allowed: the release then uses its own).
    pub default: &'static str,
    /// What the release does.
    pub own: &'static str,
}

/// The options the release fixes.
pub fn fixed() -> [Fixed; 3] {
    [
        Fixed {
            option: "demosaic",
            default: Demosaic::default().name(),
            own: Demosaic::Menon.name(),
        },
        Fixed {
            option: "tone",
            default: DisplayTone::default().name(),
            own: DisplayTone::Release.name(),
        },
        Fixed {
            option: "opcodes",
            default: OpcodeMode::default().name(),
            own: OpcodeMode::Ignore.name(),
        },
    ]
}

/// A value the release refuses: the option, the value given and the release's own.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Conflict {
    /// The option's name, without dashes.
    pub option: &'static str,
    /// The value given.
    pub value: String,
    /// What the release does.
    pub own: &'static str,
}

/// The first of `given` (option name, value as given) that names neither the option's
/// default nor the release's own value; options the release does not fix are ignored.
pub fn conflicts<'a>(given: impl IntoIterator<Item = (&'a str, &'a str)>) -> Option<Conflict> {
    let fixed = fixed();
    given.into_iter().find_map(|(option, value)| {
        let f = fixed.iter().find(|f| f.option == option)?;
        (value != f.default && value != f.own).then(|| Conflict {
            option: f.option,
            value: value.to_string(),
            own: f.own,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_and_the_release_own_pass_anything_else_conflicts() {
        for f in fixed() {
            assert_eq!(conflicts([(f.option, f.default)]), None);
            assert_eq!(conflicts([(f.option, f.own)]), None);
        }
        let c = conflicts([("tone", "srgb"), ("demosaic", "bilinear"), ("opcodes", "x")]);
        assert_eq!(
            c,
            Some(Conflict {
                option: "demosaic",
                value: "bilinear".into(),
                own: "menon",
            })
        );
        assert_eq!(conflicts([("tone", "gamma22")]).unwrap().own, "release");
        assert_eq!(conflicts([("opcodes", "apply"), ("crop", "no")]), None);
    }
}
