#!/usr/bin/env bash
# Set up a fresh Debian 12 machine for ctid and build it (Release, Ninja, into build/).
# Idempotent: installs only the packages in scripts/debian-packages.txt that are missing
# (apt-get update only then), then configures with the "release" preset and builds.
# Runs as root, or through sudo otherwise; needs no terminal (CI=true, no stdin).
#   scripts/setup.sh [extra cmake -D options for the release configure]
# Environment: CTID_JOBS (parallel jobs, default nproc), CTID_SKIP_BUILD=1 (packages only),
# CTID_PACKAGES=demo (only what the tool, the Python module and the main job need; the tests
# and benchmarks are then configured off),
# CTID_BUILD_TARGETS (space-separated targets to build instead of all; scripts/demo.sh builds
# only the tool and the Python module, the test command builds the rest),
# CTID_LINK_BIN=DIR (put a link DIR/ctid to the built tool, unless DIR/ctid is something
# else already; scripts/demo.sh uses /usr/local/bin when it can write there).
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=${CTID_JOBS:-$(nproc)}
export DEBIAN_FRONTEND=noninteractive

# CTID_PACKAGES=demo leaves out the lines marked [test] (scripts/demo.sh); anything else: all.
package_lines=$(cat "$root/scripts/debian-packages.txt")
if [[ ${CTID_PACKAGES:-all} == demo ]]; then
  package_lines=$(grep -v '#[[:space:]]*\[test\]' <<<"$package_lines")
fi
mapfile -t packages < <(sed -e 's/#.*//' -e 's/[[:space:]]//g' <<<"$package_lines" | grep -v '^$')
missing=()
for package in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$package" 2>/dev/null || true)
  [[ $status == "install ok installed" ]] || missing+=("$package")
done

if ((${#missing[@]} > 0)); then
  echo "setup: installing missing Debian packages: ${missing[*]}"
  if [[ $(id -u) -eq 0 ]]; then
    as_root=()
  elif command -v sudo >/dev/null; then
    as_root=(sudo --non-interactive env DEBIAN_FRONTEND=noninteractive)
  else
    echo "setup: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  "${as_root[@]}" apt-get update -q
  "${as_root[@]}" apt-get install -y -q "${missing[@]}" </dev/null
else
  echo "setup: all ${#packages[@]} Debian packages present"
fi

# A locale whose decimal separator is a comma, for the LC_NUMERIC tests (python/tests/
# test_locale_and_threads.py): made once from the locales package's sources when missing.
if [[ ${CTID_PACKAGES:-all} != demo ]] && ! locale -a 2>/dev/null | grep -qix 'de_DE\.utf-\?8'; then
  if [[ $(id -u) -eq 0 ]]; then
    localedef -i de_DE -f UTF-8 de_DE.UTF-8 && echo "setup: made the locale de_DE.UTF-8"
  elif command -v sudo >/dev/null; then
    sudo --non-interactive localedef -i de_DE -f UTF-8 de_DE.UTF-8 &&
      echo "setup: made the locale de_DE.UTF-8"
  else
    echo "setup: no de_DE.UTF-8 locale and no root: the comma-locale tests will be skipped" >&2
  fi
fi

if [[ ${CTID_SKIP_BUILD:-0} == 1 ]]; then
  exit 0
fi

cd "$root"
# A build/ made earlier with another generator cannot be reconfigured with Ninja.
if [[ -f build/CMakeCache.txt ]] && ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' build/CMakeCache.txt; then
  echo "setup: build/ was configured with another generator; reconfiguring from scratch"
  rm -rf build/CMakeCache.txt build/CMakeFiles
fi
# The "release" preset (CMakePresets.json) pins Release, Ninja, build/ and /usr/bin/python3.
# Without the [test] packages there is no GoogleTest or Google Benchmark to configure against,
# so the tests and benchmarks are configured off; a full set-up turns them back on.
if [[ ${CTID_PACKAGES:-all} == demo ]]; then
  suite=(-DCTID_BUILD_TESTS=OFF -DCTID_BUILD_BENCHMARKS=OFF)
else
  suite=(-DCTID_BUILD_TESTS=ON -DCTID_BUILD_BENCHMARKS=ON)
fi
cmake --preset release "${suite[@]}" "$@"
if [[ -n ${CTID_BUILD_TARGETS:-} ]]; then
  read -r -a targets <<<"$CTID_BUILD_TARGETS"
  cmake --build --preset release -j "$jobs" --target "${targets[@]}"
else
  cmake --build --preset release -j "$jobs"
fi
echo "setup: build/ is ready"

# `ctid` by name: a link in CTID_LINK_BIN, never over a file or link that is not ours.
if [[ -n ${CTID_LINK_BIN:-} && -d $CTID_LINK_BIN && -w $CTID_LINK_BIN ]]; then
  link=$CTID_LINK_BIN/ctid
  tool=$root/build/apps/ctid/ctid
  if [[ ! -e $link && ! -L $link ]] || [[ -L $link && $(readlink "$link") == "$tool" ]]; then
    ln -sfn "$tool" "$link"
    echo "setup: ctid is on PATH ($link -> $tool)"
  elif [[ -L $link && $(readlink "$link") == */build/apps/ctid/ctid ]]; then
    ln -sfn "$tool" "$link"  # another checkout's link: this one is the latest set up
    echo "setup: ctid is on PATH ($link -> $tool)"
  else
    echo "setup: $link exists and is not ctid's link; left alone (run $tool)" >&2
  fi
fi
