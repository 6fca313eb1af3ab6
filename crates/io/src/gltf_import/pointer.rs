//! Reading `KHR_animation_pointer` channels and `KHR_node_visibility` from the raw JSON
//! (the types and the table of pointers are in [`crate::gltf_pointer`]).

use glam::{Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use keyrig_core::Interpolation;
use serde_json::Value;

use super::{at, check_accessor, count_matches, make_track, ptr, GltfError, GltfErrorKind, Location, Reader};
use crate::gltf_pointer::{PointerChannel, PointerKeys, PointerTarget, SkippedChannel};
use crate::model::{ChannelTarget, ImportedModel, ModelChannel, ModelProjection, WeightsTrack};

/// A channel without `node`, taken out of the JSON before gltf-json reads it.
#[derive(Clone, Debug)]
pub(crate) struct SetAside {
    animation: usize,
    /// Its index in the file's channel list.
    channel: usize,
    sampler: Option<usize>,
    pointer: Option<String>,
}

/// What the raw JSON gave besides gltf-json's document.
#[derive(Clone, Debug, Default)]
pub(crate) struct Raw {
    set_aside: Vec<SetAside>,
    /// Per animation: the file index of each channel gltf-json holds (for error pointers).
    pub kept: Vec<Vec<usize>>,
    /// `KHR_node_visibility` of the nodes that say.
    pub node_visible: Vec<(usize, bool)>,
}

impl Raw {
    /// The file's index of channel `c` of animation `a` as gltf-json numbers it.
    pub(crate) fn file_channel(&self, a: usize, c: usize) -> usize {
        self.kept.get(a).and_then(|k| k.get(c)).copied().unwrap_or(c)
    }
}

fn json_error(e: &serde_json::Error, chunk_offset: usize) -> GltfError {
    at(
        Location::LineColumn { line: e.line(), column: e.column(), chunk_offset },
        GltfErrorKind::Json(crate::message::clip_long_tokens(&e.to_string()).into_owned()),
    )
}

/// Parses the glTF JSON; channels without `node` are set aside when gltf-json refuses them.
pub(crate) fn parse_root(json: &[u8], chunk_offset: usize) -> Result<(gltf::json::Root, Raw), GltfError> {
    let mentions = |needle: &[u8]| json.windows(needle.len()).any(|w| w == needle);
    match gltf::json::deserialize::from_slice::<gltf::json::Root>(json) {
        Ok(root) => {
            let mut raw = Raw {
                kept: root.animations.iter().map(|a| (0..a.channels.len()).collect()).collect(),
                ..Raw::default()
            };
            if mentions(b"KHR_node_visibility") {
                let value: Value = serde_json::from_slice(json).map_err(|e| json_error(&e, chunk_offset))?;
                raw.node_visible = node_visibility(&value)?;
            }
            Ok((root, raw))
        }
        Err(original) => {
            let Ok(mut value) = serde_json::from_slice::<Value>(json) else {
                return Err(json_error(&original, chunk_offset));
            };
            let (set_aside, kept) = take_nodeless_channels(&mut value);
            if set_aside.is_empty() {
                return Err(json_error(&original, chunk_offset));
            }
            let node_visible = node_visibility(&value)?;
            let root: gltf::json::Root = serde_json::from_value(value).map_err(|e| {
                ptr(
                    "",
                    GltfErrorKind::Json(format!(
                        "{} (read with the {} animation channels without a node set aside)",
                        crate::message::clip_long_tokens(&e.to_string()),
                        set_aside.len()
                    )),
                )
            })?;
            Ok((root, Raw { set_aside, kept, node_visible }))
        }
    }
}

/// Removes every channel whose target has no `node`; returns them and, per animation, the file
/// index of each channel kept.
fn take_nodeless_channels(root: &mut Value) -> (Vec<SetAside>, Vec<Vec<usize>>) {
    let mut set_aside = Vec::new();
    let mut kept_all = Vec::new();
    let Some(animations) = root.get_mut("animations").and_then(Value::as_array_mut) else {
        return (set_aside, kept_all);
    };
    for (a, animation) in animations.iter_mut().enumerate() {
        let mut kept = Vec::new();
        if let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) {
            let all = std::mem::take(channels);
            for (c, channel) in all.into_iter().enumerate() {
                let target = channel.get("target");
                if target.is_some_and(|t| t.get("node").is_none()) {
                    let pointer = target
                        .and_then(|t| t.pointer("/extensions/KHR_animation_pointer/pointer"))
                        .and_then(Value::as_str)
                        .map(str::to_owned);
                    let sampler =
                        channel.get("sampler").and_then(Value::as_u64).and_then(|s| usize::try_from(s).ok());
                    set_aside.push(SetAside { animation: a, channel: c, sampler, pointer });
                } else {
                    kept.push(c);
                    channels.push(channel);
                }
            }
        }
        kept_all.push(kept);
    }
    (set_aside, kept_all)
}

