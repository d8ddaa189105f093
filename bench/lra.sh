#!/usr/bin/env bash
# Long range attachments and strain limiting (issue 12): max and mean strain, and the share of
# the run's wall time spent in the `lra` and `strain_limit` stages, with and without them.
#
#   bench/lra.sh BIN OUT_ROOT [FRAMES]
#
# Scenes: a 1 m sheet hanging from its top edge with a soft membrane (cotton, stretching × 0.005;
# 40×40, written by this script) without / with `lra: {stretch: 0.02}`, and ARCSim's flag.json
# (../shared/arcsim, read as it is; converted to a scene to vary it) without strain limits, with
# its strain_limits [0.95, 1.05], with LRA to its pole handle, and with both; the denim skirt on
# the walking capsule mannequin (scenes/skirt_mannequin.json, waist nodes riding on the hips)
# without / with `lra: {stretch: 0.02}`. One thread.
set -euo pipefail
BIN=$(realpath "$1"); OUT=$(realpath -m "$2"); FRAMES=${3:-10}
HERE=$(cd "$(dirname "$0")/.." && pwd)
ARCSIM=$(realpath "$HERE/../shared/arcsim")
mkdir -p "$OUT/scenes"
hang() { # name, extra cloth fields
  cat > "$OUT/scenes/$1.json" <<JSON
{"version": 1, "name": "$1", "frame_time": 0.04, "steps_per_frame": 5, "frames": $FRAMES,
 "gravity": [0, 0, -9.81],
 "cloths": [{"name": "sheet", "rectangle": {"width": 1.0, "height": 1.0, "resolution": [40, 40]},
   "transform": {"rotate": [90, 1, 0, 0], "translate": [-0.5, 0, 1]},
   "material": {"preset": "cotton", "stretching_mult": 0.005},
   "handles": [{"region": {"min": [-0.01, 0.99], "max": [1.01, 1.01]}}]$2}]}
JSON
}
hang hang_soft ""
hang hang_soft_lra ', "lra": {"stretch": 0.02}'
"$BIN" convert "$ARCSIM/conf/flag.json" --out "$OUT/scenes/flag_sl.json" --base "$ARCSIM" 2>/dev/null
python3 - "$OUT/scenes" <<'PY'
import json, sys, os
d = sys.argv[1]
s = json.load(open(os.path.join(d, "flag_sl.json")))
def write(name, sl, lra):
    t = json.loads(json.dumps(s)); c = t["cloths"][0]; t["name"] = name
    if not sl: c.pop("strain_limits", None)
    if lra: c["lra"] = {"stretch": 0.05}
    json.dump(t, open(os.path.join(d, name + ".json"), "w"))
write("flag_none", False, False); write("flag_sl", True, False)
write("flag_lra", False, True); write("flag_sl_lra", True, True)
PY
python3 - "$HERE/scenes/skirt_mannequin.json" "$OUT/scenes" <<'PY'
import json, sys, os
s = json.load(open(sys.argv[1])); d = sys.argv[2]
s["cloths"][0]["mesh"] = os.path.join(os.path.dirname(sys.argv[1]), s["cloths"][0]["mesh"])
json.dump(s, open(os.path.join(d, "skirt.json"), "w"))
s["cloths"][0]["lra"] = {"stretch": 0.02}; s["name"] = "skirt_lra"
json.dump(s, open(os.path.join(d, "skirt_lra.json"), "w"))
PY
for s in ${RUNS:-hang_soft hang_soft_lra flag_none flag_sl flag_lra flag_sl_lra skirt skirt_lra}; do
  "$BIN" simulate "$OUT/scenes/$s.json" --frames "$FRAMES" --out "$OUT/$s" --threads 1 --quiet --force --progress none
done
python3 - "$OUT" <<'PY'
import json, sys, os
root = sys.argv[1]
print("| run | frames | max strain | mean strain (last frame) | faces (last) | wall s | lra share | strain_limit share | LRA max path stretch | faces at limit (last) | unconverged steps |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for s in ["hang_soft", "hang_soft_lra", "flag_none", "flag_sl", "flag_lra", "flag_sl_lra", "skirt", "skirt_lra"]:
    if not os.path.exists(os.path.join(root, s, "stats.json")):
        continue
    st = json.load(open(os.path.join(root, s, "stats.json")))
    fr = [f for f in st["frames"] if f["frame"] > 0]
    wall = sum(f["wall_s"] for f in fr)
    stage = lambda k: sum(f["stage_s"].get(k, 0.0) for f in fr)
    share = lambda k: f"{100 * stage(k) / wall:.2f}%" if any(k in f["stage_s"] for f in fr) else "–"
    lra = max((f["lra_max_stretch"] for f in fr if "lra_max_stretch" in f), default=None)
    last = fr[-1]
    print(f"| {s} | {len(fr)} | {max(f['max_strain'] for f in fr):.3f} | {last['mean_strain']:.4f} | {last['faces']} | {wall:.2f} | "
          f"{share('lra')} | {share('strain_limit')} | {'–' if lra is None else f'{lra:.4f}'} | "
          f"{last.get('strain_limit_faces', '–')} | {sum(f.get('strain_limit_unconverged', 0) for f in fr) if 'strain_limit_faces' in last else '–'} |")
PY
