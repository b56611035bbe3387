//! The 3D mode view's data: each body's pose at the equilibrium and the
//! shapes that draw it (the robot file's `<visual>` boxes, cylinders and
//! spheres, or where it has none its inertia-equivalent box; coloured as a
//! bearing where it carries a friction contact), the solids welded to the
//! world, the rails under the contacts, the
//! isolators' attach points, and, per mode, each body's rigid motion per unit
//! of the mode shape.
//!
//! A body's motion is measured on the model itself: the equilibrium state is
//! moved by plus and minus a small multiple of the shape's real (and
//! imaginary) part in tangent coordinates ([`Model::retract`]) and the body
//! poses are differenced, so any joint tree moves as the model moves it.

use fistage_analysis::{ModalAnalysis, Mode, Participation};
use fistage_model::{Frame, Model, VisualShape};
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Step of the central differences, per unit of the largest shape entry.
const STEP: f64 = 1e-6;
/// The largest displacement of a mode at exaggeration 1, as a share of the stage's span.
const SHOWN_SHARE: f64 = 0.08;
/// Density for a body whose inertia gives no box, kg/m^3 (aluminium).
const DENSITY: f64 = 2700.0;

/// The 3D view of a stage and its modes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    /// Heading of the block.
    pub title: String,
    /// Size of the stage (diagonal of what is drawn), m.
    pub span: f64,
    /// Centre of what is drawn, m.
    pub centre: [f64; 3],
    /// The moving bodies.
    pub bodies: Vec<SceneBody>,
    /// The robot file's solids on links welded to the world, world frame.
    pub ground: Vec<Shape>,
    /// The rails (counter-surfaces of the friction contacts).
    pub rails: Vec<Rail>,
    /// The isolators, drawn as lines between their attach points.
    pub isolators: Vec<SceneIsolator>,
    /// The modes to animate.
    pub modes: Vec<SceneMode>,
}

/// A body at the equilibrium and how it is drawn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneBody {
    /// Link name.
    pub name: String,
    /// Origin of the body frame in the world, m.
    pub position: [f64; 3],
    /// Orientation of the body frame (x, y, z, w).
    pub quaternion: [f64; 4],
    /// The shapes, in the body frame.
    pub shapes: Vec<Shape>,
}

/// A solid drawn on a body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Shape {
    /// `box` (size: the three edge lengths), `cylinder` (radius, length along
    /// z) or `sphere` (radius).
    pub kind: String,
    /// Dimensions, m.
    pub size: Vec<f64>,
    /// Centre in the body frame, m.
    pub position: [f64; 3],
    /// Orientation in the body frame (x, y, z, w).
    pub quaternion: [f64; 4],
    /// `visual` (from the robot file), `inertia` (the inertia-equivalent box)
    /// or `bearing` (the same, for a body carrying a friction contact).
    pub role: String,
}

/// A rail: a segment in the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Rail {
    /// One end, m.
    pub start: [f64; 3],
    /// The other end, m.
    pub end: [f64; 3],
}

/// An isolator's two attach points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneIsolator {
    /// Element name.
    pub name: String,
    /// Parent body index, -1 for the world.
    pub parent: i64,
    /// Attach point in the parent's frame (the world's for -1), m.
    pub parent_point: [f64; 3],
    /// Child body index, -1 for the world.
    pub child: i64,
    /// Attach point in the child's frame, m.
    pub child_point: [f64; 3],
}

/// One mode as the view animates it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneMode {
    /// `mode 3`.
    pub label: String,
    /// `sticking` or `slipping`.
    pub equilibrium: String,
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Whether the eigenvalue has a positive real part.
    pub unstable: bool,
    /// One line: what dominates the mode.
    pub summary: String,
    /// Exaggeration at which the largest displacement is a fixed share of the span.
    pub scale: f64,
    /// Kinetic-energy share, magnitude and phase per coordinate.
    pub participation: Vec<Participation>,
    /// Each body's motion per unit of the shape, in [`Scene::bodies`] order.
    pub bodies: Vec<BodyMotion>,
}

/// A body's rigid motion per unit of a mode shape: translation of its origin
/// and rotation vector, real and imaginary parts, world axes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BodyMotion {
    /// Translation, real part, m.
    pub translation_re: [f64; 3],
    /// Translation, imaginary part, m.
    pub translation_im: [f64; 3],
    /// Rotation vector, real part, rad.
    pub rotation_re: [f64; 3],
    /// Rotation vector, imaginary part, rad.
    pub rotation_im: [f64; 3],
}

