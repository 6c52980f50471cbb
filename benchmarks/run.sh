#!/usr/bin/env bash
# Builds and runs every Google Benchmark program in benchmarks/ (Release, build/), then
# prints one headline table: benchmark, time per iteration, and throughput counters.
#   benchmarks/run.sh [benchmark name regex, e.g. 'simulat']
# Environment: CTID_BUILD_DIR (default build/, configured by scripts/setup.sh),
#   CTID_JOBS (default nproc), BENCHMARK_MIN_TIME (seconds per benchmark, default 0.2).
# Full results: <build>/benchmarks/results/<name>.json, console output <name>.log.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${CTID_BUILD_DIR:-$root/build}
jobs=${CTID_JOBS:-$(nproc)}
filter=${1:-.}

if [[ ! -f $build/CMakeCache.txt ]]; then
  (cd "$root" && cmake --preset release >/dev/null)
fi
cmake --build "$build" -j "$jobs" --target ctid_benchmarks

results=$build/benchmarks/results
rm -rf "$results"
mkdir -p "$results"
shopt -s nullglob
programs=("$build"/benchmarks/*_benchmark)
if ((${#programs[@]} == 0)); then
  echo "benchmarks/run.sh: no benchmarks/*_benchmark.cc yet"
  exit 0
fi
for program in "${programs[@]}"; do
  name=$(basename "$program")
  [[ $name =~ $filter ]] || continue
  echo "running $name"
  "$program" --benchmark_min_time="${BENCHMARK_MIN_TIME:-0.2}" \
    --benchmark_out="$results/$name.json" --benchmark_out_format=json >"$results/$name.log" 2>&1 ||
    { echo "$name failed; its output:" >&2; cat "$results/$name.log" >&2; exit 1; }
done

/usr/bin/python3 - "$results" <<'PY'
import json, pathlib, sys

def si(value):
    for scale, prefix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if abs(value) >= scale:
            return f"{value / scale:.3g} {prefix}"
    return f"{value:.3g} "

rows = []
for path in sorted(pathlib.Path(sys.argv[1]).glob("*.json")):
    data = json.loads(path.read_text())
    for b in data.get("benchmarks", []):
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "mean":
            continue
        extras = []
        if "items_per_second" in b:
            extras.append(f"{si(b['items_per_second'])}items/s")
        if "bytes_per_second" in b:
            extras.append(f"{si(b['bytes_per_second'])}B/s")
        skip = {"name", "run_name", "run_type", "repetitions", "repetition_index", "threads",
                "iterations", "real_time", "cpu_time", "time_unit", "items_per_second",
                "bytes_per_second", "family_index", "per_family_instance_index",
                "aggregate_name", "aggregate_unit", "label", "error_occurred", "error_message"}
        for key, value in b.items():
            if key not in skip and isinstance(value, (int, float)):
                extras.append(f"{key}={si(value)}".rstrip())
        time = f"{b['real_time']:.4g} {b['time_unit']}"
        rows.append((path.stem, b["name"], time, ", ".join(extras)))

if not rows:
    print("no benchmark results")
    sys.exit(0)
headers = ("program", "benchmark", "time/iter", "throughput and counters")
widths = [max(len(str(r[i])) for r in rows + [headers]) for i in range(4)]
line = "  ".join("{:<%d}" % w for w in widths)
print()
print(line.format(*headers))
print(line.format(*("-" * w for w in widths)))
for r in rows:
    print(line.format(*r))
PY
