#!/usr/bin/python3
"""Plots a sweep written by `linespace-validate sweep`: speed-up over the exact F-BVH against the
error (rmse_bias with its standard error as a bar; the RMSE where a point has no estimate, 1 spp),
memory as marker size, one colour per family, the Pareto front joined by a line.

Usage: plot_tradeoff.py SWEEP_DIR  (reads SWEEP_DIR/sweep.json, writes SWEEP_DIR/tradeoff.{png,svg})
Run with Debian's python3 (package python3-matplotlib)."""
import json
import sys

try:
    import matplotlib
except ImportError:
    print("plot_tradeoff.py: needs Debian's python3-matplotlib (scripts/setup.sh installs it)", file=sys.stderr)
    sys.exit(2)

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(folder):
    with open(folder + "/sweep.json") as f:
        sweep = json.load(f)
    points = [p for p in sweep["points"] if "rmse" in p]
    if not points:
        sys.exit("plot_tradeoff.py: the sweep holds no measured point")
    biased = all(p.get("rmse_bias") is not None for p in points)
    for p in points:
        p["error"] = p["rmse_bias"] if biased else p["rmse"]
        p["error_se"] = p["rmse_bias_stderr"] if biased else 0.0
    fig, ax = plt.subplots(figsize=(8, 5.5), dpi=120)
    colours = {"f-ls": "tab:blue", "2l-ls": "tab:orange"}
    biggest = max(p["bytes"] for p in points)
    for family, colour in colours.items():
        fam = [p for p in points if p["structure"].startswith(family + ":")]
        if not fam:
            continue
        # An RMSE is not negative: the bar stops at 0 on the left.
        ax.errorbar([p["error"] for p in fam], [p["speedup_vs_bvh"] for p in fam],
                    xerr=[[min(p["error"], p["error_se"]) for p in fam], [p["error_se"] for p in fam]],
                    fmt="none", ecolor=colour, lw=0.8)
        ax.scatter([p["error"] for p in fam], [p["speedup_vs_bvh"] for p in fam],
                   s=[30 + 600 * p["bytes"] / biggest for p in fam], c=colour, alpha=0.55,
                   edgecolors="black", linewidths=0.5, label=family.upper())
        for p in fam:
            label = "D%d N%d" % (p["depth"], p["subdivision"])
            if len({q["angle"] for q in points}) > 1:
                label += " %g°" % p["angle"]
            if len({q.get("behind") for q in points}) > 1:
                label += " " + p["behind"]
            if len({q.get("min_triangles") for q in points}) > 1:
                label += " M%d" % p["min_triangles"]
            ax.annotate(label, (p["error"], p["speedup_vs_bvh"]), fontsize=6, xytext=(4, 3),
                        textcoords="offset points")
    # The exact F-BVH (RMSE 0, speed-up 1) is always on the front: nothing is more accurate.
    front = [{"error": 0.0, "speedup_vs_bvh": 1.0}]
    front += [p for p in points if p["pareto"]]
    front.sort(key=lambda p: (p["error"], -p["speedup_vs_bvh"]))
    ax.plot([p["error"] for p in front], [p["speedup_vs_bvh"] for p in front], "k--", lw=1,
            label="Pareto front (with F-BVH)")
    ax.scatter([0.0], [1.0], marker="*", s=160, c="black", label="F-BVH (exact)")
    ax.axhline(1.0, color="grey", lw=0.5)
    ax.set_xlabel("%s against the all-exact image (LS from bounce %d)"
                  % ("rmse_bias ± standard error" if biased else "RMSE", sweep["start_bounce"]))
    ax.set_ylabel("speed-up over F-BVH, bounces >= 1")
    spp = ("auto from %d" % sweep["spp"]) if sweep.get("spp_auto") else "%d" % sweep["spp"]
    legend = sweep["device"]
    if len({p.get("min_triangles") for p in points}) > 1:
        legend += "; M: the smallest subtree with a Line Space (--ls-min-triangles)"
    ax.set_title("%s, %dx%d, %s spp, %d bounces — marker area ∝ memory (largest %.1f MB)\n%s"
                 % (sweep["scene"], sweep["width"], sweep["height"], spp, sweep["bounces"],
                    biggest / 1e6, legend), fontsize=8)
    ax.legend(fontsize=8, markerscale=0.6)
    ax.grid(True, lw=0.3)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig(folder + "/tradeoff." + ext)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    try:
        main(sys.argv[1])
    except (OSError, ValueError, KeyError, TypeError) as e:  # a missing folder, a truncated or foreign sweep.json
        print(f"plot_tradeoff.py: {sys.argv[1]}/sweep.json: {type(e).__name__}: {e}", file=sys.stderr)
        sys.exit(2)
