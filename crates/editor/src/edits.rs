//! The document edits the panels push ([`Edit`]), applied by [`EditorApp::apply_edit`]: pose
//! changes (keys in record mode, overrides, static values), turns with their spins, IK poses,
//! and the key moves the dope sheet and the curve editor share. Each is one undo step, or part
//! of its gesture's continuous step.

use std::collections::{BTreeMap, BTreeSet};

use glam::Quat;

use crate::actions::Edit;
use crate::app::{EditorApp, IK_DRAG_GROUP};
use crate::eval::continuous_euler;
use crate::session::KeyRef;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};

impl EditorApp {
    /// Applies one edit the panels pushed.
    pub(crate) fn apply_edit(&mut self, edit: Edit) {
        match edit {
            Edit::Pose { id, value, group } => self.apply_pose(id, value, &group),
            Edit::PlaceKeys { id, keys, rest, group } => self.apply_place_keys(id, &keys, rest, &group),
            Edit::Turn { id, turn, group } => self.apply_turn(id, turn, &group),
            Edit::IkPose { rotations, label } => self.apply_ik_pose(&rotations, &label),
            Edit::MoveSelectedKeys { seconds, ticket } => {
                let moved = self.move_selected_keys(seconds);
                self.results.record(ticket, moved);
            }
            Edit::ShiftSelectedValues { component, delta, twist } => {
                self.shift_selected_values(component, delta, twist);
            }
            Edit::Scene { edit, group } => {
                let label = edit.label(self.doc.scene());
                match group {
                    Some(group) => {
                        self.doc.edit_continuous_renamed(&group, &label, |scene| edit.apply(scene))
                    }
                    None => self.doc.edit(&label, |scene| edit.apply(scene)),
                };
            }
        }
    }

    /// Applies a pose change made with a gizmo or the inspector. In record mode it writes a key
    /// at the current frame; otherwise an animated channel gets a transient override (key it
    /// with I) and a static one changes its value. `group` merges a drag into one undo step.
    pub fn apply_pose(&mut self, id: ChannelId, value: ChannelValue, group: &str) {
        let (id, value) = self.keys_channel(id, value, None);
        let animated = channels::key_count(self.doc.scene(), id) > 0;
        if self.session.record {
            let time = self.session.key_time(self.doc.scene().fps);
            let label = format!("key {}", id.label(self.doc.scene()));
            let with = self.keyed_with(&[id]);
            self.doc.edit_continuous(group, &label, |scene| {
                channels::set_key(scene, id, time, value);
                for &(c, v) in &with {
                    channels::set_key(scene, c, time, v);
                }
            });
            self.session.overrides.remove(&id);
            for (c, _) in &with {
                self.session.overrides.remove(c);
            }
        } else if animated {
            self.session.overrides.insert(id, value);
        } else {
            let label = format!("pose {}", id.label(self.doc.scene()));
            self.doc.edit_continuous(group, &label, |scene| {
                channels::set_static_value(scene, id, value);
            });
        }
    }

    /// Moves the keys of translation channel `id` to the values of `keys` (a key at each of
    /// their times keeps its interpolation) and its static value to `rest`: a copy placed by
    /// Shift+D's grab takes its whole motion along, in record mode or not, and no pose override
    /// is left on the channel.
    pub fn apply_place_keys(
        &mut self,
        id: ChannelId,
        keys: &[(f64, glam::Vec3)],
        rest: glam::Vec3,
        group: &str,
    ) {
        let label = format!("place {}", id.label(self.doc.scene()));
        self.doc.edit_continuous(group, &label, |scene| {
            for &(time, value) in keys {
                channels::set_key(scene, id, time, ChannelValue::Vec3(value));
            }
            channels::set_static_value(scene, id, ChannelValue::Vec3(rest));
        });
        self.session.overrides.remove(&id);
    }

