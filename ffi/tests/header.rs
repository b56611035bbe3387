//! The checked-in C headers `include/fistage_stage.h` (FMI 2.0) and
//! `include/fistage_stage_fmi3.h` (FMI 3.0) are what cbindgen makes of the
//! code now. To refresh them after changing an exported function, run these
//! tests with `FISTAGE_BLESS=1`.

use std::path::Path;

/// The header cbindgen generates from `sources` with `config`, compared
/// with (or, blessed, written to) `include/<header>`.
fn generated_header(config: &str, sources: &[&str], header: &str) -> String {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join(config)).expect("cbindgen config");
    let mut builder = cbindgen::Builder::new().with_config(config);
    for source in sources {
        builder = builder.with_src(crate_dir.join(source));
    }
    let mut generated = Vec::new();
    builder
        .generate()
        .expect("cbindgen parses the exports")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = crate_dir.join("include").join(header);
    if std::env::var_os("FISTAGE_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write header");
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is stale: rerun this test with FISTAGE_BLESS=1 and commit the header",
        path.display()
    );
    generated
}

#[test]
fn checked_in_header_matches_the_code() {
    let generated = generated_header(
        "cbindgen.toml",
        &["src/fmi2/types.rs", "src/fmi2/exports.rs"],
        "fistage_stage.h",
    );
    let functions = generated.matches("fmi2Status fmi2").count()
        + generated.matches("fmi2Component fmi2Instantiate(").count()
        + generated.matches("void fmi2FreeInstance(").count()
        + generated.matches("const char *fmi2Get").count();
    assert_eq!(
        functions, 44,
        "the header declares every FMI 2.0 ME and CS function once"
    );
}

#[test]
fn checked_in_fmi3_header_matches_the_code() {
    let generated = generated_header(
        "cbindgen_fmi3.toml",
        &["src/fmi3/types.rs", "src/fmi3/exports.rs"],
        "fistage_stage_fmi3.h",
    );
    let declarations: Vec<&str> = generated
        .lines()
        .filter(|l| {
            l.starts_with("fmi3") || l.starts_with("const char *fmi3") || l.starts_with("void fmi3")
        })
        .collect();
    let declared = declarations.len();
    assert!(
        declarations.iter().all(|l| !l.contains("fmi2")),
        "the FMI 3.0 header declares FMI 2.0 types"
    );
    assert_eq!(
        declared, FMI3_FUNCTIONS,
        "the FMI 3.0 header declares each of the standard's {FMI3_FUNCTIONS} functions once"
    );
}

/// The FMI 3.0 standard's functions.
const FMI3_FUNCTIONS: usize = 75;
