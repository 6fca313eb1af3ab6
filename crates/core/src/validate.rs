//! What is wrong with a scene: [`Scene::problems`].
//!
//! Rules (each problem carries the path of the field it concerns, in the syntax
//! `objects[0].skeleton.joints[2].rotation.track[4].time`; vector components are `.x .y .z .w`):
//!
//! 1. Every number is finite (RON can spell `NaN` and `inf`; an f32 field overflows to `inf`).
//! 2. `fps` > 0; the frame range is not empty (`start` ≤ `end`).
//! 3. Object names are unique and not empty, light names likewise, joint names unique within
//!    a skeleton: channel paths (`object/Arm/joint/elbow/rotation`) address them by name.
//! 4. A joint's parent is an existing joint stored before it (parents first); exactly one
//!    root, the first joint.
//! 5. Rotations (static values, rest rotations, keys) are not the zero quaternion.
//! 6. Tracks: times finite and strictly increasing, values and tangents finite, T/C/B in
//!    [-1, 1], a Hermite segment has its start key's out-tangent and its end key's in-tangent:
//!    the rules of [`crate::track`]'s validator, but every offending key is reported, not only
//!    the first. A property test keeps the rules equal to the validator's, so a scene without
//!    problems always gives valid tracks. A key's `spin` ([`crate::Spin`]) is on a rotation
//!    key other than the first, in range, not ending a Hermite segment, and agrees with the
//!    key values (Turns: a defined short way; Angle: arrives at the key's value). A track's
//!    `before` and `after` other than `Hold` ([`crate::Cycle`]) need two keys and a positive,
//!    finite period (last key time − first key time).
//! 7. Lights: non-negative intensity and colour, a non-zero direction for directional and spot
//!    lights, spot angles with 0 < inner ≤ cutoff ≤ 90 and dropoff ≥ 0.
//! 8. Camera: distance > 0, 0 < fov < 180; deformer blend fractions in [0, 1].
//! 9. A model file mesh: a non-empty path; an MD2 clip name, when given, not empty; an MD2
//!    playback rate, when given, finite and > 0.
//! 10. IK constraints: a unique, non-empty name per skeleton; an end joint inside the skeleton
//!     with at least `bones` ≥ 2 joints above it and no zero-length bone at rest
//!     ([`crate::ik_constraint::ConstraintChain::new`]); a finite target and pole; the blend's
//!     value and keys in [0, 1].
//! 11. Scene cameras ([`crate::SceneCamera`]): a unique, non-empty name; the lens value and
//!     keys in range for the projection (field of view in (0°, 180°), focal length > 0 with a
//!     sensor height > 0, orthographic height > 0); near > 0, far > near when given, an
//!     orthographic camera has a far plane; an aim's up not zero, its object (and joint)
//!     existing, its point finite; its visibility 0 or 1 with Step keys. Markers name existing cameras; `active_camera` names an
//!     existing camera; a render size has sides in 1..=16384.
//! 12. Object constraints ([`crate::object_constraint`]): a unique, non-empty name per object;
//!     targets (an aim's, a copy's, each child-of parent's, a path's space) naming an existing
//!     object or joint other than the constrained object itself, a point target finite; an
//!     influence and a path offset with value and keys in [0, 1]; an aim's up not zero; a
//!     child-of offset finite and invertible; a path of at least 2 finite points; no cycle of
//!     objects whose constraints read each other.

use std::collections::HashMap;

use glam::{Quat, Vec3};

use crate::camera_object::{AimTarget, Projection, RenderSize, SceneCamera};
use crate::ik_constraint::{ConstraintChain, ConstraintError};
use crate::key::{Animated, Interpolation, RawTrack, Spin};
use crate::object_constraint::ObjectConstraint;
use crate::scene::{
    Camera, DeformerSettings, IkConstraint, Light, LightKind, MeshSource, Object, Problem, Scene, Skeleton,
};
#[cfg(doc)]
use crate::track::AnimatedTrack;
use crate::track::{
    check_cycles, spin_chord, SpinProblem, TangentSide, TrackError, TrackValue, MIN_QUATERNION_NORM,
};

/// The path of the field a [`TrackError`] of the `Animated` value at `animated_path` concerns,
/// e.g. `objects[0].rotation` + `Unsorted { index: 4 }` → `objects[0].rotation.track[4].time`.
#[must_use]
pub fn track_error_path(animated_path: &str, err: &TrackError) -> String {
    let key = |index: usize, field: &str| join(&format!("{animated_path}.track[{index}]"), field);
    match *err {
        TrackError::Empty => join(animated_path, "track"),
        TrackError::Unsorted { index }
        | TrackError::DuplicateTime { index }
        | TrackError::NonFiniteTime { index } => key(index, "time"),
        TrackError::NonFiniteValue { index } | TrackError::ZeroQuaternion { index } => key(index, "value"),
        TrackError::NonFiniteTangent { index } => key(index, ""),
        TrackError::MissingTangent { index, side: TangentSide::In } => key(index, "in_tangent"),
        TrackError::MissingTangent { index, side: TangentSide::Out } => key(index, "out_tangent"),
        TrackError::TcbOutOfRange { index } => key(index, "tcb"),
        TrackError::Spin { index, .. } => key(index, "spin"),
        TrackError::NonFiniteStaticValue | TrackError::ZeroStaticQuaternion => join(animated_path, "value"),
        TrackError::CycleNeedsTwoKeys { end, .. } | TrackError::CyclePeriod { end, .. } => {
            join(animated_path, end.field())
        }
    }
}

/// A value that can sit in a key: knows its finite-ness per component.
pub trait KeyValue: Copy {
    /// Names of the components that are NaN or infinite (`""` for a scalar).
    fn non_finite_components(&self) -> Vec<&'static str>;
    /// True when no component is NaN or infinite.
    fn is_all_finite(&self) -> bool;
    /// For rotations: true when the value cannot be normalized. Always false otherwise.
    fn is_degenerate(&self) -> bool {
        false
    }
    /// Whether keys of this type may carry a [`Spin`].
    const ROTATION: bool = false;
    /// For rotations: what is wrong with `spin` on the key `next` after the key `prev` (both
    /// valid values, `spin` in range); the track validator's rule ([`spin_chord`]).
    fn spin_pair_problem(_prev: &Self, _next: &Self, _spin: Spin) -> Option<SpinProblem> {
        None
    }
}

impl KeyValue for f32 {
    fn is_all_finite(&self) -> bool {
        self.is_finite()
    }

    fn non_finite_components(&self) -> Vec<&'static str> {
        if self.is_finite() {
            Vec::new()
        } else {
            vec![""]
        }
    }
}

impl KeyValue for Vec3 {
    fn is_all_finite(&self) -> bool {
        self.is_finite()
    }

    fn non_finite_components(&self) -> Vec<&'static str> {
        ["x", "y", "z"]
            .into_iter()
            .zip(self.to_array())
            .filter(|(_, v)| !v.is_finite())
            .map(|(n, _)| n)
            .collect()
    }
}

