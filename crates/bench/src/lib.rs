//! `fistage bench`: measured speed and accuracy, printed as the Markdown tables
//! that BENCHMARKS.md quotes. Engine cases time only the integration (no output
//! signals, no files), take the median of several repeats, and measure the
//! error against a run at a much tighter tolerance. Identification cases time
//! whole fits on the standard synthetic data sets.
//!
//! The harness is a crate of its own so that the library crates and the
//! program's other commands do not carry it: `fistage bench` parses
//! [`BenchArgs`] and calls [`run`]. Each table is a module: `matched.rs`
//! (matched-accuracy ratios), `rhs.rs` (right-hand-side cost), `record.rs`
//! (record fits), `robust.rs` (tolerance analyses), `population.rs`
//! (stages per CPU-second of simulated populations), `fmu.rs` (FMUs through the C
//! ABI and FMPy), `python.rs` (the Python package), `peers/` (CVODE and
//! SciPy); `timing.rs` is how everything is timed.
//!
//! ```no_run
//! use clap::Parser;
//!
//! /// The program's `bench` command, as a program of its own.
//! #[derive(Parser)]
//! struct Bench {
//!     #[command(flatten)]
//!     args: fistage_bench::BenchArgs,
//! }
//!
//! // The cost of one right-hand-side evaluation, compiled, generic and by
//! // hand, as `fistage bench --rhs` prints it.
//! let bench = Bench::parse_from(["bench", "--rhs", "--repeat", "3"]);
//! fistage_bench::run(&bench.args)?;
//! # Ok::<(), anyhow::Error>(())
//! ```

mod fmu;
mod matched;
pub mod peers;
mod population;
mod python;
mod record;
mod rhs;
mod robust;
mod timing;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use fistage_model::Loaded;
use fistage_sim::{
    Engine, Excitation, ScenarioExcitation, SimSettings, Trajectory, engine_for, initial_state,
};

use crate::matched::{AccuracyRow, print_matched};
use crate::timing::{median, median_time, thread_cpu_time};

