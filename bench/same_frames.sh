#!/usr/bin/env bash
# Same frames, and where the time went, before and after a change that must not change results
# (issue 17's optimisations): each case is run with BEFORE and with NOW, one thread, one after
# the other; every written frame is compared byte for byte and the proximity and collision stage
# seconds (stats.json "stage_s") and run wall time are printed, before -> now.
#
# Usage: bench/same_frames.sh BEFORE_BIN NOW_BIN OUT
#   ARCSIM_SRC (optional): an ARCSim source tree (conf/, meshes/) for the ARCSim flag.json row.
set -uo pipefail
[ $# -eq 3 ] || { sed -n 2,9p "$0"; exit 2; }
before=$(realpath "$1"); now=$(realpath "$2"); out=$(realpath -m "$3")
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
cases=(
  "sheet_on_sphere|$root/scenes/sheet_on_sphere.json --mode adaptive --frames 12"
  "crumple_square|$root/scenes/crumple_square.json --frames 30"
  "tablecloth_pull|$root/scenes/tablecloth_pull.json --frames 12"
  "sheet_fold|$root/scenes/sheet_fold.json --frames 20"
  "twist|$root/scenes/stress/twist.json --frames 10"
  "pinch|$root/scenes/stress/pinch.json --frames 25"
  "crush|$root/scenes/stress/crush.json --frames 20"
  "skirt_walk|$root/scenes/skirt_walk.json --mode view --frames 10"
  "crowd_5|$root/scenes/crowd_5.json --mode view --frames 6"
  "dress_dance|$root/scenes/dress_dance.json --mode view --frames 20"
)
if [ -n "${ARCSIM_SRC:-}" ]; then cases+=("flag|$ARCSIM_SRC/conf/flag.json --frames 12"); fi
for c in "${cases[@]}"; do
  name=${c%%|*}; args=${c#*|}
  for tag in before now; do
    bin=$before; [ $tag = now ] && bin=$now
    rm -rf "$out/$name.$tag"
    # ARCSim confs name their meshes relative to the ARCSim tree.
    (cd "${ARCSIM_SRC:-$root}" && $bin simulate $args --threads 1 --quiet --out "$out/$name.$tag" > "$out/$name.$tag.log" 2>&1)
  done
  n=0; d=0
  for f in "$out/$name.before"/frame_*.obj; do
    n=$((n + 1)); cmp -s "$f" "$out/$name.now/$(basename "$f")" || d=$((d + 1))
  done
  python3 - "$out" "$name" "$n" "$d" <<'PY'
import json, sys
out, name, n, d = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
row = []
for tag in ("before", "now"):
    frames = json.load(open(f"{out}/{name}.{tag}/stats.json"))["frames"]
    stage = {}
    for f in frames:
        for k, v in f.get("stage_s", {}).items():
            stage[k] = stage.get(k, 0.0) + v
    row.append((stage.get("proximity", 0.0), stage.get("collision", 0.0), sum(f["wall_s"] for f in frames)))
(p0, c0, w0), (p1, c1, w1) = row
print(f"{name}: {n} frames, {d} differing; proximity {p0:.2f} -> {p1:.2f} s, collision {c0:.2f} -> {c1:.2f} s, run {w0:.2f} -> {w1:.2f} s")
PY
done
