//! `keyrig info FILE`: what a scene holds (timing, objects, skeletons, lights, tracks and key
//! counts) and what is wrong with it.
//!
//! Reads `.ron` scenes and `.glb`/`.gltf` models (mapped to a scene by keyrig-io), and
//! summarizes `.md2` models (mesh, frames, clips). Exits
//! non-zero when the file cannot be read or parsed, and also when the scene has validation
//! problems (after printing the summary and every problem).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use keyrig_core::channel::{list_channels, ChannelPath};
use keyrig_core::{LightKind, MeshSource, Scene};
use keyrig_io::scene_file::{self, LocatedProblem};

#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum InfoFormat {
    /// Human-readable text.
    #[default]
    Text,
    /// One JSON object.
    Json,
}

#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// Scene file (.ron), glTF model (.glb, .gltf), MD2 model, or VRML97 / X3D / Open Inventor
    /// file (.wrl, .wrz, .x3d, .x3dv, .iv).
    pub file: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value_t = InfoFormat::Text)]
    pub format: InfoFormat,
}

fn is_scene(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("ron"))
}

/// What `deform`, `render` and `export` need of each object's mesh beyond the scene's own
/// checks ([`Scene::problems`]), so that "problems: none" means they work: a skeleton that
/// builds; a procedural mesh that fits it (its joints all exist); a model file that loads
/// (relative to `base_dir`, the scene's folder), whose skinned mesh is bound to as many
/// joints as the object's skeleton has and which is skinned or vertex-animated (the
/// renderer draws file meshes no other way).
/// A scene's sound clips with their decoded files (or why a file does not decode).
type ClipInfo = (keyrig_core::SoundClip, Result<keyrig_io::sound::DecodedSound, String>);

/// Each clip's file is decoded on a thread of its own (the editor's way too), so a scene of
/// several long tracks takes about the time of its longest on a machine with the cores.
fn sound_clips(scene: &Scene, base_dir: &Path) -> Vec<ClipInfo> {
    let decode = |clip: &keyrig_core::SoundClip| {
        keyrig_io::sound::decode_sound_file(&base_dir.join(&clip.path)).map_err(|e| e.to_string())
    };
    std::thread::scope(|scope| {
        // A thread that cannot be started leaves its clip to be decoded here.
        let running: Vec<_> = scene
            .sounds
            .iter()
            .map(|clip| (clip, std::thread::Builder::new().spawn_scoped(scope, move || decode(clip)).ok()))
            .collect();
        running
            .into_iter()
            .map(|(clip, thread)| {
                let decoded = match thread {
                    Some(thread) => {
                        thread.join().unwrap_or_else(|_| Err(format!("{}: the decoder panicked", clip.path)))
                    }
                    None => decode(clip),
                };
                (clip.clone(), decoded)
            })
            .collect()
    })
}

fn sounds_text(sounds: &[ClipInfo]) -> String {
    use std::fmt::Write as _;
    let mut out = format!("sounds:   {}\n", sounds.len());
    for (clip, decoded) in sounds {
        let file = match decoded {
            Ok(d) => format!(
                ", {} {} Hz {} channel{}, {:.3} s",
                d.codec,
                d.summary.sample_rate,
                d.summary.channels,
                if d.summary.channels == 1 { "" } else { "s" },
                d.summary.duration()
            ),
            Err(_) => ", cannot be read (see problems)".to_owned(),
        };
        let _ = writeln!(
            out,
            "  {:?}: from frame {}, gain {}{}{file}",
            clip.path,
            clip.start_frame,
            clip.gain,
            if clip.mute { ", muted" } else { "" }
        );
    }
    out
}

fn sounds_json(sounds: &[ClipInfo]) -> serde_json::Value {
    sounds
        .iter()
        .map(|(clip, decoded)| {
            let file = decoded.as_ref().ok();
            serde_json::json!({
                "path": clip.path,
                "start_frame": clip.start_frame,
                "gain": clip.gain,
                "mute": clip.mute,
                "codec": file.map(|d| d.codec.clone()),
                "sample_rate": file.map(|d| d.summary.sample_rate),
                "channels": file.map(|d| d.summary.channels),
                "duration_s": file.map(|d| d.summary.duration()),
            })
        })
        .collect()
}