/// Arguments of `fistage bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenario to time (default: the standard suite, the paper's Fig. 5b
    /// stage with FI and the four-bearing traverse, then the identification fits).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Relative tolerances to compare (default: 1e-6, 1e-8, 1e-10 for the
    /// 1-DOF stage, 1e-6, 1e-8 for the 6-DOF traverse).
    #[arg(long, value_delimiter = ',')]
    pub rtol: Vec<f64>,
    /// Tolerance of the reference run.
    #[arg(long, default_value_t = 1e-13)]
    pub reference_rtol: f64,
    /// Repeats per case (the median is reported).
    #[arg(long, default_value_t = 21)]
    pub repeat: usize,
    /// Engines to time instead of the scenario's own (comma-separated:
    /// auto, native, imex, dop853, rk4, rosenbrock), each in its own rows of the table.
    #[arg(long, value_delimiter = ',')]
    pub engine: Vec<String>,
    /// Signal whose error is reported (default: the position read by the
    /// scenario's servo sensor, else by the model's first sensor;
    /// `encoder.position` on the shipped stages).
    #[arg(long)]
    pub signal: Option<String>,
    /// Time the FMI face only: fmi2DoStep from Rust and FMPy's simulate_fmu.
    #[arg(long)]
    pub fmu: bool,
    /// Compare the native and rapier engines side by side (wall time and
    /// accuracy against a tight native run) on the paper's Fig. 5b stage and
    /// the four-bearing traverse, or on `--scenario`.
    #[arg(long)]
    pub engines: bool,
    /// Explicit (native) against linearly implicit (rosenbrock) engine on the
    /// four-bearing traverse with its isolators' five stiff directions scaled
    /// by 0.01 (where accuracy, not the stiff modes, sets the step), 1, 10, 100 and 1000.
    #[arg(long)]
    pub stiffness: bool,
    /// Time a tolerance analysis of the four-bearing stage (or of
    /// `--scenario`, which needs a [robust] table): 10 000 linear and 1 000
    /// simulated 2 s samples, then the 40 x 40 simulated sweep of
    /// `scenarios/bench/fig06b_40x40.toml`, on one and two threads.
    #[arg(long)]
    pub robust: bool,
    /// Stages per CPU-second of simulated populations on one and two
    /// threads: the 1-DOF FI population of
    /// `scenarios/robust/fig05b_simulated.toml` (4 000 stages), 200 stages
    /// of the four-bearing population, and the 40 x 40 simulated sweep of
    /// `scenarios/bench/fig06b_40x40.toml`.
    #[arg(long)]
    pub population: bool,
    /// Time the Python package's `Scenario.run()` against the program on
    /// fig05b in one invocation (`--python` names the interpreter; default
    /// `target/py-venv/bin/python`, else `python3`).
    #[arg(long = "python-run")]
    pub python_run: bool,
    /// Time the record fit (`identify record`, one-mass and stage) on 7 s
    /// records at 10 kHz, and measure its intervals' coverage on 20
    /// disturbed records (one-mass, both horizons; the FI stage: minutes).
    #[arg(long)]
    pub record: bool,
    /// Run the peers beside the native engine in the same invocation: CVODE
    /// BDF (exact Jacobian) and Adams (SUNDIALS 6 from Debian's
    /// libsundials-dev, opened at run time) and SciPy's solve_ivp (RK45,
    /// DOP853, BDF; through the Python package, with `--python` or
    /// target/py-venv/bin/python), with a table of CPU-time ratios at the
    /// same rtol and one at matched accuracy (each peer's cost of each
    /// fistage row's relative error, read from the peer's rows).
    #[arg(long)]
    pub peers: bool,
    /// Time one right-hand side of the assembled model against a
    /// hand-written kernel of the same equations on one-axis stages of 1, 4
    /// and 8 bearings (5, 14, 26 states), and on the 6-DOF four-bearing stage.
    #[arg(long)]
    pub rhs: bool,
    /// Time each engine also on the generic evaluation of the right-hand
    /// side (no machine code), in rows of its own beside the compiled ones.
    #[arg(long)]
    pub interpreted: bool,
    /// Python with FMPy for the FMU table (default: the test environment's,
    /// `target/fmi-venv/bin/python`, else `python3`).
    #[arg(long)]
    pub python: Option<PathBuf>,
}

fn fmu_python(args: &BenchArgs) -> PathBuf {
    args.python.clone().unwrap_or_else(|| {
        let venv = PathBuf::from("target/fmi-venv/bin/python");
        if venv.is_file() {
            venv
        } else {
            PathBuf::from("python3")
        }
    })
}

pub(crate) struct Timing {
    wall_s: f64,
    cpu_s: f64,
    trajectory: Trajectory,
}

/// Timed runs of one engine on one model at one tolerance, one at a time.
struct RunTimer<'a> {
    loaded: &'a Loaded,
    x0: Vec<f64>,
    excitation: ScenarioExcitation,
    settings: SimSettings,
    walls: Vec<f64>,
    cpus: Vec<f64>,
    last: Option<Trajectory>,
}

impl<'a> RunTimer<'a> {
    fn new(loaded: &'a Loaded, rtol: f64) -> anyhow::Result<Self> {
        let scenario = &loaded.scenario;
        Ok(Self {
            loaded,
            x0: initial_state(&loaded.model, scenario)?,
            excitation: ScenarioExcitation::from_scenario(scenario),
            settings: SimSettings {
                rtol,
                ..SimSettings::from_scenario(scenario)
            },
            walls: Vec::new(),
            cpus: Vec::new(),
            last: None,
        })
    }

