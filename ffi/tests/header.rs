//! The checked-in C header `include/fistage_stage.h` is what cbindgen makes
//! of the code now. To refresh it after changing an exported function, run
//! this test with `FISTAGE_BLESS=1`.

use std::path::Path;

#[test]
fn checked_in_header_matches_the_code() {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config =
        cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_config(config)
        .with_src(crate_dir.join("src/types.rs"))
        .with_src(crate_dir.join("src/exports.rs"))
        .generate()
        .expect("cbindgen parses the exports")
        .write(&mut generated);
    let generated = String::from_utf8(generated).expect("UTF-8 header");
    let path = crate_dir.join("include/fistage_stage.h");
    if std::env::var_os("FISTAGE_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write header");
    }
    let checked_in = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        checked_in == generated,
        "{} is stale: rerun this test with FISTAGE_BLESS=1 and commit the header",
        path.display()
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
