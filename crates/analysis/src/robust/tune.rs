//! Servo gains for a whole population: the proportional and derivative gains
//! (k, c) that give the largest closed-loop bandwidth while every drawn stage
//! stays linearly stable at its slipping equilibrium with a margin (its
//! largest real part at most -margin), or, with a probability target, while
//! the upper end of the Wilson 95% interval of P(unstable) stays below it.
//! The bandwidth of a PD servo on the moving mass M is taken as its natural
//! frequency sqrt(k / M) / 2 pi, so the largest admissible k wins, and among
//! the admissible c at that k the one with the widest margin.
//!
//! The search maps the worst largest real part over the population on a
//! log grid of (k, c), then refines k by bisection at the edge of the
//! admissible region. When the servo has an integral gain, the search holds
//! the scenario's k_i and then raises it as far as the criterion allows at
//! the chosen (k, c) (up to a million times). When no gains in the range are admissible (a mode the
//! servo cannot reach, such as the anti-phase bearing modes of the
//! four-bearing stage), it says so and finds by how much one element
//! parameter at a time (isolator damping, isolator stiffness, bearing mass)
//! would have to change for some gains (of a coarse grid over the same
//! ranges) to keep the population safe.

use fistage_model::{Gain, Loaded, Parameter, RobotSpec, Scenario, assemble};
use rayon::prelude::*;
use serde::Serialize;

use super::{Probability, RobustSpec};
use crate::assess::{apply_parameter, linear_verdict};

/// What the gains must achieve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Criterion {
    /// Every stage stable with its largest real part at most -margin (1/s).
    Margin(f64),
    /// The upper 95% bound of P(unstable) at most this.
    Probability(f64),
}

/// The search's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TuneSettings {
    /// Range of k, N/m.
    pub k_range: [f64; 2],
    /// Range of c, N s/m.
    pub c_range: [f64; 2],
    /// Grid values per axis (log spaced).
    pub points: usize,
    /// What is required.
    pub criterion: Criterion,
}

/// The population's drawn stages (before the gains are set).
pub struct Population {
    members: Vec<(Scenario, RobotSpec)>,
    /// Samples the model refused (not members).
    pub refused: usize,
}

/// How the population fares at one setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Standing {
    /// The largest real part over the population (NaN when none could be computed).
    pub worst_max_real_eig: f64,
    /// Members linearly unstable.
    pub unstable: usize,
    /// Members without a verdict the numerics back.
    pub undetermined: usize,
    /// Members.
    pub members: usize,
}

impl Standing {
    /// Whether the criterion holds (an undetermined member never passes).
    pub fn admits(&self, criterion: Criterion) -> bool {
        if self.undetermined > 0 || self.members == 0 {
            return false;
        }
        match criterion {
            Criterion::Margin(margin) => self.worst_max_real_eig <= -margin,
            Criterion::Probability(target) => {
                Probability::of(self.unstable, self.members).ci95[1] <= target
            }
        }
    }
}

/// A change of one element parameter that makes the population safe.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Remedy {
    /// What is changed.
    pub what: String,
    /// The parameter paths changed, each by `factor`.
    pub parameters: Vec<String>,
    /// The smallest change found (a factor on every member's value), or
    /// `None` when none in 1/64 to 1024 suffices.
    pub factor: Option<f64>,
    /// Gains (k, c) of the coarse grid that are admissible with it.
    pub gains: Option<[f64; 2]>,
}

/// What `fistage tune` found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tuning {
    /// The criterion.
    pub criterion: Criterion,
    /// Members of the population.
    pub members: usize,
    /// Samples the model refused.
    pub refused: usize,
    /// The chosen gains (k, c), when admissible gains exist.
    pub gains: Option<[f64; 2]>,
    /// With an integral gain in the scenario's servo: the largest k_i (up to
    /// a million times the scenario's) that keeps the criterion at the chosen
    /// (k, c), found after them (the search of k and c holds the scenario's
    /// k_i), N/(m s).
    pub k_i: Option<f64>,
    /// The population at those gains (with the scenario's k_i).
    pub standing: Option<Standing>,
    /// Natural frequency sqrt(k / M) / 2 pi of the chosen servo, Hz.
    pub bandwidth_hz: Option<f64>,
    /// Moving mass M, kg.
    pub moving_mass: f64,
    /// The grid's k values, N/m.
    pub k: Vec<f64>,
    /// The grid's c values, N s/m.
    pub c: Vec<f64>,
    /// The population on the grid, row by row (c rows, k columns).
    pub grid: Vec<Standing>,
    /// With no admissible gains: element changes that make some gains of a
    /// coarse grid admissible.
    pub remedies: Vec<Remedy>,
}

