//! Shared helpers for the cross-crate tests in `tests/`: locating the shipped
//! robots and scenarios, loading them, and running them.

use std::path::PathBuf;

use fistage_model::Loaded;
use fistage_sim::RunOutput;

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A path below the repository root.
pub fn path(relative: &str) -> PathBuf {
    root().join(relative)
}

/// Loads a shipped scenario; panics with the loader's message on failure.
pub fn load(relative: &str) -> Loaded {
    fistage_model::load(&path(relative)).unwrap_or_else(|e| panic!("{e}"))
}

/// Runs a loaded scenario; panics with the engine's message on failure.
pub fn run(loaded: &Loaded) -> RunOutput {
    fistage_sim::run_scenario(loaded, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
}

/// Steady-state peak-to-peak of a signal in a run.
pub fn peak_to_peak(output: &RunOutput, signal: &str) -> f64 {
    stats(output, signal).peak_to_peak
}

/// Steady-state statistics of a signal in a run.
pub fn stats(output: &RunOutput, signal: &str) -> fistage_sim::WindowStats {
    output
        .summary
        .iter()
        .find(|s| s.name == signal)
        .unwrap_or_else(|| panic!("no signal {signal}"))
        .stats
}

/// A small deterministic generator (SplitMix64) for random test states.
pub struct SplitMix(pub u64);

impl SplitMix {
    /// Next value, uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}
