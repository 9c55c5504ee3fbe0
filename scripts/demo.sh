#!/usr/bin/env bash
# README command 1: installs what is missing, builds, starts lmdd on a
# temporary data directory and a free loopback port, runs the demo (built-in
# simulated world) against it, prints the result, and stops lmdd.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${LMD_BUILD_DIR:-$root/build}
out=${LMD_DEMO_OUT:-$root/out/demo}

"$root/scripts/setup.sh"
"$root/scripts/build.sh" >/dev/null

work=$(mktemp -d)
lmdd_pid=
cleanup() {
  if [ -n "$lmdd_pid" ] && kill -0 "$lmdd_pid" 2>/dev/null; then kill -TERM "$lmdd_pid"; wait "$lmdd_pid" || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

"$build/server/lmdd" --listen 127.0.0.1:0 --data-dir "$work/data" --log-level warn >"$work/lmdd.out" 2>&1 &
lmdd_pid=$!
port=
for _ in $(seq 100); do
  port=$(sed -n 's/^lmdd listening on port \([0-9]*\)$/\1/p' "$work/lmdd.out")
  [ -n "$port" ] && break
  kill -0 "$lmdd_pid" 2>/dev/null || { cat "$work/lmdd.out" >&2; exit 1; }
  sleep 0.1
done
[ -n "$port" ] || { echo "demo: lmdd did not start" >&2; cat "$work/lmdd.out" >&2; exit 1; }
echo "demo: lmdd is serving on 127.0.0.1:$port (data in $work/data)"

mkdir -p "$out"
"$build/client/lmdctl" --server "127.0.0.1:$port" demo --collection demo --out "$out"

kill -TERM "$lmdd_pid"
wait "$lmdd_pid"
lmdd_pid=
echo "demo: lmdd stopped cleanly"
