//! The standard URDF elements checked before [`crate::robot`] reads them, so
//! that a bad value is reported with its element, attribute and line, and so
//! that values a reader would take silently (a NaN joint limit, an empty
//! robot name, a misspelt root element) are refused: the root element is `<robot>` with a usable name,
//! every link and joint has a name, a joint's type is one URDF defines, and
//! every numeric attribute of the elements fistage reads (origins, inertia,
//! axes, limits, dynamics, geometry) holds the right count of finite numbers.

use std::path::Path;

use crate::error::LoadError;
use crate::rule::MAX_MAGNITUDE;
use crate::rule::check_name;

/// Joint types of the URDF specification.
const JOINT_TYPES: [&str; 6] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
];

/// (element path below a link or joint, attribute, count of numbers).
const LINK_NUMBERS: &[(&[&str], &str, usize)] = &[
    (&["inertial", "origin"], "xyz", 3),
    (&["inertial", "origin"], "rpy", 3),
    (&["inertial", "mass"], "value", 1),
    (&["inertial", "inertia"], "ixx", 1),
    (&["inertial", "inertia"], "ixy", 1),
    (&["inertial", "inertia"], "ixz", 1),
    (&["inertial", "inertia"], "iyy", 1),
    (&["inertial", "inertia"], "iyz", 1),
    (&["inertial", "inertia"], "izz", 1),
];

/// The same for visuals and collisions (each may come several times).
const SHAPE_NUMBERS: &[(&[&str], &str, usize)] = &[
    (&["origin"], "xyz", 3),
    (&["origin"], "rpy", 3),
    (&["geometry", "box"], "size", 3),
    (&["geometry", "cylinder"], "radius", 1),
    (&["geometry", "cylinder"], "length", 1),
    (&["geometry", "sphere"], "radius", 1),
    (&["geometry", "mesh"], "scale", 3),
];

const JOINT_NUMBERS: &[(&[&str], &str, usize)] = &[
    (&["origin"], "xyz", 3),
    (&["origin"], "rpy", 3),
    (&["axis"], "xyz", 3),
    (&["limit"], "lower", 1),
    (&["limit"], "upper", 1),
    (&["limit"], "effort", 1),
    (&["limit"], "velocity", 1),
    (&["dynamics"], "damping", 1),
    (&["dynamics"], "friction", 1),
    (&["calibration"], "rising", 1),
    (&["calibration"], "falling", 1),
    (&["mimic"], "multiplier", 1),
    (&["mimic"], "offset", 1),
    (&["safety_controller"], "soft_lower_limit", 1),
    (&["safety_controller"], "soft_upper_limit", 1),
    (&["safety_controller"], "k_position", 1),
    (&["safety_controller"], "k_velocity", 1),
];

struct Checker<'a> {
    file: &'a Path,
}

fn line(node: roxmltree::Node) -> u32 {
    node.document().text_pos_at(node.range().start).row
}

/// A standard (un-namespaced) child element of `node` by tag.
pub(crate) fn children<'n, 'i>(
    node: roxmltree::Node<'n, 'i>,
    tag: &'static str,
) -> impl Iterator<Item = roxmltree::Node<'n, 'i>> {
    node.children().filter(move |n| {
        n.is_element() && n.tag_name().namespace().is_none() && n.tag_name().name() == tag
    })
}