    /// Applies the rotations an IK drag solved for the joints of a chain, as
    /// [`EditorApp::apply_pose`] applies a gizmo rotation, all joints in one edit: in record mode
    /// each joint gets an ordinary rotation key at the current frame; otherwise keyed joints get
    /// pose overrides and unkeyed ones change their value. Every call of one drag joins one undo
    /// step ([`IK_DRAG_GROUP`], closed when the pointer is released), labelled `label`.
    pub fn apply_ik_pose(&mut self, rotations: &[(ChannelId, Quat)], label: &str) {
        let values: Vec<(ChannelId, ChannelValue)> = rotations
            .iter()
            .map(|&(id, q)| self.keys_channel(id, ChannelValue::Rotation(q.normalize()), None))
            .collect();
        if self.session.record {
            let time = self.session.key_time(self.doc.scene().fps);
            let ids: Vec<ChannelId> = values.iter().map(|&(id, _)| id).collect();
            let with = self.keyed_with(&ids);
            self.doc.edit_continuous(IK_DRAG_GROUP, label, |scene| {
                for &(id, value) in values.iter().chain(&with) {
                    channels::set_key(scene, id, time, value);
                }
            });
            for (id, _) in values.iter().chain(&with) {
                self.session.overrides.remove(id);
            }
            return;
        }
        let (animated, fixed): (Vec<_>, Vec<_>) =
            values.into_iter().partition(|(id, _)| channels::key_count(self.doc.scene(), *id) > 0);
        if !fixed.is_empty() {
            self.doc.edit_continuous(IK_DRAG_GROUP, label, |scene| {
                for &(id, value) in &fixed {
                    channels::set_static_value(scene, id, value);
                }
            });
        }
        for (id, value) in animated {
            self.session.overrides.insert(id, value);
        }
    }

    /// Applies a rotation turned with a gizmo ring or the inspector's twist field: the value
    /// `turn.value()` as [`EditorApp::apply_pose`] would, but in record mode the key also gets
    /// the spin that makes its segment from the previous key turn the way the hand went, turns
    /// included ([`channels::set_rotation_key`]).
    pub fn apply_turn(&mut self, id: ChannelId, turn: channels::Turn, group: &str) {
        let value = turn.value();
        // Euler keys: the angles follow the hand through the turn (no spin to write).
        if let (euler, e @ ChannelValue::Vec3(_)) =
            self.keys_channel(id, ChannelValue::Rotation(value), Some(turn))
        {
            self.apply_pose(euler, e, group);
            return;
        }
        if !self.session.record {
            self.apply_pose(id, ChannelValue::Rotation(value), group);
            return;
        }
        let time = self.session.key_time(self.doc.scene().fps);
        let label = format!("key {}", id.label(self.doc.scene()));
        let with = self.keyed_with(&[id]);
        self.doc.edit_continuous(group, &label, |scene| {
            channels::set_rotation_key(scene, id, time, value, Some(turn));
            for &(c, v) in &with {
                channels::set_key(scene, c, time, v);
            }
        });
        self.session.overrides.remove(&id);
        for (c, _) in &with {
            self.session.overrides.remove(c);
        }
    }

    /// The channel that holds `id`'s keys and `value` as it takes it: a rotation of an object or
    /// joint with Euler keys goes to its Euler-keys channel as the angles nearest the ones shown
    /// now (through `turn` when given; [`channels::euler_target`]); anything else as it is.
    pub(crate) fn keys_channel(
        &self,
        id: ChannelId,
        value: ChannelValue,
        turn: Option<channels::Turn>,
    ) -> (ChannelId, ChannelValue) {
        let scene = self.doc.scene();
        let Some(euler) = keyrig_core::channel_id::euler_partner(id)
            .filter(|_| id.kind() == channels::ChannelKind::Rotation)
        else {
            return (id, value);
        };
        let near = match self.value_now(euler) {
            Some(ChannelValue::Vec3(e)) => Some(e),
            _ => None,
        };
        match channels::euler_target(scene, id, value, near, self.time(), turn) {
            Some((euler, e)) => (euler, ChannelValue::Vec3(e)),
            None => (id, value),
        }
    }

    /// In record mode, what is keyed together with the channels `ids` a pose change keys: the
    /// active keying set's other channels of their items ([`KeyingSet::companions`]: a whole
    /// character's joints, or an object's location and scale with its rotation) at their
    /// values now; nothing with the default set.
    ///
    /// [`KeyingSet::companions`]: crate::keying_sets::KeyingSet::companions
    fn keyed_with(&self, ids: &[ChannelId]) -> Vec<(ChannelId, ChannelValue)> {
        let set = self.session.keying_set;
        let scene = self.doc.scene();
        let mut with: Vec<ChannelId> = Vec::new();
        for &id in ids {
            for c in set.companions(scene, id) {
                if !ids.contains(&c) && !with.contains(&c) {
                    with.push(c);
                }
            }
        }
        with.into_iter().filter_map(|c| self.value_now(c).map(|v| (c, v))).collect()
    }

