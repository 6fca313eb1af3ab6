//! X3D's XML encoding (ISO/IEC 19776-1) read with `roxmltree` into the same node tree as the
//! classic encodings: an element is a node, its attributes are fields (their text read by the
//! classic tokenizer: numbers, `"quoted"` strings, `true`/`false`), a child element goes into
//! the parent's field named by its `containerField` attribute or, without one, the node
//! type's default (`geometry` for geometry nodes, `appearance`, `material`, `coord`, …,
//! `children` otherwise). `<ROUTE>`, `<ProtoDeclare>`, `<ExternProtoDeclare>`,
//! `<ProtoInstance>` with `<fieldValue>`, and `<IS><connect>` map to their classic
//! counterparts.

use std::collections::HashMap;

use super::classic::{ParseError, MAX_DEPTH, MAX_NODES};
use super::lex::{clip, Lexer, Tok};
use super::tree::{Document, Field, FileId, Node, NodeId, Parsed, Place, Proto, ProtoField, Route, Value};

/// A parse error of the XML encoding: where (line and column, or a byte offset) and what.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum XmlError {
    /// The XML itself is malformed (roxmltree's line and column).
    Syntax { line: u32, column: u32, message: String },
    /// The X3D in well-formed XML is wrong.
    X3d(ParseError),
}

type Result<T> = std::result::Result<T, ParseError>;

fn err<T>(at: usize, message: impl Into<String>) -> Result<T> {
    Err(ParseError { at, message: message.into(), limit: false })
}

/// The field a node goes into when its element has no `containerField` (X3D's defaults).
#[must_use]
pub fn default_container(kind: &str) -> &'static str {
    match kind {
        "Box"
        | "Sphere"
        | "Cone"
        | "Cylinder"
        | "IndexedFaceSet"
        | "IndexedTriangleSet"
        | "TriangleSet"
        | "IndexedTriangleFanSet"
        | "IndexedTriangleStripSet"
        | "TriangleFanSet"
        | "TriangleStripSet"
        | "IndexedQuadSet"
        | "QuadSet"
        | "ElevationGrid"
        | "Extrusion"
        | "IndexedLineSet"
        | "LineSet"
        | "PointSet"
        | "Text"
        | "Arc2D"
        | "ArcClose2D"
        | "Circle2D"
        | "Disk2D"
        | "Polyline2D"
        | "Polypoint2D"
        | "Rectangle2D"
        | "TriangleSet2D"
        | "GeoElevationGrid"
        | "NurbsPatchSurface"
        | "NurbsCurve" => "geometry",
        "Appearance" => "appearance",
        "Material" | "TwoSidedMaterial" | "PhysicalMaterial" | "UnlitMaterial" => "material",
        "ImageTexture" | "PixelTexture" | "MovieTexture" | "MultiTexture" => "texture",
        "TextureTransform" => "textureTransform",
        "Coordinate" | "CoordinateDouble" | "GeoCoordinate" => "coord",
        "Normal" => "normal",
        "Color" | "ColorRGBA" => "color",
        "TextureCoordinate" | "TextureCoordinateGenerator" | "MultiTextureCoordinate" => "texCoord",
        "FontStyle" | "ScreenFontStyle" => "fontStyle",
        "FillProperties" => "fillProperties",
        "LineProperties" => "lineProperties",
        "AudioClip" => "source",
        "MetadataBoolean" | "MetadataDouble" | "MetadataFloat" | "MetadataInteger" | "MetadataSet"
        | "MetadataString" => "metadata",
        _ => "children",
    }
}

