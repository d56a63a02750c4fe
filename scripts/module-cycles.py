#!/usr/bin/env python3
"""List pairs of source files in the workspace that import each other.

    scripts/module-cycles.py [--all]

A file "imports" another when it names a path into it: `use crate::a::b`, `crate::a::b::f()`,
`super::x` or `self::x` resolving to that file's module. A module's own `mod` declarations
are not imports. By default a parent module (`mod.rs`, `lib.rs`) and its direct child are not
reported as a pair, since a child naming its parent's items (`super::Context`) while the
parent lists its children is how Rust declares a module tree; `--all` reports them too.
Exits 1 when a pair is found, so the check can run in CI.
"""

import os
import re
import sys

CRATES = ["pf-core", "pf-smooth", "pf-mpf", "pf-homotopy", "pf-dredge", "pf-epf", "pf-viz"]
PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE_GROUP = re.compile(r"\buse\s+(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)*)::\{([^;]*)\};", re.S)
COMMENT = re.compile(r"//[^\n]*")


def modules(src):
    """Map a module path (tuple of names) to its file, for one crate's src/."""
    out = {}
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(root, f), src)
            parts = rel[:-3].split(os.sep)
            if parts[-1] in ("mod", "lib", "main"):
                parts = parts[:-1]
            out[tuple(parts)] = os.path.join(root, f)
    return out


def resolve(mods, base, segments):
    """The file of the longest module prefix of `base + segments`."""
    path = list(base) + segments
    while path:
        if tuple(path) in mods:
            return mods[tuple(path)]
        path.pop()
    return None


def imports(mods, module, text):
    text = COMMENT.sub("", text)
    refs = []
    for m in USE_GROUP.finditer(text):
        head = [s for s in m.group(2).split("::") if s]
        for item in re.split(r",", m.group(3)):
            item = item.strip().split(" as ")[0].strip()
            first = re.split(r"::|\{", item)[0].strip()
            if first and first != "self":
                refs.append((m.group(1), head + [first]))
            elif first == "self":
                refs.append((m.group(1), head))
    for m in PATH.finditer(text):
        refs.append((m.group(1), [s for s in m.group(2).split("::") if s]))
    out = set()
    for kind, segs in refs:
        if kind == "crate":
            base = ()
        elif kind == "super":
            base = module[:-1]
            while segs and segs[0] == "super":
                base, segs = base[:-1], segs[1:]
        else:
            base = module
        f = resolve(mods, base, segs)
        if f is not None:
            out.add(f)
    return out


def main(argv):
    every = "--all" in argv
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    pairs = []
    for crate in CRATES:
        src = os.path.join(root, crate, "src")
        mods = modules(src)
        files = {f: m for m, f in mods.items()}
        graph = {}
        for module, f in mods.items():
            with open(f, encoding="utf-8") as fh:
                graph[f] = imports(mods, module, fh.read()) - {f}
        for a in sorted(graph):
            for b in sorted(graph[a]):
                if a < b and a in graph.get(b, ()):
                    ma, mb = files[a], files[b]
                    parent_child = ma == mb[:-1] or mb == ma[:-1]
                    if every or not parent_child:
                        pairs.append((os.path.relpath(a, root), os.path.relpath(b, root)))
    for a, b in pairs:
        print(f"{a} <-> {b}")
    return 1 if pairs else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
