#!/usr/bin/env bash
# Install the build tree into a temporary prefix and build + run a consumer project against it
# with find_package(yawdepth). Usage: install_consumer.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$src/tests/consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release \
  -DYAWDEPTH_EXAMPLES_DIR="$src/examples" >/dev/null
cmake --build "$tmp/build" >/dev/null
# A servo-only project: find_package(yawdepth COMPONENTS servo), no Ceres, apriltag or yaml-cpp.
cmake -S "$src/tests/consumer_servo" -B "$tmp/build-servo" -DCMAKE_PREFIX_PATH="$tmp/prefix" \
  -DCMAKE_BUILD_TYPE=Release -DYAWDEPTH_EXAMPLES_DIR="$src/examples" >"$tmp/servo-configure.log" ||
  { cat "$tmp/servo-configure.log" >&2; exit 1; }
cmake --build "$tmp/build-servo" >/dev/null
# An unknown component is refused.
mkdir -p "$tmp/bad"
printf 'cmake_minimum_required(VERSION 3.16)\nproject(bad CXX)\nfind_package(yawdepth REQUIRED COMPONENTS nosuchmodule)\n' >"$tmp/bad/CMakeLists.txt"
if cmake -S "$tmp/bad" -B "$tmp/build-bad" -DCMAKE_PREFIX_PATH="$tmp/prefix" >/dev/null 2>&1; then
  echo "find_package(yawdepth COMPONENTS nosuchmodule) did not fail" >&2; exit 1
fi
"$tmp/build/consumer"
test -x "$tmp/prefix/bin/yawdepth"
"$tmp/prefix/bin/yawdepth" --help >/dev/null
# The servo in a ViSP user's program, default options: estimated depth converges in at most 1.05x
# the iterations of true depth, from the tutorial's start and from a random one.
iterations() { "$tmp/build/servo_ibvs_4pts" --quiet "$@" | tail -1 | sed -n 's/^converged iterations=\([0-9]*\).*/\1/p'; }
for pose in 0 5; do
  t=$(iterations --depth true --pose "$pose")
  e=$(iterations --depth estimated --pose "$pose")
  [ -n "$t" ] && [ -n "$e" ] || { echo "servo_ibvs_4pts pose $pose: did not converge (true: '$t', estimated: '$e')" >&2; exit 1; }
  [ $((100 * e)) -le $((105 * t)) ] || { echo "servo_ibvs_4pts pose $pose: $e iterations against $t with true depth" >&2; exit 1; }
done
# The Pioneer with a pan head (vpSimulatorPioneerPan), front and side: within 1.05x of true depth.
pioneer() { "$tmp/build-servo/servo_pioneer_pan" --quiet "$@" | tail -1 | sed -n 's/^converged iterations=\([0-9]*\).*/\1/p'; }
for scenario in front side; do
  t=$(pioneer --depth true --scenario "$scenario")
  e=$(pioneer --depth estimated --scenario "$scenario")
  [ -n "$t" ] && [ -n "$e" ] || { echo "servo_pioneer_pan $scenario: did not converge (true: '$t', estimated: '$e')" >&2; exit 1; }
  [ $((100 * e)) -le $((105 * t)) ] || { echo "servo_pioneer_pan $scenario: $e iterations against $t with true depth" >&2; exit 1; }
done
passed=5
# The ROS package (the `ros` component, installed when the node was built): roslaunch finds the
# installed package through ROS_PACKAGE_PATH (docs/ros.md) and resolves its node to the installed
# executable, every library of which loads.
if [ -d "$tmp/prefix/share/yawdepth/ros" ]; then
  pkg=$tmp/prefix/share/yawdepth/ros
  command -v roslaunch >/dev/null || { echo "roslaunch missing (tools/bootstrap.sh installs it with the node's packages)" >&2; exit 1; }
  args=$(ROS_PACKAGE_PATH=$pkg:/usr/share roslaunch --args /yawdepth_node yawdepth yawdepth.launch \
           image:=/camera/image_raw) || { echo "roslaunch yawdepth yawdepth.launch: the installed package not found" >&2; exit 1; }
  exe=$(printf '%s\n' "$args" | tr ' ' '\n' | { grep '/yawdepth_node$' || true; } | head -n 1)
  [ -n "$exe" ] && [ "$(readlink -f "$exe")" = "$(readlink -f "$tmp/prefix/lib/yawdepth/yawdepth_node")" ] ||
    { echo "roslaunch resolves yawdepth_node to '$exe', not the installed $tmp/prefix/lib/yawdepth/yawdepth_node" >&2; exit 1; }
  ldd "$exe" >"$tmp/node_ldd" || { echo "ldd $exe failed" >&2; exit 1; }
  if grep "not found" "$tmp/node_ldd" >&2; then
    echo "the installed yawdepth_node misses the libraries above" >&2; exit 1
  fi
  passed=$((passed + 1))
fi
echo "$passed passed, 0 failed"
