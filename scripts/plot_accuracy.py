#!/usr/bin/python3
"""Plots the CSV of `gpucol-bench accuracy`: one PNG per study, time against each error it measured, one series
per scene, every point labelled with its setting and gpucol's default marked with a star.

Usage: plot_accuracy.py ACCURACY.csv OUTPUT_FOLDER
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # Files only: no display on build machines.
import matplotlib.pyplot as plt  # noqa: E402

ERRORS = [
    ("missed_pairs", "missed intersecting pairs"),
    ("false_pairs", "false intersecting pairs"),
    ("depth_error_m", "deepest depth - true penetration (m)"),
    ("normal_error_deg", "normal error (degrees)"),
    ("broadphase_missed", "broad phase missed pairs"),
    ("broadphase_extra", "broad phase extra pairs"),
    ("guess_error_rate", "share of row guesses off"),
    ("height_drift_m", "top box height drift (m)"),
    ("penetration_m", "resting penetration (m)"),
]

TIME_LABELS = {
    "time_step": "wall ms per simulated second",
    "stack_reduction": "wall ms per simulated second",
    "precision": "ms for every candidate pair (one thread)",
    "mapping_sqrt": "ms per 10^7 pair indices (one thread)",
    "cell_size": "ms per step (setAabb + pairs)",
}


def number(text):
    return float(text) if text != "" else math.nan


def main(path, folder):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"plot_accuracy.py: {path} has no rows")
    os.makedirs(folder, exist_ok=True)
    machine = rows[0]["machine"]
    studies = []
    for r in rows:
        if r["study"] not in studies:
            studies.append(r["study"])
    for study in studies:
        mine = [r for r in rows if r["study"] == study]
        errors = [(key, label) for key, label in ERRORS if any(r[key] != "" for r in mine)]
        if not errors:
            continue
        fig, axes = plt.subplots(1, len(errors), figsize=(5.2 * len(errors), 4.2), squeeze=False)
        scenes = []
        for r in mine:
            if r["scene"] not in scenes:
                scenes.append(r["scene"])
        for ax, (key, label) in zip(axes[0], errors):
            for i, scene in enumerate(scenes):
                points = [r for r in mine if r["scene"] == scene and r[key] != ""]
                if not points:
                    continue
                xs = [number(r["time_ms"]) for r in points]
                ys = [number(r[key]) for r in points]
                color = f"C{i}"
                ax.plot(xs, ys, "o", color=color, label=scene, alpha=0.8)
                for r, x, y in zip(points, xs, ys):
                    if r["default"] == "1":
                        ax.plot([x], [y], "*", color="black", markersize=15, zorder=5)
                    ax.annotate(r["setting"], (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
            times = [number(r["time_ms"]) for r in mine if r[key] != ""]
            if times and min(times) > 0 and max(times) / min(times) > 20:
                ax.set_xscale("log")  # scenes of very different cost side by side
            ax.set_xlabel(TIME_LABELS.get(study, "ms per query"))
            ax.set_ylabel(label)
            values = [number(r[key]) for r in mine if r[key] != ""]
            positive = [abs(v) for v in values if v != 0]
            if positive and max(positive) / max(min(positive), 1e-300) > 100:
                ax.set_yscale("symlog", linthresh=min(positive))
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        fig.suptitle(f"gpucol accuracy sweep: {study} (black star: default)\n{machine}", fontsize=9)
        fig.tight_layout()
        out = os.path.join(folder, f"accuracy_{study}.png")
        fig.savefig(out, dpi=110)
        plt.close(fig)
        print(f"wrote {out}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
