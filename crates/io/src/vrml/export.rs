//! A keyrig scene written as VRML97 (`.wrl`), X3D (classic `.x3dv`, XML `.x3d`) or Open
//! Inventor (`.iv`) with its animation, so that Coin3D and X3D viewers play it.
//!
//! - Every object is a `Transform` named after it (its translation, rotation and scale at the
//!   range's first frame) holding a `Shape` with its mesh and base colour. A skinned object
//!   (or an imported one with a skeleton, or a morphing one) is written as the mesh its own
//!   deformer makes (rigid, linear blend, bones blending, dual quaternion) at each sample, as
//!   a `CoordinateInterpolator` on its `Coordinate`: any VRML viewer then plays a twist
//!   without the candy wrapper.
//! - One looping `TimeSensor` spans the scene's frame range; every animated channel is an
//!   interpolator routed to its field. Its keys are the channel's values, sampled from the
//!   scene evaluator at the channel's key times and at every frame, and more where the
//!   interpolator's straight line (slerp for rotations, HSV for colours) would leave keyrig's
//!   curve by more than the tolerances ([`VrmlExportOptions`]): halving the interval until the
//!   midpoint and quarter points are within them. Rotation samples are never 90° or more
//!   apart, so that each slerp turns the way keyrig turns. In X3D, a channel whose keys
//!   X3D's `SplinePositionInterpolator`, `SplineScalarInterpolator` or
//!   `SquadOrientationInterpolator` holds exactly (evenly spaced TCB keys, no cycles; for the
//!   squad T = C = B = 0 inside and X3D's open ends) is written as one, key for key, after
//!   checking it at every frame ([`Channels`]).
//! - The writers of one value kind are one each ([`Channels::vec3`], [`Channels::scalar`],
//!   [`Channels::rotation`]) for objects and lights alike.
//! - keyrig's own scene (its keys with tension, continuity and bias, cycles, spins, skeletons)
//!   goes into the file as metadata — a `WorldInfo` `info` string (an Inventor `Info` node's
//!   `string`) that starts with [`METADATA_TAG`] and holds the scene as RON — and the importer
//!   takes the keys back from it ([`restore_metadata`]), so keyrig reads its own export back
//!   to the same keys.
//!
//! Open Inventor has no keyframe interpolators of its own; the file uses Coin's VRML97
//! interpolator nodes (`VRMLTimeSensor`, `VRMLPositionInterpolator`, …) connected by field
//! connections (`translation 0 0 0 = USE P.value_changed`), which Coin reads in `.iv` files.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{Animated, Cycles, Interpolation, MeshSource, RawTrack, Scene, Track, TrackValue};
use keyrig_eval::{LoadedMesh, Overrides, SceneEvaluator};

use super::map::hsv_lerp;
use super::splines::{self, SplineValue};

pub use super::tree::METADATA_TAG;

/// The file format, from the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    Vrml97,
    X3dClassic,
    X3dXml,
    Inventor,
}

impl ExportFormat {
    /// `.wrl`, `.x3dv`, `.x3d` or `.iv` (case-insensitive).
    #[must_use]
    pub fn of_path(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "wrl" => Some(ExportFormat::Vrml97),
            "x3dv" => Some(ExportFormat::X3dClassic),
            "x3d" => Some(ExportFormat::X3dXml),
            "iv" => Some(ExportFormat::Inventor),
            _ => None,
        }
    }
}

/// Tolerances of the resampling.
#[derive(Clone, Debug)]
pub struct VrmlExportOptions {
    /// Folder that relative `MeshSource::File` paths resolve against.
    pub base_dir: Option<PathBuf>,
    /// Largest position difference, as a fraction of the scene's size (the diagonal of its
    /// meshes' rest bounds, at least 1 unit).
    pub position_tolerance: f64,
    /// Largest rotation difference, degrees.
    pub rotation_tolerance_deg: f64,
    /// Largest colour difference per channel.
    pub colour_tolerance: f64,
}

impl Default for VrmlExportOptions {
    fn default() -> Self {
        VrmlExportOptions {
            base_dir: None,
            position_tolerance: 1e-4,
            rotation_tolerance_deg: 0.05,
            colour_tolerance: 1e-3,
        }
    }
}

/// Why a scene cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum VrmlExportError {
    #[error("{object}: its mesh cannot be read: {message}")]
    Mesh { object: String, message: String },
    #[error("the scene cannot be evaluated: {0}")]
    Evaluate(String),
    #[error("the scene cannot be written as RON metadata: {0}")]
    Metadata(String),
}

