#!/usr/bin/env bash
# Replication check on loopback: three etcd members and three lmdd nodes
# (cluster_etcd set), each a separate process, writes streaming in at 100/s
# (lmd-bench writes) while nodes die:
#   1. kill -9 the primary of a collection, ten times (a new collection each
#      time): writes must resume within 5 s, every acknowledged map must be on
#      every surviving copy, and on the killed node once it is back and caught up;
#   2. kill -9 a follower and restart it: it catches up and rejoins the
#      in-sync set; nothing acknowledged missing anywhere;
#   3. SIGSTOP the primary beyond its lease, then SIGCONT: it is fenced (a new
#      primary, a new epoch) and nothing acknowledged is lost;
#   4. kill one etcd member (a follower) during writes: writes go on;
#   5. a fourth node that holds no copy answers reads and queries (forwarded),
#      then takes the copies it ranks highest for (rebalancing): each collection
#      settles on 3 in-sync copies, every acknowledged map on all of them;
#   6. TLS and tokens between nodes;
#   7. insert throughput, one node alone and a collection with three copies;
#   8. query throughput, the queries sent to one copy and spread over three.
# Each node runs one worker thread (worker_threads=1), as if it had a core of
# its own: three nodes share this machine's cores, so throughput ratios are
# bounded by them (two cores: reads over three copies gain at most 2x).
# Ends with one line: PASS, or FAIL: <why> (exit 1).
# Run: bash deploy/test-replication.sh   (~4 min once built; installs etcd and
# the build packages through scripts/setup.sh). Env: LMD_BUILD_DIR,
# LMD_REPL_BASE_PORT (default 29300, below Linux's ephemeral ports, so that no
# outgoing connection holds one: it and the next 30 ports are used).
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${LMD_BUILD_DIR:-$root/build}
base=${LMD_REPL_BASE_PORT:-29300}
work=$(mktemp -d)
log() { printf '[test-replication] %s\n' "$*"; }
fail() { printf '[test-replication] FAIL: %s\n' "$*"; exit 1; }

bash "$root/scripts/setup.sh" >/dev/null
generator=()
command -v ninja >/dev/null && [ ! -f "$build/Makefile" ] && generator=(-G Ninja)
cmake -S "$root" -B "$build" "${generator[@]}" >/dev/null
cmake --build "$build" -j "$(nproc)" --target lmdd lmdctl lmd-bench >/dev/null
lmdd_bin=$build/server/lmdd
lmdctl_bin=$build/client/lmdctl
bench_bin=$build/bench/lmd-bench
py=/usr/bin/python3

