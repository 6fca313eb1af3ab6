//! A keyed bones-blending zone on the GPU: the arm's zone widens from 0.1 to 0.9 of each bone
//! over a second while its forearm is turned 180°; every frame the GPU skins with the bindings
//! of the zone at that time (written over the uploaded ones), matching keyrig-skin's reference
//! deformer bound for that zone, and a frame without a keyed zone puts the uploaded bindings
//! back.

use glam::Quat;
use keyrig_core::{
    Animated, DeformerKind, Interpolation, Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene,
};
use keyrig_eval::Overrides;
use keyrig_render::headless::HeadlessRenderer;
use keyrig_render::{SceneRig, SkinnedVertex, ViewOptions};
use keyrig_skin::{deform_mesh_into, BlendZone, Deformed, Execution};

fn arm(keyed_zone: bool) -> Scene {
    let mut arm = Object::new("Arm");
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    let mut skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).expect("arm skeleton");
    skeleton.joints[2].rotation = Animated::constant(Quat::from_rotation_x(std::f32::consts::PI));
    arm.skeleton = Some(skeleton);
    arm.deformer.kind = DeformerKind::BonesBlending;
    if keyed_zone {
        let widen = Animated::new(
            0.1,
            RawTrack::new(vec![
                Key::new(0.0, 0.1).with_interpolation(Interpolation::Linear),
                Key::new(1.0, 0.9).with_interpolation(Interpolation::Linear),
            ]),
        );
        arm.attributes.blend_parent_fraction = Some(widen.clone());
        arm.attributes.blend_child_fraction = Some(widen);
    }
    Scene { objects: vec![arm], ..Scene::default() }
}

/// The GPU's skinned positions of the arm at `time`.
fn gpu_positions(r: &mut HeadlessRenderer, rig: &SceneRig, time: f64) -> Vec<glam::Vec3> {
    let frame = rig.frame(time, &ViewOptions::default()).expect("frame");
    r.render_image(&frame, 64, 64).expect("render");
    r.renderer().read_vertices(0).expect("readback").iter().map(SkinnedVertex::position).collect()
}

/// keyrig-skin's reference bones blending of the arm at `time`, bound for `zone`.
fn cpu_positions(scene: &Scene, time: f64, zone: BlendZone) -> Vec<glam::Vec3> {
    let eval = keyrig_eval::SceneEvaluator::new(scene, &Default::default());
    let skin = eval.skin(0).expect("skinned");
    let state = eval.object_at(0, time, &Overrides::new()).expect("state");
    let bindings = skin.mesh.bindings(zone).expect("bindings");
    let mut out = Deformed::default();
    deform_mesh_into(
        &skin.mesh,
        &bindings,
        state.palette.as_ref().expect("palette"),
        DeformerKind::BonesBlending,
        Execution::Reference,
        &mut out,
    )
    .expect("deform");
    out.positions
}

fn worst(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max)
}

#[test]
fn the_gpu_skins_with_the_zone_of_each_frame() {
    let mut r = HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"));
    let scene = arm(true);
    let rig = SceneRig::new(&scene).expect("rig");
    rig.upload(r.renderer_mut()).expect("upload");
    // The arm is 160 cm long; gpu_skinning.rs allows the GPU 1e-4 of a model's size.
    let tolerance = 1e-4 * 160.0;
    let zone = |f: f32| BlendZone { parent_fraction: f, child_fraction: f };
    let mut seen = Vec::new();
    for (time, fraction) in [(0.0, 0.1), (1.0, 0.9), (0.5, 0.5), (0.0, 0.1)] {
        let gpu = gpu_positions(&mut r, &rig, time);
        let cpu = cpu_positions(&scene, time, zone(fraction));
        let off = worst(&gpu, &cpu);
        assert!(off <= tolerance, "t = {time}: the GPU is {off} cm off the zone-{fraction} reference");
        seen.push(gpu);
    }
    assert!(worst(&seen[0], &seen[1]) > 1.0, "a wider zone deforms the twisted arm otherwise");
    assert!(worst(&seen[0], &seen[3]) <= tolerance, "back at the first zone");

    // The same mesh id drawn from a scene whose zone is not keyed: the uploaded bindings (the
    // default zone) come back.
    let plain = arm(false);
    let rig = SceneRig::new(&plain).expect("rig");
    let gpu = gpu_positions(&mut r, &rig, 0.0);
    let off = worst(&gpu, &cpu_positions(&plain, 0.0, BlendZone::default()));
    assert!(off <= tolerance, "the uploaded bindings are back: {off} cm off");
}
