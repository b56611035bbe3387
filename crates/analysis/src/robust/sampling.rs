//! Designs of the unit cube: the uniform numbers in (0, 1) that each sample
//! of a tolerance analysis turns into parameter values. Every design gives
//! sample i from (seed, i) alone, so that shards of a study compute exactly
//! the samples a single run would, in any order.
//!
//! - `sobol`: an Owen-scrambled Sobol sequence (hash-based scrambling,
//!   Burley 2020, over the Joe-Kuo direction numbers), seeded; at most 2^16
//!   samples and 256 dimensions, best at a power of two;
//! - `random`: independent uniform numbers (a ChaCha stream per sample);
//! - `lhs`: a Latin hypercube: along each dimension the n samples fall one
//!   in each of n equal strata, in a seeded random order.

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;

pub use fistage_model::studies::Sampling;

/// Samples a scrambled Sobol design may have.
pub const MAX_SOBOL_SAMPLES: usize = 1 << 16;
/// Dimensions a scrambled Sobol design may have.
pub const MAX_SOBOL_DIMENSIONS: usize = 256;

/// A design of `samples` points in `dimensions` dimensions.
#[derive(Debug, Clone)]
pub struct Design {
    sampling: Sampling,
    seed: u64,
    samples: usize,
    dimensions: usize,
    /// Latin hypercube: the stratum of each sample, per dimension.
    strata: Vec<Vec<u32>>,
}

/// A stream of random numbers owned by (seed, stream, part).
fn stream(seed: u64, index: u64, part: u64) -> ChaCha12Rng {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    rng.set_stream(index);
    rng.set_word_pos(u128::from(part) << 64);
    rng
}

/// Open-interval uniform from 53 random bits.
fn open_uniform(rng: &mut impl Rng) -> f64 {
    ((rng.random::<u64>() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
}

impl Design {
    /// The design; `Err` says why it cannot be made.
    pub fn new(
        sampling: Sampling,
        seed: u64,
        samples: usize,
        dimensions: usize,
    ) -> Result<Self, String> {
        if sampling == Sampling::Sobol {
            if samples > MAX_SOBOL_SAMPLES {
                return Err(format!(
                    "sobol sampling gives at most {MAX_SOBOL_SAMPLES} samples, {samples} asked (use random or lhs)"
                ));
            }
            if dimensions > MAX_SOBOL_DIMENSIONS {
                return Err(format!(
                    "sobol sampling has at most {MAX_SOBOL_DIMENSIONS} dimensions, {dimensions} asked (use random or lhs)"
                ));
            }
        }
        let strata = if sampling == Sampling::Lhs {
            (0..dimensions)
                .map(|d| {
                    let mut order: Vec<u32> = (0..samples as u32).collect();
                    order.shuffle(&mut stream(seed, u64::MAX, d as u64));
                    order
                })
                .collect()
        } else {
            Vec::new()
        };
        Ok(Self {
            sampling,
            seed,
            samples,
            dimensions,
            strata,
        })
    }

    /// Samples in the design.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// The uniform numbers of sample `index`, one per dimension, each in (0, 1).
    pub fn point(&self, index: usize) -> Vec<f64> {
        match self.sampling {
            Sampling::Sobol => (0..self.dimensions)
                .map(|d| {
                    // f32 values k 2^-24; the half step keeps u inside (0, 1).
                    let u = sobol_burley::sample(index as u32, d as u32, self.seed as u32);
                    f64::from(u) + 0.5 / f64::from(1u32 << 24)
                })
                .collect(),
            Sampling::Random => {
                let mut rng = stream(self.seed, index as u64, 0);
                (0..self.dimensions)
                    .map(|_| open_uniform(&mut rng))
                    .collect()
            }
            Sampling::Lhs => {
                let mut rng = stream(self.seed, index as u64, 1);
                (0..self.dimensions)
                    .map(|d| {
                        let stratum = f64::from(self.strata[d][index]);
                        (stratum + open_uniform(&mut rng)) / self.samples as f64
                    })
                    .collect()
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design(sampling: Sampling, seed: u64, n: usize) -> Design {
        Design::new(sampling, seed, n, 3).expect("design")
    }

    /// The same seed gives the same samples, another seed others, and each
    /// sample is a function of its index alone.
    #[test]
    fn samples_are_functions_of_seed_and_index() {
        for sampling in [Sampling::Sobol, Sampling::Random, Sampling::Lhs] {
            let a = design(sampling, 7, 64);
            let b = design(sampling, 7, 64);
            let c = design(sampling, 8, 64);
            let forward: Vec<_> = (0..64).map(|i| a.point(i)).collect();
            let backward: Vec<_> = (0..64).rev().map(|i| b.point(i)).rev().collect();
            assert_eq!(forward, backward, "{sampling:?}");
            assert_ne!(forward, (0..64).map(|i| c.point(i)).collect::<Vec<_>>());
            assert!(forward.iter().flatten().all(|&u| u > 0.0 && u < 1.0));
        }
    }

    /// A Latin hypercube puts one sample in each stratum of every dimension;
    /// the first 2^k scrambled Sobol points do the same at resolution 2^-k.
    #[test]
    fn stratified_designs_fill_every_stratum() {
        let n = 256;
        for sampling in [Sampling::Lhs, Sampling::Sobol] {
            let d = design(sampling, 3, n);
            for dim in 0..3 {
                let mut strata: Vec<usize> = (0..n)
                    .map(|i| (d.point(i)[dim] * n as f64) as usize)
                    .collect();
                strata.sort_unstable();
                assert_eq!(strata, (0..n).collect::<Vec<_>>(), "{sampling:?} dim {dim}");
            }
        }
    }

    /// Estimating a smooth integral: scrambled Sobol beats plain Monte Carlo
    /// by far at the same sample count (E[u1 u2 u3] = 1/8).
    #[test]
    fn sobol_integrates_better_than_random() {
        let n = 4096;
        let error = |sampling| {
            let d = design(sampling, 11, n);
            let mean = (0..n)
                .map(|i| d.point(i).iter().product::<f64>())
                .sum::<f64>()
                / n as f64;
            (mean - 0.125).abs()
        };
        let (sobol, random) = (error(Sampling::Sobol), error(Sampling::Random));
        assert!(sobol < 2e-4, "sobol error {sobol}");
        assert!(random > sobol, "random {random} vs sobol {sobol}");
    }

    #[test]
    fn sobol_limits_are_refused() {
        assert!(Design::new(Sampling::Sobol, 0, MAX_SOBOL_SAMPLES + 1, 2).is_err());
        assert!(Design::new(Sampling::Sobol, 0, 10, MAX_SOBOL_DIMENSIONS + 1).is_err());
        assert!(Design::new(Sampling::Random, 0, MAX_SOBOL_SAMPLES + 1, 300).is_ok());
    }
}
