//! The key right of a heatmap: a colour bar with ticks and a description for continuous
//! values, or a swatch per category, plus a grey swatch for cells that were not computed.

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, DrawingBackend, PathElement, Rectangle, Text};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{Color, FontTransform, RGBColor};

use crate::axis::{Axis, Ticks};
use crate::cells::Colouring;
use crate::chart::{self, Chart, text_width};
use crate::error::DrawResult;
use crate::font;
use crate::heatmap::{ColourScale, Heatmap};
use crate::palette::{self, AXIS, MISSING};

/// Gap between the plot and the key.
const OFFSET: i32 = 16;
/// Colour bar width.
const BAR_WIDTH: i32 = 24;
/// Number of colour steps drawn in the colour bar.
const BAR_STEPS: usize = 128;
/// Side of a swatch.
const SWATCH: i32 = 18;
/// Label of the swatch for NaN cells.
const MISSING_TEXT: &str = "not computed";

/// What the key shows.
#[derive(Debug, Clone, PartialEq)]
enum Content {
    /// A colour bar over `axis` with `ticks`.
    Bar {
        axis: Axis,
        diverging: bool,
        ticks: Ticks,
    },
    /// One swatch per label.
    Categories(Vec<String>),
}

/// The measured key of one heatmap.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ColourKey {
    /// Width needed right of the map, in pixels.
    pub(crate) width: u32,
    content: Content,
    description: String,
    has_missing: bool,
}

impl ColourKey {
    /// Measures the key of `heatmap` for a plot `plot_height` pixels high.
    pub(crate) fn new<DB: DrawingBackend>(
        area: &DrawingArea<DB, Shift>,
        heatmap: &Heatmap,
        colouring: &Colouring,
        plot_height: u32,
    ) -> DrawResult<Self> {
        let content = match (colouring, &heatmap.colour_scale) {
            (Colouring::Continuous { axis, diverging }, _) => Content::Bar {
                axis: *axis,
                diverging: *diverging,
                ticks: chart::y_ticks(axis, plot_height),
            },
            (_, ColourScale::Categorical { labels }) => Content::Categories(labels.clone()),
            (Colouring::Categorical, _) => Content::Categories(Vec::new()),
        };
        let mut key = ColourKey {
            width: 0,
            content,
            description: heatmap.value_label.clone(),
            has_missing: heatmap.values.iter().any(|v| !v.is_finite()),
        };
        key.width = key.measure(area)?;
        Ok(key)
    }

    /// The width the key needs.
    fn measure<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> DrawResult<u32> {
        let style = font::regular(font::LEGEND_SIZE);
        let widest = |texts: Vec<String>| -> DrawResult<i32> {
            let mut widest = 0;
            for text in texts {
                widest = widest.max(text_width(area, &text, &style)? as i32);
            }
            Ok(widest)
        };
        let content = match &self.content {
            Content::Bar { ticks, .. } => {
                let description = if self.description.is_empty() {
                    0
                } else {
                    (font::LABEL_SIZE * 1.3) as i32 + 8
                };
                BAR_WIDTH + 14 + widest(ticks.labels())? + description
            }
            Content::Categories(labels) => SWATCH + 8 + widest(labels.clone())?,
        };
        let missing = if self.has_missing {
            SWATCH + 8 + widest(vec![MISSING_TEXT.to_string()])?
        } else {
            0
        };
        Ok((OFFSET + content.max(missing) + 16).max(0) as u32)
    }

    /// Draws the key on `area`, aligned with the plotting area of `chart`.
    pub(crate) fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        chart: &Chart<DB>,
    ) -> DrawResult {
        let (_, rows) = chart.plotting_area().get_pixel_range();
        let base = area.get_base_pixel().1;
        let (top, bottom) = (rows.start - base, rows.end - 1 - base);
        let missing_at = match &self.content {
            Content::Bar {
                axis,
                diverging,
                ticks,
            } => {
                self.draw_bar(area, (axis, *diverging, ticks), top, bottom)?;
                bottom + 22
            }
            Content::Categories(labels) => draw_categories(area, labels, top)?,
        };
        if self.has_missing {
            draw_swatch(area, (OFFSET, missing_at), MISSING, MISSING_TEXT)?;
        }
        Ok(())
    }

    /// Draws the colour bar between rows `top` and `bottom`, with its ticks and description.
    fn draw_bar<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        (axis, diverging, ticks): (&Axis, bool, &Ticks),
        top: i32,
        bottom: i32,
    ) -> DrawResult {
        let (left, right) = (OFFSET, OFFSET + BAR_WIDTH);
        let height = f64::from(bottom - top);
        let row_at = |t: f64| bottom - (t * height).round() as i32;
        for step in 0..BAR_STEPS {
            let t0 = step as f64 / BAR_STEPS as f64;
            let t1 = (step + 1) as f64 / BAR_STEPS as f64;
            let colour = Colouring::map_colour(diverging, 0.5 * (t0 + t1));
            let band = [(left, row_at(t1)), (right, row_at(t0))];
            area.draw(&Rectangle::new(band, colour.filled()))?;
        }
        area.draw(&Rectangle::new(
            [(left, top), (right, bottom)],
            AXIS.stroke_width(1),
        ))?;
        let style = font::regular(font::LEGEND_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
        for &tick in &ticks.major {
            let row = row_at((tick - axis.lo) / axis.span());
            let mark = vec![(right, row), (right + 5, row)];
            area.draw(&PathElement::new(mark, AXIS.stroke_width(1)))?;
            area.draw(&Text::new(
                ticks.label(tick),
                (right + 9, row),
                style.clone(),
            ))?;
        }
        if let Some(multiplier) = ticks.multiplier() {
            let style = font::regular(font::TICK_SIZE).pos(Pos::new(HPos::Left, VPos::Bottom));
            area.draw(&Text::new(multiplier, (left, top - 6), style))?;
        }
        self.draw_description(area, (top + bottom) / 2)
    }

    /// Writes the value description vertically along the right edge of the key.
    fn draw_description<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        middle: i32,
    ) -> DrawResult {
        if self.description.is_empty() {
            return Ok(());
        }
        let style = font::regular(font::LABEL_SIZE)
            .transform(FontTransform::Rotate270)
            .pos(Pos::new(HPos::Center, VPos::Top));
        let x = self.width as i32 - 12 - (font::LABEL_SIZE * 1.3) as i32;
        area.draw(&Text::new(self.description.as_str(), (x, middle), style))?;
        Ok(())
    }
}

/// Draws one swatch per category from row `top` down; returns the next free row.
fn draw_categories<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    labels: &[String],
    top: i32,
) -> DrawResult<i32> {
    let mut y = top;
    for (index, label) in labels.iter().enumerate() {
        draw_swatch(area, (OFFSET, y), palette::category_colour(index), label)?;
        y += SWATCH + 12;
    }
    Ok(y)
}

/// A framed square of `colour` with its top-left corner at `at`, followed by `label`.
fn draw_swatch<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    at: (i32, i32),
    colour: RGBColor,
    label: &str,
) -> DrawResult {
    let square = [at, (at.0 + SWATCH, at.1 + SWATCH)];
    area.draw(&Rectangle::new(square, colour.filled()))?;
    area.draw(&Rectangle::new(square, AXIS.stroke_width(1)))?;
    let style = font::regular(font::LEGEND_SIZE).pos(Pos::new(HPos::Left, VPos::Center));
    area.draw(&Text::new(
        label,
        (at.0 + SWATCH + 8, at.1 + SWATCH / 2),
        style,
    ))?;
    Ok(())
}
