#!/usr/bin/env bash
# Runs a bare-metal Cortex-M7 program on QEMU's MPS2 AN500 board with semihosting: the
# program's console goes to stdout, its arguments come from -append and its exit status is
# QEMU's. CMake's CMAKE_CROSSCOMPILING_EMULATOR (toolchains/arm-none-eabi-cortex-m7.cmake).
#
#   tests/baremetal/qemu-mps2-an500.sh PROGRAM.elf [ARGS...]
#
# Environment: QEMU_M7_TIMEOUT (seconds, default 60): a program that hangs is killed and the
# run fails with status 124.
set -euo pipefail

[ $# -ge 1 ] || { echo "usage: $0 PROGRAM.elf [ARGS...]" >&2; exit 2; }
elf=$1
shift
[ -f "$elf" ] || { echo "$elf: no such program" >&2; exit 2; }
command -v qemu-system-arm > /dev/null ||
  { echo "qemu-system-arm not found (apt-get install qemu-system-arm)" >&2; exit 2; }

# Semihosting passes one command line; QEMU puts the kernel's file name first (argv[0]).
cmdline="$*"

status=0
timeout --signal=KILL "${QEMU_M7_TIMEOUT:-60}" \
  qemu-system-arm -M mps2-an500 -nographic -monitor none -serial none \
  -semihosting-config enable=on,target=native -kernel "$elf" -append "$cmdline" || status=$?
if [ "$status" -eq 137 ]; then
  echo "$(basename "$elf"): no exit after ${QEMU_M7_TIMEOUT:-60} s on the emulated core (killed)" >&2
  exit 124
fi
exit "$status"
