//! Automatic binding: skinning weights for a mesh and a skeleton that come without them
//! (issue 41, item 2). Not to be confused with [`crate::binding`], which derives bones-blending
//! bindings from weights a mesh already has.
//!
//! A [`BindJob`] takes the rest positions and triangles of a mesh and a [`RestSkeleton`] and
//! gives each vertex at most four (joint, weight) pairs summing to 1, as an [`Influences`] —
//! the form [`crate::SkinnedMesh::influences`] holds, so every deformer can use them as they
//! are. docs/binding.md has the formulas and the measured figures.
//!
//! **Bones.** Joint j's bone is the set of segments from its rest position a(j) to each
//! child's; a leaf's is one segment of a quarter of its parent's distance, continuing the
//! parent's direction (a lone root is a point). Only the joints marked `deforming` get weights.
//!
//! **Visibility.** As Baran & Popović and Blender, a vertex sees a bone only when the segment
//! from the vertex to the bone's nearest point q stays inside the mesh: it must cross no
//! triangle but those around the vertex (triangles bucketed in a uniform grid, a 3D DDA walk,
//! Möller–Trumbore per triangle), and q must lie behind the surface, (v − q)·n(v) > 0 with n(v)
//! the area-weighted normal of the welded mesh (the segment would otherwise leave through the
//! vertex's own triangles, which the ray test skips). The vertex's six nearest bones are tested;
//! when none passes both, those that pass the normal test count, and when none does, all.
//!
//! **[`BindMethod::Envelope`]** (nearest bones, Maya's "closest distance" with drop-off 4):
//! the nearest visible bone j₁ (distance d₁) and those of its parent and children among the
//! vertex's nearest visible bones (at most four, distances dᵢ) get wᵢ ∝ (d₁/dᵢ)⁴; weights under
//! 1 % are dropped and the rest scaled to sum 1. (Keeping to j₁'s neighbours in the skeleton
//! stops a foot from taking weight from the other leg.)
//!
//! **[`BindMethod::Heat`]** (Baran & Popović, "Automatic Rigging and Animation of 3D
//! Characters", SIGGRAPH 2007; Blender's "automatic weights"): for every joint j, solve
//!
//! ```text
//! (L + A·H) w_j = A·H·p_j
//! ```
//!
//! over the welded surface, with L the cotangent Laplacian (L_ik = −½(cot α_ik + cot β_ik) for an
//! edge ik, L_ii = −Σ L_ik; cotangents clamped to [0, 10⁴], so the solution stays in [0, 1]),
//! A the diagonal of barycentric vertex areas (⅓ of the adjacent triangles' areas; the
//! paper's −Δ = A⁻¹L, multiplied through by A to keep the system symmetric),
//! H_ii = c/d(i)² with c = 1 and d(i) the distance to the nearest visible bone (at least 10⁻³
//! of the mesh's size), and p_j(i) = 1/k when j is one of the k bones within 10⁻⁴·d(i) of that
//! distance, else 0. The matrix is symmetric positive definite (H > 0 at every vertex) and the
//! same for every joint. Joint j's system is solved only on the vertices that have j among
//! their six nearest bones (visible or not), with w_j = 0 held elsewhere (a Dirichlet
//! boundary), so that a mesh with many bones costs about six whole-mesh solves, not one per
//! bone. Each solve is conjugate gradients in f32 (dot products in f64) with a symmetric
//! successive over-relaxation preconditioner (SSOR, ω = 1.5: a forward and a backward
//! Gauss–Seidel sweep, 4–5× fewer iterations than Jacobi on the benchmark tube), started from
//! p_j, to a residual of 10⁻³·|b|. Each vertex keeps its four largest weights, scaled to sum 1.
//! No sparse-matrix crate is used (docs/binding.md says why): the matrix is one compressed-row
//! array.
//!
//! **Meshes as files give them.** Vertices at bitwise-equal positions (glTF splits vertices at
//! UV seams) are welded before the Laplacian is built, so both sides of a seam get one weight.
//! Islands (separate pieces) are separate blocks of the same system and each solves on its
//! own. Triangles with an area under 10⁻¹² of the mesh's size squared add nothing; a vertex in
//! no other triangle keeps its nearest-bone indicator (w = p).

use glam::{DVec3, Vec3};

use crate::error::SkinError;
use crate::influences::Influences;
use crate::skeleton::RestSkeleton;

/// How [`BindJob`] computes weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindMethod {
    /// Nearest visible bones with inverse-distance fall-off (d₁/dᵢ)⁴.
    Envelope,
    /// Heat diffusion over the surface (Baran & Popović 2007).
    Heat,
}

impl BindMethod {
    /// Every method, in the order the docs list them.
    pub const ALL: [BindMethod; 2] = [BindMethod::Envelope, BindMethod::Heat];

    /// The name the CLI and the docs use: `envelope`, `heat`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BindMethod::Envelope => "envelope",
            BindMethod::Heat => "heat",
        }
    }
}

/// A leaf joint's bone continues its parent's for this fraction of the parent's length.
const LEAF_FRACTION: f32 = 0.25;

/// Influences per vertex the binder produces.
pub const MAX_BOUND_INFLUENCES: usize = 4;

