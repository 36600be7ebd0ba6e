#!/usr/bin/env bash
# Counts the instructions of each kernel with callgrind (deterministic for a given binary and CPU
# path), prints a table with instructions per pixel / per sample and the ratios to the OpenCV
# baseline, and with --check fails if any kernel costs more than 10% over the committed baseline.
#   instructions.sh HARMOLOC_INSTRUCTIONS BASELINE_FILE WORK_DIR [--check|--update]
# The table kernels run on the best segmentation path of the CPU (AVX2 on the x86-64 hosts the
# baseline was recorded on); on a CPU with another best path those are reported, not checked.
set -euo pipefail
bin=$1 baseline=$2 work=$3 mode=${4:-}
mkdir -p "$work"
kernels=(
  "seg_table 640x480" "seg_yuyv_table 640x480"
  "seg_table_scalar 640x480" "seg_yuyv_table_scalar 640x480" "seg_yuyv_decode 640x480"
  "seg_rgb 320x240" "seg_rgb 640x480" "seg_rgb 1280x720"
  "seg_rgb_opencv 640x480" "seg_yuyv 640x480" "seg_yuyv_opencv 640x480"
  "harmonic 204" "harmonic 1024" "harmonic 4096"
  "filter 256" "filter 1024" "filter 4096"
  "filter_boards 256" "filter_boards 1024" "filter_boards 4096"
  "filter_boards_kld 1024" "filter_boards_kld 4096" "filter_boards_vis 1024" "filter_boards_proj 1024" "filter_boards_proj_steady 1024"
  "filter_boards_proj_areas 1024" "filter_boards_proj_areas_steady 1024" "filter_boards_proj_areas_kld 1024"
  "kidnap_preference 25" "kidnap_preference_areas 25" "nearby_tables 4" "fix_error_grid 4096" "fix_error_grid_build 4096"
  "cycle 320x240" "cycle 640x480" "cycle_yuyv 640x480" "cycle_floor 320x240"
  "cycle_floor_kld 320x240"
)
# Kernels whose count depends on the CPU's best segmentation path.
on_best_path() { case $1 in seg_table|seg_yuyv_table|cycle|cycle_yuyv|cycle_floor|cycle_floor_kld) return 0;; *) return 1;; esac; }
repeat=4
best=$("$bin" path 0)
declare -A count
for k in "${kernels[@]}"; do
  set -- $k
  out="$work/$1_$2.out"
  valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file="$out" "$bin" "$1" "$2" > /dev/null 2> "$work/$1_$2.log" \
    || { cat "$work/$1_$2.log"; echo "FAIL: $k did not run under callgrind"; exit 1; }
  total=$(awk '/^totals:/ {print $2; exit}' "$out")
  count["$1 $2"]=$((total / repeat))
done

units() {  # per pixel for frame kernels (WxH), per sample or particle otherwise
  case $2 in *x*) echo $(( ${2%x*} * ${2#*x} ));; *) echo "$2";; esac
}
echo "segmentation path: $best (best of this CPU; *_scalar kernels force the portable one)"
printf '%-22s %10s %14s %12s\n' kernel arg instructions per-unit
for k in "${kernels[@]}"; do
  set -- $k
  n=${count["$1 $2"]}
  printf '%-22s %10s %14d %12.2f\n' "$1" "$2" "$n" "$(echo "$n / $(units "$1" "$2")" | bc -l)"
done
ratio() { echo "scale=3; ${count[$1]} / ${count[$2]}" | bc -l; }
echo "ratios (same binary, same frame, 640x480):"
echo "  segmentation, colour table / OpenCV (RGB)          $(ratio 'seg_table 640x480' 'seg_rgb_opencv 640x480')"
echo "  segmentation, YUYV table / OpenCV (YUYV)           $(ratio 'seg_yuyv_table 640x480' 'seg_yuyv_opencv 640x480')"
echo "  segmentation, scalar colour table / OpenCV (RGB)   $(ratio 'seg_table_scalar 640x480' 'seg_rgb_opencv 640x480')"
echo "  segmentation, scalar YUYV table / OpenCV (YUYV)    $(ratio 'seg_yuyv_table_scalar 640x480' 'seg_yuyv_opencv 640x480')"
echo "  segmentation, HSV arithmetic / OpenCV (RGB)        $(ratio 'seg_rgb 640x480' 'seg_rgb_opencv 640x480')"
echo "  filter step, per-board update / harmonic-fix update (1024 particles) $(ratio 'filter_boards 1024' 'filter 1024')"
echo "  filter step, KLD-sampling in steady tracking / fixed count (1024 particles) $(ratio 'filter_boards_kld 1024' 'filter_boards 1024')"
echo "  filter step, floor map with visibility / without (1024 particles) $(ratio 'filter_boards_vis 1024' 'filter_boards 1024')"
echo "  filter step, areas projected too / bearings projected (1024 particles) $(ratio 'filter_boards_proj_areas 1024' 'filter_boards_proj 1024')"
echo "  filter step, floor map in steady tracking, KLD-sampling / route map, fixed count (1024 particles) $(ratio 'filter_boards_proj_areas_kld 1024' 'filter_boards 1024')"
echo "  kidnap preference near a fix, areas and bearings / areas alone (25 cm) $(ratio 'kidnap_preference 25' 'kidnap_preference_areas 25')"
echo "  whole cycle, floor map (floor search) / route map (320x240) $(ratio 'cycle_floor 320x240' 'cycle 320x240')"
echo "  whole cycle, floor map with KLD-sampling (its default) / route map (320x240) $(ratio 'cycle_floor_kld 320x240' 'cycle 320x240')"
echo "  whole cycle / OpenCV segmentation alone (RGB)      $(ratio 'cycle 640x480' 'seg_rgb_opencv 640x480')"
echo "  whole cycle / OpenCV segmentation alone (YUYV)     $(ratio 'cycle_yuyv 640x480' 'seg_yuyv_opencv 640x480')"

if [ "$mode" = "--update" ]; then
  {
    echo "# kernel arg instructions-per-run (tests/bench/instructions.sh --update; x86_64 host build)"
    echo "# path $best"
    for k in "${kernels[@]}"; do echo "$k ${count[$k]}"; done
  } > "$baseline"
  echo "baseline written to $baseline"
elif [ "$mode" = "--check" ]; then
  [ -f "$baseline" ] || { echo "FAIL: no baseline $baseline"; exit 1; }
  recorded=$(awk '$1 == "#" && $2 == "path" {print $3}' "$baseline")
  bad=0
  while read -r name arg base; do
    case $name in "#"*|"") continue;; *_opencv) continue;; esac  # OpenCV dispatches on the CPU: not ours to pin
    now=${count["$name $arg"]:-}
    [ -n "$now" ] || continue
    if on_best_path "$name" && [ "$best" != "$recorded" ]; then
      echo "not checked: $name $arg runs the $best path here, the baseline the $recorded path"
      continue
    fi
    if [ "$now" -gt $((base + base / 10)) ]; then
      echo "REGRESSION: $name $arg costs $now instructions, baseline $base (+$(( (now - base) * 100 / base ))%)"
      bad=1
    fi
  done < "$baseline"
  [ $bad -eq 0 ] || exit 1
  echo "OK: no kernel more than 10% above the baseline"
fi
