#!/usr/bin/env bash
# The ROS 2 bags written again by the reference libraries (tests/data/bags/writers/) with fresh
# random values, into a temporary folder, and read by test_bag_ros2's comparison of every field.
#   bag_ros2_writers.sh TEST_BAG_ROS2 WRITERS_DIR
# Exit 77 (CTest's SKIP) without node, python3 or the writers' npm packages (npm ci there).
set -euo pipefail
test_bin=$1 writers=$2
if ! command -v node >/dev/null || ! command -v python3 >/dev/null || [ ! -d "$writers/node_modules/@mcap/core" ]; then
  echo "bag_ros2_writers: SKIP: needs node, python3 and $writers/node_modules (npm ci --no-audit --no-fund there)"
  exit 77
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
node "$writers/make_ros2_bags.mjs" --random --out "$out"
python3 "$writers/make_db3.py" "$out"
echo "bag_ros2_writers: seed $(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["seed"])' "$out/ros2_expected.json")"
YAWDEPTH_BAG_ROS2_DIR=$out "$test_bin" "[writers]"
