//! The evaluator's attribute channels (keyrig-core's `attributes`): an object's visibility,
//! colour, opacity, morph weights, deformer and bones-blending zone; a light's visibility,
//! range and cone. An
//! object or light whose attributes are all default has no slots at all, so a scene without
//! attributes evaluates as before.

use glam::Vec3;
use keyrig_core::attribute_id::{deformer_from_value, AttributeId};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{DeformerKind, DeformerSettings, LightAttributes, LightKind, ObjectAttributes};
use keyrig_skin::BlendZone;

use super::{EvalProblem, Overrides, Slot};

/// How an object looks at a time: what its attribute channels give.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectLook {
    /// False: the object is not drawn.
    pub visible: bool,
    /// In [0, 1]; below 1 the object is blended over what is behind it.
    pub opacity: f32,
    /// Linear RGB replacing the mesh material's base colour; `None`: the mesh's own.
    pub colour: Option<Vec3>,
    /// The deformer at this time (the keyed one, else the object's setting).
    pub deformer: DeformerKind,
    /// Keyed morph-target weights by target; empty: the mesh's own weights.
    pub morph_weights: Vec<f32>,
    /// The bones-blending zone at this time while either of its fractions is keyed (each
    /// clamped to [0, 1]; the one not keyed is the object's setting); `None`: the object's
    /// setting, which its bindings were built for.
    pub blend_zone: Option<BlendZone>,
}

impl ObjectLook {
    pub(super) fn new(deformer: DeformerKind) -> Self {
        ObjectLook {
            visible: true,
            opacity: 1.0,
            colour: None,
            deformer,
            morph_weights: Vec::new(),
            blend_zone: None,
        }
    }
}

#[derive(Clone, Debug)]
pub(super) struct ObjectAttributeRig {
    visible: Slot<f32>,
    colour: Option<Slot<Vec3>>,
    opacity: Slot<f32>,
    morph: Vec<Slot<f32>>,
    deformer: Option<Slot<f32>>,
    blend_parent: Option<Slot<f32>>,
    blend_child: Option<Slot<f32>>,
}

fn id(a: AttributeId) -> ChannelId {
    ChannelId::Attribute(a)
}

fn scalar(overrides: &Overrides, a: AttributeId, slot: &Slot<f32>, time: f64) -> f32 {
    match overrides.get(&id(a)) {
        Some(ChannelValue::Scalar(v)) => *v,
        _ => slot.sample(time),
    }
}

impl ObjectAttributeRig {
    /// `None` when every attribute is default.
    pub(super) fn new(a: &ObjectAttributes, o: usize) -> Option<Box<Self>> {
        if a.is_default() {
            return None;
        }
        Some(Box::new(ObjectAttributeRig {
            visible: Slot::new(&a.visible, id(AttributeId::ObjectVisible(o))),
            colour: a.colour.as_ref().map(|c| Slot::new(c, id(AttributeId::ObjectColour(o)))),
            opacity: Slot::new(&a.opacity, id(AttributeId::ObjectOpacity(o))),
            morph: a
                .morph_weights
                .iter()
                .enumerate()
                .map(|(target, w)| Slot::new(w, id(AttributeId::MorphWeight { object: o, target })))
                .collect(),
            deformer: a.deformer.as_ref().map(|d| Slot::new(d, id(AttributeId::Deformer(o)))),
            blend_parent: a
                .blend_parent_fraction
                .as_ref()
                .map(|f| Slot::new(f, id(AttributeId::BlendParent(o)))),
            blend_child: a
                .blend_child_fraction
                .as_ref()
                .map(|f| Slot::new(f, id(AttributeId::BlendChild(o)))),
        }))
    }

    pub(super) fn channel_count(&self) -> usize {
        2 + usize::from(self.colour.is_some())
            + self.morph.len()
            + usize::from(self.deformer.is_some())
            + usize::from(self.blend_parent.is_some())
            + usize::from(self.blend_child.is_some())
    }

    /// Brings `rig` in step with `a`; returns the number of channels rebuilt.
    pub(super) fn refresh(rig: &mut Option<Box<Self>>, a: &ObjectAttributes, o: usize) -> usize {
        let same_shape = match rig.as_deref() {
            None => a.is_default(),
            Some(r) => {
                r.colour.is_some() == a.colour.is_some()
                    && r.morph.len() == a.morph_weights.len()
                    && r.deformer.is_some() == a.deformer.is_some()
                    && r.blend_parent.is_some() == a.blend_parent_fraction.is_some()
                    && r.blend_child.is_some() == a.blend_child_fraction.is_some()
            }
        };
        let Some(r) = rig.as_deref_mut().filter(|_| same_shape) else {
            *rig = Self::new(a, o);
            return rig.as_ref().map_or(0, |r| r.channel_count());
        };
        let mut n = usize::from(r.visible.refresh(&a.visible, id(AttributeId::ObjectVisible(o))))
            + usize::from(r.opacity.refresh(&a.opacity, id(AttributeId::ObjectOpacity(o))));
        if let (Some(slot), Some(c)) = (&mut r.colour, &a.colour) {
            n += usize::from(slot.refresh(c, id(AttributeId::ObjectColour(o))));
        }
        for (target, (slot, w)) in r.morph.iter_mut().zip(&a.morph_weights).enumerate() {
            n += usize::from(slot.refresh(w, id(AttributeId::MorphWeight { object: o, target })));
        }
        for (slot, v, at) in [
            (&mut r.deformer, &a.deformer, AttributeId::Deformer(o)),
            (&mut r.blend_parent, &a.blend_parent_fraction, AttributeId::BlendParent(o)),
            (&mut r.blend_child, &a.blend_child_fraction, AttributeId::BlendChild(o)),
        ] {
            if let (Some(slot), Some(v)) = (slot, v) {
                n += usize::from(slot.refresh(v, id(at)));
            }
        }
        n
    }

