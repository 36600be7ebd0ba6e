#!/bin/sh
# /init of the test VM (busybox): loads the virtual devices, runs the drivers' tests and then the
# Linux board's harmoloc for its end-to-end run, prints what the host checks, and powers off.
# Lines starting with "VM" are read by tests/vm/run_vm_tests.sh from the console.
export PATH=/bin:/sbin:/usr/bin:/usr/sbin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mkdir -p /dev/pts /dev/shm /tmp /run
mount -t tmpfs tmp /tmp
mount -t tmpfs shm /dev/shm
mount -t configfs configfs /sys/kernel/config 2> /dev/null
say() { echo "VM: $*"; }
finish() {
  echo "VMDONE"
  sync
  poweroff -f
  sleep 5
}
trap finish EXIT

# The whole loop (HARMOLOC_VM_MODE=loop-record or loop-localize on the kernel command line; a boot
# of its own, started twice by run_vm_tests.sh): a simulated run played by vm_feeder into
# v4l2loopback (/dev/video20) and onto vcan0, the Linux board's harmoloc on those devices. The
# disk /dev/vda brings a tar in (the dataset, and the map when localizing) and takes one out
# (/tmp/out: the recording or the trajectory, the stats, the feeder's lines).
if [ "${HARMOLOC_VM_MODE:-}" = loop-record ] || [ "${HARMOLOC_VM_MODE:-}" = loop-localize ]; then
  for m in vcan can-raw virtio_pci virtio_blk; do modprobe "$m" || say "modprobe $m failed"; done
  modprobe v4l2loopback exclusive_caps=1 video_nr=20 card_label=harmoloc-loop || say "modprobe v4l2loopback failed"
  ip link add dev vcan0 type vcan && ip link set up vcan0 || say "vcan0 could not be set up"
  for _ in $(seq 50); do [ -b /dev/vda ] && break; sleep 0.1; done
  mkdir -p /tmp/in /tmp/out
  tar -xf /dev/vda -C /tmp/in || say "no input tar on /dev/vda"
  K=${HARMOLOC_VM_SLOWDOWN:-1}
  say "loop: $(ls /tmp/in | tr '\n' ' ') slowdown $K, devices $(ls /dev/video* 2> /dev/null | tr '\n' ' ')"
  echo "VMTEST-BEGIN $HARMOLOC_VM_MODE"
  /vm/vm_feeder /tmp/in/run /dev/video20 vcan0 "$K" /tmp/go /tmp/out/feeder-events.csv > /tmp/out/feeder.out 2>&1 &
  feeder=$!
  for _ in $(seq 300); do grep -q 'FEEDER ready' /tmp/out/feeder.out && break; sleep 0.1; done
  /vm/notify_listener /tmp/notify 900 > /tmp/notify.log &
  listener=$!
  if [ "$HARMOLOC_VM_MODE" = loop-record ]; then
    out="--record /tmp/out/rec"
  else
    out="--map /tmp/in/map.hmap --trajectory /tmp/out/trajectory.tum"
  fi
  T_START=$(cut -d' ' -f1 /proc/uptime)
  # shellcheck disable=SC2086
  NOTIFY_SOCKET=/tmp/notify /vm/harmoloc --config /vm/e2e/loop.toml $out --link /dev/null \
    --stats /tmp/out/stats.json > /tmp/out/harmoloc.out 2> /tmp/out/harmoloc.err &
  firmware=$!
  for _ in $(seq 600); do grep -q 'READY=1' /tmp/notify.log 2> /dev/null && break; sleep 0.1; done
  touch /tmp/go
  wait "$feeder"
  echo "feeder rc=$?" >> /tmp/out/feeder.out
  sleep 1
  kill -TERM "$firmware"
  wait "$firmware"
  rc=$?
  kill "$listener" 2> /dev/null
  cat /tmp/out/feeder.out /tmp/out/harmoloc.err
  echo "VMTEST-END $HARMOLOC_VM_MODE rc=$rc seconds=$(echo "$(cut -d' ' -f1 /proc/uptime) $T_START" | awk '{print $1 - $2}')"
  tar -cf /dev/vda -C /tmp out && sync
  say "uptime $(cut -d' ' -f1 /proc/uptime) s at the end"
  exit 0
fi

for m in configfs vivid vcan can-raw gpio-sim vimc $(echo "${HARMOLOC_VM_MODULES:-}" | tr , ' '); do
  modprobe "$m" || say "modprobe $m failed"
done
mount -t configfs configfs /sys/kernel/config 2> /dev/null
ip link add dev vcan0 type vcan && ip link set up vcan0 || say "vcan0 could not be set up"

# A gpio-sim chip with 8 lines; its name is read back, never assumed.
G=/sys/kernel/config/gpio-sim/chip0
if mkdir "$G" && mkdir "$G/bank0" && echo 8 > "$G/bank0/num_lines" && echo 1 > "$G/live"; then
  HARMOLOC_VM_GPIO_CHIP=$(cat "$G/bank0/chip_name")
  HARMOLOC_VM_GPIO_SYSFS=/sys/devices/platform/$(cat "$G/dev_name")/$HARMOLOC_VM_GPIO_CHIP
  export HARMOLOC_VM_GPIO_CHIP HARMOLOC_VM_GPIO_SYSFS
  say "gpio-sim chip $HARMOLOC_VM_GPIO_CHIP at $HARMOLOC_VM_GPIO_SYSFS"
