#!/usr/bin/env bash
# Jittered repeats (issue 18): every stress scene run from its initial positions moved by
# independent seeded jitters (`simulate --jitter-seed N`, 1 µm by default), and per scene a table
# row: runs completed, the largest crossing counts (cloth–cloth, cloth–obstacle) of any frame of
# any run, the largest principal strain, and the retried steps (sum, and the most in one run).
# One failed run or one crossing in ten is a failure of the scene.
#
#   bench/jitter.sh BIN OUT_ROOT > jitter.md
#
# Environment: SEEDS (default 10: seeds 1..SEEDS), FRAMES (default: each scene's own),
# JITTER (metres, default: the simulator's 1e-6), THREADS per run (default 1), JOBS (runs at
# once, default 1), SCENES (default: scenes/stress/*.json). A run that fails leaves its stderr in
# OUT_ROOT/<scene>/<seed>.err.
set -uo pipefail
bin=$(realpath "$1"); root=$(realpath -m "$2")
cd "$(dirname "$0")/.."
seeds=${SEEDS:-10}; threads=${THREADS:-1}; jobs=${JOBS:-1}
scenes=${SCENES:-$(ls scenes/stress/*.json)}
mkdir -p "$root"
one() { # scene seed
  local name; name=$(basename "$1" .json)
  local out="$root/$name/$2"
  rm -rf "$out"; mkdir -p "$root/$name"
  local extra=()
  [ -n "${FRAMES:-}" ] && extra+=(--frames "$FRAMES")
  [ -n "${JITTER:-}" ] && extra+=(--jitter "$JITTER")
  "$bin" simulate "$1" --jitter-seed "$2" "${extra[@]}" --out "$out" --threads "$threads" --quiet \
    --export-obstacles >/dev/null 2>"$root/$name/$2.err" || true
}
export -f one; export bin root threads FRAMES JITTER
for s in $scenes; do for k in $(seq 1 "$seeds"); do echo "$s $k"; done; done |
  xargs -P "$jobs" -n 2 bash -c 'one "$0" "$1"'
python3 - "$root" "$seeds" $scenes <<'PY'
import json, os, sys
root, seeds, scenes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print(f"| scene | completed | max crossings self / obstacle | max strain | retries (sum / max per run) | wall s (mean) |")
print("|---|---|---|---|---|---|")
for s in scenes:
    name = os.path.basename(s)[:-5]
    done, cs, co, strain, retries, walls, failed = 0, 0, 0, 0.0, [], [], []
    for k in range(1, seeds + 1):
        try:
            st = json.load(open(os.path.join(root, name, str(k), "stats.json")))
        except (OSError, ValueError):
            failed.append(k)
            continue
        fr = st["frames"]
        if st.get("error") is None:
            done += 1
        else:
            failed.append(k)
        cs = max(cs, max(f.get("crossings_self", 0) for f in fr))
        co = max(co, max(f.get("crossings_obstacle", 0) for f in fr))
        strain = max(strain, max(f["max_strain"] for f in fr))
        retries.append(st.get("retries", 0))
        walls.append(st["total_wall_s"])
    why = f" (failed: seeds {', '.join(map(str, failed))})" if failed else ""
    wall = sum(walls) / len(walls) if walls else 0
    print(f"| {name} | {done}/{seeds}{why} | {cs} / {co} | {strain:.3f} | {sum(retries)} / {max(retries, default=0)} | {wall:.1f} |")
PY