impl KeyValue for Quat {
    fn is_all_finite(&self) -> bool {
        self.is_finite()
    }

    fn non_finite_components(&self) -> Vec<&'static str> {
        ["x", "y", "z", "w"]
            .into_iter()
            .zip(self.to_array())
            .filter(|(_, v)| !v.is_finite())
            .map(|(n, _)| n)
            .collect()
    }

    fn is_degenerate(&self) -> bool {
        self.as_dquat().length() < MIN_QUATERNION_NORM
    }

    const ROTATION: bool = true;

    fn spin_pair_problem(prev: &Self, next: &Self, spin: Spin) -> Option<SpinProblem> {
        let (Ok(prev), Ok(next)) = (TrackValue::check(*prev), TrackValue::check(*next)) else {
            return None;
        };
        spin_chord(prev, next, spin).err()
    }
}

/// Collects problems under a path prefix.
pub(crate) struct Checker {
    problems: Vec<Problem>,
}

fn join(path: &str, field: &str) -> String {
    if field.is_empty() {
        path.to_string()
    } else if path.is_empty() {
        field.to_string()
    } else {
        format!("{path}.{field}")
    }
}

fn describe(v: f64) -> &'static str {
    if v.is_nan() {
        "NaN"
    } else if v > 0.0 {
        "+inf"
    } else {
        "-inf"
    }
}

impl Checker {
    pub(crate) fn push(&mut self, path: impl Into<String>, message: impl Into<String>) {
        self.problems.push(Problem { path: path.into(), message: message.into() });
    }

    fn f32(&mut self, path: &str, v: f32) -> bool {
        self.f64(path, f64::from(v))
    }

    pub(crate) fn f64(&mut self, path: &str, v: f64) -> bool {
        if v.is_finite() {
            true
        } else {
            self.push(path, format!("not a finite number ({})", describe(v)));
            false
        }
    }

    /// Checks a value's components; returns true when all are finite.
    fn value<T: KeyValue>(&mut self, path: &str, v: &T) -> bool {
        let bad = v.non_finite_components();
        for c in &bad {
            self.push(join(path, c), "not a finite number");
        }
        bad.is_empty()
    }

    fn rotation(&mut self, path: &str, q: &Quat) {
        if self.value(path, q) && q.is_degenerate() {
            self.push(path, "zero quaternion: not a rotation");
        }
    }

    /// Checks the static value and every key, reporting all problems (not only the first as
    /// [`AnimatedTrack::new`] does). The rules are the track validator's; a property test keeps
    /// the two in agreement: no problem here ⇔ `AnimatedTrack::new` succeeds and the static
    /// value is valid (checked here even when keys override it).
    pub(crate) fn animated<T: KeyValue>(&mut self, path: &str, a: &Animated<T>) {
        if self.value(&join(path, "value"), &a.value) && a.value.is_degenerate() {
            self.push(join(path, "value"), "zero quaternion: not a rotation");
        }
        self.track(&join(path, "track"), &a.track);
        // Cycles need two keys and a positive period; an unanimated value ignores them.
        if !a.track.is_empty() && !a.cycles().is_hold() {
            let times: Vec<f64> = a.track.keys.iter().map(|k| k.time).collect();
            for cycles in [
                crate::key::Cycles::new(a.before, crate::key::Cycle::Hold),
                crate::key::Cycles::new(crate::key::Cycle::Hold, a.after),
            ] {
                if let Err(err) = check_cycles(&times, cycles) {
                    self.push(track_error_path(path, &err), err.to_string());
                }
            }
        }
    }

    fn track<T: KeyValue>(&mut self, path: &str, track: &RawTrack<T>) {
        let mut previous: Option<f64> = None;
        for (i, key) in track.keys.iter().enumerate() {
            // Fast path without allocation for the usual, valid key.
            let tcb = [key.tcb.tension, key.tcb.continuity, key.tcb.bias];
            let valid = key.time.is_finite()
                && previous.is_none_or(|p| key.time > p)
                && key.value.is_all_finite()
                && !key.value.is_degenerate()
                && tcb.iter().all(|v| (-1.0..=1.0).contains(v))
                && key.in_tangent.is_none_or(|t| t.is_all_finite())
                && key.out_tangent.is_none_or(|t| t.is_all_finite())
                && key.spin.is_none();
            if valid {
                previous = Some(key.time);
                continue;
            }
            let kp = format!("{path}[{i}]");
            if self.f64(&join(&kp, "time"), key.time) {
                if let Some(prev) = previous {
                    if key.time == prev {
                        self.push(
                            join(&kp, "time"),
                            format!("duplicate key time {} s (same as key {})", key.time, i - 1),
                        );
                    } else if key.time < prev {
                        self.push(
                            join(&kp, "time"),
                            format!(
                                "keys out of order: {} s comes after key {} at {prev} s",
                                key.time,
                                i - 1
                            ),
                        );
                    }
                }
                previous = Some(key.time);
            }
            if self.value(&join(&kp, "value"), &key.value) && key.value.is_degenerate() {
                self.push(join(&kp, "value"), "zero quaternion: not a rotation");
            }
            for (name, v) in
                [("tension", key.tcb.tension), ("continuity", key.tcb.continuity), ("bias", key.tcb.bias)]
            {
                let p = format!("{kp}.tcb.{name}");
                if self.f32(&p, v) && !(-1.0..=1.0).contains(&v) {
                    self.push(p, format!("{v} is outside [-1, 1]"));
                }
            }
            for (name, tangent) in [("in_tangent", &key.in_tangent), ("out_tangent", &key.out_tangent)] {
                if let Some(t) = tangent {
                    self.value(&join(&kp, name), t);
                }
            }
            if let Some(problem) = key.spin.and_then(|spin| crate::track::spin_problem(spin, i, T::ROTATION))
            {
                self.push(join(&kp, "spin"), problem.to_string());
            }
        }
        // A Hermite segment i needs key i's out-tangent and key i+1's in-tangent.
        for (i, pair) in track.keys.windows(2).enumerate() {
            if pair[0].interpolation == Interpolation::Hermite {
                if pair[0].out_tangent.is_none() {
                    self.push(
                        format!("{path}[{i}].out_tangent"),
                        "a Hermite segment needs its start key's out_tangent",
                    );
                }
                if pair[1].in_tangent.is_none() {
                    self.push(
                        format!("{path}[{}].in_tangent", i + 1),
                        "a Hermite segment needs its end key's in_tangent",
                    );
                }
            }
            // A spin on key i+1 (in range, on a rotation) against the key values.
            if let Some(spin) = pair[1].spin.filter(|s| T::ROTATION && s.is_in_range()) {
                let at = format!("{path}[{}].spin", i + 1);
                if pair[0].interpolation == Interpolation::Hermite {
                    self.push(at, SpinProblem::AfterHermite.to_string());
                } else if [&pair[0].value, &pair[1].value]
                    .iter()
                    .all(|v| v.is_all_finite() && !v.is_degenerate())
                {
                    if let Some(problem) = T::spin_pair_problem(&pair[0].value, &pair[1].value, spin) {
                        self.push(at, problem.to_string());
                    }
                }
            }
        }
    }

