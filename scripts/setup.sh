#!/usr/bin/env bash
# Installs every Debian package the build needs (only those missing), then configures
# and builds the project in Release. Works as root on a fresh Debian 12 machine.
#   scripts/setup.sh            # install + configure + build into ./build
#   BUILD_DIR=out scripts/setup.sh
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libfmt-dev libyaml-cpp-dev libopenmesh-dev libcgal-dev libgmp-dev libmpfr-dev
  libtorch-dev libopenblas0-openmp
  libgloo-dev  # train/data_parallel.h: the headers of Gloo, which LibTorch's ProcessGroupGloo (c10d) is built on
  libcxxopts-dev catch2 libbenchmark-dev
  libstb-dev libtinygltf-dev nlohmann-json3-dev
  libssl-dev  # core/sha256.h: SHA-256 checksums of a bundle's files (OpenSSL's libcrypto)
  libsqlite3-dev  # annotate/: the tournament annotation store
  libcpp-httplib-dev  # annotate/: the web annotation tool's HTTP server
  clang-format  # scripts/check_format.sh (house/format in the test suite)
  clang libclang-rt-14-dev  # fuzz/: libFuzzer and AddressSanitizer (scripts/fuzz.sh, run by scripts/test.sh)
  chromium  # tests/browser/: the web annotation tool in a real headless browser
  python3-torch  # tests: Python's torch.jit.load must read the exported models (tests/export/vae_export_test.cpp)
  gnuplot-nox  # retarget plot (plot/) and scripts/budget_curve.sh: every picture of numbers
  ffmpeg  # retarget-infer --animation x.mp4: H.264 encoding (render/animation.h pipes frames to it); ffprobe checks the tests' MP4s
)

# Node.js and npm run the browser tests (tests/browser/); most machines have them already.
command -v npm >/dev/null || packages+=(nodejs npm)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  if [[ $(id -u) -ne 0 ]]; then sudo_cmd=(sudo); fi
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "setup: all ${#packages[@]} packages present"
fi

# Debian's LibTorch links the generic BLAS; the OpenMP OpenBLAS is ~8x faster for its
# matrix products. Make sure the alternative points at it.
openblas=$(ls /usr/lib/x86_64-linux-gnu/openblas-openmp/libblas.so.3 2>/dev/null || true)
if [[ -n "$openblas" ]] && [[ $(id -u) -eq 0 ]]; then
  update-alternatives --set libblas.so.3-x86_64-linux-gnu "$openblas" >/dev/null 2>&1 || true
  lapack=/usr/lib/x86_64-linux-gnu/openblas-openmp/liblapack.so.3
  [[ -e $lapack ]] && update-alternatives --set liblapack.so.3-x86_64-linux-gnu "$lapack" >/dev/null 2>&1 || true
fi

# The browser tests drive Chromium with Playwright (playwright-core from npm) and check glTF
# animations with the Khronos validator (gltf-validator) and three.js (three), all pinned in
# tests/browser/package-lock.json; without them those tests report themselves skipped. `npm ci`
# runs when a package is missing or the lock file is newer than the last install's record.
if command -v npm >/dev/null && [[ -f "$root/tests/browser/package-lock.json" ]]; then
  modules="$root/tests/browser/node_modules"
  if [[ ! -d $modules/playwright-core || ! -d $modules/gltf-validator || ! -d $modules/three ||
        "$root/tests/browser/package-lock.json" -nt $modules/.package-lock.json ]]; then
    (cd "$root/tests/browser" && npm ci --no-audit --no-fund --loglevel=error)
  fi
else
  echo "setup: npm not found; the browser tests will be skipped"
fi

generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [[ -f "$build_dir/CMakeCache.txt" ]]; then
  cmake -S "$root" -B "$build_dir" >/dev/null
else
  cmake -S "$root" -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$build_dir" -j"$(nproc)"
echo "setup: built into $build_dir"
