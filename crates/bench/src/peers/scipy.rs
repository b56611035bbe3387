//! SciPy's `solve_ivp` as a peer of the bench, through the Python package's
//! `Scenario.plant()` (the model's own right-hand side and exact Jacobian,
//! called from Python). It runs where a Python with fistage and SciPy is at
//! hand; otherwise the bench says which is missing and goes on. Each
//! method restarts at the inputs' discontinuities like the native driver,
//! samples the scenario's grid with `t_eval`, and times itself with
//! `time.process_time` inside the interpreter (start-up excluded).

use std::path::Path;
use std::process::Command;

use anyhow::Context;
use fistage_sim::{StepCounts, Trajectory};

use super::{PeerRun, PeerSkipped};

/// The methods timed: `RK45` is Dormand-Prince 5(4) like the native engine,
/// `DOP853` its eighth-order sibling, `BDF` SciPy's implicit multistep
/// method given the exact Jacobian.
pub const METHODS: [&str; 3] = ["RK45", "DOP853", "BDF"];

const SCRIPT: &str = r#"
import json, sys, time
try:
    import numpy as np
    from scipy.integrate import solve_ivp
    import scipy
    import fistage
except ImportError as e:
    print(json.dumps({"missing": str(e)}))
    sys.exit(0)
job = json.loads(sys.argv[1])
plant = fistage.load(job["scenario"]).plant()
times = plant.sample_times
ends = list(plant.breakpoints) + [plant.duration]
for method in job["methods"]:
    rtol = job["rtol"]
    atol = rtol * plant.atol_scale * plant.nominal
    jac = plant.jacobian if method in ("BDF", "Radau", "LSODA") else None
    started, cpu = time.perf_counter(), time.process_time()
    x, t0, samples, nfev, njev, failure = plant.x0, 0.0, [plant.x0], 0, 0, None
    for end in ends:
        grid = [min(t, end) for t in times if t0 < t <= end * (1 + 1e-14)]
        n_grid = len(grid)
        if not grid or grid[-1] < end:
            grid.append(end)
        sol = solve_ivp(plant.rhs, (t0, end), x, method=method, rtol=rtol, atol=atol,
                        jac=jac, t_eval=grid)
        nfev += sol.nfev
        njev += sol.njev
        if sol.status != 0:
            failure = sol.message
            break
        samples.extend(sol.y[:, k] for k in range(n_grid))
        x, t0 = sol.y[:, -1], end
    cpu, wall = time.process_time() - cpu, time.perf_counter() - started
    print(json.dumps({"method": method, "scipy": scipy.__version__, "cpu_s": cpu, "wall_s": wall,
                      "nfev": nfev, "njev": njev, "failure": failure,
                      "states": [float(v) for s in samples for v in s]}))
"#;

/// `solve_ivp` with each of [`METHODS`] on `scenario` at `rtol`, one run each.
pub fn scipy_runs(
    python: &Path,
    scenario: &Path,
    rtol: f64,
    n_states: usize,
    times: &[f64],
) -> anyhow::Result<Vec<Result<PeerRun, PeerSkipped>>> {
    let skipped = |reason: String| {
        Ok(vec![Err(PeerSkipped {
            method: "SciPy solve_ivp".into(),
            reason,
        })])
    };
    if let Some(why) = super::hidden() {
        return skipped(format!("Python {why}"));
    }
    let scenario = scenario
        .canonicalize()
        .with_context(|| format!("{}", scenario.display()))?;
    let job = serde_json::json!({
        "scenario": scenario,
        "rtol": rtol,
        "methods": METHODS,
    });
    let output = match Command::new(python)
        .arg("-c")
        .arg(SCRIPT)
        .arg(job.to_string())
        .output()
    {
        Ok(output) => output,
        Err(e) => return skipped(format!("{} does not start: {e}", python.display())),
    };
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let last = stderr.lines().last().unwrap_or("no message");
        return skipped(format!("{} failed: {last}", python.display()));
    }
    let mut rows = Vec::new();
    for line in String::from_utf8_lossy(&output.stdout).lines() {
        let value: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("SciPy harness printed {line:?}"))?;
        if let Some(missing) = value["missing"].as_str() {
            return skipped(format!(
                "{} lacks a package ({missing}): pip install ./python scipy",
                python.display()
            ));
        }
        rows.push(row(&value, n_states, times));
    }
    Ok(rows)
}

fn row(value: &serde_json::Value, n_states: usize, times: &[f64]) -> Result<PeerRun, PeerSkipped> {
    let method = format!(
        "SciPy {} solve_ivp {}",
        value["scipy"].as_str().unwrap_or("?"),
        value["method"].as_str().unwrap_or("?")
    );
    if let Some(failure) = value["failure"].as_str() {
        return Err(PeerSkipped {
            method,
            reason: failure.to_string(),
        });
    }
    let states: Vec<f64> = value["states"]
        .as_array()
        .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
        .unwrap_or_default();
    let samples = times.len();
    if states.len() != n_states * samples {
        return Err(PeerSkipped {
            method,
            reason: format!(
                "returned {} values, not {samples} samples of {n_states} states",
                states.len()
            ),
        });
    }
    let mut trajectory = Trajectory::with_capacity(n_states, samples);
    trajectory.times = times.to_vec();
    trajectory.states = states;
    trajectory.n_states = n_states;
    let nfev = value["nfev"].as_u64().unwrap_or(0);
    let njev = value["njev"].as_u64().unwrap_or(0);
    Ok(PeerRun {
        family: method.clone(),
        method: if njev > 0 {
            format!("{method} ({njev} Jacobians)")
        } else {
            method
        },
        wall_s: value["wall_s"].as_f64().unwrap_or(f64::NAN),
        cpu_s: value["cpu_s"].as_f64().unwrap_or(f64::NAN),
        counts: StepCounts {
            steps: 0,
            rejected: 0,
            rhs_evaluations: nfev,
        },
        steps_known: false,
        trajectory,
    })
}
