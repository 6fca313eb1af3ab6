//! `keyrig render FILE [--frame F | --frames A..B] [--deformer D] [--size WxH]
//! [--motion-blur N [--shutter S]] -o OUT`: offscreen PNGs, or a playblast (MP4, GIF, animated
//! PNG, numbered PNGs: keyrig_editor::playblast) of a scene (.ron) or a model (.glb/.gltf:
//! keyrig-io's scene mapping, first animation; .md2: GPU vertex morphing), through
//! keyrig-render's headless path (the adapter wgpu finds; lavapipe without a GPU). Models are
//! drawn with their materials (glTF base colour and texture, MD2 skins) unless `--no-textures`
//! is given.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{bail, Context};
use glam::{Mat4, Quat, Vec3};
use keyrig_core::{Camera, DeformerKind, Material};
use keyrig_editor::playblast::{self, FrameError, MotionBlur, MovieFormat, Playblast, SceneSound};
use keyrig_editor::view::LookThrough;
use keyrig_render::{
    Deform, DrawItem, FrameInput, HeadlessRenderer, LightInput, MeshData, RenderStyle, SceneRig, Selected,
    ViewOptions,
};
use keyrig_skin::SkinnedMesh;

/// Largest image side accepted on the command line.
const MAX_SIDE: u32 = 16384;
/// MD2 models animate at Quake 2's 10 frames per second on keyrig's 30 fps timeline.
const MD2_FRAMES_PER_TIMELINE_FRAME: f64 = 10.0 / 30.0;

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene (.ron) or model (.glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv, .iv) to render.
    pub file: PathBuf,
    /// Frame to render (may be fractional); the first frame of the scene's range by default.
    #[arg(long, conflicts_with = "frames", allow_negative_numbers = true)]
    pub frame: Option<f64>,
    /// Inclusive range of frames `A..B`: a playblast written as OUT says (a movie or
    /// numbered PNGs).
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Deformer for every skinned object: rigid, linear, bones-blending, dual-quaternion
    /// (default: each object's own).
    #[arg(long, value_name = "D")]
    pub deformer: Option<String>,
    /// Image size (default: the scene's render size, else 1280x720).
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,
    /// Render through the scene camera named NAME at every frame (default: the scene's
    /// active camera at each frame, switched by markers; the saved view without cameras).
    #[arg(long, value_name = "NAME", conflicts_with = "view")]
    pub camera: Option<String>,
    /// Render through the scene's saved viewport view even when it has cameras.
    #[arg(long)]
    pub view: bool,
    /// Render style: solid, wireframe, points.
    #[arg(long, default_value = "solid")]
    pub style: String,
    /// Hide the ground grid.
    #[arg(long)]
    pub no_grid: bool,
    /// Draw without materials (glTF base colour and texture, MD2 skins): plain colours.
    #[arg(long)]
    pub no_textures: bool,
    /// Hide skeletons.
    #[arg(long)]
    pub no_skeleton: bool,
    /// Highlight something and draw its motion path: `object:NAME`, `joint:OBJECT/JOINT` or
    /// `light:NAME`.
    #[arg(long, value_name = "WHAT")]
    pub select: Option<String>,
    /// Output. One frame: a PNG. A range: `shot.mp4` (H.264, with the scene's sound clips
    /// mixed as 16-bit PCM), `shot.gif` (animated GIF),
    /// `shot.png` (animated PNG), a pattern with `#`s replaced by the zero-padded frame number
    /// (`out/arm_####.png`) or an existing folder (→ `frame_0000.png` …) for numbered PNGs.
    #[arg(short, long, value_name = "OUT")]
    pub output: PathBuf,
    /// Output type of a range, instead of the one OUT's name implies: mp4, gif, apng,
    /// png-frames (numbered PNGs; a plain OUT name gets `_0000` before its extension).
    #[arg(long, value_name = "TYPE")]
    pub format: Option<String>,
    /// Motion blur: each frame is the average of N renders spread across the shutter (1: none).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub motion_blur: u32,
    /// Shutter of motion blur, a fraction of the frame interval centred on the frame (0 to 1).
    #[arg(long, value_name = "S", default_value_t = keyrig_editor::playblast::DEFAULT_SHUTTER)]
    pub shutter: f64,
}

