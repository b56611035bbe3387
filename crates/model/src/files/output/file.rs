//! Writing a file the user named: whole or not at all. The bytes go into a
//! hidden file beside the target, are flushed to the disk, and only then is
//! that file renamed over the target; a failure on the way (a full disk, a
//! folder that went away) removes the partial file and leaves whatever the
//! target held before as it was. A rename within one folder is atomic, so a
//! reader sees the old file or the new one, never a mix, and two writers of
//! one path leave one of their files whole.

use std::fs::File;
use std::io::{Error, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `bytes` to `path` whole or not at all (see the module guide).
pub fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let partial = partial_beside(path)?;
    let written = write_and_sync(&partial, bytes).and_then(|()| std::fs::rename(&partial, path));
    if written.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    written
}

/// A hidden name beside `path` that no other writer (process or thread)
/// uses at the same time.
fn partial_beside(path: &Path) -> Result<PathBuf, Error> {
    static SERIAL: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .ok_or_else(|| Error::new(ErrorKind::InvalidInput, "names no file"))?;
    let serial = SERIAL.fetch_add(1, Ordering::Relaxed);
    Ok(path.with_file_name(format!(
        ".{}.partial-{}-{serial}",
        name.to_string_lossy(),
        std::process::id()
    )))
}

fn write_and_sync(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let mut file = File::create(path)?;
    file.write_all(bytes)?;
    file.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("fistage-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder");
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .expect("listed")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_write_replaces_the_file_whole_and_leaves_nothing_beside_it() {
        let dir = scratch("replace");
        let target = dir.join("stage.fmu");
        std::fs::write(&target, "old").expect("written");
        write_whole(&target, b"new contents").expect("replaced");
        assert_eq!(std::fs::read(&target).expect("read"), b"new contents");
        assert_eq!(entries(&dir), ["stage.fmu"]);
        std::fs::remove_dir_all(dir).ok();
    }

    /// The rename fails (the target is a folder holding a file): the earlier
    /// contents stay, and no partial file is left.
    #[test]
    fn a_failed_write_leaves_the_earlier_contents_and_no_partial_file() {
        let dir = scratch("fail");
        let target = dir.join("record.csv");
        std::fs::create_dir_all(&target).expect("a folder in the way");
        std::fs::write(target.join("keep"), "earlier").expect("written");
        assert!(write_whole(&target, b"t_s,f_servo_N,x_m\n").is_err());
        assert_eq!(
            std::fs::read_to_string(target.join("keep")).expect("kept"),
            "earlier"
        );
        assert_eq!(entries(&dir), ["record.csv"]);
        assert!(write_whole(&dir.join("missing/record.csv"), b"x").is_err());
        assert_eq!(entries(&dir), ["record.csv"]);
        std::fs::remove_dir_all(dir).ok();
    }

    /// Writers racing on one path each leave a whole file: the survivor is
    /// one of theirs, never a mix.
    #[test]
    fn racing_writers_leave_one_whole_file() {
        let dir = scratch("race");
        let target = dir.join("out.csv");
        let contents: Vec<Vec<u8>> = (0..8u8).map(|i| vec![b'a' + i; 1 << 16]).collect();
        std::thread::scope(|scope| {
            for bytes in &contents {
                let target = &target;
                scope.spawn(move || write_whole(target, bytes).expect("written"));
            }
        });
        let survivor = std::fs::read(&target).expect("read");
        assert!(contents.contains(&survivor));
        assert_eq!(entries(&dir), ["out.csv"]);
        std::fs::remove_dir_all(dir).ok();
    }
}
