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

use keyrig_core::SceneCamera;

use crate::model::{ModelCamera, ModelProjection};

/// Why a camera of the file is refused: where (a JSON pointer) and what.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CameraError {
    pub pointer: String,
    /// A number that is NaN or infinite (else a value out of range).
    pub non_finite: bool,
    pub message: String,
}

/// The file's cameras, checked: finite numbers, 0 < yfov < π, znear > 0 (≥ 0 orthographic),
/// zfar > znear, a positive aspect ratio, magnifications not zero.
pub(crate) fn read_cameras(doc: &gltf::Document) -> Result<Vec<ModelCamera>, CameraError> {
    doc.cameras()
        .map(|camera| {
            let here = format!("/cameras/{}", camera.index());
            let invalid = |field: &str, message: String| CameraError {
                pointer: format!("{here}/{field}"),
                non_finite: false,
                message,
            };
            let non_finite = || CameraError {
                pointer: here.clone(),
                non_finite: true,
                message: "camera parameter".into(),
            };
            let projection = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let (yfov, znear, zfar, aspect) = (p.yfov(), p.znear(), p.zfar(), p.aspect_ratio());
                    let numbers = [yfov, znear].into_iter().chain(zfar).chain(aspect);
                    if numbers.into_iter().any(|x| !x.is_finite()) {
                        return Err(non_finite());
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
                        return Err(non_finite());
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
