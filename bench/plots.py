#!/usr/bin/python3
"""Markdown tables and plots from the benchmark CSVs (system Python: numpy + Debian's matplotlib).

    /usr/bin/python3 bench/plots.py [--results bench/results] [--images docs/images]

Reads RESULTS/compare.csv and RESULTS/scaling.csv (whichever exist); writes RESULTS/compare.md,
RESULTS/scaling.md and IMAGES/bench_compare_*.png, IMAGES/bench_scaling_*.png.
"""
import argparse
import csv
import json
import math
import os
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
TOOL_LABEL = {"qgp": "Quantized Retopo", "quadriflow": "QuadriFlow"}
TOOL_STYLE = {"qgp": dict(color="tab:blue", marker="o"), "quadriflow": dict(color="tab:orange", marker="s")}
STAGES = ["intake", "working_mesh", "cross_field", "cut_graph", "seamless_map", "tmesh", "quantization", "igm",
          "quad_extraction", "metrics"]


def number(value):
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def fmt(value, spec):
    x = number(value)
    return "—" if x is None else format(x, spec)


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


# -- comparison --

def quads_per_target(r):
    """Quads over the count asked (rows written before the column existed: from quads and target)."""
    ratio = number(r.get("quads_per_target"))
    if ratio is None and number(r.get("quads")) is not None:
        ratio = number(r["quads"]) / number(r["target"])
    return ratio


def count_cell(r):
    """'1.02', or with the fewest quads the report names when the count asked is below them: '1.35 (≥ 2 700)'."""
    ratio = quads_per_target(r)
    fewest = number(r.get("fewest_quads"))
    if ratio is None:
        return "—"
    return f"{ratio:.2f}" + (f" (≥ {fewest:,.0f})".replace(",", " ") if fewest else "")


def count_kept(r):
    """The count asked was met: within 5 %, or below the fewest quads the report names."""
    ratio, fewest = quads_per_target(r), number(r.get("fewest_quads"))
    if ratio is None:
        return False
    return abs(ratio - 1) <= 0.05 or (fewest is not None and fewest > 1.05 * number(r["target"]))


def cell_values(r):
    """Table cells of one run (dashes where the run produced no mesh)."""
    chi = {"True": "yes", "False": "**no**"}.get(r["euler_characteristic_preserved"], "—")
    sharp = "—" if not r["sharp_edge_coverage"] else f"{100 * float(r['sharp_edge_coverage']):.1f}%"
    hd = "—" if not r["hausdorff"] else f"{100 * float(r['hausdorff']):.2f}"
    return [fmt(r["seconds"], ".2f"), fmt(r["quads"], ".0f"), count_cell(r), fmt(r["irregular_vertices"], ".0f"),
            fmt(r["flipped_quads"], ".0f"), chi, hd, fmt(r["mean_angle_deviation_deg"], ".1f"),
            fmt(r["p95_angle_deviation_deg"], ".1f"), fmt(r["min_scaled_jacobian"], ".2f"), sharp]


def compare_markdown(rows):
    """One line per mesh and target, each cell 'Quantized Retopo | QuadriFlow'; status messages listed below."""
    tools = [t for t in TOOL_LABEL if any(r["tool"] == t for r in rows)]
    header = ["time s", "quads", "quads / target", "irregular", "flipped", "χ kept", "Hausdorff % diag",
              "angle dev mean °", "angle dev p95 °", "min SJ", "sharp coverage"]
    lines = [f"Cells: {' / '.join(TOOL_LABEL[t] for t in tools)}.", "",
             "| mesh | target | status | " + " | ".join(header) + " |",
             "|---|---:|---|" + "---:|" * len(header)]
    messages = {}
    cases = []
    for r in rows:
        if (r["mesh"], r["target"]) not in cases:
            cases.append((r["mesh"], r["target"]))
    for mesh, target in cases:
        runs = {r["tool"]: r for r in rows if r["mesh"] == mesh and r["target"] == target}
        statuses, cells = [], []
        for t in tools:
            r = runs.get(t)
            if r is None:
                statuses.append("not run")
                cells.append(["—"] * len(header))
                continue
            status = r["status"]
            if r["message"]:
                key = (t, r["status"], r["message"])
                messages.setdefault(key, len(messages) + 1)
                status += f" [{messages[key]}]"
            statuses.append(status)
            cells.append(cell_values(r))
        lines.append(f"| {mesh} | {target} | {' / '.join(statuses)} | "
                     + " | ".join(" / ".join(c[i] for c in cells) for i in range(len(header))) + " |")
    if messages:
        lines += ["", "Messages:", ""]
        for (tool, status, message), n in sorted(messages.items(), key=lambda kv: kv[1]):
            lines.append(f"{n}. {TOOL_LABEL.get(tool, tool)}, {status}: {message}")
    return "\n".join(lines) + "\n"


