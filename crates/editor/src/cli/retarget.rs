//! `keyrig retarget SOURCE TARGET -o OUT.ron [--map FILE] [--write-map FILE] [--action NAME]
//! [--source-action NAME] [--source-object NAME] [--object NAME] [--fps F] [--no-contacts]
//! [--reduce]`: the action the source's skeleton plays put onto the target's skeleton(s) as a
//! new action (docs/retargeting.md), and the target scene written as a scene file.
//!
//! SOURCE and TARGET are scenes or anything the other commands read as one (a BVH take, a glTF
//! or FBX model). The bone map is made from the joints' names unless `--map` gives one (RON or
//! JSON, `(pairs: [(source: "Hips", target: "mixamorig:Hips"), …])`); `--write-map` writes the
//! map used, to edit and give back. Every target object with a skeleton the map drives plays
//! the new action (a character skinned in several objects moves as one), or only `--object`.
//! The scene is written atomically and never over an input.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use keyrig_core::Scene;
use keyrig_edit::cleanup::ReduceTolerance;
use keyrig_edit::retarget::{retarget, BoneMap, RetargetOptions};

#[derive(clap::Args, Debug)]
pub struct RetargetArgs {
    /// The motion: a scene file (.ron) or model (.bvh, .glb, .gltf, .fbx, …).
    pub source: PathBuf,
    /// The rig that takes it: a scene file (.ron) or model (.glb, .gltf, .fbx, .bvh, …).
    pub target: PathBuf,
    /// Output scene file (.ron): the target scene with the new action.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Bone map file (.ron or .json) instead of the automatic map from joint names.
    #[arg(long)]
    pub map: Option<PathBuf>,
    /// Write the bone map used (.ron or .json), to edit and pass back with --map.
    #[arg(long)]
    pub write_map: Option<PathBuf>,
    /// Name of the new action (default: the source file's name; made unique).
    #[arg(long)]
    pub action: Option<String>,
    /// The source's action to retarget (default: what the source plays).
    #[arg(long)]
    pub source_action: Option<String>,
    /// The source object (default: the first object with a skeleton and keys).
    #[arg(long)]
    pub source_object: Option<String>,
    /// Only this target object (default: every object with a skeleton the map drives).
    #[arg(long)]
    pub object: Option<String>,
    /// Keys per second (default: the source's frame rate).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Copy the legs' rotations only: do not hold the feet the source plants.
    #[arg(long)]
    pub no_contacts: bool,
    /// Reduce the new keys within 0.1° and 0.0005 scene units (0.5 mm in metres), which
    /// keeps planted feet within 1 % of the leg (docs/retargeting.md).
    #[arg(long)]
    pub reduce: bool,
}

fn load(path: &Path) -> anyhow::Result<Scene> {
    if keyrig_editor::files::is_scene_file(path) {
        keyrig_io::project::load_scene(path).with_context(|| format!("{}", path.display()))
    } else {
        keyrig_editor::files::import_model(path).map_err(anyhow::Error::msg)
    }
}

fn is_json(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"))
}

fn read_map(path: &Path) -> anyhow::Result<BoneMap> {
    let bytes = keyrig_io::file_io::read_regular_file(path, 16 << 20)
        .with_context(|| format!("{}: cannot read the bone map", path.display()))?;
    let text = String::from_utf8(bytes).with_context(|| format!("{}: not UTF-8", path.display()))?;
    if is_json(path) {
        serde_json::from_str(&text).with_context(|| format!("{}: not a bone map", path.display()))
    } else {
        ron::from_str(&text).with_context(|| format!("{}: not a bone map", path.display()))
    }
}

fn write_map(path: &Path, map: &BoneMap) -> anyhow::Result<()> {
    let text = if is_json(path) {
        serde_json::to_string_pretty(map)?
    } else {
        ron::ser::to_string_pretty(map, ron::ser::PrettyConfig::default())?
    };
    keyrig_io::file_io::write_atomic(path, text.as_bytes())
        .with_context(|| format!("{}: cannot write", path.display()))
}