fn mesh_problems(scene: &Scene, base_dir: &Path) -> Vec<keyrig_core::Problem> {
    use keyrig_editor::files::{FileMesh, MeshStore};
    let mut problems = Vec::new();
    let mut store = MeshStore::default();
    for (i, object) in scene.objects.iter().enumerate() {
        let mut problem = |field: &str, message: String| {
            problems.push(keyrig_core::Problem { path: format!("objects[{i}].{field}"), message });
        };
        let rest = match object.skeleton.as_ref().map(keyrig_skin::RestSkeleton::from_scene) {
            Some(Ok(rest)) => Some(rest),
            Some(Err(e)) => {
                problem("skeleton", e.to_string());
                continue;
            }
            None => None,
        };
        match &object.mesh {
            None => {}
            Some(MeshSource::Procedural(kind)) => {
                if let Some(rest) = rest {
                    let joints = rest.len();
                    if let Err(e) = keyrig_skin::mesh_for(*kind).fit_to_skeleton(rest) {
                        problem(
                            "skeleton",
                            format!("the procedural {kind:?} mesh does not fit the skeleton's {joints} joints: {e}"),
                        );
                    }
                }
            }
            Some(MeshSource::File { path, mesh, .. }) => match store.get(Some(base_dir), path, *mesh) {
                Err(e) => problem("mesh", e.to_string()),
                Ok(FileMesh::Skinned(m)) => match &rest {
                    Some(rest) if rest.len() != m.skeleton.len() => problem(
                        "skeleton",
                        format!(
                            "{} joints, but the mesh from `{path}` is bound to {} joints",
                            rest.len(),
                            m.skeleton.len()
                        ),
                    ),
                    _ => {}
                },
                Ok(FileMesh::Morph(_)) => {}
            },
        }
    }
    problems
}

fn format_line(path: &Path) -> String {
    if keyrig_io::vrml::is_vrml_path(path) {
        return "VRML97 / X3D / Open Inventor file, mapped to a scene".to_string();
    }
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("glb" | "gltf") => "glTF model, mapped to a scene (every animation an action)".to_string(),
        Some("fbx") => "FBX model (ufbx), mapped to a scene (every animation stack an action)".to_string(),
        Some("bvh") => "BVH motion capture take, mapped to a skeleton with Euler keys".to_string(),
        _ => format!("keyrig scene, version {}", scene_file::CURRENT_VERSION),
    }
}

pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let is_md2 =
        args.file.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("md2"));
    if is_md2 {
        return md2_info(&args);
    }
    if keyrig_io::vrml::is_vrml_path(&args.file) {
        return vrml_info(&args);
    }
    let is_gltf = args
        .file
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["glb", "gltf", "fbx"].iter().any(|x| e.eq_ignore_ascii_case(x)));
    let (scene, mut problems, skipped) = if is_gltf {
        let (model, scene, problems) = super::common::load_gltf(&args.file)?;
        (scene, problems, Some(model.skipped_channels))
    } else {
        let (scene, problems) = super::common::load_scene_lenient(&args.file, "info")?;
        (scene, problems, None)
    };
    let mut sounds = Vec::new();
    if is_scene(&args.file) {
        let base_dir = keyrig_io::file_io::parent_or_dot(&args.file);
        problems.extend(
            mesh_problems(&scene, &base_dir)
                .into_iter()
                .map(|problem| LocatedProblem { problem, position: None }),
        );
        sounds = sound_clips(&scene, &base_dir);
        problems.extend(sounds.iter().enumerate().filter_map(|(i, (_, decoded))| {
            let message = decoded.as_ref().err()?.clone();
            Some(LocatedProblem {
                problem: keyrig_core::Problem { path: format!("sounds[{i}].path"), message },
                position: None,
            })
        }));
    }
    let text = match args.format {
        InfoFormat::Text => {
            let mut w = summary_text(&args.file, &scene, &problems);
            // The clips go before the problems.
            if let Some(at) = w.find("problems:").filter(|_| !sounds.is_empty()) {
                w = format!("{}{}{}", &w[..at], sounds_text(&sounds), &w[at..]);
            }
            if let Some(skipped) = &skipped {
                use std::fmt::Write as _;
                if skipped.is_empty() {
                    let _ = writeln!(w, "skipped channels: none");
                } else {
                    let _ = writeln!(w, "skipped channels: {}", skipped.len());
                    for s in skipped {
                        let _ = writeln!(w, "  {s}");
                    }
                }
            }
            w
        }
        InfoFormat::Json => {
            let mut doc = summary_json(&args.file, &scene, &problems);
            if !sounds.is_empty() {
                doc["sounds"] = sounds_json(&sounds);
            }
            if let Some(skipped) = &skipped {
                doc["skipped_channels"] = serde_json::json!(skipped
                    .iter()
                    .map(|s| serde_json::json!({"channel": s.channel, "pointer": s.pointer, "why": s.reason}))
                    .collect::<Vec<_>>());
            }
            serde_json::to_string_pretty(&doc).context("writing JSON")? + "\n"
        }
    };
    super::common::write_stdout(text.as_bytes())?;
    if !problems.is_empty() {
        bail!(
            "{}: {} validation problem{}, listed above",
            args.file.display(),
            problems.len(),
            if problems.len() == 1 { "" } else { "s" }
        );
    }
    Ok(())
}

