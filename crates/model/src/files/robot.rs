//! Robot files: the standard URDF elements fistage uses (the robot's name, its
//! links with their inertial data and visual solids, its joints) and the
//! fistage extension elements, all read with `roxmltree` from one parse, after
//! [`crate::urdf_check`] has checked every number they hold.
//!
//! Extension elements live in the namespace [`FISTAGE_NS`]:
//!
//! ```xml
//! <robot name="stage" xmlns:fistage="urn:fistage:urdf:1">
//!   <fistage:isolator name="fi" parent="table" child="bearing">
//!     <origin xyz="0 0 0" rpy="0 0 0"/>           <!-- attach frame, parent link frame -->
//!     <stiffness xyz="4e4 0 0" rpy="0 0 0"/>      <!-- N/m and N m/rad per attach axis -->
//!     <damping xyz="2 0 0" rpy="0 0 0"/>          <!-- N s/m and N m s/rad -->
//!   </fistage:isolator>
//!   <fistage:friction name="bearing_friction" link="bearing">
//!     <origin xyz="0 0 0"/>  <axis xyz="1 0 0"/>   <!-- contact point and sliding axis -->
//!     <lugre sigma0="2.2e6" sigma1="237" sigma2="14.2" f_c="5.1" f_s="6.5" v_s="0.0167"/>
//!   </fistage:friction>
//!   <fistage:actuator name="drive" link="table"> <origin xyz="0 0 0"/> <axis xyz="1 0 0"/> </fistage:actuator>
//!   <fistage:sensor name="encoder" link="table"> <origin xyz="0 0 0"/> <axis xyz="1 0 0"/> </fistage:sensor>
//! </robot>
//! ```
//!
//! This module only reads and checks each element on its own; how links join into
//! bodies is the business of [`crate::assembly`].

use crate::error::LoadError;
use crate::lugre::LugreParams;
use crate::rule::{Rule, check_name};
use crate::urdf_check::children;
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// XML namespace of the fistage extension elements.
pub const FISTAGE_NS: &str = "urn:fistage:urdf:1";

/// Kinds of URDF joint that fistage supports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Welds the child to the parent; the two links become one body.
    Fixed,
    /// Translation along the joint axis.
    Prismatic,
    /// Rotation about the joint axis (URDF `revolute` and `continuous`).
    Revolute,
    /// Six degrees of freedom.
    Floating,
}

/// A link with its inertial data as written in the file.
#[derive(Debug, Clone)]
pub struct LinkSpec {
    /// Link name.
    pub name: String,
    /// Mass, kg (0 for massless links such as `world`).
    pub mass: f64,
    /// Frame of the centre of mass and inertia axes, in the link frame.
    pub inertial_origin: Isometry3<f64>,
    /// Inertia tensor about the centre of mass in `inertial_origin` axes, kg m^2.
    pub inertia: Matrix3<f64>,
    /// The link's `<visual>` solids (boxes, cylinders, spheres), for drawing.
    pub visuals: Vec<VisualSpec>,
}

/// A `<visual>` solid of a link: what the 3D view draws.
#[derive(Debug, Clone, PartialEq)]
pub struct VisualSpec {
    /// The solid's frame in the link frame.
    pub origin: Isometry3<f64>,
    /// The solid.
    pub shape: VisualShape,
}

/// The solids URDF describes by their dimensions (meshes and capsules are
/// not drawn: a body without a drawable visual is drawn as its
/// inertia-equivalent box).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VisualShape {
    /// Edge lengths along the frame's x, y, z, m.
    Box([f64; 3]),
    /// Radius and length along the frame's z, m.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Length, m.
        length: f64,
    },
    /// Radius, m.
    Sphere(f64),
}

/// A joint as written in the file.
#[derive(Debug, Clone)]
pub struct JointSpec {
    /// Joint name.
    pub name: String,
    /// Joint kind.
    pub kind: JointKind,
    /// Parent link name.
    pub parent: String,
    /// Child link name.
    pub child: String,
    /// Joint frame in the parent link frame; the child link frame coincides with
    /// it at zero joint position.
    pub origin: Isometry3<f64>,
    /// Unit axis in the joint frame (prismatic and revolute joints).
    pub axis: Vector3<f64>,
}