pub fn run(args: RetargetArgs) -> anyhow::Result<()> {
    if !keyrig_editor::files::is_scene_file(&args.output) {
        bail!(
            "{}: the output must end in .ron (`keyrig export` writes other formats)",
            args.output.display()
        );
    }
    let source =
        super::common::with_action(load(&args.source)?, args.source_action.as_deref(), &args.source)?;
    let mut target = load(&args.target)?;
    let mut inputs = vec![
        (args.source.clone(), "the source file".to_owned()),
        (args.target.clone(), "the target file".to_owned()),
    ];
    inputs.extend(keyrig_io::project::scene_inputs(&source, None));
    inputs.extend(keyrig_io::project::scene_inputs(&target, None));
    if let Some(map) = &args.map {
        inputs.push((map.clone(), "the bone map".to_owned()));
    }
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;

    let source_object = match &args.source_object {
        Some(name) => source.objects.iter().position(|o| &o.name == name).with_context(|| {
            format!("{}: --source-object: no object is named {name:?}", args.source.display())
        })?,
        None => source
            .objects
            .iter()
            .position(|o| {
                o.skeleton.as_ref().is_some_and(|s| {
                    s.root_translation.is_animated()
                        || s.joints.iter().any(|j| {
                            j.rotation.is_animated()
                                || j.rotation_euler.as_ref().is_some_and(|e| e.is_animated())
                        })
                })
            })
            .with_context(|| format!("{}: no object has a skeleton with keys", args.source.display()))?,
    };
    let source_skeleton = source.objects[source_object]
        .skeleton
        .as_ref()
        .with_context(|| format!("{}: --source-object has no skeleton", args.source.display()))?;
    let given = args.map.as_deref().map(read_map).transpose()?;

    let objects: Vec<usize> =
        match &args.object {
            Some(name) => vec![target.objects.iter().position(|o| &o.name == name).with_context(|| {
                format!("{}: --object: no object is named {name:?}", args.target.display())
            })?],
            None => (0..target.objects.len()).filter(|&o| target.objects[o].skeleton.is_some()).collect(),
        };
    let base = args.action.clone().unwrap_or_else(|| {
        args.source
            .file_stem()
            .map_or_else(|| "Retargeted".to_owned(), |s| s.to_string_lossy().replace('/', "_"))
    });
    let action = if args.action.is_some() { base } else { target.unused_action_name(&base) };
    let mut options = RetargetOptions::new(action.clone());
    options.fps = args.fps;
    if args.no_contacts {
        options.contacts = None;
    }
    if args.reduce {
        options.reduce =
            Some(ReduceTolerance { angle_deg: 0.1, distance: 0.0005, ..ReduceTolerance::DEFAULT });
    }
    let mut said = Vec::new();
    let mut written_map = None;
    for o in objects {
        let Some(skeleton) = target.objects[o].skeleton.as_ref() else {
            bail!("{}: object {:?} has no skeleton", args.target.display(), target.objects[o].name);
        };
        let map = given.clone().unwrap_or_else(|| BoneMap::automatic(source_skeleton, skeleton));
        // Without --object, an object whose skeleton the map does not drive is left alone.
        if args.object.is_none() && (map.pairs.is_empty() || map.resolve(source_skeleton, skeleton).is_err())
        {
            continue;
        }
        let name = target.objects[o].name.clone();
        let report = retarget(&source, source_object, &mut target, o, &map, &options)
            .with_context(|| format!("retargeting onto {name:?}"))?;
        said.push(format!(
            "{name}: {} joints driven, {} keys each at {} fps, leg ratio {:.4}, {} foot contacts{}{}",
            report.pairs.len(),
            report.frames,
            report.fps,
            report.leg_ratio,
            report.contacts.len(),
            if report.not_held.is_empty() {
                String::new()
            } else {
                format!(" ({:?} not held)", report.not_held)
            },
            report.reduced.map_or_else(String::new, |r| format!(", reduced to {} keys", r.keys_after)),
        ));
        written_map.get_or_insert(map);
    }
    let Some(map) = written_map else {
        bail!(
            "{}: no target object with a skeleton the bone map drives (joint names matched: none; give --map)",
            args.target.display()
        );
    };
    if let Some(path) = &args.write_map {
        write_map(path, &map)?;
    }
    keyrig_io::project::save_scene(&args.output, &target)?;
    eprintln!("keyrig: wrote {} (action {action:?}; {})", args.output.display(), said.join("; "));
    Ok(())
}
