//! Result folders written whole or not at all. A command writes into a fresh
//! staging folder beside the target and moves it into place only when every
//! file is written; a failed command leaves the target as it was (the staging
//! folder is removed). A target that already holds files is an earlier
//! result: it is refused unless the user says `--force`, and then it is
//! replaced as a whole, so no file of the earlier result stays beside the new
//! ones. A long command (a sweep) stages into a journal folder that outlives a
//! failure, so that the next command resumes from it.
//!
//! Two commands never write one folder at once: each holds the folder's
//! lock ([`FolderLock`]) from start to commit, and a second one is refused.
//! The folder's contents when the command started are remembered
//! ([`Listing`]); if they differ at commit (a file put there meanwhile), the
//! folder is left as it is and the new result is kept beside it under a name
//! the error gives.

use std::path::{Path, PathBuf};

use super::OutputError;
use super::listing::Listing;
use super::lock::FolderLock;

/// A result being written: files go into [`ResultFolder::path`] until
/// [`ResultFolder::commit`] moves them into place.
#[derive(Debug)]
pub struct ResultFolder {
    target: PathBuf,
    staging: PathBuf,
    /// What the target held when the command started.
    found: Listing,
    /// Held until the folder is dropped: no other command writes the target.
    _lock: FolderLock,
    /// Whether the staging folder is a journal that a failed command leaves.
    keep_on_failure: bool,
    committed: bool,
}

impl ResultFolder {
    /// Starts a result for `target`. Refuses a target that is a file, or a
    /// folder holding files, unless `force`.
    pub fn begin(target: &Path, force: bool) -> Result<Self, OutputError> {
        refuse_file(target)?;
        let lock = FolderLock::take(target)?;
        let found = Listing::of(target)?;
        if holds_files(target) && !force {
            return Err(OutputError::EarlierResult(target.to_path_buf()));
        }
        let staging = staging_beside(target, &format!("partial-{}", std::process::id()))?;
        if staging.exists() {
            std::fs::remove_dir_all(&staging).map_err(OutputError::io("clear", &staging))?;
        }
        std::fs::create_dir(&staging).map_err(OutputError::io("create", &staging))?;
        Ok(Self::staged(target, staging, (lock, found), false))
    }

    /// Starts (or takes up again) a long result for `target` whose staging
    /// folder, `.<name>.journal` beside it, outlives a failed or killed
    /// command, so that the next one resumes from what it holds. The caller
    /// decides what an earlier result in `target` means (see
    /// [`holds_files`]).
    pub fn resumable(target: &Path) -> Result<Self, OutputError> {
        refuse_file(target)?;
        let lock = FolderLock::take(target)?;
        let found = Listing::of(target)?;
        let staging = staging_beside(target, "journal")?;
        std::fs::create_dir_all(&staging).map_err(OutputError::io("create", &staging))?;
        Ok(Self::staged(target, staging, (lock, found), true))
    }

    fn staged(
        target: &Path,
        staging: PathBuf,
        (lock, found): (FolderLock, Listing),
        keep_on_failure: bool,
    ) -> Self {
        Self {
            target: target.to_path_buf(),
            staging,
            found,
            _lock: lock,
            keep_on_failure,
            committed: false,
        }
    }

    /// Where the files go while the result is written.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Moves the finished result into place, replacing an earlier one whole,
    /// if the target still holds what it held when the command started;
    /// otherwise keeps the result beside it and says where.
    pub fn commit(mut self) -> Result<PathBuf, OutputError> {
        if let Some(change) = self.found.change_in(&self.target)? {
            return Err(self.keep_beside(change));
        }
        let earlier = self.staging.with_extension("earlier");
        if self.target.exists() {
            std::fs::rename(&self.target, &earlier)
                .map_err(OutputError::io("move aside the earlier", &self.target))?;
        }
        if let Err(e) = std::fs::rename(&self.staging, &self.target) {
            // Put the earlier result back: nothing is lost.
            if earlier.exists() {
                let _ = std::fs::rename(&earlier, &self.target);
            }
            return Err(OutputError::io("move the result into", &self.target)(e));
        }
        self.committed = true;
        if earlier.exists() {
            std::fs::remove_dir_all(&earlier)
                .map_err(OutputError::io("remove the earlier result", &earlier))?;
        }
        Ok(self.target.clone())
    }
}

