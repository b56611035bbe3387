//! Units of measured columns and their conversion to SI.
//!
//! Labs export velocities in mm/s, FRF magnitudes in um/N or dB, phases in
//! degrees. A column's unit comes from a suffix of its name (`velocity_mm_per_s`,
//! `force_N`, `freq_Hz`, `mag_dB`, `phase_deg`, `re_G_m_per_N`) or from a
//! bracket (`velocity [mm/s]`), or, for a column without either, from a flag.
//! Inside the crate everything is SI: m/s, N, rad/s, m/N, rad.
//!
//! | quantity | accepted units (case-insensitive; `/` may be written `_per_`) |
//! |---|---|
//! | velocity | `m/s`, `mm/s`, `um/s` (`µm/s`), `nm/s` |
//! | force | `N`, `mN`, `kN` |
//! | frequency | `Hz`, `kHz`, `rad/s` |
//! | magnitude | `m/N`, `mm/N`, `um/N`, `nm/N`, `dB` (20 log10 of the magnitude in m/N) |
//! | phase | `deg`, `rad` |
//! | real and imaginary parts | `m/N`, `mm/N`, `um/N`, `nm/N` |
//! | time (records) | `s`, `ms`, `us` |
//! | position (records) | `m`, `mm`, `um`, `nm` |

use std::f64::consts::PI;
use std::fmt;

/// A physical quantity that a data column can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// Sliding velocity, SI unit m/s.
    Velocity,
    /// Steady-state friction force, SI unit N.
    Force,
    /// Excitation frequency, SI unit rad/s.
    Frequency,
    /// FRF magnitude |G|, SI unit m/N.
    Magnitude,
    /// FRF phase arg G, SI unit rad.
    Phase,
    /// Real part of G, SI unit m/N.
    RealPart,
    /// Imaginary part of G, SI unit m/N.
    ImagPart,
    /// Sample time of a record, SI unit s.
    Time,
    /// Position of a record (the encoder), SI unit m.
    Position,
}

/// How a number in a file becomes an SI number.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Conversion {
    /// Multiply by this factor.
    Scale(f64),
    /// `10^(x / 20)`, the value being 20 log10 of the SI magnitude.
    Decibel,
}

/// A unit of one quantity, with its conversion to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    quantity: Quantity,
    name: &'static str,
    conversion: Conversion,
}

/// Spellings (normalised: lower case, `/` as `_per_`, `µ` as `u`) and units.
type UnitTable = &'static [(&'static [&'static str], &'static str, Conversion)];

const VELOCITY_UNITS: UnitTable = &[
    (&["m_per_s", "mps"], "m/s", Conversion::Scale(1.0)),
    (&["mm_per_s"], "mm/s", Conversion::Scale(1e-3)),
    (&["um_per_s"], "um/s", Conversion::Scale(1e-6)),
    (&["nm_per_s"], "nm/s", Conversion::Scale(1e-9)),
];

const FORCE_UNITS: UnitTable = &[
    (&["n"], "N", Conversion::Scale(1.0)),
    (&["mn"], "mN", Conversion::Scale(1e-3)),
    (&["kn"], "kN", Conversion::Scale(1e3)),
];

const TIME_UNITS: UnitTable = &[
    (&["s", "sec"], "s", Conversion::Scale(1.0)),
    (&["ms"], "ms", Conversion::Scale(1e-3)),
    (&["us"], "us", Conversion::Scale(1e-6)),
];

const POSITION_UNITS: UnitTable = &[
    (&["m"], "m", Conversion::Scale(1.0)),
    (&["mm"], "mm", Conversion::Scale(1e-3)),
    (&["um"], "um", Conversion::Scale(1e-6)),
    (&["nm"], "nm", Conversion::Scale(1e-9)),
];

const FREQUENCY_UNITS: UnitTable = &[
    (&["hz"], "Hz", Conversion::Scale(2.0 * PI)),
    (&["khz"], "kHz", Conversion::Scale(2.0 * PI * 1e3)),
    (&["rad_per_s", "rad_s"], "rad/s", Conversion::Scale(1.0)),
];

