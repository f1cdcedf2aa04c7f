#!/usr/bin/env bash
# docs/commands.md is what tools/gen_commands_md.sh makes from the built binary's --help: the docs and
# the help cannot disagree. SKIP (77) for a binary without Ceres (measure's default method differs:
# the checked-in reference is the full build's).
#
#   bash tests/command_reference.sh BINARY SOURCE_DIR
set -u
y=$1 src=$2
if ! "$y" measure --help | grep -q -- '--method TEXT:{paper,exact,fused,window,refine}=refine'; then
  echo "SKIP: this yawdepth has no refine (no Ceres); docs/commands.md is the full build's"
  exit 77
fi
tmp=$(mktemp "${TMPDIR:-/tmp}/commands_md.XXXXXX") || exit 1
trap 'rm -f "$tmp"' EXIT
bash "$src/tools/gen_commands_md.sh" "$y" >"$tmp" || { echo "FAIL: tools/gen_commands_md.sh failed"; exit 1; }
if ! diff -u "$src/docs/commands.md" "$tmp"; then
  echo "FAIL: docs/commands.md differs from the binary's --help (above: - checked in, + the binary)."
  echo "Regenerate it: cmake --build BUILD --target commands_md   (or: tools/gen_commands_md.sh BINARY docs/commands.md)"
  exit 1
fi
echo "docs/commands.md matches yawdepth --help"
