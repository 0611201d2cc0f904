#!/usr/bin/env python3
"""Spike rates of `blvd bench budget --csv` frames at cell boundaries and inside cells.

A frame "spikes" when it takes at least 1.5 times the median of the five
frames before it (as in tools/frame_sched.py); "boundary" frames are the first
in a new cell. For each run of the bench (local_lod0, floor, unbudgeted,
budgeted) this prints the boundary and inside spike rates, and the spike rate
k frames after a boundary (k = 0..12, against the five frames before the
boundary), which shows whether a boundary's extra cost moved to a later frame
or went away (docs/decisions/0008 §12). Several CSVs are pooled.

    python3 tools/boundary_spikes.py run1.csv [run2.csv ...]

Standard library only.
"""
import collections
import csv
import statistics
import sys

RUNS = ["local_lod0", "floor", "unbudgeted", "budgeted"]
OFFSETS = 13


def main(paths):
    bnd = collections.Counter()
    bnd_n = collections.Counter()
    ins = collections.Counter()
    ins_n = collections.Counter()
    after = collections.defaultdict(collections.Counter)
    after_n = collections.defaultdict(collections.Counter)
    for path in paths:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        for run in RUNS:
            frames = [r for r in rows if r["run"] == run]
            ms = [float(r["ms"]) for r in frames]
            for i, r in enumerate(frames):
                if i < 5:
                    continue
                base = statistics.median(ms[i - 5:i])
                spike = ms[i] >= 1.5 * base
                if r["boundary"] == "1":
                    bnd[run] += spike
                    bnd_n[run] += 1
                    for k in range(OFFSETS):
                        if i + k < len(ms):
                            after[run][k] += ms[i + k] >= 1.5 * base
                            after_n[run][k] += 1
                else:
                    ins[run] += spike
                    ins_n[run] += 1
    print("| run | boundary frames | boundary spike rate | inside spike rate | "
          + " | ".join(f"+{k}" for k in range(OFFSETS)) + " |")
    print("|---" * (4 + OFFSETS) + "|")
    for run in RUNS:
        if not bnd_n[run]:
            continue
        cells = [f"{after[run][k] / after_n[run][k]:.3f}" if after_n[run][k] else "-" for k in range(OFFSETS)]
        print(f"| {run} | {bnd_n[run]} | {bnd[run] / bnd_n[run]:.3f} | {ins[run] / max(1, ins_n[run]):.3f} | "
              + " | ".join(cells) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