/// The value of an attribute's text.
#[must_use]
pub fn attribute_value(text: &str) -> Value {
    let trimmed = text.trim();
    if trimmed.is_empty() {
        return Value::Empty;
    }
    let mut lexer = Lexer::new(trimmed, false);
    let mut numbers = Vec::new();
    let mut strings = Vec::new();
    let mut bools = Vec::new();
    let mut other = false;
    loop {
        match lexer.next() {
            Ok(t) => match t.tok {
                Tok::Eof => break,
                Tok::Number(v) => numbers.push(v),
                Tok::Str(s) => strings.push(s),
                Tok::Ident("true" | "TRUE") => bools.push(true),
                Tok::Ident("false" | "FALSE") => bools.push(false),
                _ => {
                    other = true;
                    break;
                }
            },
            Err(_) => {
                other = true;
                break;
            }
        }
    }
    match (other, numbers.is_empty(), strings.is_empty(), bools.is_empty()) {
        (false, false, true, true) => Value::Numbers(numbers),
        (false, true, false, true) => Value::Strings(strings),
        (false, true, true, false) => Value::Bools(bools),
        // An SFString written bare (`description="A view"`).
        _ => Value::Strings(vec![text.to_owned()]),
    }
}

/// A ROUTE by DEF names: from node, from field, to node, to field, byte offset.
type NamedRoute = (String, String, String, String, usize);

const NOT_FIELDS: [&str; 6] = ["DEF", "USE", "containerField", "class", "id", "style"];

struct Reader<'d> {
    doc: &'d mut Document,
    file: FileId,
    /// DEF names per scope (the file, each ProtoBody).
    defs: Vec<HashMap<String, NodeId>>,
    protos: Vec<HashMap<String, usize>>,
    /// Per scope: (from node, from field, to node, to field, byte) by name, resolved at the
    /// scope's end.
    routes: Vec<Vec<NamedRoute>>,
    template: usize,
}

/// Parses X3D XML `text` (file `file` of `doc`): returns the scene's top-level nodes, its routes
/// and its PROTOs by name.
///
/// # Errors
/// Malformed XML or X3D.
pub fn parse_x3d_xml(text: &str, doc: &mut Document, file: FileId) -> std::result::Result<Parsed, XmlError> {
    let options = roxmltree::ParsingOptions { allow_dtd: true, ..roxmltree::ParsingOptions::default() };
    let xml = roxmltree::Document::parse_with_options(text, options).map_err(|e| {
        let pos = e.pos();
        XmlError::Syntax { line: pos.row, column: pos.col, message: e.to_string() }
    })?;
    let root = xml.root_element();
    if root.tag_name().name() != "X3D" {
        return Err(XmlError::X3d(ParseError {
            at: root.range().start,
            message: format!("the root element is <{}>, not <X3D>", clip(root.tag_name().name())),
            limit: false,
        }));
    }
    let mut reader = Reader {
        doc,
        file,
        defs: vec![HashMap::new()],
        protos: vec![HashMap::new()],
        routes: vec![Vec::new()],
        template: 0,
    };
    let mut roots = Vec::new();
    for child in root.children().filter(roxmltree::Node::is_element) {
        match child.tag_name().name() {
            "head" => {
                for meta in child.children().filter(|c| c.has_tag_name("meta")) {
                    if let (Some(n), Some(c)) = (meta.attribute("name"), meta.attribute("content")) {
                        reader.doc.meta.push((n.to_owned(), c.to_owned()));
                    }
                }
            }
            "Scene" => {
                for item in child.children().filter(roxmltree::Node::is_element) {
                    if let Some((_, id)) = reader.statement(item, 1).map_err(XmlError::X3d)? {
                        roots.push(id);
                    }
                }
            }
            _ => {}
        }
    }
    let routes = reader.resolve_routes().map_err(XmlError::X3d)?;
    let protos = reader.protos.pop().unwrap_or_default();
    Ok((roots, routes, protos))
}