/// A node being written.
#[derive(Clone, Debug, Default)]
struct WNode {
    kind: &'static str,
    def: Option<String>,
    fields: Vec<(&'static str, WValue)>,
}

#[derive(Clone, Debug)]
enum WValue {
    Numbers(Vec<f64>, usize),
    Bool(bool),
    /// An SFString.
    String(String),
    Strings(Vec<String>),
    Node(Box<WNode>),
    Nodes(Vec<WNode>),
}

/// A `DEF` name from a keyrig name: letters, digits and `_` (others become `_`), not starting
/// with a digit, unique.
fn def_name(name: &str, used: &mut HashMap<String, usize>) -> String {
    let mut s: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    let n = used.entry(s.clone()).or_insert(0);
    *n += 1;
    if *n > 1 {
        s = format!("{s}_{n}");
    }
    s
}

/// Samples of a channel over `[t0, t1]`: key times and every frame, plus midpoints wherever
/// `close(a, b, mid)` says the interpolator's straight line misses keyrig's value.
fn schedule<T: Clone>(
    value: &dyn Fn(f64) -> T,
    close: &dyn Fn(&T, &T, &T, f32) -> bool,
    t0: f64,
    t1: f64,
    fps: f64,
    keys: &[f64],
) -> Vec<(f64, T)> {
    let mut times: Vec<f64> = Vec::new();
    let frames = ((t1 - t0) * fps).round().max(0.0) as i64;
    times.extend((0..=frames).map(|f| t0 + f as f64 / fps));
    times.extend(keys.iter().copied().filter(|&k| k > t0 && k < t1));
    times.sort_by(f64::total_cmp);
    times.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut out: Vec<(f64, T)> = Vec::with_capacity(times.len());
    for w in times.windows(2) {
        let (a, b) = (w[0], w[1]);
        if out.is_empty() {
            out.push((a, value(a)));
        }
        // Halve until the quarter, half and three-quarter points are on the line.
        let mut stack = vec![(a, b, 0)];
        let mut pieces = Vec::new();
        while let Some((x, y, depth)) = stack.pop() {
            let (vx, vy) = (value(x), value(y));
            let fits =
                [0.25f32, 0.5, 0.75].iter().all(|&u| close(&vx, &vy, &value(x + (y - x) * f64::from(u)), u));
            if fits || depth >= 12 {
                pieces.push(y);
            } else {
                let m = 0.5 * (x + y);
                stack.push((m, y, depth + 1));
                stack.push((x, m, depth + 1));
            }
        }
        pieces.sort_by(f64::total_cmp);
        for p in pieces {
            out.push((p, value(p)));
        }
    }
    if out.is_empty() {
        out.push((t0, value(t0)));
    }
    out
}

fn vec3_of(v: Option<ChannelValue>) -> Vec3 {
    match v {
        Some(ChannelValue::Vec3(v)) => v,
        _ => Vec3::ZERO,
    }
}

fn quat_of(v: Option<ChannelValue>) -> Quat {
    match v {
        Some(ChannelValue::Rotation(q)) => q.normalize(),
        _ => Quat::IDENTITY,
    }
}

fn scalar_of(v: Option<ChannelValue>) -> f32 {
    match v {
        Some(ChannelValue::Scalar(s)) => s,
        _ => 0.0,
    }
}

fn axis_angle(q: Quat) -> [f64; 4] {
    let (axis, angle) = q.normalize().to_axis_angle();
    if angle.abs() < 1e-12 || !axis.is_finite() {
        [0.0, 0.0, 1.0, 0.0]
    } else {
        [f64::from(axis.x), f64::from(axis.y), f64::from(axis.z), f64::from(angle)]
    }
}

/// A loaded mesh for the export: rest positions, triangles, colour, and how it is evaluated.
struct MeshOut {
    mesh: Option<Arc<keyrig_skin::SkinnedMesh>>,
    morph: Option<super::map::MorphKeys>,
    indices: Vec<u32>,
    colour: [f32; 4],
}

fn load_meshes(scene: &Scene, options: &VrmlExportOptions) -> Result<Vec<Option<MeshOut>>, VrmlExportError> {
    let mut vrml_files: HashMap<PathBuf, Arc<super::VrmlModel>> = HashMap::new();
    let mut gltf_files: HashMap<PathBuf, Arc<crate::model::ImportedModel>> = HashMap::new();
    let mut out = Vec::with_capacity(scene.objects.len());
    for object in &scene.objects {
        let fail = |message: String| VrmlExportError::Mesh { object: object.name.clone(), message };
        let entry = match &object.mesh {
            None => None,
            Some(MeshSource::Procedural(kind)) => {
                let mut mesh = keyrig_skin::mesh_for(*kind);
                if let Some(rest) =
                    object.skeleton.as_ref().and_then(|s| keyrig_skin::RestSkeleton::from_scene(s).ok())
                {
                    if let Ok(fitted) = mesh.clone().fit_to_skeleton(rest) {
                        mesh = fitted;
                    }
                }
                let indices = mesh.indices.clone();
                Some(MeshOut {
                    mesh: Some(Arc::new(mesh)),
                    morph: None,
                    indices,
                    colour: [0.8, 0.8, 0.8, 1.0],
                })
            }
            Some(MeshSource::File { path, mesh, .. }) => {
                let file = options.base_dir.as_deref().unwrap_or(Path::new("")).join(path);
                let index = mesh.unwrap_or(0);
                if super::is_vrml_path(&file) {
                    let model = match vrml_files.get(&file) {
                        Some(m) => Arc::clone(m),
                        None => {
                            let m =
                                Arc::new(super::import_vrml_file(&file).map_err(|e| fail(e.to_string()))?);
                            vrml_files.insert(file.clone(), Arc::clone(&m));
                            m
                        }
                    };
                    let m = model.meshes.get(index).ok_or_else(|| fail(format!("no mesh {index}")))?;
                    Some(MeshOut {
                        mesh: Some(Arc::new(model.skinned_mesh(index).map_err(|e| fail(e.to_string()))?)),
                        morph: m.morph.clone(),
                        indices: m.indices.clone(),
                        colour: m.material.base_colour,
                    })
                } else if file
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("glb") || e.eq_ignore_ascii_case("gltf"))
                {
                    let model = match gltf_files.get(&file) {
                        Some(m) => Arc::clone(m),
                        None => {
                            let m = Arc::new(
                                crate::gltf_import::import_gltf_file(&file)
                                    .map_err(|e| fail(e.to_string()))?,
                            );
                            gltf_files.insert(file.clone(), Arc::clone(&m));
                            m
                        }
                    };
                    let node = model
                        .nodes
                        .iter()
                        .position(|n| n.mesh == Some(index))
                        .ok_or_else(|| fail(format!("no node shows mesh {index}")))?;
                    let colour =
                        model.material(index).ok().flatten().map_or([0.8, 0.8, 0.8, 1.0], |m| m.base_colour);
                    if model.nodes[node].skin.is_some() {
                        let skinned = model.skinned_mesh(node).map_err(|e| fail(e.to_string()))?;
                        let indices = skinned.indices.clone();
                        Some(MeshOut { mesh: Some(Arc::new(skinned)), morph: None, indices, colour })
                    } else {
                        let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
                        for p in model.meshes[index]
                            .primitives
                            .iter()
                            .filter(|p| p.mode == crate::model::PrimitiveMode::Triangles)
                        {
                            let base = positions.len() as u32;
                            positions.extend_from_slice(&p.positions);
                            normals.extend(p.normals.as_deref().map_or_else(
                                || keyrig_skin::mesh::vertex_normals(&p.positions, &p.indices),
                                <[Vec3]>::to_vec,
                            ));
                            indices.extend(p.indices.iter().map(|i| i + base));
                        }
                        let n = positions.len();
                        let rest = keyrig_skin::RestSkeleton::new(&[keyrig_skin::RestJoint::new(
                            "root",
                            None,
                            Vec3::ZERO,
                            Quat::IDENTITY,
                        )])
                        .map_err(|e| fail(e.to_string()))?;
                        let rigid = keyrig_skin::SkinnedMesh::new(
                            positions,
                            normals,
                            indices.clone(),
                            vec![[0; 4]; n],
                            vec![[1.0, 0.0, 0.0, 0.0]; n],
                            Some(vec![0; n]),
                            rest,
                        )
                        .map_err(|e| fail(e.to_string()))?;
                        Some(MeshOut { mesh: Some(Arc::new(rigid)), morph: None, indices, colour })
                    }
                } else if file.extension().is_some_and(|e| e.eq_ignore_ascii_case("md2")) {
                    // An MD2 model plays its clip's frames at `fps`, looping, the last morphing
                    // back into the first: morph keys at k / fps, the first frame again at the
                    // end, repeating every n / fps.
                    let model = crate::md2::load_md2_file(&file).map_err(|e| fail(e.to_string()))?;
                    let MeshSource::File { clip, fps, .. } = object.mesh.as_ref().expect("file mesh") else {
                        unreachable!("a file mesh")
                    };
                    let fps = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
                    let range = match clip {
                        Some(name) => model
                            .clips
                            .iter()
                            .find(|c| &c.name == name)
                            .map(|c| c.frames.clone())
                            .ok_or_else(|| fail(format!("`{path}` has no clip `{name}`")))?,
                        None => 0..model.frames.len(),
                    };
                    let mut frames: Vec<super::geometry::Frame> = range
                        .filter_map(|f| model.frame_pose(f))
                        .map(|p| super::geometry::Frame { positions: p.positions, normals: p.normals })
                        .collect();
                    if frames.is_empty() || !(fps.is_finite() && fps > 0.0) {
                        return Err(fail(format!("`{path}`: no frames to play at {fps} fps")));
                    }
                    let n = frames.len();
                    frames.push(frames[0].clone());
                    let times = (0..=n).map(|k| k as f64 / fps).collect();
                    Some(MeshOut {
                        mesh: None,
                        morph: Some(super::map::MorphKeys { times, period: Some(n as f64 / fps), frames }),
                        indices: model.indices.clone(),
                        colour: [1.0, 1.0, 1.0, 1.0],
                    })
                } else {
                    return Err(fail(format!("`{path}` is not a model file keyrig reads")));
                }
            }
        };
        out.push(entry);
    }
    Ok(out)
}

