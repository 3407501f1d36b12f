#!/usr/bin/env python3
"""The two parts of scripts/gpu-check.sh that are easier in Python (standard library only, 3.7+).

  gpu_check.py icd DIR
      Finds the host's Vulkan driver (ICD) files, as the Vulkan loader would, writes each x86-64 one
      into DIR with its library's path made absolute, and prints VK_DRIVER_FILES=... and
      LINESPACE_EXTRA_LIBRARY_PATH=... (the drivers' folders) for gpu-check.sh.
  gpu_check.py libs LOG BUNDLE
      Reads a loader's LD_DEBUG=files log of a program run from BUNDLE and lists every object that
      came from the host though it should have come from the bundle (exit 1 if any, or none at all).
  gpu_check.py report LOGS OUT [--mode M] [--seconds S] [--bundle DIR]
      Reads the steps gpu-check.sh ran (LOGS/steps.tsv and each step's output) and writes
      OUT/gpu-check.json and OUT/gpu-check.md.  Exit 0 when every step ran and nothing differs, else 1.
"""
import datetime
import json
import os
import re
import subprocess
import sys

# The paper's Table 3 (GTX 1080, path tracing, averaged over its five scenes), MRays/s.
PAPER_MRAYS = {
    "bvh": 70.7, "2l-bvh": 34.3, "f-ls:8:6": 377.0, "2l-ls:4:6": 120.2,
    "f-ls:4:10": 622.6, "f-ls:6:10": 440.6, "f-ls:8:10": 346.6,
    "2l-ls:0:10": 201.8, "2l-ls:4:10": 117.7, "2l-ls:6:10": 102.2,
}
LIBRARY_DIRS = ["/usr/local/nvidia/lib64", "/usr/local/nvidia/lib", "/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu",
                "/usr/lib64", "/lib64", "/usr/local/lib", "/usr/lib", "/lib"]


def is_x86_64_elf(path):
    try:
        with open(path, "rb") as f:
            head = f.read(20)
    except OSError:
        return False
    return len(head) == 20 and head[:4] == b"\x7fELF" and head[4] == 2 and head[18:20] == b"\x3e\x00"


