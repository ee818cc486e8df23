#!/usr/bin/env python3
"""Fails when the modules of a workspace crate import each other in a cycle.

For every crate under the given directories (default: the workspace's), each
source file is a module; an edge a -> b is any path from `a` into `b`
(`use crate::b::..`, `super::b`, or an inline `crate::b::x`), tests at the end
of a file excluded. A parent declaring its children (`mod b;`) is not an
edge, using them is. The same is asked of the crate's top-level modules
(each folder taken whole: `perception/` -> `upe/` -> `step` -> `perception/`
is a cycle even when no two files import each other), so that shared stages
stay below the algorithms. Prints every cycle found and exits 1 if there is one.

    python3 scripts/module_cycles.py [crate_dir ...]
"""
import os
import re
import sys

PATH = re.compile(r"\b(crate|super|self)((?:::\w+)+)")
USE = re.compile(r"\buse\s+([^;]+);", re.S)
TEST_TAIL = re.compile(r"#\[cfg\(test\)\]\s*(pub(\(crate\))?\s+)?mod\s+\w+\s*\{", re.S)


def modules_of(src):
    """Module path (tuple) of each .rs file under src."""
    mods = {}
    for root, _, files in os.walk(src):
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(root, f), src)
            parts = rel[:-3].split(os.sep)
            if parts[-1] in ("mod", "lib", "main"):
                parts = parts[:-1]
            mods[tuple(parts)] = os.path.join(root, f)
    return mods


def expand(tree):
    """`a::{b, c::{d}}` -> ['a::b', 'a::c::d']."""
    tree = tree.strip()
    i = tree.find("{")
    if i < 0:
        return [tree]
    prefix, body = tree[:i], tree[i + 1 : tree.rfind("}")]
    parts, depth, cur = [], 0, ""
    for ch in body:
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
            continue
        depth += ch == "{"
        depth -= ch == "}"
        cur += ch
    parts.append(cur)
    out = []
    for p in parts:
        if p.strip():
            out += [prefix + q for q in expand(p)]
    return out


def strip_comments(text):
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


def edges_of(module, text, mods):
    text = strip_comments(text)
    m = TEST_TAIL.search(text)
    if m:
        text = text[: m.start()]
    paths = []
    for u in USE.findall(text):
        paths += expand(" ".join(u.split()))
    paths += [m.group(0) for m in PATH.finditer(text)]
    out = set()
    for p in paths:
        p = p.replace(" ", "")
        segs = p.split("::")
        if segs[0] == "crate":
            base, rest = (), segs[1:]
        elif segs[0] in ("super", "self"):
            base = module
            rest = segs
            while rest and rest[0] in ("super", "self"):
                if rest[0] == "super":
                    base = base[:-1]
                rest = rest[1:]
        else:
            # A child module named directly (`use occlusion::x` in a mod.rs).
            base, rest = module, segs
            if not rest or base + (rest[0],) not in mods:
                continue
        target = base
        for s in rest:
            if target + (s,) in mods:
                target = target + (s,)
            else:
                break
        out.add(target)
    out.discard(module)
    out.discard(())
    return out


def cycles(graph):
    """Strongly connected components with more than one module."""
    index, low, stack, on, out, n = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = n[0]
        n[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def main(dirs):
    bad = 0
    for d in dirs:
        src = os.path.join(d, "src")
        if not os.path.isdir(src):
            continue
        mods = modules_of(src)
        graph = {}
        for mod, path in mods.items():
            with open(path, encoding="utf-8") as f:
                graph[mod] = edges_of(mod, f.read(), mods)
        found = cycles(graph)
        # Folders taken whole: the first segment of each module path.
        top = {}
        for mod, targets in graph.items():
            if mod:
                top.setdefault(mod[:1], set()).update(t[:1] for t in targets if t and t[:1] != mod[:1])
        found = [(c, graph) for c in found] + [(c, top) for c in cycles(top) if c not in found]
        name = lambda m: "::".join(m) or "(root)"
        for comp, g in found:
            bad += 1
            print(f"{d}: module cycle: {' <-> '.join(name(m) for m in comp)}")
            for m in comp:
                deps = sorted(name(t) for t in g[m] if t in comp)
                print(f"    {name(m)} -> {', '.join(deps)}")
        if not found:
            print(f"{d}: {len(mods)} modules, no cycle")
    return 1 if bad else 0


if __name__ == "__main__":
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    # Every member of the workspace, as Cargo.toml lists them.
    with open(os.path.join(root, "Cargo.toml"), encoding="utf-8") as f:
        members = re.search(r"^members\s*=\s*\[([^\]]*)\]", f.read(), re.M)
    crates = re.findall(r'"([^"]+)"', members.group(1)) if members else []
    dirs = sys.argv[1:] or [os.path.join(root, c) for c in crates]
    sys.exit(main(dirs))
