//! `keyrig deform FILE (--frame F | --time T) --deformer rigid|linear|bones-blending|dual-quaternion
//! [--object NAME] -o OUT.obj|OUT.json`: the deformed vertices of one object at one time, in
//! the object's model (skeleton) space and the mesh's own vertex order, computed on the CPU by
//! keyrig-skin's reference implementation of the chosen deformer.
//!
//! FILE is a scene (.ron) or a glTF model (.glb/.gltf, its first animation, through
//! keyrig-io's scene mapping). A skinned glTF node is posed exactly as the glTF specification
//! defines it (every channel, M(j) = world(j)·IBM(j), weights as stored) and written in the
//! file's world axes and accessor order, so linear blend reproduces glTF's skinning; the other
//! deformers use the same joints and weights. OBJ gets `v`, `vn` and `f` lines; JSON gets
//! positions and unit normals as arrays of [x, y, z].

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use keyrig_core::{DeformerKind, MeshSource, Scene};
use keyrig_skin::{
    deform_mesh_into, mesh_for, BlendZone, Deformed, Execution, JointPalette, Pose, RestSkeleton,
    ScenePoseSampler, SkinnedMesh,
};

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").required(true).args(["frame", "time"])))]
pub struct DeformArgs {
    /// Scene (.ron) or glTF model (.glb, .gltf).
    pub file: PathBuf,
    /// Frame (may be fractional), at the scene's frames per second.
    #[arg(long, allow_hyphen_values = true)]
    pub frame: Option<f64>,
    /// Time in seconds.
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// rigid, linear, bones-blending or dual-quaternion.
    #[arg(long, value_parser = parse_deformer)]
    pub deformer: DeformerKind,
    /// The object to deform (by name); the first object with a mesh by default.
    #[arg(long)]
    pub object: Option<String>,
    /// Output file: .obj or .json.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
}

