#!/usr/bin/env python3
"""Self-test for check_includes.py: runs it on tiny fake trees and checks exit codes/output."""
# named-paths: examples (the fake trees' files, for check_named_paths.py)
import os, subprocess, sys, tempfile

CHECKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "check_includes.py")

CASES = [
    ("clean tree", {"a.h": "", "a.cpp": '#include "a.h"\n#include "b.h"\n', "b.h": ""}, 0, "no cycle"),
    ("planted cycle", {"a.h": '#include "b.h"\n', "b.h": "", "b.cpp": '#include "a.h"\n'}, 1, "cycle"),
    ("dangling include", {"a.cpp": '#include "missing.h"\n'}, 1, "resolves to no file"),
    ("kernel include via ROOT/common",
     {"common/kernels/x.h": "", "gpu/shaders/trace.comp": '#include "kernels/x.h"\n'}, 0, "no cycle"),
    ("commented-out includes ignored",
     {"a.cpp": '// #include "gone.h"\n/* #include "gone.h"\n#include "gone2.h" */\n'}, 0, "no cycle"),
    ("a layer crossed: common/ includes cpu/",
     {"common/a.h": '#include "cpu/b.h"\n', "cpu/b.h": ""}, 1, "common/ may not include cpu/"),
    ("gpu/ includes a cpu/ header the design does not list",
     {"docs/design.md": "**cpu/'s public interface**: `cpu/pub.h`.\n", "cpu/pub.h": "", "cpu/inner.h": "",
      "gpu/g.cpp": '#include "cpu/pub.h"\n#include "cpu/inner.h"\n'}, 1, "not part of cpu/'s public interface"),
    ("gpu/ includes only listed cpu/ headers",
     {"docs/design.md": "**cpu/'s public interface**: `cpu/pub.h`.\n", "cpu/pub.h": "",
      "gpu/g.cpp": '#include "cpu/pub.h"\n'}, 0, "no cycle"),
    ("angle includes ignored, skipped folders", {"a.cpp": "#include <vector>\n",
                                                  "build/x.cpp": '#include "nope.h"\n'}, 0, "no cycle"),
    ("a folder named build below the top is checked", {"cpu/build/x.cpp": '#include "nope.h"\n'}, 1,
     "resolves to no file"),
]


def run(root, *extra):
    return subprocess.run([sys.executable, CHECKER, root, *extra], capture_output=True, text=True)


def main():
    passed, failed = 0, 0
    for name, files, want_rc, want_text in CASES:
        with tempfile.TemporaryDirectory() as root:
            for rel, body in files.items():
                os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
                with open(os.path.join(root, rel), "w") as f:
                    f.write(body)
            result = run(root)
        out = result.stdout + result.stderr
        ok = result.returncode == want_rc and want_text in out
        passed, failed = passed + ok, failed + (not ok)
        print(f"{'PASS' if ok else 'FAIL'}: {name}" + ("" if ok else f" (rc={result.returncode})\n{out}"))
    with tempfile.TemporaryDirectory() as root:  # usage errors and the built-in planted-cycle check
        for name, result, want_rc in [("missing ROOT -> exit 2", run(os.path.join(root, "nope")), 2),
                                      ("--planted-cycle-selftest on empty tree", run(root, "--planted-cycle-selftest"), 0)]:
            ok = result.returncode == want_rc
            passed, failed = passed + ok, failed + (not ok)
            print(f"{'PASS' if ok else 'FAIL'}: {name}" + ("" if ok else f" (rc={result.returncode})"))
    print(f"{passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
