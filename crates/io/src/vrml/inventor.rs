//! Open Inventor's scene graph traversed as Inventor draws it: a state (transform, material,
//! coordinates, normals and their binding, texture coordinates, shape hints) that property
//! nodes change and shapes use; `Separator` saves and restores it, `TransformSeparator` the
//! transform only, `Group` neither. Shapes become [`super::map::ShapeInstance`]s with the
//! transform accumulated into one static matrix; lights and cameras likewise.

use std::sync::Arc;

use glam::{Mat4, Quat, Vec2, Vec3};
use keyrig_core::{Animated, Material};

use super::geometry::{self, PolyMesh};
use super::map::{Frame, GeometryRef, LightInstance, ShapeInstance, Traversal, View};
use super::tree::{NodeId, Value};
use super::VrmlError;

#[derive(Clone)]
struct State {
    matrix: Mat4,
    diffuse: Vec3,
    alpha: f32,
    coords: Arc<Vec<Vec3>>,
    /// The Coordinate3 node the coordinates come from (a CoordinateInterpolator may drive it).
    coord_node: Option<NodeId>,
    normals: Option<Arc<Vec<Vec3>>>,
    normal_binding: String,
    texcoords: Option<Arc<Vec<Vec2>>>,
    texture: Option<Arc<keyrig_core::TextureImage>>,
    crease: f32,
    ccw: bool,
    label: Option<String>,
    names: Vec<String>,
}

impl Default for State {
    fn default() -> Self {
        State {
            matrix: Mat4::IDENTITY,
            diffuse: Vec3::splat(0.8),
            alpha: 1.0,
            coords: Arc::new(Vec::new()),
            coord_node: None,
            normals: None,
            normal_binding: "DEFAULT".into(),
            texcoords: None,
            texture: None,
            crease: 0.0,
            ccw: true,
            label: None,
            names: Vec::new(),
        }
    }
}

fn vec3s(v: &[f64]) -> Vec<Vec3> {
    v.chunks_exact(3).map(|c| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)).collect()
}

fn name_value(t: &Traversal<'_>, id: NodeId, field: &str) -> Option<String> {
    match t.doc.node(id).value(field) {
        Some(Value::Names(n)) => n.first().cloned(),
        _ => None,
    }
}

fn nums<'a>(t: &'a Traversal<'_>, id: NodeId, field: &str) -> &'a [f64] {
    t.doc.node(id).value(field).and_then(Value::numbers).unwrap_or(&[])
}

fn num(t: &Traversal<'_>, id: NodeId, field: &str, default: f32) -> f32 {
    nums(t, id, field).first().map_or(default, |&v| if v.is_finite() { v as f32 } else { default })
}

fn v3(t: &Traversal<'_>, id: NodeId, field: &str, default: Vec3) -> Vec3 {
    match nums(t, id, field) {
        [x, y, z, ..] => Vec3::new(*x as f32, *y as f32, *z as f32),
        _ => default,
    }
}

fn rot(t: &Traversal<'_>, id: NodeId, field: &str) -> Quat {
    match nums(t, id, field) {
        [x, y, z, a, ..] => Vec3::new(*x as f32, *y as f32, *z as f32)
            .try_normalize()
            .map_or(Quat::IDENTITY, |axis| Quat::from_axis_angle(axis, *a as f32)),
        _ => Quat::IDENTITY,
    }
}

/// Parts of a cone or cylinder: `( SIDES | BOTTOM )`, `ALL` (the default).
fn has_part(t: &Traversal<'_>, id: NodeId, part: &str) -> bool {
    match t.doc.node(id).value("parts") {
        Some(Value::Names(n)) => n.iter().any(|p| p == part || p == "ALL"),
        _ => true,
    }
}

/// Traverses `t.doc`'s roots as Inventor does.
pub(crate) fn traverse(t: &mut Traversal<'_>) -> Result<(), VrmlError> {
    let roots = t.doc.roots.clone();
    let mut state = State::default();
    for root in roots {
        visit(t, root, &mut state)?;
    }
    Ok(())
}

