//! VRML97 (`.wrl`, gzipped `.wrz`), X3D (XML `.x3d`, classic `.x3dv`) and Open Inventor 2.1
//! ASCII (`.iv`) import, with their animation.
//!
//! One path serves the four encodings: the classic ones share a tokenizer and parser
//! ([`classic`]), X3D's XML maps onto the same node tree ([`xml`]); PROTOs and Inlines are
//! expanded once ([`expand`]); the mapping ([`map`]) turns the tree into a [`VrmlModel`] —
//! meshes, lights, views and tracks — and that into a keyrig [`keyrig_core::Scene`] whose
//! objects refer back to the file (`MeshSource::File { path, mesh }`), as glTF and MD2 models
//! do. `docs/interchange.md` says what maps to what.
//!
//! The file is untrusted: it must be a regular file of at most [`MAX_VRML_BYTES`] (after
//! gunzip, too), valid UTF-8, with a known header; nesting, node counts, PROTO depth, Inline
//! depth and the instances a DEF/USE graph expands to are bounded; every error names the
//! file, the line and column (and byte) and what is wrong.

pub mod classic;
pub mod expand;
pub mod export;
pub mod geometry;
mod inventor;
mod lex;
pub mod map;
pub mod splines;
pub mod tree;
pub mod xml;

use std::collections::HashMap;
use std::fmt;
use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

pub use map::{Skipped, VrmlModel};
use tree::{Document, Encoding, FileId, NodeId, Place, SourceFile};

/// Largest VRML/X3D/Inventor file keyrig reads, before and after gunzip: 1 GiB.
pub const MAX_VRML_BYTES: u64 = crate::file_io::MAX_MODEL_BYTES;
/// Deepest chain of Inlines and EXTERNPROTO files.
pub const MAX_INLINE_DEPTH: usize = 16;

/// What is wrong.
#[derive(Debug, thiserror::Error)]
pub enum VrmlErrorKind {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    #[error("gzip: {0}")]
    Gzip(String),
    #[error("not UTF-8 text: {0}")]
    NotUtf8(String),
    #[error("{0}")]
    Header(String),
    #[error("{0}")]
    Syntax(String),
    #[error("{0}")]
    Limit(String),
    #[error("{0}")]
    Invalid(String),
    #[error("{0}")]
    Unsupported(String),
}

/// Where an error is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorPlace {
    /// The file as a whole.
    File,
    /// 1-based line and column (characters), and the byte offset when known.
    Text { line: usize, column: usize, byte: Option<usize> },
}

/// A VRML/X3D/Inventor import error: the file, where in it, and what.
#[derive(Debug, thiserror::Error)]
pub struct VrmlError {
    pub file: Option<PathBuf>,
    pub place: ErrorPlace,
    pub kind: VrmlErrorKind,
}

impl fmt::Display for VrmlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}: ", file.display())?;
        }
        match self.place {
            ErrorPlace::File => {}
            ErrorPlace::Text { line, column, byte: Some(b) } => {
                write!(f, "line {line}, column {column} (byte {b}): ")?
            }
            ErrorPlace::Text { line, column, byte: None } => write!(f, "line {line}, column {column}: ")?,
        }
        write!(f, "{}", self.kind)
    }
}

impl VrmlError {
    fn whole(file: Option<&Path>, kind: VrmlErrorKind) -> Self {
        VrmlError { file: file.map(Path::to_path_buf), place: ErrorPlace::File, kind }
    }

    /// An error at byte `at` of a source file.
    pub(crate) fn at(source: &SourceFile, at: usize, kind: VrmlErrorKind) -> Self {
        let (line, column) = lex::line_column(&source.text, at);
        VrmlError {
            file: Some(source.path.clone()),
            place: ErrorPlace::Text { line, column, byte: Some(at) },
            kind,
        }
    }

    pub(crate) fn at_place(doc: &Document, place: Place, kind: VrmlErrorKind) -> Self {
        match doc.files.get(place.file.0 as usize) {
            Some(source) => VrmlError::at(source, place.at, kind),
            None => VrmlError::whole(None, kind),
        }
    }
}

