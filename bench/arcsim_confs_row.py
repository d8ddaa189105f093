#!/usr/bin/env python3
"""One row of bench/arcsim_confs.sh's table (see there), from the written frames alone.

  arcsim_confs_row.py NAME OURS_DIR ARCSIM_DIR CONF FRAMES HANDLE_R CHECK_LOG OURS_S ARCSIM_S

OURS_DIR holds viewcloth's frame_NNNN.obj and stats.json; ARCSIM_DIR ARCSim's NNNN_00.obj (may be
absent). The largest principal stretch of a face is √λ_max(Fᵀ F) − 1, F = ∂x/∂u from its `v` and
`vt` corners; "away from handles" leaves out faces whose material-space centroid lies within
HANDLE_R of a handle node's material coordinates (from the conf's cloth mesh: node handles of
cloth 0), where a point load makes the strain grow without bound as the mesh refines.
"""
import json
import math
import os
import re
import sys


def read_obj(path):
    """Positions, material coordinates, and faces as (position index, uv index) triples."""
    vs, vts, fs = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("vt "):
                vts.append(tuple(map(float, line.split()[1:3])))
            elif line.startswith("f "):
                corners = [c.split("/") for c in line.split()[1:]]
                ids = [(int(c[0]) - 1, int(c[1]) - 1 if len(c) > 1 and c[1] else int(c[0]) - 1) for c in corners]
                for k in range(1, len(ids) - 1):
                    fs.append((ids[0], ids[k], ids[k + 1]))
    return vs, vts, fs


def stretches(path, uv_scale=1.0):
    """(largest stretch − 1, material centroid) per face; the frame's `vt` times `uv_scale` are
    its material coordinates in metres."""
    vs, vts, fs = read_obj(path)
    vts = [(u * uv_scale, v * uv_scale) for u, v in vts]
    out = []
    for (a, ua), (b, ub), (c, uc) in fs:
        if max(ua, ub, uc) >= len(vts):
            continue
        d1 = [vs[b][i] - vs[a][i] for i in range(3)]
        d2 = [vs[c][i] - vs[a][i] for i in range(3)]
        e1 = (vts[ub][0] - vts[ua][0], vts[ub][1] - vts[ua][1])
        e2 = (vts[uc][0] - vts[ua][0], vts[uc][1] - vts[ua][1])
        det = e1[0] * e2[1] - e2[0] * e1[1]
        if abs(det) < 1e-18:
            continue
        # F = [d1 d2] [e1 e2]⁻¹ (3×2), C = Fᵀ F (2×2).
        inv = ((e2[1] / det, -e2[0] / det), (-e1[1] / det, e1[0] / det))
        f0 = [d1[i] * inv[0][0] + d2[i] * inv[1][0] for i in range(3)]
        f1 = [d1[i] * inv[0][1] + d2[i] * inv[1][1] for i in range(3)]
        c00 = sum(x * x for x in f0)
        c11 = sum(x * x for x in f1)
        c01 = sum(x * y for x, y in zip(f0, f1))
        lam = 0.5 * (c00 + c11) + math.sqrt(0.25 * (c00 - c11) ** 2 + c01 * c01)
        centroid = tuple((vts[ua][i] + vts[ub][i] + vts[uc][i]) / 3 for i in range(2))
        out.append((math.sqrt(lam) - 1, centroid))
    return out


def strip_comments(text):
    return re.sub(r"//[^\n]*", "", text)


def handle_uvs(conf_path):
    """Material coordinates of the node handles of cloth 0 (empty when unknown)."""
    try:
        conf = json.loads(strip_comments(open(conf_path).read()))
        root = os.path.dirname(os.path.dirname(os.path.abspath(conf_path)))
        mesh = os.path.join(root, conf["cloths"][0]["mesh"])
        vs, vts, fs = read_obj(mesh)
    except (OSError, KeyError, IndexError, ValueError):
        return []
    node_uv = {}
    for tri in fs:
        for v, u in tri:
            if u < len(vts):
                node_uv.setdefault(v, []).append(vts[u])
    out = []
    for h in conf.get("handles", []):
        if h.get("type", "node") != "node" or h.get("cloth", 0) != 0:
            continue
        for n in h.get("nodes", []):
            out.extend(node_uv.get(n, []))
    return out


