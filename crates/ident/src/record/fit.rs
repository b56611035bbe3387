//! The output-error fit of a record: all six LuGre parameters (and the mass)
//! by minimising the misfit of the simulated position to the encoder.
//!
//! * Parameters are fitted as logarithms (so they stay positive), with
//!   f_S >= f_C kept by projection.
//! * Levenberg-Marquardt on the exact forward sensitivities of
//!   [`super::plant`]; a trial step needs only the plain simulation.
//! * Continuation: first with position and velocity re-anchored to the
//!   encoder every 2 ms (nearly an equation error: a start 50% off in
//!   every parameter comes back), then the output error with the position
//!   re-anchored every horizon (10 ms by default, see
//!   [`RecordOptions::horizon`]).
//! * The start is [`super::start::estimate_start`] (nothing is asked of the
//!   user), refined by the best of a few presliding variants, since sigma0
//!   and sigma1 are the least certain first estimates, and by a grid of
//!   Stribeck curves where the record gave no Stribeck drop or no sigma2.
//! * Loss L2, or Huber's with its threshold at 1.345 robust scales.
//! * Intervals: the residuals of a record are correlated (quantisation,
//!   unmeasured forces), so Jacobian-only intervals come out far too narrow
//!   (they cover the truth in 0 to 3 of 20 disturbed records). The
//!   covariance is the linearised delete-one-block jackknife `(G-1)/G sum_b
//!   d_b d_b^T`, `d_b = (H - H_b)^-1 g_b` with `g_b` and `H_b` the score and
//!   information of block `b` (0.25 s blocks with a horizon; without one a
//!   segment with its rest, or one of 20 equal blocks when the record has
//!   fewer than 8 segments), and Student's t with (blocks - 1) degrees of
//!   freedom. It corrects the plain cluster sandwich, which is too narrow
//!   where a few blocks hold most of a parameter's information (the
//!   sliding chirp for sigma2); measured coverage in RESULTS.md. The
//!   Jacobian-only standard errors are kept alongside for comparison.

use nalgebra::{DMatrix, DVector};

use super::data::Record;
use super::plant::{Anchors, Drive, PlantTolerance, RecordParam, Simulated, Theta, simulate};
use super::segments::{Segment, anchors, blocks, detect_segments};
use super::servo_loop::ServoLoop;
use super::start::{StartEstimate, derivatives, estimate_start};
use crate::error::{IdentError, Result};
use crate::jackknife::{self, rho, weight};
use crate::stribeck::Loss;
use crate::uncertainty::{Estimate, ResidualStats, mad_scale, t95};

/// Whether the mass is known or fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MassChoice {
    /// Known, kg.
    Known(f64),
    /// Fitted with the friction.
    Fit,
}

/// Where the segments come from.
#[derive(Debug, Clone, PartialEq)]
pub enum SegmentChoice {
    /// Found from the force (rests of zero force).
    Detect,
    /// Given (a segments table).
    Given(Vec<Segment>),
    /// None: the whole record is one simulation and blocks are equal.
    Whole,
}

/// Options of a record fit.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordOptions {
    /// The mass.
    pub mass: MassChoice,
    /// The loss (L2 or Huber).
    pub loss: Loss,
    /// Relative tolerance of the plant simulation.
    pub rtol: f64,
    /// Most Levenberg-Marquardt iterations.
    pub max_iterations: usize,
    /// A start to use instead of the one found from the record (tests).
    pub start: Option<Theta>,
    /// The segments.
    pub segments: SegmentChoice,
    /// The fit's horizon, s: the simulated position is re-anchored to the
    /// encoder this often (velocity and bristle run free through the whole
    /// record). An unmeasured force makes the position drift without bound
    /// over a long motion, and a pure output error then bends the
    /// parameters to follow the drift; a horizon of 10 ms cuts the bias on a
    /// disturbed record several times and changes nothing on a clean one.
    /// `None`: pure output error, re-anchored only where a motion follows a
    /// rest. Closed loop, the horizon keeps a limit cycle (stick-slip on a
    /// moving counter-surface) from drifting out of phase, without which
    /// the fit does not converge; on a smooth tracking run `None` is better,
    /// since the servo reads every re-anchored, quantised position (sigma1
    /// off by 3e-4 on a clean 1 nm sine-tracking record, against 2e-6).
    pub horizon: Option<f64>,
    /// The scenario servo of a closed-loop record: the plant's force is
    /// then the servo's on the simulated encoder, not the recorded one
    /// (which gives only the first estimates).
    pub closed_loop: Option<ServoLoop>,
}

