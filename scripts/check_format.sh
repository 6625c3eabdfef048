#!/usr/bin/env bash
# The tree in .clang-format's style (Google, 120 columns): lists every C++ file that drifts and
# exits 1; FIX=1 rewrites them instead. Runs in the test suite as house/format.
#   scripts/check_format.sh          # check
#   FIX=1 scripts/check_format.sh    # apply
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
command -v clang-format >/dev/null || { echo "check_format: clang-format is needed (scripts/setup.sh installs it)" >&2; exit 1; }
mapfile -t files < <(git ls-files '*.cpp' '*.h')
((${#files[@]})) || { echo "check_format: no C++ files found under $root (not a git checkout?)" >&2; exit 1; }
if [[ "${FIX:-0}" == 1 ]]; then
  clang-format -i "${files[@]}"
  echo "check_format: ${#files[@]} files formatted"
  exit 0
fi
drift=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || drift+=("$f")
done
if ((${#drift[@]})); then
  printf '%s\n' "${drift[@]}"
  echo "check_format: ${#drift[@]} of ${#files[@]} files drift from .clang-format (FIX=1 scripts/check_format.sh rewrites them)"
  exit 1
fi
echo "check_format: ${#files[@]} files in .clang-format's style"