/// The scene as the text of `format`.
///
/// # Errors
/// A mesh file cannot be read, or the scene cannot be evaluated or written as metadata.
pub fn export_scene(
    scene: &Scene,
    format: ExportFormat,
    options: &VrmlExportOptions,
) -> Result<String, VrmlExportError> {
    // The metadata keeps the scene as it is; the nodes and interpolators are written from
    // quaternion keys that follow Euler keys within a tenth of the tolerance (VRML rotations
    // are axis–angles; docs/channels.md, "Euler keys").
    let original = scene;
    let range =
        (f64::from(scene.frame_range.start) / scene.fps, f64::from(scene.frame_range.end) / scene.fps);
    // VRML has no constraints: a constrained object's evaluated transform becomes keys at every
    // frame first (docs/constraints.md, "Baking and export"); the metadata keeps them.
    let mut constrained = std::borrow::Cow::Borrowed(scene);
    if scene.objects.iter().any(|o| !o.constraints.is_empty()) {
        let mut baked = scene.clone();
        keyrig_eval::bake_object_constraints(&mut baked, scene.frame_range.start, scene.frame_range.end)
            .map_err(|e| VrmlExportError::Evaluate(format!("constraints: {e}")))?;
        constrained = std::borrow::Cow::Owned(baked);
    }
    let following = constrained
        .with_quaternion_keys(range, options.rotation_tolerance_deg / 10.0)
        .map_err(|(path, e)| VrmlExportError::Metadata(format!("{path}: {e}")))?;
    let scene = following.as_ref();
    let meshes = load_meshes(scene, options)?;
    let loaded: HashMap<usize, LoadedMesh> = meshes
        .iter()
        .enumerate()
        .filter_map(|(o, m)| {
            let m = m.as_ref()?;
            let skinned = scene.objects[o].skeleton.is_some()
                || matches!(scene.objects[o].mesh, Some(MeshSource::File { .. }));
            (skinned && m.mesh.is_some())
                .then(|| (o, LoadedMesh::Skinned(Arc::clone(m.mesh.as_ref().expect("mesh")))))
        })
        .collect();
    let eval = SceneEvaluator::new(scene, &loaded);
    let fps = scene.fps;
    let (t0, t1) = (f64::from(scene.frame_range.start) / fps, f64::from(scene.frame_range.end) / fps);
    let duration = t1 - t0;
    let none = Overrides::default();
    let at = |id: ChannelId, t: f64| eval.value(id, t, &none);
    // The scene's size for the position tolerance.
    let mut lo = Vec3::MAX;
    let mut hi = Vec3::MIN;
    for m in meshes.iter().flatten() {
        for p in m.mesh.iter().flat_map(|m| m.positions.iter()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
    }
    let size = if lo.cmple(hi).all() { f64::from((hi - lo).length()).max(1.0) } else { 1.0 };
    let pos_tol = (options.position_tolerance * size) as f32;
    let animated = duration > 0.0;
    let fraction = |t: f64| if duration > 0.0 { (t - t0) / duration } else { 0.0 };
    let ch = Channels {
        eval: &eval,
        t0,
        t1,
        fps,
        pos_tol,
        rot_tol: options.rotation_tolerance_deg.to_radians() as f32,
        col_tol: options.colour_tolerance as f32,
        x3d: matches!(format, ExportFormat::X3dClassic | ExportFormat::X3dXml),
    };

    let ExportedNames { objects: object_defs, lights: light_defs, cameras: camera_defs, mut used } =
        exported_names(scene);
    let clock = def_name("KeyrigClock", &mut used);
    let mut roots: Vec<WNode> = Vec::new();
    let ron = crate::scene_file::to_string(original).map_err(|e| VrmlExportError::Metadata(e.to_string()))?;
    roots.push(WNode {
        kind: "WorldInfo",
        def: None,
        fields: vec![
            ("title", WValue::String("keyrig scene".into())),
            ("info", WValue::Strings(vec![format!("{METADATA_TAG}\n{ron}")])),
        ],
    });
    if animated {
        roots.push(WNode {
            kind: "TimeSensor",
            def: Some(clock.clone()),
            fields: vec![("cycleInterval", WValue::Numbers(vec![duration], 1)), ("loop", WValue::Bool(true))],
        });
    }
    let mut out = Animations { used, clock: clock.clone(), interpolators: Vec::new(), routes: Vec::new() };
    for (o, object) in scene.objects.iter().enumerate() {
        let def = object_defs[o].clone();
        let translation = vec3_of(at(ChannelId::ObjectTranslation(o), t0));
        let rotation = quat_of(at(ChannelId::ObjectRotation(o), t0));
        let scale = vec3_of(at(ChannelId::ObjectScale(o), t0));
        let mut fields = vec![
            ("translation", WValue::Numbers(translation.to_array().map(f64::from).to_vec(), 3)),
            ("rotation", WValue::Numbers(axis_angle(rotation).to_vec(), 4)),
            ("scale", WValue::Numbers(scale.to_array().map(f64::from).to_vec(), 3)),
        ];
        if animated {
            ch.vec3(
                &mut out,
                ChannelId::ObjectTranslation(o),
                &object.translation,
                Vec3Blend::Position,
                &def,
                "translation",
            );
            ch.vec3(&mut out, ChannelId::ObjectScale(o), &object.scale, Vec3Blend::Position, &def, "scale");
            ch.rotation(&mut out, ChannelId::ObjectRotation(o), &object.rotation, &def, "rotation");
        }
        let mut children = Vec::new();
        if let Some(m) = &meshes[o] {
            let shape_def = def_name(&format!("{def}_points"), &mut out.used);
            // The mesh at time t in the object's space: deformed by its own deformer, or
            // morphed, or at rest.
            let deformed = |t: f64| -> Option<Vec<Vec3>> {
                if let Some(morph) = &m.morph {
                    let clips = keyrig_eval::morph::MorphClips::new(morph.frames.len(), Vec::new())
                        .ok()?
                        .with_key_times(morph.times.clone(), morph.period)
                        .ok()?;
                    let b = clips.blend_at(None, 10.0, t).ok()?;
                    let (fa, fb) = (&morph.frames[b.frame_a as usize], &morph.frames[b.frame_b as usize]);
                    return Some(
                        fa.positions.iter().zip(&fb.positions).map(|(a, c)| a.lerp(*c, b.t)).collect(),
                    );
                }
                let skin = eval.skin(o)?;
                let state = eval.object_at(o, t, &none)?;
                let bindings = std::sync::Arc::clone(state.bindings(skin));
                let palette = state.palette?;
                let mut out = keyrig_skin::Deformed::default();
                keyrig_skin::deform_mesh_into(
                    &skin.mesh,
                    &bindings,
                    &palette,
                    object.deformer.kind,
                    keyrig_skin::Execution::Reference,
                    &mut out,
                )
                .ok()?;
                Some(out.positions)
            };
            let rest: Vec<Vec3> =
                deformed(t0).or_else(|| m.mesh.as_ref().map(|s| s.positions.clone())).unwrap_or_default();
            let skeleton_moves = object.skeleton.as_ref().is_some_and(|s| {
                s.root_translation.is_animated()
                    || s.joints.iter().any(|j| {
                        j.rotation.is_animated() || j.translation.is_animated() || j.scale.is_animated()
                    })
                    || s.ik_constraints.iter().any(|c| c.target.is_animated() || c.blend.is_animated())
            });
            let moves = animated && (m.morph.is_some() || eval.skin(o).is_some() && skeleton_moves);
            if moves {
                let fits = |a: &Vec<Vec3>, b: &Vec<Vec3>, mid: &Vec<Vec3>, u: f32| {
                    a.iter()
                        .zip(b)
                        .zip(mid)
                        .all(|((a, b), m)| (a.lerp(*b, u) - *m).abs().max_element() <= pos_tol)
                };
                let s = schedule(&|t| deformed(t).unwrap_or_else(|| rest.clone()), &fits, t0, t1, fps, &[]);
                out.interp_with(
                    "CoordinateInterpolator",
                    (&def, &shape_def),
                    s.iter().map(|(t, _)| fraction(*t)).collect(),
                    s.iter().flat_map(|(_, v)| v.iter().flat_map(|p| p.to_array().map(f64::from))).collect(),
                    3,
                    Vec::new(),
                    "point",
                );
            }
            let coord = WNode {
                kind: "Coordinate",
                def: Some(shape_def),
                fields: vec![(
                    "point",
                    WValue::Numbers(rest.iter().flat_map(|p| p.to_array().map(f64::from)).collect(), 3),
                )],
            };
            let index: Vec<f64> = m
                .indices
                .chunks_exact(3)
                .flat_map(|t| [f64::from(t[0]), f64::from(t[1]), f64::from(t[2]), -1.0])
                .collect();
            // The colour and opacity attributes replace the mesh's colour and scale its alpha.
            let mut c = m.colour;
            if let Some(colour) = object
                .attributes
                .colour
                .as_ref()
                .map(|_| vec3_of(at(ChannelId::Attribute(keyrig_core::AttributeId::ObjectColour(o)), t0)))
            {
                c[..3].copy_from_slice(&colour.to_array());
            }
            let alpha = c[3];
            c[3] = alpha
                * scalar_of(at(ChannelId::Attribute(keyrig_core::AttributeId::ObjectOpacity(o)), t0))
                    .clamp(0.0, 1.0);
            let colour_keys = object.attributes.colour.as_ref().filter(|a| a.is_animated());
            let opacity_keys = Some(&object.attributes.opacity).filter(|a| a.is_animated());
            let material_def = (animated && (colour_keys.is_some() || opacity_keys.is_some()))
                .then(|| def_name(&format!("{def}_material"), &mut out.used));
            if let Some(mdef) = &material_def {
                if let Some(keys) = colour_keys {
                    let id = ChannelId::Attribute(keyrig_core::AttributeId::ObjectColour(o));
                    ch.vec3(&mut out, id, keys, Vec3Blend::Colour, mdef, "diffuseColor");
                }
                if let Some(keys) = opacity_keys {
                    let id = ChannelId::Attribute(keyrig_core::AttributeId::ObjectOpacity(o));
                    let transparency = |t: f64| 1.0 - alpha * scalar_of(ch.at(id, t)).clamp(0.0, 1.0);
                    ch.scalar_resampled(&mut out, &transparency, &key_times(keys), mdef, "transparency");
                }
            }
            children.push(WNode {
                kind: "Shape",
                def: None,
                fields: vec![
                    (
                        "appearance",
                        WValue::Node(Box::new(WNode {
                            kind: "Appearance",
                            def: None,
                            fields: vec![(
                                "material",
                                WValue::Node(Box::new(WNode {
                                    kind: "Material",
                                    def: material_def,
                                    fields: vec![
                                        (
                                            "diffuseColor",
                                            WValue::Numbers(
                                                vec![f64::from(c[0]), f64::from(c[1]), f64::from(c[2])],
                                                3,
                                            ),
                                        ),
                                        ("transparency", WValue::Numbers(vec![f64::from(1.0 - c[3])], 1)),
                                    ],
                                })),
                            )],
                        })),
                    ),
                    (
                        "geometry",
                        WValue::Node(Box::new(WNode {
                            kind: "IndexedFaceSet",
                            def: None,
                            fields: vec![
                                ("coord", WValue::Node(Box::new(coord))),
                                ("coordIndex", WValue::Numbers(index, 4)),
                                ("creaseAngle", WValue::Numbers(vec![1.0], 1)),
                                ("solid", WValue::Bool(false)),
                            ],
                        })),
                    ),
                ],
            });
        }
        fields.push(("children", WValue::Nodes(children)));
        roots.push(WNode { kind: "Transform", def: Some(def), fields });
    }
    for (l, light) in scene.lights.iter().enumerate() {
        let def = light_defs[l].clone();
        let kind = match light.kind {
            keyrig_core::LightKind::Directional => "DirectionalLight",
            keyrig_core::LightKind::Point => "PointLight",
            keyrig_core::LightKind::Spot { .. } => "SpotLight",
        };
        let p = vec3_of(at(ChannelId::LightPosition(l), t0));
        let d = vec3_of(at(ChannelId::LightDirection(l), t0));
        let c = vec3_of(at(ChannelId::LightColour(l), t0));
        let i = scalar_of(at(ChannelId::LightIntensity(l), t0));
        let mut fields = vec![
            ("on", WValue::Bool(light.enabled)),
            ("color", WValue::Numbers(c.clamp(Vec3::ZERO, Vec3::ONE).to_array().map(f64::from).to_vec(), 3)),
            ("intensity", WValue::Numbers(vec![f64::from(i.clamp(0.0, 1.0))], 1)),
        ];
        if kind != "DirectionalLight" {
            fields.push(("location", WValue::Numbers(p.to_array().map(f64::from).to_vec(), 3)));
        }
        if kind != "PointLight" {
            fields.push(("direction", WValue::Numbers(d.to_array().map(f64::from).to_vec(), 3)));
        }
        if let keyrig_core::LightKind::Spot { cutoff_deg, inner_angle_deg, .. } = light.kind {
            // The cone attributes replace the kind's angles; keyed, they are interpolated
            // (degrees in keyrig, radians in VRML).
            let cone = [
                (
                    "cutOffAngle",
                    cutoff_deg,
                    &light.attributes.cutoff_deg,
                    keyrig_core::AttributeId::LightCutoff(l),
                ),
                (
                    "beamWidth",
                    inner_angle_deg,
                    &light.attributes.inner_angle_deg,
                    keyrig_core::AttributeId::LightInnerAngle(l),
                ),
            ];
            for (field, rest, attribute, id) in cone {
                let radians = |t: f64| match attribute {
                    Some(_) => scalar_of(ch.at(ChannelId::Attribute(id), t)).to_radians(),
                    None => rest.to_radians(),
                };
                fields.push((field, WValue::Numbers(vec![f64::from(radians(t0))], 1)));
                if let Some(keys) = attribute.as_ref().filter(|a| animated && a.is_animated()) {
                    ch.scalar_resampled(&mut out, &radians, &key_times(keys), &def, field);
                }
            }
        }
        if animated {
            if kind != "DirectionalLight" {
                ch.vec3(
                    &mut out,
                    ChannelId::LightPosition(l),
                    &light.position,
                    Vec3Blend::Position,
                    &def,
                    "location",
                );
            }
            if kind != "PointLight" {
                ch.vec3(
                    &mut out,
                    ChannelId::LightDirection(l),
                    &light.direction,
                    Vec3Blend::Position,
                    &def,
                    "direction",
                );
            }
            ch.vec3(&mut out, ChannelId::LightColour(l), &light.colour, Vec3Blend::Colour, &def, "color");
            ch.scalar(&mut out, ChannelId::LightIntensity(l), &light.intensity, &def, "intensity");
        }
        roots.push(WNode { kind, def: Some(def), fields });
    }
    // Cameras: the active one first (VRML binds the first Viewpoint when the world loads).
    let first = scene.active_camera_at(f64::from(scene.frame_range.start));
    let order = first.into_iter().chain((0..scene.cameras.len()).filter(|&c| Some(c) != first));
    for c in order {
        roots.push(camera_node(scene, &eval, &ch, &mut out, c, &camera_defs[c], animated));
    }
    let routes = out.routes;
    roots.extend(out.interpolators);
    Ok(match format {
        ExportFormat::Vrml97 | ExportFormat::X3dClassic => classic(format, &roots, &routes),
        ExportFormat::X3dXml => xml(&roots, &routes),
        ExportFormat::Inventor => inventor(&roots, &routes),
    })
}

fn key_times<T>(animated: &Animated<T>) -> Vec<f64> {
    animated.track.keys.iter().map(|k| k.time).collect()
}

/// Scene camera `c` as a `Viewpoint` (`position`, `orientation`, `fieldOfView` as the
/// evaluator has them at the range's start), with interpolators for what moves: the keyed
/// translation and rotation as any transform's; an aimed camera's orientation and a lens
/// (as the vertical field of view in radians) resampled from the evaluated camera.
/// Orthographic cameras are written as perspective Viewpoints (VRML97 has no other); their
/// lens stays in the metadata.
fn camera_node(
    scene: &Scene,
    eval: &SceneEvaluator,
    ch: &Channels<'_>,
    out: &mut Animations,
    c: usize,
    def: &str,
    animated: bool,
) -> WNode {
    let camera = &scene.cameras[c];
    let none = Overrides::default();
    let state = |t: f64| eval.camera_at(c, t, &none);
    let orientation = |t: f64| {
        state(t).map_or(Quat::IDENTITY, |s| Quat::from_mat3a(&s.world_from_camera.matrix3).normalize())
    };
    let fov = |t: f64| match state(t).map(|s| s.lens) {
        Some(keyrig_core::Lens::Perspective { fov_y }) => fov_y,
        _ => std::f32::consts::FRAC_PI_4,
    };
    let t0 = ch.t0;
    let position = state(t0).map_or(Vec3::ZERO, |s| s.eye());
    let fields = vec![
        ("description", WValue::String(camera.name.clone())),
        ("position", WValue::Numbers(position.to_array().map(f64::from).to_vec(), 3)),
        ("orientation", WValue::Numbers(axis_angle(orientation(t0)).to_vec(), 4)),
        ("fieldOfView", WValue::Numbers(vec![f64::from(fov(t0))], 1)),
    ];
    if animated {
        ch.vec3(
            out,
            ChannelId::CameraTranslation(c),
            &camera.translation,
            Vec3Blend::Position,
            def,
            "position",
        );
        if camera.aim.is_none() {
            ch.rotation(out, ChannelId::CameraRotation(c), &camera.rotation, def, "orientation");
        } else {
            // Where it looks follows its target and its own motion: written when it turns.
            let turns =
                ch.frame_times().iter().any(|&t| orientation(t).angle_between(orientation(t0)) > 1e-6);
            if turns {
                ch.rotation_resampled(out, &orientation, &[], def, "orientation");
            }
        }
        let perspective = camera.projection != keyrig_core::Projection::Orthographic;
        if perspective && camera.lens.is_animated() {
            ch.scalar_resampled(out, &fov, &key_times(&camera.lens), def, "fieldOfView");
        }
    }
    WNode { kind: "Viewpoint", def: Some(def.to_owned()), fields }
}

/// How a vector channel blends: VRML's straight line, or its HSV colour blend (clamped to
/// VRML's 0..1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Vec3Blend {
    Position,
    Colour,
}

