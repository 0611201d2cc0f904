#!/bin/busybox sh
# /init of the tests/vcan guest (guest.py builds the initramfs around it):
# mounts the pseudo filesystems, loads the CAN modules listed in /modules.order,
# brings up vcan0, runs /scenario.sh with /scenario.env (killed after
# SCENARIO_TIMEOUT seconds), and sends /out back
# over the second serial port (ttyS1) as base64 of a tar.gz between marker
# lines, then powers off. Any failure still sends what /out holds, plus
# /out/init.log saying what failed.
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
stty -F /dev/ttyS1 raw -echo 2>/dev/null
echo BLVD-GUEST-BOOTED > /dev/ttyS1

log() { echo "init: $*" | tee -a /out/init.log; }

send_results() {
  {
    echo BLVD-RESULTS-BEGIN
    tar -C /out -cf - . | gzip -1 | base64
    echo BLVD-RESULTS-END
  } > /dev/ttyS1
  sync
  poweroff -f
}

setup() {
  while read -r m; do
    insmod "/lib/modules/$m" || { log "insmod $m failed"; return 1; }
  done < /modules.order
  ip link add dev vcan0 type vcan || { log "ip link add vcan0 type vcan failed"; return 1; }
  ip link set up vcan0 || { log "ip link set up vcan0 failed"; return 1; }
  log "vcan0 up; kernel $(uname -r); uptime $(cut -d' ' -f1 /proc/uptime) s"
}

if setup; then
  set -a
  . /scenario.env
  set +a
  # A hung scenario still sends its logs back: the host's own timeout is the last resort.
  timeout -s KILL "${SCENARIO_TIMEOUT:-600}" sh /scenario.sh > /out/scenario.log 2>&1
  echo $? > /out/scenario.rc
  log "scenario exited with $(cat /out/scenario.rc); uptime $(cut -d' ' -f1 /proc/uptime) s"
else
  echo 125 > /out/scenario.rc
fi
send_results
