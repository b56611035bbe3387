//! Reading a user's input file: only a regular file, and only up to a size
//! limit checked before anything is read, so that a device (`/dev/zero`), a
//! pipe or a folder named as a robot, scenario or data file is a clear error
//! instead of an endless read.

use std::io::{Error, ErrorKind};
use std::path::Path;

/// Bytes a robot or scenario file may hold.
pub const MAX_DESCRIPTION_BYTES: u64 = 64 << 20;
/// Bytes a data file (a reference or identification CSV file) may hold.
pub const MAX_DATA_BYTES: u64 = 4 << 30;

/// The text of `path`, refused (as an I/O error saying why) unless it is a
/// regular file of at most `limit` bytes.
pub fn read_text(path: &Path, limit: u64) -> Result<String, Error> {
    if path.as_os_str().is_empty() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "the file name is empty",
        ));
    }
    let metadata = std::fs::metadata(path)?;
    if metadata.is_dir() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is a folder, not a file",
        ));
    }
    if !metadata.is_file() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is not a regular file (a device or a pipe)",
        ));
    }
    if metadata.len() > limit {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "holds {} bytes, more than the {limit} such a file may",
                metadata.len()
            ),
        ));
    }
    std::fs::read_to_string(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_folders_and_empty_names_are_refused() {
        let message = |path: &str| read_text(Path::new(path), 1 << 20).unwrap_err().to_string();
        assert!(message("/dev/zero").contains("not a regular file"));
        assert!(message("/tmp").contains("folder"));
        assert!(message("").contains("empty"));
        let file = std::env::temp_dir().join(format!("fistage-input-{}.txt", std::process::id()));
        std::fs::write(&file, "0123456789").unwrap();
        assert_eq!(read_text(&file, 10).unwrap(), "0123456789");
        assert!(
            read_text(&file, 9)
                .unwrap_err()
                .to_string()
                .contains("more than the 9")
        );
        let _ = std::fs::remove_file(&file);
    }
}