declare -A pids
cleanup() {
  for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

# --- etcd: three members ---------------------------------------------------------
etcd_client() { echo "127.0.0.1:$((base + $1))"; }         # members 0..2
etcd_peer() { echo "127.0.0.1:$((base + 10 + $1))"; }
initial=""
for m in 0 1 2; do initial+="${initial:+,}e$m=http://$(etcd_peer $m)"; done
start_etcd() {
  local m=$1
  etcd --name "e$m" --data-dir "$work/etcd$m" --listen-client-urls "http://$(etcd_client "$m")" \
    --advertise-client-urls "http://$(etcd_client "$m")" --listen-peer-urls "http://$(etcd_peer "$m")" \
    --initial-advertise-peer-urls "http://$(etcd_peer "$m")" --initial-cluster "$initial" \
    --initial-cluster-state new >"$work/etcd$m.log" 2>&1 &
  pids[etcd$m]=$!
}
for m in 0 1 2; do start_etcd $m; done
endpoints="$(etcd_client 0),$(etcd_client 1),$(etcd_client 2)"
for _ in $(seq 100); do
  ETCDCTL_API=3 etcdctl --endpoints "$endpoints" endpoint health >/dev/null 2>&1 && break
  sleep 0.2
done
ETCDCTL_API=3 etcdctl --endpoints "$endpoints" endpoint health >/dev/null 2>&1 || fail "etcd did not start"
log "etcd $(etcd --version | head -1 | awk '{print $3}'): 3 members on $endpoints"

# --- lmdd nodes ------------------------------------------------------------------
node_addr() { echo "127.0.0.1:$((base + 20 + $1))"; }      # nodes 1..7
start_node() {
  local n=$1
  "$lmdd_bin" --listen "$(node_addr "$n")" --data-dir "$work/n$n" --log-level warn --set worker_threads=1 \
    --set cluster_etcd="$endpoints" --set cluster_node_id="n$n" >>"$work/n$n.log" 2>&1 &
  pids[n$n]=$!
  for _ in $(seq 100); do
    "$lmdctl_bin" --server "$(node_addr "$n")" cluster >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  fail "node n$n did not start: $(tail -n 3 "$work/n$n.log")"
}
for n in 1 2 3; do start_node $n; done
servers="$(node_addr 1),$(node_addr 2),$(node_addr 3)"
log "lmdd nodes n1 n2 n3 on $servers"

cluster_json() { "$lmdctl_bin" --server "$1" cluster --json; }
# The primary's node id of collection $1 (asked of any live node).
primary_of() {
  local c=$1 n
  for n in 1 2 3 4; do
    out=$(cluster_json "$(node_addr $n)" 2>/dev/null) || continue
    echo "$out" | $py -c "import json,sys; d=json.load(sys.stdin); print(next((c['node_id'] for p in d.get('placements',[]) if p['collection']=='$c' for c in p['copies'] if c.get('primary')), ''))"
    return 0
  done
}
# Waits until every replica of collection $1 is in sync with lag 0.
wait_in_sync() {
  local c=$1
  for _ in $(seq 300); do
    if cluster_json "$(node_addr 1)" 2>/dev/null | $py -c "
import json,sys
d=json.load(sys.stdin)
p=[p for p in d.get('placements',[]) if p['collection']=='$c']
ok=p and len(p[0]['copies'])>=3 and all(c.get('in_sync') and c.get('reachable') and int(c.get('lag','0'))==0 for c in p[0]['copies'])
sys.exit(0 if ok else 1)"; then return 0; fi
    sleep 0.1
  done
  fail "collection $c: copies not back in sync after 30 s: $("$lmdctl_bin" --server "$(node_addr 1)" cluster)"
}
node_number() { echo "${1#n}"; }
# Starts a writer into collection $1 for $2 s, sending first to node $3 (1-3;
# the node that takes a collection's first write is its primary); its pid in
# writer_pid.
start_writer() {
  local first=${3:-1} order="" n
  for n in $(seq 0 2); do order+="${order:+,}$(node_addr $(( (first - 1 + n) % 3 + 1 )))"; done
  "$bench_bin" writes --servers "$order" --collection "$1" --rate 100 --seconds "$2" --acked "$work/$1.acked" \
    >"$work/$1.out" 2>"$work/$1.err" &
  writer_pid=$!
}
gap_of() { sed -n 's/.*longest gap \([0-9.]*\) s.*/\1/p' "$work/$1.out"; }
verify() {  # collection, copies needed
  "$bench_bin" writes --verify --servers "$servers" --collection "$1" --acked "$work/$1.acked" --copies "$2" \
    >"$work/$1.verify" || fail "collection $1: $(cat "$work/$1.verify")"
}

# --- 1. kill -9 the primary, ten times ---------------------------------------------
gaps=()
for k in $(seq 1 10); do
  c=kill$k
  start_writer "$c" 7 $(( (k - 1) % 3 + 1 ))
  sleep 2.5
  victim=$(primary_of "$c")
  [ -n "$victim" ] || fail "collection $c has no primary"
  kill -9 "${pids[$victim]}"
  wait "${pids[$victim]}" 2>/dev/null || true
  wait "$writer_pid" || fail "writer into $c: $(tail -n 2 "$work/$c.err")"
  gap=$(gap_of "$c")
  gaps+=("$gap")
  verify "$c" 2
  start_node "$(node_number "$victim")"
  wait_in_sync "$c"
  verify "$c" 3
  log "kill $k: primary $victim killed; writes resumed after $gap s; $(grep -c . "$work/$c.acked") acknowledged maps on all 3 copies after it caught up"
done
worst=$(printf '%s\n' "${gaps[@]}" | sort -g | tail -1)
log "failover (longest gap without an acknowledged write) over 10 kills: $(printf '%s\n' "${gaps[@]}" | sort -g | tr '\n' ' ')s; worst $worst s"
awk -v w="$worst" 'BEGIN { exit !(w <= 5.0) }' || fail "writes resumed only after $worst s (target 5 s)"

# --- 2. kill -9 a follower, restart it -----------------------------------------------
c=follower
start_writer "$c" 6
sleep 2
primary=$(primary_of "$c")
for n in 1 2 3; do [ "n$n" != "$primary" ] && follower=n$n && break; done
kill -9 "${pids[$follower]}"
wait "${pids[$follower]}" 2>/dev/null || true
wait "$writer_pid" || fail "writer into $c"
verify "$c" 2
start_node "$(node_number "$follower")"
wait_in_sync "$c"
verify "$c" 3
log "follower $follower killed during writes (longest gap $(gap_of $c) s), restarted: caught up, in sync, every acknowledged map on 3 copies"

# --- 3. SIGSTOP the primary beyond its lease ---------------------------------------
c=fence
start_writer "$c" 10
sleep 2
stopped=$(primary_of "$c")
kill -STOP "${pids[$stopped]}"
sleep 5  # the lease (2 s) expires; a copy is promoted
kill -CONT "${pids[$stopped]}"
wait "$writer_pid" || fail "writer into $c"
now=$(primary_of "$c")
[ "$now" != "$stopped" ] || fail "the paused primary $stopped is still the primary of $c"
wait_in_sync "$c"
verify "$c" 3
log "primary $stopped paused 5 s (lease 2 s): fenced, $now took over (longest gap $(gap_of $c) s); it rejoined in sync; nothing acknowledged lost"

# --- 4. kill one etcd member (not the leader) ------------------------------------
# Losing etcd's leader costs an election (about 1 s with etcd's defaults), in
# which leases cannot be renewed: a 2 s lease may lapse and its primaries fail
# over (deploy/README.md, "Operation"). A follower's loss must change nothing.
c=etcd-member
follower_member=$(ETCDCTL_API=3 etcdctl --endpoints "$endpoints" endpoint status -w json | $py -c "
import json,sys
for i,e in enumerate(json.load(sys.stdin)):
    if e['Status']['header']['member_id'] != e['Status']['leader']:
        print(i); break")
[ -n "$follower_member" ] || fail "no etcd follower found"
start_writer "$c" 6
sleep 2
kill -9 "${pids[etcd$follower_member]}"
wait "${pids[etcd$follower_member]}" 2>/dev/null || true
wait "$writer_pid" || fail "writer into $c"
verify "$c" 3
gap=$(gap_of $c)
awk -v g="$gap" 'BEGIN { exit !(g <= 1.5) }' || fail "an etcd follower's death stalled writes for $gap s"
start_etcd "$follower_member"
log "etcd member e$follower_member (a follower) killed during writes: longest gap $gap s, every acknowledged map on 3 copies"

# --- 5. a node without a copy answers ------------------------------------------------
start_node 4
first_map=$(head -n 1 "$work/kill1.acked" | cut -d' ' -f1)
"$lmdctl_bin" --server "$(node_addr 4)" get --collection kill1 --id "$first_map" --out "$work/q.points" >/dev/null \
  || fail "node n4 (no copy of kill1) did not answer a get"
"$lmdctl_bin" --server "$(node_addr 4)" list --collection kill1 >/dev/null || fail "node n4 did not answer a list"
answer=$("$lmdctl_bin" --server "$(node_addr 4)" query --collection kill1 --file "$work/q.points" --top-k 1) \
  || fail "node n4 did not answer a query"
log "node n4, just joined (no copy in sync yet), answered a get, a list and a query (forwarded): $(echo "$answer" | head -1)"
# Rebalancing: n4 copies the collections it ranks highest for; each copy it
# replaces leaves once n4 is in sync.
settled=""
for _ in $(seq 600); do
  settled=$(cluster_json "$(node_addr 1)" 2>/dev/null | $py -c "
import json,sys
d=json.load(sys.stdin)
ps=[p for p in d.get('placements',[]) if p['collection'].startswith('kill')]
ok=len(ps)==10 and all(len(p['copies'])==int(p.get('copies_wanted',0)) and all(c.get('in_sync') and c.get('reachable') and int(c.get('lag','0'))==0 for c in p['copies']) for p in ps)
print(sum(1 for p in ps for c in p['copies'] if c['node_id']=='n4') if ok else '')") && [ -n "$settled" ] && break
  sleep 0.2
done
[ -n "$settled" ] || fail "the placements did not settle after n4 joined: $("$lmdctl_bin" --server "$(node_addr 1)" cluster)"
for k in $(seq 10); do
  "$bench_bin" writes --verify --servers "$servers,$(node_addr 4)" --collection "kill$k" --acked "$work/kill$k.acked" \
    --copies 3 >"$work/kill$k.verify4" || fail "kill$k after rebalancing: $(cat "$work/kill$k.verify4")"
done
# Each copy n4 replaced is deleted by the node it left (its store lists it no more).
held=0
for _ in $(seq 100); do
  held=0
  for n in 1 2 3 4; do
    held=$(( held + $("$lmdctl_bin" --server "$(node_addr "$n")" collections | grep -c '^kill' || true) ))
  done
  [ "$held" -eq 30 ] && break
  sleep 0.2
done
[ "$held" -eq 30 ] || fail "after rebalancing the 4 nodes' stores hold $held copies of the 10 kill collections, not 30"
log "n4 took $settled of the 10 kill collections' copies (rebalancing); each settled on 3 in-sync copies holding every acknowledged map; the copies n4 replaced were deleted (30 held in all)"

# --- 6. TLS and tokens between nodes ---------------------------------------------------
bash "$root/deploy/make-dev-secrets.sh" "$work/secrets" >/dev/null
sec=$work/secrets
for n in 6 7; do
  "$lmdd_bin" --listen "$(node_addr "$n")" --data-dir "$work/n$n" --log-level warn \
    --set cluster_etcd="$endpoints" --set cluster_node_id="s$n" --set cluster_prefix=/lmd-tls \
    --set tls_cert_file="$sec/tls.crt" --set tls_key_file="$sec/tls.key" --set tokens_file="$sec/tokens" \
    --set cluster_tls_ca_file="$sec/ca.crt" --set cluster_token_file="$sec/admin.token" >>"$work/n$n.log" 2>&1 &
  pids[n$n]=$!
done
secure=(--tls-ca "$sec/ca.crt" --token "$(cat "$sec/admin.token")")
for _ in $(seq 100); do
  "$lmdctl_bin" --server "$(node_addr 7)" "${secure[@]}" cluster >/dev/null 2>&1 && break
  sleep 0.1
done
"$lmdctl_bin" --server "$(node_addr 6)" "${secure[@]}" insert --collection secure --file "$work/q.points" --id s1 >/dev/null \
  || fail "insert into the TLS cluster: $(tail -n 3 "$work/n6.log")"
"$lmdctl_bin" --server "$(node_addr 7)" "${secure[@]}" get --collection secure --id s1 >/dev/null \
  || fail "get from the TLS cluster's other node"
copies=$("$lmdctl_bin" --server "$(node_addr 7)" "${secure[@]}" cluster --json | $py -c "
import json,sys
p=[p for p in json.load(sys.stdin)['placements'] if p['collection']=='secure'][0]
print(sum(1 for c in p['copies'] if c.get('in_sync') and int(c.get('seq','0'))==1))")
[ "$copies" = 2 ] || fail "the TLS cluster holds the write on $copies copies, not 2"
"$lmdctl_bin" --server "$(node_addr 7)" --tls-ca "$sec/ca.crt" get --collection secure --id s1 >/dev/null 2>&1 \
  && fail "the TLS cluster answered a call without a token"
log "two nodes with TLS and tokens: a write to s6 on both copies over TLS, read through s7; no token, no answer"

# --- 7. insert throughput ------------------------------------------------------------
"$lmdd_bin" --listen "$(node_addr 5)" --data-dir "$work/alone" --log-level warn --set worker_threads=1 \
  >"$work/alone.log" 2>&1 &
pids[alone]=$!
sleep 1
alone=$("$bench_bin" fill --server "$(node_addr 5)" --collection fill --maps 1500 --batch 1 2>/dev/null | sed -n 's/.*(\([0-9]*\) maps\/s.*/\1/p')
replicated=$("$bench_bin" fill --server "$(node_addr 1)" --collection fill3 --maps 1500 --batch 1 2>/dev/null | sed -n 's/.*(\([0-9]*\) maps\/s.*/\1/p')
log "inserts, one map per call: one node alone $alone/s, three copies $replicated/s ($(awk -v a="$alone" -v r="$replicated" 'BEGIN { printf "%.0f", 100 * r / a }') %)"

# --- 8. query throughput ---------------------------------------------------------------
wait_in_sync fill3
rate() { sed -n 's/.*(\([0-9.]*\) queries\/s).*/\1/p'; }
one=$("$bench_bin" reads --servers "$(node_addr 1)" --collection fill3 --threads 6 --seconds 10) \
  || fail "queries to one copy: $one"
three=$("$bench_bin" reads --servers "$servers" --collection fill3 --threads 6 --seconds 10) \
  || fail "queries over three copies: $three"
log "queries, one copy: $one"
log "queries, three copies: $three"
log "query throughput over three copies: $(awk -v a="$(echo "$one" | rate)" -v b="$(echo "$three" | rate)" 'BEGIN { printf "%.2f", b / a }') x one copy's"

echo "[test-replication] PASS: 10 primary kills (worst failover $worst s), follower restart, fenced pause, etcd member loss, forwarding; no acknowledged map lost"
