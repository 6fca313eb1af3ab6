#!/usr/bin/env python3
"""Coin3D's own evaluation of a VRML97 / X3D file's animation, for keyrig's reference tests.

Usage: coin_reference.py FILE FPS LAST_FRAME

Reads FILE with Coin3D (through pivy, Debian's python3-pivy): a .wrl or .iv as it is; an .x3dv with
its X3D header and PROFILE/COMPONENT/META lines replaced by a VRML97 header (its nodes are
VRML97's); an .x3d (XML) by writing its TimeSensors, interpolators and ROUTEs as a VRML97 file
(X3D XML files with PROTOs are refused: test their classic twin). Then for every TimeSensor,
every interpolator its fraction_changed drives and every field the interpolator's
value_changed is routed to, Coin evaluates the interpolator at the fraction of each frame
0..=LAST_FRAME at FPS: fraction = t / cycleInterval, wrapped when the sensor loops, 1.0 at the
first cycle's end and 0.0 at later multiples (keyrig's repeating tracks).

Prints JSON: a list of {"sensor", "interpolator", "type", "target", "target_type", "field",
"values": [one value per frame]}, a value a list of numbers (a rotation as the quaternion
x, y, z, w; a CoordinateInterpolator's as every point's x, y, z).
"""

import json
import math
import re
import sys
import xml.etree.ElementTree as ET

try:
    from pivy import coin
except ImportError:
    sys.stderr.write("pivy (Coin3D for Python) is missing: apt-get install python3-pivy\n")
    sys.exit(3)

INTERPOLATORS = {
    "PositionInterpolator",
    "OrientationInterpolator",
    "ScalarInterpolator",
    "ColorInterpolator",
    "CoordinateInterpolator",
}


def vrml_of_x3d_xml(text):
    """TimeSensors, interpolators and ROUTEs of an X3D XML file as VRML97 text."""
    root = ET.fromstring(text)
    if any(True for _ in root.iter("ProtoDeclare")):
        raise SystemExit("X3D XML with PROTOs: compare its classic-encoding twin instead")
    out = ["#VRML V2.0 utf8"]
    for e in root.iter():
        tag = e.tag
        if tag == "TimeSensor" or tag in INTERPOLATORS:
            if "USE" in e.attrib:
                continue
            fields = []
            for k, v in e.attrib.items():
                if k in ("DEF", "containerField"):
                    continue
                if k in ("loop", "enabled"):
                    v = v.strip().upper()
                fields.append(f"{k} [ {v} ]" if k in ("key", "keyValue") else f"{k} {v}")
            out.append(f"DEF {e.attrib['DEF']} {tag} {{ {' '.join(fields)} }}")
    # Route targets become stand-in nodes of the right type, named as in the file.
    targets = {}
    for e in root.iter():
        if "DEF" in e.attrib and e.tag not in INTERPOLATORS and e.tag != "TimeSensor":
            targets[e.attrib["DEF"]] = e.tag
    routes = []
    for r in root.iter("ROUTE"):
        routes.append((r.attrib["fromNode"], r.attrib["fromField"], r.attrib["toNode"], r.attrib["toField"]))
    for name in sorted({r[2] for r in routes if r[2] in targets}):
        kind = targets[name]
        if kind in ("Transform", "Material", "Coordinate", "DirectionalLight", "PointLight", "SpotLight", "Viewpoint"):
            out.append(f"DEF {name} {kind} {{ }}")
    for r in routes:
        out.append(f"ROUTE {r[0]}.{r[1]} TO {r[2]}.{r[3]}")
    return "\n".join(out) + "\n"


def vrml_of_x3d_classic(text):
    """TimeSensors, interpolators and ROUTEs of an X3D classic file as VRML97 text (their bodies
    hold no nodes, so a brace-free match finds them)."""
    if re.search(r"^\s*PROTO\b", text, re.M):
        raise SystemExit("X3D classic with PROTOs: compare its VRML97 twin instead")
    # Comments out, strings kept.
    text = re.sub(r'("(?:[^"\\]|\\.)*")|#[^\n]*', lambda m: m.group(1) or "", text)
    out = ["#VRML V2.0 utf8"]
    kinds = "|".join(["TimeSensor"] + sorted(INTERPOLATORS))
    for m in re.finditer(r"DEF\s+(\S+)\s+(" + kinds + r")\s*\{([^{}]*)\}", text):
        body = re.sub(r"\b(enabled|description|metadata)\b[^\n]*", "", m.group(3))
        out.append(f"DEF {m.group(1)} {m.group(2)} {{ {body} }}")
    defs = dict(re.findall(r"DEF\s+(\S+)\s+(\w+)\s*\{", text))
    routes = re.findall(r"ROUTE\s+([^.\s]+)\.(\S+)\s+TO\s+([^.\s]+)\.(\S+)", text)
    for name in sorted({r[2] for r in routes}):
        kind = defs.get(name)
        if kind in ("Transform", "Material", "Coordinate", "DirectionalLight", "PointLight", "SpotLight", "Viewpoint"):
            out.append(f"DEF {name} {kind} {{ }}")
    for r in routes:
        if defs.get(r[0]) in ("TimeSensor",) or defs.get(r[0]) in INTERPOLATORS:
            out.append(f"ROUTE {r[0]}.{r[1]} TO {r[2]}.{r[3]}")
    return "\n".join(out) + "\n"


