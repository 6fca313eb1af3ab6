#!/usr/bin/env python3
"""Independent reference values for keyrig's track interpolation (docs/design.md section 3).

Writes JSON fixtures to crates/core/tests/fixtures/, which crates/core/tests/reference.rs
compares against keyrig-core's Track to 1e-6.

* Positions and scalars: scipy.interpolate.CubicHermiteSpline, with the Kochanek-Bartels
  tangents (including the non-uniform spacing factors and keyrig's end-key rule) computed here,
  independently of the Rust code, and converted to per-second derivatives.
* Rotations: numpy-quaternion's `squad` (Shoemake squad, T = C = B = 0, uniform times; compared
  on the interior segments, because numpy-quaternion uses a different end-key rule), and
  numpy-quaternion's `squad_evaluate` with control quaternions a_i, b_{i+1} computed here from
  the TCB formulas (uneven times, non-zero T/C/B, all segments).

Key values and T/C/B are rounded to float32 first, since keyrig stores them as f32.

Usage (from the repository root):
    python3 -m venv /tmp/refvenv && /tmp/refvenv/bin/pip install scipy numpy numpy-quaternion
    /tmp/refvenv/bin/python tools/reference/make_fixtures.py
"""

import json
import os

import numpy as np
import quaternion  # numpy-quaternion
import scipy
from scipy.interpolate import CubicHermiteSpline

OUT_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "crates", "core", "tests", "fixtures")
TOLERANCE = 1e-6
RNG = np.random.default_rng(20260422)


def f32(x):
    """Round to float32 and back to a Python float (what keyrig stores)."""
    return np.asarray(x, dtype=np.float32).astype(np.float64)


# ----------------------------------------------------------------------------------------------
# Kochanek-Bartels tangents (docs/design.md section 3), written independently of the Rust code.


def kb_tangents(times, chords, tcbs):
    """Per key (D_i, S_i) in value units per segment.

    chords[j] = P_{j+1} - P_j (or L(q_j, q_{j+1})). End keys: P_{-1} := P_0, P_{n+1} := P_n
    (zero chord) with mirrored spacing Delta_{-1} := Delta_0, Delta_n := Delta_{n-1}.
    """
    n = len(times)
    zero = np.zeros_like(chords[0])
    result = []
    for i in range(n):
        t, c, b = tcbs[i]
        d_prev = chords[i - 1] if i > 0 else zero
        d_next = chords[i] if i < n - 1 else zero
        dt_prev = times[i] - times[i - 1] if i > 0 else times[1] - times[0]
        dt_next = times[i + 1] - times[i] if i < n - 1 else times[n - 1] - times[n - 2]
        s = (1 - t) * (1 + b) * (1 + c) / 2 * d_prev + (1 - t) * (1 - b) * (1 - c) / 2 * d_next
        d = (1 - t) * (1 + b) * (1 - c) / 2 * d_prev + (1 - t) * (1 - b) * (1 + c) / 2 * d_next
        s = s * (2 * dt_next / (dt_prev + dt_next))
        d = d * (2 * dt_prev / (dt_prev + dt_next))
        result.append((d, s))
    return result


def sample_times(times):
    """Before the first key, at and +-1e-6 around every key, random times inside, after the last."""
    ts = [times[0] - 1.0, times[0] - 1e-6]
    for i, t in enumerate(times):
        ts.append(t)
        if i > 0:
            ts.append(t - 1e-6)
        if i < len(times) - 1:
            ts.append(t + 1e-6)
            for u in RNG.uniform(0.0, 1.0, 3):
                ts.append(t + u * (times[i + 1] - t))
    ts += [times[-1] + 1e-6, times[-1] + 2.0]
    return sorted(ts)


# ----------------------------------------------------------------------------------------------
# Positions and scalars.


