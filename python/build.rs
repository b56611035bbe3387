//! With the `embed-fmu` feature (maturin's builds), builds the FMU's shared
//! library (`fistage-fmi`, from this workspace) so that `Scenario.export_fmu`
//! needs nothing beside the installed package: the library's bytes are
//! embedded in the extension module. `FISTAGE_FMI_LIBRARY` names a library
//! built already (from this checkout) to embed instead. Without the feature
//! (cargo's checks and tests of the workspace) it does nothing.

use std::env;
use std::path::PathBuf;
use std::process::Command;

fn main() {
    if env::var_os("CARGO_FEATURE_EMBED_FMU").is_none() {
        return;
    }
    println!("cargo:rerun-if-env-changed=FISTAGE_FMI_LIBRARY");
    // A library already built from this checkout (CI builds it with the
    // tests and names it here) is embedded as it is.
    if let Some(library) = env::var_os("FISTAGE_FMI_LIBRARY") {
        let library = PathBuf::from(library);
        assert!(
            library.is_file(),
            "FISTAGE_FMI_LIBRARY names no file: {}",
            library.display()
        );
        println!("cargo:rustc-env=FISTAGE_FMI_EMBEDDED={}", library.display());
        println!("cargo:rerun-if-changed={}", library.display());
        return;
    }
    let manifest_dir = PathBuf::from(env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = manifest_dir.join("..");
    let target = PathBuf::from(env::var("OUT_DIR").expect("set by cargo")).join("fmi-target");
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "--locked", "-p", "fistage-fmi"])
        .arg("--manifest-path")
        .arg(root.join("Cargo.toml"))
        .arg("--target-dir")
        .arg(&target)
        .args(["--config", "profile.release.debug=false"])
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("RUSTFLAGS")
        .status()
        .expect("cargo runs");
    assert!(status.success(), "building fistage-fmi for the FMU failed");
    let library = target.join("release").join("libfistage_fmi.so");
    println!("cargo:rustc-env=FISTAGE_FMI_EMBEDDED={}", library.display());
    for path in [
        "../ffi",
        "../crates/model",
        "../crates/sim",
        "../Cargo.lock",
    ] {
        println!("cargo:rerun-if-changed={path}");
    }
}