fn visit(t: &mut Traversal<'_>, id: NodeId, state: &mut State) -> Result<(), VrmlError> {
    t.count_visit(id)?;
    let doc = t.doc;
    let node = doc.node(id);
    let kind = node.kind.as_str();
    let children = node.children.clone();
    match kind {
        "Separator" | "TransformSeparator" | "Group" | "Selection" | "Annotation" | "WWWAnchor" => {
            let saved = (kind != "Group").then(|| state.clone());
            if let Some(def) = &node.def {
                state.names.push(def.clone());
            }
            for c in children {
                visit(t, c, state)?;
            }
            if node.def.is_some() {
                state.names.pop();
            }
            if let Some(saved) = saved {
                if kind == "TransformSeparator" {
                    state.matrix = saved.matrix;
                } else {
                    *state = saved;
                }
            }
        }
        "Switch" => {
            let which = num(t, id, "whichChild", -1.0) as i64;
            if which == -3 {
                for c in children {
                    visit(t, c, state)?;
                }
            } else if let Some(&c) = usize::try_from(which).ok().and_then(|w| children.get(w)) {
                visit(t, c, state)?;
            }
        }
        "LOD" | "LevelOfDetail" => {
            if let Some(&c) = children.first() {
                let mut inner = state.clone();
                visit(t, c, &mut inner)?;
            }
        }
        "Transform" => {
            let c = v3(t, id, "center", Vec3::ZERO);
            let so = rot(t, id, "scaleOrientation");
            state.matrix *= Mat4::from_translation(v3(t, id, "translation", Vec3::ZERO) + c)
                * Mat4::from_quat(rot(t, id, "rotation"))
                * Mat4::from_quat(so)
                * Mat4::from_scale(v3(t, id, "scaleFactor", Vec3::ONE))
                * Mat4::from_quat(so.inverse())
                * Mat4::from_translation(-c);
        }
        "Translation" => state.matrix *= Mat4::from_translation(v3(t, id, "translation", Vec3::ZERO)),
        "Rotation" => state.matrix *= Mat4::from_quat(rot(t, id, "rotation")),
        "RotationXYZ" => {
            let angle = num(t, id, "angle", 0.0);
            let axis = match name_value(t, id, "axis").as_deref() {
                Some("Y") => Vec3::Y,
                Some("Z") => Vec3::Z,
                _ => Vec3::X,
            };
            state.matrix *= Mat4::from_axis_angle(axis, angle);
        }
        "Scale" => state.matrix *= Mat4::from_scale(v3(t, id, "scaleFactor", Vec3::ONE)),
        "MatrixTransform" => {
            let m = nums(t, id, "matrix");
            if m.len() >= 16 {
                let cols: [f32; 16] = std::array::from_fn(|i| m[i] as f32);
                state.matrix *= Mat4::from_cols_array(&cols);
            }
        }
        "ResetTransform" => state.matrix = Mat4::IDENTITY,
        "Material" => {
            state.diffuse = v3(t, id, "diffuseColor", Vec3::splat(0.8));
            state.alpha = 1.0 - num(t, id, "transparency", 0.0).clamp(0.0, 1.0);
            if nums(t, id, "diffuseColor").len() > 3 {
                t.skips_add("Material (several colours)", "only the first colour is imported", id);
            }
        }
        "BaseColor" => state.diffuse = v3(t, id, "rgb", Vec3::splat(0.8)),
        "Coordinate3" => {
            state.coords = Arc::new(vec3s(nums(t, id, "point")));
            state.coord_node = Some(id);
        }
        "Normal" => state.normals = Some(Arc::new(vec3s(nums(t, id, "vector")))),
        "NormalBinding" => {
            state.normal_binding = name_value(t, id, "value").unwrap_or_else(|| "DEFAULT".into())
        }
        "TextureCoordinate2" => {
            state.texcoords = Some(Arc::new(
                nums(t, id, "point").chunks_exact(2).map(|c| Vec2::new(c[0] as f32, c[1] as f32)).collect(),
            ));
        }
        "Texture2" => state.texture = t.texture_of(id),
        "ShapeHints" => {
            state.crease = num(t, id, "creaseAngle", 0.0);
            state.ccw = name_value(t, id, "vertexOrdering").as_deref() != Some("CLOCKWISE");
        }
        "Label" => {
            if let Some(Value::Strings(s)) = node.value("label") {
                state.label = s.first().cloned();
            }
        }
        "Cube" => {
            let size =
                Vec3::new(num(t, id, "width", 2.0), num(t, id, "height", 2.0), num(t, id, "depth", 2.0));
            push_shape(t, id, state, GeometryRef::Solid(Arc::new(geometry::box_solid(size))));
        }
        "Sphere" => push_shape(
            t,
            id,
            state,
            GeometryRef::Solid(Arc::new(geometry::sphere_solid(num(t, id, "radius", 1.0)))),
        ),
        "Cone" => {
            let s = geometry::round_solid(
                num(t, id, "bottomRadius", 1.0),
                0.0,
                num(t, id, "height", 2.0),
                has_part(t, id, "SIDES"),
                has_part(t, id, "BOTTOM"),
                false,
            );
            push_shape(t, id, state, GeometryRef::Solid(Arc::new(s)));
        }
        "Cylinder" => {
            let r = num(t, id, "radius", 1.0);
            let s = geometry::round_solid(
                r,
                r,
                num(t, id, "height", 2.0),
                has_part(t, id, "SIDES"),
                has_part(t, id, "BOTTOM"),
                has_part(t, id, "TOP"),
            );
            push_shape(t, id, state, GeometryRef::Solid(Arc::new(s)));
        }
        "IndexedFaceSet" | "FaceSet" | "IndexedTriangleStripSet" | "TriangleStripSet" | "QuadMesh" => {
            match face_set(t, id, state) {
                Ok(Some(g)) => push_shape(t, id, state, g),
                Ok(None) => {}
                Err(message) => t.skips_add(kind, &message, id),
            }
        }
        "DirectionalLight" | "PointLight" | "SpotLight" => {
            let kind_of = match kind {
                "DirectionalLight" => keyrig_core::LightKind::Directional,
                "PointLight" => keyrig_core::LightKind::Point,
                _ => {
                    let cutoff = num(t, id, "cutOffAngle", std::f32::consts::FRAC_PI_4).to_degrees();
                    keyrig_core::LightKind::Spot { cutoff_deg: cutoff, inner_angle_deg: 0.0, dropoff: 1.0 }
                }
            };
            let m = state.matrix;
            let location = if kind == "DirectionalLight" {
                Vec3::ZERO
            } else {
                v3(t, id, "location", Vec3::new(0.0, 0.0, 1.0))
            };
            let direction = v3(t, id, "direction", -Vec3::Z);
            t.lights.push(LightInstance {
                node: None,
                frames: Vec::new(),
                light: keyrig_core::Light {
                    name: node.def.clone().unwrap_or_else(|| kind.to_owned()),
                    kind: kind_of,
                    enabled: !matches!(node.value("on"), Some(Value::Bools(b)) if b.first() == Some(&false)),
                    position: Animated::constant(m.transform_point3(location)),
                    direction: Animated::constant(m.transform_vector3(direction)),
                    colour: Animated::constant(v3(t, id, "color", Vec3::ONE)),
                    intensity: Animated::constant(num(t, id, "intensity", 1.0)),
                    attributes: Default::default(),
                },
            });
        }
        "PerspectiveCamera" | "OrthographicCamera" => {
            // In the camera's own frame; the mapping places it by the state's matrix.
            let view = View {
                name: node.def.clone().unwrap_or_else(|| format!("View {}", t.views.len() + 1)),
                position: v3(t, id, "position", Vec3::new(0.0, 0.0, 1.0)),
                orientation: rot(t, id, "orientation").normalize(),
                field_of_view: num(t, id, "heightAngle", std::f32::consts::FRAC_PI_4),
                orthographic: (kind == "OrthographicCamera")
                    .then(|| num(t, id, "height", 2.0).abs().max(1e-3)),
            };
            t.views.push((view, vec![Frame::Matrix(state.matrix)], Some(id)));
        }
        "Info" => {
            let metadata = matches!(node.value("string"), Some(Value::Strings(s)) if s.iter().any(|s| s.starts_with(super::tree::METADATA_TAG)));
            if !metadata {
                t.skips_add(kind, "not imported (its text is a comment)", id);
            }
        }
        "TimeSensor" => {}
        k if k.ends_with("Interpolator") => {}
        "Complexity"
        | "DrawStyle"
        | "LightModel"
        | "Font"
        | "PickStyle"
        | "Environment"
        | "MaterialBinding"
        | "TextureCoordinateBinding"
        | "Units"
        | "TextureCoordinateDefault" => {
            t.skips_add(kind, "a drawing setting keyrig does not take", id);
        }
        "Text2" | "Text3" | "AsciiText" => t.skips_add(kind, "text is not imported", id),
        "IndexedLineSet" | "LineSet" | "PointSet" => {
            t.skips_add(kind, "lines and points are not imported (keyrig draws triangles)", id)
        }
        _ => t.skips_add(kind, "this node type is not imported", id),
    }
    Ok(())
}