impl Tuning {
    /// The grid as `region.csv`: k, c, the worst largest real part (empty
    /// where not finite), the unstable and undetermined counts and the members.
    pub fn region_csv(&self) -> String {
        let mut csv = String::from("k,c,worst_max_real_eig,unstable,undetermined,members\n");
        for (i, s) in self.grid.iter().enumerate() {
            let (k, c) = (self.k[i % self.k.len()], self.c[i / self.k.len()]);
            let worst = if s.worst_max_real_eig.is_finite() {
                format!("{:e}", s.worst_max_real_eig)
            } else {
                String::new()
            };
            csv.push_str(&format!(
                "{k:e},{c:e},{worst},{},{},{}\n",
                s.unstable, s.undetermined, s.members
            ));
        }
        csv
    }
}

fn log_grid([lo, hi]: [f64; 2], n: usize) -> Vec<f64> {
    if n < 2 {
        return vec![(lo * hi).sqrt()];
    }
    (0..n)
        .map(|i| (lo.ln() + (hi.ln() - lo.ln()) * i as f64 / (n - 1) as f64).exp())
        .collect()
}

impl Population {
    /// The first `samples` stages of the study's design.
    pub fn draw(spec: &RobustSpec, base: &Loaded, robot_file: &RobotSpec, samples: usize) -> Self {
        let columns = spec.columns();
        let mut members = Vec::new();
        let mut refused = 0;
        for index in 0..samples.min(spec.samples) {
            let mut scenario = base.scenario.clone();
            let mut robot = robot_file.clone();
            let applied = columns
                .iter()
                .zip(spec.values(index))
                .try_for_each(|(t, v)| apply_parameter(&mut scenario, &mut robot, &t.path, v));
            let builds = applied.is_ok() && assemble(robot.clone(), &scenario).is_ok();
            if builds {
                members.push((scenario, robot));
            } else {
                refused += 1;
            }
        }
        Self { members, refused }
    }

    /// Members.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// The population with gains (k, c) and every value of `scaled` paths
    /// multiplied by `factor`.
    pub fn standing(&self, gains: Option<[f64; 2]>, scaled: &[String], factor: f64) -> Standing {
        let verdicts: Vec<Option<(Option<bool>, f64)>> = self
            .members
            .par_iter()
            .map(|member| verdict(member, gains, scaled, factor))
            .collect();
        let mut standing = Standing {
            worst_max_real_eig: f64::NAN,
            unstable: 0,
            undetermined: 0,
            members: verdicts.len(),
        };
        for verdict in verdicts {
            match verdict {
                Some((stable, max_real)) => {
                    standing.worst_max_real_eig = standing.worst_max_real_eig.max(max_real);
                    match stable {
                        Some(false) => standing.unstable += 1,
                        None => standing.undetermined += 1,
                        Some(true) => {}
                    }
                }
                None => standing.undetermined += 1,
            }
        }
        standing
    }

    /// Gains of the grid (k, c values) at which the population, with the
    /// `scaled` paths multiplied by `factor`, meets `criterion`, if any. Under
    /// a margin criterion each grid point stops at its first failing member.
    fn admitted_somewhere(
        &self,
        scaled: &[String],
        factor: f64,
        k_values: &[f64],
        c_values: &[f64],
        criterion: Criterion,
    ) -> Option<[f64; 2]> {
        let points: Vec<[f64; 2]> = c_values
            .iter()
            .flat_map(|&c| k_values.iter().map(move |&k| [k, c]))
            .collect();
        points
            .par_iter()
            .copied()
            .find_any(|&gains| match criterion {
                Criterion::Margin(margin) => self.members.iter().all(|member| {
                    matches!(verdict(member, Some(gains), scaled, factor),
                    Some((Some(true), max_real)) if max_real <= -margin)
                }),
                Criterion::Probability(_) => {
                    self.standing(Some(gains), scaled, factor).admits(criterion)
                }
            })
    }