    /// Reports every name used more than once (and empty names) in `names`.
    pub(crate) fn unique_names<'a>(&mut self, what: &str, names: impl Iterator<Item = (String, &'a str)>) {
        let mut seen: HashMap<&str, usize> = HashMap::new();
        for (i, (path, name)) in names.enumerate() {
            if name.is_empty() {
                self.push(path, format!("{what} name is empty"));
            } else if name.contains('/') {
                self.push(
                    path,
                    format!("{what} name {name:?} contains '/', which separates channel path parts"),
                );
            } else if let Some(first) = seen.get(name) {
                self.push(path, format!("duplicate {what} name {name:?} (also {what} {first})"));
            } else {
                seen.insert(name, i);
            }
        }
    }

    fn object(&mut self, path: &str, object: &Object) {
        self.animated(&join(path, "translation"), &object.translation);
        self.animated(&join(path, "rotation"), &object.rotation);
        self.euler_keys(path, &object.rotation, object.rotation_mode, object.rotation_euler.as_ref());
        self.animated(&join(path, "scale"), &object.scale);
        if let Some(MeshSource::File { path: file, clip, fps, .. }) = &object.mesh {
            if file.is_empty() {
                self.push(join(path, "mesh.path"), "empty model file path");
            }
            if clip.as_deref() == Some("") {
                self.push(
                    join(path, "mesh.clip"),
                    "empty clip name (leave the field out to play every frame)",
                );
            }
            if let Some(fps) = *fps {
                let at = join(path, "mesh.fps");
                if self.f64(&at, fps) && fps <= 0.0 {
                    self.push(at, format!("playback rate {fps} must be > 0 frames per second"));
                }
            }
        }
        if let Some(skeleton) = &object.skeleton {
            self.skeleton(&join(path, "skeleton"), skeleton);
        }
        self.deformer(&join(path, "deformer"), &object.deformer);
    }

    /// Euler keys (`rotation_euler`) need an Euler rotation mode (their order) and replace the
    /// rotation's quaternion keys, which must then be absent.
    fn euler_keys(
        &mut self,
        path: &str,
        rotation: &Animated<glam::Quat>,
        mode: crate::RotationMode,
        euler: Option<&Animated<Vec3>>,
    ) {
        let Some(euler) = euler else { return };
        let at = join(path, "rotation_euler");
        self.animated(&at, euler);
        if mode.euler().is_none() {
            self.push(
                join(path, "rotation_mode"),
                "Euler keys (rotation_euler) need an Euler rotation mode, which gives their order; this one is Quaternion",
            );
        }
        if rotation.is_animated() {
            self.push(
                join(path, "rotation.track"),
                format!(
                    "{} quaternion keys beside Euler keys (rotation_euler): the rotation is one or the other; remove the quaternion keys or rotation_euler",
                    rotation.track.len()
                ),
            );
        }
    }

    fn skeleton(&mut self, path: &str, skeleton: &Skeleton) {
        let jp = |i: usize| format!("{path}.joints[{i}]");
        if skeleton.joints.is_empty() {
            self.push(join(path, "joints"), "a skeleton needs at least one joint");
        }
        for (i, joint) in skeleton.joints.iter().enumerate() {
            match joint.parent {
                None if i > 0 => self.push(
                    join(&jp(i), "parent"),
                    "only the first joint may be a root (parent None); give this joint a parent",
                ),
                Some(_) if i == 0 => {
                    self.push(join(&jp(i), "parent"), "the first joint must be the root (parent None)")
                }
                Some(p) if p >= skeleton.joints.len() => self.push(
                    join(&jp(i), "parent"),
                    format!("parent {p} is out of range (the skeleton has {} joints)", skeleton.joints.len()),
                ),
                Some(p) if p >= i => self.push(
                    join(&jp(i), "parent"),
                    format!("parent {p} must come before joint {i} (joints are stored parents first)"),
                ),
                _ => {}
            }
            self.value(&join(&jp(i), "rest_translation"), &joint.rest_translation);
            self.rotation(&join(&jp(i), "rest_rotation"), &joint.rest_rotation);
            self.animated(&join(&jp(i), "translation"), &joint.translation);
            self.animated(&join(&jp(i), "rotation"), &joint.rotation);
            self.euler_keys(&jp(i), &joint.rotation, joint.rotation_mode, joint.rotation_euler.as_ref());
            self.animated(&join(&jp(i), "scale"), &joint.scale);
        }
        self.unique_names(
            "joint",
            skeleton.joints.iter().enumerate().map(|(i, j)| (join(&jp(i), "name"), j.name.as_str())),
        );
        self.animated(&join(path, "root_translation"), &skeleton.root_translation);
        let cp = |i: usize| format!("{path}.ik_constraints[{i}]");
        for (i, constraint) in skeleton.ik_constraints.iter().enumerate() {
            self.ik_constraint(&cp(i), skeleton, constraint);
        }
        self.unique_names(
            "IK constraint",
            skeleton.ik_constraints.iter().enumerate().map(|(i, c)| (join(&cp(i), "name"), c.name.as_str())),
        );
    }

    fn ik_constraint(&mut self, path: &str, skeleton: &Skeleton, c: &IkConstraint) {
        if let Err(e) = ConstraintChain::new(skeleton, c) {
            let field = match e {
                ConstraintError::EndOutOfRange { .. } => "end",
                ConstraintError::TooFewBones { .. } | ConstraintError::ChainTooLong { .. } => "bones",
                _ => "",
            };
            self.push(join(path, field), e.to_string());
        }
        self.animated(&join(path, "target"), &c.target);
        if let Some(pole) = &c.pole {
            self.value(&join(path, "pole"), pole);
        }
        self.animated(&join(path, "blend"), &c.blend);
        let blends = std::iter::once((join(path, "blend.value"), c.blend.value)).chain(
            c.blend
                .track
                .keys
                .iter()
                .enumerate()
                .map(|(i, k)| (format!("{path}.blend.track[{i}].value"), k.value)),
        );
        for (p, v) in blends {
            if v.is_finite() && !(0.0..=1.0).contains(&v) {
                self.push(p, format!("IK/FK blend {v} is outside [0, 1] (0 = keyed FK, 1 = IK)"));
            }
        }
    }

    fn deformer(&mut self, path: &str, d: &DeformerSettings) {
        for (name, v) in [
            ("blend_parent_fraction", d.blend_parent_fraction),
            ("blend_child_fraction", d.blend_child_fraction),
        ] {
            let p = join(path, name);
            if self.f32(&p, v) && !(0.0..=1.0).contains(&v) {
                self.push(p, format!("{v} is outside [0, 1]"));
            }
        }
    }

    fn light(&mut self, path: &str, light: &Light) {
        self.animated(&join(path, "position"), &light.position);
        self.animated(&join(path, "direction"), &light.direction);
        self.animated(&join(path, "colour"), &light.colour);
        self.animated(&join(path, "intensity"), &light.intensity);
        if !matches!(light.kind, LightKind::Point) {
            let dir = &light.direction;
            if dir.value.is_finite() && dir.value.length() < 1e-6 {
                self.push(join(path, "direction.value"), "zero direction");
            }
            for (i, key) in dir.track.keys.iter().enumerate() {
                if key.value.is_finite() && key.value.length() < 1e-6 {
                    self.push(format!("{path}.direction.track[{i}].value"), "zero direction");
                }
            }
        }
        let colours = std::iter::once((join(path, "colour.value"), light.colour.value)).chain(
            light
                .colour
                .track
                .keys
                .iter()
                .enumerate()
                .map(|(i, k)| (format!("{path}.colour.track[{i}].value"), k.value)),
        );
        for (p, c) in colours {
            if c.is_finite() && c.min_element() < 0.0 {
                self.push(p, format!("negative colour component in {c}"));
            }
        }
        let intensities = std::iter::once((join(path, "intensity.value"), light.intensity.value)).chain(
            light
                .intensity
                .track
                .keys
                .iter()
                .enumerate()
                .map(|(i, k)| (format!("{path}.intensity.track[{i}].value"), k.value)),
        );
        for (p, v) in intensities {
            if v < 0.0 {
                self.push(p, format!("negative intensity {v}"));
            }
        }
        if let LightKind::Spot { cutoff_deg, inner_angle_deg, dropoff } = light.kind {
            let kp = join(path, "kind");
            let cutoff_ok = self.f32(&join(&kp, "cutoff_deg"), cutoff_deg);
            let inner_ok = self.f32(&join(&kp, "inner_angle_deg"), inner_angle_deg);
            if self.f32(&join(&kp, "dropoff"), dropoff) && dropoff < 0.0 {
                self.push(join(&kp, "dropoff"), format!("negative dropoff {dropoff}"));
            }
            if cutoff_ok && !(cutoff_deg > 0.0 && cutoff_deg <= 90.0) {
                self.push(join(&kp, "cutoff_deg"), format!("{cutoff_deg}° is outside (0°, 90°]"));
            }
            if cutoff_ok && inner_ok && !(inner_angle_deg > 0.0 && inner_angle_deg <= cutoff_deg) {
                self.push(
                    join(&kp, "inner_angle_deg"),
                    format!("{inner_angle_deg}° must be in (0°, cutoff_deg = {cutoff_deg}°]"),
                );
            }
        }
    }

    fn camera(&mut self, path: &str, c: &Camera) {
        self.value(&join(path, "target"), &c.target);
        self.f32(&join(path, "yaw_deg"), c.yaw_deg);
        self.f32(&join(path, "pitch_deg"), c.pitch_deg);
        if self.f32(&join(path, "distance"), c.distance) && c.distance <= 0.0 {
            self.push(join(path, "distance"), format!("{} must be > 0", c.distance));
        }
        if self.f32(&join(path, "fov_y_deg"), c.fov_y_deg) && !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
            self.push(join(path, "fov_y_deg"), format!("{}° is outside (0°, 180°)", c.fov_y_deg));
        }
    }
}