impl Default for RecordOptions {
    fn default() -> Self {
        Self {
            mass: MassChoice::Fit,
            loss: Loss::L2,
            rtol: 1e-8,
            max_iterations: 100,
            start: None,
            segments: SegmentChoice::Detect,
            horizon: Some(10e-3),
            closed_loop: None,
        }
    }
}

/// Where a fit stands, for a progress display.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitProgress {
    /// Iteration (0 while the start is chosen).
    pub iteration: usize,
    /// The most iterations.
    pub max_iterations: usize,
    /// RMS position residual, m.
    pub rms: f64,
}

/// A fitted record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordFit {
    /// The fitted parameters (the mass as given when it is known).
    pub theta: Theta,
    /// The parameters that were fitted.
    pub free: Vec<RecordParam>,
    /// Every parameter with its interval (the mass exact when known).
    pub estimates: Vec<(RecordParam, Estimate)>,
    /// Jacobian-only (independent residuals) standard errors of the free
    /// parameters, for comparison with the honest ones.
    pub iid_std_errors: Vec<Option<f64>>,
    /// The joint uncertainty of the free parameters (the jackknife's), when
    /// the information matrix could be inverted.
    pub joint: Option<JointUncertainty>,
    /// The first estimates from the record.
    pub start: StartEstimate,
    /// The parameters the iterations started from (the best presliding variant).
    pub refined_start: Theta,
    /// Per parameter, the box (low, high) the fit kept it in.
    pub bounds: [(f64, f64); 7],
    /// Position residual statistics, m.
    pub residuals: ResidualStats,
    /// The simulated position at every sample, m.
    pub simulated: Vec<f64>,
    /// The segments used.
    pub segments: Vec<Segment>,
    /// Number of residual blocks of the interval estimate.
    pub blocks: usize,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// Whether the output-error iterations stopped on their own (false:
    /// they hit [`RecordOptions::max_iterations`], and the answer is not a
    /// minimum).
    pub converged: bool,
    /// Plant right-hand-side evaluations in all.
    pub rhs_evaluations: u64,
    /// The loss.
    pub loss: Loss,
    /// The scenario whose servo closed the loop (closed-loop records).
    pub closed_loop: Option<String>,
}

impl RecordFit {
    /// The estimate of one parameter.
    pub fn estimate(&self, param: RecordParam) -> Estimate {
        self.estimates
            .iter()
            .find(|(p, _)| *p == param)
            .map_or(Estimate::exact(self.theta.get(param)), |(_, e)| *e)
    }
}

/// The joint uncertainty of a fit's free parameters, in the fit's own
/// space (logarithms of the parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct JointUncertainty {
    /// `Cov(ln theta)` of the free parameters, in [`RecordFit::free`] order
    /// (the linearised delete-one-block jackknife).
    pub log_covariance: DMatrix<f64>,
    /// Per block left out, `ln theta_(b) - ln theta`: how far the estimate
    /// moves without that block (the jackknife's replicates).
    pub log_replicates: Vec<DVector<f64>>,
    /// Degrees of freedom of the intervals (blocks - 1).
    pub degrees_of_freedom: usize,
}

