//! Triangles from VRML/X3D/Inventor geometry: polygon meshes (IndexedFaceSet and its kin)
//! triangulated, with normals from the file or computed with the crease angle, and the
//! primitive shapes tessellated.
//!
//! **Normals** (ISO/IEC 14772-1 §6.23, `creaseAngle`): without normals in the file, each
//! face's normal is Newell's (the polygon's area vector, normalized); the normal of a face's
//! corner is the normalized sum of the unit normals of the faces that share the corner's point
//! and meet this face at an angle ≤ `creaseAngle` (the face itself included). `creaseAngle 0`
//! (the default) gives flat faces.
//!
//! **Triangulation**: convex polygons (`convex TRUE`, the default) as a fan from their first
//! corner; others by ear clipping in the plane of their Newell normal.
//!
//! A mesh keeps its topology apart from its points ([`Tessellation`]) so that a
//! `CoordinateInterpolator`'s key frames reuse the triangles and the crease groups and only
//! move the points ([`Tessellation::frame`]).

use glam::{Vec2, Vec3};

/// Segments around the axis of tessellated spheres, cones and cylinders.
pub const ROUND_SEGMENTS: usize = 32;
/// Rings from pole to pole of tessellated spheres.
pub const SPHERE_RINGS: usize = 16;

/// A polygon mesh as the file gives it.
#[derive(Clone, Debug, Default)]
pub struct PolyMesh {
    /// Corner point indices of every face, face after face.
    pub corners: Vec<u32>,
    /// Start of each face in `corners`, plus the end.
    pub face_start: Vec<u32>,
    /// Normals per corner, when the file gives them.
    pub corner_normals: Option<Vec<Vec3>>,
    /// Texture coordinates per corner (VRML's: origin bottom-left).
    pub corner_uvs: Option<Vec<Vec2>>,
    pub crease_angle: f32,
    /// Counter-clockwise faces (seen from the front).
    pub ccw: bool,
    pub convex: bool,
}

/// Triangles with the topology to recompute points and normals for other point sets.
#[derive(Clone, Debug, Default)]
pub struct Tessellation {
    /// The point index of each output vertex.
    pub vertex_point: Vec<u32>,
    /// The faces whose normals a vertex's normal sums: `group_faces[group_start[v]..group_start[v+1]]`.
    group_start: Vec<u32>,
    group_faces: Vec<u32>,
    /// The file's normal per vertex, when it gave normals.
    explicit_normals: Option<Vec<Vec3>>,
    /// Texture coordinates per vertex, keyrig's convention (origin top-left: v = 1 − t).
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<u32>,
    corners: Vec<u32>,
    face_start: Vec<u32>,
    flip: bool,
}

/// Positions and normals of the output vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

fn newell(points: &[Vec3], corners: &[u32]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for (i, &a) in corners.iter().enumerate() {
        let b = corners[(i + 1) % corners.len()];
        let (p, q) = (points[a as usize], points[b as usize]);
        n += Vec3::new((p.y - q.y) * (p.z + q.z), (p.z - q.z) * (p.x + q.x), (p.x - q.x) * (p.y + q.y));
    }
    n
}

impl Tessellation {
    /// The face normals (unit, zero for degenerate faces) of `points`.
    fn face_normals(&self, points: &[Vec3]) -> Vec<Vec3> {
        self.face_start
            .windows(2)
            .map(|w| {
                let n = newell(points, &self.corners[w[0] as usize..w[1] as usize]).normalize_or_zero();
                if self.flip {
                    -n
                } else {
                    n
                }
            })
            .collect()
    }

    /// Positions and normals for the points `points` (the mesh's own, or a morph key's).
    /// `points` must have every index the faces use (checked when the mesh was built).
    #[must_use]
    pub fn frame(&self, points: &[Vec3]) -> Frame {
        let positions: Vec<Vec3> = self
            .vertex_point
            .iter()
            .map(|&p| points.get(p as usize).copied().unwrap_or(Vec3::ZERO))
            .collect();
        let normals = match &self.explicit_normals {
            Some(n) => n.clone(),
            None => {
                let faces = self.face_normals(points);
                (0..self.vertex_point.len())
                    .map(|v| {
                        let group =
                            &self.group_faces[self.group_start[v] as usize..self.group_start[v + 1] as usize];
                        let sum: Vec3 = group.iter().map(|&f| faces[f as usize]).sum();
                        sum.normalize_or(Vec3::Y)
                    })
                    .collect()
            }
        };
        Frame { positions, normals }
    }