/// A linear six-axis bushing between two links (a friction isolator).
#[derive(Debug, Clone)]
pub struct IsolatorSpec {
    /// Element name.
    pub name: String,
    /// Parent link name.
    pub parent: String,
    /// Child link name.
    pub child: String,
    /// Attach frame in the parent link frame. The child's attach frame is the
    /// frame that coincides with it in the zero configuration (no preload).
    pub origin: Isometry3<f64>,
    /// Stiffness along x, y, z (N/m) and about x, y, z (N m/rad) of the attach frame.
    pub stiffness: [f64; 6],
    /// Damping along x, y, z (N s/m) and about x, y, z (N m s/rad).
    pub damping: [f64; 6],
}

/// One stiffness or damping of an isolator: its name in parameter paths
/// (`k_x` .. `k_rz`, `c_x` .. `c_rz`), unit and place.
#[derive(Debug, Clone, Copy)]
pub struct IsolatorKey {
    /// Name in parameter paths.
    pub name: &'static str,
    /// SI unit, as FMI unit names write it.
    pub unit: &'static str,
    /// Damping (true) or stiffness (false).
    pub damping: bool,
    /// Attach-frame direction: 0..3 translations x, y, z; 3..6 rotations about them.
    pub direction: usize,
}

const fn isolator_key(name: &'static str, damping: bool, direction: usize) -> IsolatorKey {
    let unit = match (damping, direction < 3) {
        (false, true) => "N/m",
        (false, false) => "N.m/rad",
        (true, true) => "N.s/m",
        (true, false) => "N.m.s/rad",
    };
    IsolatorKey {
        name,
        unit,
        damping,
        direction,
    }
}

impl IsolatorSpec {
    /// Every stiffness and damping, stiffnesses first, in file order.
    pub const KEYS: [IsolatorKey; 12] = [
        isolator_key("k_x", false, 0),
        isolator_key("k_y", false, 1),
        isolator_key("k_z", false, 2),
        isolator_key("k_rx", false, 3),
        isolator_key("k_ry", false, 4),
        isolator_key("k_rz", false, 5),
        isolator_key("c_x", true, 0),
        isolator_key("c_y", true, 1),
        isolator_key("c_z", true, 2),
        isolator_key("c_rx", true, 3),
        isolator_key("c_ry", true, 4),
        isolator_key("c_rz", true, 5),
    ];

    /// What every stiffness and damping must satisfy.
    pub const RULE: Rule = Rule::NonNegative;

    /// The key named `name`.
    pub fn key(name: &str) -> Option<&'static IsolatorKey> {
        Self::KEYS.iter().find(|k| k.name == name)
    }

    /// The value of one stiffness or damping.
    pub fn get(&self, key: &IsolatorKey) -> f64 {
        if key.damping {
            self.damping[key.direction]
        } else {
            self.stiffness[key.direction]
        }
    }

    /// Sets one stiffness or damping (no check: see [`Self::RULE`]).
    pub fn set(&mut self, key: &IsolatorKey, value: f64) {
        if key.damping {
            self.damping[key.direction] = value;
        } else {
            self.stiffness[key.direction] = value;
        }
    }
}

/// A LuGre friction contact between a link and its counter-surface (rail or platform).
#[derive(Debug, Clone)]
pub struct FrictionSpec {
    /// Element name.
    pub name: String,
    /// Link that slides.
    pub link: String,
    /// Contact point in the link frame, m.
    pub point: Vector3<f64>,
    /// Sliding axis in the link frame (unit).
    pub axis: Vector3<f64>,
    /// LuGre parameters.
    pub lugre: LugreParams,
}

/// A point and direction on a link: actuators and sensors.
#[derive(Debug, Clone)]
pub struct PointAxisSpec {
    /// Element name.
    pub name: String,
    /// Link carrying the element.
    pub link: String,
    /// Point in the link frame, m.
    pub point: Vector3<f64>,
    /// Direction in the link frame (unit).
    pub axis: Vector3<f64>,
}

