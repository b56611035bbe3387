//! Reading measured data from CSV files as a lab exports them.
//!
//! The first non-comment line is a header naming the columns; lines starting with
//! `#` are comments; the delimiter is `,`, `;` or a tab (taken from the header);
//! with `;` or tab delimiters a decimal comma is accepted; a UTF-8 byte-order
//! mark (as spreadsheet programs write) is ignored.
//! Each column's unit comes from its name (see [`crate::units`]) or, for a column
//! without a unit, from [`UnitOverrides`] (the `--velocity-unit`-style flags).
//! Values are converted to SI on reading.
//!
//! * f_ss curves need a velocity and a force column.
//! * FRFs need a frequency column and either real and imaginary parts of G, or its
//!   magnitude with an optional phase. When both forms are present the complex one
//!   is used.
//!
//! Every error names the file, the line (1-based physical line, header = line 1
//! when nothing precedes it) with the 1-based data row, and the column.

use std::path::Path;

use crate::Complex;
use crate::error::{IdentError, Result};
use crate::frf::FrfData;
use crate::record::{Record, SensorColumn, StartState};
use crate::stribeck::StribeckData;
use crate::units::{Quantity, Unit};

/// Units for columns whose names carry none (the `--velocity-unit`-style flags).
/// A column that does carry a unit must agree with the flag.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UnitOverrides {
    /// Unit of an unsuffixed velocity column.
    pub velocity: Option<Unit>,
    /// Unit of an unsuffixed force column.
    pub force: Option<Unit>,
    /// Unit of an unsuffixed frequency column.
    pub frequency: Option<Unit>,
    /// Unit of an unsuffixed magnitude column.
    pub magnitude: Option<Unit>,
    /// Unit of an unsuffixed phase column.
    pub phase: Option<Unit>,
    /// Unit of unsuffixed real and imaginary part columns.
    pub response: Option<Unit>,
    /// Unit of an unsuffixed time column (records).
    pub time: Option<Unit>,
    /// Unit of an unsuffixed position column (records).
    pub position: Option<Unit>,
}

impl UnitOverrides {
    /// The override for `quantity`, if any.
    pub fn get(&self, quantity: Quantity) -> Option<Unit> {
        match quantity {
            Quantity::Velocity => self.velocity,
            Quantity::Force => self.force,
            Quantity::Frequency => self.frequency,
            Quantity::Magnitude => self.magnitude,
            Quantity::Phase => self.phase,
            Quantity::RealPart | Quantity::ImagPart => self.response,
            Quantity::Time => self.time,
            Quantity::Position => self.position,
        }
    }
}

/// Reads an f_ss(v) curve: velocity and force columns.
pub fn read_stribeck_csv(path: impl AsRef<Path>, units: &UnitOverrides) -> Result<StribeckData> {
    let (source, text) = read_file(path.as_ref())?;
    parse_stribeck_csv(&source, &text, units)
}

/// Parses an f_ss(v) curve from CSV text; `source` names it in messages.
pub fn parse_stribeck_csv(source: &str, text: &str, units: &UnitOverrides) -> Result<StribeckData> {
    let table = Table::parse(source, text)?;
    let velocity = table.require(Quantity::Velocity, units)?;
    let force = table.require(Quantity::Force, units)?;
    let lines = table.lines();
    let velocities = table.values(&velocity)?;
    let forces = table.values(&force)?;
    Ok(StribeckData {
        source: source.to_string(),
        velocity_column: velocity.name,
        force_column: force.name,
        velocity: velocities,
        force: forces,
        lines,
    })
}

/// Parses a recorded run from CSV text: time, force and position columns
/// (see [`crate::record`] for the conventions); `source` names it in messages.
pub fn parse_record_csv(source: &str, text: &str, units: &UnitOverrides) -> Result<Record> {
    let table = Table::parse(source, text)?;
    let columns = [Quantity::Time, Quantity::Force, Quantity::Position]
        .map(|quantity| table.require(quantity, units));
    let [time, force, position] = columns;
    let [time, force, position] = [time?, force?, position?];
    let record = Record {
        source: source.to_string(),
        rows: table.lines(),
        row_word: "line",
        time: table.values(&time)?,
        force: table.values(&force)?,
        position: table.values(&position)?,
        sensors: table.sensor_columns(&[time.index, force.index, position.index])?,
        columns: [time.name, force.name, position.name],
        start: StartState::default(),
    };
    record.check()?;
    Ok(record)
}

