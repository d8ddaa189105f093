#!/usr/bin/env bash
# Issue 13: why the number of tracking test functions T is not cross-validated, on the sheet of
# tests/upsample_loop.rs (scenes/hanging_sheet.json at 6 × 6 and 24 × 24 cells, both corners
# swinging for 2 s). For each T it traces the training pair (`upsample trace`), cross-validates
# the profile on it (`upsample train --cross-validate`, training frames only) and prints the best
# validation error, the barycentric embedding's error on the same frames, and their ratio. The
# validation error falls with T because the target does (T → N makes the fine run the coarse
# surface); the ratio is the share of the fine run's departure from the coarse surface that U
# does not predict on held-out blocks.
#
#     bench/upsample_tune.sh [OUT_DIR] [T...]     (default: /tmp/viewcloth_upsample_tune, 10 20 40 60 80)
#
# One thread, one process at a time; about 10 s per T here.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/viewcloth_upsample_tune}
shift || true
ts=("$@")
[ ${#ts[@]} -eq 0 ] && ts=(10 20 40 60 80)
bin=${CARGO_TARGET_DIR:-target}/release/viewcloth
[ -x "$bin" ] || cargo build --release -j 1
mkdir -p "$out"
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
left = [{"time": 0.0, "translate": [0, 0, 0]}, {"time": 0.7, "translate": [0.25, 0.25, -0.1]},
        {"time": 1.4, "translate": [0.1, -0.25, 0.1]}, {"time": 2.0, "translate": [0, 0, 0]}]
right = [{"time": 0.0, "translate": [0, 0, 0]}, {"time": 0.7, "translate": [-0.2, -0.25, 0.1]},
         {"time": 1.4, "translate": [-0.05, 0.25, -0.1]}, {"time": 2.0, "translate": [0, 0, 0]}]
for n in (6, 24):
    s = json.load(open("scenes/hanging_sheet.json"))
    s["frames"] = 50
    c = s["cloths"][0]
    c["rectangle"]["resolution"] = [n, n]
    c["handles"] = [{"nodes": [n * (n + 1)], "motion": left}, {"nodes": [(n + 1) ** 2 - 1], "motion": right}]
    json.dump(s, open(f"{out}/train_{n}.json", "w"))
PY
echo "| T | best CV error (mm) | chosen | B p_c (mm) | ratio |"
echo "|---|---|---|---|---|"
for t in "${ts[@]}"; do
  "$bin" upsample trace "$out/train_6.json" "$out/train_24.json" --test-functions "$t" --out "$out/T$t" >/dev/null
  "$bin" upsample train --coarse "$out/T$t/coarse" --fine "$out/T$t/fine" --cross-validate --out "$out/T$t/model.bin" >"$out/T$t/cv.txt"
  best=$(sed -n 4p "$out/T$t/cv.txt")
  cv=$(echo "$best" | awk -F'|' '{gsub(/ /,"",$6); print $6}')
  chosen=$(echo "$best" | awk -F'|' '{gsub(/^ +| +$/,"",$2); gsub(/ /,"",$3); gsub(/ /,"",$4); gsub(/ /,"",$5); print $2" γ "$3".."$4" c "$5}')
  bary=$(grep "^barycentric embedding" "$out/T$t/cv.txt" | sed -E 's/.*: ([0-9.]+) mm.*/\1/')
  ratio=$(python3 -c "print(f'{$cv/$bary:.3f}')")
  echo "| $t | $cv | $chosen | $bary | $ratio |"
done
