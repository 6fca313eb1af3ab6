//! A channel's runtime form in the evaluator ([`Slot`]): its validated track, or its static
//! value when the keys are invalid, with the problem; and the pose overrides that win over it.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::track::TrackValue;
use keyrig_core::{Animated, AnimatedTrack, Keys};

/// Values set on channels without keys being written (a gizmo drag, a slider), keyed by the
/// channel they replace: the evaluator shows them instead of the channel's track.
pub type Overrides = HashMap<ChannelId, ChannelValue>;

/// Something the evaluator could not take from the scene, with the field path it concerns
/// (`objects[0].skeleton.joints[2].rotation.track[1].time`). The scene still evaluates: a
/// channel whose keys are invalid holds its static value, an object whose skeleton or mesh is
/// invalid is drawn without skinning.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EvalProblem {
    pub path: String,
    pub message: String,
}

impl fmt::Display for EvalProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

/// A channel's validated track, or its static value when its keys are invalid.
#[derive(Debug)]
pub(crate) enum SlotEval<T: TrackValue> {
    Track(AnimatedTrack<T>),
    Fallback(T),
}

/// One channel: what it was built from (the shared keys and the static value), its evaluable
/// form and the problem that made it fall back. Cloning shares the evaluable form.
#[derive(Clone, Debug)]
pub(crate) struct Slot<T: TrackValue> {
    keys: Keys<T>,
    value: T,
    cycles: keyrig_core::Cycles,
    muted: bool,
    pub(crate) eval: Arc<SlotEval<T>>,
    pub(crate) problem: Option<EvalProblem>,
}

impl<T: TrackValue> Slot<T> {
    pub(crate) fn new(animated: &Animated<T>, id: ChannelId) -> Self {
        let (eval, problem) = match AnimatedTrack::new(animated) {
            Ok(track) => (SlotEval::Track(track), None),
            Err(e) => (
                SlotEval::Fallback(animated.value),
                Some(EvalProblem {
                    path: keyrig_core::validate::track_error_path(&id.field_path(), &e),
                    message: e.to_string(),
                }),
            ),
        };
        Slot {
            keys: animated.track.keys.clone(),
            value: animated.value,
            cycles: animated.cycles(),
            muted: animated.muted,
            eval: Arc::new(eval),
            problem,
        }
    }

    /// Rebuilds the slot when its channel changed (its keys are no longer the list it was
    /// built from, or its static value or its cycles differ); true when it did.
    pub(crate) fn refresh(&mut self, animated: &Animated<T>, id: ChannelId) -> bool {
        if self.keys.shares_with(&animated.track.keys)
            && self.value == animated.value
            && self.cycles == animated.cycles()
            && self.muted == animated.muted
        {
            return false;
        }
        *self = Slot::new(animated, id);
        true
    }

    /// The channel's static value (what it holds without keys).
    pub(crate) fn static_value(&self) -> T {
        self.value
    }

    /// True when the channel has keys.
    pub(crate) fn is_keyed(&self) -> bool {
        !self.keys.is_empty()
    }

    #[inline]
    pub(crate) fn sample(&self, t: f64) -> T {
        match &*self.eval {
            SlotEval::Track(track) => track.sample(t),
            SlotEval::Fallback(v) => *v,
        }
    }
}

/// A rotation channel: its quaternion keys, or its Euler keys (x, y, z degrees, each
/// interpolated on its own) turned in their order (docs/channels.md, "Euler keys").
#[derive(Clone, Debug)]
pub(crate) enum RotationSlot {
    Quat(Slot<glam::Quat>),
    Euler(Slot<glam::Vec3>, keyrig_core::EulerOrder),
}

impl RotationSlot {
    /// The slot of rotation channel `id` (`ObjectRotation` or `JointRotation`) whose keys are
    /// `rotation`, or `euler` in `mode`'s order when it has Euler keys.
    pub(crate) fn new(
        rotation: &Animated<glam::Quat>,
        euler: Option<&Animated<glam::Vec3>>,
        mode: keyrig_core::RotationMode,
        id: ChannelId,
    ) -> Self {
        match (euler, keyrig_core::channel_id::euler_partner(id)) {
            (Some(euler), Some(euler_id)) => {
                RotationSlot::Euler(Slot::new(euler, euler_id), mode.euler().unwrap_or_default())
            }
            _ => RotationSlot::Quat(Slot::new(rotation, id)),
        }
    }

    /// Rebuilds the slot when its channel changed (as [`Slot::refresh`], or it switched between
    /// quaternion and Euler keys or changed order); true when it did.
    pub(crate) fn refresh(
        &mut self,
        rotation: &Animated<glam::Quat>,
        euler: Option<&Animated<glam::Vec3>>,
        mode: keyrig_core::RotationMode,
        id: ChannelId,
    ) -> bool {
        match (&mut *self, euler, keyrig_core::channel_id::euler_partner(id)) {
            (RotationSlot::Quat(slot), None, _) => slot.refresh(rotation, id),
            (RotationSlot::Euler(slot, order), Some(euler), Some(euler_id))
                if Some(*order) == mode.euler() =>
            {
                slot.refresh(euler, euler_id)
            }
            _ => {
                *self = RotationSlot::new(rotation, euler, mode, id);
                true
            }
        }
    }

    #[inline]
    pub(crate) fn sample(&self, t: f64) -> glam::Quat {
        match self {
            RotationSlot::Quat(slot) => slot.sample(t),
            RotationSlot::Euler(slot, order) => order.to_quat(slot.sample(t)),
        }
    }

    /// The rotation without keys.
    pub(crate) fn static_value(&self) -> glam::Quat {
        match self {
            RotationSlot::Quat(slot) => slot.static_value(),
            RotationSlot::Euler(slot, order) => order.to_quat(slot.static_value()),
        }
    }

    /// True when the rotation has keys (quaternion or Euler).
    pub(crate) fn is_keyed(&self) -> bool {
        match self {
            RotationSlot::Quat(slot) => slot.is_keyed(),
            RotationSlot::Euler(slot, _) => slot.is_keyed(),
        }
    }

    /// The Euler angles at `t` and their order; `None` for quaternion keys.
    pub(crate) fn angles(&self, t: f64) -> Option<(glam::Vec3, keyrig_core::EulerOrder)> {
        match self {
            RotationSlot::Quat(_) => None,
            RotationSlot::Euler(slot, order) => Some((slot.sample(t), *order)),
        }
    }

    /// The quaternion slot (spin keys live there); `None` for Euler keys.
    pub(crate) fn quat(&self) -> Option<&Slot<glam::Quat>> {
        match self {
            RotationSlot::Quat(slot) => Some(slot),
            RotationSlot::Euler(..) => None,
        }
    }

    pub(crate) fn problem(&self) -> &Option<EvalProblem> {
        match self {
            RotationSlot::Quat(slot) => &slot.problem,
            RotationSlot::Euler(slot, _) => &slot.problem,
        }
    }
}
