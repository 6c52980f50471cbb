#!/usr/bin/env bash
# PLACEHOLDER for ctid's main job, run by scripts/demo.sh after set-up. The CLI developer
# replaces it: simulate a shipped example model with `ctid simulate` and write its data
# (later: identification on real data). scripts/demo.sh exports CTID_ROOT, CTID_BUILD_DIR
# and CTID_OUT_DIR (default out/demo/) for it.
set -euo pipefail
root=${CTID_ROOT:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
build=${CTID_BUILD_DIR:-$root/build}
out=${CTID_OUT_DIR:-$root/out/demo}
echo "main job (placeholder): the ctid CLI is not written yet."
echo "It will run: $build/apps/ctid/ctid simulate --model examples/<model>.json ... --output $out/<model>.csv"
echo "and write the simulated samples (t,u,y) under $out/."
