//! The node tree mapped onto keyrig: shapes → objects with meshes, lights, viewpoints → scene
//! cameras, and `TimeSensor` → interpolator → `ROUTE` chains → keyrig tracks (also of
//! viewpoints, materials and spot cones).
//!
//! **Objects.** Every Shape instance (a Shape reached through `USE` twice is two instances)
//! becomes one object named after the nearest `DEF` (the Shape's own, else the nearest
//! enclosing grouping node's, else its geometry's), its mesh `MeshSource::File { path, mesh }`
//! with `mesh` the index into [`VrmlModel::meshes`]. Where it sits:
//! - no animated Transform above it: the object carries the static world transform (decomposed
//!   into translation, rotation and scale when that is exact, else baked into the vertices);
//! - one animated Transform, directly at the scene root (nothing static above it), without
//!   `center` or a `scaleOrientation` that matters: its fields become the object's own
//!   translation, rotation and scale tracks, the static Transforms below it are baked into the
//!   vertices;
//! - otherwise a skeleton: one joint per Transform from the first animated one to the last
//!   (a Transform with `center` or `scaleOrientation` becomes two or three joints whose
//!   product is VRML's `T·C·R·SR·S·−SR·−C`), every joint's rest transform the identity so
//!   that its channels are the file's field values, the mesh bound rigidly to the last joint.
//!
//! **Animation.** A `TimeSensor`'s `fraction_changed` routed to an interpolator's
//! `set_fraction`, and the interpolator's `value_changed` routed to a field keyrig holds,
//! gives a track: key `kᵢ` at time `kᵢ·cycleInterval`, keys at 0 and at `cycleInterval` added
//! (holding the first and last values, as VRML holds outside the keys) so that a looping
//! sensor repeats with period `cycleInterval` ([`keyrig_core::Cycle::Repeat`]). Position,
//! scalar and coordinate interpolators are linear and orientation interpolators slerp the
//! short way — keyrig's [`keyrig_core::Interpolation::Linear`] keys, exactly. Colour
//! interpolators blend in HSV: they are resampled into linear RGB keys within
//! [`COLOUR_TOLERANCE`]. A `CoordinateInterpolator` on a shape's `Coordinate` makes that shape
//! a vertex-morphing mesh (its keys are the morph frames, at their own times), as an MD2 model
//! plays. X3D's spline and squad interpolators are converted in [`super::splines`].
//!
//! Everything the mapping does not take is listed in [`VrmlModel::skipped`] with where it is.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::sync::Arc;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use keyrig_core::{Animated, Cycle, Interpolation, Key, Material, RawTrack};

use super::expand::base_field;
use super::geometry::{self, PolyMesh, Solid, Tessellation};
use super::splines;
use super::tree::{Document, Encoding, NodeId, Place, Value};
use super::{VrmlError, VrmlErrorKind};

/// Largest difference (per RGB channel, 0..1) between a resampled colour track and the HSV
/// interpolation it stands for.
pub const COLOUR_TOLERANCE: f32 = 1e-3;
/// Most Shape, light and view instances a DEF/USE graph may expand to.
pub const MAX_INSTANCES: usize = 1_000_000;
/// Timeline rate of an imported scene.
pub const FPS: f64 = 30.0;

/// Something in the file the mapping did not take, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// The node type or feature (`Script`, `TouchSensor`, `Inline`, `emissiveColor`, …).
    pub what: String,
    /// Why, or what was done instead.
    pub why: String,
    /// `file:line:column` of the first occurrence.
    pub place: Option<String>,
    /// How many times it occurs.
    pub count: usize,
}

impl std::fmt::Display for Skipped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.what)?;
        if self.count > 1 {
            write!(f, " (×{})", self.count)?;
        }
        if let Some(p) = &self.place {
            write!(f, " at {p}")?;
        }
        write!(f, ": {}", self.why)
    }
}

/// Vertex animation of a mesh: the frames (one per key of the `CoordinateInterpolator`) at
/// their times, linear between them, repeating every `period` seconds when the sensor loops.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphKeys {
    pub times: Vec<f64>,
    pub period: Option<f64>,
    pub frames: Vec<geometry::Frame>,
}

/// One mesh of the file as keyrig draws it.
#[derive(Clone, Debug)]
pub struct VrmlMesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// keyrig's convention (origin top-left).
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<u32>,
    pub material: Material,
    /// The joints of the object's skeleton (the mesh is bound to the last); one `root` joint
    /// for an object without a skeleton.
    pub joints: Vec<String>,
    pub morph: Option<MorphKeys>,
    /// The point of the file's Coordinate each vertex shows (polygon meshes; `None` for
    /// primitives).
    pub vertex_points: Option<Vec<u32>>,
    /// The static transform applied to the file's points (the Transforms below the object's
    /// own place, or all of them when they cannot be the object's transform).
    pub baked: Mat4,
}

/// A `Viewpoint` (or Inventor camera) at rest, in world space; [`VrmlModel::cameras`] holds it
/// as a keyrig scene camera with its animation.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub name: String,
    pub position: Vec3,
    pub orientation: Quat,
    /// Radians.
    pub field_of_view: f32,
    /// The height of the view of an orthographic camera (`OrthoViewpoint`, Inventor's
    /// `OrthographicCamera`), scene units.
    pub orthographic: Option<f32>,
}

/// A whole imported VRML/X3D/Inventor file.
#[derive(Clone, Debug)]
pub struct VrmlModel {
    pub encoding: Encoding,
    /// Objects with `MeshSource::File { path: "", mesh: Some(i) }`; [`VrmlModel::to_scene`]
    /// fills in the path.
    pub objects: Vec<keyrig_core::Object>,
    pub meshes: Vec<VrmlMesh>,
    pub lights: Vec<keyrig_core::Light>,
    pub views: Vec<View>,
    /// The views as scene cameras (`camera/<name>/…` channels), with the animation of their
    /// `position`, `orientation` and `fieldOfView`; the first is the one VRML binds first.
    pub cameras: Vec<keyrig_core::SceneCamera>,
    /// Seconds of animation (the longest cycle); 0 without animation.
    pub duration: f64,
    pub skipped: Vec<Skipped>,
    /// keyrig's own scene, when the file is a keyrig export carrying it as metadata
    /// ([`super::tree::METADATA_TAG`]); its rate, range, ambient light and camera are the
    /// mapped scene's.
    pub metadata_scene: Option<keyrig_core::Scene>,
}

/// The mesh source of a skinned object of keyrig's own scene (read from an export's metadata)
/// as it can be used again: procedural meshes and none as they are, a model file when it is
/// there (a relative path taken from `file`'s folder); `None` when the file is missing.
fn mesh_again(mesh: Option<&keyrig_core::MeshSource>, file: &str) -> Option<Option<keyrig_core::MeshSource>> {
    match mesh {
        None => Some(None),
        Some(keyrig_core::MeshSource::File { path, mesh, clip, fps }) => {
            let found = std::path::Path::new(path);
            let found = if found.is_absolute() {
                found.to_path_buf()
            } else {
                std::path::Path::new(file).parent().unwrap_or(std::path::Path::new("")).join(found)
            };
            found.is_file().then(|| {
                Some(keyrig_core::MeshSource::File {
                    path: found.to_string_lossy().into_owned(),
                    mesh: *mesh,
                    clip: clip.clone(),
                    fps: *fps,
                })
            })
        }
        Some(source) => Some(Some(source.clone())),
    }
}

/// Why a mesh could not become a keyrig-skin mesh.
#[derive(Debug, thiserror::Error)]
pub enum VrmlMeshError {
    #[error("no mesh {0} in the file")]
    NoSuchMesh(usize),
    #[error(transparent)]
    Skin(#[from] keyrig_skin::SkinError),
}

impl VrmlModel {
    /// The model as a keyrig scene at 30 fps, its frame range the longest cycle (one second
    /// without animation), mesh paths `file`; the camera from the first view.
    #[must_use]
    pub fn to_scene(&self, file: &str) -> keyrig_core::Scene {
        let mut scene = keyrig_core::Scene { fps: FPS, ..keyrig_core::Scene::default() };
        if self.duration > 0.0 {
            let end = (self.duration * FPS - 1e-9).ceil();
            scene.frame_range.end = if end.is_finite() { end.clamp(1.0, 1e6) as i32 } else { 60 };
        }
        scene.objects = self.objects.clone();
        for o in &mut scene.objects {
            if let Some(keyrig_core::MeshSource::File { path, .. }) = &mut o.mesh {
                *path = file.to_owned();
            }
        }
        scene.lights = self.lights.clone();
        if let Some(view) = self.views.first() {
            scene.camera = self.camera_of(view);
        }
        scene.cameras = self.cameras.clone();
        if let Some(original) = &self.metadata_scene {
            scene.fps = original.fps;
            scene.frame_range = original.frame_range;
            scene.ambient = original.ambient;
            scene.camera = original.camera;
            scene.cameras.clone_from(&original.cameras);
            scene.active_camera.clone_from(&original.active_camera);
            scene.markers.clone_from(&original.markers);
            // A skinned object was written as the meshes its deformer made; it comes back
            // whole — skeleton, deformer and keys — when its mesh can be had again (procedural,
            // or its model file is there), else as that vertex animation.
            for object in &mut scene.objects {
                let Some(whole) =
                    original.objects.iter().find(|x| x.name == object.name && x.skeleton.is_some())
                else {
                    continue;
                };
                if let Some(mesh) = mesh_again(whole.mesh.as_ref(), file) {
                    *object = keyrig_core::Object { mesh, ..whole.clone() };
                }
            }
        }
        scene
    }

    /// The orbit camera that looks as `view` does, its target at the distance of the scene's
    /// centre along the view.
    #[must_use]
    pub fn camera_of(&self, view: &View) -> keyrig_core::Camera {
        let forward = (view.orientation * -Vec3::Z).normalize_or(-Vec3::Z);
        let (lo, hi) = self.bounds();
        let centre = if lo.cmple(hi).all() { (lo + hi) * 0.5 } else { Vec3::ZERO };
        let along = (centre - view.position).dot(forward);
        let distance = if along > 1e-3 { along } else { (centre - view.position).length().max(1.0) };
        let back = -forward;
        keyrig_core::Camera {
            target: view.position + forward * distance,
            yaw_deg: back.x.atan2(back.z).to_degrees(),
            pitch_deg: back.y.clamp(-1.0, 1.0).asin().to_degrees(),
            distance,
            fov_y_deg: view.field_of_view.to_degrees().clamp(1.0, 170.0),
        }
    }

