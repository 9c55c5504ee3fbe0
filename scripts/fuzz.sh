#!/usr/bin/env bash
# Fuzzes lmd's readers with libFuzzer: the MCAP, ROS 1 bag and rosbag2
# SQLite readers (each with the message decoders behind it) and the CARMEN
# parser, each for SECONDS (default 60), under AddressSanitizer and UBSan.
# Uses Debian's clang (clang-14, libclang-rt-14-dev): installs them if missing,
# so that the main build does not need clang. Builds into build/fuzz/ (or
# $LMD_FUZZ_DIR); corpora persist there between runs; seeds come from
# bench/fuzz/make_seeds.cc (every container variant) and ../shared/bags.
# Prints one line per target: seconds, executions, crashes (artifacts kept
# in build/fuzz/artifacts). Exits 1 if any target crashed.
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]   (targets: mcap ros1_bag rosbag2_sqlite carmen)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(mcap ros1_bag rosbag2_sqlite carmen)
out=${LMD_FUZZ_DIR:-$root/build/fuzz}

packages=(clang-14 libclang-rt-14-dev libzstd-dev liblz4-dev libbz2-dev libsqlite3-dev zlib1g-dev libeigen3-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
  echo "fuzz: installing ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cxx=clang++-14
common=(-std=c++17 -g -O1 -I"$root" -I/usr/include/eigen3)
sanitize=(-fsanitize=address,undefined -fno-sanitize-recover=undefined)
libs=(-lzstd -llz4 -lbz2 -lsqlite3 -lz)
io=(core/status.cc core/io/byte_source.cc core/io/compression.cc core/io/mcap_reader.cc core/io/ros1_bag_reader.cc
    core/io/rosbag2_sqlite_reader.cc core/io/ros_messages.cc core/io/bag.cc core/io/carmen_reader.cc
    core/util/line_splitter.cc core/util/quoted.cc)
mkdir -p "$out/obj" "$out/artifacts"

echo "fuzz: building in $out"
objs=()
for src in "${io[@]}"; do
  obj="$out/obj/$(echo "$src" | tr / _).o"
  if [ ! -f "$obj" ] || [ "$root/$src" -nt "$obj" ]; then
    "$cxx" "${common[@]}" "${sanitize[@]}" -fsanitize=fuzzer-no-link -c "$root/$src" -o "$obj"
  fi
  objs+=("$obj")
done
for t in "${targets[@]}"; do
  "$cxx" "${common[@]}" "${sanitize[@]}" -fsanitize=fuzzer "$root/bench/fuzz/${t}_fuzz.cc" "${objs[@]}" "${libs[@]}" \
    -o "$out/${t}_fuzz"
done

# Seeds: small valid files of every variant, and the real recordings under 1 MiB.
rm -rf "$out/seeds" && mkdir -p "$out/seeds"/{mcap,ros1_bag,rosbag2_sqlite,carmen}
"$cxx" "${common[@]}" -O1 "$root/bench/fuzz/make_seeds.cc" "$root/tests/core/bag_test_writers.cc" \
  "$root/core/io/mcap_writer.cc" "$root/core/io/compression.cc" "$root/core/status.cc" "${libs[@]}" -o "$out/make_seeds"
"$out/make_seeds" "$out/seeds"
bags="$root/../shared/bags"
if [ -d "$bags" ]; then
  find "$bags" -name '*.mcap' -size -1024k -exec cp {} "$out/seeds/mcap/" \;
  find "$bags" -name '*.bag' -size -1024k -exec cp {} "$out/seeds/ros1_bag/" \;
  find "$bags" -name '*.db3' -size -1024k -exec cp {} "$out/seeds/rosbag2_sqlite/" \;
fi
data="$root/../shared/data"
if [ -f "$data/orebro.log.gz" ]; then
  (zcat "$data/orebro.log.gz" || true) | head -c 200000 > "$out/seeds/carmen/orebro_head.log" || true
fi

printf '%-16s %8s %14s %8s\n' target seconds executions crashes
failed=0
for t in "${targets[@]}"; do
  mkdir -p "$out/corpus/$t"
  log="$out/$t.log"
  before=$(ls "$out/artifacts" | grep -c "^$t-" || true)
  start=$(date +%s)
  set +e
  "$out/${t}_fuzz" "$out/corpus/$t" "$out/seeds/$t" -max_total_time="$seconds" -max_len=1048576 -timeout=20 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$out/artifacts/$t-" >"$log" 2>&1
  set -e
  elapsed=$(( $(date +%s) - start ))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  after=$(ls "$out/artifacts" | grep -c "^$t-" || true)
  crashes=$((after - before))
  [ "$crashes" -gt 0 ] && failed=1
  printf '%-16s %8s %14s %8s\n' "$t" "$elapsed" "${execs:-?}" "$crashes"
done
[ "$failed" -eq 0 ] || { echo "fuzz: crashes found: see $out/artifacts and $out/<target>.log"; exit 1; }
