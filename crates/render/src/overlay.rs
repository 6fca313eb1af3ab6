//! Overlay geometry built on the CPU each frame as coloured line segments: the ground grid,
//! skeletons (octahedral bones with joint markers) and motion paths with key markers.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};

/// One end of an overlay line segment (32 bytes; vertex attributes 0 and 1 of `vs_line`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct LineVertex {
    pub position: [f32; 4],
    pub colour: [f32; 4],
}

/// Linear RGBA colours of the overlays.
pub mod colours {
    pub const GRID: [f32; 4] = [0.07, 0.07, 0.08, 1.0];
    pub const GRID_MAJOR: [f32; 4] = [0.14, 0.14, 0.16, 1.0];
    pub const AXIS_X: [f32; 4] = [0.75, 0.12, 0.12, 1.0];
    pub const AXIS_Z: [f32; 4] = [0.12, 0.25, 0.8, 1.0];
    pub const BONE: [f32; 4] = [0.85, 0.85, 0.55, 1.0];
    pub const JOINT: [f32; 4] = [0.3, 0.85, 1.0, 1.0];
    pub const SELECTED: [f32; 4] = [1.0, 0.45, 0.05, 1.0];
    pub const PATH: [f32; 4] = [0.2, 0.9, 0.4, 1.0];
    pub const KEY: [f32; 4] = [1.0, 1.0, 1.0, 1.0];
    pub const LIGHT: [f32; 4] = [1.0, 0.85, 0.3, 1.0];
    pub const CAMERA: [f32; 4] = [0.55, 0.75, 1.0, 1.0];
    pub const ACTIVE_CAMERA: [f32; 4] = [0.9, 0.9, 0.95, 1.0];
}

/// A batch of line segments (pairs of vertices).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lines {
    pub vertices: Vec<LineVertex>,
}

impl Lines {
    pub fn segment(&mut self, a: Vec3, b: Vec3, colour: [f32; 4]) {
        self.vertices.push(LineVertex { position: a.extend(1.0).to_array(), colour });
        self.vertices.push(LineVertex { position: b.extend(1.0).to_array(), colour });
    }

    /// Three axis-aligned strokes of half-length `size` through `p`.
    pub fn cross(&mut self, p: Vec3, size: f32, colour: [f32; 4]) {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            self.segment(p - axis * size, p + axis * size, colour);
        }
    }

    /// A wire octahedron around `p` (a joint marker).
    pub fn diamond(&mut self, p: Vec3, size: f32, colour: [f32; 4]) {
        let tips = [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z].map(|d| p + d * size);
        let (top, bottom) = (p + Vec3::Y * size, p - Vec3::Y * size);
        for i in 0..4 {
            self.segment(tips[i], tips[[2, 3, 1, 0][i]], colour);
            self.segment(tips[i], top, colour);
            self.segment(tips[i], bottom, colour);
        }
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

/// The ground grid on the plane y = 0: `2·half_count` cells of `spacing` each way, every
/// tenth line brighter, the X axis red and the Z axis blue.
pub fn grid(lines: &mut Lines, spacing: f32, half_count: u32) {
    let n = half_count as i32;
    let extent = spacing * half_count as f32;
    for i in -n..=n {
        let c = spacing * i as f32;
        let colour = if i % 10 == 0 { colours::GRID_MAJOR } else { colours::GRID };
        let (x_colour, z_colour) = if i == 0 { (colours::AXIS_Z, colours::AXIS_X) } else { (colour, colour) };
        lines.segment(Vec3::new(c, 0.0, -extent), Vec3::new(c, 0.0, extent), x_colour);
        lines.segment(Vec3::new(-extent, 0.0, c), Vec3::new(extent, 0.0, c), z_colour);
    }
}

/// A grid spacing that suits an orbit distance: the 1-2-5 step (…, 0.1, 0.2, 0.5, 1, 2, …)
/// nearest to an eighth of it, in log scale.
#[must_use]
pub fn grid_spacing_for(distance: f32) -> f32 {
    let d = if distance.is_finite() && distance > 0.0 { distance } else { 1.0 };
    let target = (d / 8.0).log10();
    let decade = target.floor();
    let steps = [1.0f32, 2.0, 5.0, 10.0];
    let best = steps
        .into_iter()
        .min_by(|a, b| (a.log10() + decade - target).abs().total_cmp(&(b.log10() + decade - target).abs()))
        .unwrap_or(1.0);
    best * 10f32.powf(decade)
}

/// A skeleton to draw: world-space joint positions, parents, and the selected joint.
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonOverlay {
    pub joints: Vec<Vec3>,
    pub parents: Vec<Option<usize>>,
    pub selected: Option<usize>,
}

/// Bones as wire octahedra from each parent joint to the joint (widest a fifth of the way
/// along, a tenth of the bone long), joints as small diamonds. Joints without a parent get only
/// the diamond. `marker` is the joint marker's half-size in world units.
pub fn skeleton(lines: &mut Lines, overlay: &SkeletonOverlay, marker: f32) {
    for (j, &p) in overlay.joints.iter().enumerate() {
        let joint_colour = if overlay.selected == Some(j) { colours::SELECTED } else { colours::JOINT };
        lines.diamond(p, marker, joint_colour);
        let Some(parent) = overlay.parents.get(j).copied().flatten() else { continue };
        let Some(&a) = overlay.joints.get(parent) else { continue };
        let axis = p - a;
        let length = axis.length();
        if length <= f32::EPSILON || !length.is_finite() {
            continue;
        }
        let bone_colour = if overlay.selected == Some(parent) { colours::SELECTED } else { colours::BONE };
        let dir = axis / length;
        let side = dir.any_orthonormal_vector();
        let up = dir.cross(side);
        let waist = a + axis * 0.2;
        let r = length * 0.1;
        let ring = [side, up, -side, -up].map(|d| waist + d * r);
        for i in 0..4 {
            lines.segment(a, ring[i], bone_colour);
            lines.segment(ring[i], p, bone_colour);
            lines.segment(ring[i], ring[(i + 1) % 4], bone_colour);
        }
    }
}

/// A motion path: world positions sampled over time, the positions at keys, and the current
/// position.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionPath {
    pub points: Vec<Vec3>,
    pub keys: Vec<Vec3>,
    pub current: Option<Vec3>,
}