    /// World bounds of every mesh at rest.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut b = (Vec3::MAX, Vec3::MIN);
        for o in &self.objects {
            let Some(keyrig_core::MeshSource::File { mesh: Some(m), .. }) = &o.mesh else { continue };
            let Some(mesh) = self.meshes.get(*m) else { continue };
            let world = Mat4::from_scale_rotation_translation(
                o.scale.value,
                o.rotation.value.normalize(),
                o.translation.value,
            );
            for p in &mesh.positions {
                let p = world.transform_point3(*p);
                b = (b.0.min(p), b.1.max(p));
            }
        }
        b
    }

    /// Mesh `index` as a keyrig-skin mesh bound rigidly to the last joint of
    /// [`VrmlMesh::joints`] (rest transforms the identity: positions are in that joint's
    /// space), with its texture coordinates.
    ///
    /// # Errors
    /// No such mesh, or keyrig-skin refuses it.
    pub fn skinned_mesh(&self, index: usize) -> Result<keyrig_skin::SkinnedMesh, VrmlMeshError> {
        let mesh = self.meshes.get(index).ok_or(VrmlMeshError::NoSuchMesh(index))?;
        let rest: Vec<keyrig_skin::RestJoint> = mesh
            .joints
            .iter()
            .enumerate()
            .map(|(j, name)| {
                keyrig_skin::RestJoint::new(name.clone(), j.checked_sub(1), Vec3::ZERO, Quat::IDENTITY)
            })
            .collect();
        let skeleton = keyrig_skin::RestSkeleton::new(&rest)?;
        let last = (mesh.joints.len().max(1) - 1) as u16;
        let n = mesh.positions.len();
        let skinned = keyrig_skin::SkinnedMesh::new(
            mesh.positions.clone(),
            mesh.normals.clone(),
            mesh.indices.clone(),
            vec![[last, 0, 0, 0]; n],
            vec![[1.0, 0.0, 0.0, 0.0]; n],
            Some(vec![last; n]),
            skeleton,
        )?;
        Ok(match &mesh.uvs {
            Some(uvs) => skinned.with_uvs(uvs.clone())?,
            None => skinned,
        })
    }

    /// What `keyrig info` and the editor's import message list: one line per kind of thing not
    /// imported.
    #[must_use]
    pub fn skipped_lines(&self) -> Vec<String> {
        self.skipped.iter().map(ToString::to_string).collect()
    }
}

// ---------------------------------------------------------------------------------------
// Field access

fn numbers<'a>(doc: &'a Document, id: NodeId, name: &str) -> Option<&'a [f64]> {
    doc.node(id).value(name).and_then(Value::numbers)
}

fn float(doc: &Document, id: NodeId, name: &str, default: f32) -> f32 {
    match numbers(doc, id, name) {
        Some([v, ..]) if v.is_finite() => *v as f32,
        _ => default,
    }
}

fn vec3(doc: &Document, id: NodeId, name: &str, default: Vec3) -> Vec3 {
    match numbers(doc, id, name) {
        Some([x, y, z, ..]) => {
            let v = Vec3::new(*x as f32, *y as f32, *z as f32);
            if v.is_finite() {
                v
            } else {
                default
            }
        }
        _ => default,
    }
}

fn axis_angle(v: &[f64]) -> Quat {
    let axis = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    let angle = v[3];
    match axis.try_normalize() {
        Some(axis) if angle.is_finite() => {
            // In f64 so that angles of many turns keep their digits.
            let (s, c) = (angle * 0.5).sin_cos();
            Quat::from_xyzw(axis.x * s as f32, axis.y * s as f32, axis.z * s as f32, c as f32).normalize()
        }
        _ => Quat::IDENTITY,
    }
}

fn rotation(doc: &Document, id: NodeId, name: &str) -> Quat {
    match numbers(doc, id, name) {
        Some(v) if v.len() >= 4 => axis_angle(v),
        _ => Quat::IDENTITY,
    }
}

fn boolean(doc: &Document, id: NodeId, name: &str, default: bool) -> bool {
    match doc.node(id).value(name) {
        Some(Value::Bools(b)) => b.first().copied().unwrap_or(default),
        _ => default,
    }
}

fn node_field(doc: &Document, id: NodeId, name: &str) -> Option<NodeId> {
    doc.node(id).value(name).and_then(|v| v.nodes().first().copied()).map(|n| doc.resolved(n))
}

fn strings<'a>(doc: &'a Document, id: NodeId, name: &str) -> &'a [String] {
    match doc.node(id).value(name) {
        Some(Value::Strings(s)) => s,
        _ => &[],
    }
}

fn colour(doc: &Document, id: NodeId, name: &str, default: Vec3) -> Vec3 {
    vec3(doc, id, name, default).clamp(Vec3::ZERO, Vec3::ONE)
}

// ---------------------------------------------------------------------------------------
// Animation

/// When a TimeSensor plays: its cycle and whether it loops.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Timing {
    cycle: f64,
    looping: bool,
}

/// An animated field's keys.
#[derive(Clone, Debug)]
enum Channel {
    Vec3(RawTrack<Vec3>, Timing),
    Quat(RawTrack<Quat>, Timing),
    Scalar(RawTrack<f32>, Timing),
    Points(Vec<f64>, Vec<Vec<Vec3>>, Timing),
}

impl Channel {
    fn cycles(timing: Timing) -> keyrig_core::Cycles {
        keyrig_core::Cycles::new(Cycle::Hold, if timing.looping { Cycle::Repeat } else { Cycle::Hold })
    }
}

fn animated<T: Copy>(value: T, track: &RawTrack<T>, timing: Timing) -> Animated<T> {
    Animated::new(value, track.clone()).with_cycles(Channel::cycles(timing))
}

/// A VRML field of view (radians) as keyrig's lens: degrees within (0°, 180°).
fn lens_degrees(radians: f32) -> f32 {
    if radians.is_finite() {
        radians.to_degrees().clamp(0.01, 179.9)
    } else {
        45.0
    }
}

/// `track` with every value mapped by `value` and every tangent by `tangent` (an affine map:
/// the same curve, mapped).
fn scaled<T: Copy>(track: &RawTrack<T>, value: impl Fn(T) -> T, tangent: impl Fn(T) -> T) -> RawTrack<T> {
    let mut out = track.clone();
    for k in out.keys.iter_mut() {
        k.value = value(k.value);
        k.in_tangent = k.in_tangent.map(&tangent);
        k.out_tangent = k.out_tangent.map(&tangent);
    }
    out
}

fn is_interpolator(kind: &str) -> bool {
    kind.ends_with("Interpolator")
}

/// The keys `(time, value)` of an interpolator over a cycle: key `kᵢ` at `kᵢ·cycle`, with
/// keys at 0 and `cycle` holding the end values; equal keys make a jump (the segment before
/// ends on the first of them, the value at the key is the last, VRML's and Coin's rule), kept
/// as a Step key a microsecond before it. `lerp` interpolates for the jump's held value.
fn keyed<T: Copy>(fractions: &[f64], values: &[T], cycle: f64, lerp: impl Fn(T, T, f32) -> T) -> Vec<Key<T>> {
    let mut keys: Vec<Key<T>> = Vec::with_capacity(values.len() + 2);
    let linear = |time: f64, value: T| Key::new(time, value).with_interpolation(Interpolation::Linear);
    let n = fractions.len().min(values.len());
    if n == 0 {
        return keys;
    }
    let first = fractions[0].clamp(0.0, 1.0);
    if first > 0.0 {
        keys.push(linear(0.0, values[0]));
    }
    let mut i = 0;
    while i < n {
        let f = fractions[i].clamp(0.0, 1.0);
        let mut j = i;
        while j + 1 < n && fractions[j + 1] <= fractions[i] {
            j += 1;
        }
        let t = f * cycle;
        if j > i {
            // A jump at t: the previous segment arrives at values[i]; from t on, values[j].
            if let Some(prev) = keys.last().cloned() {
                let gap = t - prev.time;
                let delta = (1e-6 * cycle).min(0.5 * gap);
                if delta > 0.0 {
                    let u = ((gap - delta) / gap) as f32;
                    let held = lerp(prev.value, values[i], u);
                    keys.push(Key::new(t - delta, held).with_interpolation(Interpolation::Step));
                }
            }
        }
        if keys.last().is_some_and(|k: &Key<T>| k.time >= t) {
            keys.pop();
        }
        keys.push(linear(t, values[j]));
        i = j + 1;
    }
    if let Some(last) = keys.last().cloned() {
        if last.time < cycle {
            keys.push(linear(cycle, last.value));
        }
    }
    keys
}

fn rgb_to_hsv(c: Vec3) -> Vec3 {
    let max = c.max_element();
    let min = c.min_element();
    let d = max - min;
    let h = if d <= 0.0 {
        0.0
    } else if max == c.x {
        ((c.y - c.z) / d).rem_euclid(6.0)
    } else if max == c.y {
        (c.z - c.x) / d + 2.0
    } else {
        (c.x - c.y) / d + 4.0
    } * 60.0;
    let s = if max > 0.0 { d / max } else { 0.0 };
    Vec3::new(h, s, max)
}

fn hsv_to_rgb(hsv: Vec3) -> Vec3 {
    let (h, s, v) = (hsv.x.rem_euclid(360.0) / 60.0, hsv.y, hsv.z);
    let i = h.floor();
    let f = h - i;
    let (p, q, t) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match i as i32 {
        0 => Vec3::new(v, t, p),
        1 => Vec3::new(q, v, p),
        2 => Vec3::new(p, v, t),
        3 => Vec3::new(p, q, v),
        4 => Vec3::new(t, p, v),
        _ => Vec3::new(v, p, q),
    }
}

/// VRML's colour interpolation between `a` and `b` (RGB) at `u`: in HSV, hue the short way
/// round the colour circle (as Coin's `SoVRMLColorInterpolator` does); a grey end takes the
/// other end's hue.
#[must_use]
pub fn hsv_lerp(a: Vec3, b: Vec3, u: f32) -> Vec3 {
    let (mut ha, mut hb) = (rgb_to_hsv(a), rgb_to_hsv(b));
    if ha.y == 0.0 {
        ha.x = hb.x;
    }
    if hb.y == 0.0 {
        hb.x = ha.x;
    }
    let mut dh = hb.x - ha.x;
    if dh > 180.0 {
        dh -= 360.0;
    } else if dh < -180.0 {
        dh += 360.0;
    }
    hsv_to_rgb(Vec3::new(ha.x + dh * u, ha.y + (hb.y - ha.y) * u, ha.z + (hb.z - ha.z) * u))
}

