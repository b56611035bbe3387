//! The plotters coordinate of every chart axis: a linear range in axis space whose grid lines
//! and labels sit at precomputed ticks.

use std::ops::Range;

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};

use crate::axis::{Axis, Ticks};

/// A linear range with fixed major (labelled) and minor grid positions.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TickedRange {
    lo: f64,
    hi: f64,
    major: Vec<f64>,
    minor: Vec<f64>,
}

impl TickedRange {
    /// The coordinate of `axis` with `ticks`.
    pub(crate) fn new(axis: &Axis, ticks: &Ticks) -> Self {
        TickedRange {
            lo: axis.lo,
            hi: axis.hi,
            major: ticks.major.clone(),
            minor: ticks.minor.clone(),
        }
    }
}

impl Ranged for TickedRange {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let t = (value - self.lo) / (self.hi - self.lo);
        let pixel = f64::from(limit.0) + t * f64::from(limit.1 - limit.0);
        // `as` saturates, so values far outside the range cannot overflow.
        pixel.round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::axis::Scale;

    #[test]
    fn maps_linearly_and_saturates() {
        let axis = Axis {
            scale: Scale::Linear,
            lo: 0.0,
            hi: 10.0,
            has_data: true,
        };
        let range = TickedRange::new(&axis, &axis.ticks(100, 20.0));
        assert_eq!(range.map(&0.0, (100, 200)), 100);
        assert_eq!(range.map(&5.0, (100, 200)), 150);
        assert_eq!(range.map(&10.0, (300, 100)), 100);
        assert_eq!(range.map(&1e300, (0, 100)), i32::MAX);
    }
}