def read(path):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    if path.lower().endswith(".x3d"):
        text = vrml_of_x3d_xml(text)
    elif path.lower().endswith(".x3dv"):
        text = vrml_of_x3d_classic(text)
    coin.SoDB.init()
    inp = coin.SoInput()
    inp.setBuffer(text)
    folder = path.rsplit("/", 1)[0] if "/" in path else "."
    coin.SoInput.addDirectoryFirst(folder)
    root = coin.SoDB.readAll(inp) if path.lower().endswith(".iv") else coin.SoDB.readAllVRML(inp)
    if root is None:
        raise SystemExit(f"Coin could not read {path}")
    root.ref()
    return root


def find_all(root, type_id):
    sa = coin.SoSearchAction()
    sa.setType(type_id, True)
    sa.setInterest(coin.SoSearchAction.ALL)
    sa.setSearchingAll(True)
    sa.apply(root)
    paths = sa.getPaths()
    return [paths[i].getTail() for i in range(paths.getLength())]


def connections(output):
    fields = coin.SoFieldList()
    output.getForwardConnections(fields)
    return [fields[i] for i in range(fields.getLength())]


def fraction(t, cycle, loop):
    q = t / cycle
    if not loop:
        return min(max(q, 0.0), 1.0)
    if q <= 1.0:
        return q
    return q - math.floor(q)


def value_field(kind):
    return {
        "VRMLPositionInterpolator": coin.SoSFVec3f,
        "VRMLOrientationInterpolator": coin.SoSFRotation,
        "VRMLScalarInterpolator": coin.SoSFFloat,
        "VRMLColorInterpolator": coin.SoSFColor,
        "VRMLCoordinateInterpolator": coin.SoMFVec3f,
    }.get(kind)


def value_of(field):
    if isinstance(field, coin.SoSFFloat):
        return [field.getValue()]
    if isinstance(field, coin.SoSFRotation):
        return list(field.getValue().getValue())
    if isinstance(field, coin.SoMFVec3f):
        return [c for i in range(field.getNum()) for c in field[i].getValue()]
    return list(field.getValue().getValue())


def main():
    path, fps, last = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    root = read(path)
    result = []
    seen = set()
    for sensor in find_all(root, coin.SoVRMLTimeSensor.getClassTypeId()):
        if sensor.getNodeId() in seen:
            continue
        seen.add(sensor.getNodeId())
        cycle = sensor.getField(coin.SbName("cycleInterval")).getValue().getValue()
        loop = bool(sensor.getField(coin.SbName("loop")).getValue())
        for frac_field in connections(sensor.getOutput(coin.SbName("fraction_changed"))):
            interp = frac_field.getContainer()
            kind = interp.getTypeId().getName().getString()
            make = value_field(kind)
            if make is None:
                continue
            probe = make()
            out = interp.getOutput(coin.SbName("value_changed"))
            probe.connectFrom(out)
            values = []
            for frame in range(0, last + 1):
                interp.getField(coin.SbName("set_fraction")).setValue(fraction(frame / fps, cycle, loop))
                values.append(value_of(probe))
            for target in connections(out):
                if target is probe or target.getContainer() is None:
                    continue
                node = target.getContainer()
                if node.getTypeId().getName().getString() == "":
                    continue
                result.append(
                    {
                        "sensor": sensor.getName().getString(),
                        "interpolator": interp.getName().getString(),
                        "type": kind.replace("VRML", "", 1),
                        "target": node.getName().getString(),
                        "target_type": node.getTypeId().getName().getString().replace("VRML", "", 1),
                        "field": node.getFieldName(target),
                        "cycle": cycle,
                        "loop": loop,
                        "values": values,
                    }
                )
            probe.disconnect()
    json.dump(result, sys.stdout)


main()
