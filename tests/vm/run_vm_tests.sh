#!/usr/bin/env bash
# The drivers' test bench (docs/testbench.md): Debian's own kernel under qemu-system-x86_64 (TCG)
# with a small initramfs (busybox, the kernel's vivid, vcan and can-raw modules, gpio-sim built
# out of tree from linux-source-6.1), the Linux board's driver tests and its harmoloc. Checks
# what the VM prints on its console and decodes the MAVLink stream that leaves it on a second
# serial line with node-mavlink on the host.
#
#   tests/vm/run_vm_tests.sh [x86_64|aarch64]   (./run test-vm installs the packages, calls both)
#
# x86_64 (default): Debian's amd64 kernel, the native Linux board (build/linux), link on ttyS1.
# aarch64: Debian's arm64 kernel under qemu-system-aarch64 -M virt -cpu cortex-a53, the
# cross-built Linux board (build/aarch64), gpio-sim cross-built against Debian's arm64 headers,
# arm64 busybox and can-utils from apt-get download, link on a virtio console (hvc0).
# Everything downloaded or built is cached in build/vm-cache (keyed by the kernel version).
# Exit status: 0 all passed; 1 a check failed; 3 the bench cannot run here (reason printed).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../.."
ROOT=$PWD
ARCH=${1:-x86_64}
CACHE=$ROOT/build/vm-cache
WORK=$ROOT/build/vm-work-$ARCH
case $ARCH in
  x86_64) DEB_ARCH=amd64; LINUX_BUILD=$ROOT/build/linux; QEMU=qemu-system-x86_64
    CONSOLE_DEV=ttyS0; LINK_DEV=/dev/ttyS1; LIB_DIRS="/lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /lib64"
    EXTRA_MODULES="" ;;
  aarch64) DEB_ARCH=arm64; LINUX_BUILD=$ROOT/build/aarch64; QEMU=qemu-system-aarch64
    CONSOLE_DEV=ttyAMA0; LINK_DEV=/dev/hvc0; LIB_DIRS="/lib/aarch64-linux-gnu /usr/lib/aarch64-linux-gnu /lib"
    EXTRA_MODULES="virtio_mmio virtio_console" ;;
  *) echo "usage: $0 [x86_64|aarch64]" >&2; exit 2 ;;
