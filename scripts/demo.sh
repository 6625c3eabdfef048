#!/usr/bin/env bash
# The main job on the bundled synthetic default, from a fresh machine: sets up, builds,
# and runs the geometry core end to end on procedurally generated meshes:
#   DR features -> reconstruction (round trip error), and deformation transfer of
#   expressions from one synthetic face-like mesh onto another of a different topology.
# Outputs (meshes you can open in any viewer, and the printed errors) go to $OUT (default out/demo).
# Later stages (datasets, VAEs, translation, inference) are added to this script as they land.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${BUILD_DIR:-$root/build}"
out="${OUT:-$root/out/demo}"
"$root/scripts/setup.sh"
"$build_dir/train/retarget" demo --out "$out"
