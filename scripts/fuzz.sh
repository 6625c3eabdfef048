#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang + AddressSanitizer) into build-fuzz/ and runs each
# for SECONDS (default 60), one after another. Fails when any target finds a crash, a hang (an
# input slower than TIMEOUT seconds, default 10), a memory blow-up (RSS_MB, default 4096: a glTF
# rig may legitimately take 2 GiB) or a sanitizer report. Corpora grow in
# build-fuzz/fuzz/corpus/<target>/ across runs; crashing inputs land in build-fuzz/fuzz/artifacts/,
# logs in build-fuzz/fuzz/logs/.
#   scripts/fuzz.sh [SECONDS]     TARGETS="ply_reader_fuzzer off_reader_fuzzer" scripts/fuzz.sh 30
set -euo pipefail
seconds="${1:-60}"
timeout="${TIMEOUT:-10}"
rss_mb="${RSS_MB:-4096}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${FUZZ_BUILD_DIR:-$root/build-fuzz}"
targets="${TARGETS:-obj_reader_fuzzer ply_reader_fuzzer off_reader_fuzzer gltf_rig_fuzzer config_fuzzer bundle_manifest_fuzzer train_config_fuzzer arkit_take_fuzzer stream_line_fuzzer weights_csv_fuzzer}"

command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is needed (apt-get install clang)" >&2; exit 1; }
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
  -DCMAKE_CXX_COMPILER=clang++ -DRETARGET_FUZZ=ON -DRETARGET_BUILD_TESTS=OFF -DRETARGET_BUILD_BENCH=OFF >/dev/null
cmake --build "$build_dir" -j"$(nproc)" --target fuzzers

fuzz="$build_dir/fuzz"
"$fuzz/write_fuzz_seeds" "$fuzz/seeds" "$root/configs"
mkdir -p "$fuzz/artifacts" "$fuzz/logs"

seeds_of() {  # the seed folders of a target
  case "$1" in
    obj_reader_fuzzer) echo "$fuzz/seeds/obj" ;;
    ply_reader_fuzzer) echo "$fuzz/seeds/ply" ;;
    off_reader_fuzzer) echo "$fuzz/seeds/off" ;;
    gltf_rig_fuzzer) echo "$fuzz/seeds/gltf" ;;
    config_fuzzer) echo "$fuzz/seeds/yaml $root/configs" ;;
    train_config_fuzzer) echo "$fuzz/seeds/train" ;;  # the profiles with their bases merged
    bundle_manifest_fuzzer) echo "$fuzz/seeds/manifest" ;;
    arkit_take_fuzzer | stream_line_fuzzer) echo "$fuzz/seeds/take" ;;
    weights_csv_fuzzer) echo "$fuzz/seeds/weights" ;;
    *) echo "fuzz.sh: unknown target $1" >&2; exit 1 ;;
  esac
}

# LibTorch (linked through retarget_core) keeps allocations alive at exit: leaks are not reported.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=0:allocator_may_return_null=0}"
failed=()
printf '%-24s %8s %12s %10s  %s\n' target seconds executions corpus result
for target in $targets; do
  corpus="$fuzz/corpus/$target"
  mkdir -p "$corpus"
  log="$fuzz/logs/$target.log"
  # shellcheck disable=SC2046
  if "$fuzz/$target" "$corpus" $(seeds_of "$target") -max_total_time="$seconds" -timeout="$timeout" \
      -rss_limit_mb="$rss_mb" -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$fuzz/artifacts/$target-" >"$log" 2>&1; then
    result=ok
  else
    result="FAILED (see $log)"
    failed+=("$target")
  fi
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1 || true)
  units=$(ls "$corpus" | wc -l)
  printf '%-24s %8s %12s %10s  %s\n' "$target" "$seconds" "${runs:-?}" "$units" "$result"
done
if ((${#failed[@]})); then
  echo "fuzz.sh: ${failed[*]} found problems; the inputs are in $fuzz/artifacts/" >&2
  exit 1
fi