/// Linear RGB keys that follow the HSV blend of `keys` within [`COLOUR_TOLERANCE`]: each
/// segment is halved until the straight RGB line stays within the tolerance of the HSV path
/// (checked at 8 points per piece).
fn resample_colour(keys: &[Key<Vec3>]) -> Vec<Key<Vec3>> {
    let mut out = Vec::with_capacity(keys.len());
    for w in keys.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.interpolation == Interpolation::Step || a.value == b.value {
            out.push(a.clone());
            continue;
        }
        let mut pieces = vec![(0.0f32, 1.0f32)];
        let mut done: Vec<f32> = vec![0.0];
        let mut depth = 0;
        while let Some((u0, u1)) = pieces.pop() {
            let (c0, c1) = (hsv_lerp(a.value, b.value, u0), hsv_lerp(a.value, b.value, u1));
            let fits = (1..8).all(|k| {
                let s = k as f32 / 8.0;
                let u = u0 + (u1 - u0) * s;
                (hsv_lerp(a.value, b.value, u) - c0.lerp(c1, s)).abs().max_element() <= COLOUR_TOLERANCE
            });
            depth += 1;
            if fits || u1 - u0 < 1.0 / 4096.0 || depth > 100_000 {
                done.push(u1);
            } else {
                let m = 0.5 * (u0 + u1);
                pieces.push((m, u1));
                pieces.push((u0, m));
            }
        }
        done.sort_by(f32::total_cmp);
        done.dedup();
        for &u in &done[..done.len() - 1] {
            let time = a.time + f64::from(u) * (b.time - a.time);
            out.push(Key::new(time, hsv_lerp(a.value, b.value, u)).with_interpolation(Interpolation::Linear));
        }
    }
    if let Some(last) = keys.last() {
        out.push(last.clone());
    }
    out
}

/// The first `n` triples of `values` (read `arity` at a time) as vectors.
fn vec3s(values: &[f64], arity: usize, n: usize) -> Vec<Vec3> {
    values.chunks_exact(arity).take(n).map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)).collect()
}

/// `closed`, `keyVelocity` and `normalizeVelocity` of a spline interpolator.
fn spline_fields<'a, T>(doc: &Document, id: NodeId, velocity: &'a [T]) -> splines::SplineFields<'a, T> {
    splines::SplineFields {
        closed: boolean(doc, id, "closed", false),
        velocity,
        normalize: boolean(doc, id, "normalizeVelocity", false),
    }
}

struct Animation {
    channels: HashMap<(NodeId, String), Channel>,
    duration: f64,
}

fn timing_of(doc: &Document, sensor: NodeId, skipped: &mut Skips) -> Timing {
    let cycle = f64::from(float(doc, sensor, "cycleInterval", 1.0));
    let cycle = if cycle > 0.0 && cycle.is_finite() { cycle } else { 1.0 };
    let looping = boolean(doc, sensor, "loop", false);
    let (start, stop) = (float(doc, sensor, "startTime", 0.0), float(doc, sensor, "stopTime", 0.0));
    let enabled = boolean(doc, sensor, "enabled", true);
    if !looping || (stop > start) || !enabled {
        skipped.add(
            "TimeSensor start",
            "a sensor that is not running when the world loads (loop FALSE, stopped, disabled, or started by a sensor) plays from time 0",
            doc.node(sensor).place,
        );
    }
    Timing { cycle, looping }
}

fn analyse_animation(doc: &Document, skipped: &mut Skips) -> Animation {
    let mut drivers: HashMap<NodeId, NodeId> = HashMap::new();
    for r in &doc.routes {
        if is_interpolator(&doc.node(r.to).kind) && base_field(&r.to_field) == "fraction" {
            drivers.entry(r.to).or_insert(r.from);
        }
    }
    let mut channels: HashMap<(NodeId, String), Channel> = HashMap::new();
    let mut duration: f64 = 0.0;
    let mut used: std::collections::HashSet<NodeId> = std::collections::HashSet::new();
    for r in &doc.routes {
        let from = doc.node(r.from);
        if !is_interpolator(&from.kind) || base_field(&r.from_field) != "value" {
            let to = doc.node(r.to);
            if !is_interpolator(&to.kind) && from.kind != "TimeSensor" {
                skipped.add(
                    format!("ROUTE {}.{} TO {}.{}", from.kind, r.from_field, to.kind, r.to_field),
                    "only TimeSensor → interpolator → field chains are imported",
                    r.place,
                );
            }
            continue;
        }
        used.insert(r.from);
        let interp = r.from;
        let Some(&sensor) = drivers.get(&interp) else {
            skipped.add(from.kind.clone(), "not driven by a TimeSensor's fraction_changed", from.place);
            continue;
        };
        if doc.node(sensor).kind != "TimeSensor" {
            skipped.add(
                from.kind.clone(),
                format!("driven by a {}, not a TimeSensor", doc.node(sensor).kind),
                from.place,
            );
            continue;
        }
        let timing = timing_of(doc, sensor, skipped);
        let target = doc.node(r.to);
        let field = base_field(&r.to_field).to_owned();
        let key = (r.to, field.clone());
        if channels.contains_key(&key) {
            skipped.add(
                format!("{}.{}", target.kind, field),
                "a second interpolator drives the same field",
                r.place,
            );
            continue;
        }
        let fractions = numbers(doc, interp, "key").unwrap_or(&[]);
        if fractions.is_empty() {
            // VRML: an interpolator without keys sends nothing.
            continue;
        }
        if fractions.windows(2).any(|w| w[1] < w[0]) || fractions.iter().any(|f| !f.is_finite()) {
            skipped.add(from.kind.clone(), "its keys are not in increasing order", from.place);
            continue;
        }
        let values = numbers(doc, interp, "keyValue").unwrap_or(&[]);
        let n = fractions.len();
        let arity = |a: usize| -> Option<usize> { (values.len() >= n * a).then_some(a) };
        let channel = match from.kind.as_str() {
            "SplinePositionInterpolator" | "SplineScalarInterpolator" | "SquadOrientationInterpolator"
                if fractions.windows(2).any(|w| w[1] <= w[0]) =>
            {
                skipped.add(
                    from.kind.clone(),
                    "equal keys (a jump) in a spline interpolator: the specification leaves the curve undefined",
                    from.place,
                );
                continue;
            }
            "PositionInterpolator" => arity(3).map(|a| {
                let v = vec3s(values, a, n);
                Channel::Vec3(RawTrack::new(keyed(fractions, &v, timing.cycle, Vec3::lerp)), timing)
            }),
            "SplinePositionInterpolator" => arity(3).map(|a| {
                let v = vec3s(values, a, n);
                let velocity = vec3s(numbers(doc, interp, "keyVelocity").unwrap_or(&[]), 3, usize::MAX);
                let fields = spline_fields(doc, interp, &velocity);
                Channel::Vec3(
                    RawTrack::new(splines::spline_keys(fractions, &v, &fields, timing.cycle)),
                    timing,
                )
            }),
            "SplineScalarInterpolator" => arity(1).map(|_| {
                let v: Vec<f32> = values.iter().take(n).map(|&x| x as f32).collect();
                let velocity: Vec<f32> =
                    numbers(doc, interp, "keyVelocity").unwrap_or(&[]).iter().map(|&x| x as f32).collect();
                let fields = spline_fields(doc, interp, &velocity);
                Channel::Scalar(
                    RawTrack::new(splines::spline_keys(fractions, &v, &fields, timing.cycle)),
                    timing,
                )
            }),
            "SquadOrientationInterpolator" => arity(4).map(|a| {
                let v: Vec<Quat> = values.chunks_exact(a).take(n).map(axis_angle).collect();
                if boolean(doc, interp, "normalizeVelocity", false) {
                    skipped.add(
                        "SquadOrientationInterpolator normalizeVelocity",
                        "a squad has no velocities to normalize: ignored",
                        from.place,
                    );
                }
                let closed = boolean(doc, interp, "closed", false);
                let (keys, _exact) =
                    splines::squad_keys(fractions, &v, closed, timing.cycle, Channel::cycles(timing));
                Channel::Quat(RawTrack::new(keys), timing)
            }),
            "ColorInterpolator" => arity(3).map(|a| {
                let v = vec3s(values, a, n);
                let keys = keyed(fractions, &v, timing.cycle, hsv_lerp);
                Channel::Vec3(RawTrack::new(resample_colour(&keys)), timing)
            }),
            "OrientationInterpolator" => arity(4).map(|a| {
                let v: Vec<Quat> = values.chunks_exact(a).take(n).map(axis_angle).collect();
                Channel::Quat(
                    RawTrack::new(keyed(fractions, &v, timing.cycle, crate::model::slerp_short)),
                    timing,
                )
            }),
            "ScalarInterpolator" => arity(1).map(|_| {
                let v: Vec<f32> = values.iter().take(n).map(|&x| x as f32).collect();
                Channel::Scalar(
                    RawTrack::new(keyed(fractions, &v, timing.cycle, |a, b, u| a + (b - a) * u)),
                    timing,
                )
            }),
            "CoordinateInterpolator" => {
                let points = values.len() / 3 / n;
                (points > 0).then(|| {
                    let frames: Vec<Vec<Vec3>> = values
                        .chunks_exact(3)
                        .map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))
                        .collect::<Vec<_>>()
                        .chunks_exact(points)
                        .take(n)
                        .map(<[Vec3]>::to_vec)
                        .collect();
                    Channel::Points(fractions.to_vec(), frames, timing)
                })
            }
            other => {
                skipped.add(other.to_owned(), "this interpolator is not imported", from.place);
                continue;
            }
        };
        let Some(channel) = channel else {
            skipped.add(
                from.kind.clone(),
                format!("keyValue has fewer values than its {n} keys need"),
                from.place,
            );
            continue;
        };
        duration = duration.max(timing.cycle);
        channels.insert(key, channel);
    }
    for node in doc.nodes.iter().filter(|n| !n.template && is_interpolator(&n.kind) && n.proto.is_none()) {
        let id = NodeId(doc.nodes.iter().position(|m| std::ptr::eq(m, node)).unwrap_or(0) as u32);
        if !used.contains(&id) && !drivers.contains_key(&id) {
            skipped.add(node.kind.clone(), "no ROUTE connects it", node.place);
        }
    }
    Animation { channels, duration }
}

// ---------------------------------------------------------------------------------------
// Traversal

/// A transform above a shape.
#[derive(Clone, Debug)]
pub(crate) enum Frame {
    /// A VRML/X3D Transform (its node, for animation and names).
    Transform { node: NodeId, name: String },
    /// A static matrix (Inventor's accumulated transform).
    Matrix(Mat4),
}

