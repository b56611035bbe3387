//! Every entry of the parameter table walked through each way in: a scenario
//! override (or `[controller]` key) reaches the assembled model and the FMI
//! variable's start value; a value an importer sets reaches the model the
//! unit rebuilds at fmi2ExitInitializationMode; and a value the loader
//! refuses is refused by the FMU too, at fmi2ExitInitializationMode.

use std::path::{Path, PathBuf};

use fistage_fmi::{Binding, Instance, variables};
use fistage_model::{Parameter, RobotSpec, Rule, Scenario, assemble};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// A value the rules admit and that differs from `nominal` (f_c moves down,
/// to stay below f_s).
fn admissible(parameter: &Parameter, nominal: f64) -> f64 {
    if parameter.path().ends_with(".f_c") {
        nominal * 0.8
    } else {
        nominal.abs() * 1.25 + 0.5
    }
}

/// A value the rule refuses.
fn refused(rule: Rule) -> f64 {
    match rule {
        Rule::Finite => f64::INFINITY,
        Rule::Spread => 1.5,
        Rule::RelativeChange => -1.5,
        Rule::NonNegative | Rule::Positive => -1.0,
    }
}

/// The scenario's own text with one parameter path set to `value`: a key of
/// `[controller]`, of `[overrides.<element>]`, or of the compensator of
/// `<element>` (`[compensation]` or its `[[compensation]]` entry).
fn scenario_setting(text: &str, parameter: &Parameter, value: f64) -> String {
    let mut table: toml::Table = text.parse().expect("scenario TOML");
    let path: Vec<&str> = parameter.path().split('.').collect();
    if let ["compensation", element, rest @ ..] = path.as_slice()
        && *element != "error"
        && !rest.is_empty()
    {
        let named =
            |e: &toml::Table| e.get("element").and_then(toml::Value::as_str) == Some(element);
        let entry = match table.get_mut("compensation") {
            Some(toml::Value::Array(entries)) => (entries.iter_mut())
                .filter_map(toml::Value::as_table_mut)
                .find(|e| named(e)),
            Some(toml::Value::Table(one)) => Some(one).filter(|e| named(e)),
            _ => None,
        }
        .unwrap_or_else(|| panic!("{parameter}: no compensator of {element}"));
        let (place, key) = match rest {
            ["error", key] => (
                entry
                    .entry("error")
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                    .as_table_mut()
                    .expect("a table"),
                *key,
            ),
            [key] => (entry, *key),
            _ => panic!("{parameter} is not a compensator key"),
        };
        place.insert(key.to_string(), toml::Value::Float(value));
        return toml::to_string(&table).expect("TOML out");
    }
    let (tables, key) = match path.as_slice() {
        ["controller", key] => (vec!["controller"], *key),
        ["overrides", element, key] => (vec!["overrides", *element], *key),
        ["compensation", "error", key] => (vec!["compensation", "error"], *key),
        ["compensation", key] => (vec!["compensation"], *key),
        ["dob", key] => (vec!["dob"], *key),
        _ => panic!("{parameter} is not a scenario key"),
    };
    let mut place = &mut table;
    for name in tables {
        place = place
            .entry(name)
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .expect("a table");
    }
    place.insert(key.to_string(), toml::Value::Float(value));
    toml::to_string(&table).expect("TOML out")
}

