#!/usr/bin/env bash
# Checks the host tools package built by `./run package` (cmake/HarmolocToolsPackaging.cmake,
# docs/deploy.md):
#   check_tools_package.sh DEB [ARCH]
# ARCH: the package's Debian architecture, this machine's by default; arm64 (the cross-built
# tools for a robot's own computer) runs the programs under qemu-user with the arm64 libraries.
# - control: name, architecture, Depends covering every shared library the programs need,
#   Conflicts with the firmware package (same program names);
# - contents: every host tool, the docs a robot owner follows;
# - every program runs --help and --version from the unpacked package;
# - the unpacked simulator, trainer and replay work together: a small simulated run is trained
#   into a map and replayed with it (the robot owner's workflow, docs/training.md);
# - manual pages, changelog, copyright and lintian (tests/packaging/package_checks.sh).
# Prints one line per check and "N passed, N failed" at the end; exits 1 on any failure.
set -uo pipefail
deb=$1
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
source "$root/tests/packaging/package_checks.sh"
require_package "$deb"
arch=${2:-$(dpkg --print-architecture)}
run=()  # how to run the package's programs on this machine
multiarch=$(gcc -print-multiarch)
if [ "$arch" != "$(dpkg --print-architecture)" ]; then
  foreign_arch "$arch"
  multiarch=$triplet
  run=("$qemu" -L "/usr/$triplet")
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "package $deb ($(stat -c %s "$deb") bytes)"

# ---- control ----
field() { dpkg-deb -f "$deb" "$1"; }
check "Package is harmoloc-tools" [ "$(field Package)" = harmoloc-tools ]
check "Architecture is $arch" [ "$(field Architecture)" = "$arch" ]
check "Conflicts with harmoloc (the firmware package's programs have the same names)" \
  [ "$(field Conflicts)" = harmoloc ]
depends=$(field Depends)
echo "     Depends: $depends"

# ---- contents ----
dpkg-deb -c "$deb" | awk '{print $6}' | sed 's|^\./|/|' > "$work/contents"
tools=(harmoloc harmoloc-sim harmoloc-train harmoloc-report harmoloc-accuracy harmoloc-scenarios
  harmoloc-sweep harmoloc-colours harmoloc-budget harmoloc-monitor)
for t in "${tools[@]}"; do check "contains /usr/bin/$t" grep -qx "/usr/bin/$t" "$work/contents"; done
for d in training.md colours.md dataset-format.md config-format.md stats-format.md wire-protocol.md; do
  check "contains /usr/share/doc/harmoloc-tools/$d" \
    grep -qx "/usr/share/doc/harmoloc-tools/$d" "$work/contents"
done
dpkg-deb -x "$deb" "$work/root"

# ---- programs: libraries, --help, --version ----
for bin in "$work"/root/usr/bin/*; do
  b=$(basename "$bin")
  for lib in $(objdump -p "$bin" | awk '$1 == "NEEDED" {print $2}'); do
    owner=$(dpkg -S "/lib/$multiarch/$lib" "/usr/lib/$multiarch/$lib" \
      2>/dev/null | head -1 | cut -d: -f1)
    owner=${owner%:*}
    if [ -z "$owner" ]; then
      bad "$b needs $lib: no installed package has it"
    elif [[ ", $depends," == *", $owner "* || ", $depends," == *", $owner,"* ]]; then
      ok "$b needs $lib: in $owner, which Depends names"
    else
      bad "$b needs $lib from $owner, which Depends does not name"
    fi
  done
  out=$(timeout -s KILL 60 "${run[@]}" "$bin" --help 2>&1)
  rc=$?
  check "$b --help runs (exit $rc)" bash -c '[ "$1" -eq 0 ] && grep -qi usage <<< "$2"' _ "$rc" "$out"
  out=$(timeout -s KILL 60 "${run[@]}" "$bin" --version 2>&1)
  check "$b --version is $b $(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")" \
    [ "$out" = "$b $(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")" ]
done

# ---- the workflow: simulate, train, replay, all from the package ----
b=$work/root/usr/bin
if timeout -s KILL 600 "${run[@]}" "$b/harmoloc-sim" --scenario tiny --seed 1 --quiet \
     --out "$work/train" > "$work/sim.txt" 2>&1 \
   && timeout -s KILL 600 "${run[@]}" "$b/harmoloc-sim" --scenario tiny --seed 2 --quiet \
     --out "$work/test" >> "$work/sim.txt" 2>&1; then
  ok "harmoloc-sim simulates a training and a test run"
else
  bad "harmoloc-sim: $(tail -3 "$work/sim.txt")"
fi
if timeout -s KILL 900 "${run[@]}" "$b/harmoloc-train" --dataset "$work/train" \
     --labels "$work/train/labels.tum" --out "$work/map.hmap" > "$work/train.txt" 2>&1; then
  ok "harmoloc-train trains a map ($(stat -c %s "$work/map.hmap") bytes)"
else
  bad "harmoloc-train: $(tail -3 "$work/train.txt")"
fi
if timeout -s KILL 900 "${run[@]}" "$b/harmoloc" --dataset "$work/test" --map "$work/map.hmap" \
     --trajectory "$work/pose.tum" --quiet > "$work/replay.txt" 2>&1 \
   && [ "$(grep -vc '^#' "$work/pose.tum")" -gt 100 ]; then
  ok "harmoloc replays the test run with the map ($(grep -vc '^#' "$work/pose.tum") poses)"
else
  bad "harmoloc replay: $(tail -3 "$work/replay.txt")"
fi

# ---- Debian policy: manual pages, changelog, lintian ----
debian_checks "$deb" harmoloc-tools "$work/root" "$work/contents"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