impl Checker {
    fn scene_camera(&mut self, path: &str, camera: &SceneCamera, scene: &Scene) {
        self.animated(&join(path, "translation"), &camera.translation);
        self.animated(&join(path, "rotation"), &camera.rotation);
        self.animated(&join(path, "lens"), &camera.lens);
        self.animated(&join(path, "visible"), &camera.visible);
        crate::channel_id::attribute_id::visibility_problems(
            &join(path, "visible"),
            &camera.visible,
            &mut |at, message| self.push(at, message),
        );
        let (range, what): (fn(f32) -> bool, &str) = match camera.projection {
            Projection::Perspective => (|v| v > 0.0 && v < 180.0, "a field of view must be in (0°, 180°)"),
            Projection::FocalLength { sensor_height_mm } => {
                let at = join(path, "projection.sensor_height_mm");
                if self.f32(&at, sensor_height_mm) && sensor_height_mm <= 0.0 {
                    self.push(at, format!("sensor height {sensor_height_mm} mm must be > 0"));
                }
                (|v| v > 0.0, "a focal length must be > 0 mm")
            }
            Projection::Orthographic => (|v| v > 0.0, "an orthographic view height must be > 0"),
        };
        let lenses = std::iter::once((join(path, "lens.value"), camera.lens.value)).chain(
            camera
                .lens
                .track
                .keys
                .iter()
                .enumerate()
                .map(|(i, k)| (format!("{path}.lens.track[{i}].value"), k.value)),
        );
        for (p, v) in lenses {
            if v.is_finite() && !range(v) {
                self.push(p, format!("{v}: {what}"));
            }
        }
        let near_ok = self.f32(&join(path, "near"), camera.near);
        if near_ok && camera.near <= 0.0 {
            self.push(join(path, "near"), format!("near plane {} must be > 0", camera.near));
        }
        if let Some(far) = camera.far {
            if self.f32(&join(path, "far"), far) && near_ok && far <= camera.near {
                self.push(
                    join(path, "far"),
                    format!("far plane {far} must be beyond the near plane {}", camera.near),
                );
            }
        } else if camera.projection == Projection::Orthographic {
            self.push(join(path, "far"), "an orthographic camera needs a far plane");
        }
        if let Some(aim) = &camera.aim {
            let ap = join(path, "aim");
            if self.value(&join(&ap, "up"), &aim.up) && aim.up.length() < 1e-6 {
                self.push(join(&ap, "up"), "zero up direction");
            }
            self.animated(&join(&ap, "roll"), &aim.roll);
            self.unit_interval(&join(&ap, "influence"), &aim.influence, "aim influence");
            self.target(&join(&ap, "target"), &aim.target, scene, "to aim at");
        }
    }

    /// An aim or constraint target: a finite point, an existing object, an existing joint.
    fn target(&mut self, tp: &str, target: &AimTarget, scene: &Scene, purpose: &str) {
        match target {
            AimTarget::Point(p) => {
                self.value(tp, p);
            }
            AimTarget::Object(name) => {
                if !scene.objects.iter().any(|o| &o.name == name) {
                    self.push(tp, format!("no object named {name:?} {purpose}"));
                }
            }
            AimTarget::Joint { object, joint } => match scene.objects.iter().find(|o| &o.name == object) {
                None => self.push(tp, format!("no object named {object:?} {purpose}")),
                Some(o) => {
                    let joints = o.skeleton.as_ref().map(|s| s.joints.as_slice()).unwrap_or_default();
                    if !joints.iter().any(|j| &j.name == joint) {
                        self.push(tp, format!("object {object:?} has no joint named {joint:?} {purpose}"));
                    }
                }
            },
        }
    }

