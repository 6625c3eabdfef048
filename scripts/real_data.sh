#!/usr/bin/env bash
# The real-data recipe (configs/recipes/real.yaml, docs/usage/real-data.md): ICT people
# (../shared/data/ict-face, drawn from its identity modes) onto the shared Weboji rabbit, in one
# `retarget pipeline` call into $OUT (default out/real-quick). Needs the build (scripts/setup.sh)
# and ../shared/data (or $RETARGET_SHARED_DATA); never copies the data. Extra arguments go to the
# pipeline:
#   scripts/real_data.sh
#   OUT=out/real-good scripts/real_data.sh --set profile=configs/train/good
#   scripts/real_data.sh --set method.budget=700 --set method.folder=method-700
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
shared="${RETARGET_SHARED_DATA:-$root/../shared/data}"
[[ -d "$shared/ict-face" ]] || { echo "real_data: $shared/ict-face not found (set RETARGET_SHARED_DATA)" >&2; exit 2; }
exec "${BUILD_DIR:-$root/build}/cli/retarget" pipeline "$root/configs/recipes/real.yaml" --out "${OUT:-$root/out/real-quick}" "$@"
