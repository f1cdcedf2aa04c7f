#!/usr/bin/env bash
# `yawdepth import-bag` on a large ROS 1 bag (written by real rosbag, benchmarks/write_large_bag.py),
# a large ROS 2 MCAP bag (by @mcap/core, benchmarks/write_large_mcap.mjs) and the same messages in
# rosbag2's SQLite bag (benchmarks/write_large_db3.py): 640x480 mono8 images
# at 30 Hz, odometry at 100 Hz, on one core (taskset -c 0). Prints one table row per format: the
# bag's size, its recording length, images, the import's time, throughput and peak memory, and the
# time `cat` takes to read the file. Target (issue 32): faster than `rosbag play` at full
# speed, i.e. the import takes less than the recording lasted; exits 1 when a format does not.
# usage: benchmarks/bench_import_bag.sh [YAWDEPTH] [SIZE_MB] [WORKDIR]   (defaults: build/tools/yawdepth 1024 a temp dir)
set -euo pipefail
Y=${1:-build/tools/yawdepth}
size=${2:-1024}
work=${3:-$(mktemp -d)}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[ -x "$Y" ] || { echo "bench_import_bag.sh: $Y not found (build the yawdepth target)" >&2; exit 1; }
mkdir -p "$work"
fail=0
printf '%-8s %10s %11s %7s %9s %9s %9s %8s %8s\n' format bag_MB recording_s images written import_s MB_per_s peak_MB cat_s
row() { # FORMAT BAG IMAGES DURATION
  local format=$1 bag=$2 images=$3 duration=$4 bytes read_s stats import_s rss_kb written
  bytes=$(stat -c %s "$bag")
  read_s=$( { /usr/bin/time -f "%e" cat "$bag" > /dev/null; } 2>&1 )
  rm -rf "$work/out"
  stats=$( { taskset -c 0 /usr/bin/time -f "%e %M" "$Y" import-bag "$bag" --out-dir "$work/out" \
             --image-topic /camera/image_raw --odom-topic /odom > "$work/import.log"; } 2>&1 | tail -1)
  read -r import_s rss_kb <<<"$stats"
  written=$(ls "$work/out/images" | wc -l)
  awk -v f="$format" -v b="$bytes" -v d="$duration" -v n="$images" -v w="$written" -v t="$import_s" -v m="$rss_kb" -v c="$read_s" \
    'BEGIN { printf "%-8s %10.0f %11.1f %7d %9d %9.1f %9.1f %8.0f %8.1f\n", f, b / 1e6, d, n, w, t, b / 1e6 / t, m / 1024, c }'
  rm -rf "$work/out" "$bag"
  awk -v t="$import_s" -v d="$duration" 'BEGIN { exit !(t < d) }' ||
    { echo "bench_import_bag.sh: $format: target missed: the import took ${import_s} s for a ${duration} s recording" >&2; fail=1; }
}
read -r images duration < <(/usr/bin/python3 "$here/write_large_bag.py" "$work/large.bag" "$size")
row ros1 "$work/large.bag" "$images" "$duration"
# MCAP by @mcap/core (tests/data/bags/writers: npm ci --no-audit --no-fund there first).
if command -v node >/dev/null && [ -d "$here/../tests/data/bags/writers/node_modules/@mcap/core" ]; then
  read -r pw ph < <(/usr/bin/python3 "$here/write_large_bag.py" --raw "$work/photo.raw")
  read -r images duration < <(node "$here/write_large_mcap.mjs" "$work/large.mcap" "$size" "$work/photo.raw" "$pw" "$ph" \
                                --messages "$work/messages.bin")
  rm -f "$work/photo.raw"
  row mcap "$work/large.mcap" "$images" "$duration"
  /usr/bin/python3 "$here/write_large_db3.py" "$work/messages.bin" "$work/large.db3"
  rm -f "$work/messages.bin"
  row db3 "$work/large.db3" "$images" "$duration"
else
  echo "bench_import_bag.sh: no node or tests/data/bags/writers/node_modules: MCAP and db3 not measured" >&2
fi
exit $fail