/// Envelope weights below this fraction of a vertex's total are dropped.
const ENVELOPE_MIN_WEIGHT: f32 = 0.01;
/// Envelope drop-off exponent (Maya's default drop-off rate for closest-distance binding).
const ENVELOPE_DROPOFF: i32 = 4;
/// Heat: each joint's weights are solved on the vertices that have it among their this many
/// nearest bones (visible or not), and held at 0 elsewhere.
const REGION_BONES: usize = 6;
/// Heat: c in H = c/d².
const HEAT_C: f64 = 1.0;
/// Heat: bones within this relative distance of the nearest one share the vertex (Blender's
/// `DISTANCE_EPSILON`).
const TIE_EPSILON: f32 = 1e-4;
/// Heat: d(i) is at least this fraction of the mesh's size (a vertex on a bone would make H
/// infinite).
const MIN_DISTANCE_FRACTION: f32 = 1e-3;
/// Cotangents are clamped to [0, COT_MAX]: negative ones (obtuse angles) would let weights
/// leave [0, 1], huge ones come from needle triangles.
const COT_MAX: f64 = 1e4;
/// Triangles with an area under this fraction of size² are skipped.
const DEGENERATE_AREA_FRACTION: f64 = 1e-12;
/// Conjugate gradients stop at |r| ≤ CG_TOLERANCE·|b| …
const CG_TOLERANCE: f64 = 1e-3;
/// … or after this many iterations.
const CG_MAX_ITERATIONS: usize = 2000;
/// The over-relaxation factor of the SSOR preconditioner (1 is symmetric Gauss–Seidel).
const SSOR_OMEGA: f32 = 1.5;

/// Binds a mesh to a skeleton: borrowed inputs, [`BindJob::run`] returns the influences.
///
/// ```
/// use keyrig_skin::{BindJob, BindMethod};
///
/// let mut mesh = keyrig_skin::mesh_for(keyrig_core::ProceduralMesh::ArmHighPoly);
/// let job = BindJob::new(&mesh.positions, &mesh.indices, &mesh.skeleton, BindMethod::Heat);
/// mesh.influences = job.run()?;
/// assert_eq!(mesh.influences.len(), 1250);
/// # Ok::<(), keyrig_skin::SkinError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct BindJob<'a> {
    /// Rest positions, in the skeleton's model (bind) space.
    pub positions: &'a [Vec3],
    /// Triangle list (any winding; normals are taken from it for visibility, so consistently
    /// counter-clockwise from outside is best).
    pub indices: &'a [u32],
    pub skeleton: &'a RestSkeleton,
    /// Which joints may get weight, one flag per joint; `None`: every joint.
    pub deforming: Option<&'a [bool]>,
    pub method: BindMethod,
}

impl<'a> BindJob<'a> {
    /// A job binding every joint.
    #[must_use]
    pub fn new(
        positions: &'a [Vec3],
        indices: &'a [u32],
        skeleton: &'a RestSkeleton,
        method: BindMethod,
    ) -> Self {
        BindJob { positions, indices, skeleton, deforming: None, method }
    }

    /// Checks the inputs: finite positions, whole triangles with indices in range, one
    /// `deforming` flag per joint and at least one set.
    ///
    /// # Errors
    /// [`SkinError::NonFiniteVertex`], [`SkinError::LengthMismatch`],
    /// [`SkinError::TriangleIndexOutOfRange`], or [`SkinError::NoDeformingJoint`].
    pub fn validate(&self) -> Result<(), SkinError> {
        if let Some(vertex) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(SkinError::NonFiniteVertex { vertex, what: "position" });
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(SkinError::LengthMismatch {
                what: "triangle indices (a multiple of 3)",
                expected: self.indices.len() / 3 * 3,
                found: self.indices.len(),
            });
        }
        let n = self.positions.len();
        if let Some((i, &index)) = self.indices.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(SkinError::TriangleIndexOutOfRange { triangle: i / 3, index, vertex_count: n });
        }
        if let Some(flags) = self.deforming {
            crate::error::check_len("deforming joint flags", self.skeleton.len(), flags.len())?;
            if !flags.iter().any(|&f| f) {
                return Err(SkinError::NoDeformingJoint);
            }
        }
        Ok(())
    }

    /// Validates, then computes each vertex's influences (at most [`MAX_BOUND_INFLUENCES`],
    /// unused slots joint 0 with weight 0).
    ///
    /// # Errors
    /// As [`BindJob::validate`].
    pub fn run(&self) -> Result<Influences, SkinError> {
        self.validate()?;
        let n = self.positions.len();
        if n == 0 {
            return Influences::new(Vec::new(), Vec::new(), self.skeleton.len());
        }
        let bones = bone_segments(self.skeleton, self.deforming);
        let welded = Welded::new(self.positions, self.indices);
        let size = bounding_size(self.positions);
        let normals = crate::mesh::vertex_normals(&welded.positions, &welded.indices);
        let mut nearest: Vec<Nearest> = welded
            .positions
            .iter()
            .zip(&normals)
            .map(|(&p, &nm)| nearest_bones(p, nm, &bones, size))
            .collect();
        let grid = TriangleGrid::new(&welded.positions, &welded.indices);
        let mut stamps = vec![0u32; welded.indices.len() / 3];
        for (v, near) in nearest.iter_mut().enumerate() {
            let p = welded.positions[v];
            let seen: Vec<(u16, f32)> = near
                .joints
                .iter()
                .copied()
                .filter(|&(j, _)| {
                    let q = bones
                        .iter()
                        .filter(|s| s.joint == j)
                        .map(|s| s.nearest_point(p))
                        .min_by(|a, b| a.distance_squared(p).total_cmp(&b.distance_squared(p)))
                        .unwrap_or(p);
                    grid.segment_is_clear(&welded.positions, &welded.indices, v as u32, p, q, &mut stamps)
                })
                .collect();
            if !seen.is_empty() {
                near.joints = seen;
            }
        }
        let per_unique = match self.method {
            BindMethod::Envelope => {
                nearest.iter().map(|near| envelope_weights(near, self.skeleton.parents())).collect()
            }
            BindMethod::Heat => heat_weights(&welded, &nearest, size),
        };
        let (mut joints, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for &u in &welded.unique_of {
            let (js, ws) = per_unique[u as usize];
            joints.push(js);
            weights.push(ws);
        }
        Influences::normalized(joints, weights, self.skeleton.len())
    }
}

