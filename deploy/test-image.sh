#!/usr/bin/env bash
# Builds the lmdd container image with podman and checks it end to end, without
# a registry or a Docker engine:
#   1. installs podman, runc, debootstrap (only what is missing);
#   2. makes local base images from a debootstrap rootfs (once; kept):
#      localhost/bookworm-minbase (build stage) and localhost/bookworm-slim
#      (runtime stage: minbase without docs, man pages and locales);
#   3. builds deploy/Dockerfile with `podman build --isolation=chroot`;
#   4. runs it (runc, explicit ulimits, a named volume, the gRPC port published
#      on a free loopback port), waits for the image's health check;
#   5. inserts a map and queries it through the published port (lmdctl of the
#      image, run in a second container on the host network);
#   6. stops it with SIGTERM and checks a clean exit (code 0, within the
#      grace period, "received SIGTERM" logged), restarts it on the same
#      volume and reads the map back;
#   7. builds the sharding proxy's image (deploy/nginx/Dockerfile) and checks
#      its nginx config.
# Prints the image size and the build time. Run as root (or with sudo):
#   bash deploy/test-image.sh
# Env: LMD_IMAGE (default localhost/lmd:test), LMD_IMAGE_NO_CACHE=1 (build
# from scratch), LMD_BUILD_JOBS (compile jobs, default: all cores).
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
image=${LMD_IMAGE:-localhost/lmd:test}
build_base=localhost/bookworm-minbase
runtime_base=localhost/bookworm-slim
mirror=${LMD_DEBIAN_MIRROR:-http://deb.debian.org/debian}
# This host's cgroup setup defeats podman's default runtime; runc with explicit
# limits works.
run_flags=(--runtime runc --ulimit nofile=1024:4096 --ulimit nproc=4096:4096)
# The short-lived helper containers need no health check.
once_flags=("${run_flags[@]}" --no-healthcheck)

log() { printf '[test-image] %s\n' "$*"; }
fail() { printf '[test-image] FAIL: %s\n' "$*" >&2; exit 1; }

if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
# Without systemd, podman logs an error for each health-check timer it cannot
# create or remove; the script runs the health check itself, so drop those.
podman() { "${sudo[@]}" command podman "$@" 2> >(grep -v 'unable to get systemd connection' >&2); }

# --- 1. packages ------------------------------------------------------------
packages=(podman runc debootstrap containernetworking-plugins iptables uidmap tar)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  log "installing ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
log "$(command podman --version), runc $(runc --version | awk 'NR==1{print $3}')"

work=$(mktemp -d /var/tmp/lmd-test-image.XXXXXX)
name=lmd-test-$$
volume=lmd-test-data-$$
cleanup() {
  podman rm -f -t 0 "$name" >/dev/null 2>&1 || true
  podman volume rm -f "$volume" >/dev/null 2>&1 || true
  "${sudo[@]}" rm -rf "$work"
}
trap cleanup EXIT

# --- 2. base images -----------------------------------------------------------
if ! podman image exists "$build_base" || ! podman image exists "$runtime_base"; then
  log "debootstrap --variant=minbase bookworm (once; takes a few minutes)"
  rootfs=$work/rootfs
  "${sudo[@]}" debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    { tail -20 "$work/debootstrap.log"; fail "debootstrap"; }
  "${sudo[@]}" rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
  "${sudo[@]}" tar -C "$rootfs" -c . | podman import - "$build_base" >/dev/null 2>&1
  # The slim variant, like the official bookworm-slim: no docs, man pages or
  # locales, and dpkg told not to install them later.
  "${sudo[@]}" rm -rf "$rootfs"/usr/share/doc/* "$rootfs"/usr/share/man/* "$rootfs"/usr/share/info/* \
    "$rootfs"/usr/share/locale/* "$rootfs"/usr/share/lintian "$rootfs"/usr/share/linda
  printf '%s\n' 'path-exclude /usr/share/doc/*' 'path-include /usr/share/doc/*/copyright' \
    'path-exclude /usr/share/man/*' 'path-exclude /usr/share/info/*' 'path-exclude /usr/share/locale/*' \
    'path-exclude /usr/share/lintian/*' | "${sudo[@]}" tee "$rootfs/etc/dpkg/dpkg.cfg.d/slim" >/dev/null
  "${sudo[@]}" tar -C "$rootfs" -c . | podman import - "$runtime_base" >/dev/null 2>&1
  "${sudo[@]}" rm -rf "$rootfs"
fi
log "base images: $build_base, $runtime_base"

# --- 3. build -------------------------------------------------------------------
build_flags=(--isolation=chroot --format docker --ulimit nofile=1024:4096 --ulimit nproc=4096:4096
  --ignorefile "$root/deploy/Dockerfile.dockerignore" -f "$root/deploy/Dockerfile"
  --build-arg "BUILD_IMAGE=$build_base" --build-arg "RUNTIME_IMAGE=$runtime_base"
  --build-arg "BUILD_JOBS=${LMD_BUILD_JOBS:-0}" -t "$image")
[ "${LMD_IMAGE_NO_CACHE:-0}" = 1 ] && build_flags+=(--no-cache)
log "podman build ${build_flags[*]} $root"
start=$(date +%s)
if ! nice -n 19 "${sudo[@]}" "$(command -v podman)" build "${build_flags[@]}" "$root" >"$work/build.log" 2>&1; then
  tail -40 "$work/build.log"
  fail "podman build"
fi
build_seconds=$(($(date +%s) - start))
size_bytes=$(podman image inspect --format '{{.Size}}' "$image")
log "built $image in ${build_seconds} s; size $((size_bytes / 1000000)) MB ($size_bytes bytes)"
healthcheck=$(podman image inspect --format '{{.Config.Healthcheck.Test}}' "$image" 2>/dev/null || true)
[[ "$healthcheck" == *lmd_health_probe* ]] || fail "image has no HEALTHCHECK (got '$healthcheck')"
log "image health check: $healthcheck; user $(podman image inspect --format '{{.Config.User}}' "$image")"

# --- 4. run ---------------------------------------------------------------------
free_port() {
  local port
  for _ in $(seq 1 100); do
    port=$((20000 + RANDOM % 20000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then echo "$port"; return; fi
  done
  fail "no free loopback port found"
}
port=$(free_port)
podman volume create "$volume" >/dev/null
start_container() {
  podman run -d --name "$name" "${run_flags[@]}" -p "127.0.0.1:$port:50051" -v "$volume:/var/lib/lmd" "$image" >/dev/null
}
wait_healthy() {
  local deadline=$((SECONDS + 60))
  while [ $SECONDS -lt $deadline ]; do
    if podman healthcheck run "$name" >/dev/null 2>&1; then return 0; fi
    [ "$(podman inspect --format '{{.State.Running}}' "$name")" = true ] || { podman logs "$name" | tail; fail "lmdd exited"; }
    sleep 1
  done
  podman logs "$name" | tail
  fail "health check not passing after 60 s"
}
start_container
log "started $name: lmdd on 127.0.0.1:$port (published), volume $volume"
wait_healthy
log "image health check passes: podman healthcheck run -> exit 0"
log "in the container: PID 1 is '$(podman exec "$name" cat /proc/1/cmdline | tr '\0' ' ')', uid $(podman exec "$name" id -u)"
podman exec "$name" lmd_health_probe --addr 127.0.0.1:50051 --timeout 2 && log "exec probe: lmd_health_probe exit 0"
if podman exec "$name" lmd_health_probe --addr 127.0.0.1:1 --timeout 1 2>"$work/probe.err"; then
  fail "probe of a closed port passed"
fi
log "exec probe of a closed port: exit 1, '$(cat "$work/probe.err")'"

# --- 5. insert and query through the published port -----------------------------
# A 6 m x 4 m room with a pillar: points every 5 cm along the walls.
awk 'BEGIN {
  for (i = 0; i <= 120; i++) { x = i * 0.05; print x, 0; print x, 4 }
  for (i = 1; i < 80; i++) { y = i * 0.05; print 0, y; print 6, y }
  for (i = 0; i <= 10; i++) { print 3 + i * 0.05, 2; print 3 + i * 0.05, 2.5; print 3, 2 + i * 0.05; print 3.5, 2 + i * 0.05 }
}' >"$work/room.txt"
chmod 0644 "$work/room.txt"; chmod 0755 "$work"
lmdctl() {
  podman run --rm "${once_flags[@]}" --network host -v "$work/room.txt:/tmp/room.txt:ro" \
    --entrypoint /usr/local/bin/lmdctl "$image" --server "127.0.0.1:$port" --timeout 10 "$@"
}
log "lmdctl insert through 127.0.0.1:$port"
lmdctl insert --collection site-a --file /tmp/room.txt --id room-1 --robot r1
lmdctl insert --collection site-a --file /tmp/room.txt --id room-2 --robot r2
log "lmdctl maps / get / query / stats"
lmdctl maps --collection site-a
got=$(lmdctl --json get --collection site-a --id room-1)
echo "$got" | cut -c1-200
[[ "$got" == *room-1* ]] || fail "get did not return room-1"
query=$(lmdctl --json query --collection site-a --file /tmp/room.txt --top-k 2 2>&1) || true
echo "$query" | cut -c1-300
[[ "$query" == *room-* ]] || fail "query returned no stored map"
lmdctl stats --collection site-a | head -5

# --- 6. SIGTERM, clean shutdown, restart on the same volume -----------------------
log "podman stop -t 30 (SIGTERM)"
t0=$(date +%s.%N)
podman stop -t 30 "$name" >/dev/null
t1=$(date +%s.%N)
code=$(podman inspect --format '{{.State.ExitCode}}' "$name")
podman logs "$name" >"$work/lmdd.log" 2>&1 || true
tail -4 "$work/lmdd.log"
[ "$code" = 0 ] || fail "lmdd exit code $code after SIGTERM"
grep -q "received SIGTERM" "$work/lmdd.log" || fail "lmdd did not log the SIGTERM"
awk -v a="$t0" -v b="$t1" 'BEGIN { exit !(b - a < 25) }' || fail "stop took more than 25 s (killed, not stopped?)"
log "clean shutdown: exit code 0 in $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s"
podman rm "$name" >/dev/null
start_container
wait_healthy
lmdctl get --collection site-a --id room-2 | head -3
lmdctl maps --collection site-a | grep -q room-1 || fail "room-1 lost across the restart"
log "restarted on the same volume: both maps are there"
podman stop -t 30 "$name" >/dev/null

# --- 7. the sharding proxy's image (deploy/nginx/Dockerfile) ---------------------------
proxy_image=${LMD_PROXY_IMAGE:-localhost/lmd-proxy:test}
start=$(date +%s)
if ! nice -n 19 "${sudo[@]}" "$(command -v podman)" build --isolation=chroot --format docker \
    --ulimit nofile=1024:4096 --ulimit nproc=4096:4096 --ignorefile "$root/deploy/Dockerfile.dockerignore" \
    -f "$root/deploy/nginx/Dockerfile" --build-arg "RUNTIME_IMAGE=$runtime_base" -t "$proxy_image" "$root" \
    >"$work/build-proxy.log" 2>&1; then
  tail -20 "$work/build-proxy.log"
  fail "podman build of the proxy image"
fi
proxy_seconds=$(($(date +%s) - start))
podman run --rm "${once_flags[@]}" "$proxy_image" -t 2>&1 | sed 's/^/    /'
[ "${PIPESTATUS[0]}" = 0 ] || fail "nginx -t in $proxy_image"
log "proxy image $proxy_image: $(podman image inspect --format '{{.Size}}' "$proxy_image" | awk '{ printf "%d MB", $1 / 1e6 }'), built in ${proxy_seconds} s; nginx -t of its default config passes as uid $(podman run --rm "${once_flags[@]}" --entrypoint id "$proxy_image" -u)"

log "image $image: $((size_bytes / 1000000)) MB; build time ${build_seconds} s"
podman images --filter "reference=$image" --format '{{.Repository}}:{{.Tag}} {{.Size}}'
log "PASS"
