#!/usr/bin/env python3
"""Check the project's quoted includes: every one resolves, and no module cycles.

Why: the project keeps its layers legible. A module (foo.h + foo.cpp, or a lone
file) may depend on lower layers, never back up through a chain that returns to
itself, so the module include graph must have no cycles. And a quoted include
must name a real file, looked up relative to the including file's folder, then
ROOT, then ROOT/common (the GLSL shaders are compiled with -I common), so the
tree reads the same way to a person as to the compiler.

The folders are layers too: common/ includes only common/, scenes/ only common/ and scenes/, cpu/
neither gpu/ nor validate/, gpu/ not validate/; and gpu/ and validate/ include from cpu/ only the
headers that ROOT/docs/design.md lists as cpu/'s public interface (its paragraph that starts with
"**cpu/'s public interface**"), so the design says what the back ends share and this keeps it true.

Usage: check_includes.py ROOT [--planted-cycle-selftest]
  Exit 0 and a one-line summary when clean, 1 with every problem otherwise,
  2 on bad usage. With --planted-cycle-selftest it checks ROOT as usual and
  also plants a two-module cycle in a scratch tree (ROOT is never touched) to
  prove the cycle detector fires; exit 1 if it does not.
"""
import os, re, sys, tempfile

SOURCE_EXTS = (".h", ".hpp", ".cpp", ".cc", ".glsl", ".comp")
SKIP_DIRS = {"build", "out", "assets"}  # at the top only: build outputs, renders, assembled scenes
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')


def source_files(root):
    for folder, dirs, files in os.walk(root):
        top = os.path.samefile(folder, root)
        dirs[:] = sorted(d for d in dirs if not (top and d in SKIP_DIRS) and not d.startswith("."))
        for name in sorted(files):
            if name.endswith(SOURCE_EXTS):
                yield os.path.relpath(os.path.join(folder, name), root).replace(os.sep, "/")


def quoted_includes(path):
    """Yield (line_number, target) for quoted includes outside comments."""
    in_block = False
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            code, rest = "", line
            while rest:  # strip /* */ and // comments (good enough for includes)
                if in_block:
                    end = rest.find("*/")
                    in_block, rest = end < 0, ("" if end < 0 else rest[end + 2:])
                    continue
                start, slashes = rest.find("/*"), rest.find("//")
                if slashes >= 0 and (start < 0 or slashes < start):
                    code, rest = code + rest[:slashes], ""
                elif start >= 0:
                    code, rest, in_block = code + rest[:start], rest[start + 2:], True
                else:
                    code, rest = code + rest, ""
            match = INCLUDE_RE.match(code)
            if match:
                yield number, match.group(1)


def resolve(root, including, target):
    for base in (os.path.dirname(including), "", "common"):
        candidate = os.path.normpath(os.path.join(base, target)).replace(os.sep, "/")
        if not candidate.startswith("../") and os.path.isfile(os.path.join(root, candidate)):
            return candidate
    return None


def module_of(rel):
    stem, ext = os.path.splitext(rel)
    return stem if ext in (".h", ".hpp", ".cpp", ".cc") else rel


def strongly_connected(graph):
    """Tarjan's algorithm, iterative; returns components with more than one node."""
    index, low, on_stack, stack, found, counter = {}, {}, set(), [], [], 0
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter; counter += 1
        stack.append(start); on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter; counter += 1
                    stack.append(child); on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop(); on_stack.discard(member); component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(component)
    return found


def cycle_in(component, graph):
    """One concrete cycle through the component's smallest module (BFS back to it)."""
    start = min(component)
    parent, queue = {start: None}, [start]
    for node in queue:
        for child in sorted(graph[node]):
            if child == start:
                path = []
                while node is not None:
                    path.append(node); node = parent[node]
                return path[::-1] + [start]
            if child in component and child not in parent:
                parent[child] = node; queue.append(child)
    raise AssertionError("component without a cycle")


# Which top-level folders a folder's files may include (tests/ and others: any).
ALLOWED = {
    "common": {"common"},
    "scenes": {"common", "scenes"},
    "cpu": {"common", "scenes", "cpu"},
    "gpu": {"common", "scenes", "cpu", "gpu"},
    "validate": {"common", "scenes", "cpu", "gpu", "validate"},
}
PUBLIC_USERS = {"gpu", "validate"}


def cpu_public_interface(root):
    """The cpu/ headers docs/design.md lists as the public interface (None: no design to read)."""
    path = os.path.join(root, "docs", "design.md")
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as f:
        text = f.read()
    start = text.find("**cpu/'s public interface**")
    if start < 0:
        return set()
    end = text.find("\n\n", start)
    return set(re.findall(r"`(cpu/[A-Za-z0-9_/]+\.h)`", text[start:end if end >= 0 else len(text)]))


def layer_problem(rel, found, public):
    """Why the include rel -> found crosses the layers wrongly, or None."""
    source, target = rel.split("/")[0], found.split("/")[0]
    if source in ALLOWED and target in ALLOWED and target not in ALLOWED[source]:
        return f"{source}/ may not include {target}/"
    if source in PUBLIC_USERS and target == "cpu" and public is not None and found not in public:
        return "not part of cpu/'s public interface (docs/design.md)"
    return None


def check(root):
    """Return (problems, summary) for the tree at root."""
    files = list(source_files(root))
    problems, graph, edge_site = [], {}, {}
    public = cpu_public_interface(root)
    for rel in files:
        graph.setdefault(module_of(rel), set())
    for rel in files:
        for number, target in quoted_includes(os.path.join(root, rel)):
            found = resolve(root, rel, target)
            if found is None:
                problems.append(f'{rel}:{number}: quoted include "{target}" resolves to no file')
                continue
            why = layer_problem(rel, found, public)
            if why:
                problems.append(f'{rel}:{number}: includes "{found}": {why}')
            a, b = module_of(rel), module_of(found)
            if a != b and b in graph:  # b not in graph: a resolvable file we do not scan
                graph[a].add(b)
                edge_site.setdefault((a, b), f"{rel}:{number}")
    for component in strongly_connected(graph):
        path = cycle_in(component, graph)
        steps = [f"{a} ({edge_site[a, b]})" for a, b in zip(path, path[1:])]
        problems.append(f"module include cycle ({len(component)} modules): "
                        + " -> ".join(steps + [path[-1]]))
    edges = sum(len(targets) for targets in graph.values())
    summary = f"{len(files)} files, {len(graph)} modules, {edges} edges"
    return problems, summary


def planted_cycle_detected():
    """Plant a.h -> b.h -> a.h in a scratch tree and confirm check() reports it."""
    with tempfile.TemporaryDirectory() as scratch:
        for name, body in {"a.h": '#include "b.h"\n', "b.h": "", "b.cpp": '#include "a.h"\n'}.items():
            with open(os.path.join(scratch, name), "w") as f:
                f.write(body)
        return any("cycle" in p for p in check(scratch)[0])


def main(argv):
    args = [a for a in argv if a != "--planted-cycle-selftest"]
    if len(args) != 1 or args[0].startswith("-") or not os.path.isdir(args[0]):
        print("usage: check_includes.py ROOT [--planted-cycle-selftest]  (ROOT must be a folder)",
              file=sys.stderr)
        return 2
    problems, summary = check(args[0])
    if "--planted-cycle-selftest" in argv and not planted_cycle_detected():
        problems.append("planted-cycle selftest: a planted a.h <-> b.cpp cycle was NOT reported")
    if problems:
        print("\n".join(problems))
        print(f"{summary}: {len(problems)} problem(s)")
        return 1
    print(f"{summary}: no cycle, every quoted include resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
