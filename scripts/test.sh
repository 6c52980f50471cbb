#!/usr/bin/env bash
# Set up (scripts/setup.sh) and run ctid's whole test suite:
#   1. clang-format check of every tracked C++ file
#   2. ctest on the Release build in build/ (unit tests + install/find_package consumer test)
#   3. unit tests again under AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/)
#   4. the libFuzzer harnesses of the readers (fuzz/, clang): every committed seed and past
#      crash once, then 15 s of fuzzing each (scripts/fuzz.sh; an hour: docs/fuzzing.md)
#   5. pytest on python/tests with /usr/bin/python3, when that folder exists
# Every step runs even if an earlier one failed; exits non-zero if any failed.
# Environment: CTID_JOBS (parallel jobs, default nproc), CTID_SKIP_ASAN=1 (skip step 3),
# CTID_SKIP_FUZZ=1 (skip step 4).
set -uo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=${CTID_JOBS:-$(nproc)}
export CTID_JOBS=$jobs
cd "$root"
start=$SECONDS

bash scripts/setup.sh || { echo "test.sh: set-up or Release build FAILED" >&2; exit 1; }
setup_seconds=$((SECONDS - start))

failed=()
results=()
run_step() {
  local name=$1
  shift
  local t0=$SECONDS
  echo
  echo "=== test.sh: $name"
  if "$@"; then
    results+=("ok     $name ($((SECONDS - t0)) s)")
  else
    results+=("FAILED $name ($((SECONDS - t0)) s)")
    failed+=("$name")
  fi
}

format_check() {
  local files=()
  if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    mapfile -t files < <(git -C "$root" ls-files '*.h' '*.hpp' '*.cc' '*.cpp')
  else
    mapfile -t files < <(find include src tests apps python benchmarks examples \
      \( -name '*.h' -o -name '*.hpp' -o -name '*.cc' -o -name '*.cpp' \) 2>/dev/null)
  fi
  echo "clang-format: checking ${#files[@]} files"
  ((${#files[@]} == 0)) || clang-format --dry-run --Werror "${files[@]}"
}

release_tests() {
  ctest --preset release -j "$jobs"
}

asan_tests() {
  cmake --preset asan >/dev/null &&
    cmake --build --preset asan -j "$jobs" &&
    ctest --preset asan -j "$jobs"
}

fuzz_tests() {
  bash scripts/fuzz.sh regress && bash scripts/fuzz.sh run 15
}

python_tests() {
  if [[ ! -d python/tests ]]; then
    echo "no python/tests yet: skipped"
    return 0
  fi
  # The extension module is built into build/python; the pure-Python package is in python/.
  local rc=0
  CTID_BUILD_DIR=$root/build PYTHONPATH="$root/build/python:$root/python${PYTHONPATH:+:$PYTHONPATH}" \
    /usr/bin/python3 -m pytest -q python/tests || rc=$?
  if ((rc == 5)); then
    echo "pytest collected no tests: counted as success"
    rc=0
  fi
  return $rc
}

run_step "clang-format" format_check
run_step "ctest (Release)" release_tests
if [[ ${CTID_SKIP_ASAN:-0} != 1 ]]; then
  run_step "ctest (ASan+UBSan)" asan_tests
fi
if [[ ${CTID_SKIP_FUZZ:-0} != 1 ]]; then
  run_step "fuzz (readers)" fuzz_tests
fi
run_step "pytest" python_tests

echo
echo "=== test.sh summary ($((SECONDS - start)) s)"
echo "  ok     set-up + Release build ($setup_seconds s)"
printf '  %s\n' "${results[@]}"
if ((${#failed[@]} > 0)); then
  echo "test.sh: FAILED: ${failed[*]}"
  exit 1
fi
echo "test.sh: all steps succeeded"
