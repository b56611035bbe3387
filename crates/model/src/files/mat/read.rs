//! Reading MAT-files (Level 5: version 6 uncompressed and version 7
//! compressed, what MATLAB's `save` and `scipy.io.savemat` write), for
//! measured records. Numeric arrays of every class are read as `f64` (MATLAB
//! stores a double array in a smaller integer type when its values allow, so
//! the storage type and the class differ); other classes (cell, struct, char,
//! sparse, objects) are listed by name and class so that a reader can say
//! what a variable is instead of what it is not. Version 7.3 files are HDF5
//! and are refused with the way out (`save -v7`).
//!
//! Layout: a 128-byte header (text, subsystem offset, version, endian mark
//! `IM` or `MI`), then data elements, each an 8-byte tag (type, byte count)
//! or a 4-byte small-element tag, padded to 8 bytes. `miCOMPRESSED` holds
//! the zlib stream of one `miMATRIX` element: array flags, dimensions, name,
//! real part (and imaginary part).

use std::io::Read;

use flate2::read::ZlibDecoder;
use thiserror::Error;

/// The largest decompressed variable read, bytes (64 M doubles: an hour and
/// three quarters of a 10 kHz record in one column): a guard against
/// corrupt or hostile streams that claim or inflate to more. A stream is
/// inflated only up to it, so a small file that would inflate to gigabytes
/// costs no more memory than this.
pub const MAX_VARIABLE_BYTES: u64 = 512 << 20;

/// What can go wrong while reading a MAT-file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MatReadError {
    /// Not a Level 5 MAT-file.
    #[error("not a MAT-file (version 6 or 7): {0}")]
    NotLevel5(String),
    /// A version 7.3 (HDF5) file.
    #[error("a version 7.3 MAT-file (HDF5) cannot be read; save it with `save(file, ..., '-v7')`")]
    Version73,
    /// The file ends inside an element.
    #[error("truncated at byte {offset}: {what}")]
    Truncated {
        /// Byte offset where the element starts.
        offset: usize,
        /// Which element.
        what: String,
    },
    /// An element is malformed.
    #[error("byte {offset}: {what}")]
    Corrupt {
        /// Byte offset of the element (in the decompressed stream for a
        /// compressed variable).
        offset: usize,
        /// What is wrong.
        what: String,
    },
}

/// The contents of one variable.
#[derive(Debug, Clone, PartialEq)]
pub enum MatContent {
    /// A real numeric array, column-major.
    Numeric {
        /// Rows.
        rows: usize,
        /// Columns (the product of all dimensions after the first).
        cols: usize,
        /// The values, column-major, converted to f64.
        data: Vec<f64>,
    },
    /// A complex numeric array (not read further).
    Complex,
    /// Anything else, by its MATLAB class name (`cell`, `struct`, `char`, ...).
    Other(&'static str),
}

/// One variable of a MAT-file.
#[derive(Debug, Clone, PartialEq)]
pub struct MatVariable {
    /// The variable's name.
    pub name: String,
    /// Its contents.
    pub content: MatContent,
}

/// Reads every top-level variable of a Level 5 MAT-file.
pub fn read_variables(bytes: &[u8]) -> Result<Vec<MatVariable>, MatReadError> {
    let order = byte_order(bytes)?;
    let mut variables = Vec::new();
    let mut cursor = Cursor {
        bytes,
        offset: 128,
        order,
    };
    while cursor.offset + 8 <= bytes.len() {
        let start = cursor.offset;
        let (kind, data) = cursor.element()?;
        match kind {
            MI_COMPRESSED => {
                let inflated = inflate(data, start)?;
                let mut inner = Cursor {
                    bytes: &inflated,
                    offset: 0,
                    order,
                };
                let (kind, data) = inner.element()?;
                if kind == MI_MATRIX {
                    variables.push(matrix(data, order)?);
                }
            }
            MI_MATRIX => variables.push(matrix(data, order)?),
            _ => {}
        }
    }
    Ok(variables)
}

const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const COMPLEX_FLAG: u32 = 0x0800;

/// Byte order of the file from its endian mark.
#[derive(Debug, Clone, Copy)]
enum Order {
    Little,
    Big,
}

fn byte_order(bytes: &[u8]) -> Result<Order, MatReadError> {
    if bytes.len() < 128 {
        return Err(MatReadError::NotLevel5(format!(
            "{} bytes, shorter than the 128-byte header",
            bytes.len()
        )));
    }
    if bytes.starts_with(b"MATLAB 7.3") || bytes[512.min(bytes.len() - 8)..].starts_with(b"\x89HDF")
    {
        return Err(MatReadError::Version73);
    }
    match &bytes[126..128] {
        b"IM" => Ok(Order::Little),
        b"MI" => Ok(Order::Big),
        other => Err(MatReadError::NotLevel5(format!(
            "no endian mark at bytes 126-127 (found {other:?}); a version 4 file or not a MAT-file"
        ))),
    }
}

/// A reader over the elements of one stream.
struct Cursor<'a> {
    bytes: &'a [u8],
    offset: usize,
    order: Order,
}

