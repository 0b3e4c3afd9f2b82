//! `--shard K/N`: one of N disjoint, deterministic slices of a campaign, so that a long
//! campaign can be spread over a CI system's own job matrix (and folded back together by
//! [`crate::fuzz::merge`]). No scheduler: each machine works out its slice from K and N.
//!
//! `gcl fuzz host` slices run indices: shard K runs indices K-1, K-1+N, K-1+2N, ...
//! `gcl fuzz device` slices generator streams: its worker w draws from stream K-1+w·N, the
//! stream worker K-1+w·N of a one-machine campaign with N times the workers would draw from.

use std::fmt;
use std::str::FromStr;

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    /// K, from 1 to N.
    pub index: u64,
    /// N, at least 1.
    pub count: u64,
}

impl Shard {
    /// The campaign's index of this shard's `t`-th item (0-based).
    pub fn global(self, t: u64) -> u64 {
        t.saturating_mul(self.count).saturating_add(self.index - 1)
    }

    /// Whether campaign index `i` is this shard's.
    pub fn owns(self, i: u64) -> bool {
        i % self.count == self.index - 1
    }

    /// How many of the campaign's indices `0..total` are this shard's.
    pub fn share(self, total: u64) -> u64 {
        (total + self.count - self.index) / self.count
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}`: write a shard as K/N, with 1 <= K <= N (1/4 is the first of four)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (u64, u64) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_indices() {
        let n = 4;
        let shards: Vec<Shard> = (1..=n).map(|k| format!("{k}/{n}").parse().unwrap()).collect();
        for i in 0..40u64 {
            assert_eq!(shards.iter().filter(|s| s.owns(i)).count(), 1, "index {i}");
        }
        for s in &shards {
            let mine: Vec<u64> = (0..10).map(|t| s.global(t)).collect();
            assert!(mine.iter().all(|&i| s.owns(i)));
            assert_eq!(s.share(10), (0..10).filter(|&i| s.owns(i)).count() as u64);
        }
        assert_eq!(shards.iter().map(|s| s.share(10)).sum::<u64>(), 10);
    }

    #[test]
    fn bad_shards_are_refused() {
        for s in ["0/4", "5/4", "1/0", "4", "a/b", "1/-2"] {
            assert!(s.parse::<Shard>().is_err(), "{s}");
        }
        assert_eq!("2/3".parse::<Shard>().unwrap().to_string(), "2/3");
    }
}
