#!/usr/bin/env python3
"""ARCSim's sphere.json on a fixed mesh, frictionless, in viewcloth and in ARCSim side by side:
the sheet's stretch while the sphere pushes it (issue 18: contact that does not drag).

The conf is ../shared/arcsim/conf/sphere.json with its 4-face square replaced by a 64 x 64 grid
(8,192 faces; the four corners first, in square4.obj's order, so `"nodes": [2, 3]` hold the same
corners), `friction` and `obs_friction` 0 and `"disable": ["remeshing"]`. Both simulators run
FRAMES frames at STEPS steps per frame (ARCSim's 8 by default). Per frame from FROM on, the mean
over faces of the largest principal stretch − 1 (the written positions against the grid's material
coordinates), over the whole sheet and over its top quarter (by the handles), for each run.

  bench/sphere_fixed_mesh.py VIEWCLOTH_BIN OUT_DIR [--arcsim ARCSIM_BIN --arcsim-src SRC]
      [--frames 60] [--steps 8] [--from 50]

ARCSIM_BIN / SRC: the build `../shared/tools/arcsim-build.sh` makes (SRC holds materials/ and
meshes/). Without --arcsim only viewcloth runs. Needs numpy. Exit 1 with one line on a failed run.
"""
import argparse
import json
import os
import re
import subprocess
import sys

import numpy as np

N = 64
HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "arcsim"))


def grid_order():
    """Vertex index of grid point (i, j): the four corners first, then row by row."""
    idx = {}
    for c in [(0, 0), (N, 0), (N, N), (0, N)]:
        idx[c] = len(idx)
    for j in range(N + 1):
        for i in range(N + 1):
            if (i, j) not in idx:
                idx[(i, j)] = len(idx)
    return idx


def write_grid(path, idx):
    verts = sorted(idx, key=idx.get)
    with open(path, "w") as out:
        for i, j in verts:
            out.write(f"v {i / N} {j / N} 0\nvt {i / N} {j / N} 0\n")
        for j in range(N):
            for i in range(N):
                a, b, c, d = (idx[p] + 1 for p in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)])
                tris = [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
                for t in tris:
                    out.write("f " + " ".join(f"{k}/{k}" for k in t) + "\n")


def write_conf(path, mesh, steps, frames, src):
    text = open(os.path.join(SHARED, "conf", "sphere.json")).read()
    text = "\n".join(line for line in text.splitlines() if not line.strip().startswith("//"))
    conf = json.loads(text)
    conf["frame_steps"] = steps
    conf["end_time"] = conf["frame_time"] * (frames + 0.5)
    conf["cloths"][0]["mesh"] = mesh
    conf["cloths"][0]["materials"][0]["data"] = os.path.join(src, "materials", "gray-interlock.json")
    conf["obstacles"][0]["mesh"] = os.path.join(src, "meshes", "sphere.obj")
    conf["friction"], conf["obs_friction"], conf["disable"] = 0, 0, ["remeshing"]
    with open(path, "w") as out:
        json.dump(conf, out, indent=1)


def positions(path):
    return np.array([[float(t) for t in line.split()[1:4]] for line in open(path) if line.startswith("v ")])


def stretch(x, faces, uv):
    dm = np.stack([uv[faces[:, 1]] - uv[faces[:, 0]], uv[faces[:, 2]] - uv[faces[:, 0]]], axis=2)
    ds = np.stack([x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]]], axis=2)
    s = np.linalg.svd(ds @ np.linalg.inv(dm), compute_uv=False)[:, 0] - 1
    top = uv[faces].mean(axis=1)[:, 1] > 0.75
    return s.mean(), s[top].mean()


def main():
    p = argparse.ArgumentParser()
    p.add_argument("viewcloth")
    p.add_argument("out")
    p.add_argument("--arcsim")
    p.add_argument("--arcsim-src", default=SHARED)
    p.add_argument("--frames", type=int, default=60)
    p.add_argument("--steps", type=int, default=8)
    p.add_argument("--from", dest="first", type=int, default=50)
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    idx = grid_order()
    mesh = os.path.abspath(os.path.join(a.out, "grid64.obj"))
    conf = os.path.abspath(os.path.join(a.out, "sphere_fixed.json"))
    write_grid(mesh, idx)
    write_conf(conf, mesh, a.steps, a.frames, os.path.abspath(a.arcsim_src))
    runs = [("viewcloth", os.path.join(a.out, "viewcloth"), "frame_%04d.obj")]
    cmd = [a.viewcloth, "simulate", conf, "--frames", str(a.frames), "--threads", "1", "--out", runs[0][1]]
    if subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode != 0:
        sys.exit(f"{conf}: viewcloth failed ({' '.join(cmd)})")
    if a.arcsim:
        out = os.path.abspath(os.path.join(a.out, "arcsim"))
        env = dict(os.environ, OMP_NUM_THREADS="1")
        cwd = os.path.dirname(os.path.dirname(os.path.abspath(a.arcsim)))
        r = subprocess.run([a.arcsim, "simulateoffline", conf, out], cwd=cwd, env=env,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if r.returncode != 0 and not os.path.exists(os.path.join(out, "%04d_00.obj" % a.frames)):
            sys.exit(f"{conf}: ARCSim failed")
        runs.append(("ARCSim", out, "%04d_00.obj"))
    uv = np.zeros((len(idx), 2))
    for (i, j), k in idx.items():
        uv[k] = (i / N, j / N)
    faces = np.array([[int(t.split("/")[0]) - 1 for t in line.split()[1:]] for line in open(mesh) if line.startswith("f ")])
    print("| frame | " + " | ".join(f"{name} mean / top" for name, _, _ in runs) + " |")
    print("|---|" + "---|" * len(runs))
    for f in range(a.first, a.frames + 1):
        cells = []
        for _, d, pattern in runs:
            path = os.path.join(d, pattern % f)
            cells.append("%.4f / %.4f" % stretch(positions(path), faces, uv) if os.path.exists(path) else "—")
        print(f"| {f} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