/// What the channel writers share: the evaluator, the range, the tolerances and whether the
/// format has X3D's spline and squad interpolators.
struct Channels<'a> {
    eval: &'a SceneEvaluator,
    t0: f64,
    t1: f64,
    fps: f64,
    pos_tol: f32,
    rot_tol: f32,
    col_tol: f32,
    x3d: bool,
}

/// keyrig's own keys of a channel when they might be one X3D spline: two or more, TCB up to the
/// last, Hold at both ends, not muted.
fn spline_candidate<T: TrackValue>(animated: &Animated<T>) -> Option<Track<T>> {
    let keys = &animated.track.keys;
    if animated.muted || animated.cycles() != Cycles::HOLD || keys.len() < 2 {
        return None;
    }
    if keys[..keys.len() - 1].iter().any(|k| k.interpolation != Interpolation::Tcb) {
        return None;
    }
    Track::with_cycles(&animated.track, Cycles::HOLD).ok()
}

/// X3D's one velocity per key (per unit of the segment parameter) from keyrig's segment
/// tangents (per second): the tangent leaving each key, the one arriving at the last.
fn key_velocities<T: SplineValue>(
    times: &[f64],
    tangent: impl Fn(usize) -> Option<(T, T)>,
) -> Option<Vec<T>> {
    let n = times.len();
    (0..n)
        .map(|i| {
            if i + 1 < n {
                tangent(i).map(|(out, _)| out.scale((times[i + 1] - times[i]) as f32))
            } else {
                tangent(n - 2).map(|(_, arriving)| arriving.scale((times[n - 1] - times[n - 2]) as f32))
            }
        })
        .collect()
}

