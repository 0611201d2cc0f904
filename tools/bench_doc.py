#!/usr/bin/env python3
"""Rewrites the measured tables of docs/benchmarks.md from the benches' JSON.

    tools/bench_doc.py OUT_DIR docs/benchmarks.md [NAME ...]

OUT_DIR is what packaging/scripts/bench.sh writes: NAME.json per benchmark and
commands.tsv (NAME <tab> the command that produced it). Each table sits
between `<!-- bench:NAME -->` and `<!-- /bench:NAME -->` in the document and
is replaced whole, with the command under it; the prose around the markers is
kept. A marker whose JSON is missing is an error: a table is never left stale
beside fresh ones. With NAMEs, only those tables are rewritten (a partial
re-measurement; the rest stay as they were).
"""
import json
import os
import re
import sys


def pct(x, digits=1):
    return "–" if x is None else f"{100 * x:.{digits}f} %"


def num(x, digits=2):
    if x is None:
        return "–"
    if isinstance(x, (int,)) or (isinstance(x, float) and digits == 0):
        return f"{x:,.0f}"
    return f"{x:.{digits}f}"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def route(j):
    rows = []
    order = ["full", "local", "radius100", "radius250", "single", "blvd"]
    for mode in sorted(j["modes"], key=lambda m: order.index(m) if m in order else len(order)):
        g = j["modes"][mode].get
        rows.append([mode, num(g("frame_ms_p50")), num(g("frame_ms_p95")), num(g("triangles_p50"), 0),
                     num(g("ssim_p50"), 3), pct(g("bad_pixels_p50"), 2), pct(g("far_bad_p50")),
                     pct(g("far_bad_p95")), pct(g("holes_p95"), 2), pct(g("spurious_p95"), 3),
                     num(g("missing_objects_poses"), 0), num(g("visibility_error_px_p95"), 1),
                     num(g("silhouette_distance_px_p95"), 1)])
    t = table(["mode", "frame ms p50", "p95", "triangles p50", "SSIM p50", "bad px p50", "far_bad p50", "p95",
               "holes p95", "spurious p95", "missing-object poses", "visibility error px p95",
               "silhouette distance px p95"], rows)
    return t + f"\n\nSpeed-up full ÷ blvd (median frame time): {num(j.get('speedup_p50'))}×, " \
               f"triangles ÷ {num(1 / j['triangle_ratio_p50'], 1) if j.get('triangle_ratio_p50') else '–'}; " \
               f"{len(j.get('blvd_poses', []))} poses, {j.get('far_scored_poses', '–')} scored for the far metrics, " \
               f"on {j.get('gl_renderer', '?')}."


def budget(j):
    target = j["target_ms"]
    rows = [["target (auto)", num(target), "–", "–", "–", "–"],
             ["local model at LOD 0", num(j["local_lod0_ms_p50"]), "–", "–", "–", "–"],
             ["unbudgeted", num(j["unbudgeted_ms_p50"]), "–", "–", "–", "–"],
             ["floor (coarsest, smallest scale)", num(j["floor_ms_p50"]), num(j["floor_ms_p95"]), "–", "–", "–"],
             ["budgeted", num(j["frame_ms_p50"]), num(j["frame_ms_p95"]),
              f"{100 * (j['frame_ms_p50'] / target - 1):+.1f} % / {j['frame_ms_p95'] / target:.2f}×",
              f"{num(j['stutter_ratio'])} (ci90 {num(j['stutter_ratio_ci90'][0])}–{num(j['stutter_ratio_ci90'][1])})",
              f"{num(j['render_scale_p50'])}, SSIM cost {num(j['ssim_cost_p50'], 3)}"]]
    checks = ", ".join(f"{k} {'met' if v else 'NOT met'}" for k, v in j.get("checks", {}).items())
    return table(["run", "frame ms p50", "p95", "p50 ÷ target − 1 / p95 ÷ target", "stutter", "render scale p50"],
                 rows) + f"\n\nTargets: {checks}. Boundary spike rate {num(j['boundary_spike_rate'], 3)}, inside " \
                         f"{num(j['inside_spike_rate'], 3)}; degraded frames {j['degraded_frames']} of {j['frames']}."


def memory(j):
    rows = [[name, f"{r['rss_peak']:,}", f"{r['table_bytes']:,}", f"{r['tracking_bytes']:,}",
             r["allocs_per_frame_max"], r["driver_allocs_per_frame_max"]] for name, r in j["runs"].items()]
    return table(["package", "peak RSS bytes", "tables bytes", "tracker bytes", "blvd allocations a frame (max)",
                  "GL driver's (max)"], rows) + \
        f"\n\nPeak RSS 4× ÷ 1× − 1: **{j['rss_diff_pct']:+.2f} %** (target ≤ 2 %), {j['route_cells']} cells " \
        f"driven; {'pass' if j['pass'] else 'FAIL'}."


def decode(j):
    def cell(p, k):
        c = p.get("cell_impostors")
        return num(c[k], 2) if c and c.get("meshes") else "–"
    def slot(p, k="memory"):
        m = p.get(k)
        return num(m["slab_bytes"] / 1048576, 1) if m else "–"
    def etc2(p):  # a cell's impostors decoded and encoded as ETC2 atlas levels (decision 0039)
        c = p.get("cell_impostors_etc2")
        return num(c["ms_p50"], 2) if c and c.get("meshes") else "–"
    rows = [[os.path.basename(p["package"]), f"{p['bytes']:,}", num(p["bytes_vs_first"]),
             num(p["blocks"]["ms_total"], 0), num(p["impostors"]["ms_total"], 0), cell(p, "ms_p50"),
             cell(p, "ms_max"), num(p["ms_total"], 0), num(p["ms_total_vs_first"]), slot(p), etc2(p),
             slot(p, "memory_etc2")] for p in j]
    return table(["package", "bytes", "÷ first", "block decode ms", "impostor decode ms",
                  "a cell's impostors ms p50", "max", "total ms", "÷ first", "GPU MiB a cell slot",
                  "ETC2: a cell's impostors ms p50", "ETC2: GPU MiB a cell slot"], rows)


