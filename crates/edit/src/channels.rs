//! Channels: the animated values of a scene, addressed by [`ChannelId`], and the key
//! operations the timeline and inspector perform on them (insert, delete, move, copy, TCB).
//!
//! These functions only change a [`Scene`]; the editor calls them through
//! [`crate::state::Document::edit`] so every change is undoable.
//!
//! # Spin keys
//! A rotation key's [`Spin`] says how it is reached from the *previous* key, so the key
//! operations keep spins meaningful (docs/channels.md, "Spins under key edits"):
//! * the first key never keeps a spin (deleting or moving keys drops it there);
//! * keys move with their spins; a spin that no longer agrees with its key's new neighbour
//!   or value is recomputed ([`crate::twist::spin_toward`]): the rotation between the two keys
//!   is kept exactly, and the whole number of turns is the one nearest the turn the segment
//!   had before (dropped when that is the short way);
//! * writing a key inside a spin segment splits the segment's turns between the two halves,
//!   and a key written with a [`Turn`] (a ring drag or the twist field in record mode) gets the
//!   spin that makes its segment turn the way the hand went.

use glam::{DVec3, Quat, Vec3};
use keyrig_core::{Cycles, Interpolation, Key, KeyType, RawTrack, Scene, Spin, Tcb, Track};

use crate::spin::{nearest_turn, spin_toward, twist_degrees};

pub use keyrig_core::channel_id::{
    channel, channel_mut as any_channel_mut, ChannelId, ChannelKind, ChannelMut, ChannelRef, ChannelValue,
};

/// A copy of one key with its value type erased (clipboard).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KeyCopy {
    pub channel: ChannelId,
    pub time: f64,
    pub value: ChannelValue,
    pub interpolation: Interpolation,
    pub tcb: Tcb,
    /// The key's type (breakdown, …); left out of the clipboard's JSON for a plain keyframe.
    #[serde(default, skip_serializing_if = "KeyType::is_keyframe")]
    pub key_type: KeyType,
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

/// The channel to change, `None` when it does not exist or is locked (a locked channel's keys
/// and value stay as they are: every edit of this module goes through here).
fn channel_mut(scene: &mut Scene, id: ChannelId) -> Option<ChannelMut<'_>> {
    any_channel_mut(scene, id).filter(|c| !match c {
        ChannelMut::Vec3(a) => a.locked,
        ChannelMut::Rotation(a) => a.locked,
        ChannelMut::Scalar(a) => a.locked,
    })
}

/// Whether channel `id` is muted (plays its static value) and locked (refuses edits).
#[must_use]
pub fn mute_and_lock(scene: &Scene, id: ChannelId) -> (bool, bool) {
    match channel(scene, id) {
        Some(ChannelRef::Vec3(a)) => (a.muted, a.locked),
        Some(ChannelRef::Rotation(a)) => (a.muted, a.locked),
        Some(ChannelRef::Scalar(a)) => (a.muted, a.locked),
        None => (false, false),
    }
}

/// Mutes or unmutes channel `id` (a locked channel too: muting changes no key); false when it
/// does not exist.
pub fn set_muted(scene: &mut Scene, id: ChannelId, muted: bool) -> bool {
    match any_channel_mut(scene, id) {
        Some(ChannelMut::Vec3(a)) => a.muted = muted,
        Some(ChannelMut::Rotation(a)) => a.muted = muted,
        Some(ChannelMut::Scalar(a)) => a.muted = muted,
        None => return false,
    }
    true
}

/// Locks or unlocks channel `id`; false when it does not exist.
pub fn set_locked(scene: &mut Scene, id: ChannelId, locked: bool) -> bool {
    match any_channel_mut(scene, id) {
        Some(ChannelMut::Vec3(a)) => a.locked = locked,
        Some(ChannelMut::Rotation(a)) => a.locked = locked,
        Some(ChannelMut::Scalar(a)) => a.locked = locked,
        None => return false,
    }
    true
}

/// Key times (seconds) of a channel, in storage order.
#[must_use]
pub fn key_times(scene: &Scene, id: ChannelId) -> Vec<f64> {
    match channel(scene, id) {
        Some(c) => with_track!(c, t => t.keys.iter().map(|k| k.time).collect()),
        None => Vec::new(),
    }
}

/// The keys of a channel whose time lies in `[from, to]` (seconds): the index of the first and
/// their times, found by binary search (tracks are sorted), so the cost follows the window,
/// not the track. Also the number of keys before and after the window and the nearest time on
/// each side (for the dope sheet's markers of keys out of view).
#[must_use]
pub fn keys_between(scene: &Scene, id: ChannelId, from: f64, to: f64) -> KeyWindow {
    match channel(scene, id) {
        Some(c) => with_track!(c, t => {
            let keys: &[Key<_>] = &t.keys;
            let first = keys.partition_point(|k| k.time < from);
            let end = keys.partition_point(|k| k.time <= to).max(first);
            KeyWindow {
                first,
                times: keys[first..end].iter().map(|k| k.time).collect(),
                before: first,
                after: keys.len() - end,
                nearest_before: first.checked_sub(1).map(|i| keys[i].time),
                nearest_after: keys.get(end).map(|k| k.time),
            }
        }),
        None => KeyWindow::default(),
    }
}