    /// One timed run.
    fn once(&mut self, engine: &dyn Engine) -> anyhow::Result<()> {
        let (wall, cpu) = (Instant::now(), thread_cpu_time());
        let trajectory = engine.simulate(
            &self.loaded.model,
            &self.x0,
            &self.excitation,
            &self.settings,
            &mut fistage_sim::no_progress,
        )?;
        self.cpus.push(thread_cpu_time() - cpu);
        self.walls.push(wall.elapsed().as_secs_f64());
        self.last = Some(trajectory);
        Ok(())
    }

    /// The median times and the last run.
    fn finish(mut self) -> anyhow::Result<Timing> {
        Ok(Timing {
            wall_s: median(&mut self.walls),
            cpu_s: median(&mut self.cpus),
            trajectory: self.last.context("no run")?,
        })
    }
}

fn time_run(
    loaded: &Loaded,
    engine: &dyn Engine,
    rtol: f64,
    repeat: usize,
) -> anyhow::Result<Timing> {
    let mut timer = RunTimer::new(loaded, rtol)?;
    for _ in 0..repeat.max(1) {
        timer.once(engine)?;
    }
    timer.finish()
}

/// Largest deviation of a signal between two trajectories on the same grid.
fn max_deviation(
    loaded: &Loaded,
    a: &Trajectory,
    b: &Trajectory,
    signal: &str,
) -> anyhow::Result<(f64, f64)> {
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let (ta, tb) = (
        a.signals(&loaded.model, &excitation),
        b.signals(&loaded.model, &excitation),
    );
    let missing = || {
        let names: Vec<&str> = loaded
            .model
            .signals()
            .iter()
            .map(|s| s.name.as_str())
            .collect();
        format!(
            "no signal {signal} (the model's signals: {})",
            names.join(", ")
        )
    };
    let (xa, xb) = (
        ta.column(signal).with_context(missing)?,
        tb.column(signal).with_context(missing)?,
    );
    anyhow::ensure!(xa.len() == xb.len(), "trajectories have different grids");
    let worst = xa
        .iter()
        .zip(xb)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max);
    let size = xb.iter().map(|v| v.abs()).fold(0.0, f64::max);
    Ok((worst, worst / size))
}

/// The signal whose error the tables report: `--signal`, else the position
/// read by the servo's sensor, else by the model's first sensor.
fn error_signal(args: &BenchArgs, loaded: &Loaded) -> anyhow::Result<String> {
    if let Some(signal) = &args.signal {
        return Ok(signal.clone());
    }
    let model = &loaded.model;
    let sensor = model
        .controller()
        .and_then(|controller| model.sensors().get(controller.sensor))
        .or_else(|| model.sensors().first())
        .with_context(|| {
            format!(
                "{}: the model has no sensor whose position to compare: name a signal with --signal",
                loaded.scenario.file.display()
            )
        })?;
    Ok(format!("{}.position", sensor.name))
}

/// The run the errors are measured against, and how the table names it: the
/// scenario's engine at the reference tolerance, or, for the fixed-step
/// rapier engine (which has no tolerance to tighten), the same engine at a
/// quarter of its step.
fn reference_for(
    args: &BenchArgs,
    loaded: &Loaded,
    engine: Box<dyn Engine>,
) -> anyhow::Result<(Box<dyn Engine>, String)> {
    use fistage_sim::rapier_engine::RapierEngine;
    if engine.kind() != fistage_model::EngineKind::Rapier {
        return Ok((engine, format!("rtol {:e}", args.reference_rtol)));
    }
    let dt = scenario_rapier_step(loaded)?;
    let mut settings = loaded.scenario.rapier.clone();
    settings.dt = Some(dt / 4.0);
    let against = format!(
        "the same engine at a quarter of its step (dt {:.3e} s)",
        dt / 4.0
    );
    Ok((Box::new(RapierEngine { settings }), against))
}

