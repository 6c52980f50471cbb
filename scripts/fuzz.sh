#!/usr/bin/env bash
# Fuzz ctid's readers with the libFuzzer harnesses in fuzz/ (clang, ASan + UBSan; docs/fuzzing.md).
#   scripts/fuzz.sh build                  configure and build build-fuzz/ (needs build/, the Release tree)
#   scripts/fuzz.sh regress                run every harness once over its committed seed corpus
#                                          (fuzz/corpus/NAME) and past crashes (fuzz/regressions/NAME)
#   scripts/fuzz.sh run SECONDS [NAME...]  fuzz each harness (default: all) for SECONDS, inputs up
#                                          to 1 MB; new inputs go to build-fuzz/corpus/NAME, crashes
#                                          to build-fuzz/crashes/NAME; prints executions and coverage
# Every command builds first. Exits non-zero if a harness crashed (or a build failed).
# Environment: CTID_JOBS (harnesses run at once, default nproc), CTID_FUZZ_MAX_LEN (bytes,
# default 1048576), CTID_FUZZ_CPU=1 (run: SECONDS are the harness's CPU time, not wall time, so
# a run on a loaded machine at low priority still fuzzes for SECONDS).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=${CTID_JOBS:-$(nproc)}
max_len=${CTID_FUZZ_MAX_LEN:-1048576}
out=$root/build-fuzz
cd "$root"

usage() {
  sed -n '2,9p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2
  exit 2
}

build() {
  if [[ ! -f build/libctid_refined_iv.a ]]; then
    echo "fuzz.sh: build/ has no Release libraries; run scripts/setup.sh first" >&2
    exit 1
  fi
  cmake -S fuzz -B "$out" -G Ninja -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCTID_RELEASE_DIR="$root/build" >/dev/null
  cmake --build "$out" -j "$jobs"
}

harnesses() {
  local name
  for name in fuzz/fuzz_*.cc; do
    name=${name#fuzz/fuzz_}
    echo "${name%.cc}"
  done
}

# One harness over its seeds and regressions, each input once.
regress_one() {
  local name=$1 inputs=()
  for dir in "fuzz/corpus/$name" "fuzz/regressions/$name"; do
    [[ -d $dir ]] && inputs+=("$dir"/*)
  done
  "$out/fuzz_$name" -runs=0 $(dictionary "$name") "${inputs[@]}" \
    >"$out/logs/regress_$name.log" 2>&1 ||
    { echo "fuzz.sh: fuzz_$name failed on a committed input; see $out/logs/regress_$name.log" >&2
      tail -20 "$out/logs/regress_$name.log" >&2; return 1; }
  echo "regress $name: $(grep -c . <(printf '%s\n' "${inputs[@]}")) inputs, no crash"
}

# The -dict= flag of a harness, if it has a dictionary.
dictionary() {
  case $1 in
    csv) echo -dict=fuzz/csv.dict ;;
    batch_manifest) echo -dict=fuzz/manifest.dict ;;
    *json*) echo -dict=fuzz/json.dict ;;
  esac
}

# One harness for $seconds; its log's last status line gives executions and coverage.
run_one() {
  local name=$1 seconds=$2
  mkdir -p "$out/corpus/$name" "$out/crashes/$name"
  local status=0 wall=$seconds interrupted=0
  [[ ${CTID_FUZZ_CPU:-0} == 1 ]] && wall=0 # no wall limit: the watchdog below stops it
  "$out/fuzz_$name" -max_total_time="$wall" -max_len="$max_len" -rss_limit_mb=4096 \
    -timeout=60 -print_final_stats=1 -interrupted_exitcode=72 $(dictionary "$name") \
    -artifact_prefix="$out/crashes/$name/" "$out/corpus/$name" "fuzz/corpus/$name" \
    >"$out/logs/run_$name.log" 2>&1 &
  local pid=$!
  if [[ ${CTID_FUZZ_CPU:-0} == 1 ]]; then
    # utime + stime (fields 14 and 15 of /proc/PID/stat, in clock ticks) against the budget;
    # SIGINT makes libFuzzer print its final statistics and exit.
    local ticks budget
    budget=$((seconds * $(getconf CLK_TCK)))
    while kill -0 "$pid" 2>/dev/null; do
      ticks=$(awk '{print $14 + $15}' "/proc/$pid/stat" 2>/dev/null || echo 0)
      if ((ticks >= budget)); then
        kill -INT "$pid" 2>/dev/null && interrupted=1
        break
      fi
      sleep 5
    done
  fi
  wait "$pid" || status=$?
  ((interrupted && status == 72)) && status=0 # 72: libFuzzer stopped by our SIGINT
  local execs cov
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$out/logs/run_$name.log" | grep -o '[0-9]*$' || true)
  cov=$(grep -o 'cov: [0-9]*' "$out/logs/run_$name.log" | tail -1 | grep -o '[0-9]*' || true)
  if ((status == 72)); then # stopped by a SIGINT from elsewhere before its time was up
    echo "fuzz.sh: fuzz_$name interrupted after ${execs:-?} executions (no crash);" \
      "log $out/logs/run_$name.log" >&2
    return 1
  fi
  if ((status != 0)); then
    echo "fuzz.sh: fuzz_$name CRASHED after ${execs:-?} executions; input in $out/crashes/$name/," \
      "log $out/logs/run_$name.log" >&2
    grep -m3 -E 'ERROR|SUMMARY|runtime error|deadly signal' "$out/logs/run_$name.log" >&2 || true
    return 1
  fi
  echo "run $name: ${seconds} s$([[ ${CTID_FUZZ_CPU:-0} == 1 ]] && echo ' CPU'), ${execs:-?} executions, coverage ${cov:-?} edges, corpus $(ls "$out/corpus/$name" | wc -l) inputs"
}

# Runs "$@" for every harness name in $names, $jobs at a time; fails if any failed.
for_each() {
  local pids=() failed=0 name
  for name in "${names[@]}"; do
    "$@" "$name" &
    pids+=($!)
    if ((${#pids[@]} >= jobs)); then
      wait "${pids[0]}" || failed=1
      pids=("${pids[@]:1}")
    fi
  done
  for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
  return $failed
}

(($# >= 1)) || usage
command=$1
shift
case $command in
  build) build ;;
  regress)
    build
    mkdir -p "$out/logs"
    mapfile -t names < <(harnesses)
    for_each regress_one
    ;;
  run)
    (($# >= 1)) || usage
    seconds=$1
    shift
    [[ $seconds =~ ^[0-9]+$ ]] || usage
    build
    mkdir -p "$out/logs"
    if (($# > 0)); then names=("$@"); else mapfile -t names < <(harnesses); fi
    run_with_seconds() { run_one "$1" "$seconds"; }
    for_each run_with_seconds
    ;;
  *) usage ;;
esac
