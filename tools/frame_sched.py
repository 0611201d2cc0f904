#!/usr/bin/env python3
"""Which threads held the CPUs during each frame of `blvd bench budget`.

Lines up the frames of `blvd bench budget --csv` (column start_mono_s,
CLOCK_MONOTONIC) with the scheduler trace of the same run, recorded with
`perf sched record -k mono`, and prints, per class of frame, the mean CPU
milliseconds each thread kind ran inside the frames of that class
(docs/decisions/0008 §9):

    perf sched record -k mono -o /tmp/ps.data -- \\
        build/sdk/cli/blvd bench budget PKG --route auto:24 --csv /tmp/b.csv
    perf sched timehist -i /tmp/ps.data > /tmp/th.txt
    python3 tools/frame_sched.py /tmp/b.csv /tmp/th.txt

A frame "spikes" when it takes at least 1.5 times the median of the five
frames before it; "boundary" frames are the first in a new cell. Standard
library only.
"""
import bisect
import collections
import csv
import re
import statistics
import sys

LINE = re.compile(r"^\s*([\d.]+)\s+\[(\d+)\]\s+(.*?)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s*$")
NAME = re.compile(r"(.*)\[(\d+)(?:/(\d+))?\]$")
KINDS = ["main", "llvmpipe", "blvd-loader", "blvd-prefetch", "<idle>", "other"]


def kind(comm, pid):
    if comm == "blvd" and pid is None:
        return "main"  # the process's first thread (perf prints no /pid for it)
    if comm.startswith("llvmpipe"):
        return "llvmpipe"
    if comm in ("blvd-loader", "blvd-prefetch", "<idle>"):
        return comm
    return "other"


def read_sched(path):
    runs = collections.defaultdict(list)  # kind -> [(start, end)] in seconds
    delay = collections.defaultdict(list)  # kind -> [(runnable, ran)]: waited for a CPU
    for line in open(path):
        m = LINE.match(line)
        if not m:
            continue
        end, name = float(m.group(1)), m.group(3)
        sch_delay, ran = float(m.group(5)) / 1000, float(m.group(6)) / 1000
        if name == "<idle>":
            comm, pid = name, "0"
        else:
            n = NAME.match(name)
            if not n:
                continue
            comm, pid = n.group(1), n.group(3)
        k = kind(comm, pid)
        runs[k].append((end - ran, end))
        if sch_delay > 0:
            delay[k].append((end - ran - sch_delay, end - ran))
    for table in (runs, delay):
        for v in table.values():
            v.sort()
    return runs, delay


def overlap_ms(intervals, starts, a, b):
    i = max(0, bisect.bisect_left(starts, a) - 64)  # an interval may start before a
    total = 0.0
    for x, y in intervals[i:bisect.bisect_right(starts, b)]:
        total += max(0.0, min(y, b) - max(x, a))
    return total * 1000


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    frames = list(csv.DictReader(open(sys.argv[1])))
    if not frames or "start_mono_s" not in frames[0]:
        sys.exit(sys.argv[1] + ": no start_mono_s column (a CSV of blvd bench budget --csv)")
    runs, delay = read_sched(sys.argv[2])
    cols = [("ran", k, runs) for k in KINDS] + [("waited", k, delay) for k in ("main", "llvmpipe")]
    starts = {(t, k): [a for a, _ in table.get(k, [])] for t, k, table in cols}
    classes = collections.defaultdict(list)
    for run in sorted({f["run"] for f in frames}):
        fr = [f for f in frames if f["run"] == run]
        ms = [float(f["ms"]) for f in fr]
        for i in range(5, len(fr)):
            spike = ms[i] >= 1.5 * statistics.median(ms[i - 5:i])
            a = float(fr[i]["start_mono_s"])
            b = a + ms[i] / 1000
            row = [ms[i]] + [overlap_ms(table.get(k, []), starts[(t, k)], a, b) for t, k, table in cols]
            cls = ("boundary" if fr[i]["boundary"] == "1" else "inside") + (" spike" if spike else "")
            classes[cls].append(row)
    head = ["frames", "frame ms"] + ["%s %s" % (t, k) for t, k, _ in cols]
    print("| class | " + " | ".join(head) + " |")
    print("|---" * (len(head) + 1) + "|")
    for cls in sorted(classes):
        rows = classes[cls]
        means = [sum(c) / len(rows) for c in zip(*rows)]
        print("| %s | %d | " % (cls, len(rows)) + " | ".join("%.2f" % m for m in means) + " |")


if __name__ == "__main__":
    main()