impl Checker<'_> {
    fn error(&self, element: String, message: String) -> LoadError {
        LoadError::robot(self.file, element, message)
    }

    fn label(&self, node: roxmltree::Node, kind: &str) -> String {
        match node.attribute("name") {
            Some(name) => format!("{kind} \"{name}\" (line {})", line(node)),
            None => format!("{kind} (line {})", line(node)),
        }
    }

    fn name(&self, node: roxmltree::Node, kind: &str) -> Result<(), LoadError> {
        let label = self.label(node, kind);
        let name = node
            .attribute("name")
            .ok_or_else(|| self.error(label.clone(), "missing attribute \"name\"".into()))?;
        check_name(name).map_err(|why| self.error(label, format!("name {name:?}: {why}")))
    }

    /// Every `attribute` of the elements at `path` below `node` holds
    /// `count` finite numbers.
    fn numbers(
        &self,
        node: roxmltree::Node,
        label: &str,
        rules: &[(&[&'static str], &str, usize)],
    ) -> Result<(), LoadError> {
        for &(path, attribute, count) in rules {
            let mut nodes = vec![node];
            for &tag in path {
                nodes = nodes.iter().flat_map(|n| children(*n, tag)).collect();
            }
            for at in nodes {
                let Some(text) = at.attribute(attribute) else {
                    continue;
                };
                let values: Vec<Option<f64>> = text
                    .split_whitespace()
                    .map(|t| {
                        t.parse::<f64>()
                            .ok()
                            .filter(|v| v.is_finite() && v.abs() <= MAX_MAGNITUDE)
                    })
                    .collect();
                if values.len() != count || values.iter().any(Option::is_none) {
                    let wanted = if count == 1 {
                        format!("a finite number of magnitude at most {MAX_MAGNITUDE:e}")
                    } else {
                        format!("{count} finite numbers of magnitude at most {MAX_MAGNITUDE:e}")
                    };
                    return Err(self.error(
                        label.to_string(),
                        format!(
                            "<{} {attribute}=\"{text}\"> (line {}): expected {wanted}",
                            at.tag_name().name(),
                            line(at)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn link(&self, node: roxmltree::Node) -> Result<(), LoadError> {
        self.name(node, "link")?;
        let label = self.label(node, "link");
        self.numbers(node, &label, LINK_NUMBERS)?;
        for kind in ["visual", "collision"] {
            for shape in children(node, kind) {
                self.numbers(shape, &label, SHAPE_NUMBERS)?;
            }
        }
        Ok(())
    }

    fn joint(&self, node: roxmltree::Node) -> Result<(), LoadError> {
        self.name(node, "joint")?;
        let label = self.label(node, "joint");
        match node.attribute("type") {
            Some(kind) if JOINT_TYPES.contains(&kind) => {}
            Some(kind) => {
                return Err(self.error(
                    label,
                    format!(
                        "type \"{kind}\" is not a URDF joint type ({})",
                        JOINT_TYPES.join(", ")
                    ),
                ));
            }
            None => return Err(self.error(label, "missing attribute \"type\"".into())),
        }
        for end in ["parent", "child"] {
            let link = children(node, end).next().and_then(|n| n.attribute("link"));
            if link.is_none_or(str::is_empty) {
                return Err(self.error(label, format!("missing <{end} link=\"...\"/>")));
            }
        }
        self.numbers(node, &label, JOINT_NUMBERS)?;
        if let Some(limit) = children(node, "limit").next() {
            let value = |a: &str| {
                limit
                    .attribute(a)
                    .and_then(|t| t.trim().parse::<f64>().ok())
            };
            if let (Some(lower), Some(upper)) = (value("lower"), value("upper"))
                && lower > upper
            {
                return Err(self.error(
                    label,
                    format!("<limit>: lower {lower} is above upper {upper}"),
                ));
            }
            for a in ["effort", "velocity"] {
                if let Some(v) = value(a)
                    && v < 0.0
                {
                    return Err(self.error(label, format!("<limit {a}=\"{v}\">: must be >= 0")));
                }
            }
        }
        Ok(())
    }
}

/// Checks the document's standard URDF elements (see the module documentation).
pub fn check_urdf(document: &roxmltree::Document, file: &Path) -> Result<(), LoadError> {
    let checker = Checker { file };
    let root = document.root_element();
    if let Some(namespace) = root.tag_name().namespace() {
        return Err(checker.error(
            format!("<{}> (line {})", root.tag_name().name(), line(root)),
            format!(
                "the root element is in namespace \"{namespace}\": URDF elements take none (bind the fistage namespace to the prefix, xmlns:fistage=\"...\")"
            ),
        ));
    }
    if root.tag_name().name() != "robot" {
        return Err(checker.error(
            format!("<{}> (line {})", root.tag_name().name(), line(root)),
            "the root element must be <robot>".into(),
        ));
    }
    checker.name(root, "robot")?;
    for node in root
        .children()
        .filter(|n| n.is_element() && n.tag_name().namespace().is_none())
    {
        match node.tag_name().name() {
            "link" => checker.link(node)?,
            "joint" => checker.joint(node)?,
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(xml: &str) -> String {
        let document = roxmltree::Document::parse(xml).expect("XML");
        check_urdf(&document, Path::new("r.urdf"))
            .expect_err("refused")
            .to_string()
    }

    const JOINT: &str = r#"<robot name="r"><link name="world"/><link name="a"/>
<joint name="j" type="prismatic"><parent link="world"/><child link="a"/>LIMIT</joint></robot>"#;

    #[test]
    fn bad_values_are_named_with_element_attribute_and_line() {
        let message = error(&JOINT.replace("LIMIT", r#"<limit lower="NaN" upper="1"/>"#));
        assert!(
            message.contains("joint \"j\"")
                && message.contains("lower=\"NaN\"")
                && message.contains("line 2"),
            "{message}"
        );
        let message = error(&JOINT.replace("LIMIT", r#"<origin xyz="abc 0 0"/>"#));
        assert!(
            message.contains("xyz=\"abc 0 0\"") && message.contains("3 finite numbers"),
            "{message}"
        );
        let message = error(&JOINT.replace("LIMIT", r#"<limit lower="1" upper="0"/>"#));
        assert!(message.contains("lower 1 is above upper 0"), "{message}");
        let message = error(&JOINT.replace("prismatic", "sliding").replace("LIMIT", ""));
        assert!(message.contains("type \"sliding\""), "{message}");
        let message = error(
            &JOINT
                .replace(r#"name="r""#, r#"name="""#)
                .replace("LIMIT", ""),
        );
        assert!(
            message.contains("robot") && message.contains("empty"),
            "{message}"
        );
        let message = error(
            &JOINT
                .replace("<robot", "<robbot")
                .replace("</robot>", "</robbot>")
                .replace("LIMIT", ""),
        );
        assert!(
            message.contains("root element must be <robot>"),
            "{message}"
        );
        let message = error(
            r#"<robot name="r"><link name="a"><inertial><mass value=""/></inertial></link></robot>"#,
        );
        assert!(
            message.contains("link \"a\"") && message.contains("<mass value=\"\">"),
            "{message}"
        );
    }

    #[test]
    fn the_shipped_robots_pass() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots");
        for name in [
            "stage_1dof_fi.urdf",
            "stage_1dof_rigid.urdf",
            "stage_4fi.urdf",
        ] {
            let text = std::fs::read_to_string(root.join(name)).expect("robot");
            let document = roxmltree::Document::parse(&text).expect("XML");
            check_urdf(&document, Path::new(name)).expect(name);
        }
    }
}
