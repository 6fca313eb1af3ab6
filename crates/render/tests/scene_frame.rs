//! Scene → frame glue: what `SceneRig::frame` produces, and the errors it
//! reports with their place in the scene.

use glam::{Quat, Vec3};
use keyrig_core::{Animated, DeformerKind, Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene};
use keyrig_eval::Overrides;
use keyrig_render::{Deform, RenderStyle, SceneFrameError, SceneRig, Selected, ViewOptions};

fn arm_scene() -> Scene {
    let mut arm = Object::new("Arm");
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    let mut skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).expect("arm skeleton");
    skeleton.joints[2].rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY),
            Key::new(1.0, Quat::from_rotation_x(1.5)),
            Key::new(2.0, Quat::from_rotation_x(3.0)),
        ]),
    );
    arm.skeleton = Some(skeleton);
    arm.deformer.kind = DeformerKind::DualQuaternion;
    arm.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(2.0, Vec3::new(0.0, 100.0, 0.0))]),
    );
    Scene { objects: vec![arm], ..Scene::default() }
}

#[test]
fn frame_has_the_skinned_arm_its_skeleton_and_the_selected_path() {
    let rig = SceneRig::new(&arm_scene()).expect("rig");
    let view = ViewOptions {
        style: RenderStyle::Wireframe,
        selection: Some(Selected::Joint { object: 0, joint: 3 }),
        ..ViewOptions::default()
    };
    let frame = rig.frame(1.0, &view).expect("frame");
    assert_eq!(frame.style, RenderStyle::Wireframe);
    assert_eq!(frame.items.len(), 1);
    let Deform::Skin { deformer, joints, .. } = &frame.items[0].deform else { panic!("the arm is skinned") };
    assert_eq!(*deformer, DeformerKind::DualQuaternion);
    assert_eq!(joints.len(), 4);
    // Halfway through the translation track.
    let origin = frame.items[0].world_from_model.transform_point3(Vec3::ZERO);
    assert!((origin.y - 50.0).abs() < 1e-3, "{origin}");

    assert_eq!(frame.skeletons.len(), 1);
    assert_eq!(frame.skeletons[0].selected, Some(3));
    assert_eq!(frame.skeletons[0].parents, vec![None, Some(0), Some(1), Some(2)]);

    // Joint 3's path: one point per frame of the default range (0..=60), a marker per key of
    // joint 3's rotation track (none: it is not keyed), and the current position.
    let path = &frame.motion_paths[0];
    assert_eq!(path.points.len(), 61);
    assert!(path.keys.is_empty());
    assert!(path.current.is_some());

    // Overriding the deformer.
    let view = ViewOptions { deformer: Some(DeformerKind::Rigid), ..ViewOptions::default() };
    let frame = rig.frame(1.0, &view).expect("frame");
    assert!(matches!(frame.items[0].deform, Deform::Skin { deformer: DeformerKind::Rigid, .. }));
    assert!(frame.motion_paths.is_empty(), "nothing selected");
}

#[test]
fn object_path_has_a_marker_per_key() {
    let rig = SceneRig::new(&arm_scene()).expect("rig");
    let path =
        rig.motion_path(Some(Selected::Object(0)), 0.5, &Overrides::new()).expect("path").expect("a path");
    assert_eq!(path.keys.len(), 2);
    assert!((path.keys[1] - Vec3::new(0.0, 100.0, 0.0)).length() < 1e-4);
}

