#!/usr/bin/env bash
# Proves the kernel library needs no C library, no C++ runtime, no heap and no OS: every function
# it exports (but the host-side map encoder) is linked with -nostdlib against libm, libgcc and a
# stub environment holding only what GCC requires of any freestanding target (memcpy, memmove,
# memset, memcmp) and the errno that libm sets. Anything else the kernels referred to (malloc,
# operator new, a system call, stdio, exception support) would be an undefined symbol.
#
#   check_freestanding.sh CXX libharmoloc_kernels.a [KEEP_DIR]
# KEEP_DIR: where to leave the linked image and its map (kernels-alone.elf, .map) for
# size_report.py.
set -euo pipefail

[ $# -eq 2 ] || [ $# -eq 3 ] || { echo "usage: $0 CXX LIBRARY [KEEP_DIR]" >&2; exit 2; }
cxx=$1
lib=$2
keep=${3:-}
nm=${cxx%g++}nm
cpu=(-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard)
# Host-side code in the kernel library; it allocates (heap_guard.encode_map).
host_only='encode_map'

work=$(mktemp -d "${TMPDIR:-/tmp}/harmoloc-freestanding-XXXXXX")
trap 'rm -rf "$work"' EXIT

cat > "$work/env.cpp" <<'CPP'
#include <cstddef>
extern "C" {
void* memcpy(void* d, const void* s, std::size_t n) {
  auto* o = static_cast<unsigned char*>(d);
  const auto* i = static_cast<const unsigned char*>(s);
  while (n-- > 0) *o++ = *i++;
  return d;
}
void* memmove(void* d, const void* s, std::size_t n) {
  auto* o = static_cast<unsigned char*>(d);
  const auto* i = static_cast<const unsigned char*>(s);
  if (o < i) {
    while (n-- > 0) *o++ = *i++;
  } else {
    while (n-- > 0) o[n] = i[n];
  }
  return d;
}
void* memset(void* d, int c, std::size_t n) {
  auto* o = static_cast<unsigned char*>(d);
  while (n-- > 0) *o++ = static_cast<unsigned char>(c);
  return d;
}
int memcmp(const void* a, const void* b, std::size_t n) {
  const auto* x = static_cast<const unsigned char*>(a);
  const auto* y = static_cast<const unsigned char*>(b);
  for (; n > 0; --n, ++x, ++y) {
    if (*x != *y) return *x < *y ? -1 : 1;
  }
  return 0;
}
int* __errno() {
  static int e;
  return &e;
}
void entry() {}
}
CPP
# -fno-builtin -fno-tree-loop-distribute-patterns: GCC would turn these loops into calls to
# themselves.
"$cxx" "${cpu[@]}" -O2 -ffreestanding -fno-builtin -fno-tree-loop-distribute-patterns \
  -c "$work/env.cpp" -o "$work/env.o"

mapfile -t roots < <("$nm" -g --defined-only "$lib" | awk '$2 == "T" { print $3 }' |
  grep -v "$host_only" | sort -u)
[ ${#roots[@]} -gt 0 ] || { echo "no functions found in $lib" >&2; exit 1; }
undefined=()
for r in "${roots[@]}"; do undefined+=("-Wl,--undefined=$r"); done

if ! "$cxx" "${cpu[@]}" -nostdlib -Wl,--entry=entry -Wl,--gc-sections \
  -Wl,-Map="$work/link.map" "${undefined[@]}" "$work/env.o" "$lib" -lm -lgcc \
  -o "$work/alone.elf" > "$work/link.log" 2>&1; then
  grep -o "undefined reference to \`[^']*'" "$work/link.log" | sort -u | sed 's/^/  /' >&2 || true
  echo "FAIL: the kernel library needs more than libm, libgcc and mem*/errno (above)" >&2
  exit 1
fi

# What the kernels took from libm and libgcc: the map names each archive member pulled in, then
# the file and symbol that needed it.
needs() {
  awk -v want="$1" '
    /^Archive member included/ { on = 1; next }
    /^(Discarded input sections|Memory Configuration)/ { on = 0 }
    !on || NF == 0 { next }
    /^[^ \t]/ { member = $1; if (NF == 1) next }
    member ~ ("/" want "\\(") && /libharmoloc_kernels\.a\(/ && match($0, /\([^()]*\)$/) {
      print substr($0, RSTART + 1, RLENGTH - 2)
    }' "$work/link.map" | sort -u | tr '\n' ' '
}
if [ -n "$keep" ]; then
  cp "$work/alone.elf" "$keep/kernels-alone.elf"
  cp "$work/link.map" "$keep/kernels-alone.elf.map"
fi

# The check can fail: rooted too, the host-side encoder brings operator new and must not link.
if "$cxx" "${cpu[@]}" -nostdlib -Wl,--entry=entry -Wl,--gc-sections "${undefined[@]}" \
  "-Wl,--undefined=$("$nm" -g --defined-only "$lib" | awk '$2 == "T" { print $3 }' | grep "$host_only" | head -1)" \
  "$work/env.o" "$lib" -lm -lgcc -o "$work/encoder.elf" > "$work/encoder.log" 2>&1 ||
  ! grep -q "operator new" "$work/encoder.log"; then
  echo "FAIL: the same link with the map encoder did not fail on operator new: the check is blind" >&2
  exit 1
fi

echo "ok: ${#roots[@]} functions link with -nostdlib: no heap, C library, C++ runtime or OS"
echo "  from libm: $(needs libm.a)"
echo "  from libgcc: $(needs libgcc.a)"
echo "  from the environment (stub): memcpy memmove memset memcmp __errno (libm's)"
