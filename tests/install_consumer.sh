#!/usr/bin/env bash
# Install the build tree into a temporary prefix and build + run a consumer project against it
# with find_package(yawdepth). Usage: install_consumer.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
cmake -S "$src/tests/consumer" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$tmp/build" >/dev/null
"$tmp/build/consumer"
test -x "$tmp/prefix/bin/yawdepth"
"$tmp/prefix/bin/yawdepth" --help >/dev/null
echo "1 passed, 0 failed"