#[test]
fn editor_states_replace_the_tracks() {
    let rig = SceneRig::new(&arm_scene()).expect("rig");
    // An override (a value being dragged) moves the drawn object and its motion path alike.
    let overrides: Overrides = [(
        keyrig_core::channel_id::ChannelId::ObjectTranslation(0),
        keyrig_core::channel_id::ChannelValue::Vec3(Vec3::new(7.0, 0.0, 0.0)),
    )]
    .into();
    let state = rig.evaluator().evaluate(0.0, &overrides);
    let frame = rig.frame_from_state(&state, &ViewOptions::default()).expect("frame");
    assert_eq!(frame.items[0].world_from_model.w_axis.x, 7.0);
    let path = rig.motion_path(Some(Selected::Object(0)), 0.0, &overrides).expect("path").expect("a path");
    assert_eq!(path.current, Some(Vec3::new(7.0, 0.0, 0.0)));

    let mut other = state.clone();
    other.objects.clear();
    let err = rig.frame_from_state(&other, &ViewOptions::default()).unwrap_err();
    assert!(err.to_string().contains("0 object states for 1 objects"), "{err}");
}

#[test]
fn bad_tracks_and_missing_meshes_name_their_place() {
    let mut scene = arm_scene();
    if let Some(skeleton) = &mut scene.objects[0].skeleton {
        skeleton.joints[2].rotation.track.keys[1].time = f64::NAN;
    }
    let err = SceneRig::new(&scene).err().expect("NaN key time");
    assert!(
        err.to_string().starts_with("objects[0].skeleton.joints[2].rotation"),
        "the error names the track: {err}"
    );

    let mut scene = arm_scene();
    scene.objects[0].mesh = Some(MeshSource::file("hero.glb", None));
    let err = SceneRig::new(&scene).err().expect("file mesh not passed in");
    assert!(matches!(err, SceneFrameError::MeshNotLoaded { object: 0, .. }), "{err}");
    assert!(err.to_string().contains("hero.glb"));

    let scene = Scene { fps: 0.0, ..arm_scene() };
    assert!(SceneRig::new(&scene).err().expect("fps 0").to_string().starts_with("fps"));
}

#[test]
fn a_procedural_arm_is_fitted_to_a_skeleton_in_metres() {
    let mut scene = arm_scene();
    if let Some(skeleton) = &mut scene.objects[0].skeleton {
        for joint in &mut skeleton.joints {
            joint.rest_translation *= 0.01;
        }
    }
    let rig = SceneRig::new(&scene).expect("rig");
    // The skeleton overlay's last joint sits at 3 bones × 0.400395 m along X at rest.
    let state = rig.evaluator().evaluate(0.0, &Overrides::new());
    let frame = rig.frame_from_state(&state, &ViewOptions::default()).expect("frame");
    assert!((frame.skeletons[0].joints[3].x - 1.201_185).abs() < 1e-4, "{}", frame.skeletons[0].joints[3]);

    // The mesh, skinned on the GPU at rest, spans the arm's 1.60158 m.
    let mut headless = keyrig_render::HeadlessRenderer::new().unwrap_or_else(|e| panic!("{e}"));
    rig.upload(headless.renderer_mut()).expect("upload");
    headless.render_image(&frame, 32, 32).expect("render");
    let vertices = headless.renderer().read_vertices(0).expect("readback");
    let max_x = vertices.iter().map(|v| v.position().x).fold(f32::MIN, f32::max);
    let min_x = vertices.iter().map(|v| v.position().x).fold(f32::MAX, f32::min);
    assert!((max_x - min_x - 1.601_58).abs() < 1e-3, "arm length {}", max_x - min_x);
}

/// A 3-frame morph mesh of one triangle whose first vertex moves along X by 1 per frame,
/// with clips `a` (frames 0..2) and `b` (frame 2).
fn morph_mesh() -> keyrig_render::MorphMesh {
    use keyrig_render::{MorphClip, MorphMesh, SkinnedVertex};
    let frames = (0..3)
        .map(|f| {
            [Vec3::new(f as f32, 0.0, 0.0), Vec3::Y, Vec3::Z]
                .iter()
                .map(|&p| SkinnedVertex::new(p, Vec3::Z))
                .collect::<Vec<_>>()
        })
        .collect();
    let clips =
        vec![MorphClip { name: "a".into(), frames: 0..2 }, MorphClip { name: "b".into(), frames: 2..3 }];
    MorphMesh::new(frames, vec![0, 1, 2], clips).expect("valid morph mesh")
}

