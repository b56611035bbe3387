//! Seeded synthetic measurements from known LuGre parameters, with the errors a
//! real stage adds: force-sensor noise, velocity ripple and encoder quantisation,
//! a few gross outliers, different friction on the two branches; FRFs with noise
//! on magnitude (dB) and phase (degrees). Also writers of lab-style CSV files.
//!
//! The generator is xoshiro256** seeded through SplitMix64, with Box-Muller
//! normal deviates: the same seed gives the same data on every platform.

use std::f64::consts::PI;
use std::fmt::Write as _;

use fistage_model::LugreParams;

use crate::Complex;
use crate::frf::FrfData;
use crate::stribeck::StribeckData;
use crate::units::{Quantity, Unit};

/// A small seeded pseudo-random generator (xoshiro256**).
#[derive(Debug, Clone)]
pub struct Rng {
    state: [u64; 4],
}

impl Rng {
    /// A generator whose sequence is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        let mut x = seed;
        let mut next = || {
            x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        Self {
            state: [next(), next(), next(), next()],
        }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.state;
        let result = s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal deviate (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }

    /// Uniform integer in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.uniform() * n as f64) as usize).min(n.saturating_sub(1))
    }
}

/// Moving mass of the paper's stage, m_t + m_b = 1.5 kg.
pub const TABLE1_MASS: f64 = 1.5;

/// Moving mass of [`small_stage`], kg.
pub const SMALL_STAGE_MASS: f64 = 0.25;

/// A small stage, far from Table 1: f_C = 1 N, f_S = 1.5 N, v_s = 3 mm/s,
/// sigma2 = 4 N s/m, sigma0 = 1.2e5 N/m, sigma1 = 30 N s/m (mass 0.25 kg).
pub fn small_stage() -> LugreParams {
    LugreParams {
        sigma0: 1.2e5,
        sigma1: 30.0,
        sigma2: 4.0,
        f_c: 1.0,
        f_s: 1.5,
        v_s: 3e-3,
    }
}

