//! `keyrig deform FILE (--frame F | --time T) --deformer rigid|linear|bones-blending|dual-quaternion
//! [--object NAME] -o OUT.obj|OUT.json`: the deformed vertices of one object at one time, in
//! the object's model (skeleton) space and the mesh's own vertex order, computed on the CPU by
//! keyrig-skin's reference implementation of the chosen deformer.
//!
//! FILE is a scene (.ron), a glTF model (.glb/.gltf, every animation an action, through
//! keyrig-io's scene mapping) or an MD2 model. A skinned glTF node is posed exactly as the glTF specification
//! defines it (every channel, M(j) = world(j)·IBM(j), weights as stored) and written in the
//! file's world axes and accessor order, so linear blend reproduces glTF's skinning; the other
//! deformers use the same joints and weights.
//!
//! Vertex-animated meshes have no skin, so the deformer does not apply to them: an MD2 model
//! (on its own, or an MD2 object of a scene) is morphed between its frames as the editor
//! plays it (every frame, or the object's clip, at the object's rate —
//! [`keyrig_core::MD2_DEFAULT_FPS`] for a model opened on its own — looping), in the file's
//! Quake units and axes (`md2` space); a glTF mesh with morph targets is morphed as glTF
//! defines it (`base + Σ wᵢ·Δᵢ`, normals likewise) with the weights the scene evaluator gives
//! its object at that time (its `morph/<i>` channels: the file's weights channel for a model
//! opened on its own, the scene's own keys for a scene's object; the model file is read only
//! for rest data), placed by the object's world transform for a model opened on its own
//! (`gltf-world` space) and in the object's model space for a scene's object (`model`). OBJ
//! gets `v`, `vn` and `f` lines; JSON gets positions and unit normals as arrays of [x, y, z].

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context};
use keyrig_core::{DeformerKind, MeshSource, Scene};
use keyrig_eval::{LoadedMesh, Overrides, SceneEvaluator};
use keyrig_skin::{deform_mesh_into, Deformed, Execution, SkinnedMesh};

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").required(true).args(["frame", "time"])))]
pub struct DeformArgs {
    /// Scene (.ron), glTF model (.glb, .gltf) or MD2 model (.md2).
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
    /// Play this action (docs/actions.md) instead of the ones active in the file.
    #[arg(long, value_name = "NAME")]
    pub action: Option<String>,
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

/// What `keyrig deform` writes: one object's vertices at one time.
struct Output {
    object: String,
    /// `model`, `gltf-world` or `md2` (see the module documentation).
    space: &'static str,
    /// `skin` (the deformer ran) or `morph` (vertex animation; the deformer does not apply).
    animation: &'static str,
    positions: Vec<glam::Vec3>,
    normals: Vec<glam::Vec3>,
    indices: Vec<u32>,
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
    let mut inputs = vec![(file.clone(), "the input file".to_owned())];
    let (time, out) = if has_extension(file, &["md2"]) {
        let scene = keyrig_editor::files::open_any(file).map_err(anyhow::Error::msg)?;
        let time = super::common::time_in_range(&scene, args.frame, args.time)?;
        inputs.extend(keyrig_io::project::scene_inputs(&scene, None));
        (time, morph_object(file, &scene, None, args.object.as_deref(), time)?)
    } else {
        let (scene, loaded, gltf): (Scene, _, Option<GltfSource>) = if has_extension(file, &["ron"]) {
            let scene = keyrig_io::scene_file::load(file)?;
            let loaded = scene_meshes(file, &scene)?;
            (scene, loaded, None)
        } else if has_extension(file, &["glb", "gltf", "fbx"]) {
            let (scene, loaded, gltf) = gltf_scene(file)?;
            (scene, loaded, Some(gltf))
        } else {
            bail!(
                "{}: unknown file type; expected a scene (.ron), a glTF model (.glb, .gltf) or an MD2 model (.md2)",
                file.display()
            );
        };
        let scene = super::common::with_action(scene, args.action.as_deref(), file)?;
        let time = super::common::time_in_range(&scene, args.frame, args.time)?;
        let base_dir = if gltf.is_some() { None } else { Some(keyrig_io::file_io::parent_or_dot(file)) };
        if gltf.is_none() {
            inputs.extend(keyrig_io::project::scene_inputs(&scene, base_dir.as_deref()));
        }
        let index = object_index(file, &scene, args.object.as_deref())?;
        let is_md2_object = matches!(
            &scene.objects[index].mesh,
            Some(MeshSource::File { path, .. }) if has_extension(Path::new(path), &["md2"])
        );
        let unskinned_gltf = gltf.as_ref().and_then(|g| {
            let node = *g.nodes.get(index)?;
            g.model.nodes[node].skin.is_none().then_some((g, node))
        });
        let scene_morph = match gltf {
            None => scene_morph_mesh(file, &scene, index)?,
            Some(_) => None,
        };
        let out = if is_md2_object {
            morph_object(file, &scene, base_dir.as_deref(), args.object.as_deref(), time)?
        } else if let Some((g, node)) = unskinned_gltf {
            let n = &g.model.nodes[node];
            let mesh = n.mesh.with_context(|| format!("{}: node {node} has no mesh", file.display()))?;
            let rest = g.model.rest_pose().weights.swap_remove(node);
            gltf_morph(file, &scene, index, &g.model, mesh, &rest, time, true)?
        } else if let Some((model, mesh, rest)) = &scene_morph {
            gltf_morph(file, &scene, index, model, *mesh, rest, time, false)?
        } else {
            skinned_output(&args, &scene, loaded, gltf.as_ref(), index, time)?
        };
        (time, out)
    };
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
    let text = match format {
        OutputFormat::Obj => obj_text(&out, &args, time),
        OutputFormat::Json => json_text(&out, &args, time)?,
    };
    keyrig_io::file_io::write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("{}: cannot write", args.output.display()))?;
    Ok(())
}