#[test]
fn morph_blend_loops_over_the_clip() {
    use keyrig_render::MorphBlend;
    let mesh = morph_mesh();
    // Every frame at 10 fps: 0.3 s is frame 3 ≡ frame 0 (the loop), 0.25 s is halfway 2 → 0.
    //   frame:  0    1    2  | 0
    //   time:   0   0.1  0.2   0.3
    let all = |time: f64| mesh.blend_at(None, 10.0, time).expect("blend");
    assert_eq!(all(0.0), MorphBlend { frame_a: 0, frame_b: 1, t: 0.0 });
    assert_eq!(all(0.15), MorphBlend { frame_a: 1, frame_b: 2, t: 0.5 });
    let wrap = all(0.25);
    assert_eq!((wrap.frame_a, wrap.frame_b), (2, 0));
    assert!((wrap.t - 0.5).abs() < 1e-5);
    assert_eq!(all(0.3).frame_a, 0);
    assert_eq!(all(-0.05).frame_a, 2, "time before 0 wraps too");
    // Clip `a` plays frames 0..2 only; clip `b` is a single frame.
    assert_eq!((mesh.blend_at(Some("a"), 10.0, 0.15).unwrap().frame_b), 0);
    let single = mesh.blend_at(Some("b"), 10.0, 7.3).unwrap();
    assert_eq!((single.frame_a, single.frame_b), (2, 2));
    let (positions, normals) = mesh.blended(mesh.blend_at(None, 10.0, 0.05).unwrap());
    assert!((positions[0].x - 0.5).abs() < 1e-6 && normals[0] == Vec3::Z);
    assert!((mesh.clip_duration(Some("a"), 10.0).unwrap() - 0.2).abs() < 1e-12);
    // Bad requests are errors, not panics.
    assert!(matches!(
        mesh.blend_at(Some("walk"), 10.0, 0.0),
        Err(keyrig_render::MorphError::NoSuchClip { .. })
    ));
    assert!(mesh.blend_at(None, 0.0, 0.0).is_err());
    assert!(mesh.blend_at(None, f64::NAN, 0.0).is_err());
    assert!(mesh.blend_at(None, 10.0, f64::INFINITY).is_err());
}

#[test]
fn morph_objects_draw_their_clip_at_the_time() {
    let mut scene = Scene::default();
    let mut object = Object::new("Model");
    object.mesh =
        Some(MeshSource::File { path: "m.md2".into(), mesh: None, clip: Some("a".into()), fps: Some(10.0) });
    scene.objects.push(object);
    let morphs = std::collections::HashMap::from([(0, morph_mesh())]);
    let rig = SceneRig::with_loaded(&scene, &std::collections::HashMap::new(), &morphs).expect("rig");
    let frame = rig.frame(0.15, &ViewOptions::default()).expect("frame");
    assert_eq!(frame.items.len(), 1);
    let Deform::Morph { frame_a, frame_b, t } = frame.items[0].deform else { panic!("a morph item") };
    assert_eq!((frame_a, frame_b), (1, 0));
    assert!((t - 0.5).abs() < 1e-5);

    // A clip the model does not have, or a bad rate, is an error at the field.
    let MeshSource::File { clip, .. } = scene.objects[0].mesh.as_mut().unwrap() else { panic!() };
    *clip = Some("walk".into());
    let err =
        SceneRig::with_loaded(&scene, &std::collections::HashMap::new(), &morphs).err().expect("no walk");
    assert!(err.to_string().contains("objects[0].mesh.clip") && err.to_string().contains("a, b"), "{err}");
    let MeshSource::File { clip, fps, .. } = scene.objects[0].mesh.as_mut().unwrap() else { panic!() };
    *clip = None;
    *fps = Some(-1.0);
    let err =
        SceneRig::with_loaded(&scene, &std::collections::HashMap::new(), &morphs).err().expect("bad fps");
    assert!(err.to_string().contains("objects[0].mesh.fps"), "{err}");
    // Without the loaded mesh the file is reported as not loaded.
    assert!(matches!(SceneRig::new(&scene), Err(SceneFrameError::MeshNotLoaded { object: 0, .. })));
}

