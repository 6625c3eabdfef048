#!/usr/bin/env bash
# The main job on the bundled synthetic default, from a fresh machine: installs and builds
# (scripts/setup.sh), then runs the method from its recipe, configs/recipes/demo.yaml, into $OUT
# (default out/demo). A second run skips what is up to date; a killed run resumes. Extra
# arguments go to `retarget pipeline` (e.g. --set method.budget=700, --from method/translation).
# What lands where: docs/usage/pipeline.md; the evaluation table is printed at the end and kept
# in $OUT/summary.txt.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/setup.sh"
exec "${BUILD_DIR:-$root/build}/cli/retarget" pipeline "$root/configs/recipes/demo.yaml" --out "${OUT:-$root/out/demo}" "$@"
