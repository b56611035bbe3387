//! Length units that keep plotted numbers readable.

/// A length unit and its factor from metres.
pub(super) struct LengthUnit {
    pub name: &'static str,
    pub scale: f64,
}

/// The unit (mm, µm or nm) in which the largest finite value reads best.
pub(super) fn length_unit(values: &[&[f64]]) -> LengthUnit {
    let largest = values
        .iter()
        .flat_map(|v| v.iter())
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    if largest >= 1e-2 {
        LengthUnit {
            name: "mm",
            scale: 1e3,
        }
    } else if largest >= 1e-5 {
        LengthUnit {
            name: "µm",
            scale: 1e6,
        }
    } else {
        LengthUnit {
            name: "nm",
            scale: 1e9,
        }
    }
}

/// The values multiplied by `scale`.
pub(super) fn scaled(values: &[f64], scale: f64) -> Vec<f64> {
    values.iter().map(|v| v * scale).collect()
}