fn push_shape(t: &mut Traversal<'_>, id: NodeId, state: &State, geometry: GeometryRef) {
    let doc = t.doc;
    let node = doc.node(id);
    let mut names: Vec<String> = Vec::new();
    if let Some(def) = &node.def {
        names.push(def.clone());
    }
    names.extend(state.label.iter().cloned());
    names.extend(state.names.iter().rev().cloned());
    names.push(node.kind.clone());
    let material = Material {
        base_colour: [state.diffuse.x, state.diffuse.y, state.diffuse.z, state.alpha],
        base_colour_texture: state.texture.clone(),
    };
    t.shapes.push(ShapeInstance {
        names,
        frames: vec![Frame::Matrix(state.matrix)],
        geometry,
        material,
        material_node: None,
        place: node.place,
    });
}

/// An IndexedFaceSet (or FaceSet, triangle strips, QuadMesh) over the state's coordinates or
/// its own `vertexProperty`.
fn face_set(t: &mut Traversal<'_>, id: NodeId, state: &State) -> Result<Option<GeometryRef>, String> {
    let doc = t.doc;
    let node = doc.node(id);
    let kind = node.kind.as_str();
    let vp = node.value("vertexProperty").and_then(|v| v.nodes().first().copied());
    let (mut coords, mut normals, mut binding, mut texcoords) = (
        Arc::clone(&state.coords),
        state.normals.clone(),
        state.normal_binding.clone(),
        state.texcoords.clone(),
    );
    let mut coord_node = state.coord_node;
    if let Some(vp) = vp {
        let v = vec3s(nums(t, vp, "vertex"));
        if !v.is_empty() {
            coords = Arc::new(v);
            coord_node = None;
        }
        let n = vec3s(nums(t, vp, "normal"));
        if !n.is_empty() {
            normals = Some(Arc::new(n));
            binding = name_value(t, vp, "normalBinding").unwrap_or_else(|| "PER_VERTEX_INDEXED".into());
        }
        let uv: Vec<Vec2> =
            nums(t, vp, "texCoord").chunks_exact(2).map(|c| Vec2::new(c[0] as f32, c[1] as f32)).collect();
        if !uv.is_empty() {
            texcoords = Some(Arc::new(uv));
        }
        if nums(t, vp, "orderedRGBA").len() > 1 {
            t.skips_add(
                "VertexProperty.orderedRGBA",
                "per-vertex and per-face colours are not imported (the material's colour is used)",
                vp,
            );
        }
    }
    let ints = |name: &str| -> Vec<i64> { nums(t, id, name).iter().map(|&v| v as i64).collect() };
    let mut mesh =
        PolyMesh { ccw: state.ccw, convex: true, crease_angle: state.crease, ..PolyMesh::default() };
    mesh.face_start.push(0);
    let start = num(t, id, "startIndex", 0.0).max(0.0) as u32;
    match kind {
        "IndexedFaceSet" => {
            let mut face = Vec::new();
            for i in ints("coordIndex") {
                if i < 0 {
                    mesh.corners.extend_from_slice(&face);
                    mesh.face_start.push(mesh.corners.len() as u32);
                    face.clear();
                } else {
                    face.push(u32::try_from(i).map_err(|_| format!("coordIndex {i}"))?);
                }
            }
            if !face.is_empty() {
                mesh.corners.extend_from_slice(&face);
                mesh.face_start.push(mesh.corners.len() as u32);
            }
        }
        "FaceSet" | "TriangleStripSet" => {
            let mut next = start;
            let counts = ints("numVertices");
            let counts = if counts.is_empty() || counts == [-1] {
                vec![i64::from(coords.len() as u32 - next.min(coords.len() as u32))]
            } else {
                counts
            };
            for c in counts {
                let c = u32::try_from(c).map_err(|_| format!("numVertices {c}"))?;
                let run: Vec<u32> = (next..next.saturating_add(c)).collect();
                if kind == "FaceSet" {
                    mesh.corners.extend_from_slice(&run);
                    mesh.face_start.push(mesh.corners.len() as u32);
                } else {
                    strip(&mut mesh, &run);
                }
                next = next.saturating_add(c);
            }
        }
        "IndexedTriangleStripSet" => {
            let mut run = Vec::new();
            for i in ints("coordIndex").into_iter().chain([-1]) {
                if i < 0 {
                    strip(&mut mesh, &run);
                    run.clear();
                } else {
                    run.push(u32::try_from(i).map_err(|_| format!("coordIndex {i}"))?);
                }
            }
        }
        "QuadMesh" => {
            let (rows, cols) =
                (num(t, id, "verticesPerColumn", 1.0) as u32, num(t, id, "verticesPerRow", 1.0) as u32);
            for r in 0..rows.saturating_sub(1) {
                for c in 0..cols.saturating_sub(1) {
                    let a = start + r * cols + c;
                    mesh.corners.extend_from_slice(&[a, a + cols, a + cols + 1, a + 1]);
                    mesh.face_start.push(mesh.corners.len() as u32);
                }
            }
        }
        _ => {}
    }
    if mesh.corners.is_empty() {
        return Ok(None);
    }
    let faces = mesh.face_start.len() - 1;
    if let Some(n) = &normals {
        let index: Vec<i64> = ints("normalIndex").into_iter().filter(|&i| i >= 0).collect();
        let get = |i: usize| -> Result<Vec3, String> {
            n.get(i)
                .copied()
                .ok_or_else(|| format!("normal index {i} is out of range (there are {})", n.len()))
        };
        let mut per_corner = Vec::with_capacity(mesh.corners.len());
        for f in 0..faces {
            for k in mesh.face_start[f] as usize..mesh.face_start[f + 1] as usize {
                let v = match binding.as_str() {
                    "OVERALL" => get(0)?,
                    "PER_PART" | "PER_FACE" => get(f)?,
                    "PER_PART_INDEXED" | "PER_FACE_INDEXED" => get(index.get(f).map_or(f, |&i| i as usize))?,
                    "PER_VERTEX" => get(k)?,
                    _ => get(index.get(k).map_or(mesh.corners[k] as usize, |&i| i as usize))?,
                };
                per_corner.push(v);
            }
        }
        mesh.corner_normals = Some(per_corner);
    }
    if let Some(uv) = &texcoords {
        let index: Vec<i64> = ints("textureCoordIndex").into_iter().filter(|&i| i >= 0).collect();
        let mut per_corner = Vec::with_capacity(mesh.corners.len());
        for (k, &c) in mesh.corners.iter().enumerate() {
            let i = index.get(k).map_or(c as usize, |&i| i as usize);
            per_corner.push(
                uv.get(i).copied().ok_or_else(|| format!("texture coordinate index {i} is out of range"))?,
            );
        }
        mesh.corner_uvs = Some(per_corner);
    }
    let tess = mesh.tessellate(&coords)?;
    if tess.indices.is_empty() {
        return Ok(None);
    }
    Ok(Some(GeometryRef::Poly { tess: Arc::new(tess), points: coords, coord: coord_node }))
}

fn strip(mesh: &mut PolyMesh, run: &[u32]) {
    for i in 2..run.len() {
        let tri =
            if i % 2 == 0 { [run[i - 2], run[i - 1], run[i]] } else { [run[i - 1], run[i - 2], run[i]] };
        mesh.corners.extend_from_slice(&tri);
        mesh.face_start.push(mesh.corners.len() as u32);
    }
}
