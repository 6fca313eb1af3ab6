//! glTF 2.0 import (.glb, .gltf with external or `data:` buffers) into an
//! [`ImportedModel`].
//!
//! The file is untrusted. The GLB container is parsed here (byte offsets in errors), the
//! JSON by serde (line:column), the document validated by the gltf crate (JSON pointer),
//! and then every accessor this importer reads is checked *before* it is read: element
//! type and component type for its use, `count ≥ 1`, and `offset + stride·(count−1) +
//! element size` inside its buffer view, the view inside its buffer, the buffer inside the
//! bytes actually present. Counts are therefore always backed by bytes of the file, so no
//! allocation exceeds what the file justifies. Values are checked finite, indices in range,
//! key times strictly increasing, the node hierarchy a forest (no cycles, one parent each).
//!
//! External buffers must be relative paths inside the model's folder (no `..`, no absolute
//! paths, no schemes other than `data:`) naming regular files.

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::fmt;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Quat, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::util::ReadOutputs;
use keyrig_core::{Interpolation, Key, RawTrack};

mod pointer;

use crate::model::{
    ChannelTarget, ImageData, ImageSource, ImportedModel, ModelAnimation, ModelChannel, ModelLight,
    ModelLightKind, ModelMesh, ModelNode, ModelPrimitive, ModelSkin, MorphTarget, PrimitiveMode, TextureRef,
    WeightsTrack,
};

/// Where in the file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// Byte offset from the start of the file (GLB container).
    Byte(usize),
    /// Line and column in the JSON text; `chunk_offset` is the byte offset of the JSON chunk
    /// inside a .glb (0 for a .gltf).
    LineColumn { line: usize, column: usize, chunk_offset: usize },
    /// A JSON pointer (RFC 6901) into the glTF document, e.g. `/accessors/3/count`.
    Pointer(String),
    /// The file as a whole (cannot be read).
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Byte(b) => write!(f, "byte {b}"),
            Location::LineColumn { line, column, chunk_offset: 0 } => {
                write!(f, "line {line}, column {column}")
            }
            Location::LineColumn { line, column, chunk_offset } => {
                write!(f, "JSON chunk at byte {chunk_offset}, line {line}, column {column}")
            }
            Location::Pointer(p) => write!(f, "{}", if p.is_empty() { "/" } else { p }),
            Location::File => write!(f, "file"),
        }
    }
}

/// What is wrong.
#[derive(Debug, thiserror::Error)]
pub enum GltfErrorKind {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    #[error("GLB container: {0}")]
    Glb(String),
    #[error("JSON: {0}")]
    Json(String),
    #[error("invalid glTF: {0}")]
    Invalid(String),
    #[error("required extension {0} is not supported")]
    UnsupportedExtension(String),
    #[error("buffer: {0}")]
    Buffer(String),
    #[error("buffer: {}: {source}", path.display())]
    BufferFile { path: PathBuf, source: std::io::Error },
    #[error("accessor: {0}")]
    Accessor(String),
    #[error("{0} is not finite")]
    NonFinite(String),
    #[error("{what} index {index} is out of range (there are {limit})")]
    IndexOutOfRange { what: String, index: usize, limit: usize },
    #[error("node {node} is its own ancestor (cycle in the node hierarchy)")]
    Cycle { node: usize },
    #[error("node {node} has more than one parent ({first} and {second})")]
    TwoParents { node: usize, first: usize, second: usize },
    #[error("animation: {0}")]
    Animation(String),
}

/// A glTF import error: the file (when known), where in it, and what.
#[derive(Debug, thiserror::Error)]
pub struct GltfError {
    pub file: Option<PathBuf>,
    pub location: Location,
    pub kind: GltfErrorKind,
}

impl fmt::Display for GltfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        write!(f, "{}: {}", self.location, self.kind)
    }
}

pub(crate) fn at(location: Location, kind: GltfErrorKind) -> GltfError {
    GltfError { file: None, location, kind }
}

pub(crate) fn ptr(p: impl Into<String>, kind: GltfErrorKind) -> GltfError {
    at(Location::Pointer(p.into()), kind)
}