/// Reads an FRF: frequency and either real and imaginary parts or magnitude (and phase).
pub fn read_frf_csv(path: impl AsRef<Path>, units: &UnitOverrides) -> Result<FrfData> {
    let (source, text) = read_file(path.as_ref())?;
    parse_frf_csv(&source, &text, units)
}

/// Parses an FRF from CSV text; `source` names it in messages.
pub fn parse_frf_csv(source: &str, text: &str, units: &UnitOverrides) -> Result<FrfData> {
    let table = Table::parse(source, text)?;
    let frequency = table.require(Quantity::Frequency, units)?;
    let omega = table.values(&frequency)?;
    table.require_positive(&frequency, &omega)?;
    let real = table.locate(Quantity::RealPart, units)?;
    let imag = table.locate(Quantity::ImagPart, units)?;
    let (response, response_column, has_phase) = match (real, imag) {
        (Some(re), Some(im)) => {
            let re_values = table.values(&re)?;
            let im_values = table.values(&im)?;
            let g = re_values
                .iter()
                .zip(&im_values)
                .map(|(&r, &i)| Complex::new(r, i))
                .collect();
            (g, format!("{}, {}", re.name, im.name), true)
        }
        (Some(part), None) | (None, Some(part)) => {
            let missing = if part.quantity == Quantity::RealPart {
                Quantity::ImagPart
            } else {
                Quantity::RealPart
            };
            return Err(IdentError::BadHeader {
                file: source.to_string(),
                line: table.header_line,
                column: part.name,
                message: format!(
                    "a complex FRF needs both parts, but there is no {missing} column (e.g. '{}')",
                    missing.example_column()
                ),
            });
        }
        (None, None) => magnitude_response(&table, units)?,
    };
    Ok(FrfData {
        source: source.to_string(),
        frequency_column: frequency.name,
        response_column,
        omega,
        response,
        has_phase,
        lines: table.lines(),
    })
}

/// Magnitude with optional phase, as complex numbers (phase 0 when absent).
fn magnitude_response(
    table: &Table,
    units: &UnitOverrides,
) -> Result<(Vec<Complex>, String, bool)> {
    let Some(magnitude) = table.locate(Quantity::Magnitude, units)? else {
        return Err(IdentError::MissingColumn {
            file: table.source.clone(),
            line: table.header_line,
            quantity: "FRF response",
            example: "re_G_m_per_N and im_G_m_per_N, or mag_m_per_N with phase_deg",
            found: table.headers.join(", "),
        });
    };
    let mag = table.values(&magnitude)?;
    table.require_positive(&magnitude, &mag)?;
    let phase_column = table.locate(Quantity::Phase, units)?;
    let phase = match &phase_column {
        Some(column) => Some(table.values(column)?),
        None => None,
    };
    let response = mag
        .iter()
        .enumerate()
        .map(|(i, &m)| Complex::from_polar(m, phase.as_ref().map_or(0.0, |p| p[i])))
        .collect();
    let name = match &phase_column {
        Some(p) => format!("{}, {}", magnitude.name, p.name),
        None => magnitude.name.clone(),
    };
    Ok((response, name, phase_column.is_some()))
}

/// Data rows a table may hold: a recorded hour at 10 kHz is 3.6e7.
pub const MAX_ROWS: usize = 50_000_000;
/// Bytes a file may hold, checked before it is read.
const MAX_FILE_BYTES: u64 = 4 << 30;

pub(crate) fn read_file(path: &Path) -> Result<(String, String)> {
    let source = path.display().to_string();
    match fistage_model::input::read_text(path, MAX_FILE_BYTES) {
        Ok(text) => Ok((source, text)),
        Err(e) => Err(IdentError::Io {
            file: source,
            source: e,
        }),
    }
}

/// A located column: its index, its name as written, its quantity and unit.
#[derive(Debug, Clone)]
struct Column {
    index: usize,
    name: String,
    quantity: Quantity,
    unit: Unit,
}

/// How a header cell relates to a quantity.
pub(crate) enum HeaderMatch {
    /// Not a column of that quantity.
    No,
    /// A column of that quantity with this unit (or none written).
    Yes(Option<Unit>),
    /// Named like the quantity, but the rest is not a unit of it.
    BadUnit(String),
}