/// `keyrig info` of a VRML97, X3D or Open Inventor file: the scene it maps to, as for a scene,
/// then its encoding, its views (Viewpoints, which its scene has as cameras),
/// the meshes that morph, and every kind of thing the mapping did not import, with where.
fn vrml_info(args: &InfoArgs) -> anyhow::Result<()> {
    let model = keyrig_io::vrml::import_vrml_file(&args.file)?;
    let name = args.file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let scene = model.to_scene(&name);
    let problems: Vec<LocatedProblem> =
        scene.problems().into_iter().map(|problem| LocatedProblem { problem, position: None }).collect();
    let morphs: Vec<(String, usize)> = model
        .objects
        .iter()
        .zip(&model.meshes)
        .filter_map(|(o, m)| m.morph.as_ref().map(|k| (o.name.clone(), k.frames.len())))
        .collect();
    let text = match args.format {
        InfoFormat::Text => {
            use std::fmt::Write as _;
            let mut w = summary_text(&args.file, &scene, &problems);
            let _ = writeln!(w, "encoding: {}", model.encoding.name());
            let _ = writeln!(w, "views:    {}", model.views.len());
            for v in &model.views {
                let _ = writeln!(
                    w,
                    "  {:?} at {:?}, field of view {:.1}°",
                    v.name,
                    v.position.to_array(),
                    v.field_of_view.to_degrees()
                );
            }
            for (object, frames) in &morphs {
                let _ = writeln!(
                    w,
                    "morph:    {object:?}: {frames} CoordinateInterpolator keys (vertex animation)"
                );
            }
            if model.skipped.is_empty() {
                let _ = writeln!(w, "not imported: nothing");
            } else {
                let _ = writeln!(w, "not imported: {}", model.skipped.len());
                for line in model.skipped_lines() {
                    let _ = writeln!(w, "  {line}");
                }
            }
            w
        }
        InfoFormat::Json => {
            let mut doc = summary_json(&args.file, &scene, &problems);
            doc["encoding"] = serde_json::json!(model.encoding.name());
            doc["views"] = serde_json::json!(model
                .views
                .iter()
                .map(|v| serde_json::json!({"name": v.name, "position": v.position.to_array(), "orientation": v.orientation.to_array(), "field_of_view": v.field_of_view}))
                .collect::<Vec<_>>());
            doc["morphs"] = serde_json::json!(morphs
                .iter()
                .map(|(o, f)| serde_json::json!({"object": o, "keys": f}))
                .collect::<Vec<_>>());
            doc["not_imported"] = serde_json::json!(model
                .skipped
                .iter()
                .map(
                    |s| serde_json::json!({"what": s.what, "why": s.why, "where": s.place, "count": s.count})
                )
                .collect::<Vec<_>>());
            serde_json::to_string_pretty(&doc).context("writing JSON")? + "\n"
        }
    };
    super::common::write_stdout(text.as_bytes())?;
    if !problems.is_empty() {
        bail!("{}: {} validation problem(s), listed above", args.file.display(), problems.len());
    }
    Ok(())
}

