"""Import circles between the source files of each crate (issue 41): fails on any.

    python3 scripts/import_circles.py [--crate src] [--crate fmu-build/src] [--graph]
    python3 scripts/import_circles.py --reachable-from src/fmi2/exports.rs   (the seam test's list)

A file depends on another when it names an item defined there: through `use` (trees expanded),
or a path in the code (`crate::…`, `super::…`, `self::…`). A name a module re-exports (`pub use`)
is followed to the file that defines it, so a `mod.rs` that re-exports from its children is not
itself a link. Comments are left out. Circles are the strongly connected components of more than
one file (Tarjan); each is printed with one cycle through it, and the exit status is 1.

Why a script and not `cargo modules dependencies --acyclic`: that tool builds on rust-analyzer,
which takes longer to compile on the CI machine than this whole check's budget.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
ITEM = re.compile(
    r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+|async\s+|const\s+|extern\s+\"C\"\s+)*"
    r"(?:struct|enum|fn|trait|type|const|static|union|mod)\s+(\w+)",
    re.M,
)
MACRO = re.compile(r"macro_rules!\s+(\w+)")
USE = re.compile(r"\b(pub(?:\([^)]*\))?\s+)?use\s+([^;]+);", re.S)
PATH = re.compile(r"(?<![\w:])((?:crate|super|self)(?:::\w+)+)")
CHILD_PATH = re.compile(r"(?<![\w:])((\w+)(?:::\w+)+)")


def strip_comments(text: str) -> str:
    """Drops // and /* */ comments, leaves string literals' contents alone."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(text[i : j + 1])
            i = j + 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i)
            i = n if j < 0 else j + 2
        else:
            out.append(c)
            i += 1
    return "".join(out)


def expand_use_tree(tree: str) -> list[str]:
    """`a::{b, c::{d, e}}` → ['a::b', 'a::c::d', 'a::c::e'] (aliases dropped)."""
    tree = re.sub(r"\s+", "", tree)
    brace = tree.find("{")
    if brace < 0:
        return [tree.split("as", 1)[0] if re.search(r"\bas\b", tree) else tree]
    prefix, body = tree[:brace], tree[brace + 1 : tree.rfind("}")]
    parts, depth, start = [], 0, 0
    for k, ch in enumerate(body):
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            parts.append(body[start:k])
            start = k + 1
    parts.append(body[start:])
    paths = []
    for part in filter(None, parts):
        for sub in expand_use_tree(part):
            paths.append(prefix.rstrip(":") if sub == "self" else prefix + sub)
    return paths


class Crate:
    def __init__(self, root: Path):
        self.root = root
        self.modules: dict[tuple[str, ...], Path] = {}
        for path in sorted(root.rglob("*.rs")):
            rel = path.relative_to(root).with_suffix("").parts
            if rel in (("lib",), ("main",)):
                module = ()
            elif rel[-1] == "mod":
                module = rel[:-1]
            else:
                module = rel
            self.modules[module] = path
        self.text = {m: strip_comments(p.read_text()) for m, p in self.modules.items()}
        self.items = {m: set(ITEM.findall(t)) | set(MACRO.findall(t)) for m, t in self.text.items()}
        self.reexports: dict[tuple[str, ...], dict[str, str]] = {}
        self.globs: dict[tuple[str, ...], list[str]] = {}
        for m, t in self.text.items():
            names, globs = {}, []
            for vis, tree in USE.findall(t):
                if vis:
                    for p in expand_use_tree(tree):
                        if p.endswith("::*"):
                            globs.append(p[: -len("::*")])
                        else:
                            names[p.rsplit("::", 1)[-1]] = p
            self.reexports[m] = names
            self.globs[m] = globs

    def resolve(self, module: tuple[str, ...], path: str, seen=()) -> tuple[str, ...] | None:
        """The module (file) that defines what `path`, written in `module`, names."""
        segments = path.split("::")
        head = segments[0]
        if head == "crate":
            at, rest = (), segments[1:]
        elif head in ("super", "self"):
            at = module
            while segments and segments[0] in ("super", "self"):
                if segments.pop(0) == "super":
                    at = at[:-1]
            rest = segments
        else:
            # A path relative to the current module: a child module or a name in scope.
            if module + (head,) in self.modules:
                at, rest = module, segments
            else:
                return None
        while rest and at + (rest[0],) in self.modules:
            at, rest = at + (rest[0],), rest[1:]
        if not rest or rest[0] == "*" or rest[0] in self.items.get(at, ()):
            return at
        name = rest[0]
        target = self.reexports.get(at, {}).get(name)
        if target and (at, name) not in seen:
            resolved = self.resolve(at, target, seen + ((at, name),))
            if resolved is not None:
                return resolved
        # A glob re-export (`pub use other::*`): the name may be defined there.
        for glob in self.globs.get(at, ()):
            if (at, glob) in seen:
                continue
            module = self.resolve(at, glob, seen + ((at, glob),))
            if module is not None and name in self.items.get(module, ()):
                return module
        return at

    def graph(self) -> dict[tuple[str, ...], set[tuple[str, ...]]]:
        edges = {m: set() for m in self.modules}
        for m, text in self.text.items():
            inline = inline_modules(text)
            paths = [(u.start(), p) for u in USE.finditer(text) for p in expand_use_tree(u.group(2))]
            paths += [(q.start(), q.group(1)) for q in PATH.finditer(text) if not within_use(text, q.start())]
            # A path from a child module (`fmu::any_model::AnyModel` in lib.rs).
            paths += [(q.start(), q.group(1)) for q in CHILD_PATH.finditer(text)
                      if m + (q.group(2),) in self.modules and not within_use(text, q.start())]
            for at, p in paths:
                # Inside an inline `mod tests { … }` the first `super` is the file's own module.
                depth = sum(start <= at < end for start, end in inline)
                while depth and p.startswith("super::"):
                    p, depth = "self::" + p[len("super::"):], depth - 1
                target = self.resolve(m, p)
                if target is not None and target != m and target in self.modules:
                    edges[m].add(target)
        return edges