    /// Rule 12: object constraints (docs/constraints.md).
    fn object_constraints(&mut self, scene: &Scene) {
        for (o, object) in scene.objects.iter().enumerate() {
            let cp = |i: usize| format!("objects[{o}].constraints[{i}]");
            for (i, c) in object.constraints.iter().enumerate() {
                self.object_constraint(&cp(i), object, c, scene);
            }
            self.unique_names(
                "constraint",
                object.constraints.iter().enumerate().map(|(i, c)| (join(&cp(i), "name"), c.name.as_str())),
            );
        }
        let (_, on_cycle) = crate::object_constraint::evaluation_order(scene);
        for o in on_cycle {
            let names: Vec<&str> = crate::object_constraint::dependencies(scene, o)
                .into_iter()
                .map(|d| scene.objects[d].name.as_str())
                .collect();
            self.push(
                format!("objects[{o}].constraints"),
                format!(
                    "the constraints of {:?} form a cycle (its targets {} depend on it again): they are not applied",
                    scene.objects[o].name,
                    names.join(", ")
                ),
            );
        }
    }

    /// A keyed value whose value and keys must lie in [0, 1].
    fn unit_interval(&mut self, at: &str, a: &Animated<f32>, what: &str) {
        self.animated(at, a);
        let values = std::iter::once((join(at, "value"), a.value))
            .chain(a.track.keys.iter().enumerate().map(|(i, k)| (format!("{at}.track[{i}].value"), k.value)));
        for (p, v) in values {
            if v.is_finite() && !(0.0..=1.0).contains(&v) {
                self.push(p, format!("{what} {v} is outside [0, 1]"));
            }
        }
    }

    fn object_constraint(&mut self, path: &str, object: &Object, c: &ObjectConstraint, scene: &Scene) {
        use crate::object_constraint::ConstraintKind as K;
        self.unit_interval(&join(path, "influence"), &c.influence, "influence");
        let target = |this: &mut Self, tp: String, t: &AimTarget| {
            this.target(&tp, t, scene, "to constrain to");
            let own = match t {
                AimTarget::Object(name) | AimTarget::Joint { object: name, .. } => name == &object.name,
                AimTarget::Point(_) => false,
            };
            if own {
                this.push(tp, format!("{:?} cannot be constrained to itself", object.name));
            }
        };
        match &c.kind {
            K::AimAt { target: t, up, .. } => {
                target(self, join(path, "kind.target"), t);
                let up_path = join(path, "kind.up");
                if self.value(&up_path, up) && up.length() < 1e-6 {
                    self.push(up_path, "zero up direction");
                }
            }
            K::CopyLocation { target: t } | K::CopyRotation { target: t } => {
                target(self, join(path, "kind.target"), t);
            }
            K::ChildOf { parents, parent } => {
                for (i, p) in parents.iter().enumerate() {
                    target(self, format!("{path}.kind.parents[{i}].target"), &p.target);
                    if !p.offset.is_finite() || p.offset.determinant().abs() < 1e-12 {
                        self.push(
                            format!("{path}.kind.parents[{i}].offset"),
                            "the offset is not a finite, invertible matrix",
                        );
                    }
                }
                self.animated(&join(path, "kind.parent"), parent);
            }
            K::FollowPath { points, space, offset, .. } => {
                if points.len() < 2 {
                    self.push(
                        join(path, "kind.points"),
                        format!("a path needs at least 2 points; it has {}", points.len()),
                    );
                }
                for (i, p) in points.iter().enumerate() {
                    self.value(&format!("{path}.kind.points[{i}]"), p);
                }
                if let Some(space) = space {
                    target(self, join(path, "kind.space"), &AimTarget::Object(space.clone()));
                }
                self.unit_interval(&join(path, "kind.offset"), offset, "path offset");
            }
        }
    }

    fn cameras_and_markers(&mut self, scene: &Scene) {
        for (i, camera) in scene.cameras.iter().enumerate() {
            self.scene_camera(&format!("cameras[{i}]"), camera, scene);
        }
        self.unique_names(
            "camera",
            scene.cameras.iter().enumerate().map(|(i, c)| (format!("cameras[{i}].name"), c.name.as_str())),
        );
        let known = |name: &str| scene.cameras.iter().any(|c| c.name == name);
        if let Some(name) = scene.active_camera.as_deref().filter(|n| !known(n)) {
            self.push("active_camera", format!("no camera named {name:?}"));
        }
        for (i, marker) in scene.markers.iter().enumerate() {
            if let Some(name) = marker.camera.as_deref().filter(|n| !known(n)) {
                self.push(format!("markers[{i}].camera"), format!("no camera named {name:?}"));
            }
        }
        if let Some(RenderSize { width, height }) = scene.render_size {
            for (name, v) in [("width", width), ("height", height)] {
                if !(1..=RenderSize::MAX_SIDE).contains(&v) {
                    self.push(
                        format!("render_size.{name}"),
                        format!("{v} pixels is outside 1..={}", RenderSize::MAX_SIDE),
                    );
                }
            }
        }
    }
}

impl Scene {
    /// The problems of the actions (docs/actions.md): names unique, not empty, without '/';
    /// each object's action listed; each stored channel's path naming an object's channel of
    /// the same value type, once per action, with valid keys.
    fn action_problems(&self, c: &mut Checker) {
        c.unique_names(
            "action",
            self.actions.iter().enumerate().map(|(i, a)| (format!("actions[{i}].name"), a.name.as_str())),
        );
        for (i, object) in self.objects.iter().enumerate() {
            if let Some(name) = &object.action {
                if self.action_index(name).is_none() {
                    c.push(format!("objects[{i}].action"), format!("there is no action {name:?} in actions"));
                }
            }
        }
        for (a, action) in self.actions.iter().enumerate() {
            let mut seen = std::collections::HashSet::new();
            for (k, channel) in action.channels.iter().enumerate() {
                let here = format!("actions[{a}].channels[{k}]");
                if !seen.insert(channel.path.as_str()) {
                    c.push(format!("{here}.path"), format!("channel {:?} is stored twice", channel.path));
                }
                match &channel.keys {
                    crate::action_keys::ActionKeys::Vec3(k) => c.animated(&format!("{here}.keys"), k),
                    crate::action_keys::ActionKeys::Rotation(k) => c.animated(&format!("{here}.keys"), k),
                    crate::action_keys::ActionKeys::Scalar(k) => c.animated(&format!("{here}.keys"), k),
                }
            }
        }
        for p in self.stored_path_problems() {
            c.push(p.path, p.message);
        }
    }

