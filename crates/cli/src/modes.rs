//! `fistage modes SCENARIO`: equilibria, eigenvalues, mode shapes and their
//! coupling, as a table, `modes.json`, and top-view pictures of the dominant
//! mode shapes.

use std::path::{Path, PathBuf};

use anyhow::Context;
use fistage_analysis::{ModalAnalysis, Mode, Verdict, modal_analysis};
use fistage_model::{EquilibriumKind, Frame, JointMotion, Loaded};
use fistage_plot::{Series, XyPlot, write_xy};
use fistage_sim::initial_state;
use nalgebra::Vector3;

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
        pictures.extend(draw_dominant_shapes(
            &loaded,
            analysis,
            args.shapes,
            staging,
        )?);
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
            "wrote modes.json and {} pictures in {}",
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

/// Modes worth drawing: unstable ones first, then oscillatory modes with
/// mechanical content, lowest frequency first.
fn dominant_modes(analysis: &ModalAnalysis, count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..analysis.modes.len())
        .filter(|&k| analysis.modes[k].oscillatory && analysis.modes[k].bristle_share < 0.5)
        .collect();
    order.sort_by(|&a, &b| {
        let (ma, mb) = (&analysis.modes[a], &analysis.modes[b]);
        (mb.real > 0.0)
            .cmp(&(ma.real > 0.0))
            .then(ma.frequency_hz.total_cmp(&mb.frequency_hz))
    });
    order.truncate(count);
    order
}

/// Points of each body seen from above: isolator attach points (and the body
/// origin), in world coordinates at the equilibrium.
fn body_points(loaded: &Loaded, state: &[f64]) -> Vec<Vec<Vector3<f64>>> {
    let model = &loaded.model;
    let poses = model.body_poses(state);
    let mut points: Vec<Vec<Vector3<f64>>> =
        poses.iter().map(|(_, origin)| vec![*origin]).collect();
    for isolator in model.isolators() {
        for (frame, local) in [
            (isolator.parent, isolator.parent_attach.translation.vector),
            (isolator.child, isolator.child_attach.translation.vector),
        ] {
            if let Frame::Body(b) = frame {
                let (rotation, origin) = poses[b];
                points[b].push(origin + rotation * local);
            }
        }
    }
    points
}

/// Planar displacement of a world point on body b for a mode shape (real part
/// after phase alignment), from the body's joint coordinates.
fn displacement(
    loaded: &Loaded,
    state: &[f64],
    shape: &[f64],
    index: usize,
    point: &Vector3<f64>,
) -> Vector3<f64> {
    let model = &loaded.model;
    let poses = model.body_poses(state);
    let body = &model.bodies()[index];
    let v0 = body.joint.v_offset;
    // Joint frame axes in the world (for root bodies the parent is the world).
    let parent_rotation = body
        .parent
        .map_or(nalgebra::Matrix3::identity(), |p| poses[p].0);
    let joint_rotation = parent_rotation * body.joint.origin_rotation;
    let origin = poses[index].1;
    match body.joint.motion {
        JointMotion::Prismatic { axis } => joint_rotation * axis * shape[v0],
        JointMotion::Revolute { axis } => {
            (joint_rotation * axis * shape[v0]).cross(&(point - origin))
        }
        JointMotion::Floating => {
            let translation =
                joint_rotation * Vector3::new(shape[v0], shape[v0 + 1], shape[v0 + 2]);
            let rotation =
                joint_rotation * Vector3::new(shape[v0 + 3], shape[v0 + 4], shape[v0 + 5]);
            translation + rotation.cross(&(point - origin))
        }
    }
}