def median(values):
    values = sorted(v for v in values if v is not None)
    if not values:
        return None
    n = len(values)
    return values[n // 2] if n % 2 else 0.5 * (values[n // 2 - 1] + values[n // 2])


def time_ratios(rows):
    """Per mesh and target where both tools ran: (mesh, triangles, target, qgp s, QuadriFlow s, ratio, qgp peak MB,
    statuses); the ratio is qgp's time over QuadriFlow's, only where both gave a mesh."""
    runs = defaultdict(dict)
    for r in rows:
        runs[(r["mesh"], r["target"])][r["tool"]] = r
    out = []
    for (mesh, target), by_tool in runs.items():
        q, f = by_tool.get("qgp"), by_tool.get("quadriflow")
        if q is None or f is None:
            continue
        qs, fs = number(q["seconds"]), number(f["seconds"])
        both_ok = q["status"] == "ok" and f["status"] == "ok" and qs is not None and fs
        out.append((mesh, q["input_triangles"], target, qs, fs, qs / fs if both_ok else None,
                    number(q.get("peak_memory_mb")), f"{q['status']} / {f['status']}"))
    return out


def ratio_markdown(rows):
    """The time ratio table: one line per mesh and target, then how many are slower and the median ratio."""
    ratios = time_ratios(rows)
    lines = ["| mesh | triangles | target | Quantized Retopo s | QuadriFlow s | ratio | Quantized Retopo peak MB "
             "| status |", "|---|---:|---:|---:|---:|---:|---:|---|"]
    for mesh, triangles, target, qs, fs, ratio, peak, status in ratios:
        lines.append(f"| {mesh} | {triangles} | {target} | {fmt(qs, '.2f')} | {fmt(fs, '.2f')} | "
                     f"{fmt(ratio, '.2f')} | {fmt(peak, '.0f')} | {status} |")
    compared = [r[5] for r in ratios if r[5] is not None]
    slower = sum(r > 1 for r in compared)
    lines += ["", f"Quantized Retopo slower than QuadriFlow on {slower} of {len(compared)} runs where both gave a "
              f"mesh; median ratio {fmt(median(compared), '.2f')}."]
    return "\n".join(lines) + "\n"


def compare_summary(rows):
    lines = ["| tool | runs | ok | refused | unchanged | timeout | crashed | χ kept (of ok) | count kept (of ok) "
             "| flipped quads total | median time s | median Hausdorff % | median p95 angle ° | median min SJ |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    by_tool = defaultdict(list)
    for r in rows:
        by_tool[r["tool"]].append(r)
    for tool, rs in by_tool.items():
        ok = [r for r in rs if r["status"] == "ok"]
        count = lambda s: sum(r["status"] == s for r in rs)  # noqa: E731
        hd = median([number(r["hausdorff"]) for r in ok])
        lines.append(
            f"| {TOOL_LABEL.get(tool, tool)} | {len(rs)} | {len(ok)} | {count('refused')} | {count('unchanged')} "
            f"| {count('timeout')} | {count('crashed')} "
            f"| {sum(r['euler_characteristic_preserved'] == 'True' for r in ok)} "
            f"| {sum(count_kept(r) for r in ok)} "
            f"| {sum(int(number(r['flipped_quads']) or 0) for r in ok)} "
            f"| {fmt(median([number(r['seconds']) for r in rs]), '.2f')} "
            f"| {'—' if hd is None else format(100 * hd, '.2f')} "
            f"| {fmt(median([number(r['p95_angle_deviation_deg']) for r in ok]), '.1f')} "
            f"| {fmt(median([number(r['min_scaled_jacobian']) for r in ok]), '.3f')} |")
    return "\n".join(lines) + "\n"


def compare_plots(rows, images):
    paths = []
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for tool in TOOL_LABEL:
        for target, fill in zip(sorted({int(r["target"]) for r in rows}), ["full", "none"]):
            pts = [(int(r["input_triangles"]), float(r["seconds"])) for r in rows
                   if r["tool"] == tool and int(r["target"]) == target and number(r["seconds"]) is not None]
            if pts:
                x, y = zip(*pts)
                ax.scatter(x, y, label=f"{TOOL_LABEL[tool]} ({target} quads)", facecolors=None if fill == "full"
                           else "none", edgecolors=TOOL_STYLE[tool]["color"], **TOOL_STYLE[tool])
    ax.set(xscale="log", yscale="log", xlabel="input triangles", ylabel="wall time in Blender (s)",
           title="Time per run (all statuses)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    paths.append(save(fig, images, "bench_compare_time.png"))

    metrics = [("hausdorff", "Hausdorff (% of diagonal)", 100.0),
               ("p95_angle_deviation_deg", "p95 angle deviation (°)", 1),
               ("irregular_vertices", "irregular vertices", 1), ("min_scaled_jacobian", "min scaled Jacobian", 1)]
    meshes = sorted({r["mesh"] for r in rows},
                    key=lambda m: min(int(r["input_triangles"]) for r in rows if r["mesh"] == m))
    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    for ax, (key, label, scale) in zip(axes.flat, metrics):
        for tool in TOOL_LABEL:
            for target, fill in zip(sorted({int(r["target"]) for r in rows}), ["full", "none"]):
                pts = [(meshes.index(r["mesh"]), number(r[key]) * scale) for r in rows
                       if r["tool"] == tool and int(r["target"]) == target and r["status"] == "ok"
                       and number(r[key]) is not None]
                if pts:
                    x, y = zip(*pts)
                    ax.scatter(x, y, label=f"{TOOL_LABEL[tool]} ({target})", facecolors=None if fill == "full"
                               else "none", edgecolors=TOOL_STYLE[tool]["color"], **TOOL_STYLE[tool])
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xticks(range(len(meshes)))
        ax.set_xticklabels([os.path.splitext(m)[0][:12] for m in meshes], rotation=70, fontsize=7)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.955), ncol=4, fontsize=8)
    fig.suptitle("Quality of successful runs (same native measurement for both tools)", y=0.995, fontsize=10)
    paths.append(save(fig, images, "bench_compare_quality.png", rect=(0, 0, 1, 0.91)))
    return paths


# -- scaling --

def peak_mb(row):
    """Peak memory of a run; none for a killed run (its figure is not the pipeline's, see scaling.py)."""
    return None if row["status"] == "timeout" else number(row["peak_rss_mb"])


def growth_exponents(rows):
    """Per size-series row: the exponent k of wall time ~ triangles^k from the shape's previous level
    (1 is linear; n log n shows as slightly above 1); None for a shape's first level or a failed run."""
    exponents, previous = {}, {}
    for i, r in enumerate(rows):
        if r["series"] != "size" or r["status"] != "ok":
            continue
        n, t = int(r["triangles"]), number(r["wall_s"])
        before = previous.get(r["shape"])
        if before and t and before[1] and n > before[0]:
            exponents[i] = math.log(t / before[1]) / math.log(n / before[0])
        previous[r["shape"]] = (n, t)
    return exponents


def scaling_markdown(rows):
    exponents = growth_exponents(rows)
    lines = ["| series | shape | triangles | target | status | wall s | growth | peak MB | quads | "
             + " | ".join(s.replace("_", " ") for s in STAGES) + " |",
             "|---|---|---:|---:|---|---:|---:|---:|---:|" + "---:|" * len(STAGES)]
    for i, r in enumerate(rows):
        status = r["status"]
        if status != "ok" and r["message"]:
            message = r["message"].replace("|", "/")
            status += ": " + (message if len(message) <= 50 else message[:47] + "...")
        lines.append(f"| {r['series']} | {r['shape']} | {int(r['triangles']):,} | {r['target']} | {status} "
                     f"| {fmt(r['wall_s'], '.2f')} | {fmt(exponents.get(i), '.2f')} | {fmt(peak_mb(r), '.0f')} "
                     f"| {fmt(r['quads'], '.0f')} | "
                     + " | ".join(fmt(r[s + '_s'], '.2f') for s in STAGES) + " |")
    return "\n".join(lines) + "\n"


def scaling_plots(rows, images):
    paths = []
    for series, xkey, xlabel in [("size", "triangles", "input triangles"), ("density", "target", "target quads")]:
        rs = [r for r in rows if r["series"] == series]
        if not rs:
            continue
        fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.2))
        for shape in sorted({r["shape"] for r in rs}):
            pts = sorted((int(r[xkey]), number(r["wall_s"]), peak_mb(r)) for r in rs
                         if r["shape"] == shape)
            x = [p[0] for p in pts]
            nan = float("nan")
            ax_t.plot(x, [nan if p[1] is None else p[1] for p in pts], marker="o", label=f"{shape} total (wall)")
            ax_m.plot(x, [nan if p[2] is None else p[2] for p in pts], marker="o", label=shape)
        failed = [(int(r[xkey]), number(r["wall_s"])) for r in rs if r["status"] != "ok"]
        if failed:
            ax_t.scatter(*zip(*failed), marker="x", color="black", zorder=3, label="run refused / timed out")
        # Per-stage times of the first shape, to show where the time goes.
        shape = sorted({r["shape"] for r in rs})[0]
        pts = sorted((int(r[xkey]), r) for r in rs if r["shape"] == shape)
        for stage in STAGES:
            ys = [number(r[stage + "_s"]) for _, r in pts]
            if any(y for y in ys if y is not None):
                ax_t.plot([x for x, _ in pts], [y if y else float("nan") for y in ys], linestyle="--",
                          linewidth=1, label=f"{shape}: {stage}")
        ax_t.set(xscale="log", yscale="log", xlabel=xlabel, ylabel="seconds", title="Time (wall and per stage)")
        ax_m.set(xscale="log", yscale="log", xlabel=xlabel, ylabel="peak resident memory (MB)", title="Peak memory")
        for ax in (ax_t, ax_m):
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=7)
        fig.suptitle(f"Native pipeline (qgp remesh) against {xlabel}", fontsize=10)
        paths.append(save(fig, images, f"bench_scaling_{series}.png"))
    return paths