impl Scene {
    /// The view of `model` at the equilibrium of `analysis`, with the modes
    /// numbered in `shown` (indices into `analysis.modes`).
    pub fn new(model: &Model, analysis: &ModalAnalysis, shown: &[usize]) -> Self {
        let state = &analysis.state;
        let poses = model.body_poses(state);
        let bodies: Vec<SceneBody> = model
            .bodies()
            .iter()
            .enumerate()
            .map(|(b, body)| {
                let bearing = model.frictions().iter().any(|f| f.body == b);
                let drawn = visual_shapes(model, Frame::Body(b), bearing);
                SceneBody {
                    name: body.name.clone(),
                    position: poses[b].1.into(),
                    quaternion: quaternion_of(&poses[b].0),
                    shapes: if drawn.is_empty() {
                        vec![inertia_box(body.mass, &body.com, &body.inertia, bearing)]
                    } else {
                        drawn
                    },
                }
            })
            .collect();
        let (centre, span) = extent(&bodies);
        let mut scene = Scene {
            title: format!(
                "{} equilibrium: the stage and its modes",
                analysis.equilibrium
            ),
            span,
            centre: centre.into(),
            ground: visual_shapes(model, Frame::World, false),
            rails: rails(model, &poses, span),
            isolators: isolators(model),
            modes: Vec::new(),
            bodies,
        };
        scene.modes = shown
            .iter()
            .map(|&k| scene.mode(model, analysis, k))
            .collect();
        scene
    }

    /// Mode `k` of `analysis` as the view animates it.
    fn mode(&self, model: &Model, analysis: &ModalAnalysis, k: usize) -> SceneMode {
        let mode = &analysis.modes[k];
        let motions = body_motions(model, analysis, mode);
        let largest = motions
            .iter()
            .zip(&self.bodies)
            .map(|(m, body)| reach(m, body))
            .fold(0.0, f64::max);
        SceneMode {
            label: format!("mode {}", k + 1),
            equilibrium: analysis.equilibrium.clone(),
            frequency_hz: mode.frequency_hz,
            damping_ratio: mode.damping_ratio,
            unstable: mode.real > 0.0 && !mode.neutral,
            summary: format!(
                "dominated by {}, eigenvalue {:.4e} {:+.4e}i 1/s, bristle share {:.2}",
                mode.dominant, mode.real, mode.imag, mode.bristle_share
            ),
            scale: if largest > 0.0 {
                SHOWN_SHARE * self.span / largest
            } else {
                0.0
            },
            participation: mode.participation.clone(),
            bodies: motions,
        }
    }
}

