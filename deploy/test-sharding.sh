#!/usr/bin/env bash
# Sharding check on loopback: three lmdd shards behind nginx (the gRPC proxy of
# deploy/nginx/lmd-proxy.conf, which hashes the x-lmd-collection header).
#   1. installs nginx-light (if no nginx) and the build packages, builds lmdd
#      and lmdctl (only those targets) into build/ (or $LMD_BUILD_DIR);
#   2. starts shards on 127.0.0.1:50061..50063 and nginx on 127.0.0.1:50060;
#   3. inserts two maps into each of six collections through the proxy;
#   4. asks every shard directly which collections it holds: each collection
#      must sit on exactly one shard, whole; gets, lists and queries each
#      collection through the proxy and checks in nginx's access log that the
#      shard that answered is the one holding it;
#   5. kills (SIGKILL) the shard holding the most collections: calls for its
#      collections through the proxy must fail with UNAVAILABLE, the others must
#      keep answering, and no collection may appear on another shard;
#   6. restarts it on the same data directory: its collections answer again,
#      every map still there;
#   7. adds a fourth shard the way deploy/README.md says (deploy/lmd-placement
#      names the collections that move, deploy/move-collection.sh copies them,
#      nginx reloads, a second pass copies again and deletes the originals) and
#      checks every collection answers from its new place;
#   8. runs deploy/k8s/proxy.yaml's nginx config (TLS both sides) on loopback in
#      front of three shards with TLS and tokens.
# Run: bash deploy/test-sharding.sh   (root or sudo for the installs; ~1 min
# once built). Env: LMD_SHARD_BASE_PORT (default 50060: it and the next nine
# ports on 127.0.0.1 are used), LMD_BUILD_DIR.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${LMD_BUILD_DIR:-$root/build}
base=${LMD_SHARD_BASE_PORT:-50060}
proxy=127.0.0.1:$base
shards=(127.0.0.1:$((base + 1)) 127.0.0.1:$((base + 2)) 127.0.0.1:$((base + 3)))
collections=(warehouse-a plant-1 office-1f office-3f dock-a dock-b)

log() { printf '[test-sharding] %s\n' "$*"; }
fail() { printf '[test-sharding] FAIL: %s\n' "$*" >&2; exit 1; }