/// The keys of a channel inside a time window ([`keys_between`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct KeyWindow {
    /// Index of the first key in the window.
    pub first: usize,
    /// Times of the keys in the window, seconds.
    pub times: Vec<f64>,
    /// Keys before and after the window.
    pub before: usize,
    pub after: usize,
    /// The time of the last key before and the first key after the window.
    pub nearest_before: Option<f64>,
    pub nearest_after: Option<f64>,
}

/// The value of key `index` of a channel.
#[must_use]
pub fn key_value(scene: &Scene, id: ChannelId, index: usize) -> Option<ChannelValue> {
    match channel(scene, id)? {
        ChannelRef::Vec3(a) => a.track.keys.get(index).map(|k| ChannelValue::Vec3(k.value)),
        ChannelRef::Rotation(a) => a.track.keys.get(index).map(|k| ChannelValue::Rotation(k.value)),
        ChannelRef::Scalar(a) => a.track.keys.get(index).map(|k| ChannelValue::Scalar(k.value)),
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

/// What key `index` of channel `id` means to the animator ([`KeyType`]); `None` when it does
/// not exist.
#[must_use]
pub fn key_type(scene: &Scene, id: ChannelId, index: usize) -> Option<KeyType> {
    let c = channel(scene, id)?;
    with_track!(c, t => t.keys.get(index).map(|k| k.key_type))
}

/// The types of keys `first .. first + count` of channel `id` (fewer where the track ends;
/// none when it does not exist): what the dope sheet draws for the keys in view.
#[must_use]
pub fn key_types(scene: &Scene, id: ChannelId, first: usize, count: usize) -> Vec<KeyType> {
    let Some(c) = channel(scene, id) else { return Vec::new() };
    with_track!(c, t => t.keys.iter().skip(first).take(count).map(|k| k.key_type).collect())
}

/// Sets the type of one key (breakdown, …). Returns false when the key does not exist or its
/// channel is locked.
pub fn set_key_type(scene: &mut Scene, id: ChannelId, index: usize, key_type: KeyType) -> bool {
    let Some(c) = channel_mut(scene, id) else { return false };
    with_track_mut!(c, t => match t.keys.get_mut(index) {
        Some(k) => {
            k.key_type = key_type;
            true
        }
        None => false,
    })
}

/// Turns the keys `indices` of a position or scalar channel into Hermite keys with explicit
/// tangents equal to those their curve has now, so it keeps its shape: the segment starting at
/// key i takes `(S_i, D_{i+1})` per second ([`Track::segment_tangents`]) as key i's out-tangent
/// and key i+1's in-tangent, and key i gets the in-tangent of the segment ending at it. Returns
/// false (scene unchanged) for rotations (Squad has no per-second Hermite form that keeps its
/// shape), a channel without two keys, or a track that does not evaluate.
pub fn convert_to_hermite(scene: &mut Scene, id: ChannelId, indices: &[usize]) -> bool {
    /// `segments[i]`: the per-second tangents of segment i (`None` for Step).
    fn convert<T: Clone>(track: &mut RawTrack<T>, segments: &[Option<(T, T)>], indices: &[usize]) -> bool {
        let n = track.keys.len();
        if n < 2 {
            return false;
        }
        for &i in indices.iter().filter(|&&i| i < n) {
            // The segment before the key (its in-tangent) and after it (out-tangent, and the
            // next key's in-tangent).
            let before = i.checked_sub(1).and_then(|p| segments.get(p).cloned().flatten());
            let after = segments.get(i).cloned().flatten();
            let key = &mut track.keys[i];
            key.interpolation = Interpolation::Hermite;
            if let Some((_, inn)) = before.clone() {
                key.in_tangent = Some(inn);
            }
            match after {
                Some((out, next_in)) => {
                    key.out_tangent = Some(out);
                    track.keys[i + 1].in_tangent = Some(next_in);
                }
                // The last key starts no segment; its out-tangent continues the curve.
                None => key.out_tangent = before.map(|(_, inn)| inn).or_else(|| key.out_tangent.clone()),
            }
        }
        true
    }
    let Some(cycles) = cycles(scene, id) else { return false };
    match channel_mut(scene, id) {
        Some(ChannelMut::Vec3(a)) => {
            let Ok(evaluated) = Track::with_cycles(&a.track, cycles) else { return false };
            let segments: Vec<_> = (0..a.track.keys.len()).map(|i| evaluated.segment_tangents(i)).collect();
            convert(&mut a.track, &segments, indices)
        }
        Some(ChannelMut::Scalar(a)) => {
            let Ok(evaluated) = Track::with_cycles(&a.track, cycles) else { return false };
            let segments: Vec<_> = (0..a.track.keys.len()).map(|i| evaluated.segment_tangents(i)).collect();
            convert(&mut a.track, &segments, indices)
        }
        _ => false,
    }
}

/// Whether a key's in- and out-tangent components are one tangent: its handles are aligned
/// (equal per second: the curve has no kink at the key), to a millionth of the larger.
#[must_use]
pub fn tangents_aligned(inn: f32, out: f32) -> bool {
    (inn - out).abs() <= 1e-6 * inn.abs().max(out.abs()).max(1.0)
}

/// Makes the in- and out-tangent of key `index` (a Hermite position or scalar key) one tangent,
/// their mean per component, so that its handles are aligned again. Returns false when the key
/// has not both tangents.
pub fn align_tangents(scene: &mut Scene, id: ChannelId, index: usize) -> bool {
    fn align<T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>>(
        key: Option<&mut keyrig_core::Key<T>>,
    ) -> bool {
        let Some(key) = key else { return false };
        let (Some(inn), Some(out)) = (key.in_tangent, key.out_tangent) else { return false };
        let mean = (inn + out) * 0.5;
        key.in_tangent = Some(mean);
        key.out_tangent = Some(mean);
        true
    }
    match channel_mut(scene, id) {
        Some(ChannelMut::Vec3(a)) => align(a.track.keys.get_mut(index)),
        Some(ChannelMut::Scalar(a)) => align(a.track.keys.get_mut(index)),
        _ => false,
    }
}

/// How a handle drag treats the key's other handle (docs/channels.md, "Hermite handles").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleDrag {
    /// The other handle turns with it while the two are aligned (Blender's Aligned, Maya's
    /// unified tangents): the curve keeps no kink. A key whose handles are broken (they
    /// differ) moves the dragged handle alone.
    Aligned,
    /// The dragged handle moves alone, breaking the pair (Alt+drag; Blender's Free).
    Free,
}

/// Sets component `component` of key `index`'s in- or out-tangent (value units per second) of
/// a Hermite position or scalar key; with [`HandleDrag::Aligned`] the other tangent's
/// component follows when the two were aligned ([`tangents_aligned`]). Returns false when
/// there is no such tangent.
pub fn set_tangent_component(
    scene: &mut Scene,
    id: ChannelId,
    index: usize,
    outgoing: bool,
    component: usize,
    value: f32,
    drag: HandleDrag,
) -> bool {
    if !value.is_finite() {
        return false;
    }
    // The dragged tangent's component and the other's, as mutable references.
    fn set(mine: &mut f32, other: Option<&mut f32>, value: f32, drag: HandleDrag) {
        if let Some(other) = other {
            if drag == HandleDrag::Aligned && tangents_aligned(*mine, *other) {
                *other = value;
            }
        }
        *mine = value;
    }
    match channel_mut(scene, id) {
        Some(ChannelMut::Vec3(a)) => {
            let Some(key) = a.track.keys.get_mut(index) else { return false };
            let (mine, other) = if outgoing {
                (&mut key.out_tangent, &mut key.in_tangent)
            } else {
                (&mut key.in_tangent, &mut key.out_tangent)
            };
            match mine {
                Some(t) if component < 3 => {
                    set(&mut t[component], other.as_mut().map(|o| &mut o[component]), value, drag);
                    true
                }
                _ => false,
            }
        }
        Some(ChannelMut::Scalar(a)) => {
            let Some(key) = a.track.keys.get_mut(index) else { return false };
            let (mine, other) = if outgoing {
                (&mut key.out_tangent, &mut key.in_tangent)
            } else {
                (&mut key.in_tangent, &mut key.out_tangent)
            };
            match mine {
                Some(t) if component == 0 => {
                    set(t, other.as_mut(), value, drag);
                    true
                }
                _ => false,
            }
        }
        _ => false,
    }
}

/// The in- and out-tangents (per second) of key `index` of a position or scalar channel, as
/// component lists.
#[must_use]
pub fn key_tangents(scene: &Scene, id: ChannelId, index: usize) -> (Option<Vec<f32>>, Option<Vec<f32>>) {
    match channel(scene, id) {
        Some(ChannelRef::Vec3(a)) => a.track.keys.get(index).map_or((None, None), |k| {
            (k.in_tangent.map(|t| t.to_array().to_vec()), k.out_tangent.map(|t| t.to_array().to_vec()))
        }),
        Some(ChannelRef::Scalar(a)) => a
            .track
            .keys
            .get(index)
            .map_or((None, None), |k| (k.in_tangent.map(|t| vec![t]), k.out_tangent.map(|t| vec![t]))),
        _ => (None, None),
    }
}

/// Multiplies every key time of the scene by `factor` (> 0); Hermite tangents, stored per
/// second, are divided by it so the curves keep their shape in frames.
pub fn scale_key_times(scene: &mut Scene, factor: f64) {
    if !(factor.is_finite() && factor > 0.0) || factor == 1.0 {
        return;
    }
    for id in ChannelId::all(scene) {
        let Some(c) = any_channel_mut(scene, id) else { continue };
        with_track_mut!(c, t => {
            if !t.keys.is_empty() {
                for k in t.keys.iter_mut() {
                    k.time *= factor;
                    let per = (1.0 / factor) as f32;
                    k.in_tangent = k.in_tangent.map(|v| v * per);
                    k.out_tangent = k.out_tangent.map(|v| v * per);
                }
            }
        });
    }
}

/// The time of the last key of the scene, seconds (`None` without keys).
#[must_use]
pub fn last_key_time(scene: &Scene) -> Option<f64> {
    ChannelId::all(scene)
        .into_iter()
        .flat_map(|id| key_times(scene, id))
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))))
}