impl RecordFit {
    /// `Cov(theta)` of the free parameters in SI units (first order:
    /// `diag(theta) Cov(ln theta) diag(theta)`).
    pub fn covariance(&self) -> Option<DMatrix<f64>> {
        let joint = self.joint.as_ref()?;
        let values: Vec<f64> = self.free.iter().map(|&p| self.theta.get(p)).collect();
        Some(DMatrix::from_fn(values.len(), values.len(), |i, j| {
            values[i] * joint.log_covariance[(i, j)] * values[j]
        }))
    }

    /// The jackknife replicates of the free parameters in SI units: the
    /// estimate with each block left out, `theta * exp(d_b)`.
    pub fn replicates(&self) -> Vec<Vec<f64>> {
        let Some(joint) = self.joint.as_ref() else {
            return Vec::new();
        };
        joint
            .log_replicates
            .iter()
            .map(|d| {
                self.free
                    .iter()
                    .enumerate()
                    .map(|(j, &p)| self.theta.get(p) * d[j].exp())
                    .collect()
            })
            .collect()
    }
}

/// What the jackknife gives: every parameter's estimate, the Jacobian-only
/// standard errors of the free ones, and their joint uncertainty.
struct Intervals {
    estimates: Vec<(RecordParam, Estimate)>,
    iid: Vec<Option<f64>>,
    joint: Option<JointUncertainty>,
}

/// The misfit of one simulation.
struct Misfit {
    sim: Simulated,
    residual: Vec<f64>,
    cost: f64,
}

