//! The renderer with hand-built frames: lights behave as documented (spot cone, point fall-off,
//! directional), styles draw, and bad input gets a typed error instead of a panic.

use glam::{Mat4, Quat, Vec3};
use keyrig_core::{Camera, DeformerKind, LightKind};
use keyrig_render::{
    Deform, DrawItem, FrameInput, HeadlessRenderer, JointPose, LightInput, MeshData, RenderError,
    RenderStyle, SkinnedVertex,
};

const SIZE: u32 = 64;

fn headless() -> HeadlessRenderer {
    HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"))
}

/// A 2×2 quad on y = 0 facing up (two triangles), subdivided so lighting is per pixel anyway.
fn floor() -> (Vec<SkinnedVertex>, Vec<u32>) {
    let corners = [
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, 1.0),
    ];
    let vertices = corners.iter().map(|&p| SkinnedVertex::new(p, Vec3::Y)).collect();
    (vertices, vec![0, 2, 1, 0, 3, 2])
}

/// Looking straight down at the floor, which fills the image.
fn top_camera() -> Camera {
    Camera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 90.0, distance: 1.0, fov_y_deg: 80.0 }
}

fn floor_frame(lights: Vec<LightInput>) -> FrameInput {
    let mut frame = FrameInput::new(top_camera());
    frame.grid_spacing = None;
    frame.ambient = Vec3::ZERO;
    frame.background = Vec3::ZERO;
    frame.lights = lights;
    frame.items.push(DrawItem {
        mesh: 1,
        world_from_model: Mat4::IDENTITY,
        deform: Deform::None,
        colour: Vec3::ONE,
        opacity: 1.0,
        selected: false,
        ghost: None,
    });
    frame
}

fn red(image: &keyrig_render::image::RgbaImage, x: u32, y: u32) -> u8 {
    image.get_pixel(x, y).0[0]
}

fn light(kind: LightKind, position: Vec3, direction: Vec3, intensity: f32) -> LightInput {
    LightInput { kind, position, direction, colour: Vec3::ONE, intensity, range: None }
}

#[test]
fn spot_light_lights_its_cone_only() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let spot = light(
        LightKind::Spot { cutoff_deg: 20.0, inner_angle_deg: 10.0, dropoff: 1.0 },
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::NEG_Y,
        0.2,
    );
    let (image, _) = r.render_image(&floor_frame(vec![spot]), SIZE, SIZE).expect("render");
    let centre = red(&image, SIZE / 2, SIZE / 2);
    let corner = red(&image, 3, 3);
    assert!(centre > 150, "inside the inner cone: {centre}");
    assert_eq!(corner, 0, "outside the cut-off the spot adds nothing");

    // The same light as a point light reaches the corner, dimmer than the centre (1/d² and
    // the angle of incidence).
    let point = light(LightKind::Point, Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Y, 0.2);
    let (image, _) = r.render_image(&floor_frame(vec![point]), SIZE, SIZE).expect("render");
    let (centre, corner) = (red(&image, SIZE / 2, SIZE / 2), red(&image, 3, 3));
    assert!(corner > 0 && corner < centre / 2, "point light: centre {centre}, corner {corner}");
}

#[test]
fn directional_light_is_even_and_one_sided() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::new(0.0, -1.0, 0.0), 0.5);
    let (image, _) = r.render_image(&floor_frame(vec![sun]), SIZE, SIZE).expect("render");
    let (centre, corner) = (red(&image, SIZE / 2, SIZE / 2), red(&image, 3, 3));
    // Diffuse 0.5 everywhere (specular varies a little with the view direction).
    assert!(centre.abs_diff(corner) < 40, "centre {centre}, corner {corner}");
    assert!(corner > 150, "0.5 linear is about 188 in sRGB: {corner}");

    // Light from below: the floor's lit side faces away; the view sees its unlit top.
    let below = light(LightKind::Directional, Vec3::ZERO, Vec3::Y, 0.5);
    let (image, _) = r.render_image(&floor_frame(vec![below]), SIZE, SIZE).expect("render");
    assert_eq!(red(&image, SIZE / 2, SIZE / 2), 0);
}

