//! Lines of any shape (phase portraits) reduced by pixel coverage: segments that only retrace
//! pixels already drawn are skipped, and a trace too dense for that is drawn as the raster of
//! the pixel cells it covers.

use crate::geometry::{PixelMap, Point};

/// Side of the coverage cells in pixels: about the line width.
pub(crate) const CELL: f64 = 2.0;
/// Cost of starting a new polyline, in points (an SVG polyline element is about as long as
/// eight points).
const RUN_COST: usize = 8;
/// Upper bound on the points of one line (plus [`RUN_COST`] per polyline); denser traces
/// become a raster of covered cells.
const MAX_COST: usize = 40_000;

/// How a line of any shape is drawn.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Trace {
    /// Polylines in axis space.
    Lines(Vec<Vec<Point>>),
    /// Filled rectangles (opposite corners in axis space) covering the pixels of the trace.
    Cells(Vec<[Point; 2]>),
}

/// The trace of `points` (axis space, non-finite values mark gaps) on the pixel grid of `map`.
pub(crate) fn trace(points: &[Point], map: &PixelMap) -> Trace {
    let runs = thin_lines(points, map);
    let cost: usize = runs.iter().map(|run| run.len() + RUN_COST).sum();
    if cost <= MAX_COST {
        Trace::Lines(runs)
    } else {
        Trace::Cells(raster(points, map))
    }
}

/// Polylines keeping only segments that pass through a cell no kept segment has passed
/// through, so an orbit traced again and again is drawn once. A few skipped segments between
/// kept ones are drawn anyway rather than breaking the line; longer stretches break it.
fn thin_lines(points: &[Point], map: &PixelMap) -> Vec<Vec<Point>> {
    let mut coverage = Coverage::new(map);
    let mut runs = Vec::new();
    let mut run: Vec<Point> = Vec::new();
    // Ends of the segments skipped since the last point of `run`.
    let mut skipped: Vec<Point> = Vec::new();
    for segment in segments(points, map) {
        let Some((q, p)) = segment else {
            end_run(&mut runs, &mut run);
            skipped.clear();
            continue;
        };
        if coverage.mark_segment(q, p) {
            if run.last() != Some(&q) {
                if run.is_empty() || skipped.len() > RUN_COST {
                    end_run(&mut runs, &mut run);
                    run.push(q);
                } else {
                    run.append(&mut skipped);
                }
            }
            skipped.clear();
            run.push(p);
        } else if !run.is_empty() {
            skipped.push(p);
            if skipped.len() > RUN_COST {
                end_run(&mut runs, &mut run);
                skipped.clear();
            }
        }
    }
    end_run(&mut runs, &mut run);
    runs
}

/// Rectangles covering every cell the trace passes through, merged along rows.
fn raster(points: &[Point], map: &PixelMap) -> Vec<[Point; 2]> {
    let mut coverage = Coverage::new(map);
    for (q, p) in segments(points, map).flatten() {
        coverage.mark_segment(q, p);
    }
    coverage.rectangles(map)
}

/// The segments between consecutive finite points of `points`, skipping points in the same
/// pixel as the point before them; `None` marks a visible gap, that is non-finite values
/// between points whose cells do not touch. Narrower gaps are bridged.
fn segments<'p>(
    points: &'p [Point],
    map: &'p PixelMap,
) -> impl Iterator<Item = Option<(Point, Point)>> + 'p {
    let mut previous: Option<Point> = None;
    let mut gap = false;
    points.iter().filter_map(move |&p| {
        if !(p.0.is_finite() && p.1.is_finite()) {
            gap = true;
            return None;
        }
        let Some(q) = previous else {
            previous = Some(p);
            return None;
        };
        if cell_of(map, q, 1.0) == cell_of(map, p, 1.0) {
            gap = false;
            return None;
        }
        previous = Some(p);
        let broken = gap && !adjacent(cell_of(map, q, CELL), cell_of(map, p, CELL));
        gap = false;
        Some(if broken { None } else { Some((q, p)) })
    })
}

/// The `size`-pixel cell holding `p`.
fn cell_of(map: &PixelMap, p: Point, size: f64) -> (i64, i64) {
    let (x, y) = map.pixel_of(p);
    ((x / size).floor() as i64, (y / size).floor() as i64)
}

/// Whether two cells touch (including diagonally).
fn adjacent(a: (i64, i64), b: (i64, i64)) -> bool {
    a.0.abs_diff(b.0) <= 1 && a.1.abs_diff(b.1) <= 1
}

/// Keeps `run` if it can be drawn as a line (two points or more) and starts a new one.
fn end_run(runs: &mut Vec<Vec<Point>>, run: &mut Vec<Point>) {
    if run.len() >= 2 {
        runs.push(std::mem::take(run));
    } else {
        run.clear();
    }
}

/// Which cells of the plot area a line has passed through, and how far along the line
/// (in pixels) it last did.
struct Coverage<'m> {
    map: &'m PixelMap,
    columns: usize,
    rows: usize,
    /// Path length at the latest visit of each cell; NaN for cells never visited.
    visited: Vec<f64>,
    /// Path length drawn so far.
    travelled: f64,
}

/// A cell visited within this much path length (pixels) is still being drawn, not retraced.
const RECENT: f64 = 3.0 * CELL;

