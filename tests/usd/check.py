"""Reads a viewcloth USD layer back with Pixar's USD library (tests/usd.rs runs it in a venv
holding `usd-core`) and checks it against what the run wrote in its OBJ frames.

usage: check.py LAYER EXPECTED.json

EXPECTED.json: {"start": 1001, "end": 1005, "fps": 25, "cloth": "/World/cloth/sheet",
"obstacles": ["/World/obstacles/sphere"],
"obstacle_velocities": {"/World/obstacles/sphere": [vx, vy, vz]} (optional: every point's velocity at every time), "frames": {"1001": {"points": [[x, y, z], ...],
"velocities": [...] (optional: else only counted), "faces": [[a, b, c], ...], "uvs": [[[u, v] x 3], ...]}, ...}}

Prints one line per check; exits 1 at the first failure, saying what differed.
"""

import json
import sys

from pxr import Usd, UsdGeom

TOL = 2e-6  # 32-bit floats in the layer, 9 decimals in the OBJ


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def close(a, b, what):
    for i, (p, q) in enumerate(zip(a, b)):
        for x, y in zip(p, q):
            if abs(x - y) > TOL * max(1.0, abs(y)):
                fail(f"{what}[{i}]: {tuple(p)} in the layer, {tuple(q)} in the run")
    if len(a) != len(b):
        fail(f"{what}: {len(a)} in the layer, {len(b)} in the run")


def main():
    layer, expected = sys.argv[1], json.load(open(sys.argv[2]))
    stage = Usd.Stage.Open(layer)
    if stage is None:
        fail(f"{layer} does not open")
    meta = (stage.GetStartTimeCode(), stage.GetEndTimeCode(), stage.GetTimeCodesPerSecond())
    if meta != (expected["start"], expected["end"], expected["fps"]):
        fail(f"start, end, time codes per second {meta}, expected {expected['start'], expected['end'], expected['fps']}")
    if UsdGeom.GetStageUpAxis(stage) != "Z" or UsdGeom.GetStageMetersPerUnit(stage) != 1.0:
        fail("upAxis / metersPerUnit")
    print(f"ok: frames {meta[0]:.0f}..{meta[1]:.0f} at {meta[2]} per second, Z up, metres")

    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(expected["cloth"]))
    if not mesh:
        fail(f"no Mesh at {expected['cloth']}")
    st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
    if st.GetInterpolation() != UsdGeom.Tokens.faceVarying:
        fail(f"primvars:st interpolation {st.GetInterpolation()}")
    codes = mesh.GetPointsAttr().GetTimeSamples()
    want_codes = [float(c) for c in range(expected["start"], expected["end"] + 1)]
    if codes != want_codes:
        fail(f"points time codes {codes}, expected {want_codes}")
    for code in range(expected["start"], expected["end"] + 1):
        frame = expected["frames"][str(code)]
        points = mesh.GetPointsAttr().Get(code)
        counts = mesh.GetFaceVertexCountsAttr().Get(code)
        indices = mesh.GetFaceVertexIndicesAttr().Get(code)
        valid, why = UsdGeom.Mesh.ValidateTopology(indices, counts, len(points))
        if not valid:
            fail(f"time {code}: ValidateTopology: {why}")
        if len(points) != len(frame["points"]):
            fail(f"time {code}: {len(points)} points, the run has {len(frame['points'])}")
        close(points, frame["points"], f"time {code}: points")
        if "velocities" in frame:
            close(mesh.GetVelocitiesAttr().Get(code), frame["velocities"], f"time {code}: velocities")
        elif len(mesh.GetVelocitiesAttr().Get(code) or []) != len(points):
            fail(f"time {code}: not one velocity per point")
        faces = [list(indices[3 * f : 3 * f + 3]) for f in range(len(counts))]
        if list(counts) != [3] * len(frame["faces"]) or faces != frame["faces"]:
            fail(f"time {code}: faces differ from the run's")
        uvs = st.ComputeFlattened(code)
        close(uvs, [uv for face in frame["uvs"] for uv in face], f"time {code}: st")
        lo, hi = mesh.GetExtentAttr().Get(code)
        if any(p[i] < lo[i] - TOL or p[i] > hi[i] + TOL for p in points for i in range(3)):
            fail(f"time {code}: a point outside the extent")
        v = "velocities" if "velocities" in frame else "one velocity per point,"
        print(f"ok: time {code}: {len(points)} points, {len(counts)} faces, topology valid, {v} st as the run's")
    for path in expected["obstacles"]:
        body = UsdGeom.Mesh(stage.GetPrimAtPath(path))
        if not body:
            fail(f"no Mesh at {path}")
        n = len(body.GetPointsAttr().Get(expected["start"]))
        valid, why = UsdGeom.Mesh.ValidateTopology(
            body.GetFaceVertexIndicesAttr().Get(), body.GetFaceVertexCountsAttr().Get(), n
        )
        if not valid or len(body.GetPointsAttr().GetTimeSamples()) != len(want_codes):
            fail(f"{path}: {why or 'time samples'}")
        print(f"ok: {path}: {n} points at every time code, topology valid")
        want = expected.get("obstacle_velocities", {}).get(path)
        if want is not None:
            for code in range(expected["start"], expected["end"] + 1):
                got = body.GetVelocitiesAttr().Get(code)
                close(got, [want] * n, f"{path}: time {code}: velocities")
            print(f"ok: {path}: every point's velocity {tuple(want)} at every time code")


main()