/// `keyrig info` of an MD2 model: its mesh, frames and clips (MD2 is vertex animation; it has
/// no channels to sample).
fn md2_info(args: &InfoArgs) -> anyhow::Result<()> {
    use std::fmt::Write as _;
    let model = keyrig_io::md2::load_md2_file(&args.file)?;
    let vertices = model.frames.first().map_or(0, |f| f.positions.len());
    let triangles = model.indices.len() / 3;
    let text = match args.format {
        InfoFormat::Text => {
            let mut w = String::new();
            let _ = writeln!(w, "file:     {}", args.file.display());
            let _ = writeln!(w, "format:   MD2 model (vertex animation: whole frames, no channels)");
            let _ = writeln!(
                w,
                "mesh:     {vertices} vertices, {} render vertices, {triangles} triangles",
                model.vertex_xyz.len()
            );
            let _ = writeln!(
                w,
                "skin:     {}×{}, {}",
                model.skin_width,
                model.skin_height,
                match &model.skin {
                    Some(skin) => format!("image {}", skin.path.display()),
                    None => "no image found next to the file".to_string(),
                }
            );
            let _ = writeln!(w, "frames:   {}", model.frames.len());
            let _ = writeln!(w, "clips:    {}", model.clips.len());
            for clip in &model.clips {
                let _ = writeln!(
                    w,
                    "  {:?}: frames {}..{} ({} frames)",
                    clip.name,
                    clip.frames.start,
                    clip.frames.end,
                    clip.frames.len()
                );
            }
            w
        }
        InfoFormat::Json => {
            let clips: Vec<_> = model
                .clips
                .iter()
                .map(|c| serde_json::json!({"name": c.name, "first_frame": c.frames.start, "frames": c.frames.len()}))
                .collect();
            let doc = serde_json::json!({
                "file": args.file.display().to_string(),
                "format": "md2",
                "vertices": vertices,
                "render_vertices": model.vertex_xyz.len(),
                "triangles": triangles,
                "frames": model.frames.len(),
                "clips": clips,
            });
            serde_json::to_string_pretty(&doc).context("writing JSON")? + "\n"
        }
    };
    super::common::write_stdout(text.as_bytes())
}

fn mesh_text(mesh: Option<&MeshSource>) -> String {
    match mesh {
        None => "none".to_string(),
        Some(MeshSource::Procedural(p)) => format!("procedural {p:?}"),
        Some(MeshSource::File { path, mesh, clip, fps }) => {
            let mut text = format!("file {path:?}");
            if let Some(i) = mesh {
                text += &format!(", mesh {i}");
            }
            if let Some(clip) = clip {
                text += &format!(", clip {clip:?}");
            }
            if let Some(fps) = fps {
                text += &format!(", {fps} fps");
            }
            text
        }
    }
}

fn light_kind_text(kind: &LightKind) -> String {
    match kind {
        LightKind::Directional => "directional".to_string(),
        LightKind::Point => "point".to_string(),
        LightKind::Spot { cutoff_deg, inner_angle_deg, dropoff } => {
            format!("spot (cutoff {cutoff_deg}°, inner {inner_angle_deg}°, dropoff {dropoff})")
        }
    }
}

/// Where a channel path's names point, found by name once per scene (a linear search per
/// channel made `info` quadratic: 100,000 objects took minutes). The first object, joint,
/// constraint or light of a name is the one a path names.
struct ByName<'a> {
    objects: HashMap<&'a str, usize>,
    lights: HashMap<&'a str, usize>,
    /// Per object index: its skeleton's joints and IK constraints by name.
    joints: HashMap<usize, (Names<'a>, Names<'a>)>,
}

/// Indices by name.
type Names<'a> = HashMap<&'a str, usize>;

impl<'a> ByName<'a> {
    fn new(scene: &'a Scene) -> Self {
        let first = |names: &mut dyn Iterator<Item = &'a str>| {
            let mut map = HashMap::new();
            for (i, name) in names.enumerate() {
                map.entry(name).or_insert(i);
            }
            map
        };
        let joints = scene
            .objects
            .iter()
            .enumerate()
            .filter_map(|(o, object)| {
                let s = object.skeleton.as_ref()?;
                Some((
                    o,
                    (
                        first(&mut s.joints.iter().map(|j| j.name.as_str())),
                        first(&mut s.ik_constraints.iter().map(|c| c.name.as_str())),
                    ),
                ))
            })
            .collect();
        ByName {
            objects: first(&mut scene.objects.iter().map(|o| o.name.as_str())),
            lights: first(&mut scene.lights.iter().map(|l| l.name.as_str())),
            joints,
        }
    }
}