/// Converts a gltf-json path (`meshes[0].attributes["POSITION"]`) to a JSON pointer
/// (`/meshes/0/attributes/POSITION`).
#[must_use]
pub fn json_pointer_from_path(path: &str) -> String {
    let path = path.split(" = ").next().unwrap_or(path);
    let mut out = String::new();
    let mut token = String::new();
    let mut in_quotes = false;
    let flush = |out: &mut String, token: &mut String| {
        if !token.is_empty() {
            out.push('/');
            out.push_str(&token.replace('~', "~0").replace('/', "~1"));
            token.clear();
        }
    };
    for c in path.chars() {
        match c {
            '"' => in_quotes = !in_quotes,
            '.' | '[' | ']' if !in_quotes => flush(&mut out, &mut token),
            _ => token.push(c),
        }
    }
    flush(&mut out, &mut token);
    out
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn u32_at(data: &[u8], offset: usize) -> Option<u32> {
    data.get(offset..offset + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The chunks of a .glb: JSON bytes, the JSON chunk's byte offset, and the BIN chunk.
type GlbChunks<'a> = (&'a [u8], usize, Option<&'a [u8]>);

/// Splits a .glb into its chunks, checking the header and every chunk length.
fn parse_glb(data: &[u8]) -> Result<GlbChunks<'_>, GltfError> {
    let glb = |offset: usize, msg: String| at(Location::Byte(offset), GltfErrorKind::Glb(msg));
    if data.len() < 12 {
        return Err(glb(0, format!("file is {} bytes, shorter than the 12-byte header", data.len())));
    }
    let version = u32_at(data, 4).unwrap_or(0);
    if version != 2 {
        return Err(glb(4, format!("version is {version}, expected 2")));
    }
    let length = u32_at(data, 8).unwrap_or(0) as usize;
    if length != data.len() {
        return Err(glb(8, format!("header length is {length} but the file is {} bytes", data.len())));
    }
    let mut offset = 12;
    let mut json = None;
    let mut bin = None;
    while offset < data.len() {
        let (Some(chunk_len), Some(chunk_type)) = (u32_at(data, offset), u32_at(data, offset + 4)) else {
            return Err(glb(offset, "chunk header is cut off".into()));
        };
        let start = offset + 8;
        let end = start.checked_add(chunk_len as usize).filter(|&e| e <= data.len());
        let Some(end) = end else {
            return Err(glb(offset, format!("chunk length {chunk_len} reaches past the end of the file")));
        };
        match chunk_type {
            CHUNK_JSON if json.is_none() && offset == 12 => json = Some((&data[start..end], start)),
            CHUNK_JSON => return Err(glb(offset + 4, "JSON must be the first and only JSON chunk".into())),
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(&data[start..end]),
            CHUNK_BIN => return Err(glb(offset + 4, "BIN chunk must follow the JSON chunk, once".into())),
            _ => {} // Unknown chunks are skipped, as the specification requires.
        }
        offset = end;
    }
    let (json, json_offset) = json.ok_or_else(|| glb(12, "no JSON chunk".into()))?;
    Ok((json, json_offset, bin))
}

/// Imports a .glb or .gltf held in memory. External buffer files cannot be resolved (there
/// is no folder) and are an error; `data:` URIs and the GLB BIN chunk work.
///
/// # Errors
/// Every malformed input gives a [`GltfError`] with its location.
pub fn import_gltf_slice(data: &[u8]) -> Result<ImportedModel, GltfError> {
    import(data, None)
}

/// Reads and imports the .glb or .gltf at `path`; external buffers resolve next to it.
/// The file and its external buffers must be regular files of at most
/// [`crate::file_io::MAX_MODEL_BYTES`] bytes (checked before reading).
///
/// # Errors
/// The file cannot be read, is not a regular file or is too large, or is malformed ([`GltfError`] with the file and location).
pub fn import_gltf_file(path: &Path) -> Result<ImportedModel, GltfError> {
    let with_file = |mut e: GltfError| {
        e.file = Some(path.to_path_buf());
        e
    };
    let data = crate::file_io::read_regular_file(path, crate::file_io::MAX_MODEL_BYTES)
        .map_err(|e| with_file(at(Location::File, GltfErrorKind::Io(e))))?;
    let base = crate::file_io::parent_or_dot(path);
    import(&data, Some(&base)).map_err(with_file)
}

/// Extensions this importer understands (others may be used, but not required).
const SUPPORTED_REQUIRED: [&str; 3] = ["KHR_lights_punctual", "KHR_node_visibility", "KHR_animation_pointer"];

fn import(data: &[u8], base: Option<&Path>) -> Result<ImportedModel, GltfError> {
    let (json_bytes, chunk_offset, bin) =
        if data.starts_with(GLB_MAGIC) { parse_glb(data)? } else { (data, 0, None) };
    let (mut root, raw) = pointer::parse_root(json_bytes, chunk_offset)?;
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_REQUIRED.contains(&ext.as_str()) {
            return Err(ptr(
                format!("/extensionsRequired/{i}"),
                GltfErrorKind::UnsupportedExtension(ext.clone()),
            ));
        }
    }
    // The gltf crate refuses required extensions it does not know; these are read here
    // (crate::gltf_pointer).
    root.extensions_required.retain(|e| !crate::gltf_pointer::READ_FROM_JSON.contains(&e.as_str()));
    check_position_indices(&root)?;
    let doc = match gltf::Document::from_json(root) {
        Ok(doc) => doc,
        Err(gltf::Error::Validation(errors)) => {
            let (path, error) = errors.into_iter().next().map_or_else(
                || (String::new(), "validation failed".to_owned()),
                |(p, e)| {
                    let path = crate::message::clip_long_tokens(p.as_str()).into_owned();
                    (json_pointer_from_path(&path), e.to_string())
                },
            );
            return Err(ptr(path, GltfErrorKind::Invalid(error)));
        }
        Err(e) => return Err(ptr("", GltfErrorKind::Invalid(e.to_string()))),
    };
    let buffers = load_buffers(&doc, base, bin)?;
    let budget = data.len() + buffers.iter().map(|b| b.len()).sum::<usize>();
    let cx = Reader { buffers: &buffers, budget, unbacked: RefCell::default(), cache: Decoded::default() };

    // Meshes first, and their JSON let go before the nodes are read: in a file made of many
    // meshes that JSON is most of the parsed document (docs/benchmarks.md, "Import memory").
    let meshes = read_meshes(&cx, &doc)?;
    let doc = without_mesh_json(doc);
    let nodes = read_nodes(&doc)?;
    let mut model = ImportedModel { nodes, meshes, ..ImportedModel::default() };
    model.roots = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().map(|n| n.index()).collect(),
        None => (0..model.nodes.len()).filter(|&i| model.nodes[i].parent.is_none()).collect(),
    };
    model.images = read_images(&doc);
    model.image_data = read_image_data(&doc, &buffers, base);
    model.skins = doc.skins().map(|s| read_skin(&cx, &s)).collect::<Result<_, _>>()?;
    model.lights = read_lights(&doc)?;
    model.cameras = crate::gltf_camera::read_cameras(&doc).map_err(|e| {
        let kind = if e.non_finite {
            GltfErrorKind::NonFinite(e.message)
        } else {
            GltfErrorKind::Invalid(e.message)
        };
        ptr(e.pointer, kind)
    })?;
    check_skinned_meshes(&model)?;
    check_animation_json(doc.as_json(), &raw)?;
    model.animations =
        doc.animations().map(|a| read_animation(&cx, &model, &a, &raw)).collect::<Result<_, _>>()?;
    pointer::read_pointer_channels(&cx, &doc, &mut model, &raw)?;
    Ok(model)
}

/// Loads every buffer: the GLB BIN chunk (borrowed), `data:` URIs, or relative files.
fn load_buffers<'a>(
    doc: &gltf::Document,
    base: Option<&Path>,
    mut bin: Option<&'a [u8]>,
) -> Result<Vec<Cow<'a, [u8]>>, GltfError> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let here = format!("/buffers/{}", buffer.index());
        let bytes: Cow<'a, [u8]> = match buffer.source() {
            gltf::buffer::Source::Bin => Cow::Borrowed(bin.take().ok_or_else(|| {
                ptr(&here, GltfErrorKind::Buffer("refers to a missing GLB BIN chunk".into()))
            })?),
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
                    .map_err(|e| ptr(format!("{here}/uri"), GltfErrorKind::Buffer(e.to_string())))?;
                Cow::Owned(data.0)
            }
            gltf::buffer::Source::Uri(uri) => {
                Cow::Owned(read_relative(base, uri).map_err(|kind| ptr(format!("{here}/uri"), kind))?)
            }
        };
        if bytes.len() < buffer.length() {
            return Err(ptr(
                format!("{here}/byteLength"),
                GltfErrorKind::Buffer(format!(
                    "byteLength is {} but only {} bytes exist",
                    buffer.length(),
                    bytes.len()
                )),
            ));
        }
        out.push(bytes);
    }
    Ok(out)
}

/// Decodes `%XX` escapes of a URI.
fn percent_decode(uri: &str) -> Result<String, GltfErrorKind> {
    let bad_escape = || GltfErrorKind::Buffer(format!("bad escape in URI {uri:?}"));
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = uri.get(i + 1..i + 3).ok_or_else(bad_escape)?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| bad_escape())?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| GltfErrorKind::Buffer(format!("URI {uri:?} is not UTF-8")))
}

