//! A tuning's section: the chosen gains and what they give, and the map of
//! the population's worst largest real part over the (k, c) grid with the
//! admissible region and the chosen gains on it.

use fistage_analysis::robust::tune::{Criterion, Tuning};
use fistage_model::Loaded;
use serde_json::{Value, json};

use crate::block::number;
use crate::sections::run::name_of;
use crate::{Block, Section, plot};

/// The section of `tuning` of the population of `loaded`.
pub fn section(loaded: &Loaded, tuning: &Tuning) -> Section {
    let criterion = match tuning.criterion {
        Criterion::Margin(m) => {
            format!("every stage's largest real part at most -{} 1/s", number(m))
        }
        Criterion::Probability(p) => {
            format!("upper 95% bound of P(unstable) at most {}", number(p))
        }
    };
    let gains = tuning.gains.map_or_else(
        || "none on the grid meets the criterion".to_string(),
        |[k, c]| format!("k = {} N/m, c = {} N s/m", number(k), number(c)),
    );
    let mut blocks = vec![Block::facts(
        "tuning",
        vec![
            ["program".into(), crate::page::generator()],
            [
                "scenario".into(),
                loaded.scenario.file.display().to_string(),
            ],
            ["criterion".into(), criterion],
            [
                "population".into(),
                format!(
                    "{} stages ({} refused by the model)",
                    tuning.members, tuning.refused
                ),
            ],
            ["chosen gains".into(), gains],
            [
                "bandwidth".into(),
                tuning
                    .bandwidth_hz
                    .map_or("-".into(), |b| format!("{} Hz", number(b))),
            ],
        ],
    )];
    if tuning.gains.is_none() {
        for remedy in &tuning.remedies {
            blocks.push(Block::warning(remedy.what.clone()));
        }
    }
    blocks.push(region(tuning));
    Section {
        heading: format!("tune: {}", name_of(loaded)),
        source: loaded.scenario.file.display().to_string(),
        blocks,
    }
}

fn region(tuning: &Tuning) -> Block {
    let width = tuning.k.len();
    let cell = |f: &dyn Fn(usize) -> Value| -> Vec<Vec<Value>> {
        (0..tuning.c.len())
            .map(|row| (0..width).map(|col| f(row * width + col)).collect())
            .collect()
    };
    let z = cell(&|i| {
        let s = &tuning.grid[i];
        if s.undetermined > 0 {
            Value::Null
        } else {
            plot::value(s.worst_max_real_eig)
        }
    });
    let admitted = cell(&|i| {
        json!(if tuning.grid[i].admits(tuning.criterion) {
            "yes"
        } else {
            "no"
        })
    });
    let counts = cell(&|i| {
        json!(format!(
            "{} of {}",
            tuning.grid[i].unstable, tuning.grid[i].members
        ))
    });
    let mut traces = vec![json!({
        "type": "heatmap", "x": plot::values(&tuning.k), "y": plot::values(&tuning.c), "z": z,
        "colorscale": "RdBu", "reversescale": true, "zmid": 0,
        "colorbar": { "title": { "text": "worst Re(lambda) [1/s]" } },
        "customdata": admitted.iter().zip(&counts).map(|(a, c)| a.iter().zip(c).map(|(a, c)| json!([a, c])).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "hovertemplate": "k %{x:.4g} N/m, c %{y:.4g} N s/m<br>worst largest real part %{z:.4g} 1/s<br>unstable %{customdata[1]}<br>admissible: %{customdata[0]}<extra></extra>",
    })];
    let admissible: Vec<usize> = (0..tuning.grid.len())
        .filter(|&i| tuning.grid[i].admits(tuning.criterion))
        .collect();
    traces.push(json!({
        "type": "scatter", "mode": "markers", "name": "admissible",
        "x": admissible.iter().map(|&i| plot::value(tuning.k[i % width])).collect::<Vec<_>>(),
        "y": admissible.iter().map(|&i| plot::value(tuning.c[i / width])).collect::<Vec<_>>(),
        "marker": { "symbol": "circle-open", "color": "#1a9850", "size": 7 }, "hoverinfo": "skip",
    }));
    if let Some([k, c]) = tuning.gains {
        traces.push(json!({
            "type": "scatter", "mode": "markers", "name": "chosen gains", "x": [k], "y": [c],
            "marker": { "symbol": "star", "color": "#000000", "size": 16 },
        }));
    }
    Block::Plot {
        title: format!(
            "worst largest real part over {} stages, admissible gains circled",
            tuning.members
        ),
        traces,
        layout: json!({
            "xaxis": { "title": { "text": "k [N/m]" }, "type": "log", "exponentformat": "SI" },
            "yaxis": { "title": { "text": "c [N s/m]" }, "type": "log" },
            "hovermode": "closest", "legend": { "orientation": "h", "y": -0.2 },
        }),
        height: 560,
    }
}