    /// Number of output vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertex_point.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertex_point.is_empty()
    }
}

/// What is wrong with a mesh (a message; the caller names the node and the place).
pub type GeometryError = String;

impl PolyMesh {
    /// Triangulates the mesh over `points`, computing crease groups; faces with fewer than 3
    /// corners or no area are left out.
    ///
    /// # Errors
    /// A corner indexes past `points`.
    pub fn tessellate(&self, points: &[Vec3]) -> Result<Tessellation, GeometryError> {
        if let Some(&bad) = self.corners.iter().find(|&&c| c as usize >= points.len()) {
            return Err(format!("point index {bad} is out of range (there are {} points)", points.len()));
        }
        let faces = self.face_start.len().saturating_sub(1);
        let mut t = Tessellation {
            corners: self.corners.clone(),
            face_start: self.face_start.clone(),
            flip: !self.ccw,
            ..Tessellation::default()
        };
        let face_normals = t.face_normals(points);
        // Faces around each point (CSR), for crease groups.
        let cos_crease = self.crease_angle.clamp(0.0, std::f32::consts::PI).cos();
        let smooth = self.corner_normals.is_none() && self.crease_angle > 0.0;
        let (mut around_start, mut around) = (vec![0u32; points.len() + 1], Vec::new());
        if smooth {
            for &c in &self.corners {
                around_start[c as usize + 1] += 1;
            }
            for i in 0..points.len() {
                around_start[i + 1] += around_start[i];
            }
            around = vec![0u32; self.corners.len()];
            let mut fill = around_start.clone();
            for f in 0..faces {
                for &c in &self.corners[self.face_start[f] as usize..self.face_start[f + 1] as usize] {
                    around[fill[c as usize] as usize] = f as u32;
                    fill[c as usize] += 1;
                }
            }
        }
        let mut explicit = self.corner_normals.as_ref().map(|_| Vec::new());
        let mut uvs = self.corner_uvs.as_ref().map(|_| Vec::new());
        let mut vertex_of: std::collections::HashMap<(u32, Vec<u32>), u32> = std::collections::HashMap::new();
        t.group_start.push(0);
        let mut polygon: Vec<u32> = Vec::new();
        let mut tris: Vec<[usize; 3]> = Vec::new();
        for f in 0..faces {
            let (start, end) = (self.face_start[f] as usize, self.face_start[f + 1] as usize);
            if end - start < 3 || face_normals[f] == Vec3::ZERO {
                continue;
            }
            polygon.clear();
            for corner in start..end {
                let point = self.corners[corner];
                // The faces this corner's normal sums.
                let group: Vec<u32> = if smooth {
                    let mut g: Vec<u32> = around
                        [around_start[point as usize] as usize..around_start[point as usize + 1] as usize]
                        .iter()
                        .copied()
                        .filter(|&g| face_normals[g as usize].dot(face_normals[f]) >= cos_crease - 1e-6)
                        .collect();
                    g.dedup();
                    g
                } else {
                    vec![f as u32]
                };
                let shareable = smooth && explicit.is_none() && uvs.is_none();
                let vertex = if shareable {
                    let next = t.vertex_point.len() as u32;
                    *vertex_of.entry((point, group.clone())).or_insert(next)
                } else {
                    t.vertex_point.len() as u32
                };
                if vertex as usize == t.vertex_point.len() {
                    t.vertex_point.push(point);
                    t.group_faces.extend_from_slice(&group);
                    t.group_start.push(t.group_faces.len() as u32);
                    if let (Some(e), Some(n)) = (explicit.as_mut(), &self.corner_normals) {
                        e.push(n[corner].normalize_or(face_normals[f]));
                    }
                    if let (Some(u), Some(c)) = (uvs.as_mut(), &self.corner_uvs) {
                        let uv = c[corner];
                        u.push(Vec2::new(uv.x, 1.0 - uv.y));
                    }
                }
                polygon.push(vertex);
            }
            tris.clear();
            if self.convex || polygon.len() == 3 {
                tris.extend((1..polygon.len() - 1).map(|i| [0, i, i + 1]));
            } else {
                let pts: Vec<Vec3> = self.corners[start..end].iter().map(|&c| points[c as usize]).collect();
                ear_clip(&pts, face_normals[f] * if self.ccw { 1.0 } else { -1.0 }, &mut tris);
            }
            for tri in &tris {
                let [a, b, c] = tri.map(|i| polygon[i]);
                if self.ccw {
                    t.indices.extend_from_slice(&[a, b, c]);
                } else {
                    t.indices.extend_from_slice(&[a, c, b]);
                }
            }
        }
        t.explicit_normals = explicit;
        t.uvs = uvs;
        Ok(t)
    }
}