/// The rapier engine's step for a scenario: its `rapier.dt`, else the one
/// the engine derives from the model's fastest mode at the start.
fn scenario_rapier_step(loaded: &Loaded) -> anyhow::Result<f64> {
    let x0 = initial_state(&loaded.model, &loaded.scenario)?;
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let (dt, _) = fistage_sim::rapier_engine::rapier_step(
        &loaded.model,
        &x0,
        &excitation.inputs(0.0),
        &loaded.scenario.rapier,
        1.0 / loaded.scenario.sample_rate,
    );
    Ok(dt)
}

/// Runs the benchmark and prints Markdown.
pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    anyhow::ensure!(args.repeat >= 1, "--repeat must be at least 1, got 0");
    let suite = Path::new("scenarios/paper/fig05b_fi.toml");
    if args.scenario.is_none() && !suite.is_file() {
        anyhow::bail!(
            "the default suite reads the repository's scenarios/ ({} is not here): run it from the repository root, or give --scenario FILE",
            suite.display()
        );
    }
    if args.fmu {
        return crate::fmu::fmu_table(&fmu_python(args), args.repeat.min(5));
    }
    if args.stiffness {
        return stiffness_table(args);
    }
    if args.rhs {
        return crate::rhs::rhs_table(args.repeat);
    }
    if args.python_run {
        let python = args.python.clone().unwrap_or_else(|| {
            let venv = PathBuf::from("target/py-venv/bin/python");
            if venv.is_file() {
                venv
            } else {
                PathBuf::from("python3")
            }
        });
        return crate::python::python_table(&python);
    }
    if args.record {
        crate::record::record_table(args.repeat)?;
        println!();
        crate::record::coverage_table()?;
        println!();
        return crate::record::stage_coverage_table();
    }
    if args.population {
        return crate::population::population_table();
    }
    if args.robust {
        let scenario = args
            .scenario
            .clone()
            .unwrap_or_else(|| PathBuf::from("scenarios/robust/four_bearing_population.toml"));
        return crate::robust::robust_table(&scenario);
    }
    if args.engines {
        let scenarios = match &args.scenario {
            Some(scenario) => vec![scenario.clone()],
            None => vec![
                PathBuf::from("scenarios/paper/fig05b_fi.toml"),
                PathBuf::from("scenarios/coupling/friction20_traverse.toml"),
            ],
        };
        for scenario in scenarios {
            engines_table(args, &scenario)?;
            println!();
        }
        return Ok(());
    }
    match &args.scenario {
        Some(scenario) => {
            let rtol = if args.rtol.is_empty() {
                vec![1e-6, 1e-8, 1e-10]
            } else {
                args.rtol.clone()
            };
            engine_table(args, scenario, &rtol)
        }
        None => {
            engine_table(
                args,
                &PathBuf::from("scenarios/paper/fig05b_fi.toml"),
                &[1e-6, 1e-8, 1e-10],
            )?;
            println!();
            engine_table(
                args,
                &PathBuf::from("scenarios/coupling/friction20_traverse.toml"),
                &[1e-6, 1e-8],
            )?;
            println!();
            ident_table(args.repeat)?;
            println!();
            crate::record::record_table(args.repeat)?;
            println!();
            crate::fmu::fmu_table(&fmu_python(args), args.repeat.min(5))
        }
    }
}