impl Reader<'_> {
    fn place(&self, at: usize) -> Place {
        Place { file: self.file, at }
    }

    fn resolve_routes(&mut self) -> Result<Vec<Route>> {
        let routes = self.routes.pop().unwrap_or_default();
        let defs = self.defs.last().cloned().unwrap_or_default();
        routes
            .into_iter()
            .map(|(from, from_field, to, to_field, at)| {
                let find = |name: &str| match defs.get(name) {
                    Some(&id) => Ok(id),
                    None => err(at, format!("ROUTE: no node named `{}`", clip(name))),
                };
                Ok(Route { from: find(&from)?, from_field, to: find(&to)?, to_field, place: self.place(at) })
            })
            .collect()
    }

    /// An element in a list of nodes: a node (returned with its container field), a ROUTE or
    /// a PROTO declaration.
    fn statement(&mut self, e: roxmltree::Node<'_, '_>, depth: usize) -> Result<Option<(String, NodeId)>> {
        let at = e.range().start;
        if depth > MAX_DEPTH {
            return Err(ParseError {
                at,
                message: format!("nodes are nested more than {MAX_DEPTH} levels deep"),
                limit: true,
            });
        }
        match e.tag_name().name() {
            "ROUTE" => {
                let get = |a: &str| {
                    e.attribute(a).map(str::to_owned).ok_or_else(|| ParseError {
                        at,
                        message: format!("<ROUTE> has no {a} attribute"),
                        limit: false,
                    })
                };
                let route = (get("fromNode")?, get("fromField")?, get("toNode")?, get("toField")?, at);
                if let Some(r) = self.routes.last_mut() {
                    r.push(route);
                }
                Ok(None)
            }
            "ProtoDeclare" | "ExternProtoDeclare" => {
                self.proto(e, depth)?;
                Ok(None)
            }
            "IS" | "field" | "fieldValue" | "ProtoInterface" | "ProtoBody" | "connect" | "IMPORT"
            | "EXPORT" | "meta" | "component" | "unit" => Ok(None),
            _ => self.node(e, depth).map(Some),
        }
    }

    fn node(&mut self, e: roxmltree::Node<'_, '_>, depth: usize) -> Result<(String, NodeId)> {
        let at = e.range().start;
        let tag = e.tag_name().name();
        let kind = if tag == "ProtoInstance" {
            e.attribute("name").ok_or_else(|| ParseError {
                at,
                message: "<ProtoInstance> has no name".into(),
                limit: false,
            })?
        } else {
            tag
        };
        let container = e.attribute("containerField").unwrap_or_else(|| default_container(kind)).to_owned();
        if let Some(name) = e.attribute("USE") {
            return match self.defs.last().and_then(|d| d.get(name)) {
                Some(&id) => Ok((container, id)),
                None => err(
                    at,
                    format!(
                        "USE {}: no node named so is defined before this point (a node cannot USE itself)",
                        clip(name)
                    ),
                ),
            };
        }
        if self.doc.nodes.len() >= MAX_NODES {
            return Err(ParseError { at, message: format!("more than {MAX_NODES} nodes"), limit: true });
        }
        let id = NodeId(self.doc.nodes.len() as u32);
        let proto = self.protos.iter().rev().find_map(|p| p.get(kind).copied());
        self.doc.nodes.push(Node {
            kind: kind.to_owned(),
            def: e.attribute("DEF").map(str::to_owned),
            fields: Vec::new(),
            children: Vec::new(),
            place: self.place(at),
            proto,
            expanded: None,
            template: self.template > 0,
            depth: 0,
        });
        let mut fields: Vec<Field> = Vec::new();
        if tag != "ProtoInstance" {
            for a in e.attributes() {
                if NOT_FIELDS.contains(&a.name()) {
                    continue;
                }
                fields.push(Field {
                    name: a.name().to_owned(),
                    value: attribute_value(a.value()),
                    place: self.place(a.range().start),
                });
            }
        }
        let mut lists: Vec<(String, Vec<NodeId>, usize)> = Vec::new();
        for child in e.children().filter(roxmltree::Node::is_element) {
            match child.tag_name().name() {
                "IS" => {
                    for c in child.children().filter(|c| c.has_tag_name("connect")) {
                        if let (Some(nf), Some(pf)) = (c.attribute("nodeField"), c.attribute("protoField")) {
                            fields.retain(|f| f.name != nf);
                            fields.push(Field {
                                name: nf.to_owned(),
                                value: Value::Is(pf.to_owned()),
                                place: self.place(c.range().start),
                            });
                        }
                    }
                }
                "fieldValue" => {
                    let name = child.attribute("name").unwrap_or_default().to_owned();
                    let cat = child.range().start;
                    let value = match child.attribute("value") {
                        Some(v) => attribute_value(v),
                        None => {
                            let mut nodes = Vec::new();
                            for n in child.children().filter(roxmltree::Node::is_element) {
                                if let Some((_, id)) = self.statement(n, depth + 1)? {
                                    nodes.push(id);
                                }
                            }
                            Value::Nodes(nodes)
                        }
                    };
                    fields.push(Field { name, value, place: self.place(cat) });
                }
                "field" => {} // A Script's interface: Scripts are not run.
                _ => {
                    if let Some((container, id)) = self.statement(child, depth + 1)? {
                        match lists.iter_mut().find(|(n, _, _)| *n == container) {
                            Some((_, ids, _)) => ids.push(id),
                            None => lists.push((container, vec![id], child.range().start)),
                        }
                    }
                }
            }
        }
        for (name, ids, at) in lists {
            fields.push(Field { name, value: Value::Nodes(ids), place: self.place(at) });
        }
        let node = &mut self.doc.nodes[id.0 as usize];
        node.fields = fields;
        if let (Some(def), Some(scope)) = (e.attribute("DEF"), self.defs.last_mut()) {
            scope.insert(def.to_owned(), id);
        }
        Ok((container, id))
    }

    fn proto(&mut self, e: roxmltree::Node<'_, '_>, depth: usize) -> Result<()> {
        let at = e.range().start;
        let name = e
            .attribute("name")
            .ok_or_else(|| ParseError {
                at,
                message: format!("<{}> has no name", e.tag_name().name()),
                limit: false,
            })?
            .to_owned();
        let external = e.tag_name().name() == "ExternProtoDeclare";
        let interface: Vec<roxmltree::Node<'_, '_>> = if external {
            e.children().filter(|c| c.has_tag_name("field")).collect()
        } else {
            e.children()
                .filter(|c| c.has_tag_name("ProtoInterface"))
                .flat_map(|i| i.children().filter(|c| c.has_tag_name("field")))
                .collect()
        };
        let mut fields = Vec::new();
        for f in interface {
            let fname = f.attribute("name").unwrap_or_default().to_owned();
            let default = match f.attribute("value") {
                Some(v) => Some(attribute_value(v)),
                None => {
                    let mut nodes = Vec::new();
                    for n in f.children().filter(roxmltree::Node::is_element) {
                        if let Some((_, id)) = self.statement(n, depth + 1)? {
                            nodes.push(id);
                        }
                    }
                    (!external).then_some(Value::Nodes(nodes))
                }
            };
            fields.push(ProtoField {
                access: f.attribute("accessType").unwrap_or("initializeOnly").to_owned(),
                kind: f.attribute("type").unwrap_or_default().to_owned(),
                name: fname,
                default,
            });
        }
        let index = self.doc.protos.len();
        if external {
            let urls = match e.attribute("url").map(attribute_value) {
                Some(Value::Strings(s)) => s,
                _ => Vec::new(),
            };
            self.doc.protos.push(Proto {
                name: name.clone(),
                fields,
                body: Vec::new(),
                routes: Vec::new(),
                extern_urls: Some(urls),
                place: self.place(at),
            });
        } else {
            self.defs.push(HashMap::new());
            self.protos.push(HashMap::new());
            self.routes.push(Vec::new());
            self.template += 1;
            let mut body = Vec::new();
            for b in e.children().filter(|c| c.has_tag_name("ProtoBody")) {
                for n in b.children().filter(roxmltree::Node::is_element) {
                    if let Some((_, id)) = self.statement(n, depth + 1)? {
                        body.push(id);
                    }
                }
            }
            self.template -= 1;
            let routes = self.resolve_routes()?;
            self.defs.pop();
            self.protos.pop();
            self.doc.protos.push(Proto {
                name: name.clone(),
                fields,
                body,
                routes,
                extern_urls: None,
                place: self.place(at),
            });
        }
        if let Some(p) = self.protos.last_mut() {
            p.insert(name, index);
        }
        Ok(())
    }
}
