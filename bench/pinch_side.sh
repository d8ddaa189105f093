#!/bin/bash
# Pinches during the run (issue 16, README "Pinches during the run"): two viewcloth binaries
# one after the other, one thread each, on the scenes where obstacles close on cloth and on
# dress_dance (where they do not), with the obstacles exported; prints each run's frames,
# largest strain after frame 10, retried attempts, crossings and wall time from its stats.json.
#
#   bench/pinch_side.sh BEFORE_BIN AFTER_BIN OUT_DIR ARCSIM_CONF_DIR
set -euo pipefail
[ $# -eq 4 ] || { echo "usage: $0 BEFORE_BIN AFTER_BIN OUT_DIR ARCSIM_CONF_DIR" >&2; exit 2; }
before=$1 after=$2 out=$3 confs=$4
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
for run in "crush2:$confs/crush2.json:50" "crush:$confs/crush.json:50" \
    "pinch:$here/scenes/stress/pinch.json:25" "dance:$here/scenes/dress_dance.json:12"; do
  IFS=: read -r name scene frames <<< "$run"
  for which in before after; do
    bin=$before; [ "$which" = after ] && bin=$after
    dir="$out/${name}_$which"; rm -rf "$dir"
    "$bin" simulate "$scene" --frames "$frames" --threads 1 --export-obstacles --out "$dir" --quiet \
      2> "$dir.err" || echo "$name $which: $(grep -o 'error: .*' "$dir.err" | head -1)"
    python3 - "$dir" "$name $which" <<'PY'
import json, sys
fr = json.load(open(sys.argv[1] + "/stats.json"))["frames"]
late = [f["max_strain"] for f in fr[11:]] or [0.0]
tried = sum(f["steps"] + f["retries"] for f in fr)
print(f"{sys.argv[2]}: {len(fr) - 1} frames, strain after f10 {max(late):.3f}, "
      f"{sum(f['retries'] for f in fr)} of {tried} attempts retried, "
      f"self crossings max {max(f['crossings_self'] for f in fr)}, "
      f"obstacle crossings max {max(f['crossings_obstacle'] for f in fr[1:])}, "
      f"{sum(f['wall_s'] for f in fr):.1f} s")
PY
  done
done
