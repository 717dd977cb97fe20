#!/usr/bin/env python3
"""The architecture drawn from organtex's imports: which source file names
an item of which other file, whether any two files reach each other (a
loop), whether a file imports from a floor above its own, and which files
are over the size limit.

Every `crate::`, `super::` and `self::` path of the library's production
code is resolved to the file that defines the item, following re-exports
(`pub use`) of `mod.rs` files to the file behind them; a module brought
into scope by `use` is followed where the code names items through it.
`mod` declarations and re-exports are a module's table of contents, not
arrows. `#[cfg(test)]` modules are left out (tests may reach anywhere).

    tools/architecture.py            print the floors, the arrows' summary
    tools/architecture.py --check    exit 1 on a loop, an upward arrow or
                                     a file over --max-lines (1000)
    tools/architecture.py --dot      the file graph for Graphviz

Floors, top to bottom (an arrow may only point to the same floor or one
below; a floor's modules may import each other, without loops). Written by
hand, as docs/architecture.md explains them:
"""

import argparse
import re
import sys
from collections import defaultdict
from pathlib import Path

FLOORS = [
    ["main", "cli", "bench"],
    ["app"],
    ["bake"],
    ["render"],
    ["runtime"],
    ["scene"],
    ["solid"],
    ["db"],
    ["synth", "blend"],
    ["unwrap", "tetra", "segment"],
    ["mesh"],
    ["linalg", "raster", "memory", "progress", "rng", "atomic", "digest", "fuzz", "error", "lib"],
]
# The fuzz targets reach every parser; they sit beside the library's root,
# which names every module.
EXEMPT_FROM_FLOORS = {"fuzz", "lib"}

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip(text):
    """Source without comments, string and char literals (kept as blanks so
    line numbers hold), and without #[cfg(test)] modules."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    out.append("\n" if text[i] == "\n" else "")
                    i += 1
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and not re.match(r"[A-Za-z0-9_]", text[i - 1] if i else " "):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            end = n if end < 0 else end + 1 + len(hashes)
            out.append('""' + "\n" * text.count("\n", i, end))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j + 1
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", text[i:i + 4]) or (c == "'" and text.startswith("'\\u{", i)):
            j = text.find("'", i + 1 if text[i + 1] != "\\" else i + 3)
            out.append("' '")
            i = j + 1
        else:
            out.append(c)
            i += 1
    code = "".join(out)
    # Drop #[cfg(test)] mod NAME { ... } by brace matching.
    while True:
        m = re.search(r"#\[cfg\(test\)\]\s*(pub\s+)?mod\s+" + IDENT + r"\s*\{", code)
        if not m:
            break
        depth, j = 1, m.end()
        while j < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[j], 0)
            j += 1
        code = code[:m.start()] + "\n" * code.count("\n", m.start(), j) + code[j:]
    return code


def expand_use(tree):
    """`a::{b, c::{d, e as f}}` -> [(['a','b'], 'b'), (['a','c','d'], 'd'), (['a','c','e'], 'f')]."""
    tree = re.sub(r"\s+", "", tree)
    results = []

    def walk(prefix, s):
        # split s at top-level commas
        parts, depth, cur = [], 0, ""
        for ch in s:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
            else:
                cur += ch
        if cur:
            parts.append(cur)
        for p in parts:
            if not p:
                continue
            brace = p.find("{")
            if brace >= 0:
                head = p[:brace].rstrip(":")
                segs = [x for x in head.split("::") if x]
                walk(prefix + segs, p[brace + 1:-1])
            else:
                alias = None
                if "as" in p and re.search(r"[^:]as[A-Za-z_]", p):
                    # `xasy` after whitespace removal: split at the last "as"
                    m = re.match(r"(.*?)as(" + IDENT + r")$", p)
                    if m and not m.group(1).endswith(":"):
                        p, alias = m.group(1), m.group(2)
                segs = [x for x in p.split("::") if x]
                if segs == ["self"]:
                    segs = []
                    name = prefix[-1] if prefix else None
                else:
                    name = segs[-1] if segs else None
                results.append((prefix + segs, alias or name))

    walk([], tree)
    return results


class Crate:
    def __init__(self, src):
        self.src = src
        self.files = {}  # module tuple -> path
        for p in sorted(src.rglob("*.rs")):
            rel = p.relative_to(src)
            parts = list(rel.with_suffix("").parts)
            if parts == ["lib"]:
                mod = ()
            elif parts == ["main"]:
                mod = ("main",)
            elif parts[-1] == "mod":
                mod = tuple(parts[:-1])
            else:
                mod = tuple(parts)
            self.files[mod] = p
        self.code = {m: strip(p.read_text()) for m, p in self.files.items()}
        self.reexports = {m: self._reexports(m) for m in self.files}

    def is_dir_module(self, mod):
        p = self.files[mod]
        return p.name in ("mod.rs", "lib.rs")

    def parent(self, mod):
        """The module `super` names from file module `mod`."""
        return mod[:-1]

    def _reexports(self, mod):
        out = {}
        for m in re.finditer(r"\bpub(\([a-z]+\))?\s+use\s+([^;]+);", self.code[mod]):
            for segs, name in expand_use(m.group(2)):
                if name and name != "*":
                    out[name] = segs
        return out

    def resolve(self, base, segs, seen=None):
        """The file module that defines the item `segs` names from `base`,
        or None for paths outside the crate."""
        if not segs:
            return None
        seen = seen or set()
        head, rest = segs[0], segs[1:]
        if head == "crate" or head == "organtex":
            cur = ()
        elif head == "super":
            cur = self.parent(base)
            while rest and rest[0] == "super":
                cur, rest = cur[:-1], rest[1:]
        elif head == "self":
            cur = base
        else:
            return None
        while rest and (cur + (rest[0],)) in self.files:
            cur, rest = cur + (rest[0],), rest[1:]
        if rest and rest[0] in self.reexports.get(cur, {}) and (cur, rest[0]) not in seen:
            seen.add((cur, rest[0]))
            target = self.reexports[cur][rest[0]]
            if target and target[0] not in ("crate", "super", "self"):
                target = ["self"] + target
            found = self.resolve(cur, target + rest[1:], seen)
            if found is not None:
                return found
        return cur

    def arrows(self):
        """file module -> {file module: first line}"""
        edges = defaultdict(dict)
        for mod, code in self.code.items():
            base = mod if not mod or self.is_dir_module(mod) else mod
            aliases = {}
            use_spans = []

            def add(target, pos):
                if target is None or target == mod:
                    return
                line = code.count("\n", 0, pos) + 1
                edges[mod].setdefault(target, line)

            for m in re.finditer(r"\b(pub(\([a-z]+\))?\s+)?use\s+([^;]+);", code):
                use_spans.append((m.start(), m.end()))
                public = bool(m.group(1))
                for segs, name in expand_use(m.group(3)):
                    if not segs or segs[0] not in ("crate", "super", "self", "organtex"):
                        continue
                    scope = self.scope(mod)
                    target = self.resolve(scope, segs)
                    if target is None:
                        continue
                    # A module named whole: follow its later uses.
                    full = self.module_of(scope, segs)
                    if full is not None and name:
                        aliases[name] = full
                        if public and self.is_dir_module(mod):
                            continue
                        if not public:
                            continue
                    if public and self.is_dir_module(mod):
                        continue  # a re-export: the table of contents
                    add(target, m.start())
            in_use = lambda pos: any(a <= pos < b for a, b in use_spans)
            for m in re.finditer(r"(?<![A-Za-z0-9_:])((crate|super|self|organtex)(::" + IDENT + r")+)", code):
                if in_use(m.start()):
                    continue
                segs = m.group(1).split("::")
                add(self.resolve(self.scope(mod), segs), m.start())
            for alias, target_mod in aliases.items():
                for m in re.finditer(r"(?<![A-Za-z0-9_:])" + re.escape(alias) + r"((::" + IDENT + r")+)", code):
                    if in_use(m.start()):
                        continue
                    segs = ["crate", *target_mod] + m.group(1).split("::")[1:]
                    add(self.resolve((), segs), m.start())
        return edges

    def scope(self, mod):
        """The module whose `super` is the file's parent: a file module's own
        path (super = its parent), a mod.rs's own path (super = its parent
        too)."""
        return mod

    def module_of(self, base, segs):
        """If `segs` names a module (not an item), that module's path."""
        head, rest = segs[0], segs[1:]
        if head in ("crate", "organtex"):
            cur = ()
        elif head == "super":
            cur = self.parent(base)
            while rest and rest[0] == "super":
                cur, rest = cur[:-1], rest[1:]
        else:
            cur = base
        while rest and (cur + (rest[0],)) in self.files:
            cur, rest = cur + (rest[0],), rest[1:]
        return cur if not rest else None