fn walk(scenario_file: &str) -> usize {
    let file = root().join(scenario_file);
    let text = std::fs::read_to_string(&file).expect("scenario text");
    let scenario = Scenario::from_file(&file).expect("scenario");
    let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    let resources = std::env::temp_dir().join(format!(
        "fistage-parameter-walk-{}-{}",
        std::process::id(),
        file.file_stem().and_then(|s| s.to_str()).unwrap_or("s")
    ));
    std::fs::create_dir_all(&resources).expect("resources folder");
    fistage_fmi::package::write_resources(&file, &resources).expect("resources");
    let mut walked = 0;
    let entries = Parameter::all(&scenario, &robot);
    for parameter in entries.iter().filter(|p| p.is_fmi_variable()) {
        let nominal = parameter.read(&scenario, &robot);
        let value = admissible(parameter, nominal);
        // 1. Scenario file → model → FMI start value.
        let edited = scenario_setting(&text, parameter, value);
        let edited_scenario = Scenario::from_str(&edited, &file).expect("edited scenario");
        let (_, model) = assemble(robot.clone(), &edited_scenario)
            .unwrap_or_else(|e| panic!("{parameter} = {value}: {e}"));
        assert_eq!(parameter.read_model(&model), Some(value), "{parameter}");
        let list = variables(&model, &edited_scenario);
        let variable = list
            .iter()
            .find(|v| matches!(&v.binding, Binding::Parameter(p) if p == parameter))
            .unwrap_or_else(|| panic!("{parameter} is an FMI variable"));
        assert_eq!(variable.name, parameter.short_name());
        assert_eq!(variable.start, Some(value), "{parameter}");
        assert_eq!(variable.unit, parameter.unit());
        // 2. Importer → rebuilt model → read back.
        let mut instance = Instance::new(&resources, None).expect("instance");
        let vr = variable.value_reference;
        instance.set_real(&[vr], &[value]).expect("set");
        instance.enter_initialization().expect("enter");
        instance
            .exit_initialization()
            .unwrap_or_else(|e| panic!("{parameter} = {value}: {e}"));
        assert_eq!(
            parameter.read_model(instance.model()),
            Some(value),
            "{parameter}"
        );
        let mut back = [0.0];
        instance.get_real(&[vr], &mut back).expect("get");
        assert_eq!(back[0], value);
        // 3. A value the loader refuses, the FMU refuses.
        let bad = refused(parameter.rule());
        let edited = scenario_setting(&text, parameter, bad);
        let loader = Scenario::from_str(&edited, &file)
            .and_then(|s| assemble(robot.clone(), &s).map(|_| ()));
        assert!(loader.is_err(), "the loader takes {parameter} = {bad}");
        let mut instance = Instance::new(&resources, None).expect("instance");
        if instance.set_real(&[vr], &[bad]).is_ok() {
            instance.enter_initialization().expect("enter");
            let error = instance
                .exit_initialization()
                .expect_err("the FMU refuses what the loader refuses");
            assert!(
                error.to_string().contains(parameter.short_name()),
                "{error}"
            );
        }
        walked += 1;
    }
    let _ = std::fs::remove_dir_all(&resources);
    walked
}

#[test]
fn every_fmi_parameter_walks_from_file_and_importer_into_the_model() {
    let one_dof = walk("scenarios/paper/fig05b_fi.toml");
    let four_bearing = walk("scenarios/coupling/friction20_traverse.toml");
    println!("walked {one_dof} + {four_bearing} parameters");
    // fig05b: 3 gains, 6 LuGre, 12 isolator; four bearings: 3 + 4 * 6 + 4 * 12.
    assert_eq!(one_dof, 3 + 6 + 12);
    assert_eq!(four_bearing, 3 + 4 * 6 + 4 * 12);
    // The compensator's model and its errors, and the observer, are FMU
    // parameters too: the LuGre feedforward of Fig. 3a (6 values, 6 errors)
    // and the observer of Fig. 3b (bandwidth, nominal mass).
    let compensated = walk("scenarios/paper/fig03a_lugre_fi.toml");
    let observed = walk("scenarios/paper/fig03b_dob_fi.toml");
    println!("walked {compensated} and {observed} parameters with compensation");
    assert_eq!(compensated, 3 + 6 + 12 + 6 + 6);
    assert_eq!(observed, 3 + 6 + 12 + 2);
    // One compensator per bearing: each one's model and errors, by element
    // (`compensation.friction_fl.error.f_c`).
    let per_bearing = walk("scenarios/compensation/friction20_traverse_per_bearing.toml");
    println!("walked {per_bearing} parameters with four compensators");
    assert_eq!(per_bearing, 3 + 4 * 6 + 4 * 12 + 4 * (6 + 6));
}