/// Parses `WxH`.
fn parse_size(text: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .with_context(|| format!("--size `{text}`: expected WIDTHxHEIGHT, e.g. 1280x720"))?;
    let parse = |s: &str, what: &str| -> anyhow::Result<u32> {
        let v: u32 = s
            .trim()
            .parse()
            .with_context(|| format!("--size `{text}`: {what} `{s}` is not a whole number"))?;
        if v == 0 || v > MAX_SIDE {
            bail!("--size `{text}`: {what} must be between 1 and {MAX_SIDE}");
        }
        Ok(v)
    };
    Ok((parse(w, "width")?, parse(h, "height")?))
}

/// Parses `A..B` (inclusive, A ≤ B, whole frames).
fn parse_range(text: &str) -> anyhow::Result<(i64, i64)> {
    let (a, b) =
        text.split_once("..").with_context(|| format!("--frames `{text}`: expected A..B, e.g. 0..30"))?;
    let a: i64 =
        a.trim().parse().with_context(|| format!("--frames `{text}`: start `{a}` is not a whole number"))?;
    let b: i64 =
        b.trim().parse().with_context(|| format!("--frames `{text}`: end `{b}` is not a whole number"))?;
    if a > b {
        bail!("--frames `{text}`: start {a} is after end {b}");
    }
    if b - a > 100_000 {
        bail!("--frames `{text}`: {} frames is more than 100000", b - a + 1);
    }
    Ok((a, b))
}

/// Renders frames on demand.
trait FrameSource {
    fn frame(&self, frame: f64) -> anyhow::Result<FrameInput>;
    fn default_frame(&self) -> f64;
    /// Errors when `frame` is outside what the source plays (`what` names the argument).
    fn check(&self, frame: f64, what: &str) -> anyhow::Result<()>;
    /// Frames per second of the timeline (a movie's frame rate).
    fn fps(&self) -> f64;
}

struct SceneSource {
    rig: SceneRig,
    view: ViewOptions,
    /// Which scene camera each frame is seen through (`None`: the saved view).
    through: Option<LookThrough>,
}

/// The camera a scene is rendered through: `None` is the scene's saved viewport view.
fn through_of(scene: &keyrig_core::Scene, args: &RenderArgs) -> anyhow::Result<Option<LookThrough>> {
    match &args.camera {
        Some(name) => scene.camera_index(name).map(|c| Some(LookThrough::Camera(c))).with_context(|| {
            let names: Vec<&str> = scene.cameras.iter().map(|c| c.name.as_str()).collect();
            if names.is_empty() {
                format!("--camera `{name}`: the scene has no cameras")
            } else {
                format!("--camera `{name}`: no camera named `{name}` (cameras: {})", names.join(", "))
            }
        }),
        None if args.view || scene.cameras.is_empty() => Ok(None),
        None => Ok(Some(LookThrough::Active)),
    }
}

impl FrameSource for SceneSource {
    fn frame(&self, frame: f64) -> anyhow::Result<FrameInput> {
        Ok(playblast::scene_frame(&self.rig, &self.view, self.through, frame)?)
    }

    fn default_frame(&self) -> f64 {
        f64::from(self.rig.scene().frame_range.start)
    }

    fn check(&self, frame: f64, what: &str) -> anyhow::Result<()> {
        super::common::check_frame(self.rig.scene(), frame, what)
    }

    fn fps(&self) -> f64 {
        self.rig.scene().fps
    }
}

