#!/usr/bin/env bash
# Installs the independent MCAP reader that scripts/mcap-check.mjs uses
# (npm's @mcap/core, @foxglove/rosmsg, @foxglove/rosmsg2-serialization, pinned)
# into build/mcap-check (or $1), outside the sources; the --mcap test of
# lmd_server_tests uses it when present and skips, saying so, when not.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dir=${1:-$root/build/mcap-check}
command -v npm >/dev/null || { echo "mcap-check-install: npm not found (Debian: apt-get install nodejs npm)"; exit 1; }
mkdir -p "$dir"
npm install --no-audit --no-fund --prefix "$dir" @mcap/core@2.2.2 @foxglove/rosmsg@5.0.5 \
  @foxglove/rosmsg2-serialization@3.1.0
echo "mcap-check-install: installed into $dir"