#[test]
fn styles_draw_different_pixels() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::NEG_Y, 1.0);
    let mut lit = |style| {
        let mut frame = floor_frame(vec![sun]);
        // Far enough that the whole floor, corners included, is in view.
        frame.camera.distance = 3.0;
        frame.style = style;
        let (image, stats) = r.render_image(&frame, SIZE, SIZE).expect("render");
        // Solid draws an opaque mesh's front faces, then (after every opaque item's front faces)
        // its back faces.
        let draws = if style == RenderStyle::Solid { 2 } else { 1 };
        assert_eq!(stats.draw_calls, draws, "{style:?}");
        image.pixels().filter(|p| p.0[0] > 0).count()
    };
    let solid = lit(RenderStyle::Solid);
    let wireframe = lit(RenderStyle::Wireframe);
    let points = lit(RenderStyle::Points);
    assert!(solid > (SIZE * SIZE) as usize / 8, "the floor covers a good part of the image: {solid}");
    assert!(wireframe > 0 && wireframe < solid / 2, "wireframe covers only edges: {wireframe} of {solid}");
    assert!(points > 0 && points < wireframe, "points cover only vertices: {points}");
}

#[test]
fn bad_input_is_a_typed_error() {
    let mut r = headless();
    let (vertices, indices) = floor();

    let err = r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &[0, 1, 9] }).unwrap_err();
    assert!(matches!(err, RenderError::IndexOutOfRange { position: 2, index: 9, vertex_count: 4 }), "{err}");

    let mut nan = vertices.clone();
    nan[2] = SkinnedVertex::new(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y);
    let err = r.upload_mesh(1, &MeshData::Static { vertices: &nan, indices: &indices }).unwrap_err();
    assert!(matches!(err, RenderError::NonFinite { index: 2, .. }), "{err}");

    // A frame that names a mesh never uploaded.
    let err = r.render_image(&floor_frame(vec![]), SIZE, SIZE).unwrap_err();
    assert!(matches!(err, RenderError::UnknownMesh(1)), "{err}");

    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let err = r.render_image(&floor_frame(vec![]), 0, 10).unwrap_err();
    assert!(matches!(err, RenderError::InvalidSize { width: 0, .. }), "{err}");

    // Skinning a static mesh, and a skin with the wrong number of joints.
    let mut frame = floor_frame(vec![]);
    let pose = JointPose::from_rigid(Mat4::IDENTITY, Mat4::IDENTITY, Quat::IDENTITY);
    frame.items[0].deform =
        Deform::Skin { deformer: DeformerKind::LinearBlend, joints: vec![pose], bindings: None, morph: None };
    let err = r.render_image(&frame, SIZE, SIZE).unwrap_err();
    assert!(err.to_string().contains("not a skinned mesh"), "{err}");

    let positions: Vec<Vec3> = vertices.iter().map(SkinnedVertex::position).collect();
    let normals = vec![Vec3::Y; 4];
    let joints = vec![[0u32, 0, 0, 0]; 4];
    let weights = vec![[1.0f32, 0.0, 0.0, 0.0]; 4];
    let rigid = vec![0u32; 4];
    let blend = vec![keyrig_render::BlendBinding { joint: 0, t: 0.0 }; 4];
    let binds = vec![Mat4::IDENTITY; 2];
    let skin = keyrig_render::SkinMeshInput {
        positions: &positions,
        normals: &normals,
        joints: &joints,
        weights: &weights,
        rigid_joints: &rigid,
        blend: &blend,
        bind_from_model: &binds,
    };
    r.upload_mesh(1, &MeshData::Skinned { skin, indices: &indices }).expect("upload skin");
    let err = r.render_image(&frame, SIZE, SIZE).unwrap_err();
    assert!(matches!(err, RenderError::JointCountMismatch { mesh: 1, expected: 2, actual: 1 }), "{err}");

    // A camera with a NaN.
    let mut frame = floor_frame(vec![]);
    frame.camera.yaw_deg = f32::NAN;
    assert!(matches!(r.render_image(&frame, SIZE, SIZE), Err(RenderError::NonFinite { .. })));
}

/// Uploads the floor as mesh 1, skinned to one joint with full weight (bones-blending
/// parameter `t`); returns its rest positions.
fn upload_floor_skin(r: &mut HeadlessRenderer, t: f32) -> Vec<Vec3> {
    let (vertices, indices) = floor();
    let positions: Vec<Vec3> = vertices.iter().map(SkinnedVertex::position).collect();
    let normals = vec![Vec3::Y; 4];
    let joints = vec![[0u32, 0, 0, 0]; 4];
    let weights = vec![[1.0f32, 0.0, 0.0, 0.0]; 4];
    let rigid = vec![0u32; 4];
    let blend = vec![keyrig_render::BlendBinding { joint: 0, t }; 4];
    let binds = vec![Mat4::IDENTITY];
    let skin = keyrig_render::SkinMeshInput {
        positions: &positions,
        normals: &normals,
        joints: &joints,
        weights: &weights,
        rigid_joints: &rigid,
        blend: &blend,
        bind_from_model: &binds,
    };
    r.upload_mesh(1, &MeshData::Skinned { skin, indices: &indices }).expect("upload");
    positions
}