struct Md2Source {
    frame_count: usize,
    camera: Camera,
    style: RenderStyle,
    grid: bool,
    /// The model has a skin and textures are on.
    textured: bool,
}

impl FrameSource for Md2Source {
    fn frame(&self, frame: f64) -> anyhow::Result<FrameInput> {
        let last = (self.frame_count - 1) as f64;
        let position = (frame * MD2_FRAMES_PER_TIMELINE_FRAME).clamp(0.0, last);
        let a = position.floor();
        let mut input = FrameInput::new(self.camera);
        input.style = self.style;
        input.textures = self.textured;
        if !self.grid {
            input.grid_spacing = None;
        }
        input.lights = vec![LightInput {
            kind: keyrig_core::LightKind::Directional,
            position: Vec3::ZERO,
            direction: Vec3::new(-0.4, -1.0, -0.6),
            colour: Vec3::ONE,
            intensity: 0.9,
            range: None,
        }];
        input.ambient = Vec3::splat(0.15);
        input.items.push(DrawItem {
            mesh: 0,
            // Quake's Z up to keyrig's Y up.
            world_from_model: Mat4::from_quat(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)),
            deform: Deform::Morph {
                frame_a: a as u32,
                frame_b: (a as u32 + 1).min(last as u32),
                t: (position - a) as f32,
            },
            // The skin as it is (white × texture), or the plain colour.
            opacity: 1.0,
            colour: if self.textured { Vec3::ONE } else { Vec3::new(0.7, 0.65, 0.6) },
            selected: false,
            ghost: None,
        });
        Ok(input)
    }

    fn default_frame(&self) -> f64 {
        0.0
    }

    fn fps(&self) -> f64 {
        // keyrig's timeline rate, on which MD2 frames play at MD2_FRAMES_PER_TIMELINE_FRAME.
        30.0
    }

    fn check(&self, frame: f64, what: &str) -> anyhow::Result<()> {
        let last = (self.frame_count - 1) as f64 / MD2_FRAMES_PER_TIMELINE_FRAME;
        if !(0.0..=last + 1e-9).contains(&frame) {
            bail!(
                "{what} is outside the model's frame range 0..={last} ({} MD2 frames at {} per timeline frame)",
                self.frame_count,
                MD2_FRAMES_PER_TIMELINE_FRAME
            );
        }
        Ok(())
    }
}

/// Parses `--select` against the scene's names.
fn parse_selection(scene: &keyrig_core::Scene, text: &str) -> anyhow::Result<Selected> {
    let object_index = |name: &str| {
        scene.objects.iter().position(|o| o.name == name).with_context(|| {
            let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
            format!("--select `{text}`: no object named `{name}` (objects: {})", names.join(", "))
        })
    };
    match text.split_once(':') {
        Some(("object", name)) => Ok(Selected::Object(object_index(name)?)),
        Some(("light", name)) => {
            let index = scene.lights.iter().position(|l| l.name == name).with_context(|| {
                let names: Vec<&str> = scene.lights.iter().map(|l| l.name.as_str()).collect();
                format!("--select `{text}`: no light named `{name}` (lights: {})", names.join(", "))
            })?;
            Ok(Selected::Light(index))
        }
        Some(("joint", path)) => {
            let (object, joint) = path
                .split_once('/')
                .with_context(|| format!("--select `{text}`: expected joint:OBJECT/JOINT"))?;
            let o = object_index(object)?;
            let joints = scene.objects[o].skeleton.as_ref().map(|s| s.joints.as_slice()).unwrap_or_default();
            let j = joints.iter().position(|j| j.name == joint).with_context(|| {
                let names: Vec<&str> = joints.iter().map(|j| j.name.as_str()).collect();
                format!("--select `{text}`: `{object}` has no joint `{joint}` (joints: {})", names.join(", "))
            })?;
            Ok(Selected::Joint { object: o, joint: j })
        }
        _ => bail!("--select `{text}`: expected object:NAME, joint:OBJECT/JOINT or light:NAME"),
    }
}

