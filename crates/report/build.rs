//! Packs the report's script with the libraries it embeds (Plotly's cartesian
//! bundle and three.js, pinned in `web/package-lock.json`) into one file, and
//! gathers their licences, both into `OUT_DIR`.
//!
//! The libraries come from the npm registry through `npm ci` (Node.js 18 or
//! newer); esbuild, pinned beside them, bundles and minifies. Nothing is
//! written into the source tree. Without npm the crate still builds: the
//! bundle is left empty and every page refuses to be written, by name
//! (`ReportError::Unavailable`). `FISTAGE_REPORT_REQUIRED=1` turns that into
//! a build failure (CI sets it). `FISTAGE_REPORT_BUNDLE=DIR` takes a bundle
//! made earlier (`report.js` and `licences.txt`) instead of running npm.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The libraries the page embeds: package folder and how its licence is named.
const EMBEDDED: [(&str, &str); 2] = [("plotly.js-cartesian-dist-min", "MIT"), ("three", "MIT")];

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    let web = manifest.join("web");
    for watched in ["package.json", "package-lock.json", "src"] {
        println!("cargo::rerun-if-changed={}", web.join(watched).display());
    }
    println!("cargo::rerun-if-env-changed=FISTAGE_REPORT_REQUIRED");
    println!("cargo::rerun-if-env-changed=FISTAGE_REPORT_BUNDLE");
    println!("cargo::rustc-check-cfg=cfg(fistage_report_unavailable)");
    let made = match std::env::var_os("FISTAGE_REPORT_BUNDLE") {
        Some(dir) => copy_bundle(Path::new(&dir), &out),
        None => bundle(&web, &out),
    };
    if let Err(why) = made {
        if std::env::var("FISTAGE_REPORT_REQUIRED").is_ok_and(|v| v == "1") {
            panic!("the HTML report's bundle could not be made: {why}");
        }
        println!("cargo::warning=fistage builds without its HTML report: {why}");
        println!("cargo::rustc-cfg=fistage_report_unavailable");
        write(&out.join("report.js"), "");
        write(&out.join("licences.txt"), "");
        write(&out.join("unavailable.txt"), &why);
    } else {
        write(&out.join("unavailable.txt"), "");
    }
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

fn copy_bundle(dir: &Path, out: &Path) -> Result<(), String> {
    for name in ["report.js", "licences.txt"] {
        std::fs::copy(dir.join(name), out.join(name)).map_err(|e| {
            format!(
                "FISTAGE_REPORT_BUNDLE: cannot copy {}: {e}",
                dir.join(name).display()
            )
        })?;
    }
    Ok(())
}

/// `npm ci` in a copy of `web` under `out`, then esbuild into `out/report.js`.
fn bundle(web: &Path, out: &Path) -> Result<(), String> {
    let work = out.join("web");
    std::fs::create_dir_all(work.join("src")).map_err(|e| e.to_string())?;
    for name in ["package.json", "package-lock.json"] {
        std::fs::copy(web.join(name), work.join(name)).map_err(|e| format!("{name}: {e}"))?;
    }
    let sources = std::fs::read_dir(web.join("src")).map_err(|e| format!("web/src: {e}"))?;
    for entry in sources {
        let entry = entry.map_err(|e| e.to_string())?;
        std::fs::copy(entry.path(), work.join("src").join(entry.file_name()))
            .map_err(|e| format!("{}: {e}", entry.path().display()))?;
    }
    let installed = work.join("node_modules/.package-lock.json");
    let lock_unchanged = std::fs::read(work.join("package-lock.json")).ok()
        == std::fs::read(work.join("node_modules/.fistage-lock")).ok();
    if !(installed.exists() && lock_unchanged) {
        run(
            Command::new(npm())
                .args([
                    "ci",
                    "--ignore-scripts",
                    "--no-audit",
                    "--no-fund",
                    "--loglevel=error",
                ])
                .current_dir(&work),
            "npm ci (Node.js's package manager, fetching the pinned libraries)",
        )?;
        std::fs::copy(
            work.join("package-lock.json"),
            work.join("node_modules/.fistage-lock"),
        )
        .map_err(|e| e.to_string())?;
    }
    run(
        Command::new("node")
            .arg("node_modules/esbuild/bin/esbuild")
            .args([
                "src/main.js",
                "--bundle",
                "--minify",
                "--format=iife",
                "--legal-comments=none",
            ])
            .arg(format!("--outfile={}", out.join("report.js").display()))
            .arg("--log-level=error")
            .current_dir(&work),
        "esbuild (bundling the report's script)",
    )?;
    let mut licences = String::new();
    for (package, licence) in EMBEDDED {
        let folder = work.join("node_modules").join(package);
        let version = package_version(&folder)?;
        let text = std::fs::read_to_string(folder.join("LICENSE"))
            .map_err(|e| format!("{package}: licence: {e}"))?;
        licences.push_str(&format!(
            "{package} {version} ({licence})\n\n{}\n\n",
            text.trim()
        ));
    }
    write(&out.join("licences.txt"), &licences);
    Ok(())
}

fn npm() -> &'static str {
    if cfg!(windows) { "npm.cmd" } else { "npm" }
}

fn package_version(folder: &Path) -> Result<String, String> {
    let text = std::fs::read_to_string(folder.join("package.json"))
        .map_err(|e| format!("{}: {e}", folder.display()))?;
    text.lines()
        .find_map(|line| {
            let line = line.trim();
            line.strip_prefix("\"version\":")
                .map(|v| v.trim().trim_end_matches(',').trim_matches('"').to_string())
        })
        .ok_or_else(|| format!("{}: no version", folder.display()))
}

fn run(command: &mut Command, what: &str) -> Result<(), String> {
    let output = command
        .output()
        .map_err(|e| format!("{what}: cannot start: {e}"))?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{what} failed ({}): {}",
            output.status,
            String::from_utf8_lossy(&output.stderr).trim()
        ))
    }
}