fn ident_table(repeat: usize) -> anyhow::Result<()> {
    use fistage_ident::synth::{TABLE1_MASS, benchmark_frf_data, benchmark_stribeck_data};
    use fistage_ident::{
        FrfOptions, Loss, StribeckOptions, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
    };
    let stribeck = benchmark_stribeck_data();
    let frf = benchmark_frf_data();
    println!(
        "LuGre identification on the standard synthetic data (Table 1 with noise), median of {repeat} fits, release build\n"
    );
    println!("| fit | data | ms per fit |");
    println!("|---|---|---|");
    for loss in [Loss::L2, Loss::Huber, Loss::L1] {
        let options = StribeckOptions {
            loss,
            ..StribeckOptions::default()
        };
        let t = median_time(
            repeat,
            || Ok(fit_stribeck(&stribeck, &options).map(|_| ())?),
        )?;
        println!(
            "| Stribeck, {} | f_ss, {} points | {:.3} |",
            loss.name(),
            stribeck.len(),
            t * 1e3
        );
    }
    let t = median_time(repeat, || {
        Ok(fit_stribeck_asymmetric(&stribeck, &StribeckOptions::default()).map(|_| ())?)
    })?;
    println!(
        "| Stribeck, l2, asymmetric (3 fits + test) | f_ss, {} points | {:.3} |",
        stribeck.len(),
        t * 1e3
    );
    for (name, options) in [
        ("known mass", FrfOptions::with_mass(TABLE1_MASS)),
        ("fitted mass", FrfOptions::default()),
    ] {
        let t = median_time(repeat, || Ok(fit_frf(&frf, &options).map(|_| ())?))?;
        println!(
            "| FRF, complex, {name} | {} frequencies | {:.3} |",
            frf.len(),
            t * 1e3
        );
    }
    Ok(())
}

