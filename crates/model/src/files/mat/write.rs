//! MAT-files of signal tables, as MATLAB's `save` writes them by default
//! (version 7: the Level 5 format with every variable compressed), for
//! MATLAB, Octave and `scipy.io.loadmat`.
//!
//! The file holds `time` (s) and one column vector per signal, each named
//! by a valid MATLAB identifier made from the signal's name (`encoder.position`
//! becomes `encoder_position`; see [`matlab_names`]), and `signals`, an
//! n x 3 cell array of the variable name, the original signal name and its
//! unit for every signal (`time` first).
//!
//! Layout (MAT-File Format, Level 5): a 128-byte header (text, subsystem
//! offset, version 0x0100, endian mark `IM`), then one `miCOMPRESSED`
//! element per variable holding the zlib stream of its `miMATRIX` element:
//! array flags, dimensions, name, data. Every element is padded to 8 bytes.

use std::io::{self, Write};

use flate2::Compression;
use flate2::write::ZlibEncoder;

const MI_INT8: u32 = 1;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_DOUBLE: u32 = 9;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MX_CELL_CLASS: u32 = 1;
const MX_CHAR_CLASS: u32 = 4;
const MX_DOUBLE_CLASS: u32 = 6;
/// The longest variable name MATLAB accepts.
const MAX_NAME: usize = 63;

/// A MATLAB value this writer can hold.
enum Value<'a> {
    /// A real column vector.
    Column(&'a [f64]),
    /// A 1 x n character array.
    Text(&'a str),
    /// A rows x columns cell array, cells in row-major order here.
    Cells(usize, usize, Vec<Value<'a>>),
}

/// Valid, distinct MATLAB identifiers for `names`, none equal to a name in
/// `taken`: characters other than letters, digits and `_` become `_`, a
/// name not starting with a letter gets the prefix `x`, names are cut to
/// 63 characters, and a repeated name gets `_2`, `_3`, ...
pub fn matlab_names(names: &[String], taken: &[&str]) -> Vec<String> {
    let mut used: Vec<String> = taken.iter().map(|s| s.to_string()).collect();
    names
        .iter()
        .map(|name| {
            let mut base: String = name
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            if !base.starts_with(|c: char| c.is_ascii_alphabetic()) {
                base.insert(0, 'x');
            }
            base.truncate(MAX_NAME);
            let mut candidate = base.clone();
            let mut k = 2;
            while used.contains(&candidate) {
                let suffix = format!("_{k}");
                let mut stem = base.clone();
                stem.truncate(MAX_NAME - suffix.len());
                candidate = stem + &suffix;
                k += 1;
            }
            used.push(candidate.clone());
            candidate
        })
        .collect()
}

/// A table of signals on one time grid, as the MAT-file holds it.
#[derive(Debug, Clone, Copy)]
pub struct Signals<'a> {
    /// Sample times, s.
    pub times: &'a [f64],
    /// Signal names (any text; the variables get [`matlab_names`]).
    pub names: &'a [String],
    /// Their units.
    pub units: &'a [String],
    /// One column of samples per signal.
    pub columns: &'a [Vec<f64>],
}

impl Signals<'_> {
    /// Writes the table as a version 7 MAT-file (see the module guide).
    pub fn write_mat<W: Write>(&self, out: &mut W) -> io::Result<()> {
        out.write_all(&header())?;
        let names = matlab_names(self.names, &["time", "signals"]);
        write_variable(out, "time", &Value::Column(self.times))?;
        for (name, column) in names.iter().zip(self.columns) {
            write_variable(out, name, &Value::Column(column))?;
        }
        let mut cells = vec![Value::Text("time"), Value::Text("time"), Value::Text("s")];
        for ((name, original), unit) in names.iter().zip(self.names).zip(self.units) {
            cells.extend([Value::Text(name), Value::Text(original), Value::Text(unit)]);
        }
        let rows = cells.len() / 3;
        write_variable(out, "signals", &Value::Cells(rows, 3, cells))
    }
}

/// Writes named column vectors as a version 7 MAT-file; the names must be
/// valid MATLAB identifiers (see [`matlab_names`]).
pub fn write_columns<W: Write>(out: &mut W, columns: &[(&str, &[f64])]) -> io::Result<()> {
    out.write_all(&header())?;
    for (name, column) in columns {
        write_variable(out, name, &Value::Column(column))?;
    }
    Ok(())
}

