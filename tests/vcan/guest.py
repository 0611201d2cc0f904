#!/usr/bin/env python3
"""A throwaway Debian qemu guest with a vcan bus, for tests/vcan.

Three steps, each usable on its own (see README.md):

  fetch      apt-get download Debian's linux-image-amd64 (its versioned kernel
             package), busybox-static and can-utils into a cache folder and
             unpack them with dpkg-deb -x. Nothing is installed on the host. The
             kernel is also decompressed to an ELF vmlinux, which qemu boots
             through PVH about 5 s faster than the bzImage under TCG.
  initramfs  a cpio+gzip image: busybox, the can/can-raw/can-dev/vcan modules
             (with their modinfo dependencies, in load order), can-utils, the
             binaries under test with every library ldd lists, input files, and
             guest_init.sh as /init, which brings up vcan0 and runs a scenario.
  boot       qemu-system-x86_64 under TCG (optionally KVM first, with a short
             boot deadline and a fallback to TCG), with a hard timeout. The guest
             sends /out back over its second serial port as base64 of a tar.gz
             between marker lines, so no guest filesystem driver is needed.

Errors raise GuestError with a message naming what failed. qemu is killed on
every exit path, and dies with its parent (PR_SET_PDEATHSIG), so no qemu
outlives a run.
"""
import argparse
import base64
import ctypes
import fcntl
import glob
import gzip
import io
import os
import re
import shutil
import signal
import subprocess
import sys
import tarfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
MODULES = ["can", "can-raw", "can-dev", "vcan"]
CAN_UTILS = ["candump", "canplayer", "cansend"]
BEGIN, END, BOOTED = b"BLVD-RESULTS-BEGIN", b"BLVD-RESULTS-END", b"BLVD-GUEST-BOOTED"


class GuestError(Exception):
    pass


class Unavailable(GuestError):
    """qemu or a Debian package cannot be obtained on this host (the test skips)."""


SKIP = 77  # CTest SKIP_RETURN_CODE of the vcan tests


def unavailable_status(name, err):
    """Prints why test `name` has no guest and returns its exit status: SKIP,
    or 1 under BLVD_VCAN_REQUIRE=1 (CI, where deps.sh installed qemu)."""
    if os.environ.get("BLVD_VCAN_REQUIRE") == "1":
        print("%s: FAIL: %s (BLVD_VCAN_REQUIRE=1)" % (name, err))
        return 1
    print("%s: SKIP: %s" % (name, err))
    return SKIP


def run(cmd, **kw):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, **kw)
    if r.returncode != 0:
        raise GuestError("%s failed (%d): %s" % (" ".join(cmd), r.returncode, r.stdout.decode(errors="replace")[-2000:]))
    return r.stdout.decode(errors="replace")


# ---- fetch -----------------------------------------------------------------

