#!/usr/bin/env bash
# Builds (if needed) and runs harmoloc's libFuzzer targets, one after the other (one core).
#
#   tests/fuzz/run_fuzzers.sh [SECONDS]           every target for SECONDS (default 10): the CI run
#   tests/fuzz/run_fuzzers.sh --long SECONDS      a long run (not in CI): SECONDS per target,
#                                                 corpus kept in build/fuzz/long-corpus/
#   options: --only T1,T2   only these targets     --no-build   use the existing build/fuzz
#            --list         print the targets and exit
#
# Before fuzzing, each target replays its saved reproducers (tests/fuzz/regressions/<target>/).
# The committed seeds (tests/fuzz/corpus/<target>/) are copied to a working corpus, so a run
# never modifies them. Findings (crash, sanitizer report, broken property, leak, timeout,
# out-of-memory) are kept in build/fuzz/artifacts/<target>/ and make the script exit 1; logs are
# in build/fuzz/logs/. Environment: CXX (default clang++-14), FUZZ_BUILD_DIR (default
# build/fuzz), FUZZ_EXTRA_ARGS (more libFuzzer flags).
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
BUILD=${FUZZ_BUILD_DIR:-$ROOT/build/fuzz}
TARGETS=(map_decode map_roundtrip config metadata frame_index ppm_header candump_line candump_log
  tum scenario segment mavlink_inbound encoder_csv signing_state area_log)

dict_for() {
  case "$1" in
    config | metadata | scenario) echo "$HERE/dict/toml.dict" ;;
    frame_index | ppm_header | candump_line | candump_log | tum | encoder_csv | area_log) echo "$HERE/dict/dataset_text.dict" ;;
    signing_state) echo "$HERE/dict/signing_state.dict" ;;
    *) echo "" ;;
  esac
}

usage() { sed -n '2,16p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; }

seconds=10
long=0
build=1
only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --long) long=1; seconds=${2:?--long needs SECONDS}; shift 2 ;;
    --only) only=${2:?--only needs target names}; shift 2 ;;
    --no-build) build=0; shift ;;
    --list) printf '%s\n' "${TARGETS[@]}"; exit 0 ;;
    -h | --help) usage; exit 0 ;;
    [0-9]*) seconds=$1; shift ;;
    *) usage >&2; exit 2 ;;
  esac
done
case "$seconds" in '' | *[!0-9]*) echo "SECONDS must be a whole number" >&2; exit 2 ;; esac
if [ -n "$only" ]; then
  IFS=, read -r -a selected <<< "$only"
  for t in "${selected[@]}"; do
    printf '%s\n' "${TARGETS[@]}" | grep -qx "$t" || { echo "unknown target '$t' (--list)" >&2; exit 2; }
  done
  TARGETS=("${selected[@]}")
fi

say() { printf '\033[1m==> %s\033[0m\n' "$*" >&2; }

if [ "$build" -eq 1 ]; then
  cxx=${CXX:-}
  if [ -z "$cxx" ]; then
    for c in clang++-14 clang++; do command -v "$c" > /dev/null && { cxx=$c; break; }; done
  fi
  [ -n "$cxx" ] || { echo "clang++ not found (apt-get install clang-14 libclang-rt-14-dev)" >&2; exit 2; }
  if [ ! -f "$BUILD/build.ninja" ]; then
    say "configuring the fuzz targets with $cxx ($BUILD)"
    cmake -S "$HERE" -B "$BUILD" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" > /dev/null
  fi
  say "building the fuzz targets"
  # One compile job: the targets are small, and the machine may be busy with other builds.
  cmake --build "$BUILD" -j "${FUZZ_BUILD_JOBS:-1}" | grep -v '^\[' || true
  [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "fuzz build failed" >&2; exit 2; }
fi

mkdir -p "$BUILD/artifacts" "$BUILD/logs"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:symbolize=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
work_root=$(mktemp -d "${TMPDIR:-/tmp}/harmoloc-fuzz-run-XXXXXX")
trap 'rm -rf "$work_root"' EXIT
# The targets' scratch files (fuzz_common.hpp) go here too, so a crashed fuzzer leaves nothing.
mkdir -p "$work_root/tmp"

# Classifies a failed run from its log.
classify() {
  local log=$1
  if grep -q 'ERROR: libFuzzer: timeout' "$log"; then echo timeout
  elif grep -q 'ERROR: libFuzzer: out-of-memory' "$log"; then echo out-of-memory
  elif grep -q 'ERROR: LeakSanitizer' "$log"; then echo leak
  elif grep -q '==harmoloc-fuzz== FINDING' "$log"; then echo property
  elif grep -q 'ERROR: AddressSanitizer' "$log"; then echo "asan:$(grep -o 'AddressSanitizer: [a-z-]*' "$log" | head -1 | cut -d' ' -f2)"
  elif grep -q 'runtime error:' "$log"; then echo ubsan
  elif grep -q 'ERROR: libFuzzer: deadly signal' "$log"; then echo crash
  elif grep -q 'uncaught exception\|terminate called' "$log"; then echo exception
  else echo "failed"
  fi
}