/// Reads the external buffer file `uri` names, relative to the model's folder `base`.
fn read_relative(base: Option<&Path>, uri: &str) -> Result<Vec<u8>, GltfErrorKind> {
    let buffer = |message: String| GltfErrorKind::Buffer(message);
    let Some(base) = base else {
        return Err(buffer(format!("external file {uri:?} cannot be resolved when importing from memory")));
    };
    if uri.contains(':') {
        return Err(buffer(format!("URI {uri:?}: only relative paths and data: URIs are supported")));
    }
    let rel = PathBuf::from(percent_decode(uri)?);
    if rel.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
        return Err(buffer(format!("URI {uri:?} must stay inside the model's folder")));
    }
    let path = base.join(rel);
    crate::file_io::read_regular_file(&path, crate::file_io::MAX_MODEL_BYTES)
        .map_err(|source| GltfErrorKind::BufferFile { path, source })
}

/// Borrowed buffers, the byte budget that bounds accessors without a buffer view, and the
/// accessors decoded so far.
pub(crate) struct Reader<'a, 'b> {
    buffers: &'a [Cow<'b, [u8]>],
    budget: usize,
    /// Bytes of accessors without a buffer view (all-zero sparse bases) accepted so far:
    /// they have no bytes of their own in the file, so together they must fit the budget.
    unbacked: RefCell<(usize, HashSet<usize>)>,
    cache: Decoded,
}

/// Accessors decoded once and shared (by accessor index): a file whose primitives use one
/// accessor many times holds its values once.
#[derive(Default)]
struct Decoded {
    vec3: RefCell<HashMap<usize, Arc<[Vec3]>>>,
    vec2: RefCell<HashMap<usize, Arc<[Vec2]>>>,
    joints: RefCell<HashMap<usize, Arc<[[u16; 4]]>>>,
    weights: RefCell<HashMap<usize, Arc<[[f32; 4]]>>>,
    indices: RefCell<HashMap<usize, Arc<[u32]>>>,
}

/// The cached value of accessor `index` in `cache`, decoding it with `decode` the first time.
fn shared<T>(
    cache: &RefCell<HashMap<usize, Arc<[T]>>>,
    index: usize,
    decode: impl FnOnce() -> Result<Vec<T>, GltfError>,
) -> Result<Arc<[T]>, GltfError> {
    if let Some(v) = cache.borrow().get(&index) {
        return Ok(Arc::clone(v));
    }
    let v: Arc<[T]> = decode()?.into();
    cache.borrow_mut().insert(index, Arc::clone(&v));
    Ok(v)
}

impl Reader<'_, '_> {
    pub(crate) fn get<'s>(&'s self) -> impl Fn(gltf::Buffer<'_>) -> Option<&'s [u8]> + Clone + 's {
        let buffers = self.buffers;
        move |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d[..])
    }
}

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// Checks that accessor `acc` has one of `dims`/`types` and lies inside the file's bytes.
pub(crate) fn check_accessor(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    use_: &str,
    dims: &[Dimensions],
    types: &[DataType],
) -> Result<usize, GltfError> {
    let here = format!("/accessors/{}", acc.index());
    let bad = |msg: String| ptr(&here, GltfErrorKind::Accessor(format!("{msg} (used as {use_})")));
    if !dims.contains(&acc.dimensions()) || !types.contains(&acc.data_type()) {
        return Err(bad(format!("type {:?} of {:?} is not allowed", acc.dimensions(), acc.data_type())));
    }
    let count = acc.count();
    if count == 0 {
        return Err(bad("count is 0".into()));
    }
    let elem = component_size(acc.data_type()) * acc.dimensions().multiplicity();
    match acc.view() {
        Some(view) => {
            check_view(cx, &view)?;
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(bad(format!("byteStride {stride} is smaller than the element size {elem}")));
            }
            let end = stride
                .checked_mul(count - 1)
                .and_then(|n| n.checked_add(acc.offset()))
                .and_then(|n| n.checked_add(elem));
            if end.is_none_or(|end| end > view.length()) {
                return Err(bad(format!(
                    "{count} elements of {elem} bytes (stride {stride}) at offset {} do not fit in buffer view {} ({} bytes)",
                    acc.offset(),
                    view.index(),
                    view.length()
                )));
            }
        }
        None if acc.sparse().is_none() => {
            return Err(bad("has neither a bufferView nor sparse values".into()));
        }
        None => {
            // Counted once per accessor, however often it is used.
            let mut unbacked = cx.unbacked.borrow_mut();
            if unbacked.1.insert(acc.index()) {
                match count.checked_mul(elem).and_then(|n| n.checked_add(unbacked.0)) {
                    Some(total) if total <= cx.budget => unbacked.0 = total,
                    _ => {
                        return Err(bad(format!(
                            "accessors without a bufferView would decode to more than the file's {} bytes",
                            cx.budget
                        )))
                    }
                }
            }
        }
    }
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(bad(format!("sparse count {n} must be in 1..={count}")));
        }
        let idx_size = match sparse.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        for (view, offset, size, what) in [
            (sparse.indices().view(), sparse.indices().offset(), idx_size, "sparse indices"),
            (sparse.values().view(), sparse.values().offset(), elem, "sparse values"),
        ] {
            check_view(cx, &view)?;
            if n.checked_mul(size).and_then(|b| b.checked_add(offset)).is_none_or(|end| end > view.length()) {
                return Err(bad(format!("{what} do not fit in buffer view {}", view.index())));
            }
        }
    }
    Ok(count)
}

fn check_view(cx: &Reader<'_, '_>, view: &gltf::buffer::View<'_>) -> Result<(), GltfError> {
    let data_len = cx.buffers.get(view.buffer().index()).map_or(0, |b| b.len());
    let end = view.offset().checked_add(view.length());
    if end.is_none_or(|e| e > data_len || e > view.buffer().length()) {
        return Err(ptr(
            format!("/bufferViews/{}", view.index()),
            GltfErrorKind::Buffer(format!(
                "{} bytes at offset {} do not fit in buffer {} ({} bytes)",
                view.length(),
                view.offset(),
                view.buffer().index(),
                view.buffer().length().min(data_len)
            )),
        ));
    }
    Ok(())
}