def _download(pkg, into):
    """apt-get download PKG into `into`; returns the .deb path. As root, an
    empty or stale package list (a fresh container) is refreshed once."""
    # Bounded waits: without a network this fails in about a minute instead of hanging.
    cmd = ["apt-get", "-o", "Acquire::Retries=1", "-o", "Acquire::http::Timeout=30", "download", "-q", pkg]
    r = subprocess.run(cmd, cwd=into, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    if r.returncode != 0 and os.geteuid() == 0:
        subprocess.run(["apt-get", "-o", "DPkg::Lock::Timeout=600", "update", "-qq"], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        r = subprocess.run(cmd, cwd=into, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    debs = sorted(glob.glob(os.path.join(into, glob.escape(pkg) + "_*.deb")))
    if r.returncode != 0 or not debs:
        raise Unavailable("apt-get download %s failed: %s" % (pkg, r.stdout.decode(errors="replace").strip()[-800:]))
    return debs[-1]


def _extract_vmlinux(vmlinuz, out):
    """The ELF kernel inside a bzImage (Debian's is XZ-compressed; zstd/gzip handled too)."""
    data = open(vmlinuz, "rb").read()
    for magic, cmd in ((b"\xfd7zXZ\x00", ["xz", "-dc", "--single-stream"]), (b"\x28\xb5\x2f\xfd", ["zstd", "-dcq"]),
                       (b"\x1f\x8b\x08\x00", ["gzip", "-dc"])):
        pos = data.find(magic)
        if not shutil.which(cmd[0]):
            continue
        while pos >= 0:
            r = subprocess.run(cmd, input=data[pos:], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
            if r.stdout[:4] == b"\x7fELF":
                with open(out, "wb") as f:
                    f.write(r.stdout)
                return True
            pos = data.find(magic, pos + 1)
    return False


def _prune_modules(root):
    """Keeps only the CAN modules of the unpacked kernel (400 MB -> 1 MB)."""
    for p in glob.glob(os.path.join(root, "lib", "modules", "*", "kernel", "**", "*.ko*"), recursive=True):
        if "/can/" not in p:
            os.remove(p)


def fetch(cache):
    """Fills `cache` once; later calls return at once. Returns a dict of paths."""
    os.makedirs(cache, exist_ok=True)
    stamp = os.path.join(cache, "ready")
    with open(os.path.join(cache, ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # two tests may fetch at once
        if not os.path.exists(stamp):
            if not shutil.which("apt-get") or not shutil.which("dpkg-deb"):
                raise Unavailable("apt-get/dpkg-deb not found: the guest kernel comes from Debian's archive")
            debs = os.path.join(cache, "debs")
            root = os.path.join(cache, "root")
            shutil.rmtree(debs, ignore_errors=True)
            shutil.rmtree(root, ignore_errors=True)
            os.makedirs(debs)
            meta = _download("linux-image-amd64", debs)
            dep = run(["dpkg-deb", "-f", meta, "Depends"]).strip()
            m = re.match(r"(linux-image-[0-9][^ ,(]*)", dep)
            if not m:
                raise GuestError("linux-image-amd64 depends on %r, not a versioned linux-image package" % dep)
            for pkg in (m.group(1), "busybox-static", "can-utils"):
                run(["dpkg-deb", "-x", _download(pkg, debs), root])
            shutil.rmtree(debs)  # 70 MB we no longer need
            _prune_modules(root)
            vmlinuz = sorted(glob.glob(os.path.join(root, "boot", "vmlinuz-*")))
            if not vmlinuz:
                raise GuestError("no /boot/vmlinuz-* in %s" % m.group(1))
            kver = os.path.basename(vmlinuz[-1])[len("vmlinuz-"):]
            vmlinux = os.path.join(cache, "vmlinux")
            if not _extract_vmlinux(vmlinuz[-1], vmlinux) and os.path.exists(vmlinux):
                os.remove(vmlinux)
            with open(stamp, "w") as f:
                f.write(kver + "\n")
    kver = open(stamp).read().strip()
    root = os.path.join(cache, "root")
    vmlinux = os.path.join(cache, "vmlinux")
    return {
        "kver": kver,
        "root": root,
        "vmlinuz": os.path.join(root, "boot", "vmlinuz-" + kver),
        "vmlinux": vmlinux if os.path.exists(vmlinux) else None,
        "modules": os.path.join(root, "lib", "modules", kver),
        "busybox": os.path.join(root, "bin", "busybox"),
        "can_utils": os.path.join(root, "usr", "bin"),
    }


# ---- initramfs ---------------------------------------------------------------

def _module_files(moddir):
    """name -> path of every .ko[.xz|.zst] in a kernel's module tree."""
    out = {}
    for p in glob.glob(os.path.join(moddir, "kernel", "**", "*.ko*"), recursive=True):
        name = re.sub(r"\.ko(\.xz|\.zst|\.gz)?$", "", os.path.basename(p))
        out[name.replace("_", "-")] = p
    return out


def _module_bytes(path):
    if path.endswith(".xz"):
        return subprocess.run(["xz", "-dc", path], check=True, stdout=subprocess.PIPE).stdout
    if path.endswith(".zst"):
        return subprocess.run(["zstd", "-dcq", path], check=True, stdout=subprocess.PIPE).stdout
    if path.endswith(".gz"):
        return subprocess.run(["gzip", "-dc", path], check=True, stdout=subprocess.PIPE).stdout
    return open(path, "rb").read()


def _depends(ko):
    """The modinfo `depends=` list of a module's bytes."""
    for field in ko.split(b"\0"):
        if field.startswith(b"depends="):
            return [d.replace("_", "-") for d in field[8:].decode().split(",") if d]
    return []


def _load_order(names, files):
    """Modules and their dependencies, dependencies first: [(name, bytes)]."""
    order, seen = [], set()

    def visit(n):
        if n in seen:
            return
        seen.add(n)
        if n not in files:
            raise GuestError("kernel module %s not found in the kernel package" % n)
        data = _module_bytes(files[n])
        for d in _depends(data):
            visit(d)
        order.append((n, data))

    for n in names:
        visit(n)
    return order


def _ldd(binary):
    """Absolute paths of the shared libraries (and loader) `binary` needs."""
    out = run(["ldd", binary])
    if "not a dynamic executable" in out or "statically linked" in out:
        return []
    libs = []
    for line in out.splitlines():
        m = re.search(r"=>\s*(/\S+)", line) or re.match(r"\s*(/\S+)", line)
        if m:
            libs.append(m.group(1))
        elif "not found" in line:
            raise GuestError("ldd %s: %s" % (binary, line.strip()))
    return libs


def _write_cpio(stage, f):
    """The tree under `stage` as a newc (SVR4, no CRC) cpio archive, root-owned,
    entries sorted so the image is reproducible (no cpio binary needed)."""
    def entry(name, mode, data, ino):
        hdr = "070701" + "".join("%08X" % v for v in (ino, mode, 0, 0, 1, 0, len(data), 0, 0, 0, 0, len(name) + 1, 0))
        f.write(hdr.encode() + name.encode() + b"\0")
        f.write(b"\0" * (-(110 + len(name) + 1) % 4))
        f.write(data)
        f.write(b"\0" * (-len(data) % 4))

    ino = 1
    for dirpath, dirnames, filenames in sorted(os.walk(stage)):
        dirnames.sort()
        rel = os.path.relpath(dirpath, stage)
        if rel != ".":
            entry(rel, 0o040755, b"", ino)
            ino += 1
        for fn in sorted(filenames):
            p = os.path.join(dirpath, fn)
            name = os.path.normpath(os.path.join(rel, fn))
            with open(p, "rb") as src:
                entry(name, 0o100000 | (os.stat(p).st_mode & 0o7777), src.read(), ino)
            ino += 1
    entry("TRAILER!!!", 0, b"", 0)


def initramfs(guest, out, binaries, files, scenario, env):
    """Writes the initramfs `out`.

    binaries: host paths copied to /bin (with their ldd libraries);
    files: {guest path: host path}; scenario: host path of the scenario script,
    run by /init as /scenario.sh with `env` ({name: value}) in /scenario.env."""
    stage = out + ".d"
    shutil.rmtree(stage, ignore_errors=True)
    for d in ("bin", "dev", "proc", "sys", "tmp", "out", "in", "lib/modules"):
        os.makedirs(os.path.join(stage, d))

    def put(src, dst, mode=None):
        dst = os.path.join(stage, dst.lstrip("/"))
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        shutil.copyfile(src, dst)  # follows symlinks
        if mode is not None:
            os.chmod(dst, mode)

    put(guest["busybox"], "/bin/busybox", 0o755)
    put(os.path.join(HERE, "guest_init.sh"), "/init", 0o755)
    put(scenario, "/scenario.sh", 0o755)
    with open(os.path.join(stage, "scenario.env"), "w") as f:
        for k, v in env.items():
            f.write("%s='%s'\n" % (k, str(v).replace("'", "'\\''")))
    mods = _load_order(MODULES, _module_files(guest["modules"]))
    with open(os.path.join(stage, "modules.order"), "w") as f:
        for name, data in mods:
            with open(os.path.join(stage, "lib/modules", name + ".ko"), "wb") as m:
                m.write(data)
            f.write(name + ".ko\n")
    libs = set()
    bins = [os.path.join(guest["can_utils"], b) for b in CAN_UTILS] + list(binaries)
    for b in bins:
        if not os.path.isfile(b):
            raise GuestError("binary for the guest not found: %s" % b)
        put(b, "/bin/" + os.path.basename(b), 0o755)
        libs.update(_ldd(b))
    for lib in sorted(libs):
        put(lib, lib, 0o755)
        # A library from the build tree (libblvd) is also put in /lib, where
        # the loader looks when the binary's RUNPATH does not exist: the guest
        # mounts a tmpfs over /tmp, which hides a build tree under /tmp.
        if not lib.startswith(("/lib", "/usr/")):
            put(lib, "/lib/" + os.path.basename(lib), 0o755)
    for dst, src in files.items():
        if not os.path.isfile(src):
            raise GuestError("input file for the guest not found: %s" % src)
        put(src, dst)
    # gzip -1: the guest's decompression runs under TCG.
    with gzip.open(out, "wb", compresslevel=1) as f:
        _write_cpio(stage, f)
    shutil.rmtree(stage)
    return out


# ---- boot --------------------------------------------------------------------

def require_qemu():
    """Unavailable unless qemu-system-x86_64 is on PATH (checked before any download)."""
    if not shutil.which("qemu-system-x86_64"):
        raise Unavailable("qemu-system-x86_64 not found (Debian: apt-get install qemu-system-x86; see packaging/scripts/deps.sh)")


def _qemu_cmd(kernel, initrd, accel, console, results, mem_mb, smp):
    return ["qemu-system-x86_64", "-accel", accel, "-cpu", "max" if accel == "tcg" else "host",
            "-m", str(mem_mb), "-smp", str(smp), "-nodefaults", "-no-user-config", "-display", "none",
            "-no-reboot", "-monitor", "none", "-kernel", kernel, "-initrd", initrd,
            "-append", "console=ttyS0 panic=-1 loglevel=4 no_timer_check tsc=reliable rdinit=/init",
            "-serial", "file:" + console, "-serial", "file:" + results]


def _read(path):
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return b""


def _die_with_parent():
    """In the qemu child: SIGKILL when the test process dies, however it dies
    (a CTest timeout kills the driver without letting it clean up)."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def _boot_once(cmd, console, results, timeout_s, boot_deadline_s):
    """Runs qemu until it exits. Returns (state, seconds): state is 'ok',
    'timeout' or 'noboot' (no BOOTED marker within boot_deadline_s)."""
    for p in (console, results):
        if os.path.exists(p):
            os.remove(p)
    t0 = time.monotonic()
    qemu_log = open(os.path.join(os.path.dirname(console), "qemu.log"), "wb")  # a file: a pipe could fill and block qemu
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=qemu_log, stderr=subprocess.STDOUT,
                            preexec_fn=_die_with_parent)
    try:
        while True:
            try:
                proc.wait(timeout=0.2)
                break
            except subprocess.TimeoutExpired:
                pass
            el = time.monotonic() - t0
            if el > timeout_s:
                return "timeout", el
            if boot_deadline_s and el > boot_deadline_s and BOOTED not in _read(results):
                return "noboot", el
        if proc.returncode != 0:
            raise GuestError("qemu exited with %d: %s" % (proc.returncode, _read(qemu_log.name).decode(errors="replace")[-2000:]))
        return "ok", time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        qemu_log.close()


def boot(guest, initrd, out_dir, timeout_s=240, accel="tcg", mem_mb=768, smp=2, kvm_boot_deadline_s=20):
    """Boots the guest, waits for it to power off and unpacks its /out into
    out_dir. Returns {"accel", "boot_s", "console"}. accel: tcg, kvm or auto
    (KVM if /dev/kvm opens and the guest reaches /init in time, else TCG)."""
    require_qemu()
    os.makedirs(out_dir, exist_ok=True)
    kernel = guest["vmlinux"] or guest["vmlinuz"]
    console = os.path.join(out_dir, "console.log")
    results = os.path.join(out_dir, "serial1.txt")
    tries = []
    if accel in ("kvm", "auto") and os.access("/dev/kvm", os.R_OK | os.W_OK):
        tries.append(("kvm", kvm_boot_deadline_s))
    if accel in ("tcg", "auto") or not tries:
        tries.append(("tcg", 0))
    state, secs, used = None, 0, None
    for a, deadline in tries:
        used = a
        try:
            state, secs = _boot_once(_qemu_cmd(kernel, initrd, a, console, results, mem_mb, smp), console, results,
                                     timeout_s, deadline)
        except GuestError as e:  # KVM on a host that only pretends to have it: qemu aborts
            if a == "tcg":
                raise
            sys.stderr.write("guest: %s failed (%s); falling back to TCG\n" % (a, str(e).splitlines()[0][:200]))
            continue
        if state == "ok" or a == "tcg":
            break
        sys.stderr.write("guest: %s did not boot within %ds; falling back to TCG\n" % (a, deadline))
    tail = _read(console).decode(errors="replace")[-3000:]
    if state != "ok":
        raise GuestError("qemu (%s) ran past its %d s timeout and was killed; console tail:\n%s" % (used, timeout_s, tail))
    data = _read(results)
    b, e = data.find(BEGIN), data.find(END)
    if b < 0 or e < b:
        raise GuestError("the guest sent no results (markers missing on its second serial port); console tail:\n" + tail)
    payload = base64.b64decode(b"".join(data[b + len(BEGIN):e].split()))
    with tarfile.open(fileobj=io.BytesIO(payload), mode="r:gz") as t:
        for m in t.getmembers():
            if not (m.isfile() or m.isdir()) or m.name.startswith("/") or ".." in m.name.split("/"):
                raise GuestError("unexpected entry in the guest's results: %s" % m.name)
        if hasattr(tarfile, "data_filter"):  # Python >= 3.11.4 / 3.12
            t.extractall(out_dir, filter="data")
        else:
            t.extractall(out_dir)
    return {"accel": used, "boot_s": secs, "console": console}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("command", choices=["fetch"])
    ap.add_argument("--cache", required=True)
    a = ap.parse_args()
    try:
        g = fetch(a.cache)
    except GuestError as e:
        sys.exit("guest: %s" % e)
    for k, v in g.items():
        print("%s=%s" % (k, v))


if __name__ == "__main__":
    main()
