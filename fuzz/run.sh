#!/usr/bin/env bash
# Fuzz the scene parser and the OBJ loader (issue 5) with libFuzzer through cargo-fuzz.
#   fuzz/run.sh [SECONDS per target, default 600]
# Works on the stable toolchain: RUSTC_BOOTSTRAP lets cargo-fuzz pass its nightly-only flags,
# and `-s none` builds without a sanitizer (safe Rust; the targets look for panics and aborts).
# Seeds: the shipped scenes and meshes. Findings land in fuzz/artifacts/<target>/.
set -euo pipefail
cd "$(dirname "$0")"
SECONDS_PER_TARGET=${1:-600}
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
mkdir -p corpus/scene corpus/obj
cp ../scenes/*.json ../scenes/stress/*.json corpus/scene/
cp ../scenes/meshes/*.obj ../scenes/stress/meshes/*.obj corpus/obj/
export RUSTC_BOOTSTRAP=1
cargo fuzz run -s none scene -- -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=2048 -max_len=8192
cargo fuzz run -s none obj -- -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=2048 -max_len=16384