/// Splits `velocity [mm/s]`, `velocity (mm/s)`, `velocity_mm_per_s` against one stem.
pub(crate) fn match_header(name: &str, quantity: Quantity) -> HeaderMatch {
    let lower = name.trim().to_lowercase();
    let (stem_part, bracket_unit) = split_bracket(&lower);
    let mut bad = None;
    for alias in quantity.aliases() {
        if let Some(unit_text) = bracket_unit {
            if stem_part == *alias {
                return match Unit::parse(quantity, unit_text) {
                    Some(u) => HeaderMatch::Yes(Some(u)),
                    None => HeaderMatch::BadUnit(unit_text.to_string()),
                };
            }
            continue;
        }
        if stem_part == *alias {
            return HeaderMatch::Yes(None);
        }
        let Some(rest) = stem_part.strip_prefix(alias) else {
            continue;
        };
        let Some(unit_text) = rest.strip_prefix(['_', ' ', '/']) else {
            continue;
        };
        match Unit::parse(quantity, unit_text) {
            Some(u) => return HeaderMatch::Yes(Some(u)),
            None => bad = bad.or_else(|| Some(unit_text.to_string())),
        }
    }
    bad.map_or(HeaderMatch::No, HeaderMatch::BadUnit)
}

/// The sensor a further position column reads, and its unit:
/// `("bearing_encoder", nm)` for `bearing_encoder_nm` or `bearing_encoder
/// [nm]`; None for a name without a position unit.
pub(crate) fn sensor_header(name: &str) -> Option<(String, Unit)> {
    let trimmed = name.trim();
    let lower = trimmed.to_lowercase();
    let (stem, unit_text) = match split_bracket(&lower) {
        (stem, Some(unit)) => (stem.to_string(), unit.to_string()),
        (_, None) => {
            let (stem, unit) = lower.rsplit_once(['_', ' '])?;
            (stem.trim().to_string(), unit.to_string())
        }
    };
    let unit = Unit::parse(Quantity::Position, &unit_text)?;
    // The sensor's name as written (names are case sensitive in robot files).
    let sensor = trimmed.get(..stem.len())?.trim().to_string();
    (!sensor.is_empty()).then_some((sensor, unit))
}

/// `("velocity", Some("mm/s"))` for `velocity [mm/s]` or `velocity (mm/s)`.
fn split_bracket(lower: &str) -> (&str, Option<&str>) {
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let (Some(start), true) = (lower.find(open), lower.ends_with(close)) {
            let stem = lower[..start].trim().trim_end_matches('_');
            return (stem, Some(&lower[start + 1..lower.len() - 1]));
        }
    }
    (lower, None)
}

/// The parsed CSV: header and records with their line numbers.
struct Table {
    source: String,
    decimal_comma: bool,
    header_line: u64,
    headers: Vec<String>,
    records: Vec<(u64, csv::StringRecord)>,
}

