#!/usr/bin/env bash
# Issue 16's bar on every ARCSim 0.2.1 conf: each runs its first FRAMES frames in viewcloth (and,
# when ARCSIM_BIN is given, in ARCSim itself, one after the other), and per conf a table row:
# frames completed, faces at frames 1, 10, 25 and FRAMES for both, crossings (viewcloth's
# stats.json: cloth–cloth / cloth–obstacle, the most at any frame), the largest principal stretch
# after frame 10 measured from the written frames (`v` against `vt`: both simulators write
# material coordinates) over all faces and over the faces farther than HANDLE_R from every
# handle node, retried steps, warnings `check` printed, and wall time.
#
#   ARCSIM_SRC=/path/to/arcsim-build/src [ARCSIM_BIN=$ARCSIM_SRC/bin/arcsim] \
#     bench/arcsim_confs.sh BIN OUT_ROOT [CONF ...] > bar.md
#
# ARCSIM_SRC is the source tree `../shared/tools/arcsim-build.sh` makes (conf/, meshes/,
# materials/). CONF names default to every conf there but karate (its .mot is absent from the
# mirror). Environment: FRAMES (default 50), TIMEOUT per run in seconds (default 1800), THREADS
# (default 1; ARCSim gets OMP_NUM_THREADS=THREADS), HANDLE_R (metres, default 0.05). ARCSim runs
# until its end_time, so it is stopped once frame FRAMES is written.
set -uo pipefail
bin=$(realpath "$1"); root=$(realpath -m "$2"); shift 2
src=${ARCSIM_SRC:?set ARCSIM_SRC to an ARCSim source tree (conf/, meshes/, materials/)}
frames=${FRAMES:-50}; limit=${TIMEOUT:-1800}; threads=${THREADS:-1}
here=$(cd "$(dirname "$0")" && pwd)
confs=("$@")
if [ ${#confs[@]} -eq 0 ]; then
  for c in "$src"/conf/*.json; do
    n=$(basename "$c" .json); [ "$n" = karate ] || confs+=("$n")
  done
fi
mkdir -p "$root"
echo "| conf | viewcloth frames | faces f1 / f10 / f25 / f$frames (viewcloth; ARCSim) | crossings | max stretch − 1 after f10, all / away from handles (viewcloth; ARCSim) | retries | warnings | wall s (viewcloth; ARCSim) |"
echo "|---|---|---|---|---|---|---|---|"
for name in "${confs[@]}"; do
  conf=$src/conf/$name.json
  out=$root/$name; arc=$root/$name.arcsim
  rm -rf "$out" "$arc"
  "$bin" check "$conf" > "$root/$name.check" 2>&1
  start=$(date +%s.%N)
  (cd "$src" && timeout "$limit" "$bin" simulate "$conf" --frames "$frames" --out "$out" --threads "$threads" \
    --quiet --export-obstacles > "$root/$name.err" 2>&1)
  ours_s=$(echo "$(date +%s.%N) - $start" | bc)
  arc_s=""
  if [ -n "${ARCSIM_BIN:-}" ]; then
    start=$(date +%s.%N)
    last=$(printf "%s/%04d_00.obj" "$arc" "$frames")
    (cd "$src" && OMP_NUM_THREADS=$threads timeout "$limit" "$ARCSIM_BIN" simulateoffline "conf/$name.json" "$arc" \
      > "$root/$name.arcsim.log" 2>&1) &
    pid=$!
    # Frame N is complete once frame N + 1 has started (or ARCSim has ended).
    next=$(printf "%s/%04d_00.obj" "$arc" "$((frames + 1))")
    while kill -0 $pid 2>/dev/null && [ ! -e "$next" ]; do sleep 1; done
    pkill -P $pid 2>/dev/null; kill $pid 2>/dev/null; wait $pid 2>/dev/null
    arc_s=$(echo "$(date +%s.%N) - $start" | bc)
    [ -e "$last" ] || arc_s="$arc_s (stopped before f$frames)"
  fi
  python3 "$here/arcsim_confs_row.py" "$name" "$out" "$arc" "$conf" "$frames" "${HANDLE_R:-0.05}" \
    "$root/$name.check" "$ours_s" "$arc_s"
done
