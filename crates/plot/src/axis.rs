//! Axes: linear or logarithmic scales, data ranges (with padding and sensible ranges for
//! constant data), tick positions and tick label text.
//!
//! Charts are drawn in "axis space": values on a log axis are replaced by their base-10
//! logarithm, so every chart uses the same linear plotters coordinate with custom ticks.

/// Values whose magnitude exceeds this are treated like non-finite values, so that spans and
/// pixel positions can never overflow.
const HUGE: f64 = 1e300;

/// Unicode minus sign used in tick labels.
const MINUS: char = '\u{2212}';

/// How data values map onto an axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scale {
    /// Values are drawn as they are.
    Linear,
    /// Values are drawn by their base-10 logarithm; values `<= 0` cannot be drawn.
    Log,
}

impl Scale {
    /// `Log` when `log` is true.
    pub(crate) fn from_log(log: bool) -> Self {
        if log { Scale::Log } else { Scale::Linear }
    }

    /// The axis-space position of `value`, or `None` when it cannot be drawn
    /// (non-finite, huge, or not positive on a log scale).
    pub(crate) fn to_axis(self, value: f64) -> Option<f64> {
        if !value.is_finite() || value.abs() > HUGE {
            return None;
        }
        match self {
            Scale::Linear => Some(value),
            Scale::Log if value > 0.0 => Some(value.log10()),
            Scale::Log => None,
        }
    }
}

/// One axis: its scale and its range in axis space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Axis {
    /// The scale.
    pub(crate) scale: Scale,
    /// Lower end in axis space.
    pub(crate) lo: f64,
    /// Upper end in axis space (always greater than `lo`).
    pub(crate) hi: f64,
    /// Whether any drawable value fixed the range.
    pub(crate) has_data: bool,
}

impl Axis {
    /// The axis spanning `values` (already in axis space; non-finite ones are ignored), widened
    /// by `pad` times the span on each side. Constant data get a non-zero range around the
    /// value; no data give a default range.
    pub(crate) fn fit(scale: Scale, values: impl IntoIterator<Item = f64>, pad: f64) -> Self {
        let (lo, hi) = values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        if lo > hi {
            return Axis {
                scale,
                lo: 0.0,
                hi: 1.0,
                has_data: false,
            };
        }
        let span = hi - lo;
        let (lo, hi) = if span <= 1e-12 * lo.abs().max(hi.abs()) || span == 0.0 {
            constant_range(scale, 0.5 * (lo + hi))
        } else {
            (lo - pad * span, hi + pad * span)
        };
        Axis {
            scale,
            lo,
            hi,
            has_data: true,
        }
    }

    /// The length of the range in axis space.
    pub(crate) fn span(&self) -> f64 {
        self.hi - self.lo
    }

    /// The axis widened symmetrically about its centre to `span` (never narrowed).
    pub(crate) fn widened_to(&self, span: f64) -> Self {
        if !span.is_finite() || span <= self.span() {
            return *self;
        }
        let centre = 0.5 * (self.lo + self.hi);
        Axis {
            lo: centre - 0.5 * span,
            hi: centre + 0.5 * span,
            ..*self
        }
    }

    /// Ticks for an axis `pixels` long, aiming at roughly `spacing` pixels between labels.
    pub(crate) fn ticks(&self, pixels: u32, spacing: f64) -> Ticks {
        let target = (f64::from(pixels) / spacing).clamp(2.0, 12.0);
        match self.scale {
            Scale::Linear => linear_ticks(self.lo, self.hi, target),
            Scale::Log => log_ticks(self.lo, self.hi, target),
        }
    }
}

/// A range around a constant value `v` (in axis space).
fn constant_range(scale: Scale, v: f64) -> (f64, f64) {
    match scale {
        Scale::Log => (v - 0.5, v + 0.5),
        Scale::Linear if v == 0.0 => (-1.0, 1.0),
        Scale::Linear => (v - 0.1 * v.abs(), v + 0.1 * v.abs()),
    }
}

/// Tick positions in axis space and how to label them.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Ticks {
    /// Labelled ticks with major grid lines.
    pub(crate) major: Vec<f64>,
    /// Unlabelled minor grid lines (log axes).
    pub(crate) minor: Vec<f64>,
    /// How labels are written.
    format: LabelFormat,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum LabelFormat {
    /// Labels show `value / 10^exponent` with a fixed number of decimals.
    Linear { exponent: i32, decimals: usize },
    /// Labels show the value whose logarithm is the tick position; with `powers`, decades
    /// are written as powers of ten (10⁻⁵), otherwise as plain numbers (0.001).
    Log { powers: bool },
}