/// One segment of joint `joint`'s bone, in model space.
#[derive(Clone, Copy, Debug)]
struct Segment {
    joint: u16,
    start: Vec3,
    end: Vec3,
}

impl Segment {
    /// The point of the segment nearest to `p`.
    fn nearest_point(&self, p: Vec3) -> Vec3 {
        let d = self.end - self.start;
        let len2 = d.length_squared();
        if len2 <= f32::MIN_POSITIVE {
            return self.start;
        }
        let t = ((p - self.start).dot(d) / len2).clamp(0.0, 1.0);
        self.start + t * d
    }
}

/// The bone segments of the deforming joints (docs on the module).
fn bone_segments(skeleton: &RestSkeleton, deforming: Option<&[bool]>) -> Vec<Segment> {
    let mut segments = Vec::new();
    for j in 0..skeleton.len() {
        if deforming.is_some_and(|d| !d[j]) {
            continue;
        }
        let start = skeleton.rest_position(j);
        let children = skeleton.children(j);
        if children.is_empty() {
            let end = match skeleton.parents()[j] {
                Some(p) => start + LEAF_FRACTION * (start - skeleton.rest_position(p)),
                None => start,
            };
            segments.push(Segment { joint: j as u16, start, end });
        } else {
            for &c in children {
                segments.push(Segment { joint: j as u16, start, end: skeleton.rest_position(c) });
            }
        }
    }
    segments
}

/// The diagonal of the positions' bounding box (1 for an empty or single-point mesh).
fn bounding_size(positions: &[Vec3]) -> f32 {
    let (lo, hi) = positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), &p| (l.min(p), h.max(p)));
    let size = (hi - lo).length();
    if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    }
}

/// The mesh with vertices at bitwise-equal positions merged (−0.0 counts as 0.0).
struct Welded {
    /// One position per unique vertex.
    positions: Vec<Vec3>,
    /// The triangles over unique vertices.
    indices: Vec<u32>,
    /// The unique vertex of each input vertex.
    unique_of: Vec<u32>,
}

impl Welded {
    fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let key = |p: Vec3| [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits(), (p.z + 0.0).to_bits()];
        let mut first = std::collections::HashMap::with_capacity(positions.len());
        let mut unique = Vec::with_capacity(positions.len());
        let unique_of: Vec<u32> = positions
            .iter()
            .map(|&p| {
                *first.entry(key(p)).or_insert_with(|| {
                    unique.push(p);
                    (unique.len() - 1) as u32
                })
            })
            .collect();
        let indices = indices.iter().map(|&i| unique_of[i as usize]).collect();
        Welded { positions: unique, indices, unique_of }
    }
}

/// Triangles bucketed in a uniform grid (about one cell per triangle), for segment tests.
struct TriangleGrid {
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// Triangles of cell c: `triangles[cell_start[c]..cell_start[c + 1]]`.
    cell_start: Vec<u32>,
    triangles: Vec<u32>,
    /// Query counter for `stamps` (a triangle is tested once per query).
    query: std::cell::Cell<u32>,
}

impl TriangleGrid {
    fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let (lo, hi) = positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), &p| (l.min(p), h.max(p)));
        let extent = (hi - lo).max(Vec3::splat(1e-6));
        let tris = (indices.len() / 3).max(1) as f32;
        let cell = (extent.x * extent.y * extent.z / tris).cbrt().max(extent.max_element() / 256.0);
        let dims = [0, 1, 2].map(|k| ((extent[k] / cell).ceil() as usize).clamp(1, 256));
        let cell_of = |p: Vec3| -> [usize; 3] {
            [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell).floor().max(0.0) as usize).min(dims[k] - 1))
        };
        let index = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
        let mut count = vec![0u32; dims[0] * dims[1] * dims[2] + 1];
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for (t, tri) in indices.chunks_exact(3).enumerate() {
                let p = [0, 1, 2].map(|k| positions[tri[k] as usize]);
                let (a, b) = (cell_of(p[0].min(p[1]).min(p[2])), cell_of(p[0].max(p[1]).max(p[2])));
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            f(index([x, y, z]), t as u32);
                        }
                    }
                }
            }
        };
        each(&mut |c, _| count[c + 1] += 1);
        for c in 1..count.len() {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        let mut triangles = vec![0u32; *count.last().unwrap_or(&0) as usize];
        each(&mut |c, t| {
            triangles[fill[c] as usize] = t;
            fill[c] += 1;
        });
        TriangleGrid { origin: lo, cell, dims, cell_start: count, triangles, query: std::cell::Cell::new(0) }
    }

    /// Whether the segment from vertex `from` (at `a`) to `b` crosses no triangle other than
    /// those `from` is a corner of (3D DDA through the cells, Möller–Trumbore per triangle).
    fn segment_is_clear(
        &self,
        positions: &[Vec3],
        indices: &[u32],
        from: u32,
        a: Vec3,
        b: Vec3,
        stamps: &mut [u32],
    ) -> bool {
        let query = self.query.get().wrapping_add(1);
        self.query.set(query);
        let d = b - a;
        let length = d.length();
        if length <= 0.0 {
            return true;
        }
        let start = (a - self.origin) / self.cell;
        let mut c = [0, 1, 2].map(|k| (start[k].floor().max(0.0) as usize).min(self.dims[k] - 1));
        let step = [0, 1, 2].map(|k| if d[k] > 0.0 { 1i64 } else { -1 });
        let t_delta = [0, 1, 2].map(|k| if d[k] != 0.0 { (self.cell / d[k]).abs() } else { f32::INFINITY });
        let mut t_max = [0, 1, 2].map(|k| {
            if d[k] == 0.0 {
                f32::INFINITY
            } else {
                let boundary = if d[k] > 0.0 { (c[k] + 1) as f32 } else { c[k] as f32 };
                ((self.origin[k] + boundary * self.cell) - a[k]) / d[k]
            }
        });
        loop {
            let cell = (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0];
            let range = self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize;
            for &t in &self.triangles[range] {
                if stamps[t as usize] == query {
                    continue;
                }
                stamps[t as usize] = query;
                let tri = &indices[3 * t as usize..3 * t as usize + 3];
                if tri.contains(&from) {
                    continue;
                }
                if let Some(h) = segment_hits_triangle(a, d, tri.iter().map(|&i| positions[i as usize])) {
                    if h > 1e-4 && h < 1.0 - 1e-4 {
                        return false;
                    }
                }
            }
            let k = if t_max[0] < t_max[1] {
                if t_max[0] < t_max[2] {
                    0
                } else {
                    2
                }
            } else if t_max[1] < t_max[2] {
                1
            } else {
                2
            };
            if t_max[k] > 1.0 {
                return true;
            }
            let next = c[k] as i64 + step[k];
            if next < 0 || next >= self.dims[k] as i64 {
                return true;
            }
            c[k] = next as usize;
            t_max[k] += t_delta[k];
        }
    }
}

