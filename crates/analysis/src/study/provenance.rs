//! Where a piece of work came from: every study folder (a sweep's or a
//! tolerance analysis's whole run, shard or resumed journal) holds `provenance.json` with the items that decide its
//! numbers: the program version, the scenario and robot file contents, the
//! grid and the analysis settings, plus which shard it is. Merging and
//! resuming compare them item by item and refuse pieces that differ, naming
//! the first item that does.

use std::collections::BTreeMap;
use std::path::Path;

use fistage_model::output::OutputError;
use serde::{Deserialize, Serialize};

use super::StudyError;

/// The file in every study folder.
pub const PROVENANCE_FILE: &str = "provenance.json";

/// What produced a piece of work.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Provenance {
    /// Items that must agree for pieces to merge, by name.
    pub items: BTreeMap<String, String>,
    /// Which shard (`i/n`), or `all`.
    pub shard: String,
}

/// A short content hash: CRC-32 and length, as hex.
fn content_hash(bytes: &[u8]) -> String {
    format!(
        "crc32 {:08x}, {} bytes",
        crc32fast::hash(bytes),
        bytes.len()
    )
}

impl Provenance {
    /// The provenance of a study of kind `study` (`sweep`, `robust`) of
    /// `scenario_file` (or, when given, the scenario text `scenario_text`
    /// that stands for it) with this grid (or design) and these analysis
    /// settings (their debug form), as shard `shard`.
    pub fn of_study(
        study: &str,
        (scenario_file, scenario_text): (&Path, Option<&[u8]>),
        robot_file: &Path,
        grid: &str,
        analysis: &str,
        shard: Option<(usize, usize)>,
    ) -> Result<Self, StudyError> {
        let read = |file: &Path| std::fs::read(file).map_err(OutputError::io("read", file));
        let scenario = match scenario_text {
            Some(text) => text.to_vec(),
            None => read(scenario_file)?,
        };
        let mut items = BTreeMap::new();
        items.insert(
            "program".to_string(),
            format!("fistage {}", env!("CARGO_PKG_VERSION")),
        );
        items.insert("scenario file".to_string(), content_hash(&scenario));
        items.insert("robot file".to_string(), content_hash(&read(robot_file)?));
        items.insert("study".to_string(), study.to_string());
        items.insert("grid".to_string(), grid.to_string());
        items.insert("analysis settings".to_string(), analysis.to_string());
        Ok(Self {
            items,
            shard: shard.map_or("all".into(), |(i, n)| format!("{i}/{n}")),
        })
    }

    /// Adds the content of another input file under `name` (a comparison's
    /// further cases, say): pieces merge only when it agrees too.
    pub fn with_file(mut self, name: &str, file: &Path) -> Result<Self, StudyError> {
        let bytes = std::fs::read(file).map_err(OutputError::io("read", file))?;
        self.items.insert(name.to_string(), content_hash(&bytes));
        Ok(self)
    }

    /// Adds an item that must agree for pieces to merge (overrides made
    /// outside the files, say).
    pub fn with_item(mut self, name: &str, value: String) -> Self {
        self.items.insert(name.to_string(), value);
        self
    }

    /// Reads a folder's provenance; a folder without one holds no work of
    /// known origin.
    pub fn read(folder: &Path) -> Result<Option<Self>, StudyError> {
        let file = folder.join(PROVENANCE_FILE);
        if !file.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&file).map_err(OutputError::io("read", &file))?;
        let provenance = serde_json::from_str(&text).map_err(|e| StudyError::BadProvenance {
            path: file.clone(),
            why: e.to_string(),
        })?;
        Ok(Some(provenance))
    }

    /// Writes it into a folder.
    pub fn write(&self, folder: &Path) -> Result<(), StudyError> {
        let file = folder.join(PROVENANCE_FILE);
        let text = serde_json::to_string_pretty(self).unwrap_or_default() + "\n";
        Ok(std::fs::write(&file, text).map_err(OutputError::io("write", &file))?)
    }

    /// The kind of study in words, as errors name it.
    fn kind(&self) -> &'static str {
        match self.items.get("study").map(String::as_str) {
            Some("sweep") => "sweep",
            Some("robust") => "tolerance analysis",
            Some("compare") => "comparison",
            _ => "study",
        }
    }

    /// The first item in which `other` differs from this one, if any.
    pub fn first_difference(&self, other: &Self) -> Option<String> {
        let names = self.items.keys().chain(other.items.keys());
        names
            .filter(|name| self.items.get(*name) != other.items.get(*name))
            .min()
            .map(|name| {
                let show = |p: &Self| {
                    p.items
                        .get(name)
                        .cloned()
                        .unwrap_or_else(|| "absent".into())
                };
                format!("{name}: {} here, {} there", show(self), show(other))
            })
    }

    /// Refuses the work (`items`) in `folder` unless it has this
    /// provenance; `advice` says what to do instead.
    pub fn check_folder(
        &self,
        folder: &Path,
        items: &'static str,
        advice: &'static str,
    ) -> Result<Self, StudyError> {
        let Some(theirs) = Self::read(folder)? else {
            return Err(StudyError::UnknownOrigin {
                folder: folder.to_path_buf(),
                items,
                advice,
            });
        };
        if let Some(difference) = self.first_difference(&theirs) {
            return Err(StudyError::OtherWork {
                folder: folder.to_path_buf(),
                kind: self.kind(),
                difference,
                advice,
            });
        }
        Ok(theirs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(grid: &str) -> Provenance {
        let mut items = BTreeMap::new();
        items.insert("study".to_string(), "sweep".to_string());
        items.insert("grid".to_string(), grid.to_string());
        items.insert("program".to_string(), "fistage 0".to_string());
        Provenance {
            items,
            shard: "0/2".into(),
        }
    }

    #[test]
    fn the_first_differing_item_is_named() {
        assert_eq!(sample("a").first_difference(&sample("a")), None);
        let difference = sample("a").first_difference(&sample("b")).expect("differs");
        assert!(
            difference.starts_with("grid: a here, b there"),
            "{difference}"
        );
        let mut shard = sample("a");
        shard.shard = "1/2".into();
        assert_eq!(
            sample("a").first_difference(&shard),
            None,
            "shards differ, work agrees"
        );
    }
}
