"""The code's shape stays readable (docs/ARCHITECTURE.md): small modules and functions, short
docstrings, no private names reached across modules, no import cycles.

Limits: a module at most 450 lines, a function at most 80, a docstring at most 25 (backend and
frontend, generated tables aside).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from shared_data import REPO

BACKEND = REPO / "backend" / "autohaptics"
FRONTEND = REPO / "frontend"
MAX_MODULE_LINES = 450
MAX_FUNCTION_LINES = 80
MAX_DOCSTRING_LINES = 25
GENERATED = {"intensity/iso532_tables.py"}  # the standard's tables, written out, not code


def _py_modules() -> dict[str, Path]:
    """{dotted module name: path} of the backend package, generated tables left out."""
    out = {}
    for path in sorted(BACKEND.rglob("*.py")):
        rel = path.relative_to(BACKEND).as_posix()
        if rel in GENERATED:
            continue
        parts = ["autohaptics", *path.relative_to(BACKEND).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _py_modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8")) for name, path in MODULES.items()}
JS_FILES = sorted(p for p in (FRONTEND / "src").rglob("*.js"))


def _rel(path: Path) -> str:
    return path.relative_to(REPO).as_posix()


def test_modules_are_short():
    long = {_rel(p): n for p in [*MODULES.values(), *JS_FILES, *FRONTEND.glob("css/*.css")]
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES}
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def test_python_functions_and_docstrings_are_short():
    long_fn, long_doc = {}, {}
    for name, tree in TREES.items():
        nodes = [tree, *ast.walk(tree)]
        for node in nodes:
            where = f"{name}:{getattr(node, 'name', '<module>')}"
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = node.end_lineno - node.lineno + 1
                if n > MAX_FUNCTION_LINES:
                    long_fn[where] = n
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
                doc = ast.get_docstring(node, clean=False)
                if doc is not None and len(doc.splitlines()) > MAX_DOCSTRING_LINES:
                    long_doc[where] = len(doc.splitlines())
    assert not long_fn, f"functions over {MAX_FUNCTION_LINES} lines: {long_fn}"
    assert not long_doc, f"docstrings over {MAX_DOCSTRING_LINES} lines: {long_doc}"


def _imports(name: str, tree: ast.Module) -> list[tuple[str, str | None]]:
    """(module, imported name or None) for every import of ``name``'s source, relative ones resolved."""
    package = name if MODULES[name].name == "__init__.py" else name.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, None) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - node.level + 1]
                base = ".".join([*anchor, base] if base else anchor)
            out += [(base, a.name) for a in node.names]
    return out


def _internal_target(module: str, imported: str | None) -> str | None:
    """The project module an import statement depends on (a submodule when it names one)."""
    if imported is not None and f"{module}.{imported}" in MODULES:
        return f"{module}.{imported}"
    return module if module in MODULES else None


def test_no_private_name_is_imported_across_modules():
    bad = []
    for name, tree in TREES.items():
        aliases = {}
        for module, imported in _imports(name, tree):
            target = _internal_target(module, imported)
            if target is None:
                continue
            if imported and imported.startswith("_") and not imported.startswith("__") and target == module:
                bad.append(f"{name} imports {module}.{imported}")
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                for a in node.names:
                    if _internal_target(node.module or "", a.name) == f"{node.module}.{a.name}":
                        aliases[a.asname or a.name] = f"{node.module}.{a.name}"
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name in MODULES and a.asname:
                        aliases[a.asname] = a.name
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in aliases and node.attr.startswith("_")
                    and not node.attr.startswith("__")):
                bad.append(f"{name} uses {aliases[node.value.id]}.{node.attr}")
    assert not bad, "private names used across modules:\n" + "\n".join(sorted(set(bad)))


def test_no_import_cycle():
    graph = {name: set() for name in MODULES}
    for name, tree in TREES.items():
        for module, imported in _imports(name, tree):
            target = _internal_target(module, imported)
            if target is not None and target != name and not name.startswith(target + "."):
                graph[name].add(target)
    cycles = [scc for scc in _strongly_connected(graph) if len(scc) > 1]
    assert not cycles, f"import cycles: {cycles}"
    packages: dict[str, set[str]] = {}
    for name, targets in graph.items():  # the same between the top-level packages (layers)
        top = ".".join(name.split(".")[:2])
        packages.setdefault(top, set()).update(t2 for t in targets if (t2 := ".".join(t.split(".")[:2])) != top)
    cycles = [scc for scc in _strongly_connected(packages) if len(scc) > 1]
    assert not cycles, f"import cycles between packages: {cycles}"


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components, iteratively."""
    index, low, on_stack, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                scc = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    scc.append(w)
                    if w == node:
                        break
                out.append(sorted(scc))
    return out


# ------------------------------------------------------------------ JavaScript
_FN_START = re.compile(
    r"(\bfunction\b[^{;]*\)\s*$"  # function name(...) / function (...)
    r"|=>\s*$"  # (...) => {
    r"|^\s*(?:static\s+|async\s+|get\s+|set\s+|#)*(?!(?:if|for|while|switch|catch|with)\b)[A-Za-z_$][\w$]*\s*\([^;]*\)\s*$)"  # method(...) {
)


def _js_blocks(text: str):
    """(start line, end line, head) of every brace block, strings, template literals and comments
    skipped. ``head`` is the code before the opening brace on its line."""
    stack, line, i, n = [], 1, 0, len(text)
    line_start = 0
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            line_start = i + 1
        elif text.startswith("//", i):
            i = text.find("\n", i) - 1 if text.find("\n", i) >= 0 else n
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            line += text.count("\n", i, end)
            i = end + 1
        elif c in "'\"`":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            line += text.count("\n", i, j)
            i = j
        elif c == "{":
            stack.append((line, text[line_start:i]))
        elif c == "}" and stack:
            start, head = stack.pop()
            yield start, line, head
        i += 1


def test_javascript_functions_are_short():
    long = {}
    for path in JS_FILES:
        for start, end, head in _js_blocks(path.read_text(encoding="utf-8")):
            if _FN_START.search(head.rstrip()) and end - start + 1 > MAX_FUNCTION_LINES:
                long[f"{_rel(path)}:{start}"] = end - start + 1
    assert not long, f"JavaScript functions over {MAX_FUNCTION_LINES} lines: {long}"


@pytest.mark.parametrize("lines,expected", [
    ("function f(a) {\n  return 1;\n}\n", [(1, 3)]),
    ("const s = '{';\nclass A {\n  m(x) {\n    return `}${x}`;\n  }\n}\n", [(3, 5), (2, 6)]),
])
def test_js_block_scanner_skips_strings(lines, expected):
    assert [(a, b) for a, b, _ in _js_blocks(lines)] == expected