rows=()
failed=0
total=${#TARGETS[@]}
n=0
for t in "${TARGETS[@]}"; do
  n=$((n + 1))
  bin="$BUILD/${t}_fuzz"
  [ -x "$bin" ] || { echo "$bin missing (run without --no-build)" >&2; exit 2; }
  log="$BUILD/logs/$t.log"
  artifacts="$BUILD/artifacts/$t"
  mkdir -p "$artifacts"
  : > "$log"

  # 1. Saved reproducers must no longer fail.
  result=""
  mapfile -t repro < <(find "$HERE/regressions/$t" -type f ! -name '*.md' 2> /dev/null | sort)
  if [ ${#repro[@]} -gt 0 ]; then
    if ! TMPDIR="$work_root/tmp" "$bin" -timeout=5 -rss_limit_mb=2048 -artifact_prefix="$artifacts/" "${repro[@]}" \
      >> "$log" 2>&1; then
      result="REGRESSION $(classify "$log")"
    fi
  fi

  # 2. Fuzz from a copy of the committed seeds.
  execs="-" rate="-" cov="-"
  if [ -z "$result" ]; then
    if [ "$long" -eq 1 ]; then
      corpus="$BUILD/long-corpus/$t"
      if [ ! -d "$corpus" ]; then mkdir -p "$corpus"; cp "$HERE/corpus/$t/"* "$corpus/"; fi
    else
      corpus="$work_root/$t"
      mkdir -p "$corpus"
      cp "$HERE/corpus/$t/"* "$corpus/"
    fi
    args=(-max_total_time="$seconds" -timeout=5 -rss_limit_mb=2048 -print_final_stats=1
      -artifact_prefix="$artifacts/")
    d=$(dict_for "$t")
    [ -n "$d" ] && args+=(-dict="$d")
    # shellcheck disable=SC2206
    [ -n "${FUZZ_EXTRA_ARGS:-}" ] && args+=(${FUZZ_EXTRA_ARGS})
    say "[$n/$total] $t: ${seconds} s"
    status=0
    # The outer timeout only catches a fuzzer that hangs outside an input (libFuzzer's own
    # -timeout covers each input).
    TMPDIR="$work_root/tmp" timeout --signal=KILL $((seconds + 120)) "$bin" "${args[@]}" "$corpus" \
      >> "$log" 2>&1 || status=$?
    execs=$(grep -oE 'stat::number_of_executed_units: +[0-9]+' "$log" | tail -1 | awk '{print $2}' || true)
    rate=$(grep -oE 'stat::average_exec_per_sec: +[0-9]+' "$log" | tail -1 | awk '{print $2}' || true)
    cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 | awk '{print $2 "/" $4}' || true)
    if [ -z "$execs" ]; then  # a crash skips the final stats; take the last status line
      execs=$(grep -o '^#[0-9]*' "$log" | tail -1 | tr -d '#' || true)
      rate=$(grep -o 'exec/s: [0-9]*' "$log" | tail -1 | awk '{print $2}' || true)
    fi
    if [ "$status" -eq 0 ]; then
      result=ok
    elif [ "$status" -eq 137 ]; then
      result="hung (killed)"
    else
      result=$(classify "$log")
    fi
  fi
  if [ "$result" != ok ]; then
    failed=1
    unit=$(grep -o "Test unit written to [^ ]*" "$log" | tail -1 | awk '{print $5}' || true)
    [ -n "$unit" ] && result="$result -> ${unit#"$ROOT"/}"
    echo "---- $t: $result (log: ${log#"$ROOT"/})"
    { grep -E 'ERROR:|FINDING|runtime error|Assertion|SUMMARY' "$log" | grep -v 'deadly signal' | head -4
      grep -E "^ +#[0-9]+ 0x[0-9a-f]+ in .* $ROOT/" "$log" | grep -v "/tests/fuzz/fuzz_common" | head -6
    } | sed 's/^/    /' || true
  fi
  rows+=("$(printf '%-14s %12s %8s %14s  %s' "$t" "${execs:--}" "${rate:--}" "${cov:--}" "$result")")
done

printf '\n%-14s %12s %8s %14s  %s\n' target execs exec/s "cov/features" result
for r in "${rows[@]}"; do echo "$r"; done
if [ "$long" -eq 1 ]; then
  echo
  echo "Long-run corpora: $BUILD/long-corpus/<target>. To fold new inputs into the committed seeds:"
  echo "  $BUILD/<target>_fuzz -merge=1 tests/fuzz/corpus/<target> $BUILD/long-corpus/<target>"
fi
if [ "$failed" -ne 0 ]; then
  echo "findings: see build/fuzz/artifacts/ and build/fuzz/logs/ (reproduce: build/fuzz/<target>_fuzz FILE)" >&2
  exit 1
fi