    pub(super) fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        let scalars = [&self.visible, &self.opacity]
            .into_iter()
            .chain(&self.morph)
            .chain(&self.deformer)
            .chain(&self.blend_parent)
            .chain(&self.blend_child);
        for p in scalars
            .filter_map(|s| s.problem.as_ref())
            .chain(self.colour.iter().filter_map(|c| c.problem.as_ref()))
        {
            f(p);
        }
    }

    /// Writes the look at `time` over `look` (its weights vector is reused).
    pub(super) fn fill(
        rig: Option<&Self>,
        o: usize,
        time: f64,
        overrides: &Overrides,
        settings: &DeformerSettings,
        look: &mut ObjectLook,
    ) {
        let setting = settings.kind;
        look.morph_weights.clear();
        let Some(r) = rig else {
            look.visible = true;
            look.opacity = 1.0;
            look.colour = None;
            look.deformer = setting;
            look.blend_zone = None;
            // Overrides of attributes that are not set yet (a slider dragged before keying).
            if overrides.is_empty() {
                return;
            }
            if let Some(ChannelValue::Scalar(v)) = overrides.get(&id(AttributeId::ObjectVisible(o))) {
                look.visible = *v >= 0.5;
            }
            if let Some(ChannelValue::Scalar(v)) = overrides.get(&id(AttributeId::ObjectOpacity(o))) {
                look.opacity = v.clamp(0.0, 1.0);
            }
            return;
        };
        look.visible = scalar(overrides, AttributeId::ObjectVisible(o), &r.visible, time) >= 0.5;
        let opacity = scalar(overrides, AttributeId::ObjectOpacity(o), &r.opacity, time);
        look.opacity = if opacity.is_nan() { 1.0 } else { opacity.clamp(0.0, 1.0) };
        look.colour = r.colour.as_ref().map(|slot| match overrides.get(&id(AttributeId::ObjectColour(o))) {
            Some(ChannelValue::Vec3(v)) => *v,
            _ => slot.sample(time),
        });
        look.morph_weights.extend(r.morph.iter().enumerate().map(|(target, slot)| {
            scalar(overrides, AttributeId::MorphWeight { object: o, target }, slot, time)
        }));
        look.deformer = r
            .deformer
            .as_ref()
            .and_then(|slot| deformer_from_value(scalar(overrides, AttributeId::Deformer(o), slot, time)))
            .unwrap_or(setting);
        let fraction = |slot: &Option<Slot<f32>>, a: AttributeId, setting: f32| match slot {
            Some(slot) => {
                let v = scalar(overrides, a, slot, time);
                if v.is_nan() {
                    setting
                } else {
                    v.clamp(0.0, 1.0)
                }
            }
            None => setting,
        };
        look.blend_zone = (r.blend_parent.is_some() || r.blend_child.is_some()).then(|| BlendZone {
            parent_fraction: fraction(
                &r.blend_parent,
                AttributeId::BlendParent(o),
                settings.blend_parent_fraction,
            ),
            child_fraction: fraction(
                &r.blend_child,
                AttributeId::BlendChild(o),
                settings.blend_child_fraction,
            ),
        });
    }

    /// The value of one of these channels at `time` (no overrides).
    pub(super) fn value(rig: Option<&Self>, a: AttributeId, time: f64) -> Option<ChannelValue> {
        let Some(r) = rig else {
            // Unset rigs hold the defaults: shown and opaque.
            return matches!(a, AttributeId::ObjectVisible(_) | AttributeId::ObjectOpacity(_))
                .then_some(ChannelValue::Scalar(1.0));
        };
        Some(match a {
            AttributeId::ObjectVisible(_) => ChannelValue::Scalar(r.visible.sample(time)),
            AttributeId::ObjectOpacity(_) => ChannelValue::Scalar(r.opacity.sample(time)),
            AttributeId::ObjectColour(_) => ChannelValue::Vec3(r.colour.as_ref()?.sample(time)),
            AttributeId::MorphWeight { target, .. } => {
                ChannelValue::Scalar(r.morph.get(target)?.sample(time))
            }
            AttributeId::Deformer(_) => ChannelValue::Scalar(r.deformer.as_ref()?.sample(time)),
            AttributeId::BlendParent(_) => ChannelValue::Scalar(r.blend_parent.as_ref()?.sample(time)),
            AttributeId::BlendChild(_) => ChannelValue::Scalar(r.blend_child.as_ref()?.sample(time)),
            _ => return None,
        })
    }
}

