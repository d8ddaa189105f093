#!/usr/bin/env python3
"""When the sheet of ARCSim's sphere.json slides off the sphere (issue 18's bar: within ±5 frames
of ARCSim's), measured from the written frames alone, for a viewcloth run and an ARCSim run alike.

Per frame: the cloth area (cm²) whose face centroids lie within 1 cm of the sphere's surface
(radius 0.1 m). The slide-off frame is the first frame after the contact peak where that area falls
below 50 cm² (ARCSim: 477 cm² at frame 60, 10 at 62).

  bench/sphere_slide_off.py RUN_DIR                 # viewcloth run made with --export-obstacles
  bench/sphere_slide_off.py ARCSIM_OUT --arcsim     # ARCSim's simulateoffline output directory
  ... [--from F] [--table]

viewcloth frames are frame_NNNN.obj with the sphere in obstacle_<name>_NNNN.obj (its centre: the
mean of its vertices); ARCSim's are NNNN_00.obj with the sphere's transform in NNNNobs00.txt.
Exit 1 with one line when a directory holds neither.
"""
import math
import os
import re
import sys

RADIUS, BAND, OFF_CM2 = 0.1, 0.01, 50.0


def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                vs.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("f "):
                fs.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    return vs, fs


def ours(run, frame):
    cloth = os.path.join(run, "frame_%04d.obj" % frame)
    obstacles = sorted(n for n in os.listdir(run) if n.startswith("obstacle_") and n.endswith("_%04d.obj" % frame))
    if not os.path.exists(cloth) or not obstacles:
        return None
    vs, _ = read_obj(os.path.join(run, obstacles[0]))
    centre = tuple(sum(v[i] for v in vs) / len(vs) for i in range(3))
    return cloth, centre


def arcsim(run, frame):
    cloth = os.path.join(run, "%04d_00.obj" % frame)
    xf = os.path.join(run, "%04dobs00.txt" % frame)
    if not os.path.exists(cloth) or not os.path.exists(xf):
        return None
    m = re.search(r'translate x="([-\d.e]+)" y="([-\d.e]+)" z="([-\d.e]+)"', open(xf).read())
    return cloth, tuple(float(v) for v in m.groups())


def near_area(cloth, centre):
    vs, fs = read_obj(cloth)
    area = 0.0
    for t in fs:
        a, b, c = (vs[i] for i in t[:3])
        g = tuple((a[i] + b[i] + c[i]) / 3 for i in range(3))
        if math.dist(g, centre) < RADIUS + BAND:
            u = [b[i] - a[i] for i in range(3)]
            w = [c[i] - a[i] for i in range(3)]
            n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
            area += 0.5 * math.sqrt(sum(x * x for x in n))
    return area * 1e4


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    if len(args) < 1:
        print(__doc__.strip().splitlines()[0], file=sys.stderr)
        return 2
    run = args[0]
    if not os.path.isdir(run):
        print(f"{run}: not a directory", file=sys.stderr)
        return 1
    start = int(argv[argv.index("--from") + 1]) if "--from" in argv else 0
    frame_of = arcsim if "--arcsim" in argv else ours
    rows, frame = [], start
    while (found := frame_of(run, frame)) is not None:
        rows.append((frame, near_area(*found)))
        frame += 1
    if not rows:
        print(f"{run}: no frames with the sphere's position from frame {start} on "
              "(a viewcloth run needs --export-obstacles)", file=sys.stderr)
        return 1
    if "--table" in argv:
        for f, a in rows:
            print(f"{f}\t{a:.0f}")
    peak = max(range(len(rows)), key=lambda i: rows[i][1])
    if rows[peak][1] < OFF_CM2:
        print(f"{run}: frames {start}–{rows[-1][0]}: never on the sphere (under {OFF_CM2:.0f} cm² near it)")
        return 0
    off = next((f for f, a in rows[peak:] if a < OFF_CM2), None)
    last = rows[-1][0]
    print(f"{run}: contact peak {rows[peak][1]:.0f} cm² at frame {rows[peak][0]}; "
          + (f"slides off at frame {off}" if off is not None else f"still on the sphere at frame {last}"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