/// The parameter h of a + h·d where it crosses the triangle, if it does (Möller–Trumbore).
fn segment_hits_triangle(a: Vec3, d: Vec3, mut corners: impl Iterator<Item = Vec3>) -> Option<f32> {
    let (p0, p1, p2) = (corners.next()?, corners.next()?, corners.next()?);
    let (e1, e2) = (p1 - p0, p2 - p0);
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() <= f32::EPSILON * e1.length_squared().max(e2.length_squared()) * d.length() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = a - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(qv) * inv)
}

/// A vertex's bones by distance: the visible ones, nearest first (all bones when none is
/// visible), each joint once at its nearest segment.
#[derive(Clone, Debug)]
struct Nearest {
    /// (joint, distance), nearest first, at most [`REGION_BONES`].
    joints: Vec<(u16, f32)>,
    /// The same, visible or not.
    any: Vec<(u16, f32)>,
}

fn nearest_bones(p: Vec3, normal: Vec3, bones: &[Segment], size: f32) -> Nearest {
    let mut visible: Vec<(u16, f32)> = Vec::new();
    let mut all: Vec<(u16, f32)> = Vec::new();
    for s in bones {
        let q = s.nearest_point(p);
        let d = (p - q).length().max(MIN_DISTANCE_FRACTION * size);
        insert_nearest(&mut all, s.joint, d);
        if (p - q).dot(normal) > 0.0 {
            insert_nearest(&mut visible, s.joint, d);
        }
    }
    let joints = if visible.is_empty() { all.clone() } else { visible };
    Nearest { joints, any: all }
}

/// Keeps `list` the nearest [`REGION_BONES`] joints, each once, sorted by distance.
fn insert_nearest(list: &mut Vec<(u16, f32)>, joint: u16, d: f32) {
    if let Some(k) = list.iter().position(|&(j, _)| j == joint) {
        if list[k].1 <= d {
            return;
        }
        list.remove(k);
    }
    let at = list.iter().position(|&(_, e)| d < e).unwrap_or(list.len());
    if at < REGION_BONES {
        list.insert(at, (joint, d));
        list.truncate(REGION_BONES);
    }
}

type VertexInfluences = ([u16; 4], [f32; 4]);

fn envelope_weights(nearest: &Nearest, parents: &[Option<usize>]) -> VertexInfluences {
    let (j1, d1) = nearest.joints[0];
    let adjacent = |j: u16| {
        let (a, b) = (usize::from(j), usize::from(j1));
        a == b || parents[a] == Some(b) || parents[b] == Some(a)
    };
    let raw: Vec<(u16, f32)> = nearest
        .joints
        .iter()
        .filter(|&&(j, _)| adjacent(j))
        .take(MAX_BOUND_INFLUENCES)
        .map(|&(j, d)| (j, (d1 / d).powi(ENVELOPE_DROPOFF)))
        .collect();
    let total: f32 = raw.iter().map(|x| x.1).sum();
    let (mut js, mut ws) = ([0u16; 4], [0.0f32; 4]);
    let mut k = 0;
    for (j, w) in raw {
        if w >= ENVELOPE_MIN_WEIGHT * total {
            js[k] = j;
            ws[k] = w;
            k += 1;
        }
    }
    (js, ws)
}

/// A symmetric sparse matrix in compressed rows (every row lists its diagonal too), f32: the
/// weights need about three digits, and halving the bytes each iteration reads is what makes
/// the solve fast (it is bound by memory traffic).
struct Csr {
    row_start: Vec<u32>,
    columns: Vec<u32>,
    values: Vec<f32>,
    /// Where each row's diagonal entry is (columns are sorted within a row).
    diagonal_at: Vec<u32>,
    /// 1 / the diagonal.
    inverse_diagonal: Vec<f32>,
}