/// Fits `record`; `progress` is told of every iteration and stops the fit
/// (with [`IdentError::Cancelled`]) by returning false.
pub fn fit_record(
    record: &Record,
    options: &RecordOptions,
    progress: &mut dyn FnMut(&FitProgress) -> bool,
) -> Result<RecordFit> {
    record.check()?;
    if options.loss == Loss::L1 {
        return Err(IdentError::InvalidOption(
            "a record fit takes loss l2 or huber".into(),
        ));
    }
    if let Some(h) = options.horizon
        && !(h.is_finite() && h > 0.0)
    {
        return Err(IdentError::InvalidOption(format!(
            "the horizon must be a positive number of seconds, got {}",
            fistage_model::rule::show(h)
        )));
    }
    if !(options.rtol >= 1e-14 && options.rtol < 1e-2) {
        return Err(IdentError::InvalidOption(format!(
            "rtol {} is outside [1e-14, 1e-2)",
            options.rtol
        )));
    }
    let known_mass = match options.mass {
        MassChoice::Known(m) if m.is_finite() && m > 0.0 => Some(m),
        MassChoice::Known(m) => {
            return Err(IdentError::InvalidOption(format!(
                "the mass must be a positive number of kg, got {}",
                fistage_model::rule::show(m)
            )));
        }
        MassChoice::Fit => None,
    };
    // The first estimates read friction against slip: on a moving
    // counter-surface, from the record seen from it.
    let start = match &options.closed_loop {
        Some(servo) if servo.platform_velocity != 0.0 => estimate_start(
            &record.relative_to_platform(servo.platform_velocity),
            known_mass,
        )?,
        _ => estimate_start(record, known_mass)?,
    };
    let free: Vec<RecordParam> = RecordParam::ALL
        .iter()
        .copied()
        .filter(|p| *p != RecordParam::Mass || known_mass.is_none())
        .collect();
    let segments = match &options.segments {
        // A servo holds the stage where a rest of zero force would be.
        SegmentChoice::Detect if options.closed_loop.is_some() => Vec::new(),
        SegmentChoice::Detect => detect_segments(record),
        SegmentChoice::Given(s) => s.clone(),
        SegmentChoice::Whole => Vec::new(),
    };
    let anchors = anchors(&segments);
    let mut first = options.start.unwrap_or(start.theta);
    if let Some(m) = known_mass {
        first.0[RecordParam::Mass.index()] = m;
    }
    // A start on the bound f_S = f_C leaves v_s without influence.
    let (fc, fs) = (RecordParam::FC.index(), RecordParam::FS.index());
    first.0[fs] = first.0[fs].max(1.05 * first.0[fc]);
    let problem = Problem {
        record,
        drive: options
            .closed_loop
            .as_ref()
            .map_or(Drive::Recorded, Drive::Servo),
        free: &free,
        anchors: Anchors {
            samples: &anchors,
            velocity: None,
        },
        loss: options.loss,
        rtol: options.rtol,
        center: first,
        spread: spread(&start.ruled, options.start.is_some()),
    };
    if !progress(&FitProgress {
        iteration: 0,
        max_iterations: options.max_iterations,
        rms: f64::NAN,
    }) {
        return Err(IdentError::Cancelled);
    }
    // Continuation: first with the simulated position re-anchored to the
    // encoder every 10 ms, where the misfit is nearly the velocity's and a
    // far start cannot drift into another basin; then the output error.
    let velocity = derivatives(record).velocity;
    let horizons: Vec<Vec<usize>> = [2e-3]
        .iter()
        .map(|&h| periodic_anchors(record, &anchors, h))
        .collect();
    let short = |samples| Problem {
        anchors: Anchors {
            samples,
            velocity: Some(&velocity),
        },
        ..problem
    };
    let refined_start = if options.start.is_some() {
        first
    } else {
        short(&horizons[0]).best_variant(first, &start.ruled)?
    };
    let (mut theta, mut iterations, mut rhs_evaluations) = (refined_start, 0, 0);
    for samples in &horizons {
        let stage =
            short(samples).levenberg_marquardt(theta, options.max_iterations, 1e-6, progress)?;
        theta = stage.theta;
        iterations += stage.iterations;
        rhs_evaluations += stage.rhs_evaluations;
    }
    let final_anchors = match options.horizon {
        Some(h) => periodic_anchors(record, &anchors, h),
        None => anchors.clone(),
    };
    let problem = Problem {
        anchors: Anchors {
            samples: &final_anchors,
            velocity: None,
        },
        ..problem
    };
    let mut outcome =
        problem.levenberg_marquardt(theta, options.max_iterations, 1e-13, progress)?;
    outcome.iterations += iterations;
    outcome.rhs_evaluations += rhs_evaluations;
    let block_ranges = match options.horizon {
        Some(_) => equal_blocks(record, BLOCK_DURATION),
        None => residual_blocks(&segments, record.len()),
    };
    let Intervals {
        estimates,
        iid,
        joint,
    } = problem.intervals(&outcome, &block_ranges, known_mass);
    let bounds = std::array::from_fn(|i| {
        let (center, spread) = (problem.center.0[i], problem.spread[i]);
        (center / spread, center * spread)
    });
    let residuals: Vec<f64> = outcome.misfit.residual.clone();
    let stats = ResidualStats::new(&residuals, &record.position, &record.rows, free.len());
    Ok(RecordFit {
        theta: outcome.theta,
        free,
        estimates,
        iid_std_errors: iid,
        joint,
        start,
        refined_start,
        bounds,
        residuals: stats,
        simulated: outcome.misfit.sim.position,
        segments,
        blocks: block_ranges.len(),
        iterations: outcome.iterations,
        converged: outcome.converged,
        rhs_evaluations: outcome.rhs_evaluations,
        loss: options.loss,
        closed_loop: options.closed_loop.as_ref().map(|s| s.source.clone()),
    })
}

/// The box of every parameter around its start: [`RULED_BOX`] for the
/// `ruled` ones unless the start was given.
fn spread(ruled: &[RecordParam], given: bool) -> [f64; 7] {
    let mut out = [BOX; 7];
    if !given {
        for p in ruled {
            out[p.index()] = RULED_BOX;
        }
    }
    out
}

/// `anchors` and a sample every `interval` seconds, sorted.
fn periodic_anchors(record: &Record, anchors: &[usize], interval: f64) -> Vec<usize> {
    let every = ((interval / record.sample_interval()).round() as usize).max(1);
    let mut out: Vec<usize> = (every..record.len()).step_by(every).collect();
    out.extend_from_slice(anchors);
    out.sort_unstable();
    out.dedup();
    out
}

