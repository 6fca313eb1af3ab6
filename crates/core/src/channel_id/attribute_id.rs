//! Attribute channels by index (keyrig-core's `attributes` holds their data): the
//! [`AttributeId`] of [`ChannelId::Attribute`], their path names, value rules and validation.

use serde::{Deserialize, Serialize};

use super::{ChannelId, ChannelKind, ChannelMut, ChannelRef};
use crate::key::{Animated, Interpolation};
use crate::scene::{DeformerKind, LightKind, Scene};

fn is_shown(a: &Animated<f32>) -> bool {
    !a.is_animated() && a.value == 1.0
}

/// The deformer a keyed deformer value selects: the nearest index into [`DeformerKind::ALL`],
/// clamped; `None` for a non-finite value.
#[must_use]
pub fn deformer_from_value(v: f32) -> Option<DeformerKind> {
    if !v.is_finite() {
        return None;
    }
    let i = v.round().clamp(0.0, (DeformerKind::ALL.len() - 1) as f32) as usize;
    Some(DeformerKind::ALL[i])
}

/// The keyed value of a deformer (its index in [`DeformerKind::ALL`]).
#[must_use]
pub fn deformer_value(kind: DeformerKind) -> f32 {
    DeformerKind::ALL.iter().position(|&k| k == kind).unwrap_or(1) as f32
}

/// One attribute channel, by index (the [`ChannelId::Attribute`] of the editor, the evaluator
/// and overrides).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum AttributeId {
    ObjectVisible(usize),
    ObjectColour(usize),
    ObjectOpacity(usize),
    MorphWeight {
        object: usize,
        target: usize,
    },
    Deformer(usize),
    /// The bones-blending zone's reach into the parent bone (`blend_parent_fraction`).
    BlendParent(usize),
    /// The bones-blending zone's reach into the child bone (`blend_child_fraction`).
    BlendChild(usize),
    LightVisible(usize),
    LightRange(usize),
    LightCutoff(usize),
    LightInnerAngle(usize),
}

/// The name of an attribute in a channel path (`object/<o>/<name>`, `light/<l>/<name>`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AttributeProperty {
    Visible,
    Colour,
    Opacity,
    /// `morph/<target index>`.
    Morph(usize),
    Deformer,
    BlendParent,
    BlendChild,
    Range,
    Cutoff,
    InnerAngle,
}

/// Object attributes by path name (`morph/<i>` aside).
pub const OBJECT_ATTRIBUTES: [&str; 7] =
    ["visible", "colour", "opacity", "morph", "deformer", "blend_parent_fraction", "blend_child_fraction"];
/// Light attributes by path name.
pub const LIGHT_ATTRIBUTES: [&str; 4] = ["visible", "range", "cutoff_deg", "inner_angle_deg"];

impl AttributeProperty {
    /// The property's part of a channel path (`visible`, `morph/2`).
    #[must_use]
    pub fn path_name(self) -> String {
        match self {
            AttributeProperty::Visible => "visible".into(),
            AttributeProperty::Colour => "colour".into(),
            AttributeProperty::Opacity => "opacity".into(),
            AttributeProperty::Morph(i) => format!("morph/{i}"),
            AttributeProperty::Deformer => "deformer".into(),
            AttributeProperty::BlendParent => "blend_parent_fraction".into(),
            AttributeProperty::BlendChild => "blend_child_fraction".into(),
            AttributeProperty::Range => "range".into(),
            AttributeProperty::Cutoff => "cutoff_deg".into(),
            AttributeProperty::InnerAngle => "inner_angle_deg".into(),
        }
    }

    /// An object attribute by its path name (not `morph`).
    #[must_use]
    pub fn of_object(name: &str) -> Option<Self> {
        Some(match name {
            "visible" => AttributeProperty::Visible,
            "colour" | "color" => AttributeProperty::Colour,
            "opacity" => AttributeProperty::Opacity,
            "deformer" => AttributeProperty::Deformer,
            "blend_parent_fraction" => AttributeProperty::BlendParent,
            "blend_child_fraction" => AttributeProperty::BlendChild,
            _ => return None,
        })
    }