/// What the channel does before its first key and after its last ([`Cycles`]); `None` when
/// the channel does not exist.
#[must_use]
pub fn cycles(scene: &Scene, id: ChannelId) -> Option<Cycles> {
    Some(match channel(scene, id)? {
        ChannelRef::Vec3(a) => a.cycles(),
        ChannelRef::Rotation(a) => a.cycles(),
        ChannelRef::Scalar(a) => a.cycles(),
    })
}

/// Sets the channel's behaviour before its first key and after its last. Returns false when
/// the channel does not exist. A cycle other than Hold needs two keys (the caller offers it
/// only then; [`delete_keys`] returns a channel to Hold when fewer remain).
pub fn set_cycles(scene: &mut Scene, id: ChannelId, cycles: Cycles) -> bool {
    let Some(c) = channel_mut(scene, id) else { return false };
    let (before, after) = match c {
        ChannelMut::Vec3(a) => (&mut a.before, &mut a.after),
        ChannelMut::Rotation(a) => (&mut a.before, &mut a.after),
        ChannelMut::Scalar(a) => (&mut a.before, &mut a.after),
    };
    *before = cycles.before;
    *after = cycles.after;
    true
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
/// match. Rotation keys go through [`set_rotation_key`] without a turn (spins stay valid).
pub fn set_key(scene: &mut Scene, id: ChannelId, time: f64, value: ChannelValue) -> Option<usize> {
    if let Some((euler, e)) = euler_target(scene, id, value, None, time, None) {
        return set_key(scene, euler, time, ChannelValue::Vec3(e));
    }
    match (channel_mut(scene, id)?, value) {
        (ChannelMut::Vec3(a), ChannelValue::Vec3(v)) => Some(insert_sorted(&mut a.track, Key::new(time, v))),
        (ChannelMut::Rotation(a), ChannelValue::Rotation(q)) => {
            Some(set_rotation_key_in(&mut a.track, time, q.normalize(), None))
        }
        (ChannelMut::Scalar(a), ChannelValue::Scalar(s)) => {
            // Switches (visibility, the deformer) are whole numbers keyed with Step keys.
            let key = match id {
                id if id.is_switch() => {
                    Key::new(time, s.round()).with_interpolation(keyrig_core::Interpolation::Step)
                }
                _ => Key::new(time, s),
            };
            Some(insert_sorted(&mut a.track, key))
        }
        _ => None,
    }
}

/// Where rotation `value` of channel `id` goes when its object or joint has Euler keys
/// (docs/channels.md, "Euler keys"): the Euler-keys channel and the angles of `value` nearest
/// `near` (by default the keys' angles at `time`, or their static value while unkeyed). With a
/// `turn`, the angles follow the hand through the turn, so a two-turn ring drag adds 720° to
/// one angle. `None` for every other channel and value (they are written as they are).
#[must_use]
pub fn euler_target(
    scene: &Scene,
    id: ChannelId,
    value: ChannelValue,
    near: Option<Vec3>,
    time: f64,
    turn: Option<Turn>,
) -> Option<(ChannelId, Vec3)> {
    let ChannelValue::Rotation(q) = value else { return None };
    if id.kind() != ChannelKind::Rotation {
        return None;
    }
    let (keys, order) = keyrig_core::channel_id::euler_keys(scene, id)?;
    let euler = keyrig_core::channel_id::euler_partner(id)?;
    let mut e = near.unwrap_or_else(|| {
        keyrig_core::AnimatedTrack::new(keys).map_or(keys.value, |track| track.sample(time))
    });
    if let Some(turn) = turn {
        e = order.angles_near(turn.from, e);
        let steps = (turn.degrees.abs() / 10.0).ceil().clamp(1.0, 1.0e5) as usize;
        for step in 1..=steps {
            let part = Turn { degrees: turn.degrees * step as f64 / steps as f64, ..turn };
            e = order.angles_near(part.value(), e);
        }
    }
    Some((euler, order.angles_near(q.normalize(), e)))
}

/// How a rotation was reached when it was turned with a gizmo ring or the twist field: from
/// `from` (the channel's value at that time before the turn) by `degrees` about `axis`, a
/// direction in the channel's parent frame, so that the new value is `R(axis, degrees)·from`.
/// `degrees` may be several turns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turn {
    pub from: Quat,
    pub axis: Vec3,
    pub degrees: f64,
}