/// Vertex and index buffers go to the GPU once per mesh change: a rig rebuilt around an
/// evaluator updated after a key edit sends none, one after a deformer setting change sends
/// that object's mesh again.
#[test]
fn rebuilt_rigs_upload_only_changed_meshes() {
    let mut scene = arm_scene();
    scene
        .objects
        .push(Object { mesh: Some(MeshSource::Procedural(ProceduralMesh::Cube)), ..Object::new("Cube") });
    let mut headless = keyrig_render::HeadlessRenderer::new().unwrap_or_else(|e| panic!("{e}"));
    let mut eval =
        std::sync::Arc::new(keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new()));
    let morphs = std::collections::HashMap::new();
    let first = SceneRig::with_evaluator(&scene, std::sync::Arc::clone(&eval), &morphs);
    assert_eq!(first.upload_changed(headless.renderer_mut(), None).expect("upload"), 2);

    // A key edit: the evaluator keeps the meshes, nothing is sent.
    scene.objects[0].skeleton.as_mut().unwrap().joints[2].rotation.track.keys[1].value =
        Quat::from_rotation_x(0.5);
    let rebuilt = std::sync::Arc::make_mut(&mut eval).update(&scene, &std::collections::HashMap::new());
    assert_eq!((rebuilt.channels, rebuilt.meshes), (1, 0));
    let second = SceneRig::with_evaluator(&scene, std::sync::Arc::clone(&eval), &morphs);
    assert_eq!(second.upload_changed(headless.renderer_mut(), Some(&first)).expect("upload"), 0);

    // The arm's blend zone: its bindings are rebuilt and its mesh sent again, the cube's not.
    scene.objects[0].deformer.blend_parent_fraction = 0.4;
    std::sync::Arc::make_mut(&mut eval).update(&scene, &std::collections::HashMap::new());
    let third = SceneRig::with_evaluator(&scene, std::sync::Arc::clone(&eval), &morphs);
    assert_eq!(third.upload_changed(headless.renderer_mut(), Some(&second)).expect("upload"), 1);
    // And the frame still draws both.
    let state = third.evaluator().evaluate(0.5, &Overrides::new());
    let frame = third.frame_from_state(&state, &ViewOptions::default()).expect("frame");
    headless.render_image(&frame, 32, 32).expect("render");
    assert_eq!(frame.items.len(), 2);
}

