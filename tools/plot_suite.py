#!/usr/bin/env python3
"""Plots of a `voca bench suite` folder, as PNG and SVG in <dir>/plots:

  bitrate.*          median ATE and RTE against bitrate per system, with success rates (the paper's Fig. 7)
  guess_distance.*   distance from the initial guess to the converged track, from the previous position
                     and from the motion-vector prior (the paper's Fig. 5; frontend statistics)
  trajectories_<bitrate>.*  top views of every sequence's estimates against the ground truth
  stage_times.*      mean time per frame of the decode, frontend and backend stages per system

Needs matplotlib (Debian: python3-matplotlib). Usage: tools/plot_suite.py <suite-output-dir>
"""

import argparse
import csv
import json
import math
import os
import sys

plt = None


def load_matplotlib():
    global plt
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as pyplot
    except ImportError:
        sys.exit("plot_suite.py: matplotlib is missing (Debian: apt install python3-matplotlib)")
    plt = pyplot


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def bitrate_kbps(label):
    """'500k' -> 500; 'raw' -> None."""
    if label == "raw":
        return None
    return float(label[:-1]) if label.endswith("k") else float(label) / 1000.0


def save(fig, out_dir, name):
    os.makedirs(out_dir, exist_ok=True)
    written = []
    for ext in ("png", "svg"):
        path = os.path.join(out_dir, f"{name}.{ext}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        written.append(path)
    plt.close(fig)
    return written


def plot_bitrate(summary, out_dir):
    """Median ATE / RTE against bitrate, one line per system; success rate below."""
    systems = []
    for row in summary:
        if row["system"] not in systems:
            systems.append(row["system"])
    encoded = [r for r in summary if r["bitrate"] != "raw"]
    if not encoded:
        return []
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    panels = [("med_ate_m", "median ATE [cm]"), ("med_rte_m", "median RTE [cm]"), ("sr_ate", "ATE success rate [%]")]
    for system in systems:
        rows = sorted((r for r in encoded if r["system"] == system), key=lambda r: bitrate_kbps(r["bitrate"]))
        if not rows:
            continue
        x = [bitrate_kbps(r["bitrate"]) for r in rows]
        for ax, (key, _) in zip(axes, panels):
            scale = 100.0
            y = [number(r[key]) for r in rows]
            y = [v * scale if v is not None else math.nan for v in y]
            ax.plot(x, y, marker="o", label=system)
        raw = [r for r in summary if r["system"] == system and r["bitrate"] == "raw"]
        for r in raw:  # the raw-image baseline as a dashed level
            for ax, (key, _) in zip(axes, panels):
                v = number(r[key])
                if v is not None:
                    ax.axhline(100.0 * v, linestyle="--", linewidth=1, color="gray")
    for ax, (_, label) in zip(axes, panels):
        ax.set_xscale("log")
        ax.set_xlabel("bitrate per camera [kbit/s]")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[2].set_ylim(-5, 105)
    axes[0].legend(fontsize=8)
    fig.suptitle("Accuracy against bitrate (dashed: raw images); failed runs count as infinity in the medians")
    return save(fig, out_dir, "bitrate")


def load_statistics(row):
    """A successful run's statistics JSON, or None when the run failed or its file is missing or unreadable."""
    if row["status"] != "ok" or not row.get("statistics"):
        return None
    try:
        with open(row["statistics"]) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def histogram(stats_json, key):
    h = stats_json.get("frontend", {}).get(key)
    if not h:
        return None
    return h["bin_px"], {float(b[0]): int(b[1]) for b in h["bins"]}


def plot_guess_distance(results, out_dir):
    """Sum the frontend's guess-to-solution histograms over the successful runs with a prior."""
    previous, prior = {}, {}
    bin_px = None
    for row in results:
        stats = None if row.get("mode") in ("", "none") else load_statistics(row)
        if stats is None:
            continue
        for key, target in (("guess_distance_previous", previous), ("guess_distance_prior", prior)):
            h = histogram(stats, key)
            if h is None:
                continue
            bin_px = h[0]
            for start, count in h[1].items():
                target[start] = target.get(start, 0) + count
    if not previous or not prior:
        return []
    # The statistics bin finely; a quarter pixel is enough to see where the guesses land.
    coarse_px = max(bin_px, 0.25)
    fig, ax = plt.subplots(figsize=(7, 4))
    for data, label in ((previous, "without MV (previous position)"), (prior, "with MV (codec prior)")):
        total = sum(data.values())
        bins = {}
        for start, count in data.items():
            key = math.floor(start / coarse_px + 1e-9) * coarse_px
            bins[key] = bins.get(key, 0) + count
        starts = sorted(bins)
        ax.step([b + coarse_px for b in starts], [100.0 * bins[b] / total for b in starts], where="pre",
                label=f"{label}, {total} tracks")
    ax.set_yscale("log")
    ax.set_xlabel(f"initial guess to converged position [px] ({coarse_px:g} px bins, last: overflow)")
    ax.set_ylabel("tracks [%]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("Prior-to-solution distance (runs with a motion-vector prior)")
    return save(fig, out_dir, "guess_distance")


def load_positions(path, with_times=False):
    """[(x, y, z)] of a TUM, EuRoC csv or KITTI (12 numbers per row) trajectory; with_times: also the
    times in seconds (None for KITTI, which has none)."""
    points, times = [], []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line or line[0] == "#" or line[0].isalpha():
                continue
            csv_row = "," in line  # EuRoC csv: nanoseconds; TUM: seconds, space separated
            values = [float(v) for v in line.replace(",", " ").split()]
            if len(values) == 12:  # KITTI 3x4 rows
                points.append((values[3], values[7], values[11]))
                times.append(None)
            else:  # EuRoC csv (ns, p, q) or TUM (s, p, q)
                points.append((values[1], values[2], values[3]))
                times.append(values[0] * 1e-9 if csv_row else values[0])
    return (points, times) if with_times else points


def aligned(row):
    """The estimate's positions after the ATE alignment stored in its statistics (as it was evaluated)."""
    points = load_positions(row["trajectory"])
    try:
        with open(row["statistics"]) as f:
            T = json.load(f)["eval"]["ate"]["T_gt_est"]
    except (OSError, ValueError, KeyError, TypeError):
        return points
    return [tuple(sum(T[r][c] * p[c] for c in range(3)) + T[r][3] for r in range(3)) for p in points]


def top_axes(points):
    """The two axes along which the ground truth moves most: a top view for drones and cars alike."""
    extents = [max(p[i] for p in points) - min(p[i] for p in points) for i in range(3)]
    return sorted(sorted(range(3), key=lambda i: -extents[i])[:2])


def plot_trajectories(results, out_dir):
    written = []
    bitrates = []
    for row in results:
        if row["bitrate"] and row["bitrate"] not in bitrates:
            bitrates.append(row["bitrate"])
    names = "xyz"
    for bitrate in bitrates:
        rows = [r for r in results if r["bitrate"] == bitrate]
        sequences = []
        for r in rows:
            if r["sequence"] not in sequences:
                sequences.append(r["sequence"])
        cols = min(3, len(sequences))
        nrows = math.ceil(len(sequences) / cols)
        fig, axes = plt.subplots(nrows, cols, figsize=(5 * cols, 4.5 * nrows), squeeze=False)
        for ax, sequence in zip(axes.flat, sequences):
            seq_rows = [r for r in rows if r["sequence"] == sequence]
            gt_path = next((r["ground_truth"] for r in seq_rows if r.get("ground_truth")), "")
            plane = [0, 1]
            if gt_path and os.path.exists(gt_path):
                gt, gt_times = load_positions(gt_path, with_times=True)
                # Only the stretch the runs estimated (a clip's ground truth may cover the whole recording).
                spans = [load_positions(r["trajectory"], with_times=True)[1] for r in seq_rows
                         if r["status"] == "ok" and os.path.exists(r.get("trajectory", ""))]
                spans = [t for t in spans if t and t[0] is not None]
                if spans and gt_times and gt_times[0] is not None:
                    first, last = min(t[0] for t in spans), max(t[-1] for t in spans)
                    kept = [p for p, t in zip(gt, gt_times) if first - 0.05 <= t <= last + 0.05]
                    gt = kept or gt
                plane = top_axes(gt)
                ax.plot([p[plane[0]] for p in gt], [p[plane[1]] for p in gt], color="black", linewidth=2,
                        label="ground truth")
            for r in seq_rows:
                if r["status"] != "ok" or not os.path.exists(r.get("trajectory", "")):
                    continue
                points = aligned(r) if r.get("statistics") else load_positions(r["trajectory"])
                ate = number(r["ate_m"])
                ax.plot([p[plane[0]] for p in points], [p[plane[1]] for p in points], linewidth=1,
                        label=f"{r['system']} (ATE {100 * ate:.2f} cm)" if ate is not None else r["system"])
            ax.set_title(sequence)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_xlabel(f"{names[plane[0]]} [m]")
            ax.set_ylabel(f"{names[plane[1]]} [m]")
            ax.legend(fontsize=7)
            ax.grid(True, alpha=0.3)
        for ax in list(axes.flat)[len(sequences):]:
            ax.axis("off")
        fig.suptitle(f"Top views at {bitrate} (estimates aligned as for the ATE)")
        written += save(fig, out_dir, f"trajectories_{bitrate}")
    return written


def plot_stage_times(results, out_dir):
    """Mean per-frame time of each stage per system, over its successful runs."""
    sums = {}
    for row in results:
        stats = load_statistics(row)
        if stats is None:
            continue
        columns = stats.get("frame_columns", [])
        wanted = [c for c in ("decode_ms", "frontend_ms", "backend_ms") if c in columns]
        entry = sums.setdefault(f"{row['system']} @ {row['bitrate']}", {c: [0.0, 0] for c in wanted})
        for frame in stats.get("frame_rows", []):
            for c in wanted:
                entry[c][0] += frame[columns.index(c)]
                entry[c][1] += 1
    if not sums:
        return []
    labels = list(sums)
    fig, ax = plt.subplots(figsize=(max(6, 0.6 * len(labels) + 2), 4))
    bottom = [0.0] * len(labels)
    for stage in ("decode_ms", "frontend_ms", "backend_ms"):
        values = [sums[l][stage][0] / sums[l][stage][1] if sums[l].get(stage, [0, 0])[1] else 0.0 for l in labels]
        ax.bar(labels, values, bottom=bottom, label=stage.replace("_ms", ""))
        bottom = [b + v for b, v in zip(bottom, values)]
    ax.set_ylabel("mean time per frame [ms]")
    ax.set_title("Time per frame by stage (wall time of each stage)")
    ax.legend()
    plt.setp(ax.get_xticklabels(), rotation=45, ha="right", fontsize=8)
    return save(fig, out_dir, "stage_times")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("dir", help="output folder of `voca bench suite` (with summary.csv and results.csv)")
    parser.add_argument("--out", help="where to write the plots (default: <dir>/plots)")
    args = parser.parse_args()
    for name in ("summary.csv", "results.csv"):
        if not os.path.exists(os.path.join(args.dir, name)):
            sys.exit(f"plot_suite.py: {args.dir} has no {name}: run `voca bench suite` or `voca bench collect` first")
    load_matplotlib()
    out_dir = args.out or os.path.join(args.dir, "plots")
    summary = read_csv(os.path.join(args.dir, "summary.csv"))
    results = read_csv(os.path.join(args.dir, "results.csv"))
    written = []
    written += plot_bitrate(summary, out_dir)
    written += plot_guess_distance(results, out_dir)
    written += plot_trajectories(results, out_dir)
    written += plot_stage_times(results, out_dir)
    for path in written:
        print(path)
    if not written:
        sys.exit("plot_suite.py: nothing to plot (no successful runs)")


if __name__ == "__main__":
    main()
