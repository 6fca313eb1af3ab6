//! PROTO instances and Inlines replaced by what they stand for (ISO/IEC 14772-1 §4.8, §6.25).
//!
//! A PROTO instance becomes a copy of the PROTO's body: every body node reachable from the
//! body is copied once per instance (so `DEF`/`USE` sharing inside the body is kept), a field
//! written `f IS x` takes the instance's value of `x` (or the PROTO's default), and the body's
//! ROUTEs are copied between the copies. The instance then *is* the copy of the first body
//! node ([`super::tree::Node::expanded`]); the other body nodes (sensors, interpolators) live
//! on, reached through the routes. Routes to or from an instance's interface field are moved
//! onto the body fields connected to it by `IS`.
//!
//! A PROTO that instantiates itself, directly or through others, would never end: instances
//! may be nested [`MAX_PROTO_DEPTH`] deep, and the document as a whole holds at most
//! [`super::classic::MAX_NODES`] nodes.

use std::collections::HashMap;

use super::classic::MAX_NODES;
use super::tree::{Document, Field, Node, NodeId, Place, Route, Value};

/// Deepest nesting of PROTO instances (an instance inside a PROTO body inside …).
pub const MAX_PROTO_DEPTH: u32 = 32;

/// Why expansion stopped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExpandError {
    pub place: Place,
    pub message: String,
}

/// The interface field of a PROTO instance → the body fields it is connected to.
pub type Interface = HashMap<(NodeId, String), Vec<(NodeId, String)>>;

/// `set_x` and `x_changed` name the exposed field `x` (VRML97 §4.7); routes and `IS` may use
/// either form.
#[must_use]
pub fn base_field(name: &str) -> &str {
    let name = name.strip_prefix("set_").unwrap_or(name);
    name.strip_suffix("_changed").unwrap_or(name)
}

/// Expands every PROTO instance of `doc` that is not itself inside a PROTO body (templates),
/// including the instances that the copies contain. `resolve_extern(doc, proto)` loads the body
/// of an EXTERNPROTO the first time one of its instances is met.
///
/// # Errors
/// An instance nested too deep, too many nodes, an unknown PROTO field, or what
/// `resolve_extern` reports.
pub fn expand_protos(
    doc: &mut Document,
    resolve_extern: &mut dyn FnMut(&mut Document, usize) -> Result<(), ExpandError>,
) -> Result<Interface, ExpandError> {
    let mut interface = Interface::new();
    let mut i = 0;
    while i < doc.nodes.len() {
        let node = &doc.nodes[i];
        if let (Some(proto), false) = (node.proto, node.template) {
            if doc.protos[proto].extern_urls.is_some() && doc.protos[proto].body.is_empty() {
                resolve_extern(doc, proto)?;
            }
            instantiate(doc, NodeId(i as u32), proto, &mut interface)?;
        }
        i += 1;
    }
    // Routes to and from instances go to the fields their interface is connected to.
    let routes = std::mem::take(&mut doc.routes);
    let mut out = Vec::with_capacity(routes.len());
    for route in routes {
        let froms = ends(&interface, route.from, &route.from_field);
        let tos = ends(&interface, route.to, &route.to_field);
        for (from, from_field) in &froms {
            for (to, to_field) in &tos {
                out.push(Route {
                    from: *from,
                    from_field: from_field.clone(),
                    to: *to,
                    to_field: to_field.clone(),
                    place: route.place,
                });
            }
        }
    }
    doc.routes = out;
    Ok(interface)
}

/// The body fields a route end stands for (itself when the node is not an instance or the
/// field not part of its interface).
fn ends(interface: &Interface, node: NodeId, field: &str) -> Vec<(NodeId, String)> {
    let mut out = Vec::new();
    let mut stack = vec![(node, field.to_owned(), 0)];
    while let Some((n, f, depth)) = stack.pop() {
        match interface.get(&(n, base_field(&f).to_owned())).or_else(|| interface.get(&(n, f.clone()))) {
            Some(targets) if depth < MAX_PROTO_DEPTH => {
                stack.extend(targets.iter().map(|(m, g)| (*m, g.clone(), depth + 1)));
            }
            _ => out.push((n, f)),
        }
    }
    out
}