fn has_extension(path: &Path, extensions: &[&str]) -> bool {
    path.extension().is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// A glTF model as a scene (keyrig-io's mapping, first animation) with its meshes: skinned
/// nodes through keyrig-io's `skinned_mesh`, other mesh nodes as rigid meshes on one joint.
/// A glTF file's scene, its meshes and their materials, by object.
type GltfScene = (keyrig_core::Scene, HashMap<usize, SkinnedMesh>, HashMap<usize, Arc<Material>>);

fn gltf_scene(path: &Path) -> anyhow::Result<GltfScene> {
    let model = keyrig_io::fbx::import_model_file(path)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let mut scene =
        model.to_scene_all(&name).with_context(|| format!("{}: mapping to a scene", path.display()))?;
    // keyrig-io's to_scene makes one object per node with a mesh, in node order.
    let mesh_nodes: Vec<usize> =
        model.nodes.iter().enumerate().filter(|(_, n)| n.mesh.is_some()).map(|(i, _)| i).collect();
    let (mut loaded, mut materials) = (HashMap::new(), HashMap::new());
    for (object, &node) in mesh_nodes.iter().enumerate() {
        // A texture that cannot be decoded leaves the base colour (the mesh is still drawn).
        if let Some(material) = model.nodes[node]
            .mesh
            .and_then(|m| model.material(m).unwrap_or_else(|e| Some(e.without_texture())))
        {
            materials.insert(object, Arc::new(material));
        }
        let mesh = if model.nodes[node].skin.is_some() {
            model.skinned_mesh(node).with_context(|| format!("{}: node {node}", path.display()))?
        } else {
            let Some(mesh) = model.nodes[node].mesh else { continue };
            model.rigid_mesh(mesh).with_context(|| format!("{}: mesh of node {node}", path.display()))?
        };
        loaded.insert(object, mesh);
    }
    frame_scene(&mut scene, &loaded);
    Ok((scene, loaded, materials))
}

/// Points the scene's camera at the models' rest bounds (glTF files carry no keyrig camera).
fn frame_scene(scene: &mut keyrig_core::Scene, loaded: &HashMap<usize, SkinnedMesh>) {
    let mut points = Vec::new();
    for (&object, mesh) in loaded {
        let Some(o) = scene.objects.get(object) else { continue };
        let world = keyrig_editor::files::rest_world_from_object(o);
        points.extend(mesh.positions.iter().map(|&p| world.transform_point3(p)));
    }
    keyrig_editor::files::frame_model_scene(scene, points);
}

fn md2_source(path: &Path, headless: &mut HeadlessRenderer, args: &RenderArgs) -> anyhow::Result<Md2Source> {
    let model = keyrig_io::md2::load_md2_file(path)?;
    // The editor's conversion (also used for MD2 objects of scene files).
    let mesh = keyrig_editor::files::morph_mesh_from_md2(&model)
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let frames = mesh.frames();
    let renderer = headless.renderer_mut();
    renderer
        .upload_mesh_with_uvs(0, &MeshData::Morph { frames, indices: mesh.indices() }, mesh.uvs())
        .with_context(|| format!("{}: uploading the model", path.display()))?;
    let texture = mesh.material().and_then(|m| m.base_colour_texture.as_deref());
    renderer.set_texture(0, texture).with_context(|| format!("{}: uploading its skin", path.display()))?;
    // Frame the first frame's bounds (in Y-up world space).
    let to_world = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let (min, max) = frames[0].iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| {
        let p = to_world * v.position();
        (lo.min(p), hi.max(p))
    });
    let radius = ((max - min).length() * 0.5).max(1e-3);
    let camera = Camera {
        target: (min + max) * 0.5,
        yaw_deg: 30.0,
        pitch_deg: 15.0,
        distance: radius * 2.8,
        fov_y_deg: 45.0,
    };
    Ok(Md2Source {
        frame_count: frames.len(),
        camera,
        style: style_of(args)?,
        grid: !args.no_grid,
        textured: texture.is_some() && !args.no_textures,
    })
}

