#!/usr/bin/env bash
# Set up (scripts/setup.sh) and run ctid's main job (examples/main_job.sh), which writes
# its output under out/demo/ and says where.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
bash "$root/scripts/setup.sh"
export CTID_ROOT=$root
export CTID_BUILD_DIR=$root/build
export CTID_OUT_DIR=${CTID_OUT_DIR:-$root/out/demo}
exec bash "$root/examples/main_job.sh" "$@"
