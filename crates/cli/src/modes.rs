//! `fistage modes SCENARIO`: equilibria, eigenvalues, mode shapes and their
//! coupling, as a table, `modes.json`, and top-view pictures of the dominant
//! mode shapes.

use std::path::PathBuf;

use anyhow::Context;
use fistage_analysis::{ModalAnalysis, Mode, Verdict, modal_analysis};
use fistage_model::{EquilibriumKind, JointMotion, Loaded};
use fistage_sim::initial_state;

use fistage_model::output::ResultFolder;

/// Which equilibria to analyse.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Which {
    /// Contacts stuck (pre-motion).
    Sticking,
    /// Contacts sliding at the platform (or traverse) velocity.
    Slipping,
    /// Both.
    Both,
}

/// An equilibrium asked for that the stage does not have, and why.
#[derive(serde::Serialize)]
struct Unavailable {
    /// `sticking` or `slipping`.
    equilibrium: &'static str,
    /// Why it was not found.
    reason: String,
}

/// Arguments of `fistage modes`.
#[derive(clap::Args)]
pub struct ModesArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Equilibria to analyse.
    #[arg(long, value_enum, default_value_t = Which::Both)]
    pub equilibrium: Which,
    /// Output folder for modes.json and the mode-shape pictures (default: out/<scenario>-modes).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// How many dominant mode shapes to draw per equilibrium.
    #[arg(long, default_value_t = 4)]
    pub shapes: usize,
    /// Replace an earlier result in the output folder (as a whole).
    #[arg(long)]
    pub force: bool,
    /// Skip the HTML page (report.html).
    #[arg(long)]
    pub no_report: bool,
}

/// Runs the command.
pub fn run(args: &ModesArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    let scenario = &loaded.scenario;
    let inputs = fistage_analysis::modes::equilibrium_inputs(scenario);
    let start = initial_state(&loaded.model, scenario)?;
    let kinds: Vec<EquilibriumKind> = match args.equilibrium {
        Which::Sticking => vec![EquilibriumKind::Sticking],
        Which::Slipping => vec![EquilibriumKind::Slipping],
        Which::Both => vec![EquilibriumKind::Sticking, EquilibriumKind::Slipping],
    };
    // With both asked for, an equilibrium the stage does not have (no
    // slipping one where the counter-surfaces stand still) is named, not fatal.
    let mut analyses = Vec::new();
    let mut unavailable = Vec::new();
    for kind in kinds {
        match modal_analysis(&loaded.model, &inputs, kind, &start) {
            Ok(analysis) => analyses.push(analysis),
            Err(e) if args.equilibrium == Which::Both => unavailable.push(Unavailable {
                equilibrium: kind.name(),
                reason: e.to_string(),
            }),
            Err(e) => {
                return Err(anyhow::Error::new(e)
                    .context(format!("{}: modal analysis", args.scenario.display())));
            }
        }
    }
    anyhow::ensure!(
        !analyses.is_empty(),
        "{}: modal analysis: no equilibrium to analyse: {}",
        args.scenario.display(),
        unavailable
            .iter()
            .map(|u| u.reason.as_str())
            .collect::<Vec<_>>()
            .join("; ")
    );
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| fistage_model::output::default_folder(&args.scenario, "modes"));
    let folder = ResultFolder::begin(&out_dir, args.force)?;
    let staging = folder.path();
    let json = serde_json::json!({
        "scenario": scenario.file.display().to_string(),
        "slip_velocity_m_per_s": -inputs.platform_velocity,
        "analyses": analyses,
        "unavailable": unavailable,
    });
    let text = serde_json::to_string_pretty(&json)?;
    std::fs::write(staging.join("modes.json"), text.clone() + "\n")
        .with_context(|| format!("cannot write {}", staging.join("modes.json").display()))?;
    let mut pictures = Vec::new();
    for analysis in &analyses {
        pictures.extend(fistage_plot::figures::modes::write(
            &loaded,
            analysis,
            args.shapes,
            staging,
        )?);
    }
    let mut page = Vec::new();
    if !args.no_report {
        let reasons: Vec<String> = unavailable.iter().map(|u| u.reason.clone()).collect();
        page.extend(crate::report::write(staging, || {
            fistage_report::sections::modes::section(&loaded, &analyses, &reasons)
        })?);
    }
    let out_dir = folder.commit()?;
    if args.json {
        println!("{text}");
    } else {
        for analysis in &analyses {
            print_table(analysis);
        }
        for missing in &unavailable {
            println!("{}", missing.reason);
        }
        print_routh_hurwitz(&loaded, inputs.platform_velocity);
        println!(
            "wrote modes.json{} and {} pictures in {}",
            page.iter().map(|p| format!(", {p}")).collect::<String>(),
            pictures.len(),
            out_dir.display()
        );
    }
    if let Some(undetermined) = analyses.iter().find(|a| a.verdict == Verdict::Undetermined) {
        anyhow::bail!(
            "{}: the {} equilibrium's stability is undetermined: {}",
            args.scenario.display(),
            undetermined.equilibrium,
            undetermined.undetermined_reason.as_deref().unwrap_or("")
        );
    }
    Ok(())
}