/// A Shape reached in the traversal.
#[derive(Clone, Debug)]
pub(crate) struct ShapeInstance {
    pub names: Vec<String>,
    pub frames: Vec<Frame>,
    pub geometry: GeometryRef,
    pub material: Material,
    /// The VRML/X3D `Material` node (for its animation).
    pub material_node: Option<NodeId>,
    pub place: Place,
}

#[derive(Clone, Debug)]
pub(crate) enum GeometryRef {
    /// A polygon mesh over the points of `coord` (a Coordinate node, for morphing) or given.
    Poly {
        tess: Arc<Tessellation>,
        points: Arc<Vec<Vec3>>,
        coord: Option<NodeId>,
    },
    Solid(Arc<Solid>),
}

#[derive(Clone, Debug)]
pub(crate) struct LightInstance {
    pub node: Option<NodeId>,
    pub frames: Vec<Frame>,
    pub light: keyrig_core::Light,
}

/// Aggregated list of what was not imported.
#[derive(Default)]
pub(crate) struct Skips {
    items: BTreeMap<(String, String), (usize, Place)>,
}

impl Skips {
    pub fn add(&mut self, what: impl Into<String>, why: impl Into<String>, place: Place) {
        let entry = self.items.entry((what.into(), why.into())).or_insert((0, place));
        entry.0 += 1;
    }

    fn into_list(self, doc: &Document) -> Vec<Skipped> {
        self.items
            .into_iter()
            .map(|((what, why), (count, place))| Skipped {
                what,
                why,
                place: Some(place_text(doc, place)),
                count,
            })
            .collect()
    }
}

pub(crate) fn place_text(doc: &Document, place: Place) -> String {
    match doc.files.get(place.file.0 as usize) {
        Some(f) => {
            let (line, column) = super::lex::line_column(&f.text, place.at);
            let name = f
                .path
                .file_name()
                .map_or_else(|| f.path.display().to_string(), |n| n.to_string_lossy().into_owned());
            format!("{name}:{line}:{column}")
        }
        None => format!("byte {}", place.at),
    }
}

/// Nodes that are read through the routes or their parents, never listed.
const HANDLED_ELSEWHERE: [&str; 9] = [
    "TimeSensor",
    "Coordinate",
    "Normal",
    "TextureCoordinate",
    "Appearance",
    "Material",
    "ImageTexture",
    "PixelTexture",
    "Color",
];

pub(crate) struct Traversal<'d> {
    pub doc: &'d Document,
    pub skips: Skips,
    pub shapes: Vec<ShapeInstance>,
    pub lights: Vec<LightInstance>,
    /// Each view with the transforms above it and its node (for its animation).
    pub views: Vec<(View, Vec<Frame>, Option<NodeId>)>,
    visits: usize,
    geometry_cache: HashMap<NodeId, Option<GeometryRef>>,
    texture_cache: HashMap<NodeId, Option<Arc<keyrig_core::TextureImage>>>,
}

impl<'d> Traversal<'d> {
    pub fn new(doc: &'d Document) -> Self {
        Traversal {
            doc,
            skips: Skips::default(),
            shapes: Vec::new(),
            lights: Vec::new(),
            views: Vec::new(),
            visits: 0,
            geometry_cache: HashMap::new(),
            texture_cache: HashMap::new(),
        }
    }

    /// Visits the VRML/X3D scene graph from the document's roots.
    ///
    /// # Errors
    /// Too many instances, or a graph nested too deep.
    pub fn visit_roots(&mut self) -> Result<(), VrmlError> {
        let (mut frames, mut names) = (Vec::new(), Vec::new());
        let roots = self.doc.roots.clone();
        self.visit_all(&roots, &mut frames, &mut names)
    }

    pub fn count_visit(&mut self, id: NodeId) -> Result<(), VrmlError> {
        self.visits += 1;
        if self.visits > MAX_INSTANCES {
            return Err(VrmlError::at_place(
                self.doc,
                self.doc.node(id).place,
                VrmlErrorKind::Limit(format!(
                    "the scene's DEF/USE graph expands to more than {MAX_INSTANCES} node instances"
                )),
            ));
        }
        Ok(())
    }

    fn visit_all(
        &mut self,
        ids: &[NodeId],
        frames: &mut Vec<Frame>,
        names: &mut Vec<String>,
    ) -> Result<(), VrmlError> {
        for &id in ids {
            self.visit(id, frames, names)?;
        }
        Ok(())
    }

    fn visit(
        &mut self,
        id: NodeId,
        frames: &mut Vec<Frame>,
        names: &mut Vec<String>,
    ) -> Result<(), VrmlError> {
        let doc = self.doc;
        let id = doc.resolved(id);
        self.count_visit(id)?;
        if frames.len() > 4 * super::classic::MAX_DEPTH {
            return Err(VrmlError::at_place(
                doc,
                doc.node(id).place,
                VrmlErrorKind::Limit("Inlines and PROTOs nest the scene graph too deep".into()),
            ));
        }
        let node = doc.node(id);
        let kind = node.kind.as_str();
        let named = node.def.is_some();
        if let Some(def) = &node.def {
            names.push(def.clone());
        }
        let children = |name: &str| node.value(name).map(Value::nodes).unwrap_or(&[]).to_vec();
        match kind {
            "Transform" | "CADPart" => {
                let name = node.def.clone().unwrap_or_else(|| kind.to_owned());
                frames.push(Frame::Transform { node: id, name });
                self.visit_all(&children("children"), frames, names)?;
                frames.pop();
            }
            "Group" | "StaticGroup" | "Anchor" | "Collision" | "CADAssembly" | "CADLayer" | "Billboard" => {
                if kind == "Billboard" {
                    self.skips.add(
                        "Billboard",
                        "its turning towards the viewer is not imported (drawn as a Group)",
                        node.place,
                    );
                }
                self.visit_all(&children("children"), frames, names)?;
            }
            "CADFace" => self.visit_all(&children("shape"), frames, names)?,
            "Switch" => {
                let choice = float(doc, id, "whichChoice", -1.0) as i64;
                let list =
                    if node.value("choice").is_some() { children("choice") } else { children("children") };
                if let Some(&c) = usize::try_from(choice).ok().and_then(|c| list.get(c)) {
                    self.visit(c, frames, names)?;
                }
            }
            "LOD" => {
                let list =
                    if node.value("level").is_some() { children("level") } else { children("children") };
                if list.len() > 1 {
                    self.skips.add("LOD", "only the first (most detailed) level is imported", node.place);
                }
                if let Some(&first) = list.first() {
                    self.visit(first, frames, names)?;
                }
            }
            "Shape" => self.shape(id, frames, names)?,
            "DirectionalLight" | "PointLight" | "SpotLight" => self.light(id, frames),
            "Viewpoint" | "OrthoViewpoint" => {
                let name = node
                    .def
                    .clone()
                    .or_else(|| strings(doc, id, "description").first().cloned())
                    .unwrap_or_else(|| format!("View {}", self.views.len() + 1));
                // OrthoViewpoint's fieldOfView is the view's box (minX, minY, maxX, maxY).
                let orthographic = (node.kind == "OrthoViewpoint").then(|| {
                    let b = numbers(doc, id, "fieldOfView").filter(|b| b.len() >= 4).unwrap_or(&[-1.0, -1.0, 1.0, 1.0]);
                    ((b[3] - b[1]) as f32).abs().max(1e-3)
                });
                let view = View {
                    name,
                    position: vec3(doc, id, "position", Vec3::new(0.0, 0.0, 10.0)),
                    orientation: rotation(doc, id, "orientation"),
                    field_of_view: if orthographic.is_some() {
                        std::f32::consts::FRAC_PI_4
                    } else {
                        float(doc, id, "fieldOfView", std::f32::consts::FRAC_PI_4)
                    },
                    orthographic,
                };
                self.views.push((view, frames.clone(), Some(id)));
            }
            "WorldInfo" if node.value("info").is_some_and(|v| matches!(v, Value::Strings(s) if s.iter().any(|s| s.starts_with(super::tree::METADATA_TAG)))) => {}
            "WorldInfo" | "NavigationInfo" | "Background" | "TextureBackground" | "Fog" | "Sound"
            | "Script" | "TouchSensor" | "ProximitySensor" | "VisibilitySensor" | "PlaneSensor"
            | "SphereSensor" | "CylinderSensor" | "KeySensor" | "StringSensor" | "BooleanFilter"
            | "BooleanSequencer" | "IntegerSequencer" | "BooleanToggle" | "BooleanTrigger"
            | "TimeTrigger" | "IntegerTrigger" | "MetadataSet" | "MetadataString" | "MetadataFloat"
            | "MetadataDouble" | "MetadataInteger" | "MetadataBoolean" | "EaseInEaseOut" => {
                self.skips.add(kind.to_owned(), "not imported (keyrig has no counterpart)", node.place);
            }
            _ if HANDLED_ELSEWHERE.contains(&kind) || is_interpolator(kind) => {}
            _ => {
                let why = match node.proto {
                    Some(p) if doc.protos[p].body.is_empty() => {
                        "a PROTO whose definition could not be loaded"
                    }
                    _ => "this node type is not imported",
                };
                self.skips.add(kind.to_owned(), why, node.place);
            }
        }
        if named {
            names.pop();
        }
        Ok(())
    }

    fn shape(&mut self, id: NodeId, frames: &[Frame], names: &[String]) -> Result<(), VrmlError> {
        let doc = self.doc;
        let node = doc.node(id);
        let Some(geometry) = node_field(doc, id, "geometry") else { return Ok(()) };
        let Some(g) = self.geometry(geometry) else { return Ok(()) };
        let appearance = node_field(doc, id, "appearance");
        let material = self.appearance(appearance);
        let material_node = appearance.and_then(|a| node_field(doc, a, "material"));
        let mut hints: Vec<String> = names.iter().rev().cloned().collect();
        if let Some(def) = &doc.node(geometry).def {
            hints.push(def.clone());
        }
        hints.push(doc.node(geometry).kind.clone());
        self.shapes.push(ShapeInstance {
            names: hints,
            frames: frames.to_vec(),
            geometry: g,
            material,
            material_node,
            place: node.place,
        });
        Ok(())
    }

