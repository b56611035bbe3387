//! Output files: the format chosen by the file extension, rendering a figure into memory with
//! the SVG or bitmap backend, PNG encoding, and writing the file.

use std::path::Path;

use plotters::backend::RGBPixel;
use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, DrawingBackend, IntoDrawingArea, SVGBackend};
use plotters::style::WHITE;

use crate::error::{DrawError, DrawResult, PlotError};
use crate::font;

/// The output file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Format {
    /// Scalable vector graphics; text stays text.
    Svg,
    /// An RGB bitmap in a PNG file.
    Png,
}

impl Format {
    /// The format named by the extension of `path` (case-insensitive).
    pub(crate) fn from_path(path: &Path) -> Result<Self, PlotError> {
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("svg") => Ok(Format::Svg),
            Some("png") => Ok(Format::Png),
            _ => Err(PlotError::UnsupportedExtension {
                path: path.to_path_buf(),
            }),
        }
    }
}

impl Format {
    /// Whether thick polylines must be drawn segment by segment. The bitmap rasteriser joins
    /// the segments of a thick polyline into one polygon, which grows spikes where a line turns
    /// back on itself (as decimated oscillations do); separate segments avoid that.
    pub(crate) fn needs_segments(self) -> bool {
        self == Format::Png
    }
}

/// Something that draws a whole figure onto a drawing area of any backend.
pub(crate) trait Painter {
    /// Draws onto `root`, which is already filled white, for output in `format`.
    fn paint<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        format: Format,
    ) -> DrawResult;
}

/// Renders `painter` at `size` pixels and writes it to `path` in the format its extension names.
pub(crate) fn render(
    path: &Path,
    size: (u32, u32),
    painter: &impl Painter,
) -> Result<(), PlotError> {
    let format = Format::from_path(path)?;
    let backend_error = |error: DrawError| PlotError::Backend {
        path: path.to_path_buf(),
        message: error.0,
    };
    font::ensure_registered().map_err(backend_error)?;
    let bytes = match format {
        Format::Svg => render_svg(size, painter).map(String::into_bytes),
        Format::Png => render_png(size, painter),
    }
    .map_err(backend_error)?;
    std::fs::write(path, bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Renders into an SVG document held in memory.
fn render_svg(size: (u32, u32), painter: &impl Painter) -> DrawResult<String> {
    let mut document = String::new();
    {
        let root = SVGBackend::with_string(&mut document, size).into_drawing_area();
        paint_root(&root, painter, Format::Svg)?;
    }
    Ok(document)
}

/// Renders into an RGB buffer and encodes it as PNG.
fn render_png(size: (u32, u32), painter: &impl Painter) -> DrawResult<Vec<u8>> {
    let (width, height) = size;
    let mut pixels = vec![0_u8; width as usize * height as usize * 3];
    {
        let backend = BitMapBackend::<RGBPixel>::with_buffer_and_format(&mut pixels, size)
            .map_err(|e| DrawError(e.to_string()))?;
        let root = backend.into_drawing_area();
        paint_root(&root, painter, Format::Png)?;
    }
    encode_png(&pixels, size).map_err(|e| DrawError(format!("PNG encoding failed: {e}")))
}

/// Encodes 8-bit RGB pixels, row after row, as a PNG file.
fn encode_png(pixels: &[u8], (width, height): (u32, u32)) -> Result<Vec<u8>, png::EncodingError> {
    let mut encoded = Vec::new();
    let mut encoder = png::Encoder::new(&mut encoded, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(pixels)?;
    writer.finish()?;
    Ok(encoded)
}

/// Clears the root, lets the painter draw and flushes the backend.
fn paint_root<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    painter: &impl Painter,
    format: Format,
) -> DrawResult {
    root.fill(&WHITE)?;
    painter.paint(root, format)?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn format_follows_extension_case_insensitively() {
        assert_eq!(
            Format::from_path(Path::new("a/b.svg")).ok(),
            Some(Format::Svg)
        );
        assert_eq!(
            Format::from_path(Path::new("b.PNG")).ok(),
            Some(Format::Png)
        );
    }

    #[test]
    fn other_extensions_are_rejected_naming_the_path() {
        for name in ["figure.pdf", "figure", "figure.svg.txt"] {
            let error = Format::from_path(Path::new(name)).err();
            let message = error.map(|e| e.to_string()).unwrap_or_default();
            assert!(message.contains(name), "{message}");
        }
    }
}
