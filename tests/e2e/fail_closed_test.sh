#!/usr/bin/env bash
# What the adversarial probe of issue 16 found at run time, each now closed (docs/reliability.md,
# "Adversarial probes"): every tool's command line speaks one line and exit 2.
source "$(dirname "$0")/lib.sh" "$@"
out="$WORK/fail_closed"
rm -rf "$out"; mkdir -p "$out"
run() { "$BIN/harmoloc" --dataset "$WORK/test" --map "$WORK/tiny.hmap" "$@"; }
frames=$(($(wc -l < "$WORK/test/frames.csv") - 1))

# --- Every tool: --version; a usage error is one line "TOOL: reason", exit 2 (before: exit
# 106/109/114, two lines without the tool's name; --seed -1 read as 18446744073709551615).
cli_error() {  # cli_error TOOL PATTERN ARGS...
  local tool=$1 pattern=$2 status=0; shift 2
  "$BIN/$tool" "$@" > /dev/null 2> "$out/cli.err" || status=$?
  [ "$status" -eq 2 ] || { cat "$out/cli.err"; fail "$tool $*: exit status $status, expected 2"; }
  [ "$(wc -l < "$out/cli.err")" -eq 1 ] || { cat "$out/cli.err"; fail "$tool $*: not one line"; }
  grep -q "^$tool: .*$pattern" "$out/cli.err" || { cat "$out/cli.err"; fail "$tool $*: '$pattern' missing"; }
}
version=$(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$(dirname "$0")/../../CMakeLists.txt")
for tool in harmoloc harmoloc-sim harmoloc-train harmoloc-budget harmoloc-report harmoloc-accuracy harmoloc-scenarios; do
  [ "$("$BIN/$tool" --version)" = "$tool $version" ] || fail "$tool --version"
  cli_error "$tool" "" --no-such-option  # (or the first required option it misses)
  "$BIN/$tool" --help > /dev/null || fail "$tool --help"
done
cli_error harmoloc "--dataset is required" --map "$WORK/tiny.hmap"
cli_error harmoloc "--loop" --dataset "$WORK/test" --map "$WORK/tiny.hmap" --loop -1
cli_error harmoloc-sim "--seed: must not be negative: -1" --seed -1 --out "$out/sim"
cli_error harmoloc-sim "--seed" --seed x --out "$out/sim"
cli_error harmoloc-accuracy "must not be negative" --train-seed -3
cli_error harmoloc-train "--labels is required" --dataset "$WORK/train" --out "$out/x.hmap"
echo "ok  7 tools: --version, --help, one-line usage errors with exit 2, negative seeds refused"

echo "OK: command lines"
