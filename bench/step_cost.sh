#!/usr/bin/env bash
# Step cost beside ARCSim (issue 17): ARCSim 0.2.1, a viewcloth binary before a change and one
# after it, run one after the other on the same ARCSim conf, alternating, ROUNDS times; prints
# each process's wall time and writes the runs under OUT.
#
# Usage: bench/step_cost.sh ARCSIM_SRC BEFORE_BIN NOW_BIN OUT [CONF] [FRAMES]
#   ARCSIM_SRC  the src/ of ../shared/tools/arcsim-build.sh's build (has bin/arcsim and conf/)
#   CONF        a conf name in ../shared/arcsim/conf (default square); FRAMES default: all
#   THREADS (default 2) threads each; ROUNDS (default 2).
# Stage sums: python3 over OUT/*/stats.json, "stage_s" (viewcloth); OUT/arcsim-*/timing (ARCSim).
set -euo pipefail
[ $# -ge 4 ] || { sed -n 2,11p "$0"; exit 2; }
arcsim=$(cd "$1" && pwd); before=$(realpath "$2"); now=$(realpath "$3"); out=$(realpath -m "$4")
conf=${5:-square}; frames=${6:-}
threads=${THREADS:-2}; rounds=${ROUNDS:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
wall() { local s e; s=$(date +%s.%N); "$@" >/dev/null 2>&1 || echo "(failed: $*)" >&2; e=$(date +%s.%N); echo "$e - $s" | bc; }
arcsim_run() {
  cd "$arcsim"
  if [ -z "$frames" ]; then
    OMP_NUM_THREADS=$threads ./bin/arcsim simulateoffline "conf/$conf.json" "$1"
  else
    # Stop ARCSim once frame FRAMES is written (the conf is run as shipped; a copy with
    # "end_frame": FRAMES added, which ARCSim honours, would stop it too).
    OMP_NUM_THREADS=$threads ./bin/arcsim simulateoffline "conf/$conf.json" "$1" &
    local pid=$!
    while kill -0 $pid 2>/dev/null; do
      [ -e "$1/$(printf %04d $((frames + 1)))_00.obj" ] && { kill $pid; break; }
      sleep 0.2
    done
    wait $pid || true
  fi
}
flags=(--threads "$threads" --force --quiet)
[ -n "$frames" ] && flags+=(--frames "$frames")
for r in $(seq 1 "$rounds"); do
  echo "$conf round $r: ARCSim $(wall arcsim_run "$out/arcsim-$r") s"
  echo "$conf round $r: before $(wall "$before" simulate "$here/../shared/arcsim/conf/$conf.json" --out "$out/before-$r" "${flags[@]}") s"
  echo "$conf round $r: now $(wall "$now" simulate "$here/../shared/arcsim/conf/$conf.json" --out "$out/now-$r" "${flags[@]}") s"
done