/// Ear clipping of a simple polygon `pts` (in order, counter-clockwise about `normal`):
/// triangles as indices into `pts`. Falls back to a fan when no ear is found (a
/// self-intersecting polygon).
fn ear_clip(pts: &[Vec3], normal: Vec3, out: &mut Vec<[usize; 3]>) {
    let n = normal.normalize_or(Vec3::Z);
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let p2: Vec<Vec2> = pts.iter().map(|p| Vec2::new(p.dot(u), p.dot(v))).collect();
    let mut idx: Vec<usize> = (0..pts.len()).collect();
    let cross = |a: Vec2, b: Vec2, c: Vec2| (b - a).perp_dot(c - a);
    let mut guard = 0;
    while idx.len() > 3 && guard < pts.len() * pts.len() {
        guard += 1;
        let m = idx.len();
        let mut clipped = false;
        for i in 0..m {
            let (a, b, c) = (idx[(i + m - 1) % m], idx[i], idx[(i + 1) % m]);
            if cross(p2[a], p2[b], p2[c]) <= 0.0 {
                continue;
            }
            let inside = idx.iter().any(|&k| {
                k != a && k != b && k != c && {
                    let p = p2[k];
                    cross(p2[a], p2[b], p) >= 0.0
                        && cross(p2[b], p2[c], p) >= 0.0
                        && cross(p2[c], p2[a], p) >= 0.0
                }
            });
            if !inside {
                out.push([a, b, c]);
                idx.remove(i);
                clipped = true;
                break;
            }
        }
        if !clipped {
            break;
        }
    }
    if idx.len() >= 3 {
        out.extend((1..idx.len() - 1).map(|i| [idx[0], idx[i], idx[i + 1]]));
    }
}

/// A mesh made in code (a primitive): positions, normals, keyrig-convention UVs, triangles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Solid {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

impl Solid {
    fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        // VRML's (s, t) with t up → keyrig's v down.
        self.uvs.push(Vec2::new(uv.x, 1.0 - uv.y));
        (self.positions.len() - 1) as u32
    }

    /// A quad a-b-c-d, counter-clockwise seen from outside.
    fn quad(&mut self, corners: [Vec3; 4], n: Vec3) {
        let uv = [Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)];
        let i: Vec<u32> = corners.iter().zip(uv).map(|(&p, uv)| self.vertex(p, n, uv)).collect();
        self.indices.extend_from_slice(&[i[0], i[1], i[2], i[0], i[2], i[3]]);
    }
}

/// A box centred on the origin with the given full size (VRML `Box`, Inventor `Cube`).
#[must_use]
pub fn box_solid(size: Vec3) -> Solid {
    let h = size * 0.5;
    let mut s = Solid::default();
    let (x, y, z) = (h.x, h.y, h.z);
    // Front, back, right, left, top, bottom; each seen from outside, texture upright.
    s.quad([Vec3::new(-x, -y, z), Vec3::new(x, -y, z), Vec3::new(x, y, z), Vec3::new(-x, y, z)], Vec3::Z);
    s.quad(
        [Vec3::new(x, -y, -z), Vec3::new(-x, -y, -z), Vec3::new(-x, y, -z), Vec3::new(x, y, -z)],
        -Vec3::Z,
    );
    s.quad([Vec3::new(x, -y, z), Vec3::new(x, -y, -z), Vec3::new(x, y, -z), Vec3::new(x, y, z)], Vec3::X);
    s.quad(
        [Vec3::new(-x, -y, -z), Vec3::new(-x, -y, z), Vec3::new(-x, y, z), Vec3::new(-x, y, -z)],
        -Vec3::X,
    );
    s.quad([Vec3::new(-x, y, z), Vec3::new(x, y, z), Vec3::new(x, y, -z), Vec3::new(-x, y, -z)], Vec3::Y);
    s.quad(
        [Vec3::new(-x, -y, -z), Vec3::new(x, -y, -z), Vec3::new(x, -y, z), Vec3::new(-x, -y, z)],
        -Vec3::Y,
    );
    s
}