def save(fig, images, name, rect=None):
    fig.tight_layout(rect=rect)
    path = os.path.join(images, name)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


BEGIN, END = "<!-- bench-results:begin -->", "<!-- bench-results:end -->"


def update_doc(doc, results, images, compare, scaling):
    """Replaces the text between the BEGIN/END markers of `doc` with the latest tables and images."""
    if not os.path.exists(doc):
        return False
    with open(doc) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return False
    rel = lambda p: os.path.relpath(p, os.path.dirname(os.path.abspath(doc)))  # noqa: E731
    parts = [BEGIN, "", "*Generated by `bench/plots.py` from the CSVs of the last `scripts/bench.sh` run.*", ""]
    if compare:
        meta = {}
        meta_path = os.path.join(results, "compare.json")
        if os.path.exists(meta_path):
            with open(meta_path) as f:
                meta = json.load(f)
        parts += [f"### Comparison ({len({r['mesh'] for r in compare})} meshes, targets "
                  f"{', '.join(sorted({r['target'] for r in compare}, key=int))} quads; Blender "
                  f"{meta.get('blender', '?')}, Quantized Retopo {meta.get('qgp', '?')})", "",
                  compare_summary(compare), "Time against QuadriFlow (ratio: Quantized Retopo's time over "
                  "QuadriFlow's):", "", ratio_markdown(compare), "Per run:", "", compare_markdown(compare)]
        for name in ("bench_compare_time.png", "bench_compare_quality.png"):
            if os.path.exists(os.path.join(images, name)):
                parts.append(f"![{name}]({rel(os.path.join(images, name))})")
        renders = sorted(n for n in os.listdir(images) if n.startswith("compare_") and n.endswith(".png"))
        if renders:
            parts += ["", "Renders (input | Quantized Retopo | QuadriFlow):", ""]
            parts += [f"![{n}]({rel(os.path.join(images, n))})" for n in renders]
        parts.append("")
    if scaling:
        parts += ["### Scaling of the native pipeline", "", scaling_markdown(scaling)]
        for name in ("bench_scaling_size.png", "bench_scaling_density.png"):
            if os.path.exists(os.path.join(images, name)):
                parts.append(f"![{name}]({rel(os.path.join(images, name))})")
        parts.append("")
    parts.append(END)
    head, rest = text.split(BEGIN, 1)
    tail = rest.split(END, 1)[1]
    with open(doc, "w") as f:
        f.write(head + "\n".join(parts) + tail)
    return True


