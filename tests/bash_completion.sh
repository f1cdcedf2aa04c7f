#!/usr/bin/env bash
# The bash completion generated at build time: sourced in bash, it completes the commands, a
# command's options, an IsMember option's words and file names; `cmake --install` puts it in
# PREFIX/share/bash-completion/completions/yawdepth.
#
#   bash tests/bash_completion.sh COMPLETION_FILE BUILD_DIR
set -u
script=$1 build=$2
PASSED=0 FAILED=0
pass() { PASSED=$((PASSED + 1)); }
fail() { FAILED=$((FAILED + 1)); echo "FAIL: $*"; }
W=$(mktemp -d "${TMPDIR:-/tmp}/yawdepth_completion.XXXXXX") || exit 1
trap 'rm -rf "$W"' EXIT

# complete WORDS...: COMPREPLY for the command line WORDS (the last one being completed), one per line.
complete_words() {
  bash -c 'source "$1"; shift; COMP_WORDS=("$@"); COMP_CWORD=$(($# - 1)); _yawdepth; printf "%s\n" "${COMPREPLY[@]}"' \
    sh "$script" "$@" 2>/dev/null | sort
}
[ -s "$script" ] && bash -n "$script" && pass || fail "$script: missing or not valid bash"
got=$(complete_words yawdepth est | tr '\n' ' ')
[ "$got" = "estimate " ] && pass || fail "'yawdepth est' completes to '$got', not 'estimate'"
got=$(complete_words yawdepth '' | wc -l)
[ "$got" -ge 9 ] && pass || fail "'yawdepth ' offers $got words, not the 9 commands"
got=$(complete_words yawdepth estimate --sigma-p | tr '\n' ' ')
[ "$got" = "--sigma-px " ] && pass || fail "'estimate --sigma-p' completes to '$got'"
got=$(complete_words yawdepth estimate --method '' | tr '\n' ' ')
case $got in *exact*fused*paper*refine*window*) pass ;; *) fail "'estimate --method ' offers '$got'" ;; esac
got=$(complete_words yawdepth calibrate-rig --min-yaw | tr '\n' ' ')
case $got in *--min-yaw-span-deg*) pass ;; *) fail "'calibrate-rig --min-yaw' offers '$got'" ;; esac
got=$(complete_words yawdepth error-analysis --ca | tr '\n' ' ')
case $got in *--camera*) pass ;; *) fail "'error-analysis --ca' offers '$got'" ;; esac
for c in estimate measure track error-analysis simulate calibrate-camera calibrate-rig import import-bag; do
  got=$(complete_words yawdepth "$c" --q | tr '\n' ' ')
  [ "$got" = "--quiet " ] && pass || fail "'$c --q' completes to '$got'"
  got=$(complete_words yawdepth "$c" --con | tr '\n' ' ')
  [ "$got" = "--config " ] && pass || fail "'$c --con' completes to '$got'"
done
mkdir -p "$W/files" && : >"$W/files/cam.yaml" && : >"$W/files/rig.yaml"
got=$(complete_words yawdepth estimate --camera "$W/files/ca" | tr '\n' ' ')
[ "$got" = "$W/files/cam.yaml " ] && pass || fail "'estimate --camera DIR/ca' completes to '$got'"

# Installed by cmake --install (its own component, so that this test needs no other target built;
# a plain `cmake --install` installs every component).
if cmake --install "$build" --prefix "$W/prefix" --component bash_completion >"$W/install.log" 2>&1 &&
  cmp -s "$script" "$W/prefix/share/bash-completion/completions/yawdepth"; then pass; else
  fail "cmake --install does not put the completion in PREFIX/share/bash-completion/completions/yawdepth: $(tail -n 2 "$W/install.log")"
fi
echo "$PASSED passed, $FAILED failed"
[ "$FAILED" -eq 0 ]
