#!/usr/bin/env bash
# ctid's main job, run by scripts/demo.sh after set-up: simulate the shipped example systems
# of González et al. Section 6 with `ctid simulate` and write their data as CSV.
#   1. Section 6.1: the open-loop four-mode additive system driven by a random-phase
#      multisine (4 periods, flat from 0.01 to 3 Hz, h = 0.05 s), with the paper's coloured
#      noise v = (q + 0.5)/(q - 0.85) e, var e = 0.02.
#   2. Section 6.2: the two-mode plant under the paper's PID controller, multisine reference.
# Writes under $CTID_OUT_DIR (default out/demo/). Files there are replaced only if this
# script wrote them before (it leaves a marker file) or when called with --force.
set -euo pipefail
root=${CTID_ROOT:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
build=${CTID_BUILD_DIR:-$root/build}
out=${CTID_OUT_DIR:-$root/out/demo}
ctid=$build/apps/ctid/ctid
models=$root/examples/models

if [[ ! -x $ctid ]]; then
  echo "main_job: $ctid not found; build first (scripts/demo.sh does)" >&2
  exit 1
fi
mkdir -p "$out"
marker=$out/.written-by-ctid-main-job
force=()
if [[ ${1:-} == --force || -e $marker ]]; then
  force=(--force)
fi

open_loop=$out/gonzalez_6_1_open_loop.csv
closed_loop=$out/gonzalez_6_2_closed_loop.csv
"$ctid" simulate "${force[@]}" \
  --model "$models/gonzalez_6_1_open_loop.json" \
  --excitation-spec "$models/multisine_0.01_3hz.json" \
  --noise-filter "$models/gonzalez_6_1_noise_filter.json" --noise-std 0.1414213562373095 \
  --noise-seed 2 --output "$open_loop"
"$ctid" simulate "${force[@]}" \
  --model "$models/gonzalez_6_2_plant.json" \
  --controller "$models/gonzalez_6_2_pid.json" \
  --excitation multisine --samples 8192 --periods 4 --max-frequency-hz 3 --seed 1 \
  --noise-std 0.1 --noise-seed 2 --output "$closed_loop"
touch "$marker"

# A short summary of each file: samples, duration, and mean/standard deviation per column.
summarize() {
  awk -F, -v name="$(basename "$1")" '
    NR == 1 { for (i = 1; i <= NF; i++) col[i] = $i; n = NF; next }
    { rows++; for (i = 1; i <= n; i++) { s[i] += $i; ss[i] += $i * $i } last = $1; if (rows == 1) first = $1 }
    END {
      printf "%s: %d samples over %.2f s\n", name, rows, last - first
      for (i = 2; i <= n; i++) {
        m = s[i] / rows; v = ss[i] / rows - m * m; if (v < 0) v = 0
        printf "  %-2s mean %+.4f  std %.4f\n", col[i], m, sqrt(v)
      }
    }' "$1"
}
echo
summarize "$open_loop"
summarize "$closed_loop"
echo
echo "Data written to $out/ (columns t,u,y and r in closed loop; docs/formats.md)."

# The headline example: one modal model of the measured flexible structure (DaISy 96-013)
# from both shakers to all 28 accelerometers (examples/flexible_structure_mimo.py,
# docs/examples/flexible_structure_mimo.md), then the single-input fit of shaker 2 ->
# accelerometer 28 (examples/flexible_structure.py). They need the Python module of this
# build; without it the job above still stands.
if compgen -G "$build/python/ctid/_ctid*.so" >/dev/null; then
  echo
  CTID_BUILD_DIR=$build /usr/bin/python3 "$root/examples/flexible_structure_mimo.py" \
    --out "$out/flexible_structure_mimo"
  echo
  CTID_BUILD_DIR=$build /usr/bin/python3 "$root/examples/flexible_structure.py" \
    --out "$out/flexible_structure"
else
  echo "main_job: $build/python/ctid has no built module; skipping the flexible-structure" \
    "examples (configure with -DCTID_BUILD_PYTHON=ON)" >&2
fi