def our_uv_scale(conf_path):
    """Metres per unit of viewcloth's frame `vt`. viewcloth writes `vt` in the input mesh's
    units; for a mesh without `vt` those are its positions before the cloth's transform, while
    ARCSim's material coordinates (and its frames' `vt`) are the transformed positions: the
    transform's scale then converts."""
    try:
        conf = json.loads(strip_comments(open(conf_path).read()))
        root = os.path.dirname(os.path.dirname(os.path.abspath(conf_path)))
        cloth = conf["cloths"][0]
        _, vts, _ = read_obj(os.path.join(root, cloth["mesh"]))
    except (OSError, KeyError, IndexError, ValueError):
        return 1.0
    if vts:
        return 1.0
    scale = cloth.get("transform", {}).get("scale", 1.0)
    return float(scale) if isinstance(scale, (int, float)) else 1.0


def frame_path(d, f, arcsim):
    return os.path.join(d, f"{f:04d}_00.obj" if arcsim else f"frame_{f:04d}.obj")


def faces(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return sum(1 for line in f if line.startswith("f "))


def max_stretch(d, frames, arcsim, handles, radius, uv_scale=1.0):
    """Largest stretch − 1 over frames 10..frames, over all faces and away from handles."""
    worst_all = worst_away = None
    for f in range(10, frames + 1):
        p = frame_path(d, f, arcsim)
        if not os.path.exists(p):
            break
        for s, c in stretches(p, uv_scale):
            worst_all = s if worst_all is None else max(worst_all, s)
            if all(math.dist(c, h) > radius for h in handles):
                worst_away = s if worst_away is None else max(worst_away, s)
    return worst_all, worst_away


def fmt(x, spec=".3f"):
    return "–" if x is None else format(x, spec)


def main():
    name, ours, arc, conf, frames, radius, check_log, ours_s, arc_s = sys.argv[1:10]
    frames, radius = int(frames), float(radius)
    handles = handle_uvs(conf)
    stats_path = os.path.join(ours, "stats.json")
    stats = json.load(open(stats_path)) if os.path.exists(stats_path) else {"frames": []}
    fr = stats["frames"]
    done = max((f["frame"] for f in fr), default=-1)
    error = stats.get("error")
    cross = (max((f.get("crossings_self", 0) for f in fr), default=0),
             max((f.get("crossings_obstacle", 0) for f in fr), default=0))
    retries = sum(f.get("retries", 0) for f in fr)
    steps = sum(f.get("steps", 0) for f in fr)
    marks = [1, 10, 25, frames]
    faces_ours = " / ".join(fmt(faces(frame_path(ours, f, False)) if f <= frames else None, "d") for f in marks)
    faces_arc = " / ".join(fmt(faces(frame_path(arc, f, True)) if f <= frames else None, "d") for f in marks)
    s_ours = max_stretch(ours, frames, False, handles, radius, our_uv_scale(conf))
    s_arc = max_stretch(arc, frames, True, handles, radius)
    with open(check_log) as f:
        warnings = sum(1 for line in f if "warning" in line.lower())
    status = f"{done}" + ("" if error is None else f" (stopped: {error[:80]})")
    arc_time = "–" if not arc_s else f"{float(arc_s.split()[0]):.0f}" + arc_s[len(arc_s.split()[0]):]
    print(f"| {name} | {status} | {faces_ours}; {faces_arc} | {cross[0]} / {cross[1]} | "
          f"{fmt(s_ours[0])} / {fmt(s_ours[1])}; {fmt(s_arc[0])} / {fmt(s_arc[1])} | {retries} of {steps} | "
          f"{warnings} | {float(ours_s):.0f}; {arc_time} |")


if __name__ == "__main__":
    main()
