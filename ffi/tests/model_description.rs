//! The model description of exported stages: well-formed XML, unique names
//! and value references, start values equal to the model's, a model structure
//! that lists exactly the outputs and, for Model Exchange, one derivative per
//! state pointing at its state, declared units, and a GUID that is stable for
//! the same model and changes with it.

use std::collections::HashSet;
use std::path::PathBuf;

use fistage_fmi::{Capabilities, model_description};

fn load(relative: &str) -> fistage_model::Loaded {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(relative);
    fistage_model::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

const CAPABILITIES: Capabilities = Capabilities {
    fmu_state: true,
    directional_derivatives: true,
};

fn check(relative: &str) -> String {
    let loaded = load(relative);
    let xml = model_description(&loaded.model, &loaded.scenario, CAPABILITIES);
    if let Ok(dir) = std::env::var("FISTAGE_WRITE_MODEL_DESCRIPTIONS") {
        let name = relative.replace('/', "_").replace(".toml", ".xml");
        std::fs::write(PathBuf::from(dir).join(name), &xml).expect("write");
    }
    let document = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let root = document.root_element();
    assert_eq!(root.attribute("fmiVersion"), Some("2.0"));
    let units: HashSet<&str> = root
        .descendants()
        .filter(|n| n.has_tag_name("Unit"))
        .filter_map(|n| n.attribute("name"))
        .collect();
    let variables: Vec<roxmltree::Node> = root
        .descendants()
        .filter(|n| n.has_tag_name("ScalarVariable"))
        .collect();
    let mut names = HashSet::new();
    let mut references = HashSet::new();
    let mut outputs = Vec::new();
    let mut states = Vec::new();
    let mut derivatives = Vec::new();
    for (index, variable) in variables.iter().enumerate() {
        let name = variable.attribute("name").expect("name");
        assert!(names.insert(name), "{name} twice");
        assert!(
            references.insert(variable.attribute("valueReference").expect("vr")),
            "{name}: reference twice"
        );
        let real = variable
            .children()
            .find(|c| c.has_tag_name("Real"))
            .expect("Real");
        let unit = real.attribute("unit").expect("unit");
        assert!(units.contains(unit), "{name}: unit {unit} not declared");
        match variable.attribute("causality") {
            Some("parameter") | Some("input") => {
                assert!(real.attribute("start").is_some(), "{name} needs a start")
            }
            Some("output") => {
                assert!(real.attribute("start").is_none());
                outputs.push(index + 1);
            }
            Some("local") => match real.attribute("derivative") {
                Some(of) => {
                    let of: usize = of.parse().expect("derivative index");
                    let state = variables[of - 1].attribute("name").expect("name");
                    assert_eq!(
                        name,
                        format!("der({state})"),
                        "{name} differentiates {state}"
                    );
                    derivatives.push(index + 1);
                }
                None => states.push(index + 1),
            },
            other => panic!("{name}: causality {other:?}"),
        }
    }
    assert_eq!(outputs.len(), loaded.model.signals().len());
    let listed: Vec<usize> = root
        .descendants()
        .find(|n| n.has_tag_name("Outputs"))
        .expect("Outputs")
        .children()
        .filter_map(|n| n.attribute("index"))
        .map(|i| i.parse().expect("index"))
        .collect();
    assert_eq!(
        listed, outputs,
        "ModelStructure/Outputs lists exactly the outputs"
    );
    assert_eq!(states.len(), loaded.model.n_states());
    assert_eq!(derivatives.len(), loaded.model.n_states());
    let listed: Vec<usize> = root
        .descendants()
        .find(|n| n.has_tag_name("Derivatives"))
        .expect("Derivatives")
        .children()
        .filter_map(|n| n.attribute("index"))
        .map(|i| i.parse().expect("index"))
        .collect();
    assert_eq!(
        listed, derivatives,
        "ModelStructure/Derivatives lists every derivative"
    );
    assert!(root.descendants().any(|n| n.has_tag_name("ModelExchange")));
    // Parameter starts are the model's values, exactly.
    let start = |name: &str| -> f64 {
        variables
            .iter()
            .find(|v| v.attribute("name") == Some(name))
            .and_then(|v| v.children().find(|c| c.has_tag_name("Real")))
            .and_then(|r| r.attribute("start"))
            .expect("start")
            .parse()
            .expect("number")
    };
    let controller = loaded.model.controller().expect("controller");
    assert_eq!(start("controller.k"), controller.k);
    for friction in loaded.model.frictions() {
        assert_eq!(
            start(&format!("{}.sigma0", friction.name)),
            friction.lugre.sigma0
        );
        assert_eq!(start(&format!("{}.v_s", friction.name)), friction.lugre.v_s);
    }
    assert_eq!(
        start("platform_velocity"),
        loaded.scenario.platform_velocity
    );
    xml
}

#[test]
fn one_dof_stage_description() {
    let xml = check("scenarios/paper/fig05b_fi.toml");
    assert!(xml.contains("name=\"encoder.position\""));
    assert!(xml.contains("modelIdentifier=\"fistage_stage\""));
}

#[test]
fn six_dof_stage_description() {
    let xml = check("scenarios/coupling/friction20_traverse.toml");
    for name in [
        "table.yaw",
        "friction_rr.force",
        "isolator_fl.dx",
        "isolator_fl.k_rz",
    ] {
        assert!(xml.contains(&format!("name=\"{name}\"")), "{name}");
    }
}

#[test]
fn guid_is_stable_and_follows_the_model() {
    let guid = |xml: &str| -> String {
        let start = xml.find("guid=\"").expect("guid") + 6;
        xml[start..start + 38].to_string()
    };
    let loaded = load("scenarios/paper/fig05b_fi.toml");
    let first = guid(&model_description(
        &loaded.model,
        &loaded.scenario,
        CAPABILITIES,
    ));
    let again = guid(&model_description(
        &loaded.model,
        &loaded.scenario,
        CAPABILITIES,
    ));
    assert_eq!(first, again);
    assert!(first.starts_with('{') && first.ends_with('}'), "{first}");
    let other = load("scenarios/paper/fig05a_fi.toml");
    let changed = guid(&model_description(
        &other.model,
        &other.scenario,
        CAPABILITIES,
    ));
    assert_ne!(first, changed, "c = 10 and c = 100 must not share a GUID");
}

/// The FMI 3.0 description: one independent `time`, unique value
/// references, each derivative naming its state by value reference, every
/// derivative in the model structure, and the FMI 2.0 GUID of the same
/// model as the instantiation token.
#[test]
fn fmi3_description_is_consistent() {
    for scenario in [
        "scenarios/paper/fig05b_fi.toml",
        "scenarios/coupling/friction20_traverse.toml",
    ] {
        let loaded = load(scenario);
        let xml = fistage_fmi::fmi3::model_description::model_description(
            &loaded.model,
            &loaded.scenario,
            CAPABILITIES,
        );
        let document = roxmltree::Document::parse(&xml).expect("well-formed XML");
        let root = document.root_element();
        assert_eq!(root.attribute("fmiVersion"), Some("3.0"));
        let fmi2 = model_description(&loaded.model, &loaded.scenario, CAPABILITIES);
        let token = root.attribute("instantiationToken").expect("token");
        assert!(fmi2.contains(&format!("guid=\"{token}\"")), "{scenario}");
        let variables: Vec<roxmltree::Node> = root
            .descendants()
            .filter(|n| n.has_tag_name("Float64"))
            .collect();
        let by_reference: std::collections::HashMap<&str, &str> = variables
            .iter()
            .map(|v| {
                (
                    v.attribute("valueReference").expect("vr"),
                    v.attribute("name").expect("name"),
                )
            })
            .collect();
        assert_eq!(
            by_reference.len(),
            variables.len(),
            "{scenario}: a reference twice"
        );
        let independent: Vec<_> = variables
            .iter()
            .filter(|v| v.attribute("causality") == Some("independent"))
            .collect();
        assert_eq!(independent.len(), 1);
        assert_eq!(independent[0].attribute("name"), Some("time"));
        let mut derivatives = Vec::new();
        for v in &variables {
            if let Some(of) = v.attribute("derivative") {
                let state = by_reference[of];
                assert_eq!(v.attribute("name"), Some(format!("der({state})").as_str()));
                derivatives.push(v.attribute("valueReference").expect("vr"));
            }
        }
        assert_eq!(derivatives.len(), loaded.model.n_states());
        let listed: Vec<&str> = root
            .descendants()
            .filter(|n| n.has_tag_name("ContinuousStateDerivative"))
            .filter_map(|n| n.attribute("valueReference"))
            .collect();
        assert_eq!(listed, derivatives, "{scenario}");
    }
}