impl Table {
    fn parse(source: &str, text: &str) -> Result<Table> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let delimiter = detect_delimiter(text);
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .delimiter(delimiter)
            .from_reader(text.as_bytes());
        let csv_error = |e: csv::Error| IdentError::Csv {
            file: source.to_string(),
            line: e.position().map_or(0, |p| p.line()),
            message: e.to_string(),
        };
        let header_record = reader.headers().map_err(csv_error)?.clone();
        let header_line = header_record.position().map_or(1, |p| p.line());
        let headers: Vec<String> = header_record.iter().map(str::to_string).collect();
        if headers.iter().all(|h| h.is_empty()) {
            return Err(IdentError::Csv {
                file: source.to_string(),
                line: header_line,
                message: "no header: the first line must name the columns".to_string(),
            });
        }
        let mut records = Vec::new();
        for record in reader.records() {
            let record = record.map_err(csv_error)?;
            let line = record.position().map_or(0, |p| p.line());
            if record.iter().all(str::is_empty) {
                continue;
            }
            if records.len() == MAX_ROWS {
                return Err(IdentError::Csv {
                    file: source.to_string(),
                    line,
                    message: format!("more than {MAX_ROWS} data rows; thin or split the data"),
                });
            }
            records.push((line, record));
        }
        Ok(Table {
            source: source.to_string(),
            decimal_comma: delimiter != b',',
            header_line,
            headers,
            records,
        })
    }

    /// Every column but `taken` whose name is a sensor's with a position
    /// unit (`bearing_encoder_nm`, `bearing [um]`).
    fn sensor_columns(&self, taken: &[usize]) -> Result<Vec<SensorColumn>> {
        let mut out = Vec::new();
        for (index, name) in self.headers.iter().enumerate() {
            if taken.contains(&index) {
                continue;
            }
            let Some((sensor, unit)) = sensor_header(name) else {
                continue;
            };
            let column = Column {
                index,
                name: name.clone(),
                quantity: Quantity::Position,
                unit,
            };
            out.push(SensorColumn {
                sensor,
                column: name.clone(),
                values: self.values(&column)?,
            });
        }
        Ok(out)
    }

    fn lines(&self) -> Vec<u64> {
        self.records.iter().map(|(line, _)| *line).collect()
    }

    /// The column holding `quantity`, or an error naming what was found.
    fn require(&self, quantity: Quantity, units: &UnitOverrides) -> Result<Column> {
        self.locate(quantity, units)?
            .ok_or_else(|| IdentError::MissingColumn {
                file: self.source.clone(),
                line: self.header_line,
                quantity: quantity.name(),
                example: quantity.example_column(),
                found: self.headers.join(", "),
            })
    }

    /// The column holding `quantity`, if there is one.
    fn locate(&self, quantity: Quantity, units: &UnitOverrides) -> Result<Option<Column>> {
        let mut found: Option<(usize, Option<Unit>)> = None;
        let mut bad_unit: Option<(usize, String)> = None;
        for (index, name) in self.headers.iter().enumerate() {
            match match_header(name, quantity) {
                HeaderMatch::No => {}
                HeaderMatch::BadUnit(text) => {
                    bad_unit.get_or_insert((index, text));
                }
                HeaderMatch::Yes(unit) => {
                    if let Some((first, _)) = found {
                        return Err(self.header_error(
                            index,
                            format!(
                                "ambiguous: both '{}' and this column look like {quantity}; rename one",
                                self.headers[first]
                            ),
                        ));
                    }
                    found = Some((index, unit));
                }
            }
        }
        match (found, bad_unit) {
            (Some((index, unit)), _) => self.resolve_unit(index, quantity, unit, units).map(Some),
            (None, Some((index, text))) => Err(self.header_error(
                index,
                format!(
                    "unknown {quantity} unit '{text}' (known: {})",
                    quantity.known_units()
                ),
            )),
            (None, None) => Ok(None),
        }
    }

    /// Combines the unit in the name with the flag: one of them must say it, and
    /// they must agree when both do.
    fn resolve_unit(
        &self,
        index: usize,
        quantity: Quantity,
        in_name: Option<Unit>,
        units: &UnitOverrides,
    ) -> Result<Column> {
        let flag = units.get(quantity);
        let unit = match (in_name, flag) {
            (Some(a), Some(b)) if a != b => {
                return Err(self.header_error(
                    index,
                    format!("the column says {a} but {} says {b}", quantity.unit_flag()),
                ));
            }
            (Some(u), _) | (None, Some(u)) => u,
            (None, None) => {
                return Err(self.header_error(
                    index,
                    format!(
                        "no unit: name the column like '{}' or pass {} (known: {})",
                        quantity.example_column(),
                        quantity.unit_flag(),
                        quantity.known_units()
                    ),
                ));
            }
        };
        Ok(Column {
            index,
            name: self.headers[index].clone(),
            quantity,
            unit,
        })
    }

    /// The column's values in SI units.
    fn values(&self, column: &Column) -> Result<Vec<f64>> {
        self.records
            .iter()
            .enumerate()
            .map(|(i, (_, record))| {
                let text = record.get(column.index).unwrap_or("");
                let value = self.parse_cell(i, column, text)?;
                Ok(column.unit.to_si(value))
            })
            .collect()
    }

    /// Rejects values <= 0 (in SI, as given in `values`), quoting the cell as written.
    fn require_positive(&self, column: &Column, values: &[f64]) -> Result<()> {
        match values.iter().position(|&v| v <= 0.0) {
            None => Ok(()),
            Some(i) => {
                let text = self.records[i].1.get(column.index).unwrap_or("");
                Err(self.cell_error(
                    i,
                    &column.name,
                    format!(
                        "{} must be > 0, got {text} {}",
                        column.quantity, column.unit
                    ),
                ))
            }
        }
    }

    fn parse_cell(&self, i: usize, column: &Column, text: &str) -> Result<f64> {
        if text.is_empty() {
            return Err(self.cell_error(i, &column.name, "empty cell".to_string()));
        }
        let parsed = match text.parse::<f64>() {
            Err(_) if self.decimal_comma => text.replace(',', ".").parse::<f64>(),
            result => result,
        };
        match parsed {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => {
                Err(self.cell_error(i, &column.name, format!("'{text}' is not a finite number")))
            }
            Err(_) => Err(self.cell_error(i, &column.name, format!("'{text}' is not a number"))),
        }
    }

    fn cell_error(&self, i: usize, column: &str, message: String) -> IdentError {
        IdentError::BadCell {
            file: self.source.clone(),
            line: self.records[i].0,
            row: i + 1,
            column: column.to_string(),
            message,
        }
    }

    fn header_error(&self, index: usize, message: String) -> IdentError {
        IdentError::BadHeader {
            file: self.source.clone(),
            line: self.header_line,
            column: self.headers[index].clone(),
            message,
        }
    }
}