fn read_nodes(doc: &gltf::Document) -> Result<Vec<ModelNode>, GltfError> {
    let mut nodes: Vec<ModelNode> = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            let here = format!("/nodes/{}", n.index());
            let (t, r, s) = (Vec3::from_array(t), Quat::from_array(r), Vec3::from_array(s));
            if !(t.is_finite() && r.is_finite() && s.is_finite()) {
                return Err(ptr(&here, GltfErrorKind::NonFinite("node transform".into())));
            }
            let rotation = r.try_normalize_quat().ok_or_else(|| {
                ptr(format!("{here}/rotation"), GltfErrorKind::Invalid("rotation has zero length".into()))
            })?;
            if let Some(w) = n.weights() {
                if w.iter().any(|x| !x.is_finite()) {
                    return Err(ptr(
                        format!("{here}/weights"),
                        GltfErrorKind::NonFinite("morph weight".into()),
                    ));
                }
            }
            Ok(ModelNode {
                name: n.name().map_or_else(|| format!("node{}", n.index()), str::to_owned),
                parent: None,
                children: n.children().map(|c| c.index()).collect(),
                translation: t,
                rotation,
                scale: s,
                // From the JSON: the meshes' own JSON is gone (`without_mesh_json`).
                mesh: doc.as_json().nodes[n.index()].mesh.map(|m| m.value()),
                skin: n.skin().map(|s| s.index()),
                light: n.light().map(|l| l.index()),
                camera: n.camera().map(|c| c.index()),
                weights: n.weights().map(<[f32]>::to_vec),
                visible: true,
            })
        })
        .collect::<Result<_, _>>()?;
    for p in 0..nodes.len() {
        for ci in 0..nodes[p].children.len() {
            let c = nodes[p].children[ci];
            if c == p {
                return Err(ptr(format!("/nodes/{p}/children/{ci}"), GltfErrorKind::Cycle { node: p }));
            }
            if let Some(first) = nodes[c].parent {
                return Err(ptr(
                    format!("/nodes/{p}/children/{ci}"),
                    GltfErrorKind::TwoParents { node: c, first, second: p },
                ));
            }
            nodes[c].parent = Some(p);
        }
    }
    // Every node has at most one parent now, so a cycle is a walk up that comes back to a
    // node of the same walk. Marking finished nodes keeps this linear in the node count.
    const UNSEEN: u8 = 0;
    const ON_WALK: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![UNSEEN; nodes.len()];
    let mut walk = Vec::new();
    for start in 0..nodes.len() {
        let mut cur = Some(start);
        while let Some(c) = cur {
            match state[c] {
                DONE => break,
                ON_WALK => return Err(ptr(format!("/nodes/{c}"), GltfErrorKind::Cycle { node: c })),
                _ => {
                    state[c] = ON_WALK;
                    walk.push(c);
                    cur = nodes[c].parent;
                }
            }
        }
        for c in walk.drain(..) {
            state[c] = DONE;
        }
    }
    Ok(nodes)
}

fn read_images(doc: &gltf::Document) -> Vec<ImageSource> {
    // Read from the JSON: the wrapper API unwraps fields that validation does not require.
    doc.as_json()
        .images
        .iter()
        .map(|img| match (&img.uri, img.buffer_view) {
            (Some(uri), _) => ImageSource::Uri(uri.clone()),
            (None, Some(view)) => ImageSource::BufferView {
                view: view.value(),
                mime_type: img.mime_type.as_ref().map_or_else(String::new, |m| m.0.clone()),
            },
            (None, None) => ImageSource::Uri(String::new()),
        })
        .collect()
}

/// The bytes of every image, where they can be read (see [`ImageData`]); an image that cannot
/// be read is `None`, never an error: images are not needed to pose or deform a model.
fn read_image_data(
    doc: &gltf::Document,
    buffers: &[Cow<'_, [u8]>],
    base: Option<&Path>,
) -> Vec<Option<ImageData>> {
    let sniff = |bytes: &[u8]| {
        if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            Some("image/png")
        } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
            Some("image/jpeg")
        } else {
            None
        }
    };
    // Read from the JSON, as `read_images` does: `gltf::Image::source` unwraps a view's
    // `mimeType` and an image's `uri`, which validation does not require (found by fuzzing:
    // an image with a buffer view and no MIME type panicked).
    doc.as_json()
        .images
        .iter()
        .map(|image| {
            let bytes: Vec<u8> = match (&image.uri, image.buffer_view) {
                (_, Some(view)) => {
                    let view = doc.views().nth(view.value())?;
                    let data = buffers.get(view.buffer().index())?;
                    data.get(view.offset()..view.offset().checked_add(view.length())?)?.to_vec()
                }
                (Some(uri), None) if uri.starts_with("data:") => {
                    gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None).ok()?.0
                }
                (Some(uri), None) => read_relative(base, uri).ok()?,
                (None, None) => return None,
            };
            let mime_type = sniff(&bytes)?.to_owned();
            Some(ImageData { bytes: bytes.into(), mime_type })
        })
        .collect()
}

fn read_lights(doc: &gltf::Document) -> Result<Vec<ModelLight>, GltfError> {
    use gltf::json::extensions::scene::khr_lights_punctual::Type;
    use gltf::json::validation::Checked;
    let Some(lights) = doc.as_json().extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()) else {
        return Ok(Vec::new());
    };
    lights
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let here = format!("/extensions/KHR_lights_punctual/lights/{i}");
            let kind = match (&l.type_, &l.spot) {
                (Checked::Valid(Type::Directional), _) => ModelLightKind::Directional,
                (Checked::Valid(Type::Point), _) => ModelLightKind::Point,
                (Checked::Valid(Type::Spot), Some(spot)) => ModelLightKind::Spot {
                    inner_cone_angle: spot.inner_cone_angle,
                    outer_cone_angle: spot.outer_cone_angle,
                },
                _ => {
                    return Err(ptr(
                        &here,
                        GltfErrorKind::Invalid("light type or spot parameters invalid".into()),
                    ))
                }
            };
            let numbers = l.color.iter().chain([&l.intensity]).chain(l.range.as_ref());
            if numbers.into_iter().any(|x| !x.is_finite()) {
                return Err(ptr(&here, GltfErrorKind::NonFinite("light parameter".into())));
            }
            Ok(ModelLight {
                name: l.name.clone().unwrap_or_else(|| format!("light{i}")),
                kind,
                colour: Vec3::from_array(l.color),
                intensity: l.intensity,
                range: l.range,
            })
        })
        .collect()
}

fn finite_vec3s(values: Vec<[f32; 3]>, here: &str, what: &str) -> Result<Vec<Vec3>, GltfError> {
    values
        .into_iter()
        .map(|v| {
            let v = Vec3::from_array(v);
            if v.is_finite() {
                Ok(v)
            } else {
                Err(ptr(here, GltfErrorKind::NonFinite(what.into())))
            }
        })
        .collect()
}

pub(crate) fn count_matches(got: usize, expected: usize, here: &str) -> Result<(), GltfError> {
    if got == expected {
        Ok(())
    } else {
        Err(ptr(here, GltfErrorKind::Accessor(format!("read {got} elements, expected {expected}"))))
    }
}

