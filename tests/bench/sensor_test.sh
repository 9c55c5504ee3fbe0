#!/bin/sh
# lmd-eval reads a log as a shorter-range or noisier laser would see it
# (--max-range, --range-noise) or a narrower one (--fov), and its maps as a robot on drifting odometry
# (--map-drift) or one that sends shorter maps (--map-length) would build
# them: a robot drives 8 m along x past a wall 2 m
# to its right and one 8 m to its left. Read as it is, its maps hold both
# walls; read with --max-range 5, the far wall's returns are no returns and
# the near wall's within 5 m are left; with --range-noise 0.05, the near
# wall's points spread across it by a few centimetres (the noise is along
# each beam); with --fov 60, the beams within 30 deg of the heading alone
# reach the near wall 3.46 m (2 / tan 30 deg) or more ahead, so no map holds
# a point of it within 3 m of its first pose; with --map-drift 2, each map's near wall beside its route
# bends away from y = -2 by tens of centimetres at its far end, while the
# maps' frames and the place truth stay the log's; with --map-length 2.5,
# twice as many maps (one per metre) of at most 2.5 m of travel each.
# usage: sensor_test.sh LMD_EVAL WORKDIR
set -eu
eval_bin=$1
work=$2
rm -rf "$work" && mkdir -p "$work"
awk 'BEGIN {
  for (i = 0; i < 40; i++) {
    line = "FLASER 180"
    for (b = 0; b < 180; b++) {  # beams from the right (-89.5 deg) to the left (+89.5 deg) of the heading
      s = sin((b + 0.5 - 90) * 3.14159265 / 180)
      r = s < 0 ? -2 / s : 8 / s  # the wall y = -2 on the right, y = 8 on the left
      line = line " " (r < 30 ? sprintf("%.3f", r) : "30.0")
    }
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
"$eval_bin" export --log "$work/corridor.log" --range-noise 0.05 --out "$work/noisy" 2> /dev/null
spread() {  # standard deviation of the near wall's y, in whole cm
  awk '$1 == "P" && $3 < 0 { n++; s += $3; ss += $3 * $3 } END { printf "%d", 100 * sqrt(ss / n - (s / n) ^ 2) }' "$1"
}
spread_full=$(spread "$work/full/corridor.maps.txt")
spread_noisy=$(spread "$work/noisy/corridor.maps.txt")
# The same corridor seen by a 360-deg lidar whose scans start at 0 rad
# (ROBOTLASER1, 1 deg per beam): --fov 60 keeps 330-359 deg and 0-30 deg,
# which must stay on the right and the left of the heading.
awk 'BEGIN {
  for (i = 0; i < 40; i++) {
    line = "ROBOTLASER1 0 0 6.283185 0.017453 30 0.01 0 360"
    for (b = 0; b < 360; b++) {
      s = sin(b * 3.14159265 / 180)
      r = s < -1e-6 ? -2 / s : s > 1e-6 ? 8 / s : 30
      line = line " " (r < 30 ? sprintf("%.3f", r) : "30.0")
    }
    x = i * 0.2
    printf "%s 0 %.2f 0 0 %.2f 0 0 0 0 0 0 0 0 host 0\n", line, x, x
  }
}' > "$work/lidar.log"
"$eval_bin" export --log "$work/lidar.log" --fov 60 --out "$work/lidar_narrow" 2> /dev/null
between=$(awk '$1 == "P" && $3 > -1.5 && $3 < 7.5' "$work/lidar_narrow/lidar.maps.txt" | wc -l)
lidar_right=$(awk '$1 == "P" && $3 < 0' "$work/lidar_narrow/lidar.maps.txt" | wc -l)
lidar_beside=$(awk '$1 == "P" && $3 < 0 && $2 < 3' "$work/lidar_narrow/lidar.maps.txt" | wc -l)
echo "360-deg lidar cut to 60 deg: $lidar_right near-wall points, $lidar_beside within 3 m of a map's frame, $between between the walls"
"$eval_bin" export --log "$work/corridor.log" --fov 60 --out "$work/narrow" 2> /dev/null
beside() { awk '$1 == "P" && $3 < 0 && $2 < 3' "$1" | wc -l; }  # near-wall points within 3 m of a map's frame
beside_full=$(beside "$work/full/corridor.maps.txt")
beside_narrow=$(beside "$work/narrow/corridor.maps.txt")
near_narrow=$(awk '$1 == "P" && $3 < 0' "$work/narrow/corridor.maps.txt" | wc -l)
echo "near wall within 3 m of a map's frame: $beside_full points as recorded, $beside_narrow with --fov 60 (of $near_narrow)"
"$eval_bin" export --log "$work/corridor.log" --map-drift 2 --out "$work/drift" 2> /dev/null
bend() {  # the largest distance from y = -2 of a near-wall point beside the 5 m a map drove, in whole cm
  awk '$1 == "P" && $3 < 0 && $2 >= 0 && $2 <= 5 { d = $3 + 2; if (d < 0) d = -d; if (d > m) m = d } END { printf "%d", 100 * m }' "$1"
}
frames() { awk '$1 == "MAP" { print $8, $9, $10 }' "$1"; }
bend_full=$(bend "$work/full/corridor.maps.txt")
bend_drift=$(bend "$work/drift/corridor.maps.txt")
same_frames=$([ "$(frames "$work/full/corridor.maps.txt")" = "$(frames "$work/drift/corridor.maps.txt")" ] && echo yes || echo no)
same_truth=$(cmp -s "$work/full/corridor.truth.txt" "$work/drift/corridor.truth.txt" && echo yes || echo no)
echo "near wall bent by $bend_full cm as recorded, $bend_drift cm on drifting odometry; same frames $same_frames, same truth $same_truth"
"$eval_bin" export --log "$work/corridor.log" --map-length 2.5 --out "$work/short_maps" 2> /dev/null
maps() { awk '$1 == "MAP"' "$1" | wc -l; }
longest() { awk '$1 == "MAP" && $7 - $6 > m { m = $7 - $6 } END { printf "%d", 10 * m }' "$1"; }  # dm of travel
maps_full=$(maps "$work/full/corridor.maps.txt")
maps_short=$(maps "$work/short_maps/corridor.maps.txt")
longest_full=$(longest "$work/full/corridor.maps.txt")
longest_short=$(longest "$work/short_maps/corridor.maps.txt")
echo "maps: $maps_full of up to $longest_full dm, $maps_short of up to $longest_short dm with --map-length 2.5"
echo "far wall points: $far_full as recorded, $far_short at 5 m; near wall: $near_full and $near_short"
echo "near wall spread: $spread_full cm as recorded, $spread_noisy cm with 5 cm of noise"
[ "$far_full" -gt 0 ] && [ "$near_full" -gt 0 ] && [ "$far_short" -eq 0 ] && [ "$near_short" -gt 0 ] &&
  [ "$beside_full" -gt 0 ] && [ "$beside_narrow" -eq 0 ] && [ "$near_narrow" -gt 0 ] &&
  [ "$lidar_right" -gt 0 ] && [ "$lidar_beside" -eq 0 ] && [ "$between" -eq 0 ] &&
  [ "$spread_full" -eq 0 ] && [ "$spread_noisy" -ge 2 ] && [ "$spread_noisy" -le 6 ] &&
  [ "$bend_full" -eq 0 ] && [ "$bend_drift" -ge 10 ] && [ "$same_frames" = yes ] && [ "$same_truth" = yes ] &&
  [ "$maps_short" -eq $((2 * maps_full)) ] && [ "$longest_full" -gt 25 ] && [ "$longest_short" -le 25 ]
