#!/usr/bin/env bash
# Record what ctid computes on a fixed set of commands, so that a refactoring can be shown to
# change no estimate: run it on the tree before and after, then compare the two folders with
# scripts/compare_snapshots.py (numbers must be identical; only renamed fields may differ; with
# --relative BOUND, numbers within BOUND: issue 38's rule for changes that may alter rounding).
#   scripts/behaviour_snapshot.sh OUT_DIR [BUILD_DIR]
# Takes about a minute on two cores. Uses the shipped models, data/ and ../shared/data.
# Covers every command that estimates: fit (SISO, additive, closed loop, several channels),
# validate, frf, fit-frf, structure, track (one and several channels), batch, feedback, oma
# (each method) and study.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=${1:?usage: behaviour_snapshot.sh OUT_DIR [BUILD_DIR]}
build=$(cd "${2:-$root/build}" && pwd)
ctid=$build/apps/ctid/ctid
models=$root/examples/models
data=$root/../shared/data
mkdir -p "$out"
out=$(cd "$out" && pwd)
cd "$out"
run() { # name, command...: stdout+stderr into name.txt (the exit status on its last line)
  local name=$1
  shift
  local rc=0
  "$@" >"$name.txt" 2>&1 || rc=$?
  echo "exit $rc" >>"$name.txt"
}
run sim_open "$ctid" simulate --force -m "$models/gonzalez_6_1_open_loop.json" \
  --excitation-spec "$models/multisine_0.01_3hz.json" \
  --noise-filter "$models/gonzalez_6_1_noise_filter.json" --noise-std 0.1414213562373095 \
  --noise-seed 2 -o open.csv
run sim_closed "$ctid" simulate --force -m "$models/gonzalez_6_2_plant.json" \
  -c "$models/gonzalez_6_2_pid.json" -e multisine -n 8192 --periods 4 --max-frequency-hz 3 \
  --seed 1 --noise-std 0.1 --noise-seed 2 -o closed.csv
run fit_modes "$ctid" fit open.csv --modes 4 --force -o fit_modes.json
run fit_modes_start "$ctid" fit open.csv --modes 4 --initial fit_modes.json --noise white \
  --history --force -o fit_modes_start.json
run fit_unfactored "$ctid" fit open.csv --poles 8 --zeros 6 --force -o fit_unfactored.json
run fit_relocate "$ctid" fit open.csv --modes 4 --relocate-modes --force -o fit_relocate.json
run fit_clsrivc "$ctid" fit closed.csv --poles 4 --zeros 2 -c "$models/gonzalez_6_2_pid.json" \
  --force -o fit_clsrivc.json
run fit_additive_cl "$ctid" fit closed.csv --submodel 2,0 --submodel 2,0 \
  -c "$models/gonzalez_6_2_pid.json" --force -o fit_additive_cl.json
cp "$data/contsid_aerothermal_pt326/pt326_est.csv" pt326_est.csv
run fit_pt326 "$ctid" fit pt326_est.csv --poles 1 --zeros 0 \
  --input-column u_heater_voltage --output-column y_outlet_temperature --time-column t_s --delay-scan-samples 0:8 --force -o fit_pt326.json
run validate_modes "$ctid" validate fit_modes.json open.csv --force -o validate_modes.json
run frf_welch "$ctid" frf open.csv --force -o frf_welch.csv
run frf_periodic "$ctid" frf open.csv --period 2048 --force -o frf_periodic.csv
run sim_loop "$ctid" simulate --force -m "$models/de_iuliis_section4_loop.json" -e multisine \
  -n 600 -T 0.05 --periods 2 --max-frequency-hz 0.6 -o loop.csv
run feedback "$ctid" feedback loop.csv --forward-order 3 --feedback-order 3 --delay 0.5 \
  --hold foh --force -o feedback.json
run study_open "$ctid" study open-loop --sizes 2 --runs 3 --threads 2 --no-plot --force -o study_open
run study_closed "$ctid" study closed-loop --sizes 2 --runs 3 --threads 2 --no-plot --force -o study_closed
cp "$root/data/daisy_flexible_structure/flexible_structure.csv" flexible_structure.csv
flex=flexible_structure.csv
run fit_mimo "$ctid" fit "$flex" --time-column t_s --input-columns u1_force,u2_force \
  --output-columns y1_acc:y6_acc --modes 4 --force -o fit_mimo.json
run frf_matrix "$ctid" frf "$flex" --time-column t_s --input-columns u1_force,u2_force \
  --output-columns y1_acc:y4_acc --force -o frf_matrix.csv
run fit_frf "$ctid" fit-frf frf_matrix.csv --modes 4 --band 10:500 --force -o fit_frf.json
run structure "$ctid" structure open.csv --modes 2:5 --force -o structure.json
run track "$ctid" track "$flex" --time-column t_s --input-column u1_force --output-column y1_acc \
  --modes 2 --window 2 --force -o track.json
run track_mimo "$ctid" track "$flex" --time-column t_s --input-columns u1_force,u2_force \
  --output-columns y1_acc:y4_acc --modes 3 --window 2 --force -o track_mimo.json
cat >manifest.json <<'JSON'
{"spec": {"zeros": 2},
 "records": [{"name": "open", "data": "open.csv", "poles": 4},
             {"name": "closed_as_open", "data": "closed.csv", "poles": 4},
             {"name": "modes", "data": "open.csv", "modes": 4, "zeros": null},
             {"name": "two_structures", "data": "open.csv", "poles": 4, "modes": 4}]}
JSON
run batch "$ctid" batch manifest.json --out batch --jobs 2 --force
rm -f batch/timings.json # wall-clock seconds, not results (summary columns "seconds" are skipped)
for method in ssi-cov ssi-data fdd efdd; do
  run "oma_$method" "$ctid" oma "$flex" --time-column t_s --output-columns y1_acc:y8_acc \
    --method "$method" --max-order 60 --force -o "oma_$method.json"
done
# SSI-cov with standard errors (the runs above have blocks too short for them): perturbation
# with all and with two references, and segments.
run oma_errors "$ctid" oma "$flex" --time-column t_s --output-columns y1_acc:y8_acc \
  --block-rows 20 --max-order 40 --force -o oma_errors.json
run oma_errors_refs "$ctid" oma "$flex" --time-column t_s --output-columns y1_acc:y8_acc \
  --reference-columns y1_acc,y4_acc --block-rows 20 --max-order 40 --force -o oma_errors_refs.json
run oma_segments "$ctid" oma "$flex" --time-column t_s --output-columns y1_acc:y8_acc \
  --block-rows 20 --max-order 40 --uncertainty segments --force -o oma_segments.json