impl Channels<'_> {
    fn at(&self, id: ChannelId, t: f64) -> Option<ChannelValue> {
        self.eval.value(id, t, &Overrides::default())
    }

    fn fraction(&self, t: f64) -> f64 {
        (t - self.t0) / (self.t1 - self.t0)
    }

    fn schedule<T: Clone>(
        &self,
        value: &dyn Fn(f64) -> T,
        close: &dyn Fn(&T, &T, &T, f32) -> bool,
        keys: &[f64],
    ) -> Vec<(f64, T)> {
        schedule(value, close, self.t0, self.t1, self.fps, keys)
    }

    /// Every frame of the range.
    fn frame_times(&self) -> Vec<f64> {
        let frames = ((self.t1 - self.t0) * self.fps).round().max(0.0) as i64;
        (0..=frames).map(|f| self.t0 + f as f64 / self.fps).collect()
    }

    /// A `ScalarInterpolator` following `value` within the tolerance (an absolute 10⁻⁴ of
    /// the scene's size, at least 10⁻⁶).
    fn scalar_resampled(
        &self,
        out: &mut Animations,
        value: &dyn Fn(f64) -> f32,
        key_times: &[f64],
        name: &str,
        field: &'static str,
    ) {
        let close = |a: &f32, b: &f32, m: &f32, u: f32| (a + (b - a) * u - m).abs() <= self.pos_tol.max(1e-6);
        let s = self.schedule(value, &close, key_times);
        let fractions = s.iter().map(|(t, _)| self.fraction(*t)).collect();
        out.interp(
            "ScalarInterpolator",
            name,
            fractions,
            s.iter().map(|(_, v)| f64::from(*v)).collect(),
            1,
            field,
        );
    }

    /// An `OrientationInterpolator` following `value` within the rotation tolerance, no two
    /// samples 90° apart (so that every slerp turns the way keyrig turns).
    fn rotation_resampled(
        &self,
        out: &mut Animations,
        value: &dyn Fn(f64) -> Quat,
        key_times: &[f64],
        name: &str,
        field: &'static str,
    ) {
        let close = |a: &Quat, b: &Quat, m: &Quat, u: f32| {
            a.angle_between(*b) < std::f32::consts::FRAC_PI_2
                && crate::model::slerp_short(*a, *b, u).angle_between(*m) <= self.rot_tol
        };
        let s = self.schedule(value, &close, key_times);
        let fractions = s.iter().map(|(t, _)| self.fraction(*t)).collect();
        let values = s.iter().flat_map(|(_, q)| axis_angle(*q)).collect();
        out.interp("OrientationInterpolator", name, fractions, values, 4, field);
    }

    /// Where an exported spline is compared with keyrig: every frame, three points between
    /// frames, and the key times in the range.
    fn check_times(&self, keys: &[f64]) -> Vec<f64> {
        let frames = ((self.t1 - self.t0) * self.fps).round().max(0.0) as i64;
        let mut times: Vec<f64> = (0..=frames * 4)
            .map(|q| self.t0 + q as f64 / (4.0 * self.fps))
            .filter(|&t| t <= self.t1)
            .collect();
        times.extend(keys.iter().copied().filter(|&k| k >= self.t0 && k <= self.t1));
        times
    }

    /// The fractions of an X3D spline with these keys and velocities when it plays `value`
    /// within `tolerance` at every [`Channels::check_times`] (read back as keyrig reads it).
    fn exact_spline<T: TrackValue + SplineValue>(
        &self,
        times: &[f64],
        values: &[T],
        velocity: &[T],
        value: impl Fn(f64) -> T,
        distance: impl Fn(T, T) -> f32,
        tolerance: f32,
    ) -> Option<Vec<f64>> {
        let fractions: Vec<f64> = times.iter().map(|&t| self.fraction(t)).collect();
        let fields = splines::SplineFields { closed: false, velocity, normalize: false };
        let keys = splines::spline_keys(&fractions, values, &fields, self.t1 - self.t0);
        let track = Track::new(&RawTrack::new(keys)).ok()?;
        self.check_times(times)
            .into_iter()
            .all(|t| distance(track.sample(t - self.t0), value(t)) <= tolerance)
            .then_some(fractions)
    }

    /// A vector channel: X3D's `SplinePositionInterpolator` where it is exact, else a
    /// `PositionInterpolator` (or `ColorInterpolator`) resampled within the tolerance.
    fn vec3(
        &self,
        out: &mut Animations,
        id: ChannelId,
        animated: &Animated<Vec3>,
        blend: Vec3Blend,
        name: &str,
        field: &'static str,
    ) {
        if !animated.is_animated() {
            return;
        }
        let key_times: Vec<f64> = animated.track.keys.iter().map(|k| k.time).collect();
        let flat = |v: &mut dyn Iterator<Item = Vec3>| v.flat_map(|v| v.to_array().map(f64::from)).collect();
        if blend == Vec3Blend::Colour {
            let close = |a: &Vec3, b: &Vec3, m: &Vec3, u: f32| {
                (hsv_lerp(*a, *b, u) - *m).abs().max_element() <= self.col_tol
            };
            let s =
                self.schedule(&|t| vec3_of(self.at(id, t)).clamp(Vec3::ZERO, Vec3::ONE), &close, &key_times);
            let fractions = s.iter().map(|(t, _)| self.fraction(*t)).collect();
            out.interp("ColorInterpolator", name, fractions, flat(&mut s.iter().map(|(_, v)| *v)), 3, field);
            return;
        }
        let value = |t: f64| vec3_of(self.at(id, t));
        if let Some(track) = spline_candidate(animated).filter(|_| self.x3d) {
            let times = track.key_times();
            let exact = key_velocities(times, |i| track.segment_tangents(i)).and_then(|velocity| {
                let distance = |a: Vec3, b: Vec3| (a - b).abs().max_element();
                let fractions = self.exact_spline(
                    times,
                    track.key_values(),
                    &velocity,
                    value,
                    distance,
                    self.pos_tol / 10.0,
                )?;
                Some((fractions, velocity))
            });
            if let Some((fractions, velocity)) = exact {
                out.interp_with(
                    "SplinePositionInterpolator",
                    (name, name),
                    fractions,
                    flat(&mut track.key_values().iter().copied()),
                    3,
                    vec![("keyVelocity", WValue::Numbers(flat(&mut velocity.into_iter()), 3))],
                    field,
                );
                return;
            }
        }
        let close =
            |a: &Vec3, b: &Vec3, m: &Vec3, u: f32| (a.lerp(*b, u) - *m).abs().max_element() <= self.pos_tol;
        let s = self.schedule(&value, &close, &key_times);
        let fractions = s.iter().map(|(t, _)| self.fraction(*t)).collect();
        out.interp("PositionInterpolator", name, fractions, flat(&mut s.iter().map(|(_, v)| *v)), 3, field);
    }

    /// A scalar channel (clamped to VRML's 0..1): X3D's `SplineScalarInterpolator` where it is
    /// exact, else a resampled `ScalarInterpolator`.
    fn scalar(
        &self,
        out: &mut Animations,
        id: ChannelId,
        animated: &Animated<f32>,
        name: &str,
        field: &'static str,
    ) {
        if !animated.is_animated() {
            return;
        }
        let value = |t: f64| scalar_of(self.at(id, t)).clamp(0.0, 1.0);
        if let Some(track) = spline_candidate(animated).filter(|_| self.x3d) {
            let times = track.key_times();
            let exact = key_velocities(times, |i| track.segment_tangents(i)).and_then(|velocity| {
                let fractions = self.exact_spline(
                    times,
                    track.key_values(),
                    &velocity,
                    value,
                    |a, b| (a - b).abs(),
                    1e-5,
                )?;
                Some((fractions, velocity))
            });
            if let Some((fractions, velocity)) = exact {
                let numbers = |v: &[f32]| v.iter().map(|&x| f64::from(x)).collect();
                out.interp_with(
                    "SplineScalarInterpolator",
                    (name, name),
                    fractions,
                    numbers(track.key_values()),
                    1,
                    vec![("keyVelocity", WValue::Numbers(numbers(&velocity), 1))],
                    field,
                );
                return;
            }
        }
        self.scalar_resampled(out, &value, &key_times(animated), name, field);
    }

    /// A rotation channel: X3D's `SquadOrientationInterpolator` where it is exact, else an
    /// `OrientationInterpolator` resampled within the tolerance, no two samples 90° apart.
    fn rotation(
        &self,
        out: &mut Animations,
        id: ChannelId,
        animated: &Animated<Quat>,
        name: &str,
        field: &'static str,
    ) {
        if !animated.is_animated() {
            return;
        }
        let value = |t: f64| quat_of(self.at(id, t));
        if let Some(track) = spline_candidate(animated).filter(|t| self.x3d && !t.has_spin()) {
            let fractions: Vec<f64> = track.key_times().iter().map(|&t| self.fraction(t)).collect();
            let curve = splines::SquadCurve::new(&fractions, track.key_values(), false);
            let tolerance = f64::from(self.rot_tol) / 10.0;
            let exact = self.check_times(track.key_times()).into_iter().all(|t| {
                splines::rotation_angle(curve.eval(self.fraction(t)), value(t).as_dquat()) <= tolerance
            });
            if exact {
                let values = track.key_values().iter().flat_map(|q| axis_angle(*q)).collect();
                out.interp("SquadOrientationInterpolator", name, fractions, values, 4, field);
                return;
            }
        }
        self.rotation_resampled(out, &value, &key_times(animated), name, field);
    }
}

