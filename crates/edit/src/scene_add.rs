//! What the *Add* menu adds (Blender's Add menu, Maya's Create): an empty, primitive meshes
//! (cube, sphere, plane, keyrig's procedural meshes), lights (point, sun, spot) and a scene
//! camera. Each new item stands where the view looks (the orbit camera's target, as Blender
//! adds at its 3D cursor), a light 2 units above it; it is one undo step and becomes the
//! selection. The editor gives it a free name ([`crate::app::unique_name`]) and adds the camera
//! through the scene-camera work (`Command::AddCamera`).

use glam::Vec3;
use keyrig_core::{Animated, Light, LightKind, MeshSource, Object, ProceduralMesh};

/// One entry of the *Add* menu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AddKind {
    Empty,
    Cube,
    Sphere,
    Plane,
    PointLight,
    SunLight,
    SpotLight,
    Camera,
}

/// A new object or light, built by [`build`].
#[derive(Clone, Debug, PartialEq)]
pub enum Added {
    Object(Box<Object>),
    Light(Light),
}

/// How far above the view's target a new light stands.
pub const LIGHT_HEIGHT: f32 = 2.0;

impl AddKind {
    /// The menu's entries, in order (separators after the plane and the spot light).
    pub const ALL: [AddKind; 8] = [
        AddKind::Empty,
        AddKind::Cube,
        AddKind::Sphere,
        AddKind::Plane,
        AddKind::PointLight,
        AddKind::SunLight,
        AddKind::SpotLight,
        AddKind::Camera,
    ];

    /// The menu entry's text.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            AddKind::Empty => "Empty",
            AddKind::Cube => "Cube",
            AddKind::Sphere => "Sphere",
            AddKind::Plane => "Plane",
            AddKind::PointLight => "Point light",
            AddKind::SunLight => "Sun light",
            AddKind::SpotLight => "Spot light",
            AddKind::Camera => "Camera",
        }
    }

    /// What the entry adds, for its tooltip.
    #[must_use]
    pub fn tooltip(self) -> &'static str {
        match self {
            AddKind::Empty => "An object with no mesh, drawn as its axes: a handle to animate or aim at",
            AddKind::Cube => "A 1-unit cube where the view looks",
            AddKind::Sphere => "A sphere 1 unit across where the view looks",
            AddKind::Plane => "A 1 × 1 square facing up where the view looks",
            AddKind::PointLight => "A light shining every way, above where the view looks",
            AddKind::SunLight => "A directional light (only its direction counts)",
            AddKind::SpotLight => "A cone of light pointing down at where the view looks",
            AddKind::Camera => "A scene camera where the view is, looking as it looks (Ctrl+Shift+C)",
        }
    }

    /// The name a new item is given, before it is made unique.
    #[must_use]
    pub fn base_name(self) -> &'static str {
        match self {
            AddKind::Empty => "Empty",
            AddKind::Cube => "Cube",
            AddKind::Sphere => "Sphere",
            AddKind::Plane => "Plane",
            AddKind::PointLight => "Point",
            AddKind::SunLight => "Sun",
            AddKind::SpotLight => "Spot",
            AddKind::Camera => "Camera",
        }
    }

    /// Whether the item is a light (named among the lights) rather than an object.
    #[must_use]
    pub fn is_light(self) -> bool {
        matches!(self, AddKind::PointLight | AddKind::SunLight | AddKind::SpotLight)
    }
}

/// The object or light `kind` adds, named `name`, for a view looking at `target`; `None` for
/// the camera, which the scene-camera code adds.
#[must_use]
pub fn build(kind: AddKind, name: String, target: Vec3) -> Option<Added> {
    let object = |mesh: Option<ProceduralMesh>| {
        let mut object = Object::new(name.clone());
        object.translation = Animated::constant(target);
        object.mesh = mesh.map(MeshSource::Procedural);
        Some(Added::Object(Box::new(object)))
    };
    let light = |kind: LightKind, intensity: f32| {
        Some(Added::Light(Light {
            name: name.clone(),
            kind,
            enabled: true,
            position: Animated::constant(target + Vec3::Y * LIGHT_HEIGHT),
            direction: Animated::constant(match kind {
                LightKind::Directional => Vec3::new(-0.4, -1.0, -0.6),
                _ => -Vec3::Y,
            }),
            colour: Animated::constant(Vec3::ONE),
            intensity: Animated::constant(intensity),
            attributes: Default::default(),
        }))
    };
    match kind {
        AddKind::Empty => object(None),
        AddKind::Cube => object(Some(ProceduralMesh::Cube)),
        AddKind::Sphere => object(Some(ProceduralMesh::Sphere)),
        AddKind::Plane => object(Some(ProceduralMesh::Plane)),
        AddKind::PointLight => light(LightKind::Point, 4.0),
        AddKind::SunLight => light(LightKind::Directional, 0.9),
        AddKind::SpotLight => {
            light(LightKind::Spot { cutoff_deg: 30.0, inner_angle_deg: 20.0, dropoff: 2.0 }, 8.0)
        }
        AddKind::Camera => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_stand_where_the_view_looks_and_every_entry_is_valid() {
        let target = Vec3::new(1.0, 0.5, -2.0);
        for kind in AddKind::ALL {
            let added = build(kind, kind.base_name().to_owned(), target);
            let mut scene = keyrig_core::Scene::default();
            match added {
                Some(Added::Object(o)) => {
                    assert!(!kind.is_light());
                    assert_eq!(o.translation.value, target, "{kind:?}");
                    scene.objects.push(*o);
                }
                Some(Added::Light(l)) => {
                    assert!(kind.is_light());
                    assert_eq!(l.position.value, target + Vec3::Y * LIGHT_HEIGHT, "{kind:?}");
                    scene.lights.push(l);
                }
                None => assert_eq!(kind, AddKind::Camera),
            }
            assert!(scene.problems().is_empty(), "{kind:?}: {:?}", scene.problems());
        }
    }
}