#[derive(Clone, Debug)]
pub(super) struct LightAttributeRig {
    visible: Slot<f32>,
    range: Option<Slot<f32>>,
    cutoff: Option<Slot<f32>>,
    inner: Option<Slot<f32>>,
}

impl LightAttributeRig {
    pub(super) fn new(a: &LightAttributes, l: usize) -> Option<Box<Self>> {
        if a.is_default() {
            return None;
        }
        let slot = |v: &Option<keyrig_core::Animated<f32>>, at: AttributeId| {
            v.as_ref().map(|v| Slot::new(v, id(at)))
        };
        Some(Box::new(LightAttributeRig {
            visible: Slot::new(&a.visible, id(AttributeId::LightVisible(l))),
            range: slot(&a.range, AttributeId::LightRange(l)),
            cutoff: slot(&a.cutoff_deg, AttributeId::LightCutoff(l)),
            inner: slot(&a.inner_angle_deg, AttributeId::LightInnerAngle(l)),
        }))
    }

    fn channel_count(&self) -> usize {
        1 + usize::from(self.range.is_some())
            + usize::from(self.cutoff.is_some())
            + usize::from(self.inner.is_some())
    }

    pub(super) fn refresh(rig: &mut Option<Box<Self>>, a: &LightAttributes, l: usize) -> usize {
        let same_shape = match rig.as_deref() {
            None => a.is_default(),
            Some(r) => {
                r.range.is_some() == a.range.is_some()
                    && r.cutoff.is_some() == a.cutoff_deg.is_some()
                    && r.inner.is_some() == a.inner_angle_deg.is_some()
            }
        };
        let Some(r) = rig.as_deref_mut().filter(|_| same_shape) else {
            *rig = Self::new(a, l);
            return rig.as_ref().map_or(0, |r| r.channel_count());
        };
        let mut n = usize::from(r.visible.refresh(&a.visible, id(AttributeId::LightVisible(l))));
        for (slot, v, at) in [
            (&mut r.range, &a.range, AttributeId::LightRange(l)),
            (&mut r.cutoff, &a.cutoff_deg, AttributeId::LightCutoff(l)),
            (&mut r.inner, &a.inner_angle_deg, AttributeId::LightInnerAngle(l)),
        ] {
            if let (Some(slot), Some(v)) = (slot, v) {
                n += usize::from(slot.refresh(v, id(at)));
            }
        }
        n
    }

    pub(super) fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        let slots = std::iter::once(&self.visible).chain(&self.range).chain(&self.cutoff).chain(&self.inner);
        for p in slots.filter_map(|s| s.problem.as_ref()) {
            f(p);
        }
    }

    /// Visibility, range and the kind with its keyed cone at `time`.
    pub(super) fn apply(
        rig: Option<&Self>,
        l: usize,
        time: f64,
        overrides: &Overrides,
        kind: LightKind,
    ) -> (bool, Option<f32>, LightKind) {
        let Some(r) = rig else {
            if overrides.is_empty() {
                return (true, None, kind);
            }
            let visible = match overrides.get(&id(AttributeId::LightVisible(l))) {
                Some(ChannelValue::Scalar(v)) => *v >= 0.5,
                _ => true,
            };
            return (visible, None, kind);
        };
        let visible = scalar(overrides, AttributeId::LightVisible(l), &r.visible, time) >= 0.5;
        let range = r.range.as_ref().map(|s| scalar(overrides, AttributeId::LightRange(l), s, time));
        let kind = match kind {
            LightKind::Spot { cutoff_deg, inner_angle_deg, dropoff } => {
                let cutoff = r
                    .cutoff
                    .as_ref()
                    .map_or(cutoff_deg, |s| scalar(overrides, AttributeId::LightCutoff(l), s, time));
                let inner = r
                    .inner
                    .as_ref()
                    .map_or(inner_angle_deg, |s| scalar(overrides, AttributeId::LightInnerAngle(l), s, time));
                LightKind::Spot { cutoff_deg: cutoff, inner_angle_deg: inner.min(cutoff), dropoff }
            }
            other => other,
        };
        (visible, range, kind)
    }

    pub(super) fn value(rig: Option<&Self>, a: AttributeId, time: f64) -> Option<ChannelValue> {
        let Some(r) = rig else {
            return matches!(a, AttributeId::LightVisible(_)).then_some(ChannelValue::Scalar(1.0));
        };
        let slot = match a {
            AttributeId::LightVisible(_) => &r.visible,
            AttributeId::LightRange(_) => r.range.as_ref()?,
            AttributeId::LightCutoff(_) => r.cutoff.as_ref()?,
            AttributeId::LightInnerAngle(_) => r.inner.as_ref()?,
            _ => return None,
        };
        Some(ChannelValue::Scalar(slot.sample(time)))
    }
}