impl ResultFolder {
    /// The target changed under the command: the finished result moves to
    /// a free name beside it, the target stays as it is.
    fn keep_beside(&mut self, change: String) -> OutputError {
        let name = self
            .target
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        let parent = self.staging.parent().unwrap_or(Path::new("."));
        let kept = (0..)
            .map(|k| match k {
                0 => parent.join(format!("{name}.new")),
                k => parent.join(format!("{name}.new-{k}")),
            })
            .find(|path| !path.exists())
            .unwrap_or_else(|| parent.join(format!("{name}.new")));
        let kept = match std::fs::rename(&self.staging, &kept) {
            Ok(()) => {
                self.committed = true;
                Ok(kept)
            }
            Err(e) => Err(e.to_string()),
        };
        OutputError::Changed {
            target: self.target.clone(),
            change,
            kept,
        }
    }
}

/// `out/<scenario stem>-<command>`, the folder a command writes without `--out`.
pub fn default_folder(scenario: &Path, command: &str) -> PathBuf {
    let stem = scenario
        .file_stem()
        .map_or(command.into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from("out").join(format!("{stem}-{command}"))
}

/// Whether `target` is a folder that holds any file (an earlier result).
pub fn holds_files(target: &Path) -> bool {
    std::fs::read_dir(target).is_ok_and(|mut entries| entries.next().is_some())
}

fn refuse_file(target: &Path) -> Result<(), OutputError> {
    if target.is_file() {
        return Err(OutputError::IsAFile(target.to_path_buf()));
    }
    Ok(())
}

/// `.<name>.<tag>` in the target's parent folder (made if missing), on the
/// same file system as the target, so that moving it into place is a rename.
pub fn staging_beside(target: &Path, tag: &str) -> Result<PathBuf, OutputError> {
    let parent = match target.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(OutputError::io("create", &parent))?;
    let name = target
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    Ok(parent.join(format!(".{name}.{tag}")))
}

impl Drop for ResultFolder {
    fn drop(&mut self) {
        if !self.committed && !self.keep_on_failure {
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fistage-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        dir
    }

    #[test]
    fn a_result_replaces_an_earlier_one_whole_and_only_when_forced() {
        let dir = scratch("replace");
        let target = dir.join("out");
        let first = ResultFolder::begin(&target, false).expect("new folder");
        std::fs::write(first.path().join("a.csv"), "1").expect("write");
        std::fs::write(first.path().join("plot.svg"), "<svg/>").expect("write");
        first.commit().expect("commit");
        assert!(
            ResultFolder::begin(&target, false).is_err(),
            "an earlier result is refused"
        );
        let second = ResultFolder::begin(&target, true).expect("forced");
        std::fs::write(second.path().join("a.csv"), "2").expect("write");
        second.commit().expect("commit");
        assert_eq!(std::fs::read_to_string(target.join("a.csv")).unwrap(), "2");
        assert!(
            !target.join("plot.svg").exists(),
            "no stale file from the earlier result"
        );
        let leftovers: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(leftovers.len(), 1, "no staging folder left behind");
    }

    #[test]
    fn a_failed_result_leaves_the_earlier_one_untouched() {
        let dir = scratch("failed");
        let target = dir.join("out");
        std::fs::create_dir_all(&target).expect("folder");
        std::fs::write(target.join("keep.csv"), "old").expect("write");
        {
            let partial = ResultFolder::begin(&target, true).expect("forced");
            std::fs::write(partial.path().join("keep.csv"), "half").expect("write");
            // Dropped without commit: the command failed.
        }
        assert_eq!(
            std::fs::read_to_string(target.join("keep.csv")).unwrap(),
            "old"
        );
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    }
}
