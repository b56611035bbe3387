//! A minimal ZIP writer for FMU archives: stored (uncompressed) entries with
//! CRC-32, local headers, a central directory and its end record. Every
//! importer reads stored entries; archives stay small enough (the library
//! dominates) that compression is not worth a dependency.

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320).
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut table = [0u32; 256];
    for (i, entry) in table.iter_mut().enumerate() {
        let mut c = i as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
        *entry = c;
    }
    !bytes.iter().fold(!0u32, |crc, &b| {
        table[((crc ^ u32::from(b)) & 0xff) as usize] ^ (crc >> 8)
    })
}

struct Entry {
    name: String,
    crc: u32,
    size: u32,
    offset: u32,
}

/// Builds a ZIP archive in memory.
#[derive(Default)]
pub struct ZipWriter {
    bytes: Vec<u8>,
    entries: Vec<Entry>,
}

/// 1980-01-01 00:00 in MS-DOS date/time form: archives do not depend on when they were built.
const DOS_TIME: u16 = 0;
const DOS_DATE: u16 = (1 << 5) | 1;

impl ZipWriter {
    fn u16(&mut self, v: u16) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    fn u32(&mut self, v: u32) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }

    /// Adds a file (stored). Names use `/` separators.
    pub fn add(&mut self, name: &str, data: &[u8]) {
        let entry = Entry {
            name: name.to_string(),
            crc: crc32(data),
            size: data.len() as u32,
            offset: self.bytes.len() as u32,
        };
        self.u32(0x0403_4b50);
        self.u16(20); // version needed: 2.0
        self.u16(0x0800); // flags: UTF-8 names
        self.u16(0); // method: stored
        self.u16(DOS_TIME);
        self.u16(DOS_DATE);
        self.u32(entry.crc);
        self.u32(entry.size);
        self.u32(entry.size);
        self.u16(entry.name.len() as u16);
        self.u16(0);
        self.bytes.extend_from_slice(entry.name.as_bytes());
        self.bytes.extend_from_slice(data);
        self.entries.push(entry);
    }

    /// The finished archive.
    pub fn finish(mut self) -> Vec<u8> {
        let directory_start = self.bytes.len() as u32;
        let entries = std::mem::take(&mut self.entries);
        for entry in &entries {
            self.u32(0x0201_4b50);
            self.u16(0x031e); // made by: Unix, 3.0
            self.u16(20);
            self.u16(0x0800);
            self.u16(0);
            self.u16(DOS_TIME);
            self.u16(DOS_DATE);
            self.u32(entry.crc);
            self.u32(entry.size);
            self.u32(entry.size);
            self.u16(entry.name.len() as u16);
            self.u16(0); // extra
            self.u16(0); // comment
            self.u16(0); // disk
            self.u16(0); // internal attributes
            self.u32(0o100644 << 16); // external: regular file, rw-r--r--
            self.u32(entry.offset);
            self.bytes.extend_from_slice(entry.name.as_bytes());
        }
        let directory_size = self.bytes.len() as u32 - directory_start;
        self.u32(0x0605_4b50);
        self.u16(0);
        self.u16(0);
        self.u16(entries.len() as u16);
        self.u16(entries.len() as u16);
        self.u32(directory_size);
        self.u32(directory_start);
        self.u16(0);
        self.bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_standard_check_string() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn archive_lists_entries_in_its_central_directory() {
        let mut zip = ZipWriter::default();
        zip.add("a.txt", b"hello");
        zip.add("dir/b.bin", &[0, 1, 2]);
        let bytes = zip.finish();
        let end = bytes.len() - 22;
        assert_eq!(&bytes[end..end + 4], &0x0605_4b50u32.to_le_bytes());
        assert_eq!(u16::from_le_bytes([bytes[end + 10], bytes[end + 11]]), 2);
        let start = u32::from_le_bytes(bytes[end + 16..end + 20].try_into().unwrap()) as usize;
        assert_eq!(&bytes[start..start + 4], &0x0201_4b50u32.to_le_bytes());
        assert_eq!(&bytes[30..35], b"a.txt");
        assert_eq!(&bytes[35..40], b"hello");
    }
}
