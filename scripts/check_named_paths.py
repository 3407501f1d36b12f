#!/usr/bin/env python3
"""Check that every project path named in the sources' comments and in the docs exists.

Why: comments and docs point a reader at files ("the weights: cpu/trace/trace_rays.h"). When a
file moves into another folder, a pointer that names its old place sends the reader nowhere, and
nothing else notices: the compiler reads includes, not comments.

A named path is a token that starts with one of the project's top folders and ends in a source or
script extension, e.g. `common/kernels/hit.h` or `scripts/setup.sh`; it must exist below ROOT.
Files may name paths that are examples on purpose by carrying the marker "named-paths: examples"
(the include checker's self-test plants files like `cpu/pub.h`).

Usage: check_named_paths.py ROOT [--selftest]
  Exit 0 and a one-line summary when every named path exists, 1 listing each one that does not
  (file:line path), 2 on bad usage. With --selftest it also checks a scratch tree with one stale
  and one good pointer (ROOT is never touched) and fails unless exactly the stale one is reported.
"""
import os, re, sys, tempfile

TOP = ("common", "cpu", "gpu", "scenes", "validate", "tests", "scripts", "cmake", "docs")
EXTS = ("h", "hpp", "cpp", "glsl", "comp", "sh", "py", "cmake", "md")
PATH_RE = re.compile(r"(?<![\w/.-])((?:%s)/[A-Za-z0-9_./-]+\.(?:%s))(?![\w])" % ("|".join(TOP), "|".join(EXTS)))
READ_EXTS = (".h", ".hpp", ".cpp", ".glsl", ".comp", ".sh", ".py", ".cmake", ".md", ".txt")
SKIP_DIRS = {"build", "out", "assets", ".git"}  # at the top only
MARKER = "named-paths: " + "examples"  # split, so this file does not mark itself


def files_to_read(root):
    for folder, dirs, files in os.walk(root):
        if folder == root:
            dirs[:] = [d for d in dirs if d not in SKIP_DIRS]
        for name in files:
            if name.endswith(READ_EXTS):
                yield os.path.join(folder, name)


def stale_paths(root):
    stale, named = [], 0
    for path in sorted(files_to_read(root)):
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except (UnicodeDecodeError, OSError):
            continue
        if MARKER in text:
            continue
        for number, line in enumerate(text.splitlines(), 1):
            for ref in PATH_RE.findall(line):
                named += 1
                ref = ref.rstrip(".")
                # Relative to the repository root, or (in docs) to the naming file's folder.
                if not (os.path.exists(os.path.join(root, ref)) or
                        os.path.exists(os.path.join(os.path.dirname(path), ref))):
                    stale.append("%s:%d %s" % (os.path.relpath(path, root), number, ref))
    return stale, named


def selftest():
    with tempfile.TemporaryDirectory() as scratch:
        os.makedirs(os.path.join(scratch, "cpu", "trace"))
        with open(os.path.join(scratch, "cpu", "trace", "here.h"), "w") as f:
            f.write("// moved: see cpu/gone.h; still here: cpu/trace/here.h\n")
        stale, _ = stale_paths(scratch)
        return stale == ["cpu/trace/here.h:1 cpu/gone.h"], stale


def main(argv):
    if len(argv) not in (2, 3) or (len(argv) == 3 and argv[2] != "--selftest") or not os.path.isdir(argv[1]):
        print("usage: check_named_paths.py ROOT [--selftest]", file=sys.stderr)
        return 2
    root = os.path.abspath(argv[1])
    if len(argv) == 3:
        ok, got = selftest()
        if not ok:
            print("check_named_paths: the self-test's stale pointer was not reported alone: %r" % got)
            return 1
    stale, named = stale_paths(root)
    if stale:
        print("check_named_paths: %d named path(s) do not exist:" % len(stale))
        for s in stale:
            print("  " + s)
        return 1
    print("check_named_paths: %d named paths, all exist" % named)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