impl<'a> Cursor<'a> {
    fn u32_at(&self, at: usize) -> u32 {
        let b = [
            self.bytes[at],
            self.bytes[at + 1],
            self.bytes[at + 2],
            self.bytes[at + 3],
        ];
        match self.order {
            Order::Little => u32::from_le_bytes(b),
            Order::Big => u32::from_be_bytes(b),
        }
    }

    /// The next element's type and data; moves past it (and its padding).
    fn element(&mut self) -> Result<(u32, &'a [u8]), MatReadError> {
        let start = self.offset;
        let truncated = |what: &str| MatReadError::Truncated {
            offset: start,
            what: what.to_string(),
        };
        if start + 8 > self.bytes.len() {
            return Err(truncated("element tag"));
        }
        let first = self.u32_at(start);
        if first >> 16 != 0 {
            // Small element: type and size in one word, data in the next four bytes.
            let (kind, size) = (first & 0xffff, (first >> 16) as usize);
            if size > 4 {
                return Err(MatReadError::Corrupt {
                    offset: start,
                    what: format!("a small element claims {size} bytes (at most 4)"),
                });
            }
            self.offset = start + 8;
            return Ok((kind, &self.bytes[start + 4..start + 4 + size]));
        }
        let size = self.u32_at(start + 4) as usize;
        let data_start = start + 8;
        let end = data_start
            .checked_add(size)
            .filter(|&e| e <= self.bytes.len())
            .ok_or_else(|| truncated(&format!("an element of {size} bytes")))?;
        // Compressed elements are not padded; everything else is, to 8 bytes.
        self.offset = if first == MI_COMPRESSED {
            end
        } else {
            (end + 7) & !7
        }
        .min(self.bytes.len());
        Ok((first, &self.bytes[data_start..end]))
    }
}

fn inflate(data: &[u8], offset: usize) -> Result<Vec<u8>, MatReadError> {
    let mut out = Vec::new();
    ZlibDecoder::new(data)
        .take(MAX_VARIABLE_BYTES + 1)
        .read_to_end(&mut out)
        .map_err(|e| MatReadError::Corrupt {
            offset,
            what: format!("compressed variable: {e}"),
        })?;
    if out.len() as u64 > MAX_VARIABLE_BYTES {
        return Err(MatReadError::Corrupt {
            offset,
            what: format!(
                "the compressed variable inflates to more than {} MiB, the most a variable may \
                 hold",
                MAX_VARIABLE_BYTES >> 20
            ),
        });
    }
    Ok(out)
}

/// Reads a `miMATRIX` element's contents.
fn matrix(data: &[u8], order: Order) -> Result<MatVariable, MatReadError> {
    let mut cursor = Cursor {
        bytes: data,
        offset: 0,
        order,
    };
    let corrupt = |offset: usize, what: &str| MatReadError::Corrupt {
        offset,
        what: what.to_string(),
    };
    if data.is_empty() {
        return Ok(MatVariable {
            name: String::new(),
            content: MatContent::Other("empty"),
        });
    }
    let (_, flags) = cursor.element()?;
    if flags.len() < 4 {
        return Err(corrupt(0, "array flags shorter than 4 bytes"));
    }
    let flag_word = Cursor {
        bytes: flags,
        offset: 0,
        order,
    }
    .u32_at(0);
    let class = flag_word & 0xff;
    let (dims_kind, dims) = cursor.element()?;
    let dims = numbers(dims_kind, dims, order).ok_or_else(|| corrupt(8, "dimensions"))?;
    let (_, name) = cursor.element()?;
    let name = String::from_utf8_lossy(name).into_owned();
    let content = match class_name(class) {
        Some(other) => MatContent::Other(other),
        None if flag_word & COMPLEX_FLAG != 0 => MatContent::Complex,
        None => {
            let at = cursor.offset;
            let (kind, real) = cursor.element()?;
            let values =
                numbers(kind, real, order).ok_or_else(|| corrupt(at, "unknown data type"))?;
            let rows = dims.first().copied().unwrap_or(0.0) as usize;
            let cols = dims.iter().skip(1).product::<f64>() as usize;
            if values.len() != rows * cols {
                return Err(corrupt(
                    at,
                    &format!(
                        "variable '{name}': {} values for dimensions {rows} x {cols}",
                        values.len()
                    ),
                ));
            }
            MatContent::Numeric {
                rows,
                cols,
                data: values,
            }
        }
    };
    Ok(MatVariable { name, content })
}