/// Whether `path` names a file this module reads (by extension, case-insensitive):
/// `.wrl`, `.wrz`, `.x3d`, `.x3dv`, `.x3dz`, `.x3dvz`, `.iv`.
#[must_use]
pub fn is_vrml_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv", "vrml"].iter().any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// The encoding a text's first line announces.
fn detect(text: &str) -> Result<Encoding, String> {
    let start = text.trim_start_matches('\u{feff}');
    let first = start.lines().next().unwrap_or("").trim_end();
    if first.starts_with("#VRML V2.0") {
        Ok(Encoding::Vrml97)
    } else if first.starts_with("#X3D V") {
        Ok(Encoding::X3dClassic)
    } else if first.starts_with("#Inventor V2.")
        || first.starts_with("#Inventor V1.0")
        || first.starts_with("#VRML V1.0")
    {
        if first.contains("binary") {
            Err(format!(
                "`{}`: binary Open Inventor files are not supported; keyrig reads the ASCII encoding",
                lex::clip(first)
            ))
        } else {
            Ok(Encoding::Inventor)
        }
    } else if start.trim_start().starts_with('<') {
        Ok(Encoding::X3dXml)
    } else {
        Err(format!(
            "the first line `{}` is not a VRML97 (`#VRML V2.0 utf8`), X3D (`#X3D V3.3 utf8` or XML) or Open Inventor (`#Inventor V2.1 ascii`) header",
            lex::clip(&first.chars().take(60).collect::<String>())
        ))
    }
}

/// The bytes of a file as text: gunzipped when it starts with gzip's magic (a `.wrz`, `.x3dz`
/// or gzipped `.wrl`), at most [`MAX_VRML_BYTES`] either way, and valid UTF-8.
fn decode(bytes: Vec<u8>, file: Option<&Path>) -> Result<String, VrmlError> {
    let bytes = if bytes.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(bytes.as_slice())
            .take(MAX_VRML_BYTES + 1)
            .read_to_end(&mut out)
            .map_err(|e| VrmlError::whole(file, VrmlErrorKind::Gzip(e.to_string())))?;
        if out.len() as u64 > MAX_VRML_BYTES {
            return Err(VrmlError::whole(
                file,
                VrmlErrorKind::Limit(format!("the gzipped file unpacks to more than {MAX_VRML_BYTES} bytes")),
            ));
        }
        out
    } else {
        bytes
    };
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let text = String::from_utf8_lossy(&e.as_bytes()[..at]);
        let (line, column) = lex::line_column(&text, at);
        VrmlError {
            file: file.map(Path::to_path_buf),
            place: ErrorPlace::Text { line, column, byte: Some(at) },
            kind: VrmlErrorKind::NotUtf8(format!(
                "byte 0x{:02x} does not begin a UTF-8 character",
                e.as_bytes()[at]
            )),
        }
    })
}

/// Reads and maps the file at `path` (any of the encodings, gzipped or not), following local
/// Inlines and EXTERNPROTOs within its folder.
///
/// # Errors
/// The file cannot be read, or is not valid ([`VrmlError`] with the place).
pub fn import_vrml_file(path: &Path) -> Result<VrmlModel, VrmlError> {
    let bytes = crate::file_io::read_regular_file(path, MAX_VRML_BYTES)
        .map_err(|e| VrmlError::whole(Some(path), VrmlErrorKind::Io(e)))?;
    let text = decode(bytes, Some(path))?;
    let folder = path.parent().map(Path::to_path_buf);
    import_text(text, path.to_path_buf(), folder)
}

/// Imports a file held in memory (named `name` in messages). Inlines and EXTERNPROTOs are not
/// followed (there is no folder) and are listed as not imported.
///
/// # Errors
/// As [`import_vrml_file`].
pub fn import_vrml_slice(bytes: &[u8], name: &str) -> Result<VrmlModel, VrmlError> {
    let text = decode(bytes.to_vec(), Some(Path::new(name)))?;
    import_text(text, PathBuf::from(name), None)
}

