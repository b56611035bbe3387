//! What the program writes for a user, whole or not at all: single files
//! ([`write_whole`]) and result folders ([`ResultFolder`]), with the lock
//! that keeps two writers out of one folder and the listing that tells
//! whether a folder changed while a result was being written.

mod file;
mod folder;
mod listing;
mod lock;

use std::path::PathBuf;

pub use file::write_whole;
pub use folder::{ResultFolder, default_folder, holds_files, staging_beside};

/// Why a result could not be written; every variant names the path.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file-system call failed.
    #[error("cannot {action} {}: {source}", path.display())]
    Io {
        /// What was being done ("create", "read", "remove", ...).
        action: &'static str,
        /// On which path.
        path: PathBuf,
        /// The system's reason.
        source: std::io::Error,
    },
    /// The output names a file, not a folder.
    #[error("{}: is a file, not an output folder; name a folder with --out", .0.display())]
    IsAFile(PathBuf),
    /// The folder holds an earlier result and replacing it was not asked for.
    #[error(
        "{}: holds an earlier result; give --force to replace it (force=True in Python), or choose another folder with --out",
        .0.display()
    )]
    EarlierResult(PathBuf),
    /// Another command (or thread) is writing the folder now.
    #[error(
        "{}: another command is writing this folder now (its lock is {}); wait for it, or choose another --out",
        target.display(),
        lock.display()
    )]
    Locked {
        /// The folder.
        target: PathBuf,
        /// Its lock file.
        lock: PathBuf,
    },
    /// The folder changed while the result was written: it was left alone.
    #[error(
        "{}: changed while this command ran ({change}); it was left as it is, and {}",
        target.display(),
        match kept {
            Ok(kept) => format!("the new result is in {}", kept.display()),
            Err(why) => format!("the new result could not be kept beside it ({why})"),
        }
    )]
    Changed {
        /// The folder.
        target: PathBuf,
        /// The first change found, in words.
        change: String,
        /// Where the new result went, or why it could not be kept.
        kept: Result<PathBuf, String>,
    },
}

impl OutputError {
    /// A failed file-system call on `path`.
    pub fn io(
        action: &'static str,
        path: impl Into<PathBuf>,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| Self::Io {
            action,
            path,
            source,
        }
    }
}