/// Everything a robot file says, checked element by element.
#[derive(Debug, Clone)]
pub struct RobotSpec {
    /// The file it came from.
    pub file: PathBuf,
    /// Robot name.
    pub name: String,
    /// Links.
    pub links: Vec<LinkSpec>,
    /// Joints.
    pub joints: Vec<JointSpec>,
    /// Isolator bushings.
    pub isolators: Vec<IsolatorSpec>,
    /// LuGre friction contacts.
    pub frictions: Vec<FrictionSpec>,
    /// Force actuators.
    pub actuators: Vec<PointAxisSpec>,
    /// Position sensors (encoders).
    pub sensors: Vec<PointAxisSpec>,
}

impl RobotSpec {
    /// Reads and checks a robot file.
    pub fn from_file(path: &Path) -> Result<Self, LoadError> {
        let text = crate::input::read_text(path, crate::input::MAX_DESCRIPTION_BYTES).map_err(
            |reason| LoadError::Io {
                file: path.to_path_buf(),
                reason,
            },
        )?;
        Self::from_str(&text, path)
    }

    /// Reads and checks robot XML; `file` is used in messages and nothing else.
    pub fn from_str(text: &str, file: &Path) -> Result<Self, LoadError> {
        check_nesting(text).map_err(|message| LoadError::Syntax {
            file: file.to_path_buf(),
            message,
        })?;
        let document = roxmltree::Document::parse(text).map_err(|e| LoadError::Syntax {
            file: file.to_path_buf(),
            message: format!("malformed XML: {e}"),
        })?;
        crate::urdf_check::check_urdf(&document, file)?;
        let root = document.root_element();
        let reader = ExtensionReader { file };
        let mut spec = RobotSpec {
            file: file.to_path_buf(),
            name: root.attribute("name").unwrap_or_default().to_string(),
            links: children(root, "link")
                .map(|l| link_spec(l, file))
                .collect::<Result<_, _>>()?,
            joints: children(root, "joint")
                .map(|j| joint_spec(j, file))
                .collect::<Result<_, _>>()?,
            isolators: Vec::new(),
            frictions: Vec::new(),
            actuators: Vec::new(),
            sensors: Vec::new(),
        };
        reader.read_extensions(&document, &mut spec)?;
        spec.check_names()?;
        Ok(spec)
    }

    /// Element names must be unique and must not shadow link names, so that a
    /// scenario override by name is never ambiguous.
    fn check_names(&self) -> Result<(), LoadError> {
        let every_name = (self.links.iter().map(|l| ("link", &l.name)))
            .chain(self.joints.iter().map(|j| ("joint", &j.name)))
            .chain(self.isolators.iter().map(|e| ("isolator", &e.name)))
            .chain(self.frictions.iter().map(|e| ("friction", &e.name)))
            .chain(self.actuators.iter().map(|e| ("actuator", &e.name)))
            .chain(self.sensors.iter().map(|e| ("sensor", &e.name)));
        for (kind, name) in every_name {
            if let Err(why) = check_name(name) {
                return Err(LoadError::robot(
                    &self.file,
                    format!("{kind} {name:?}"),
                    format!(
                        "unusable name: {why} (names become CSV headers, signal and FMI variable names)"
                    ),
                ));
            }
        }
        let mut links = HashSet::new();
        for link in &self.links {
            if !links.insert(link.name.as_str()) {
                return Err(LoadError::robot(
                    &self.file,
                    format!("link \"{}\"", link.name),
                    "defined twice",
                ));
            }
        }
        let mut joints = HashSet::new();
        for joint in &self.joints {
            if !joints.insert(joint.name.as_str()) {
                return Err(LoadError::robot(
                    &self.file,
                    format!("joint \"{}\"", joint.name),
                    "defined twice",
                ));
            }
        }
        let mut elements = HashSet::new();
        let names = self
            .isolators
            .iter()
            .map(|e| ("isolator", &e.name))
            .chain(self.frictions.iter().map(|e| ("friction", &e.name)))
            .chain(self.actuators.iter().map(|e| ("actuator", &e.name)))
            .chain(self.sensors.iter().map(|e| ("sensor", &e.name)));
        for (kind, name) in names {
            let element = format!("{kind} \"{name}\"");
            if links.contains(name.as_str()) {
                return Err(LoadError::robot(
                    &self.file,
                    element,
                    "has the name of a link; element names must differ from link names",
                ));
            }
            if !elements.insert(name.as_str()) {
                return Err(LoadError::robot(
                    &self.file,
                    element,
                    "element name used twice",
                ));
            }
        }
        Ok(())
    }
}

