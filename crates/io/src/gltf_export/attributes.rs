//! Export of the keyed attributes (keyrig-core `attributes`) and of a scene camera's lens and
//! visibility, and the one writer of every `KHR_animation_pointer` channel
//! ([`Document::write_pointers`]): visibility as `KHR_node_visibility`
//! (the node's `visible`, and a `KHR_animation_pointer` STEP channel with boolean output when it
//! is keyed), an object's colour and opacity as its own material's `baseColorFactor` (static at
//! the start of the frame range, keyed through a pointer channel; `alphaMode` BLEND when the
//! object is ever translucent), a light's range and spot cone through pointer channels on
//! `KHR_lights_punctual`, morph weights as the mesh node's `weights` channel. A scene without
//! attributes exports exactly as before.
//!
//! Both extensions are declared in `extensionsUsed` only: a viewer without them (Blender 3.4)
//! still opens the file and shows the rest pose of those properties.
//!
//! Scalar channels are written through the translation path ([`super::vec3_channel`]) on
//! (x, 0, 0), so they get the same exact STEP / LINEAR / CUBICSPLINE mapping, cycles and Blender
//! mode as every other channel.

use super::{
    resample_linear, scene_err, step_breaks, vec3_channel, Channel, Document, ExportError, ExportOptions,
    CYCLE_POSITION_TOLERANCE,
};
use glam::{Quat, Vec3};
use keyrig_core::{Animated, AnimatedTrack, Interpolation, Key, LightKind, RawTrack};
use serde_json::{json, Value};

/// A channel whose target is a `KHR_animation_pointer` pointer; `boolean` outputs are written
/// as UNSIGNED_BYTE 0/1 (the extension's form for booleans).
pub(super) struct PointerChannel {
    pub pointer: String,
    pub channel: Channel,
    pub boolean: bool,
}

/// `a` as (x, 0, 0) keys, tangents likewise.
fn lift(a: &Animated<f32>) -> Animated<Vec3> {
    let key = |k: &Key<f32>| Key {
        time: k.time,
        value: Vec3::new(k.value, 0.0, 0.0),
        interpolation: k.interpolation,
        tcb: k.tcb,
        in_tangent: k.in_tangent.map(|t| Vec3::new(t, 0.0, 0.0)),
        out_tangent: k.out_tangent.map(|t| Vec3::new(t, 0.0, 0.0)),
        spin: None,
        key_type: k.key_type,
    };
    Animated::new(Vec3::new(a.value, 0.0, 0.0), RawTrack::new(a.track.keys.iter().map(key).collect()))
        .with_cycles(a.cycles())
}

/// The channel of a scalar track (values through `scale`, a linear map); `None` when not keyed.
fn scalar_channel(
    a: &Animated<f32>,
    scale: f32,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    let identity = (Quat::IDENTITY, Vec3::ZERO);
    let Some(mut c) = vec3_channel(0, "pointer", &lift(a), identity, options, range, here)? else {
        return Ok(None);
    };
    c.values = c.values.chunks_exact(3).map(|v| v[0] * scale).collect();
    c.width = 1;
    Ok(Some(c))
}

fn sample(a: &Animated<f32>, t: f64, here: &str) -> Result<f32, ExportError> {
    Ok(AnimatedTrack::new(a).map_err(|e| scene_err(here, e.to_string()))?.sample(t))
}

/// Sets `visible` on node `node` (its value at `t0`) and keys it when `visible` is keyed.
pub(super) fn visibility(
    doc: &mut Document,
    node: usize,
    visible: &Animated<f32>,
    t0: f64,
    here: &str,
) -> Result<(), ExportError> {
    if !visible.is_animated() && visible.value == 1.0 {
        return Ok(());
    }
    let shown = sample(visible, t0, here)? >= 0.5;
    doc.nodes[node]["extensions"]["KHR_node_visibility"] = json!({"visible": shown});
    doc.node_visibility = true;
    if visible.is_animated() {
        let track = AnimatedTrack::new(visible).map_err(|e| scene_err(here, e.to_string()))?;
        // Step keys (validation): the keys as they are, 0/1.
        let times: Vec<f32> = visible.track.keys.iter().map(|k| k.time as f32).collect();
        let values: Vec<f32> =
            visible.track.keys.iter().map(|k| if track.sample(k.time) >= 0.5 { 1.0 } else { 0.0 }).collect();
        doc.pointers.push(PointerChannel {
            pointer: format!("/nodes/{node}/extensions/KHR_node_visibility/visible"),
            channel: Channel { node, path: "pointer", interpolation: "STEP", times, values, width: 1 },
            boolean: true,
        });
    }
    Ok(())
}

