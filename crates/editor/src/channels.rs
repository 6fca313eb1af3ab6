//! Channels: the animated values of a scene, addressed by [`ChannelId`], and the key
//! operations the timeline and inspector perform on them (insert, delete, move, copy, TCB).
//!
//! These functions only change a [`Scene`]; the editor calls them through
//! [`crate::state::Document::edit`] so every change is undoable.

use keyrig_core::{Interpolation, Key, RawTrack, Scene, Tcb};

pub use keyrig_core::channel_id::{
    channel, channel_mut, ChannelId, ChannelKind, ChannelMut, ChannelRef, ChannelValue,
};

/// A copy of one key with its value type erased (clipboard).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KeyCopy {
    pub channel: ChannelId,
    pub time: f64,
    pub value: ChannelValue,
    pub interpolation: Interpolation,
    pub tcb: Tcb,
}

/// The first line of keys copied to the system clipboard; JSON of the keys follows.
pub const CLIPBOARD_HEADER: &str = "keyrig keys 1";

/// Copied keys as text for the system clipboard: [`CLIPBOARD_HEADER`], a newline, then the
/// keys as JSON (another keyrig window pastes them with [`keys_from_clipboard_text`]).
#[must_use]
pub fn keys_to_clipboard_text(keys: &[KeyCopy]) -> String {
    // Serializing plain numbers and enums cannot fail; an empty list is the fallback.
    let json = serde_json::to_string(keys).unwrap_or_else(|_| "[]".to_owned());
    format!("{CLIPBOARD_HEADER}\n{json}")
}

/// Keys from system clipboard text written by [`keys_to_clipboard_text`]; `None` for any
/// other text (or keys with non-finite times or values).
#[must_use]
pub fn keys_from_clipboard_text(text: &str) -> Option<Vec<KeyCopy>> {
    let (header, json) = text.trim_start().split_once('\n')?;
    if header.trim() != CLIPBOARD_HEADER {
        return None;
    }
    let keys: Vec<KeyCopy> = serde_json::from_str(json).ok()?;
    let finite = |k: &KeyCopy| {
        k.time.is_finite()
            && match k.value {
                ChannelValue::Vec3(v) => v.is_finite(),
                ChannelValue::Rotation(q) => q.is_finite() && q.length_squared() > 0.0,
                ChannelValue::Scalar(s) => s.is_finite(),
            }
    };
    keys.iter().all(finite).then_some(keys)
}

/// Calls `$body` with `$track` bound to the `&RawTrack<_>` of a [`ChannelRef`].
macro_rules! with_track {
    ($chan:expr, $track:ident => $body:expr) => {
        match $chan {
            ChannelRef::Vec3(a) => {
                let $track = &a.track;
                $body
            }
            ChannelRef::Rotation(a) => {
                let $track = &a.track;
                $body
            }
            ChannelRef::Scalar(a) => {
                let $track = &a.track;
                $body
            }
        }
    };
}

/// Calls `$body` with `$track` bound to the `&mut RawTrack<_>` of a [`ChannelMut`].
macro_rules! with_track_mut {
    ($chan:expr, $track:ident => $body:expr) => {
        match $chan {
            ChannelMut::Vec3(a) => {
                let $track = &mut a.track;
                $body
            }
            ChannelMut::Rotation(a) => {
                let $track = &mut a.track;
                $body
            }
            ChannelMut::Scalar(a) => {
                let $track = &mut a.track;
                $body
            }
        }
    };
}

/// Key times (seconds) of a channel, in storage order.
#[must_use]
pub fn key_times(scene: &Scene, id: ChannelId) -> Vec<f64> {
    match channel(scene, id) {
        Some(c) => with_track!(c, t => t.keys.iter().map(|k| k.time).collect()),
        None => Vec::new(),
    }
}

/// Number of keys of a channel (0 when it does not exist).
#[must_use]
pub fn key_count(scene: &Scene, id: ChannelId) -> usize {
    match channel(scene, id) {
        Some(c) => with_track!(c, t => t.len()),
        None => 0,
    }
}

/// Interpolation mode and TCB of one key.
#[must_use]
pub fn key_params(scene: &Scene, id: ChannelId, index: usize) -> Option<(f64, Interpolation, Tcb)> {
    let c = channel(scene, id)?;
    with_track!(c, t => t.keys.get(index).map(|k| (k.time, k.interpolation, k.tcb)))
}