#[test]
fn skinned_item_moves_with_its_joints() {
    let mut r = headless();
    let positions = upload_floor_skin(&mut r, 1.0);
    let shift = Vec3::new(0.25, 0.0, 0.0);
    for deformer in DeformerKind::ALL {
        let mut frame = floor_frame(vec![]);
        let pose = JointPose::from_rigid(
            Mat4::from_translation(shift),
            Mat4::from_translation(shift),
            Quat::IDENTITY,
        );
        frame.items[0].deform = Deform::Skin { deformer, joints: vec![pose], bindings: None, morph: None };
        let (_, stats) = r.render_image(&frame, SIZE, SIZE).expect("render");
        assert_eq!(stats.joint_bytes, 240);
        let out = r.renderer().read_vertices(1).expect("readback");
        for (v, p) in out.iter().zip(&positions) {
            assert!(
                (v.position() - (*p + shift)).length() < 1e-6,
                "{deformer:?}: {} vs {}",
                v.position(),
                *p + shift
            );
        }
    }
}

#[test]
fn an_uploaded_skin_draws_its_rest_pose_before_any_deformation() {
    let mut r = headless();
    let positions = upload_floor_skin(&mut r, 0.0);
    let out = r.renderer().read_vertices(1).expect("readback");
    assert_eq!(out.iter().map(SkinnedVertex::position).collect::<Vec<_>>(), positions);

    let (vertices, indices) = floor();
    let frames = vec![
        vertices.clone(),
        vertices.iter().map(|v| SkinnedVertex::new(v.position() * 2.0, Vec3::Y)).collect(),
    ];
    r.upload_mesh(2, &MeshData::Morph { frames: &frames, indices: &indices }).expect("upload morph");
    let out = r.renderer().read_vertices(2).expect("readback");
    assert_eq!(out, vertices, "a morphing mesh starts at its first frame");
}

/// A 2×2 checker texture: red, green / blue, yellow (sRGB-encoded bytes).
fn checker(sampler: keyrig_core::Sampler) -> keyrig_core::TextureImage {
    #[rustfmt::skip]
    let rgba = vec![
        255, 0, 0, 255,    0, 255, 0, 255,
        0, 0, 255, 255,    255, 255, 0, 255,
    ];
    keyrig_core::TextureImage::new(2, 2, rgba, sampler).expect("2×2 texture")
}

/// The floor with texture coordinates (0, 0) at corner (−1, −1) to (`extent`, `extent`) at
/// (1, 1), lit by ambient light only so that the image shows the albedo.
fn textured_floor(
    r: &mut HeadlessRenderer,
    extent: f32,
    texture: Option<&keyrig_core::TextureImage>,
) -> FrameInput {
    let (vertices, indices) = floor();
    let uvs = [
        glam::Vec2::new(0.0, 0.0),
        glam::Vec2::new(extent, 0.0),
        glam::Vec2::new(extent, extent),
        glam::Vec2::new(0.0, extent),
    ];
    let renderer = r.renderer_mut();
    renderer
        .upload_mesh_with_uvs(1, &MeshData::Static { vertices: &vertices, indices: &indices }, Some(&uvs))
        .expect("upload");
    renderer.set_texture(1, texture).expect("texture");
    let mut frame = floor_frame(Vec::new());
    frame.ambient = Vec3::ONE;
    frame
}

/// The image's distinct colours, each quantized to 32 levels per channel.
fn colours(image: &keyrig_render::image::RgbaImage) -> std::collections::HashSet<[u8; 3]> {
    image.pixels().map(|p| [p.0[0] / 8, p.0[1] / 8, p.0[2] / 8]).collect()
}