    #[must_use]
    pub fn problems(&self) -> Vec<Problem> {
        let mut c = Checker { problems: Vec::new() };
        if c.f64("fps", self.fps) && self.fps <= 0.0 {
            c.push("fps", format!("{} must be > 0", self.fps));
        }
        if self.frame_range.start > self.frame_range.end {
            c.push(
                "frame_range",
                format!(
                    "empty range: start {} is after end {}",
                    self.frame_range.start, self.frame_range.end
                ),
            );
        }
        if let Some(p) = self.preview_range.filter(|p| p.start > p.end) {
            c.push("preview_range", format!("empty range: start {} is after end {}", p.start, p.end));
        }
        c.value("ambient", &self.ambient);
        for (i, object) in self.objects.iter().enumerate() {
            c.object(&format!("objects[{i}]"), object);
        }
        c.object_constraints(self);
        c.unique_names(
            "object",
            self.objects.iter().enumerate().map(|(i, o)| (format!("objects[{i}].name"), o.name.as_str())),
        );
        for (i, light) in self.lights.iter().enumerate() {
            c.light(&format!("lights[{i}]"), light);
        }
        c.unique_names(
            "light",
            self.lights.iter().enumerate().map(|(i, l)| (format!("lights[{i}].name"), l.name.as_str())),
        );
        for id in crate::channel_id::attribute_id::every(self) {
            match id.get(self) {
                Some(crate::channel_id::ChannelRef::Scalar(a)) => c.animated(&id.field_path(), a),
                Some(crate::channel_id::ChannelRef::Vec3(a)) => c.animated(&id.field_path(), a),
                _ => {}
            }
            crate::channel_id::attribute_id::attribute_problems(self, id, &mut |path, message| {
                c.push(path, message)
            });
        }
        c.camera("camera", &self.camera);
        c.cameras_and_markers(self);
        for (i, clip) in self.sounds.iter().enumerate() {
            c.f64(&format!("sounds[{i}].start_frame"), clip.start_frame);
            if c.f64(&format!("sounds[{i}].gain"), f64::from(clip.gain)) && clip.gain < 0.0 {
                c.push(format!("sounds[{i}].gain"), format!("{} must be ≥ 0", clip.gain));
            }
            if clip.path.is_empty() {
                c.push(format!("sounds[{i}].path"), "the path is empty".to_owned());
            }
        }
        for (i, pose) in self.poses.iter().enumerate() {
            for (v, value) in pose.values.iter().enumerate() {
                let path = format!("poses[{i}].values[{v}].value");
                match value.value {
                    crate::channel_id::ChannelValue::Vec3(x) => {
                        c.value(&path, &x);
                    }
                    crate::channel_id::ChannelValue::Rotation(q) => c.rotation(&path, &q),
                    crate::channel_id::ChannelValue::Scalar(x) => {
                        c.value(&path, &x);
                    }
                }
            }
        }
        c.unique_names(
            "pose",
            self.poses.iter().enumerate().map(|(i, p)| (format!("poses[{i}].name"), p.name.as_str())),
        );
        self.action_problems(&mut c);
        clip_problems(self, &mut c);
        if let Some(image) = &self.reference_image {
            if image.path.is_empty() {
                c.push("reference_image.path", "the path is empty".to_owned());
            }
            if !(0.0..=1.0).contains(&image.opacity) {
                c.push("reference_image.opacity", format!("{} is outside 0..=1", image.opacity));
            }
        }
        c.problems
    }
}

