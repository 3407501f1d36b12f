#!/usr/bin/python3
"""Statistics of a render's linear image (total.exr), for choosing the PNG's exposure and finding fireflies.

    scripts/image-stats.py out/render/total.exr [...]

Per image: the mean 8-bit PNG level (0-255, sRGB, clamped) that each automatic exposure rule gives --
`key`, render's rule (the log-average luminance of the lit pixels becomes 0.18; common/render/exposure.h)
and `p99`, the validator's RMSE scale (the 99th-percentile luminance becomes 1; image_metrics.h) --
and the firefly count: pixels brighter than k times the median of their 5x5 neighbourhood (and than
1/20 of the 99th percentile, so that noise in the dark does not count), for k = 2, 3, 5 and 8.
Reads the EXR through oiiotool (Debian's openimageio-tools, which scripts/setup.sh does not install:
`apt-get install openimageio-tools`); numbers are computed here, not by the renderer.
"""
import math
import statistics
import subprocess
import sys


def load(path):
    """Rows of (r, g, b) per pixel, top row first."""
    text = subprocess.run(["oiiotool", "--dumpdata:empty=1", path], check=True, capture_output=True, text=True).stdout
    pixels = {}
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("Pixel ("):
            xy, values = line[len("Pixel ("):].split("):")
            x, y = map(int, xy.split(","))
            pixels[(y, x)] = tuple(float(v) for v in values.split()[:3])
    height = max(k[0] for k in pixels) + 1
    width = max(k[1] for k in pixels) + 1
    return [[pixels[(y, x)] for x in range(width)] for y in range(height)]


def luminance(p):
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]


def srgb(v):
    v = min(max(v, 0.0), 1.0)
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055


def png_mean(rows, multiplier):
    levels = [round(255 * srgb(c * multiplier)) for row in rows for p in row for c in p]
    return sum(levels) / len(levels)


def main(paths):
    for path in paths:
        rows = load(path)
        h, w = len(rows), len(rows[0])
        lum = [[luminance(p) for p in row] for row in rows]
        flat = sorted(v for row in lum for v in row)
        p99 = flat[int(math.floor(0.99 * (len(flat) - 1)))]
        lit = [v for v in flat if v > 0.0 and math.isfinite(v)]
        key = 0.18 / math.exp(sum(math.log(v) for v in lit) / len(lit)) if lit else 1.0
        p99_scale = 1.0 / p99 if p99 > 0.0 else 1.0
        counts = {}
        for k in (2, 3, 5, 8):
            counts[k] = 0
        for y in range(h):
            for x in range(w):
                v = lum[y][x]
                if v <= p99 / 20:
                    continue
                near = [lum[min(max(y + dy, 0), h - 1)][min(max(x + dx, 0), w - 1)] for dy in range(-2, 3) for dx in range(-2, 3)]
                median = statistics.median(near)
                for k in counts:
                    counts[k] += v > k * median
        print(f"{path}: {w}x{h}; PNG mean, key rule (x{key:.4g}) {png_mean(rows, key):.0f}, p99 rule (x{p99_scale:.4g}) "
              f"{png_mean(rows, p99_scale):.0f}; pixels over k x their 5x5 median: "
              + ", ".join(f"k={k}: {n}" for k, n in counts.items()))


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    try:
        main(sys.argv[1:])
    except FileNotFoundError as e:
        if e.filename == "oiiotool":
            print("image-stats.py: needs oiiotool: apt-get install openimageio-tools", file=sys.stderr)
        else:
            print(f"image-stats.py: {e}", file=sys.stderr)
        sys.exit(2)
    except subprocess.CalledProcessError as e:
        print(f"image-stats.py: oiiotool could not read {e.cmd[-1]}: {(e.stderr or '').strip().splitlines()[:1]}", file=sys.stderr)
        sys.exit(2)
    except ValueError as e:  # an image of no pixels
        print(f"image-stats.py: {e}", file=sys.stderr)
        sys.exit(2)