impl Turn {
    /// The rotation the turn arrives at, `R(axis, degrees)·from`.
    #[must_use]
    pub fn value(&self) -> Quat {
        let axis = self.axis.normalize_or(Vec3::X);
        (Quat::from_axis_angle(axis, self.degrees.to_radians() as f32) * self.from).normalize()
    }
}

/// Writes the rotation key `value` at `time` like [`set_key`], keeping spins valid (module
/// documentation). With a `turn`, the key gets the [`Spin`] that makes the segment from the
/// previous key turn as the hand did: the turn already made from the previous key to
/// `turn.from` (counting the turns of a spin segment) plus `turn.degrees`. Returns the key's
/// index, or `None` when `id` is not a rotation channel.
pub fn set_rotation_key(
    scene: &mut Scene,
    id: ChannelId,
    time: f64,
    value: Quat,
    turn: Option<Turn>,
) -> Option<usize> {
    if let Some((euler, e)) = euler_target(scene, id, ChannelValue::Rotation(value), None, time, turn) {
        return set_key(scene, euler, time, ChannelValue::Vec3(e));
    }
    match channel_mut(scene, id)? {
        ChannelMut::Rotation(a) => Some(set_rotation_key_in(&mut a.track, time, value.normalize(), turn)),
        _ => None,
    }
}

