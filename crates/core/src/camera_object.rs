//! Scene cameras, timeline markers and the render size: the cameras an animator places and
//! keys, and the shots they make (docs/scene-format.md, "Cameras and markers").
//!
//! Not to be confused with [`crate::Camera`], the viewport's orbit view saved with a scene.
//!
//! A [`SceneCamera`] is a scene object: a keyed translation and rotation (every key option a
//! transform has: TCB, Squad, spins, cycles), a keyed lens (vertical field of view, focal
//! length on a sensor, or orthographic height) and clip planes. It looks down its local −Z
//! axis with +Y up, as a glTF camera does. An optional [`Aim`] points it at an object, a joint
//! or a point instead of its keyed rotation (3ds Max's target camera, Blender's Track To).
//!
//! [`Marker`]s name frames of the timeline; a marker bound to a camera makes it the active
//! camera from its frame on (`Scene::active_camera_at`), as Blender's markers bound to
//! cameras.

use glam::{Mat3, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::key::Animated;

/// A camera placed in the scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneCamera {
    /// Unique among the scene's cameras; used in channel paths (`camera/<name>/lens`).
    pub name: String,
    /// How [`SceneCamera::lens`] is read.
    pub projection: Projection,
    /// The keyed lens: the vertical field of view in degrees ([`Projection::Perspective`]),
    /// the focal length in millimetres ([`Projection::FocalLength`]) or the height of the view
    /// in scene units ([`Projection::Orthographic`]).
    pub lens: Animated<f32>,
    /// Near clip plane, scene units (> 0).
    pub near: f32,
    /// Far clip plane, scene units (> near); `None` is an infinite far plane (perspective
    /// only, as glTF's perspective camera without `zfar`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far: Option<f32>,
    /// Position in world space.
    pub translation: Animated<Vec3>,
    /// Orientation in world space: the camera looks down its local −Z with +Y up. Unused
    /// while an [`Aim`] is set.
    pub rotation: Animated<Quat>,
    /// Points the camera at something instead of its keyed rotation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aim: Option<Aim>,
    /// 1 shown, 0 hidden (Step keys, channel `camera/<name>/visible`): a hidden camera's
    /// frustum is not drawn (glTF `KHR_node_visibility` on its node). Left out of the file
    /// while always shown.
    #[serde(default = "shown", skip_serializing_if = "is_shown")]
    pub visible: Animated<f32>,
}

fn shown() -> Animated<f32> {
    Animated::constant(1.0)
}

fn is_shown(a: &Animated<f32>) -> bool {
    !a.is_animated() && a.value == 1.0
}

impl SceneCamera {
    /// A perspective camera with a 40° vertical field of view at `translation`, looking down
    /// −Z, clipping at 0.1 and 1000 units.
    #[must_use]
    pub fn new(name: impl Into<String>, translation: Vec3) -> Self {
        SceneCamera {
            name: name.into(),
            projection: Projection::Perspective,
            lens: Animated::constant(40.0),
            near: 0.1,
            far: Some(1000.0),
            translation: Animated::constant(translation),
            rotation: Animated::constant(Quat::IDENTITY),
            aim: None,
            visible: shown(),
        }
    }
}

/// What a camera's keyed lens means.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Projection {
    /// Perspective; the lens is the vertical field of view in degrees, in (0, 180).
    Perspective,
    /// Perspective; the lens is the focal length in millimetres (> 0) on a sensor
    /// `sensor_height_mm` tall: vertical field of view = 2·atan(sensor / (2·focal length)).
    FocalLength { sensor_height_mm: f32 },
    /// Orthographic; the lens is the height of the view in scene units (> 0).
    Orthographic,
}

impl Projection {
    /// The name shown in the editor.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Projection::Perspective => "Perspective (field of view)",
            Projection::FocalLength { .. } => "Perspective (focal length)",
            Projection::Orthographic => "Orthographic",
        }
    }

    /// The unit of the lens value.
    #[must_use]
    pub fn lens_unit(self) -> &'static str {
        match self {
            Projection::Perspective => "°",
            Projection::FocalLength { .. } => "mm",
            Projection::Orthographic => "units",
        }
    }

    /// What the lens value is, for labels.
    #[must_use]
    pub fn lens_name(self) -> &'static str {
        match self {
            Projection::Perspective => "field of view",
            Projection::FocalLength { .. } => "focal length",
            Projection::Orthographic => "view height",
        }
    }
}

/// The evaluated lens of a camera at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// Vertical field of view in radians.
    Perspective { fov_y: f32 },
    /// Height of the view in scene units.
    Orthographic { height: f32 },
}

