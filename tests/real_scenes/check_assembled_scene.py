#!/usr/bin/python3
"""ctest: assembles the FIREPLACE-like scene into a temporary folder and checks it from the outside:
the counts our loader reports (linespace-cpu build --json) against the paper's (typed in below) and
against the glTF file's own accessors, that CREDITS.md names every furniture model in the file with a
creator and a licence, and that a second run skips the up-to-date scene.  Fails (exit 1), never skips,
when the source packages are missing: run scripts/assemble-scenes.sh --small (or scripts/setup.sh)."""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile

PAPER = {"objects": 49, "triangles": 143_000}  # FIREPLACE ROOM, Table 2 of the paper


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def glb_json(path):
    with open(path, "rb") as f:
        magic, version, length = struct.unpack("<4sII", f.read(12))
        if magic != b"glTF" or version != 2 or length != os.path.getsize(path):
            fail("%s: not a glTF 2.0 binary of the size its header gives" % path)
        chunk_length, chunk_type = struct.unpack("<I4s", f.read(8))
        if chunk_type != b"JSON":
            fail("%s: first chunk is not JSON" % path)
        return json.loads(f.read(chunk_length))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cpu", required=True)
    ap.add_argument("--assembler", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="linespace_real_scenes_") as out:
        run = subprocess.run(["/usr/bin/python3", args.assembler, "--out", out, "fireplace"],
                             capture_output=True, text=True)
        print(run.stdout + run.stderr, end="")
        if run.returncode != 0:
            fail("the assembler exited %d (sources missing? run scripts/assemble-scenes.sh --small)" % run.returncode)
        scene = os.path.join(out, "fireplace.glb")

        build = subprocess.run([args.cpu, "build", "--scene", scene, "--structure", "2l-bvh", "--json"],
                               capture_output=True, text=True)
        if build.returncode != 0:
            fail("linespace-cpu build exited %d: %s" % (build.returncode, build.stderr.strip()))
        loaded = json.loads(build.stdout)
        print("loader: %d objects, %d instances, %d triangles" % (loaded["objects"], loaded["instances"], loaded["triangles"]))

        # The paper's counts, within 10 %.
        for key, target in PAPER.items():
            if abs(loaded[key] - target) > 0.1 * target:
                fail("%s: %d, more than 10 %% from the paper's %d" % (key, loaded[key], target))

        # The file's own view: mesh-bearing nodes, unique meshes, index counts of triangle primitives.
        doc = glb_json(scene)
        mesh_nodes = [n for n in doc["nodes"] if "mesh" in n]
        tris_per_mesh = [sum(doc["accessors"][p["indices"]]["count"] // 3 for p in m["primitives"]) for m in doc["meshes"]]
        file_counts = {"objects": len({n["mesh"] for n in mesh_nodes}), "instances": len(mesh_nodes),
                       "triangles": sum(tris_per_mesh[n["mesh"]] for n in mesh_nodes)}
        for key, value in file_counts.items():
            if loaded[key] != value:
                fail("%s: the loader reports %d, the file holds %d" % (key, loaded[key], value))
        if not any(m.get("emissiveFactor") for m in doc["materials"]):
            fail("no emissive material: the scene has no light")
        if not any(n.get("camera") is not None and doc["cameras"][n["camera"]]["type"] == "perspective" for n in doc["nodes"]):
            fail("no perspective camera node")

        # Every furniture mesh is credited, with a creator and a licence, on one CREDITS.md line.
        credits = open(os.path.join(out, "CREDITS.md")).read().splitlines()
        furniture = [m["name"] for m in doc["meshes"] if not m["name"].startswith("room/")]
        if len(furniture) < PAPER["objects"] * 0.8:
            fail("only %d furniture meshes" % len(furniture))
        for name in furniture:
            lines = [l for l in credits if l.startswith("- `%s` " % name)]
            if not lines:
                fail("CREDITS.md does not name %s" % name)
            if " by " not in lines[0] or "licence CC" not in lines[0]:
                fail("CREDITS.md gives %s no creator or no CC licence: %s" % (name, lines[0]))

        # Idempotent: a second run leaves the file alone.
        before = os.stat(scene).st_mtime_ns
        again = subprocess.run(["/usr/bin/python3", args.assembler, "--out", out, "fireplace"], capture_output=True, text=True)
        if again.returncode != 0 or "up to date" not in again.stdout or os.stat(scene).st_mtime_ns != before:
            fail("a second run did not skip the up-to-date scene: " + again.stdout + again.stderr)
    print("ok")


if __name__ == "__main__":
    main()