/// A synthetic constant-velocity friction test.
#[derive(Debug, Clone, PartialEq)]
pub struct StribeckSynth {
    /// Friction of the positive branch (and of the negative one unless `negative` is set).
    pub params: LugreParams,
    /// Friction of the negative branch, for asymmetric data.
    pub negative: Option<LugreParams>,
    /// Test velocities per sign, logarithmically spaced.
    pub points_per_sign: usize,
    /// Smallest |v|, m/s.
    pub v_min: f64,
    /// Largest |v|, m/s.
    pub v_max: f64,
    /// Standard deviation of the force-sensor noise, N.
    pub force_noise: f64,
    /// Relative standard deviation of the velocity actually held (speed ripple).
    pub velocity_noise: f64,
    /// Velocity quantum of the encoder-based measurement (resolution / averaging window), m/s.
    pub velocity_quantum: f64,
    /// Number of gross outliers.
    pub outliers: usize,
    /// Typical size of an outlier, N (each is 0.7 to 1.3 times this, random sign).
    pub outlier_size: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl StribeckSynth {
    /// Exact data: 40 velocities per sign from v_s/30 to 40 v_s, no noise.
    pub fn clean(params: LugreParams) -> Self {
        Self {
            params,
            negative: None,
            points_per_sign: 40,
            v_min: params.v_s / 30.0,
            v_max: 40.0 * params.v_s,
            force_noise: 0.0,
            velocity_noise: 0.0,
            velocity_quantum: 0.0,
            outliers: 0,
            outlier_size: 0.0,
            seed: 0,
        }
    }

    /// Realistic noise: force noise 1% of f_C, speed ripple 0.1%, encoder of
    /// 0.1 um read over 0.1 s (velocity quantum 1 um/s).
    pub fn noisy(params: LugreParams, seed: u64) -> Self {
        Self {
            force_noise: 0.01 * params.f_c,
            velocity_noise: 1e-3,
            velocity_quantum: 1e-6,
            seed,
            ..Self::clean(params)
        }
    }

    /// Adds `count` gross outliers of about `size` newtons.
    pub fn with_outliers(self, count: usize, size: f64) -> Self {
        Self {
            outliers: count,
            outlier_size: size,
            ..self
        }
    }

    /// Gives the negative branch its own friction.
    pub fn with_negative(self, negative: LugreParams) -> Self {
        Self {
            negative: Some(negative),
            ..self
        }
    }

    /// The measured curve, sorted by velocity, in memory (source `synthetic`).
    pub fn generate(&self) -> StribeckData {
        self.generate_with_outliers().0
    }

    /// The measured curve and the indices of the points made outliers.
    pub fn generate_with_outliers(&self) -> (StribeckData, Vec<usize>) {
        let mut rng = Rng::new(self.seed);
        let n = self.points_per_sign.max(1);
        let magnitudes: Vec<f64> = (0..n)
            .map(|i| {
                let t = if n > 1 {
                    i as f64 / (n - 1) as f64
                } else {
                    0.0
                };
                self.v_min * (self.v_max / self.v_min).powf(t)
            })
            .collect();
        let mut velocity = Vec::with_capacity(2 * n);
        let mut force = Vec::with_capacity(2 * n);
        let branches = [
            (-1.0, self.negative.unwrap_or(self.params)),
            (1.0, self.params),
        ];
        for (sign, params) in branches {
            let ordered: Vec<f64> = if sign < 0.0 {
                magnitudes.iter().rev().map(|m| -m).collect()
            } else {
                magnitudes.clone()
            };
            for v_true in ordered {
                let held = v_true * (1.0 + self.velocity_noise * rng.normal());
                velocity.push(self.quantise(held, v_true));
                force.push(params.steady_state_force(held) + self.force_noise * rng.normal());
            }
        }
        let outliers = self.add_outliers(&mut rng, &mut force);
        (StribeckData::new("synthetic", velocity, force), outliers)
    }

    /// Rounds to the velocity quantum, never to zero or across the sign.
    fn quantise(&self, v: f64, v_true: f64) -> f64 {
        if self.velocity_quantum <= 0.0 {
            return v;
        }
        let q = (v / self.velocity_quantum).round() * self.velocity_quantum;
        if q == 0.0 || q.signum() != v_true.signum() {
            self.velocity_quantum.copysign(v_true)
        } else {
            q
        }
    }

    fn add_outliers(&self, rng: &mut Rng, force: &mut [f64]) -> Vec<usize> {
        let mut hit = Vec::new();
        while hit.len() < self.outliers.min(force.len()) {
            let i = rng.below(force.len());
            if hit.contains(&i) {
                continue;
            }
            hit.push(i);
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            force[i] += sign * self.outlier_size * (0.7 + 0.6 * rng.uniform());
        }
        hit.sort_unstable();
        hit
    }
}

/// A synthetic pre-motion FRF measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfSynth {
    /// sigma0, N/m.
    pub sigma0: f64,
    /// sigma1 + sigma2, N s/m.
    pub damping: f64,
    /// m_t + m_b, kg.
    pub mass: f64,
    /// Lowest frequency, Hz.
    pub f_min_hz: f64,
    /// Highest frequency, Hz.
    pub f_max_hz: f64,
    /// Number of frequencies, logarithmically spaced.
    pub points: usize,
    /// Standard deviation of the magnitude noise, dB.
    pub magnitude_noise_db: f64,
    /// Standard deviation of the phase noise, degrees.
    pub phase_noise_deg: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl FrfSynth {
    /// Exact data: 100 frequencies from a tenth to ten times the natural frequency.
    ///
    /// Stiffness and damping are those of the model's friction force linearised
    /// at rest (paper Eq. 32), taken from [`LugreParams::force_and_z_rate`]: at
    /// v = 0 a bristle deflection z gives the force sigma0 z, at z = 0 a velocity
    /// v gives (sigma1 + sigma2) v, both exactly.
    pub fn clean(params: &LugreParams, mass: f64) -> Self {
        let (stiffness, _) = params.force_and_z_rate(0.0, 1.0);
        let (damping, _) = params.force_and_z_rate(1.0, 0.0);
        let f_n = (stiffness / mass).sqrt() / (2.0 * PI);
        Self {
            sigma0: stiffness,
            damping,
            mass,
            f_min_hz: f_n / 10.0,
            f_max_hz: 10.0 * f_n,
            points: 100,
            magnitude_noise_db: 0.0,
            phase_noise_deg: 0.0,
            seed: 0,
        }
    }

    /// Realistic noise: 0.1 dB on magnitude, 0.5 degrees on phase.
    pub fn noisy(params: &LugreParams, mass: f64, seed: u64) -> Self {
        Self {
            magnitude_noise_db: 0.1,
            phase_noise_deg: 0.5,
            seed,
            ..Self::clean(params, mass)
        }
    }

    /// The measured FRF (complex, with phase), in memory (source `synthetic`).
    pub fn generate(&self) -> FrfData {
        let mut rng = Rng::new(self.seed);
        let n = self.points.max(1);
        let mut omega = Vec::with_capacity(n);
        let mut response = Vec::with_capacity(n);
        for i in 0..n {
            let t = if n > 1 {
                i as f64 / (n - 1) as f64
            } else {
                0.0
            };
            let w = 2.0 * PI * self.f_min_hz * (self.f_max_hz / self.f_min_hz).powf(t);
            let g = Complex::new(self.sigma0 - self.mass * w * w, w * self.damping).inv();
            let gain = 10f64.powf(self.magnitude_noise_db * rng.normal() / 20.0);
            let turn = (self.phase_noise_deg * rng.normal()).to_radians();
            omega.push(w);
            response.push(g * Complex::from_polar(gain, turn));
        }
        FrfData::new_complex("synthetic", omega, response)
    }
}

/// Writes an f_ss curve as a lab would export it, e.g. `velocity_mm_per_s,force_N`.
pub fn stribeck_csv(data: &StribeckData, velocity_unit: Unit, force_unit: Unit) -> String {
    let mut out = format!(
        "velocity_{},force_{}\n",
        velocity_unit.suffix(),
        force_unit.suffix()
    );
    for (v, f) in data.velocity.iter().zip(&data.force) {
        let _ = writeln!(
            out,
            "{},{}",
            velocity_unit.from_si(*v),
            force_unit.from_si(*f)
        );
    }
    out
}

/// Column layout of an FRF file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrfCsvLayout {
    /// `re_G_<unit>`, `im_G_<unit>`.
    Complex(Unit),
    /// `mag_<unit>`, `phase_<unit>`.
    MagnitudePhase(Unit, Unit),
    /// `mag_<unit>` only.
    Magnitude(Unit),
}

