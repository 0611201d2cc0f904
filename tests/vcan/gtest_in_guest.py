#!/usr/bin/env python3
"""Runs a GoogleTest binary inside the tests/vcan guest, where AF_CAN and vcan0
exist, and asserts that the selected tests ran there (none skipped) and passed.

This is how the SocketCAN adapter's tests that need a CAN-capable kernel
(tests/adapters/can: a vcan0 loopback with filters, an unknown interface) run
on a host whose kernel has no AF_CAN. Exit status: 0 pass, 1 fail, 77 skip
(no qemu / no Debian packages; BLVD_VCAN_REQUIRE=1 makes that a failure).
"""
import argparse
import json
import os
import shutil
import signal
import sys

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import guest  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--name", required=True)
    ap.add_argument("--cache", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--gtest", required=True, help="the GoogleTest binary")
    ap.add_argument("--filter", required=True, help="--gtest_filter pattern")
    ap.add_argument("--must-run", nargs="+", default=[], help="Suite.Test names that must run and pass, not skip")
    ap.add_argument("--timeout-s", type=float, default=120)
    ap.add_argument("--accel", default=os.environ.get("BLVD_VCAN_ACCEL", "tcg"), choices=["tcg", "kvm", "auto"])
    a = ap.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    out = os.path.join(a.work, "out")
    try:
        guest.require_qemu()
        g = guest.fetch(a.cache)
        env = {"GTEST": "/bin/" + os.path.basename(a.gtest), "GTEST_FILTER": a.filter,
               "SCENARIO_TIMEOUT": int(max(10, a.timeout_s - 40))}
        initrd = guest.initramfs(g, os.path.join(a.work, "initrd.gz"), [a.gtest], {},
                                 os.path.join(guest.HERE, "scenario_gtest.sh"), env)
        vm = guest.boot(g, initrd, out, timeout_s=a.timeout_s, accel=a.accel)
    except guest.Unavailable as e:
        return guest.unavailable_status(a.name, e)
    except (guest.GuestError, OSError) as e:
        print("%s: FAIL: %s" % (a.name, e))
        return 1

    log = os.path.join(out, "gtest.log")
    if os.path.exists(log):
        sys.stdout.write(open(log, errors="replace").read()[-6000:])
    try:
        report = json.load(open(os.path.join(out, "gtest.json")))
    except (OSError, ValueError) as e:
        sys.stdout.write(open(os.path.join(out, "console.log"), errors="replace").read()[-3000:])
        print("%s: FAIL: no GoogleTest report from the guest (%s)" % (a.name, e))
        return 1
    ran, problems = {}, []
    for suite in report.get("testsuites", []):
        for t in suite.get("testsuite", []):
            name = "%s.%s" % (suite["name"], t["name"])
            skipped = t.get("result") == "SKIPPED" or t.get("status") == "NOTRUN"
            ran[name] = "skipped" if skipped else ("failed" if t.get("failures") else "passed")
            if t.get("failures"):
                problems.append("%s failed: %s" % (name, t["failures"][0].get("failure", "")[:300]))
    for name in a.must_run:
        if ran.get(name) != "passed":
            problems.append("%s %s in the guest" % (name, ran.get(name, "did not run")))
    if not ran:
        problems.append("no test matched --gtest_filter=%s" % a.filter)
    summary = {"test": a.name, "kernel": g["kver"], "accel": vm["accel"], "vm_s": vm["boot_s"], "results": ran}
    if problems:
        print("%s: FAIL: %s\n%s" % (a.name, "; ".join(problems), json.dumps(summary)))
        return 1
    print("%s: PASS %s" % (a.name, json.dumps(summary)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