# --- 1. packages and build --------------------------------------------------------
if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
missing=()
command -v nginx >/dev/null || [ -x /usr/sbin/nginx ] || missing+=(nginx-light)
command -v python3 >/dev/null || missing+=(python3)  # deploy/lmd-placement
if [ ${#missing[@]} -gt 0 ]; then
  log "installing ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)
bash "$root/scripts/setup.sh"
generator=()
command -v ninja >/dev/null && [ ! -f "$build/Makefile" ] && generator=(-G Ninja)
cmake -S "$root" -B "$build" "${generator[@]}" >/dev/null
cmake --build "$build" -j "$(nproc)" --target lmdd lmdctl >/dev/null
lmdd_bin=$build/server/lmdd
lmdctl_bin=$build/client/lmdctl
log "$("$nginx_bin" -v 2>&1); lmdd and lmdctl from $build"

# --- 2. shards and proxy -------------------------------------------------------------
port_open() { (exec 3<>"/dev/tcp/${1%:*}/${1##*:}") 2>/dev/null; }
for address in "$proxy" "${shards[@]}" "127.0.0.1:$((base + 4))"; do
  port_open "$address" && fail "$address is in use (set LMD_SHARD_BASE_PORT)"
done

work=$(mktemp -d /tmp/lmd-test-sharding.XXXXXX)
chmod 0755 "$work"  # nginx's workers (user nobody) write its temp directories
pids=()
nginx_pid=
cleanup() {
  [ -n "$nginx_pid" ] && kill "$nginx_pid" 2>/dev/null || true
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

lmdctl() { timeout 60 "$lmdctl_bin" --timeout 10 "$@"; }
wait_serving() {  # ADDRESS: until ListCollections answers, 30 s at most
  local deadline=$((SECONDS + 30))
  until lmdctl --server "$1" collections >/dev/null 2>&1; do
    [ $SECONDS -lt $deadline ] || fail "$1 not serving after 30 s"
    sleep 0.2
  done
}
start_shard() {  # INDEX
  local i=$1
  mkdir -p "$work/shard$i"
  "$lmdd_bin" --listen "${shards[$i]}" --data-dir "$work/shard$i/data" >>"$work/shard$i/lmdd.log" 2>&1 &
  pids[$i]=$!
  wait_serving "${shards[$i]}"
}
for i in 0 1 2; do start_shard "$i"; done
log "shards: ${shards[*]} (pids ${pids[*]})"

mkdir -p "$work/nginx"
sed -e "s/127\.0\.0\.1:50060/$proxy/; s/127\.0\.0\.1:50061/${shards[0]}/; s/127\.0\.0\.1:50062/${shards[1]}/" \
  -e "s/127\.0\.0\.1:50063/${shards[2]}/" "$root/deploy/nginx/lmd-proxy.conf" >"$work/nginx/nginx.conf"
"$nginx_bin" -t -q -p "$work/nginx/" -c "$work/nginx/nginx.conf" -e "$work/nginx/error.log" ||
  fail "nginx -t rejected the config"
"$nginx_bin" -p "$work/nginx/" -c "$work/nginx/nginx.conf" -e "$work/nginx/error.log" -g 'daemon off;' \
  >>"$work/nginx/stderr.log" 2>&1 &
nginx_pid=$!
wait_serving "$proxy"
log "nginx (pid $nginx_pid) on $proxy: hash \$http_x_lmd_collection consistent over the three shards"

# --- 3. ingest through the proxy ---------------------------------------------------------
# Map k of collection c: a rectangular room whose size depends on (c, k), walls
# sampled every 5 cm, with a pillar; ids <collection>-m1, -m2.
make_map() {  # SEED FILE
  awk -v s="$1" 'BEGIN {
    w = 4 + (s * 7) % 5; h = 3 + (s * 3) % 4; px = 1 + (s % 3); py = 1 + (s % 2)
    for (x = 0; x <= w + 1e-9; x += 0.05) { print x, 0; print x, h }
    for (y = 0.05; y < h; y += 0.05) { print 0, y; print w, y }
    for (d = 0; d <= 0.5 + 1e-9; d += 0.05) { print px + d, py; print px + d, py + 0.5; print px, py + d; print px + 0.5, py + d }
  }' >"$2"
}
seed=0
for c in "${collections[@]}"; do
  for k in 1 2; do
    seed=$((seed + 1))
    make_map "$seed" "$work/$c-m$k.txt"
    lmdctl --server "$proxy" insert --collection "$c" --file "$work/$c-m$k.txt" --id "$c-m$k" --robot "robot-$k" >/dev/null ||
      fail "insert $c-m$k through the proxy"
  done
done
log "inserted 2 maps into each of ${#collections[@]} collections through $proxy"

# --- 4. placement and queries ----------------------------------------------------------
declare -A home  # collection -> shard index
snapshot_placement() {  # fills $work/placement.<i> with "name maps" per shard
  for i in 0 1 2; do
    lmdctl --server "${shards[$i]}" collections | awk '{ sub("maps=", "", $2); print $1, $2 }' >"$work/placement.$i"
  done
}
snapshot_placement
for c in "${collections[@]}"; do
  holders=()
  for i in 0 1 2; do
    if grep -q "^$c " "$work/placement.$i"; then holders+=("$i"); fi
  done
  [ ${#holders[@]} -eq 1 ] || fail "$c is on ${#holders[@]} shards (${holders[*]:-none})"
  maps=$(awk -v c="$c" '$1 == c { print $2 }' "$work/placement.${holders[0]}")
  [ "$maps" = 2 ] || fail "$c holds $maps maps on shard ${holders[0]}, want 2"
  home[$c]=${holders[0]}
done
# The placement tool of deploy/README.md agrees with nginx.
expected=$("$root/deploy/lmd-placement" --shards "$(IFS=,; echo "${shards[*]}")" "${collections[@]}")
for c in "${collections[@]}"; do
  grep -qx "$c ${shards[${home[$c]}]}" <<<"$expected" || fail "deploy/lmd-placement puts $c elsewhere: $expected"
done
log "placement as deploy/lmd-placement computes it"
for i in 0 1 2; do
  held=$(awk '{ printf "%s%s(%s maps)", sep, $1, $2; sep = ", " }' "$work/placement.$i")
  log "shard $i (${shards[$i]}) holds: ${held:-nothing}"
done

: >"$work/nginx/access.log"  # only the query calls from here on
for c in "${collections[@]}"; do
  lmdctl --server "$proxy" get --collection "$c" --id "$c-m1" >/dev/null || fail "get $c-m1 through the proxy"
  listed=$(lmdctl --server "$proxy" maps --collection "$c" | grep -c "$c-m")
  [ "$listed" = 2 ] || fail "maps of $c through the proxy lists $listed maps"
  top=$(lmdctl --server "$proxy" query --collection "$c" --file "$work/$c-m2.txt" --top-k 2 | awk 'NR == 1 { print $2 }')
  [ "$top" = "$c-m2" ] || fail "query of $c-m2 through the proxy: top hit '$top'"
done
sleep 0.5  # nginx writes its access log line after the call
for c in "${collections[@]}"; do
  answered=$(grep "collection=\"$c\"" "$work/nginx/access.log" | sed 's/.* shard=\([^ ]*\) .*/\1/' | sort -u | tr '\n' ' ')
  [ "$answered" = "${shards[${home[$c]}]} " ] || fail "calls for $c answered by '$answered', want ${shards[${home[$c]}]}"
done
log "get, maps and query (top hit = the query's own map) of every collection through the proxy,"
log "  each answered by the shard holding it (nginx access log: $(wc -l <"$work/nginx/access.log") calls)"
sed -n '1p' "$work/nginx/access.log" | sed 's/^/    /'
# Calls without a collection (ListCollections, Stats of everything) carry no
# header: nginx spreads them over the shards, so each shard is asked directly.
: >"$work/nginx/access.log"
for _ in 1 2 3 4 5 6; do lmdctl --server "$proxy" collections >/dev/null; done
sleep 0.5
log "6 ListCollections calls without the header went to: $(sed 's/.* shard=\([^ ]*\) .*/\1/' "$work/nginx/access.log" | sort | uniq -c | awk '{ printf "%s%s x%s", sep, $2, $1; sep = ", " }')"

# --- 5. one shard down ------------------------------------------------------------------
victim=0
for i in 1 2; do
  [ "$(wc -l <"$work/placement.$i")" -gt "$(wc -l <"$work/placement.$victim")" ] && victim=$i
done
kill -KILL "${pids[$victim]}"
wait "${pids[$victim]}" 2>/dev/null || true
log "killed shard $victim (${shards[$victim]}, SIGKILL)"
failed=0 answered=0
for c in "${collections[@]}"; do
  if out=$(lmdctl --server "$proxy" get --collection "$c" --id "$c-m1" 2>&1); then
    [ "${home[$c]}" != "$victim" ] || fail "$c (on the dead shard) still answered: $out"
    answered=$((answered + 1))
    log "  $c (shard ${home[$c]}): OK"
  else
    [ "${home[$c]}" = "$victim" ] || fail "$c (on live shard ${home[$c]}) failed: $out"
    out=$(tail -n 1 <<<"$out")
    [[ "$out" == "lmdctl: UNAVAILABLE: "* ]] || fail "$c failed without UNAVAILABLE: $out"
    failed=$((failed + 1))
    log "  $c (shard ${home[$c]}): $out"
  fi
done
# An insert for a dead shard's collection must not land elsewhere.
for c in "${collections[@]}"; do
  [ "${home[$c]}" = "$victim" ] || continue
  if lmdctl --server "$proxy" insert --collection "$c" --file "$work/$c-m1.txt" --id "$c-m3" >/dev/null 2>&1; then
    fail "insert into $c succeeded while its shard was down"
  fi
done
for i in 0 1 2; do
  [ "$i" = "$victim" ] && continue
  for c in "${collections[@]}"; do
    [ "${home[$c]}" = "$victim" ] || continue
    lmdctl --server "${shards[$i]}" collections | grep -q "^$c " && fail "$c appeared on shard $i during the outage"
  done
done
log "shard $victim down: its $failed collection(s) fail with UNAVAILABLE (inserts too, nothing rehashed),"
log "  the other $answered keep answering"

# --- 6. back up --------------------------------------------------------------------------
start_shard "$victim"
log "restarted shard $victim on its data directory (pid ${pids[$victim]})"
for c in "${collections[@]}"; do
  lmdctl --server "$proxy" get --collection "$c" --id "$c-m2" >/dev/null || fail "get $c-m2 after the restart"
  listed=$(lmdctl --server "$proxy" maps --collection "$c" | grep -c "$c-m")
  [ "$listed" = 2 ] || fail "$c lists $listed maps after the restart, want 2"
done
snapshot_placement
for c in "${collections[@]}"; do
  grep -q "^$c 2$" "$work/placement.${home[$c]}" || fail "$c not whole on shard ${home[$c]} after the restart"
done
log "all ${#collections[@]} collections answer again, every map intact, placement unchanged"

# --- 7. adding a fourth shard (deploy/README.md, "Adding a shard") -------------------
new_shard=127.0.0.1:$((base + 4))
port_open "$new_shard" && fail "$new_shard is in use"
old_list=$(IFS=,; echo "${shards[*]}")
shards+=("$new_shard")
start_shard 3
new_list=$(IFS=,; echo "${shards[*]}")
moves=$("$root/deploy/lmd-placement" --shards "$old_list" --new-shards "$new_list" "${collections[@]}")
[ -n "$moves" ] || fail "no collection moves to the new shard (choose other names)"
log "shard 3 ($new_shard) started empty; deploy/lmd-placement says these move to it:"
sed 's/^/    /' <<<"$moves"
grep -v -- "-> $new_shard\$" <<<"$moves" && fail "a collection moves between old shards"
# a) copy while the proxy still routes to the old shards
while read -r c from _ to; do
  LMDCTL=$lmdctl_bin "$root/deploy/move-collection.sh" --from "$from" --to "$to" --collection "$c" | sed 's/^/    /'
done <<<"$moves"
# b) the proxy's upstream gets the new server; nginx reloads without dropping calls
sed -i "s|^\( *\)server ${shards[2]} max_fails=0;|&\n\1server $new_shard max_fails=0;|" "$work/nginx/nginx.conf"
grep -q "server $new_shard max_fails=0;" "$work/nginx/nginx.conf" || fail "could not add the shard to nginx.conf"
"$nginx_bin" -t -q -p "$work/nginx/" -c "$work/nginx/nginx.conf" -e "$work/nginx/error.log" || fail "nginx -t"
kill -HUP "$nginx_pid"
# c) copy again (writes that reached the old shard meanwhile), then delete there
first_moved=$(awk 'NR == 1 { print $1 }' <<<"$moves")
deadline=$((SECONDS + 20))
until : >"$work/nginx/access.log" && lmdctl --server "$proxy" maps --collection "$first_moved" >/dev/null &&
  sleep 0.3 && grep -q "shard=$new_shard " "$work/nginx/access.log"; do
  [ $SECONDS -lt $deadline ] || fail "nginx still routes $first_moved to its old shard after the reload"
done
while read -r c from _ to; do
  LMDCTL=$lmdctl_bin "$root/deploy/move-collection.sh" --from "$from" --to "$to" --collection "$c" --delete |
    sed 's/^/    /'
done <<<"$moves"
log "nginx reloaded with four shards"
expected=$("$root/deploy/lmd-placement" --shards "$new_list" "${collections[@]}")
: >"$work/nginx/access.log"
for c in "${collections[@]}"; do
  want=$(awk -v c="$c" '$1 == c { print $2 }' <<<"$expected")
  lmdctl --server "$want" maps --collection "$c" | grep -c "$c-m" | grep -qx 2 || fail "$c not whole on $want"
  listed=$(lmdctl --server "$proxy" maps --collection "$c" | grep -c "$c-m")
  [ "$listed" = 2 ] || fail "maps of $c through the proxy lists $listed maps after the move"
  top=$(lmdctl --server "$proxy" query --collection "$c" --file "$work/$c-m1.txt" --top-k 2 | awk 'NR == 1 { print $2 }')
  [ "$top" = "$c-m1" ] || fail "query of $c-m1 after the move: top hit '$top'"
done
sleep 0.5
for c in "${collections[@]}"; do
  want=$(awk -v c="$c" '$1 == c { print $2 }' <<<"$expected")
  answered=$(grep "collection=\"$c\"" "$work/nginx/access.log" | sed 's/.* shard=\([^ ]*\) .*/\1/' | sort -u | tr '\n' ' ')
  [ "$answered" = "$want " ] || fail "calls for $c answered by '$answered', want $want"
done
while read -r c from _ to; do
  left=$(lmdctl --server "$from" maps --collection "$c" 2>/dev/null | wc -l)
  [ "$left" = 0 ] || fail "$c still has $left maps on $from"
done <<<"$moves"
log "after the move every collection is whole on its new shard, answered there through the proxy,"
log "  and the moved ones hold no map on their old shard"

# --- 8. the Kubernetes proxy config: TLS on both sides, tokens ------------------------
# deploy/k8s/proxy.yaml's nginx.conf with the shard Services, ports and mount
# paths rewritten to loopback; three more shards with TLS and tokens.
bash "$root/deploy/make-dev-secrets.sh" "$work/secrets" lmdd >/dev/null
admin=$(cat "$work/secrets/admin.token")
tls_shards=(127.0.0.1:$((base + 5)) 127.0.0.1:$((base + 6)) 127.0.0.1:$((base + 7)))
tls_proxy=127.0.0.1:$((base + 8))
for address in "${tls_shards[@]}" "$tls_proxy" "127.0.0.1:$((base + 9))"; do
  port_open "$address" && fail "$address is in use"
done
tls_flags=(--tls-ca "$work/secrets/ca.crt")
for i in 0 1 2; do
  mkdir -p "$work/tls$i"
  "$lmdd_bin" --listen "${tls_shards[$i]}" --data-dir "$work/tls$i/data" --set "tls_cert_file=$work/secrets/tls.crt" \
    --set "tls_key_file=$work/secrets/tls.key" --set "tokens_file=$work/secrets/tokens" >>"$work/tls$i/lmdd.log" 2>&1 &
  pids+=($!)
done
mkdir -p "$work/nginx-tls"
awk '/^  nginx.conf: [|]/ { on = 1; next } on && /^---/ { exit } on { sub(/^    /, ""); print }' \
  "$root/deploy/k8s/proxy.yaml" |
  sed -e "s|lmd-shard-0:50051|${tls_shards[0]}|; s|lmd-shard-1:50051|${tls_shards[1]}|; s|lmd-shard-2:50051|${tls_shards[2]}|" \
    -e "s|listen 8443 |listen $tls_proxy |; s|listen 8080;|listen 127.0.0.1:$((base + 9));|" \
    -e "s|/tmp/|$work/nginx-tls/|g; s|/etc/lmd/tls/|$work/secrets/|g; s|/dev/stdout|$work/nginx-tls/access.log|" \
    >"$work/nginx-tls/nginx.conf"
"$nginx_bin" -t -q -p "$work/nginx-tls/" -c "$work/nginx-tls/nginx.conf" -e "$work/nginx-tls/error.log" ||
  fail "nginx -t rejected deploy/k8s/proxy.yaml's config"
"$nginx_bin" -p "$work/nginx-tls/" -c "$work/nginx-tls/nginx.conf" -e "$work/nginx-tls/error.log" -g 'daemon off;' \
  >>"$work/nginx-tls/stderr.log" 2>&1 &
nginx_tls_pid=$!
pids+=("$nginx_tls_pid")
for address in "${tls_shards[@]}" "$tls_proxy"; do
  deadline=$((SECONDS + 30))
  until lmdctl --server "$address" "${tls_flags[@]}" --tls-server-name localhost --token "$admin" collections >/dev/null 2>&1; do
    [ $SECONDS -lt $deadline ] || fail "$address not serving over TLS after 30 s"
    sleep 0.2
  done
done
for c in "${collections[@]}"; do
  lmdctl --server "$tls_proxy" "${tls_flags[@]}" --tls-server-name localhost --token "$admin" \
    insert --collection "$c" --file "$work/$c-m1.txt" --id "$c-m1" >/dev/null || fail "TLS insert of $c through the proxy"
done
expected=$("$root/deploy/lmd-placement" --shards "$(IFS=,; echo "${tls_shards[*]}")" "${collections[@]}")
for c in "${collections[@]}"; do
  want=$(awk -v c="$c" '$1 == c { print $2 }' <<<"$expected")
  lmdctl --server "$want" "${tls_flags[@]}" --tls-server-name localhost --token "$admin" get --collection "$c" --id "$c-m1" \
    >/dev/null || fail "$c is not on $want"
  lmdctl --server "$tls_proxy" "${tls_flags[@]}" --tls-server-name localhost --token "$admin" \
    get --collection "$c" --id "$c-m1" >/dev/null || fail "TLS get of $c through the proxy"
done
out=$(lmdctl --server "$tls_proxy" "${tls_flags[@]}" --tls-server-name localhost get --collection "${collections[0]}" \
  --id "${collections[0]}-m1" 2>&1) && fail "a call without a token passed the proxy and lmdd"
[[ "$(tail -n 1 <<<"$out")" == "lmdctl: UNAUTHENTICATED: "* ]] || fail "no token: want UNAUTHENTICATED, got: $out"
curl -fsS "http://127.0.0.1:$((base + 9))/healthz" >/dev/null 2>&1 || [ ! -x "$(command -v curl)" ] || fail "proxy /healthz"
log "deploy/k8s/proxy.yaml's nginx config on loopback: TLS to the proxy and from it to TLS + token shards"
log "  (name lmdd verified), ${#collections[@]} collections placed as deploy/lmd-placement says; no token: UNAUTHENTICATED"
log "PASS"
