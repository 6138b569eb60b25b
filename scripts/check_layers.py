#!/usr/bin/env python3
"""Checks the dependency rule of geocull's code (run by CI; exits 1 on a violation).

Rust (src/): every `crate::<module>` path in code (comments ignored) must point to the same module
or to a lower layer:

    python -> render -> {cull, iso} -> gpu -> scene -> {grid, camera} -> lod -> error

(`grid` sits at the level of `lod` and may use it; `camera` and `grid` do not use each other.)

(`cull` and `iso` do not use each other; `crate::TestRng`, `crate::Result`, `crate::Error` are the
crate root's re-exports and allowed everywhere.) Nor do files import one another in a circle, within a
layer or across (a file and the modules it declares, its ancestors and descendants, aside: a parent
that names its child's functions while the child takes its parent's types is Rust's module idiom).
Test modules (`#[cfg(test)] mod tests { .. }` at a file's end; `tests.rs`, `tests_*.rs`, `*_tests.rs`)
are left out.

Python (python/geocull/ and its subpackages, such as geocull.bench): no import cycle among the
package's modules at import time (module-level imports), and no module imports another module's
underscore-prefixed name (``from .x import _y``, ``from ..x import _y``), anywhere in the file.
Private *modules* with public names (``_convert``, ``_errors``, ``_geocull``) are the package's
internal API and may be imported.

Sizes: no source file of src/ or python/geocull over MAX_FILE_LINES lines without its tests (a
Rust file's `#[cfg(test)] mod tests { .. }` at its end and test files left out), and no function
over MAX_FN_LINES lines (Rust: from its `fn` line to the closing brace at its indent, as rustfmt
lays it out; Python: the function's statement).
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# module -> the modules it may use (besides itself)
BELOW: dict[str, set[str]] = {
    "error": set(),
    "camera": {"error"},
    "lod": {"error"},
    "grid": {"error", "lod"},
    "scene": {"error", "camera", "lod", "grid"},
    "gpu": {"error", "camera", "lod", "grid", "scene"},
    "cull": {"error", "camera", "lod", "grid", "scene", "gpu"},
    "iso": {"error", "camera", "lod", "grid", "scene", "gpu"},
    "render": {"error", "camera", "lod", "grid", "scene", "gpu", "cull", "iso"},
    "python": {"error", "camera", "lod", "grid", "scene", "gpu", "cull", "iso", "render"},
}
ROOT_ITEMS = {"TestRng", "Result", "Error"}
MAX_FILE_LINES = 700
MAX_FN_LINES = 150
TEST_MODULE = "#[cfg(test)]\nmod tests {"  # a Rust file's own tests, at its end
RUST_FN = re.compile(r"^(\s*)(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?fn\s+(\w+)")


def rust_module(path: Path) -> str | None:
    rel = path.relative_to(ROOT / "src")
    if rel.parts == ("lib.rs",):
        return None
    return rel.parts[0].removesuffix(".rs")


def strip_comments(text: str) -> str:
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def check_rust() -> list[str]:
    errors = []
    for path in sorted((ROOT / "src").rglob("*.rs")):
        mod = rust_module(path)
        if mod is None:
            continue
        if mod not in BELOW:
            errors.append(f"{path.relative_to(ROOT)}: module `{mod}` has no layer in scripts/check_layers.py")
            continue
        code = strip_comments(path.read_text())
        for m in re.finditer(r"\bcrate::([A-Za-z_][A-Za-z0-9_]*)", code):
            target = m.group(1)
            if target == mod or target in ROOT_ITEMS or target in BELOW[mod]:
                continue
            line = code[: m.start()].count("\n") + 1
            errors.append(f"{path.relative_to(ROOT)}:{line}: `{mod}` may not use `crate::{target}`")
    return errors


def rust_file_modules() -> dict[tuple[str, ...], Path]:
    """Every product file of src/ by its module path: src/a/b.rs and src/a/b/mod.rs are ("a", "b")."""
    files = {}
    for path in sorted((ROOT / "src").rglob("*.rs")):
        parts = path.relative_to(ROOT / "src").with_suffix("").parts
        if is_test_file(path) or parts == ("lib",):
            continue
        files[tuple(parts[:-1]) if parts[-1] == "mod" else tuple(parts)] = path
    return files


def use_paths(tree: str, prefix: list[str]) -> list[list[str]]:
    """The paths of a `use` tree (`a::{b, c::{d, e}}`, whitespace removed), each as segments."""
    out: list[list[str]] = []
    depth, start = 0, 0
    brace = tree.find("{")
    if brace < 0:
        return [prefix + [p for p in tree.split("::") if p and p != "*"]]
    head = prefix + [p for p in tree[:brace].split("::") if p]
    inner = tree[brace + 1: tree.rfind("}")]
    for i, ch in enumerate(inner + ","):
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        elif ch == "," and depth == 0:
            part = inner[start:i]
            if part:
                out += use_paths(part, head)
            start = i + 1
    return out


def check_rust_cycles() -> list[str]:
    files = rust_file_modules()
    graph: dict[tuple[str, ...], set[tuple[str, ...]]] = {m: set() for m in files}
    for mod, path in files.items():
        code = strip_comments(path.read_text())
        code = code.split(TEST_MODULE)[0]
        here = list(mod)
        children = set(re.findall(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", code, re.M))
        paths = [use_paths(re.sub(r"\s+", "", m.group(1)), []) for m in re.finditer(r"\buse\s+([^;]+);", code)]
        paths = [p for group in paths for p in group]
        paths += [m.group(0).split("::") for m in re.finditer(r"\b(?:crate|super|self)(?:::[A-Za-z_]\w*)+", code)]
        paths += [m.group(0).split("::") for c in children for m in re.finditer(rf"\b{c}(?:::[A-Za-z_]\w*)+", code)]
        for segs in paths:
            if segs[0] == "crate":
                target = segs[1:]
            elif segs[0] in ("super", "self"):
                base = here[:]
                while segs and segs[0] in ("super", "self"):
                    if segs[0] == "super":
                        base = base[:-1]
                    segs = segs[1:]
                target = base + segs
            elif segs[0] in children:
                target = here + segs
            else:
                continue
            hit = max((k for k in range(len(target) + 1) if tuple(target[:k]) in files), default=None)
            if hit is None:
                continue
            dest = tuple(target[:hit])
            if dest[: len(mod)] == mod or mod[: len(dest)] == dest:
                continue  # itself, an ancestor or a descendant
            graph[mod].add(dest)
    named = {m: str(files[m].relative_to(ROOT)) for m in files}
    return cycles({named[m]: {named[n] for n in v} for m, v in graph.items()}, "rust file cycle")


def python_modules(pkg: Path) -> dict[str, Path]:
    """The package's modules by dotted name below ``geocull``: ``scene``, ``bench`` (bench/__init__.py),
    ``bench.report``; the package's own ``__init__.py`` is ``__init__``."""
    modules = {}
    for p in sorted(pkg.rglob("*.py")):
        parts = list(p.relative_to(pkg).with_suffix("").parts)
        if parts[-1] == "__init__" and len(parts) > 1:
            parts.pop()
        modules[".".join(parts)] = p
    return modules