/// `KHR_node_visibility` of every node that has it.
fn node_visibility(root: &Value) -> Result<Vec<(usize, bool)>, GltfError> {
    let mut out = Vec::new();
    let Some(nodes) = root.get("nodes").and_then(Value::as_array) else { return Ok(out) };
    for (n, node) in nodes.iter().enumerate() {
        let Some(ext) = node.pointer("/extensions/KHR_node_visibility") else { continue };
        match ext.get("visible") {
            None => out.push((n, true)),
            Some(Value::Bool(b)) => out.push((n, *b)),
            Some(other) => {
                return Err(ptr(
                    format!("/nodes/{n}/extensions/KHR_node_visibility/visible"),
                    GltfErrorKind::Invalid(format!("visible must be true or false, not {other}")),
                ))
            }
        }
    }
    Ok(out)
}

/// The key times of a sampler's input accessor: checked, finite and strictly increasing.
pub(crate) fn key_times(
    cx: &Reader<'_, '_>,
    input: &gltf::Accessor<'_>,
    here: &str,
) -> Result<Vec<f32>, GltfError> {
    const F32: &[DataType] = &[DataType::F32];
    let key_count = check_accessor(cx, input, "animation input", &[Dimensions::Scalar], F32)?;
    let times: Vec<f32> =
        gltf::accessor::Iter::<f32>::new(input.clone(), cx.get()).map(Iterator::collect).unwrap_or_default();
    count_matches(times.len(), key_count, &format!("{here}/input"))?;
    let at_accessor = format!("/accessors/{}", input.index());
    for (k, w) in times.windows(2).enumerate() {
        if w[0].partial_cmp(&w[1]) != Some(std::cmp::Ordering::Less) {
            return Err(ptr(
                &at_accessor,
                GltfErrorKind::Animation(format!(
                    "key times must increase: key {k} at {} then {}",
                    w[0], w[1]
                )),
            ));
        }
    }
    if times.iter().any(|t| !t.is_finite()) {
        return Err(ptr(&at_accessor, GltfErrorKind::NonFinite("key time".into())));
    }
    Ok(times)
}

/// What a pointer names, or why it is skipped.
enum Parsed {
    Node(usize, NodePart),
    Target(PointerTarget),
}

#[derive(Clone, Copy)]
enum NodePart {
    Translation,
    Rotation,
    Scale,
    Weights,
}

/// Splits an RFC 6901 pointer into its unescaped tokens.
fn tokens(pointer: &str) -> Option<Vec<String>> {
    let rest = pointer.strip_prefix('/')?;
    Some(rest.split('/').map(|t| t.replace("~1", "/").replace("~0", "~")).collect())
}