#[test]
fn a_textured_quad_shows_the_texture_colours_and_the_toggle_turns_them_off() {
    let nearest = keyrig_core::Sampler {
        mag_filter: keyrig_core::FilterMode::Nearest,
        min_filter: keyrig_core::FilterMode::Nearest,
        mipmap_filter: None,
        ..keyrig_core::Sampler::default()
    };
    let texture = checker(nearest);
    let mut r = headless();
    let frame = textured_floor(&mut r, 1.0, Some(&texture));
    assert!(r.renderer().has_texture(1));
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    // Seen from above with yaw 0, world −Z is up in the image and +X to the right: texture
    // coordinate (0, 0) at world (−1, −1) is the top-left of the image.
    let at = |x: u32, y: u32| {
        let p = image.get_pixel(x, y).0;
        [p[0], p[1], p[2]]
    };
    let q = SIZE / 4;
    assert_eq!(at(q, q), [255, 0, 0], "top left: red");
    assert_eq!(at(3 * q, q), [0, 255, 0], "top right: green");
    assert_eq!(at(q, 3 * q), [0, 0, 255], "bottom left: blue");
    assert_eq!(at(3 * q, 3 * q), [255, 255, 0], "bottom right: yellow");

    // The draw item's colour multiplies the texture (glTF base colour factor × texture).
    let mut tinted = frame.clone();
    tinted.items[0].colour = Vec3::new(1.0, 0.0, 1.0);
    let (image, _) = r.render_image(&tinted, SIZE, SIZE).expect("render");
    assert_eq!(image.get_pixel(3 * q, 3 * q).0[..3], [255, 0, 0], "yellow × magenta = red");

    // Textures off: the plain white colour everywhere.
    let mut plain = frame.clone();
    plain.textures = false;
    let (image, _) = r.render_image(&plain, SIZE, SIZE).expect("render");
    assert_eq!(colours(&image), [[31, 31, 31]].into_iter().collect(), "one flat white");

    // Taking the texture away does the same.
    r.renderer_mut().set_texture(1, None).expect("no texture");
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    assert_eq!(colours(&image).len(), 1);
}

#[test]
fn the_sampler_wrap_mode_and_filters_are_used() {
    let nearest = keyrig_core::Sampler {
        mag_filter: keyrig_core::FilterMode::Nearest,
        min_filter: keyrig_core::FilterMode::Nearest,
        mipmap_filter: None,
        ..keyrig_core::Sampler::default()
    };
    let mut r = headless();
    let q = SIZE / 8;
    // Coordinates 0..2 across the floor: repeat shows the checker twice per side.
    let repeat = checker(nearest);
    let frame = textured_floor(&mut r, 2.0, Some(&repeat));
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    assert_eq!(image.get_pixel(q, q).0[..3], [255, 0, 0], "u, v ≈ 0.25: red");
    assert_eq!(image.get_pixel(5 * q, q).0[..3], [255, 0, 0], "u ≈ 1.25 wraps to 0.25: red");
    assert_eq!(image.get_pixel(7 * q, q).0[..3], [0, 255, 0], "u ≈ 1.75 wraps to 0.75: green");

    // Clamp to edge: past 1 the last column (green at the top) repeats.
    let clamp = checker(keyrig_core::Sampler {
        wrap_u: keyrig_core::WrapMode::ClampToEdge,
        wrap_v: keyrig_core::WrapMode::ClampToEdge,
        ..nearest
    });
    let frame = textured_floor(&mut r, 2.0, Some(&clamp));
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    assert_eq!(image.get_pixel(5 * q, q).0[..3], [0, 255, 0], "u ≈ 1.25 clamps to the green edge");
    assert_eq!(image.get_pixel(7 * q, 7 * q).0[..3], [255, 255, 0], "both clamp: yellow");

    // Mirrored repeat: u ≈ 1.25 mirrors to 0.75 (green).
    let mirror = checker(keyrig_core::Sampler {
        wrap_u: keyrig_core::WrapMode::MirroredRepeat,
        wrap_v: keyrig_core::WrapMode::MirroredRepeat,
        ..nearest
    });
    let frame = textured_floor(&mut r, 2.0, Some(&mirror));
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    assert_eq!(image.get_pixel(5 * q, q).0[..3], [0, 255, 0], "u ≈ 1.25 mirrors to 0.75: green");

    // Linear magnification blends neighbouring texels: the centre of a nearest-filtered
    // checker is one of its colours, a linear one mixes all four.
    let linear = checker(keyrig_core::Sampler::default());
    let frame = textured_floor(&mut r, 1.0, Some(&linear));
    let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
    let centre = image.get_pixel(SIZE / 2, SIZE / 2).0;
    assert!(centre[..3].iter().all(|&c| c > 60 && c < 230), "linear blend at the centre: {centre:?}");
    assert!(colours(&image).len() > 20, "a smooth gradient");
}