/// The index of the object named `name`, or of the first object with a mesh.
fn object_index(file: &Path, scene: &Scene, name: Option<&str>) -> anyhow::Result<usize> {
    match name {
        Some(name) => scene.objects.iter().position(|o| o.name == name).with_context(|| {
            let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
            format!("{}: no object named `{name}` (objects: {})", file.display(), names.join(", "))
        }),
        None => scene
            .objects
            .iter()
            .position(|o| o.mesh.is_some())
            .with_context(|| format!("{}: no object has a mesh", file.display())),
    }
}

/// A skinned object through keyrig-skin's reference deformer (see the module documentation).
fn skinned_output(
    args: &DeformArgs,
    scene: &Scene,
    loaded: Vec<Option<SkinnedMesh>>,
    gltf: Option<&GltfSource>,
    index: usize,
    time: f64,
) -> anyhow::Result<Output> {
    let file = &args.file;
    let object = &scene.objects[index];
    let at = || format!("{}: object `{}`", file.display(), object.name);
    match &object.mesh {
        None => bail!("{}: object `{}` has no mesh", file.display(), object.name),
        Some(MeshSource::File { path, .. }) if loaded.get(index).is_none_or(Option::is_none) => bail!(
            "{}: objects[{index}] (`{}`).mesh: `{path}` has no skinned mesh to deform",
            file.display(),
            object.name
        ),
        _ => {}
    }
    // The one scene evaluator poses the object, as the editor and `render` do.
    let meshes: HashMap<usize, LoadedMesh> = loaded
        .into_iter()
        .enumerate()
        .filter_map(|(o, m)| m.map(|m| (o, LoadedMesh::Skinned(Arc::new(m)))))
        .collect();
    let eval = SceneEvaluator::new(scene, &meshes);
    if let Some(problem) = eval.problems().first() {
        bail!("{}: {problem}", file.display());
    }
    let skin = eval.skin(index).with_context(|| format!("{}: the mesh cannot be skinned", at()))?;
    let state = eval.object_at(index, time, &Overrides::new()).with_context(at)?;
    if let Some(error) = state.palette_error {
        return Err(error).with_context(at);
    }
    let bindings = Arc::clone(state.bindings(skin));
    let palette = state.palette.with_context(|| format!("{}: no joint palette", at()))?;
    let mut out = Deformed::default();
    deform_mesh_into(&skin.mesh, &bindings, &palette, args.deformer, Execution::Reference, &mut out)
        .with_context(|| format!("{}: {} deformer", at(), args.deformer.cli_name()))?;
    // A skinned glTF node's skeleton reaches up to the file's scene root, so its model space
    // is the file's world space, where the glTF specification skins.
    let skinned_gltf = gltf
        .and_then(|g| g.nodes.get(index))
        .is_some_and(|&node| gltf.is_some_and(|g| g.model.nodes[node].skin.is_some()));
    Ok(Output {
        object: object.name.clone(),
        space: if skinned_gltf { "gltf-world" } else { "model" },
        animation: "skin",
        positions: out.positions,
        normals: out.normals,
        indices: skin.mesh.indices.clone(),
    })
}

