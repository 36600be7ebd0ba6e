#!/usr/bin/env bash
# Builds a target that must fail to link on an undefined symbol (the heap guard's probes,
# CMakeLists.txt) and passes only if it does, for that reason: a compile error or another link
# error is a failure too.
#
#   expect_link_failure.sh BUILD_DIR TARGET SYMBOL
set -euo pipefail

[ $# -eq 3 ] || { echo "usage: $0 BUILD_DIR TARGET SYMBOL" >&2; exit 2; }
build=$1
target=$2
symbol=$3

log=$(cmake --build "$build" --target "$target" 2>&1) && {
  echo "FAIL: $target linked, but it references $symbol and the heap guard must reject it" >&2
  exit 1
}
if grep -q "undefined reference to \`$symbol'" <<< "$log"; then
  echo "ok: $target does not link: $(grep -m1 -o "undefined reference to \`$symbol'" <<< "$log")"
  exit 0
fi
echo "$log" | grep -E "error|undefined" | head -5 >&2
echo "FAIL: $target failed to build, but not on an undefined $symbol (above)" >&2
exit 1
