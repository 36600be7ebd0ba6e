#!/usr/bin/env bash
# The scaling table of docs/performance.md, measured: instructions (callgrind, deterministic) of
# segmentation and of the whole cycle against resolution, board count, particles and training
# samples, each varied with the others at the cycle's defaults (640x480 RGB24, 6 boards, 1024
# particles, 204 samples), with the straight line a * x + b fitted to each series (least
# squares; the largest deviation of a point from the line is printed), then the same kernels
# timed by harmoloc-bench (ns per frame or cycle, median of 5).
#   scaling.sh BIN_DIR WORK_DIR [--no-time|--time-only]
set -euo pipefail
bindir=$1 work=$2 mode=${3:-}
mkdir -p "$work"
repeat=4

count() {  # instructions of one run of kernel $1 with argument $2
  local out="$work/$1_$2.out"
  valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file="$out" \
    "$bindir/harmoloc-instructions" "$1" "$2" > /dev/null 2> "$work/$1_$2.log" \
    || { cat "$work/$1_$2.log"; echo "FAIL: $1 $2 did not run under callgrind" >&2; exit 1; }
  echo $(( $(awk '/^totals:/ {print $2; exit}' "$out") / repeat ))
}

xvalue() {  # the x of a point: pixels for WxH, the number otherwise
  case $1 in *x*) echo $(( ${1%x*} * ${1#*x} ));; *) echo "$1";; esac
}

# series NAME X-NAME KERNEL ARG...: one line per point, then the fit.
series() {
  local name=$1 xname=$2 kernel=$3
  shift 3
  local points=""
  printf '%s (%s, against %s)\n' "$name" "$kernel" "$xname"
  for arg in "$@"; do
    local n
    n=$(count "$kernel" "$arg")
    printf '  %-10s %12d instructions\n' "$arg" "$n"
    points+="$(xvalue "$arg") $n"$'\n'
  done
  printf '%s' "$points" | fit "$xname" instructions
}

# fit XNAME: least-squares line through "x y" lines on stdin.
fit() {
  awk -v xname="$1" -v yname="$2" '
    { x[NR] = $1; y[NR] = $2; sx += $1; sy += $2; sxx += $1 * $1; sxy += $1 * $2 }
    END {
      n = NR; a = (n * sxy - sx * sy) / (n * sxx - sx * sx); b = (sy - a * sx) / n
      worst = 0
      for (i = 1; i <= n; ++i) { d = (y[i] - (a * x[i] + b)) / y[i]; if (d < 0) d = -d; if (d > worst) worst = d }
      printf "  fit: %s = %.4g * %s + %.4g (largest deviation %.1f%%)\n", yname, a, xname, b, 100 * worst
    }'
}

if [ "$mode" != "--time-only" ]; then
series "segmentation RGB24, colour table" pixels seg_table 320x240 640x480 1280x720
series "segmentation YUYV, YUYV table" pixels seg_yuyv_table 320x240 640x480 1280x720
series "segmentation RGB24, colour table, scalar path" pixels seg_table_scalar 320x240 640x480 1280x720
series "segmentation YUYV, YUYV table, scalar path" pixels seg_yuyv_table_scalar 320x240 640x480 1280x720
series "whole cycle RGB24" pixels cycle 320x240 640x480 1280x720
series "whole cycle YUYV" pixels cycle_yuyv 320x240 640x480 1280x720
series "segmentation RGB24 at 640x480" boards seg_table_boards 1 2 3 4 5 6 7 8
series "segmentation YUYV at 640x480" boards seg_yuyv_table_boards 1 2 3 4 5 6 7 8
series "whole cycle at 640x480" boards cycle_boards 1 2 4 6 8
series "whole cycle at 640x480" particles cycle_particles 256 1024 4096
series "whole cycle at 640x480" samples cycle_samples 204 1024 4096
fi

[ "$mode" = "--no-time" ] && exit 0
echo
echo "time (harmoloc-bench, median of 5 repetitions, microseconds; args: width/height/path/boards"
echo "for the tables, path -1 the best one; width/height/format/boards/particles/samples for the"
echo "cycle):"
"$bindir/harmoloc-bench" \
  --benchmark_filter='BM_Segment(Rgb24|Yuyv)(Table|OpenCV)|BM_WholeCycle' \
  --benchmark_repetitions=5 --benchmark_report_aggregates_only=true 2>/dev/null \
  | awk '/_median/ && $3 == "us" {sub(/_median$/, "", $1); print $1, $2}' > "$work/bench.txt"
awk '{printf "  %-50s %10s\n", $1, $2}' "$work/bench.txt"

# time_series NAME XNAME "X BENCHMARK"...: the points, then the fit.
time_series() {
  local name=$1 xname=$2
  shift 2
  echo "$name, time against $xname"
  local points=""
  for point in "$@"; do
    points+=$(awk -v x="${point%% *}" -v b="${point#* }" '$1 == b {print x, $2}' "$work/bench.txt")$'\n'
  done
  printf '%s' "$points" | awk '{printf "  %-10s %10s us\n", $1, $2}'
  printf '%s' "$points" | fit "$xname" microseconds
}
time_series "segmentation RGB24, colour table, best path" pixels \
  "76800 BM_SegmentRgb24Table/320/240/-1/6" "307200 BM_SegmentRgb24Table/640/480/-1/6" \
  "921600 BM_SegmentRgb24Table/1280/720/-1/6"
time_series "segmentation YUYV, YUYV table, best path" pixels \
  "76800 BM_SegmentYuyvTable/320/240/-1/6" "307200 BM_SegmentYuyvTable/640/480/-1/6" \
  "921600 BM_SegmentYuyvTable/1280/720/-1/6"
for table in Rgb24 Yuyv; do
  points=()
  for b in 1 2 3 4 5 6 7 8; do points+=("$b BM_Segment${table}Table/640/480/-1/$b"); done
  time_series "segmentation $table at 640x480, best path" boards "${points[@]}"
done
time_series "whole cycle RGB24" pixels "76800 BM_WholeCycle/320/240/0/6/1024/204" \
  "307200 BM_WholeCycle/640/480/0/6/1024/204" "921600 BM_WholeCycle/1280/720/0/6/1024/204"
time_series "whole cycle YUYV" pixels "76800 BM_WholeCycle/320/240/1/6/1024/204" \
  "307200 BM_WholeCycle/640/480/1/6/1024/204" "921600 BM_WholeCycle/1280/720/1/6/1024/204"
time_series "whole cycle at 640x480" boards "1 BM_WholeCycle/640/480/0/1/1024/204" \
  "2 BM_WholeCycle/640/480/0/2/1024/204" "4 BM_WholeCycle/640/480/0/4/1024/204" \
  "6 BM_WholeCycle/640/480/0/6/1024/204" "8 BM_WholeCycle/640/480/0/8/1024/204"
time_series "whole cycle at 640x480" particles "256 BM_WholeCycle/640/480/0/6/256/204" \
  "1024 BM_WholeCycle/640/480/0/6/1024/204" "4096 BM_WholeCycle/640/480/0/6/4096/204"
time_series "whole cycle at 640x480" samples "204 BM_WholeCycle/640/480/0/6/1024/204" \
  "1024 BM_WholeCycle/640/480/0/6/1024/1024" "4096 BM_WholeCycle/640/480/0/6/1024/4096"