/// Gives the meshes of `object_nodes` a material of their own with the object's colour and
/// opacity at `t0`, keyed through a pointer channel.
pub(super) fn material(
    doc: &mut Document,
    object_nodes: &[usize],
    attributes: &keyrig_core::ObjectAttributes,
    t0: f64,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let opacity = &attributes.opacity;
    let colour = attributes.colour.as_ref();
    if colour.is_none() && !opacity.is_animated() && opacity.value == 1.0 {
        return Ok(());
    }
    let c_here = format!("{here}.attributes.colour");
    let o_here = format!("{here}.attributes.opacity");
    let colour_track =
        colour.map(AnimatedTrack::new).transpose().map_err(|e| scene_err(&c_here, e.to_string()))?;
    let opacity_track = AnimatedTrack::new(opacity).map_err(|e| scene_err(&o_here, e.to_string()))?;
    let translucent = opacity.value < 1.0 || opacity.track.keys.iter().any(|k| k.value < 1.0);
    let meshes: Vec<usize> =
        object_nodes.iter().filter_map(|&n| doc.nodes[n]["mesh"].as_u64()).map(|m| m as usize).collect();
    for m in meshes {
        let prims = doc.meshes[m]["primitives"].as_array().map_or(0, Vec::len);
        for p in 0..prims {
            let old = doc.meshes[m]["primitives"][p]["material"].as_u64().map(|i| i as usize);
            let mut mat = old.and_then(|i| doc.materials.get(i).cloned()).unwrap_or_else(
                || json!({"pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0}}),
            );
            let file_colour = mat["pbrMetallicRoughness"]["baseColorFactor"]
                .as_array()
                .map(|a| a.iter().filter_map(Value::as_f64).map(|x| x as f32).collect::<Vec<f32>>())
                .filter(|a| a.len() == 4)
                .map_or(Vec3::ONE, |a| Vec3::new(a[0], a[1], a[2]));
            let rgb0 = colour_track.as_ref().map_or(file_colour, |t| t.sample(t0));
            let a0 = opacity_track.sample(t0);
            mat["pbrMetallicRoughness"]["baseColorFactor"] = json!([rgb0.x, rgb0.y, rgb0.z, a0]);
            if translucent {
                mat["alphaMode"] = json!("BLEND");
            }
            mat["name"] =
                json!(format!("{} material", doc.nodes[object_nodes[0]]["name"].as_str().unwrap_or("")));
            doc.materials.push(mat);
            let index = doc.materials.len() - 1;
            doc.meshes[m]["primitives"][p]["material"] = json!(index);
            if let Some(channel) = base_colour_channel(colour, opacity, file_colour, options, range, here)? {
                doc.pointers.push(PointerChannel {
                    pointer: format!("/materials/{index}/pbrMetallicRoughness/baseColorFactor"),
                    channel,
                    boolean: false,
                });
            }
        }
    }
    Ok(())
}

/// The VEC4 baseColorFactor channel of a colour and an opacity: exact when one of them is keyed
/// (the other is constant: its value in the value slots, 0 in the tangent slots), resampled as
/// LINEAR keys within 1e-4 when both are.
fn base_colour_channel(
    colour: Option<&Animated<Vec3>>,
    opacity: &Animated<f32>,
    file_colour: Vec3,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    let identity = (Quat::IDENTITY, Vec3::ZERO);
    let colour_keyed = colour.filter(|c| c.is_animated());
    let c_here = format!("{here}.attributes.colour");
    let o_here = format!("{here}.attributes.opacity");
    let widen = |c: Channel, f: &dyn Fn(&[f32], bool) -> [f32; 4], per: usize| {
        let cubic = c.interpolation == "CUBICSPLINE";
        let values =
            c.values.chunks_exact(per).enumerate().flat_map(|(i, v)| f(v, cubic && i % 3 != 1)).collect();
        Channel { values, width: 4, ..c }
    };
    match (colour_keyed, opacity.is_animated()) {
        (None, false) => Ok(None),
        (Some(c), false) => {
            let a = sample(opacity, 0.0, &o_here)?;
            let ch = vec3_channel(0, "pointer", c, identity, options, range, &c_here)?;
            Ok(ch.map(|ch| widen(ch, &|v, tangent| [v[0], v[1], v[2], if tangent { 0.0 } else { a }], 3)))
        }
        (None, true) => {
            let rgb = match colour {
                Some(c) => AnimatedTrack::new(c).map_err(|e| scene_err(&c_here, e.to_string()))?.sample(0.0),
                None => file_colour,
            };
            let ch = scalar_channel(opacity, 1.0, options, range, &o_here)?;
            Ok(ch.map(|ch| {
                widen(
                    ch,
                    &|v, tangent| if tangent { [0.0, 0.0, 0.0, v[0]] } else { [rgb.x, rgb.y, rgb.z, v[0]] },
                    1,
                )
            }))
        }
        (Some(c), true) => {
            // Keyed at the same times in the same way (an imported baseColorFactor): element by
            // element, exact.
            let cc = vec3_channel(0, "pointer", c, identity, options, range, &c_here)?;
            let oc = scalar_channel(opacity, 1.0, options, range, &o_here)?;
            if let (Some(cc), Some(oc)) = (cc, oc) {
                if cc.times == oc.times && cc.interpolation == oc.interpolation {
                    let values = cc
                        .values
                        .chunks_exact(3)
                        .zip(&oc.values)
                        .flat_map(|(v, &a)| [v[0], v[1], v[2], a])
                        .collect();
                    return Ok(Some(Channel { values, width: 4, ..cc }));
                }
            }
            let ct = AnimatedTrack::new(c).map_err(|e| scene_err(&c_here, e.to_string()))?;
            let ot = AnimatedTrack::new(opacity).map_err(|e| scene_err(&o_here, e.to_string()))?;
            let mut times: Vec<f64> = c.track.keys.iter().chain([]).map(|k| k.time).collect();
            times.extend(opacity.track.keys.iter().map(|k| k.time));
            times.extend([range.0, range.1]);
            times.sort_by(f64::total_cmp);
            times.dedup();
            let step = |keys: &[Key<f32>]| -> Vec<f64> {
                let t: Vec<f64> = keys.iter().map(|k| k.time).collect();
                step_breaks(&t, |i| keys.get(i).map(|k| k.interpolation)).1
            };
            let colour_steps: Vec<Key<f32>> = c
                .track
                .keys
                .iter()
                .map(|k| Key::new(k.time, 0.0).with_interpolation(k.interpolation))
                .collect();
            let mut jumps = step(&colour_steps);
            jumps.extend(step(&opacity.track.keys));
            times.extend(jumps.iter().copied());
            times.sort_by(f64::total_cmp);
            times.dedup();
            jumps.sort_by(f64::total_cmp);
            let f = |t: f64| -> Vec<f64> {
                let rgb = ct.sample(t);
                vec![f64::from(rgb.x), f64::from(rgb.y), f64::from(rgb.z), f64::from(ot.sample(t))]
            };
            let (t, v) = resample_linear(&f, &times, &jumps, CYCLE_POSITION_TOLERANCE, super::euclidean);
            Ok(Some(Channel {
                node: 0,
                path: "pointer",
                interpolation: "LINEAR",
                times: t.iter().map(|&t| t as f32).collect(),
                values: v.iter().flatten().map(|&x| x as f32).collect(),
                width: 4,
            }))
        }
    }
}

/// The light's static range and keyed cone on its `KHR_lights_punctual` entry `entry`, and
/// pointer channels for its keyed range and cone.
#[allow(clippy::too_many_arguments)]
pub(super) fn light(
    doc: &mut Document,
    light: &keyrig_core::Light,
    index: usize,
    entry: &mut Value,
    t0: f64,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let a = &light.attributes;
    let base = format!("/extensions/KHR_lights_punctual/lights/{index}");
    if let Some(r) = &a.range {
        entry["range"] = json!(sample(r, t0, &format!("{here}.attributes.range"))?);
    }
    if let (LightKind::Spot { .. }, true) =
        (light.kind, a.cutoff_deg.is_some() || a.inner_angle_deg.is_some())
    {
        let outer = match &a.cutoff_deg {
            Some(c) => sample(c, t0, &format!("{here}.attributes.cutoff_deg"))?.to_radians(),
            None => entry["spot"]["outerConeAngle"].as_f64().unwrap_or(0.785) as f32,
        };
        let inner = match &a.inner_angle_deg {
            Some(c) => sample(c, t0, &format!("{here}.attributes.inner_angle_deg"))?.to_radians(),
            None => entry["spot"]["innerConeAngle"].as_f64().unwrap_or(0.0) as f32,
        };
        let outer = outer.clamp(1e-4, std::f32::consts::FRAC_PI_2);
        entry["spot"] = json!({"innerConeAngle": inner.clamp(0.0, outer - 1e-4), "outerConeAngle": outer});
    }
    // Colour and intensity keep their export from before attributes (their values at the start
    // of the range), so a scene without attributes exports exactly as it did and stays
    // readable by glTF readers that refuse channels without a node (the gltf crate 1.4).
    let deg = 1f32.to_radians();
    let scalars: [(Option<&Animated<f32>>, &str, f32, String); 3] = [
        (a.range.as_ref(), "range", 1.0, format!("{here}.attributes.range")),
        (a.cutoff_deg.as_ref(), "spot/outerConeAngle", deg, format!("{here}.attributes.cutoff_deg")),
        (
            a.inner_angle_deg.as_ref(),
            "spot/innerConeAngle",
            deg,
            format!("{here}.attributes.inner_angle_deg"),
        ),
    ];
    for (animated, property, scale, field) in scalars {
        let Some(animated) = animated else { continue };
        if property.starts_with("spot") && !matches!(light.kind, LightKind::Spot { .. }) {
            continue;
        }
        if let Some(channel) = scalar_channel(animated, scale, options, range, &field)? {
            doc.pointers.push(PointerChannel {
                pointer: format!("{base}/{property}"),
                channel,
                boolean: false,
            });
        }
    }
    Ok(())
}

/// Pointer channels of scene camera `camera`'s keyed lens (entry `index` of `cameras`), for
/// images of `aspect`: a field of view in degrees as `perspective/yfov` in radians and an
/// orthographic height as `orthographic/ymag` (half of it) and `xmag` (`ymag · aspect`), key for
/// key through [`scalar_channel`] (linear maps, exact); a focal length, whose field of view is
/// not linear in it, as LINEAR `yfov` keys at every frame of `frames` and every key time.
#[allow(clippy::too_many_arguments)]
pub(super) fn camera_lens(
    doc: &mut Document,
    camera: &keyrig_core::SceneCamera,
    index: usize,
    lens: &AnimatedTrack<f32>,
    aspect: Option<f32>,
    frames: &[f64],
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    if !camera.lens.is_animated() {
        return Ok(());
    }
    let here = format!("{here}.lens");
    let pointer = |field: &str| format!("/cameras/{index}/{field}");
    let push = |doc: &mut Document, field: &str, channel: Option<Channel>| {
        if let Some(channel) = channel {
            doc.pointers.push(PointerChannel { pointer: pointer(field), channel, boolean: false });
        }
    };
    match camera.projection {
        keyrig_core::Projection::Perspective => {
            let c = scalar_channel(&camera.lens, 1f32.to_radians(), options, range, &here)?;
            push(doc, "perspective/yfov", c);
        }
        keyrig_core::Projection::Orthographic => {
            let ymag = scalar_channel(&camera.lens, 0.5, options, range, &here)?;
            let xmag =
                scalar_channel(&camera.lens, 0.5 * aspect.unwrap_or(16.0 / 9.0), options, range, &here)?;
            push(doc, "orthographic/ymag", ymag);
            push(doc, "orthographic/xmag", xmag);
        }
        keyrig_core::Projection::FocalLength { .. } => {
            let mut times: Vec<f64> = frames.to_vec();
            times.extend(camera.lens.track.keys.iter().map(|k| k.time));
            times.sort_by(f64::total_cmp);
            times.dedup();
            if times.len() < 2 {
                return Ok(());
            }
            let values = times
                .iter()
                .map(|&t| match keyrig_core::Lens::of(camera.projection, lens.sample(t)) {
                    keyrig_core::Lens::Perspective { fov_y } => fov_y,
                    keyrig_core::Lens::Orthographic { height } => height,
                })
                .collect();
            let times = times.iter().map(|&t| t as f32).collect();
            let channel =
                Channel { node: 0, path: "pointer", interpolation: "LINEAR", times, values, width: 1 };
            push(doc, "perspective/yfov", Some(channel));
        }
    }
    Ok(())
}

/// The weights track of an object's keyed morph weights: one key per time of any target's keys,
/// exact when every target is keyed at the same times with the same interpolation (an imported
/// weights channel), else LINEAR keys within 1e-4 of each weight.
pub(super) fn weights_track(
    weights: &[Animated<f32>],
    range: (f64, f64),
    here: &str,
) -> Result<Option<crate::model::WeightsTrack>, ExportError> {
    if weights.iter().all(|w| !w.is_animated()) {
        return Ok(None);
    }
    let targets = weights.len();
    let first = weights.iter().find(|w| w.is_animated()).map(|w| &w.track.keys);
    let same = first.is_some_and(|f| {
        weights.iter().all(|w| {
            w.track.keys.len() == f.len()
                && w.cycles().is_hold()
                && w.track.keys.iter().zip(f.iter()).all(|(a, b)| {
                    a.time == b.time
                        && a.interpolation == b.interpolation
                        && matches!(
                            a.interpolation,
                            Interpolation::Step | Interpolation::Linear | Interpolation::Hermite
                        )
                })
        })
    });
    if let (true, Some(first)) = (same, first) {
        let keys = (0..first.len())
            .map(|k| {
                let hermite = first[k].interpolation == Interpolation::Hermite;
                Key {
                    time: first[k].time,
                    value: weights.iter().map(|w| w.track.keys[k].value).collect::<Vec<f32>>(),
                    interpolation: first[k].interpolation,
                    tcb: first[k].tcb,
                    in_tangent: hermite
                        .then(|| weights.iter().map(|w| w.track.keys[k].in_tangent.unwrap_or(0.0)).collect()),
                    out_tangent: hermite.then(|| {
                        weights.iter().map(|w| w.track.keys[k].out_tangent.unwrap_or(0.0)).collect()
                    }),
                    spin: None,
                    key_type: first[k].key_type,
                }
            })
            .collect();
        return Ok(Some(crate::model::WeightsTrack { targets, keys }));
    }
    let tracks = weights
        .iter()
        .enumerate()
        .map(|(i, w)| AnimatedTrack::new(w).map_err(|e| scene_err(format!("{here}[{i}]"), e.to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let mut times: Vec<f64> = weights.iter().flat_map(|w| w.track.keys.iter().map(|k| k.time)).collect();
    times.extend([range.0, range.1]);
    times.sort_by(f64::total_cmp);
    times.dedup();
    let f = |t: f64| -> Vec<f64> { tracks.iter().map(|tr| f64::from(tr.sample(t))).collect() };
    let (t, v) = resample_linear(&f, &times, &[], CYCLE_POSITION_TOLERANCE, super::max_abs);
    let keys = t
        .iter()
        .zip(v)
        .map(|(&t, v)| {
            Key::new(t, v.iter().map(|&x| x as f32).collect::<Vec<f32>>())
                .with_interpolation(Interpolation::Linear)
        })
        .collect();
    Ok(Some(crate::model::WeightsTrack { targets, keys }))
}

impl Document {
    /// Writes the pointer channels' samplers and channels after the node channels' (`samplers`
    /// and `channels` of the one animation).
    pub(super) fn write_pointers(&mut self, samplers: &mut Vec<Value>, channels: &mut Vec<Value>) {
        for p in std::mem::take(&mut self.pointers) {
            let c = &p.channel;
            let input = self.b.floats(&c.times, 1, "SCALAR", None, true);
            let output = if p.boolean {
                let bytes: Vec<u8> = c.values.iter().map(|&v| u8::from(v >= 0.5)).collect();
                let view = self.b.view(&bytes, None);
                self.b.accessor(view, UNSIGNED_BYTE, bytes.len(), "SCALAR", None)
            } else {
                let (width, type_) = match c.width {
                    4 => (4, "VEC4"),
                    3 => (3, "VEC3"),
                    _ => (1, "SCALAR"),
                };
                self.b.floats(&c.values, width, type_, None, false)
            };
            samplers.push(json!({"input": input, "output": output, "interpolation": c.interpolation}));
            channels.push(json!({
                "sampler": samplers.len() - 1,
                "target": {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": p.pointer}}}
            }));
            self.animation_pointer = true;
        }
    }
}

const UNSIGNED_BYTE: u32 = 5121;