/// The name of a class that is not a numeric array, or None for numeric classes.
fn class_name(class: u32) -> Option<&'static str> {
    match class {
        1 => Some("cell"),
        2 => Some("struct"),
        3 => Some("object"),
        4 => Some("char"),
        5 => Some("sparse"),
        6..=15 => None,
        16 => Some("function handle"),
        17 => Some("opaque"),
        _ => Some("unknown class"),
    }
}

/// The values of a numeric element as f64, or None for an unknown data type.
fn numbers(kind: u32, data: &[u8], order: Order) -> Option<Vec<f64>> {
    macro_rules! convert {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            data.chunks_exact(N)
                .map(|c| {
                    let mut b = [0u8; N];
                    b.copy_from_slice(c);
                    (match order {
                        Order::Little => <$t>::from_le_bytes(b),
                        Order::Big => <$t>::from_be_bytes(b),
                    }) as f64
                })
                .collect()
        }};
    }
    Some(match kind {
        MI_INT8 => convert!(i8),
        MI_UINT8 => convert!(u8),
        MI_INT16 => convert!(i16),
        MI_UINT16 => convert!(u16),
        MI_INT32 => convert!(i32),
        MI_UINT32 => convert!(u32),
        MI_SINGLE => convert!(f32),
        MI_DOUBLE => convert!(f64),
        MI_INT64 => convert!(i64),
        MI_UINT64 => convert!(u64),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mat::Signals;

    /// The crate's own writer's files read back: names and values.
    #[test]
    fn reads_what_the_writer_writes() {
        let table = Signals {
            times: &[0.0, 0.5, 1.0],
            names: &["table_x.q".into(), "encoder.position".into()],
            units: &["m".into(), "m".into()],
            columns: &[vec![1.0, -2.5, 3.25], vec![1e-9, 2e-9, 7.0]],
        };
        let mut bytes = Vec::new();
        table.write_mat(&mut bytes).expect("in memory");
        let variables = read_variables(&bytes).expect("a version 7 file");
        let get = |name: &str| {
            variables
                .iter()
                .find(|v| v.name == name)
                .map(|v| v.content.clone())
        };
        assert_eq!(
            get("table_x_q"),
            Some(MatContent::Numeric {
                rows: 3,
                cols: 1,
                data: vec![1.0, -2.5, 3.25]
            })
        );
        assert_eq!(
            get("encoder_position"),
            Some(MatContent::Numeric {
                rows: 3,
                cols: 1,
                data: vec![1e-9, 2e-9, 7.0]
            })
        );
        assert_eq!(get("signals"), Some(MatContent::Other("cell")));
    }

    #[test]
    fn refuses_what_is_not_level_5() {
        assert!(matches!(
            read_variables(b"short"),
            Err(MatReadError::NotLevel5(_))
        ));
        let mut hdf = b"MATLAB 7.3 MAT-file".to_vec();
        hdf.resize(1024, 0);
        assert_eq!(read_variables(&hdf), Err(MatReadError::Version73));
        let mut truncated = Vec::new();
        Signals {
            times: &[0.0; 100],
            names: &[],
            units: &[],
            columns: &[],
        }
        .write_mat(&mut truncated)
        .expect("in memory");
        truncated.truncate(140);
        assert!(matches!(
            read_variables(&truncated),
            Err(MatReadError::Truncated { .. })
        ));
    }

    /// A small compressed variable that inflates past the limit (zeros
    /// compress a thousandfold) is refused after inflating no more than the
    /// limit, with the byte it starts at.
    #[test]
    fn a_variable_that_inflates_past_the_limit_is_refused() {
        use flate2::Compression;
        use flate2::write::ZlibEncoder;
        use std::io::Write;
        let mut encoder = ZlibEncoder::new(Vec::new(), Compression::best());
        let zeros = vec![0u8; 1 << 20];
        for _ in 0..(MAX_VARIABLE_BYTES >> 20) + 1 {
            encoder.write_all(&zeros).expect("compressed");
        }
        let stream = encoder.finish().expect("compressed");
        assert!(stream.len() < 2 << 20, "{} bytes", stream.len());
        let mut file = vec![b' '; 128];
        file[124..128].copy_from_slice(&[0x00, 0x01, b'I', b'M']);
        file.extend_from_slice(&15u32.to_le_bytes());
        file.extend_from_slice(&(stream.len() as u32).to_le_bytes());
        file.extend_from_slice(&stream);
        let error = read_variables(&file).expect_err("refused");
        assert!(
            matches!(&error, MatReadError::Corrupt { offset: 128, what } if what.contains("512 MiB")),
            "{error}"
        );
    }
}