/// The deepest element nesting a robot file may have (URDF needs about 5).
const MAX_NESTING: usize = 64;

/// Refuses a file nested deeper than [`MAX_NESTING`] before any parser sees
/// it (recursive parsers would exhaust the stack on a very deep file).
/// Comments, processing instructions, CDATA and declarations do not nest.
fn check_nesting(text: &str) -> Result<(), String> {
    let bytes = text.as_bytes();
    let (mut depth, mut i) = (0usize, 0usize);
    let skip_to = |from: usize, end: &[u8]| {
        (from..bytes.len())
            .find(|&k| bytes[k..].starts_with(end))
            .map_or(bytes.len(), |k| k + end.len())
    };
    while i < bytes.len() {
        match bytes[i] {
            b'<' if bytes[i..].starts_with(b"<!--") => i = skip_to(i, b"-->"),
            b'<' if bytes[i..].starts_with(b"<![CDATA[") => i = skip_to(i, b"]]>"),
            b'<' if bytes[i..].starts_with(b"<?") => i = skip_to(i, b"?>"),
            b'<' if bytes[i..].starts_with(b"<!") => i = skip_to(i, b">"),
            b'<' if bytes[i..].starts_with(b"</") => {
                depth = depth.saturating_sub(1);
                i = skip_to(i, b">");
            }
            b'<' => {
                let end = skip_to(i, b">");
                let self_closing = end >= 2 && bytes[end - 2] == b'/';
                if !self_closing {
                    depth += 1;
                    if depth > MAX_NESTING {
                        let line = bytes[..i].iter().filter(|&&b| b == b'\n').count() + 1;
                        return Err(format!(
                            "line {line}: elements nested more than {MAX_NESTING} deep"
                        ));
                    }
                }
                i = end;
            }
            _ => i += 1,
        }
    }
    Ok(())
}

/// The first standard child element of `node` named `tag`.
fn first<'n, 'i>(
    node: roxmltree::Node<'n, 'i>,
    tag: &'static str,
) -> Option<roxmltree::Node<'n, 'i>> {
    children(node, tag).next()
}

/// The numbers of `attribute` (checked by [`crate::urdf_check`]: finite, and
/// as many as it holds), or `default` where the element or attribute is absent.
fn numbers<const N: usize>(
    node: Option<roxmltree::Node>,
    attribute: &str,
    default: [f64; N],
) -> [f64; N] {
    let Some(text) = node.and_then(|n| n.attribute(attribute)) else {
        return default;
    };
    let mut values = default;
    for (value, word) in values.iter_mut().zip(text.split_whitespace()) {
        *value = word.parse().unwrap_or(*value);
    }
    values
}

/// The pose of the `<origin>` child of `node` (identity where absent).
fn origin_of(node: roxmltree::Node) -> Isometry3<f64> {
    let origin = first(node, "origin");
    isometry_from_xyz_rpy(
        numbers(origin, "xyz", [0.0; 3]),
        numbers(origin, "rpy", [0.0; 3]),
    )
}

/// URDF pose convention: translate by xyz, rotate by fixed-axis roll, pitch, yaw.
pub fn isometry_from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2]),
    )
}