    /// A light attribute by its path name.
    #[must_use]
    pub fn of_light(name: &str) -> Option<Self> {
        Some(match name {
            "visible" => AttributeProperty::Visible,
            "range" => AttributeProperty::Range,
            "cutoff_deg" => AttributeProperty::Cutoff,
            "inner_angle_deg" => AttributeProperty::InnerAngle,
            _ => return None,
        })
    }

    /// The id of this property of object `o` (`None` for a light property).
    #[must_use]
    pub fn object_id(self, o: usize) -> Option<AttributeId> {
        Some(match self {
            AttributeProperty::Visible => AttributeId::ObjectVisible(o),
            AttributeProperty::Colour => AttributeId::ObjectColour(o),
            AttributeProperty::Opacity => AttributeId::ObjectOpacity(o),
            AttributeProperty::Morph(target) => AttributeId::MorphWeight { object: o, target },
            AttributeProperty::Deformer => AttributeId::Deformer(o),
            AttributeProperty::BlendParent => AttributeId::BlendParent(o),
            AttributeProperty::BlendChild => AttributeId::BlendChild(o),
            _ => return None,
        })
    }

    /// The id of this property of light `l` (`None` for an object property).
    #[must_use]
    pub fn light_id(self, l: usize) -> Option<AttributeId> {
        Some(match self {
            AttributeProperty::Visible => AttributeId::LightVisible(l),
            AttributeProperty::Range => AttributeId::LightRange(l),
            AttributeProperty::Cutoff => AttributeId::LightCutoff(l),
            AttributeProperty::InnerAngle => AttributeId::LightInnerAngle(l),
            _ => return None,
        })
    }
}

impl AttributeId {
    #[must_use]
    pub fn kind(self) -> ChannelKind {
        match self {
            AttributeId::ObjectColour(_) => ChannelKind::Vec3,
            _ => ChannelKind::Scalar,
        }
    }

    /// The object (`Ok`) or light (`Err`) it belongs to.
    pub fn owner(self) -> Result<usize, usize> {
        match self {
            AttributeId::ObjectVisible(o)
            | AttributeId::ObjectColour(o)
            | AttributeId::ObjectOpacity(o)
            | AttributeId::MorphWeight { object: o, .. }
            | AttributeId::Deformer(o)
            | AttributeId::BlendParent(o)
            | AttributeId::BlendChild(o) => Ok(o),
            AttributeId::LightVisible(l)
            | AttributeId::LightRange(l)
            | AttributeId::LightCutoff(l)
            | AttributeId::LightInnerAngle(l) => Err(l),
        }
    }

    /// The same attribute of object or light `i` (of the same kind of owner).
    #[must_use]
    pub fn with_owner(self, i: usize) -> Self {
        match self {
            AttributeId::ObjectVisible(_) => AttributeId::ObjectVisible(i),
            AttributeId::ObjectColour(_) => AttributeId::ObjectColour(i),
            AttributeId::ObjectOpacity(_) => AttributeId::ObjectOpacity(i),
            AttributeId::MorphWeight { target, .. } => AttributeId::MorphWeight { object: i, target },
            AttributeId::Deformer(_) => AttributeId::Deformer(i),
            AttributeId::BlendParent(_) => AttributeId::BlendParent(i),
            AttributeId::BlendChild(_) => AttributeId::BlendChild(i),
            AttributeId::LightVisible(_) => AttributeId::LightVisible(i),
            AttributeId::LightRange(_) => AttributeId::LightRange(i),
            AttributeId::LightCutoff(_) => AttributeId::LightCutoff(i),
            AttributeId::LightInnerAngle(_) => AttributeId::LightInnerAngle(i),
        }
    }

