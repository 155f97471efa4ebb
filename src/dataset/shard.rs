//! Sharding: `--shard I/N` (0-based I) keeps the inputs whose stable hash of the relative
//! path is I modulo N. It never depends on positions, so adding or removing files moves only
//! those files, and the N shards partition the inputs exactly.

use super::stable_u64;
use crate::error::{Error, Result};

/// One shard of N.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 0-based shard index, `< count`.
    pub index: u32,
    /// Number of shards, `>= 1`.
    pub count: u32,
}

impl Shard {
    /// The whole input set.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parse `I/N` with `0 <= I < N`.
    pub fn parse(s: &str) -> Result<Shard> {
        let bad = || {
            Error::invalid(format!(
                "--shard {s:?}: expected I/N with 0 <= I < N (e.g. 0/8 .. 7/8)"
            ))
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// True when the input with this relative path belongs to this shard.
    pub fn selects(&self, rel: &str) -> bool {
        self.count <= 1
            || stable_u64(&["shard", rel]) % u64::from(self.count) == u64::from(self.index)
    }

    /// True for the whole set.
    pub fn is_all(&self) -> bool {
        self.count <= 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_partition() {
        assert_eq!(Shard::parse("2/5").unwrap(), Shard { index: 2, count: 5 });
        for bad in ["5/5", "1/0", "x/2", "3", "-1/2", ""] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        let rels: Vec<String> = (0..500).map(|i| format!("d/{i}.dng")).collect();
        let n = 7;
        let mut counts = vec![0usize; n];
        for r in &rels {
            let owners: Vec<u32> = (0..n as u32)
                .filter(|&i| {
                    Shard {
                        index: i,
                        count: n as u32,
                    }
                    .selects(r)
                })
                .collect();
            assert_eq!(owners.len(), 1, "{r}");
            counts[owners[0] as usize] += 1;
        }
        assert!(counts.iter().all(|&c| c > 40), "{counts:?}");
        assert!(Shard::ALL.selects("anything"));
    }
}
