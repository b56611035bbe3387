//! The lock a command holds on the output folder it writes: a hidden file
//! `.<name>.lock` beside the folder, locked with the operating system's
//! advisory file lock, which the system releases when the process ends in
//! any way (so a killed command leaves no lock that refuses the next one).
//! A second command that finds the lock held is refused at once.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::{Path, PathBuf};

use super::{OutputError, staging_beside};

/// The held lock of one output folder; released (and its file removed) on drop.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    file: File,
}

impl FolderLock {
    /// Takes the lock of `target`, or refuses when another command holds it.
    pub fn take(target: &Path) -> Result<Self, OutputError> {
        let path = staging_beside(target, "lock")?;
        // The file a holder removes on release may be the one just opened:
        // then open the new one and lock again.
        for _ in 0..8 {
            let file = OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .open(&path)
                .map_err(OutputError::io("open the lock", &path))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => {
                    return Err(OutputError::Locked {
                        target: target.to_path_buf(),
                        lock: path,
                    });
                }
                Err(TryLockError::Error(e)) => return Err(OutputError::io("lock", &path)(e)),
            }
            if still_at(&file, &path) {
                let mut lock = Self { path, file };
                lock.note_holder();
                return Ok(lock);
            }
        }
        Err(OutputError::Locked {
            target: target.to_path_buf(),
            lock: path,
        })
    }

    /// The holder's process id in the file, for a user wondering who holds it.
    fn note_holder(&mut self) {
        let _ = self.file.set_len(0);
        let _ = writeln!(self.file, "{}", std::process::id());
    }
}

/// Whether `path` still names the file `file` was opened from.
#[cfg(unix)]
fn still_at(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(held), Ok(named)) => held.dev() == named.dev() && held.ino() == named.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn still_at(_file: &File, path: &Path) -> bool {
    path.exists()
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        // Removed while still held, so that no one locks a file that is gone.
        // Elsewhere than Unix an open file cannot be removed: it stays.
        if cfg!(unix) {
            let _ = std::fs::remove_file(&self.path);
        }
        let _ = self.file.unlock();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_until_the_first_lets_go() {
        let dir = std::env::temp_dir().join(format!("fistage-model-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch");
        let target = dir.join("out");
        let first = FolderLock::take(&target).expect("free");
        let refused = FolderLock::take(&target).expect_err("held");
        assert!(refused.to_string().contains("another command"), "{refused}");
        drop(first);
        let again = FolderLock::take(&target).expect("free again");
        drop(again);
        assert_eq!(
            std::fs::read_dir(&dir).expect("dir").count(),
            0,
            "no lock file left behind"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