impl Csr {
    /// (M·x)_i for one row, reading x at every column (zero outside the rows being solved).
    #[inline]
    fn row_times(&self, i: usize, x: &[f32]) -> f32 {
        let range = self.row_start[i] as usize..self.row_start[i + 1] as usize;
        let mut s = 0.0f32;
        for (&c, &v) in self.columns[range.clone()].iter().zip(&self.values[range]) {
            s += v * x[c as usize];
        }
        s
    }

    /// z = M⁻¹·r for the symmetric successive over-relaxation (SSOR) preconditioner
    /// M ∝ (D/ω + L)·(D/ω)⁻¹·(D/ω + Lᵀ), on the `rows` listed (ascending; z is zero elsewhere):
    /// a forward Gauss–Seidel sweep, then a backward one, in place.
    fn ssor(&self, rows: &[u32], r: &[f32], z: &mut [f32]) {
        for &i in rows {
            let i = i as usize;
            let range = self.row_start[i] as usize..self.diagonal_at[i] as usize;
            let mut s = r[i];
            for (&c, &v) in self.columns[range.clone()].iter().zip(&self.values[range]) {
                s -= v * z[c as usize];
            }
            z[i] = SSOR_OMEGA * s * self.inverse_diagonal[i];
        }
        for &i in rows.iter().rev() {
            let i = i as usize;
            let range = self.diagonal_at[i] as usize + 1..self.row_start[i + 1] as usize;
            let mut s = 0.0f32;
            for (&c, &v) in self.columns[range.clone()].iter().zip(&self.values[range]) {
                s += v * z[c as usize];
            }
            z[i] -= SSOR_OMEGA * s * self.inverse_diagonal[i];
        }
    }
}

/// The cotangent Laplacian L (positive semi-definite) and the barycentric vertex areas.
fn cotangent_laplacian(positions: &[Vec3], indices: &[u32], size: f32) -> (Vec<(u32, u32, f64)>, Vec<f64>) {
    let n = positions.len();
    let min_area = DEGENERATE_AREA_FRACTION * f64::from(size) * f64::from(size);
    let mut areas = vec![0.0f64; n];
    let mut edges: Vec<(u32, u32, f64)> = Vec::with_capacity(indices.len());
    for tri in indices.chunks_exact(3) {
        let v = [tri[0], tri[1], tri[2]];
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            continue;
        }
        let p = v.map(|i| positions[i as usize].as_dvec3());
        let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
        if twice_area.is_nan() || 0.5 * twice_area < min_area {
            continue;
        }
        for k in 0..3 {
            areas[v[k] as usize] += twice_area / 6.0;
            // The angle at corner k is opposite edge (k+1, k+2).
            let (i, j) = (v[(k + 1) % 3], v[(k + 2) % 3]);
            let (a, b): (DVec3, DVec3) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let cot = (a.dot(b) / twice_area).clamp(0.0, COT_MAX);
            edges.push((i.min(j), i.max(j), 0.5 * cot));
        }
    }
    (edges, areas)
}

/// Assembles L + diag(shift) in compressed rows from L's edge weights (an edge may repeat).
fn assemble(n: usize, mut edges: Vec<(u32, u32, f64)>, shift: &[f64]) -> Csr {
    edges.sort_unstable_by_key(|&(i, j, _)| (i, j));
    let mut merged: Vec<(u32, u32, f64)> = Vec::with_capacity(edges.len());
    for (i, j, w) in edges {
        match merged.last_mut() {
            Some(last) if last.0 == i && last.1 == j => last.2 += w,
            _ => merged.push((i, j, w)),
        }
    }
    let mut diagonal = shift.to_vec();
    let mut count = vec![1usize; n];
    for &(i, j, w) in &merged {
        diagonal[i as usize] += w;
        diagonal[j as usize] += w;
        count[i as usize] += 1;
        count[j as usize] += 1;
    }
    let mut row_start: Vec<u32> = Vec::with_capacity(n + 1);
    row_start.push(0);
    for c in &count {
        row_start.push(row_start.last().copied().unwrap_or(0) + *c as u32);
    }
    let nnz = row_start[n] as usize;
    let mut columns = vec![0u32; nnz];
    let mut values = vec![0.0f32; nnz];
    let mut fill: Vec<usize> = row_start[..n].iter().map(|&r| r as usize).collect();
    let mut put = |r: usize, c: u32, v: f64, fill: &mut Vec<usize>| {
        columns[fill[r]] = c;
        values[fill[r]] = v as f32;
        fill[r] += 1;
    };
    for (i, &d) in diagonal.iter().enumerate() {
        put(i, i as u32, d, &mut fill);
    }
    for &(i, j, w) in &merged {
        put(i as usize, j, -w, &mut fill);
        put(j as usize, i, -w, &mut fill);
    }
    // Columns in increasing order: the entries before the diagonal are the strictly lower
    // triangle (the forward sweep of the preconditioner), those after it the upper.
    let mut diagonal_at = vec![0u32; n];
    let mut row: Vec<(u32, f32)> = Vec::new();
    for i in 0..n {
        let range = row_start[i] as usize..row_start[i + 1] as usize;
        row.clear();
        row.extend(columns[range.clone()].iter().copied().zip(values[range.clone()].iter().copied()));
        row.sort_unstable_by_key(|e| e.0);
        for (k, (c, v)) in range.zip(&row) {
            columns[k] = *c;
            values[k] = *v;
            if *c as usize == i {
                diagonal_at[i] = k as u32;
            }
        }
    }
    let inverse_diagonal = diagonal.iter().map(|&d| (1.0 / d) as f32).collect();
    Csr { row_start, columns, values, diagonal_at, inverse_diagonal }
}

