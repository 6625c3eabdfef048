#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh) and runs the whole test suite through CTest, then a short
# run of every fuzz target (scripts/fuzz.sh: FUZZ_SECONDS each, default 30; 0 skips it; its
# clang build lives in build-fuzz/ and takes ~15 minutes the first time).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
"$root/scripts/setup.sh"
cd "$build_dir"
ctest --output-on-failure -j"$(nproc)" "$@"
fuzz_seconds="${FUZZ_SECONDS:-30}"
if [[ "$fuzz_seconds" != 0 ]]; then
  "$root/scripts/fuzz.sh" "$fuzz_seconds"
fi