/// The 128-byte header.
fn header() -> Vec<u8> {
    let text = format!(
        "MATLAB 5.0 MAT-file, written by fistage {}",
        env!("CARGO_PKG_VERSION")
    );
    let mut bytes = text.into_bytes();
    bytes.resize(116, b' ');
    bytes.extend([0u8; 8]);
    bytes.extend(0x0100u16.to_le_bytes());
    bytes.extend(*b"IM");
    bytes
}

/// One variable, compressed.
fn write_variable<W: Write>(out: &mut W, name: &str, value: &Value) -> io::Result<()> {
    let mut matrix = Vec::new();
    matrix_element(&mut matrix, name, value);
    let mut encoder = ZlibEncoder::new(Vec::new(), Compression::default());
    encoder.write_all(&matrix)?;
    let compressed = encoder.finish()?;
    let size = u32::try_from(compressed.len())
        .map_err(|_| io::Error::other(format!("variable {name} is too large for a MAT-file")))?;
    out.write_all(&MI_COMPRESSED.to_le_bytes())?;
    out.write_all(&size.to_le_bytes())?;
    out.write_all(&compressed)
}

/// A tagged element: type, byte count, data, padding to 8 bytes.
fn element(buffer: &mut Vec<u8>, kind: u32, data: &[u8]) {
    buffer.extend(kind.to_le_bytes());
    buffer.extend((data.len() as u32).to_le_bytes());
    buffer.extend(data);
    buffer.resize(buffer.len().next_multiple_of(8), 0);
}

/// An `miMATRIX` element: flags, dimensions, name, data.
fn matrix_element(buffer: &mut Vec<u8>, name: &str, value: &Value) {
    let mut body = Vec::new();
    let (class, rows, columns) = match value {
        Value::Column(values) => (MX_DOUBLE_CLASS, values.len(), 1),
        Value::Text(text) => (MX_CHAR_CLASS, 1, text.encode_utf16().count()),
        Value::Cells(rows, columns, _) => (MX_CELL_CLASS, *rows, *columns),
    };
    let flags: Vec<u8> = [class, 0].iter().flat_map(|v| v.to_le_bytes()).collect();
    element(&mut body, MI_UINT32, &flags);
    let dims: Vec<u8> = [rows as i32, columns as i32]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    element(&mut body, MI_INT32, &dims);
    element(&mut body, MI_INT8, name.as_bytes());
    match value {
        Value::Column(values) => {
            let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
            element(&mut body, MI_DOUBLE, &data);
        }
        Value::Text(text) => {
            let data: Vec<u8> = text.encode_utf16().flat_map(|c| c.to_le_bytes()).collect();
            element(&mut body, MI_UINT16, &data);
        }
        Value::Cells(rows, columns, cells) => {
            // Column-major, as MATLAB stores every array.
            for column in 0..*columns {
                for row in 0..*rows {
                    matrix_element(&mut body, "", &cells[row * columns + column]);
                }
            }
        }
    }
    buffer.extend(MI_MATRIX.to_le_bytes());
    buffer.extend((body.len() as u32).to_le_bytes());
    buffer.extend(body);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_valid_and_distinct() {
        let names: Vec<String> = ["encoder.position", "encoder-position", "1st", "time", "_z"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let made = matlab_names(&names, &["time", "signals"]);
        assert_eq!(
            made,
            [
                "encoder_position",
                "encoder_position_2",
                "x1st",
                "time_2",
                "x_z"
            ]
        );
        let long = vec!["a".repeat(80), "a".repeat(80)];
        let made = matlab_names(&long, &[]);
        assert!(made.iter().all(|n| n.len() <= MAX_NAME), "{made:?}");
        assert_ne!(made[0], made[1]);
    }

    /// The layout a Level 5 reader walks: header, then tagged compressed
    /// elements whose byte counts add up to the file.
    #[test]
    fn elements_tile_the_file() {
        let table = Signals {
            names: &["encoder.position".into()],
            units: &["m".into()],
            times: &[0.0, 0.1, 0.2],
            columns: &[vec![1.0, 2.0, 3.0]],
        };
        let mut bytes = Vec::new();
        table.write_mat(&mut bytes).expect("written");
        assert_eq!(&bytes[124..128], &[0x00, 0x01, b'I', b'M']);
        let mut at = 128;
        let mut variables = 0;
        while at < bytes.len() {
            let kind = u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
            let size = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().expect("4 bytes"));
            assert_eq!(kind, MI_COMPRESSED);
            at += 8 + size as usize;
            variables += 1;
        }
        assert_eq!(
            (at, variables),
            (bytes.len(), 3),
            "time, one signal, signals"
        );
    }
}
