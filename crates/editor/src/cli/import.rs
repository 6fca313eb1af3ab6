//! `keyrig import MODEL.glb|MODEL.gltf|MODEL.md2 -o SCENE.ron [--animation N] [--scale S]`: a scene file
//! made from a model, as the editor opens it (File ▸ Open): glTF through keyrig-io's mapping
//! (skinned meshes with their skeleton and every channel of animation N, by default the
//! first; other meshes as objects; KHR lights), an MD2 model as one object playing every frame
//! at 10 fps, turned Y-up and scaled to metres; the camera framed on the model and a sun added
//! when the model has no light. The model stays in its file: the scene refers to it by a path
//! relative to the scene's folder when the model lies in that folder or below it, else by its
//! absolute path. `--scale` scales the model about the origin on top of its file's unit
//! (`files::placement::scale_by`); 0, a negative number or NaN is refused. The scene is written atomically and never over the model.

use std::path::PathBuf;

use anyhow::{bail, Context};

#[derive(clap::Args, Debug)]
pub struct ImportArgs {
    /// Model file (.glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv, .iv).
    pub model: PathBuf,
    /// Output scene file (.ron).
    #[arg(short, long)]
    pub output: PathBuf,
    /// glTF: the animation whose channels the scene takes (0 = the first).
    #[arg(long)]
    pub animation: Option<usize>,
    /// Scale the model by this factor on top of its file's unit (glTF, VRML metres; FBX its
    /// own unit converted to metres): 0.01 for a model made in centimetres (the glTF Fox).
    #[arg(long, value_parser = parse_scale, allow_negative_numbers = true)]
    pub scale: Option<f32>,
}

fn parse_scale(text: &str) -> Result<f32, String> {
    keyrig_editor::files::placement::parse_import_scale(text)
}

pub fn run(args: ImportArgs) -> anyhow::Result<()> {
    let ext = args.model.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("glb" | "gltf" | "fbx" | "bvh" | "md2"))
        && !keyrig_io::vrml::is_vrml_path(&args.model)
    {
        bail!(
            "{}: the model must be a .glb, .gltf, .fbx, .bvh, .md2, .wrl, .wrz, .x3d, .x3dv or .iv file",
            args.model.display()
        );
    }
    if !keyrig_editor::files::is_scene_file(&args.output) {
        bail!("{}: the output must end in .ron", args.output.display());
    }
    keyrig_io::file_io::refuse_overwriting(
        &args.output,
        &[(args.model.clone(), "the input model".to_owned())],
    )?;
    let mut scene = keyrig_editor::files::open_any(&args.model).map_err(anyhow::Error::msg)?;
    let absolute = std::fs::canonicalize(&args.model)
        .with_context(|| format!("{}: cannot resolve the path", args.model.display()))?;
    if let Some(animation) = args.animation {
        if ext.as_deref() == Some("md2") {
            bail!("--animation is for glTF models; an MD2 model plays all its frames");
        }
        if keyrig_io::vrml::is_vrml_path(&args.model) {
            bail!("--animation is for glTF models; a VRML/X3D/Inventor file plays all its TimeSensors");
        }
        if keyrig_io::bvh::is_bvh_path(&args.model) {
            bail!("--animation is for glTF and FBX models; a BVH take is one animation");
        }
        let model = keyrig_io::fbx::import_model_file(&args.model)?;
        if animation >= model.animations.len() {
            bail!(
                "{}: --animation {animation}: the model has {} animation(s)",
                args.model.display(),
                model.animations.len()
            );
        }
        let mapped = model
            .to_scene(&absolute.to_string_lossy(), Some(animation))
            .with_context(|| format!("{}: mapping to a scene", args.model.display()))?;
        scene.objects = mapped.objects;
        scene.frame_range = mapped.frame_range;
    }
    // The import scale, as File ▸ Import scale applies it: objects, lights, cameras and the
    // framed view, about the origin.
    if let Some(scale) = args.scale {
        keyrig_editor::files::placement::scale_by(&mut scene, scale);
    }
    // Model paths relative to the scene's folder where the model lies below it, as the
    // editor saves them.
    keyrig_io::project::save_scene(&args.output, &scene)?;
    eprintln!(
        "keyrig: wrote {} ({} objects, {} lights, frames {}..={})",
        args.output.display(),
        scene.objects.len(),
        scene.lights.len(),
        scene.frame_range.start,
        scene.frame_range.end
    );
    Ok(())
}