fn instantiate(
    doc: &mut Document,
    instance: NodeId,
    proto: usize,
    interface: &mut Interface,
) -> Result<(), ExpandError> {
    let inst = doc.nodes[instance.0 as usize].clone();
    let def = &doc.protos[proto];
    let name = def.name.clone();
    if inst.depth >= MAX_PROTO_DEPTH {
        return Err(ExpandError {
            place: inst.place,
            message: format!(
                "PROTO {name}: instances are nested more than {MAX_PROTO_DEPTH} deep (does the PROTO instantiate itself?)"
            ),
        });
    }
    // The instance's value of each interface field: what it wrote, else the default.
    let mut values: HashMap<String, Value> = HashMap::new();
    for f in &def.fields {
        if let Some(v) = &f.default {
            values.insert(f.name.clone(), v.clone());
        }
    }
    for field in &inst.fields {
        let key = base_field(&field.name);
        let Some(declared) = def.fields.iter().find(|f| f.name == field.name || f.name == key) else {
            return Err(ExpandError {
                place: field.place,
                message: format!("PROTO {name} has no field `{}`", super::lex::clip(&field.name)),
            });
        };
        values.insert(declared.name.clone(), field.value.clone());
    }
    let body = def.body.clone();
    let routes = def.routes.clone();
    let mut copies: HashMap<NodeId, NodeId> = HashMap::new();
    // Copy the body graph: first allocate every reachable template node, then fill fields.
    let mut order = Vec::new();
    let mut stack: Vec<NodeId> = body.iter().rev().copied().collect();
    while let Some(id) = stack.pop() {
        if copies.contains_key(&id) {
            continue;
        }
        let node = &doc.nodes[id.0 as usize];
        if !node.template {
            // A node the instance passed in (through IS) or a node outside the body.
            continue;
        }
        if doc.nodes.len() >= MAX_NODES {
            return Err(ExpandError {
                place: inst.place,
                message: format!("PROTO {name}: the scene grows past {MAX_NODES} nodes"),
            });
        }
        let new = NodeId(doc.nodes.len() as u32);
        copies.insert(id, new);
        order.push(id);
        let mut copy = node.clone();
        copy.template = false;
        copy.depth = inst.depth + 1;
        copy.expanded = None;
        for f in &node.fields {
            if let Value::Nodes(ns) = &f.value {
                stack.extend(ns.iter().rev().copied());
            }
        }
        stack.extend(node.children.iter().rev().copied());
        doc.nodes.push(copy);
    }
    let map = |id: NodeId, copies: &HashMap<NodeId, NodeId>| copies.get(&id).copied().unwrap_or(id);
    for old in order {
        let new = copies[&old];
        let node: &Node = &doc.nodes[new.0 as usize];
        let mut fields: Vec<Field> = Vec::with_capacity(node.fields.len());
        for f in &node.fields {
            let value = match &f.value {
                Value::Is(x) => {
                    interface.entry((instance, x.clone())).or_default().push((new, f.name.clone()));
                    match values.get(x) {
                        Some(v) => v.clone(),
                        None => continue,
                    }
                }
                Value::Nodes(ns) => Value::Nodes(ns.iter().map(|&n| map(n, &copies)).collect()),
                other => other.clone(),
            };
            fields.push(Field { name: f.name.clone(), value, place: f.place });
        }
        let children: Vec<NodeId> = node.children.iter().map(|&n| map(n, &copies)).collect();
        let node = &mut doc.nodes[new.0 as usize];
        node.fields = fields;
        node.children = children;
    }
    for r in routes {
        doc.routes.push(Route { from: map(r.from, &copies), to: map(r.to, &copies), ..r });
    }
    doc.nodes[instance.0 as usize].expanded = body.first().map(|&b| map(b, &copies));
    Ok(())
}
