#!/usr/bin/env bash
# The installed headers stand on their own: install the build tree into a temporary prefix, then
# compile one translation unit per installed header (the header alone, twice: its include guard),
# in a project that finds the package (find_package(yawdepth)) and links the header's module, so
# that the compiler sees the package's include flags and nothing of the source tree. An installed
# header that includes one that is not installed, or that misses an include, fails here and is
# named. Also: README.md's list of installed headers is the list installed.
# Usage: installed_headers.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" >/dev/null
inc="$tmp/prefix/include"
mapfile -t headers < <(cd "$inc" && find yawdepth -name '*.h' | LC_ALL=C sort)
[ "${#headers[@]}" -gt 0 ] || { echo "no header installed under $inc" >&2; exit 1; }

# README.md: one line per installed header, "- `yawdepth/.../x.h`: what it is for".
listed=$(sed -n 's/^- `\(yawdepth\/[^`]*\.h\)`.*/\1/p' "$src/README.md" | LC_ALL=C sort)
installed=$(printf '%s\n' "${headers[@]}")
if [ "$listed" != "$installed" ]; then
  echo "README.md's installed headers differ from those installed (<: README only, >: installed only):" >&2
  diff <(echo "$listed") <(echo "$installed") | grep '^[<>]' >&2
  exit 1
fi

proj="$tmp/project"
mkdir -p "$proj"
{
  echo 'cmake_minimum_required(VERSION 3.16)'
  echo 'project(installed_headers CXX)'
  echo 'set(CMAKE_CXX_STANDARD 17)'
  echo 'set(CMAKE_CXX_STANDARD_REQUIRED ON)'
  echo 'find_package(yawdepth REQUIRED)'
} >"$proj/CMakeLists.txt"
n=0
for h in "${headers[@]}"; do
  # yawdepth/<module>/x.h belongs to yawdepth::<module>; yawdepth/error.h to yawdepth::core.
  module=$(echo "$h" | awk -F/ 'NF == 3 { print $2 } NF == 2 { print "core" }')
  n=$((n + 1))
  printf '// %s on its own\n#include <%s>\n#include <%s>\n' "$h" "$h" "$h" >"$proj/tu_$n.cpp"
  echo "add_library(tu_$n OBJECT tu_$n.cpp) # $h" >>"$proj/CMakeLists.txt"
  echo "target_link_libraries(tu_$n PRIVATE yawdepth::$module)" >>"$proj/CMakeLists.txt"
  echo "target_compile_options(tu_$n PRIVATE -Wall -Wextra)" >>"$proj/CMakeLists.txt"
done
cmake -S "$proj" -B "$tmp/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" >"$tmp/configure.log" 2>&1 ||
  { cat "$tmp/configure.log" >&2; exit 1; }
failed=0
for i in $(seq 1 "$n"); do
  h=${headers[$((i - 1))]}
  if ! cmake --build "$tmp/build" --target "tu_$i" >"$tmp/tu_$i.log" 2>&1; then
    echo "FAIL: $h does not compile on its own from the install prefix:" >&2
    grep -m 5 -e 'error' "$tmp/tu_$i.log" >&2 || tail -n 5 "$tmp/tu_$i.log" >&2
    failed=$((failed + 1))
  fi
done
echo "$((n - failed)) passed, $failed failed ($n installed headers)"
[ "$failed" -eq 0 ]