    fn appearance(&mut self, appearance: Option<NodeId>) -> Material {
        let doc = self.doc;
        // VRML's default without a Material: unlit white; with one: diffuse 0.8.
        let mut base = [1.0, 1.0, 1.0, 1.0];
        let mut texture = None;
        if let Some(app) = appearance {
            if let Some(m) = node_field(doc, app, "material") {
                let d = colour(doc, m, "diffuseColor", Vec3::splat(0.8));
                let alpha = 1.0 - float(doc, m, "transparency", 0.0).clamp(0.0, 1.0);
                base = [d.x, d.y, d.z, alpha];
                let emissive = vec3(doc, m, "emissiveColor", Vec3::ZERO);
                if emissive != Vec3::ZERO {
                    self.skips.add(
                        "Material.emissiveColor",
                        "not imported (keyrig materials have a base colour only)",
                        doc.node(m).place,
                    );
                }
                if doc.node(m).value("specularColor").is_some() || doc.node(m).value("shininess").is_some() {
                    self.skips.add(
                        "Material.specularColor/shininess",
                        "not imported (keyrig materials have a base colour only)",
                        doc.node(m).place,
                    );
                }
            }
            if let Some(t) = node_field(doc, app, "texture") {
                texture = self.texture(t);
            }
            if let Some(tt) = node_field(doc, app, "textureTransform") {
                self.skips.add("TextureTransform", "not imported", doc.node(tt).place);
            }
        }
        Material { base_colour: base, base_colour_texture: texture }
    }

    fn texture(&mut self, id: NodeId) -> Option<Arc<keyrig_core::TextureImage>> {
        if let Some(t) = self.texture_cache.get(&id) {
            return t.clone();
        }
        let doc = self.doc;
        let node = doc.node(id);
        let sampler = keyrig_core::Sampler {
            wrap_u: if boolean(doc, id, "repeatS", true) {
                keyrig_core::WrapMode::Repeat
            } else {
                keyrig_core::WrapMode::ClampToEdge
            },
            wrap_v: if boolean(doc, id, "repeatT", true) {
                keyrig_core::WrapMode::Repeat
            } else {
                keyrig_core::WrapMode::ClampToEdge
            },
            ..keyrig_core::Sampler::default()
        };
        let image = match node.kind.as_str() {
            "ImageTexture" | "Texture2" => match numbers(doc, id, "image") {
                Some(image) if node.kind == "Texture2" && image.len() > 3 => sf_image(image),
                _ => {
                    let urls: Vec<String> =
                        strings(doc, id, if node.kind == "Texture2" { "filename" } else { "url" }).to_vec();
                    self.load_image(&urls, node.place)
                }
            },
            "PixelTexture" => numbers(doc, id, "image").and_then(sf_image),
            other => {
                self.skips.add(other.to_owned(), "this texture node is not imported", node.place);
                None
            }
        };
        let texture = image
            .and_then(|(w, h, rgba)| keyrig_core::TextureImage::new(w, h, rgba, sampler).ok().map(Arc::new));
        self.texture_cache.insert(id, texture.clone());
        texture
    }

    fn load_image(&mut self, urls: &[String], place: Place) -> Option<(u32, u32, Vec<u8>)> {
        let doc = self.doc;
        let file = doc.files.get(place.file.0 as usize)?;
        let folder = file.path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut reasons = Vec::new();
        for url in urls {
            let path = match super::local_file(&folder, url) {
                Ok(p) => p,
                Err(reason) => {
                    reasons.push(reason);
                    continue;
                }
            };
            match crate::file_io::read_regular_file(&path, crate::file_io::MAX_MODEL_BYTES)
                .map_err(|e| e.to_string())
                .and_then(|bytes| image::load_from_memory(&bytes).map_err(|e| e.to_string()))
            {
                Ok(img) => {
                    let img = img.to_rgba8();
                    return Some((img.width(), img.height(), img.into_raw()));
                }
                Err(e) => reasons.push(format!("`{}`: {e}", super::lex::clip(url))),
            }
        }
        self.skips.add("ImageTexture", format!("no image could be read ({})", reasons.join("; ")), place);
        None
    }

    fn geometry(&mut self, id: NodeId) -> Option<GeometryRef> {
        if let Some(g) = self.geometry_cache.get(&id) {
            return g.clone();
        }
        let g = self.make_geometry(id);
        self.geometry_cache.insert(id, g.clone());
        g
    }

    fn make_geometry(&mut self, id: NodeId) -> Option<GeometryRef> {
        let doc = self.doc;
        let node = doc.node(id);
        let place = node.place;
        let solid = |s: Solid| Some(GeometryRef::Solid(Arc::new(s)));
        match node.kind.as_str() {
            "Box" => solid(geometry::box_solid(vec3(doc, id, "size", Vec3::splat(2.0)))),
            "Sphere" => solid(geometry::sphere_solid(float(doc, id, "radius", 1.0))),
            "Cone" => solid(geometry::round_solid(
                float(doc, id, "bottomRadius", 1.0),
                0.0,
                float(doc, id, "height", 2.0),
                boolean(doc, id, "side", true),
                boolean(doc, id, "bottom", true),
                false,
            )),
            "Cylinder" => {
                let r = float(doc, id, "radius", 1.0);
                solid(geometry::round_solid(
                    r,
                    r,
                    float(doc, id, "height", 2.0),
                    boolean(doc, id, "side", true),
                    boolean(doc, id, "bottom", true),
                    boolean(doc, id, "top", true),
                ))
            }
            "IndexedFaceSet"
            | "IndexedTriangleSet"
            | "TriangleSet"
            | "IndexedTriangleFanSet"
            | "IndexedTriangleStripSet"
            | "TriangleFanSet"
            | "TriangleStripSet"
            | "IndexedQuadSet"
            | "QuadSet"
            | "ElevationGrid" => match self.poly(id) {
                Ok(g) => g,
                Err(message) => {
                    self.skips.add(node.kind.clone(), message, place);
                    None
                }
            },
            other => {
                self.skips.add(
                    other.to_owned(),
                    "this geometry is not imported (keyrig draws triangles)",
                    place,
                );
                None
            }
        }
    }

    fn poly(&mut self, id: NodeId) -> Result<Option<GeometryRef>, String> {
        let doc = self.doc;
        let node = doc.node(id);
        let kind = node.kind.as_str();
        let coord = node_field(doc, id, "coord");
        let points: Vec<Vec3> = if kind == "ElevationGrid" {
            let (nx, nz) = (
                float(doc, id, "xDimension", 0.0).max(0.0) as usize,
                float(doc, id, "zDimension", 0.0).max(0.0) as usize,
            );
            let (dx, dz) = (float(doc, id, "xSpacing", 1.0), float(doc, id, "zSpacing", 1.0));
            let heights = numbers(doc, id, "height").unwrap_or(&[]);
            if heights.len() < nx.saturating_mul(nz) {
                return Err(format!("{} heights for a {nx}×{nz} grid", heights.len()));
            }
            (0..nz)
                .flat_map(|z| (0..nx).map(move |x| (x, z)))
                .map(|(x, z)| Vec3::new(x as f32 * dx, heights[z * nx + x] as f32, z as f32 * dz))
                .collect()
        } else {
            let Some(c) = coord else { return Ok(None) };
            numbers(doc, c, "point")
                .unwrap_or(&[])
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
                .collect()
        };
        if points.iter().any(|p| !p.is_finite()) {
            return Err("a point is not finite".into());
        }
        let ints = |name: &str| -> Vec<i64> {
            numbers(doc, id, name).unwrap_or(&[]).iter().map(|&v| v as i64).collect()
        };
        let mut mesh = PolyMesh {
            ccw: boolean(doc, id, "ccw", true),
            convex: boolean(doc, id, "convex", true),
            crease_angle: float(doc, id, "creaseAngle", 0.0),
            ..PolyMesh::default()
        };
        let mut push_face = |mesh: &mut PolyMesh, face: &[u32]| {
            if mesh.face_start.is_empty() {
                mesh.face_start.push(0);
            }
            mesh.corners.extend_from_slice(face);
            mesh.face_start.push(mesh.corners.len() as u32);
        };
        let to_u32 = |i: i64| -> Result<u32, String> {
            u32::try_from(i).map_err(|_| format!("index {i} is negative"))
        };
        match kind {
            "IndexedFaceSet" => {
                let mut face = Vec::new();
                for i in ints("coordIndex") {
                    if i < 0 {
                        push_face(&mut mesh, &face);
                        face.clear();
                    } else {
                        face.push(to_u32(i)?);
                    }
                }
                if !face.is_empty() {
                    push_face(&mut mesh, &face);
                }
            }
            "IndexedTriangleSet" | "TriangleSet" => {
                let index: Vec<u32> = if kind == "TriangleSet" {
                    (0..points.len() as u32 / 3 * 3).collect()
                } else {
                    ints("index").into_iter().map(to_u32).collect::<Result<_, _>>()?
                };
                for t in index.chunks_exact(3) {
                    push_face(&mut mesh, t);
                }
                smooth_by_default(doc, id, &mut mesh);
            }
            "IndexedQuadSet" | "QuadSet" => {
                let index: Vec<u32> = if kind == "QuadSet" {
                    (0..points.len() as u32 / 4 * 4).collect()
                } else {
                    ints("index").into_iter().map(to_u32).collect::<Result<_, _>>()?
                };
                for q in index.chunks_exact(4) {
                    push_face(&mut mesh, q);
                }
                smooth_by_default(doc, id, &mut mesh);
            }
            "IndexedTriangleFanSet" | "IndexedTriangleStripSet" => {
                let mut run = Vec::new();
                let mut runs = Vec::new();
                for i in ints("index") {
                    if i < 0 {
                        runs.push(std::mem::take(&mut run));
                    } else {
                        run.push(to_u32(i)?);
                    }
                }
                runs.push(run);
                for r in runs.iter().filter(|r| r.len() >= 3) {
                    fan_or_strip(&mut mesh, r, kind.contains("Fan"), &mut push_face);
                }
                smooth_by_default(doc, id, &mut mesh);
            }
            "TriangleFanSet" | "TriangleStripSet" => {
                let counts = ints(if kind == "TriangleFanSet" { "fanCount" } else { "stripCount" });
                let mut start = 0u32;
                for c in counts {
                    let c = to_u32(c)?;
                    let run: Vec<u32> = (start..start.saturating_add(c)).collect();
                    if run.len() >= 3 {
                        fan_or_strip(&mut mesh, &run, kind == "TriangleFanSet", &mut push_face);
                    }
                    start = start.saturating_add(c);
                }
                smooth_by_default(doc, id, &mut mesh);
            }
            "ElevationGrid" => {
                let nx = float(doc, id, "xDimension", 0.0).max(0.0) as u32;
                let nz = float(doc, id, "zDimension", 0.0).max(0.0) as u32;
                for z in 0..nz.saturating_sub(1) {
                    for x in 0..nx.saturating_sub(1) {
                        let a = z * nx + x;
                        push_face(&mut mesh, &[a, a + nx, a + nx + 1, a + 1]);
                    }
                }
            }
            _ => {}
        }
        if mesh.face_start.is_empty() {
            return Ok(None);
        }
        let faces = mesh.face_start.len() - 1;
        // Normals given by the file.
        if let Some(n) = node_field(doc, id, "normal") {
            let vectors: Vec<Vec3> = numbers(doc, n, "vector")
                .unwrap_or(&[])
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
                .collect();
            let per_vertex = boolean(doc, id, "normalPerVertex", true);
            let index = ints("normalIndex");
            mesh.corner_normals =
                Some(per_corner(&mesh, &vectors, &index, per_vertex, faces, kind == "IndexedFaceSet")?);
        }
        if let Some(t) = node_field(doc, id, "texCoord") {
            let uvs: Vec<Vec2> = numbers(doc, t, "point")
                .unwrap_or(&[])
                .chunks_exact(2)
                .map(|p| Vec2::new(p[0] as f32, p[1] as f32))
                .collect();
            let index = ints("texCoordIndex");
            mesh.corner_uvs = Some(per_corner(&mesh, &uvs, &index, true, faces, kind == "IndexedFaceSet")?);
        } else if kind == "ElevationGrid" {
            let nx = float(doc, id, "xDimension", 0.0).max(2.0) - 1.0;
            let nz = float(doc, id, "zDimension", 0.0).max(2.0) - 1.0;
            let dx = float(doc, id, "xSpacing", 1.0);
            let dz = float(doc, id, "zSpacing", 1.0);
            mesh.corner_uvs = Some(
                mesh.corners
                    .iter()
                    .map(|&c| {
                        let p = points[c as usize];
                        Vec2::new(p.x / dx / nx, p.z / dz / nz)
                    })
                    .collect(),
            );
        }
        if node.value("color").is_some() {
            self.skips.add(
                format!("{kind}.color"),
                "per-vertex and per-face colours are not imported (the material's colour is used)",
                node.place,
            );
        }
        let tess = mesh.tessellate(&points)?;
        if tess.indices.is_empty() {
            return Ok(None);
        }
        Ok(Some(GeometryRef::Poly { tess: Arc::new(tess), points: Arc::new(points), coord }))
    }
}

