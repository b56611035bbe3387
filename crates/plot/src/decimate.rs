//! Reduction of long series to what the plot area can show, so files stay small and writing
//! stays fast, while non-finite values break lines instead of failing.
//!
//! * Lines whose x values are monotonic (time responses, spectra) keep, per pixel column, the
//!   first, lowest, highest and last point, so oscillation envelopes and extrema survive.
//! * Gaps (non-finite values) break a line only where the break would be visible: across at
//!   least one empty pixel.
//! * Other lines (phase portraits) are reduced by pixel coverage (see [`crate::coverage`]).
//! * Markers keep one point per pixel cell; the cell grows until the count is bounded.
//!
//! All points are in axis space; a non-finite coordinate marks a gap.

use std::collections::HashSet;

use crate::axis::{Axis, Scale};
use crate::coverage::{self, Trace};
use crate::geometry::{PixelMap, Point};

/// Upper bound on the markers kept for one series.
const MAX_MARKERS: usize = 40_000;

/// What to draw for a line series on the pixel grid of `map`.
pub(crate) fn line_trace(points: &[Point], map: &PixelMap) -> Trace {
    if is_monotonic(points) {
        Trace::Lines(by_column(points, map))
    } else {
        coverage::trace(points, map)
    }
}

/// A series with monotonic x reduced for a reader that cannot draw every point (an
/// interactive plot): per one of `columns` equal columns of the x range, the first, lowest,
/// highest and last point, so envelopes and extrema survive; the runs between visible gaps
/// (non-finite values), each in x order. Other series are returned whole, one run.
pub fn envelope(points: &[(f64, f64)], columns: u32) -> Vec<Vec<(f64, f64)>> {
    if !is_monotonic(points) {
        return vec![points.to_vec()];
    }
    let x = Axis::fit(Scale::Linear, points.iter().map(|p| p.0), 0.0);
    let y = Axis::fit(Scale::Linear, points.iter().map(|p| p.1), 0.0);
    by_column(points, &PixelMap::new(&x, &y, (columns.max(1), 1)))
}

/// The marker positions to draw: one finite, visible point per pixel cell.
pub(crate) fn marker_points(points: &[Point], map: &PixelMap) -> Vec<Point> {
    let mut cell = 1.0;
    let (width, height) = map.size();
    loop {
        let kept = one_per_cell(points, map, cell);
        if kept.len() <= MAX_MARKERS || cell > width.max(height) {
            return kept;
        }
        cell *= 2.0;
    }
}

fn is_finite((x, y): Point) -> bool {
    x.is_finite() && y.is_finite()
}

/// Whether the x values of the finite points never decrease, or never increase.
fn is_monotonic(points: &[Point]) -> bool {
    let mut xs = points.iter().filter(|&&p| is_finite(p)).map(|p| p.0);
    let Some(mut previous) = xs.next() else {
        return true;
    };
    let (mut rises, mut falls) = (false, false);
    for x in xs {
        rises |= x > previous;
        falls |= x < previous;
        if rises && falls {
            return false;
        }
        previous = x;
    }
    true
}

/// The first, lowest, highest and last point seen in one pixel column, with their indices.
struct Column {
    index: i64,
    first: (usize, Point),
    low: (usize, Point),
    high: (usize, Point),
    last: (usize, Point),
}

impl Column {
    fn new(index: i64, i: usize, p: Point) -> Self {
        Column {
            index,
            first: (i, p),
            low: (i, p),
            high: (i, p),
            last: (i, p),
        }
    }

    fn add(&mut self, i: usize, p: Point) {
        if p.1 < self.low.1.1 {
            self.low = (i, p);
        }
        if p.1 > self.high.1.1 {
            self.high = (i, p);
        }
        self.last = (i, p);
    }

    /// Appends the kept points in their original order.
    fn flush_into(self, run: &mut Vec<Point>) {
        let mut kept = [self.first, self.low, self.high, self.last];
        kept.sort_by_key(|&(i, _)| i);
        let mut previous = None;
        for (i, p) in kept {
            if previous != Some(i) {
                run.push(p);
                previous = Some(i);
            }
        }
    }
}

