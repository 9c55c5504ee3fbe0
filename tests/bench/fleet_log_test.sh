#!/bin/sh
# lmd-bench load --mode fleet on a real log's world: each robot drives the
# log's maps from its own start and, at the log's end, goes on from its
# beginning (a kidnap). Across that jump its odometry says nothing, so it
# asks globally instead of sending a prior (one of about a hundred metres,
# past lmdd's limit, made every such call an error). On orebro (77 maps
# driven), 4 robots for 30 ticks: the last starts 20 maps before the end.
# usage: fleet_log_test.sh LMDD LMD_BENCH LOG WORKDIR   (exit 77: no LOG)
set -eu
lmdd=$1
bench=$2
log=$3
work=$4
[ -f "$log" ] || { echo "no $log: skipped"; exit 77; }
rm -rf "$work" && mkdir -p "$work"
"$lmdd" --listen 127.0.0.1:0 --data-dir "$work/data" --log-level warn > "$work/lmdd.out" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait $pid 2>/dev/null || true' EXIT
port=
for _ in $(seq 100); do
  port=$(sed -n 's/^lmdd listening on port \([0-9]*\)$/\1/p' "$work/lmdd.out")
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || { echo "lmdd did not start"; cat "$work/lmdd.out"; exit 1; }
"$bench" load --server "127.0.0.1:$port" --collection fleet --mode fleet --log "$log" \
  --robots 4 --hz 10 --seconds 3 > "$work/load.out" 2>&1
cat "$work/load.out" | grep -v '^load: '
grep -q 'errors=0' "$work/load.out" || { echo "FAIL: calls failed"; exit 1; }
grep -Eq 'global [1-9]' "$work/load.out" || { echo "FAIL: no global query after the kidnap"; exit 1; }
echo "fleet on a log: no errors, kidnapped robots asked globally"