/// The path as a polyline, keys as crosses, the current position as a diamond.
pub fn motion_path(lines: &mut Lines, path: &MotionPath, marker: f32) {
    for pair in path.points.windows(2) {
        lines.segment(pair[0], pair[1], colours::PATH);
    }
    for &k in &path.keys {
        lines.cross(k, marker, colours::KEY);
    }
    if let Some(c) = path.current {
        lines.diamond(c, marker * 0.8, colours::SELECTED);
    }
}

/// A light drawn in the viewport: where it is and where it shines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightGizmo {
    pub kind: keyrig_core::LightKind,
    pub position: Vec3,
    pub direction: Vec3,
    pub selected: bool,
}

/// Every light gets a diamond at its position; a point light a cross through it; a directional
/// light an arrow along its direction; a spot light the edges of its cut-off cone and a ring at
/// the cone's end. `marker` is the diamond's half-size; the arrow and cone are 10 markers long.
pub fn light_gizmo(lines: &mut Lines, gizmo: &LightGizmo, marker: f32) {
    use keyrig_core::LightKind;
    let colour = if gizmo.selected { colours::SELECTED } else { colours::LIGHT };
    let p = gizmo.position;
    lines.diamond(p, marker, colour);
    let dir = gizmo.direction.normalize_or(Vec3::NEG_Y);
    let length = marker * 10.0;
    match gizmo.kind {
        LightKind::Point => lines.cross(p, marker * 2.0, colour),
        LightKind::Directional => {
            let tip = p + dir * length;
            lines.segment(p, tip, colour);
            let side = dir.any_orthonormal_vector();
            let up = dir.cross(side);
            for d in [side, -side, up, -up] {
                lines.segment(tip, tip - dir * marker * 2.0 + d * marker, colour);
            }
        }
        LightKind::Spot { cutoff_deg, .. } => {
            let angle = cutoff_deg.clamp(0.0, 89.0).to_radians();
            let side = dir.any_orthonormal_vector();
            let up = dir.cross(side);
            let centre = p + dir * length;
            let radius = length * angle.tan();
            let ring: Vec<Vec3> = (0..16)
                .map(|i| {
                    let a = i as f32 / 16.0 * std::f32::consts::TAU;
                    centre + (side * a.cos() + up * a.sin()) * radius
                })
                .collect();
            for i in 0..16 {
                lines.segment(ring[i], ring[(i + 1) % 16], colour);
            }
            for i in (0..16).step_by(4) {
                lines.segment(p, ring[i], colour);
            }
        }
    }
}

/// A scene camera drawn in the viewport: its frustum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraGizmo {
    pub camera: keyrig_eval::CameraState,
    /// Width over height of the image it renders.
    pub aspect: f32,
    pub selected: bool,
    /// The scene's active camera at this time.
    pub active: bool,
}