/// Per-column decimation of a line with monotonic x. A gap only breaks the line when it
/// leaves at least one pixel column empty; narrower gaps would not be visible.
fn by_column(points: &[Point], map: &PixelMap) -> Vec<Vec<Point>> {
    let mut runs = Vec::new();
    let mut run = Vec::new();
    let mut column: Option<Column> = None;
    let mut gap = false;
    for (i, &p) in points.iter().enumerate() {
        if !is_finite(p) {
            gap = true;
            continue;
        }
        let index = map.pixel_of(p).0.floor() as i64;
        match column.as_mut() {
            Some(current) if current.index == index => current.add(i, p),
            _ => {
                if let Some(done) = column.take() {
                    let previous = done.index;
                    done.flush_into(&mut run);
                    if gap && previous.abs_diff(index) > 1 {
                        end_run(&mut runs, &mut run);
                    }
                }
                column = Some(Column::new(index, i, p));
            }
        }
        gap = false;
    }
    if let Some(done) = column {
        done.flush_into(&mut run);
    }
    end_run(&mut runs, &mut run);
    runs
}

/// The first finite, visible point in each `cell`-pixel square.
fn one_per_cell(points: &[Point], map: &PixelMap, cell: f64) -> Vec<Point> {
    let mut seen = HashSet::new();
    points
        .iter()
        .copied()
        .filter(|&p| is_finite(p) && map.contains(p))
        .filter(|&p| seen.insert(cell_of(map, p, cell)))
        .collect()
}

fn cell_of(map: &PixelMap, p: Point, cell: f64) -> (i64, i64) {
    let (x, y) = map.pixel_of(p);
    ((x / cell).floor() as i64, (y / cell).floor() as i64)
}