impl<'m> Coverage<'m> {
    fn new(map: &'m PixelMap) -> Self {
        let (width, height) = map.size();
        let columns = (width / CELL).ceil() as usize;
        let rows = (height / CELL).ceil() as usize;
        let visited = vec![f64::NAN; columns * rows];
        Coverage {
            map,
            columns,
            rows,
            visited,
            travelled: 0.0,
        }
    }

    /// Visits the cells along the visible part of the segment from `a` to `b`; returns whether
    /// it reaches a cell the line has not passed through before (apart from just now).
    fn mark_segment(&mut self, a: Point, b: Point) -> bool {
        let Some((a, b)) = self.map.clip_segment(a, b) else {
            return false;
        };
        let (a, b) = (self.map.pixel_of(a), self.map.pixel_of(b));
        let length = (b.0 - a.0).hypot(b.1 - a.1);
        let steps = (2.0 * length / CELL).ceil().max(1.0) as usize;
        let mut fresh = false;
        for k in 0..=steps {
            let t = k as f64 / steps as f64;
            let at = self.travelled + t * length;
            fresh |= self.mark((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)), at);
        }
        self.travelled += length;
        fresh
    }

    /// Visits the cell holding `pixel` at path length `at`; returns whether the cell is new or
    /// was visited only just before.
    fn mark(&mut self, pixel: Point, at: f64) -> bool {
        let column = (pixel.0 / CELL).floor().max(0.0) as usize;
        let row = (pixel.1 / CELL).floor().max(0.0) as usize;
        let column = column.min(self.columns.saturating_sub(1));
        let row = row.min(self.rows.saturating_sub(1));
        let Some(visited) = self.visited.get_mut(row * self.columns + column) else {
            return false;
        };
        let fresh = visited.is_nan() || at - *visited < RECENT;
        if fresh {
            *visited = at;
        }
        fresh
    }

    /// The covered cells as rectangles in axis space, merged along rows.
    fn rectangles(&self, map: &PixelMap) -> Vec<[Point; 2]> {
        let mut rectangles = Vec::new();
        for (row, cells) in self.visited.chunks(self.columns.max(1)).enumerate() {
            let mut column = 0;
            while column < cells.len() {
                if cells[column].is_nan() {
                    column += 1;
                    continue;
                }
                let start = column;
                while column < cells.len() && !cells[column].is_nan() {
                    column += 1;
                }
                let top_left = (start as f64 * CELL, row as f64 * CELL);
                let bottom_right = (column as f64 * CELL, (row + 1) as f64 * CELL);
                rectangles.push([map.axis_of(top_left), map.axis_of(bottom_right)]);
            }
        }
        rectangles
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axis::{Axis, Scale};

    fn map_for(points: &[Point], size: (u32, u32)) -> PixelMap {
        let x = Axis::fit(Scale::Linear, points.iter().map(|p| p.0), 0.05);
        let y = Axis::fit(Scale::Linear, points.iter().map(|p| p.1), 0.05);
        PixelMap::new(&x, &y, size)
    }

    fn circle(turns: usize, per_turn: usize, shrink: f64) -> Vec<Point> {
        (0..turns * per_turn)
            .map(|i| {
                let angle = i as f64 / per_turn as f64 * std::f64::consts::TAU;
                let r = 1.0 - shrink * i as f64 / (turns * per_turn) as f64;
                (r * angle.cos(), r * angle.sin())
            })
            .collect()
    }

    #[test]
    fn retraced_orbits_are_drawn_once() {
        let once = circle(1, 2_000, 0.0);
        let many = circle(200, 2_000, 0.0);
        let map = map_for(&once, (600, 600));
        let (Trace::Lines(first), Trace::Lines(repeated)) =
            (trace(&once, &map), trace(&many, &map))
        else {
            panic!("a clean orbit is drawn as lines");
        };
        let count = |runs: &[Vec<Point>]| runs.iter().map(Vec::len).sum::<usize>();
        assert!(
            count(&repeated) <= count(&first) + 50,
            "{} vs {}",
            count(&repeated),
            count(&first)
        );
    }

    #[test]
    fn dense_spirals_become_a_bounded_raster() {
        let spiral = circle(1_500, 300, 0.5);
        let map = map_for(&spiral, (700, 700));
        let Trace::Cells(cells) = trace(&spiral, &map) else {
            panic!("a dense spiral is rasterised");
        };
        assert!(
            !cells.is_empty() && cells.len() < 350 * 6,
            "{} rectangles",
            cells.len()
        );
        // The hole in the middle stays empty.
        let centre = map.pixel_of((0.0, 0.0));
        let covers_centre = cells.iter().any(|[a, b]| {
            let (a, b) = (map.pixel_of(*a), map.pixel_of(*b));
            a.0 <= centre.0 && centre.0 <= b.0 && a.1 <= centre.1 && centre.1 <= b.1
        });
        assert!(!covers_centre);
    }

    #[test]
    fn visible_gaps_break_lines() {
        let points = vec![
            (0.0, 0.0),
            (1.0, 1.0),
            (f64::NAN, 0.5),
            (2.0, 0.0),
            (1.5, 1.0),
        ];
        let map = map_for(&points, (300, 300));
        let Trace::Lines(runs) = trace(&points, &map) else {
            panic!("few points are drawn as lines");
        };
        assert_eq!(
            runs,
            vec![vec![(0.0, 0.0), (1.0, 1.0)], vec![(2.0, 0.0), (1.5, 1.0)]]
        );
    }
}