fn style_of(args: &RenderArgs) -> anyhow::Result<RenderStyle> {
    RenderStyle::from_cli_name(&args.style)
        .with_context(|| format!("--style `{}`: expected solid, wireframe or points", args.style))
}

pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let explicit_size = args.size.as_deref().map(parse_size).transpose()?;
    let style = style_of(&args)?;
    let deformer = match &args.deformer {
        None => None,
        Some(name) => Some(DeformerKind::from_cli_name(name).with_context(|| {
            format!("--deformer `{name}`: expected rigid, linear, bones-blending or dual-quaternion")
        })?),
    };
    if let Some(f) = args.frame {
        if !f.is_finite() {
            bail!("--frame {f}: not a finite number");
        }
    }
    let range = args.frames.as_deref().map(parse_range).transpose()?;

    // What an output must never replace: the file rendered, the models a scene uses, an MD2 skin.
    let mut inputs = vec![(args.file.clone(), "the input file".to_owned())];
    if has_extension(&args.file, &["md2"]) {
        if let Some(skin) = keyrig_io::md2::skin_of_file(&args.file) {
            inputs.push((skin, "the model's skin image".to_owned()));
        }
    }
    let mut headless = HeadlessRenderer::new().context("opening a GPU device for offscreen rendering")?;
    let mut scene_size = None;
    // A scene's sound clips, for an MP4's sound track.
    let mut sound = SceneSound::default();
    let source: Box<dyn FrameSource> = if has_extension(&args.file, &["md2"]) {
        if args.camera.is_some() {
            bail!("--camera: {} is an MD2 model; it has no scene cameras", args.file.display());
        }
        if deformer.is_some() {
            bail!(
                "--deformer: {} is a vertex-animated MD2 model; it has no skin to deform",
                args.file.display()
            );
        }
        Box::new(md2_source(&args.file, &mut headless, &args)?)
    } else {
        let (scene, loaded, morphs, materials) = if has_extension(&args.file, &["glb", "gltf", "fbx"]) {
            let (scene, loaded, materials) = gltf_scene(&args.file)?;
            (scene, loaded, HashMap::new(), materials)
        } else if keyrig_io::vrml::is_vrml_path(&args.file) || keyrig_io::bvh::is_bvh_path(&args.file) {
            // The editor's opening of the model (its first view as the camera, or framed), and
            // its meshes through the editor's mesh store.
            let scene = keyrig_editor::files::open_any(&args.file).map_err(anyhow::Error::msg)?;
            let meshes = keyrig_editor::files::render_meshes(&scene, None)
                .map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?;
            (scene, meshes.skinned, meshes.morphs, meshes.materials)
        } else {
            // Model files of the scene (glTF skins, MD2 morphs) resolve against its folder.
            let scene = keyrig_io::scene_file::load(&args.file)?;
            inputs.extend(keyrig_io::project::scene_inputs(&scene, args.file.parent()));
            sound = SceneSound {
                clips: scene.sounds.clone(),
                base_dir: args.file.parent().map(Path::to_path_buf),
            };
            let meshes = keyrig_editor::files::render_meshes(&scene, args.file.parent())
                .map_err(|e| anyhow::anyhow!("{}: {e}", args.file.display()))?;
            (scene, meshes.skinned, meshes.morphs, meshes.materials)
        };
        let rig = SceneRig::with_loaded(&scene, &loaded, &morphs)
            .with_context(|| format!("{}: preparing the scene", args.file.display()))?
            .with_materials(&materials);
        rig.upload(headless.renderer_mut())
            .with_context(|| format!("{}: uploading meshes", args.file.display()))?;
        let selection = match &args.select {
            Some(text) => Some(parse_selection(&scene, text)?),
            None => None,
        };
        let view = ViewOptions {
            style,
            deformer,
            grid: !args.no_grid,
            skeletons: !args.no_skeleton,
            selection,
            textures: !args.no_textures,
            ..playblast::playblast_view(None)
        };
        let through = through_of(&scene, &args)?;
        scene_size = scene.render_size.map(|s| (s.width, s.height));
        Box::new(SceneSource { rig, view, through })
    };
    let (width, height) = explicit_size.or(scene_size).unwrap_or((1280, 720));

    let motion_blur = MotionBlur { samples: args.motion_blur, shutter: args.shutter };
    motion_blur.validate()?;
    let mut frame_input = |frame: f64| -> Result<FrameInput, FrameError> {
        source.frame(frame).map_err(|e| e.context(format!("{}", args.file.display())).into())
    };

    match range {
        None => {
            if let Some(format) = &args.format {
                bail!("--format {format}: give --frames A..B for a movie; one --frame writes one PNG");
            }
            let frame = args.frame.unwrap_or_else(|| source.default_frame());
            source.check(frame, &format!("--frame {frame}"))?;
            keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
            let image = playblast::render_blurred(
                &mut headless,
                &mut frame_input,
                frame,
                &motion_blur.offsets(),
                (width, height),
            )?;
            playblast::write_png(&args.output, &image)?;
            eprintln!("keyrig: wrote {} ({width}×{height}, frame {frame})", args.output.display());
        }
        Some((a, b)) => {
            for end in [a, b] {
                source.check(
                    end as f64,
                    &format!("--frames {}: frame {end}", args.frames.as_deref().unwrap_or("")),
                )?;
            }
            let format = match &args.format {
                Some(name) => MovieFormat::from_cli_name(name)
                    .with_context(|| format!("--format `{name}`: expected mp4, gif, apng or png-frames"))?,
                None => MovieFormat::of_output(&args.output)?,
            };
            let blast = Playblast {
                first: a,
                last: b,
                fps: source.fps(),
                size: (width, height),
                format,
                output: args.output.clone(),
                motion_blur,
                sound,
            };
            blast.validate()?;
            blast.check_outputs(&inputs)?;
            let bar = indicatif::ProgressBar::new(u64::from(blast.frame_count()));
            bar.set_style(
                indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} frames, {eta} left")
                    .map_err(|e| anyhow::anyhow!("progress bar template: {e}"))?
                    .progress_chars("=> "),
            );
            bar.set_message("rendering");
            let summary = blast.run(&mut headless, &mut frame_input, &mut |progress| {
                bar.set_position(u64::from(progress.done));
                std::ops::ControlFlow::Continue(())
            });
            bar.finish_and_clear();
            let summary = summary?;
            let place = match format {
                MovieFormat::PngFrames => playblast::numbered_output(&args.output, a)
                    .parent()
                    .map(|p| p.display().to_string())
                    .unwrap_or_else(|| ".".into()),
                _ => args.output.display().to_string(),
            };
            eprintln!(
                "keyrig: wrote {} frames ({width}×{height}, {} fps, {}) to {place} in {:.1} s (rendering {:.1} s, encoding {:.1} s)",
                summary.frames,
                blast.fps,
                format.cli_name(),
                summary.wall_time.as_secs_f64(),
                summary.render_time.as_secs_f64(),
                summary.encode_time.as_secs_f64(),
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_ranges_parse_or_explain() {
        assert_eq!(parse_size("640x360").unwrap(), (640, 360));
        assert!(parse_size("0x10").unwrap_err().to_string().contains("between 1"));
        assert!(parse_size("big").unwrap_err().to_string().contains("WIDTHxHEIGHT"));
        assert_eq!(parse_range("-2..3").unwrap(), (-2, 3));
        assert!(parse_range("5..1").unwrap_err().to_string().contains("after end"));
    }
}