/// The largest displacement of any point of `body`'s shapes under `motion`
/// (bounded by the origin's translation plus the rotation times the reach).
fn reach(motion: &BodyMotion, body: &SceneBody) -> f64 {
    let radius = body
        .shapes
        .iter()
        .map(|s| {
            Vector3::from(s.position).norm() + s.size.iter().map(|v| v * v).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max);
    let norm = |v: &[f64; 3]| Vector3::from(*v).norm();
    (norm(&motion.translation_re) + radius * norm(&motion.rotation_re))
        .max(norm(&motion.translation_im) + radius * norm(&motion.rotation_im))
}

/// Each body's motion along the real and imaginary parts of `mode`'s shape.
fn body_motions(model: &Model, analysis: &ModalAnalysis, mode: &Mode) -> Vec<BodyMotion> {
    let tangent = model.tangent(&analysis.state);
    let mut real = vec![0.0; tangent.names.len()];
    let mut imaginary = vec![0.0; tangent.names.len()];
    // The shape's entries are the first tangent coordinates (the positions), in order.
    for (i, entry) in mode.participation.iter().enumerate() {
        let phase = entry.phase_deg.to_radians();
        real[i] = entry.magnitude * phase.cos();
        imaginary[i] = entry.magnitude * phase.sin();
    }
    let along = |direction: &[f64]| -> Vec<([f64; 3], [f64; 3])> {
        let step: Vec<f64> = direction.iter().map(|d| d * STEP).collect();
        let back: Vec<f64> = step.iter().map(|d| -d).collect();
        let plus = model.body_poses(&model.retract(&analysis.state, &step));
        let minus = model.body_poses(&model.retract(&analysis.state, &back));
        plus.iter()
            .zip(&minus)
            .map(|((rp, op), (rm, om))| {
                let translation = (op - om) / (2.0 * STEP);
                let turn = Rotation3::from_matrix_unchecked(rp * rm.transpose());
                (
                    translation.into(),
                    (turn.scaled_axis() / (2.0 * STEP)).into(),
                )
            })
            .collect()
    };
    along(&real)
        .into_iter()
        .zip(along(&imaginary))
        .map(
            |((translation_re, rotation_re), (translation_im, rotation_im))| BodyMotion {
                translation_re,
                translation_im,
                rotation_re,
                rotation_im,
            },
        )
        .collect()
}

/// The robot file's visual solids on `frame`, as shapes in its frame.
fn visual_shapes(model: &Model, frame: Frame, bearing: bool) -> Vec<Shape> {
    model
        .visuals()
        .iter()
        .filter(|v| v.frame == frame)
        .map(|v| {
            let (kind, size) = match v.shape {
                VisualShape::Box(size) => ("box", size.to_vec()),
                VisualShape::Cylinder { radius, length } => ("cylinder", vec![radius, length]),
                VisualShape::Sphere(radius) => ("sphere", vec![radius]),
            };
            let q = v.origin.rotation;
            Shape {
                kind: kind.into(),
                size,
                position: v.origin.translation.vector.into(),
                quaternion: [q.i, q.j, q.k, q.w],
                role: if bearing { "bearing" } else { "visual" }.into(),
            }
        })
        .collect()
}

/// The box of uniform density with the body's mass and principal moments of
/// inertia, at its centre of mass along its principal axes; a cube of
/// aluminium's density where the moments give no box.
fn inertia_box(mass: f64, com: &Vector3<f64>, inertia: &Matrix3<f64>, bearing: bool) -> Shape {
    let eigen = SymmetricEigen::new(*inertia);
    let moments = eigen.eigenvalues;
    let sum = moments.sum();
    let edges: Vec<f64> = (0..3)
        .map(|i| (6.0 * (sum - 2.0 * moments[i]) / mass).sqrt())
        .collect();
    let cube = (mass / DENSITY).cbrt();
    let (size, axes) = if edges.iter().all(|e| e.is_finite() && *e > 0.05 * cube) {
        let mut axes = eigen.eigenvectors;
        if axes.determinant() < 0.0 {
            axes.column_mut(2).neg_mut();
        }
        (edges, axes)
    } else {
        (vec![cube; 3], Matrix3::identity())
    };
    Shape {
        kind: "box".into(),
        size,
        position: (*com).into(),
        quaternion: quaternion_of(&axes),
        role: if bearing { "bearing" } else { "inertia" }.into(),
    }
}

/// A rotation matrix as (x, y, z, w).
fn quaternion_of(rotation: &Matrix3<f64>) -> [f64; 4] {
    let q = UnitQuaternion::from_matrix(rotation);
    [q.i, q.j, q.k, q.w]
}

/// Centre and diagonal of the box holding every body's shapes.
fn extent(bodies: &[SceneBody]) -> (Vector3<f64>, f64) {
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for body in bodies {
        let rotation = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            body.quaternion[3],
            body.quaternion[0],
            body.quaternion[1],
            body.quaternion[2],
        ));
        for shape in &body.shapes {
            let centre = Vector3::from(body.position) + rotation * Vector3::from(shape.position);
            let half = 0.5 * shape.size.iter().fold(0.0_f64, |a, b| a.max(*b));
            lo = lo.inf(&centre.add_scalar(-half));
            hi = hi.sup(&centre.add_scalar(half));
        }
    }
    if lo.x > hi.x {
        return (Vector3::zeros(), 0.1);
    }
    (0.5 * (lo + hi), (hi - lo).norm().max(1e-3))
}

/// One rail per friction contact: along its sliding axis through the contact
/// point, one and a half spans long.
fn rails(model: &Model, poses: &[(Matrix3<f64>, Vector3<f64>)], span: f64) -> Vec<Rail> {
    model
        .frictions()
        .iter()
        .map(|f| {
            let (rotation, origin) = poses[f.body];
            let point = origin + rotation * f.point;
            let half = 0.75 * span * f.axis.normalize();
            Rail {
                start: (point - half).into(),
                end: (point + half).into(),
            }
        })
        .collect()
}

