#!/usr/bin/env bash
# ctest for lmd_health_probe: exit 0 against a serving lmdd (plaintext), 1 with
# one line on stderr against a closed port and after lmdd stopped, 2 on a
# usage error.  Usage: probe_test.sh LMDD PROBE
set -uo pipefail
lmdd=$1 probe=$2
work=$(mktemp -d)
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; cat "$work/lmdd.log" 2>/dev/null; exit 1; }

"$lmdd" --listen 127.0.0.1:0 --data-dir "$work/data" >"$work/lmdd.log" 2>&1 &
pid=$!
port=
for _ in $(seq 1 100); do
  port=$(sed -n 's/^lmdd listening on port \([0-9]*\)$/\1/p' "$work/lmdd.log")
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || fail "lmdd did not start"

"$probe" --addr "127.0.0.1:$port" --timeout 5 || fail "probe of a serving lmdd: exit $?"
echo "ok: serving lmdd -> exit 0"

"$probe" --addr "127.0.0.1:$port" --tls-ca /nonexistent.pem 2>"$work/err"; code=$?
[ "$code" = 1 ] && [ "$(wc -l <"$work/err")" = 1 ] || fail "unreadable CA: exit $code, $(cat "$work/err")"
echo "ok: unreadable CA -> exit 1: $(cat "$work/err")"

"$probe" --timeout nope 2>/dev/null; code=$?
[ "$code" = 2 ] || fail "bad --timeout: exit $code, want 2"
echo "ok: usage error -> exit 2"

kill "$pid"; wait "$pid"; pid=
"$probe" --addr "127.0.0.1:$port" --timeout 2 2>"$work/err"; code=$?
[ "$code" = 1 ] && [ "$(wc -l <"$work/err")" = 1 ] || fail "stopped lmdd: exit $code, $(cat "$work/err")"
echo "ok: stopped lmdd -> exit 1: $(cat "$work/err")"

# TLS: a certificate from deploy/make-dev-secrets.sh (valid for localhost).
bash "$(dirname "$0")/../make-dev-secrets.sh" "$work/tls" >/dev/null || fail "make-dev-secrets.sh"
: >"$work/lmdd.log"
"$lmdd" --listen 127.0.0.1:0 --data-dir "$work/data" --set "tls_cert_file=$work/tls/tls.crt" \
  --set "tls_key_file=$work/tls/tls.key" >"$work/lmdd.log" 2>&1 &
pid=$!
port=
for _ in $(seq 1 100); do
  port=$(sed -n 's/^lmdd listening on port \([0-9]*\)$/\1/p' "$work/lmdd.log")
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || fail "lmdd with TLS did not start"
"$probe" --addr "127.0.0.1:$port" --tls-ca "$work/tls/ca.crt" --tls-server-name localhost ||
  fail "TLS probe: exit $?"
echo "ok: TLS lmdd, --tls-ca + --tls-server-name -> exit 0"
"$probe" --addr "127.0.0.1:$port" --timeout 2 2>"$work/err"; code=$?
[ "$code" = 1 ] || fail "plaintext probe of a TLS lmdd: exit $code"
echo "ok: plaintext probe of a TLS lmdd -> exit 1: $(cat "$work/err")"