impl Lens {
    /// The lens of `projection` for the keyed value `lens` (see [`SceneCamera::lens`]).
    #[must_use]
    pub fn of(projection: Projection, lens: f32) -> Lens {
        match projection {
            Projection::Perspective => Lens::Perspective { fov_y: lens.to_radians() },
            Projection::FocalLength { sensor_height_mm } => {
                Lens::Perspective { fov_y: fov_y_from_focal_length(lens, sensor_height_mm) }
            }
            Projection::Orthographic => Lens::Orthographic { height: lens },
        }
    }
}

/// Vertical field of view (radians) of a lens of `focal_length_mm` on a sensor
/// `sensor_height_mm` tall: 2·atan(sensor / (2·focal length)), the pinhole model.
#[must_use]
pub fn fov_y_from_focal_length(focal_length_mm: f32, sensor_height_mm: f32) -> f32 {
    2.0 * (sensor_height_mm / (2.0 * focal_length_mm)).atan()
}

/// The focal length (mm) that gives a vertical field of view of `fov_y` radians on a sensor
/// `sensor_height_mm` tall; the inverse of [`fov_y_from_focal_length`].
#[must_use]
pub fn focal_length_from_fov_y(fov_y: f32, sensor_height_mm: f32) -> f32 {
    sensor_height_mm / (2.0 * (fov_y * 0.5).tan())
}

/// An aim constraint: the camera looks at `target`, its up as close to `up` as looking there
/// allows, turned by `roll` degrees about its view axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Aim {
    pub target: AimTarget,
    /// World-space up direction (need not be unit; not zero).
    #[serde(default = "y_up")]
    pub up: Vec3,
    /// Keyed roll about the view axis, degrees: a right-handed turn of the camera about its
    /// own +Z (positive tilts its up towards its left, so the image turns clockwise).
    #[serde(default = "no_roll")]
    pub roll: Animated<f32>,
    /// Keyed influence in [0, 1] (docs/constraints.md): 0 the keyed rotation, 1 the aim, slerp
    /// between; left out of the file while 1 and not keyed (channel `camera/<name>/aim_influence`).
    #[serde(default = "full_influence", skip_serializing_if = "is_full_influence")]
    pub influence: Animated<f32>,
}

fn full_influence() -> Animated<f32> {
    Animated::constant(1.0)
}

fn is_full_influence(a: &Animated<f32>) -> bool {
    !a.is_animated() && a.value == 1.0
}

fn y_up() -> Vec3 {
    Vec3::Y
}

fn no_roll() -> Animated<f32> {
    Animated::constant(0.0)
}

impl Aim {
    /// Looking at `target` with +Y up and no roll.
    #[must_use]
    pub fn at(target: AimTarget) -> Self {
        Aim { target, up: y_up(), roll: no_roll(), influence: full_influence() }
    }
}

/// What an aimed camera looks at.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum AimTarget {
    /// The origin of an object (its world translation), by name.
    Object(String),
    /// A joint of an object's skeleton (its world position at that time), by names.
    Joint { object: String, joint: String },
    /// A fixed point in world space.
    Point(Vec3),
}

/// The world rotation of a camera at `eye` looking at `target` (its −Z towards the target)
/// with its +Y as close to `up` as possible, then turned by `roll_deg` about its view axis.
/// When `up` is along the view direction, the world axis least aligned with the view
/// direction is used instead. `None` when the eye is on the target or a value is not finite.
#[must_use]
pub fn aim_rotation(eye: Vec3, target: Vec3, up: Vec3, roll_deg: f32) -> Option<Quat> {
    let forward = (target - eye).try_normalize()?;
    let up = up.try_normalize().unwrap_or(Vec3::Y);
    let mut right = forward.cross(up);
    if right.length_squared() < 1e-10 {
        let a = forward.abs();
        let fallback = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        right = forward.cross(fallback);
    }
    let right = right.try_normalize()?;
    let camera_up = right.cross(forward);
    let aim = Quat::from_mat3(&Mat3::from_cols(right, camera_up, -forward));
    roll_deg.is_finite().then(|| (aim * Quat::from_rotation_z(roll_deg.to_radians())).normalize())
}

/// A named frame of the timeline; bound to a camera, the camera becomes the active one from
/// this frame on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Marker {
    pub name: String,
    pub frame: i32,
    /// The name of the camera that becomes active at this marker.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<String>,
}

/// The size of rendered images, pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSize {
    pub width: u32,
    pub height: u32,
}

impl RenderSize {
    /// Largest side accepted (as `keyrig render --size`).
    pub const MAX_SIDE: u32 = 16384;