/// Key count and key time range of one channel, read from the raw keys (also for invalid ones).
fn channel_keys(scene: &Scene, names: &ByName<'_>, channel: &ChannelPath) -> (usize, Option<(f64, f64)>) {
    use keyrig_core::channel::{LightProperty as L, ObjectProperty as O};
    fn span<T>(keys: &[keyrig_core::Key<T>]) -> (usize, Option<(f64, f64)>) {
        let range = match (keys.first(), keys.last()) {
            (Some(a), Some(b)) => Some((a.time, b.time)),
            _ => None,
        };
        (keys.len(), range)
    }
    let object = |name: &str| names.objects.get(name).map(|&o| (o, &scene.objects[o]));
    let skeleton_part = |name: &str, part: &str, ik: bool| {
        let (o, object) = object(name)?;
        let skeleton = object.skeleton.as_ref()?;
        let (joints, constraints) = names.joints.get(&o)?;
        Some((skeleton, *if ik { constraints } else { joints }.get(part)?))
    };
    match channel {
        ChannelPath::Object { object: name, property } => {
            let Some((_, o)) = object(name) else { return (0, None) };
            match property {
                O::Translation => span(&o.translation.track.keys),
                // A rotation with Euler keys has its keys there.
                O::Rotation | O::RotationEuler => match &o.rotation_euler {
                    Some(euler) => span(&euler.track.keys),
                    None => span(&o.rotation.track.keys),
                },
                O::Scale => span(&o.scale.track.keys),
                O::RootTranslation => {
                    o.skeleton.as_ref().map_or((0, None), |s| span(&s.root_translation.track.keys))
                }
            }
        }
        ChannelPath::Joint { object, joint, property } => skeleton_part(object, joint, false)
            .map(|(s, j)| &s.joints[j])
            .map_or((0, None), |j| match property {
                keyrig_core::channel::JointProperty::Translation => span(&j.translation.track.keys),
                keyrig_core::channel::JointProperty::Rotation
                | keyrig_core::channel::JointProperty::RotationEuler => match &j.rotation_euler {
                    Some(euler) => span(&euler.track.keys),
                    None => span(&j.rotation.track.keys),
                },
                keyrig_core::channel::JointProperty::Scale => span(&j.scale.track.keys),
            }),
        ChannelPath::Ik { object, constraint, property } => skeleton_part(object, constraint, true)
            .map(|(s, c)| &s.ik_constraints[c])
            .map_or((0, None), |c| match property {
                keyrig_core::channel::IkProperty::Target => span(&c.target.track.keys),
                keyrig_core::channel::IkProperty::Blend => span(&c.blend.track.keys),
            }),
        ChannelPath::Constraint { object: name, constraint, property } => object(name)
            .and_then(|(_, o)| o.constraints.iter().find(|c| c.name == *constraint))
            .and_then(|c| property.of(c))
            .map_or((0, None), |a| span(&a.track.keys)),
        ChannelPath::Attribute { light, owner, property } => {
            let id = if *light {
                names.lights.get(owner.as_str()).and_then(|&l| property.light_id(l))
            } else {
                names.objects.get(owner.as_str()).and_then(|&o| property.object_id(o))
            };
            match id.and_then(|id| id.get(scene)) {
                Some(keyrig_core::channel_id::ChannelRef::Scalar(a)) => span(&a.track.keys),
                Some(keyrig_core::channel_id::ChannelRef::Vec3(a)) => span(&a.track.keys),
                Some(keyrig_core::channel_id::ChannelRef::Rotation(a)) => span(&a.track.keys),
                None => (0, None),
            }
        }
        ChannelPath::Light { light, property } => {
            let Some(l) = names.lights.get(light.as_str()).map(|&l| &scene.lights[l]) else {
                return (0, None);
            };
            match property {
                L::Position => span(&l.position.track.keys),
                L::Direction => span(&l.direction.track.keys),
                L::Colour => span(&l.colour.track.keys),
                L::Intensity => span(&l.intensity.track.keys),
            }
        }
        ChannelPath::Camera { camera, property } => {
            use keyrig_core::channel::CameraProperty as C;
            let Some(c) = scene.camera_index(camera).map(|c| &scene.cameras[c]) else { return (0, None) };
            match property {
                C::Translation => span(&c.translation.track.keys),
                C::Rotation => span(&c.rotation.track.keys),
                C::Lens => span(&c.lens.track.keys),
                C::Roll => c.aim.as_ref().map_or((0, None), |a| span(&a.roll.track.keys)),
                C::AimInfluence => c.aim.as_ref().map_or((0, None), |a| span(&a.influence.track.keys)),
                C::Visible => span(&c.visible.track.keys),
            }
        }
    }
}