const F32: &[DataType] = &[DataType::F32];

/// A checked float VEC3 accessor (positions, normals, morph displacements), decoded once.
fn shared_vec3s(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    here: &str,
    what: &str,
) -> Result<Arc<[Vec3]>, GltfError> {
    shared(&cx.cache.vec3, acc.index(), || {
        let values: Vec<[f32; 3]> = gltf::accessor::Iter::<[f32; 3]>::new(acc.clone(), cx.get())
            .map(Iterator::collect)
            .unwrap_or_default();
        let v = finite_vec3s(values, here, what)?;
        count_matches(v.len(), acc.count(), here)?;
        Ok(v)
    })
}

/// A checked TEXCOORD accessor (float or normalized integers), decoded once.
fn shared_texcoords(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    here: &str,
) -> Result<Arc<[Vec2]>, GltfError> {
    use gltf::mesh::util::ReadTexCoords;
    shared(&cx.cache.vec2, acc.index(), || {
        let (a, get) = (acc.clone(), cx.get());
        let read = match acc.data_type() {
            DataType::U8 => gltf::accessor::Iter::new(a, get).map(ReadTexCoords::U8),
            DataType::U16 => gltf::accessor::Iter::new(a, get).map(ReadTexCoords::U16),
            _ => gltf::accessor::Iter::new(a, get).map(ReadTexCoords::F32),
        };
        let v: Vec<Vec2> = read.map(|t| t.into_f32().map(Vec2::from_array).collect()).unwrap_or_default();
        count_matches(v.len(), acc.count(), here)?;
        if v.iter().any(|t| !t.is_finite()) {
            return Err(ptr(here, GltfErrorKind::NonFinite("texture coordinate".into())));
        }
        Ok(v)
    })
}

/// A checked JOINTS accessor, decoded once.
fn shared_joints(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    here: &str,
) -> Result<Arc<[[u16; 4]]>, GltfError> {
    use gltf::mesh::util::ReadJoints;
    shared(&cx.cache.joints, acc.index(), || {
        let (a, get) = (acc.clone(), cx.get());
        let read = match acc.data_type() {
            DataType::U8 => gltf::accessor::Iter::new(a, get).map(ReadJoints::U8),
            _ => gltf::accessor::Iter::new(a, get).map(ReadJoints::U16),
        };
        let v: Vec<[u16; 4]> = read.map(|j| j.into_u16().collect()).unwrap_or_default();
        count_matches(v.len(), acc.count(), here)?;
        Ok(v)
    })
}

/// A checked WEIGHTS accessor (float or normalized integers), decoded once.
fn shared_weights(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    here: &str,
) -> Result<Arc<[[f32; 4]]>, GltfError> {
    use gltf::mesh::util::ReadWeights;
    shared(&cx.cache.weights, acc.index(), || {
        let (a, get) = (acc.clone(), cx.get());
        let read = match acc.data_type() {
            DataType::U8 => gltf::accessor::Iter::new(a, get).map(ReadWeights::U8),
            DataType::U16 => gltf::accessor::Iter::new(a, get).map(ReadWeights::U16),
            _ => gltf::accessor::Iter::new(a, get).map(ReadWeights::F32),
        };
        let v: Vec<[f32; 4]> = read.map(|w| w.into_f32().collect()).unwrap_or_default();
        count_matches(v.len(), acc.count(), here)?;
        if v.iter().flatten().any(|w| !w.is_finite()) {
            return Err(ptr(here, GltfErrorKind::NonFinite("weight".into())));
        }
        Ok(v)
    })
}

/// A checked index accessor, decoded once (as read; primitive modes are converted later).
fn shared_indices(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    here: &str,
) -> Result<Arc<[u32]>, GltfError> {
    use gltf::mesh::util::ReadIndices;
    shared(&cx.cache.indices, acc.index(), || {
        let (a, get) = (acc.clone(), cx.get());
        let read = match acc.data_type() {
            DataType::U8 => gltf::accessor::Iter::new(a, get).map(ReadIndices::U8),
            DataType::U16 => gltf::accessor::Iter::new(a, get).map(ReadIndices::U16),
            _ => gltf::accessor::Iter::new(a, get).map(ReadIndices::U32),
        };
        let v: Vec<u32> = read.map(|i| i.into_u32().collect()).unwrap_or_default();
        count_matches(v.len(), acc.count(), here)?;
        Ok(v)
    })
}

/// Reads every mesh. Meshes whose primitives are written identically (the same accessors,
/// material, mode and targets) share one decoded primitive list: a file that repeats one mesh's
/// primitives a hundred thousand times holds them once.
fn read_meshes(cx: &Reader<'_, '_>, doc: &gltf::Document) -> Result<Vec<ModelMesh>, GltfError> {
    // An `Arc<Vec>`, not an `Arc<[_]>`: the list moves in without a copy.
    let mut lists: HashMap<String, Arc<Vec<ModelPrimitive>>> = HashMap::new();
    let mut meshes = Vec::with_capacity(doc.meshes().len());
    for mesh in doc.meshes() {
        // The JSON of the mesh's primitives is the key: equal text, equal primitives.
        let key = serde_json::to_string(&doc.as_json().meshes[mesh.index()].primitives)
            .map_err(|e| ptr(format!("/meshes/{}", mesh.index()), GltfErrorKind::Invalid(e.to_string())))?;
        let primitives = match lists.get(&key) {
            Some(list) => Arc::clone(list),
            None => {
                let list = Arc::new(read_primitives(cx, &mesh)?);
                lists.insert(key, Arc::clone(&list));
                list
            }
        };
        let weights = mesh.weights().map(<[f32]>::to_vec).unwrap_or_default();
        if weights.iter().any(|w| !w.is_finite()) {
            return Err(ptr(
                format!("/meshes/{}/weights", mesh.index()),
                GltfErrorKind::NonFinite("morph weight".into()),
            ));
        }
        meshes.push(ModelMesh {
            name: mesh.name().map_or_else(|| format!("mesh{}", mesh.index()), str::to_owned),
            primitives,
            weights,
        });
    }
    Ok(meshes)
}

/// The document without its meshes' JSON, once [`read_meshes`] has read them. Nothing read
/// after it reaches a mesh through the document (nodes name their mesh by index, from the JSON).
fn without_mesh_json(doc: gltf::Document) -> gltf::Document {
    let mut root = doc.into_json();
    root.meshes = Vec::new();
    gltf::Document::from_json_without_validation(root)
}