esac
HOST_BIN=$ROOT/build/host/bin
T0=$(date +%s.%N)
say() { printf '\033[1m==> vm: %s\033[0m\n' "$*" >&2; }
cannot() { echo "VM TEST BENCH CANNOT RUN: $*" >&2; exit 3; }
fail() { echo "FAIL: $*" >&2; FAILED=$((FAILED + 1)); }
elapsed() { python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" "$1" "$(date +%s.%N)"; }
FAILED=0

for tool in "$QEMU" busybox depmod modprobe cpio xz make gcc node python3 readelf; do
  command -v "$tool" > /dev/null || cannot "'$tool' is missing (./run test-vm installs it)"
done
[ -x "$HOST_BIN/harmoloc-sim" ] || cannot "the host board is not built (build/host/bin/harmoloc-sim)"
[ -d tests/mavlink/node_modules/node-mavlink ] || cannot "node-mavlink is not installed (./run setup)"

# ---- the kernel: Debian's current 6.1 amd64 image, unpacked, never installed ------------------
# The amd64 kernel's version names the arm64 one too (same Debian kernel build).
KVER_AMD64=${HARMOLOC_VM_KERNEL:-$(apt-cache depends linux-image-amd64 2> /dev/null |
  sed -n 's/.*Depends: linux-image-\(.*\)$/\1/p' | head -1)}
[ -n "$KVER_AMD64" ] || cannot "apt does not know linux-image-amd64 (apt-get update?)"
KVER=${KVER_AMD64%-amd64}-$DEB_ARCH
[ -d "/usr/src/linux-headers-$KVER_AMD64" ] || cannot "linux-headers-$KVER_AMD64 is not installed (./run test-vm installs it)"
mkdir -p "$CACHE/debs"
# fetch PACKAGE[:ARCH]: its .deb into build/vm-cache/debs once (apt-get download, never
# installed); prints the file.
fetch() {
  local name=${1%%:*}
  ls "$CACHE/debs/${name}"_*"_$DEB_ARCH.deb" > /dev/null 2>&1 || ls "$CACHE/debs/${name}"_*_all.deb > /dev/null 2>&1 ||
    (cd "$CACHE/debs" && apt-get download "$1" > /dev/null 2>&1) || cannot "apt-get download $1 failed (offline?)"
  local f found=""
  for f in "$CACHE/debs/${name}"_*"_$DEB_ARCH.deb" "$CACHE/debs/${name}"_*_all.deb; do
    [ -e "$f" ] && found=$f
  done
  echo "$found"
}
KDIR=$CACHE/kernel-$KVER
if [ ! -f "$KDIR/.done" ]; then
  say "fetching and unpacking linux-image-$KVER (apt-get download)"
  rm -rf "$KDIR"; mkdir -p "$KDIR"
  dpkg-deb -x "$(fetch "linux-image-$KVER:$DEB_ARCH")" "$KDIR/root"
  depmod -b "$KDIR/root" "$KVER"
  touch "$KDIR/.done"
fi
VMLINUZ=$KDIR/root/boot/vmlinuz-$KVER
# Userland pieces of the guest's architecture: busybox and canplayer; the kernel headers.
if [ "$ARCH" = x86_64 ]; then
  BUSYBOX=$(command -v busybox); CANPLAYER=$(command -v canplayer || true)
  [ -n "$CANPLAYER" ] || cannot "canplayer (can-utils) is missing"
  KHEADERS=/usr/src/linux-headers-$KVER; KMAKE=()
else
  U=$CACHE/userland-$DEB_ARCH
  if [ ! -f "$U/.done" ]; then
    rm -rf "$U"; mkdir -p "$U"
    dpkg-deb -x "$(fetch "busybox-static:$DEB_ARCH")" "$U"
    dpkg-deb -x "$(fetch "can-utils:$DEB_ARCH")" "$U"
    touch "$U/.done"
  fi
  BUSYBOX=$U/bin/busybox; CANPLAYER=$U/usr/bin/canplayer
  # Debian's arm64 headers, unpacked: their kbuild scripts link to the host's linux-kbuild-6.1
  # (x86_64 tools), their common part is the amd64 headers' dependency (the same version).
  KHEADERS=$CACHE/headers-$KVER/usr/src/linux-headers-$KVER
  if [ ! -f "$KHEADERS/.config" ]; then
    rm -rf "$CACHE/headers-$KVER"
    dpkg-deb -x "$(fetch "linux-headers-$KVER:$DEB_ARCH")" "$CACHE/headers-$KVER"
    ln -sfn /usr/lib/linux-kbuild-6.1/scripts "$KHEADERS/scripts"
    ln -sfn /usr/lib/linux-kbuild-6.1/tools "$KHEADERS/tools"
  fi
  command -v aarch64-linux-gnu-gcc-12 > /dev/null || cannot "aarch64-linux-gnu-gcc-12 is missing (./run test-arm64 installs it)"
  KMAKE=(ARCH=arm64 CROSS_COMPILE=aarch64-linux-gnu-)
fi
[ -x "$BUSYBOX" ] || cannot "busybox ($DEB_ARCH) is missing"

# ---- the few kernel sources the out-of-tree modules need, from linux-source-6.1 (one pass) -------
KSRC=$CACHE/linux-source-files
if [ ! -f "$KSRC/.done" ]; then
  say "unpacking gpio-sim, irq_sim and vimc sources from linux-source-6.1 (apt-get download)"
  rm -rf "$KSRC"; mkdir -p "$KSRC"
  dpkg-deb --fsys-tarfile "$(fetch linux-source-6.1)" | tar -xO ./usr/src/linux-source-6.1.tar.xz |
    tar -xJ -C "$KSRC" --strip-components=1 --wildcards linux-source-6.1/drivers/gpio/gpio-sim.c \
      linux-source-6.1/drivers/gpio/gpiolib.h linux-source-6.1/kernel/irq/irq_sim.c \
      'linux-source-6.1/drivers/media/test-drivers/vimc/*.[ch]'
  touch "$KSRC/.done"
fi

# ---- gpio-sim, built out of tree (Debian's kernels have CONFIG_GPIO_SIM off) -------------------
GSIM=$CACHE/gpio-sim-$KVER
if [ ! -f "$GSIM/gpio-sim.ko" ]; then
  say "building gpio-sim out of tree against linux-headers-$KVER"
  rm -rf "$GSIM"; mkdir -p "$GSIM"
  cp "$KSRC/drivers/gpio/gpio-sim.c" "$GSIM/gpio-sim-main.c"
  cp "$KSRC/drivers/gpio/gpiolib.h" "$GSIM/"
  # irq_to_desc() is not exported to modules; generic_handle_irq_safe() does the same here.
  sed 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq_safe(irqnum);/' \
    "$KSRC/kernel/irq/irq_sim.c" > "$GSIM/irq_sim.c"
  grep -q 'generic_handle_irq_safe(irqnum)' "$GSIM/irq_sim.c" || cannot "irq_sim.c did not take the patch"
  cp tests/vm/gpio-sim/Kbuild "$GSIM/Kbuild"
  make -s -C "$KHEADERS" M="$GSIM" "${KMAKE[@]}" modules > "$GSIM/build.log" 2>&1 ||
    { tail -20 "$GSIM/build.log" >&2; cannot "gpio-sim did not build (see $GSIM/build.log)"; }
fi
# vimc (the virtual media-controller camera libcamera's vimc pipeline drives) is off in Debian's
# kernels too (CONFIG_VIDEO_VIMC not set): built out of tree the same way, unpatched.
VIMC=$CACHE/vimc-$KVER
if [ ! -f "$VIMC/vimc.ko" ]; then
  say "building vimc out of tree against linux-headers-$KVER"
  rm -rf "$VIMC"; mkdir -p "$VIMC"
  cp "$KSRC"/drivers/media/test-drivers/vimc/*.[ch] "$VIMC/"
  printf 'obj-m := vimc.o\nvimc-y := vimc-core.o vimc-common.o vimc-streamer.o vimc-capture.o vimc-debayer.o vimc-scaler.o vimc-sensor.o vimc-lens.o\n' > "$VIMC/Kbuild"
  make -s -C "$KHEADERS" M="$VIMC" "${KMAKE[@]}" modules > "$VIMC/build.log" 2>&1 ||
    { tail -20 "$VIMC/build.log" >&2; cannot "vimc did not build (see $VIMC/build.log)"; }
fi
# v4l2loopback (a V4L2 device fed with our own frames, for the whole-loop run): Debian's
# v4l2loopback-dkms is source only; built out of tree the same way, unpatched.
# The whole loop runs on x86_64 only (HARMOLOC_VM_LOOP=0 skips it there).
LOOP=$([ "$ARCH" = x86_64 ] && echo "${HARMOLOC_VM_LOOP:-1}" || echo 0)
V4L2LB=$CACHE/v4l2loopback-$KVER
if [ "$LOOP" = 1 ] && [ ! -f "$V4L2LB/v4l2loopback.ko" ]; then
  say "building v4l2loopback out of tree against linux-headers-$KVER (v4l2loopback-dkms source)"
  rm -rf "$V4L2LB"; mkdir -p "$V4L2LB/deb"
  dpkg-deb -x "$(fetch v4l2loopback-dkms)" "$V4L2LB/deb"
  cp "$V4L2LB"/deb/usr/src/v4l2loopback-*/v4l2loopback.c "$V4L2LB"/deb/usr/src/v4l2loopback-*/v4l2loopback_formats.h "$V4L2LB/"
  printf 'obj-m := v4l2loopback.o\n' > "$V4L2LB/Kbuild"
  make -s -C "$KHEADERS" M="$V4L2LB" "${KMAKE[@]}" modules > "$V4L2LB/build.log" 2>&1 ||
    { tail -20 "$V4L2LB/build.log" >&2; cannot "v4l2loopback did not build (see $V4L2LB/build.log)"; }
fi
# libcamera's IPA modules (the vimc pipeline needs ipa_vimc), unpacked from Debian's libcamera-ipa.
IPA=$CACHE/libcamera-ipa-$DEB_ARCH
if [ ! -f "$IPA/.done" ]; then
  rm -rf "$IPA"; mkdir -p "$IPA"
  dpkg-deb -x "$(fetch "libcamera-ipa:$DEB_ARCH")" "$IPA"
  touch "$IPA/.done"
fi
say "kernel $KVER, gpio-sim, vimc$([ "$LOOP" = 1 ] && echo " and v4l2loopback") modules ready ($(elapsed "$T0") s)"

# ---- the Linux board, native x86_64 (build/linux) ----------------------------------------------
T1=$(date +%s.%N)
PRESET=$([ "$ARCH" = x86_64 ] && echo linux || echo aarch64)
say "building the Linux board for $ARCH (build/$(basename "$LINUX_BUILD")): harmoloc, vm_drivers_test"
cmake --preset "$PRESET" > /dev/null
cmake --build --preset "$PRESET" -j "$(nproc)" --target harmoloc vm_drivers_test vm_libcamera_test notify_listener $([ "$LOOP" = 1 ] && echo vm_feeder) > "$CACHE/build-$ARCH.log" 2>&1 ||
  { tail -30 "$CACHE/build-$ARCH.log" >&2; echo "FAIL: the Linux board did not build" >&2; exit 1; }
say "Linux board built ($(elapsed "$T1") s)"

# ---- data for the end-to-end run: a map at vivid's 320x180, the simulated robot's CAN log ------
rm -rf "$WORK"; mkdir -p "$WORK/e2e"
E2E=$WORK/e2e
cat > "$E2E/scenario.toml" <<'EOF'
base = "tiny"
name = "vm-320x180"
description = "the tiny scenario at vivid's webcam size"
[camera]
width_px = 320
height_px = 180
EOF
"$HOST_BIN/harmoloc-sim" --scenario "$E2E/scenario.toml" --seed 1 --out "$E2E/train" --quiet
"$HOST_BIN/harmoloc-train" --dataset "$E2E/train" --labels "$E2E/train/labels.tum" --out "$E2E/map.hmap" > "$E2E/train.log"

# ---- initramfs ---------------------------------------------------------------------------------
T2=$(date +%s.%N)
IRD=$WORK/initramfs
mkdir -p "$IRD"/{bin,sbin,usr/bin,usr/sbin,proc,sys,dev,tmp,run,vm/e2e,lib/modules}
cp "$BUSYBOX" "$IRD/bin/busybox"
# The applet list from the host's busybox (the same package; the guest's may be another arch).
for applet in $(busybox --list); do
  [ -e "$IRD/bin/$applet" ] || ln -s busybox "$IRD/bin/$applet"
done
cp tests/vm/init.sh "$IRD/init"; chmod +x "$IRD/init"
cp "$LINUX_BUILD/bin/harmoloc" "$LINUX_BUILD/bin/vm_drivers_test" "$LINUX_BUILD/bin/vm_libcamera_test" \
  "$LINUX_BUILD/bin/notify_listener" "$CANPLAYER" "$IRD/vm/"
[ "$LOOP" = 1 ] && cp "$LINUX_BUILD/bin/vm_feeder" "$IRD/vm/"
# libcamera's IPA modules, their proxies and configuration, where libcamera looks for them.
cp -a "$IPA/usr" "$IRD/"
ln -sf /vm/canplayer "$IRD/usr/bin/canplayer"
cp tests/vm/can_encoders.log "$IRD/vm/"
cp "$E2E/map.hmap" "$IRD/vm/e2e/"
# The simulated robot's encoders: candump -l lines, interface can0, replayed onto vcan0.
cp "$E2E/train/encoders.log" "$IRD/vm/e2e/encoders.log"
cat > "$IRD/vm/e2e/harmoloc.toml" <<'EOF'
[camera]
driver = "v4l2"
device = "/dev/video0"
width = 320
height = 180
format = "auto"
[encoders]
driver = "can"
[can]
interface = "vcan0"
[link]
device = "@LINK_DEV@"
baud = 115200
EOF
sed -i "s|@LINK_DEV@|$LINK_DEV|" "$IRD/vm/e2e/harmoloc.toml"
# The whole loop's firmware config: the loopback as the camera, vcan0 as the encoder bus; the
# cycle's rate and time-outs slowed by the same factor as the feeder plays the run.
LOOP_K=${HARMOLOC_VM_LOOP_SLOWDOWN:-2}
python3 - "$LOOP_K" > "$IRD/vm/e2e/loop.toml" <<'PY'
import sys
k = float(sys.argv[1])
print(f"""[cycle]
rate_hz = {30 / k:g}
camera_timeout_ms = {250 * k:g}
encoder_timeout_ms = {250 * k:g}
[camera]
driver = "v4l2"
device = "/dev/video20"
width = 320
height = 180
format = "auto"
[encoders]
driver = "can"
[can]
interface = "vcan0"
""")
PY
printf '[camera]\ndevice = "/dev/video7"\nwidth = 320\nheight = 180\n[can]\ninterface = "vcan0"\n' > "$IRD/vm/e2e/bad_camera.toml"
# Shared libraries of the programs: the NEEDED closure (readelf, so it works for either
# architecture) found in the architecture's library folders, and the dynamic loader.
needed_closure() {
  local todo=("$@") seen=" " f lib dir found
  while [ ${#todo[@]} -gt 0 ]; do
    f=${todo[0]}; todo=("${todo[@]:1}")
    for lib in $(readelf -d "$f" 2> /dev/null | sed -n 's/.*Shared library: \[\(.*\)\]/\1/p'); do
      case $seen in *" $lib "*) continue ;; esac
      seen="$seen$lib "
      found=""
      for dir in $LIB_DIRS; do [ -e "$dir/$lib" ] && { found=$dir/$lib; break; }; done
      [ -n "$found" ] || cannot "library $lib (needed by $(basename "$f")) not found in $LIB_DIRS"
      echo "$found"
      todo+=("$found")
    done
  done
}
for lib in $(needed_closure "$IRD/vm/harmoloc" "$IRD/vm/vm_drivers_test" "$IRD/vm/vm_libcamera_test" "$IRD/vm/notify_listener" "$IRD/vm/canplayer" \
  "$IRD"/usr/lib/*/libcamera/ipa_vimc.so "$IRD"/usr/lib/*/libcamera/vimc_ipa_proxy | sort -u); do
  mkdir -p "$IRD$(dirname "$lib")"
  cp -L "$lib" "$IRD$lib"
done
INTERP=$(readelf -l "$IRD/vm/harmoloc" | sed -n 's/.*Requesting program interpreter: \(.*\)\]/\1/p')
mkdir -p "$IRD$(dirname "$INTERP")"
cp -L "$INTERP" "$IRD$INTERP"
# Modules: the dependency closure of what the tests load, decompressed (busybox modprobe reads
# plain .ko), plus gpio-sim.
MODS=$IRD/lib/modules/$KVER
mkdir -p "$MODS/extra"
for m in configfs vivid vcan can-raw virtio_pci virtio_blk $EXTRA_MODULES $(modinfo -F depends "$VIMC/vimc.ko" | tr , ' ') \
  $([ "$LOOP" = 1 ] && modinfo -F depends "$V4L2LB/v4l2loopback.ko" | tr , ' '); do
  modprobe -d "$KDIR/root" -S "$KVER" --show-depends "$m" 2> /dev/null | awk '$1 == "insmod" {print $2}'
done | sort -u | while read -r ko; do
  rel=${ko#"$KDIR/root/lib/modules/$KVER/"}
  mkdir -p "$MODS/$(dirname "$rel")"
  case $ko in
    *.xz) xz -dc "$ko" > "$MODS/${rel%.xz}" ;;
    *) cp "$ko" "$MODS/$rel" ;;
  esac
done
cp "$GSIM/gpio-sim.ko" "$VIMC/vimc.ko" "$MODS/extra/"
[ "$LOOP" = 1 ] && cp "$V4L2LB/v4l2loopback.ko" "$MODS/extra/"
cp "$KDIR/root/lib/modules/$KVER"/modules.{order,builtin,builtin.modinfo} "$MODS/" 2> /dev/null || true
depmod -b "$IRD" "$KVER"
(cd "$IRD" && find . | cpio -o -H newc --quiet | gzip -1 > "$WORK/initramfs.cpio.gz")
say "initramfs $(du -h "$WORK/initramfs.cpio.gz" | cut -f1) ($(elapsed "$T2") s)"

# HARMOLOC_VM_LOOP_ONLY=1 skips this boot and its checks (the whole loop alone, below).
VM_S=skipped
if [ "${HARMOLOC_VM_LOOP_ONLY:-0}" != 1 ]; then

# ---- the command the host sends down the line: SET_POSE (unsigned, from a ground station) ------
cat > "$WORK/commands.json" <<'EOF'
[{"name": "set_pose", "command": 31011, "params": [1.0, -0.5, 0.3, 0.05, 0.05, 0, 0],
  "sysid": 255, "compid": 190, "targetSystem": 1, "targetComponent": 197,
  "key": null, "linkId": 0, "timestampMs": 0}]
EOF
node tests/mavlink/link_peer.js frames "$WORK/commands.json" "$WORK/commands.out.json"
COMMAND_HEX=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['set_pose'])" "$WORK/commands.out.json")

