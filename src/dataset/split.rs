//! Train/val split, deterministic: `--val N` puts the last N inputs (by sorted relative
//! path) in val, as the paper did (first 60 train, last 10 val); `--val-fraction F` puts an
//! input in val when a seeded hash of its relative path falls below F, so the split of a
//! file never depends on which other files exist or on its position.

use super::{discover::Input, stable_u64};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which split an input belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    /// Training set.
    Train,
    /// Validation set.
    Val,
    /// Real captures (`real-pairs`, docs/real-pairs.md): neither split of a synthetic run.
    Real,
}

impl Split {
    /// Folder name: `train`, `val` or `real`.
    pub fn name(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Val => "val",
            Split::Real => "real",
        }
    }
}

/// How to split.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SplitRule {
    /// Everything is train.
    AllTrain,
    /// The last N by sorted relative path are val.
    LastN(usize),
    /// Val with probability F, by a hash of (seed, relative path).
    Fraction {
        /// Fraction in [0, 1].
        fraction: f64,
        /// Seed of the hash.
        seed: u64,
    },
}

/// Split of every input (`inputs` sorted by relative path, as `discover` returns them).
pub fn assign(inputs: &[Input], rule: SplitRule) -> Result<Vec<Split>> {
    match rule {
        SplitRule::AllTrain => Ok(vec![Split::Train; inputs.len()]),
        SplitRule::LastN(n) => {
            if n > inputs.len() {
                return Err(Error::invalid(format!(
                    "--val {n} but only {} inputs were found",
                    inputs.len()
                )));
            }
            let first_val = inputs.len() - n;
            Ok((0..inputs.len())
                .map(|i| {
                    if i >= first_val {
                        Split::Val
                    } else {
                        Split::Train
                    }
                })
                .collect())
        }
        SplitRule::Fraction { fraction, seed } => {
            if !(0.0..=1.0).contains(&fraction) {
                return Err(Error::invalid(format!(
                    "--val-fraction {fraction} is not within [0, 1]"
                )));
            }
            Ok(inputs
                .iter()
                .map(|inp| {
                    let h = stable_u64(&["split", &seed.to_string(), &inp.rel]);
                    // Top 53 bits as a uniform number in [0, 1).
                    let u = (h >> 11) as f64 / (1u64 << 53) as f64;
                    if u < fraction {
                        Split::Val
                    } else {
                        Split::Train
                    }
                })
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn inputs(n: usize) -> Vec<Input> {
        (0..n)
            .map(|i| Input {
                rel: format!("img_{i:04}.dng"),
                path: PathBuf::from(format!("img_{i:04}.dng")),
            })
            .collect()
    }

    #[test]
    fn last_n_is_the_paper_split() {
        let s = assign(&inputs(70), SplitRule::LastN(10)).unwrap();
        assert_eq!(s.iter().filter(|&&x| x == Split::Train).count(), 60);
        assert!(s[..60].iter().all(|&x| x == Split::Train));
        assert!(s[60..].iter().all(|&x| x == Split::Val));
        assert!(assign(&inputs(5), SplitRule::LastN(6)).is_err());
        assert_eq!(
            assign(&inputs(3), SplitRule::AllTrain).unwrap(),
            vec![Split::Train; 3]
        );
    }

    #[test]
    fn fraction_is_seeded_positional_free_and_close() {
        let all = inputs(2000);
        let rule = SplitRule::Fraction {
            fraction: 0.2,
            seed: 7,
        };
        let s = assign(&all, rule).unwrap();
        let val = s.iter().filter(|&&x| x == Split::Val).count();
        assert!((340..460).contains(&val), "{val}");
        // A file's split does not depend on the others.
        let sub: Vec<Input> = all.iter().step_by(3).cloned().collect();
        let s2 = assign(&sub, rule).unwrap();
        for (k, inp) in sub.iter().enumerate() {
            let i = all.iter().position(|a| a.rel == inp.rel).unwrap();
            assert_eq!(s2[k], s[i]);
        }
        // Another seed gives another split.
        let s3 = assign(
            &all,
            SplitRule::Fraction {
                fraction: 0.2,
                seed: 8,
            },
        )
        .unwrap();
        assert_ne!(s, s3);
        assert!(assign(
            &all,
            SplitRule::Fraction {
                fraction: 1.5,
                seed: 0
            }
        )
        .is_err());
    }
}
