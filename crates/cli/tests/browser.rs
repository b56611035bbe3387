//! The HTML pages in a real browser: headless Chromium opens the pages of
//! shipped scenarios from `file://` (no server, no network) and the test
//! reads back what the page checked of itself (`#selftest`): no error, no
//! request, every plot drawn, every 3D view drawn and its animation moving.
//! The mode view's body motions are checked against `modes.json`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::cli::{optional_hidden, repository, scratch, succeeds, system_tests_required};

/// The fig05b run's page may take at most this many bytes.
const RUN_PAGE_LIMIT: u64 = 5_000_000;

/// Chromium as Debian installs it (or `FISTAGE_CHROMIUM`), or why not.
fn chromium() -> Result<PathBuf, String> {
    if let Some(hidden) = optional_hidden() {
        return Err(hidden);
    }
    let candidate = std::env::var_os("FISTAGE_CHROMIUM")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("chromium"));
    match Command::new(&candidate).arg("--version").output() {
        Ok(out) if out.status.success() => Ok(candidate),
        _ => Err(format!(
            "no {} (Debian's chromium; .ci/run installs it)",
            candidate.display()
        )),
    }
}

/// Whether this build writes pages: without npm at build time it leaves
/// them out, saying so on a run (Node.js is then a missing component). A
/// run that fails otherwise fails the test.
fn pages_written(test: &str) -> Result<(), String> {
    let dir = scratch(&format!("pages-written-{test}"));
    let output = crate::cli::fistage()
        .arg("run")
        .arg(repository().join("scenarios/paper/fig05b_fi.toml"))
        .arg("--out")
        .arg(dir.join("run"))
        .arg("--no-plots")
        .output()
        .expect("fistage runs");
    let stderr = String::from_utf8_lossy(&output.stderr).trim().to_string();
    assert!(output.status.success(), "{stderr}");
    let written = dir.join("run/report.html").exists();
    std::fs::remove_dir_all(&dir).ok();
    match (written, stderr.contains("report.html not written")) {
        (true, _) => Ok(()),
        (false, true) => Err(stderr),
        (false, false) => panic!("no report.html and no word why: {stderr}"),
    }
}

/// Chromium, or None after saying SKIPPED (a failure where the system tests
/// are required).
fn browser_or_skip(test: &str) -> Option<PathBuf> {
    match chromium().and_then(|path| pages_written(test).map(|()| path)) {
        Ok(path) => Some(path),
        Err(why) if system_tests_required() => {
            panic!("the browser test needs Chromium and a build with pages: {why}")
        }
        Err(why) => {
            eprintln!("SKIPPED: the browser test: {why}");
            None
        }
    }
}

