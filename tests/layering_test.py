#!/usr/bin/env python3
"""Checks the library's layering from its #include lines and its function names.

A unit is a header with its implementation (lib/src/gi/march.h and march.cpp); a public header
(lib/include/ssgi/X.h) belongs to the unit whose source includes it first, as its own header, and
is a unit of its own when none does (types only). Fails, with one line per finding, when:
  - an include of lib/src or cli names a library header without its wing ("march.h" instead of
    "gi/march.h"), so that only the library's source root need be on the include path;
  - a unit includes a unit of a higher wing (WINGS below: io, then gi, then the pipeline, the
    sequence processor, run, the options; compare, reference and the plan beside the pipeline);
  - the units include each other in a circle;
  - a public header includes anything but another public header (ssgi/...) or a system header:
    a header of lib/src would have to be installed with it;
  - a unit defines a free function (at namespace scope, in an anonymous namespace or not) of a
    name that a unit it includes, directly or through others, defines too, and either calls it
    where the other unit's header declares that name (the call reads as the other unit's), or
    the two definitions call a function of the other unit alike (one job written twice under
    one name: a reader, or grep, takes the one for the other).
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


INCLUDE_ANY = re.compile(r'^\s*#\s*include\s+([<"])([^>"]+)[>"]')
TOKEN = re.compile(r"[A-Za-z_]\w*|::|->|\d[\w.']*|\S")
IDENTIFIER = re.compile(r"[A-Za-z_]\w*$")
NOT_A_NAME = {"if", "for", "while", "switch", "return", "catch", "sizeof", "alignof", "decltype",
              "static_assert", "new", "delete", "throw", "noexcept", "alignas", "operator"}


def code_tokens(text):
    """The tokens of C++ source without its comments, literals' contents and preprocessor lines."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            out.append(" ")
            i = n if j < 0 else j + 2
        elif text.startswith('R"', i) and not (i > 0 and (text[i - 1].isalnum() or
                                                          text[i - 1] == "_")):
            delimiter = text[i + 2:text.find("(", i)]
            i = text.find(")" + delimiter + '"', i) + len(delimiter) + 2
            out.append('""')
        elif c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):  # not 1'000
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        elif c == "#" and text[text.rfind("\n", 0, i) + 1:i].strip() == "":
            while True:  # the directive, with its continuation lines
                j = text.find("\n", i)
                if j < 0 or text[j - 1] != "\\":
                    i = n if j < 0 else j
                    break
                i = j + 1
        else:
            out.append(c)
            i += 1
    return TOKEN.findall("".join(out))


def function_name(statement):
    """The name of the function a statement declares or defines (before its ';' or body), else
    None: the identifier before its first parenthesis, past any template header."""
    s = statement
    if s[:1] == ["template"]:
        depth = 0
        for k, t in enumerate(s[1:], 1):
            depth += {"<": 1, ">": -1}.get(t, 0)
            if depth <= 0:
                s = s[k + 1:]
                break
    if "(" not in s or any(k in s for k in ("class", "struct", "union", "enum", "namespace")):
        return None
    p = s.index("(")
    if p == 0 or "=" in s[:p] or "using" in s[:p]:
        return None  # a variable, a lambda, an alias
    name = s[p - 1]
    if (not IDENTIFIER.match(name) or name in NOT_A_NAME or name.isupper() or
            (p >= 2 and s[p - 2] == "~")):
        return None  # an operator, a destructor, a macro (HWY_EXPORT(...))
    if p >= 2 and s[p - 2] == "::":
        return "::" + name  # a member defined outside its class: Class::name
    return name


def in_constructor_list(statement):
    """Whether a statement is a constructor's head up to its member initialisers: X(...) : a(b)."""
    depth, closed = 0, False
    for t in statement:
        if t == "(":
            depth += 1
        elif t == ")":
            depth -= 1
            closed = closed or depth == 0
        elif t == ":" and depth == 0 and closed:
            return True
    return False


