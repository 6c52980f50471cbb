#!/usr/bin/env bash
# Set up (scripts/setup.sh) and run ctid's main job (examples/main_job.sh), which writes
# its output under out/demo/ and says where.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# The main job needs the tool and the Python module only, and none of the test-only packages;
# scripts/test.sh installs and builds the rest.
CTID_PACKAGES=${CTID_PACKAGES:-demo} CTID_BUILD_TARGETS=${CTID_BUILD_TARGETS:-"ctid_app _ctid"} \
  CTID_LINK_BIN=${CTID_LINK_BIN:-/usr/local/bin} bash "$root/scripts/setup.sh"
export CTID_ROOT=$root
export CTID_BUILD_DIR=$root/build
export CTID_OUT_DIR=${CTID_OUT_DIR:-$root/out/demo}
exec bash "$root/examples/main_job.sh" "$@"