def check_python() -> list[str]:
    pkg = ROOT / "python" / "geocull"
    modules = python_modules(pkg)
    errors = []
    graph: dict[str, set[str]] = {m: set() for m in modules}  # module-level imports, as Python runs them
    anywhere: dict[str, set[str]] = {m: set() for m in modules}  # every import: in functions, for type hints
    for name, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        top_level = set(id(n) for n in tree.body)
        # the package a relative import starts from: "" for geocull itself, "bench" for geocull.bench's modules
        package = name if path.name == "__init__.py" and name != "__init__" else name.rpartition(".")[0]
        for node in ast.walk(tree):
            targets: list[tuple[str, list[str]]] = []
            if isinstance(node, ast.ImportFrom):
                if node.level >= 1:
                    parts = package.split(".") if package else []
                    if node.level - 1 > len(parts):
                        continue  # above geocull: not the package's business
                    base = ".".join(parts[: len(parts) - (node.level - 1)] + ([node.module] if node.module else []))
                    names = [a.name for a in node.names]
                    if node.module:
                        targets.append((base, names))
                    else:  # from . import x, y: submodules, or names of the package's __init__
                        where = pkg.joinpath(*base.split(".")) if base else pkg
                        subs = [n for n in names if (where / n).is_dir() or any(where.glob(f"{n}.*"))]
                        targets.extend((f"{base}.{n}".lstrip("."), []) for n in subs)
                        if len(subs) < len(names):
                            targets.append((base or "__init__", [n for n in names if n not in subs]))
                elif node.level == 0 and (node.module or "").startswith("geocull."):
                    targets.append((node.module.split(".", 1)[1], [a.name for a in node.names]))
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.startswith("geocull."):
                        targets.append((a.name.split(".", 1)[1], []))
            for mod, names in targets:
                for n in names:
                    if n.startswith("_") and not n.startswith("__") and f"{mod}.{n}" not in modules:
                        errors.append(f"{path.relative_to(ROOT)}:{node.lineno}: imports private name {mod}.{n}")
                if mod in modules and mod != name and not name.startswith(mod + "."):
                    anywhere[name].add(mod)
                if id(node) not in top_level:
                    continue
                # importing a.b imports the package a first, unless this module is inside a already
                chain = mod.split(".")
                for i in range(1, len(chain) + 1):
                    m = ".".join(chain[:i])
                    if m in modules and m != name and not name.startswith(m + "."):
                        graph[name].add(m)
    # cycles among module-level imports (an import error at run time), then among all imports (a
    # design that no module can be understood without the others: none either)
    errors += cycles(graph, "python import cycle")
    if not errors:
        errors += cycles(anywhere, "python import cycle (imports in functions or for type hints included)")
    return errors