    /// Moves every selected key by `delta` seconds as one continuous edit. Refused (returns
    /// false) when a key would land on another key.
    pub fn move_selected_keys(&mut self, delta: f64) -> bool {
        let mut by_channel: BTreeMap<ChannelId, Vec<usize>> = BTreeMap::new();
        for k in &self.session.selection.keys {
            by_channel.entry(k.channel).or_default().push(k.index);
        }
        let mut trial = self.doc.scene().clone();
        let mut new_keys = BTreeSet::new();
        for (id, indices) in &by_channel {
            match channels::move_keys(&mut trial, *id, indices, delta) {
                Some(new_indices) => {
                    new_keys.extend(new_indices.into_iter().map(|index| KeyRef { channel: *id, index }));
                }
                None => return false,
            }
        }
        self.doc.edit_continuous("move keys", "move keys", |scene| *scene = trial);
        self.session.selection.keys = new_keys;
        true
    }

    /// Adds `delta` to component `component` of every selected key (an Euler angle for
    /// rotations, degrees; with `twist`, the twist about the bone axis) as one continuous edit.
    pub fn shift_selected_values(&mut self, component: usize, delta: f32, twist: bool) {
        let keys: Vec<KeyRef> = self.session.selection.keys.iter().copied().collect();
        let label = if keys.len() == 1 {
            "move key value".to_owned()
        } else {
            format!("move {} key values", keys.len())
        };
        // Each rotation key as the curves read it: its rotation mode and its Euler angles,
        // continuous from the channel's first key (so a component moves the way it is drawn).
        let readings: Vec<(keyrig_core::RotationMode, Option<glam::Vec3>)> = {
            let scene = self.doc.scene();
            let eval = self.evaluator();
            let none = crate::eval::PoseOverrides::new();
            keys.iter()
                .map(|k| {
                    let mode = keyrig_core::channel_id::rotation_mode(scene, k.channel);
                    let time = channels::key_params(scene, k.channel, k.index).map(|p| p.0);
                    let euler = match (mode.euler(), time) {
                        (Some(order), Some(time)) if k.channel.kind() == channels::ChannelKind::Rotation => {
                            continuous_euler(&eval, scene, k.channel, order, time, &none)
                        }
                        _ => None,
                    };
                    (mode, euler)
                })
                .collect()
        };
        self.doc.edit_continuous("curve value", &label, |scene| {
            for (k, (mode, euler)) in keys.iter().zip(readings) {
                let Some((time, _, _)) = channels::key_params(scene, k.channel, k.index) else { continue };
                let Some(value) = channels::key_value(scene, k.channel, k.index) else { continue };
                let moved = match value {
                    ChannelValue::Vec3(mut v) if component < 3 => {
                        v[component] += delta;
                        ChannelValue::Vec3(v)
                    }
                    ChannelValue::Scalar(s) if component == 0 => ChannelValue::Scalar(s + delta),
                    ChannelValue::Rotation(q) if twist && component == 0 => {
                        // A twist about the bone axis, in the key's own frame.
                        let turn = Quat::from_axis_angle(keyrig_edit::spin::BONE_AXIS, delta.to_radians());
                        ChannelValue::Rotation((q * turn).normalize())
                    }
                    ChannelValue::Rotation(q) if !twist => match mode.euler() {
                        Some(order) if component < 3 => {
                            let mut e = euler.map_or_else(|| order.angles(q), |e| order.angles_near(q, e));
                            e[component] += delta;
                            ChannelValue::Rotation(order.to_quat(e))
                        }
                        None if component < 4 => {
                            // w, x, y, z as the curves draw them.
                            let mut v = [q.w, q.x, q.y, q.z];
                            v[component] += delta;
                            let moved = Quat::from_xyzw(v[1], v[2], v[3], v[0]);
                            if moved.length() < 1e-6 {
                                continue;
                            }
                            ChannelValue::Rotation(moved.normalize())
                        }
                        _ => continue,
                    },
                    _ => continue,
                };
                channels::set_key(scene, k.channel, time, moved);
            }
        });
    }
}