/// Parses `text` as file `path` into the next file slot of `doc`.
fn parse_into(doc: &mut Document, text: String, path: PathBuf) -> Result<(FileId, tree::Parsed), VrmlError> {
    let encoding = detect(&text).map_err(|m| VrmlError {
        file: Some(path.clone()),
        place: ErrorPlace::Text { line: 1, column: 1, byte: Some(0) },
        kind: VrmlErrorKind::Header(m),
    })?;
    let file = FileId(doc.files.len() as u32);
    let text: Arc<str> = Arc::from(text);
    doc.files.push(SourceFile { path: path.clone(), text: Arc::clone(&text), encoding });
    let source = doc.files[file.0 as usize].clone();
    let parse_error = |e: classic::ParseError| {
        let kind = if e.limit { VrmlErrorKind::Limit(e.message) } else { VrmlErrorKind::Syntax(e.message) };
        VrmlError::at(&source, e.at, kind)
    };
    match encoding {
        Encoding::X3dXml => {
            xml::parse_x3d_xml(&text, doc, file).map(|parsed| (file, parsed)).map_err(|e| match e {
                xml::XmlError::Syntax { line, column, message } => VrmlError {
                    file: Some(path.clone()),
                    place: ErrorPlace::Text { line: line as usize, column: column as usize, byte: None },
                    kind: VrmlErrorKind::Syntax(format!("XML: {message}")),
                },
                xml::XmlError::X3d(e) => parse_error(e),
            })
        }
        _ => {
            // The header line is a comment to the tokenizer.
            let parser = classic::Parser::new(&text, encoding, doc, file);
            parser.parse_file().map(|parsed| (file, parsed)).map_err(parse_error)
        }
    }
}

/// A URL of an Inline or EXTERNPROTO as a file inside `folder`: relative, without `..`, no
/// scheme; `None` (with the reason) otherwise.
fn local_file(folder: &Path, url: &str) -> Result<PathBuf, String> {
    let url = url.split('#').next().unwrap_or("");
    if url.is_empty() {
        return Err("an empty URL".into());
    }
    if url.contains("://")
        || url.starts_with("urn:")
        || url.starts_with("data:")
        || url.starts_with("javascript:")
    {
        return Err(format!("`{}` is not a file in the model's folder", lex::clip(url)));
    }
    let rel = Path::new(url);
    if rel.is_absolute() || rel.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir)) {
        // `..` may still stay inside the folder the model was opened from: the corpus'
        // Sourcebook figures Inline `../Chapter13/…`. Allowed when it resolves below the
        // folder's parent chain root the import started from (checked by the caller).
        if rel.is_absolute() {
            return Err(format!("`{}` is an absolute path", lex::clip(url)));
        }
    }
    Ok(folder.join(rel))
}

struct Loader {
    /// The folder of the file imported first: Inlines must stay inside it or its parent (the
    /// Sourcebook's figures Inline `../Chapter13/…` from their chapter folder).
    root: Option<PathBuf>,
    skipped: Vec<(String, String, Place)>,
}

impl Loader {
    /// Reads the first readable local file among `urls` (relative to the file `from`).
    fn read(
        &mut self,
        doc: &Document,
        from: FileId,
        urls: &[String],
        what: &str,
        place: Place,
    ) -> Option<(PathBuf, String)> {
        let Some(root) = &self.root else {
            self.skipped.push((
                what.to_owned(),
                format!("{} (read from memory: no folder to look in)", urls.join(" ")),
                place,
            ));
            return None;
        };
        let folder = doc.files[from.0 as usize].path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut reasons = Vec::new();
        for url in urls {
            let path = match local_file(&folder, url) {
                Ok(p) => p,
                Err(reason) => {
                    reasons.push(reason);
                    continue;
                }
            };
            let canonical = match std::fs::canonicalize(&path) {
                Ok(c) => c,
                Err(e) => {
                    reasons.push(format!("`{}`: {e}", lex::clip(url)));
                    continue;
                }
            };
            let allowed = root.parent().map_or(root.as_path(), |p| p);
            if !canonical.starts_with(allowed) {
                reasons.push(format!("`{}` lies outside the model's folder", lex::clip(url)));
                continue;
            }
            match crate::file_io::read_regular_file(&canonical, MAX_VRML_BYTES)
                .map_err(|e| e.to_string())
                .and_then(|b| decode(b, Some(&canonical)).map_err(|e| e.to_string()))
            {
                Ok(text) => return Some((canonical, text)),
                Err(e) => reasons.push(format!("`{}`: {e}", lex::clip(url))),
            }
        }
        self.skipped.push((what.to_owned(), reasons.join("; "), place));
        None
    }
}