/// Sum of the shares of coordinates whose name starts with one of the prefixes.
fn share_of(mode: &Mode, select: impl Fn(&str) -> bool) -> f64 {
    mode.participation
        .iter()
        .filter(|p| select(&p.coordinate))
        .map(|p| p.share)
        .sum()
}

fn print_table(analysis: &ModalAnalysis) {
    let verdict = match analysis.verdict {
        Verdict::Stable => "stable".to_string(),
        Verdict::Unstable => "UNSTABLE".to_string(),
        Verdict::Undetermined => format!(
            "UNDETERMINED: {}",
            analysis.undetermined_reason.as_deref().unwrap_or("")
        ),
    };
    println!(
        "{} equilibrium: {verdict} (largest real part {:.4e} 1/s, {} neutral)",
        analysis.equilibrium, analysis.max_real_part, analysis.neutral
    );
    let floating: Vec<&str> = analysis
        .coordinates
        .iter()
        .filter_map(|c| c.strip_suffix(".x"))
        .collect();
    let table = floating.first().copied().unwrap_or("");
    println!(
        "{:>3} {:>11} {:>9} {:>12} {:>12}  {:>6} {:>6} {:>6} {:>6} {:>8} {:>7}  dominant",
        "#",
        "f_n [Hz]",
        "zeta",
        "Re [1/s]",
        "Im [rad/s]",
        "x",
        "y+z",
        "r+p",
        "yaw",
        "bearings",
        "bristle"
    );
    for (k, mode) in analysis.modes.iter().enumerate() {
        let is = |c: &str, axis: &str| c == format!("{table}.{axis}");
        // A neutral eigenvalue's damping ratio is the sign of its round-off.
        let zeta = if mode.neutral {
            "neutral".to_string()
        } else {
            format!("{:.4}", mode.damping_ratio)
        };
        println!(
            "{:>3} {:>11.3} {:>9} {:>12.4e} {:>12.4e}  {:>6.3} {:>6.3} {:>6.3} {:>6.3} {:>8.3} {:>7.3}  {}",
            k + 1,
            mode.frequency_hz,
            zeta,
            mode.real,
            mode.imag,
            share_of(mode, |c| is(c, "x")),
            share_of(mode, |c| is(c, "y") || is(c, "z")),
            share_of(mode, |c| is(c, "roll") || is(c, "pitch")),
            share_of(mode, |c| is(c, "yaw")),
            share_of(mode, |c| !c.starts_with(&format!("{table}."))),
            mode.bristle_share,
            mode.dominant
        );
    }
    println!(
        "(x, y+z, r+p, yaw, bearings: shares of the mode's kinetic energy; bristle: share of the scaled eigenvector)\n"
    );
}

/// For the rigid 1-DOF stage (one prismatic body, one contact, a PD servo),
/// the paper's Routh-Hurwitz test at the slipping equilibrium, as printed and corrected.
fn print_routh_hurwitz(loaded: &Loaded, platform_velocity: f64) {
    use fistage_analysis::routh::{RigidStage, rigid_slipping};
    let model = &loaded.model;
    let (Some(controller), [body], [friction]) =
        (model.controller(), model.bodies(), model.frictions())
    else {
        return;
    };
    if !matches!(body.joint.motion, JointMotion::Prismatic { .. })
        || controller.k_i != 0.0
        || platform_velocity == 0.0
    {
        return;
    }
    let test = rigid_slipping(&RigidStage {
        mass: body.mass,
        k: controller.k,
        c: controller.c,
        lugre: friction.lugre,
        platform_velocity,
    });
    let [a1, a2, a3] = test.coefficients;
    println!(
        "Routh-Hurwitz (rigid stage, slipping): a1 = {a1:.6e}, a2 = {a2:.6e}, a3 = {a3:.6e}; corrected: {}; as printed in the paper: {}",
        if test.stable { "stable" } else { "unstable" },
        if test.stable_as_printed {
            "stable"
        } else {
            "unstable"
        }
    );
}