else
  say "gpio-sim chip could not be created"
fi
export HARMOLOC_VM_CAN_LOG=/vm/can_encoders.log
say "devices: $(ls /dev/video* 2> /dev/null | tr '\n' ' ') $(ip link show vcan0 2> /dev/null | head -1)"
say "uptime $(cut -d' ' -f1 /proc/uptime) s before the tests"

echo "VMTEST-BEGIN drivers"
/vm/vm_drivers_test --gtest_color=no
echo "VMTEST-END drivers rc=$?"

# libcamera (Debian 0.0.3, its vimc pipeline handler and IPA) on vimc.
# libcamera finds cameras through libudev, which lists only devices udev has initialised; with
# no udev daemon here, mark the media and video devices initialised in udev's database.
mkdir -p /run/udev/data
for d in /sys/bus/media/devices/* /sys/class/video4linux/*; do
  [ -f "$d/dev" ] && printf 'I:1\n' > "/run/udev/data/c$(cat "$d/dev")"
done
echo "VMTEST-BEGIN libcamera"
LIBCAMERA_LOG_LEVELS='*:WARN' LIBCAMERA_LOG_FILE=/tmp/libcamera.log /vm/vm_libcamera_test --gtest_color=no
rc=$?
[ "$rc" = 0 ] || grep -E 'ERROR|WARN' /tmp/libcamera.log | head -30 | sed 's/^/libcamera-log: /'
echo "VMTEST-END libcamera rc=$rc"

# End to end: vivid as the camera, the simulated run's encoder log played onto vcan0 (looped),
# the MAVLink stream out on the second serial line (/dev/ttyS1 on x86_64, the virtio console
# /dev/hvc0 on aarch64; read on the host).
echo "VMTEST-BEGIN harmoloc"
canplayer -l i -I /vm/e2e/encoders.log vcan0=can0 &
player=$!
# As the packaged service runs it (Type=notify, WatchdogSec): the notify socket systemd would
# give, its messages printed as NOTIFY lines for the host to check.
/vm/notify_listener /tmp/notify "$((${HARMOLOC_VM_SECONDS:-12} + 20))" > /tmp/notify.log &
listener=$!
sleep 0.2
NOTIFY_SOCKET=/tmp/notify WATCHDOG_USEC=1000000 \
/vm/harmoloc --config /vm/e2e/harmoloc.toml --map /vm/e2e/map.hmap --duration "${HARMOLOC_VM_SECONDS:-12}" \
  --stats /tmp/stats.json --trajectory /tmp/trajectory.tum &
firmware=$!
# Stats on request while it runs (SIGUSR1, as `systemctl kill -s USR1 harmoloc` sends it): once
# start-up is over (READY=1 to the notify socket) and a second has run, the file must appear
# without the run stopping.
for _ in $(seq 200); do grep -q 'READY=1' /tmp/notify.log 2> /dev/null && break; sleep 0.1; done
sleep 1
kill -USR1 "$firmware"
for _ in $(seq 50); do [ -s /tmp/stats.json ] && break; sleep 0.1; done
cp /tmp/stats.json /tmp/stats_on_request.json 2> /dev/null
wait "$firmware"
rc=$?
kill "$player" 2> /dev/null
sleep 0.3
kill "$listener" 2> /dev/null
cat /tmp/notify.log
echo "VMTEST-END harmoloc rc=$rc"
echo "VMSTATS-BEGIN"
cat /tmp/stats.json
echo "VMSTATS-END"
echo "VMSTATS-REQUEST-BEGIN"
cat /tmp/stats_on_request.json 2> /dev/null
echo "VMSTATS-REQUEST-END"
echo "VM: trajectory lines $(wc -l < /tmp/trajectory.tum)"
# Recording a training run on the robot (no map): vivid's frames and vcan0's counters into a
# dataset folder, the cycle never waiting for the disk. The host checks what it says.
canplayer -l i -I /vm/e2e/encoders.log vcan0=can0 &
player=$!
/vm/harmoloc --config /vm/e2e/harmoloc.toml --link /dev/null --record /tmp/rec --duration 6 \
  > /tmp/rec.out 2> /tmp/rec.err
rc=$?
kill "$player" 2> /dev/null
echo "VMTEST-END record rc=$rc frames=$(($(wc -l < /tmp/rec/frames.csv) - 1)) files=$(ls /tmp/rec/frames | wc -l)" \
  "encoders=$(($(wc -l < /tmp/rec/encoders.csv) - 1)) areas=$(($(wc -l < /tmp/rec/areas.csv) - 3))" \
  "format=$(sed -n 's/^pixel_format = "\(.*\)"/\1/p' /tmp/rec/metadata.toml) $(grep -m1 'recorded' /tmp/rec.err || tail -1 /tmp/rec.err)"
rm -rf /tmp/rec
# A missing device must stop start-up with exit status 2 and one line.
/vm/harmoloc --config /vm/e2e/bad_camera.toml --map /vm/e2e/map.hmap --link /dev/null > /tmp/out 2> /tmp/err
echo "VMTEST-END bad_camera rc=$? lines=$(wc -l < /tmp/err) $(cat /tmp/err)"
say "uptime $(cut -d' ' -f1 /proc/uptime) s at the end"
