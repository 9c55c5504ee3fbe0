#!/usr/bin/env bash
# README command 2: installs what is missing, builds, runs the whole test suite.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${LMD_BUILD_DIR:-$root/build}
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
# The independent MCAP reader (npm) for the --mcap test; without it (no npm
# or no registry) that test skips and says so.
if [ ! -d "$build/mcap-check/node_modules/@mcap/core" ]; then
  "$root/scripts/mcap-check-install.sh" "$build/mcap-check" >/dev/null 2>&1 ||
    echo "test: could not install @mcap/core with npm; the MCAP reader test will skip"
fi
cd "$build"
ctest --output-on-failure -j "$(nproc)" --timeout 300