    #[must_use]
    pub fn property(self) -> AttributeProperty {
        match self {
            AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_) => AttributeProperty::Visible,
            AttributeId::ObjectColour(_) => AttributeProperty::Colour,
            AttributeId::ObjectOpacity(_) => AttributeProperty::Opacity,
            AttributeId::MorphWeight { target, .. } => AttributeProperty::Morph(target),
            AttributeId::Deformer(_) => AttributeProperty::Deformer,
            AttributeId::BlendParent(_) => AttributeProperty::BlendParent,
            AttributeId::BlendChild(_) => AttributeProperty::BlendChild,
            AttributeId::LightRange(_) => AttributeProperty::Range,
            AttributeId::LightCutoff(_) => AttributeProperty::Cutoff,
            AttributeId::LightInnerAngle(_) => AttributeProperty::InnerAngle,
        }
    }

    /// Short name for labels ("visible", "morph 2", "blend zone (parent)").
    #[must_use]
    pub fn channel_name(self) -> &'static str {
        match self {
            AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_) => "visible",
            AttributeId::ObjectColour(_) => "colour",
            AttributeId::ObjectOpacity(_) => "opacity",
            AttributeId::MorphWeight { .. } => "morph weight",
            AttributeId::Deformer(_) => "deformer",
            AttributeId::BlendParent(_) => "blend zone (parent)",
            AttributeId::BlendChild(_) => "blend zone (child)",
            AttributeId::LightRange(_) => "range",
            AttributeId::LightCutoff(_) => "cutoff",
            AttributeId::LightInnerAngle(_) => "inner angle",
        }
    }

    /// The field path of its `Animated` value (`objects[0].attributes.opacity`).
    #[must_use]
    pub fn field_path(self) -> String {
        let owner = match self.owner() {
            Ok(o) => format!("objects[{o}].attributes"),
            Err(l) => format!("lights[{l}].attributes"),
        };
        match self {
            AttributeId::MorphWeight { target, .. } => format!("{owner}.morph_weights[{target}]"),
            AttributeId::LightCutoff(_) => format!("{owner}.cutoff_deg"),
            AttributeId::LightInnerAngle(_) => format!("{owner}.inner_angle_deg"),
            _ => format!("{owner}.{}", self.property().path_name()),
        }
    }

    /// The name of its object or light.
    #[must_use]
    pub fn owner_name(self, scene: &Scene) -> Option<String> {
        match self.owner() {
            Ok(o) => scene.objects.get(o).map(|o| o.name.clone()),
            Err(l) => scene.lights.get(l).map(|l| l.name.clone()),
        }
    }

    /// The attribute channels of object `o` that are in use: visibility and opacity while keyed
    /// or not 1 (as a joint's translation is listed only where it is keyed or not zero), the
    /// others while they are set. Every object has visibility and opacity channels whether
    /// listed or not; keying one lists it.
    #[must_use]
    pub fn of_object(scene: &Scene, o: usize) -> Vec<ChannelId> {
        let Some(object) = scene.objects.get(o) else { return Vec::new() };
        let a = &object.attributes;
        let mut out = Vec::new();
        if !is_shown(&a.visible) {
            out.push(AttributeId::ObjectVisible(o));
        }
        if a.colour.is_some() {
            out.push(AttributeId::ObjectColour(o));
        }
        if !is_shown(&a.opacity) {
            out.push(AttributeId::ObjectOpacity(o));
        }
        out.extend((0..a.morph_weights.len()).map(|target| AttributeId::MorphWeight { object: o, target }));
        if a.deformer.is_some() {
            out.push(AttributeId::Deformer(o));
        }
        push_blend_zone(a, o, &mut out);
        out.into_iter().map(ChannelId::Attribute).collect()
    }

    /// The attribute channels of light `l` that are in use: visibility while keyed or not 1, the
    /// others while they are set.
    #[must_use]
    pub fn of_light(scene: &Scene, l: usize) -> Vec<ChannelId> {
        let Some(light) = scene.lights.get(l) else { return Vec::new() };
        let a = &light.attributes;
        let mut out = Vec::new();
        for (set, id) in [
            (!is_shown(&a.visible), AttributeId::LightVisible(l)),
            (a.range.is_some(), AttributeId::LightRange(l)),
            (a.cutoff_deg.is_some(), AttributeId::LightCutoff(l)),
            (a.inner_angle_deg.is_some(), AttributeId::LightInnerAngle(l)),
        ] {
            if set {
                out.push(id);
            }
        }
        out.into_iter().map(ChannelId::Attribute).collect()
    }

    /// Borrows the channel; `None` when it does not exist in `scene`.
    #[must_use]
    pub fn get(self, scene: &Scene) -> Option<ChannelRef<'_>> {
        match self.owner() {
            Ok(o) => {
                let a = &scene.objects.get(o)?.attributes;
                Some(match self {
                    AttributeId::ObjectColour(_) => ChannelRef::Vec3(a.colour.as_ref()?),
                    AttributeId::ObjectVisible(_) => ChannelRef::Scalar(&a.visible),
                    AttributeId::ObjectOpacity(_) => ChannelRef::Scalar(&a.opacity),
                    AttributeId::MorphWeight { target, .. } => {
                        ChannelRef::Scalar(a.morph_weights.get(target)?)
                    }
                    AttributeId::Deformer(_) => ChannelRef::Scalar(a.deformer.as_ref()?),
                    AttributeId::BlendParent(_) => ChannelRef::Scalar(a.blend_parent_fraction.as_ref()?),
                    AttributeId::BlendChild(_) => ChannelRef::Scalar(a.blend_child_fraction.as_ref()?),
                    _ => return None,
                })
            }
            Err(l) => {
                let a = &scene.lights.get(l)?.attributes;
                Some(ChannelRef::Scalar(match self {
                    AttributeId::LightVisible(_) => &a.visible,
                    AttributeId::LightRange(_) => a.range.as_ref()?,
                    AttributeId::LightCutoff(_) => a.cutoff_deg.as_ref()?,
                    AttributeId::LightInnerAngle(_) => a.inner_angle_deg.as_ref()?,
                    _ => return None,
                }))
            }
        }
    }

    /// Mutably borrows the channel; `None` when it does not exist in `scene`.
    #[must_use]
    pub fn get_mut(self, scene: &mut Scene) -> Option<ChannelMut<'_>> {
        match self.owner() {
            Ok(o) => {
                let a = &mut scene.objects.get_mut(o)?.attributes;
                Some(match self {
                    AttributeId::ObjectColour(_) => ChannelMut::Vec3(a.colour.as_mut()?),
                    AttributeId::ObjectVisible(_) => ChannelMut::Scalar(&mut a.visible),
                    AttributeId::ObjectOpacity(_) => ChannelMut::Scalar(&mut a.opacity),
                    AttributeId::MorphWeight { target, .. } => {
                        ChannelMut::Scalar(a.morph_weights.get_mut(target)?)
                    }
                    AttributeId::Deformer(_) => ChannelMut::Scalar(a.deformer.as_mut()?),
                    AttributeId::BlendParent(_) => ChannelMut::Scalar(a.blend_parent_fraction.as_mut()?),
                    AttributeId::BlendChild(_) => ChannelMut::Scalar(a.blend_child_fraction.as_mut()?),
                    _ => return None,
                })
            }
            Err(l) => {
                let a = &mut scene.lights.get_mut(l)?.attributes;
                Some(ChannelMut::Scalar(match self {
                    AttributeId::LightVisible(_) => &mut a.visible,
                    AttributeId::LightRange(_) => a.range.as_mut()?,
                    AttributeId::LightCutoff(_) => a.cutoff_deg.as_mut()?,
                    AttributeId::LightInnerAngle(_) => a.inner_angle_deg.as_mut()?,
                    _ => return None,
                }))
            }
        }
    }

    /// The range a value of this channel must lie in, with what it means; `None` for colour.
    #[must_use]
    pub fn value_range(self) -> Option<(f32, f32)> {
        match self {
            AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_) => Some((0.0, 1.0)),
            AttributeId::ObjectOpacity(_) | AttributeId::BlendParent(_) | AttributeId::BlendChild(_) => {
                Some((0.0, 1.0))
            }
            AttributeId::Deformer(_) => Some((0.0, (DeformerKind::ALL.len() - 1) as f32)),
            AttributeId::LightCutoff(_) | AttributeId::LightInnerAngle(_) => Some((0.0, 90.0)),
            AttributeId::LightRange(_) => Some((0.0, f32::INFINITY)),
            AttributeId::ObjectColour(_) | AttributeId::MorphWeight { .. } => None,
        }
    }

    /// True for switches: values are whole numbers and keys are Step (visibility, deformer).
    #[must_use]
    pub fn is_switch(self) -> bool {
        matches!(
            self,
            AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_) | AttributeId::Deformer(_)
        )
    }
}