# ---- boot -------------------------------------------------------------------------------------
T3=$(date +%s.%N)
SOCK=$WORK/link.sock
VM_TIMEOUT_S=${HARMOLOC_VM_TIMEOUT_S:-900}
python3 -u tests/vm/link_listener.py "$SOCK" "$WORK/link.bin" "$COMMAND_HEX" 0 "$VM_TIMEOUT_S" > "$WORK/listener.out" 2> "$WORK/listener.err" &
LISTENER=$!
for _ in $(seq 100); do grep -q listening "$WORK/listener.out" 2> /dev/null && break; sleep 0.1; done
if [ "$ARCH" = x86_64 ]; then
  MACHINE=(-accel tcg -cpu max -serial "file:$WORK/console.log" -serial "unix:$SOCK")
else
  # virt has one UART (the console); the link is a virtio console on the same Unix socket.
  MACHINE=(-M virt -accel tcg -cpu cortex-a53 -serial "file:$WORK/console.log"
    -chardev "socket,id=link,path=$SOCK" -device virtio-serial-device -device virtconsole,chardev=link)
fi
say "booting Debian's kernel $KVER under $QEMU (TCG, 1 CPU); console in build/$(basename "$WORK")/console.log"
set +e
timeout -s KILL "$VM_TIMEOUT_S" "$QEMU" "${MACHINE[@]}" -smp 1 -m 768 -nographic -no-reboot \
  -kernel "$VMLINUZ" -initrd "$WORK/initramfs.cpio.gz" \
  -append "console=$CONSOLE_DEV quiet loglevel=3 panic=-1 HARMOLOC_VM_SECONDS=${HARMOLOC_VM_SECONDS:-12} HARMOLOC_VM_MODULES=$(echo "$EXTRA_MODULES" | tr ' ' ,)" \
  -monitor none > "$WORK/qemu.out" 2>&1