/// A sphere of `radius` about the origin; texture `s` runs once around from −Z (VRML §6.44).
#[must_use]
pub fn sphere_solid(radius: f32) -> Solid {
    let mut s = Solid::default();
    let (segments, rings) = (ROUND_SEGMENTS, SPHERE_RINGS);
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let phi = std::f32::consts::PI * (1.0 - v);
        for k in 0..=segments {
            let u = k as f32 / segments as f32;
            let theta = std::f32::consts::TAU * u;
            // s = 0 at −Z, increasing counter-clockwise seen from +Y (towards −X first).
            let n = Vec3::new(-theta.sin() * phi.sin(), phi.cos(), -theta.cos() * phi.sin());
            s.vertex(n * radius, n, Vec2::new(u, v));
        }
    }
    let row = (segments + 1) as u32;
    for r in 0..rings as u32 {
        for k in 0..segments as u32 {
            let (a, b) = (r * row + k, (r + 1) * row + k);
            s.indices.extend_from_slice(&[a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    s
}

/// A cylinder (`top_radius` = `bottom_radius`) or cone (`top_radius` 0) along Y, centred on
/// the origin, with the parts asked for.
#[must_use]
pub fn round_solid(
    bottom_radius: f32,
    top_radius: f32,
    height: f32,
    side: bool,
    bottom: bool,
    top: bool,
) -> Solid {
    let mut s = Solid::default();
    let n = ROUND_SEGMENTS;
    let h = height * 0.5;
    let angle = |k: usize| std::f32::consts::TAU * k as f32 / n as f32;
    let dir = |a: f32| Vec3::new(-a.sin(), 0.0, -a.cos());
    if side {
        let slope = (bottom_radius - top_radius) / height.max(1e-12);
        for k in 0..n {
            let (a0, a1) = (angle(k), angle(k + 1));
            let (d0, d1) = (dir(a0), dir(a1));
            let n0 = (d0 + Vec3::Y * slope).normalize_or(d0);
            let n1 = (d1 + Vec3::Y * slope).normalize_or(d1);
            let (u0, u1) = (k as f32 / n as f32, (k + 1) as f32 / n as f32);
            let b0 = s.vertex(d0 * bottom_radius - Vec3::Y * h, n0, Vec2::new(u0, 0.0));
            let b1 = s.vertex(d1 * bottom_radius - Vec3::Y * h, n1, Vec2::new(u1, 0.0));
            let t1 = s.vertex(d1 * top_radius + Vec3::Y * h, n1, Vec2::new(u1, 1.0));
            let t0 = s.vertex(d0 * top_radius + Vec3::Y * h, n0, Vec2::new(u0, 1.0));
            s.indices.extend_from_slice(&[b0, b1, t1, b0, t1, t0]);
            if top_radius == 0.0 {
                // The apex triangles keep one triangle each (the second is degenerate).
                s.indices.truncate(s.indices.len() - 3);
            }
        }
    }
    let mut cap = |y: f32, radius: f32, up: bool| {
        let normal = if up { Vec3::Y } else { -Vec3::Y };
        let centre = s.vertex(Vec3::Y * y, normal, Vec2::splat(0.5));
        let ring: Vec<u32> = (0..n)
            .map(|k| {
                let d = dir(angle(k));
                s.vertex(
                    d * radius + Vec3::Y * y,
                    normal,
                    Vec2::new(0.5 + 0.5 * d.x, 0.5 - 0.5 * d.z * if up { 1.0 } else { -1.0 }),
                )
            })
            .collect();
        for k in 0..n {
            let (a, b) = (ring[k], ring[(k + 1) % n]);
            if up {
                s.indices.extend_from_slice(&[centre, a, b]);
            } else {
                s.indices.extend_from_slice(&[centre, b, a]);
            }
        }
    };
    if bottom && bottom_radius > 0.0 {
        cap(-h, bottom_radius, false);
    }
    if top && top_radius > 0.0 {
        cap(h, top_radius, true);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_normal(s: &Solid) -> Vec3 {
        s.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| s.positions[i as usize]);
                (b - a).cross(c - a)
            })
            .sum()
    }

    /// Closed solids have outward faces: the signed volume is positive and the summed area
    /// vectors cancel.
    #[test]
    fn primitives_are_closed_and_face_outwards() {
        for (name, s, volume) in [
            ("box", box_solid(Vec3::new(2.0, 3.0, 4.0)), 24.0),
            ("sphere", sphere_solid(1.0), 4.0 / 3.0 * std::f32::consts::PI),
            ("cylinder", round_solid(1.0, 1.0, 2.0, true, true, true), 2.0 * std::f32::consts::PI),
            ("cone", round_solid(1.0, 0.0, 3.0, true, true, false), std::f32::consts::PI),
        ] {
            let v: f32 = s
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [t[0], t[1], t[2]].map(|i| s.positions[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!((v - volume).abs() < 0.03 * volume, "{name}: volume {v}, expected about {volume}");
            assert!(area_normal(&s).length() < 1e-3, "{name}: {}", area_normal(&s));
        }
    }

    #[test]
    fn crease_angle_shares_normals_of_shallow_faces_only() {
        // Two faces folded by 30° along the X axis, and a third at 90°.
        let points = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.5_f32.sin() * 0.0 + (30f32).to_radians().sin(), -(30f32).to_radians().cos()),
            Vec3::new(0.0, (30f32).to_radians().sin(), -(30f32).to_radians().cos()),
        ];
        let mesh = |crease: f32| PolyMesh {
            corners: vec![0, 1, 2, 3, 1, 0, 5, 4],
            face_start: vec![0, 4, 8],
            crease_angle: crease,
            ccw: false,
            convex: true,
            ..PolyMesh::default()
        };
        let flat = mesh(0.0).tessellate(&points).unwrap().frame(&points);
        assert_eq!(flat.positions.len(), 8);
        assert!((flat.normals[0] - Vec3::Y).length() < 1e-6, "{}", flat.normals[0]);
        let smooth_t = mesh(0.6).tessellate(&points).unwrap();
        assert_eq!(smooth_t.len(), 6, "the shared edge's two points are shared");
        let smooth = smooth_t.frame(&points);
        let shared = smooth.normals[smooth_t.vertex_point.iter().position(|&p| p == 0).unwrap()];
        assert!((shared.angle_between(Vec3::Y).to_degrees() - 15.0).abs() < 1e-3, "{shared}");
        let sharp = mesh(0.5).tessellate(&points).unwrap();
        assert_eq!(sharp.len(), 8, "30° is more than 0.5 rad? no: 0.524 > 0.5, so not shared");
    }

    #[test]
    fn concave_polygons_are_ear_clipped() {
        // An L shape.
        let points: Vec<Vec3> = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]
            .iter()
            .map(|&(x, y)| Vec3::new(x as f32, y as f32, 0.0))
            .collect();
        let mesh = PolyMesh {
            corners: (0..6).collect(),
            face_start: vec![0, 6],
            ccw: true,
            convex: false,
            ..PolyMesh::default()
        };
        let t = mesh.tessellate(&points).unwrap();
        let f = t.frame(&points);
        let area: f32 = t
            .indices
            .chunks_exact(3)
            .map(|tri| {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| f.positions[i as usize]);
                (b - a).cross(c - a).z / 2.0
            })
            .sum();
        assert!((area - 3.0).abs() < 1e-6, "{area}");
        assert!(mesh.tessellate(&points[..4]).unwrap_err().contains("out of range"));
    }
}
