//! The force program of a lab-style identification run, scaled to the
//! stage's friction levels: rests; a small chirp (presliding: sigma0 and the
//! damping); breakaway ramps both ways (f_S); a sub-breakaway hold (creep);
//! a large chirp (sliding through the Stribeck curve and the viscous range,
//! and the mass); force steps beyond breakaway both ways; a sub-breakaway
//! step. 7 s.

use super::segments::Segment;

/// One piece of the program.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Piece {
    /// Zero force.
    Rest,
    /// `amplitude sin(phase(t))`, frequency log-swept from `f0` to `f1` Hz.
    Chirp { amplitude: f64, f0: f64, f1: f64 },
    /// Linear from 0 to `peak`.
    Ramp { peak: f64 },
    /// Constant.
    Hold { level: f64 },
}

impl Piece {
    fn kind(self) -> &'static str {
        match self {
            Self::Rest => "rest",
            Self::Chirp { .. } => "chirp",
            Self::Ramp { .. } => "ramp",
            Self::Hold { .. } => "step",
        }
    }

    /// The force `s` seconds into a piece of length `length`.
    fn force(self, s: f64, length: f64) -> f64 {
        match self {
            Self::Rest => 0.0,
            Self::Chirp { amplitude, f0, f1 } => {
                // Phase of a log sweep: 2 pi f0 L / ln(f1/f0) (exp(s ln(f1/f0)/L) - 1).
                let rate = (f1 / f0).ln() / length;
                let phase = 2.0 * std::f64::consts::PI * f0 * ((rate * s).exp() - 1.0) / rate;
                amplitude * phase.sin()
            }
            Self::Ramp { peak } => peak * s / length,
            Self::Hold { level } => level,
        }
    }
}

/// The program's pieces and durations for friction levels `f_c`, `f_s`.
fn pieces(f_c: f64, f_s: f64) -> Vec<(Piece, f64)> {
    use Piece::*;
    vec![
        (Rest, 0.2),
        (
            Chirp {
                amplitude: 0.4 * f_c,
                f0: 5.0,
                f1: 300.0,
            },
            1.0,
        ),
        (Rest, 0.3),
        (Ramp { peak: 1.2 * f_s }, 0.4),
        (Rest, 0.3),
        (Ramp { peak: -1.2 * f_s }, 0.4),
        (Rest, 0.3),
        (Hold { level: 0.6 * f_c }, 0.3),
        (Rest, 0.3),
        (
            Chirp {
                amplitude: 1.5 * f_s,
                f0: 2.0,
                f1: 30.0,
            },
            2.0,
        ),
        (Rest, 0.3),
        (Hold { level: 1.1 * f_s }, 0.05),
        (Rest, 0.2),
        (Hold { level: -1.1 * f_s }, 0.05),
        (Rest, 0.2),
        (Hold { level: 0.8 * f_c }, 0.2),
        (Rest, 0.5),
    ]
}

/// The program sampled every `dt`: times, the force held over each interval,
/// and the segments.
pub fn lab_program(f_c: f64, f_s: f64, dt: f64) -> (Vec<f64>, Vec<f64>, Vec<Segment>) {
    let mut time = Vec::new();
    let mut force = Vec::new();
    let mut segments = Vec::new();
    for (piece, length) in pieces(f_c, f_s) {
        let start = time.len();
        let count = (length / dt).round() as usize;
        for i in 0..count {
            // Times as k dt exactly, the way a simulation samples them.
            time.push((start + i) as f64 * dt);
            force.push(piece.force(i as f64 * dt, length));
        }
        segments.push(Segment {
            start,
            end: time.len(),
            kind: piece.kind().to_string(),
        });
    }
    (time, force, segments)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_program_is_contiguous_and_scaled() {
        let (time, force, segments) = lab_program(1.0, 1.5, 1e-4);
        assert_eq!(time.len(), force.len());
        assert!((time.len() as f64 * 1e-4 - 7.0).abs() < 1e-9);
        assert!(
            time.windows(2)
                .all(|w| ((w[1] - w[0]) - 1e-4).abs() < 1e-12)
        );
        let peak = force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        assert!((peak - 2.25).abs() < 1e-3, "{peak}");
        assert_eq!(segments.last().map(|s| s.end), Some(time.len()));
        assert!(segments.windows(2).all(|w| w[0].end == w[1].start));
    }
}