fn read_primitives(cx: &Reader<'_, '_>, mesh: &gltf::Mesh<'_>) -> Result<Vec<ModelPrimitive>, GltfError> {
    let mut primitives = Vec::with_capacity(mesh.primitives().len());
    for prim in mesh.primitives() {
        let here = format!("/meshes/{}/primitives/{}", mesh.index(), prim.index());
        let attr = |name: &str| format!("{here}/attributes/{name}");

        let pos_acc = prim.get(&gltf::Semantic::Positions).ok_or_else(|| {
            ptr(format!("{here}/attributes"), GltfErrorKind::Invalid("primitive has no POSITION".into()))
        })?;
        let n = check_accessor(cx, &pos_acc, "POSITION", &[Dimensions::Vec3], F32)?;
        let positions = shared_vec3s(cx, &pos_acc, &attr("POSITION"), "position")?;

        let normals = match prim.get(&gltf::Semantic::Normals) {
            Some(acc) => {
                check_same_count(cx, &acc, "NORMAL", &[Dimensions::Vec3], F32, n, &attr("NORMAL"))?;
                Some(shared_vec3s(cx, &acc, &attr("NORMAL"), "normal")?)
            }
            None => None,
        };
        let texcoords = match prim.get(&gltf::Semantic::TexCoords(0)) {
            Some(acc) => {
                let types = [DataType::F32, DataType::U8, DataType::U16];
                check_same_count(
                    cx,
                    &acc,
                    "TEXCOORD_0",
                    &[Dimensions::Vec2],
                    &types,
                    n,
                    &attr("TEXCOORD_0"),
                )?;
                Some(shared_texcoords(cx, &acc, &attr("TEXCOORD_0"))?)
            }
            None => None,
        };
        let mut joint_sets = Vec::new();
        let mut weight_sets = Vec::new();
        for set in 0u32.. {
            let (Some(j_acc), Some(w_acc)) =
                (prim.get(&gltf::Semantic::Joints(set)), prim.get(&gltf::Semantic::Weights(set)))
            else {
                break;
            };
            let (jn, wn) = (format!("JOINTS_{set}"), format!("WEIGHTS_{set}"));
            check_same_count(
                cx,
                &j_acc,
                &jn,
                &[Dimensions::Vec4],
                &[DataType::U8, DataType::U16],
                n,
                &attr(&jn),
            )?;
            let wt = [DataType::F32, DataType::U8, DataType::U16];
            check_same_count(cx, &w_acc, &wn, &[Dimensions::Vec4], &wt, n, &attr(&wn))?;
            joint_sets.push(shared_joints(cx, &j_acc, &attr(&jn))?);
            weight_sets.push(shared_weights(cx, &w_acc, &attr(&wn))?);
        }

        let mut targets = Vec::new();
        for (t, target) in prim.morph_targets().enumerate() {
            let there = format!("{here}/targets/{t}");
            let read =
                |acc: Option<gltf::Accessor<'_>>, what: &str| -> Result<Option<Arc<[Vec3]>>, GltfError> {
                    let Some(acc) = acc else { return Ok(None) };
                    check_same_count(cx, &acc, what, &[Dimensions::Vec3], F32, n, &there)?;
                    Ok(Some(shared_vec3s(cx, &acc, &there, what)?))
                };
            let positions = read(target.positions(), "morph POSITION")?;
            let normals = read(target.normals(), "morph NORMAL")?;
            targets.push(MorphTarget { positions, normals });
        }

        let raw_indices: Arc<[u32]> = match prim.indices() {
            Some(acc) => {
                let types = [DataType::U8, DataType::U16, DataType::U32];
                check_accessor(cx, &acc, "indices", &[Dimensions::Scalar], &types)?;
                let v = shared_indices(cx, &acc, &format!("{here}/indices"))?;
                if let Some(&bad) = v.iter().find(|&&i| i as usize >= n) {
                    return Err(ptr(
                        format!("{here}/indices"),
                        GltfErrorKind::IndexOutOfRange {
                            what: "vertex".into(),
                            index: bad as usize,
                            limit: n,
                        },
                    ));
                }
                v
            }
            None => (0..n as u32).collect(),
        };
        let (mode, indices) = convert_mode(prim.mode(), raw_indices);

        let material = prim.material();
        let pbr = material.pbr_metallic_roughness();
        let base_colour_texture = pbr.base_color_texture().map(|info| TextureRef {
            texture: info.texture().index(),
            image: info.texture().source().index(),
            texcoord_set: info.tex_coord(),
            sampler: sampler_of(&info.texture().sampler()),
        });
        primitives.push(ModelPrimitive {
            mode,
            positions,
            normals,
            texcoords,
            indices,
            joint_sets,
            weight_sets,
            morph_targets: targets,
            base_colour_factor: pbr.base_color_factor(),
            base_colour_texture,
            material: material.index(),
        });
    }
    Ok(primitives)
}

fn check_same_count(
    cx: &Reader<'_, '_>,
    acc: &gltf::Accessor<'_>,
    use_: &str,
    dims: &[Dimensions],
    types: &[DataType],
    expected: usize,
    here: &str,
) -> Result<(), GltfError> {
    let count = check_accessor(cx, acc, use_, dims, types)?;
    if count != expected {
        return Err(ptr(
            here,
            GltfErrorKind::Accessor(format!("{use_} has {count} elements, POSITION has {expected}")),
        ));
    }
    Ok(())
}

/// Triangle strips and fans become lists; line strips and loops become line lists. Lists
/// keep the decoded (shared) indices; a triangle list's incomplete last triangle is dropped.
fn convert_mode(mode: gltf::mesh::Mode, idx: Arc<[u32]>) -> (PrimitiveMode, Arc<[u32]>) {
    use gltf::mesh::Mode;
    let whole = |idx: Arc<[u32]>, per: usize| {
        if idx.len().is_multiple_of(per) {
            idx
        } else {
            idx[..idx.len() / per * per].into()
        }
    };
    match mode {
        Mode::Triangles => (PrimitiveMode::Triangles, whole(idx, 3)),
        Mode::TriangleStrip => (
            PrimitiveMode::Triangles,
            (0..idx.len().saturating_sub(2))
                .flat_map(|i| {
                    if i % 2 == 0 {
                        [idx[i], idx[i + 1], idx[i + 2]]
                    } else {
                        [idx[i + 1], idx[i], idx[i + 2]]
                    }
                })
                .collect(),
        ),
        Mode::TriangleFan => (
            PrimitiveMode::Triangles,
            (1..idx.len().saturating_sub(1)).flat_map(|i| [idx[0], idx[i], idx[i + 1]]).collect(),
        ),
        Mode::Lines => (PrimitiveMode::Lines, whole(idx, 2)),
        Mode::LineStrip => (PrimitiveMode::Lines, idx.windows(2).flat_map(|w| [w[0], w[1]]).collect()),
        Mode::LineLoop => {
            let mut out: Vec<u32> = idx.windows(2).flat_map(|w| [w[0], w[1]]).collect();
            if let (Some(&first), Some(&last)) = (idx.first(), idx.last()) {
                if idx.len() > 2 {
                    out.extend([last, first]);
                }
            }
            (PrimitiveMode::Lines, out.into())
        }
        Mode::Points => (PrimitiveMode::Points, idx),
    }
}

