#!/usr/bin/env bash
# Retried steps per scene (issue 18's bar: under 2% of the steps on every shipped scene, on the
# uniform `sheet_on_sphere` reference and on ARCSim's sphere, square, flag and dress-blue).
#
#   bench/retries.sh BIN OUT_ROOT                       # every run below
#   RUNS="hanging_sheet arcsim:square:325" bench/retries.sh BIN OUT_ROOT
#
# A run is a shipped scene's stem (scenes/<stem>.json, its own frame count), `reference` (the
# uniform sheet_on_sphere reference compare makes: --mode uniform, 40 frames) or
# `arcsim:<conf>:<frames>` (../shared/arcsim/conf/<conf>.json). One thread each, so that the wall
# times of two binaries run one after the other compare. Prints a Markdown table (also in
# OUT_ROOT/retries.md): steps taken, retries and their share, the steps whose friction iteration
# ended unconverged, the factorisations friction added, and the wall time.
set -euo pipefail
BIN=${1:?usage: bench/retries.sh BIN OUT_ROOT}
OUT=${2:?usage: bench/retries.sh BIN OUT_ROOT}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
ARCSIM=$ROOT/../shared/arcsim
DEFAULT="crumple_square drape_stiff flag_wind hanging_sheet sheet_fold sheet_on_sphere skirt_mannequin tablecloth_pull reference arcsim:square:325 arcsim:flag:23 arcsim:sphere:70 arcsim:dress-blue:60"
RUNS=${RUNS:-$DEFAULT}
mkdir -p "$OUT"
table=$OUT/retries.md
printf '| run | frames | steps | retries | share | friction unconverged | friction refactorisations | wall s |\n|---|---:|---:|---:|---:|---:|---:|---:|\n' > "$table"
for run in $RUNS; do
    dir=$OUT/${run//:/_}
    case $run in
        reference) args=("$ROOT/scenes/sheet_on_sphere.json" --mode uniform --frames 40) ;;
        arcsim:*)
            IFS=: read -r _ conf frames <<< "$run"
            if [ ! -f "$ARCSIM/conf/$conf.json" ]; then
                echo "SKIP $run: $ARCSIM/conf/$conf.json not found" >&2
                continue
            fi
            args=("$ARCSIM/conf/$conf.json" --frames "$frames") ;;
        *) args=("$ROOT/scenes/$run.json") ;;
    esac
    if ! "$BIN" simulate "${args[@]}" --threads 1 --quiet --force --out "$dir" 2> "$dir.err"; then
        echo "| $run | failed: $(tail -1 "$dir.err") | | | | | | |" >> "$table"
        continue
    fi
    python3 - "$dir/stats.json" "$run" >> "$table" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
fr = s["frames"]
steps = sum(f.get("steps", 0) for f in fr)
retries = s.get("retries", 0)
unconv = sum(f.get("friction_unconverged", 0) for f in fr)
refac = sum(f.get("friction_refactors", 0) for f in fr)
share = 100.0 * retries / steps if steps else 0.0
print(f"| {sys.argv[2]} | {len(fr) - 1} | {steps} | {retries} | {share:.1f}% | {unconv} | {refac} | {s['total_wall_s']:.1f} |")
EOF
done
cat "$table"