/// `,` unless the header line has more `;` or tabs than commas.
fn detect_delimiter(text: &str) -> u8 {
    let header = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    let count = |c: char| header.matches(c).count();
    let (commas, semicolons, tabs) = (count(','), count(';'), count('\t'));
    if semicolons > commas && semicolons >= tabs {
        b';'
    } else if tabs > commas {
        b'\t'
    } else {
        b','
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stems(name: &str, q: Quantity) -> Option<Option<&'static str>> {
        match match_header(name, q) {
            HeaderMatch::Yes(u) => Some(u.map(|u| u.name())),
            _ => None,
        }
    }

    #[test]
    fn header_forms() {
        assert_eq!(
            stems("velocity_mm_per_s", Quantity::Velocity),
            Some(Some("mm/s"))
        );
        assert_eq!(
            stems("Velocity [mm/s]", Quantity::Velocity),
            Some(Some("mm/s"))
        );
        assert_eq!(stems("v (um/s)", Quantity::Velocity), Some(Some("um/s")));
        assert_eq!(stems("velocity", Quantity::Velocity), Some(None));
        assert_eq!(stems("force_N", Quantity::Force), Some(Some("N")));
        assert_eq!(stems("f_ss_mN", Quantity::Force), Some(Some("mN")));
        assert_eq!(stems("freq_Hz", Quantity::Frequency), Some(Some("Hz")));
        assert_eq!(stems("freq_Hz", Quantity::Force), None);
        assert_eq!(stems("mag_dB", Quantity::Magnitude), Some(Some("dB")));
        assert_eq!(stems("re_G_m_per_N", Quantity::RealPart), Some(Some("m/N")));
        assert_eq!(
            stems("im_G_um_per_N", Quantity::ImagPart),
            Some(Some("um/N"))
        );
        assert_eq!(stems("phase_deg", Quantity::Phase), Some(Some("deg")));
        assert!(matches!(
            match_header("velocity_in_per_s", Quantity::Velocity),
            HeaderMatch::BadUnit(u) if u == "in_per_s"
        ));
    }

    #[test]
    fn semicolons_and_comments() {
        let text = "\u{feff}# exported by the lab\nvelocity_mm_per_s;force_N\n1.5;5.0\n-1,5;-5,0\n";
        let data = parse_stribeck_csv("t.csv", text, &UnitOverrides::default()).unwrap();
        assert_eq!(data.velocity, vec![1.5e-3, -1.5e-3]);
        assert_eq!(data.force, vec![5.0, -5.0]);
        assert_eq!(data.lines, vec![3, 4]);
        let text = "velocity [mm/s]\tforce (N)\n2\t6.1\n";
        let data = parse_stribeck_csv("t.tsv", text, &UnitOverrides::default()).unwrap();
        assert_eq!((data.velocity[0], data.force[0]), (2e-3, 6.1));
    }

    /// A file too large to hold is refused from its size, before it is read
    /// (a sparse file: nothing is written to disk).
    #[test]
    fn a_file_too_large_is_refused_before_it_is_read() {
        let path = std::env::temp_dir().join(format!("fistage-huge-{}.csv", std::process::id()));
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_FILE_BYTES + 1).unwrap();
        let error = read_file(&path).unwrap_err().to_string();
        let _ = std::fs::remove_file(&path);
        assert!(error.contains("more than the 4294967296"), "{error}");
        assert!(error.contains("fistage-huge-"), "{error}");
    }
}