/// Keeps `run` if it can be drawn as a line (two points or more) and starts a new one.
fn end_run(runs: &mut Vec<Vec<Point>>, run: &mut Vec<Point>) {
    if run.len() >= 2 {
        runs.push(std::mem::take(run));
    } else {
        run.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An interactive plot's reduction keeps every column's extremes: a
    /// 200 000-sample decaying oscillation keeps its first, largest and
    /// smallest values in at most four points per column, and a gap stays a gap.
    #[test]
    fn the_envelope_keeps_the_extremes_in_four_points_per_column() {
        let mut points: Vec<Point> = (0..200_000)
            .map(|i| {
                let t = i as f64 * 1e-5;
                (
                    t,
                    (-t).exp() * (2.0 * std::f64::consts::PI * 317.0 * t).sin(),
                )
            })
            .collect();
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.1), hi.max(p.1))
            });
        let runs = envelope(&points, 500);
        assert_eq!(runs.len(), 1);
        assert!(runs[0].len() <= 4 * 501, "{}", runs[0].len());
        assert!(runs[0].iter().any(|p| p.1 == lo) && runs[0].iter().any(|p| p.1 == hi));
        assert_eq!(runs[0][0], points[0]);
        for p in &mut points[90_000..110_000] {
            p.1 = f64::NAN;
        }
        assert_eq!(envelope(&points, 500).len(), 2);
    }

    /// The polylines of a line trace (these tests never produce a raster).
    fn lines(points: &[Point], map: &PixelMap) -> Vec<Vec<Point>> {
        match line_trace(points, map) {
            Trace::Lines(runs) => runs,
            Trace::Cells(_) => Vec::new(),
        }
    }

    fn map_for(points: &[Point], size: (u32, u32)) -> PixelMap {
        let x = Axis::fit(Scale::Linear, points.iter().map(|p| p.0), 0.0);
        let y = Axis::fit(Scale::Linear, points.iter().map(|p| p.1), 0.05);
        PixelMap::new(&x, &y, size)
    }

    /// A decaying oscillation much faster than the pixel grid, with one spike each way.
    fn dense_oscillation(n: usize) -> Vec<Point> {
        let mut points: Vec<Point> = (0..n)
            .map(|i| {
                let t = i as f64 * 1e-5;
                (t, (-t / 2.0).exp() * (t * 2_000.0).sin())
            })
            .collect();
        points[123_457].1 = 3.5;
        points[400_001].1 = -2.75;
        points
    }

    #[test]
    fn column_decimation_keeps_extremes_and_bounds_the_count() {
        let points = dense_oscillation(500_000);
        let map = map_for(&points, (800, 300));
        let runs = lines(&points, &map);
        let kept: Vec<Point> = runs.concat();
        assert_eq!(runs.len(), 1);
        assert!(kept.len() <= 4 * 801, "{} points kept", kept.len());
        assert!(kept.len() > 800);
        let max = kept.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let min = kept.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        assert_eq!((min, max), (-2.75, 3.5));
        assert_eq!(kept.first(), points.first());
        assert_eq!(kept.last(), points.last());
    }

    #[test]
    fn envelope_of_the_oscillation_survives() {
        let points = dense_oscillation(500_000);
        let map = map_for(&points, (800, 300));
        let kept = lines(&points, &map).concat();
        // Near t = 4.5 the envelope is exp(-2.25) ~ 0.105: both signs must still reach it.
        let near: Vec<f64> = kept
            .iter()
            .filter(|p| (p.0 - 4.5).abs() < 0.01)
            .map(|p| p.1)
            .collect();
        assert!(near.iter().any(|&y| y > 0.1) && near.iter().any(|&y| y < -0.1));
    }

    #[test]
    fn wide_gaps_break_lines_and_lone_points_are_dropped() {
        let points = vec![
            (0.0, 0.0),
            (1.0, 1.0),
            (2.0, f64::NAN),
            (3.0, 1.0),
            (4.0, 0.0),
            (f64::INFINITY, 1.0),
            (6.0, 2.0),
            (7.0, f64::NAN),
        ];
        let runs = lines(&points, &map_for(&points, (700, 300)));
        assert_eq!(
            runs,
            vec![vec![(0.0, 0.0), (1.0, 1.0)], vec![(3.0, 1.0), (4.0, 0.0)]]
        );
    }

    #[test]
    fn sub_pixel_gaps_do_not_break_dense_lines() {
        let points: Vec<Point> = (0..10_000)
            .map(|i| {
                (
                    i as f64,
                    if i % 2 == 0 {
                        f64::NAN
                    } else {
                        (i as f64).sin()
                    },
                )
            })
            .collect();
        let runs = lines(&points, &map_for(&points, (500, 300)));
        assert_eq!(runs.len(), 1);
        assert!(runs[0].len() <= 4 * 501);
    }

    #[test]
    fn all_nan_gives_nothing_to_draw() {
        let points = vec![(f64::NAN, f64::NAN); 10];
        let map = map_for(&[(0.0, 0.0), (1.0, 1.0)], (100, 100));
        assert!(lines(&points, &map).is_empty());
        assert!(marker_points(&points, &map).is_empty());
    }

    #[test]
    fn marker_clouds_are_bounded() {
        let points: Vec<Point> = (0..500_000)
            .map(|i| {
                let t = i as f64 * 0.025;
                (t.cos() * (1.0 + t.sin() * 0.3), (1.7 * t).sin())
            })
            .collect();
        let map = map_for(&points, (700, 700));
        let kept = marker_points(&points, &map);
        assert!(
            kept.len() <= MAX_MARKERS && kept.len() > 1_000,
            "{} markers",
            kept.len()
        );
    }

    #[test]
    fn markers_keep_one_point_per_pixel() {
        let points = vec![(0.0, 0.0), (1e-9, 1e-9), (1.0, 1.0), (0.5, f64::NAN)];
        let kept = marker_points(&points, &map_for(&points, (100, 100)));
        assert_eq!(kept, vec![(0.0, 0.0), (1.0, 1.0)]);
    }
}