/// Twist-like turn of `next` relative to `prev` about `axis` (in `prev`'s frame), degrees in
/// (−180, 180].
fn turn_about(prev: Quat, next: Quat, axis: DVec3) -> f64 {
    twist_degrees(prev.as_dquat().conjugate() * next.as_dquat(), axis)
}

/// The turn of segment `i` of `track` about `axis`: its spin's angle when it has one about
/// (nearly) that axis, else the short way's twist about it.
fn segment_turn(track: &Track<Quat>, i: usize, axis: DVec3) -> f64 {
    let values = track.key_values();
    match track.segment_spin(i) {
        Some((s, degrees)) if s.dot(axis).abs() > 0.5 => degrees * s.dot(axis).signum(),
        _ => turn_about(values[i], values[i + 1], axis),
    }
}

/// What each key's spin meant: its axis (in the previous key's frame) and signed angle, for
/// keys that have one.
fn spin_intents(keys: &[Key<Quat>]) -> Vec<Option<(Vec3, f64)>> {
    (0..keys.len())
        .map(|i| {
            let spin = keys[i].spin?;
            let prev = keys.get(i.checked_sub(1)?)?.value;
            match keyrig_core::track::spin_chord(prev.as_dquat(), keys[i].value.as_dquat(), spin) {
                Ok(Some(c)) => Some((c.axis.as_vec3(), c.degrees)),
                Ok(None) => None,
                Err(_) => match spin {
                    Spin::Angle { axis, degrees } => Some((axis, degrees)),
                    Spin::Turns(_) => None,
                },
            }
        })
        .collect()
}

/// Drops the first key's spin and recomputes every spin that no longer agrees with its key
/// and the previous key from `intents[i]` (what it meant before the edit; the spin's own
/// angle when `None`). Spins with other problems (out of range, after Hermite) are left for
/// validation to report.
fn repair_spins(keys: &mut [Key<Quat>], intents: &[Option<(Vec3, f64)>]) {
    if let Some(first) = keys.first_mut() {
        first.spin = None;
    }
    for i in 1..keys.len() {
        let Some(spin) = keys[i].spin else { continue };
        let (prev, next) = (keys[i - 1].value, keys[i].value);
        match keyrig_core::track::spin_chord(prev.as_dquat(), next.as_dquat(), spin) {
            Ok(_) => {}
            Err(keyrig_core::SpinProblem::Disagrees | keyrig_core::SpinProblem::AmbiguousAxis) => {
                let intent = intents.get(i).copied().flatten().or(match spin {
                    Spin::Angle { axis, degrees } => Some((axis, degrees)),
                    Spin::Turns(_) => None,
                });
                keys[i].spin = intent.and_then(|(axis, degrees)| spin_toward(prev, next, axis, degrees));
            }
            Err(_) => {}
        }
    }
}

