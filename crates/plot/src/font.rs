//! The embedded font (DejaVu Sans from the `dejavu` crate), its registration with plotters and
//! the text styles used across all figures.

use std::sync::OnceLock;

use plotters::style::{FontStyle, IntoFont, RGBColor, TextStyle, register_font};

use crate::error::DrawError;

/// Font family name given to plotters. SVG output carries it verbatim as `font-family`, so
/// viewers use DejaVu Sans when installed and fall back to their default sans-serif font.
pub(crate) const FAMILY: &str = "DejaVu Sans, sans-serif";

/// Figure title size.
pub(crate) const TITLE_SIZE: f64 = 26.0;
/// Axis description size.
pub(crate) const LABEL_SIZE: f64 = 20.0;
/// Tick label size.
pub(crate) const TICK_SIZE: f64 = 17.0;
/// Legend and colour bar text size.
pub(crate) const LEGEND_SIZE: f64 = 17.0;
/// Size of the "no data" note.
pub(crate) const NOTE_SIZE: f64 = 22.0;

/// Colour of ordinary text.
pub(crate) const TEXT_COLOUR: RGBColor = RGBColor(20, 20, 20);
/// Colour of the "no data" note.
pub(crate) const NOTE_COLOUR: RGBColor = RGBColor(120, 120, 120);

/// Registers the embedded regular and bold faces once per process.
pub(crate) fn ensure_registered() -> Result<(), DrawError> {
    static REGISTERED: OnceLock<Result<(), DrawError>> = OnceLock::new();
    REGISTERED.get_or_init(register_faces).clone()
}

fn register_faces() -> Result<(), DrawError> {
    let faces = [
        (FontStyle::Normal, dejavu::sans::regular()),
        (FontStyle::Bold, dejavu::sans::bold()),
    ];
    for (style, bytes) in faces {
        register_font(FAMILY, style, bytes)
            .map_err(|_| DrawError(format!("the embedded {} font is invalid", style.as_str())))?;
    }
    Ok(())
}

/// Regular text of the given size.
pub(crate) fn regular(size: f64) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&TEXT_COLOUR)
}

/// Bold text of the given size.
pub(crate) fn bold(size: f64) -> TextStyle<'static> {
    (FAMILY, size, FontStyle::Bold)
        .into_font()
        .color(&TEXT_COLOUR)
}
