//! Reading records from CSV files and from MAT-files (version 6 or 7, as
//! MATLAB's `save` writes them by default). Columns and variables are found
//! by name and unit suffix, the same way in both: `t_s`, `f_servo_N`,
//! `x_nm` (or `x_um`, `x_m`, `position [mm]`, ...).

use std::path::Path;

use fistage_model::mat::{MatContent, MatVariable, read_variables};

use super::data::{Record, SensorColumn, StartState};
use crate::csv_input::{
    HeaderMatch, UnitOverrides, match_header, parse_record_csv, read_file, sensor_header,
};
use crate::error::{IdentError, Result};
use crate::units::{Quantity, Unit};

/// The largest MAT-file read, bytes.
const MAX_MAT_BYTES: u64 = 4 << 30;

/// Reads a record: a `.mat` file by its extension, CSV otherwise.
pub fn read_record(path: impl AsRef<Path>, units: &UnitOverrides) -> Result<Record> {
    let path = path.as_ref();
    let is_mat = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mat"));
    if is_mat {
        read_record_mat(path, units)
    } else {
        let (source, text) = read_file(path)?;
        parse_record_csv(&source, &text, units)
    }
}

/// Reads a record from a MAT-file: one vector variable each for time, force
/// and position, named like the CSV columns.
pub fn read_record_mat(path: &Path, units: &UnitOverrides) -> Result<Record> {
    let source = path.display().to_string();
    let io_error = |e: std::io::Error| IdentError::Io {
        file: source.clone(),
        source: e,
    };
    let size = std::fs::metadata(path).map_err(io_error)?.len();
    if size > MAX_MAT_BYTES {
        return Err(IdentError::Io {
            file: source,
            source: std::io::Error::other(format!("{size} bytes; at most {MAX_MAT_BYTES}")),
        });
    }
    let bytes = std::fs::read(path).map_err(io_error)?;
    parse_record_mat(&source, &bytes, units)
}

/// Parses a record from the bytes of a MAT-file; `source` names it in messages.
pub fn parse_record_mat(source: &str, bytes: &[u8], units: &UnitOverrides) -> Result<Record> {
    let variables = read_variables(bytes).map_err(|e| IdentError::NotMatFile {
        file: source.to_string(),
        message: e.to_string(),
    })?;
    let find = |quantity| find_variable(source, &variables, quantity, units);
    let (time_name, time) = find(Quantity::Time)?;
    let (force_name, force) = find(Quantity::Force)?;
    let (position_name, position) = find(Quantity::Position)?;
    let taken = [&time_name, &force_name, &position_name];
    let sensors = sensor_variables(source, &variables, &taken)?;
    let record = Record {
        source: source.to_string(),
        rows: (1..=time.len() as u64).collect(),
        row_word: "element",
        columns: [time_name, force_name, position_name],
        time,
        force,
        position,
        start: StartState::default(),
        sensors,
    };
    record.check()?;
    Ok(record)
}

/// Every variable but `taken` named like a sensor with a position unit
/// (`bearing_encoder_nm`), in SI units.
fn sensor_variables(
    source: &str,
    variables: &[MatVariable],
    taken: &[&String],
) -> Result<Vec<SensorColumn>> {
    let mut out = Vec::new();
    for variable in variables.iter().filter(|v| !taken.contains(&&v.name)) {
        let Some((sensor, unit)) = sensor_header(&variable.name) else {
            continue;
        };
        let values = vector(source, variable)?;
        out.push(SensorColumn {
            sensor,
            column: variable.name.clone(),
            values: values.iter().map(|&v| unit.to_si(v)).collect(),
        });
    }
    Ok(out)
}

/// The values of a real numeric vector variable.
fn vector<'a>(source: &str, variable: &'a MatVariable) -> Result<&'a Vec<f64>> {
    match &variable.content {
        MatContent::Numeric { rows, cols, data } if *rows == 1 || *cols == 1 => Ok(data),
        MatContent::Numeric { rows, cols, .. } => Err(variable_error(
            source,
            &variable.name,
            format!("a {rows} x {cols} matrix; a vector is needed"),
        )),
        MatContent::Complex => Err(variable_error(
            source,
            &variable.name,
            "complex; real values are needed".into(),
        )),
        MatContent::Other(class) => Err(variable_error(
            source,
            &variable.name,
            format!("a {class} array; a numeric vector is needed"),
        )),
    }
}

/// The one vector variable holding `quantity`, in SI units.
fn find_variable(
    source: &str,
    variables: &[MatVariable],
    quantity: Quantity,
    units: &UnitOverrides,
) -> Result<(String, Vec<f64>)> {
    let mut found: Option<(&MatVariable, Option<Unit>)> = None;
    let mut bad_unit = None;
    for variable in variables {
        match match_header(&variable.name, quantity) {
            HeaderMatch::No => {}
            HeaderMatch::BadUnit(text) => {
                bad_unit.get_or_insert((variable.name.clone(), text));
            }
            HeaderMatch::Yes(unit) => {
                if let Some((first, _)) = found {
                    return Err(variable_error(
                        source,
                        &variable.name,
                        format!(
                            "ambiguous: both '{}' and this variable look like {quantity}; rename one",
                            first.name
                        ),
                    ));
                }
                found = Some((variable, unit));
            }
        }
    }
    let Some((variable, in_name)) = found else {
        if let Some((name, text)) = bad_unit {
            return Err(variable_error(
                source,
                &name,
                format!(
                    "unknown {quantity} unit '{text}' (known: {})",
                    quantity.known_units()
                ),
            ));
        }
        let names: Vec<&str> = variables.iter().map(|v| v.name.as_str()).collect();
        return Err(IdentError::MissingVariable {
            file: source.to_string(),
            quantity: quantity.name(),
            example: quantity.example_column(),
            found: names.join(", "),
        });
    };
    let unit = match (in_name, units.get(quantity)) {
        (Some(a), Some(b)) if a != b => {
            return Err(variable_error(
                source,
                &variable.name,
                format!("the name says {a} but {} says {b}", quantity.unit_flag()),
            ));
        }
        (Some(u), _) | (None, Some(u)) => u,
        (None, None) => {
            return Err(variable_error(
                source,
                &variable.name,
                format!(
                    "no unit: name the variable like '{}' or pass {}",
                    quantity.example_column(),
                    quantity.unit_flag()
                ),
            ));
        }
    };
    let values = vector(source, variable)?;
    Ok((
        variable.name.clone(),
        values.iter().map(|&v| unit.to_si(v)).collect(),
    ))
}

fn variable_error(source: &str, name: &str, message: String) -> IdentError {
    IdentError::BadVariable {
        file: source.to_string(),
        variable: name.to_string(),
        message,
    }
}
