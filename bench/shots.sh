#!/usr/bin/env bash
# Issue 19's bars on the film shots: each shot run uniform (the reference), adaptive and view,
# one after the other with the same thread count, compared from the shot camera.
#
#   bench/shots.sh BIN OUT_ROOT                         # every shot, its own length
#   SHOTS="skirt_walk dress_dance" FRAMES=25 THREADS=1 bench/shots.sh BIN OUT_ROOT
#
# A shot is scenes/<name>.json with its camera. Runs `viewcloth compare --no-floor` per shot
# (the chaos floor would add three more uniform runs; pass FLOOR=1 to run it) and prints a
# Markdown table (also OUT_ROOT/shots.md): wall time and mean faces of each mode, the speed-ups
# view/adaptive and view/uniform, and the visible errors (shading normal, silhouette, distance
# on the visible cloth) of view against adaptive. Each shot's full report is in
# OUT_ROOT/<shot>/compare.md.
set -euo pipefail
BIN=${1:?usage: bench/shots.sh BIN OUT_ROOT}
OUT=${2:?usage: bench/shots.sh BIN OUT_ROOT}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SHOTS=${SHOTS:-"dress_dance skirt_walk crowd_5 flag_closeup sheet_drape"}
THREADS=${THREADS:-1}
mkdir -p "$OUT"
table=$OUT/shots.md
printf '| shot | frames | wall s uniform / adaptive / view | faces uniform / adaptive / view | view speed-up vs adaptive / uniform | visible error view ÷ adaptive: normal, silhouette, distance |\n|---|---:|---|---|---|---|\n' > "$table"
for shot in $SHOTS; do
    scene=$ROOT/scenes/$shot.json
    if [ ! -f "$scene" ]; then
        echo "SKIP $shot: $scene not found" >&2
        continue
    fi
    args=("$scene" --modes adaptive,view --threads "$THREADS" --quiet --out "$OUT/$shot")
    [ -n "${FRAMES:-}" ] && args+=(--frames "$FRAMES")
    [ -z "${FLOOR:-}" ] && args+=(--no-floor)
    rm -rf "${OUT:?}/$shot"
    if ! "$BIN" compare "${args[@]}" > "$OUT/$shot.log" 2>&1; then
        echo "| $shot | failed: $(tail -1 "$OUT/$shot.log") | | | | |" >> "$table"
        continue
    fi
    python3 - "$OUT/$shot/compare.json" "$shot" >> "$table" <<'EOF'
import json, sys
c = json.load(open(sys.argv[1]))
runs = {m["name"]: m for m in c["modes"]}
ref, ada, view = c["reference"], runs["adaptive"], runs["view"]
def err(m):
    e = m["errors"]
    return e["visible"]["normal_deg"], e["visible"]["silhouette"], e["geometric_visible"]["mean"]
ea, ev = err(ada), err(view)
ratio = lambda a, b: f"{a / b:.2f}" if b > 0 else "–"
print(f"| {sys.argv[2]} | {c['frames']} "
      f"| {ref['wall_s']:.1f} / {ada['wall_s']:.1f} / {view['wall_s']:.1f} "
      f"| {ref['mean_faces']:.0f} / {ada['mean_faces']:.0f} / {view['mean_faces']:.0f} "
      f"| {ada['wall_s'] / view['wall_s']:.2f}× / {ref['wall_s'] / view['wall_s']:.2f}× "
      f"| {ratio(ev[0], ea[0])}, {ratio(ev[1], ea[1])}, {ratio(ev[2], ea[2])} "
      f"({ev[0]:.2f}° vs {ea[0]:.2f}°; {ev[2] * 1e3:.1f} vs {ea[2] * 1e3:.1f} mm) |")
EOF
done
cat "$table"
