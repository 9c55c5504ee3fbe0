#!/usr/bin/env bash
# Copies one collection from one lmdd shard to another with lmdctl, map by map
# (same map ids, so running it again is harmless: an insert with an existing
# id replaces the map), checks that the target holds every map of the source,
# and with --delete then deletes the maps from the source. Used when adding a
# shard (deploy/README.md, "Adding a shard").
#
#   deploy/move-collection.sh --from HOST:PORT --to HOST:PORT --collection C [--delete]
#
# Talk to the shards directly, never through the proxy. Extra lmdctl flags
# (TLS, token) come from $LMDCTL_FLAGS, e.g.
#   LMDCTL_FLAGS="--tls-ca ca.crt --tls-server-name lmdd --token $ADMIN" deploy/move-collection.sh ...
# $LMDCTL is the lmdctl binary (default: build/client/lmdctl, else lmdctl on PATH).
#
# What travels: map id, points, trajectory (pose lines) and robot id. What
# does not, because lmdctl's points files do not carry it: scans, sequence,
# time and pose hint. Coordinates go through text with 6 significant digits.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
lmdctl_bin=${LMDCTL:-$root/build/client/lmdctl}
[ -x "$lmdctl_bin" ] || lmdctl_bin=$(command -v lmdctl) || { echo "move-collection: no lmdctl" >&2; exit 2; }
from= to= collection= delete=0
while [ $# -gt 0 ]; do
  case $1 in
    --from) from=$2; shift 2 ;;
    --to) to=$2; shift 2 ;;
    --collection) collection=$2; shift 2 ;;
    --delete) delete=1; shift ;;
    *) echo "move-collection: unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -n "$from" ] && [ -n "$to" ] && [ -n "$collection" ] ||
  { echo "usage: move-collection.sh --from HOST:PORT --to HOST:PORT --collection C [--delete]" >&2; exit 2; }
# shellcheck disable=SC2086  # LMDCTL_FLAGS is a list of flags
ctl() { local server=$1; shift; timeout 120 "$lmdctl_bin" --server "$server" ${LMDCTL_FLAGS:-} --timeout 60 "$@" </dev/null; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ctl "$from" maps --collection "$collection" >"$work/source"
count=$(wc -l <"$work/source")
while read -r id robot _; do
  robot=${robot#robot=}
  ctl "$from" get --collection "$collection" --id "$id" --out "$work/map.txt" >/dev/null
  if [ "$robot" = "-" ]; then robot_flag=(); else robot_flag=(--robot "$robot"); fi
  ctl "$to" insert --collection "$collection" --file "$work/map.txt" --id "$id" "${robot_flag[@]}" >/dev/null
done <"$work/source"
ctl "$to" maps --collection "$collection" | awk '{ print $1 }' | sort >"$work/target"
missing=$(awk '{ print $1 }' "$work/source" | sort | comm -23 - "$work/target" | wc -l)
[ "$missing" -eq 0 ] || { echo "move-collection: $missing maps of $collection missing on $to" >&2; exit 1; }
echo "copied $count maps of $collection from $from to $to"
if [ "$delete" = 1 ]; then
  while read -r id _; do
    ctl "$from" delete --collection "$collection" --id "$id" >/dev/null
  done <"$work/source"
  echo "deleted $count maps of $collection from $from"
fi