/// The skinned meshes of a scene's glTF objects (characters; meshes without a skin bound
/// rigidly to one joint), by object index, read through the editor's mesh store from paths
/// relative to the scene's folder: the scene poses them with its own keys, IK and deformer
/// choice, as the editor and `render` do.
fn scene_meshes(file: &Path, scene: &Scene) -> anyhow::Result<Vec<Option<SkinnedMesh>>> {
    let base_dir = keyrig_io::file_io::parent_or_dot(file);
    let mut store = keyrig_editor::files::MeshStore::default();
    let mut loaded = Vec::with_capacity(scene.objects.len());
    for (o, object) in scene.objects.iter().enumerate() {
        let mesh = match &object.mesh {
            Some(MeshSource::File { path, mesh, .. }) if !has_extension(Path::new(path), &["md2"]) => {
                match store.get(Some(&base_dir), path, *mesh).map_err(|e| {
                    anyhow::anyhow!("{}: objects[{o}] (`{}`).mesh: {e}", file.display(), object.name)
                })? {
                    keyrig_editor::files::FileMesh::Skinned(m) => Some((**m).clone()),
                    _ => None,
                }
            }
            _ => None,
        };
        loaded.push(mesh);
    }
    Ok(loaded)
}

/// An MD2 object (of a scene, or the object a model opened on its own becomes) morphed to
/// `time`, as the editor plays it.
fn morph_object(
    file: &Path,
    scene: &Scene,
    base_dir: Option<&Path>,
    name: Option<&str>,
    time: f64,
) -> anyhow::Result<Output> {
    let index = object_index(file, scene, name)?;
    let object = &scene.objects[index];
    let Some(MeshSource::File { path, mesh, clip, fps }) = &object.mesh else {
        bail!("{}: object `{}` has no model file mesh", file.display(), object.name);
    };
    let mut store = keyrig_editor::files::MeshStore::default();
    let loaded = store.get(base_dir, path, *mesh).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let keyrig_editor::files::FileMesh::Morph(morph) = loaded else {
        bail!("{}: object `{}`: `{path}` is not a vertex-animated model", file.display(), object.name);
    };
    let fps = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
    let blend = morph
        .blend_at(clip.as_deref(), fps, time)
        .with_context(|| format!("{}: object `{}`", file.display(), object.name))?;
    let (positions, normals) = morph.blended(blend);
    Ok(Output {
        object: object.name.clone(),
        space: "md2",
        animation: "morph",
        positions,
        normals,
        indices: morph.indices().to_vec(),
    })
}

/// A glTF mesh with morph targets at `time`, posed by the scene evaluator as the editor and
/// `render` pose it: the object's morph-weight channels (`object/<name>/morph/<i>`, the file's
/// weights channel when it was imported) and its placement come from the evaluator; the model
/// file gives only rest data (base positions and normals, the targets' displacements, the
/// default weights of targets the object does not key). Every triangle primitive is morphed
/// (`base + Σ wᵢ·Δᵢ`, normals likewise, or computed from the morphed triangles when the file
/// has none). With `place` the vertices are placed by the object's world transform (a glTF
/// file opened on its own: its nodes' world space), else they stay in the object's model space.
#[allow(clippy::too_many_arguments)]
fn gltf_morph(
    file: &Path,
    scene: &Scene,
    index: usize,
    model: &keyrig_io::model::ImportedModel,
    mesh: usize,
    rest_weights: &[f32],
    time: f64,
    place: bool,
) -> anyhow::Result<Output> {
    use keyrig_io::model::{ImportedModel, PrimitiveMode};
    let object = &scene.objects[index].name;
    let at = || format!("{}: object `{object}`", file.display());
    let mesh = model.meshes.get(mesh).with_context(|| format!("{}: mesh {mesh} does not exist", at()))?;
    let eval = SceneEvaluator::new(scene, &HashMap::new());
    if let Some(problem) = eval.problems().first() {
        bail!("{}: {problem}", file.display());
    }
    let state = eval.object_at(index, time, &Overrides::new()).with_context(at)?;
    let mut weights = rest_weights.to_vec();
    if weights.len() < state.look.morph_weights.len() {
        weights.resize(state.look.morph_weights.len(), 0.0);
    }
    weights[..state.look.morph_weights.len()].copy_from_slice(&state.look.morph_weights);
    let world = if place { glam::Mat4::from(state.world_from_object) } else { glam::Mat4::IDENTITY };
    let normal_matrix = glam::Mat3::from_mat4(world).inverse().transpose();
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for prim in mesh.primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles) {
        let base = positions.len() as u32;
        let morphed = ImportedModel::morphed_positions(prim, &weights);
        let prim_normals = match &prim.normals {
            Some(n) => {
                let mut n = n.to_vec();
                for (target, &w) in prim.morph_targets.iter().zip(&weights) {
                    if let Some(d) = &target.normals {
                        for (n, d) in n.iter_mut().zip(d.iter()) {
                            *n += w * *d;
                        }
                    }
                }
                n
            }
            None => keyrig_skin::mesh::vertex_normals(&morphed, &prim.indices),
        };
        positions.extend(morphed.iter().map(|&p| world.transform_point3(p)));
        normals.extend(prim_normals.iter().map(|&n| normal_matrix * n));
        indices.extend(prim.indices.iter().map(|&i| base + i));
    }
    if positions.is_empty() {
        bail!("{}: its mesh `{}` has no triangles", at(), mesh.name);
    }
    Ok(Output {
        object: object.clone(),
        space: if place { "gltf-world" } else { "model" },
        animation: "morph",
        positions,
        normals,
        indices,
    })
}