/// What the page reported of itself, and what the browser printed.
fn open(browser: &Path, page: &Path, profile: &Path) -> (serde_json::Value, String) {
    let url = format!("file://{}#selftest", page.display());
    let output = Command::new(browser)
        .args([
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--use-angle=swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--enable-logging=stderr",
            "--v=0",
            "--virtual-time-budget=10000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(&url)
        .output()
        .expect("chromium starts");
    let dom = String::from_utf8_lossy(&output.stdout);
    let log = String::from_utf8_lossy(&output.stderr).into_owned();
    let marker = "<pre id=\"fistage-selftest\">";
    let start = dom
        .find(marker)
        .unwrap_or_else(|| panic!("{url}: the page reported nothing; browser said:\n{log}"))
        + marker.len();
    let end = start + dom[start..].find("</pre>").expect("the report ends");
    let text = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&amp;", "&");
    (
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{url}: {e}: {text}")),
        log,
    )
}

/// Fails unless the page rendered cleanly: no error or request, every plot
/// drawn, every view drawn and moving.
fn assert_rendered(page: &Path, verdict: &serde_json::Value, log: &str, views: usize) {
    let name = page.display();
    assert_eq!(verdict["errors"], serde_json::json!([]), "{name}: errors");
    assert_eq!(
        verdict["requests"],
        serde_json::json!([]),
        "{name}: requests"
    );
    // The one message let through is the GL driver's note that reading the
    // pixels back (this test's own check) stalls the pipeline.
    let console: Vec<&str> = log
        .lines()
        .filter(|l| l.contains("CONSOLE") || l.contains("Uncaught"))
        .filter(|l| !l.contains("GL Driver Message (OpenGL, Performance, GL_CLOSE_PATH_NV, High): GPU stall due to ReadPixels"))
        .collect();
    assert!(console.is_empty(), "{name}: console: {console:?}");
    let plots = verdict["plots"].as_array().expect("plots");
    assert!(!plots.is_empty(), "{name}: no plot");
    assert!(
        plots.iter().all(|p| p == true),
        "{name}: a plot did not draw: {plots:?}"
    );
    let drawn = verdict["views"].as_array().expect("views");
    assert_eq!(drawn.len(), views, "{name}: 3D views");
    for view in drawn {
        let share = |key: &str| view[key].as_f64().expect("a share");
        assert!(share("drawn_share") > 0.01, "{name}: blank view {view}");
        assert!(share("moved_share") > 1e-4, "{name}: still view {view}");
    }
}

/// The page's data (the JSON it carries).
fn page_data(page: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(page).expect("page");
    let open = "id=\"fistage-report-data\">";
    let start = text.find(open).expect("data") + open.len();
    let end = start + text[start..].find("</script>").expect("data ends");
    serde_json::from_str(&text[start..end]).expect("data parses")
}

/// The bearings' motions in the page's 3D view are the mode shapes of
/// `modes.json`: each bearing slides on its rail along x, so its translation
/// per unit of shape is the shape entry, magnitude times the cosine (real
/// part) and sine (imaginary part) of its phase. The page measures them by
/// moving the model, modes.json reads them off the eigenvector.
fn assert_motions_match_modes_json(folder: &Path) {
    let modes: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("modes.json")).unwrap()).unwrap();
    let page = page_data(&folder.join("report.html"));
    let scenes: Vec<&serde_json::Value> = page["sections"][0]["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|b| b["type"] == "scene")
        .collect();
    let analyses = modes["analyses"].as_array().unwrap();
    assert_eq!(scenes.len(), analyses.len());
    let mut anti_phase = 0;
    let mut checked = 0;
    for (scene, analysis) in scenes.iter().zip(analyses) {
        let bodies: Vec<&str> = scene["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["name"].as_str().unwrap())
            .collect();
        for shown in scene["modes"].as_array().unwrap() {
            let number: usize = shown["label"].as_str().unwrap()[5..].parse().unwrap();
            let mode = &analysis["modes"][number - 1];
            let hz = mode["frequency_hz"].as_f64().unwrap();
            assert!((shown["frequency_hz"].as_f64().unwrap() - hz).abs() <= 1e-12 * hz);
            let mut signs = Vec::new();
            for entry in mode["participation"].as_array().unwrap() {
                let coordinate = entry["coordinate"].as_str().unwrap();
                let Some(b) = bodies.iter().position(|n| *n == coordinate) else {
                    continue;
                };
                let magnitude = entry["magnitude"].as_f64().unwrap();
                let phase = entry["phase_deg"].as_f64().unwrap().to_radians();
                let motion = &shown["bodies"][b];
                let re = motion["translation_re"][0].as_f64().unwrap();
                let im = motion["translation_im"][0].as_f64().unwrap();
                assert!(
                    (re - magnitude * phase.cos()).abs() < 1e-6
                        && (im - magnitude * phase.sin()).abs() < 1e-6,
                    "{coordinate} in {}: view ({re}, {im}), modes.json {magnitude} at {} deg",
                    shown["label"],
                    phase.to_degrees()
                );
                checked += 1;
                if magnitude > 0.5 {
                    signs.push(phase.cos().signum());
                }
            }
            if signs.contains(&1.0) && signs.contains(&-1.0) {
                anti_phase += 1;
            }
        }
    }
    assert!(checked > 10, "only {checked} bearing entries checked");
    assert!(anti_phase > 0, "no mode with bearings in anti-phase");
}

/// `fistage run` of the paper's Fig. 5b stage into `out`, without the static plots.
fn run_fig05b(out: &Path, extra: &[&str]) {
    let scenario = repository().join("scenarios/paper/fig05b_fi.toml");
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "run".as_ref(),
        scenario.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--no-plots".as_ref(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    succeeds(&args);
}

#[test]
fn report_pages_render_in_a_real_browser_and_show_the_modes_of_modes_json() {
    let Some(browser) = browser_or_skip("modes") else {
        return;
    };
    let dir = scratch("browser");
    let repo = repository();
    let run = dir.join("fig05b");
    let modes = dir.join("four_bearing_modes");
    run_fig05b(&run, &[]);
    succeeds(&[
        "modes".as_ref(),
        repo.join("scenarios/coupling/symmetric_fig05b.toml")
            .as_os_str(),
        "--out".as_ref(),
        modes.as_os_str(),
    ]);
    let study = dir.join("study.html");
    succeeds(&[
        "report".as_ref(),
        run.as_os_str(),
        modes.as_os_str(),
        "-o".as_ref(),
        study.as_os_str(),
    ]);
    let run_page = run.join("report.html");
    let size = std::fs::metadata(&run_page).unwrap().len();
    assert!(size <= RUN_PAGE_LIMIT, "fig05b's page is {size} bytes");
    let profile = dir.join("profile");
    for (page, views) in [(run_page, 0), (modes.join("report.html"), 2), (study, 2)] {
        let (verdict, log) = open(&browser, &page, &profile);
        assert_rendered(&page, &verdict, &log, views);
    }
    assert_motions_match_modes_json(&modes);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn no_report_skips_the_page_and_report_refuses_a_folder_without_one() {
    let dir = scratch("no-report");
    let run = dir.join("run");
    run_fig05b(&run, &["--no-report"]);
    assert!(run.join("summary.json").exists());
    assert!(!run.join("report.html").exists());
    let output = crate::cli::fistage()
        .args(["report".as_ref(), run.as_os_str(), "-o".as_ref()])
        .arg(dir.join("page.html"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no report.html"), "{stderr}");
    assert!(!dir.join("page.html").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// The block of the page's first section with this title.
fn block<'a>(page: &'a serde_json::Value, title: &str) -> &'a serde_json::Value {
    page["sections"][0]["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["title"] == title)
        .unwrap_or_else(|| panic!("no block {title}"))
}

/// The leading number of a cell such as `0.9531 (95% interval ...)`.
fn leading_number(cell: &serde_json::Value) -> f64 {
    let text = cell.as_str().unwrap();
    text.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn study_and_fit_pages_render_and_carry_the_numbers_of_their_json() {
    let Some(browser) = browser_or_skip("studies") else {
        return;
    };
    let dir = scratch("browser-studies");
    let repo = repository();
    let robust = dir.join("robust");
    let population = repo.join("scenarios/robust/four_bearing_population.toml");
    succeeds(&[
        "robust".as_ref(),
        population.as_os_str(),
        "--samples".as_ref(),
        "32".as_ref(),
        "--out".as_ref(),
        robust.as_os_str(),
    ]);
    let tune = dir.join("tune");
    succeeds(&[
        "tune".as_ref(),
        population.as_os_str(),
        "--samples".as_ref(),
        "8".as_ref(),
        "--points".as_ref(),
        "5".as_ref(),
        "--out".as_ref(),
        tune.as_os_str(),
    ]);
    let record = dir.join("record.csv");
    succeeds(&[
        "identify".as_ref(),
        "simulate-record".as_ref(),
        repo.join("robots/stage_1dof_rigid.urdf").as_os_str(),
        "--out".as_ref(),
        record.as_os_str(),
    ]);
    let fit = dir.join("fit");
    succeeds(&[
        "identify".as_ref(),
        "record".as_ref(),
        record.as_os_str(),
        "--out".as_ref(),
        fit.as_os_str(),
    ]);
    let curve = dir.join("stribeck.csv");
    succeeds(&[
        "identify".as_ref(),
        "simulate-stribeck".as_ref(),
        repo.join("robots/stage_1dof_rigid.urdf").as_os_str(),
        "--out".as_ref(),
        curve.as_os_str(),
    ]);
    let stribeck = dir.join("stribeck");
    succeeds(&[
        "identify".as_ref(),
        "stribeck".as_ref(),
        curve.as_os_str(),
        "--out".as_ref(),
        stribeck.as_os_str(),
    ]);
    let sweep = dir.join("sweep");
    succeeds(&[
        "sweep".as_ref(),
        repo.join("scenarios/paper/fig06b_fi_vp20.toml").as_os_str(),
        "--out".as_ref(),
        sweep.as_os_str(),
    ]);
    let compare = dir.join("compare");
    let paper = repo.join("scenarios/paper");
    succeeds(&[
        "compare".as_ref(),
        paper.join("fig03a_ff_rigid.toml").as_os_str(),
        paper.join("fig03a_ff_fi.toml").as_os_str(),
        "--baseline".as_ref(),
        paper.join("fig03a_baseline.toml").as_os_str(),
        "--out".as_ref(),
        compare.as_os_str(),
    ]);
    let profile = dir.join("profile");
    for folder in [&robust, &tune, &fit, &stribeck, &sweep, &compare] {
        let page = folder.join("report.html");
        let (verdict, log) = open(&browser, &page, &profile);
        assert_rendered(&page, &verdict, &log, 0);
    }
    // The population's probability as summary.json has it.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(robust.join("summary.json")).unwrap())
            .unwrap();
    let page = page_data(&robust.join("report.html"));
    let facts = block(&page, "population");
    let shown = facts["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|row| row[0] == "P(linearly unstable)")
        .map(|row| leading_number(&row[1]))
        .unwrap();
    let estimate = summary["p_unstable_linear"]["estimate"].as_f64().unwrap();
    assert!(
        (shown - estimate).abs() <= 1e-3 * estimate.abs().max(1e-3),
        "{shown} {estimate}"
    );
    // The fitted parameters as fit.json has them.
    let fitted: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fit.join("fit.json")).unwrap()).unwrap();
    let page = page_data(&fit.join("report.html"));
    for row in block(&page, "parameters")["rows"].as_array().unwrap() {
        let name = row[0].as_str().unwrap();
        let value = fitted[name]["value"].as_f64().unwrap();
        let shown = leading_number(&row[2]);
        assert!(
            (shown / value - 1.0).abs() < 1e-3,
            "{name}: page {shown}, fit.json {value}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
