#!/usr/bin/env bash
# Instructions of the whole cycle (steady state: 6 boards, 1024 particles, 204-sample map) and of
# its stages' kernels run alone, counted by callgrind between harmoloc-instructions' start/stop
# markers: segmentation (the cycle's path and table), the harmonic query over 204 samples, the
# particle filter's predict + per-board update + resample + estimate with 1024 particles (the
# harmonic-fix update of older maps beside it, for comparison); "rest" is the
# whole cycle minus those three (acquire, encoders, link, accounting). (callgrind's
# --toggle-collect per stage function would count the stages inside the cycle itself, but on
# aarch64 it loses track at tail calls, such as segment_rgb24's into its NEON kernel.)
# seg_table_noise is segmentation on a frame of random bytes: every pixel another table line.
# With --aarch64 the binary is the aarch64 build's and runs under Debian's arm64 valgrind
# (downloaded with apt-get download, unpacked into WORK) inside qemu-aarch64, so the counts are
# of the A64 code a Cortex-A53 runs: NEON segmentation, the aarch64 libm. docs/performance.md
# turns them into an A53 time estimate.
#   stage_instructions.sh HARMOLOC_INSTRUCTIONS WORK [--aarch64]
# The aarch64 binary: cmake -S . -B build/aarch64 -DHARMOLOC_BUILD_ARM_BENCH=ON &&
# cmake --build build/aarch64 --target harmoloc-instructions
set -euo pipefail
bin=$(realpath "$1") work=$2 mode=${3:-}
mkdir -p "$work"
work=$(realpath "$work")
repeat=4  # harmoloc-instructions measures 4 cycles

if [ "$mode" = --aarch64 ]; then
  vg=$work/valgrind-arm64
  if [ ! -x "$vg/usr/libexec/valgrind/callgrind-arm64-linux" ]; then
    (cd "$work" && apt-get download valgrind:arm64 > /dev/null 2>&1) \
      || { echo "apt-get download valgrind:arm64 failed (dpkg --add-architecture arm64; apt-get update)"; exit 1; }
    dpkg-deb -x "$work"/valgrind_*_arm64.deb "$vg"
  fi
  # The tool binary directly: valgrind's launcher would exec it, which qemu-user cannot follow.
  run_bin=(qemu-aarch64 -L /usr/aarch64-linux-gnu)
  run_callgrind() {
    VALGRIND_LIB=$vg/usr/libexec/valgrind VALGRIND_LAUNCHER=$vg/usr/bin/valgrind.bin \
      qemu-aarch64 -L /usr/aarch64-linux-gnu "$vg/usr/libexec/valgrind/callgrind-arm64-linux" \
      --tool=callgrind "$@"
  }
else
  run_bin=()
  run_callgrind() { valgrind --tool=callgrind "$@"; }
fi

# With --aarch64, callgrind also simulates caches shaped like a Cortex-A53's (32 KiB 2-way L1I,
# 32 KiB 4-way L1D, 512 KiB 16-way L2 as on a Raspberry Pi 3, 64-byte lines; LRU, no prefetch)
# and the table gets the L1D and L2 read misses per run.
cache=()
[ "$mode" = --aarch64 ] && cache=(--cache-sim=yes --I1=32768,2,64 --D1=32768,4,64 --LL=524288,16,64)

declare -A ir d1 ll
count() {  # count KERNEL ARG: instructions (and misses) per run into ir/d1/ll[KERNEL_ARG]
  local out=$work/$1_$2.out log=$work/$1_$2.log
  run_callgrind --instr-atstart=no "${cache[@]}" --callgrind-out-file="$out" "$bin" "$1" "$2" \
    > /dev/null 2> "$log" || { cat "$log"; echo "FAIL: $1 $2 under callgrind"; exit 1; }
  # events: Ir [Dr Dw I1mr D1mr D1mw ILmr DLmr DLmw]
  read -r -a t <<< "$(awk '/^totals:/ {$1 = ""; print; exit}' "$out")"
  ir[$1_$2]=$((t[0] / repeat))
  d1[$1_$2]=$(( ${#t[@]} > 1 ? t[4] / repeat : 0 ))
  ll[$1_$2]=$(( ${#t[@]} > 1 ? t[7] / repeat : 0 ))
}

for k in "harmonic 204" "filter 1024" "filter_boards 1024" "filter_boards_vis 1024" "seg_table 320x240" "seg_table 640x480" \
  "seg_yuyv_table 640x480" "seg_table_noise 320x240" "seg_table_noise 640x480" \
  "cycle 320x240" "cycle 640x480" "cycle_yuyv 640x480"; do
  count $k
done

echo "per run ($([ "$mode" = --aarch64 ] && echo "aarch64 build, callgrind under qemu-aarch64, A53-like caches" || echo "this build, callgrind")), segmentation path $("${run_bin[@]}" "$bin" path 0)"
printf '%-26s %12s %12s %12s\n' kernel instructions "L1D misses" "L2 misses"
for k in harmonic_204 filter_1024 filter_boards_1024 filter_boards_vis_1024 seg_table_320x240 seg_table_640x480 seg_yuyv_table_640x480 \
  seg_table_noise_320x240 seg_table_noise_640x480 cycle_320x240 cycle_640x480 cycle_yuyv_640x480; do
  printf '%-26s %12d %12d %12d\n' "$k" "${ir[$k]}" "${d1[$k]}" "${ll[$k]}"
done
echo
echo "stages of the cycle (instructions)"
row() { printf '%-34s %14s %14s %14s\n' "$@"; }
row stage cycle@320x240 cycle@640x480 cycle_yuyv@640x480
row "segment" "${ir[seg_table_320x240]}" "${ir[seg_table_640x480]}" "${ir[seg_yuyv_table_640x480]}"
row "localize (harmonic query, 204)" "${ir[harmonic_204]}" "${ir[harmonic_204]}" "${ir[harmonic_204]}"
row "predict + update (filter, 1024)" "${ir[filter_boards_1024]}" "${ir[filter_boards_1024]}" "${ir[filter_boards_1024]}"
rest=()
for k in "cycle_320x240 seg_table_320x240" "cycle_640x480 seg_table_640x480" \
  "cycle_yuyv_640x480 seg_yuyv_table_640x480"; do
  set -- $k
  rest+=($((ir[$1] - ir[$2] - ir[harmonic_204] - ir[filter_boards_1024])))
done
row "rest (whole minus the above)" "${rest[@]}"
row "whole cycle" "${ir[cycle_320x240]}" "${ir[cycle_640x480]}" "${ir[cycle_yuyv_640x480]}"