    /// The c of the grid that best admits gain k (widest margin), if any.
    fn best_c(&self, k: f64, c_values: &[f64], criterion: Criterion) -> Option<(f64, Standing)> {
        c_values
            .iter()
            .map(|&c| (c, self.standing(Some([k, c]), &[], 1.0)))
            .filter(|(_, s)| s.admits(criterion))
            .min_by(|a, b| a.1.worst_max_real_eig.total_cmp(&b.1.worst_max_real_eig))
    }
}

/// One member's linear verdict with gains (k, c) and the `scaled` paths
/// multiplied by `factor`; `None` when it cannot be built or analysed.
fn verdict(
    (scenario, robot): &(Scenario, RobotSpec),
    gains: Option<[f64; 2]>,
    scaled: &[String],
    factor: f64,
) -> Option<(Option<bool>, f64)> {
    let mut scenario = scenario.clone();
    let mut robot = robot.clone();
    if let (Some([k, c]), Some(controller)) = (gains, scenario.controller.as_mut()) {
        *controller.gain_mut(Gain::K) = k;
        *controller.gain_mut(Gain::C) = c;
    }
    for path in scaled {
        let parameter = Parameter::resolve(path, &scenario, &robot).ok()?;
        let value = parameter.read(&scenario, &robot) * factor;
        parameter.write(&mut scenario, &mut robot, value).ok()?;
    }
    let (robot, model) = assemble(robot, &scenario).ok()?;
    linear_verdict(&Loaded {
        scenario,
        robot,
        model,
    })
}

/// Moving mass: every body's mass.
fn moving_mass(loaded: &Loaded) -> f64 {
    loaded.model.bodies().iter().map(|b| b.mass).sum()
}

/// Searches the gains; see the module documentation.
pub fn tune(
    population: &Population,
    base: &Loaded,
    robot_file: &RobotSpec,
    settings: &TuneSettings,
    progress: &(dyn Fn(f64) + Sync),
) -> Tuning {
    let k = log_grid(settings.k_range, settings.points);
    let c = log_grid(settings.c_range, settings.points);
    let total = (k.len() * c.len()) as f64;
    let mut grid = Vec::with_capacity(k.len() * c.len());
    for (row, &cv) in c.iter().enumerate() {
        for &kv in &k {
            grid.push(population.standing(Some([kv, cv]), &[], 1.0));
        }
        progress((row + 1) as f64 * k.len() as f64 / total);
    }
    let criterion = settings.criterion;
    // The largest admissible k on the grid, then bisection towards the next one.
    let best_column = (0..k.len())
        .rev()
        .find(|&col| (0..c.len()).any(|row| grid[row * k.len() + col].admits(criterion)));
    let (gains, standing) = match best_column {
        None => (None, None),
        Some(col) => {
            let (mut lo, mut hi) = (k[col], k.get(col + 1).copied());
            let mut best = population.best_c(lo, &c, criterion);
            if let Some(mut hi_k) = hi.take() {
                for _ in 0..12 {
                    let mid = (lo * hi_k).sqrt();
                    match population.best_c(mid, &c, criterion) {
                        Some(found) => {
                            lo = mid;
                            best = Some(found);
                        }
                        None => hi_k = mid,
                    }
                }
            }
            match best {
                Some((cv, s)) => (Some([lo, cv]), Some(s)),
                None => (None, None),
            }
        }
    };
    let mass = moving_mass(base);
    let scenario_k_i = base.scenario.controller.as_ref().map_or(0.0, |c| c.k_i);
    let k_i = match gains {
        Some(at) if scenario_k_i > 0.0 => {
            Some(scenario_k_i * largest_integral_factor(population, at, criterion))
        }
        _ => None,
    };
    let remedies = if gains.is_none() {
        let coarse = |range| log_grid(range, settings.points.min(8));
        remedies(
            population,
            base,
            robot_file,
            criterion,
            (&coarse(settings.k_range), &coarse(settings.c_range)),
        )
    } else {
        Vec::new()
    };
    Tuning {
        criterion,
        members: population.len(),
        refused: population.refused,
        gains,
        k_i,
        standing,
        bandwidth_hz: gains.map(|[kv, _]| (kv / mass).sqrt() / std::f64::consts::TAU),
        moving_mass: mass,
        k,
        c,
        grid,
        remedies,
    }
}