/// Jacobi-preconditioned conjugate gradients for a symmetric positive definite `m`, on the
/// `rows` listed (the unknowns elsewhere are held at 0: a Dirichlet boundary), from the initial
/// guess in `x` (zero outside `rows`). Returns the iterations taken.
///
/// `scratch` vectors must be zero outside `rows` (they are left so).
fn conjugate_gradients(m: &Csr, rows: &[u32], b: &[f32], x: &mut [f32], scratch: &mut CgScratch) -> usize {
    let CgScratch { r, z, p, q } = scratch;
    let (mut b_norm2, mut r2) = (0.0f64, 0.0f64);
    for &i in rows {
        let i = i as usize;
        r[i] = b[i] - m.row_times(i, x);
        b_norm2 += f64::from(b[i]) * f64::from(b[i]);
        r2 += f64::from(r[i]) * f64::from(r[i]);
    }
    m.ssor(rows, r, z);
    let mut rz = 0.0f64;
    for &i in rows {
        let i = i as usize;
        p[i] = z[i];
        rz += f64::from(r[i]) * f64::from(z[i]);
    }
    let stop2 = CG_TOLERANCE * CG_TOLERANCE * b_norm2;
    for iteration in 0..CG_MAX_ITERATIONS {
        if r2 <= stop2 || rz <= 0.0 {
            return iteration;
        }
        let mut pq = 0.0f64;
        for &i in rows {
            let i = i as usize;
            q[i] = m.row_times(i, p);
            pq += f64::from(p[i]) * f64::from(q[i]);
        }
        if pq <= 0.0 {
            return iteration;
        }
        let alpha = (rz / pq) as f32;
        r2 = 0.0;
        for &i in rows {
            let i = i as usize;
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            r2 += f64::from(r[i]) * f64::from(r[i]);
        }
        m.ssor(rows, r, z);
        let mut rz_next = 0.0f64;
        for &i in rows {
            let i = i as usize;
            rz_next += f64::from(r[i]) * f64::from(z[i]);
        }
        let beta = (rz_next / rz) as f32;
        rz = rz_next;
        for &i in rows {
            let i = i as usize;
            p[i] = z[i] + beta * p[i];
        }
    }
    CG_MAX_ITERATIONS
}

struct CgScratch {
    r: Vec<f32>,
    z: Vec<f32>,
    p: Vec<f32>,
    q: Vec<f32>,
}

