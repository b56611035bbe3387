//! The figures of a modal analysis: each dominant mode's shape seen from
//! above, the bodies at rest and displaced (motion exaggerated).

use std::path::Path;

use fistage_analysis::ModalAnalysis;
use fistage_model::{Frame, JointMotion, Loaded};
use nalgebra::Vector3;

use super::svg_and_png;
use crate::{PlotError, Series, XyPlot, write_xy};

/// Points of each body seen from above: isolator attach points (and the body
/// origin), in world coordinates at the equilibrium.
fn body_points(loaded: &Loaded, state: &[f64]) -> Vec<Vec<Vector3<f64>>> {
    let model = &loaded.model;
    let poses = model.body_poses(state);
    let mut points: Vec<Vec<Vector3<f64>>> =
        poses.iter().map(|(_, origin)| vec![*origin]).collect();
    for isolator in model.isolators() {
        for (frame, local) in [
            (isolator.parent, isolator.parent_attach.translation.vector),
            (isolator.child, isolator.child_attach.translation.vector),
        ] {
            if let Frame::Body(b) = frame {
                let (rotation, origin) = poses[b];
                points[b].push(origin + rotation * local);
            }
        }
    }
    points
}

/// Planar displacement of a world point on body b for a mode shape (real part
/// after phase alignment), from the body's joint coordinates.
fn displacement(
    loaded: &Loaded,
    state: &[f64],
    shape: &[f64],
    index: usize,
    point: &Vector3<f64>,
) -> Vector3<f64> {
    let model = &loaded.model;
    let poses = model.body_poses(state);
    let body = &model.bodies()[index];
    let v0 = body.joint.v_offset;
    // Joint frame axes in the world (for root bodies the parent is the world).
    let parent_rotation = body
        .parent
        .map_or(nalgebra::Matrix3::identity(), |p| poses[p].0);
    let joint_rotation = parent_rotation * body.joint.origin_rotation;
    let origin = poses[index].1;
    match body.joint.motion {
        JointMotion::Prismatic { axis } => joint_rotation * axis * shape[v0],
        JointMotion::Revolute { axis } => {
            (joint_rotation * axis * shape[v0]).cross(&(point - origin))
        }
        JointMotion::Floating => {
            let translation =
                joint_rotation * Vector3::new(shape[v0], shape[v0 + 1], shape[v0 + 2]);
            let rotation =
                joint_rotation * Vector3::new(shape[v0 + 3], shape[v0 + 4], shape[v0 + 5]);
            translation + rotation.cross(&(point - origin))
        }
    }
}

/// Draws the top views of up to `count` dominant modes of `analysis` into
/// `dir` (`mode_<equilibrium>_<rank>`); returns the file names.
pub fn write(
    loaded: &Loaded,
    analysis: &ModalAnalysis,
    count: usize,
    dir: &Path,
) -> Result<Vec<String>, PlotError> {
    let points = body_points(loaded, &analysis.state);
    let all: Vec<&Vector3<f64>> = points.iter().flatten().collect();
    let span = all
        .iter()
        .flat_map(|a| {
            all.iter()
                .map(move |b| ((a.x - b.x).powi(2) + (a.y - b.y).powi(2)).sqrt())
        })
        .fold(0.0_f64, f64::max)
        .max(1e-3);
    let mut written = Vec::new();
    for (rank, &k) in analysis.mechanical_modes().iter().take(count).enumerate() {
        let mode = &analysis.modes[k];
        // Real shape: magnitude x cos(phase), scaled so the largest point moves 15% of the span.
        let shape: Vec<f64> = mode
            .participation
            .iter()
            .map(|p| p.magnitude * p.phase_deg.to_radians().cos())
            .collect();
        let mut moved: Vec<Vec<Vector3<f64>>> = Vec::new();
        let mut largest = 0.0_f64;
        for (b, body_points) in points.iter().enumerate() {
            let d: Vec<Vector3<f64>> = body_points
                .iter()
                .map(|p| displacement(loaded, &analysis.state, &shape, b, p))
                .collect();
            largest = d.iter().map(|v| v.xy().norm()).fold(largest, f64::max);
            moved.push(d);
        }
        let scale = if largest > 0.0 {
            0.15 * span / largest
        } else {
            0.0
        };
        let mut series = Vec::new();
        for (b, body) in loaded.model.bodies().iter().enumerate() {
            let at_rest = &points[b];
            let displaced: Vec<Vector3<f64>> = at_rest
                .iter()
                .zip(&moved[b])
                .map(|(p, d)| p + d * scale)
                .collect();
            let outline = |pts: &[Vector3<f64>]| -> (Vec<f64>, Vec<f64>) {
                // The attach points (after the body origin) outline the body.
                let ring = convex_ring(if pts.len() > 3 { &pts[1..] } else { pts });
                (
                    ring.iter().map(|p| p.x * 1e3).collect(),
                    ring.iter().map(|p| p.y * 1e3).collect(),
                )
            };
            if matches!(body.joint.motion, JointMotion::Floating) {
                let (x, y) = outline(at_rest);
                series.push(Series::line(format!("{} at rest", body.name), x, y));
                let (x, y) = outline(&displaced);
                series.push(Series::line(format!("{} in mode", body.name), x, y));
            } else {
                let last = at_rest.len() - 1;
                series.push(Series::line_and_markers(
                    body.name.clone(),
                    vec![at_rest[last].x * 1e3, displaced[last].x * 1e3],
                    vec![at_rest[last].y * 1e3, displaced[last].y * 1e3],
                ));
            }
        }
        let mut plot = XyPlot::new(
            format!(
                "{} mode {}: {:.2} Hz, zeta {:.4}{}",
                analysis.equilibrium,
                k + 1,
                mode.frequency_hz,
                mode.damping_ratio,
                if mode.real > 0.0 { ", UNSTABLE" } else { "" }
            ),
            "x [mm] (top view, motion exaggerated)",
            "y [mm]",
            series,
        );
        plot.equal_aspect = true;
        let stem = format!("mode_{}_{}", analysis.equilibrium, rank + 1);
        written.extend(svg_and_png(dir, &stem, |path| write_xy(&plot, path))?);
    }
    Ok(written)
}

/// Points of a body's outline in angular order around their centroid, closed.
fn convex_ring(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    if points.len() < 3 {
        return points.to_vec();
    }
    let centre = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let mut ring: Vec<Vector3<f64>> = points
        .iter()
        .filter(|p| (p.xy() - centre.xy()).norm() > 1e-9)
        .copied()
        .collect();
    ring.sort_by(|a, b| {
        let angle = |p: &Vector3<f64>| (p.y - centre.y).atan2(p.x - centre.x);
        angle(a).total_cmp(&angle(b))
    });
    ring.dedup_by(|a, b| (a.xy() - b.xy()).norm() < 1e-9);
    if let Some(first) = ring.first().copied() {
        ring.push(first);
    }
    ring
}