/// X3D's triangle sets without normals are lit smoothly (`normalPerVertex TRUE`): every
/// corner shares the normal of its point.
fn smooth_by_default(doc: &Document, id: NodeId, mesh: &mut PolyMesh) {
    if boolean(doc, id, "normalPerVertex", true) {
        mesh.crease_angle = std::f32::consts::PI;
    }
}

fn fan_or_strip(mesh: &mut PolyMesh, run: &[u32], fan: bool, push: &mut impl FnMut(&mut PolyMesh, &[u32])) {
    for i in 2..run.len() {
        let tri = if fan {
            [run[0], run[i - 1], run[i]]
        } else if i % 2 == 0 {
            [run[i - 2], run[i - 1], run[i]]
        } else {
            [run[i - 1], run[i - 2], run[i]]
        };
        push(mesh, &tri);
    }
}

/// Per-corner values from a list and an index (VRML's rules for `normalIndex` /
/// `texCoordIndex`: per vertex through the index, else through `coordIndex`; per face through
/// the index, else in order).
fn per_corner<T: Copy>(
    mesh: &PolyMesh,
    values: &[T],
    index: &[i64],
    per_vertex: bool,
    faces: usize,
    indexed_faces: bool,
) -> Result<Vec<T>, String> {
    let get = |i: i64| -> Result<T, String> {
        usize::try_from(i)
            .ok()
            .and_then(|i| values.get(i).copied())
            .ok_or_else(|| format!("index {i} is out of range (there are {} values)", values.len()))
    };
    let mut out = Vec::with_capacity(mesh.corners.len());
    if per_vertex {
        if index.is_empty() || !indexed_faces {
            for &c in &mesh.corners {
                out.push(get(i64::from(c))?);
            }
        } else {
            let flat: Vec<i64> = index.iter().copied().filter(|&i| i >= 0).collect();
            for k in 0..mesh.corners.len() {
                out.push(get(*flat.get(k).unwrap_or(&-1))?);
            }
        }
    } else {
        for f in 0..faces {
            let v = get(if index.is_empty() { f as i64 } else { *index.get(f).unwrap_or(&-1) })?;
            let n = (mesh.face_start[f + 1] - mesh.face_start[f]) as usize;
            out.extend(std::iter::repeat_n(v, n));
        }
    }
    Ok(out)
}

/// An SFImage (`width height components pixels…`, rows bottom to top) as RGBA rows top to
/// bottom.
fn sf_image(v: &[f64]) -> Option<(u32, u32, Vec<u8>)> {
    let (w, h, c) = (*v.first()? as u64, *v.get(1)? as u64, *v.get(2)? as u64);
    if w == 0 || h == 0 || !(1..=4).contains(&c) || w.checked_mul(h)? != (v.len() - 3) as u64 {
        return None;
    }
    let (w, h) = (w as usize, h as usize);
    let mut rgba = vec![0u8; w * h * 4];
    for row in 0..h {
        for x in 0..w {
            let p = v[3 + row * w + x] as u64;
            let px = match c {
                1 => [p as u8, p as u8, p as u8, 255],
                2 => [(p >> 8) as u8, (p >> 8) as u8, (p >> 8) as u8, p as u8],
                3 => [(p >> 16) as u8, (p >> 8) as u8, p as u8, 255],
                _ => [(p >> 24) as u8, (p >> 16) as u8, (p >> 8) as u8, p as u8],
            };
            let out_row = h - 1 - row;
            rgba[(out_row * w + x) * 4..(out_row * w + x) * 4 + 4].copy_from_slice(&px);
        }
    }
    Some((w as u32, h as u32, rgba))
}

impl Traversal<'_> {
    pub(crate) fn skips_add(&mut self, what: &str, why: &str, id: NodeId) {
        let place = self.doc.node(id).place;
        self.skips.add(what.to_owned(), why.to_owned(), place);
    }

    pub(crate) fn texture_of(&mut self, id: NodeId) -> Option<Arc<keyrig_core::TextureImage>> {
        self.texture(id)
    }
}

// ---------------------------------------------------------------------------------------
// Lights

impl Traversal<'_> {
    fn light(&mut self, id: NodeId, frames: &[Frame]) {
        let doc = self.doc;
        let node = doc.node(id);
        let kind = match node.kind.as_str() {
            "DirectionalLight" => keyrig_core::LightKind::Directional,
            "PointLight" => keyrig_core::LightKind::Point,
            _ => {
                // VRML allows up to π/2 (and files hold more); keyrig's spot is within (0°, 90°].
                let angle = |f: &str, rest: f32| {
                    let a = float(doc, id, f, rest).to_degrees();
                    if a.is_finite() {
                        a.clamp(0.01, 90.0)
                    } else {
                        rest.to_degrees()
                    }
                };
                let cutoff = angle("cutOffAngle", std::f32::consts::FRAC_PI_4);
                let beam = angle("beamWidth", std::f32::consts::FRAC_PI_2);
                keyrig_core::LightKind::Spot {
                    cutoff_deg: cutoff,
                    inner_angle_deg: beam.min(cutoff),
                    dropoff: 1.0,
                }
            }
        };
        if float(doc, id, "ambientIntensity", 0.0) != 0.0 {
            self.skips.add(
                format!("{}.ambientIntensity", node.kind),
                "not imported (keyrig's ambient light is the scene's)",
                node.place,
            );
        }
        let name = node.def.clone().unwrap_or_else(|| node.kind.clone());
        let position =
            if node.kind == "DirectionalLight" { Vec3::ZERO } else { vec3(doc, id, "location", Vec3::ZERO) };
        self.lights.push(LightInstance {
            node: Some(id),
            frames: frames.to_vec(),
            light: keyrig_core::Light {
                name,
                kind,
                enabled: boolean(doc, id, "on", true),
                position: Animated::constant(position),
                direction: Animated::constant(vec3(doc, id, "direction", -Vec3::Z)),
                colour: Animated::constant(colour(doc, id, "color", Vec3::ONE)),
                intensity: Animated::constant(float(doc, id, "intensity", 1.0)),
                attributes: Default::default(),
            },
        });
    }
}

// ---------------------------------------------------------------------------------------
// Objects

/// The static local matrix of a Transform: `T·C·R·SR·S·−SR·−C`.
fn transform_matrix(doc: &Document, id: NodeId) -> Mat4 {
    let t = vec3(doc, id, "translation", Vec3::ZERO);
    let r = rotation(doc, id, "rotation");
    let s = vec3(doc, id, "scale", Vec3::ONE);
    let c = vec3(doc, id, "center", Vec3::ZERO);
    let so = rotation(doc, id, "scaleOrientation");
    Mat4::from_translation(t + c)
        * Mat4::from_quat(r)
        * Mat4::from_quat(so)
        * Mat4::from_scale(s)
        * Mat4::from_quat(so.inverse())
        * Mat4::from_translation(-c)
}

fn frame_matrix(doc: &Document, frame: &Frame) -> Mat4 {
    match frame {
        Frame::Transform { node, .. } => transform_matrix(doc, *node),
        Frame::Matrix(m) => *m,
    }
}

/// The decomposition of `m` into translation, rotation and scale, when it recomposes to `m`.
fn exact_trs(m: Mat4) -> Option<(Vec3, Quat, Vec3)> {
    let (s, r, t) = m.to_scale_rotation_translation();
    let back = Mat4::from_scale_rotation_translation(s, r, t);
    let size = m.abs().to_cols_array().iter().fold(1.0f32, |a, &b| a.max(b));
    let close = (back - m).to_cols_array().iter().all(|d| d.abs() <= 1e-5 * size);
    (close && s.is_finite() && r.is_finite() && t.is_finite()).then_some((t, r.normalize(), s))
}

struct Mapper<'d> {
    doc: &'d Document,
    anim: Animation,
    skips: Skips,
    names: HashMap<String, usize>,
}