fn set_rotation_key_in(track: &mut RawTrack<Quat>, time: f64, value: Quat, turn: Option<Turn>) -> usize {
    let intents = spin_intents(&track.keys);
    let old = Track::new(track).ok();
    let existing = track.keys.iter().position(|k| (k.time - time).abs() < TIME_EPS);
    let prev = track.keys.iter().rposition(|k| k.time < time - TIME_EPS);
    let next = match existing {
        Some(k) => (k + 1 < track.keys.len()).then_some(k + 1),
        None => track.keys.iter().position(|k| k.time > time),
    };
    // The turn's axis in the previous key's frame (or the spin segment's axis), the turn from
    // the previous key to the new value about it, and what is left of the old turn to the next
    // key — all measured before the edit.
    let plan = old.as_ref().zip(prev).and_then(|(old, p)| {
        let q_p = track.keys[p].value.normalize();
        let segment = old.segment_spin(p);
        let (axis_prev, from, degrees) = match turn {
            Some(turn) => {
                let axis = (q_p.inverse() * turn.axis.normalize_or(Vec3::X)).as_dvec3();
                (axis, turn.from, turn.degrees)
            }
            None => (segment?.0, old.sample(time), 0.0),
        };
        let short = turn_about(q_p, from, axis_prev);
        let offset = match (segment, old.spin_degrees(time)) {
            (Some((s, _)), Some(d)) if s.dot(axis_prev).abs() > 0.5 => {
                nearest_turn(short, d * s.dot(axis_prev).signum())
            }
            _ => short,
        };
        let hand = offset + degrees;
        let next_remaining = next.filter(|&n| track.keys[n].spin.is_some()).map(|n| {
            let total: f64 = (p..n).map(|i| segment_turn(old, i, axis_prev)).sum();
            total - hand
        });
        let axis_parent = (q_p.as_dquat() * axis_prev).as_vec3();
        Some((p, axis_prev.as_vec3(), hand, axis_parent, next_remaining))
    });
    let k = insert_sorted(track, Key::new(time, value));
    let mut intents: Vec<Option<(Vec3, f64)>> = match existing {
        Some(_) => intents,
        None => {
            let mut v = intents;
            v.insert(k, None);
            v
        }
    };
    if let Some((p, axis_prev, hand, axis_parent, next_remaining)) = plan {
        track.keys[k].spin = spin_toward(track.keys[p].value, value, axis_prev, hand);
        intents[k] = None;
        if let Some(remaining) = next_remaining {
            if let Some(n) = track.keys.get_mut(k + 1) {
                let axis_here = value.inverse() * axis_parent;
                n.spin = spin_toward(value, n.value, axis_here, remaining);
                intents[k + 1] = None;
            }
        }
    }
    repair_spins(&mut track.keys, &intents);
    k
}

/// Sets the static value (the pose used while the channel has no keys).
pub fn set_static_value(scene: &mut Scene, id: ChannelId, value: ChannelValue) -> bool {
    if let Some((euler, e)) = euler_target(scene, id, value, None, 0.0, None) {
        return set_static_value(scene, euler, ChannelValue::Vec3(e));
    }
    match (channel_mut(scene, id), value) {
        (Some(ChannelMut::Vec3(a)), ChannelValue::Vec3(v)) => a.value = v,
        (Some(ChannelMut::Rotation(a)), ChannelValue::Rotation(q)) => a.value = q.normalize(),
        (Some(ChannelMut::Scalar(a)), ChannelValue::Scalar(s)) => a.value = s,
        _ => return false,
    }
    true
}

/// Deletes the keys with the given indices of one channel. Returns how many were deleted.
/// A rotation key whose previous key goes keeps its spin recomputed from the new previous key
/// with the turns of the segments it now spans; the new first key loses its spin.
pub fn delete_keys(scene: &mut Scene, id: ChannelId, indices: &[usize]) -> usize {
    let deleted = delete_keys_keeping_cycles(scene, id, indices);
    // A cycle needs two keys: with fewer left the channel holds again (else the scene would
    // not evaluate).
    if key_count(scene, id) < 2 {
        set_cycles(scene, id, Cycles::HOLD);
    }
    deleted
}