/// The interpolators and routes being written.
struct Animations {
    used: HashMap<String, usize>,
    clock: String,
    interpolators: Vec<WNode>,
    routes: Vec<(String, &'static str, String, &'static str)>,
}

impl Animations {
    /// An interpolator of `kind` with `keys` (fractions) and `values` (`arity` numbers each),
    /// driven by the clock and routed to `name.field` (`name` is the target's DEF).
    fn interp(
        &mut self,
        kind: &'static str,
        name: &str,
        keys: Vec<f64>,
        values: Vec<f64>,
        arity: usize,
        field: &'static str,
    ) {
        self.interp_with(kind, (name, name), keys, values, arity, Vec::new(), field);
    }

    /// [`Animations::interp`] with more fields (a spline's `keyVelocity`); `(name, target)`:
    /// the interpolator is named `name_field` and routed to `target.field`.
    #[allow(clippy::too_many_arguments)]
    fn interp_with(
        &mut self,
        kind: &'static str,
        (name, target): (&str, &str),
        keys: Vec<f64>,
        values: Vec<f64>,
        arity: usize,
        more: Vec<(&'static str, WValue)>,
        field: &'static str,
    ) {
        let def = def_name(&format!("{name}_{field}"), &mut self.used);
        let mut fields =
            vec![("key", WValue::Numbers(keys, 1)), ("keyValue", WValue::Numbers(values, arity))];
        fields.extend(more);
        self.interpolators.push(WNode { kind, def: Some(def.clone()), fields });
        self.routes.push((self.clock.clone(), "fraction_changed", def.clone(), "set_fraction"));
        self.routes.push((def, "value_changed", target.to_owned(), field));
    }
}

/// The DEF names of the scene's objects and lights, in order (the same for the export and for
/// reading it back), and the names taken.
fn exported_names(scene: &Scene) -> ExportedNames {
    let mut used = HashMap::new();
    let objects = scene.objects.iter().map(|o| def_name(&o.name, &mut used)).collect();
    let lights = scene.lights.iter().map(|l| def_name(&l.name, &mut used)).collect();
    let cameras = scene.cameras.iter().map(|c| def_name(&c.name, &mut used)).collect();
    ExportedNames { objects, lights, cameras, used }
}

/// The DEF names of a scene's objects, lights and cameras, and every name taken.
struct ExportedNames {
    objects: Vec<String>,
    lights: Vec<String>,
    cameras: Vec<String>,
    used: HashMap<String, usize>,
}

fn quote(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

fn numbers(out: &mut String, v: &[f64], arity: usize, indent: &str) {
    for (i, x) in v.iter().enumerate() {
        if i > 0 && arity > 0 && i % (arity * 4).max(4) == 0 {
            out.push('\n');
            out.push_str(indent);
        } else if i > 0 {
            out.push(' ');
        }
        let x = if x.is_finite() { *x } else { 0.0 };
        let _ = write!(out, "{}", x as f32);
    }
}

fn classic_node(out: &mut String, n: &WNode, depth: usize) {
    let indent = "  ".repeat(depth);
    if let Some(d) = &n.def {
        let _ = write!(out, "DEF {d} ");
    }
    let _ = writeln!(out, "{} {{", n.kind);
    for (name, value) in &n.fields {
        let _ = write!(out, "{indent}  {name} ");
        match value {
            WValue::Numbers(v, arity) => {
                let list = *arity == 1 && (name.ends_with("ey") || v.len() != 1)
                    || *arity > 1 && v.len() > *arity
                    || name.ends_with("Index")
                    || name == &"keyValue"
                    || name == &"point";
                if list {
                    out.push_str("[ ");
                }
                numbers(out, v, *arity, &format!("{indent}    "));
                if list {
                    out.push_str(" ]");
                }
            }
            WValue::Bool(b) => out.push_str(if *b { "TRUE" } else { "FALSE" }),
            WValue::String(s) => out.push_str(&quote(s)),
            WValue::Strings(s) => {
                out.push_str("[ ");
                out.push_str(&s.iter().map(|s| quote(s)).collect::<Vec<_>>().join(" "));
                out.push_str(" ]");
            }
            WValue::Node(child) => classic_node(out, child, depth + 1),
            WValue::Nodes(children) => {
                out.push_str("[\n");
                for c in children {
                    out.push_str(&"  ".repeat(depth + 2));
                    classic_node(out, c, depth + 2);
                }
                let _ = write!(out, "{indent}  ]");
            }
        }
        out.push('\n');
    }
    let _ = writeln!(out, "{indent}}}");
}

fn classic(
    format: ExportFormat,
    roots: &[WNode],
    routes: &[(String, &'static str, String, &'static str)],
) -> String {
    let mut out = String::new();
    if format == ExportFormat::X3dClassic {
        out.push_str("#X3D V3.3 utf8\nPROFILE Immersive\n\n");
    } else {
        out.push_str("#VRML V2.0 utf8\n\n");
    }
    out.push_str("# Written by keyrig. keyrig's own keys are in the WorldInfo below.\n");
    for n in roots {
        classic_node(&mut out, n, 0);
    }
    for (a, af, b, bf) in routes {
        let _ = writeln!(out, "ROUTE {a}.{af} TO {b}.{bf}");
    }
    out
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\n', "&#10;")
}

fn xml_node(out: &mut String, n: &WNode, container: Option<&str>, depth: usize) {
    let indent = "  ".repeat(depth);
    let _ = write!(out, "{indent}<{}", n.kind);
    if let Some(d) = &n.def {
        let _ = write!(out, " DEF=\"{d}\"");
    }
    if let Some(c) = container {
        let _ = write!(out, " containerField=\"{c}\"");
    }
    let mut children: Vec<(&str, &WNode)> = Vec::new();
    for (name, value) in &n.fields {
        match value {
            WValue::Numbers(v, arity) => {
                let mut text = String::new();
                numbers(&mut text, v, *arity, " ");
                let _ = write!(out, " {name}=\"{}\"", text.replace('\n', " "));
            }
            WValue::Bool(b) => {
                let _ = write!(out, " {name}=\"{}\"", if *b { "true" } else { "false" });
            }
            WValue::String(s) => {
                let _ = write!(out, " {name}=\"{}\"", xml_escape(s));
            }
            WValue::Strings(s) => {
                let _ = write!(
                    out,
                    " {name}=\"{}\"",
                    xml_escape(&s.iter().map(|s| quote(s)).collect::<Vec<_>>().join(" "))
                );
            }
            WValue::Node(child) => children.push((name, child)),
            WValue::Nodes(list) => children.extend(list.iter().map(|c| (*name, c))),
        }
    }
    if children.is_empty() {
        out.push_str("/>\n");
    } else {
        out.push_str(">\n");
        for (name, c) in children {
            xml_node(out, c, Some(name), depth + 1);
        }
        let _ = writeln!(out, "{indent}</{}>", n.kind);
    }
}

fn xml(roots: &[WNode], routes: &[(String, &'static str, String, &'static str)]) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<X3D profile=\"Immersive\" version=\"3.3\">\n  <head>\n    <meta name=\"generator\" content=\"keyrig\"/>\n  </head>\n  <Scene>\n");
    for n in roots {
        xml_node(&mut out, n, None, 2);
    }
    for (a, af, b, bf) in routes {
        let _ =
            writeln!(out, "    <ROUTE fromNode=\"{a}\" fromField=\"{af}\" toNode=\"{b}\" toField=\"{bf}\"/>");
    }
    out.push_str("  </Scene>\n</X3D>\n");
    out
}

