#!/usr/bin/env bash
# Digest of a set of runs' outputs, without timings: for refactors that must not change results.
#
#   bench/digest.sh BIN OUT_ROOT > digest.txt      # then diff two digests
#
# Runs BIN (a viewcloth binary) on every shipped scene, the view shot, and ARCSim's sphere and
# square (../shared/arcsim), a few frames each, with checkpoints and exported obstacles, then
# prints one line per output file: its SHA-256, where stats.json has its timings (wall_s,
# stage_s, total_wall_s) removed and a checkpoint is hashed without its statistics (they carry
# timings) and without the absolute scene and camera paths (they name the checkout).
set -euo pipefail
bin=$(realpath "$1"); root=$2
cd "$(dirname "$0")/.."
shared=../shared/arcsim
mkdir -p "$root"
run() { # name frames args...
  local name=$1 frames=$2; shift 2
  rm -rf "$root/$name"
  "$bin" simulate "$@" --frames "$frames" --out "$root/$name" --quiet --export-obstacles \
    --checkpoint-every 5 --threads 2 >/dev/null 2>"$root/$name.err" || echo "run $name failed: $(cat "$root/$name.err")" >&2
}
for s in scenes/*.json; do run "$(basename "$s" .json)" 12 "$s"; done
for s in scenes/stress/*.json; do run "stress_$(basename "$s" .json)" 6 "$s"; done
run default 8
run sphere_view 12 scenes/sheet_on_sphere.json --camera cameras/sheet_on_sphere_pan.json
run arcsim_sphere 60 "$shared/conf/sphere.json"
run arcsim_square 40 "$shared/conf/square.json"
python3 - "$root" <<'PY'
import hashlib, json, os, sys
root = sys.argv[1]
def checkpoint_state(b):
    # Everything from the format version up to the statistics, less the run record's absolute
    # scene and camera paths (they name the checkout): see src/sim/checkpoint.rs.
    u64 = lambda o: int.from_bytes(b[o:o + 8], "little")
    o = 8 + 4
    o += 8 + u64(o)                      # writer's version
    keep = b[8:o]
    for tag_then_path in (True, False, True):
        tag = b[o]; o += 1
        keep += bytes([tag])
        if tag_then_path and tag == 1:
            o += 8 + u64(o)              # scene / camera path
    end = b.rfind(b'{"scene"') - 8
    return keep + b[o:end]
def strip(o):
    if isinstance(o, dict):
        return {k: strip(v) for k, v in o.items() if k not in ("wall_s", "stage_s", "total_wall_s")}
    if isinstance(o, list):
        return [strip(v) for v in o]
    return o
for run in sorted(os.listdir(root)):
    d = os.path.join(root, run)
    if not os.path.isdir(d):
        continue
    for f in sorted(os.listdir(d)):
        b = open(os.path.join(d, f), "rb").read()
        if f == "stats.json":
            b = json.dumps(strip(json.loads(b)), sort_keys=True).encode()
        elif f.startswith("checkpoint_"):
            b = checkpoint_state(b)
        print(hashlib.sha256(b).hexdigest()[:16], run + "/" + f)
PY