/// A camera's frustum as Blender draws it: lines from the eye to the corners of its image
/// rectangle `12·marker` in front of it (an orthographic camera: a box from the eye's plane),
/// the rectangle, and a filled-in triangle on its top edge that shows which way is up.
pub fn camera_gizmo(lines: &mut Lines, gizmo: &CameraGizmo, marker: f32) {
    let colour = if gizmo.selected {
        colours::SELECTED
    } else if gizmo.active {
        colours::ACTIVE_CAMERA
    } else {
        colours::CAMERA
    };
    let depth = marker * 12.0;
    let camera = &gizmo.camera;
    let far = camera.image_corners(gizmo.aspect, depth);
    let near = match camera.lens {
        keyrig_core::Lens::Perspective { .. } => [camera.eye(); 4],
        keyrig_core::Lens::Orthographic { .. } => camera.image_corners(gizmo.aspect, 0.0),
    };
    for i in 0..4 {
        lines.segment(near[i], far[i], colour);
        lines.segment(far[i], far[(i + 1) % 4], colour);
        if near[i] != near[(i + 1) % 4] {
            lines.segment(near[i], near[(i + 1) % 4], colour);
        }
    }
    // The up triangle over the top edge (corners 2 and 3 are top right and top left).
    let (top_right, top_left) = (far[2], far[3]);
    let width = top_right - top_left;
    let up = camera.world_from_camera.transform_vector3(glam::Vec3::Y).normalize_or(glam::Vec3::Y);
    let apex = (top_right + top_left) * 0.5 + up * width.length() * 0.3;
    let (a, b) = (top_left + width * 0.2, top_right - width * 0.2);
    lines.segment(a, apex, colour);
    lines.segment(apex, b, colour);
    lines.segment(b, a, colour);
}

/// Moves every vertex by a transform (e.g. model to world).
pub fn transform(lines: &mut [LineVertex], world_from_model: &Mat4) {
    for v in lines {
        let p = world_from_model.transform_point3(Vec3::new(v.position[0], v.position[1], v.position[2]));
        v.position = p.extend(1.0).to_array();
    }
}

/// Unique undirected edges of a triangle list, as a line-list index buffer (wireframe without
/// the POLYGON_MODE_LINE feature).
#[must_use]
pub fn edge_indices(triangles: &[u32]) -> Vec<u32> {
    let mut edges: Vec<(u32, u32)> = triangles
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| if a < b { (a, b) } else { (b, a) })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    edges.into_iter().flat_map(|(a, b)| [a, b]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_frustum_reaches_its_image_corners() {
        let camera = keyrig_eval::CameraState {
            world_from_camera: glam::Affine3A::from_translation(Vec3::new(0.0, 1.0, 5.0)),
            lens: keyrig_core::Lens::Perspective { fov_y: 90f32.to_radians() },
            near: 0.1,
            far: Some(100.0),
            visible: true,
        };
        let gizmo = CameraGizmo { camera, aspect: 2.0, selected: false, active: true };
        let mut lines = Lines::default();
        camera_gizmo(&mut lines, &gizmo, 0.1);
        // 4 eye-to-corner lines, 4 rectangle edges, 3 triangle edges.
        assert_eq!(lines.len(), (4 + 4 + 3) * 2);
        // 1.2 units in front (down −Z), a 90° field of view: 1.2 up and 2.4 to the side.
        let top_right = Vec3::new(2.4, 2.2, 3.8);
        assert!(lines
            .vertices
            .iter()
            .any(|v| Vec3::from_slice(&v.position[..3]).abs_diff_eq(top_right, 1e-5)));
        assert!(lines.vertices.iter().all(|v| v.colour == colours::ACTIVE_CAMERA));
    }

    #[test]
    fn shared_edges_appear_once() {
        // Two triangles sharing the edge 1–2: 5 unique edges.
        let lines = edge_indices(&[0, 1, 2, 2, 1, 3]);
        assert_eq!(lines, vec![0, 1, 0, 2, 1, 2, 1, 3, 2, 3]);
    }

    #[test]
    fn grid_spacing_is_a_one_two_five_step() {
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5 * b;
        assert!(close(grid_spacing_for(80.0), 10.0));
        assert!(close(grid_spacing_for(3.2), 0.5));
        assert!(close(grid_spacing_for(320.0), 50.0));
        assert!(close(grid_spacing_for(1.6), 0.2));
        assert!(close(grid_spacing_for(f32::NAN), 0.1));
    }

    #[test]
    fn skeleton_draws_a_bone_per_parented_joint() {
        let overlay = SkeletonOverlay {
            joints: vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
            parents: vec![None, Some(0), Some(1)],
            selected: Some(1),
        };
        let mut lines = Lines::default();
        skeleton(&mut lines, &overlay, 0.05);
        // 3 diamonds × 12 segments + 2 bones × 12 segments, 2 vertices each.
        assert_eq!(lines.len(), (3 * 12 + 2 * 12) * 2);
        assert!(lines.vertices.iter().any(|v| v.colour == colours::SELECTED));
    }
}