/// Onion skinning: ghosts of the arm at other times are skinned into buffers of their own (each
/// shows its own frame's pose in the same frame as the current one), drawn translucent over
/// the opaque scene with their tint.
#[test]
fn ghosts_show_other_frames_poses_translucent_and_tinted() {
    use keyrig_render::Ghost;
    let scene = arm_scene();
    let rig = SceneRig::new(&scene).expect("rig");
    let view = ViewOptions::default();
    let mut headless = keyrig_render::HeadlessRenderer::new().unwrap_or_else(|e| panic!("{e}"));
    rig.upload(headless.renderer_mut()).expect("upload");
    assert!(rig.upload_ghosts(headless.renderer_mut(), 0, 2).expect("ghosts"), "the arm has a skinned mesh");

    // The pose at 0.5 s and at 1.5 s, rendered as the current frame.
    let pose_at = |headless: &mut keyrig_render::HeadlessRenderer, time: f64| {
        let frame = rig.frame(time, &view).expect("frame");
        headless.render_image(&frame, 64, 64).expect("render");
        headless.renderer().read_vertices(0).expect("readback")
    };
    let at_half = pose_at(&mut headless, 0.5);
    let at_one_and_half = pose_at(&mut headless, 1.5);

    // The frame at 1 s with ghosts at 0.5 s (red) and 1.5 s (green).
    let eval = rig.evaluator();
    let mut frame = rig.frame(1.0, &view).expect("frame");
    let plain = frame.clone();
    for (g, (time, tint)) in [(0.5, Vec3::X), (1.5, Vec3::Y)].into_iter().enumerate() {
        let state = eval.object_at(0, time, &Overrides::new()).expect("state");
        let ghost = Ghost { tint, opacity: 0.4 };
        let items = rig.ghost_items(0, g, &state, &view, ghost).expect("ghost items");
        assert_eq!(items.len(), 1);
        assert_eq!(items[0].mesh, SceneRig::ghost_mesh(0, g));
        frame.items.extend(items);
    }
    let (with_ghosts, stats) = headless.render_image(&frame, 64, 64).expect("render");
    let close = |a: &[keyrig_render::SkinnedVertex], b: &[keyrig_render::SkinnedVertex]| {
        a.iter().zip(b).all(|(u, v)| (u.position() - v.position()).length() < 1e-3)
    };
    let ghost_0 = headless.renderer().read_vertices(SceneRig::ghost_mesh(0, 0)).expect("ghost 0");
    let ghost_1 = headless.renderer().read_vertices(SceneRig::ghost_mesh(0, 1)).expect("ghost 1");
    let current = headless.renderer().read_vertices(0).expect("current");
    assert!(close(&ghost_0, &at_half), "ghost 0 shows the pose at 0.5 s");
    assert!(close(&ghost_1, &at_one_and_half), "ghost 1 shows the pose at 1.5 s");
    assert!(!close(&current, &at_half) && !close(&current, &at_one_and_half), "the arm shows 1 s");

    let (without, plain_stats) = headless.render_image(&plain, 64, 64).expect("render");
    assert_eq!(stats.draw_calls, plain_stats.draw_calls + 2, "one draw per ghost");
    let changed: Vec<(u32, u32)> = (0..64)
        .flat_map(|y| (0..64).map(move |x| (x, y)))
        .filter(|&(x, y)| with_ghosts.get_pixel(x, y) != without.get_pixel(x, y))
        .collect();
    assert!(!changed.is_empty(), "the ghosts are drawn");
    // Translucent: no changed pixel takes the tint outright, and red or green rises where a
    // ghost covers the background.
    let tinted = changed.iter().any(|&(x, y)| {
        let (a, b) = (with_ghosts.get_pixel(x, y).0, without.get_pixel(x, y).0);
        a[0] > b[0] + 10 || a[1] > b[1] + 10
    });
    assert!(tinted, "ghost pixels take their tint");
}