/// The largest factor (1 to 1e6) on every member's integral gain that keeps
/// the criterion at gains `at`, by bisection in log.
fn largest_integral_factor(population: &Population, at: [f64; 2], criterion: Criterion) -> f64 {
    let path = ["controller.k_i".to_string()];
    let admits = |f: f64| population.standing(Some(at), &path, f).admits(criterion);
    let (mut lo, mut hi) = (1.0f64, 1e6f64);
    if admits(hi) {
        return hi;
    }
    for _ in 0..24 {
        let mid = (lo * hi).sqrt();
        if admits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The element parameters tried when no gains suffice, as (what, paths).
fn candidates(base: &Loaded, robot_file: &RobotSpec) -> Vec<(String, Vec<String>)> {
    let paths = |key: &str| -> Vec<String> {
        robot_file
            .isolators
            .iter()
            .map(|i| format!("overrides.{}.{key}", i.name))
            .collect()
    };
    let mut list = Vec::new();
    if !robot_file.isolators.is_empty() {
        list.push((
            "isolator damping (c_x of every isolator)".to_string(),
            paths("c_x"),
        ));
        list.push((
            "isolator stiffness (k_x of every isolator)".to_string(),
            paths("k_x"),
        ));
    }
    if Parameter::resolve("beta", &base.scenario, robot_file).is_ok() {
        list.push((
            "bearing mass (beta: every link with a friction contact)".to_string(),
            vec!["beta".to_string()],
        ));
    }
    list
}

/// For each candidate, the smallest change (a factor, tried from 1 outwards
/// in both directions on a log scale, then bisected) that makes the
/// population safe at some gains of the coarse grid (k values, c values).
fn remedies(
    population: &Population,
    base: &Loaded,
    robot_file: &RobotSpec,
    criterion: Criterion,
    (k_values, c_values): (&[f64], &[f64]),
) -> Vec<Remedy> {
    candidates(base, robot_file)
        .into_iter()
        .map(|(what, parameters)| {
            let safe = |f: f64| {
                population.admitted_somewhere(&parameters, f, k_values, c_values, criterion)
            };
            let found = smallest_safe_factor(&safe);
            Remedy {
                what,
                parameters,
                factor: found.map(|(f, _)| f),
                gains: found.map(|(_, g)| g),
            }
        })
        .collect()
}

/// The factor nearest 1 (on a log scale, from 1/64 to 1024) for which
/// `safe` finds gains, refined by bisection against the last factor that
/// failed, with those gains.
fn smallest_safe_factor(safe: &dyn Fn(f64) -> Option<[f64; 2]>) -> Option<(f64, [f64; 2])> {
    for step in 1..=10 {
        for f in [2f64.powi(step), 2f64.powi(-step)] {
            if f < 1.0 / 64.0 {
                continue;
            }
            let Some(mut gains) = safe(f) else {
                continue;
            };
            let (mut failed, mut passed) = (if f > 1.0 { f / 2.0 } else { f * 2.0 }, f);
            for _ in 0..8 {
                let mid = (failed * passed).sqrt();
                match safe(mid) {
                    Some(at) => {
                        passed = mid;
                        gains = at;
                    }
                    None => failed = mid,
                }
            }
            return Some((passed, gains));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_grids_span_their_range() {
        let g = log_grid([1e3, 1e7], 5);
        assert_eq!(g.len(), 5);
        assert!((g[0] - 1e3).abs() < 1e-9 && (g[4] - 1e7).abs() < 1e-6);
        assert!((g[2] - 1e5).abs() < 1e-6);
    }

    #[test]
    fn undetermined_members_never_pass() {
        let s = Standing {
            worst_max_real_eig: -5.0,
            unstable: 0,
            undetermined: 1,
            members: 10,
        };
        assert!(!s.admits(Criterion::Margin(0.0)));
        let sound = Standing {
            undetermined: 0,
            ..s
        };
        assert!(sound.admits(Criterion::Margin(1.0)));
        assert!(!sound.admits(Criterion::Margin(10.0)));
        // 0 of 10 unstable: the Wilson upper bound is 0.28.
        assert!(sound.admits(Criterion::Probability(0.3)));
        assert!(!sound.admits(Criterion::Probability(0.2)));
    }
}