    /// Width over height.
    #[must_use]
    pub fn aspect(self) -> f32 {
        self.width as f32 / self.height.max(1) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn close(a: Quat, b: Quat) -> bool {
        a.dot(b).abs() > 1.0 - 1e-6
    }

    #[test]
    fn aim_from_the_front_is_the_identity() {
        // Eye on +Z looking at the origin: the rest orientation (looking down −Z, +Y up).
        let q = aim_rotation(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 0.0).unwrap();
        assert!(close(q, Quat::IDENTITY), "{q}");
    }

    #[test]
    fn aim_matches_the_hand_computed_basis() {
        // Eye at (3, 0, 0) looking at the origin, +Y up. By hand: forward f = (−1, 0, 0),
        // right = f × up = (0, 0, −1), camera up = right × f = (0, 1, 0), back = −f = (1, 0, 0).
        // The matrix with those columns is a +90° turn about Y.
        let q = aim_rotation(Vec3::new(3.0, 0.0, 0.0), Vec3::ZERO, Vec3::Y, 0.0).unwrap();
        assert!(close(q, Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)), "{q}");
        let m = Mat3::from_quat(q);
        assert!(m.x_axis.abs_diff_eq(Vec3::new(0.0, 0.0, -1.0), 1e-6));
        assert!(m.y_axis.abs_diff_eq(Vec3::Y, 1e-6));
        assert!(m.z_axis.abs_diff_eq(Vec3::X, 1e-6));
    }

    #[test]
    fn aim_from_above_at_an_angle() {
        // Eye at (0, 4, 4) looking at the origin: down 45°. By hand: f = (0, −1, −1)/√2,
        // right = f × Y = (1, 0, 0), camera up = right × f = (0, 1, −1)/√2: a −45° turn about X.
        let q = aim_rotation(Vec3::new(0.0, 4.0, 4.0), Vec3::ZERO, Vec3::Y, 0.0).unwrap();
        assert!(close(q, Quat::from_rotation_x(-std::f32::consts::FRAC_PI_4)), "{q}");
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!((q * Vec3::Y).abs_diff_eq(Vec3::new(0.0, s, -s), 1e-6));
    }

    #[test]
    fn roll_turns_about_the_view_axis() {
        // 90° of roll: the camera's up becomes its old left (counter-clockwise in the image).
        let q = aim_rotation(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 90.0).unwrap();
        assert!((q * Vec3::Y).abs_diff_eq(Vec3::NEG_X, 1e-6), "{}", q * Vec3::Y);
        assert!((q * Vec3::NEG_Z).abs_diff_eq(Vec3::NEG_Z, 1e-6));
    }

    #[test]
    fn looking_along_up_still_aims() {
        let q = aim_rotation(Vec3::new(0.0, 5.0, 0.0), Vec3::ZERO, Vec3::Y, 0.0).unwrap();
        assert!((q * Vec3::NEG_Z).abs_diff_eq(Vec3::NEG_Y, 1e-6));
        assert!(aim_rotation(Vec3::ONE, Vec3::ONE, Vec3::Y, 0.0).is_none());
        assert!(aim_rotation(Vec3::ZERO, Vec3::X, Vec3::Y, f32::NAN).is_none());
    }

    #[test]
    fn focal_length_and_field_of_view() {
        // A 50 mm lens on a 24 mm tall (full-frame) sensor: 2·atan(12/50) = 26.99°.
        let fov = fov_y_from_focal_length(50.0, 24.0);
        assert!((fov.to_degrees() - 26.991_466).abs() < 1e-4, "{}", fov.to_degrees());
        assert!((focal_length_from_fov_y(fov, 24.0) - 50.0).abs() < 1e-4);
        assert_eq!(Lens::of(Projection::Perspective, 90.0), Lens::Perspective { fov_y: 90f32.to_radians() });
        assert_eq!(Lens::of(Projection::Orthographic, 3.0), Lens::Orthographic { height: 3.0 });
    }

    #[test]
    fn markers_switch_the_active_camera() {
        let mut scene = Scene::default();
        assert_eq!(scene.active_camera_at(0.0), None);
        scene.cameras = vec![SceneCamera::new("Wide", Vec3::Z), SceneCamera::new("Close", Vec3::X)];
        assert_eq!(scene.active_camera_at(0.0), Some(0));
        scene.active_camera = Some("Close".into());
        assert_eq!(scene.active_camera_at(0.0), Some(1));
        scene.markers = vec![
            Marker { name: "cut".into(), frame: 20, camera: Some("Wide".into()) },
            Marker { name: "note".into(), frame: 25, camera: None },
            Marker { name: "back".into(), frame: 40, camera: Some("Close".into()) },
            Marker { name: "gone".into(), frame: 50, camera: Some("Missing".into()) },
        ];
        assert_eq!(scene.active_camera_at(19.9), Some(1));
        assert_eq!(scene.active_camera_at(20.0), Some(0));
        assert_eq!(scene.active_camera_at(39.0), Some(0));
        assert_eq!(scene.active_camera_at(60.0), Some(1));
    }
}