def functions(tokens):
    """(definitions, declarations) of a file's tokens: definitions as (name, is free, first and
    last token of the body), where free means at namespace scope, not in a class; declarations
    as the names of functions declared at namespace scope without a body."""
    definitions, declarations, scopes, start, i = [], set(), [], 0, 0
    while i < len(tokens):
        t, scope, statement = tokens[i], scopes[-1] if scopes else "namespace", tokens[start:i]
        if t == ";":
            name = function_name(statement) if scope == "namespace" else None
            if name and not name.startswith("::"):
                declarations.add(name)
            start = i + 1
        elif t == "}":
            if scopes:
                scopes.pop()
            start = i + 1
        elif t == ":" and statement in (["public"], ["private"], ["protected"]):
            start = i + 1
        elif t == "{":
            depth, end = 0, i
            for end in range(i, len(tokens)):
                depth += {"{": 1, "}": -1}.get(tokens[end], 0)
                if depth == 0:
                    break
            if statement[-1:] == ["namespace"] or statement[:1] in (["namespace"], ["extern"]) or \
                    statement[:2] == ["inline", "namespace"]:
                scopes.append("namespace")
                start = i + 1
            elif any(k in statement for k in ("class", "struct", "union")) and \
                    "(" not in statement and "=" not in statement:
                scopes.append("class")
                start = i + 1
            elif in_constructor_list(statement) and statement and IDENTIFIER.match(statement[-1]):
                i = end + 1  # a member's braced initialiser, x{...}: the statement goes on
                continue
            else:
                name = function_name(statement) if statement else None
                if name:
                    definitions.append((name.lstrip(":"), scope == "namespace" and
                                        not name.startswith("::"), i + 1, end))
                i = start = end + 1  # a body, an initialiser or an enum: skipped whole
                continue
        i += 1
    return definitions, declarations


def called(tokens, first=0, last=None, bare=False):
    """The names called in tokens[first:last]; bare: not as a member (x.f(), p->f()) or
    qualified (std::f())."""
    last = len(tokens) - 1 if last is None else min(last, len(tokens) - 1)
    return {tokens[k] for k in range(max(first, 1), last)
            if tokens[k + 1] == "(" and IDENTIFIER.match(tokens[k]) and
            not (bare and tokens[k - 1] in (".", "->", "::"))}


def namesake_findings(files, unit, edges, root):
    """Free functions of one unit that share a name with a function of a unit it includes."""
    parsed = {}  # unit -> list of (path, tokens, definitions, declarations of a header)
    for rel, path, is_public in files:
        with open(path, encoding="utf-8") as f:
            tokens = code_tokens(f.read())
        definitions, declarations = functions(tokens)
        parsed.setdefault(unit(rel, is_public), []).append(
            (path, tokens, definitions, declarations if rel.endswith(".h") else set()))

    def below(u):
        seen, todo = set(), [u]
        while todo:
            for v in edges.get(todo.pop(), ()):
                if v not in seen and v != u:
                    seen.add(v)
                    todo.append(v)
        return seen

    findings = []
    for u in sorted(parsed):
        bare_calls = set().union(*(called(t, bare=True) for _, t, _, _ in parsed[u]))
        for v in sorted(below(u) & parsed.keys()):
            theirs = [(t, d) for _, t, ds, _ in parsed[v] for d in ds]
            their_names = {d[0] for _, d in theirs}
            their_declarations = set().union(*(dc for _, _, _, dc in parsed[v]))
            for path, tokens, definitions, _ in parsed[u]:
                for name, free, first, last in definitions:
                    if not free or name not in their_names:
                        continue
                    where = f"{os.path.relpath(path, root)}: {name}() of {u} and {name}() of {v}"
                    if name in their_declarations and name in bare_calls:
                        findings.append(f"{where}, which {u} includes, have one name: {u} calls "
                                        f"its own where {v}'s header declares the other")
                        continue
                    mine = called(tokens, first, last)
                    alike = set()
                    for t, (n, _, a, b) in theirs:
                        if n == name:
                            alike |= mine & called(t, a, b) & (their_names | their_declarations)
                    alike.discard(name)
                    if alike:
                        findings.append(f"{where}, which {u} includes, have one name and both "
                                        f"call {', '.join(sorted(alike))} of {v}: name each for "
                                        "what it does")
    return findings


def public_header_findings(public, src, root):
    """Includes of a public header that are neither public headers nor system headers."""
    wings = {n for n in os.listdir(src) if os.path.isdir(os.path.join(src, n))}
    findings = []
    for d, _, names in os.walk(public):
        for n in sorted(names):
            path = os.path.join(d, n)
            with open(path, encoding="utf-8") as f:
                for line in f:
                    m = INCLUDE_ANY.match(line)
                    if not m:
                        continue
                    quote, inc = m.groups()
                    if inc.startswith("ssgi/"):
                        continue
                    if quote == '"' or inc.split("/")[0] in wings or \
                            os.path.exists(os.path.join(src, inc)):
                        close = ">" if quote == "<" else quote
                        findings.append(f"{os.path.relpath(path, root)}: #include {quote}{inc}"
                                        f"{close} is neither a public header (ssgi/...) nor a "
                                        "system header")
    return findings


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

    findings += public_header_findings(public, src, root)
    findings += namesake_findings(files, unit, edges, root)

    for f in findings:
        print("layering_test: " + f, file=sys.stderr)
    if findings:
        return 1
    print(f"layering_test: {len(edges)} units, {sum(map(len, edges.values()))} includes between "
          "them, no circle, none upwards; public headers include only public and system "
          "headers; "
          "no free function named as a function of a unit it includes and called where that one "
          "is declared, or built alike")
    return 0


if __name__ == "__main__":
    sys.exit(main())