/// Sets the interpolation mode and TCB of one key. Returns false when the key does not exist.
pub fn set_key_params(scene: &mut Scene, id: ChannelId, index: usize, mode: Interpolation, tcb: Tcb) -> bool {
    let Some(c) = channel_mut(scene, id) else { return false };
    with_track_mut!(c, t => match t.keys.get_mut(index) {
        Some(k) => {
            k.interpolation = mode;
            k.tcb = tcb;
            true
        }
        None => false,
    })
}

/// Index of the key at `time` (within half a millisecond), if any.
#[must_use]
pub fn key_at(scene: &Scene, id: ChannelId, time: f64) -> Option<usize> {
    key_times(scene, id).iter().position(|&t| (t - time).abs() < TIME_EPS)
}

/// Two key times closer than this are the same frame.
pub const TIME_EPS: f64 = 5e-4;

fn insert_sorted<T: Clone>(track: &mut RawTrack<T>, key: Key<T>) -> usize {
    if let Some(i) = track.keys.iter().position(|k| (k.time - key.time).abs() < TIME_EPS) {
        // Keep the existing key's interpolation settings, replace its value.
        let old = &mut track.keys[i];
        old.value = key.value;
        return i;
    }
    let i = track.keys.iter().position(|k| k.time > key.time).unwrap_or(track.keys.len());
    track.keys.insert(i, key);
    i
}

/// Writes a key with `value` at `time` (replacing the value of a key already there). When the
/// channel had no keys and `value` differs from its pose, the pose is kept as its static value.
/// Returns the key's index, or `None` when the channel does not exist or the value type does not
/// match.
pub fn set_key(scene: &mut Scene, id: ChannelId, time: f64, value: ChannelValue) -> Option<usize> {
    match (channel_mut(scene, id)?, value) {
        (ChannelMut::Vec3(a), ChannelValue::Vec3(v)) => Some(insert_sorted(&mut a.track, Key::new(time, v))),
        (ChannelMut::Rotation(a), ChannelValue::Rotation(q)) => {
            Some(insert_sorted(&mut a.track, Key::new(time, q.normalize())))
        }
        (ChannelMut::Scalar(a), ChannelValue::Scalar(s)) => {
            Some(insert_sorted(&mut a.track, Key::new(time, s)))
        }
        _ => None,
    }
}

/// Sets the static value (the pose used while the channel has no keys).
pub fn set_static_value(scene: &mut Scene, id: ChannelId, value: ChannelValue) -> bool {
    match (channel_mut(scene, id), value) {
        (Some(ChannelMut::Vec3(a)), ChannelValue::Vec3(v)) => a.value = v,
        (Some(ChannelMut::Rotation(a)), ChannelValue::Rotation(q)) => a.value = q.normalize(),
        (Some(ChannelMut::Scalar(a)), ChannelValue::Scalar(s)) => a.value = s,
        _ => return false,
    }
    true
}

/// Deletes the keys with the given indices of one channel. Returns how many were deleted.
pub fn delete_keys(scene: &mut Scene, id: ChannelId, indices: &[usize]) -> usize {
    let Some(c) = channel_mut(scene, id) else { return 0 };
    with_track_mut!(c, t => {
        let before = t.keys.len();
        let mut i = 0;
        t.keys.retain(|_| {
            let keep = !indices.contains(&i);
            i += 1;
            keep
        });
        before - t.keys.len()
    })
}

/// Copies one key.
#[must_use]
pub fn copy_key(scene: &Scene, id: ChannelId, index: usize) -> Option<KeyCopy> {
    let (time, value, interpolation, tcb) = match channel(scene, id)? {
        ChannelRef::Vec3(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Vec3(k.value), k.interpolation, k.tcb)
        }
        ChannelRef::Rotation(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Rotation(k.value), k.interpolation, k.tcb)
        }
        ChannelRef::Scalar(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Scalar(k.value), k.interpolation, k.tcb)
        }
    };
    Some(KeyCopy { channel: id, time, value, interpolation, tcb })
}

/// Pastes a copied key into its channel at `time`. Returns the new key's index.
pub fn paste_key(scene: &mut Scene, copy: &KeyCopy, time: f64) -> Option<usize> {
    let index = set_key(scene, copy.channel, time, copy.value)?;
    set_key_params(scene, copy.channel, index, copy.interpolation, copy.tcb);
    Some(index)
}

/// Moves keys of one channel by `delta` seconds. Refused (returns `None`, scene unchanged) when
/// a moved key would land on a key that does not move, or two moved keys would coincide.
/// On success returns the new indices of the moved keys, in the order of `indices`.
pub fn move_keys(scene: &mut Scene, id: ChannelId, indices: &[usize], delta: f64) -> Option<Vec<usize>> {
    if !delta.is_finite() {
        return None;
    }
    let c = channel_mut(scene, id)?;
    with_track_mut!(c, t => move_in_track(t, indices, delta))
}

