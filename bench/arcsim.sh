#!/usr/bin/env bash
# Side-by-side benchmark against ARCSim (issue 6). Runs ARCSim's own scene files from
# ../shared/arcsim through `viewcloth simulate` (read directly, no conversion step) and reports per
# scene: wall time per frame (mean, median), faces over time, the minimum cloth–obstacle
# clearance (measured from the written frames and obstacle meshes) and penetrations, next to
# ARCSim 0.2.1's figures from ../shared/arcsim/README.md (measured on this machine kind).
#
#   bench/arcsim.sh                      # all four scenes
#   SCENES="sphere:60 square:325" bench/arcsim.sh
#   ARCSIM=/path/to/arcsim OUT=/tmp/bench bench/arcsim.sh
#
# Frame counts as in the README: square 325 (complete), flag 23, dress-blue 100, sphere 185. Times
# are compared over the same frames as each ARCSim row: sphere's first 60 (quiet machine) and 185
# (busy machine), dress-blue's first 60 and 100.
# Results: $OUT/<scene>/{stats.json,report.json}, $OUT/summary.md.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
ARCSIM=${ARCSIM:-$ROOT/../shared/arcsim}
OUT=${OUT:-$ROOT/target/bench-arcsim}
SCENES=${SCENES:-"sphere:185 square:325 flag:23 dress-blue:100"}
if [ ! -d "$ARCSIM/conf" ]; then
    echo "SKIP: ARCSim data not found at $ARCSIM" >&2
    exit 0
fi
cd "$ROOT"
cargo build --release --quiet --bin viewcloth --example arcsim_report
BIN=$ROOT/target/release/viewcloth
REPORT=$ROOT/target/release/examples/arcsim_report
mkdir -p "$OUT"

# ARCSim's figures (README of ../shared/arcsim): faces over time, s/frame mean / median.
arcsim_ref() {
    case $1 in
        sphere) echo "128 → 2977 (f40) → 6555 (f60) → 1606 (f90) → 14089 (f185)|first 60: 1.42 / 1.03 (quiet); 185: 3.2 / 1.7 (busy)|0.6–3.6 mm (0.1006–0.1036 m from the centre)" ;;
        square) echo "128 → 474 (squeezed) → 130|0.19|–" ;;
        flag) echo "118 → 20122 (f20)|23|–" ;;
        dress-blue) echo "3197 → 9928 (f60) → 7341 (f100), max 9984|first 60: 6.1 / 5.5 (quiet); 100: 5.9 / 5.5|–" ;;
    esac
}
# Spans (first N frames) timed separately, matching ARCSim's rows.
spans() {
    case $1 in
        sphere) echo "60,185" ;;
        dress-blue) echo "60,100" ;;
        *) echo "" ;;
    esac
}
marks() {
    case $1 in
        sphere) echo "0,1,20,40,60,90,185" ;;
        square) echo "0,1,25,100,150,175,250,300,325" ;;
        flag) echo "0,1,10,20,23" ;;
        dress-blue) echo "0,1,20,60,100" ;;
    esac
}

SUMMARY=$OUT/summary.md
STAGES=$OUT/stages.md
echo "| scene | where viewcloth's time goes (stats.json stage_s, share of the run) |" > "$STAGES"
echo "|---|---|" >> "$STAGES"
{
    echo "| scene | frames | viewcloth s/frame mean / median | ARCSim s/frame | viewcloth faces | ARCSim faces | min clearance (m) | penetrations |"
    echo "|---|---|---|---|---|---|---|---|"
} > "$SUMMARY"
for spec in $SCENES; do
    scene=${spec%%:*}
    frames=${spec##*:}
    dir=$OUT/$scene
    rm -rf "$dir"
    echo "== $scene ($frames frames)" >&2
    status=0
    "$BIN" simulate "$ARCSIM/conf/$scene.json" --frames "$frames" --out "$dir" --quiet --export-obstacles || status=$?
    [ $status -eq 0 ] || echo "   viewcloth stopped with exit code $status (see $dir/stats.json)" >&2
    "$REPORT" "$dir" "$(marks "$scene")" "$(spans "$scene")" > "$dir/report.json"
    IFS='|' read -r ref_faces ref_time ref_clear <<< "$(arcsim_ref "$scene")"
    python3 - "$dir/report.json" "$scene" "$ref_faces" "$ref_time" "$ref_clear" "$STAGES" >> "$SUMMARY" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
scene, ref_faces, ref_time, ref_clear, stages = sys.argv[2:7]
faces = " → ".join(f"{v} (f{k})" for k, v in r["faces_at"].items())
clear = "–" if r["min_clearance_m"] is None else f'{r["min_clearance_m"]:.2e} (f{r["min_clearance_frame"]})'
note = "" if r["error"] is None else " (stopped early)"
times = f'{r["mean_s"]:.3f} / {r["median_s"]:.3f}'
if r["spans"]:
    times = "; ".join(f'{n}: {s["mean_s"]:.3f} / {s["median_s"]:.3f}' for n, s in r["spans"].items())
print(f'| {scene} | {r["frames"]}{note} | {times} | {ref_time} | {faces}, max {r["max_faces"]} | '
      f'{ref_faces} | {clear} (ARCSim: {ref_clear}) | {r["penetrations"]} |')
top = sorted(r["stage_s"].items(), key=lambda kv: -kv[1])[:7]
total = sum(r["stage_s"].values()) or 1
with open(stages, "a") as f:
    f.write(f"| {scene} | " + ", ".join(f"{k} {100 * v / total:.0f}%" for k, v in top) + " |\n")
PY
done
echo >> "$SUMMARY"
cat "$STAGES" >> "$SUMMARY"
cat "$SUMMARY"
