#!/usr/bin/env bash
# Checks the host tools package built by `./run package` (cmake/HarmolocToolsPackaging.cmake,
# docs/deploy.md):
#   check_tools_package.sh DEB
# - control: name, architecture (this machine's), Depends covering every shared library the
#   programs need, Conflicts with the firmware package (same program names);
# - contents: every host tool, the docs a robot owner follows;
# - every program runs --help and --version from the unpacked package;
# - manual pages, changelog, copyright and lintian (tests/packaging/package_checks.sh).
# Prints one line per check and "N passed, N failed" at the end; exits 1 on any failure.
set -uo pipefail
deb=$1
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
source "$root/tests/packaging/package_checks.sh"
require_package "$deb"
arch=$(dpkg --print-architecture)
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
    owner=$(dpkg -S "/lib/$(gcc -print-multiarch)/$lib" "/usr/lib/$(gcc -print-multiarch)/$lib" \
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
  out=$(timeout -s KILL 60 "$bin" --help 2>&1)
  rc=$?
  check "$b --help runs (exit $rc)" bash -c '[ "$1" -eq 0 ] && grep -qi usage <<< "$2"' _ "$rc" "$out"
  out=$(timeout -s KILL 60 "$bin" --version 2>&1)
  check "$b --version is $b $(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")" \
    [ "$out" = "$b $(sed -n 's/^project(harmoloc VERSION \([0-9.]*\).*/\1/p' "$root/CMakeLists.txt")" ]
done

# ---- Debian policy: manual pages, changelog, lintian ----
debian_checks "$deb" harmoloc-tools "$work/root" "$work/contents"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