/// A scene camera in one line: projection, lens, clip planes and aim.
fn scene_camera_text(c: &keyrig_core::SceneCamera) -> String {
    use keyrig_core::{AimTarget, Projection};
    let lens = match c.projection {
        Projection::Perspective => format!("perspective, field of view {}°", c.lens.value),
        Projection::FocalLength { sensor_height_mm } => {
            format!("perspective, focal length {} mm on a {sensor_height_mm} mm sensor", c.lens.value)
        }
        Projection::Orthographic => format!("orthographic, view height {}", c.lens.value),
    };
    let far = c.far.map_or_else(|| "infinity".to_owned(), |f| f.to_string());
    let aim = match c.aim.as_ref().map(|a| &a.target) {
        None => String::new(),
        Some(AimTarget::Object(o)) => format!(", aimed at {o:?}"),
        Some(AimTarget::Joint { object, joint }) => format!(", aimed at {object:?}/{joint:?}"),
        Some(AimTarget::Point(p)) => format!(", aimed at {p}"),
    };
    format!("{lens}, clip {}..{far}{aim}", c.near)
}

/// An animated channel: its path, key count and key time range.
type AnimatedChannel = (String, usize, Option<(f64, f64)>);

fn duration_s(scene: &Scene) -> f64 {
    f64::from(scene.frame_range.end - scene.frame_range.start) / scene.fps
}

/// Channel names up to this many characters are padded into a column.
const MAX_PAD: usize = 120;

/// One action's line: name, where it plays, channels, keys and the frames its keys span.
fn action_text(scene: &Scene, a: &keyrig_core::ActionSummary) -> String {
    let span = a.time_range.map_or_else(
        || "no keys".to_owned(),
        |(t0, t1)| {
            format!(
                "{} key{}, frames {}..={} ({t0:.3}..{t1:.3} s)",
                a.keys,
                if a.keys == 1 { "" } else { "s" },
                (t0 * scene.fps).round(),
                (t1 * scene.fps).round()
            )
        },
    );
    let active = if a.active_on.is_empty() {
        "not playing".to_owned()
    } else {
        format!("active on {}", a.active_on.iter().map(|n| format!("{n:?}")).collect::<Vec<_>>().join(", "))
    };
    format!(
        "{:?}: {active}, {} channel{}, {span}",
        a.name,
        a.channels,
        if a.channels == 1 { "" } else { "s" }
    )
}

