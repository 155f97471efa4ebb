//! Options whose values are a few names (`--demosaic mhc`, `--motion shake`): each such enum
//! spells its names once, in one [`choices!`](crate::choices) list, and everything else reads
//! that list: its `name()`, `Display` and `FromStr` (the macro derives them), the command
//! line's value parsers and their `[possible values: ...]` (src/cli/args.rs, and the
//! synthesis table's choice columns, [`crate::synth::options::OPTIONS`], which hold the
//! same [`Name`]s), Python's keyword arguments (parsed by the same `FromStr`) and docs/cli.md
//! (generated from `--help`). tests/it/choices.rs walks every [`Choice`] type.

use crate::error::Error;

/// One value of an option with a few values: its name, its other spellings and what it
/// means. The synthesis table's choice columns ([`crate::synth::options::Kind::Choice`]) are
/// lists of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Name {
    /// The value as typed (and as shown).
    pub name: &'static str,
    /// What it means (one line).
    pub help: &'static str,
    /// Other spellings of the same value (accepted, not listed).
    pub aliases: &'static [&'static str],
    /// The value as shown when the name takes a parameter, `name:PARAM` (`truncated:K`):
    /// `name:` and any text are accepted, and the setter parses the text. None: the name
    /// alone.
    pub param: Option<&'static str>,
}

impl Name {
    /// A plain name: no alias, no parameter.
    pub const fn new(name: &'static str, help: &'static str) -> Name {
        Name {
            name,
            help,
            aliases: &[],
            param: None,
        }
    }

    /// A name with its aliases, no parameter.
    pub const fn of(
        name: &'static str,
        aliases: &'static [&'static str],
        help: &'static str,
    ) -> Name {
        Name {
            name,
            help,
            aliases,
            param: None,
        }
    }

    /// The value as a list of choices shows it (`truncated:K`).
    pub fn shown(&self) -> &'static str {
        self.param.unwrap_or(self.name)
    }

    /// Whether `text` spells this value: its name, an alias, or `name:...` when it takes a
    /// parameter (the setter checks the parameter).
    pub fn accepts(&self, text: &str) -> bool {
        match self.param {
            Some(_) => text
                .strip_prefix(self.name)
                .is_some_and(|rest| rest.starts_with(':')),
            None => self.name == text || self.aliases.contains(&text),
        }
    }
}

/// An enum whose values are named by a [`choices!`](crate::choices) list.
pub trait Choice: Copy + PartialEq + std::fmt::Debug + 'static {
    /// The names, in the order lists show them.
    const NAMES: &'static [Name];
    /// The value of each of [`Choice::NAMES`], in the same order.
    const VALUES: &'static [Self];
    /// Whether a name is recognised whatever its ASCII case (the render and eval options'
    /// rule; the synthesis options' names are case-sensitive).
    const IGNORE_CASE: bool;

    /// The error for a text that names no value (each type's own message, which names its
    /// values).
    fn unknown(text: &str) -> Error;

    /// The value `text` names (a name or an alias, under the type's case rule).
    fn parse_name(text: &str) -> Result<Self, Error> {
        let folded = text.to_ascii_lowercase();
        let t = if Self::IGNORE_CASE { &folded } else { text };
        Self::NAMES
            .iter()
            .zip(Self::VALUES)
            .find(|(n, _)| n.accepts(t))
            .map(|(_, v)| *v)
            .ok_or_else(|| Self::unknown(text))
    }

    /// The name of `value`.
    fn name_of(value: Self) -> &'static str {
        Self::VALUES
            .iter()
            .position(|v| *v == value)
            .map_or("", |i| Self::NAMES[i].name)
    }
}

/// The names of `T`'s values, joined by `sep` and the last by `last` (`"a, b or c"`): what
/// the error messages list.
pub fn listed<T: Choice>(sep: &str, last: &str) -> String {
    list(T::NAMES, sep, last)
}

/// `names` as shown ([`Name::shown`]), joined by `sep` and the last by `last`.
pub fn list(names: &[Name], sep: &str, last: &str) -> String {
    let names: Vec<&str> = names.iter().map(Name::shown).collect();
    match names.split_last() {
        Some((l, [])) => l.to_string(),
        Some((l, rest)) => format!("{}{last}{l}", rest.join(sep)),
        None => String::new(),
    }
}

/// Implements [`Choice`] for a field-less enum from one list of its names, and derives from
/// it a `const fn name(self)`, `Display` (the name) and `FromStr` ([`Choice::parse_name`]):
///
/// ```ignore
/// choices! {
///     Demosaic, ignore_case: true,
///     unknown: |s| Error::invalid(format!("unknown demosaic method {s:?}")),
///     Bilinear => "bilinear": "Bilinear interpolation",
///     Mhc => "mhc" | "malvar": "Malvar-He-Cutler",
/// }
/// ```
///
/// The first name of each value is its name, the others are aliases (accepted, not listed);
/// the text after `:` is its one-line help.
#[macro_export]
macro_rules! choices {
    (
        $ty:ident, ignore_case: $ic:literal,
        unknown: |$s:ident| $err:expr,
        $($var:ident => $name:literal $(| $alias:literal)* : $help:literal),+ $(,)?
    ) => {
        impl $crate::choice::Choice for $ty {
            const NAMES: &'static [$crate::choice::Name] =
                &[$($crate::choice::Name::of($name, &[$($alias),*], $help)),+];
            const VALUES: &'static [Self] = &[$(Self::$var),+];
            const IGNORE_CASE: bool = $ic;
            fn unknown($s: &str) -> $crate::error::Error {
                $err
            }
        }

        impl $ty {
            /// The value's name (its one spelling, in the type's [`choices!`](crate::choices)
            /// list).
            pub const fn name(self) -> &'static str {
                match self {
                    $(Self::$var => $name),+
                }
            }
        }

        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::error::Error;
            fn from_str(s: &str) -> ::std::result::Result<Self, Self::Err> {
                <Self as $crate::choice::Choice>::parse_name(s)
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Fruit {
        Apple,
        Pear,
    }

    crate::choices! {
        Fruit, ignore_case: true,
        unknown: |s| Error::invalid(format!("fruit {s:?} ({})", listed::<Fruit>(", ", " or "))),
        Apple => "apple" | "pomme": "An apple",
        Pear => "pear": "A pear",
    }

    #[test]
    fn names_aliases_case_and_the_message() {
        assert_eq!("apple".parse::<Fruit>().unwrap(), Fruit::Apple);
        assert_eq!("POMME".parse::<Fruit>().unwrap(), Fruit::Apple);
        assert_eq!(Fruit::Pear.to_string(), "pear");
        assert_eq!(Fruit::name_of(Fruit::Pear), "pear");
        let e = "fig".parse::<Fruit>().unwrap_err().to_string();
        assert!(e.contains("fruit \"fig\" (apple or pear)"), "{e}");
        assert_eq!(listed::<Fruit>(", ", ", "), "apple, pear");
    }
}
