#!/usr/bin/env python3
"""Checks the library's layering from its #include lines.

A unit is a header with its implementation (lib/src/gi/march.h and march.cpp); a public header
(lib/include/ssgi/X.h) belongs to the unit whose source includes it first, as its own header, and
is a unit of its own when none does (types only). Fails, with one line per finding, when:
  - an include of lib/src or cli names a library header without its wing ("march.h" instead of
    "gi/march.h"), so that only the library's source root need be on the include path;
  - a unit includes a unit of a higher wing (WINGS below: io, then gi, then the pipeline, the
    sequence processor, run, the options; compare, reference and the plan beside the pipeline);
  - the units include each other in a circle;
  - a public header includes a header of lib/src (an installed program has none of them).
Usage: layering_test.py [PROJECT_SOURCE_DIR]
"""
import os
import re
import sys

# A unit may include units of its own rank or below. Ranks of the units at lib/src's root are
# given one by one; a folder's units share the folder's rank.
WINGS = {
    "parallel": 0, "buffers": 0, "throw": 0, "image": 0, "log": 0, "settings": 0,
    "version": 0,
    "io": 1,
    "gi": 2,
    "compare": 3, "reference": 3, "plan": 3,
    "pipeline": 4,
    "sequence_processor": 5,
    "run": 6, "memory": 6, "memory_plan": 6, "threads": 6, "simd": 6,
    "options": 7,
}

INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def includes(path):
    with open(path, encoding="utf-8") as f:
        return [m.group(1) for m in map(INCLUDE.match, f) if m]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    src = os.path.join(root, "lib", "src")
    public = os.path.join(root, "lib", "include")
    findings = []

    files = []  # (path relative to its include root, absolute path, is public)
    for base, is_public in ((src, False), (public, True)):
        for d, _, names in os.walk(base):
            for n in sorted(names):
                if n.endswith((".h", ".cpp")):
                    p = os.path.join(d, n)
                    files.append((os.path.relpath(p, base), p, is_public))
    headers = {rel for rel, _, _ in files if rel.endswith(".h")}
    bare = {os.path.basename(h): h for h in headers if not h.startswith("ssgi/")}

    def unit_of_source(rel):
        return os.path.splitext(rel)[0]

    # The public headers' units: the source that includes one first, as its own header.
    owner = {}
    for rel, path, is_public in files:
        if not is_public and rel.endswith(".cpp"):
            first = includes(path)[:1]
            if first and first[0].startswith("ssgi/"):
                owner[first[0]] = unit_of_source(rel)

    def unit(rel, is_public):
        if is_public:
            return owner.get(rel, os.path.splitext(rel)[0])
        return unit_of_source(rel)

    def rank(u):
        head = u.split("/")[0]
        return WINGS.get(head)

    edges = {}
    for rel, path, is_public in files:
        u = unit(rel, is_public)
        edges.setdefault(u, set())
        for inc in includes(path):
            if inc.startswith("hwy/") or inc.endswith(".cpp"):
                continue  # Highway's per-target re-inclusion of the file itself
            if inc in headers:
                v = unit(inc, inc.startswith("ssgi/"))
            elif inc == "ssgi/version.h":
                v = "version"
            else:
                if inc in bare and bare[inc] != inc:
                    findings.append(f"{os.path.relpath(path, root)}: #include \"{inc}\" does not "
                                    f"name its wing: \"{bare[inc]}\"")
                continue
            if is_public and not inc.startswith("ssgi/"):
                findings.append(f"{os.path.relpath(path, root)}: the public header includes "
                                f"\"{inc}\", a header of lib/src")
            if v == u:
                continue
            edges[u].add(v)
            ru, rv = rank(u), rank(v)
            if ru is not None and rv is not None and rv > ru:
                findings.append(f"{os.path.relpath(path, root)}: {u} (wing rank {ru}) includes "
                                f"{v} (rank {rv}), a wing above it")

    # The CLI names the library's internal headers by their wing too.
    for d, _, names in os.walk(os.path.join(root, "cli")):
        for n in sorted(names):
            p = os.path.join(d, n)
            if n.endswith((".h", ".cpp")):
                for inc in includes(p):
                    if inc in bare and bare[inc] != inc and not os.path.exists(os.path.join(d, inc)):
                        findings.append(f"{os.path.relpath(p, root)}: #include \"{inc}\" does not "
                                        f"name its wing: \"{bare[inc]}\"")

    # Circles: Tarjan's strongly connected components of the unit graph.
    index, low, on_stack, stack, circles = {}, {}, set(), [], []
    counter = [0]

    def visit(u):
        index[u] = low[u] = counter[0]
        counter[0] += 1
        stack.append(u)
        on_stack.add(u)
        for v in sorted(edges.get(u, ())):
            if v not in index:
                visit(v)
                low[u] = min(low[u], low[v])
            elif v in on_stack:
                low[u] = min(low[u], index[v])
        if low[u] == index[u]:
            component = []
            while True:
                v = stack.pop()
                on_stack.discard(v)
                component.append(v)
                if v == u:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    sys.setrecursionlimit(10000)
    for u in sorted(edges):
        if u not in index:
            visit(u)
    for c in circles:
        findings.append("units include each other in a circle: " + ", ".join(c))

    for f in findings:
        print("layering_test: " + f, file=sys.stderr)
    if findings:
        return 1
    print(f"layering_test: {len(edges)} units, {sum(map(len, edges.values()))} includes between "
          "them, no circle, none upwards")
    return 0


if __name__ == "__main__":
    sys.exit(main())
