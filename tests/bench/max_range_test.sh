#!/bin/sh
# lmd-eval reads a log as a shorter-range laser would see it (--max-range):
# a robot drives 8 m along x past a wall 2 m to its right and one 8 m to its
# left. Read as it is, its maps hold both walls; read with --max-range 5,
# the far wall's returns are no returns and only the near wall is left.
# usage: max_range_test.sh LMD_EVAL WORKDIR
set -eu
eval_bin=$1
work=$2
rm -rf "$work" && mkdir -p "$work"
awk 'BEGIN {
  for (i = 0; i < 40; i++) {
    line = "FLASER 180"
    for (b = 0; b < 180; b++) line = line " " (b < 90 ? "2.0" : "8.0")  # beams right of the heading, then left
    x = i * 0.2
    printf "%s %.2f 0 0 %.2f 0 0 0 host 0\n", line, x, x
  }
}' > "$work/corridor.log"
"$eval_bin" export --log "$work/corridor.log" --out "$work/full" 2> /dev/null
"$eval_bin" export --log "$work/corridor.log" --max-range 5 --out "$work/short" 2> /dev/null
far_full=$(awk '$1 == "P" && $3 > 5' "$work/full/corridor.maps.txt" | wc -l)
near_full=$(awk '$1 == "P" && $3 < 0' "$work/full/corridor.maps.txt" | wc -l)
far_short=$(awk '$1 == "P" && $3 > 5' "$work/short/corridor.maps.txt" | wc -l)
near_short=$(awk '$1 == "P" && $3 < 0' "$work/short/corridor.maps.txt" | wc -l)
echo "far wall points: $far_full as recorded, $far_short at 5 m; near wall: $near_full and $near_short"
[ "$far_full" -gt 0 ] && [ "$near_full" -gt 0 ] && [ "$far_short" -eq 0 ] && [ "$near_short" -eq "$near_full" ]
