//! A modal analysis's section: per equilibrium the verdict, the eigenvalues
//! in the complex plane, the table of modes, and the stage in 3D with every
//! mode of mechanical content animated on it.

use fistage_analysis::{ModalAnalysis, Verdict};
use fistage_model::Loaded;
use serde_json::json;

use crate::block::number;
use crate::sections::run::name_of;
use crate::{Block, Scene, Section, plot};

/// Modes shown in 3D at most per equilibrium.
const MAX_SHOWN: usize = 24;

/// The section of the modal analyses of `loaded`; `unavailable` names the
/// equilibria asked for that the stage does not have, with the reason.
pub fn section(loaded: &Loaded, analyses: &[ModalAnalysis], unavailable: &[String]) -> Section {
    let mut blocks = vec![Block::facts(
        "provenance",
        vec![
            ["program".into(), crate::page::generator()],
            [
                "scenario".into(),
                loaded.scenario.file.display().to_string(),
            ],
            ["robot".into(), loaded.scenario.robot.display().to_string()],
        ],
    )];
    blocks.extend(unavailable.iter().map(|why| Block::note(why.clone())));
    for analysis in analyses {
        blocks.push(verdict(analysis));
        blocks.push(eigenvalues(analysis));
        blocks.push(Block::Scene(Box::new(Scene::new(
            &loaded.model,
            analysis,
            &shown_modes(analysis),
        ))));
        blocks.push(mode_table(analysis));
    }
    Section {
        heading: format!("modes: {}", name_of(loaded)),
        source: loaded.scenario.file.display().to_string(),
        blocks,
    }
}

fn verdict(analysis: &ModalAnalysis) -> Block {
    let text = format!(
        "{} equilibrium: {} (largest real part {:.4e} 1/s, {} neutral eigenvalues)",
        analysis.equilibrium,
        match analysis.verdict {
            Verdict::Stable => "stable".to_string(),
            Verdict::Unstable => "UNSTABLE".to_string(),
            Verdict::Undetermined => format!(
                "undetermined: {}",
                analysis.undetermined_reason.as_deref().unwrap_or("")
            ),
        },
        analysis.max_real_part,
        analysis.neutral
    );
    if analysis.verdict == Verdict::Stable {
        Block::note(text)
    } else {
        Block::warning(text)
    }
}

/// The modes with mechanical content ([`ModalAnalysis::mechanical_modes`]);
/// where there are none, every mode that is not neutral.
fn shown_modes(analysis: &ModalAnalysis) -> Vec<usize> {
    let mut order = analysis.mechanical_modes();
    if order.is_empty() {
        order = (0..analysis.modes.len())
            .filter(|&k| !analysis.modes[k].neutral)
            .collect();
    }
    order.truncate(MAX_SHOWN);
    order
}

fn eigenvalues(analysis: &ModalAnalysis) -> Block {
    let (stable, unstable): (Vec<usize>, Vec<usize>) = (0..analysis.modes.len())
        .filter(|&k| !analysis.modes[k].neutral)
        .partition(|&k| analysis.modes[k].real <= 0.0);
    let trace = |name: &str, modes: &[usize], colour: &str| {
        json!({
            "type": "scatter", "mode": "markers", "name": name,
            "x": modes.iter().map(|&k| plot::value(analysis.modes[k].real)).collect::<Vec<_>>(),
            "y": modes.iter().map(|&k| plot::value(analysis.modes[k].imag / std::f64::consts::TAU)).collect::<Vec<_>>(),
            "text": modes.iter().map(|&k| format!("mode {}: {}", k + 1, analysis.modes[k].dominant)).collect::<Vec<_>>(),
            "hovertemplate": "%{text}<br>Re %{x:.4e} 1/s<br>Im/2pi %{y:.4g} Hz<extra></extra>",
            "marker": { "color": colour, "size": 9 },
        })
    };
    let mut block = plot::figure(
        &format!(
            "{} equilibrium: eigenvalues (upper half plane)",
            analysis.equilibrium
        ),
        vec![
            trace("stable", &stable, "#4575b4"),
            trace("unstable", &unstable, "#d73027"),
        ],
        "real part [1/s]",
        "imaginary part / 2 pi [Hz]",
    );
    if let Block::Plot { layout, .. } = &mut block {
        layout["hovermode"] = json!("closest");
        layout["xaxis"]["type"] = json!("linear");
        layout["yaxis"]["type"] = json!("log");
    }
    block
}

fn mode_table(analysis: &ModalAnalysis) -> Block {
    Block::Table {
        title: format!("{} equilibrium: every mode", analysis.equilibrium),
        columns: [
            "mode",
            "frequency [Hz]",
            "damping ratio",
            "real part [1/s]",
            "dominant coordinate",
            "bristle share",
            "",
        ]
        .map(String::from)
        .to_vec(),
        rows: analysis
            .modes
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let flag = if m.neutral {
                    "neutral"
                } else if m.real > 0.0 {
                    "UNSTABLE"
                } else {
                    ""
                };
                vec![
                    (k + 1).to_string(),
                    number(m.frequency_hz),
                    number(m.damping_ratio),
                    number(m.real),
                    m.dominant.clone(),
                    number(m.bristle_share),
                    flag.into(),
                ]
            })
            .collect(),
    }
}