fn engine_table(args: &BenchArgs, scenario: &Path, rtols: &[f64]) -> anyhow::Result<()> {
    let loaded = fistage_model::load(scenario)?;
    let signal = error_signal(args, &loaded)?;
    let engine = engine_for(&loaded.scenario);
    let timed: Vec<Box<dyn Engine>> = if args.engine.is_empty() {
        vec![engine_for(&loaded.scenario)]
    } else {
        args.engine
            .iter()
            .map(|name| {
                let kind: fistage_model::EngineKind = name
                    .parse()
                    .map_err(|e: String| anyhow::anyhow!("--engine: {e}"))?;
                Ok(fistage_sim::engine_in(&loaded.scenario, kind))
            })
            .collect::<anyhow::Result<_>>()?
    };
    let engine_name = engine.name();
    let (reference_engine, against) = reference_for(args, &loaded, engine)?;
    eprintln!("reference run ({against}) ...");
    let reference = time_run(&loaded, reference_engine.as_ref(), args.reference_rtol, 1)?;
    let simulated = loaded.scenario.duration;
    println!(
        "`{}` ({} s simulated, engine {}, median of {} runs, error of `{}` against {against}, release build)\n",
        scenario.display(),
        simulated,
        engine_name,
        args.repeat,
        signal,
    );
    println!("{}\n", compile_note(&loaded.model));
    let interpreted = Loaded {
        model: loaded.model.interpreted(),
        ..loaded.clone()
    };
    let evaluations: Vec<(&Loaded, &str)> = if args.interpreted {
        vec![(&loaded, ""), (&interpreted, ", generic evaluation")]
    } else {
        vec![(&loaded, "")]
    };
    println!(
        "| rtol | wall ms | CPU ms | x real time | steps | rejected | RHS evals | max error (m) | relative error | method |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let cvode = args.peers.then(crate::peers::cvode::Cvode::open);
    let mut ratios = Vec::new();
    let mut fistage_rows = Vec::new();
    let mut peer_rows: Vec<(String, Vec<AccuracyRow>)> = Vec::new();
    // One run of every contender per round, the rounds one after the other:
    // fistage's engines (and their generic evaluation) and, with --peers,
    // CVODE's methods, at every tolerance, so a drift of the machine's speed
    // falls on all of them alike.
    let contenders: Vec<(&dyn Engine, &Loaded, &str)> = timed
        .iter()
        .flat_map(|engine| {
            evaluations
                .iter()
                .map(move |(l, s)| (engine.as_ref(), *l, *s))
        })
        .collect();
    let mut per_rtol = Vec::with_capacity(rtols.len());
    for &rtol in rtols {
        let runs: Vec<RunTimer> = contenders
            .iter()
            .map(|(_, evaluated, _)| RunTimer::new(evaluated, rtol))
            .collect::<anyhow::Result<_>>()?;
        let cvode_timer = match &cvode {
            Some(Ok(cvode)) => Some(crate::peers::CvodeTimer::new(cvode, &loaded, rtol)?),
            _ => None,
        };
        per_rtol.push((rtol, runs, cvode_timer));
    }
    for _ in 0..args.repeat.max(1) {
        for (_, runs, cvode_timer) in &mut per_rtol {
            for (run, (engine, _, _)) in runs.iter_mut().zip(&contenders) {
                run.once(*engine)?;
            }
            if let Some(timer) = cvode_timer {
                timer.round();
            }
        }
    }
    for (rtol, runs, cvode_timer) in per_rtol {
        let mut first = None;
        for (run, (_, _, label)) in runs.into_iter().zip(&contenders) {
            let timing = run.finish()?;
            let (error, relative) =
                max_deviation(&loaded, &timing.trajectory, &reference.trajectory, &signal)?;
            let counts = timing.trajectory.stats.counts;
            println!(
                "| {rtol:.0e} | {:.2} | {:.2} | {:.0} | {} | {} | {} | {error:.2e} | {relative:.2e} | fistage {}{label} |",
                timing.wall_s * 1e3,
                timing.cpu_s * 1e3,
                simulated / timing.cpu_s,
                counts.steps,
                counts.rejected,
                counts.rhs_evaluations,
                timing.trajectory.stats.engine,
            );
            if first.is_none() {
                fistage_rows.push(AccuracyRow {
                    rtol,
                    cpu_s: timing.cpu_s,
                    relative,
                });
                first = Some(timing);
            }
        }
        let timing = first.context("no engine timed")?;
        let Some(cvode) = &cvode else { continue };
        let mut peers = match (cvode, cvode_timer) {
            (Ok(_), Some(timer)) => timer.finish(),
            (Err(reason), _) => vec![Err(crate::peers::PeerSkipped {
                method: "CVODE".into(),
                reason: reason.clone(),
            })],
            (Ok(_), None) => Vec::new(),
        };
        let times = &timing.trajectory.times;
        peers.extend(crate::peers::scipy::scipy_runs(
            &peer_python(args),
            scenario,
            rtol,
            loaded.model.n_states(),
            times,
        )?);
        for peer in peers {
            match peer {
                Ok(run) => {
                    let (error, relative) =
                        max_deviation(&loaded, &run.trajectory, &reference.trajectory, &signal)?;
                    let (steps, rejected) = if run.steps_known {
                        (
                            run.counts.steps.to_string(),
                            run.counts.rejected.to_string(),
                        )
                    } else {
                        ("-".to_string(), "-".to_string())
                    };
                    println!(
                        "| {rtol:.0e} | {:.2} | {:.2} | {:.0} | {steps} | {rejected} | {} | {error:.2e} | {relative:.2e} | {} |",
                        run.wall_s * 1e3,
                        run.cpu_s * 1e3,
                        simulated / run.cpu_s,
                        run.counts.rhs_evaluations,
                        run.method,
                    );
                    let row = AccuracyRow {
                        rtol,
                        cpu_s: run.cpu_s,
                        relative,
                    };
                    match peer_rows
                        .iter_mut()
                        .find(|(family, _)| *family == run.family)
                    {
                        Some((_, rows)) => rows.push(row),
                        None => peer_rows.push((run.family.clone(), vec![row])),
                    }
                    ratios.push((rtol, run.method, run.cpu_s / timing.cpu_s, relative));
                }
                Err(skipped) => println!(
                    "| {rtol:.0e} | - | - | - | - | - | - | - | - | {}: not run ({}) |",
                    skipped.method, skipped.reason
                ),
            }
        }
    }
    if !ratios.is_empty() {
        println!(
            "\nCPU time of each peer over fistage's at the same rtol, in this one invocation:\n"
        );
        println!("| rtol | peer | peer CPU / fistage CPU | peer relative error |");
        println!("|---|---|---|---|");
        for (rtol, method, ratio, relative) in ratios {
            println!("| {rtol:.0e} | {method} | {ratio:.1} | {relative:.2e} |");
        }
    }
    print_matched(&fistage_rows, &peer_rows);
    Ok(())
}

/// What was compiled to machine code for `model` and how long that took
/// (once per model, before any timed run), or why nothing was.
fn compile_note(model: &fistage_model::Model) -> String {
    use fistage_codegen::{Function, NotCompiled, machine_code};
    let parts: Vec<String> = [
        (Function::Rhs, "right-hand side"),
        (Function::ImplicitStage, "implicit bristle stage"),
    ]
    .into_iter()
    .filter_map(|(function, name)| match machine_code(model, function) {
        Ok(native) => Some(format!(
            "{name} compiled to machine code in {:.1} ms ({} operations)",
            native.compile_time().as_secs_f64() * 1e3,
            native.operations()
        )),
        Err(NotCompiled::NoBristles) => None,
        Err(why) => Some(format!("{name} evaluated generically ({why})")),
    })
    .collect();
    format!(
        "{}; once per model, before the timed runs.",
        parts.join(", ")
    )
}

/// The Python the SciPy peer runs: `--python`, else the package's test environment, else python3.
fn peer_python(args: &BenchArgs) -> PathBuf {
    args.python.clone().unwrap_or_else(|| {
        let venv = PathBuf::from("target/py-venv/bin/python");
        if venv.is_file() {
            venv
        } else {
            PathBuf::from("python3")
        }
    })
}

/// Relative difference of the steady-state peak-to-peak of a signal.
fn p2p_difference(
    loaded: &Loaded,
    a: &Trajectory,
    b: &Trajectory,
    signal: &str,
) -> anyhow::Result<f64> {
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let [start, end] = loaded.scenario.window;
    let p2p = |trajectory: &Trajectory| -> anyhow::Result<f64> {
        let table = trajectory.signals(&loaded.model, &excitation);
        let column = table
            .column(signal)
            .with_context(|| format!("no signal {signal}"))?;
        let window = table
            .times
            .iter()
            .zip(column)
            .filter(|(t, _)| **t >= start && **t <= end)
            .map(|(_, v)| *v);
        let (lo, hi) = window.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        Ok(hi - lo)
    };
    let (pa, pb) = (p2p(a)?, p2p(b)?);
    Ok((pa - pb).abs() / pb.abs().max(1e-300))
}

/// Native (two tolerances) and rapier (its default step, half and a quarter
/// of it) on one scenario, against a native run at the reference tolerance.
fn engines_table(args: &BenchArgs, scenario: &Path) -> anyhow::Result<()> {
    use fistage_sim::rapier_engine::RapierEngine;
    let loaded = fistage_model::load(scenario)?;
    let signal = error_signal(args, &loaded)?;
    let native = fistage_sim::AdaptiveEngine::NATIVE;
    eprintln!("reference run at rtol {:e} ...", args.reference_rtol);
    let reference = time_run(&loaded, &native, args.reference_rtol, 1)?;
    let simulated = loaded.scenario.duration;
    let repeat = args.repeat.min(3);
    println!(
        "`{}` ({simulated} s simulated; median of {repeat} runs; errors of `{}` against native at rtol {:e}; p2p over the window {:?} s)\n",
        scenario.display(),
        signal,
        args.reference_rtol,
        loaded.scenario.window
    );
    println!(
        "| engine | setting | wall s | x real time | steps | model evaluations | max error (m) | relative error | steady p2p difference |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let row = |engine: &dyn Engine, setting: String, rtol: f64| -> anyhow::Result<()> {
        let timing = time_run(&loaded, engine, rtol, repeat)?;
        let (error, relative) =
            max_deviation(&loaded, &timing.trajectory, &reference.trajectory, &signal)?;
        let p2p = p2p_difference(&loaded, &timing.trajectory, &reference.trajectory, &signal)?;
        let counts = timing.trajectory.stats.counts;
        println!(
            "| {} | {setting} | {:.3} | {:.1} | {} | {} | {error:.2e} | {relative:.2e} | {p2p:.2e} |",
            engine.name(),
            timing.wall_s,
            simulated / timing.wall_s,
            counts.steps,
            counts.rhs_evaluations,
        );
        Ok(())
    };
    for rtol in [1e-6, 1e-8] {
        row(&native, format!("rtol {rtol:.0e}"), rtol)?;
    }
    let dt = scenario_rapier_step(&loaded)?;
    for divisor in [1.0, 2.0, 4.0] {
        let mut engine = RapierEngine {
            settings: loaded.scenario.rapier.clone(),
        };
        engine.settings.dt = Some(dt / divisor);
        let label = if divisor == 1.0 {
            format!("dt {:.2e} s (default)", dt)
        } else {
            format!("dt {:.2e} s", dt / divisor)
        };
        // The tolerance is unused by the fixed-step engine.
        row(&engine, label, loaded.scenario.solver.rtol)?;
    }
    Ok(())
}

/// Native and Rosenbrock engines as the isolators' stiff directions (y, z and
/// the three rotations) are made stiffer: where explicit steps stop paying.
fn stiffness_table(args: &BenchArgs) -> anyhow::Result<()> {
    let scenario = args
        .scenario
        .clone()
        .unwrap_or_else(|| PathBuf::from("scenarios/coupling/friction20_traverse.toml"));
    let base = fistage_model::load(&scenario)?;
    let signal = error_signal(args, &base)?;
    let rtol = args.rtol.first().copied().unwrap_or(1e-6);
    let repeat = args.repeat.min(3);
    println!(
        "`{}` ({} s simulated, rtol {rtol:e}, median of {repeat} runs; `{}` statistics over the window {:?} s)\n",
        scenario.display(),
        base.scenario.duration,
        signal,
        base.scenario.window
    );
    println!(
        "| stiff directions x | engine | wall s | steps | rejected | RHS evals (incl. Jacobians) | p2p of signal | mean of signal |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for factor in [0.01, 1.0, 10.0, 100.0, 1000.0] {
        let mut robot = base.robot.clone();
        for isolator in &mut robot.isolators {
            for k in &mut isolator.stiffness[1..] {
                *k *= factor;
            }
        }
        let (robot, model) = fistage_model::assemble(robot, &base.scenario)?;
        let loaded = Loaded {
            scenario: base.scenario.clone(),
            robot,
            model,
        };
        let engines: [&dyn Engine; 2] = [
            &fistage_sim::AdaptiveEngine::NATIVE,
            &fistage_sim::AdaptiveEngine::new(fistage_sim::MethodKind::Rosenbrock),
        ];
        for engine in engines {
            let timing = time_run(&loaded, engine, rtol, repeat)?;
            let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
            let table = timing.trajectory.signals(&loaded.model, &excitation);
            let summary = fistage_sim::summarize(
                &table,
                loaded.scenario.window[0],
                loaded.scenario.window[1],
            );
            let stats = summary
                .iter()
                .find(|s| s.name == signal)
                .map(|s| s.stats)
                .with_context(|| format!("no signal {signal}"))?;
            let counts = timing.trajectory.stats.counts;
            println!(
                "| {factor} | {} | {:.3} | {} | {} | {} | {:.5e} | {:.5e} |",
                engine.name(),
                timing.wall_s,
                counts.steps,
                counts.rejected,
                counts.rhs_evaluations,
                stats.peak_to_peak,
                stats.mean,
            );
        }
    }
    Ok(())
}
