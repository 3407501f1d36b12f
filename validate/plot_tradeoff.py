#!/usr/bin/python3
"""Plots a sweep written by `linespace-validate sweep`: speed-up over the exact F-BVH against RMSE,
memory as marker size, one colour per family, the Pareto front joined by a line.

Usage: plot_tradeoff.py SWEEP_DIR  (reads SWEEP_DIR/sweep.json, writes SWEEP_DIR/tradeoff.{png,svg})
Run with Debian's python3 (package python3-matplotlib)."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(folder):
    with open(folder + "/sweep.json") as f:
        sweep = json.load(f)
    points = [p for p in sweep["points"] if "rmse" in p]
    if not points:
        sys.exit("plot_tradeoff.py: the sweep holds no measured point")
    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    colours = {"f-ls": "tab:blue", "2l-ls": "tab:orange"}
    biggest = max(p["bytes"] for p in points)
    for family, colour in colours.items():
        fam = [p for p in points if p["structure"].startswith(family + ":")]
        if not fam:
            continue
        ax.scatter([p["rmse"] for p in fam], [p["speedup_vs_bvh"] for p in fam],
                   s=[30 + 600 * p["bytes"] / biggest for p in fam], c=colour, alpha=0.55,
                   edgecolors="black", linewidths=0.5, label=family.upper())
        for p in fam:
            label = "D%d N%d" % (p["depth"], p["subdivision"])
            if len({q["angle"] for q in points}) > 1:
                label += " %g°" % p["angle"]
            ax.annotate(label, (p["rmse"], p["speedup_vs_bvh"]), fontsize=6, xytext=(4, 3),
                        textcoords="offset points")
    # The exact F-BVH (RMSE 0, speed-up 1) is always on the front: nothing is more accurate.
    front = [{"rmse": 0.0, "speedup_vs_bvh": 1.0}]
    front += sorted((p for p in points if p["pareto"]), key=lambda p: p["rmse"])
    front.sort(key=lambda p: (p["rmse"], -p["speedup_vs_bvh"]))
    ax.plot([p["rmse"] for p in front], [p["speedup_vs_bvh"] for p in front], "k--", lw=1,
            label="Pareto front (with F-BVH)")
    ax.scatter([0.0], [1.0], marker="*", s=160, c="black", label="F-BVH (exact)")
    ax.axhline(1.0, color="grey", lw=0.5)
    ax.set_xlabel("RMSE against the all-exact image (LS from bounce %d)" % sweep["start_bounce"])
    ax.set_ylabel("speed-up over F-BVH, bounces >= 1")
    ax.set_title("%s, %dx%d, %d spp, %d bounces — marker area ∝ memory (largest %.1f MB)\n%s"
                 % (sweep["scene"], sweep["width"], sweep["height"], sweep["spp"], sweep["bounces"],
                    biggest / 1e6, sweep["device"]), fontsize=8)
    ax.legend(fontsize=8, markerscale=0.6)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(folder + "/tradeoff." + ext)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
