//! The seeds of the `fmu_state` fuzz target (`fuzz/corpus/fmu_state/`) are
//! states this unit serializes today, at every phase a state can be taken in
//! (and with the integral gain on, which adds a state), Co-Simulation and
//! Model Exchange: each one restores in a fresh instance of its interface
//! and is byte for byte what the unit writes now. A change
//! of the state format fails here until the seeds are written again with
//! `FISTAGE_WRITE_FUZZ_SEEDS=1 cargo test -p fistage-fmi --test integration fuzz_seeds`.

use std::path::{Path, PathBuf};

use fistage_fmi::{Instance, Interface};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn resources() -> PathBuf {
    let folder = std::env::temp_dir().join(format!("fistage-fuzz-seeds-{}", std::process::id()));
    std::fs::create_dir_all(&folder).expect("resources folder");
    fistage_fmi::package::write_resources(&root().join("scenarios/paper/fig05b_fi.toml"), &folder)
        .expect("resources");
    folder
}

fn vr(instance: &Instance, name: &str) -> u32 {
    instance
        .variables()
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .value_reference
}

/// (file name, interface, serialized state) for each phase.
fn seeds(folder: &Path) -> Vec<(&'static str, Interface, Vec<u8>)> {
    let mut unit = Instance::new(folder, None).expect("instance");
    let mut seeds = Vec::new();
    let mut take = |name, unit: &Instance| {
        seeds.push((name, unit.interface(), unit.serialize(&unit.snapshot())))
    };
    take("instantiated.bin", &unit);
    unit.setup_experiment(Some(1e-6), 0.0, Some(5.0))
        .expect("setup");
    unit.enter_initialization().expect("enter");
    let k_i = vr(&unit, "controller.k_i");
    unit.set_real(&[k_i], &[2.0e3]).expect("integral gain");
    take("initialization_with_integral.bin", &unit);
    unit.set_real(&[k_i], &[0.0]).expect("integral gain off");
    unit.exit_initialization().expect("exit");
    take("initialized.bin", &unit);
    let mut t = 0.0;
    for k in 1..=50 {
        let next = f64::from(k) * 1e-3;
        unit.do_step(t, next - t).expect("step");
        t = next;
    }
    take("stepping.bin", &unit);
    unit.terminate().expect("terminate");
    take("terminated.bin", &unit);
    let mut unit =
        Instance::for_interface(folder, None, Interface::ModelExchange).expect("instance");
    unit.enter_initialization().expect("enter");
    unit.exit_initialization().expect("exit");
    take("model_exchange_event.bin", &unit);
    unit.enter_continuous_time_mode().expect("continuous");
    let mut x = vec![0.0; unit.model().n_states()];
    unit.get_continuous_states(&mut x).expect("states");
    x[0] += 1e-6;
    unit.set_time(0.01).expect("time");
    unit.set_continuous_states(&x).expect("states");
    take("model_exchange_continuous.bin", &unit);
    seeds
}

#[test]
fn fuzz_seeds_are_states_of_this_unit() {
    let folder = resources();
    let corpus = root().join("fuzz/corpus/fmu_state");
    let write = std::env::var_os("FISTAGE_WRITE_FUZZ_SEEDS").is_some();
    for (name, interface, bytes) in seeds(&folder) {
        let file = corpus.join(name);
        if write {
            std::fs::write(&file, &bytes).expect("write seed");
        }
        let stored = std::fs::read(&file).unwrap_or_default();
        assert!(
            stored == bytes,
            "{} is not what the unit serializes now: write the seeds again (see this file's header)",
            file.display()
        );
        let mut fresh = Instance::for_interface(&folder, None, interface).expect("instance");
        let snapshot = fresh.deserialize(&stored).expect("seed deserializes");
        fresh.restore(&snapshot).expect("seed restores");
        assert_eq!(
            fresh.serialize(&fresh.snapshot()),
            stored,
            "{name} round trip"
        );
    }
    let _ = std::fs::remove_dir_all(&folder);
}