const COMPLIANCE_UNITS: UnitTable = &[
    (&["m_per_n"], "m/N", Conversion::Scale(1.0)),
    (&["mm_per_n"], "mm/N", Conversion::Scale(1e-3)),
    (&["um_per_n"], "um/N", Conversion::Scale(1e-6)),
    (&["nm_per_n"], "nm/N", Conversion::Scale(1e-9)),
];

const MAGNITUDE_UNITS: UnitTable = &[
    (&["m_per_n"], "m/N", Conversion::Scale(1.0)),
    (&["mm_per_n"], "mm/N", Conversion::Scale(1e-3)),
    (&["um_per_n"], "um/N", Conversion::Scale(1e-6)),
    (&["nm_per_n"], "nm/N", Conversion::Scale(1e-9)),
    (
        &["db", "db_m_per_n", "db_re_m_per_n"],
        "dB",
        Conversion::Decibel,
    ),
];

const PHASE_UNITS: UnitTable = &[
    (
        &["deg", "degree", "degrees"],
        "deg",
        Conversion::Scale(PI / 180.0),
    ),
    (&["rad", "radian", "radians"], "rad", Conversion::Scale(1.0)),
];

impl Quantity {
    /// The name used in messages, e.g. `velocity`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Velocity => "velocity",
            Self::Force => "force",
            Self::Frequency => "frequency",
            Self::Magnitude => "magnitude",
            Self::Phase => "phase",
            Self::RealPart => "real part",
            Self::ImagPart => "imaginary part",
            Self::Time => "time",
            Self::Position => "position",
        }
    }

    /// An accepted column name, for messages.
    pub fn example_column(self) -> &'static str {
        match self {
            Self::Velocity => "velocity_mm_per_s",
            Self::Force => "force_N",
            Self::Frequency => "freq_Hz",
            Self::Magnitude => "mag_m_per_N",
            Self::Phase => "phase_deg",
            Self::RealPart => "re_G_m_per_N",
            Self::ImagPart => "im_G_m_per_N",
            Self::Time => "t_s",
            Self::Position => "x_nm",
        }
    }

    /// The column-name stems (lower case) that denote this quantity.
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            Self::Velocity => &["velocity", "vel", "speed", "v"],
            Self::Force => &[
                "friction_force",
                "servo_force",
                "f_servo",
                "f_cmd",
                "friction",
                "force",
                "f_ss",
                "fss",
                "f",
            ],
            Self::Frequency => &["frequency", "freq", "omega", "f", "w"],
            Self::Magnitude => &["magnitude", "mag_g", "g_mag", "abs_g", "mag", "gain"],
            Self::Phase => &["phase_g", "g_phase", "arg_g", "phase", "angle"],
            Self::RealPart => &["real_g", "re_g", "g_re", "real", "re"],
            Self::ImagPart => &["imag_g", "im_g", "g_im", "imag", "im"],
            Self::Time => &["time", "t"],
            Self::Position => &["position", "pos", "encoder", "x_table", "x"],
        }
    }

    /// The flag that sets this quantity's unit for a column without one.
    pub fn unit_flag(self) -> &'static str {
        match self {
            Self::Velocity => "--velocity-unit",
            Self::Force => "--force-unit",
            Self::Frequency => "--freq-unit",
            Self::Magnitude => "--mag-unit",
            Self::Phase => "--phase-unit",
            Self::RealPart | Self::ImagPart => "--response-unit",
            Self::Time => "--time-unit",
            Self::Position => "--position-unit",
        }
    }

    fn units(self) -> UnitTable {
        match self {
            Self::Velocity => VELOCITY_UNITS,
            Self::Force => FORCE_UNITS,
            Self::Frequency => FREQUENCY_UNITS,
            Self::Magnitude => MAGNITUDE_UNITS,
            Self::Phase => PHASE_UNITS,
            Self::RealPart | Self::ImagPart => COMPLIANCE_UNITS,
            Self::Time => TIME_UNITS,
            Self::Position => POSITION_UNITS,
        }
    }

    /// The accepted unit names, comma separated, for messages.
    pub fn known_units(self) -> String {
        self.units()
            .iter()
            .map(|(_, name, _)| *name)
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl fmt::Display for Quantity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Lower case, `µ`/`μ` as `u`, `/` as `_per_`, no spaces, no leading or trailing `_`.
fn normalise_unit(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.trim().chars() {
        match c {
            'µ' | 'μ' => out.push('u'),
            '/' => out.push_str("_per_"),
            ' ' | '\t' => {}
            _ => out.extend(c.to_lowercase()),
        }
    }
    while out.contains("__") {
        out = out.replace("__", "_");
    }
    out.trim_matches('_').to_string()
}

impl Unit {
    /// Parses a unit of `quantity` written as in a column suffix or a flag
    /// (`mm/s`, `mm_per_s`, `dB`, `deg`, ...). `None` if it is not a unit of that quantity.
    pub fn parse(quantity: Quantity, text: &str) -> Option<Unit> {
        let key = normalise_unit(text);
        quantity
            .units()
            .iter()
            .find(|(spellings, _, _)| spellings.contains(&key.as_str()))
            .map(|&(_, name, conversion)| Unit {
                quantity,
                name,
                conversion,
            })
    }

    /// The SI unit of `quantity`.
    pub fn si(quantity: Quantity) -> Unit {
        let (_, name, conversion) = quantity.units()[0];
        Unit {
            quantity,
            name,
            conversion,
        }
    }

    /// The quantity this unit measures.
    pub fn quantity(&self) -> Quantity {
        self.quantity
    }

    /// The unit's usual spelling, e.g. `mm/s`.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Converts a value in this unit to SI.
    pub fn to_si(&self, value: f64) -> f64 {
        match self.conversion {
            Conversion::Scale(factor) => value * factor,
            Conversion::Decibel => 10f64.powf(value / 20.0),
        }
    }

    /// Converts an SI value to this unit (the inverse of [`Unit::to_si`]).
    pub fn from_si(&self, value: f64) -> f64 {
        match self.conversion {
            Conversion::Scale(factor) => value / factor,
            Conversion::Decibel => 20.0 * value.log10(),
        }
    }

    /// The column-name suffix for this unit, e.g. `mm_per_s` or `dB`.
    pub fn suffix(&self) -> String {
        self.name.replace('/', "_per_")
    }
}

impl fmt::Display for Unit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suffix_spellings_parse() {
        let v = Unit::parse(Quantity::Velocity, "mm_per_s").unwrap();
        assert_eq!(v.to_si(16.7), 16.7e-3);
        assert_eq!(Unit::parse(Quantity::Velocity, "mm/s"), Some(v));
        assert_eq!(
            Unit::parse(Quantity::Velocity, "µm/s").unwrap().to_si(1.0),
            1e-6
        );
        assert_eq!(Unit::parse(Quantity::Force, "mN").unwrap().to_si(5.0), 5e-3);
        let hz = Unit::parse(Quantity::Frequency, "Hz").unwrap();
        assert!((hz.to_si(1.0) - 2.0 * PI).abs() < 1e-15);
        let db = Unit::parse(Quantity::Magnitude, "dB").unwrap();
        assert!((db.to_si(-120.0) - 1e-6).abs() < 1e-20);
        assert!((db.from_si(1e-6) + 120.0).abs() < 1e-12);
        let deg = Unit::parse(Quantity::Phase, "deg").unwrap();
        assert!((deg.to_si(-90.0) + PI / 2.0).abs() < 1e-15);
        assert_eq!(
            Unit::parse(Quantity::RealPart, "nm/N").unwrap().to_si(1.0),
            1e-9
        );
        assert_eq!(Unit::parse(Quantity::Velocity, "N"), None);
        assert_eq!(Unit::parse(Quantity::Magnitude, "furlong"), None);
    }

    #[test]
    fn suffix_round_trips() {
        for q in [Quantity::Velocity, Quantity::Magnitude, Quantity::Phase] {
            for &(_, name, _) in q.units() {
                let unit = Unit::parse(q, name).unwrap();
                assert_eq!(Unit::parse(q, &unit.suffix()), Some(unit));
            }
        }
    }
}
