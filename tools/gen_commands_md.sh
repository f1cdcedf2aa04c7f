#!/usr/bin/env bash
# docs/commands.md, the command reference, from the binary's own --help (so the two cannot disagree):
#
#   tools/gen_commands_md.sh BINARY [OUT]      (OUT: written atomically; default standard output)
#
# or `cmake --build build --target commands_md`. The ctest command_reference compares the checked-in
# file with this script's output. CLI11 2.1's help does not depend on the terminal's width, and the
# binary's name is taken as `yawdepth` whatever its path, so the output depends on the build only
# through what the build has (Ceres: measure's default method).
set -euo pipefail
y=${1:?usage: gen_commands_md.sh BINARY [OUT]}
out=${2:-}

generate() {
  local commands
  commands=$("$y" --help | awk '/^Subcommands:/ { f = 1; next } f && NF { print $1 }')
  echo "<!-- Generated from \`yawdepth --help\` by tools/gen_commands_md.sh: do not edit. Regenerate with"
  echo "     \`cmake --build build --target commands_md\` (the ctest command_reference checks it). -->"
  echo "# yawdepth command reference"
  echo
  echo "Every command's \`--help\`, verbatim. The files, messages and exit statuses are in"
  echo "[formats.md](formats.md)."
  echo
  echo '```'
  "$y" --help
  echo '```'
  for c in $commands; do
    echo
    echo "## \`yawdepth $c\`"
    echo
    echo '```'
    "$y" "$c" --help
    echo '```'
  done
}

if [ -z "$out" ]; then
  generate
else
  tmp=$(mktemp "$(dirname "$out")/.commands.md.XXXXXX")
  trap 'rm -f "$tmp"' EXIT
  generate >"$tmp"
  chmod 0644 "$tmp" # mktemp makes it private; the reference is an ordinary file
  mv "$tmp" "$out"
  trap - EXIT
fi
