//! Scenario names: built-in names, files and `generated:SEED`, and lists of them.
//!
//! Entry points:
//! - [`Scenario::load`] — a scenario by file path, built-in name or `generated:SEED`.
//! - [`expand_names`] — `generated:0..9` and comma lists to scenario names.

use std::path::Path;

use crate::error::{Error, Result};
use crate::generator::GENERATED_PREFIX;
use crate::scenario::{builtin_text, Scenario};

impl Scenario {
    /// Load a scenario by file path, by built-in name (`paper_simple`, ...), or as
    /// `generated:SEED`, member SEED of the generated benchmark set
    /// ([`crate::generator::benchmark_scenario`]). A name ending in `.json` or containing a
    /// path separator is always read as a file.
    pub fn load(name_or_path: &str) -> Result<Scenario> {
        if Path::new(name_or_path).is_file() || builtin_text(name_or_path).is_some() {
            return Scenario::open(name_or_path);
        }
        if let Some(seed) = name_or_path.strip_prefix(GENERATED_PREFIX) {
            let seed: u64 = seed.parse().map_err(|_| {
                Error::argument(
                    "scenario",
                    name_or_path,
                    "a generated scenario is named generated:SEED with a whole-number seed",
                )
            })?;
            return crate::generator::benchmark_scenario(seed);
        }
        Scenario::open(name_or_path)
    }
}

/// Expand a comma-separated list of names where `generated:A..B` stands for
/// `generated:A`, …, `generated:B` (inclusive).
pub fn expand_names(list: &str) -> Result<Vec<String>> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match item
            .strip_prefix(GENERATED_PREFIX)
            .and_then(|r| r.split_once(".."))
        {
            Some((a, b)) => {
                let bad = || {
                    Error::argument(
                        "scenarios",
                        item,
                        "expected generated:A..B with whole numbers A <= B",
                    )
                };
                let a: u64 = a.parse().map_err(|_| bad())?;
                let b: u64 = b.parse().map_err(|_| bad())?;
                if a > b || b - a > 10_000 {
                    return Err(bad());
                }
                out.extend((a..=b).map(|i| format!("{GENERATED_PREFIX}{i}")));
            }
            None => out.push(item.to_string()),
        }
    }
    Ok(out)
}