/// Open Inventor: Separators with Inventor's property nodes, Coin's VRML interpolators, and
/// field connections in place of ROUTEs.
fn inventor(roots: &[WNode], routes: &[(String, &'static str, String, &'static str)]) -> String {
    let mut out = String::from("#Inventor V2.1 ascii\n\n# Written by keyrig. keyrig's own keys are in the Info node below.\n\nSeparator {\n");
    // Interpolators and the clock first, so that connections can USE them.
    let connection = |target: &str, field: &str| -> Option<String> {
        routes.iter().find(|r| r.2 == target && r.3 == field).map(|r| format!(" = USE {}.{}", r.0, r.1))
    };
    let nums = |v: &[f64]| {
        let mut s = String::new();
        numbers(&mut s, v, 3, "    ");
        s
    };
    for n in roots {
        match n.kind {
            "TimeSensor"
            | "PositionInterpolator"
            | "OrientationInterpolator"
            | "ScalarInterpolator"
            | "ColorInterpolator"
            | "CoordinateInterpolator" => {
                let def = n.def.clone().unwrap_or_default();
                let _ = writeln!(out, "  DEF {def} VRML{} {{", n.kind);
                for (name, value) in &n.fields {
                    match value {
                        WValue::Numbers(v, _) if n.kind == "TimeSensor" => {
                            let _ = writeln!(out, "    {name} {}", nums(v));
                        }
                        WValue::Numbers(v, _) => {
                            let _ = writeln!(out, "    {name} [ {} ]", nums(v));
                        }
                        WValue::Bool(b) => {
                            let _ = writeln!(out, "    {name} {}", if *b { "TRUE" } else { "FALSE" });
                        }
                        _ => {}
                    }
                }
                if let Some(c) = connection(&def, "set_fraction") {
                    let _ = writeln!(out, "    set_fraction 0{c}");
                }
                out.push_str("  }\n");
            }
            _ => {}
        }
    }
    let num_field = |n: &WNode, name: &str| -> Option<Vec<f64>> {
        n.fields.iter().find(|(f, _)| *f == name).and_then(|(_, v)| match v {
            WValue::Numbers(v, _) => Some(v.clone()),
            _ => None,
        })
    };
    // Viewpoints as perspective cameras before the shapes: the first one views the scene,
    // the others wait in a Switch that shows none of them (their connections still play).
    let cameras: Vec<&WNode> = roots.iter().filter(|n| n.kind == "Viewpoint").collect();
    for (i, n) in cameras.iter().enumerate() {
        if i == 1 {
            out.push_str("  Switch {\n    whichChild -1\n");
        }
        let def = n.def.clone().unwrap_or_default();
        let field = |vrml: &str, default: Vec<f64>| {
            format!(
                "{}{}",
                nums(&num_field(n, vrml).unwrap_or(default)),
                connection(&def, vrml).unwrap_or_default()
            )
        };
        let _ = writeln!(
            out,
            "  DEF {def} PerspectiveCamera {{\n    position {}\n    orientation {}\n    heightAngle {}\n  }}",
            field("position", vec![0.0, 0.0, 10.0]),
            field("orientation", vec![0.0, 0.0, 1.0, 0.0]),
            field("fieldOfView", vec![std::f64::consts::FRAC_PI_4])
        );
        if i > 0 && i + 1 == cameras.len() {
            out.push_str("  }\n");
        }
    }
    for n in roots {
        match n.kind {
            "WorldInfo" => {
                if let Some((_, WValue::Strings(s))) = n.fields.iter().find(|(f, _)| *f == "info") {
                    let _ = writeln!(out, "  Info {{ string {} }}", quote(&s.join("\n")));
                }
            }
            "Transform" => {
                let def = n.def.clone().unwrap_or_default();
                let _ = writeln!(out, "  DEF {def} Separator {{");
                let t = num_field(n, "translation").unwrap_or(vec![0.0; 3]);
                let r = num_field(n, "rotation").unwrap_or(vec![0.0, 0.0, 1.0, 0.0]);
                let s = num_field(n, "scale").unwrap_or(vec![1.0; 3]);
                let _ = writeln!(
                    out,
                    "    DEF {def}_xf Transform {{\n      translation {}{}\n      rotation {}{}\n      scaleFactor {}{}\n    }}",
                    nums(&t),
                    connection(&def, "translation").unwrap_or_default(),
                    nums(&r),
                    connection(&def, "rotation").unwrap_or_default(),
                    nums(&s),
                    connection(&def, "scale").unwrap_or_default()
                );
                if let Some((_, WValue::Nodes(children))) = n.fields.iter().find(|(f, _)| *f == "children") {
                    for shape in children {
                        let node = |name: &str| {
                            shape.fields.iter().find(|(f, _)| *f == name).and_then(|(_, v)| {
                                if let WValue::Node(n) = v {
                                    Some(n.as_ref().clone())
                                } else {
                                    None
                                }
                            })
                        };
                        let (Some(app), Some(geo)) = (node("appearance"), node("geometry")) else { continue };
                        if let Some((_, WValue::Node(m))) = app.fields.iter().find(|(f, _)| *f == "material")
                        {
                            let d = num_field(m, "diffuseColor").unwrap_or(vec![0.8; 3]);
                            let tr = num_field(m, "transparency").unwrap_or(vec![0.0]);
                            let mdef = m.def.clone().unwrap_or_default();
                            let _ = writeln!(
                                out,
                                "    {}Material {{ diffuseColor {}{} transparency {}{} }}",
                                m.def.as_ref().map(|d| format!("DEF {d} ")).unwrap_or_default(),
                                nums(&d),
                                connection(&mdef, "diffuseColor").unwrap_or_default(),
                                nums(&tr),
                                connection(&mdef, "transparency").unwrap_or_default()
                            );
                        }
                        if let Some((_, WValue::Node(c))) = geo.fields.iter().find(|(f, _)| *f == "coord") {
                            let cdef = c.def.clone().unwrap_or_default();
                            let p = num_field(c, "point").unwrap_or_default();
                            let _ = writeln!(
                                out,
                                "    DEF {cdef} Coordinate3 {{ point [ {} ]{} }}",
                                nums(&p),
                                connection(&cdef, "point").unwrap_or_default()
                            );
                        }
                        out.push_str("    ShapeHints { vertexOrdering COUNTERCLOCKWISE creaseAngle 1 }\n");
                        let idx = num_field(&geo, "coordIndex").unwrap_or_default();
                        let mut s = String::new();
                        numbers(&mut s, &idx, 4, "      ");
                        let _ = writeln!(out, "    IndexedFaceSet {{ coordIndex [ {s} ] }}");
                    }
                }
                out.push_str("  }\n");
            }
            "DirectionalLight" | "PointLight" | "SpotLight" => {
                let def = n.def.clone().unwrap_or_default();
                let _ = writeln!(out, "  DEF {def} {} {{", n.kind);
                for (name, value) in &n.fields {
                    let field = match *name {
                        "beamWidth" => continue,
                        other => other,
                    };
                    match value {
                        WValue::Numbers(v, _) => {
                            let _ = writeln!(
                                out,
                                "    {field} {}{}",
                                nums(v),
                                connection(&def, name).unwrap_or_default()
                            );
                        }
                        WValue::Bool(b) => {
                            let _ = writeln!(out, "    {field} {}", if *b { "TRUE" } else { "FALSE" });
                        }
                        _ => {}
                    }
                }
                out.push_str("  }\n");
            }
            _ => {}
        }
    }
    out.push_str("}\n");
    out
}

