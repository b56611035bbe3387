//! `fistage bench --python`: the Python package's `Scenario.run()` against
//! the same work in this program, on fig05b (5 s), in one invocation: the
//! program loads, assembles, runs and summarises the scenario in process
//! (what `fistage run --no-plots` does before it writes files), Python does
//! the same through `fistage.Scenario.run()` (numpy arrays out). Medians of
//! 15 after a warm-up; the ratio is the figure of merit.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, bail};

/// The scenario timed.
const SCENARIO: &str = "scenarios/paper/fig05b_fi.toml";

/// Repeats of each side.
const REPEATS: usize = 15;

/// Prints the Markdown table; `python` must import `fistage`.
pub fn python_table(python: &Path) -> anyhow::Result<()> {
    let scenario = Path::new(SCENARIO);
    let rust = crate::timing::median_time(REPEATS, || {
        let loaded = fistage_model::load(scenario)?;
        let output = fistage_sim::run_scenario(&loaded, &mut fistage_sim::no_progress)?;
        let _ = fistage_sim::summary::document(&loaded, &output);
        Ok(())
    })?;
    let script = format!(
        "import fistage, time\n\
         s = fistage.load({SCENARIO:?})\n\
         s.run()\n\
         t = []\n\
         for _ in range({REPEATS}):\n\
         \x20   a = time.perf_counter(); s.run(); t.append(time.perf_counter() - a)\n\
         t.sort()\n\
         print(t[len(t) // 2])\n"
    );
    let out = Command::new(python)
        .args(["-c", &script])
        .output()
        .with_context(|| format!("cannot run {}", python.display()))?;
    if !out.status.success() {
        bail!(
            "{} could not run the package (pip install ./python first): {}",
            python.display(),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let py: f64 = String::from_utf8_lossy(&out.stdout)
        .trim()
        .parse()
        .context("the Python timing")?;
    println!(
        "`Scenario.run()` against the program on `{SCENARIO}` (load, assemble, run, summary; median of {REPEATS}, release build)\n"
    );
    println!("| side | ms per run | ratio to the program |");
    println!("|---|---:|---:|");
    println!("| program, in process | {:.2} | 1.00 |", rust * 1e3);
    println!(
        "| Python `Scenario.run()` ({}) | {:.2} | {:.2} |",
        python.display(),
        py * 1e3,
        py / rust
    );
    Ok(())
}