fn link_spec(link: roxmltree::Node, file: &Path) -> Result<LinkSpec, LoadError> {
    let name = link.attribute("name").unwrap_or_default();
    let element = format!("link \"{name}\"");
    let inertial = first(link, "inertial");
    let [mass] = numbers(inertial.and_then(|i| first(i, "mass")), "value", [0.0]);
    if !mass.is_finite() || mass < 0.0 {
        return Err(LoadError::robot(
            file,
            element,
            format!("mass must be >= 0, got {}", crate::rule::show(mass)),
        ));
    }
    if mass > 0.0 && !crate::rule::Rule::Positive.admits(mass) {
        return Err(LoadError::robot(
            file,
            element,
            format!(
                "mass must be {} (or 0 for a massless link), got {}",
                crate::rule::Rule::Positive.requirement_for(mass),
                crate::rule::show(mass)
            ),
        ));
    }
    let moments = inertial.and_then(|i| first(i, "inertia"));
    let [ixx, ixy, ixz, iyy, iyz, izz] =
        ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"].map(|key| numbers(moments, key, [0.0])[0]);
    let inertia = Matrix3::new(
        ixx, ixy, ixz, //
        ixy, iyy, iyz, //
        ixz, iyz, izz,
    );
    if inertia.iter().any(|v| !v.is_finite()) {
        return Err(LoadError::robot(file, element, "inertia must be finite"));
    }
    check_inertia(&inertia).map_err(|m| LoadError::robot(file, &element, m))?;
    let inertial_origin = inertial.map_or_else(Isometry3::identity, origin_of);
    if inertial_origin
        .translation
        .vector
        .iter()
        .any(|v| !v.is_finite())
    {
        return Err(LoadError::robot(
            file,
            element,
            "inertial origin must be finite",
        ));
    }
    Ok(LinkSpec {
        name: name.to_string(),
        mass,
        inertial_origin,
        inertia,
        visuals: visuals(link, file)?,
    })
}

/// The drawable `<visual>` solids of `link` (boxes, cylinders, spheres), with
/// positive sizes; meshes and capsules are left out.
fn visuals(link: roxmltree::Node, file: &Path) -> Result<Vec<VisualSpec>, LoadError> {
    let name = link.attribute("name").unwrap_or_default();
    let mut solids = Vec::new();
    for (k, visual) in children(link, "visual").enumerate() {
        let element = format!("link \"{name}\" visual {}", k + 1);
        let Some(geometry) = first(visual, "geometry") else {
            return Err(LoadError::robot(file, element, "missing <geometry>"));
        };
        let shape = if let Some(solid) = first(geometry, "box") {
            VisualShape::Box(numbers(Some(solid), "size", [0.0; 3]))
        } else if let Some(solid) = first(geometry, "cylinder") {
            VisualShape::Cylinder {
                radius: numbers(Some(solid), "radius", [0.0])[0],
                length: numbers(Some(solid), "length", [0.0])[0],
            }
        } else if let Some(solid) = first(geometry, "sphere") {
            VisualShape::Sphere(numbers(Some(solid), "radius", [0.0])[0])
        } else {
            continue;
        };
        let sizes: Vec<f64> = match shape {
            VisualShape::Box(size) => size.to_vec(),
            VisualShape::Cylinder { radius, length } => vec![radius, length],
            VisualShape::Sphere(radius) => vec![radius],
        };
        if sizes.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(LoadError::robot(
                file,
                element,
                format!("geometry sizes must be positive and finite, got {sizes:?}"),
            ));
        }
        solids.push(VisualSpec {
            origin: origin_of(visual),
            shape,
        });
    }
    Ok(solids)
}

/// A physical inertia tensor has non-negative principal moments that satisfy the
/// triangle inequality.
fn check_inertia(inertia: &Matrix3<f64>) -> Result<(), String> {
    let moments = inertia.symmetric_eigenvalues();
    let tolerance = 1e-9 * moments.amax().max(f64::MIN_POSITIVE);
    if moments.iter().any(|&m| m < -tolerance) {
        return Err(format!(
            "inertia must be positive semi-definite, principal moments are {:.6e}, {:.6e}, {:.6e}",
            moments[0], moments[1], moments[2]
        ));
    }
    let (a, b, c) = (moments[0], moments[1], moments[2]);
    if a > b + c + tolerance || b > a + c + tolerance || c > a + b + tolerance {
        return Err(format!(
            "principal moments {a:.6e}, {b:.6e}, {c:.6e} violate the triangle inequality"
        ));
    }
    Ok(())
}