def hermite_reference(times, values, tcbs, whole_track):
    """Samples of the TCB track; values has shape (n, dim)."""
    chords = [values[j + 1] - values[j] for j in range(len(times) - 1)]
    tangents = kb_tangents(times, chords, tcbs)
    if whole_track:
        # C = 0 everywhere: the per-second velocity is the same on both sides of each key
        # (that is what the spacing factors are for), so one C1 spline with one derivative per
        # key reproduces the whole track. Key i's derivative from S_i (or D_i at the last key).
        n = len(times)
        dydx = []
        for i in range(n):
            if i < n - 1:
                dydx.append(tangents[i][1] / (times[i + 1] - times[i]))
            else:
                dydx.append(tangents[i][0] / (times[i] - times[i - 1]))
            if 0 < i < n - 1:
                left = tangents[i][0] / (times[i] - times[i - 1])
                assert np.allclose(left, dydx[i], rtol=1e-12, atol=1e-12), "C = 0 must be C1"
        splines = [CubicHermiteSpline(times, values, np.array(dydx), axis=0)]
    else:
        # One two-knot spline per segment, with S_i / dt and D_{i+1} / dt as derivatives.
        splines = []
        for i in range(len(times) - 1):
            dt = times[i + 1] - times[i]
            dydx = np.array([tangents[i][1] / dt, tangents[i + 1][0] / dt])
            splines.append(CubicHermiteSpline(times[i : i + 2], values[i : i + 2], dydx, axis=0))

    samples = []
    for t in sample_times(times):
        if t <= times[0]:
            v = values[0]
        elif t >= times[-1]:
            v = values[-1]
        else:
            seg = int(np.searchsorted(times, t, side="right")) - 1
            spline = splines[0] if whole_track else splines[seg]
            v = spline(t)
        samples.append({"time": float(t), "value": [float(x) for x in np.atleast_1d(v)]})
    return samples


def position_fixture(name, times, dim, tcb_mode, whole_track, description):
    n = len(times)
    values = f32(RNG.uniform(-1.5, 1.5, (n, dim)))
    if tcb_mode == "zero":
        tcbs = np.zeros((n, 3))
    elif tcb_mode == "c0":
        tcbs = f32(RNG.uniform(-0.8, 0.8, (n, 3)))
        tcbs[:, 1] = 0.0
    else:
        tcbs = f32(RNG.uniform(-0.8, 0.8, (n, 3)))
    samples = hermite_reference(times, values, tcbs, whole_track)
    keys = [
        {"time": float(times[i]), "value": [float(x) for x in values[i]], "tcb": [float(x) for x in tcbs[i]]}
        for i in range(n)
    ]
    write(name, description, "scipy.interpolate.CubicHermiteSpline " + scipy.__version__, keys, samples)


# ----------------------------------------------------------------------------------------------
# Rotations.


def random_rotation_keys(n, max_step_deg):
    """Unit quaternions, consecutive keys at most max_step_deg apart (rotation angle)."""
    qs = [quaternion.from_rotation_vector(RNG.normal(size=3) * 0.5)]
    for _ in range(n - 1):
        axis = RNG.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = np.radians(RNG.uniform(10.0, max_step_deg))
        qs.append(qs[-1] * quaternion.from_rotation_vector(axis * angle))
    stored = f32(quaternion.as_float_array(np.array(qs)))
    for i in range(1, n):
        if np.dot(stored[i - 1], stored[i]) < 0:
            stored[i] = -stored[i]
    # keyrig reads the f32 values and normalizes them in f64 on validation; do the same.
    unit = stored / np.linalg.norm(stored, axis=1, keepdims=True)
    return stored, unit


def quat_key_json(times, stored, tcbs):
    # stored rows are (w, x, y, z), exactly representable in f32; JSON stores glam order
    # [x, y, z, w].
    return [
        {
            "time": float(times[i]),
            "value": [float(stored[i][1]), float(stored[i][2]), float(stored[i][3]), float(stored[i][0])],
            "tcb": [float(x) for x in tcbs[i]],
        }
        for i in range(len(times))
    ]


def quat_json(q):
    a = quaternion.as_float_array(q)
    return [float(a[1]), float(a[2]), float(a[3]), float(a[0])]


def squad_uniform_fixture(name):
    n = 8
    times = np.arange(n, dtype=np.float64) * 0.5
    stored, unit = random_rotation_keys(n, 100.0)
    qs = quaternion.as_quat_array(unit)
    # Interior segments only: numpy-quaternion sets a_0 = q_0 and b_n = q_n at the ends,
    # keyrig uses P_{-1} := P_0 (see docs/interpolation.md).
    ts = [t for t in sample_times(times) if times[1] <= t <= times[-2]]
    out = quaternion.squad(qs, times, np.array(ts))
    samples = [{"time": float(t), "value": quat_json(q)} for t, q in zip(ts, out)]
    write(
        name,
        "Shoemake squad (T = C = B = 0), uniform times, interior segments [t_1, t_{n-1}]",
        "numpy-quaternion squad " + quaternion.__version__,
        quat_key_json(times, stored, np.zeros((n, 3))),
        samples,
    )