def ldconfig_paths(name):
    for exe in ("ldconfig", "/sbin/ldconfig", "/usr/sbin/ldconfig"):
        try:
            text = subprocess.run([exe, "-p"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                  universal_newlines=True, timeout=20).stdout
        except (OSError, subprocess.SubprocessError):
            continue
        return [line.rsplit("=>", 1)[1].strip() for line in text.splitlines()
                if line.strip().startswith(name + " ") and "=>" in line]
    return []


def resolve_library(library, json_dir):
    """The absolute x86-64 file a driver file's library_path names, and how it was found."""
    if os.path.isabs(library):
        return (library, "absolute") if is_x86_64_elf(library) else (None, "not an x86-64 library")
    if "/" in library:
        path = os.path.normpath(os.path.join(json_dir, library))
        return (path, "relative to its file") if is_x86_64_elf(path) else (None, "not an x86-64 library")
    for path in ldconfig_paths(library):
        if is_x86_64_elf(path):
            return path, "ldconfig -p"
    dirs = [d for d in os.environ.get("LD_LIBRARY_PATH", "").split(":") if d] + LIBRARY_DIRS
    for d in dirs:
        path = os.path.join(d, library)
        if is_x86_64_elf(path):
            return path, "found in " + d
    return None, "not found by ldconfig -p, LD_LIBRARY_PATH or " + ", ".join(LIBRARY_DIRS)


def driver_files():
    """The ICD files the Vulkan loader would read, in its order (VK_DRIVER_FILES / VK_ICD_FILENAMES win)."""
    named = os.environ.get("VK_DRIVER_FILES") or os.environ.get("VK_ICD_FILENAMES")
    if named:
        return [p for p in named.split(":") if p]
    home = os.environ.get("HOME", "")
    config = [os.environ.get("XDG_CONFIG_HOME", os.path.join(home, ".config"))] + \
        os.environ.get("XDG_CONFIG_DIRS", "/etc/xdg").split(":") + ["/etc"]
    data = [os.environ.get("XDG_DATA_HOME", os.path.join(home, ".local/share"))] + \
        os.environ.get("XDG_DATA_DIRS", "/usr/local/share:/usr/share").split(":") + ["/usr/local/nvidia/share"]
    files = []
    for base in config + data:
        d = os.path.join(base, "vulkan", "icd.d")
        if os.path.isdir(d):
            files += [os.path.join(d, f) for f in sorted(os.listdir(d)) if f.endswith(".json")]
    seen, unique = set(), []
    for f in files:
        real = os.path.realpath(f)
        if real not in seen:
            seen.add(real)
            unique.append(f)
    return unique


def cmd_icd(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    written, lib_dirs, notes = [], [], []
    for i, path in enumerate(driver_files()):
        try:
            with open(path) as f:
                doc = json.load(f)
            library = doc["ICD"]["library_path"]
        except (OSError, ValueError, KeyError, TypeError) as e:
            notes.append({"file": path, "library": None, "resolved": None, "how": "unreadable: %s" % e})
            continue
        resolved, how = resolve_library(library, os.path.dirname(os.path.abspath(path)))
        if resolved and any(n["resolved"] and os.path.realpath(n["resolved"]) == os.path.realpath(resolved) for n in notes):
            how += "; the same library as an earlier file, so skipped"  # else the device would be listed twice
            notes.append({"file": path, "library": library, "resolved": None, "how": how})
            continue
        notes.append({"file": path, "library": library, "resolved": resolved, "how": how})
        if not resolved:
            continue
        doc["ICD"]["library_path"] = resolved
        target = os.path.join(out_dir, "%02d-%s" % (i, os.path.basename(path)))
        with open(target, "w") as f:
            json.dump(doc, f, indent=2)
        written.append(target)
        if os.path.dirname(resolved) not in lib_dirs:
            lib_dirs.append(os.path.dirname(resolved))
    with open(os.path.join(out_dir, "icd.json"), "w") as f:
        json.dump({"drivers": notes}, f, indent=2)
    for n in notes:
        print("icd: %s: %s -> %s (%s)" % (n["file"], n["library"], n["resolved"] or "skipped", n["how"]))
    if not notes:
        print("icd: no Vulkan driver file in the loader's folders or /usr/local/nvidia/share/vulkan/icd.d")
    print("VK_DRIVER_FILES=" + ":".join(written))
    print("LINESPACE_EXTRA_LIBRARY_PATH=" + ":".join(lib_dirs))
    return 0


# --- the report ------------------------------------------------------------------------------------

def read(path):
    try:
        with open(path, errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def status_of(rc):
    if rc == "-":
        return "skipped (time budget spent)"
    if rc in ("124", "137"):
        return "timed out"
    return "ok" if rc == "0" else "exit " + rc


def last_line(text):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return lines[-1].strip() if lines else ""


def library_origins(log, bundle):
    """Each object the loader mapped (from LD_DEBUG=files), where from, and who asked for it.  Only a
    Vulkan driver or layer (opened by the bundle's libvulkan) and what those need may come from the host."""
    bundle = os.path.realpath(bundle) if bundle else ""
    asked = {}  # name -> (how, by)
    loaded = []
    for line in log.splitlines():
        m = re.search(r"file=(\S+) \[\d+\];\s+(needed|dynamically loaded) by (\S+)", line)
        if m:
            asked.setdefault(m.group(1), (m.group(2), m.group(3)))
        m = re.search(r"calling init: (\S+)", line)
        if m:
            loaded.append(m.group(1))
    in_bundle = lambda p: bool(bundle) and os.path.realpath(p).startswith(bundle + os.sep)
    # Allowed from the host: what the bundle's libvulkan opened (drivers, layers), then what those need.
    allowed = {os.path.basename(n) for n, (how, by) in asked.items()
               if how == "dynamically loaded" and os.path.basename(by).startswith("libvulkan.so") and in_bundle(by)}
    grew = True
    while grew:
        more = {os.path.basename(n) for n, (how, by) in asked.items()
                if how == "needed" and not in_bundle(by) and os.path.basename(by) in allowed}
        grew = not more <= allowed
        allowed |= more
    rows, problems = [], []
    for path in loaded:
        name = os.path.basename(path)
        how, by = asked.get(path, asked.get(name, ("", "")))
        if in_bundle(path):
            origin = "bundle"
        elif name in allowed:
            origin = "host: Vulkan driver or layer" if how == "dynamically loaded" else "host: needed by " + os.path.basename(by)
        else:
            origin = "host (NOT from the bundle)"
            problems.append(path)
        rows.append({"path": path, "origin": origin, "asked": (how + " by " + by) if how else ""})
    return rows, problems


def cmd_report(logs, out, mode, seconds, bundle):
    steps = []
    for line in read(os.path.join(logs, "steps.tsv")).splitlines():
        f = line.split("\t")
        if len(f) == 7:
            steps.append(dict(zip(["id", "kind", "scene", "structures", "allowed_s", "seconds", "rc"], f)))
    problems = []
    report = {"mode": mode, "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
              "seconds": seconds, "bundle": read(os.path.join(bundle, "MANIFEST")).splitlines()[:2] if bundle else [],
              "device": None, "devices": [], "icd": [], "libraries": {}, "cross_checks": [], "bench": [], "rmse": [],
              "steps": []}
    icd = read(os.path.join(os.path.dirname(logs), "icd", "icd.json"))
    report["icd"] = json.loads(icd)["drivers"] if icd else []
    for s in steps:
        outp, errp = (read(os.path.join(logs, s["id"] + e)) for e in (".out", ".err"))
        s["status"] = status_of(s["rc"])
        s["error"] = "" if s["rc"] in ("0", "-") else last_line(errp)  # a skipped step's status says why
        report["steps"].append(s)
        if s["kind"] == "devices":
            try:
                report["devices"] = json.loads(outp)["devices"]
                report["device"] = next((d for d in report["devices"] if d.get("default")), None)
            except ValueError:
                problems.append("devices: " + (s["error"] or "no output"))
        elif s["kind"] == "libraries":
            rows, bad = library_origins(errp, bundle)
            report["libraries"] = {"objects": rows, "not_from_bundle": bad}
            if not rows:
                problems.append("libraries: the loader's log lists no object (" + s["status"] + ")")
            problems += ["library not from the bundle: " + p for p in bad]
        elif s["kind"] in ("candidates", "hits"):
            m = re.search(r"(\d+) compared, (\d+) mismatches", outp)
            first = [l.strip() for l in outp.splitlines() if l.startswith("  ")][:10]
            row = {"check": s["kind"], "scene": s["scene"], "structure": s["structures"], "status": s["status"],
                   "compared": int(m.group(1)) if m else None, "mismatches": int(m.group(2)) if m else None,
                   "first_mismatches": first, "seconds": float(s["seconds"]), "error": s["error"]}
            report["cross_checks"].append(row)
            if row["mismatches"]:
                problems.append("%s %s on %s: %d mismatches" % (s["kind"], s["structures"], s["scene"], row["mismatches"]))
            elif s["rc"] != "0" or m is None:
                problems.append("%s %s on %s: %s %s" % (s["kind"], s["structures"], s["scene"], s["status"], s["error"]))
        elif s["kind"] == "bench":
            try:
                results = json.loads(outp)["results"]
            except (ValueError, KeyError):
                results = []
                problems.append("bench %s on %s: %s %s" % (s["structures"], s["scene"], s["status"], s["error"]))
            for structure in s["structures"].split(","):
                r = next((r for r in results if r.get("structure") == structure), None)
                report["bench"].append({"scene": s["scene"], "structure": structure,
                                        "mrays_per_s": r["mrays_per_s"] if r else None,
                                        "bytes": r.get("bytes") if r else None, "status": s["status"] if not r else "ok"})
        elif s["kind"] == "rmse":
            if s["rc"] != "0":
                problems.append("rmse (%s): %s %s" % (s["id"], s["status"], s["error"]))
    # Ratios to this device's own F-BVH on the same scene and rays.
    for row in report["bench"]:
        base = next((r["mrays_per_s"] for r in report["bench"] if r["scene"] == row["scene"] and r["structure"] == "bvh"), None)
        row["ratio_vs_bvh"] = row["mrays_per_s"] / base if row["mrays_per_s"] and base else None
        row["paper_mrays_per_s"] = PAPER_MRAYS.get(row["structure"])
        row["paper_ratio_vs_bvh"] = PAPER_MRAYS[row["structure"]] / PAPER_MRAYS["bvh"] if row["structure"] in PAPER_MRAYS else None
    # rmse: the CPU's and the device's rows side by side; they should be equal.
    rows = {}
    for device in ("cpu", "gpu"):
        text = read(os.path.join(logs, "rmse-%s.json" % device))
        for r in (json.loads(text)["rows"] if text else []):
            rows.setdefault((r["structure"], r["start_bounce"]), {})[device] = r
    scene = next((s["scene"] for s in steps if s["kind"] == "rmse"), "")
    for (structure, k), pair in sorted(rows.items()):
        cpu, gpu = pair.get("cpu", {}).get("rmse"), pair.get("gpu", {}).get("rmse")
        same = cpu is not None and gpu is not None and cpu == gpu
        report["rmse"].append({"scene": scene, "structure": structure, "start_bounce": k, "rmse_cpu": cpu, "rmse_gpu": gpu,
                               "equal": same, "gpu_mrays_per_s": pair.get("gpu", {}).get("mrays_per_s")})
        if not same:
            problems.append("rmse of %s from bounce %s: cpu %s, gpu %s" % (structure, k, cpu, gpu))
    if not steps:
        problems.append("no step ran")
    report["problems"] = problems
    report["passed"] = not problems
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "gpu-check.json"), "w") as f:
        json.dump(report, f, indent=2)
    with open(os.path.join(out, "gpu-check.md"), "w") as f:
        f.write(markdown(report))
    print("gpu-check: %s; wrote %s/gpu-check.json and gpu-check.md" %
          ("passed" if not problems else "%d problem(s): %s" % (len(problems), problems[0]), out))
    return 0 if not problems else 1


def fmt(x, spec="%.2f"):
    return "—" if x is None else spec % x


def short(scene):
    return os.path.basename(scene).replace(".glb", "")


def markdown(r):
    d = r["device"] or {}
    lines = ["# gpu-check (%s)" % r["mode"], "",
             "- device: **%s** (%s, Vulkan %s), driver %s %s" % (d.get("name", "none"), d.get("type", "?"),
                                                             d.get("api_version", "?"), d.get("driver_name", "?"),
                                                             d.get("driver_info", "")),
             "- date: %s; %s s in all; %s" % (r["date"], r["seconds"], "; ".join(r["bundle"])),
             "- verdict: **%s**" % ("passed" if r["passed"] else "%d problem(s)" % len(r["problems"]))]
    lines += ["  - " + p for p in r["problems"][:20]]
    lines += ["", "## Vulkan drivers", "", "| driver file | library | used |", "|---|---|---|"]
    lines += ["| %s | %s | %s (%s) |" % (i["file"], i["library"], i["resolved"] or "no", i["how"]) for i in r["icd"]]
    libs = r["libraries"].get("objects", [])
    lines += ["", "## Libraries", "",
              "%d objects loaded; from the bundle: %d; from the host: %d (Vulkan drivers, layers and what they need); "
              "not from the bundle though they should be: %d." %
              (len(libs), sum(o["origin"] == "bundle" for o in libs), sum(o["origin"].startswith("host:") for o in libs),
               len(r["libraries"].get("not_from_bundle", [])))]
    lines += ["- " + p for p in r["libraries"].get("not_from_bundle", [])]
    lines += ["", "## Cross-checks: CPU against the device, bit for bit", "",
              "| check | scene | structure | compared | mismatches | status | s |", "|---|---|---|---:|---:|---|---:|"]
    for c in r["cross_checks"]:
        lines.append("| %s | %s | %s | %s | %s | %s | %.1f |" % (c["check"], short(c["scene"]), c["structure"],
                                                                 fmt(c["compared"], "%d"), fmt(c["mismatches"], "%d"),
                                                                 c["status"], c["seconds"]))
    firsts = [c for c in r["cross_checks"] if c["first_mismatches"]]
    for c in firsts:
        lines += ["", "First mismatches, %s %s on %s (where: CPU | device):" % (c["check"], c["structure"], short(c["scene"])), "", "```"]
        lines += c["first_mismatches"] + ["```"]
    lines += ["", "## Speed (linespace-gpu bench: diffuse rays, closest hit)", "",
              "MRays/s of this device and ratios to its own F-BVH on the same rays, beside the paper's GTX 1080 "
              "(Table 3: path tracing, averaged over its scenes, so only the ratios compare).", "",
              "| scene | structure | MRays/s | × F-BVH | paper MRays/s | paper × F-BVH |", "|---|---|---:|---:|---:|---:|"]
    for b in r["bench"]:
        lines.append("| %s | %s | %s | %s | %s | %s |" % (short(b["scene"]), b["structure"],
                                                          fmt(b["mrays_per_s"]) if b["mrays_per_s"] else b["status"],
                                                          fmt(b["ratio_vs_bvh"]), fmt(b["paper_mrays_per_s"], "%.1f"),
                                                          fmt(b["paper_ratio_vs_bvh"])))
    lines += ["", "## Renders: rmse from bounce 1 on the CPU and on the device", "",
              "| scene | structure | rmse, CPU | rmse, device | equal | device indirect MRays/s |", "|---|---|---:|---:|---|---:|"]
    for x in r["rmse"]:
        lines.append("| %s | %s | %s | %s | %s | %s |" % (short(x["scene"]), x["structure"], fmt(x["rmse_cpu"], "%.6g"),
                                                          fmt(x["rmse_gpu"], "%.6g"), "yes" if x["equal"] else "**no**",
                                                          fmt(x["gpu_mrays_per_s"])))
    lines += ["", "## Steps", "", "| step | allowed s | took s | status | last error line |", "|---|---:|---:|---|---|"]
    for s in r["steps"]:
        lines.append("| %s | %s | %s | %s | %s |" % (s["id"], s["allowed_s"], s["seconds"], s["status"],
                                                    s["error"].replace("|", "\\|")[:160]))
    return "\n".join(lines) + "\n"


def cmd_libs(log, bundle):
    rows, bad = library_origins(read(log), bundle)
    host = [r for r in rows if r["origin"] != "bundle"]
    print("libraries: %d objects, %d from the bundle, %d from the host as a Vulkan driver or layer needs them, "
          "%d from the host though the bundle should have them" % (len(rows), len(rows) - len(host), len(host) - len(bad), len(bad)))
    for r in rows:
        if r["origin"] != "bundle":
            print("  %s: %s (%s)" % (r["path"], r["origin"], r["asked"]))
    return 0 if rows and not bad else 1


def main(argv):
    if len(argv) == 3 and argv[1] == "icd":
        return cmd_icd(argv[2])
    if len(argv) == 4 and argv[1] == "libs":
        return cmd_libs(argv[2], argv[3])
    if len(argv) >= 4 and argv[1] == "report":
        opts = dict(zip(argv[4::2], argv[5::2]))
        return cmd_report(argv[2], argv[3], opts.get("--mode", "full"), opts.get("--seconds", "?"), opts.get("--bundle", ""))
    sys.stderr.write(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