fn draw_dominant_shapes(
    loaded: &Loaded,
    analysis: &ModalAnalysis,
    count: usize,
    out_dir: &Path,
) -> anyhow::Result<Vec<String>> {
    let points = body_points(loaded, &analysis.state);
    let all: Vec<&Vector3<f64>> = points.iter().flatten().collect();
    let span = all
        .iter()
        .flat_map(|a| {
            all.iter()
                .map(move |b| ((a.x - b.x).powi(2) + (a.y - b.y).powi(2)).sqrt())
        })
        .fold(0.0_f64, f64::max)
        .max(1e-3);
    let mut written = Vec::new();
    for (rank, &k) in dominant_modes(analysis, count).iter().enumerate() {
        let mode = &analysis.modes[k];
        // Real shape: magnitude x cos(phase), scaled so the largest point moves 15% of the span.
        let shape: Vec<f64> = mode
            .participation
            .iter()
            .map(|p| p.magnitude * p.phase_deg.to_radians().cos())
            .collect();
        let mut moved: Vec<Vec<Vector3<f64>>> = Vec::new();
        let mut largest = 0.0_f64;
        for (b, body_points) in points.iter().enumerate() {
            let d: Vec<Vector3<f64>> = body_points
                .iter()
                .map(|p| displacement(loaded, &analysis.state, &shape, b, p))
                .collect();
            largest = d.iter().map(|v| v.xy().norm()).fold(largest, f64::max);
            moved.push(d);
        }
        let scale = if largest > 0.0 {
            0.15 * span / largest
        } else {
            0.0
        };
        let mut series = Vec::new();
        for (b, body) in loaded.model.bodies().iter().enumerate() {
            let at_rest = &points[b];
            let displaced: Vec<Vector3<f64>> = at_rest
                .iter()
                .zip(&moved[b])
                .map(|(p, d)| p + d * scale)
                .collect();
            let outline = |pts: &[Vector3<f64>]| -> (Vec<f64>, Vec<f64>) {
                // The attach points (after the body origin) outline the body.
                let ring = convex_ring(if pts.len() > 3 { &pts[1..] } else { pts });
                (
                    ring.iter().map(|p| p.x * 1e3).collect(),
                    ring.iter().map(|p| p.y * 1e3).collect(),
                )
            };
            if matches!(body.joint.motion, JointMotion::Floating) {
                let (x, y) = outline(at_rest);
                series.push(Series::line(format!("{} at rest", body.name), x, y));
                let (x, y) = outline(&displaced);
                series.push(Series::line(format!("{} in mode", body.name), x, y));
            } else {
                let last = at_rest.len() - 1;
                series.push(Series::line_and_markers(
                    body.name.clone(),
                    vec![at_rest[last].x * 1e3, displaced[last].x * 1e3],
                    vec![at_rest[last].y * 1e3, displaced[last].y * 1e3],
                ));
            }
        }
        let mut plot = XyPlot::new(
            format!(
                "{} mode {}: {:.2} Hz, zeta {:.4}{}",
                analysis.equilibrium,
                k + 1,
                mode.frequency_hz,
                mode.damping_ratio,
                if mode.real > 0.0 { ", UNSTABLE" } else { "" }
            ),
            "x [mm] (top view, motion exaggerated)",
            "y [mm]",
            series,
        );
        plot.equal_aspect = true;
        for extension in ["svg", "png"] {
            let name = format!("mode_{}_{}.{extension}", analysis.equilibrium, rank + 1);
            write_xy(&plot, &out_dir.join(&name)).with_context(|| format!("cannot draw {name}"))?;
            written.push(name);
        }
    }
    Ok(written)
}

/// Points of a body's outline in angular order around their centroid, closed.
fn convex_ring(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    if points.len() < 3 {
        return points.to_vec();
    }
    let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let mut ring: Vec<Vector3<f64>> = points
        .iter()
        .filter(|p| (p.xy() - centre.xy()).norm() > 1e-9)
        .copied()
        .collect();
    ring.sort_by(|a, b| {
        let angle = |p: &Vector3<f64>| (p.y - centre.y).atan2(p.x - centre.x);
        angle(a).total_cmp(&angle(b))
    });
    ring.dedup_by(|a, b| (a.xy() - b.xy()).norm() < 1e-9);
    if let Some(first) = ring.first().copied() {
        ring.push(first);
    }
    ring
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