def squad_tcb_fixture(name):
    n = 9
    steps = f32(RNG.uniform(0.05, 1.5, n - 1))
    times = np.concatenate([[0.25], 0.25 + np.cumsum(steps)])
    stored, unit = random_rotation_keys(n, 90.0)
    tcbs = f32(RNG.uniform(-0.6, 0.6, (n, 3)))
    qs = quaternion.as_quat_array(unit)

    def log_between(a, b):
        return quaternion.as_float_array(np.log(a.inverse() * b))[1:]

    def exp_vec(v):
        return np.exp(np.quaternion(0.0, *v))

    logs = [log_between(qs[j], qs[j + 1]) for j in range(n - 1)]
    tangents = kb_tangents(times, logs, tcbs)
    a = [qs[i] * exp_vec((tangents[i][1] - logs[i]) / 2) for i in range(n - 1)]
    b = [qs[i + 1] * exp_vec((logs[i] - tangents[i + 1][0]) / 2) for i in range(n - 1)]
    for i in range(n - 1):
        # numpy-quaternion's slerp takes the short way; keyrig's squad does not flip. They
        # agree when every pair slerped is less than 90 degrees apart in 4-D, as here.
        for p, q in [(qs[i], qs[i + 1]), (a[i], b[i]), (qs[i], a[i]), (qs[i + 1], b[i])]:
            assert np.dot(quaternion.as_float_array(p), quaternion.as_float_array(q)) > 0.2
    samples = []
    for t in sample_times(times):
        if t <= times[0]:
            q = qs[0]
        elif t >= times[-1]:
            q = qs[-1]
        else:
            i = int(np.searchsorted(times, t, side="right")) - 1
            tau = (t - times[i]) / (times[i + 1] - times[i])
            q = quaternion.squad_evaluate(tau, qs[i], a[i], b[i], qs[i + 1])
        samples.append({"time": float(t), "value": quat_json(q)})
    write(
        name,
        "Squad with TCB (controls from docs/design.md section 3 incl. spacing factors), uneven times",
        "numpy-quaternion squad_evaluate " + quaternion.__version__ + " with controls computed in Python",
        quat_key_json(times, stored, tcbs),
        samples,
    )


# ----------------------------------------------------------------------------------------------


def write(name, description, reference, keys, samples):
    os.makedirs(OUT_DIR, exist_ok=True)
    doc = {
        "description": description,
        "reference": reference,
        "generator": "tools/reference/make_fixtures.py",
        "tolerance": TOLERANCE,
        "keys": keys,
        "samples": samples,
    }
    path = os.path.join(OUT_DIR, name + ".json")
    with open(path, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print(f"wrote {os.path.normpath(path)}: {len(keys)} keys, {len(samples)} samples")


def uneven_times(n, start=0.0):
    steps = f32(RNG.uniform(0.05, 1.5, n - 1))
    return np.concatenate([[start], start + np.cumsum(steps)])


def main():
    position_fixture(
        "vec3_catmull_rom_uniform",
        np.arange(7, dtype=np.float64) * 0.25,
        3,
        "zero",
        True,
        "Vec3 Catmull-Rom (T = C = B = 0), uniform times",
    )
    position_fixture(
        "vec3_tcb_c0_uneven",
        uneven_times(9, -1.0),
        3,
        "c0",
        True,
        "Vec3 TCB with C = 0 (random T, B), uneven times: one C1 spline through all keys",
    )
    position_fixture(
        "vec3_tcb_uneven",
        uneven_times(9, 0.5),
        3,
        "random",
        False,
        "Vec3 TCB with random T, C, B, uneven times: one Hermite spline per segment",
    )
    position_fixture(
        "scalar_tcb_uneven",
        uneven_times(8, 2.0),
        1,
        "random",
        False,
        "scalar TCB with random T, C, B, uneven times: one Hermite spline per segment",
    )
    squad_uniform_fixture("quat_squad_uniform")
    squad_tcb_fixture("quat_squad_tcb_uneven")


if __name__ == "__main__":
    main()
