#!/bin/sh
# Issue 19's film shots in view and adaptive mode, one thread: per run the wall time per frame
# and the faces per frame (mean and at sampled frames), from stats.json.
# The bars (error against time, with the uniform reference): bench/shots.sh.
#   bench/shots_speed.sh BIN OUT_ROOT [FRAMES]   (FRAMES: all of each shot's when absent)
#   SHOTS="flag_closeup skirt_walk" MODES=view bench/shots_speed.sh …
# dress_dance and crowd_5 need ARCSim's data in ../shared/arcsim beside the repository.
set -eu
BIN=$1 OUT=$2 FRAMES=${3:-}
SHOTS=${SHOTS:-"sheet_drape flag_closeup skirt_walk dress_dance crowd_5"}
MODES=${MODES:-"view adaptive"}
for shot in $SHOTS; do
  for mode in $MODES; do
    dir=$OUT/$shot-$mode
    set -- "$BIN" simulate "scenes/$shot.json" --threads 1 --mode "$mode" --out "$dir" --force --quiet
    [ -n "$FRAMES" ] && set -- "$@" --frames "$FRAMES"
    "$@"
    python3 - "$dir/stats.json" "$shot" "$mode" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
fr = [f for f in d["frames"] if f["frame"] > 0]
n = len(fr)
wall = sum(f["wall_s"] for f in fr) / n
faces = sum(f["faces"] for f in fr) / n
picks = sorted({fr[0]["frame"], fr[n // 3]["frame"], fr[2 * n // 3]["frame"], fr[-1]["frame"]})
at = ", ".join(f'{f["frame"]}: {f["wall_s"]:.2f} s {f["faces"]} faces' for f in fr if f["frame"] in picks)
print(f"{sys.argv[2]:13} {sys.argv[3]:9} {n:3} frames  {wall:6.2f} s/frame  {faces:7.0f} faces/frame  ({at})")
PY
  done
done