fn delete_keys_keeping_cycles(scene: &mut Scene, id: ChannelId, indices: &[usize]) -> usize {
    let Some(c) = channel_mut(scene, id) else { return 0 };
    if let ChannelMut::Rotation(a) = c {
        return delete_rotation_keys(&mut a.track, indices);
    }
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

fn delete_rotation_keys(track: &mut RawTrack<Quat>, indices: &[usize]) -> usize {
    let before = track.keys.len();
    let mut intents = spin_intents(&track.keys);
    // Kept keys whose previous key goes: (old index, axis, turn from the new previous key).
    let mut spanning: Vec<(usize, Vec3, f64)> = Vec::new();
    if let Ok(old) = Track::new(track) {
        // A kept key with a spin whose previous key goes spans the deleted segments too.
        let mut last_kept: Option<usize> = None;
        for (i, intent) in intents.iter().enumerate() {
            if indices.contains(&i) {
                continue;
            }
            if let (Some(p), Some((axis, _))) = (last_kept, intent) {
                if p + 1 < i {
                    let axis = axis.as_dvec3().normalize_or(DVec3::X);
                    let total = (p..i).map(|j| segment_turn(&old, j, axis)).sum();
                    spanning.push((i, axis.as_vec3(), total));
                }
            }
            last_kept = Some(i);
        }
    }
    let mut i = 0;
    track.keys.retain(|_| {
        let keep = !indices.contains(&i);
        i += 1;
        keep
    });
    let mut i = 0;
    intents.retain(|_| {
        let keep = !indices.contains(&i);
        i += 1;
        keep
    });
    for (old_i, axis, total) in spanning {
        let new_i = old_i - indices.iter().filter(|&&d| d < old_i).count();
        if new_i > 0 {
            let (prev, next) = (track.keys[new_i - 1].value, track.keys[new_i].value);
            track.keys[new_i].spin = spin_toward(prev, next, axis, total);
        }
    }
    repair_spins(&mut track.keys, &intents);
    before - track.keys.len()
}

/// Copies one key.
#[must_use]
pub fn copy_key(scene: &Scene, id: ChannelId, index: usize) -> Option<KeyCopy> {
    let (time, value, interpolation, tcb, key_type) = match channel(scene, id)? {
        ChannelRef::Vec3(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Vec3(k.value), k.interpolation, k.tcb, k.key_type)
        }
        ChannelRef::Rotation(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Rotation(k.value), k.interpolation, k.tcb, k.key_type)
        }
        ChannelRef::Scalar(a) => {
            let k = a.track.keys.get(index)?;
            (k.time, ChannelValue::Scalar(k.value), k.interpolation, k.tcb, k.key_type)
        }
    };
    Some(KeyCopy { channel: id, time, value, interpolation, tcb, key_type })
}

/// Pastes a copied key into its channel at `time`. Returns the new key's index.
pub fn paste_key(scene: &mut Scene, copy: &KeyCopy, time: f64) -> Option<usize> {
    let index = set_key(scene, copy.channel, time, copy.value)?;
    set_key_params(scene, copy.channel, index, copy.interpolation, copy.tcb);
    set_key_type(scene, copy.channel, index, copy.key_type);
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
    if let ChannelMut::Rotation(a) = c {
        // Spins move with their keys; those whose previous key changed are recomputed.
        let intents = spin_intents(&a.track.keys);
        let new_index_of_old = permute_in_track(&mut a.track, indices, delta)?;
        let mut new_intents = vec![None; intents.len()];
        for (old, &new) in new_index_of_old.iter().enumerate() {
            new_intents[new] = intents[old];
        }
        repair_spins(&mut a.track.keys, &new_intents);
        return Some(indices.iter().map(|&i| new_index_of_old[i]).collect());
    }
    with_track_mut!(c, t => move_in_track(t, indices, delta))
}

fn move_in_track<T: Clone>(track: &mut RawTrack<T>, indices: &[usize], delta: f64) -> Option<Vec<usize>> {
    let new_index_of_old = permute_in_track(track, indices, delta)?;
    Some(indices.iter().map(|&i| new_index_of_old[i]).collect())
}

