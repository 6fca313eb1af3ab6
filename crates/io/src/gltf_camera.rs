//! glTF cameras (glTF 2.0 §3.10, `cameras` on nodes) in and out of keyrig's scene cameras.
//!
//! - Import: each camera of the file is read into a [`ModelCamera`]; each node that holds one
//!   becomes a [`keyrig_core::SceneCamera`] at the node's rest world position and rotation
//!   (a camera looks down its node's −Z with +Y up in glTF as in keyrig; the node's scale does
//!   not apply), keyed by the node's own translation and rotation channels when it is a root
//!   node. A perspective camera's `yfov` (radians) becomes a field of view in degrees, an
//!   orthographic camera's `ymag` (half the view's height) a view height of `2·ymag`. The
//!   first camera with an aspect ratio (`aspectRatio`, or `xmag / ymag`) sets the scene's
//!   render size (720 pixels tall).
//! - Export ([`crate::gltf_export`]): each scene camera becomes a root node with a camera, its
//!   translation and rotation channels as an object's; an aimed camera's rotation is baked.

use glam::Mat4;
use keyrig_core::{Animated, Projection, RenderSize, SceneCamera};

use crate::gltf_import::{GltfError, GltfErrorKind};
use crate::model::{ChannelTarget, ImportedModel};

/// A glTF camera.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCamera {
    pub name: String,
    pub projection: ModelProjection,
}

/// A glTF camera's projection, as the file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelProjection {
    Perspective { yfov: f32, aspect_ratio: Option<f32>, znear: f32, zfar: Option<f32> },
    Orthographic { xmag: f32, ymag: f32, znear: f32, zfar: f32 },
}

impl ModelProjection {
    /// Width over height, when the file says.
    #[must_use]
    pub fn aspect_ratio(self) -> Option<f32> {
        match self {
            ModelProjection::Perspective { aspect_ratio, .. } => aspect_ratio,
            ModelProjection::Orthographic { xmag, ymag, .. } => Some(xmag / ymag),
        }
    }
}

/// The file's cameras, checked: finite numbers, 0 < yfov < π, znear > 0 (≥ 0 orthographic),
/// zfar > znear, a positive aspect ratio, magnifications not zero.
pub(crate) fn read_cameras(doc: &gltf::Document) -> Result<Vec<ModelCamera>, GltfError> {
    doc.cameras()
        .map(|camera| {
            let here = format!("/cameras/{}", camera.index());
            let invalid = |field: &str, message: String| {
                crate::gltf_import::pointer_error(format!("{here}/{field}"), GltfErrorKind::Invalid(message))
            };
            let projection = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let (yfov, znear, zfar, aspect) = (p.yfov(), p.znear(), p.zfar(), p.aspect_ratio());
                    let numbers = [yfov, znear].into_iter().chain(zfar).chain(aspect);
                    if numbers.into_iter().any(|x| !x.is_finite()) {
                        return Err(crate::gltf_import::pointer_error(
                            here,
                            GltfErrorKind::NonFinite("camera parameter".into()),
                        ));
                    }
                    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                        return Err(invalid("perspective/yfov", format!("{yfov} is outside (0, π)")));
                    }
                    if znear <= 0.0 {
                        return Err(invalid("perspective/znear", format!("{znear} must be > 0")));
                    }
                    if let Some(zfar) = zfar.filter(|&f| f <= znear) {
                        return Err(invalid("perspective/zfar", format!("{zfar} must be > znear {znear}")));
                    }
                    if let Some(aspect) = aspect.filter(|&a| a <= 0.0) {
                        return Err(invalid("perspective/aspectRatio", format!("{aspect} must be > 0")));
                    }
                    ModelProjection::Perspective { yfov, aspect_ratio: aspect, znear, zfar }
                }
                gltf::camera::Projection::Orthographic(o) => {
                    let (xmag, ymag, znear, zfar) = (o.xmag(), o.ymag(), o.znear(), o.zfar());
                    if [xmag, ymag, znear, zfar].iter().any(|x| !x.is_finite()) {
                        return Err(crate::gltf_import::pointer_error(
                            here,
                            GltfErrorKind::NonFinite("camera parameter".into()),
                        ));
                    }
                    if xmag == 0.0 || ymag == 0.0 {
                        return Err(invalid(
                            "orthographic",
                            format!("xmag {xmag} and ymag {ymag} must not be 0"),
                        ));
                    }
                    if znear < 0.0 || zfar <= znear {
                        return Err(invalid(
                            "orthographic/zfar",
                            format!("need 0 ≤ znear ({znear}) < zfar ({zfar})"),
                        ));
                    }
                    ModelProjection::Orthographic { xmag: xmag.abs(), ymag: ymag.abs(), znear, zfar }
                }
            };
            let name = camera.name().map_or_else(|| format!("camera{}", camera.index()), str::to_owned);
            Ok(ModelCamera { name, projection })
        })
        .collect()
}

