//! Plot-area geometry: mapping axis-space points to pixels and clipping polylines to the
//! visible range.

use crate::axis::Axis;

/// A point in axis space (or pixels, where stated).
pub(crate) type Point = (f64, f64);

/// The visible axis-space rectangle of a plot and its size in pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PixelMap {
    x_lo: f64,
    x_hi: f64,
    y_lo: f64,
    y_hi: f64,
    width: f64,
    height: f64,
}

impl PixelMap {
    /// The map for a plot area of `size` pixels showing the ranges of `x` and `y`.
    pub(crate) fn new(x: &Axis, y: &Axis, size: (u32, u32)) -> Self {
        PixelMap {
            x_lo: x.lo,
            x_hi: x.hi,
            y_lo: y.lo,
            y_hi: y.hi,
            width: f64::from(size.0.max(1)),
            height: f64::from(size.1.max(1)),
        }
    }

    /// Plot area size in pixels.
    pub(crate) fn size(&self) -> (f64, f64) {
        (self.width, self.height)
    }

    /// Pixel position of `point`, measured from the top-left corner of the plot area.
    pub(crate) fn pixel_of(&self, (x, y): Point) -> Point {
        (
            (x - self.x_lo) / (self.x_hi - self.x_lo) * self.width,
            (self.y_hi - y) / (self.y_hi - self.y_lo) * self.height,
        )
    }

    /// The axis-space point at `pixel` (inverse of [`PixelMap::pixel_of`]).
    pub(crate) fn axis_of(&self, (px, py): Point) -> Point {
        (
            self.x_lo + px / self.width * (self.x_hi - self.x_lo),
            self.y_hi - py / self.height * (self.y_hi - self.y_lo),
        )
    }

    /// Whether `point` lies in the visible rectangle.
    pub(crate) fn contains(&self, (x, y): Point) -> bool {
        x >= self.x_lo && x <= self.x_hi && y >= self.y_lo && y <= self.y_hi
    }

    /// The parts of the polyline `run` inside the visible rectangle.
    pub(crate) fn clip(&self, run: &[Point]) -> Vec<Vec<Point>> {
        if run.iter().all(|&p| self.contains(p)) {
            return vec![run.to_vec()];
        }
        let mut pieces = Vec::new();
        let mut current: Vec<Point> = Vec::new();
        for pair in run.windows(2) {
            let Some((start, end)) = self.clip_segment(pair[0], pair[1]) else {
                flush(&mut pieces, &mut current);
                continue;
            };
            if current.last() != Some(&start) {
                flush(&mut pieces, &mut current);
                current.push(start);
            }
            current.push(end);
            if end != pair[1] {
                flush(&mut pieces, &mut current);
            }
        }
        flush(&mut pieces, &mut current);
        pieces
    }

    /// Liang-Barsky clipping of the segment from `p` to `q`. The unclipped ends are returned
    /// exactly, so consecutive visible segments join up.
    pub(crate) fn clip_segment(&self, p: Point, q: Point) -> Option<(Point, Point)> {
        let (dx, dy) = (q.0 - p.0, q.1 - p.1);
        let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
        let edges = [
            (-dx, p.0 - self.x_lo),
            (dx, self.x_hi - p.0),
            (-dy, p.1 - self.y_lo),
            (dy, self.y_hi - p.1),
        ];
        for (direction, distance) in edges {
            if direction == 0.0 {
                if distance < 0.0 {
                    return None;
                }
                continue;
            }
            let t = distance / direction;
            if direction < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return None;
            }
        }
        let at = |t: f64| (p.0 + t * dx, p.1 + t * dy);
        let start = if t0 == 0.0 { p } else { at(t0) };
        let end = if t1 == 1.0 { q } else { at(t1) };
        Some((start, end))
    }
}

/// Moves `current` into `pieces` if it is a drawable polyline, and clears it.
fn flush(pieces: &mut Vec<Vec<Point>>, current: &mut Vec<Point>) {
    if current.len() >= 2 {
        pieces.push(std::mem::take(current));
    } else {
        current.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axis::Scale;

    fn unit_map() -> PixelMap {
        let axis = Axis {
            scale: Scale::Linear,
            lo: 0.0,
            hi: 1.0,
            has_data: true,
        };
        PixelMap::new(&axis, &axis, (100, 50))
    }

    #[test]
    fn pixels_grow_right_and_down() {
        let map = unit_map();
        assert_eq!(map.pixel_of((0.0, 1.0)), (0.0, 0.0));
        assert_eq!(map.pixel_of((1.0, 0.0)), (100.0, 50.0));
        assert_eq!(map.axis_of((50.0, 25.0)), (0.5, 0.5));
    }

    #[test]
    fn inside_runs_are_kept_whole() {
        let run = vec![(0.1, 0.1), (0.5, 0.9), (0.9, 0.2)];
        assert_eq!(unit_map().clip(&run), vec![run]);
    }

    #[test]
    fn runs_leaving_the_range_are_cut_at_the_border() {
        let run = vec![(0.5, 0.5), (1.5, 0.5), (1.5, 0.2), (0.5, 0.2)];
        let pieces = unit_map().clip(&run);
        assert_eq!(
            pieces,
            vec![vec![(0.5, 0.5), (1.0, 0.5)], vec![(1.0, 0.2), (0.5, 0.2)]]
        );
    }

    #[test]
    fn segments_crossing_the_whole_range_are_kept() {
        let pieces = unit_map().clip(&[(-1.0, 0.5), (2.0, 0.5)]);
        assert_eq!(pieces, vec![vec![(0.0, 0.5), (1.0, 0.5)]]);
        assert!(unit_map().clip(&[(-1.0, 2.0), (-0.5, 3.0)]).is_empty());
    }
}