impl Mapper<'_> {
    fn unique(&mut self, base: &str) -> String {
        let base = base.replace('/', "_");
        let n = self.names.entry(base.clone()).or_insert(0);
        *n += 1;
        if *n == 1 {
            base
        } else {
            format!("{base} {n}")
        }
    }

    fn vec3_channel(&self, node: NodeId, field: &str) -> Option<(&RawTrack<Vec3>, Timing)> {
        match self.anim.channels.get(&(node, field.to_owned()))? {
            Channel::Vec3(t, timing) => Some((t, *timing)),
            _ => None,
        }
    }

    fn quat_channel(&self, node: NodeId, field: &str) -> Option<(&RawTrack<Quat>, Timing)> {
        match self.anim.channels.get(&(node, field.to_owned()))? {
            Channel::Quat(t, timing) => Some((t, *timing)),
            _ => None,
        }
    }

    fn frame_animated(&self, frame: &Frame) -> bool {
        match frame {
            Frame::Transform { node, .. } => {
                ["translation", "rotation", "scale", "center", "scaleOrientation"]
                    .iter()
                    .any(|f| self.anim.channels.contains_key(&(*node, (*f).to_owned())))
            }
            Frame::Matrix(_) => false,
        }
    }

    /// Whether a Transform is T·R·S alone (no centre, no scale orientation that matters).
    fn plain(&self, node: NodeId) -> bool {
        let doc = self.doc;
        let c = vec3(doc, node, "center", Vec3::ZERO);
        let so = rotation(doc, node, "scaleOrientation");
        let s = vec3(doc, node, "scale", Vec3::ONE);
        let scale_animated = self.vec3_channel(node, "scale").is_some();
        c == Vec3::ZERO
            && (so.angle_between(Quat::IDENTITY) < 1e-6 || (s.x == s.y && s.y == s.z && !scale_animated))
    }

    /// The animated translation, rotation and scale of a plain Transform.
    fn trs(&self, node: NodeId) -> (Animated<Vec3>, Animated<Quat>, Animated<Vec3>) {
        let doc = self.doc;
        let t = vec3(doc, node, "translation", Vec3::ZERO);
        let r = rotation(doc, node, "rotation");
        let s = vec3(doc, node, "scale", Vec3::ONE);
        let t = match self.vec3_channel(node, "translation") {
            Some((track, timing)) => animated(t, track, timing),
            None => Animated::constant(t),
        };
        let r = match self.quat_channel(node, "rotation") {
            Some((track, timing)) => animated(r, track, timing),
            None => Animated::constant(r),
        };
        let s = match self.vec3_channel(node, "scale") {
            Some((track, timing)) => animated(s, track, timing),
            None => Animated::constant(s),
        };
        (t, r, s)
    }

    /// The joints of one frame (1 to 3, see the module documentation).
    fn joints_of(
        &mut self,
        frame: &Frame,
        out: &mut Vec<keyrig_core::Joint>,
        used: &mut HashMap<String, usize>,
    ) {
        let mut unique = |base: String| {
            let base = base.replace('/', "_");
            let n = used.entry(base.clone()).or_insert(0);
            *n += 1;
            if *n == 1 {
                base
            } else {
                format!("{base} {n}")
            }
        };
        let parent = |out: &Vec<keyrig_core::Joint>| out.len().checked_sub(1);
        match frame {
            Frame::Matrix(m) => {
                let (t, r, s) = exact_trs(*m).unwrap_or((m.w_axis.truncate(), Quat::IDENTITY, Vec3::ONE));
                let mut j = keyrig_core::Joint::new(
                    unique("Transform".into()),
                    parent(out),
                    Vec3::ZERO,
                    Quat::IDENTITY,
                );
                j.translation = Animated::constant(t);
                j.rotation = Animated::constant(r);
                j.scale = Animated::constant(s);
                out.push(j);
            }
            Frame::Transform { node, name } => {
                let node = *node;
                let doc = self.doc;
                for f in ["center", "scaleOrientation"] {
                    if self.anim.channels.contains_key(&(node, f.to_owned())) {
                        self.skips.add(
                            format!("Transform.{f} animation"),
                            "not imported (its value at rest is used)",
                            doc.node(node).place,
                        );
                    }
                }
                let (t, r, s) = self.trs(node);
                if self.plain(node) {
                    let mut j = keyrig_core::Joint::new(
                        unique(name.clone()),
                        parent(out),
                        Vec3::ZERO,
                        Quat::IDENTITY,
                    );
                    j.translation = t;
                    j.rotation = r;
                    j.scale = s;
                    out.push(j);
                    return;
                }
                let c = vec3(doc, node, "center", Vec3::ZERO);
                let so = rotation(doc, node, "scaleOrientation");
                let mut shifted = t.clone();
                shifted.value += c;
                for k in shifted.track.keys.iter_mut() {
                    k.value += c;
                }
                let mut j1 =
                    keyrig_core::Joint::new(unique(name.clone()), parent(out), Vec3::ZERO, Quat::IDENTITY);
                j1.translation = shifted;
                j1.rotation = r;
                let with_so = so.angle_between(Quat::IDENTITY) >= 1e-6;
                if !with_so {
                    j1.scale = s;
                    out.push(j1);
                } else {
                    out.push(j1);
                    let mut j2 = keyrig_core::Joint::new(
                        unique(format!("{name} scaleOrientation")),
                        parent(out),
                        Vec3::ZERO,
                        Quat::IDENTITY,
                    );
                    j2.rotation = Animated::constant(so);
                    j2.scale = s;
                    out.push(j2);
                }
                let mut j3 = keyrig_core::Joint::new(
                    unique(format!("{name} center")),
                    parent(out),
                    Vec3::ZERO,
                    Quat::IDENTITY,
                );
                j3.translation = Animated::constant(-(so.inverse() * c));
                j3.rotation = Animated::constant(so.inverse());
                out.push(j3);
            }
        }
    }
}

/// Applies `m` to a mesh's positions and normals (inverse transpose), reversing the triangles
/// when `m` mirrors.
fn bake(m: Mat4, positions: &mut [Vec3], normals: &mut [Vec3], indices: &mut [u32]) {
    if m == Mat4::IDENTITY {
        return;
    }
    let n = Mat3::from_mat4(m).inverse().transpose();
    for p in positions.iter_mut() {
        *p = m.transform_point3(*p);
    }
    for v in normals.iter_mut() {
        *v = (n * *v).normalize_or(*v);
    }
    if m.determinant() < 0.0 {
        for t in indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
    }
}

/// Maps the expanded document to a [`VrmlModel`]; `skipped` holds what loading left out.
/// `traversal` has visited the scene graph (VRML/X3D: [`Traversal::visit_roots`]; Inventor:
/// `inventor::traverse`).
pub(crate) fn map_document(
    doc: &Document,
    mut traversal: Traversal<'_>,
    skipped: Vec<(String, String, Place)>,
    path: &Path,
) -> Result<VrmlModel, VrmlError> {
    let encoding = doc.files.first().map_or(Encoding::Vrml97, |f| f.encoding);
    let mut skips = std::mem::take(&mut traversal.skips);
    for (what, why, place) in skipped {
        skips.add(what, why, place);
    }
    let anim = analyse_animation(doc, &mut skips);
    let mut mapper = Mapper { doc, anim, skips, names: HashMap::new() };
    let mut objects = Vec::new();
    let mut meshes = Vec::new();
    for shape in &traversal.shapes {
        let (object, mesh) = mapper.shape(shape);
        objects.push(object);
        meshes.push(mesh);
    }
    for (o, object) in objects.iter_mut().enumerate() {
        object.mesh =
            Some(keyrig_core::MeshSource::File { path: String::new(), mesh: Some(o), clip: None, fps: None });
    }
    let mut lights = Vec::new();
    let mut light_names = HashMap::new();
    for l in &traversal.lights {
        lights.push(mapper.light(l, &mut light_names));
    }
    let mut camera_names = HashMap::new();
    let cameras: Vec<keyrig_core::SceneCamera> = traversal
        .views
        .iter()
        .map(|(v, frames, node)| mapper.camera(v, frames, *node, &mut camera_names))
        .collect();
    let views: Vec<View> = traversal
        .views
        .iter()
        .map(|(v, frames, _)| {
            let m = frames.iter().fold(Mat4::IDENTITY, |acc, f| acc * frame_matrix(doc, f));
            let (_, r, _) = m.to_scale_rotation_translation();
            View {
                position: m.transform_point3(v.position),
                orientation: (r * v.orientation).normalize(),
                ..v.clone()
            }
        })
        .collect();
    for ((node, field), _) in mapper.anim.channels.iter() {
        let kind = doc.node(*node).kind.as_str();
        let taken = matches!(
            (kind, field.as_str()),
            ("Transform" | "CADPart", "translation" | "rotation" | "scale" | "center" | "scaleOrientation")
                | ("Coordinate" | "Coordinate3", "point")
                | (
                    "DirectionalLight" | "PointLight" | "SpotLight",
                    "location" | "direction" | "color" | "intensity"
                )
                | ("SpotLight", "cutOffAngle" | "beamWidth")
                | ("Viewpoint" | "PerspectiveCamera", "position" | "orientation" | "fieldOfView")
                | ("PerspectiveCamera", "heightAngle")
                | ("OrthoViewpoint" | "OrthographicCamera", "position" | "orientation")
        ) || (encoding != Encoding::Inventor
            && matches!((kind, field.as_str()), ("Material", "diffuseColor" | "transparency")));
        if !taken {
            let why = match kind {
                "Material" if encoding == Encoding::Inventor => {
                    "an Inventor material's animation is not imported (keyrig's own export carries it as metadata)"
                }
                "Material" => "keyrig animates a material's diffuse colour and transparency only",
                _ => "keyrig has no channel for this field",
            };
            mapper.skips.add(format!("{kind}.{field} animation"), why, doc.node(*node).place);
        }
    }
    let skipped = mapper.skips.into_list(doc);
    let _ = path;
    let model = VrmlModel {
        encoding,
        objects,
        meshes,
        lights,
        views,
        cameras,
        duration: mapper.anim.duration,
        skipped,
        metadata_scene: None,
    };
    Ok(model)
}