/// Length of a residual block when the position is re-anchored every
/// horizon, s: 25 horizons, five correlation times of the disturbances the
/// coverage was measured with (`fistage bench --record`).
const BLOCK_DURATION: f64 = 0.25;

/// Consecutive blocks of `duration` seconds.
fn equal_blocks(record: &Record, duration: f64) -> Vec<(usize, usize)> {
    let n = record.len();
    let len = ((duration / record.sample_interval()) as usize).clamp(1, n);
    (0..n).step_by(len).map(|a| (a, (a + len).min(n))).collect()
}

/// Blocks of the interval estimate without a horizon: segment blocks when there are at least
/// 8, else 20 equal blocks.
fn residual_blocks(segments: &[Segment], n: usize) -> Vec<(usize, usize)> {
    let from_segments = blocks(segments);
    if from_segments.len() >= 8 {
        return from_segments;
    }
    let count = 20.min(n / 10).max(2);
    (0..count)
        .map(|b| (b * n / count, (b + 1) * n / count))
        .collect()
}

/// The result of the iterations.
struct Outcome {
    theta: Theta,
    misfit: Misfit,
    iterations: usize,
    rhs_evaluations: u64,
    /// Whether the iterations stopped on their own before the limit.
    converged: bool,
}

/// What every simulation of one fit shares.
#[derive(Clone, Copy)]
struct Problem<'a> {
    record: &'a Record,
    drive: Drive<'a>,
    free: &'a [RecordParam],
    anchors: Anchors<'a>,
    loss: Loss,
    rtol: f64,
    /// The start: every parameter stays within a factor `spread` of it.
    center: Theta,
    /// Per parameter, how far from the start it may go: [`BOX`], or
    /// [`RULED_BOX`] for one the record gave no estimate of.
    spread: [f64; 7],
}

/// How far from the start a parameter may go: a factor of 100 either way
/// (the first estimates from a record are far closer; the box keeps a far
/// start from escaping into degenerate directions such as f_S -> inf with
/// v_s -> 0, and a fit that ends on it says so).
const BOX: f64 = 100.0;

/// How far from its start a parameter set by a rule (no estimate from the
/// record: sigma2 without steady sliding, sigma0 and sigma1 without
/// presliding) may go: a rule is no centre to stay near.
const RULED_BOX: f64 = 1e6;