/// Stack of the thread that parses and maps a file: the readers recurse once per level of
/// nesting (bounded by [`classic::MAX_DEPTH`] and the Inline and PROTO depths), which a
/// default 2 MiB thread stack cannot hold in every build. Only what is touched is used.
const IMPORT_STACK_BYTES: usize = 512 << 20;

fn import_text(text: String, path: PathBuf, folder: Option<PathBuf>) -> Result<VrmlModel, VrmlError> {
    let name = path.clone();
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("keyrig-vrml-import".into())
            .stack_size(IMPORT_STACK_BYTES)
            .spawn_scoped(scope, move || import_text_here(text, path, folder))
            .map_err(|e| VrmlError::whole(Some(&name), VrmlErrorKind::Io(e)))?
            .join()
            .unwrap_or_else(|_| {
                Err(VrmlError::whole(
                    Some(&name),
                    VrmlErrorKind::Invalid("the import stopped unexpectedly".into()),
                ))
            })
    })
}

fn import_text_here(text: String, path: PathBuf, folder: Option<PathBuf>) -> Result<VrmlModel, VrmlError> {
    let mut doc = Document::default();
    let (_, (roots, routes, _)) = parse_into(&mut doc, text, path.clone())?;
    doc.roots = roots;
    doc.routes.extend(routes);
    let root = folder.map(|f| std::fs::canonicalize(&f).unwrap_or(f));
    let mut loader = Loader { root, skipped: Vec::new() };
    // Inlines: each is parsed into the document and stands for a group of its nodes. New
    // Inlines in inlined files are found as the loop reaches them; the chain is bounded.
    let mut chain: HashMap<FileId, (usize, Vec<PathBuf>)> = HashMap::new();
    chain.insert(FileId(0), (0, vec![path.clone()]));
    let mut extern_files: HashMap<PathBuf, (FileId, HashMap<String, usize>)> = HashMap::new();
    let mut interface = expand::Interface::new();
    loop {
        let before = doc.nodes.len();
        let new_interface = expand::expand_protos(&mut doc, &mut |doc, proto| {
            resolve_extern(doc, proto, &mut loader, &mut extern_files, &chain)
        })
        .map_err(|e| VrmlError::at_place(&doc, e.place, VrmlErrorKind::Limit(e.message)))?;
        interface.extend(new_interface);
        let mut inlined = false;
        for i in 0..doc.nodes.len() {
            let node = &doc.nodes[i];
            if node.kind != "Inline" || node.template || node.expanded.is_some() {
                continue;
            }
            let place = node.place;
            let urls = match node.value("url") {
                Some(tree::Value::Strings(s)) => s.clone(),
                _ => Vec::new(),
            };
            let (depth, mut paths) = chain.get(&place.file).cloned().unwrap_or((0, Vec::new()));
            // Mark it done whatever happens next.
            let group = push_group(&mut doc, place, Vec::new())?;
            doc.nodes[i].expanded = Some(group);
            if depth + 1 > MAX_INLINE_DEPTH {
                return Err(VrmlError::at_place(
                    &doc,
                    place,
                    VrmlErrorKind::Limit(format!("Inlines are nested more than {MAX_INLINE_DEPTH} deep")),
                ));
            }
            let Some((file_path, text)) = loader.read(&doc, place.file, &urls, "Inline", place) else {
                continue;
            };
            if paths.contains(&file_path) {
                return Err(VrmlError::at_place(
                    &doc,
                    place,
                    VrmlErrorKind::Invalid(format!("Inline of {} includes itself", file_path.display())),
                ));
            }
            paths.push(file_path.clone());
            let (file, (roots, routes, _)) = parse_into(&mut doc, text, file_path)?;
            chain.insert(file, (depth + 1, paths));
            doc.routes.extend(routes);
            if let tree::Value::Nodes(children) = &mut doc.nodes[group.0 as usize].fields[0].value {
                children.extend(roots);
            }
            inlined = true;
        }
        if !inlined && doc.nodes.len() == before {
            break;
        }
        if !inlined {
            break;
        }
    }
    let _ = interface;
    let mut traversal = map::Traversal::new(&doc);
    if doc.files.first().is_some_and(|f| f.encoding == Encoding::Inventor) {
        inventor::traverse(&mut traversal)?;
    } else {
        traversal.visit_roots()?;
    }
    let mut model = map::map_document(&doc, traversal, loader.skipped, &path)?;
    // A file keyrig wrote carries keyrig's own scene: its keys come back exactly.
    export::restore_metadata(&doc, &mut model);
    Ok(model)
}

