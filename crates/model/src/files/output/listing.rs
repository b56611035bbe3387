//! What an output folder holds: every file under it with its size and
//! modification time, so that a command can tell at commit whether the
//! folder it is about to replace is still the one it found.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use super::OutputError;

/// The files under a folder (none when it does not exist), by relative path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Listing {
    files: BTreeMap<PathBuf, (u64, Option<SystemTime>)>,
}

impl Listing {
    /// What `folder` holds now.
    pub fn of(folder: &Path) -> Result<Self, OutputError> {
        let mut listing = Self {
            files: BTreeMap::new(),
        };
        listing.add(folder, Path::new(""))?;
        Ok(listing)
    }

    fn add(&mut self, folder: &Path, relative: &Path) -> Result<(), OutputError> {
        let entries = match std::fs::read_dir(folder) {
            Ok(entries) => entries,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(OutputError::io("read", folder)(e)),
        };
        for entry in entries {
            let entry = entry.map_err(OutputError::io("read", folder))?;
            let name = relative.join(entry.file_name());
            let metadata = entry
                .metadata()
                .map_err(OutputError::io("read", entry.path()))?;
            if metadata.is_dir() {
                self.files.insert(name.clone(), (0, None));
                self.add(&entry.path(), &name)?;
            } else {
                self.files
                    .insert(name, (metadata.len(), metadata.modified().ok()));
            }
        }
        Ok(())
    }

    /// How `folder` differs from this listing now (the first difference,
    /// in words), or `None` when it holds the same files.
    pub fn change_in(&self, folder: &Path) -> Result<Option<String>, OutputError> {
        let now = Self::of(folder)?;
        let show = |path: &PathBuf| folder.join(path).display().to_string();
        for (path, found) in &self.files {
            match now.files.get(path) {
                None => return Ok(Some(format!("{} was removed", show(path)))),
                Some(current) if current != found => {
                    return Ok(Some(format!("{} was changed", show(path))));
                }
                Some(_) => {}
            }
        }
        Ok(now
            .files
            .keys()
            .find(|path| !self.files.contains_key(*path))
            .map(|path| format!("{} was added", show(path))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn added_changed_and_removed_files_are_named() {
        let dir =
            std::env::temp_dir().join(format!("fistage-model-listing-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        std::fs::write(dir.join("a.csv"), "1").expect("write");
        let found = Listing::of(&dir).expect("listing");
        assert_eq!(found.change_in(&dir).expect("read"), None);
        std::fs::write(dir.join("notes.txt"), "mine").expect("write");
        let added = found.change_in(&dir).expect("read").expect("a change");
        assert!(added.contains("notes.txt was added"), "{added}");
        std::fs::remove_file(dir.join("notes.txt")).expect("remove");
        std::fs::write(dir.join("a.csv"), "12").expect("write");
        let changed = found.change_in(&dir).expect("read").expect("a change");
        assert!(changed.contains("a.csv was changed"), "{changed}");
        std::fs::remove_file(dir.join("a.csv")).expect("remove");
        let removed = found.change_in(&dir).expect("read").expect("a change");
        assert!(removed.contains("a.csv was removed"), "{removed}");
        std::fs::remove_dir_all(&dir).ok();
        let gone = Listing::of(&dir).expect("missing folder");
        assert_eq!(gone.change_in(&dir).expect("read"), None);
    }
}