#[test]
fn texture_coordinates_of_the_wrong_length_are_a_typed_error() {
    let mut r = headless();
    let (vertices, indices) = floor();
    let err = r
        .renderer_mut()
        .upload_mesh_with_uvs(
            1,
            &MeshData::Static { vertices: &vertices, indices: &indices },
            Some(&[glam::Vec2::ZERO]),
        )
        .expect_err("one uv for four vertices");
    assert!(matches!(err, RenderError::LengthMismatch { expected: 4, actual: 1, .. }), "{err}");
    assert!(matches!(r.renderer_mut().set_texture(9, None), Err(RenderError::UnknownMesh(9))));
}

/// A selected object is tinted, not painted over: where it faces the eye its shading stays
/// (within a small tint), so a selected model's pose and texture can still be seen.
#[test]
fn selection_tints_without_hiding_the_shading() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::NEG_Y, 0.5);
    let render = |r: &mut HeadlessRenderer, selected: bool| {
        let mut frame = floor_frame(vec![sun]);
        frame.items[0].selected = selected;
        let (image, _) = r.render_image(&frame, SIZE, SIZE).expect("render");
        image.get_pixel(SIZE / 2, SIZE / 2).0
    };
    let plain = render(&mut r, false);
    let selected = render(&mut r, true);
    assert!(selected[0] >= plain[0], "tinted towards orange: {plain:?} → {selected:?}");
    assert!(selected[2] < plain[2], "tinted: {plain:?} → {selected:?}");
    assert!(
        plain[2] - selected[2] <= 15,
        "the shading shows through the tint where the surface faces the eye: {plain:?} → {selected:?}"
    );
}

/// sRGB encoding of a linear value in 0..=1, as the sRGB render target stores it.
fn srgb(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

#[test]
fn opacity_blends_the_object_over_the_background() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let sun = light(LightKind::Directional, Vec3::ZERO, Vec3::NEG_Y, 0.5);
    let centre_at = |r: &mut HeadlessRenderer, opacity: f32, background: Vec3| {
        let mut frame = floor_frame(vec![sun]);
        frame.background = background;
        frame.items[0].opacity = opacity;
        let (image, stats) = r.render_image(&frame, SIZE, SIZE).expect("render");
        (red(&image, SIZE / 2, SIZE / 2), stats.draw_calls)
    };
    let (opaque, _) = centre_at(&mut r, 1.0, Vec3::ZERO);
    let (half, calls) = centre_at(&mut r, 0.5, Vec3::ZERO);
    assert_eq!(calls, 1);
    // Blending happens on linear values (the target is sRGB): over black, half of the lit
    // floor's linear value, then encoded. The lit value (diffuse 0.5 plus a little specular)
    // is read back from the opaque image.
    let lit_linear = {
        let c = f32::from(opaque) / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let expected = srgb(0.5 * lit_linear) * 255.0;
    assert!((f32::from(half) - expected).abs() <= 3.0, "half {half}, expected {expected}, opaque {opaque}");
    let (invisible, calls) = centre_at(&mut r, 0.0, Vec3::new(0.2, 0.0, 0.0));
    assert_eq!(calls, 0, "an object at opacity 0 is not drawn");
    assert!((f32::from(invisible) - srgb(0.2) * 255.0).abs() <= 2.0, "background shows: {invisible}");
}

#[test]
fn a_light_range_ends_its_light_smoothly() {
    let mut r = headless();
    let (vertices, indices) = floor();
    r.upload_mesh(1, &MeshData::Static { vertices: &vertices, indices: &indices }).expect("upload");
    let point =
        |range| LightInput { range, ..light(LightKind::Point, Vec3::new(0.0, 0.5, 0.0), Vec3::NEG_Y, 0.2) };
    let (image, _) = r.render_image(&floor_frame(vec![point(None)]), SIZE, SIZE).expect("render");
    let (centre, corner) = (red(&image, SIZE / 2, SIZE / 2), red(&image, 3, 3));
    assert!(corner > 0);
    // Range 0.6: the centre (d = 0.5) keeps 1 − (0.5/0.6)⁴ ≈ 0.52 of its light; the corners
    // (d > 1) get none.
    let (image, _) = r.render_image(&floor_frame(vec![point(Some(0.6))]), SIZE, SIZE).expect("render");
    let (c2, k2) = (red(&image, SIZE / 2, SIZE / 2), red(&image, 3, 3));
    assert_eq!(k2, 0, "beyond the range");
    assert!(c2 > 0 && c2 < centre, "inside the range, dimmed: {c2} < {centre}");
}