impl Mapper<'_> {
    fn shape(&mut self, shape: &ShapeInstance) -> (keyrig_core::Object, VrmlMesh) {
        let doc = self.doc;
        let base = shape.names.first().cloned().unwrap_or_else(|| "Shape".into());
        let name = self.unique(&base);
        let mut object = keyrig_core::Object::new(name.clone());
        object.deformer.kind = keyrig_core::DeformerKind::Rigid;
        let (mut positions, mut normals, uvs, mut indices, coord) = match &shape.geometry {
            GeometryRef::Solid(s) => {
                (s.positions.clone(), s.normals.clone(), Some(s.uvs.clone()), s.indices.clone(), None)
            }
            GeometryRef::Poly { tess, points, coord } => {
                let f = tess.frame(points);
                (f.positions, f.normals, tess.uvs.clone(), tess.indices.clone(), *coord)
            }
        };
        let vertex_points = match &shape.geometry {
            GeometryRef::Poly { tess, .. } => Some(tess.vertex_point.clone()),
            GeometryRef::Solid(_) => None,
        };
        let morph_channel = coord.and_then(|c| match self.anim.channels.get(&(c, "point".to_owned())) {
            Some(Channel::Points(keys, frames, timing)) => Some((keys.clone(), frames.clone(), *timing)),
            _ => None,
        });
        let animated: Vec<usize> =
            shape.frames.iter().enumerate().filter(|(_, f)| self.frame_animated(f)).map(|(i, _)| i).collect();
        let matrices: Vec<Mat4> = shape.frames.iter().map(|f| frame_matrix(doc, f)).collect();
        let product =
            |range: std::ops::Range<usize>| matrices[range].iter().fold(Mat4::IDENTITY, |a, m| a * *m);
        let mut joints: Vec<keyrig_core::Joint> = Vec::new();
        let bake_matrix;
        let place_static = |object: &mut keyrig_core::Object, m: Mat4| -> Mat4 {
            match exact_trs(m) {
                Some((t, r, s)) => {
                    object.translation = Animated::constant(t);
                    object.rotation = Animated::constant(r);
                    object.scale = Animated::constant(s);
                    Mat4::IDENTITY
                }
                None => m,
            }
        };
        if animated.is_empty() || morph_channel.is_some() {
            if !animated.is_empty() {
                self.skips.add(
                    "Transform animation above a morphing shape",
                    "not imported: an object either morphs or follows a skeleton (the transforms at rest are used)",
                    shape.place,
                );
            }
            bake_matrix = place_static(&mut object, product(0..matrices.len()));
        } else {
            let (a, b) = (animated[0], animated[animated.len() - 1]);
            let prefix = product(0..a);
            let single = a == b && prefix.abs_diff_eq(Mat4::IDENTITY, 1e-9);
            let single_plain = match &shape.frames[a] {
                Frame::Transform { node, .. } => single && self.plain(*node),
                Frame::Matrix(_) => false,
            };
            if single_plain {
                if let Frame::Transform { node, .. } = &shape.frames[a] {
                    let (t, r, s) = self.trs(*node);
                    object.translation = t;
                    object.rotation = r;
                    object.scale = s;
                }
                bake_matrix = product(a + 1..matrices.len());
            } else {
                let mut used = HashMap::new();
                let first = match exact_trs(prefix) {
                    Some(_) => {
                        place_static(&mut object, prefix);
                        a
                    }
                    None => 0,
                };
                for f in &shape.frames[first..=b] {
                    self.joints_of(f, &mut joints, &mut used);
                }
                bake_matrix = product(b + 1..matrices.len());
            }
        }
        bake(bake_matrix, &mut positions, &mut normals, &mut indices);
        let morph = morph_channel.and_then(|(keys, frames, timing)| {
            let GeometryRef::Poly { tess, points, .. } = &shape.geometry else { return None };
            if frames.iter().any(|f| f.len() < points.len()) {
                self.skips.add(
                    "CoordinateInterpolator",
                    format!("its key values have fewer points than the Coordinate's {}", points.len()),
                    shape.place,
                );
                return None;
            }
            let morph_frames: Vec<geometry::Frame> = frames
                .iter()
                .map(|points| {
                    let mut f = tess.frame(points);
                    let mut scratch = indices.clone();
                    bake(bake_matrix, &mut f.positions, &mut f.normals, &mut scratch);
                    f
                })
                .collect();
            let times: Vec<f64> = keys.iter().map(|k| k.clamp(0.0, 1.0) * timing.cycle).collect();
            Some(MorphKeys { times, period: timing.looping.then_some(timing.cycle), frames: morph_frames })
        });
        let joint_names: Vec<String> = if joints.is_empty() {
            vec!["root".into()]
        } else {
            joints.iter().map(|j| j.name.clone()).collect()
        };
        if !joints.is_empty() {
            object.skeleton = Some(keyrig_core::Skeleton::new(joints));
        }
        let mesh = VrmlMesh {
            name,
            positions,
            normals,
            uvs,
            indices,
            material: shape.material.clone(),
            joints: joint_names,
            morph,
            vertex_points,
            baked: bake_matrix,
        };
        self.material_animation(shape, &mut object);
        (object, mesh)
    }

    /// A `Material`'s animated `diffuseColor` and `transparency` as the object's colour and
    /// opacity attributes (opacity = 1 − transparency, an affine map of the keys: exact).
    fn material_animation(&self, shape: &ShapeInstance, object: &mut keyrig_core::Object) {
        let Some(m) = shape.material_node else { return };
        let field = |f: &str| self.anim.channels.get(&(m, f.to_owned()));
        if let Some(Channel::Vec3(track, timing)) = field("diffuseColor") {
            let rest = Vec3::from_slice(&shape.material.base_colour[..3]);
            object.attributes.colour = Some(animated(rest, track, *timing));
        }
        if let Some(Channel::Scalar(track, timing)) = field("transparency") {
            let opaque = scaled(track, |t: f32| 1.0 - t.clamp(0.0, 1.0), |t: f32| -t);
            object.attributes.opacity = animated(shape.material.base_colour[3], &opaque, *timing);
        }
    }

    /// A view as a scene camera, placed by the transforms above it, with the animation of its
    /// `position`, `orientation` and `fieldOfView` (radians → the lens in degrees).
    fn camera(
        &mut self,
        view: &View,
        frames: &[Frame],
        node: Option<NodeId>,
        names: &mut HashMap<String, usize>,
    ) -> keyrig_core::SceneCamera {
        let doc = self.doc;
        let base = view.name.replace('/', "_");
        let n = names.entry(base.clone()).or_insert(0);
        *n += 1;
        let name = if *n > 1 { format!("{base} {n}") } else { base };
        let m = frames.iter().fold(Mat4::IDENTITY, |acc, f| acc * frame_matrix(doc, f));
        let (_, r, _) = m.to_scale_rotation_translation();
        let linear = Mat3::from_mat4(m);
        let mut camera = keyrig_core::SceneCamera::new(name, m.transform_point3(view.position));
        camera.rotation = Animated::constant((r * view.orientation).normalize());
        camera.far = None;
        match view.orthographic {
            Some(height) => {
                camera.projection = keyrig_core::Projection::Orthographic;
                camera.lens = Animated::constant(height);
                // keyrig's orthographic cameras need a far plane; VRML's has none.
                camera.far = Some(1e6);
            }
            None => camera.lens = Animated::constant(lens_degrees(view.field_of_view)),
        }
        let Some(node) = node else { return camera };
        if frames.iter().any(|f| self.frame_animated(f)) {
            self.skips.add(
                "Viewpoint under an animated Transform",
                "the camera stays where the transforms put it at rest",
                doc.node(node).place,
            );
        }
        let field = |f: &str| self.anim.channels.get(&(node, f.to_owned()));
        if let Some(Channel::Vec3(track, timing)) = field("position") {
            // Into world space: the same affine image of the curve (tangents by the linear part).
            let keys = scaled(track, |p| m.transform_point3(p), |t| linear * t);
            camera.translation = animated(camera.translation.value, &keys, *timing);
        }
        if let Some(Channel::Quat(track, timing)) = field("orientation") {
            // r·q for every key: slerp and squad commute with a fixed rotation in front.
            let keys = scaled(track, |q| (r * q).normalize(), |t| r * t);
            camera.rotation = animated(camera.rotation.value, &keys, *timing);
        }
        let fov = field("fieldOfView").or_else(|| field("heightAngle"));
        if let (Some(Channel::Scalar(track, timing)), None) = (fov, view.orthographic) {
            let keys = scaled(track, lens_degrees, |v: f32| v.to_degrees());
            camera.lens = animated(camera.lens.value, &keys, *timing);
        }
        camera
    }

    fn light(&mut self, l: &LightInstance, names: &mut HashMap<String, usize>) -> keyrig_core::Light {
        let doc = self.doc;
        let mut light = l.light.clone();
        let n = names.entry(light.name.clone()).or_insert(0);
        *n += 1;
        if *n > 1 {
            light.name = format!("{} {n}", light.name);
        }
        light.name = light.name.replace('/', "_");
        if l.frames.iter().any(|f| self.frame_animated(f)) {
            self.skips.add(
                "light under an animated Transform",
                "the light stays where the transforms put it at rest",
                l.node.map_or(Place { file: super::tree::FileId(0), at: 0 }, |n| doc.node(n).place),
            );
        }
        let m = l.frames.iter().fold(Mat4::IDENTITY, |acc, f| acc * frame_matrix(doc, f));
        let Some(node) = l.node else { return light };
        let field = |f: &str| self.anim.channels.get(&(node, f.to_owned())).cloned();
        if let Some(Channel::Vec3(track, timing)) = field("location") {
            light.position = animated(light.position.value, &track, timing);
        }
        if let Some(Channel::Vec3(track, timing)) = field("direction") {
            light.direction = animated(light.direction.value, &track, timing);
        }
        if let Some(Channel::Vec3(track, timing)) = field("color") {
            light.colour = animated(light.colour.value, &track, timing);
        }
        if let Some(Channel::Scalar(track, timing)) = field("intensity") {
            light.intensity = animated(light.intensity.value, &track, timing);
        }
        // A spot's cone in radians → the cone attributes in degrees (a scale: exact).
        // Within keyrig's 0 < inner ≤ cutoff ≤ 90° (VRML's beam wider than the cut-off has no
        // falloff: the inner angle is the cut-off).
        if let keyrig_core::LightKind::Spot { cutoff_deg, inner_angle_deg, .. } = light.kind {
            let degrees = |f: &str, rest: f32, most: f32| match field(f) {
                Some(Channel::Scalar(track, timing)) => Some(animated(
                    rest,
                    &scaled(&track, |v: f32| v.to_degrees().clamp(0.01, most), |v: f32| v.to_degrees()),
                    timing,
                )),
                _ => None,
            };
            let cutoff = degrees("cutOffAngle", cutoff_deg, 90.0);
            let most_inner = if cutoff.is_some() { 90.0 } else { cutoff_deg };
            if let Some(a) = degrees("beamWidth", inner_angle_deg, most_inner) {
                light.attributes.inner_angle_deg = Some(a);
            }
            light.attributes.cutoff_deg = cutoff;
        }
        // Into world space: an affine image of linear keys is the same image of the line.
        if m != Mat4::IDENTITY {
            light.position.value = m.transform_point3(light.position.value);
            let r = Mat3::from_mat4(m);
            for k in light.position.track.keys.iter_mut() {
                k.value = m.transform_point3(k.value);
                // Spline tangents are differences: the linear part alone.
                k.in_tangent = k.in_tangent.map(|t| r * t);
                k.out_tangent = k.out_tangent.map(|t| r * t);
            }
            light.direction.value = r * light.direction.value;
            for k in light.direction.track.keys.iter_mut() {
                k.value = r * k.value;
                k.in_tangent = k.in_tangent.map(|t| r * t);
                k.out_tangent = k.out_tangent.map(|t| r * t);
            }
        }
        light
    }
}