fn joint_spec(joint: roxmltree::Node, file: &Path) -> Result<JointSpec, LoadError> {
    let name = joint.attribute("name").unwrap_or_default();
    let element = format!("joint \"{name}\"");
    let kind = match joint.attribute("type").unwrap_or_default() {
        "fixed" => JointKind::Fixed,
        "prismatic" => JointKind::Prismatic,
        "revolute" | "continuous" => JointKind::Revolute,
        "floating" => JointKind::Floating,
        other => {
            return Err(LoadError::robot(
                file,
                element,
                format!(
                    "joint type \"{other}\" is not supported (use fixed, prismatic, revolute, continuous or floating)"
                ),
            ));
        }
    };
    let link_of = |tag: &'static str| {
        first(joint, tag)
            .and_then(|n| n.attribute("link"))
            .map(str::to_string)
            .ok_or_else(|| {
                LoadError::robot(file, &element, format!("missing <{tag} link=\"...\"/>"))
            })
    };
    let (parent, child) = (link_of("parent")?, link_of("child")?);
    // URDF's default axis is x.
    let axis = Vector3::from(numbers(first(joint, "axis"), "xyz", [1.0, 0.0, 0.0]));
    let needs_axis = matches!(kind, JointKind::Prismatic | JointKind::Revolute);
    let axis = if needs_axis {
        unit_axis(axis).map_err(|m| LoadError::robot(file, &element, m))?
    } else {
        Vector3::x()
    };
    Ok(JointSpec {
        name: name.to_string(),
        kind,
        parent,
        child,
        origin: origin_of(joint),
        axis,
    })
}

fn unit_axis(axis: Vector3<f64>) -> Result<Vector3<f64>, String> {
    let norm = axis.norm();
    if !norm.is_finite() || norm < 1e-12 {
        return Err(format!(
            "axis must be a non-zero finite vector, got [{} {} {}]",
            crate::rule::show(axis.x),
            crate::rule::show(axis.y),
            crate::rule::show(axis.z)
        ));
    }
    Ok(axis / norm)
}

/// Reads the `fistage:` elements of one document.
struct ExtensionReader<'a> {
    file: &'a Path,
}