def name(mod):
    return "/".join(mod) if mod else "lib"


def floor_of(mod):
    top = mod[0] if mod else "lib"
    for k, floor in enumerate(FLOORS):
        if top in floor:
            return k, top
    return None, top


def loops(nodes, edges):
    """Strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, {}):
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

    for v in sorted(nodes):
        if v not in index:
            visit(v)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--src", default=str(Path(__file__).resolve().parent.parent / "src"))
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--dot", action="store_true")
    ap.add_argument("--max-lines", type=int, default=1000)
    args = ap.parse_args()
    crate = Crate(Path(args.src))
    edges = crate.arrows()
    if args.dot:
        print("digraph organtex {")
        for a, targets in sorted(edges.items()):
            for b in sorted(targets):
                print(f'  "{name(a)}" -> "{name(b)}";')
        print("}")
        return 0
    problems = []
    for comp in loops(crate.files.keys(), edges):
        inside = [f"{name(a)} -> {name(b)} (line {edges[a][b]})" for a in comp for b in comp if b in edges.get(a, {})]
        problems.append("loop between " + ", ".join(name(c) for c in comp) + ":\n      " + "\n      ".join(inside))
    for a, targets in sorted(edges.items()):
        fa, ta = floor_of(a)
        if ta in EXEMPT_FROM_FLOORS:
            continue
        for b, line in sorted(targets.items()):
            fb, tb = floor_of(b)
            if fa is None or fb is None:
                problems.append(f"{name(a)} or {name(b)}: a top-level module on no floor (add it to FLOORS)")
            elif fb < fa:
                problems.append(f"upward: {name(a)} (floor {ta}) -> {name(b)} (floor {tb}), line {line}")
    for mod, path in sorted(crate.files.items()):
        lines = path.read_text().count("\n")
        if lines > args.max_lines:
            problems.append(f"{path}: {lines} lines, over {args.max_lines}")
    arrows = sum(len(t) for t in edges.values())
    print(f"{len(crate.files)} files, {arrows} arrows between them; floors, top to bottom:")
    for floor in FLOORS:
        print("  " + ", ".join(floor))
    for p in problems:
        print("  " + p)
    if not problems:
        print("no loop between files, no upward arrow, no file over", args.max_lines, "lines")
    return 1 if problems and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