fn isolators(model: &Model) -> Vec<SceneIsolator> {
    let index = |frame: Frame| match frame {
        Frame::World => -1,
        Frame::Body(b) => b as i64,
    };
    model
        .isolators()
        .iter()
        .map(|iso| SceneIsolator {
            name: iso.name.clone(),
            parent: index(iso.parent),
            parent_point: iso.parent_attach.translation.vector.into(),
            child: index(iso.child),
            child_point: iso.child_attach.translation.vector.into(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inertia-equivalent box of a uniform plate is the plate: the
    /// four-bearing stage's table (1 kg, 150 x 150 x 16.5 mm).
    #[test]
    fn the_inertia_box_of_a_plate_is_the_plate() {
        let (a, b, c) = (0.15, 0.15, 0.0165);
        let mass = 1.0;
        let inertia = Matrix3::from_diagonal(&Vector3::new(
            mass * (b * b + c * c) / 12.0,
            mass * (a * a + c * c) / 12.0,
            mass * (a * a + b * b) / 12.0,
        ));
        let shape = inertia_box(mass, &Vector3::new(0.0, 0.0, 0.01), &inertia, false);
        let mut size = shape.size.clone();
        size.sort_by(f64::total_cmp);
        for (got, want) in size.iter().zip([c, a, b]) {
            assert!((got - want).abs() < 1e-12, "{size:?}");
        }
        assert_eq!(shape.position, [0.0, 0.0, 0.01]);
        assert_eq!(shape.role, "inertia");
    }

    /// The four-bearing stage is drawn from its robot file's boxes, with a
    /// rail under each bearing and a strut per isolator; the table's modes
    /// move it rigidly (no body moves where the shape has no entry).
    #[test]
    fn the_four_bearing_stage_is_drawn_from_its_visuals() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let loaded =
            fistage_model::load(&root.join("scenarios/coupling/symmetric_fig05b.toml")).unwrap();
        let inputs = fistage_analysis::modes::equilibrium_inputs(&loaded.scenario);
        let start = fistage_model::initial_state(&loaded.model, &loaded.scenario).unwrap();
        let analysis = fistage_analysis::modal_analysis(
            &loaded.model,
            &inputs,
            fistage_model::EquilibriumKind::Sticking,
            &start,
        )
        .unwrap();
        let shown = analysis.mechanical_modes();
        let scene = Scene::new(&loaded.model, &analysis, &shown);
        let table = scene.bodies.iter().find(|b| b.name == "table").unwrap();
        assert_eq!(table.shapes.len(), 1);
        assert_eq!(table.shapes[0].size, vec![0.15, 0.15, 0.0165]);
        assert_eq!(table.shapes[0].role, "visual");
        let bearings = scene
            .bodies
            .iter()
            .filter(|b| b.shapes[0].role == "bearing");
        assert_eq!(bearings.count(), 4);
        assert_eq!((scene.rails.len(), scene.isolators.len()), (4, 4));
        assert!(scene.ground.is_empty());
        // The sticking stage's first shown mode is the table on its isolators
        // along x: the stuck bearings move on their bristles only, under 5% of it.
        let mode = &scene.modes[0];
        let moved = |name: &str| {
            let b = scene.bodies.iter().position(|b| b.name == name).unwrap();
            Vector3::from(mode.bodies[b].translation_re).norm()
        };
        for bearing in ["bearing_fl", "bearing_fr", "bearing_rl", "bearing_rr"] {
            assert!(moved(bearing) < 0.05 * moved("table"), "{bearing}");
        }
        assert!(mode.scale > 0.0);
    }

    /// A point mass has no box of its moments: a cube of its mass.
    #[test]
    fn a_point_mass_is_drawn_as_a_cube_of_its_mass() {
        let shape = inertia_box(0.27, &Vector3::zeros(), &Matrix3::zeros(), true);
        for edge in &shape.size {
            assert!((edge - (0.27 / DENSITY).cbrt()).abs() < 1e-12);
        }
        assert_eq!(shape.role, "bearing");
    }
}
