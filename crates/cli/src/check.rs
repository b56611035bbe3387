//! `fistage check SCENARIO`: load and validate a scenario and its robot
//! without simulating (everything `fistage run` checks before it integrates:
//! signal names, colliders, the start state), and print what was assembled: bodies, joints, elements, the
//! evaluation path, whether it runs as machine code, the integration method
//! the default engine chose and why,
//! the state layout and the output signals.

use std::path::PathBuf;

use fistage_codegen::{Function, NotCompiled, machine_code};
use fistage_model::{EvaluationPath, Frame, JointMotion, Model};

/// Arguments of `fistage check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
}

/// Runs the command.
pub fn run(args: &CheckArgs) -> anyhow::Result<()> {
    let loaded = fistage_model::load(&args.scenario)?;
    for note in loaded.model.notes() {
        eprintln!("warning: {}: {note}", args.scenario.display());
    }
    fistage_sim::validate(&loaded)?;
    let model = &loaded.model;
    println!("{}: ok", args.scenario.display());
    println!(
        "robot {} ({})",
        model.name(),
        loaded.scenario.robot.display()
    );
    print_bodies(model);
    print_elements(model);
    println!("evaluation: {}", evaluation_path(model.evaluation_path()));
    print_native(model);
    print_method(&loaded)?;
    println!("states ({}):", model.n_states());
    for ((name, kind), nominal) in model
        .layout()
        .names
        .iter()
        .zip(&model.layout().kinds)
        .zip(&model.layout().nominal)
    {
        println!("  {name:<32} [{}]  nominal {nominal:.1e}", kind.unit());
    }
    println!("signals ({}):", model.signals().len());
    for signal in model.signals() {
        println!("  {} [{}]", signal.name, signal.unit);
    }
    Ok(())
}

/// The engine and, for the default engine, the method it chose and why.
fn print_method(loaded: &fistage_model::Loaded) -> anyhow::Result<()> {
    let scenario = &loaded.scenario;
    let engine = scenario.solver.engine;
    if engine != fistage_model::EngineKind::Auto {
        println!("engine: {engine} (solver.engine)");
        return Ok(());
    }
    let x0 = fistage_sim::initial_state(&loaded.model, scenario)?;
    let choice = fistage_sim::AutoEngine::for_scenario(scenario).choice(
        &loaded.model,
        &x0,
        scenario.solver.rtol,
    );
    println!(
        "engine: auto -> {} ({})",
        fistage_sim::engine_kind_of(choice.method).name(),
        choice.reason
    );
    Ok(())
}

/// Whether the right-hand side and the implicit bristle stage run as
/// machine code, and their size, or why not.
fn print_native(model: &Model) {
    for (function, name) in [
        (Function::Rhs, "right-hand side"),
        (Function::ImplicitStage, "implicit bristle stage"),
    ] {
        match machine_code(model, function) {
            Ok(native) => println!(
                "{name}: machine code, {} operations, {} guarded branches, compiled in {:.1} ms",
                native.operations(),
                native.guards(),
                native.compile_time().as_secs_f64() * 1e3
            ),
            Err(NotCompiled::NoBristles) => {}
            Err(why) => println!("{name}: evaluated generically ({why})"),
        }
    }
}

fn evaluation_path(path: EvaluationPath) -> &'static str {
    match path {
        EvaluationPath::ConstantJacobian => {
            "constant Jacobian rows (no joint turns a body: kinematics linear in the coordinates)"
        }
        EvaluationPath::RootedBodies => {
            "rooted bodies (every body jointed straight to the world: free Newton-Euler bodies and rail masses)"
        }
        EvaluationPath::General => "general recursive dynamics (bodies in chains)",
    }
}

fn frame_name(model: &Model, frame: Frame) -> String {
    match frame {
        Frame::World => "world".into(),
        Frame::Body(b) => model.bodies()[b].name.clone(),
    }
}

fn print_bodies(model: &Model) {
    println!("bodies ({}):", model.bodies().len());
    for body in model.bodies() {
        let parent = body
            .parent
            .map_or("world".to_string(), |p| model.bodies()[p].name.clone());
        let kind = match body.joint.motion {
            JointMotion::Prismatic { axis } => {
                format!("prismatic [{:.3} {:.3} {:.3}]", axis.x, axis.y, axis.z)
            }
            JointMotion::Revolute { axis } => {
                format!("revolute [{:.3} {:.3} {:.3}]", axis.x, axis.y, axis.z)
            }
            JointMotion::Floating => "floating".into(),
        };
        println!(
            "  {} on {} ({kind}) to {parent}: mass {:.6} kg, com [{:.4} {:.4} {:.4}] m, links {}",
            body.name,
            body.joint.name,
            body.mass,
            body.com.x,
            body.com.y,
            body.com.z,
            body.links.join(", ")
        );
    }
}

fn print_elements(model: &Model) {
    for isolator in model.isolators() {
        println!(
            "  isolator {}: {} -> {}, stiffness {:?}, damping {:?}",
            isolator.name,
            frame_name(model, isolator.parent),
            frame_name(model, isolator.child),
            isolator.stiffness,
            isolator.damping
        );
    }
    for friction in model.frictions() {
        let p = &friction.lugre;
        println!(
            "  friction {} on {}: sigma0 {} sigma1 {} sigma2 {} f_c {} f_s {} v_s {}",
            friction.name,
            model.bodies()[friction.body].name,
            p.sigma0,
            p.sigma1,
            p.sigma2,
            p.f_c,
            p.f_s,
            p.v_s
        );
    }
    for actuator in model.actuators() {
        println!(
            "  actuator {} on {}",
            actuator.name,
            model.bodies()[actuator.body].name
        );
    }
    for sensor in model.sensors() {
        println!(
            "  sensor {} on {}",
            sensor.name,
            model.bodies()[sensor.body].name
        );
    }
    if let Some(c) = &model.controller() {
        println!(
            "  controller: {} -> {}, k {} c {} k_i {}",
            model.sensors()[c.sensor].name,
            model.actuators()[c.actuator].name,
            c.k,
            c.c,
            c.k_i
        );
        for feedforward in &c.feedforward {
            println!("  {}", describe_compensator(feedforward));
        }
        if let Some(o) = &c.observer {
            println!(
                "  observer: nominal mass {} kg, cut-off {} Hz",
                o.nominal_mass,
                // The bandwidth as written (the cut-off is held in rad/s).
                (o.cutoff / (2.0 * std::f64::consts::PI) * 1e9).round() / 1e9
            );
        }
    }
}

/// One compensator in a line: the element it models, its model's
/// parameters, and where it acts.
fn describe_compensator(f: &fistage_model::elements::Feedforward) -> String {
    use fistage_model::elements::FrictionModel;
    let model = match &f.model {
        FrictionModel::Lugre(p) => format!(
            "lugre sigma0 {} sigma1 {} sigma2 {} f_c {} f_s {} v_s {}",
            p.sigma0, p.sigma1, p.sigma2, p.f_c, p.f_s, p.v_s
        ),
        FrictionModel::Dahl(p) => {
            format!(
                "dahl sigma {} f_c {} exponent {}",
                p.sigma, p.f_c, p.exponent
            )
        }
    };
    let acts = match &f.bearing {
        Some(b) => format!(
            "simulated behind its isolator (bearing {} kg, k {} N/m, c {} N s/m)",
            b.mass, b.stiffness, b.damping
        ),
        None => "fed forward at the table".to_string(),
    };
    format!(
        "compensator of {}: {model}, {acts}",
        f.element.as_deref().unwrap_or("(no element)")
    )
}