def track(j):
    t = j.get("targets", {})
    def target(k):
        if k not in t:
            return ""
        b = t[k]
        return (f"≥ {b['min']}" if "min" in b else f"≤ {b['max']}") + (" met" if b.get("met") else " **NOT met**")
    keys = ["on_cell_sigma5", "on_cell_sigma15", "on_cell_sigma5_calibrated", "on_cell_sigma15_calibrated",
            "on_cell_sigma5_chained", "on_cell_sigma15_chained", "on_cell_sigma5_resumed",
            "on_cell_sigma15_resumed", "update_us_p50", "fusion_err_m_p50", "dr_drift_pct"]
    rows = [[k, num(j.get(k), 4), target(k)] for k in keys if k in j]
    return table(["figure", "value", "target"], rows)


def scale(j):
    rows = []
    for r in j["runs"]:
        b, f = r["blvd"], r["full"]
        rows.append([f"{r['copies']:.0f}", f"{r['cells']:,}", num(b["frame_ms_p50"]), num(b["frame_ms_p95"]),
                     num(b["triangles_p50"], 0), num(f["frame_ms_p50"]), num(f["frame_ms_p95"]),
                     num(f["triangles_p50"], 0), f"{num(r['speedup_p50'])}×", f"{int(r['rss_peak']):,}",
                     f"{r['gpu_high_water']:,}"])
    t = table(["copies", "cells", "blvd ms p50", "p95", "blvd triangles p50", "full ms p50", "p95",
               "full triangles p50", "speed-up", "peak RSS bytes", "GPU high water bytes"], rows)
    c = j["checks"]
    return t + f"\n\nLargest against the first: blvd frame time p50 {j['blvd_ms_p50_change_pct']:+.1f} % " \
               f"(goal ±5 %: {'met' if c['blvd_ms_within'] else '**not met**'}), full model " \
               f"{j['full_ms_p50_change_pct']:+.1f} %, peak RSS {j['rss_peak_change_pct']:+.2f} % " \
               f"(goal ±1 %: {'met' if c['rss_within'] else '**not met**'})."


RENDER = {"route": route, "budget": budget, "memory": memory, "decode": decode, "track": track, "scale": scale}


def bake(out_dir, name):
    info = json.load(open(os.path.join(out_dir, f"{name}.json")))
    secs = open(os.path.join(out_dir, f"{name}.time")).read().strip()
    c = info["counts"]
    # The bake's own summary (stdout) says what a cell with impostors cost.
    summary = open(os.path.join(out_dir, f"{name}.txt")).read()
    m = re.search(r"per impostor cell ([\d.]+) s \(item buffers ([\d.]+) ms a sample\), ([\d.]+) ms an impostor mesh",
                  summary)
    per_cell = f"{m.group(1)} s ({m.group(2)} ms a sample, {m.group(3)} ms a mesh)" if m else "–"
    k = re.search(r"package per km of street (\d+) bytes \(([\d.]+) km\), per cell (\d+) bytes", summary)
    per_km = f"{int(k.group(1)):,} ({k.group(2)} km)" if k else "–"
    cell_bytes = f"{int(k.group(3)):,}" if k else "–"
    return table(["package", "bake", "bytes", "bytes per km of street", "bytes per cell", "blocks", "cells",
                  "buildings", "triangles (level 0)", "a cell with impostors"],
                 [[os.path.basename(info["file"]), secs, f"{info['bytes']:,}", per_km, cell_bytes, c["blocks"],
                   c["cells"], f"{c['buildings']:,}", f"{c['triangles']:,}", per_cell]])


def command_text(cmd):
    # bench.sh times bakes with /usr/bin/time -f FMT -o FILE: show the blvd command alone.
    return re.sub(r"^/usr/bin/time -f \S+ s -o \S+ ", "", cmd)


def main():
    out_dir, doc, only = sys.argv[1], sys.argv[2], set(sys.argv[3:])
    commands = {}
    for line in open(os.path.join(out_dir, "commands.tsv")):
        name, cmd = line.rstrip("\n").split("\t", 1)
        commands[name] = command_text(cmd)
    text = open(doc).read()

    rewritten = []

    def replace(m):
        name = m.group(1)
        if only and name not in only:
            return m.group(0)
        rewritten.append(name)
        if name not in commands:
            sys.exit(f"bench_doc: {doc}: no run of '{name}' in {out_dir}/commands.tsv")
        if name.startswith("bake."):
            body = bake(out_dir, "bake-" + name.split(".", 1)[1])
        else:  # route, route.sf, ...: the renderer of the part before the dot
            body = RENDER[name.split(".")[0]](json.load(open(os.path.join(out_dir, f"{name}.json"))))
        return f"<!-- bench:{name} -->\n{body}\n\n`{commands[name]}`\n<!-- /bench:{name} -->"

    text, n = re.subn(r"<!-- bench:([\w.]+) -->.*?<!-- /bench:\1 -->", replace, text, flags=re.S)
    if n == 0:
        sys.exit(f"bench_doc: {doc} has no <!-- bench:NAME --> markers")
    open(doc, "w").write(text)
    print(f"bench_doc: {len(rewritten)} of {n} tables rewritten in {doc}")


if __name__ == "__main__":
    main()