fn read_skin(cx: &Reader<'_, '_>, skin: &gltf::Skin<'_>) -> Result<ModelSkin, GltfError> {
    let here = format!("/skins/{}", skin.index());
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    if joints.is_empty() {
        return Err(ptr(format!("{here}/joints"), GltfErrorKind::Invalid("skin has no joints".into())));
    }
    let inverse_bind_matrices = match skin.inverse_bind_matrices() {
        Some(acc) => {
            let count = check_accessor(cx, &acc, "inverseBindMatrices", &[Dimensions::Mat4], F32)?;
            if count < joints.len() {
                return Err(ptr(
                    format!("{here}/inverseBindMatrices"),
                    GltfErrorKind::Accessor(format!("{count} matrices for {} joints", joints.len())),
                ));
            }
            let m: Vec<Mat4> = skin
                .reader(cx.get())
                .read_inverse_bind_matrices()
                .map(|it| it.map(|c| Mat4::from_cols_array_2d(&c)).collect())
                .unwrap_or_default();
            count_matches(m.len(), count, &format!("{here}/inverseBindMatrices"))?;
            if m.iter().any(|m| !m.is_finite()) {
                return Err(ptr(
                    format!("{here}/inverseBindMatrices"),
                    GltfErrorKind::NonFinite("matrix".into()),
                ));
            }
            m
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    Ok(ModelSkin {
        name: skin.name().map_or_else(|| format!("skin{}", skin.index()), str::to_owned),
        joints,
        inverse_bind_matrices,
        skeleton: skin.skeleton().map(|n| n.index()),
        deformer: None,
    })
}

/// Every joint index of a skinned mesh must name one of its skin's joints.
fn check_skinned_meshes(model: &ImportedModel) -> Result<(), GltfError> {
    // Each (mesh, skin) pair once: many nodes may show one skinned mesh, and checking it per
    // node would take time proportional to nodes × vertices.
    let mut checked = HashSet::new();
    for (i, node) in model.nodes.iter().enumerate() {
        let (Some(m), Some(s)) = (node.mesh, node.skin) else { continue };
        if !checked.insert((m, s)) {
            continue;
        }
        let (Some(mesh), Some(skin)) = (model.meshes.get(m), model.skins.get(s)) else { continue };
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (set, joints) in prim.joint_sets.iter().enumerate() {
                if let Some(&bad) = joints.iter().flatten().find(|&&j| usize::from(j) >= skin.joints.len()) {
                    return Err(ptr(
                        format!("/meshes/{m}/primitives/{p}/attributes/JOINTS_{set}"),
                        GltfErrorKind::IndexOutOfRange {
                            what: format!("joint (mesh used by node {i} with skin {s})"),
                            index: usize::from(bad),
                            limit: skin.joints.len(),
                        },
                    ));
                }
            }
        }
    }
    Ok(())
}

/// gltf-json's own validation indexes the POSITION accessor before checking its index.
fn check_position_indices(root: &gltf::json::Root) -> Result<(), GltfError> {
    let position = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(index) = prim.attributes.get(&position) {
                let limit = root.accessors.len();
                if index.value() >= limit {
                    return Err(ptr(
                        format!("/meshes/{m}/primitives/{p}/attributes/POSITION"),
                        GltfErrorKind::IndexOutOfRange {
                            what: "accessor".into(),
                            index: index.value(),
                            limit,
                        },
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The gltf crate's validation does not check animation channels and samplers fully, and its
/// accessors unwrap them; so check every index and enum here first.
fn check_animation_json(root: &gltf::json::Root, raw: &pointer::Raw) -> Result<(), GltfError> {
    use gltf::json::validation::Checked;
    for (a, anim) in root.animations.iter().enumerate() {
        for (c, ch) in anim.channels.iter().enumerate() {
            let here = format!("/animations/{a}/channels/{}", raw.file_channel(a, c));
            let checks = [
                (format!("{here}/sampler"), "sampler", ch.sampler.value(), anim.samplers.len()),
                (format!("{here}/target/node"), "node", ch.target.node.value(), root.nodes.len()),
            ];
            for (pointer, what, index, limit) in checks {
                if index >= limit {
                    return Err(ptr(
                        pointer,
                        GltfErrorKind::IndexOutOfRange { what: what.into(), index, limit },
                    ));
                }
            }
            if !matches!(ch.target.path, Checked::Valid(_)) {
                return Err(ptr(
                    format!("{here}/target/path"),
                    GltfErrorKind::Invalid("unknown target path".into()),
                ));
            }
        }
        for (s, sampler) in anim.samplers.iter().enumerate() {
            let here = format!("/animations/{a}/samplers/{s}");
            for (field, index) in [("input", sampler.input.value()), ("output", sampler.output.value())] {
                if index >= root.accessors.len() {
                    return Err(ptr(
                        format!("{here}/{field}"),
                        GltfErrorKind::IndexOutOfRange {
                            what: "accessor".into(),
                            index,
                            limit: root.accessors.len(),
                        },
                    ));
                }
            }
            if !matches!(sampler.interpolation, Checked::Valid(_)) {
                return Err(ptr(
                    format!("{here}/interpolation"),
                    GltfErrorKind::Invalid("unknown interpolation".into()),
                ));
            }
        }
    }
    Ok(())
}

fn read_animation(
    cx: &Reader<'_, '_>,
    model: &ImportedModel,
    anim: &gltf::Animation<'_>,
    raw: &pointer::Raw,
) -> Result<ModelAnimation, GltfError> {
    let mut channels = Vec::new();
    for channel in anim.channels() {
        let sampler = channel.sampler();
        let here = format!("/animations/{}/samplers/{}", anim.index(), sampler.index());
        let node = channel.target().node().index();
        let times = pointer::key_times(cx, &sampler.input(), &here)?;
        let key_count = times.len();
        let reader = channel.reader(cx.get());
        let interpolation = match sampler.interpolation() {
            gltf::animation::Interpolation::Step => Interpolation::Step,
            gltf::animation::Interpolation::Linear => Interpolation::Linear,
            gltf::animation::Interpolation::CubicSpline => Interpolation::Hermite,
        };
        let per_key = if interpolation == Interpolation::Hermite { 3 } else { 1 };
        let output = sampler.output();
        let out_here = format!("/accessors/{}", output.index());
        let property = channel.target().property();
        use gltf::animation::Property;
        let (dims, types): (Dimensions, &[DataType]) = match property {
            Property::Translation | Property::Scale => (Dimensions::Vec3, F32),
            Property::Rotation => {
                (Dimensions::Vec4, &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16])
            }
            Property::MorphTargetWeights => (
                Dimensions::Scalar,
                &[DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16],
            ),
        };
        let out_count = check_accessor(cx, &output, "animation output", &[dims], types)?;
        let targets = if property == Property::MorphTargetWeights {
            let mesh = model.nodes.get(node).and_then(|n| n.mesh).and_then(|m| model.meshes.get(m));
            let targets = mesh.and_then(|m| m.primitives.first()).map_or(0, |p| p.morph_targets.len());
            if targets == 0 {
                return Err(ptr(
                    format!(
                        "/animations/{}/channels/{}/target",
                        anim.index(),
                        raw.file_channel(anim.index(), channel.index())
                    ),
                    GltfErrorKind::Animation(format!(
                        "animates morph weights of node {node}, whose mesh has no targets"
                    )),
                ));
            }
            targets
        } else {
            1
        };
        if out_count != key_count * per_key * targets {
            return Err(ptr(
                format!("{here}/output"),
                GltfErrorKind::Animation(format!(
                    "output has {out_count} elements, expected {key_count} keys × {per_key} × {targets}"
                )),
            ));
        }
        let outputs = reader.read_outputs().ok_or_else(|| {
            ptr(format!("{here}/output"), GltfErrorKind::Accessor("output cannot be read".into()))
        })?;
        let target = match outputs {
            ReadOutputs::Translations(it) => {
                let v = finite_vec3s(it.collect(), &out_here, "translation")?;
                count_matches(v.len(), out_count, &out_here)?;
                ChannelTarget::Translation(make_track(&times, &v, interpolation))
            }
            ReadOutputs::Scales(it) => {
                let v = finite_vec3s(it.collect(), &out_here, "scale")?;
                count_matches(v.len(), out_count, &out_here)?;
                ChannelTarget::Scale(make_track(&times, &v, interpolation))
            }
            ReadOutputs::Rotations(it) => {
                let raw: Vec<[f32; 4]> = it.into_f32().collect();
                count_matches(raw.len(), out_count, &out_here)?;
                let mut v = Vec::with_capacity(raw.len());
                for (i, q) in raw.into_iter().enumerate() {
                    let q = Quat::from_array(q);
                    if !q.is_finite() {
                        return Err(ptr(&out_here, GltfErrorKind::NonFinite("rotation".into())));
                    }
                    // Values are normalized; CUBICSPLINE tangents (slots 0 and 2) are not.
                    let is_value = per_key == 1 || i % 3 == 1;
                    v.push(if is_value {
                        q.try_normalize_quat().ok_or_else(|| {
                            ptr(&out_here, GltfErrorKind::Animation(format!("rotation {i} has zero length")))
                        })?
                    } else {
                        q
                    });
                }
                ChannelTarget::Rotation(make_track(&times, &v, interpolation))
            }
            ReadOutputs::MorphTargetWeights(it) => {
                let raw: Vec<f32> = it.into_f32().collect();
                count_matches(raw.len(), out_count, &out_here)?;
                if raw.iter().any(|w| !w.is_finite()) {
                    return Err(ptr(&out_here, GltfErrorKind::NonFinite("morph weight".into())));
                }
                let groups: Vec<Vec<f32>> = raw.chunks(targets).map(<[f32]>::to_vec).collect();
                let track = make_track(&times, &groups, interpolation);
                ChannelTarget::Weights(WeightsTrack { targets, keys: track.keys.to_vec() })
            }
        };
        channels.push(ModelChannel { node, target });
    }
    Ok(ModelAnimation {
        name: anim.name().map_or_else(|| format!("animation{}", anim.index()), str::to_owned),
        channels,
        pointers: Vec::new(),
    })
}

/// Builds keys from times and sampler outputs; CUBICSPLINE outputs come as
/// (in-tangent a_k, value v_k, out-tangent b_k) per key and keep their per-second tangents.
pub(crate) fn make_track<T: Clone>(times: &[f32], values: &[T], interpolation: Interpolation) -> RawTrack<T> {
    let keys = times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            if interpolation == Interpolation::Hermite {
                let mut key =
                    Key::new(f64::from(t), values[3 * k + 1].clone()).with_interpolation(interpolation);
                key.in_tangent = Some(values[3 * k].clone());
                key.out_tangent = Some(values[3 * k + 2].clone());
                key
            } else {
                Key::new(f64::from(t), values[k].clone()).with_interpolation(interpolation)
            }
        })
        .collect();
    RawTrack::new(keys)
}

/// Normalization of quaternions read from a file.
trait TryNormalizeQuat: Sized {
    fn try_normalize_quat(self) -> Option<Self>;
}

impl TryNormalizeQuat for Quat {
    fn try_normalize_quat(self) -> Option<Quat> {
        glam::Vec4::from(self).try_normalize().map(Quat::from_vec4)
    }
}

/// keyrig's sampler for a glTF sampler; filters the file leaves out are linear, with linear
/// mipmaps for minification (glTF leaves them to the implementation).
fn sampler_of(sampler: &gltf::texture::Sampler<'_>) -> keyrig_core::Sampler {
    use gltf::texture::{MagFilter, MinFilter, WrappingMode};
    use keyrig_core::{FilterMode, WrapMode};
    let wrap = |mode| match mode {
        WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
        WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        WrappingMode::Repeat => WrapMode::Repeat,
    };
    let mag_filter = match sampler.mag_filter() {
        Some(MagFilter::Nearest) => FilterMode::Nearest,
        Some(MagFilter::Linear) | None => FilterMode::Linear,
    };
    let (min_filter, mipmap_filter) = match sampler.min_filter() {
        Some(MinFilter::Nearest) => (FilterMode::Nearest, None),
        Some(MinFilter::Linear) => (FilterMode::Linear, None),
        Some(MinFilter::NearestMipmapNearest) => (FilterMode::Nearest, Some(FilterMode::Nearest)),
        Some(MinFilter::LinearMipmapNearest) => (FilterMode::Linear, Some(FilterMode::Nearest)),
        Some(MinFilter::NearestMipmapLinear) => (FilterMode::Nearest, Some(FilterMode::Linear)),
        Some(MinFilter::LinearMipmapLinear) | None => (FilterMode::Linear, Some(FilterMode::Linear)),
    };
    keyrig_core::Sampler {
        wrap_u: wrap(sampler.wrap_s()),
        wrap_v: wrap(sampler.wrap_t()),
        mag_filter,
        min_filter,
        mipmap_filter,
    }
}
