#!/usr/bin/env bash
# Runs clang-tidy (.clang-tidy) over ctid's C++ sources using build/compile_commands.json.
# Not part of scripts/test.sh (it takes minutes on 2 cores); run it before a larger change.
#   scripts/tidy.sh [files...]   (default: every src/, apps/ and python/src/ .cc file)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
if [[ ! -f build/compile_commands.json ]]; then
  bash scripts/setup.sh
fi
if (($# > 0)); then
  files=("$@")
else
  mapfile -t files < <(git ls-files 'src/*.cc' 'apps/*.cc' 'python/src/*.cc')
fi
echo "clang-tidy: ${#files[@]} files"
status=0
printf '%s\0' "${files[@]}" |
  xargs -0 -r -n 1 -P "${CTID_JOBS:-$(nproc)}" clang-tidy -p build --quiet || status=$?
exit $status