/// The bones-blending zone channels of object `o` that are set.
fn push_blend_zone(a: &crate::attributes::ObjectAttributes, o: usize, out: &mut Vec<AttributeId>) {
    if a.blend_parent_fraction.is_some() {
        out.push(AttributeId::BlendParent(o));
    }
    if a.blend_child_fraction.is_some() {
        out.push(AttributeId::BlendChild(o));
    }
}

/// Every attribute channel of `scene`, listed or not (visibility and opacity of every object,
/// visibility of every light, the set ones): what validation and undo accounting walk.
#[must_use]
pub fn every(scene: &Scene) -> Vec<AttributeId> {
    let mut out = Vec::new();
    for (o, object) in scene.objects.iter().enumerate() {
        let a = &object.attributes;
        out.push(AttributeId::ObjectVisible(o));
        out.push(AttributeId::ObjectOpacity(o));
        if a.colour.is_some() {
            out.push(AttributeId::ObjectColour(o));
        }
        out.extend((0..a.morph_weights.len()).map(|target| AttributeId::MorphWeight { object: o, target }));
        if a.deformer.is_some() {
            out.push(AttributeId::Deformer(o));
        }
        push_blend_zone(a, o, &mut out);
    }
    for (l, light) in scene.lights.iter().enumerate() {
        let a = &light.attributes;
        out.push(AttributeId::LightVisible(l));
        for (set, id) in [
            (a.range.is_some(), AttributeId::LightRange(l)),
            (a.cutoff_deg.is_some(), AttributeId::LightCutoff(l)),
            (a.inner_angle_deg.is_some(), AttributeId::LightInnerAngle(l)),
        ] {
            if set {
                out.push(id);
            }
        }
    }
    out
}

