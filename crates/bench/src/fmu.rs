//! `fistage bench --fmu`: the cost of the FMI face. The raw cost of one
//! `fmi2DoStep` is timed by calling the exported C functions in this process
//! (the same code the shared library carries), against the continuous native
//! run over the same span; FMPy's `simulate_fmu` is timed on the packaged FMU
//! through both interfaces (Co-Simulation, and Model Exchange with FMPy's
//! CVode) when a python with FMPy is available.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{Context, bail};
use fistage_fmi::exports::{
    fmi2DoStep, fmi2EnterInitializationMode, fmi2ExitInitializationMode, fmi2FreeInstance,
    fmi2Instantiate, fmi2SetupExperiment,
};
use fistage_fmi::package::{default_library_locations, write_resources};
use fistage_sim::{AdaptiveEngine, Engine, ScenarioExcitation, SimSettings, initial_state};

/// A scratch folder removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> anyhow::Result<Self> {
        let dir = std::env::temp_dir().join(format!("fistage-bench-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        Ok(Self(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Seconds for `span` simulated seconds in `step`-sized fmi2DoStep calls.
fn time_do_steps(resources: &Path, guid: &str, span: f64, step: f64) -> anyhow::Result<f64> {
    let uri = std::ffi::CString::new(format!("file://{}", resources.display()))?;
    let guid = std::ffi::CString::new(guid)?;
    // SAFETY: valid strings; no callbacks (null is allowed and means no logging).
    let c = unsafe {
        fmi2Instantiate(
            c"bench".as_ptr(),
            1,
            guid.as_ptr(),
            uri.as_ptr(),
            std::ptr::null(),
            0,
            0,
        )
    };
    if c.is_null() {
        bail!("fmi2Instantiate failed for {}", resources.display());
    }
    let mut ok = fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == 0
        && fmi2EnterInitializationMode(c) == 0
        && fmi2ExitInitializationMode(c) == 0;
    let steps = (span / step).round() as usize;
    let start = Instant::now();
    let mut t = 0.0;
    for k in 0..steps {
        let next = (k + 1) as f64 * step;
        ok &= fmi2DoStep(c, t, next - t, 1) == 0;
        t = next;
    }
    let elapsed = start.elapsed().as_secs_f64();
    fmi2FreeInstance(c);
    if !ok {
        bail!("a call failed while stepping {}", resources.display());
    }
    Ok(elapsed)
}

fn native_time(scenario: &Path, span: f64) -> anyhow::Result<f64> {
    let mut loaded = fistage_model::load(scenario)?;
    loaded.scenario.duration = span;
    let x0 = initial_state(&loaded.model, &loaded.scenario)?;
    let settings = SimSettings::from_scenario(&loaded.scenario);
    let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
    let start = Instant::now();
    AdaptiveEngine::NATIVE.simulate(
        &loaded.model,
        &x0,
        &excitation,
        &settings,
        &mut fistage_sim::no_progress,
    )?;
    Ok(start.elapsed().as_secs_f64())
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Median wall time of FMPy's simulate_fmu over `span` at `step` through
/// `interface` (`CoSimulation`, or `ModelExchange` with CVode), or why not.
fn fmpy_time(
    python: &Path,
    fmu: &Path,
    (span, step): (f64, f64),
    interface: &str,
    repeat: usize,
) -> Result<f64, String> {
    let solver = match interface {
        "ModelExchange" => ", solver='CVode'",
        _ => "",
    };
    let script = format!(
        "import time, fmpy\n\
         times = []\n\
         for _ in range({repeat}):\n\
         \x20   start = time.perf_counter()\n\
         \x20   fmpy.simulate_fmu({fmu:?}, stop_time={span}, output_interval={step}, fmi_type='{interface}'{solver})\n\
         \x20   times.append(time.perf_counter() - start)\n\
         times.sort()\n\
         print(times[len(times) // 2])\n",
        fmu = fmu.display().to_string(),
    );
    let output = Command::new(python)
        .arg("-c")
        .arg(script)
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).trim().to_string());
    }
    String::from_utf8_lossy(&output.stdout)
        .trim()
        .parse()
        .map_err(|e| format!("unexpected FMPy output: {e}"))
}

/// Prints the FMU table.
pub fn fmu_table(python: &Path, repeat: usize) -> anyhow::Result<()> {
    let program = std::env::current_exe()?;
    let library = default_library_locations(&program)
        .into_iter()
        .find(|p| p.is_file())
        .context(
            "libfistage_fmi.so not found beside this program (cargo build --release -p fistage)",
        )?;
    println!(
        "| scenario | span s | step ms | doSteps | native run ms | via fmi2DoStep ms | µs per fmi2DoStep | FMPy CS s | FMPy ME (CVode) s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (scenario, span) in [
        ("scenarios/paper/fig05b_fi.toml", 10.0),
        ("scenarios/coupling/friction20_traverse.toml", 1.0),
    ] {
        let scenario = PathBuf::from(scenario);
        let name = scenario
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("stage")
            .to_string();
        let scratch = Scratch::new(&name)?;
        write_resources(&scenario, &scratch.0)?;
        let guid = fistage_fmi::Instance::new(&scratch.0, None)
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .guid()
            .to_string();
        let step = 1e-3;
        let runs = repeat.max(1);
        let direct = median(
            (0..runs)
                .map(|_| time_do_steps(&scratch.0, &guid, span, step))
                .collect::<anyhow::Result<_>>()?,
        );
        let native = median(
            (0..runs)
                .map(|_| native_time(&scenario, span))
                .collect::<anyhow::Result<_>>()?,
        );
        let fmu = scratch.0.join(format!("{name}.fmu"));
        std::fs::write(&fmu, fistage_fmi::build_fmu(&scenario, &library)?)?;
        let fmpy =
            |interface: &str| match fmpy_time(python, &fmu, (span, step), interface, 3.min(runs)) {
                Ok(seconds) => format!("{seconds:.2}"),
                Err(why) => {
                    eprintln!("FMPy ({interface}) not timed: {why}");
                    "n/a".into()
                }
            };
        let (cs, me) = (fmpy("CoSimulation"), fmpy("ModelExchange"));
        let steps = (span / step).round();
        println!(
            "| {name} | {span} | {} | {steps} | {:.1} | {:.1} | {:.1} | {cs} | {me} |",
            step * 1e3,
            native * 1e3,
            direct * 1e3,
            direct / steps * 1e6,
        );
    }
    Ok(())
}