fn move_in_track<T: Clone>(track: &mut RawTrack<T>, indices: &[usize], delta: f64) -> Option<Vec<usize>> {
    if indices.iter().any(|&i| i >= track.keys.len()) {
        return None;
    }
    let new_time = |i: usize, t: f64| if indices.contains(&i) { t + delta } else { t };
    let mut times: Vec<(f64, usize)> =
        track.keys.iter().enumerate().map(|(i, k)| (new_time(i, k.time), i)).collect();
    times.sort_by(|a, b| a.0.total_cmp(&b.0));
    if times.windows(2).any(|w| (w[1].0 - w[0].0).abs() < TIME_EPS) {
        return None;
    }
    // Permute the keys into their new order.
    let mut old: Vec<Option<Key<T>>> = std::mem::take(&mut *track.keys).into_iter().map(Some).collect();
    let mut new_index_of_old = vec![0; old.len()];
    for (new_i, &(time, old_i)) in times.iter().enumerate() {
        let mut key = old[old_i].take()?;
        key.time = time;
        track.keys.push(key);
        new_index_of_old[old_i] = new_i;
    }
    Some(indices.iter().map(|&i| new_index_of_old[i]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    #[test]
    fn clipboard_text_round_trips_and_refuses_other_text() {
        let keys = vec![KeyCopy {
            channel: ChannelId::JointRotation { object: 0, joint: 2 },
            time: 0.5,
            value: ChannelValue::Rotation(Quat::from_rotation_z(0.3)),
            interpolation: Interpolation::Linear,
            tcb: Tcb::new(0.1, -0.2, 0.3),
        }];
        let text = keys_to_clipboard_text(&keys);
        assert!(text.starts_with(CLIPBOARD_HEADER), "{text}");
        assert_eq!(keys_from_clipboard_text(&text), Some(keys));
        assert_eq!(keys_from_clipboard_text("hello"), None);
        assert_eq!(keys_from_clipboard_text("keyrig keys 1\n[{\"bad\": 1}]"), None);
    }

    use keyrig_core::Object;

    fn scene_with_keys(times: &[f64]) -> Scene {
        let mut scene = Scene::default();
        let mut o = Object::new("Box");
        o.translation.track =
            RawTrack::new(times.iter().map(|&t| Key::new(t, Vec3::new(t as f32, 0.0, 0.0))).collect());
        scene.objects.push(o);
        scene
    }

    #[test]
    fn set_key_inserts_in_time_order_and_replaces_at_same_time() {
        let mut scene = scene_with_keys(&[0.0, 1.0]);
        let id = ChannelId::ObjectTranslation(0);
        assert_eq!(set_key(&mut scene, id, 0.5, ChannelValue::Vec3(Vec3::ONE)), Some(1));
        assert_eq!(key_times(&scene, id), vec![0.0, 0.5, 1.0]);
        assert_eq!(set_key(&mut scene, id, 0.5, ChannelValue::Vec3(Vec3::Y)), Some(1));
        assert_eq!(key_count(&scene, id), 3);
        // Wrong value type is refused.
        assert_eq!(set_key(&mut scene, id, 0.7, ChannelValue::Scalar(1.0)), None);
    }

    #[test]
    fn move_keys_reorders_and_refuses_collisions() {
        let mut scene = scene_with_keys(&[0.0, 1.0, 2.0]);
        let id = ChannelId::ObjectTranslation(0);
        // Key 0 moves past key 1: new order 1, 0, 2.
        assert_eq!(move_keys(&mut scene, id, &[0], 1.5), Some(vec![1]));
        assert_eq!(key_times(&scene, id), vec![1.0, 1.5, 2.0]);
        // Landing on an unmoved key is refused and changes nothing.
        let before = scene.clone();
        assert_eq!(move_keys(&mut scene, id, &[0], 1.0), None);
        assert_eq!(scene, before);
    }

    #[test]
    fn delete_and_paste_round_trip() {
        let mut scene = scene_with_keys(&[0.0, 1.0]);
        let id = ChannelId::ObjectTranslation(0);
        let copy = copy_key(&scene, id, 1).expect("key 1 exists");
        assert_eq!(delete_keys(&mut scene, id, &[1]), 1);
        assert_eq!(key_times(&scene, id), vec![0.0]);
        assert_eq!(paste_key(&mut scene, &copy, 2.0), Some(1));
        assert_eq!(key_times(&scene, id), vec![0.0, 2.0]);
    }
}