impl Ticks {
    /// The label of the tick at axis-space position `position`.
    pub(crate) fn label(&self, position: f64) -> String {
        match self.format {
            LabelFormat::Linear { exponent, decimals } => {
                fixed(position / 10_f64.powi(exponent), decimals)
            }
            LabelFormat::Log { powers } => log_label(position, powers),
        }
    }

    /// The common factor shown once beside the axis (such as "×10⁻⁶"), if labels are scaled.
    pub(crate) fn multiplier(&self) -> Option<String> {
        match self.format {
            LabelFormat::Linear { exponent, .. } if exponent != 0 => {
                Some(format!("\u{d7}10{}", superscript(exponent)))
            }
            _ => None,
        }
    }

    /// All labels, for measuring the space they need.
    pub(crate) fn labels(&self) -> Vec<String> {
        self.major.iter().map(|&t| self.label(t)).collect()
    }
}

/// The "nice" step (1, 2 or 5 times a power of ten) nearest to `raw` on a log scale.
fn nice_step(raw: f64) -> f64 {
    let magnitude = 10_f64.powf(raw.log10().floor());
    let normalised = raw / magnitude;
    // Geometric midpoints between 1, 2, 5 and 10.
    let factor = [
        (1.0, 2_f64.sqrt()),
        (2.0, 10_f64.sqrt()),
        (5.0, 50_f64.sqrt()),
    ]
    .into_iter()
    .find(|&(_, upper)| normalised < upper)
    .map_or(10.0, |(factor, _)| factor);
    factor * magnitude
}

fn linear_ticks(lo: f64, hi: f64, target: f64) -> Ticks {
    let step = nice_step((hi - lo) / target);
    let mut major = Vec::new();
    if step.is_finite() && step > 0.0 {
        let first = (lo / step - 1e-9).ceil();
        for i in 0..64 {
            let tick = (first + f64::from(i)) * step;
            if tick > hi + 1e-9 * step {
                break;
            }
            major.push(if tick.abs() < 1e-9 * step { 0.0 } else { tick });
        }
    }
    let largest = lo.abs().max(hi.abs());
    let exponent = engineering_exponent(largest);
    let scaled_step = step / 10_f64.powi(exponent);
    let decimals = (-(scaled_step.log10() + 1e-9).floor()).clamp(0.0, 15.0) as usize;
    Ticks {
        major,
        minor: Vec::new(),
        format: LabelFormat::Linear { exponent, decimals },
    }
}

/// The power of ten (a multiple of three) factored out of labels, or 0 for moderate values.
fn engineering_exponent(largest: f64) -> i32 {
    if !largest.is_finite() || largest <= 0.0 {
        return 0;
    }
    let exponent = largest.log10().floor() as i32;
    if (-2..=3).contains(&exponent) {
        0
    } else {
        3 * exponent.div_euclid(3)
    }
}

fn log_ticks(lo: f64, hi: f64, target: f64) -> Ticks {
    let first_decade = lo.floor() as i32;
    let last_decade = hi.ceil() as i32;
    let inside = |p: f64| p >= lo - 1e-9 && p <= hi + 1e-9;
    let decades: Vec<f64> = (first_decade..=last_decade)
        .map(f64::from)
        .filter(|&d| inside(d))
        .collect();
    let mantissa_ticks = |mantissas: &[f64]| -> Vec<f64> {
        (first_decade..=last_decade)
            .flat_map(|d| mantissas.iter().map(move |m| f64::from(d) + m.log10()))
            .filter(|&p| inside(p))
            .collect()
    };
    let stride = (decades.len() as f64 / target).ceil().max(1.0) as usize;
    // Minor lines at every mantissa only while decades are few enough to stay readable.
    let candidates = if stride == 1 {
        mantissa_ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    } else {
        decades.clone()
    };
    let major: Vec<f64> = if decades.len() >= 2 {
        decades.iter().copied().step_by(stride).collect()
    } else {
        let coarse = mantissa_ticks(&[1.0, 2.0, 5.0]);
        if coarse.len() >= 2 {
            coarse
        } else {
            candidates.clone()
        }
    };
    let minor = candidates
        .into_iter()
        .filter(|p| !major.iter().any(|m| (m - p).abs() < 1e-9))
        .collect();
    // Plain numbers only while every label stays short; otherwise powers of ten throughout.
    let powers = major.iter().any(|p| !(-3.5..=3.5).contains(p));
    Ticks {
        major,
        minor,
        format: LabelFormat::Log { powers },
    }
}

/// `value` with `decimals` decimals, a typographic minus and no negative zero.
fn fixed(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        return text.trim_start_matches('-').to_string();
    }
    text.replace('-', &MINUS.to_string())
}