/// Why a pointer channel is set aside: its pointer names nothing keyrig holds.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
enum Unheld {
    #[error("not a JSON pointer (no leading '/')")]
    NotAPointer,
    #[error("{what} {index} does not exist (the file has {count})")]
    NoSuch { what: &'static str, index: usize, count: usize },
    #[error("{text:?} is not a {what} index")]
    NotAnIndex { what: &'static str, text: String },
    #[error("camera {camera} is not {projection}")]
    OtherProjection { camera: usize, projection: String },
    #[error("{0}")]
    Property(&'static str),
}

fn parse_pointer(pointer: &str, model: &ImportedModel, materials: usize) -> Result<Parsed, Unheld> {
    let Some(tokens) = tokens(pointer) else { return Err(Unheld::NotAPointer) };
    let t: Vec<&str> = tokens.iter().map(String::as_str).collect();
    let index = |s: &str, what: &'static str, count: usize| -> Result<usize, Unheld> {
        match s.parse::<usize>() {
            Ok(i) if i < count => Ok(i),
            Ok(index) => Err(Unheld::NoSuch { what, index, count }),
            Err(_) => Err(Unheld::NotAnIndex { what, text: s.to_owned() }),
        }
    };
    match t.as_slice() {
        ["nodes", n, rest @ ..] => {
            let n = index(n, "node", model.nodes.len())?;
            match rest {
                ["translation"] => Ok(Parsed::Node(n, NodePart::Translation)),
                ["rotation"] => Ok(Parsed::Node(n, NodePart::Rotation)),
                ["scale"] => Ok(Parsed::Node(n, NodePart::Scale)),
                ["weights"] => Ok(Parsed::Node(n, NodePart::Weights)),
                ["extensions", "KHR_node_visibility", "visible"] => {
                    Ok(Parsed::Target(PointerTarget::NodeVisible(n)))
                }
                _ => Err(Unheld::Property(
                    "keyrig animates a node's translation, rotation, scale, weights and visibility",
                )),
            }
        }
        ["materials", m, "pbrMetallicRoughness", "baseColorFactor"] => {
            Ok(Parsed::Target(PointerTarget::MaterialBaseColour(index(m, "material", materials)?)))
        }
        ["materials", ..] => Err(Unheld::Property(
            "keyrig animates a material's base colour and opacity (baseColorFactor) only",
        )),
        ["extensions", "KHR_lights_punctual", "lights", l, rest @ ..] => {
            let l = index(l, "light", model.lights.len())?;
            match rest {
                ["color"] => Ok(Parsed::Target(PointerTarget::LightColour(l))),
                ["intensity"] => Ok(Parsed::Target(PointerTarget::LightIntensity(l))),
                ["range"] => Ok(Parsed::Target(PointerTarget::LightRange(l))),
                ["spot", "innerConeAngle"] => Ok(Parsed::Target(PointerTarget::LightInnerCone(l))),
                ["spot", "outerConeAngle"] => Ok(Parsed::Target(PointerTarget::LightOuterCone(l))),
                _ => Err(Unheld::Property(
                    "keyrig animates a light's color, intensity, range and spot cone angles",
                )),
            }
        }
        ["cameras", c, rest @ ..] => {
            let c = index(c, "camera", model.cameras.len())?;
            let orthographic = matches!(model.cameras[c].projection, ModelProjection::Orthographic { .. });
            match (rest, orthographic) {
                (["perspective", "yfov"], false) => Ok(Parsed::Target(PointerTarget::CameraYfov(c))),
                (["orthographic", "ymag"], true) => Ok(Parsed::Target(PointerTarget::CameraYmag(c))),
                (["orthographic", "xmag"], true) => Err(Unheld::Property(
                    "keyrig's orthographic view width follows its height (ymag) and the scene's render aspect",
                )),
                (["perspective", "aspectRatio"], false) => {
                    Err(Unheld::Property("keyrig's aspect ratio is the scene's render size, not keyed"))
                }
                (["perspective" | "orthographic", "znear" | "zfar"], _) => {
                    Err(Unheld::Property("keyrig's clip planes are not keyed: the camera keeps the file's"))
                }
                (["perspective", ..], true) | (["orthographic", ..], false) => {
                    Err(Unheld::OtherProjection { camera: c, projection: rest[0].to_owned() })
                }
                _ => Err(Unheld::Property("keyrig animates a camera's yfov (perspective) or ymag (orthographic)")),
            }
        }
        _ => Err(Unheld::Property("keyrig holds no animated property there")),
    }
}

/// Reads the set-aside channels of every animation: node transform and weight pointers become
/// channels of `channels[a]`, the other properties keyrig holds pointer channels of
/// `pointers[a]`; the rest goes to `skipped`.
pub(crate) fn read_pointer_channels(
    cx: &Reader<'_, '_>,
    doc: &gltf::Document,
    model: &mut ImportedModel,
    raw: &Raw,
) -> Result<(), GltfError> {
    let materials = doc.materials().len();
    let animations: Vec<gltf::Animation<'_>> = doc.animations().collect();
    for aside in &raw.set_aside {
        let channel_here = format!("/animations/{}/channels/{}", aside.animation, aside.channel);
        let skip = |reason: String| SkippedChannel {
            channel: channel_here.clone(),
            pointer: aside.pointer.clone(),
            reason,
        };
        let Some(pointer) = &aside.pointer else {
            model
                .skipped_channels
                .push(skip("no node and no KHR_animation_pointer: ignored, as glTF 2.0 says".into()));
            continue;
        };
        let parsed = match parse_pointer(pointer, model, materials) {
            Ok(p) => p,
            Err(reason) => {
                model.skipped_channels.push(skip(reason.to_string()));
                continue;
            }
        };
        let Some(animation) = animations.get(aside.animation) else { continue };
        let sampler = aside.sampler.and_then(|s| animation.samplers().nth(s)).ok_or_else(|| {
            ptr(
                format!("{channel_here}/sampler"),
                GltfErrorKind::IndexOutOfRange {
                    what: "sampler".into(),
                    index: aside.sampler.unwrap_or(usize::MAX),
                    limit: animation.samplers().count(),
                },
            )
        })?;
        let here = format!("/animations/{}/samplers/{}", aside.animation, sampler.index());
        let times = key_times(cx, &sampler.input(), &here)?;
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::Hermite,
        };
        let per_key = if interpolation == Interpolation::Hermite { 3 } else { 1 };
        let output = sampler.output();
        let out_here = format!("/accessors/{}", output.index());
        let floats = |dims: Dimensions, per_element: usize| -> Result<Vec<f32>, GltfError> {
            let count = check_accessor(cx, &output, "animation output", &[dims], &[DataType::F32])?;
            let values: Vec<f32> = match dims {
                Dimensions::Scalar => gltf::accessor::Iter::<f32>::new(output.clone(), cx.get())
                    .map(Iterator::collect)
                    .unwrap_or_default(),
                Dimensions::Vec3 => gltf::accessor::Iter::<[f32; 3]>::new(output.clone(), cx.get())
                    .map(|it| it.flatten().collect())
                    .unwrap_or_default(),
                _ => gltf::accessor::Iter::<[f32; 4]>::new(output.clone(), cx.get())
                    .map(|it| it.flatten().collect())
                    .unwrap_or_default(),
            };
            count_matches(values.len(), count * dims.multiplicity(), &out_here)?;
            if count != times.len() * per_key * per_element {
                return Err(ptr(
                    format!("{here}/output"),
                    GltfErrorKind::Animation(format!(
                        "output has {count} elements, expected {} keys × {per_key} × {per_element}",
                        times.len()
                    )),
                ));
            }
            if values.iter().any(|v| !v.is_finite()) {
                return Err(ptr(&out_here, GltfErrorKind::NonFinite(format!("value of {pointer}"))));
            }
            Ok(values)
        };
        let vec3s = |v: Vec<f32>| v.chunks_exact(3).map(Vec3::from_slice).collect::<Vec<_>>();
        match parsed {
            Parsed::Node(node, part) => {
                let target = match part {
                    NodePart::Translation => ChannelTarget::Translation(make_track(
                        &times,
                        &vec3s(floats(Dimensions::Vec3, 1)?),
                        interpolation,
                    )),
                    NodePart::Scale => ChannelTarget::Scale(make_track(
                        &times,
                        &vec3s(floats(Dimensions::Vec3, 1)?),
                        interpolation,
                    )),
                    NodePart::Rotation => {
                        let raw = floats(Dimensions::Vec4, 1)?;
                        let mut qs = Vec::with_capacity(raw.len() / 4);
                        for (i, q) in raw.chunks_exact(4).enumerate() {
                            let q = Vec4::from_slice(q);
                            let is_value = per_key == 1 || i % 3 == 1;
                            qs.push(glam::Quat::from_vec4(if is_value {
                                q.try_normalize().ok_or_else(|| {
                                    ptr(
                                        &out_here,
                                        GltfErrorKind::Animation(format!("rotation {i} has zero length")),
                                    )
                                })?
                            } else {
                                q
                            }));
                        }
                        ChannelTarget::Rotation(make_track(&times, &qs, interpolation))
                    }
                    NodePart::Weights => {
                        let targets = model.nodes[node]
                            .mesh
                            .and_then(|m| model.meshes.get(m))
                            .and_then(|m| m.primitives.first())
                            .map_or(0, |p| p.morph_targets.len());
                        if targets == 0 {
                            model
                                .skipped_channels
                                .push(skip(format!("node {node}'s mesh has no morph targets")));
                            continue;
                        }
                        let raw = floats(Dimensions::Scalar, targets)?;
                        let groups: Vec<Vec<f32>> = raw.chunks(targets).map(<[f32]>::to_vec).collect();
                        let track = make_track(&times, &groups, interpolation);
                        ChannelTarget::Weights(WeightsTrack { targets, keys: track.keys.to_vec() })
                    }
                };
                if let Some(a) = model.animations.get_mut(aside.animation) {
                    a.channels.push(ModelChannel { node, target });
                }
            }
            Parsed::Target(target) => {
                let keys = match target {
                    PointerTarget::NodeVisible(_) => {
                        if interpolation != Interpolation::Step {
                            model.skipped_channels.push(skip(
                                "a boolean is animated with STEP interpolation only (KHR_animation_pointer)"
                                    .into(),
                            ));
                            continue;
                        }
                        let count = check_accessor(
                            cx,
                            &output,
                            "animation output (boolean)",
                            &[Dimensions::Scalar],
                            &[DataType::U8],
                        )?;
                        let values: Vec<u8> = gltf::accessor::Iter::<u8>::new(output.clone(), cx.get())
                            .map(Iterator::collect)
                            .unwrap_or_default();
                        count_matches(values.len(), count, &out_here)?;
                        if count != times.len() {
                            return Err(ptr(
                                format!("{here}/output"),
                                GltfErrorKind::Animation(format!(
                                    "output has {count} elements, expected {} keys",
                                    times.len()
                                )),
                            ));
                        }
                        let values: Vec<f32> =
                            values.iter().map(|&b| if b == 0 { 0.0 } else { 1.0 }).collect();
                        PointerKeys::Scalar(make_track(&times, &values, Interpolation::Step))
                    }
                    PointerTarget::MaterialBaseColour(_) => {
                        let v = floats(Dimensions::Vec4, 1)?;
                        let v: Vec<Vec4> = v.chunks_exact(4).map(Vec4::from_slice).collect();
                        PointerKeys::Vec4(make_track(&times, &v, interpolation))
                    }
                    PointerTarget::LightColour(_) => PointerKeys::Vec3(make_track(
                        &times,
                        &vec3s(floats(Dimensions::Vec3, 1)?),
                        interpolation,
                    )),
                    PointerTarget::LightIntensity(_)
                    | PointerTarget::CameraYfov(_)
                    | PointerTarget::CameraYmag(_)
                    | PointerTarget::LightRange(_)
                    | PointerTarget::LightInnerCone(_)
                    | PointerTarget::LightOuterCone(_) => PointerKeys::Scalar(make_track(
                        &times,
                        &floats(Dimensions::Scalar, 1)?,
                        interpolation,
                    )),
                };
                if let Some(a) = model.animations.get_mut(aside.animation) {
                    a.pointers.push(PointerChannel { pointer: pointer.clone(), target, keys });
                }
            }
        }
    }
    for &(node, visible) in &raw.node_visible {
        if let Some(n) = model.nodes.get_mut(node) {
            n.visible = visible;
        }
    }
    Ok(())
}