def cycles(graph: dict[str, set[str]], what: str) -> list[str]:
    """One line per cycle found by a depth-first walk of ``graph`` (module -> the modules it imports)."""
    errors = []
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                cycle = stack[stack.index(n):] + [n]
                errors.append(f"{what}: " + " -> ".join(cycle))
            elif n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)
    return errors


def is_test_file(path: Path) -> bool:
    """A Rust file of tests only: tests.rs, tests_*.rs, *_tests.rs."""
    return re.fullmatch(r"tests|tests_\w+|\w+_tests", path.stem) is not None


def check_sizes() -> list[str]:
    errors = []
    for path in sorted((ROOT / "src").rglob("*.rs")):
        if is_test_file(path):
            continue
        lines = path.read_text().split(TEST_MODULE)[0].splitlines()
        end = len(lines)
        rel = path.relative_to(ROOT)
        if end > MAX_FILE_LINES:
            errors.append(f"{rel}: {end} lines without its tests (at most {MAX_FILE_LINES})")
        for i, line in enumerate(lines[:end]):
            m = RUST_FN.match(line)
            if not m or line.rstrip().endswith(";"):
                continue
            close = m.group(1) + "}"
            n = next((j - i + 1 for j in range(i + 1, end) if lines[j].rstrip() == close), 1)
            if n > MAX_FN_LINES:
                errors.append(f"{rel}:{i + 1}: fn {m.group(7)} has {n} lines (at most {MAX_FN_LINES})")
    for path in sorted((ROOT / "python" / "geocull").rglob("*.py")):
        text = path.read_text()
        rel = path.relative_to(ROOT)
        if len(text.splitlines()) > MAX_FILE_LINES:
            errors.append(f"{rel}: {len(text.splitlines())} lines (at most {MAX_FILE_LINES})")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = (node.end_lineno or node.lineno) - node.lineno + 1
                if n > MAX_FN_LINES:
                    errors.append(f"{rel}:{node.lineno}: def {node.name} has {n} lines (at most {MAX_FN_LINES})")
    return errors


def main() -> int:
    errors = check_rust() + check_rust_cycles() + check_python() + check_sizes()
    for e in errors:
        print(e)
    if errors:
        print(f"check_layers: {len(errors)} violation(s)")
        return 1
    print("check_layers: dependency rule holds (Rust layers, no circle of files; Python: no cycle, "
          f"no private cross-imports; files <= {MAX_FILE_LINES} lines, functions <= {MAX_FN_LINES})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