QEMU_RC=$?
set -e
wait "$LISTENER" || true
VM_S=$(elapsed "$T3")
say "VM ran $VM_S s (qemu exit $QEMU_RC); $(cat "$WORK/listener.err")"
CONSOLE=$WORK/console.log
tr -d '\r' < "$CONSOLE" > "$WORK/console.txt"
CONSOLE=$WORK/console.txt

# ---- checks -------------------------------------------------------------------------------------
grep -q '^VMDONE' "$CONSOLE" || fail "the VM did not finish its script (timeout $VM_TIMEOUT_S s or a crash); see $CONSOLE"
sed -n '/^VMTEST-BEGIN drivers/,/^VMTEST-END drivers/p' "$CONSOLE" | grep -E '^\[ *(OK|FAILED|PASSED|RUN) *\]|VMSTAT' | grep -v '^\[ RUN' >&2 || true
grep -q '^VMTEST-END drivers rc=0' "$CONSOLE" || {
  sed -n '/^VMTEST-BEGIN drivers/,/^VMTEST-END drivers/p' "$CONSOLE" | grep -B3 -A12 'Failure\|FAILED' | head -80 >&2
  fail "driver tests in the VM failed (vm_drivers_test)"
}
sed -n '/^VMTEST-BEGIN libcamera/,/^VMTEST-END libcamera/p' "$CONSOLE" | grep -E '^\[ *(OK|FAILED|PASSED) *\]|VMSTAT' >&2 || true
grep -q '^VMTEST-END libcamera rc=0' "$CONSOLE" || {
  sed -n '/^VMTEST-BEGIN libcamera/,/^VMTEST-END libcamera/p' "$CONSOLE" | grep -B3 -A12 'Failure\|FAILED\|ERROR' | head -60 >&2
  fail "the libcamera driver's test against vimc failed in the VM (vm_libcamera_test)"
}
grep -q '^VMTEST-END harmoloc rc=0' "$CONSOLE" || fail "harmoloc (Linux board) did not complete its run in the VM: $(grep -m3 'harmoloc' "$CONSOLE" | tr '\n' ' ')"
# The service notifications (Type=notify with a 1 s watchdog): READY first, the watchdog fed all
# along (every 0.5 s; at least a quarter of that is asked, as the VM's emulated CPU may lag), a
# STATUS with the first health change (vivid shows no boards: odometry only), STOPPING last.
NOTIFY_LOG=$(sed -n '/^VMTEST-BEGIN harmoloc/,/^VMTEST-END harmoloc/p' "$CONSOLE" | tr -d '\r' | grep '^NOTIFY ' || true)
say "service notifications in the VM: $(grep -c 'WATCHDOG=1' <<< "$NOTIFY_LOG") watchdog, $(grep -m1 'READY=1' <<< "$NOTIFY_LOG" | cut -d' ' -f3-)"
python3 - "${HARMOLOC_VM_SECONDS:-12}" "$NOTIFY_LOG" <<'PY' || fail "the service notifications (sd_notify) in the VM: $(head -c 600 <<< "$NOTIFY_LOG")"
import sys
seconds, lines = float(sys.argv[1]), [l.split(' ', 2)[2] for l in sys.argv[2].splitlines() if l.count(' ') >= 2]
watchdogs = sum(1 for l in lines if l == 'WATCHDOG=1')
ok = (bool(lines) and lines[0].startswith('READY=1|STATUS=localizing')
      and lines[-1].startswith('STOPPING=1|STATUS=')
      and any(l.startswith('STATUS=harmoloc: health ') for l in lines)
      and watchdogs >= seconds / 2)