/// When `model` was written by keyrig ([`METADATA_TAG`] in a WorldInfo or Info), its objects
/// and lights take back the keys of keyrig's own scene (matched by name), with the scene's
/// rate and range: tension, continuity, bias, cycles and spins as they were. Returns whether
/// metadata was found.
pub fn restore_metadata(doc: &super::tree::Document, model: &mut super::VrmlModel) -> bool {
    let Some(text) = doc.nodes.iter().find_map(|n| {
        let field = match n.kind.as_str() {
            "WorldInfo" => "info",
            "Info" => "string",
            _ => return None,
        };
        match n.value(field) {
            Some(super::tree::Value::Strings(s)) => {
                s.iter().find_map(|s| s.strip_prefix(METADATA_TAG).map(str::to_owned))
            }
            _ => None,
        }
    }) else {
        return false;
    };
    let Ok(scene) = crate::scene_file::from_str(text.trim_start(), Path::new("metadata")) else {
        return false;
    };
    let ExportedNames { objects: object_defs, lights: light_defs, cameras: camera_defs, .. } =
        exported_names(&scene);
    for object in &mut model.objects {
        let Some(o) = object_defs.iter().position(|d| *d == object.name) else { continue };
        let original = &scene.objects[o];
        object.name.clone_from(&original.name);
        object.deformer = original.deformer;
        // A skinned object was written as the meshes its deformer made: it comes back as that
        // morph here, and whole from the metadata scene where its mesh can be had again
        // (`VrmlModel::to_scene`); others take their keys back.
        if original.skeleton.is_none() {
            object.translation = original.translation.clone();
            object.rotation = original.rotation.clone();
            object.scale = original.scale.clone();
            object.attributes = original.attributes.clone();
        } else {
            // The morph it came back as still shows, colours and fades as it did.
            object.attributes.visible = original.attributes.visible.clone();
            object.attributes.colour.clone_from(&original.attributes.colour);
            object.attributes.opacity = original.attributes.opacity.clone();
        }
    }
    for light in &mut model.lights {
        if let Some(l) = light_defs.iter().position(|d| *d == light.name) {
            *light = scene.lights[l].clone();
        }
    }
    for camera in &mut model.cameras {
        if let Some(c) = camera_defs.iter().position(|d| *d == camera.name) {
            *camera = scene.cameras[c].clone();
        }
    }
    // What the metadata gives back is not missing.
    model.skipped.retain(|s| !s.why.contains("keyrig's own export carries it"));
    model.metadata_scene = Some(scene);
    true
}
