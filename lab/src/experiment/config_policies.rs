//! The policy lists of the experiment's configuration (`policies`,
//! `[map] policies`), read as typed [`PolicySpec`]s: each string is parsed
//! once, while the file is read, and a bad one is refused there naming its
//! key and the entry; a list over [`MAX_LIST_ENTRIES`] is refused, naming its
//! key and length, before any entry is parsed. The reader's errors are
//! given on one line ([`one_line`]), where it would show a snippet.

use crate::error::Error;
use crate::limits::{check_len, MAX_LIST_ENTRIES};
use crate::trigger::PolicySpec;
use serde::de::Error as _;
use serde::{Deserialize, Deserializer};

/// `policies = [...]`.
pub(super) fn policies<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<PolicySpec>, D::Error> {
    specs(d, "policies")
}

/// `[map] policies = [...]`.
pub(super) fn map_policies<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<PolicySpec>, D::Error> {
    specs(d, "map.policies")
}

/// A list of policy strings under `key`, parsed.
fn specs<'de, D: Deserializer<'de>>(d: D, key: &str) -> Result<Vec<PolicySpec>, D::Error> {
    let list = Vec::<String>::deserialize(d)?;
    check_len(key, list.len(), MAX_LIST_ENTRIES).map_err(D::Error::custom)?;
    list.iter()
        .map(|s| {
            PolicySpec::parse(s).map_err(|e| D::Error::custom(Error::invalid(key, e.to_string())))
        })
        .collect()
}

/// The TOML reader's error on one line: its position (line and column,
/// from 1, as the reader counts them) and its message, without the snippet
/// of the source it shows over several lines.
pub(super) fn one_line(e: &toml::de::Error, text: &str) -> String {
    match e.span().and_then(|s| text.get(..s.start)) {
        Some(before) => {
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            format!(
                "TOML parse error at line {line}, column {column}: {}",
                e.message().trim_end()
            )
        }
        None => format!("TOML parse error: {}", e.message().trim_end()),
    }
}

/// A built-in list of policy strings (the defaults and the demo's), parsed.
/// Each is a constant known to parse (checked by the tests below); one that
/// did not would be left out rather than stop the program.
pub(super) fn builtin(list: &[&str]) -> Vec<PolicySpec> {
    list.iter().filter_map(|s| s.parse().ok()).collect()
}

#[cfg(test)]
mod tests {
    use super::super::config::{ExperimentConfig, MapSection, DEMO_POLICIES};

    #[test]
    fn every_builtin_list_parses_whole() {
        assert_eq!(ExperimentConfig::demo().policies.len(), DEMO_POLICIES.len());
        assert_eq!(ExperimentConfig::default().policies.len(), 12);
        assert_eq!(MapSection::default().policies.len(), 12);
        assert_eq!(MapSection::reduced().policies.len(), 7);
    }
}