/// The problems of the scene's clip tracks and layers, each at its field path
/// (docs/clips.md, "Checks").
pub(crate) fn clip_problems(scene: &crate::Scene, c: &mut Checker) {
    let unit = |c: &mut Checker, path: &str, a: &crate::key::Animated<f32>| {
        c.animated(path, a);
        let outside = std::iter::once(a.value)
            .chain(a.track.keys.iter().map(|k| k.value))
            .find(|v| !(0.0..=1.0).contains(v));
        if let Some(v) = outside {
            c.push(path, format!("{v} is outside 0..=1"));
        }
    };
    for (o, object) in scene.objects.iter().enumerate() {
        c.unique_names(
            "clip track",
            object
                .clip_tracks
                .iter()
                .enumerate()
                .map(|(t, track)| (format!("objects[{o}].clip_tracks[{t}].name"), track.name.as_str())),
        );
        for (t, track) in object.clip_tracks.iter().enumerate() {
            let mut previous_end: Option<f64> = None;
            for (s, strip) in track.strips.iter().enumerate() {
                let at = |field: &str| format!("objects[{o}].clip_tracks[{t}].strips[{s}].{field}");
                if scene.action_index(&strip.action).is_none() {
                    c.push(at("action"), format!("there is no action {:?} in actions", strip.action));
                }
                let finite = [
                    ("start", strip.start),
                    ("action_in", strip.action_in),
                    ("action_out", strip.action_out),
                    ("speed", strip.speed),
                    ("repeat", strip.repeat),
                    ("blend_in", strip.blend_in),
                    ("blend_out", strip.blend_out),
                ]
                .into_iter()
                .fold(true, |ok, (field, v)| c.f64(&at(field), v) && ok);
                if !finite {
                    continue;
                }
                if strip.action_out <= strip.action_in {
                    c.push(
                        at("action_out"),
                        format!("{} must be after action_in {}", strip.action_out, strip.action_in),
                    );
                }
                for (field, v) in [("speed", strip.speed), ("repeat", strip.repeat)] {
                    if v <= 0.0 {
                        c.push(at(field), format!("{v} must be > 0"));
                    }
                }
                for (field, v) in [("blend_in", strip.blend_in), ("blend_out", strip.blend_out)] {
                    if v < 0.0 {
                        c.push(at(field), format!("{v} must be ≥ 0"));
                    }
                }
                let length = strip.length();
                if length.is_finite()
                    && length > 0.0
                    && strip.blend_in + strip.blend_out > length * (1.0 + 1e-9)
                {
                    c.push(
                        at("blend_out"),
                        format!(
                            "blend in {} and blend out {} are longer than the strip ({length} frames)",
                            strip.blend_in, strip.blend_out
                        ),
                    );
                }
                if let Some(end) = previous_end {
                    if strip.start < end - 1e-9 {
                        c.push(
                            at("start"),
                            format!(
                                "frame {} is before the end of the strip before it (frame {end}): strips \
                                 of a track are in time order and do not overlap",
                                strip.start
                            ),
                        );
                    }
                }
                previous_end = Some(strip.end());
                unit(c, &at("influence"), &strip.influence);
            }
        }
    }
    c.unique_names(
        "layer",
        scene.layers.iter().enumerate().map(|(l, layer)| (format!("layers[{l}].name"), layer.name.as_str())),
    );
    for (l, layer) in scene.layers.iter().enumerate() {
        let path = format!("layers[{l}].action");
        if scene.action_index(&layer.action).is_none() {
            c.push(path, format!("there is no action {:?} in actions", layer.action));
        } else if let Some(o) = scene.objects.iter().position(|o| o.action.as_deref() == Some(&layer.action))
        {
            c.push(
                path,
                format!(
                    "action {:?} is active on object {:?}: a layer's action plays only in the layer",
                    layer.action, scene.objects[o].name
                ),
            );
        }
        unit(c, &format!("layers[{l}].weight"), &layer.weight);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::key::{Key, Tcb};
    use crate::scene::Joint;
    use crate::track::AnimatedTrack;
    use proptest::prelude::*;

    fn joint(name: &str, parent: Option<usize>) -> Joint {
        Joint::new(name, parent, Vec3::X, Quat::IDENTITY)
    }

    fn paths(scene: &Scene) -> Vec<String> {
        scene.problems().into_iter().map(|p| p.path).collect()
    }

    #[test]
    fn cameras_markers_and_render_size() {
        use crate::camera_object::{Aim, AimTarget, Marker, Projection, RenderSize, SceneCamera};
        let mut s = Scene::default();
        s.objects.push(crate::scene::Object::new("Arm"));
        let mut wide = SceneCamera::new("Wide", Vec3::Z);
        wide.aim = Some(Aim::at(AimTarget::Object("Arm".into())));
        s.cameras.push(wide);
        s.markers.push(Marker { name: "cut".into(), frame: 10, camera: Some("Wide".into()) });
        s.render_size = Some(RenderSize { width: 640, height: 360 });
        assert_eq!(s.problems(), Vec::new());

        let mut bad = SceneCamera::new("Wide", Vec3::Z);
        bad.projection = Projection::Orthographic;
        bad.lens.value = -1.0;
        bad.near = 0.0;
        bad.far = None;
        bad.aim = Some(Aim {
            up: Vec3::ZERO,
            ..Aim::at(AimTarget::Joint { object: "Arm".into(), joint: "elbow".into() })
        });
        s.cameras.push(bad);
        let mut focal = SceneCamera::new("Focal", Vec3::Z);
        focal.projection = Projection::FocalLength { sensor_height_mm: 0.0 };
        focal.lens.track = RawTrack::new(vec![Key::new(0.0, 50.0), Key::new(1.0, 0.0)]);
        s.cameras.push(focal);
        s.active_camera = Some("Tele".into());
        s.markers.push(Marker { name: "x".into(), frame: 0, camera: Some("Nope".into()) });
        s.render_size = Some(RenderSize { width: 0, height: 20000 });
        assert_eq!(
            paths(&s),
            [
                "cameras[1].lens.value",
                "cameras[1].near",
                "cameras[1].far",
                "cameras[1].aim.up",
                "cameras[1].aim.target",
                "cameras[2].projection.sensor_height_mm",
                "cameras[2].lens.track[1].value",
                "cameras[1].name",
                "active_camera",
                "markers[1].camera",
                "render_size.width",
                "render_size.height",
            ]
        );
        assert!(s.problems()[4].message.contains("has no joint named \"elbow\""));
    }

    #[test]
    fn default_scene_is_valid() {
        assert_eq!(Scene::default().problems(), Vec::new());
    }

    #[test]
    fn timing_and_non_finite_numbers() {
        let mut s = Scene { fps: 0.0, ..Scene::default() };
        s.frame_range.start = 10;
        s.frame_range.end = 9;
        s.ambient.y = f32::NAN;
        s.camera.distance = f32::INFINITY;
        assert_eq!(paths(&s), ["fps", "frame_range", "ambient.y", "camera.distance"]);
        s.fps = f64::NAN;
        assert_eq!(s.problems()[0].message, "not a finite number (NaN)");
    }

    #[test]
    fn model_file_clip_and_fps() {
        let mut s = Scene::default();
        let mut o = Object::new("Sydney");
        o.mesh = Some(MeshSource::File {
            path: "sydney.md2".into(),
            mesh: None,
            clip: Some("run".into()),
            fps: Some(10.0),
        });
        s.objects.push(o);
        assert_eq!(s.problems(), Vec::new());
        for (fps, message) in [
            (0.0, "playback rate 0 must be > 0 frames per second"),
            (-2.5, "playback rate -2.5 must be > 0 frames per second"),
            (f64::NAN, "not a finite number (NaN)"),
            (f64::INFINITY, "not a finite number (+inf)"),
        ] {
            let Some(MeshSource::File { fps: f, .. }) = &mut s.objects[0].mesh else { panic!("a file mesh") };
            *f = Some(fps);
            let problems = s.problems();
            assert_eq!(problems.len(), 1, "{fps}: {problems:?}");
            assert_eq!(problems[0].path, "objects[0].mesh.fps");
            assert_eq!(problems[0].message, message);
        }
        s.objects[0].mesh =
            Some(MeshSource::File { path: String::new(), mesh: None, clip: Some(String::new()), fps: None });
        assert_eq!(paths(&s), ["objects[0].mesh.path", "objects[0].mesh.clip"]);
    }

    #[test]
    fn key_problems_have_key_paths() {
        let mut s = Scene::default();
        let mut o = Object::new("Cube");
        o.translation.track = RawTrack::new(vec![
            Key::new(0.0, Vec3::ZERO),
            Key::new(1.0, Vec3::new(0.0, f32::NEG_INFINITY, 0.0)),
            Key::new(0.5, Vec3::ONE).with_tcb(Tcb::new(2.0, 0.0, 0.0)),
            Key::new(0.5, Vec3::ONE).with_interpolation(Interpolation::Hermite),
            Key::new(2.0, Vec3::ONE),
        ]);
        o.rotation.track = RawTrack::new(vec![Key::new(0.0, Quat::from_xyzw(0.0, 0.0, 0.0, 0.0))]);
        s.objects.push(o);
        let problems = s.problems();
        let got: Vec<&str> = problems.iter().map(|p| p.path.as_str()).collect();
        assert_eq!(
            got,
            [
                "objects[0].translation.track[1].value.y",
                "objects[0].translation.track[2].time",
                "objects[0].translation.track[2].tcb.tension",
                "objects[0].translation.track[3].time",
                "objects[0].translation.track[3].out_tangent",
                "objects[0].translation.track[4].in_tangent",
                "objects[0].rotation.track[0].value",
            ]
        );
        assert!(problems[1].message.contains("out of order"), "{}", problems[1].message);
        assert!(problems[3].message.contains("duplicate"), "{}", problems[3].message);
    }

    #[test]
    fn valid_scene_means_valid_tracks() {
        // Every `Animated` of a scene without problems builds with `AnimatedTrack::new`.
        let mut a = Animated::constant(Vec3::ZERO);
        a.track = RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::ONE)]);
        let mut c = Checker { problems: Vec::new() };
        c.animated("a", &a);
        assert!(c.problems.is_empty());
        assert!(AnimatedTrack::new(&a).is_ok());
        assert_eq!(
            track_error_path("objects[1].rotation", &TrackError::Unsorted { index: 4 }),
            "objects[1].rotation.track[4].time"
        );
        assert_eq!(
            track_error_path("a", &TrackError::MissingTangent { index: 2, side: TangentSide::Out }),
            "a.track[2].out_tangent"
        );
        assert_eq!(track_error_path("a", &TrackError::NonFiniteStaticValue), "a.value");
    }

    #[test]
    fn joint_parents_and_names() {
        let mut s = Scene::default();
        let mut o = Object::new("Arm");
        o.skeleton = Some(Skeleton {
            joints: vec![
                joint("a", None),
                joint("b", Some(2)),
                joint("c", Some(7)),
                joint("b", Some(0)),
                joint("d", None),
            ],
            root_translation: Animated::constant(Vec3::ZERO),
            ik_constraints: Vec::new(),
        });
        s.objects.push(o);
        s.objects.push(Object::new("Arm"));
        let problems = s.problems();
        let got: Vec<String> = problems.iter().map(ToString::to_string).collect();
        assert_eq!(
            got,
            [
                "objects[0].skeleton.joints[1].parent: parent 2 must come before joint 1 (joints are stored parents first)",
                "objects[0].skeleton.joints[2].parent: parent 7 is out of range (the skeleton has 5 joints)",
                "objects[0].skeleton.joints[4].parent: only the first joint may be a root (parent None); give this joint a parent",
                "objects[0].skeleton.joints[3].name: duplicate joint name \"b\" (also joint 1)",
                "objects[1].name: duplicate object name \"Arm\" (also object 0)",
            ]
        );
    }

    #[test]
    fn light_rules() {
        let mut s = Scene::default();
        s.lights.push(Light {
            name: "Spot".into(),
            kind: LightKind::Spot { cutoff_deg: 30.0, inner_angle_deg: 40.0, dropoff: -1.0 },
            enabled: true,
            position: Animated::constant(Vec3::ZERO),
            direction: Animated::constant(Vec3::ZERO),
            colour: Animated::constant(Vec3::new(1.0, -0.5, 1.0)),
            intensity: Animated::constant(-2.0),
            attributes: Default::default(),
        });
        assert_eq!(
            paths(&s),
            [
                "lights[0].direction.value",
                "lights[0].colour.value",
                "lights[0].intensity.value",
                "lights[0].kind.dropoff",
                "lights[0].kind.inner_angle_deg",
            ]
        );
    }

    fn problems_of<T: KeyValue>(a: &Animated<T>) -> Vec<Problem> {
        let mut c = Checker { problems: Vec::new() };
        c.animated("a", a);
        c.problems
    }

    /// What the track validator accepts, plus a valid static value: `problems` also checks the
    /// static value of a keyed property (every number in a file must be finite), which
    /// `AnimatedTrack::new` ignores once there are keys.
    fn agrees<T: KeyValue + crate::track::TrackValue>(a: &Animated<T>) -> bool {
        AnimatedTrack::new(a).is_ok() && a.value.is_all_finite() && !a.value.is_degenerate()
    }

    /// Numbers that hit every rule: ordinary, boundary, out of range, non-finite.
    fn number() -> impl Strategy<Value = f32> + Clone {
        prop_oneof![
            4 => -1.0f32..1.0,
            1 => Just(1.0f32),
            1 => Just(-1.0f32),
            1 => Just(1.5f32),
            1 => Just(0.0f32),
            1 => Just(f32::NAN),
            1 => Just(f32::INFINITY),
            1 => Just(1e-7f32),
        ]
    }

    fn raw_keys<T: std::fmt::Debug + Clone>(
        value: impl Strategy<Value = T> + Clone,
    ) -> impl Strategy<Value = Vec<Key<T>>> {
        let key = (
            prop_oneof![8 => 0.0f64..0.5, 1 => Just(f64::NAN), 1 => Just(0.0f64)],
            value.clone(),
            (number(), number(), number()),
            0..4u8,
            prop::option::of(value.clone()),
            prop::option::of(value),
            prop::option::weighted(0.3, spin()),
        );
        prop::collection::vec(key, 0..6).prop_map(|raw| {
            let mut t = 0.0;
            raw.into_iter()
                .map(|(dt, value, (tension, continuity, bias), mode, in_tangent, out_tangent, spin)| {
                    t += dt;
                    Key {
                        time: t,
                        value,
                        interpolation: [
                            Interpolation::Step,
                            Interpolation::Linear,
                            Interpolation::Tcb,
                            Interpolation::Hermite,
                        ][mode as usize],
                        tcb: Tcb::new(tension, continuity, bias),
                        in_tangent,
                        out_tangent,
                        spin,
                        key_type: crate::KeyType::Keyframe,
                    }
                })
                .collect()
        })
    }

    /// Spins that hit every rule: ordinary and extreme turns, angles that may or may not agree
    /// with the (random) values, zero and non-finite axes and angles.
    fn spin() -> impl Strategy<Value = Spin> + Clone {
        prop_oneof![
            3 => (-3..=3i32).prop_map(Spin::Turns),
            1 => prop_oneof![Just(1000i32), Just(-1000), Just(1001), Just(i32::MIN)].prop_map(Spin::Turns),
            3 => (number(), number(), number(), prop_oneof![
                3 => -720.0..720.0f64,
                1 => Just(360.0f64),
                1 => Just(360_000.0f64),
                1 => Just(360_000.5f64),
                1 => Just(f64::NAN),
            ])
                .prop_map(|(x, y, z, degrees)| Spin::Angle { axis: Vec3::new(x, y, z), degrees }),
        ]
    }

    fn vec3() -> impl Strategy<Value = Vec3> + Clone {
        (number(), number(), number()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    fn quat() -> impl Strategy<Value = Quat> + Clone {
        prop_oneof![
            4 => (number(), number(), number(), number()).prop_map(|(x, y, z, w)| Quat::from_xyzw(x, y, z, w)),
            1 => Just(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)),
            1 => Just(Quat::from_xyzw(0.0, 0.0, 0.0, 9e-7)),
            1 => Just(Quat::from_xyzw(0.0, 0.0, 0.0, 1.1e-6)),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn same_rules_as_the_track_validator_vec3(value in vec3(), keys in raw_keys(vec3())) {
            let a = Animated::new(value, RawTrack::new(keys));
            prop_assert_eq!(problems_of(&a).is_empty(), agrees(&a), "{:?}", a);
        }

        #[test]
        fn same_rules_as_the_track_validator_quat(value in quat(), keys in raw_keys(quat())) {
            let a = Animated::new(value, RawTrack::new(keys));
            prop_assert_eq!(problems_of(&a).is_empty(), agrees(&a), "{:?}", a);
        }

        #[test]
        fn same_rules_as_the_track_validator_scalar(value in number(), keys in raw_keys(number())) {
            let a = Animated::new(value, RawTrack::new(keys));
            prop_assert_eq!(problems_of(&a).is_empty(), agrees(&a), "{:?}", a);
        }
    }
}
