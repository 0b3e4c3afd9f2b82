//! What a report folded from shards holds (`gcl fuzz merge`): which shards, of how many.

use serde::{Deserialize, Serialize};

/// The slices a merged folder holds.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Merged {
    /// N: the campaign's number of shards.
    pub count: u64,
    /// The K of every shard folded, ascending.
    pub shards: Vec<u64>,
}

impl Merged {
    /// The shards of the campaign not folded.
    pub fn missing(&self) -> Vec<u64> {
        (1..=self.count).filter(|k| !self.shards.contains(k)).collect()
    }

    /// Whether every shard of the campaign was folded.
    pub fn complete(&self) -> bool {
        self.missing().is_empty()
    }

    /// `shards 1–4 of 4`, or `shards 1, 3 of 4 (INCOMPLETE: 2 and 4 missing)`.
    pub fn describe(&self) -> String {
        let missing = self.missing();
        let mut s = format!(
            "shard{} {} of {}",
            if self.shards.len() == 1 { "" } else { "s" },
            ranges(&self.shards),
            self.count
        );
        if !missing.is_empty() {
            s.push_str(&format!(
                " (INCOMPLETE: {} missing, {} runs are not in it)",
                ranges(&missing),
                if missing.len() == 1 { "its" } else { "their" }
            ));
        }
        s
    }
}

/// `1–4`, `1, 3`, `1–2, 5`: ascending numbers, runs of three or more as ranges.
fn ranges(ks: &[u64]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < ks.len() {
        let mut j = i;
        while j + 1 < ks.len() && ks[j + 1] == ks[j] + 1 {
            j += 1;
        }
        match j - i {
            0 => parts.push(ks[i].to_string()),
            1 => parts.extend([ks[i].to_string(), ks[j].to_string()]),
            _ => parts.push(format!("{}–{}", ks[i], ks[j])),
        }
        i = j + 1;
    }
    parts.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_of_three_or_more_are_ranges() {
        assert_eq!(ranges(&[1, 2, 5, 7, 8, 9]), "1, 2, 5, 7–9");
    }
}
