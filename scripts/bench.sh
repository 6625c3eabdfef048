#!/usr/bin/env bash
# Builds (scripts/setup.sh) and runs the benchmarks; prints medians over repetitions.
# Never part of the test suite. Extra arguments go to Google Benchmark, e.g.
#   scripts/bench.sh --benchmark_filter=DrFeatures
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
"$root/scripts/setup.sh" >/dev/null
# OpenBLAS 0.3.21 does not recognise this CPU; its Skylake-X kernels are ~5x faster
# where the CPU has AVX-512. It must be set before the process starts.
if grep -q avx512f /proc/cpuinfo && [[ -z ${OPENBLAS_CORETYPE:-} ]]; then export OPENBLAS_CORETYPE=SkylakeX; fi
exec "$build_dir/bench/retarget_bench" --benchmark_repetitions=7 --benchmark_report_aggregates_only=true \
  --benchmark_display_aggregates_only=true "$@"