IMPL = re.compile(r"^\s*impl(?:<[^{]*?>)?\s+(?:[\w:]+(?:<[^{]*?>)?\s+for\s+)?(?:[\w]+::)*(\w+)", re.M)


def impl_edges(crate: Crate, edges) -> dict:
    """For reachability: a type's file → each file of the same module with an `impl` block for
    it. A method is called on a value, by no path the graph sees; whoever reaches the type
    reaches the methods its module gives it (`PmorDynamics`'s step is in pmor/integrator.rs,
    its type in pmor/mod.rs). An impl in another module is that module's extension (the offline
    constructors `rom::flank` adds to `FlankGrid`, `closed_forms::mesh_stiffness` to
    `LumpedMesh`), reached only by a path to it. Not for the circle check: an impl block that
    uses its type is no circle."""
    definers: dict[str, list] = {}
    for m, names in crate.items.items():
        for name in names:
            definers.setdefault(name, []).append(m)
    extra = {m: set() for m in crate.modules}
    for m, text in crate.text.items():
        for found in IMPL.finditer(text):
            owners = definers.get(found.group(1), [])
            # A name defined in several files: the one this file imports, where it imports one.
            owners = [o for o in owners if o in edges[m]] or owners
            for owner in owners:
                same_module = (owner[:-1] if crate.modules[owner].stem != "mod" else owner) == m[:-1]
                if owner != m and same_module:
                    extra[owner].add(m)
    return extra


def inline_modules(text: str) -> list[tuple[int, int]]:
    """The spans of `mod name { … }` blocks."""
    spans = []
    for found in re.finditer(r"\bmod\s+\w+\s*\{", text):
        depth, i = 0, found.end() - 1
        while i < len(text):
            depth += text[i] == "{"
            depth -= text[i] == "}"
            if depth == 0:
                break
            i += 1
        spans.append((found.start(), i))
    return spans


def within_use(text: str, at: int) -> bool:
    """Whether the offset lies in a `use …;` statement (its paths are read by `USE`)."""
    line_start = text.rfind(";", 0, at) + 1
    return re.match(r"\s*(?:#\[[^\]]*\]\s*)*(?:pub(?:\([^)]*\))?\s+)?use\s", text[line_start:at + 1]) is not None


def strongly_connected(edges):
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            out.append(component)

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def one_cycle(edges, component):
    """A shortest cycle through the component's first file (breadth-first)."""
    members = set(component)
    start = sorted(component)[0]
    parents, frontier = {start: None}, [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(edges[v] & members):
                if w == start:
                    cycle = [v]
                    while parents[cycle[-1]] is not None:
                        cycle.append(parents[cycle[-1]])
                    return [start] + cycle[::-1][1:] + [start] if len(cycle) > 1 else [start, v, start]
                if w not in parents:
                    parents[w] = v
                    nxt.append(w)
        frontier = nxt
    return component


def reachable(edges, starts) -> list:
    """The files `starts` depend on, directly or not, and `starts` themselves, sorted."""
    seen, frontier = set(starts), list(starts)
    while frontier:
        for w in edges[frontier.pop()]:
            if w not in seen:
                seen.add(w)
                frontier.append(w)
    return sorted(seen)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--crate", action="append", type=Path, help="a crate's source root (default: src, fmu-build/src)")
    parser.add_argument("--graph", action="store_true", help="print every file's dependencies")
    parser.add_argument("--reachable-from", nargs="+", type=Path, metavar="FILE",
                        help="print, one a line, the files these files reach through their dependencies "
                             "(themselves included), and check nothing else")
    args = parser.parse_args()
    if args.reachable_from:
        crate = Crate(REPO_ROOT / "src")
        by_path = {p.resolve(): m for m, p in crate.modules.items()}
        edges = crate.graph()
        for m, extensions in impl_edges(crate, edges).items():
            edges[m] |= extensions
        for f in reachable(edges, [by_path[(REPO_ROOT / f).resolve()] for f in args.reachable_from]):
            print(crate.modules[f].relative_to(REPO_ROOT))
        return 0
    roots = args.crate or [REPO_ROOT / "src", REPO_ROOT / "fmu-build" / "src"]
    circles = 0
    for root in roots:
        crate = Crate(root)
        edges = crate.graph()
        name = lambda m: str(crate.modules[m].relative_to(REPO_ROOT))  # noqa: E731
        if args.graph:
            for m in sorted(edges):
                print(f"{name(m)} → {', '.join(sorted(name(t) for t in edges[m]))}")
        for component in strongly_connected(edges):
            circles += 1
            cycle = one_cycle(edges, component)
            print(f"import circle of {len(component)} files in {root.relative_to(REPO_ROOT)}:")
            print("  " + " → ".join(name(m) for m in cycle))
            others = sorted(set(component) - set(cycle))
            if others:
                print("  and through it: " + ", ".join(name(m) for m in others))
    if circles:
        print(f"{circles} import circle(s): break each at its depth (a type moved where both sides see it, a trait at the seam)")
        return 1
    print(f"no import circle between the source files of {', '.join(str(r.relative_to(REPO_ROOT)) for r in roots)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
