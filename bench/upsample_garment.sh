#!/usr/bin/env bash
# Issue 13 on a garment with mid-scale wrinkles: the A-line denim skirt on the walking capsule
# mannequin (scenes/skirt_mannequin.json), coarse 32 × 11 (384 nodes, 704 faces) and fine
# 64 × 22 (1472 nodes, 2816 faces: the shipped mesh), both written by examples/make_skirt.rs.
# Both pairs are tracked runs (`upsample trace`, T = 60, its default), the model trained with
# `--cross-validate` (prior and γ chosen on the training frames only). Two held-out tests:
#   1. window: trained on frames 0–60 of the walk, tested on frames 61–92 of the same run;
#   2. faster walk: trained on all of the walk, tested on the same gait played 1.25× faster
#      (every motion key at 0.8 × its time: other speeds, other wrinkles).
# For each it prints, against the tracked fine run: the upsampled mesh, Loop subdivision of the
# coarse run (one level: 2816 faces, the fine mesh's count) and the coarse mesh itself — mean
# surface distance and mean distance between points of equal material coordinates
# (examples/upsample_heldout.rs), in mm; then the same for the walk model on its own training
# frames (in sample: what U can fit, not what it predicts), and each traced run's crossings and
# penetrations from its stats.json (the tracking projection is not collision-checked).
#
#     bench/upsample_garment.sh [OUT_DIR]        (default: /tmp/viewcloth_upsample_garment)
#
# One thread, one process at a time; the two traced pairs take 100 and 80 s here, training
# (cross-validation included) 15 s each. A traced pair already in OUT_DIR that finished is reused.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-/tmp/viewcloth_upsample_garment}
target=${CARGO_TARGET_DIR:-target}
bin=$target/release/viewcloth
cargo build --release -j 1 --bin viewcloth --example make_skirt --example upsample_heldout >/dev/null 2>&1 \
  || cargo build --release -j 1 --bin viewcloth --example make_skirt --example upsample_heldout
mkdir -p "$out"
"$target/release/examples/make_skirt" "$out/coarse_mesh" --around 32 --down 11 >/dev/null
"$target/release/examples/make_skirt" "$out/fine_mesh" >/dev/null
python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
for d in ("coarse_mesh", "fine_mesh"):
    s = json.load(open(f"{out}/{d}/skirt_mannequin.json"))
    s["name"] = "skirt_fast"
    s["end_time"] = round(0.8 * s["end_time"], 4)
    for o in s["obstacles"]:
        for k in o["motion"]:
            k["time"] = round(0.8 * k["time"], 4)
    json.dump(s, open(f"{out}/{d}/skirt_fast.json", "w"), indent=1)
PY
trace() {
  [ -f "$out/$1/fine/stats.json" ] && python3 -c "import json,sys; sys.exit(json.load(open('$out/$1/fine/stats.json')).get('error') is not None)" \
    && [ "$(ls "$out/$1/fine" | grep -c '^frame_')" -gt 1 ] && return 0
  /usr/bin/time -f "trace $1: %e s" "$bin" upsample trace "$out/coarse_mesh/$2" "$out/fine_mesh/$2" --threads 1 --out "$out/$1"
}
trace walk skirt_mannequin.json
trace fast skirt_fast.json
last=$(ls "$out/walk/coarse" | grep '^frame_' | sed -E 's/frame_0*([0-9]+)\.obj/\1/' | sort -n | tail -1)
split=60
# Training set of the window test: frames 0..split of the walk.
for r in coarse fine; do
  mkdir -p "$out/walk_early/$r"
  for k in $(seq 0 $split); do cp "$out/walk/$r/$(printf 'frame_%04d.obj' "$k")" "$out/walk_early/$r/"; done
done
train() {
  /usr/bin/time -f "train $1: %e s" "$bin" upsample train --coarse "$out/$1/coarse" --fine "$out/$1/fine" \
    --cross-validate --out "$out/$1.bin" >"$out/$1.cv.txt"
  echo "$1: $(sed -n 4p "$out/$1.cv.txt") (best of $(grep -c '^| \(zero\|barycentric\) |' "$out/$1.cv.txt"))"
  grep '^barycentric embedding' "$out/$1.cv.txt"
  tail -1 "$out/$1.cv.txt"
}
train walk_early
train walk
measure() { # name model coarse_dir fine_dir frames
  "$bin" upsample apply "$out/$2.bin" --coarse "$3" --out "$out/$1/upsampled" >/dev/null
  "$bin" upsample loop --coarse "$3" --model "$out/$2.bin" --out "$out/$1/loop" >/dev/null
  "$target/release/examples/upsample_heldout" "$4" --frames "$5" \
    upsampled="$out/$1/upsampled" loop="$out/$1/loop" coarse="$3"
}
echo
echo "Held out 1 — frames $((split + 1))..$last of the walk, model trained on frames 0..$split:"
measure window walk_early "$out/walk/coarse" "$out/walk/fine" "$((split + 1))..$last"
flast=$(ls "$out/fast/coarse" | grep '^frame_' | sed -E 's/frame_0*([0-9]+)\.obj/\1/' | sort -n | tail -1)
echo
echo "Held out 2 — the walk 1.25× faster, frames 1..$flast, model trained on all $((last + 1)) frames of the walk:"
measure faster walk "$out/fast/coarse" "$out/fast/fine" "1..$flast"
echo
echo "In sample — the walk model on its own training frames 1..$last:"
measure in_sample walk "$out/walk/coarse" "$out/walk/fine" "1..$last"
echo
echo "| traced run | frames | frames with crossings | most self / obstacle crossing pairs | most penetrating nodes | retries | own wall (s) |"
echo "|---|---|---|---|---|---|---|"
for run in walk fast; do
  for r in coarse fine; do
    python3 - "$out/$run/$r/stats.json" "$run $r" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
f = s["frames"]
crossed = sum(1 for x in f if x["crossings_self"] + x["crossings_obstacle"] > 0)
print(f"| {sys.argv[2]} | {len(f)} | {crossed} | {max(x['crossings_self'] for x in f)} / {max(x['crossings_obstacle'] for x in f)} | "
      f"{max(x.get('penetrations', 0) for x in f)} | {s['retries']} | {sum(x['wall_s'] for x in f):.1f} |")
PY
  done
done