fn summary_text(path: &Path, scene: &Scene, problems: &[LocatedProblem]) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let w = &mut out;
    let range = scene.frame_range;
    let _ = writeln!(w, "file:     {}", path.display());
    let _ = writeln!(w, "format:   {}", format_line(path));
    let _ = writeln!(
        w,
        "timing:   {} fps, frames {}..={} ({} frames, {:.3} s)",
        scene.fps,
        range.start,
        range.end,
        i64::from(range.end) - i64::from(range.start) + 1,
        duration_s(scene)
    );
    let _ = writeln!(w, "ambient:  {}", scene.ambient);
    let _ = writeln!(w, "objects:  {}", scene.objects.len());
    for o in &scene.objects {
        let _ = writeln!(
            w,
            "  {:?}: mesh {}, deformer {}",
            o.name,
            mesh_text(o.mesh.as_ref()),
            o.deformer.kind.cli_name()
        );
        if let Some(skeleton) = &o.skeleton {
            let _ = writeln!(w, "    skeleton: {} joints", skeleton.joints.len());
            for (i, j) in skeleton.joints.iter().enumerate() {
                let parent = match j.parent.and_then(|p| skeleton.joints.get(p)) {
                    Some(p) => format!("parent {:?}", p.name),
                    None if j.parent.is_some() => {
                        format!("parent {} (missing)", j.parent.unwrap_or_default())
                    }
                    None => "root".to_string(),
                };
                let _ = writeln!(
                    w,
                    "      [{i}] {:?}: {parent}, rest translation {}",
                    j.name, j.rest_translation
                );
            }
        }
    }
    let _ = writeln!(w, "lights:   {}", scene.lights.len());
    for l in &scene.lights {
        let _ = writeln!(
            w,
            "  {:?}: {}{}",
            l.name,
            light_kind_text(&l.kind),
            if l.enabled { "" } else { ", disabled" }
        );
    }
    let c = &scene.camera;
    let _ = writeln!(
        w,
        "camera:   target {}, yaw {}°, pitch {}°, distance {}, fov {}°",
        c.target, c.yaw_deg, c.pitch_deg, c.distance, c.fov_y_deg
    );
    if !scene.cameras.is_empty() {
        let _ = writeln!(w, "cameras:  {}", scene.cameras.len());
        for c in &scene.cameras {
            let active = if scene.active_camera_at(f64::from(range.start)) == scene.camera_index(&c.name) {
                " (active at the first frame)"
            } else {
                ""
            };
            let _ = writeln!(w, "  {:?}: {}{active}", c.name, scene_camera_text(c));
        }
    }
    if !scene.markers.is_empty() {
        let _ = writeln!(w, "markers:  {}", scene.markers.len());
        for m in &scene.markers {
            let camera = m.camera.as_ref().map_or(String::new(), |c| format!(", switches to camera {c:?}"));
            let _ = writeln!(w, "  frame {}: {:?}{camera}", m.frame, m.name);
        }
    }
    if let Some(size) = scene.render_size {
        let _ = writeln!(w, "render:   {}x{}", size.width, size.height);
    }
    if !scene.actions.is_empty() {
        let _ = writeln!(w, "actions:  {}", scene.actions.len());
        for a in scene.action_summaries() {
            let _ = writeln!(w, "  {}", action_text(scene, &a));
        }
    }
    for object in scene.objects.iter().filter(|o| !o.clip_tracks.is_empty()) {
        let _ =
            writeln!(w, "clips:    {:?}, {} track(s), bottom first", object.name, object.clip_tracks.len());
        for track in &object.clip_tracks {
            let _ = writeln!(w, "  {}", track_text(track));
            for strip in &track.strips {
                let _ = writeln!(w, "    {}", strip_text(strip));
            }
        }
    }
    if !scene.layers.is_empty() {
        let _ = writeln!(w, "layers:   {}", scene.layers.len());
        for layer in &scene.layers {
            let _ = writeln!(w, "  {}", layer_text(layer));
        }
    }
    let channels = list_channels(scene);
    let names = ByName::new(scene);
    let animated: Vec<AnimatedChannel> = channels
        .iter()
        .filter_map(|ch| {
            let (n, span) = channel_keys(scene, &names, ch);
            (n > 0).then(|| (ch.to_string(), n, span))
        })
        .collect();
    let total: usize = animated.iter().map(|a| a.1).sum();
    let _ =
        writeln!(w, "tracks:   {} animated of {} channels, {} keys", animated.len(), channels.len(), total);
    // Pad by hand: a format width above u16::MAX (a 65,505-character name makes one) panics
    // in `format!`. Names longer than the column limit are not padded at all.
    let width = animated.iter().map(|a| a.0.chars().count()).filter(|&n| n <= MAX_PAD).max().unwrap_or(0);
    for (name, n, span) in &animated {
        let span = span.map_or(String::new(), |(a, b)| format!(", {a:.3}..{b:.3} s"));
        let pad = width.saturating_sub(name.chars().count());
        let _ = writeln!(w, "  {name}{}  {n} key{}{span}", " ".repeat(pad), if *n == 1 { "" } else { "s" });
    }
    if problems.is_empty() {
        let _ = writeln!(w, "problems: none");
    } else {
        let _ = writeln!(w, "problems: {}", problems.len());
        for p in problems {
            match p.position {
                Some((line, column)) => {
                    let _ = writeln!(w, "  {}:{line}:{column}: {}", path.display(), p.problem);
                }
                None => {
                    let _ = writeln!(w, "  {}: {}", path.display(), p.problem);
                }
            }
        }
    }
    out
}