def main():
    ap = argparse.ArgumentParser(prog="bench/plots.py")
    ap.add_argument("--results", default=os.path.join(REPO, "bench", "results"))
    ap.add_argument("--images", default=os.path.join(REPO, "docs", "images"))
    ap.add_argument("--doc", default=os.path.join(REPO, "docs", "benchmark.md"),
                    help="markdown file whose results section (between the markers) is regenerated")
    args = ap.parse_args()
    os.makedirs(args.images, exist_ok=True)
    compare = read_csv(os.path.join(args.results, "compare.csv"))
    if compare:
        with open(os.path.join(args.results, "compare.md"), "w") as f:
            f.write("## Summary\n\n" + compare_summary(compare) + "\n## Time against QuadriFlow\n\n"
                    + ratio_markdown(compare) + "\n## All runs\n\n" + compare_markdown(compare))
        print(ratio_markdown(compare))
        for p in compare_plots(compare, args.images):
            print(f"plots: {p}")
    scaling = read_csv(os.path.join(args.results, "scaling.csv"))
    if scaling:
        with open(os.path.join(args.results, "scaling.md"), "w") as f:
            f.write(scaling_markdown(scaling))
        for p in scaling_plots(scaling, args.images):
            print(f"plots: {p}")
    if update_doc(args.doc, args.results, args.images, compare, scaling):
        print(f"plots: updated {args.doc}")
    print(f"plots: tables in {args.results}/compare.md, scaling.md")


if __name__ == "__main__":
    main()
