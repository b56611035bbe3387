//! The FMU archive: deflate-compressed entries, a library without debug
//! information, small enough to mail (fig05b at most 3 MB), and a library
//! that is not a fistage FMI shared object is refused.

use crate::support;

use std::io::Read;

#[test]
fn fig05b_fmu_is_deflated_small_and_carries_no_debug_information() {
    let folder = support::scratch("package");
    let fmu = support::fmu("scenarios/paper/fig05b_fi.toml", &folder);
    let size = std::fs::metadata(&fmu).expect("fmu written").len();
    println!("fig05b FMU: {:.2} MB", size as f64 / 1e6);
    assert!(size <= 3_000_000, "{size} bytes");
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&fmu).expect("open")).expect("zip");
    let mut names = Vec::new();
    for i in 0..archive.len() {
        let mut entry = archive.by_index(i).expect("entry");
        let name = entry.name().expect("UTF-8 entry name").to_string();
        assert_eq!(
            entry.compression(),
            zip::CompressionMethod::Deflated,
            "{name}"
        );
        if name.ends_with(".so") {
            let mut library = Vec::new();
            entry.read_to_end(&mut library).expect("inflate");
            use object::Object;
            let elf = object::read::elf::ElfFile64::<object::Endianness>::parse(&*library)
                .expect("the packaged library is a 64-bit ELF file");
            let debug: Vec<_> = elf
                .sections()
                .filter_map(|s| object::ObjectSection::name(&s).ok().map(str::to_string))
                .filter(|name| name.starts_with(".debug"))
                .collect();
            assert!(debug.is_empty(), "debug sections in the library: {debug:?}");
        }
        names.push(name);
    }
    names.sort();
    assert_eq!(
        names,
        [
            "binaries/linux64/fistage_stage.so",
            "modelDescription.xml",
            "resources/robot.urdf",
            "resources/scenario.toml",
        ]
    );
}

#[test]
fn a_library_that_is_not_the_fmi_shared_object_is_refused() {
    let folder = support::scratch("package-bad-library");
    let scenario = support::root().join("scenarios/paper/fig05b_fi.toml");
    let text = folder.join("notes.txt");
    std::fs::write(&text, "not a library").expect("write");
    let message = fistage_fmi::build_fmu(&scenario, &text)
        .expect_err("a text file is no library")
        .to_string();
    assert!(message.contains("not an ELF shared library"), "{message}");
    // An ELF executable (this test program) is not a shared library either.
    let exe = std::env::current_exe().expect("test binary");
    let message = fistage_fmi::build_fmu(&scenario, &exe)
        .expect_err("an executable is no FMU library")
        .to_string();
    assert!(
        message.contains("not a shared library") || message.contains("does not export"),
        "{message}"
    );
}