/// The problems of one attribute channel beyond its track's (the track itself is checked by the
/// validator as every channel's): values out of range, switches with fractional values or keys
/// that are not Step, a spot cone on a light that is not a spot. `push(path, message)`.
pub(crate) fn attribute_problems(scene: &Scene, id: AttributeId, push: &mut dyn FnMut(String, String)) {
    let field = id.field_path();
    if matches!(id, AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_)) {
        if let Some(ChannelRef::Scalar(a)) = id.get(scene) {
            visibility_problems(&field, a, push);
        }
        return;
    }
    match id.get(scene) {
        Some(ChannelRef::Scalar(a)) => {
            let values = std::iter::once((format!("{field}.value"), a.value)).chain(
                a.track.keys.iter().enumerate().map(|(i, k)| (format!("{field}.track[{i}].value"), k.value)),
            );
            for (path, v) in values {
                if !v.is_finite() {
                    continue; // The track check reports it.
                }
                if let Some((lo, hi)) = id.value_range() {
                    let ok = if matches!(id, AttributeId::LightRange(_)) {
                        v > 0.0
                    } else {
                        (lo..=hi).contains(&v)
                    };
                    if !ok {
                        let what = match id {
                            AttributeId::LightRange(_) => "a range must be > 0".to_string(),
                            _ => format!("{} must be in [{lo}, {hi}]", id.channel_name()),
                        };
                        push(path.clone(), format!("{v}: {what}"));
                    }
                }
                if id.is_switch() && v.fract() != 0.0 {
                    push(path, format!("{v}: {} is a whole number (Step keys)", id.channel_name()));
                }
            }
            if id.is_switch() {
                for (i, k) in a.track.keys.iter().enumerate() {
                    if k.interpolation != Interpolation::Step {
                        push(
                            format!("{field}.track[{i}].interpolation"),
                            format!("{} keys are Step keys, not {:?}", id.channel_name(), k.interpolation),
                        );
                    }
                }
            }
        }
        Some(ChannelRef::Vec3(a)) => {
            let values = std::iter::once((format!("{field}.value"), a.value)).chain(
                a.track.keys.iter().enumerate().map(|(i, k)| (format!("{field}.track[{i}].value"), k.value)),
            );
            for (path, c) in values {
                if c.is_finite() && c.min_element() < 0.0 {
                    push(path, format!("negative colour component in {c}"));
                }
            }
        }
        Some(ChannelRef::Rotation(_)) | None => {}
    }
    if let AttributeId::LightCutoff(l) | AttributeId::LightInnerAngle(l) = id {
        if scene.lights.get(l).is_some_and(|light| !matches!(light.kind, LightKind::Spot { .. })) {
            push(field, format!("light {l} is not a spot light, so it has no cone"));
        }
    }
}