sys.exit(0 if ok else 1)
PY
# The recording on the robot: every file there, frames (vivid's YUYV) and counts that agree.
REC_LINE=$(grep -m1 '^VMTEST-END record' "$CONSOLE" || true)
say "recording in the VM: ${REC_LINE#VMTEST-END record }"
python3 - "$REC_LINE" <<'PY' || fail "harmoloc --record on the Linux board in the VM: $REC_LINE"
import re, sys
f = dict(re.findall(r'(\w+)=(\S+)', sys.argv[1]))
ok = (f.get('rc') == '0' and int(f.get('frames', 0)) >= 5 and f.get('files') == f.get('frames')
      and int(f.get('encoders', 0)) >= 10 and int(f.get('areas', 0)) >= 5
      and f.get('format') in ('yuyv', 'rgb24'))
sys.exit(0 if ok else 1)
PY
grep -q '^VMTEST-END bad_camera rc=2 lines=1 harmoloc: camera /dev/video7: No such file or directory' "$CONSOLE" ||
  fail "a missing camera must give exit status 2 and one line: $(grep '^VMTEST-END bad_camera' "$CONSOLE")"
sed -n '/^VMSTATS-BEGIN/,/^VMSTATS-END/p' "$CONSOLE" | sed '1d;$d' > "$WORK/stats.json"
grep '^harmoloc:' "$CONSOLE" >&2 || true
python3 - "$WORK/stats.json" "${HARMOLOC_VM_SECONDS:-12}" >&2 <<'PY' || fail "the end-to-end run's stats do not hold"
import json, sys
s = json.load(open(sys.argv[1]))
seconds = float(sys.argv[2])
bad = []
def need(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok: bad.append(what)
need(s["board"] == "linux", f"board {s['board']}")
need(s["cycles"] >= 10 * seconds, f"{s['cycles']} cycles in {seconds:.0f} s")
need(s["camera"]["frames"] >= 30, f"{s['camera']['frames']} frames from vivid (>= 30)")
need(s["camera"]["errors"] == 0 and s["camera"]["corrupt"] == 0, "no camera errors or corrupt frames")
need(s["encoders"]["samples"] >= 50 * seconds, f"{s['encoders']['samples']} CAN encoder samples from vcan0")
need(s["encoders"]["bad_length"] == 0 and s["encoders"]["ignored_id"] == 0, "no bad CAN frames")
need(s["link"]["frames_sent"] > 0 and s["link"]["errors"] == 0, f"{s['link']['frames_sent']} link frames sent, no errors")
need(s["link"]["frames_dropped"] == 0, f"{s['link']['frames_dropped']} link frames dropped")
need(s["inbound"]["commands_accepted"] == 1, f"{s['inbound']['commands_accepted']} command accepted (SET_POSE from the host)")
need(s["health_cycles"]["odometry_only"] > 0, "odometry-only cycles after SET_POSE (vivid's test pattern is not on the map)")
print(f"VM e2e: cycle median {s['stages']['cycle']['median_us']} us, p99 {s['stages']['cycle']['p99_us']} us, "
      f"acquire median {s['stages']['acquire']['median_us']} us, overruns {s['overruns']}")
sys.exit(1 if bad else 0)
PY
# The stats asked for with SIGUSR1 mid-run: written by then, the run still going, fewer cycles
# than at the end.
sed -n '/^VMSTATS-REQUEST-BEGIN/,/^VMSTATS-REQUEST-END/p' "$CONSOLE" | sed '1d;$d' > "$WORK/stats_on_request.json"
python3 - "$WORK/stats_on_request.json" "$WORK/stats.json" >&2 <<'PY' || fail "no stats on SIGUSR1 while running"
import json, sys
try:
    mid = json.load(open(sys.argv[1]))
except ValueError as e:
    print(f"FAIL the stats file written on SIGUSR1 is not JSON ({e})")
    sys.exit(1)
end = json.load(open(sys.argv[2]))
ok = mid.get("ended") == "running" and 0 < mid.get("cycles", 0) < end["cycles"]
print(("ok   " if ok else "FAIL ") + f"stats on SIGUSR1 mid-run: ended {mid.get('ended')!r}, "
      f"{mid.get('cycles')} cycles of {end['cycles']}")
sys.exit(0 if ok else 1)
PY
[ -s "$WORK/link.bin" ] || fail "nothing arrived on the link ($LINK_DEV)"
if [ -s "$WORK/link.bin" ]; then
  say "decoding the link ($(stat -c %s "$WORK/link.bin") bytes from $LINK_DEV) with node-mavlink"
  node tests/mavlink/decode_link.js --expect-latency "$WORK/link.bin" || fail "node-mavlink did not decode the VM's link cleanly (or its capture-to-send reports)"
  # Negative control: a flipped byte must be caught.
  python3 -c "import sys; d=bytearray(open(sys.argv[1],'rb').read()); d[len(d)//2]^=0x40; open(sys.argv[2],'wb').write(d)" "$WORK/link.bin" "$WORK/link-bad.bin"
  if node tests/mavlink/decode_link.js "$WORK/link-bad.bin" > /dev/null 2>&1; then fail "a corrupted copy of the link passed the decoder"; fi
fi

fi  # HARMOLOC_VM_LOOP_ONLY

# ---- the whole loop: a simulated run through the kernel's drivers, trained and localized --------
# Boot 1 (HARMOLOC_VM_MODE=loop-record): vm_feeder plays the simulated run ($E2E/train: frames
# into v4l2loopback's /dev/video20, its candump log onto vcan0, one clock, slowed by LOOP_K) while
# the Linux board records it (harmoloc --record). The recording comes out on a virtio disk (a
# tar), the map is trained from it on the host (labels moved onto the VM's clock). Boot 2
# (loop-localize): the same run played again, the Linux board localizes with that map. Its
# position RMS error against the ground truth must be within 1 cm of a host replay's of the same
# run with the same map, or within 1.5 times it. The labels and the trajectory move between the
# clocks through the feeder's events (when each write() began and returned), not its schedule:
# a VM that falls behind is not scored as a wrong pose (docs/testbench.md).
if [ "$LOOP" = 1 ]; then
  T4=$(date +%s.%N)
  L=$WORK/loop
  mkdir -p "$L/in/run"
  cp -r "$E2E/train/." "$L/in/run/"
  # loop_boot MODE: the tar of $L/in on the disk in, the tar the VM wrote back unpacked in $L/MODE.
  loop_boot() {
    local mode=$1 img=$L/$1.img
    (cd "$L/in" && tar -cf "$img" .)
    truncate -s 512M "$img"
    timeout -s KILL "${HARMOLOC_VM_TIMEOUT_S:-900}" "$QEMU" -accel tcg -cpu "$LOOP_CPU" -smp 1 -m 1024 -nographic -no-reboot \
      -serial "file:$L/$mode.console.log" -drive "file=$img,format=raw,if=virtio" \
      -kernel "$VMLINUZ" -initrd "$WORK/initramfs.cpio.gz" \
      -append "console=$CONSOLE_DEV quiet loglevel=3 panic=-1 HARMOLOC_VM_MODE=$mode HARMOLOC_VM_SLOWDOWN=$LOOP_K" \
      -monitor none > "$L/$mode.qemu.out" 2>&1 || true
    tr -d '\r' < "$L/$mode.console.log" > "$L/$mode.console.txt"
    rm -rf "$L/$mode"; mkdir -p "$L/$mode"
    tar -xf "$img" -C "$L/$mode" 2> /dev/null || true
    rm -f "$img"
  }
  # Without AVX2: under this QEMU's TCG (7.2) with -cpu max the Linux board's AVX2 segmentation
  # counted other areas than the host's on the same frames (docs/testbench.md).
  LOOP_CPU=${HARMOLOC_VM_LOOP_CPU:-max,-avx2}
  loop_feeder_line() { grep -m1 '^FEEDER start_mono_ns' "$L/$1/out/feeder.out" 2> /dev/null || true; }
  loop_summary() {
    echo "$(grep -m1 "^VMTEST-END $1" "$L/$1.console.txt" || echo "no VMTEST-END $1") | $(grep -m1 '^FEEDER done' "$L/$1/out/feeder.out" 2> /dev/null || echo 'no feeder summary')"
  }
  say "whole loop, boot 1: the simulated run through v4l2loopback and vcan0 (slowdown $LOOP_K), recorded"
  loop_boot loop-record
  say "loop-record: $(loop_summary loop-record) ($(elapsed "$T4") s so far)"
  REC=$L/loop-record/out/rec
  FEED1=$(loop_feeder_line loop-record)
  LOOP_OK=1
  if [ -z "$FEED1" ] || [ ! -s "$REC/frames.csv" ]; then
    fail "whole loop: no recording came out of the VM ($(loop_summary loop-record)); console in $L/loop-record.console.txt"
    LOOP_OK=0
  else
    if ! python3 tests/vm/loop_clock.py to-vm "$FEED1" "$E2E/train/labels.tum" "$L/labels-vm.tum" \
      --events "$L/loop-record/out/feeder-events.csv" --encoders "$REC/encoders.csv"; then
      fail "whole loop: the labels could not be moved onto the VM's clock (tests/vm/loop_clock.py)"; LOOP_OK=0
    elif "$HOST_BIN/harmoloc-train" --dataset "$REC" --labels "$L/labels-vm.tum" --out "$L/in/map.hmap" > "$L/train.log" 2>&1; then
      say "map trained on the VM's recording: $(grep -c . "$REC/frames.csv") frame lines"
    else
      tail -5 "$L/train.log" >&2; fail "whole loop: harmoloc-train refused the VM's recording"; LOOP_OK=0
    fi
  fi
  if [ "$LOOP_OK" = 1 ]; then
    say "whole loop, boot 2: the same run again, localized with that map"
    loop_boot loop-localize
    say "loop-localize: $(loop_summary loop-localize) ($(elapsed "$T4") s so far)"
    FEED2=$(loop_feeder_line loop-localize)
    "$HOST_BIN/harmoloc" --dataset "$E2E/train" --map "$L/in/map.hmap" --trajectory "$L/host.tum" > "$L/host.log" 2>&1 ||
      { tail -3 "$L/host.log" >&2; fail "whole loop: the host replay failed"; }
    if [ -n "$FEED2" ] && [ -s "$L/loop-localize/out/trajectory.tum" ] && [ -s "$L/host.tum" ]; then
      EVENTS2=$L/loop-localize/out/feeder-events.csv
      python3 tests/vm/loop_clock.py to-sim "$FEED2" "$L/loop-localize/out/trajectory.tum" "$L/vm.tum" \
        --events "$EVENTS2" --truth "$E2E/train/groundtruth.tum" ||
        { fail "whole loop: the VM's trajectory could not be moved onto the dataset's clock"; : > "$L/vm.tum"; }
      python3 tests/vm/loop_check.py "$E2E/train/groundtruth.tum" "$L/host.tum" "$L/vm.tum" \
        "$(loop_summary loop-record)" "$(loop_summary loop-localize)" >&2 ||
        fail "whole loop: the VM's pose is not as good as the host replay's (trajectories in $L)"
      # Negative control: the same VM trajectory read 0.5 s late on the dataset's clock must fail.
      python3 tests/vm/loop_clock.py to-sim "$FEED2" "$L/loop-localize/out/trajectory.tum" "$L/vm-shifted.tum" \
        --events "$EVENTS2" --truth "$E2E/train/groundtruth.tum" --late-s 0.5 2> /dev/null
      if python3 tests/vm/loop_check.py "$E2E/train/groundtruth.tum" "$L/host.tum" "$L/vm-shifted.tum" > "$L/check-shifted.txt" 2>&1; then
        fail "whole loop: a VM trajectory 0.5 s off passed the check: $(tail -1 "$L/check-shifted.txt")"
      else
        say "negative control (the VM's trajectory 0.5 s off) fails as it must: $(grep 'RMS' "$L/check-shifted.txt")"
      fi
    else
      fail "whole loop: no trajectory came out of the VM ($(loop_summary loop-localize)); console in $L/loop-localize.console.txt"
    fi
  fi
  say "whole loop: $(elapsed "$T4") s (two boots, training, host replay)"
fi

TOTAL=$(elapsed "$T0")
echo "VM bench ($ARCH): kernel $KVER, VM $VM_S s, whole bench $TOTAL s"
if [ "$FAILED" -gt 0 ]; then
  echo "VM bench ($ARCH): $FAILED check(s) failed" >&2
  exit 1
fi
echo "VM bench ($ARCH): all checks passed"