/// Adds a scene camera for each node of `model` that holds a camera (see the module
/// documentation), named after the node (or its camera), unique among the scene's cameras.
pub(crate) fn add_scene_cameras(
    model: &ImportedModel,
    world: &[Mat4],
    channels_of: &[Vec<&ChannelTarget>],
    scene: &mut keyrig_core::Scene,
) {
    for (i, node) in model.nodes.iter().enumerate() {
        let Some(camera) = node.camera.and_then(|c| model.cameras.get(c)) else { continue };
        let (_, rotation, translation) = world[i].to_scale_rotation_translation();
        // The node's name, unless the file left it out (then the camera's).
        let base = if node.name == format!("node{i}") { camera.name.clone() } else { node.name.clone() };
        let name = if scene.camera_index(&base).is_some() {
            (1..).map(|n| format!("{base}.{n:03}")).find(|n| scene.camera_index(n).is_none()).unwrap_or(base)
        } else {
            base
        };
        let mut out = SceneCamera::new(name, translation);
        out.rotation = Animated::constant(rotation.normalize());
        match camera.projection {
            ModelProjection::Perspective { yfov, znear, zfar, .. } => {
                out.projection = Projection::Perspective;
                out.lens = Animated::constant(yfov.to_degrees());
                (out.near, out.far) = (znear, zfar);
            }
            ModelProjection::Orthographic { ymag, znear, zfar, .. } => {
                out.projection = Projection::Orthographic;
                out.lens = Animated::constant(2.0 * ymag);
                // keyrig's near plane is > 0; glTF allows an orthographic znear of 0.
                (out.near, out.far) = (znear.max(1e-4).min(zfar * 0.5), Some(zfar));
            }
        }
        if node.parent.is_none() {
            for target in &channels_of[i] {
                match target {
                    ChannelTarget::Translation(t) => out.translation.track = t.clone(),
                    ChannelTarget::Rotation(t) => out.rotation.track = t.clone(),
                    ChannelTarget::Scale(_) | ChannelTarget::Weights(_) => {}
                }
            }
        }
        if scene.render_size.is_none() {
            if let Some(aspect) = camera.projection.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0) {
                let width = (720.0 * aspect).round().clamp(1.0, f32::from(u16::MAX)) as u32;
                scene.render_size = Some(RenderSize { width: width.min(RenderSize::MAX_SIDE), height: 720 });
            }
        }
        scene.cameras.push(out);
    }
}

/// The glTF `cameras` entry of `camera` with its lens value `lens` (at the start of the
/// frame range) for images of `aspect` = width / height: glTF's `yfov` is the vertical field
/// of view in radians, `ymag` half the view's height, `xmag = ymag · aspect`.
pub(crate) fn camera_json(camera: &SceneCamera, lens: f32, aspect: Option<f32>) -> serde_json::Value {
    use serde_json::json;
    match keyrig_core::Lens::of(camera.projection, lens) {
        keyrig_core::Lens::Perspective { fov_y } => {
            let mut p = json!({"yfov": fov_y, "znear": camera.near});
            if let Some(far) = camera.far {
                p["zfar"] = json!(far);
            }
            if let Some(aspect) = aspect {
                p["aspectRatio"] = json!(aspect);
            }
            json!({"name": camera.name, "type": "perspective", "perspective": p})
        }
        keyrig_core::Lens::Orthographic { height } => {
            let ymag = height * 0.5;
            let xmag = ymag * aspect.unwrap_or(16.0 / 9.0);
            let far = camera.far.unwrap_or(camera.near * 1e6);
            json!({"name": camera.name, "type": "orthographic",
                   "orthographic": {"xmag": xmag, "ymag": ymag, "znear": camera.near, "zfar": far}})
        }
    }
}