impl ExtensionReader<'_> {
    fn read_extensions(
        &self,
        document: &roxmltree::Document,
        spec: &mut RobotSpec,
    ) -> Result<(), LoadError> {
        let root = document.root_element();
        for node in root.children().filter(|n| n.is_element()) {
            if node.tag_name().namespace() != Some(FISTAGE_NS) {
                if node.tag_name().name().contains(':') || node.tag_name().namespace().is_some() {
                    self.warn_foreign(node)?;
                }
                continue;
            }
            match node.tag_name().name() {
                "isolator" => spec.isolators.push(self.isolator(node)?),
                "friction" => spec.frictions.push(self.friction(node)?),
                "actuator" => spec.actuators.push(self.point_axis(node, "actuator")?),
                "sensor" => spec.sensors.push(self.point_axis(node, "sensor")?),
                other => {
                    return Err(LoadError::robot(
                        self.file,
                        format!("fistage:{other}"),
                        "unknown element (expected isolator, friction, actuator or sensor)",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Elements of other namespaces are allowed (e.g. `drake:`), but an element
    /// whose namespace looks like a mistyped fistage one is an error.
    fn warn_foreign(&self, node: roxmltree::Node) -> Result<(), LoadError> {
        if let Some(ns) = node.tag_name().namespace()
            && (ns.contains("fistage") || node.lookup_prefix(ns) == Some("fistage"))
        {
            return Err(LoadError::robot(
                self.file,
                node.tag_name().name(),
                format!("namespace \"{ns}\" is not the fistage namespace \"{FISTAGE_NS}\""),
            ));
        }
        Ok(())
    }

    fn element_label(&self, node: roxmltree::Node, kind: &str) -> String {
        match node.attribute("name") {
            Some(name) => format!("{kind} \"{name}\" (line {})", self.line(node)),
            None => format!("{kind} (line {})", self.line(node)),
        }
    }

    fn line(&self, node: roxmltree::Node) -> u32 {
        node.document().text_pos_at(node.range().start).row
    }

    fn error(&self, element: &str, message: impl Into<String>) -> LoadError {
        LoadError::robot(self.file, element, message)
    }

    fn required_attribute<'n>(
        &self,
        node: roxmltree::Node<'n, '_>,
        element: &str,
        attribute: &str,
    ) -> Result<&'n str, LoadError> {
        node.attribute(attribute)
            .ok_or_else(|| self.error(element, format!("missing attribute \"{attribute}\"")))
    }

    fn check_attributes(
        &self,
        node: roxmltree::Node,
        element: &str,
        allowed: &[&str],
    ) -> Result<(), LoadError> {
        for attribute in node.attributes() {
            if attribute.namespace().is_none() && !allowed.contains(&attribute.name()) {
                return Err(self.error(
                    element,
                    format!(
                        "unknown attribute \"{}\" on <{}> (allowed: {})",
                        attribute.name(),
                        node.tag_name().name(),
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Child elements by tag; unknown tags are errors.
    fn children<'n, 'i>(
        &self,
        node: roxmltree::Node<'n, 'i>,
        element: &str,
        allowed: &[&str],
    ) -> Result<Vec<roxmltree::Node<'n, 'i>>, LoadError> {
        let mut seen = HashSet::new();
        let mut children = Vec::new();
        for child in node.children().filter(|n| n.is_element()) {
            let tag = child.tag_name().name();
            if !allowed.contains(&tag) {
                return Err(self.error(
                    element,
                    format!("unknown child <{tag}> (allowed: {})", allowed.join(", ")),
                ));
            }
            if !seen.insert(tag) {
                return Err(self.error(element, format!("<{tag}> given twice")));
            }
            children.push(child);
        }
        Ok(children)
    }

    fn find<'n, 'i>(
        children: &[roxmltree::Node<'n, 'i>],
        tag: &str,
    ) -> Option<roxmltree::Node<'n, 'i>> {
        children
            .iter()
            .copied()
            .find(|c| c.tag_name().name() == tag)
    }

    fn vector(
        &self,
        node: roxmltree::Node,
        element: &str,
        attribute: &str,
    ) -> Result<Option<[f64; 3]>, LoadError> {
        let Some(text) = node.attribute(attribute) else {
            return Ok(None);
        };
        let place = format!("<{} {attribute}=\"{text}\">", node.tag_name().name());
        let values: Vec<f64> = text
            .split_whitespace()
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| self.error(element, format!("{place}: expected three numbers")))?;
        match values.as_slice() {
            [a, b, c] if values.iter().all(|v| crate::rule::Rule::Finite.admits(*v)) => {
                Ok(Some([*a, *b, *c]))
            }
            _ => Err(self.error(
                element,
                format!(
                    "{place}: expected three finite numbers of magnitude at most {:e}",
                    crate::rule::MAX_MAGNITUDE
                ),
            )),
        }
    }

    fn origin(
        &self,
        children: &[roxmltree::Node],
        element: &str,
    ) -> Result<Isometry3<f64>, LoadError> {
        let Some(origin) = Self::find(children, "origin") else {
            return Ok(Isometry3::identity());
        };
        self.check_attributes(origin, element, &["xyz", "rpy"])?;
        let xyz = self.vector(origin, element, "xyz")?.unwrap_or_default();
        let rpy = self.vector(origin, element, "rpy")?.unwrap_or_default();
        Ok(isometry_from_xyz_rpy(xyz, rpy))
    }

    fn axis(&self, children: &[roxmltree::Node], element: &str) -> Result<Vector3<f64>, LoadError> {
        let axis = Self::find(children, "axis")
            .ok_or_else(|| self.error(element, "missing <axis xyz=\"...\"/>"))?;
        self.check_attributes(axis, element, &["xyz"])?;
        let xyz = self
            .vector(axis, element, "xyz")?
            .ok_or_else(|| self.error(element, "<axis> needs xyz"))?;
        unit_axis(Vector3::from(xyz)).map_err(|m| self.error(element, m))
    }

    /// Six non-negative values from `xyz` (translational) and `rpy` (rotational).
    fn six_axis(
        &self,
        node: Option<roxmltree::Node>,
        element: &str,
        what: &str,
    ) -> Result<[f64; 6], LoadError> {
        let Some(node) = node else {
            return Ok([0.0; 6]);
        };
        self.check_attributes(node, element, &["xyz", "rpy"])?;
        if node.attribute("xyz").is_none() && node.attribute("rpy").is_none() {
            return Err(self.error(
                element,
                format!("<{what}> gives neither xyz nor rpy (leave out the element for none)"),
            ));
        }
        let t = self.vector(node, element, "xyz")?.unwrap_or_default();
        let r = self.vector(node, element, "rpy")?.unwrap_or_default();
        let values = [t[0], t[1], t[2], r[0], r[1], r[2]];
        for value in values {
            IsolatorSpec::RULE
                .check(value)
                .map_err(|e| self.error(element, format!("{what} {e}")))?;
        }
        Ok(values)
    }

    fn isolator(&self, node: roxmltree::Node) -> Result<IsolatorSpec, LoadError> {
        let element = self.element_label(node, "isolator");
        self.check_attributes(node, &element, &["name", "parent", "child"])?;
        let name = self.required_attribute(node, &element, "name")?;
        let parent = self.required_attribute(node, &element, "parent")?;
        let child = self.required_attribute(node, &element, "child")?;
        if parent == child {
            return Err(self.error(&element, "parent and child must be different links"));
        }
        let children = self.children(node, &element, &["origin", "stiffness", "damping"])?;
        let stiffness_node = Self::find(&children, "stiffness")
            .ok_or_else(|| self.error(&element, "missing <stiffness xyz=\"..\" rpy=\"..\"/>"))?;
        Ok(IsolatorSpec {
            name: name.to_string(),
            parent: parent.to_string(),
            child: child.to_string(),
            origin: self.origin(&children, &element)?,
            stiffness: self.six_axis(Some(stiffness_node), &element, "stiffness")?,
            damping: self.six_axis(Self::find(&children, "damping"), &element, "damping")?,
        })
    }

    fn friction(&self, node: roxmltree::Node) -> Result<FrictionSpec, LoadError> {
        let element = self.element_label(node, "friction");
        self.check_attributes(node, &element, &["name", "link"])?;
        let name = self.required_attribute(node, &element, "name")?;
        let link = self.required_attribute(node, &element, "link")?;
        let children = self.children(node, &element, &["origin", "axis", "lugre"])?;
        let lugre_node = Self::find(&children, "lugre").ok_or_else(|| {
            self.error(
                &element,
                "missing <lugre sigma0=.. sigma1=.. sigma2=.. f_c=.. f_s=.. v_s=../>",
            )
        })?;
        self.check_attributes(lugre_node, &element, &LugreParams::NAMES)?;
        let mut lugre = LugreParams::paper_table1();
        for key in &LugreParams::KEYS {
            let name = key.name;
            let text = self.required_attribute(lugre_node, &element, name)?;
            let value = text.trim().parse().map_err(|_| {
                self.error(&element, format!("<lugre {name}=\"{text}\">: not a number"))
            })?;
            key.set(&mut lugre, value);
        }
        lugre
            .validate()
            .map_err(|e| self.error(&element, e.to_string()))?;
        Ok(FrictionSpec {
            name: name.to_string(),
            link: link.to_string(),
            point: self.origin(&children, &element)?.translation.vector,
            axis: self.axis(&children, &element)?,
            lugre,
        })
    }

    fn point_axis(&self, node: roxmltree::Node, kind: &str) -> Result<PointAxisSpec, LoadError> {
        let element = self.element_label(node, kind);
        self.check_attributes(node, &element, &["name", "link"])?;
        let name = self.required_attribute(node, &element, "name")?;
        let link = self.required_attribute(node, &element, "link")?;
        let children = self.children(node, &element, &["origin", "axis"])?;
        Ok(PointAxisSpec {
            name: name.to_string(),
            link: link.to_string(),
            point: self.origin(&children, &element)?.translation.vector,
            axis: self.axis(&children, &element)?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A refused axis shows its numbers as the user wrote them, not 300
    /// digits of a tiny one.
    #[test]
    fn a_refused_axis_is_shown_readably() {
        let refused = unit_axis(Vector3::new(1e-300, 0.0, 0.0)).expect_err("too short");
        assert!(refused.ends_with("got [1e-300 0 0]"), "{refused}");
        assert!(unit_axis(Vector3::new(0.0, 2.0, 0.0)).is_ok());
    }
}