/// The glTF model file and mesh of scene object `index` when it is an unskinned glTF mesh with
/// morph targets (read for its rest data), with the mesh's default weights.
fn scene_morph_mesh(
    file: &Path,
    scene: &Scene,
    index: usize,
) -> anyhow::Result<Option<(keyrig_io::model::ImportedModel, usize, Vec<f32>)>> {
    let Some(MeshSource::File { path, mesh, .. }) = &scene.objects[index].mesh else { return Ok(None) };
    if !has_extension(Path::new(path), &["glb", "gltf", "fbx"]) {
        return Ok(None);
    }
    let full = keyrig_io::file_io::parent_or_dot(file).join(path);
    let model = keyrig_io::fbx::import_model_file(&full)
        .with_context(|| format!("{}: objects[{index}].mesh: {}", file.display(), full.display()))?;
    let m = mesh.unwrap_or(0);
    let Some(found) = model.meshes.get(m) else { return Ok(None) };
    let morphs = found.primitives.iter().any(|p| !p.morph_targets.is_empty());
    let skinned = model.nodes.iter().any(|n| n.mesh == Some(m) && n.skin.is_some());
    if !morphs || skinned {
        return Ok(None);
    }
    let weights = found.weights.clone();
    Ok(Some((model, m, weights)))
}

/// The object to deform and its mesh. Scene objects with a procedural mesh get it generated
/// (bound to the object's own skeleton and scaled to its length, as the renderer does); glTF
/// A glTF model as a scene (keyrig-io's mapping, every animation an action), with the skinned meshes of
/// its skinned mesh nodes by object index.
fn gltf_scene(path: &Path) -> anyhow::Result<(Scene, Vec<Option<SkinnedMesh>>, GltfSource)> {
    let model = keyrig_io::fbx::import_model_file(path)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let scene =
        model.to_scene_all(&name).with_context(|| format!("{}: mapping to a scene", path.display()))?;
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

/// The glTF model behind a scene made by [`gltf_scene`]: the model (rest data) and the node of
/// each scene object (by object index).
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

fn header(out: &Output, args: &DeformArgs, time: f64) -> String {
    let deformer = match out.animation {
        "morph" => "no deformer (vertex morphing)".to_owned(),
        _ => format!("{} deformer", args.deformer.cli_name()),
    };
    format!(
        "keyrig deform: {} object `{}`, {deformer}, t = {time} s, {} vertices, {} space",
        args.file.display(),
        out.object,
        out.positions.len(),
        out.space
    )
}

fn obj_text(out: &Output, args: &DeformArgs, time: f64) -> String {
    let mut text = String::with_capacity(out.positions.len() * 64);
    let _ = writeln!(text, "# {}", header(out, args, time));
    for p in &out.positions {
        let _ = writeln!(text, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &out.normals {
        let n = n.normalize_or_zero();
        let _ = writeln!(text, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in out.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    text
}

fn json_text(out: &Output, args: &DeformArgs, time: f64) -> anyhow::Result<String> {
    let triple = |v: glam::Vec3| [v.x, v.y, v.z];
    let value = serde_json::json!({
        "file": args.file.display().to_string(),
        "object": out.object,
        "deformer": args.deformer.cli_name(),
        "animation": out.animation,
        "time": time,
        "vertex_count": out.positions.len(),
        "space": out.space,
        "positions": out.positions.iter().map(|&p| triple(p)).collect::<Vec<_>>(),
        "normals": out.normals.iter().map(|n| triple(n.normalize_or_zero())).collect::<Vec<_>>(),
        "indices": out.indices,
    });
    Ok(serde_json::to_string(&value)?)
}