/// A `Group` holding `children` (what an Inline stands for).
fn push_group(doc: &mut Document, place: Place, children: Vec<NodeId>) -> Result<NodeId, VrmlError> {
    if doc.nodes.len() >= classic::MAX_NODES {
        return Err(VrmlError::at_place(
            doc,
            place,
            VrmlErrorKind::Limit(format!("more than {} nodes", classic::MAX_NODES)),
        ));
    }
    let id = NodeId(doc.nodes.len() as u32);
    doc.nodes.push(tree::Node {
        kind: "Group".into(),
        def: None,
        fields: vec![tree::Field { name: "children".into(), value: tree::Value::Nodes(children), place }],
        children: Vec::new(),
        place,
        proto: None,
        expanded: None,
        template: false,
        depth: 0,
    });
    Ok(id)
}

/// Loads an EXTERNPROTO's definition: the first local file of its URLs, the PROTO named by the
/// URL's `#fragment` or, without one, the PROTO of the same name (else the file's first).
fn resolve_extern(
    doc: &mut Document,
    proto: usize,
    loader: &mut Loader,
    files: &mut HashMap<PathBuf, (FileId, HashMap<String, usize>)>,
    chain: &HashMap<FileId, (usize, Vec<PathBuf>)>,
) -> Result<(), expand::ExpandError> {
    let p = doc.protos[proto].clone();
    let urls = p.extern_urls.clone().unwrap_or_default();
    let fail = |message: String| expand::ExpandError { place: p.place, message };
    if chain.get(&p.place.file).is_some_and(|(d, _)| *d + 1 > MAX_INLINE_DEPTH) {
        return Err(fail(format!(
            "EXTERNPROTO {}: files are nested more than {MAX_INLINE_DEPTH} deep",
            p.name
        )));
    }
    let wanted = urls
        .iter()
        .find_map(|u| u.split_once('#').map(|(_, f)| f.to_owned()))
        .unwrap_or_else(|| p.name.clone());
    let Some((path, text)) =
        loader.read(doc, p.place.file, &urls, &format!("EXTERNPROTO {}", p.name), p.place)
    else {
        // Not loaded: its instances stand for nothing (the loader lists why).
        doc.protos[proto].extern_urls = None;
        return Ok(());
    };
    let (_, protos) = match files.get(&path) {
        Some(entry) => entry.clone(),
        None => {
            let (file, (_roots, _routes, protos)) = parse_into(doc, text, path.clone())
                .map_err(|e| fail(format!("EXTERNPROTO {}: {e}", p.name)))?;
            files.insert(path.clone(), (file, protos.clone()));
            (file, protos)
        }
    };
    let Some(&found) = protos.get(&wanted) else {
        return Err(fail(format!("EXTERNPROTO {}: {} has no PROTO {wanted}", p.name, path.display())));
    };
    if found == proto {
        return Err(fail(format!("EXTERNPROTO {} refers to itself", p.name)));
    }
    let def = doc.protos[found].clone();
    let target = &mut doc.protos[proto];
    target.body = def.body;
    target.routes = def.routes;
    // The declaration's fields take the definition's defaults.
    for f in &mut target.fields {
        if let Some(d) = def.fields.iter().find(|d| d.name == f.name) {
            f.default.clone_from(&d.default);
        }
    }
    Ok(())
}
