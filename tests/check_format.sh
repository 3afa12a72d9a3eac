#!/usr/bin/env bash
# Fails (listing the files) when a tracked C++ file differs from what .clang-format makes of it.
# Usage: check_format.sh SOURCE_DIR
set -euo pipefail
cd "$1"
mapfile -t files < <(git ls-files '*.cpp' '*.hpp' 2>/dev/null || find . -name '*.[ch]pp' -not -path './build*')
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run -Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if ((${#bad[@]})); then
  echo "not formatted by .clang-format (run: clang-format -i FILE): ${bad[*]}" >&2
  exit 1
fi
echo "format: ${#files[@]} files checked"