/// Label of a log-axis tick at `position` (the logarithm of the value), written as a power
/// of ten when `powers` is set.
fn log_label(position: f64, powers: bool) -> String {
    let decade = (position + 1e-9).floor();
    let mut mantissa = 10_f64.powf(position - decade).round();
    let mut exponent = decade as i32;
    if mantissa >= 10.0 {
        mantissa = 1.0;
        exponent += 1;
    }
    if !powers {
        return fixed(
            mantissa * 10_f64.powi(exponent),
            exponent.min(0).unsigned_abs() as usize,
        );
    }
    if mantissa == 1.0 {
        format!("10{}", superscript(exponent))
    } else {
        format!("{mantissa}\u{d7}10{}", superscript(exponent))
    }
}

/// `value` written with Unicode superscript digits.
pub(crate) fn superscript(value: i32) -> String {
    const DIGITS: [char; 10] = [
        '\u{2070}', '\u{b9}', '\u{b2}', '\u{b3}', '\u{2074}', '\u{2075}', '\u{2076}', '\u{2077}',
        '\u{2078}', '\u{2079}',
    ];
    value
        .to_string()
        .chars()
        .map(|c| match c.to_digit(10) {
            Some(d) => DIGITS[d as usize],
            None => '\u{207b}',
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_data_get_a_non_zero_range() {
        let axis = Axis::fit(Scale::Linear, [3.0, 3.0, 3.0], 0.05);
        assert!(axis.has_data && axis.lo < 3.0 && axis.hi > 3.0);
        let zero = Axis::fit(Scale::Linear, [0.0], 0.05);
        assert_eq!((zero.lo, zero.hi), (-1.0, 1.0));
        let log = Axis::fit(Scale::Log, [2.0], 0.0);
        assert!(log.span() > 0.9);
    }

    #[test]
    fn no_data_gives_a_default_range() {
        let axis = Axis::fit(Scale::Linear, [f64::NAN, f64::INFINITY], 0.05);
        assert!(!axis.has_data);
        assert!(axis.span() > 0.0);
    }

    #[test]
    fn log_scale_rejects_non_positive_and_non_finite_values() {
        assert_eq!(Scale::Log.to_axis(100.0), Some(2.0));
        assert_eq!(Scale::Log.to_axis(0.0), None);
        assert_eq!(Scale::Log.to_axis(-1.0), None);
        assert_eq!(Scale::Linear.to_axis(f64::NAN), None);
        assert_eq!(Scale::Linear.to_axis(1e301), None);
    }

    #[test]
    fn linear_ticks_are_nice_and_inside_the_range() {
        let axis = Axis {
            scale: Scale::Linear,
            lo: -0.3,
            hi: 2.2,
            has_data: true,
        };
        let ticks = axis.ticks(500, 100.0);
        assert_eq!(ticks.labels(), ["0.0", "0.5", "1.0", "1.5", "2.0"]);
        assert!(ticks.multiplier().is_none());
    }

    #[test]
    fn small_values_are_scaled_by_a_common_factor() {
        let axis = Axis {
            scale: Scale::Linear,
            lo: -2e-6,
            hi: 4e-6,
            has_data: true,
        };
        let ticks = axis.ticks(300, 60.0);
        assert_eq!(
            ticks.multiplier().as_deref(),
            Some("\u{d7}10\u{207b}\u{2076}")
        );
        assert!(ticks.labels().contains(&"\u{2212}2".to_string()));
        assert!(ticks.labels().contains(&"4".to_string()));
    }

    #[test]
    fn log_ticks_label_decades() {
        let axis = Axis {
            scale: Scale::Log,
            lo: -1.0,
            hi: 5.0,
            has_data: true,
        };
        let ticks = axis.ticks(900, 90.0);
        assert_eq!(
            ticks.labels()[..3],
            ["10\u{207b}\u{b9}", "10\u{2070}", "10\u{b9}"]
        );
        assert!(ticks.labels().contains(&"10\u{2074}".to_string()));
        assert!(!ticks.minor.is_empty());
        let short = Axis {
            scale: Scale::Log,
            lo: -1.0,
            hi: 3.0,
            has_data: true,
        };
        assert_eq!(
            short.ticks(900, 90.0).labels(),
            ["0.1", "1", "10", "100", "1000"]
        );
    }

    #[test]
    fn narrow_log_ranges_get_mantissa_ticks() {
        let axis = Axis {
            scale: Scale::Log,
            lo: 0.1,
            hi: 0.9,
            has_data: true,
        };
        let labels = axis.ticks(300, 60.0).labels();
        assert_eq!(labels, ["2", "5"]);
    }

    #[test]
    fn tick_generation_is_bounded_for_extreme_ranges() {
        let axis = Axis::fit(Scale::Linear, [-1e300, 1e300], 0.05);
        assert!(axis.ticks(300, 60.0).major.len() <= 64);
        let tiny = Axis::fit(Scale::Linear, [1.0, 1.0 + 1e-15], 0.05);
        assert!(tiny.span() > 0.1);
    }
}