fn heat_weights(welded: &Welded, nearest: &[Nearest], size: f32) -> Vec<VertexInfluences> {
    let n = welded.positions.len();
    let (edges, areas) = cotangent_laplacian(&welded.positions, &welded.indices, size);
    // A·H on the diagonal, and which joints share each vertex's nearest distance. A vertex in
    // no triangle (area 0) has no edges either: its row is 1·w = p.
    let mut shift = vec![0.0f64; n];
    let mut sources: Vec<Vec<(u16, f32)>> = Vec::with_capacity(n);
    for (i, near) in nearest.iter().enumerate() {
        let d1 = near.joints[0].1;
        let tied: Vec<u16> =
            near.joints.iter().filter(|&&(_, d)| d <= d1 * (1.0 + TIE_EPSILON)).map(|&(j, _)| j).collect();
        let share = 1.0 / tied.len() as f32;
        sources.push(tied.into_iter().map(|j| (j, share)).collect());
        let h = HEAT_C / (f64::from(d1) * f64::from(d1));
        shift[i] = if areas[i] > 0.0 { areas[i] * h } else { 1.0 };
    }
    let m = assemble(n, edges, &shift);
    // Each joint is solved where it is among a vertex's REGION_BONES nearest bones, visible or
    // not; elsewhere its weight is held at 0 (it is rarely among the four largest there).
    let joint_count = nearest
        .iter()
        .flat_map(|near| near.joints.iter().chain(&near.any).map(|&(j, _)| usize::from(j) + 1))
        .max()
        .unwrap_or(0);
    let mut regions: Vec<Vec<u32>> = vec![Vec::new(); joint_count];
    for (i, near) in nearest.iter().enumerate() {
        for &(j, _) in &near.any {
            regions[usize::from(j)].push(i as u32);
        }
        for &(j, _) in &near.joints {
            if !near.any.iter().any(|a| a.0 == j) {
                regions[usize::from(j)].push(i as u32);
            }
        }
    }
    let mut best: Vec<VertexInfluences> = vec![([0; 4], [0.0; 4]); n];
    let (mut b, mut x) = (vec![0.0f32; n], vec![0.0f32; n]);
    let mut scratch = CgScratch { r: vec![0.0; n], z: vec![0.0; n], p: vec![0.0; n], q: vec![0.0; n] };
    for (joint, rows) in regions.iter().enumerate() {
        let joint = joint as u16;
        let is_source = |i: usize| sources[i].iter().find(|s| s.0 == joint).map_or(0.0, |s| s.1);
        if rows.iter().all(|&i| is_source(i as usize) == 0.0) {
            continue;
        }
        for &i in rows {
            let i = i as usize;
            let p = is_source(i);
            b[i] = (shift[i] * f64::from(p)) as f32;
            x[i] = p;
        }
        conjugate_gradients(&m, rows, &b, &mut x, &mut scratch);
        for &i in rows {
            let i = i as usize;
            keep_largest(&mut best[i], joint, x[i]);
            (b[i], x[i], scratch.r[i], scratch.z[i], scratch.p[i], scratch.q[i]) =
                (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        }
    }
    // Every vertex has weight from its nearest bone (p > 0 there); a solve that lost it to
    // round-off falls back to that bone.
    for (slot, near) in best.iter_mut().zip(nearest) {
        if slot.1.iter().sum::<f32>() <= 0.0 {
            *slot = ([near.joints[0].0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]);
        }
    }
    best
}

/// Puts (joint, w) into the four largest weights of a vertex when it is larger than the least.
fn keep_largest(slot: &mut VertexInfluences, joint: u16, w: f32) {
    if w.is_nan() || w <= 0.0 {
        return;
    }
    let (js, ws) = slot;
    let least = (1..4).fold(0, |m, k| if ws[k] < ws[m] { k } else { m });
    if w > ws[least] {
        js[least] = joint;
        ws[least] = w;
    }
}

/// Binding lives here, not in `mesh`, so that `mesh` does not import `bind` (which builds on
/// `mesh`'s normals and tubes): no module import cycle.
impl crate::mesh::SkinnedMesh {
    /// The mesh with weights computed from its rest positions and skeleton by [`BindJob`]
    /// (docs/binding.md) in place of its own; `deforming` (one flag per joint, `None`: all)
    /// says which joints may get weight. The single weights are dropped, so
    /// [`crate::SkinnedMesh::bindings`] derives the rigid and bones-blending bindings from the new
    /// weights.
    ///
    /// ```
    /// use keyrig_skin::{BindJob, BindMethod};
    ///
    /// let arm = keyrig_skin::mesh_for(keyrig_core::ProceduralMesh::ArmHighPoly);
    /// let job = BindJob::new(&arm.positions, &arm.indices, &arm.skeleton, BindMethod::Envelope);
    /// let influences = job.run()?; // one (joints, weights) per vertex, validated
    /// assert_eq!(influences.len(), arm.positions.len());
    /// // Or the whole mesh, its single weights dropped so that bindings() follow the new weights:
    /// let arm = arm.rebound(BindMethod::Heat, None)?;
    /// let bindings = arm.bindings(keyrig_skin::BlendZone::default())?;
    /// assert_eq!(bindings.rigid.len(), 1250);
    /// # Ok::<(), keyrig_skin::SkinError>(())
    /// ```
    ///
    /// # Errors
    /// As [`BindJob::validate`].
    pub fn rebound(mut self, method: BindMethod, deforming: Option<&[bool]>) -> Result<Self, SkinError> {
        let job =
            BindJob { deforming, ..BindJob::new(&self.positions, &self.indices, &self.skeleton, method) };
        self.influences = job.run()?;
        self.bones = None;
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::RestJoint;
    use glam::Quat;

    /// A chain of `bones` joints along +X, `length` apart.
    fn chain(bones: usize, length: f32) -> RestSkeleton {
        let joints: Vec<RestJoint> = (0..bones)
            .map(|j| {
                let t = if j == 0 { Vec3::ZERO } else { Vec3::X * length };
                RestJoint::new(format!("j{j}"), j.checked_sub(1), t, Quat::IDENTITY)
            })
            .collect();
        RestSkeleton::new(&joints).unwrap()
    }

    /// A closed tube along +X from 0 to `length`, radius 1.
    fn tube(rings: usize, sides: usize, length: f32) -> (Vec<Vec3>, Vec<u32>) {
        crate::mesh::tube_mesh(rings, sides, length, 1.0)
    }

    #[test]
    fn every_method_gives_normalised_weights_that_follow_the_nearest_bone() {
        let skeleton = chain(3, 4.0);
        let (positions, indices) = tube(41, 16, 12.0);
        for method in BindMethod::ALL {
            let influences = BindJob::new(&positions, &indices, &skeleton, method).run().unwrap();
            assert_eq!(influences.len(), positions.len());
            for (v, (js, ws)) in influences.joints().iter().zip(influences.weights()).enumerate() {
                let x = positions[v].x;
                let dominant = js[(0..4).fold(0, |m, k| if ws[k] > ws[m] { k } else { m })];
                // Mid-bone vertices belong to their bone.
                let expected = if (1.0..3.0).contains(&x) {
                    Some(0)
                } else if (5.0..7.0).contains(&x) {
                    Some(1)
                } else if x > 9.0 {
                    Some(2)
                } else {
                    None
                };
                if let Some(e) = expected {
                    assert_eq!(dominant, e, "{method:?}: vertex {v} at x = {x}: {js:?} {ws:?}");
                }
            }
        }
    }

    #[test]
    fn heat_weights_blend_smoothly_across_a_joint() {
        let skeleton = chain(2, 5.0);
        let (positions, indices) = tube(51, 16, 10.0);
        let influences = BindJob::new(&positions, &indices, &skeleton, BindMethod::Heat).run().unwrap();
        // The weight of joint 1 along the tube: 0 at the start, 1 at the end, ½ at the joint,
        // rising monotonically.
        let mut profile: Vec<(f32, f32)> = Vec::new();
        for (v, (js, ws)) in influences.joints().iter().zip(influences.weights()).enumerate() {
            let w1: f32 = js.iter().zip(ws).filter(|(j, _)| **j == 1).map(|(_, w)| *w).sum();
            profile.push((positions[v].x, w1));
        }
        profile.sort_by(|a, b| a.0.total_cmp(&b.0));
        let at = |x: f32| {
            let near: Vec<f32> = profile.iter().filter(|p| (p.0 - x).abs() < 0.11).map(|p| p.1).collect();
            near.iter().sum::<f32>() / near.len() as f32
        };
        assert!(at(1.0) < 0.02, "{}", at(1.0));
        // x = 9 lies past the leaf bone (5 to 6.25), where joint 0 still leaks in a little.
        assert!(at(9.0) > 0.9, "{}", at(9.0));
        assert!((at(5.0) - 0.5).abs() < 0.05, "{}", at(5.0));
        assert!(at(4.0) > 0.05 && at(4.0) < 0.5, "blends before the joint: {}", at(4.0));
        for x in 1..10 {
            assert!(at(x as f32 + 0.2) >= at(x as f32 - 0.2) - 1e-3, "monotone near {x}");
        }
    }

    #[test]
    fn seams_islands_degenerate_triangles_and_lone_vertices_still_bind() {
        let skeleton = chain(2, 5.0);
        let (mut positions, mut indices) = tube(21, 8, 10.0);
        // A second island: a copy shifted sideways, with its vertices duplicated at a "seam"
        // (a second copy of one ring used by half its triangles).
        let base = positions.len() as u32;
        let copy: Vec<Vec3> = positions.iter().map(|p| *p + Vec3::Y * 5.0).collect();
        positions.extend(&copy);
        let seam_start = positions.len() as u32;
        positions.extend(copy[80..88].iter().copied());
        let mut second: Vec<u32> = indices.iter().map(|i| i + base).collect();
        for (k, i) in second.iter_mut().enumerate() {
            if k % 2 == 0 && (base + 80..base + 88).contains(i) {
                *i = seam_start + (*i - base - 80);
            }
        }
        indices.extend(second);
        // A degenerate triangle and a zero-area one, and a vertex in no triangle.
        indices.extend([0, 0, 1, 0, 1, 1]);
        positions.push(Vec3::new(9.0, 0.0, 0.0));
        for method in BindMethod::ALL {
            let influences = BindJob::new(&positions, &indices, &skeleton, method).run().unwrap();
            // Welded vertices agree exactly.
            for k in 0..8 {
                let (a, b) = ((base + 80 + k) as usize, (seam_start + k) as usize);
                assert_eq!(influences.joints()[a], influences.joints()[b], "{method:?}");
                assert_eq!(influences.weights()[a], influences.weights()[b], "{method:?}");
            }
            let lone = positions.len() - 1;
            assert_eq!(influences.joints()[lone][0], 1, "{method:?}: the lone vertex follows joint 1");
        }
    }

    #[test]
    fn non_deforming_joints_get_no_weight() {
        let skeleton = chain(3, 4.0);
        let (positions, indices) = tube(21, 8, 12.0);
        let deforming = [false, true, true];
        for method in BindMethod::ALL {
            let job = BindJob {
                deforming: Some(&deforming),
                ..BindJob::new(&positions, &indices, &skeleton, method)
            };
            let influences = job.run().unwrap();
            for (js, ws) in influences.joints().iter().zip(influences.weights()) {
                for (j, w) in js.iter().zip(ws) {
                    assert!(*j != 0 || *w == 0.0, "{method:?}: {js:?} {ws:?}");
                }
            }
        }
    }

    #[test]
    fn a_segment_is_clear_inside_the_mesh_and_blocked_through_it() {
        let (positions, indices) = tube(21, 16, 10.0);
        let grid = TriangleGrid::new(&positions, &indices);
        let mut stamps = vec![0u32; indices.len() / 3];
        // Vertex 8·16 + 4 (ring 8, angle 90°) is at (4, 0, 1).
        let v = 8 * 16 + 4;
        let p = positions[v];
        assert!((p - Vec3::new(4.0, 0.0, 1.0)).length() < 1e-5, "{p}");
        let mut clear = |to: Vec3| grid.segment_is_clear(&positions, &indices, v as u32, p, to, &mut stamps);
        // To the axis and to points inside: clear.
        assert!(clear(Vec3::new(4.0, 0.0, 0.0)));
        assert!(clear(Vec3::new(7.5, 0.3, -0.5)));
        // Through the far wall, or out past the end cap: blocked.
        assert!(!clear(Vec3::new(4.0, 0.0, -3.0)));
        assert!(!clear(Vec3::new(12.0, 0.0, 0.0)));
        // Outwards through the vertex's own triangles only: the ray test does not see it (the
        // normal test does).
        assert!(clear(Vec3::new(4.0, 0.0, 3.0)));
    }

    #[test]
    fn bad_inputs_are_named() {
        let skeleton = chain(2, 1.0);
        let positions = [Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)];
        let job = BindJob::new(&positions, &[0, 1, 2], &skeleton, BindMethod::Heat);
        assert_eq!(job.run().unwrap_err(), SkinError::NonFiniteVertex { vertex: 2, what: "position" });
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let job = BindJob::new(&positions, &[0, 1, 3], &skeleton, BindMethod::Heat);
        assert!(matches!(job.run(), Err(SkinError::TriangleIndexOutOfRange { triangle: 0, index: 3, .. })));
        let job = BindJob {
            deforming: Some(&[false, false]),
            ..BindJob::new(&positions, &[0, 1, 2], &skeleton, BindMethod::Envelope)
        };
        assert_eq!(job.run().unwrap_err(), SkinError::NoDeformingJoint);
        let job = BindJob {
            deforming: Some(&[true]),
            ..BindJob::new(&positions, &[0, 1, 2], &skeleton, BindMethod::Envelope)
        };
        assert!(matches!(job.run(), Err(SkinError::LengthMismatch { .. })));
        assert!(BindJob::new(&[], &[], &skeleton, BindMethod::Heat).run().unwrap().is_empty());
    }
}