/// The problems of a visibility channel (of an object, a light or a scene camera) at `field`
/// beyond its track's: values other than 0 and 1, keys that are not Step.
pub(crate) fn visibility_problems(field: &str, a: &Animated<f32>, push: &mut dyn FnMut(String, String)) {
    let values = std::iter::once((format!("{field}.value"), a.value))
        .chain(a.track.keys.iter().enumerate().map(|(i, k)| (format!("{field}.track[{i}].value"), k.value)));
    for (path, v) in values {
        if !v.is_finite() {
            continue; // The track check reports it.
        }
        if !(0.0..=1.0).contains(&v) {
            push(path.clone(), format!("{v}: visible must be in [0, 1]"));
        }
        if v.fract() != 0.0 {
            push(path, format!("{v}: visible is a whole number (Step keys)"));
        }
    }
    for (i, k) in a.track.keys.iter().enumerate() {
        if k.interpolation != Interpolation::Step {
            push(
                format!("{field}.track[{i}].interpolation"),
                format!("visible keys are Step keys, not {:?}", k.interpolation),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::attributes::LightAttributes;
    use crate::channel::ChannelPath;
    use crate::channel_id::ChannelValue;
    use crate::key::{Key, RawTrack};
    use crate::scene::{Light, Object};
    use glam::Vec3;

    fn scene() -> Scene {
        let mut scene = Scene::default();
        let mut cube = Object::new("Cube");
        cube.attributes.visible = Animated::new(
            1.0,
            RawTrack::new(vec![
                Key::new(0.0, 1.0).with_interpolation(Interpolation::Step),
                Key::new(1.0, 0.0).with_interpolation(Interpolation::Step),
            ]),
        );
        cube.attributes.opacity = Animated::new(
            1.0,
            RawTrack::new(
                vec![Key::new(0.0, 1.0), Key::new(2.0, 0.0)]
                    .into_iter()
                    .map(|k| k.with_interpolation(Interpolation::Linear))
                    .collect(),
            ),
        );
        scene.objects.push(cube);
        scene.lights.push(Light {
            name: "Spot".into(),
            kind: LightKind::Spot { cutoff_deg: 30.0, inner_angle_deg: 20.0, dropoff: 1.0 },
            enabled: true,
            position: Animated::constant(Vec3::Y),
            direction: Animated::constant(Vec3::NEG_Y),
            colour: Animated::constant(Vec3::ONE),
            intensity: Animated::constant(1.0),
            attributes: LightAttributes {
                cutoff_deg: Some(Animated::constant(40.0)),
                ..LightAttributes::default()
            },
        });
        scene
    }

    #[test]
    fn paths_parse_resolve_and_sample() {
        let s = scene();
        let sample = |p: &str, t: f64| ChannelPath::parse(p).and_then(|c| c.resolve(&s)).map(|c| c.sample(t));
        assert_eq!(sample("object/Cube/visible", 0.5), Ok(ChannelValue::Scalar(1.0)));
        assert_eq!(sample("object/Cube/visible", 1.0), Ok(ChannelValue::Scalar(0.0)));
        assert_eq!(sample("object/Cube/opacity", 1.0), Ok(ChannelValue::Scalar(0.5)));
        assert_eq!(sample("light/Spot/cutoff_deg", 0.0), Ok(ChannelValue::Scalar(40.0)));
        assert_eq!(sample("light/Spot/visible", 0.0), Ok(ChannelValue::Scalar(1.0)));
        let err = sample("object/Cube/colour", 0.0).unwrap_err().to_string();
        assert!(err.contains("object \"Cube\" has no colour channel; it is set in the scene file as objects[0].attributes.colour"), "{err}");
        let err = sample("object/Cube/morph/2", 0.0).unwrap_err().to_string();
        assert!(err.contains("has no morph/2 channel (it keys 0 morph-target weights"), "{err}");
        for text in [
            "object/Cube/visible",
            "object/Cube/morph/3",
            "light/Spot/inner_angle_deg",
            "object/Cube/deformer",
            "object/Cube/blend_parent_fraction",
            "object/Cube/blend_child_fraction",
        ] {
            assert_eq!(ChannelPath::parse(text).map(|p| p.to_string()), Ok(text.to_string()));
        }
        // Listed: the keyed visibility and opacity, the set cone; not the default light visibility.
        let listed: Vec<String> = crate::channel::list_channels(&s).iter().map(ToString::to_string).collect();
        assert!(
            listed.contains(&"object/Cube/opacity".into())
                && listed.contains(&"light/Spot/cutoff_deg".into())
        );
        assert!(!listed.contains(&"light/Spot/visible".into()));
    }

    #[test]
    fn validation_of_switches_ranges_and_cones() {
        let mut s = scene();
        assert!(s.problems().is_empty(), "{:?}", s.problems());
        s.objects[0].attributes.visible.track.keys[1].value = 0.5;
        s.objects[0].attributes.visible.track.keys[0].interpolation = Interpolation::Linear;
        s.objects[0].attributes.opacity.value = 1.5;
        s.lights[0].kind = LightKind::Point;
        s.objects[0].attributes.deformer = Some(Animated::constant(7.0));
        s.objects[0].attributes.blend_parent_fraction =
            Some(Animated::new(0.25, RawTrack::new(vec![Key::new(0.0, 0.25), Key::new(1.0, -0.5)])));
        s.objects[0].attributes.blend_child_fraction = Some(Animated::constant(1.5));
        let problems: Vec<String> = s.problems().iter().map(ToString::to_string).collect();
        for expected in [
            "objects[0].attributes.visible.track[1].value: 0.5: visible is a whole number (Step keys)",
            "objects[0].attributes.visible.track[0].interpolation: visible keys are Step keys, not Linear",
            "objects[0].attributes.opacity.value: 1.5: opacity must be in [0, 1]",
            "objects[0].attributes.deformer.value: 7: deformer must be in [0, 3]",
            "objects[0].attributes.blend_parent_fraction.track[1].value: -0.5: blend zone (parent) must be in [0, 1]",
            "objects[0].attributes.blend_child_fraction.value: 1.5: blend zone (child) must be in [0, 1]",
            "lights[0].attributes.cutoff_deg: light 0 is not a spot light, so it has no cone",
        ] {
            assert!(problems.iter().any(|p| p == expected), "{expected}\n{problems:#?}");
        }
    }

    #[test]
    fn blend_zone_channels_exist_once_set() {
        let mut s = scene();
        let sample =
            |s: &Scene, p: &str| ChannelPath::parse(p).and_then(|c| c.resolve(s)).map(|c| c.sample(0.5));
        let err = sample(&s, "object/Cube/blend_child_fraction").unwrap_err().to_string();
        assert!(
            err.contains("has no blend_child_fraction channel; it is set in the scene file as objects[0].attributes.blend_child_fraction"),
            "{err}"
        );
        s.objects[0].attributes.blend_child_fraction =
            Some(Animated::new(0.1, RawTrack::new(vec![Key::new(0.0, 0.1), Key::new(1.0, 0.9)])));
        let listed: Vec<String> = crate::channel::list_channels(&s).iter().map(ToString::to_string).collect();
        assert!(listed.contains(&"object/Cube/blend_child_fraction".into()), "{listed:?}");
        assert!(!listed.contains(&"object/Cube/blend_parent_fraction".into()));
        match sample(&s, "object/Cube/blend_child_fraction") {
            Ok(ChannelValue::Scalar(v)) => assert!((v - 0.5).abs() < 1e-6, "{v}"),
            other => panic!("{other:?}"),
        }
        assert!(every(&s).contains(&AttributeId::BlendChild(0)));
        assert_eq!(AttributeId::BlendChild(0).field_path(), "objects[0].attributes.blend_child_fraction");
        assert!(!AttributeId::BlendChild(0).is_switch());
    }

    #[test]
    fn deformer_values_name_the_four_deformers() {
        for (i, kind) in DeformerKind::ALL.into_iter().enumerate() {
            assert_eq!(deformer_value(kind), i as f32);
            assert_eq!(deformer_from_value(i as f32), Some(kind));
        }
        assert_eq!(deformer_from_value(f32::NAN), None);
    }

    #[test]
    fn default_attributes_are_left_out_of_files() {
        let mut s = Scene::default();
        s.objects.push(Object::new("A"));
        let text = serde_json::to_string(&s).unwrap();
        assert!(!text.contains("attributes"), "{text}");
        let mut s2 = scene();
        s2.objects[0].attributes.opacity = Animated::constant(1.0);
        let text = serde_json::to_string(&s2).unwrap();
        let back: Scene = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s2);
    }
}