impl Problem<'_> {
    fn misfit(&self, theta: &Theta, sensitivities: bool, threshold: f64) -> Result<Misfit> {
        let tolerance = PlantTolerance::for_theta(theta, self.rtol);
        let sim = simulate(
            self.record,
            self.drive,
            theta,
            self.free,
            sensitivities,
            &self.anchors,
            tolerance,
        )?;
        let residual: Vec<f64> = sim
            .position
            .iter()
            .zip(&self.record.position)
            .map(|(s, m)| s - m)
            .collect();
        let cost = residual.iter().map(|&r| rho(self.loss, r, threshold)).sum();
        Ok(Misfit {
            sim,
            residual,
            cost,
        })
    }

    /// The start among presliding variants (sigma0 x {1/2, 1, 2}, sigma1 x
    /// {1/3, 1, 3}) with the least L2 misfit; then, where the record gave
    /// no Stribeck drop (f_S = f_C) or no sigma2 (no steady sliding, as in
    /// a servo's sine tracking, where the bristles lag the velocity), among
    /// a grid of Stribeck curves (f_S / f_C x v_s over the record's speeds)
    /// and sigma2 values: a rule's value is no start.
    fn best_variant(&self, theta: Theta, ruled: &[RecordParam]) -> Result<Theta> {
        let mut best = (f64::INFINITY, theta);
        let consider = |t: Theta, best: &mut (f64, Theta)| {
            if let Ok(m) = self.misfit(&t, false, f64::INFINITY)
                && m.cost.is_finite()
                && m.cost < best.0
            {
                *best = (m.cost, t);
            }
        };
        for s0 in [1.0, 0.5, 2.0] {
            for s1 in [1.0, 1.0 / 3.0, 3.0] {
                let mut t = theta;
                t.0[RecordParam::Sigma0.index()] *= s0;
                t.0[RecordParam::Sigma1.index()] *= s1;
                consider(t, &mut best);
            }
        }
        let (fc, fs, vs, s2) = (
            RecordParam::FC.index(),
            RecordParam::FS.index(),
            RecordParam::VS.index(),
            RecordParam::Sigma2.index(),
        );
        let no_drop = theta.0[fs] <= 1.06 * theta.0[fc];
        if !(no_drop || ruled.contains(&RecordParam::Sigma2)) {
            return Ok(best.1);
        }
        let center = best.1;
        let critical = 2.0 * (center.0[RecordParam::Sigma0.index()] * center.mass()).sqrt();
        // The measured velocity the anchored problem carries (found once per fit).
        let top_speed = (self.anchors.velocity.into_iter().flatten())
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let level = 0.5 * (center.0[fc] + center.0[fs]);
        for ratio in [1.1, 1.3, 1.6] {
            for k in 0..5 {
                for damping in [1e-3, 1e-2] {
                    let mut t = center;
                    t.0[fc] = level / (0.5 * (1.0 + ratio));
                    t.0[fs] = ratio * t.0[fc];
                    t.0[vs] = top_speed * 0.03 * 2f64.powi(k);
                    t.0[s2] = damping * critical;
                    consider(t, &mut best);
                }
            }
        }
        Ok(best.1)
    }

    /// Levenberg-Marquardt in the logarithms of the free parameters.
    fn levenberg_marquardt(
        &self,
        start: Theta,
        max_iterations: usize,
        converged: f64,
        progress: &mut dyn FnMut(&FitProgress) -> bool,
    ) -> Result<Outcome> {
        let p = self.free.len();
        let mut theta = start;
        let mut threshold = f64::INFINITY;
        let mut current = self.misfit(&theta, true, threshold)?;
        let mut rhs_evaluations = current.sim.rhs_evaluations;
        let mut lambda = 1e-3;
        let mut iterations = 0;
        let mut finished = false;
        while iterations < max_iterations {
            iterations += 1;
            if self.loss == Loss::Huber {
                threshold = 1.345 * mad_scale(&current.residual).max(1e-300);
                current.cost = current
                    .residual
                    .iter()
                    .map(|&r| rho(self.loss, r, threshold))
                    .sum();
            }
            let (h, g) = normal_equations(&current, p, self.loss, threshold);
            if !progress(&FitProgress {
                iteration: iterations,
                max_iterations,
                rms: rms(&current.residual),
            }) {
                return Err(IdentError::Cancelled);
            }
            let mut accepted = false;
            let mut small_step = false;
            while lambda < 1e12 {
                let mut damped = h.clone();
                for j in 0..p {
                    damped[(j, j)] += lambda * h[(j, j)].max(1e-300);
                }
                let Some(step) = damped.cholesky().map(|c| c.solve(&(-&g))) else {
                    lambda *= 10.0;
                    continue;
                };
                let longest = step.amax();
                let step = if longest > 1.0 { step / longest } else { step };
                let trial = self.apply(&theta, &step);
                small_step = step.amax() < 1e-9;
                let trial_misfit = self.misfit(&trial, false, threshold);
                if let Ok(m) = &trial_misfit {
                    rhs_evaluations += m.sim.rhs_evaluations;
                }
                match trial_misfit {
                    Ok(m) if m.cost.is_finite() && m.cost < current.cost => {
                        let relative = (current.cost - m.cost) / current.cost.max(1e-300);
                        theta = trial;
                        lambda = (lambda / 3.0).max(1e-12);
                        accepted = true;
                        current = self.misfit(&theta, true, threshold)?;
                        rhs_evaluations += current.sim.rhs_evaluations;
                        small_step |= relative < converged;
                        break;
                    }
                    _ => {
                        lambda *= 4.0;
                        if small_step {
                            break;
                        }
                    }
                }
            }
            if !accepted || small_step {
                finished = true;
                break;
            }
        }
        Ok(Outcome {
            theta,
            misfit: current,
            iterations,
            rhs_evaluations,
            converged: finished,
        })
    }

    /// `theta * exp(step)` on the free parameters, with f_S >= f_C.
    fn apply(&self, theta: &Theta, step: &DVector<f64>) -> Theta {
        let mut out = *theta;
        for (j, param) in self.free.iter().enumerate() {
            let i = param.index();
            let (center, spread) = (self.center.0[i], self.spread[i]);
            out.0[i] = (out.0[i] * step[j].exp()).clamp(center / spread, center * spread);
        }
        let (fc, fs) = (RecordParam::FC.index(), RecordParam::FS.index());
        out.0[fs] = out.0[fs].max(out.0[fc]);
        out
    }

    /// Block-jackknife estimates of every parameter, the Jacobian-only
    /// standard errors of the free ones, and their joint uncertainty.
    fn intervals(
        &self,
        outcome: &Outcome,
        block_ranges: &[(usize, usize)],
        known_mass: Option<f64>,
    ) -> Intervals {
        let p = self.free.len();
        let threshold = if self.loss == Loss::Huber {
            1.345 * mad_scale(&outcome.misfit.residual).max(1e-300)
        } else {
            f64::INFINITY
        };
        let jac = &outcome.misfit.sim.jacobian;
        let r = &outcome.misfit.residual;
        let w = |k: usize| weight(self.loss, r[k], threshold);
        let (h, _) = jackknife::normal_equations(jac, r, &w, p);
        let found = jackknife::block_jackknife(&h, jac, r, &w, block_ranges);
        let inverse = found.as_ref().map(|j| j.inverse.clone());
        let (jackknife, replicates) = match found {
            Some(j) => (Some(j.covariance), Some(j.replicates)),
            None => (None, None),
        };
        let g = block_ranges.len() as f64;
        let n = r.len() as f64;
        let s2 = outcome.misfit.residual.iter().map(|v| v * v).sum::<f64>() / (n - p as f64);
        let t = t95((g - 1.0).max(1.0));
        let mut estimates = Vec::new();
        let mut iid = Vec::new();
        for param in RecordParam::ALL {
            let value = outcome.theta.get(param);
            let Some(j) = self.free.iter().position(|q| *q == param) else {
                estimates.push((param, Estimate::exact(known_mass.unwrap_or(value))));
                continue;
            };
            let se = jackknife
                .as_ref()
                .map(|c| c[(j, j)])
                .filter(|v| v.is_finite() && *v >= 0.0)
                .map(|v| value * v.sqrt());
            iid.push(
                inverse
                    .as_ref()
                    .map(|c| c[(j, j)] * s2)
                    .filter(|v| v.is_finite() && *v >= 0.0)
                    .map(|v| value * v.sqrt()),
            );
            estimates.push((param, Estimate::new(value, se, t, 0.0)));
        }
        let joint = jackknife
            .zip(replicates)
            .filter(|(c, _)| c.iter().all(|v| v.is_finite()))
            .map(|(log_covariance, log_replicates)| JointUncertainty {
                log_covariance,
                log_replicates,
                degrees_of_freedom: block_ranges.len().saturating_sub(1),
            });
        Intervals {
            estimates,
            iid,
            joint,
        }
    }
}

/// `H = J^T W J` and `g = J^T W r` of the current misfit.
fn normal_equations(
    misfit: &Misfit,
    p: usize,
    loss: Loss,
    threshold: f64,
) -> (DMatrix<f64>, DVector<f64>) {
    let r = &misfit.residual;
    let w = |k: usize| weight(loss, r[k], threshold);
    jackknife::normal_equations(&misfit.sim.jacobian, r, &w, p)
}

fn rms(r: &[f64]) -> f64 {
    (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt()
}