fn parse_deformer(name: &str) -> Result<DeformerKind, String> {
    DeformerKind::from_cli_name(name).ok_or_else(|| {
        let names: Vec<&str> = DeformerKind::ALL.iter().map(|k| k.cli_name()).collect();
        format!("unknown deformer `{name}`; expected one of: {}", names.join(", "))
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum OutputFormat {
    Obj,
    Json,
}

fn has_extension(path: &Path, extensions: &[&str]) -> bool {
    path.extension().is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// What `keyrig deform` deforms: a mesh bound to its rest skeleton, the pose sampler of the
/// object's scene skeleton (none: rest pose), and the object's blend zone.
struct Target {
    /// Index of the object in the scene.
    index: usize,
    object: String,
    /// The space of the output: `model` (the object's skeleton space) or `gltf-world` (a
    /// skinned glTF node: the file's world axes, as the glTF specification skins).
    space: &'static str,
    mesh: SkinnedMesh,
    poser: Option<ScenePoseSampler>,
    zone: BlendZone,
}

pub fn run(args: DeformArgs) -> anyhow::Result<()> {
    let format = if has_extension(&args.output, &["obj"]) {
        OutputFormat::Obj
    } else if has_extension(&args.output, &["json"]) {
        OutputFormat::Json
    } else {
        bail!("{}: the output must end in .obj or .json", args.output.display());
    };
    let file = &args.file;
    let (scene, loaded, gltf) = if has_extension(file, &["ron"]) {
        (keyrig_io::scene_file::load(file)?, Vec::new(), None)
    } else if has_extension(file, &["glb", "gltf"]) {
        let (scene, loaded, gltf) = gltf_scene(file)?;
        (scene, loaded, Some(gltf))
    } else if has_extension(file, &["md2"]) {
        bail!("{}: MD2 models have no skeleton to deform (they animate by vertex morphing)", file.display());
    } else {
        bail!("{}: unknown file type; expected a scene (.ron) or a glTF model (.glb, .gltf)", file.display());
    };
    let time = match (args.frame, args.time) {
        (Some(frame), None) => {
            if !frame.is_finite() {
                bail!("--frame {frame}: not a finite number");
            }
            frame / scene.fps
        }
        (None, Some(time)) if time.is_finite() => time,
        (None, Some(time)) => bail!("--time {time}: not a finite number"),
        _ => bail!("give exactly one of --frame and --time"),
    };
    let mut target = pick_target(file, &scene, loaded, args.object.as_deref())?;
    let pose = match &target.poser {
        Some(poser) => poser.sample(time),
        None => Pose::rest(target.mesh.skeleton.len()),
    };
    let at = || format!("{}: object `{}`", file.display(), target.object);
    let palette = JointPalette::new(&target.mesh.skeleton, &pose).with_context(at)?;
    let bindings = target.mesh.bindings(target.zone).with_context(at)?;
    let mut out = Deformed::default();
    deform_mesh_into(&target.mesh, &bindings, &palette, args.deformer, Execution::Reference, &mut out)
        .with_context(|| format!("{}: {} deformer", at(), args.deformer.cli_name()))?;
    // A skinned glTF node's skeleton reaches up to the file's scene root, so its model space
    // is the file's world space, where the glTF specification skins.
    let skinned_gltf = gltf
        .as_ref()
        .and_then(|g| g.nodes.get(target.index))
        .is_some_and(|&node| gltf.as_ref().is_some_and(|g| g.model.nodes[node].skin.is_some()));
    if skinned_gltf {
        target.space = "gltf-world";
    }
    let text = match format {
        OutputFormat::Obj => obj_text(&target, &args, time, &out),
        OutputFormat::Json => json_text(&target, &args, time, &out)?,
    };
    std::fs::write(&args.output, text).with_context(|| format!("{}: cannot write", args.output.display()))?;
    Ok(())
}

/// The object to deform and its mesh. Scene objects with a procedural mesh get it generated
/// (bound to the object's own skeleton and scaled to its length, as the renderer does); glTF
/// objects come with their loaded mesh.
fn pick_target(
    file: &Path,
    scene: &Scene,
    mut loaded: Vec<Option<SkinnedMesh>>,
    name: Option<&str>,
) -> anyhow::Result<Target> {
    let index = match name {
        Some(name) => scene.objects.iter().position(|o| o.name == name).with_context(|| {
            let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
            format!("{}: no object named `{name}` (objects: {})", file.display(), names.join(", "))
        })?,
        None => scene
            .objects
            .iter()
            .position(|o| o.mesh.is_some())
            .with_context(|| format!("{}: no object has a mesh", file.display()))?,
    };
    let object = &scene.objects[index];
    let at = |field: &str| format!("{}: objects[{index}] (`{}`).{field}", file.display(), object.name);
    let rest = match &object.skeleton {
        Some(skeleton) => Some(RestSkeleton::from_scene(skeleton).with_context(|| at("skeleton"))?),
        None => None,
    };
    let mesh = match &object.mesh {
        None => bail!("{}: object `{}` has no mesh", file.display(), object.name),
        Some(MeshSource::Procedural(kind)) => match &rest {
            Some(rest) => mesh_for(*kind).fit_to_skeleton(rest.clone()).with_context(|| at("skeleton"))?,
            None => mesh_for(*kind),
        },
        Some(MeshSource::File { path, .. }) => match loaded.get_mut(index).and_then(Option::take) {
            Some(mesh) => {
                if let Some(rest) = &rest {
                    if rest.len() != mesh.skeleton.len() {
                        bail!(
                            "{}: {} joints, but the mesh from `{path}` is bound to {}",
                            at("skeleton"),
                            rest.len(),
                            mesh.skeleton.len()
                        );
                    }
                }
                mesh
            }
            None => bail!(
                "{}: the mesh comes from `{path}`; deform the model file itself (keyrig deform {path} …)",
                at("mesh")
            ),
        },
    };
    let poser = match &object.skeleton {
        Some(skeleton) => Some(ScenePoseSampler::new(skeleton).with_context(|| at("skeleton"))?),
        None => None,
    };
    let zone = BlendZone::from_settings(&object.deformer).with_context(|| at("deformer"))?;
    Ok(Target { index, object: object.name.clone(), space: "model", mesh, poser, zone })
}

/// A glTF model as a scene (keyrig-io's mapping, first animation), with the skinned meshes of
/// its skinned mesh nodes by object index.
fn gltf_scene(path: &Path) -> anyhow::Result<(Scene, Vec<Option<SkinnedMesh>>, GltfSource)> {
    let model = keyrig_io::gltf_import::import_gltf_file(path)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let animation = (!model.animations.is_empty()).then_some(0);
    let scene = model
        .to_scene(&name, animation)
        .with_context(|| format!("{}: mapping to a scene", path.display()))?;
    // keyrig-io's to_scene makes one object per node with a mesh, in node order.
    let mut loaded = Vec::new();
    let mut nodes = Vec::new();
    for (node, n) in model.nodes.iter().enumerate().filter(|(_, n)| n.mesh.is_some()) {
        nodes.push(node);
        loaded.push(match n.skin {
            Some(_) => {
                check_weights(&model, node)
                    .with_context(|| format!("{}: node {node} (`{}`)", path.display(), n.name))?;
                Some(model.skinned_mesh(node).with_context(|| format!("{}: node {node}", path.display()))?)
            }
            None => None,
        });
    }
    Ok((scene, loaded, GltfSource { model, nodes }))
}

/// The glTF model behind a scene made by [`gltf_scene`]: the model, the animation used and the
/// node of each scene object (by object index).
struct GltfSource {
    model: keyrig_io::model::ImportedModel,
    nodes: Vec<usize>,
}

/// Checks the weights of a skinned node's mesh as stored in the file (the scene mapping keeps
/// the four largest positive weights and would hide bad ones): every weight finite and ≥ 0,
/// not all zero.
fn check_weights(model: &keyrig_io::model::ImportedModel, node: usize) -> anyhow::Result<()> {
    let Some(mesh) = model.nodes[node].mesh.and_then(|m| model.meshes.get(m)) else { return Ok(()) };
    for (p, primitive) in mesh.primitives.iter().enumerate() {
        for vertex in 0..primitive.positions.len() {
            let mut sum = 0.0f32;
            for (set, weights) in primitive.weight_sets.iter().enumerate() {
                let Some(ws) = weights.get(vertex) else { continue };
                for (i, &w) in ws.iter().enumerate() {
                    if !w.is_finite() {
                        bail!("mesh `{}` primitive {p} vertex {vertex}: weight WEIGHTS_{set}[{i}] = {w} is not finite", mesh.name);
                    }
                    if w < 0.0 {
                        bail!("mesh `{}` primitive {p} vertex {vertex}: weight WEIGHTS_{set}[{i}] = {w} is negative", mesh.name);
                    }
                    sum += w;
                }
            }
            if !primitive.weight_sets.is_empty() && sum == 0.0 {
                bail!("mesh `{}` primitive {p} vertex {vertex}: all weights are zero", mesh.name);
            }
        }
    }
    Ok(())
}

fn header(target: &Target, args: &DeformArgs, time: f64) -> String {
    format!(
        "keyrig deform: {} object `{}`, {} deformer, t = {time} s, {} vertices, {} space",
        args.file.display(),
        target.object,
        args.deformer.cli_name(),
        target.mesh.vertex_count(),
        target.space
    )
}

fn obj_text(target: &Target, args: &DeformArgs, time: f64, out: &Deformed) -> String {
    let mut text = String::with_capacity(out.positions.len() * 64);
    let _ = writeln!(text, "# {}", header(target, args, time));
    for p in &out.positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &out.normals {
        let n = n.normalize_or_zero();
        let _ = writeln!(text, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in target.mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    text
}

fn json_text(target: &Target, args: &DeformArgs, time: f64, out: &Deformed) -> anyhow::Result<String> {
    let triple = |v: glam::Vec3| [v.x, v.y, v.z];
    let value = serde_json::json!({
        "file": args.file.display().to_string(),
        "object": target.object,
        "deformer": args.deformer.cli_name(),
        "time": time,
        "vertex_count": out.positions.len(),
        "space": target.space,
        "positions": out.positions.iter().map(|&p| triple(p)).collect::<Vec<_>>(),
        "normals": out.normals.iter().map(|n| triple(n.normalize_or_zero())).collect::<Vec<_>>(),
        "indices": target.mesh.indices,
    });
    Ok(serde_json::to_string(&value)?)
}