/// Issue 31: a glTF model's morph-target weights are scene channels that the evaluator samples
/// and the GPU draws. AnimatedMorphCube's scene (its weights channel as `morph/0` and `morph/1`)
/// is drawn at several times; the vertices the GPU deforms are the glTF specification's
/// morph of the file's base by the file's weights at that time (`base + Σ wᵢ·Δᵢ`, computed here
/// from keyrig-io's reading of the file, not through the evaluator), normals likewise, and a
/// time whose weights are zero gives the base back.
#[test]
fn gltf_morph_targets_are_drawn_with_the_evaluated_weights() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/corpus/gltf/AnimatedMorphCube/AnimatedMorphCube.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).expect("import");
    let scene = model.to_scene("AnimatedMorphCube.glb", Some(0)).expect("scene");
    assert_eq!(scene.objects[0].attributes.morph_weights.len(), 2, "one channel per target");
    let mesh = model.rigid_mesh(0).expect("mesh");
    assert_eq!(mesh.morph_targets.len(), 2);
    let rig = SceneRig::with_meshes(&scene, &std::collections::HashMap::from([(0, mesh)])).expect("rig");
    let view = ViewOptions::default();
    let mut headless = keyrig_render::HeadlessRenderer::new().unwrap_or_else(|e| panic!("{e}"));
    rig.upload(headless.renderer_mut()).expect("upload");
    let node = model.nodes.iter().position(|n| n.mesh == Some(0)).unwrap();
    let prim = &model.meshes[0].primitives[0];
    let mut morphed_somewhere = false;
    for time in [0.0, 0.5, 1.0, 1.5, 2.2, 0.0] {
        let frame = rig.frame(time, &view).expect("frame");
        headless.render_image(&frame, 32, 32).expect("render");
        let drawn = headless.renderer().read_vertices(0).expect("readback");
        let weights = &model.pose_at(Some(0), time).weights[node];
        let want = keyrig_io::model::ImportedModel::morphed_positions(prim, weights);
        assert_eq!(drawn.len(), want.len());
        for (v, (d, w)) in drawn.iter().zip(&want).enumerate() {
            assert!((d.position() - *w).length() < 1e-5, "t {time} vertex {v}: {} vs {w}", d.position());
        }
        if let Some(normals) = &prim.normals {
            let mut n = normals.to_vec();
            for (target, &w) in prim.morph_targets.iter().zip(weights) {
                if let Some(d) = &target.normals {
                    for (n, d) in n.iter_mut().zip(d.iter()) {
                        *n += w * *d;
                    }
                }
            }
            for (d, n) in drawn.iter().zip(&n) {
                assert!(
                    (d.normal() - n.normalize()).length() < 1e-4,
                    "t {time}: normal {} vs {n}",
                    d.normal()
                );
            }
        }
        morphed_somewhere |=
            drawn.iter().zip(&prim.positions[..]).any(|(d, p)| (d.position() - *p).length() > 1e-3);
    }
    assert!(morphed_somewhere, "the weights move the cube at some time");
}

/// Issue 31: a scene camera's visibility channel hides its frustum while it is 0 (Step keys),
/// and a hidden camera can still be looked through.
#[test]
fn hidden_cameras_draw_no_frustum() {
    use keyrig_core::{Interpolation, SceneCamera};
    let mut scene = arm_scene();
    let step = |t: f64, v: f32| Key::new(t, v).with_interpolation(Interpolation::Step);
    let mut blinking = SceneCamera::new("Blinking", Vec3::new(0.0, 1.0, 5.0));
    blinking.visible =
        Animated::new(1.0, RawTrack::new(vec![step(0.0, 1.0), step(1.0, 0.0), step(1.5, 1.0)]));
    let mut hidden = SceneCamera::new("Hidden", Vec3::new(3.0, 1.0, 5.0));
    hidden.visible = Animated::constant(0.0);
    scene.cameras = vec![blinking, hidden];
    assert_eq!(scene.problems(), Vec::new());
    let rig = SceneRig::new(&scene).expect("rig");
    let view = ViewOptions { cameras: true, ..ViewOptions::default() };
    let shown = |time: f64, view: &ViewOptions| -> Vec<Vec3> {
        let frame = rig.frame(time, view).expect("frame");
        frame.camera_gizmos.iter().map(|g| g.camera.eye()).collect()
    };
    assert_eq!(shown(0.5, &view), vec![Vec3::new(0.0, 1.0, 5.0)], "only the shown camera");
    assert_eq!(shown(1.2, &view), Vec::<Vec3>::new(), "both hidden");
    assert_eq!(shown(1.5, &view), vec![Vec3::new(0.0, 1.0, 5.0)]);
    let state = rig.evaluator().evaluate(1.2, &Overrides::new());
    assert!(!state.cameras[0].visible && !state.cameras[1].visible);
    assert!(state.cameras[1].is_usable(), "a hidden camera can still be looked through");
}