/// Moves the keys `indices` by `delta` and sorts; returns the new index of every old key.
fn permute_in_track<T: Clone>(track: &mut RawTrack<T>, indices: &[usize], delta: f64) -> Option<Vec<usize>> {
    if indices.iter().any(|&i| i >= track.keys.len()) {
        return None;
    }
    let mut moves = vec![false; track.keys.len()];
    for &i in indices {
        moves[i] = true;
    }
    let new_time = |i: usize, t: f64| if moves[i] { t + delta } else { t };
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
    Some(new_index_of_old)
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
            key_type: KeyType::Breakdown,
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

    // Spin keys under key edits. Timeline of the forearm track used below (seconds):
    //
    //   0 ─────────── 1 ─────────── 2
    //   A 0°          B 0°+360°      C 90°
    fn twist_track(keys: &[(f64, f64, Option<f64>)]) -> Scene {
        let mut scene = Scene::default();
        let mut o = Object::new("Arm");
        o.rotation.track = RawTrack::new(
            keys.iter()
                .map(|&(t, deg, spin)| {
                    let k = Key::new(t, Quat::from_rotation_x((deg as f32).to_radians()))
                        .with_interpolation(Interpolation::Linear);
                    match spin {
                        Some(d) => k.with_spin(Spin::Angle { axis: Vec3::X, degrees: d }),
                        None => k,
                    }
                })
                .collect(),
        );
        scene.objects.push(o);
        scene
    }

    const ROT: ChannelId = ChannelId::ObjectRotation(0);

    fn spins(scene: &Scene) -> Vec<Option<f64>> {
        scene.objects[0]
            .rotation
            .track
            .keys
            .iter()
            .map(|k| match k.spin {
                None => None,
                Some(Spin::Angle { axis, degrees }) => {
                    assert!((axis - Vec3::X).length() < 1e-4, "axis {axis:?}");
                    Some((degrees * 1000.0).round() / 1000.0)
                }
                Some(other) => panic!("{other:?}"),
            })
            .collect()
    }

    fn assert_valid(scene: &Scene) {
        Track::new(&scene.objects[0].rotation.track).expect("the track stays valid");
    }

    #[test]
    fn a_turned_key_gets_the_spin_of_the_turn_either_way() {
        for degrees in [720.0, -450.0, 540.0, 90.0, -1000.0] {
            let mut scene = twist_track(&[(0.0, 0.0, None)]);
            let turn = Turn { from: Quat::IDENTITY, axis: Vec3::X, degrees };
            set_rotation_key(&mut scene, ROT, 1.0, turn.value(), Some(turn));
            let expected = (degrees.abs() >= 179.0).then_some(degrees);
            assert_eq!(spins(&scene), vec![None, expected], "turned {degrees}°");
            assert_valid(&scene);
        }
    }

    #[test]
    fn a_turn_from_inside_a_spin_segment_counts_the_turns_already_made() {
        // 0 → 360° over two seconds; at 1.5 s the track is at 270°; a further +180° there is
        // 450° from A, and the rest of the segment (to 360°) turns back −90°, the short way.
        let mut scene = twist_track(&[(0.0, 0.0, None), (2.0, 0.0, Some(360.0))]);
        let from = Quat::from_rotation_x(270_f32.to_radians());
        let turn = Turn { from, axis: Vec3::X, degrees: 180.0 };
        assert_eq!(set_rotation_key(&mut scene, ROT, 1.5, turn.value(), Some(turn)), Some(1));
        assert_eq!(spins(&scene), vec![None, Some(450.0), None]);
        assert_valid(&scene);
    }

    #[test]
    fn keying_inside_a_spin_segment_splits_its_turns() {
        // I at the middle of a 720° segment: two segments of 360°.
        let mut scene = twist_track(&[(0.0, 0.0, None), (2.0, 0.0, Some(720.0))]);
        let middle = channel_value_at(&scene, 1.0);
        set_key(&mut scene, ROT, 1.0, ChannelValue::Rotation(middle));
        assert_eq!(spins(&scene), vec![None, Some(360.0), Some(360.0)]);
        assert_valid(&scene);
    }

    fn channel_value_at(scene: &Scene, t: f64) -> Quat {
        Track::new(&scene.objects[0].rotation.track).expect("valid").sample(t)
    }

    #[test]
    fn deleting_keys_keeps_spins_valid() {
        // Deleting the first key: B may not keep a spin as the new first key.
        let mut scene = twist_track(&[(0.0, 0.0, None), (1.0, 0.0, Some(360.0)), (2.0, 90.0, None)]);
        delete_keys(&mut scene, ROT, &[0]);
        assert_eq!(spins(&scene), vec![None, None]);
        assert_valid(&scene);
        // Deleting B: C is now reached from A by B's 360° and C's 90°.
        let mut scene = twist_track(&[(0.0, 0.0, None), (1.0, 0.0, Some(360.0)), (2.0, 90.0, Some(90.0))]);
        delete_keys(&mut scene, ROT, &[1]);
        assert_eq!(spins(&scene), vec![None, Some(450.0)]);
        assert_valid(&scene);
    }

    #[test]
    fn moving_keys_keeps_spins_with_their_keys() {
        let mut scene = twist_track(&[(0.0, 0.0, None), (1.0, 0.0, Some(360.0)), (2.0, 90.0, None)]);
        assert_eq!(move_keys(&mut scene, ROT, &[1, 2], 0.5), Some(vec![1, 2]));
        assert_eq!(spins(&scene), vec![None, Some(360.0), None]);
        // B past C: B's 360° is now reached from C (90°): the turn nearest 360° is 270°.
        assert_eq!(move_keys(&mut scene, ROT, &[1], 2.0), Some(vec![2]));
        assert_eq!(spins(&scene), vec![None, None, Some(-450.0 + 720.0)]);
        assert_valid(&scene);
        // A after everything: the first key (the old C) loses nothing, A gets no spin of its
        // own, and a spin never stays on the first key.
        let mut scene = twist_track(&[(0.0, 0.0, None), (1.0, 0.0, Some(360.0))]);
        assert_eq!(move_keys(&mut scene, ROT, &[0], 5.0), Some(vec![1]));
        assert_eq!(spins(&scene), vec![None, None]);
        assert_valid(&scene);
    }

    #[test]
    fn editing_a_spin_keys_value_recomputes_its_spin() {
        // B (360° from A) set to 30° about X: 390°, the turn nearest the old 360°.
        let mut scene = twist_track(&[(0.0, 0.0, None), (1.0, 0.0, Some(360.0)), (2.0, 0.0, Some(-360.0))]);
        set_key(&mut scene, ROT, 1.0, ChannelValue::Rotation(Quat::from_rotation_x(30_f32.to_radians())));
        // C keeps going back a whole turn from B's new value: −390°.
        assert_eq!(spins(&scene), vec![None, Some(390.0), Some(-390.0)]);
        assert_valid(&scene);
    }
}