/// Writes an FRF as a lab would export it, frequencies in `freq_unit`.
pub fn frf_csv(data: &FrfData, freq_unit: Unit, layout: FrfCsvLayout) -> String {
    let freq = format!("freq_{}", freq_unit.suffix());
    let mut out = match layout {
        FrfCsvLayout::Complex(u) => format!("{freq},re_G_{0},im_G_{0}\n", u.suffix()),
        FrfCsvLayout::MagnitudePhase(m, p) => {
            format!("{freq},mag_{},phase_{}\n", m.suffix(), p.suffix())
        }
        FrfCsvLayout::Magnitude(m) => format!("{freq},mag_{}\n", m.suffix()),
    };
    for (w, g) in data.omega.iter().zip(&data.response) {
        let f = freq_unit.from_si(*w);
        let _ = match layout {
            FrfCsvLayout::Complex(u) => {
                writeln!(out, "{f},{},{}", u.from_si(g.re), u.from_si(g.im))
            }
            FrfCsvLayout::MagnitudePhase(m, p) => {
                writeln!(out, "{f},{},{}", m.from_si(g.norm()), p.from_si(g.arg()))
            }
            FrfCsvLayout::Magnitude(m) => writeln!(out, "{f},{}", m.from_si(g.norm())),
        };
    }
    out
}

/// The unit of `quantity` named `name`; panics on a name that is not one (for
/// writing test files, never for user input).
pub fn unit(quantity: Quantity, name: &str) -> Unit {
    match Unit::parse(quantity, name) {
        Some(u) => u,
        None => panic!("{name} is not a unit of {quantity}"),
    }
}

/// The 80-point f_ss curve of Table 1 with realistic noise (seed 1): the
/// standard Stribeck timing case.
pub fn benchmark_stribeck_data() -> StribeckData {
    StribeckSynth::noisy(LugreParams::paper_table1(), 1).generate()
}

/// The 100-point FRF of Table 1 with realistic noise (seed 1): the standard
/// FRF timing case.
pub fn benchmark_frf_data() -> FrfData {
    FrfSynth::noisy(&LugreParams::paper_table1(), TABLE1_MASS, 1).generate()
}