fn summary_json(path: &Path, scene: &Scene, problems: &[LocatedProblem]) -> serde_json::Value {
    use serde_json::json;
    let objects: Vec<_> = scene
        .objects
        .iter()
        .map(|o| {
            json!({
                "name": o.name,
                "mesh": mesh_text(o.mesh.as_ref()),
                "deformer": o.deformer.kind.cli_name(),
                "joints": o.skeleton.as_ref().map(|s| s.joints.iter().map(|j| json!({
                    "name": j.name,
                    "parent": j.parent,
                })).collect::<Vec<_>>()),
            })
        })
        .collect();
    let lights: Vec<_> = scene
        .lights
        .iter()
        .map(|l| json!({"name": l.name, "kind": light_kind_text(&l.kind), "enabled": l.enabled}))
        .collect();
    let names = ByName::new(scene);
    let tracks: Vec<_> = list_channels(scene)
        .iter()
        .filter_map(|ch| {
            let (n, span) = channel_keys(scene, &names, ch);
            (n > 0).then(|| json!({"channel": ch.to_string(), "keys": n, "first_time": span.map(|s| s.0), "last_time": span.map(|s| s.1)}))
        })
        .collect();
    let problems: Vec<_> = problems
        .iter()
        .map(|p| {
            json!({
                "path": p.problem.path,
                "message": p.problem.message,
                "line": p.position.map(|p| p.0),
                "column": p.position.map(|p| p.1),
            })
        })
        .collect();
    let mut out = json!({
        "file": path.display().to_string(),
        "version": scene_file::CURRENT_VERSION,
        "fps": scene.fps,
        "frame_range": [scene.frame_range.start, scene.frame_range.end],
        "duration_s": duration_s(scene),
        "objects": objects,
        "lights": lights,
        "tracks": tracks,
        "keys": tracks.iter().filter_map(|t| t["keys"].as_u64()).sum::<u64>(),
        "problems": problems,
    });
    // Scenes without cameras and markers print what they printed before these existed.
    if !scene.cameras.is_empty() {
        out["cameras"] = scene
            .cameras
            .iter()
            .map(|c| json!({"name": c.name, "description": scene_camera_text(c)}))
            .collect();
    }
    if !scene.actions.is_empty() {
        out["actions"] = scene
            .action_summaries()
            .iter()
            .map(|a| {
                json!({
                    "name": a.name,
                    "active_on": a.active_on,
                    "channels": a.channels,
                    "keys": a.keys,
                    "first_time": a.time_range.map(|r| r.0),
                    "last_time": a.time_range.map(|r| r.1),
                })
            })
            .collect();
    }
    if scene.objects.iter().any(|o| !o.clip_tracks.is_empty()) {
        out["clip_tracks"] = scene
            .objects
            .iter()
            .filter(|o| !o.clip_tracks.is_empty())
            .map(|o| {
                json!({
                    "object": o.name,
                    "tracks": o.clip_tracks.iter().map(|t| json!({
                        "name": t.name,
                        "mute": t.mute,
                        "solo": t.solo,
                        "strips": t.strips.iter().map(|s| json!({
                            "action": s.action,
                            "start": s.start,
                            "end": s.end(),
                            "description": strip_text(s),
                        })).collect::<Vec<_>>(),
                    })).collect::<Vec<_>>(),
                })
            })
            .collect();
    }
    if !scene.layers.is_empty() {
        out["layers"] = scene
            .layers
            .iter()
            .map(|l| json!({"name": l.name, "action": l.action, "description": layer_text(l)}))
            .collect();
    }
    if !scene.markers.is_empty() {
        out["markers"] = scene
            .markers
            .iter()
            .map(|m| json!({"name": m.name, "frame": m.frame, "camera": m.camera}))
            .collect();
    }
    out
}

/// One clip track: its name and whether it plays.
fn track_text(track: &keyrig_core::ClipTrack) -> String {
    let state = match (track.mute, track.solo) {
        (true, _) => ", muted",
        (false, true) => ", solo",
        _ => "",
    };
    format!("track {:?}{state}: {} strip(s)", track.name, track.strips.len())
}

/// One strip: its action, frames and what is not at its default (docs/clips.md).
fn strip_text(s: &keyrig_core::Strip) -> String {
    let mut out =
        format!("{:?} frames {}..{} (action {}..{})", s.action, s.start, s.end(), s.action_in, s.action_out);
    if s.speed != 1.0 {
        out += &format!(", speed {}", s.speed);
    }
    if s.repeat != 1.0 {
        out += &format!(", repeat {}", s.repeat);
    }
    if s.reverse {
        out += ", reversed";
    }
    if s.blend_in != 0.0 || s.blend_out != 0.0 {
        out += &format!(", blend {}/{}", s.blend_in, s.blend_out);
    }
    if s.influence.is_animated() {
        out += &format!(", influence keyed ({} keys)", s.influence.track.len());
    } else if s.influence.value != 1.0 {
        out += &format!(", influence {}", s.influence.value);
    }
    if s.blend != keyrig_core::StripBlend::Replace {
        out += &format!(", {:?}", s.blend);
    }
    if s.extrapolation != keyrig_core::Extrapolation::HoldForward {
        out += &format!(", extrapolation {:?}", s.extrapolation);
    }
    if s.continue_root {
        out += ", root continues";
    }
    out
}

/// One layer: its action, mode, weight and state.
fn layer_text(l: &keyrig_core::Layer) -> String {
    let weight = if l.weight.is_animated() {
        format!("weight keyed ({} keys)", l.weight.track.len())
    } else {
        format!("weight {}", l.weight.value)
    };
    let state = match (l.mute, l.solo) {
        (true, _) => ", muted",
        (false, true) => ", solo",
        _ => "",
    };
    format!("{:?}: action {:?}, {:?}, {weight}{state}", l.name, l.action, l.mode)
}
