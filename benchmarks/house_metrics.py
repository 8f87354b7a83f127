"""The house's measurements (issue 35): how easy the library is to change, from its source alone.

    python benchmarks/house_metrics.py [--root .] [--json FILE]

Prints, for the package ``solidshell/`` (compiled kernels -- functions decorated with numba's
``njit``/``jit``/``vectorize`` -- left out of the function figures):
  * the 15 longest functions (lines from ``def`` to the last line of the body);
  * functions with more than 10 parameters;
  * ``hasattr``/``getattr`` calls (every one in the package: a probe of the project's own objects or
    of a module/library; the listing names each, so the two can be told apart);
  * places where the solver-kind list appears (a tuple/list/set literal or a Literal[...] holding
    "static", "explicit" and "relax");
  * import cycles between the package's modules (strongly connected components of the graph of
    module-level and function-level ``import``s);
  * files under benchmarks/out and line counts of docs/*.md.
Reads files only; imports nothing of the project.
"""

from __future__ import annotations

import argparse
import ast
import json
from pathlib import Path

KINDS = {"static", "explicit", "relax"}
COMPILED = {"njit", "jit", "vectorize", "guvectorize", "generated_jit", "cfunc", "stencil"}


def _decorator_names(fn) -> set[str]:
    out = set()
    for d in fn.decorator_list:
        d = d.func if isinstance(d, ast.Call) else d
        out.add(d.attr if isinstance(d, ast.Attribute) else getattr(d, "id", ""))
    return out


def _module_name(root: Path, path: Path) -> str:
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(mod: str, is_pkg: bool, tree: ast.AST, known: set[str]) -> set[str]:
    out = set()
    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                pref = base[: len(base) - node.level + 1]
                head = ".".join(pref + ([node.module] if node.module else []))
            else:
                head = node.module or ""
            # `from pkg import mod` depends on pkg.mod (which Python runs after pkg's __init__, as any
            # submodule import does), `from pkg import name` on pkg
            subs = [f"{head}.{a.name}" for a in node.names]
            names = [n for n in subs if n in known] or [head]
        else:
            continue
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "__future__":
            continue
        for n in names:
            while n and n not in known:
                n = n.rpartition(".")[0]
            if n and n != mod:
                out.add(n)
    return out


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with more than one module."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
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

    import sys

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return out


def measure(root: Path) -> dict:
    pkg = root / "solidshell"
    files = sorted(p for p in pkg.rglob("*.py") if "__pycache__" not in p.parts)
    trees = {p: ast.parse(p.read_text(), str(p)) for p in files}
    mods = {_module_name(root, p): p for p in files}
    known = set(mods)
    funcs, probes, kind_lists, graph = [], [], [], {}
    for p, tree in trees.items():
        rel = str(p.relative_to(root))
        mod = _module_name(root, p)
        graph[mod] = _imports(mod, p.name == "__init__.py", tree, known)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                if _decorator_names(node) & COMPILED:
                    continue
                a = node.args
                nparams = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                if a.args and a.args[0].arg in ("self", "cls"):
                    nparams -= 1
                funcs.append(
                    {
                        "where": f"{rel}:{node.lineno}",
                        "name": node.name,
                        "lines": node.end_lineno - node.lineno + 1,
                        "params": nparams,
                    }
                )
            elif isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("hasattr", "getattr"):
                probes.append(f"{rel}:{node.lineno}")
            elif isinstance(node, (ast.Tuple, ast.List, ast.Set)):
                vals = {e.value for e in node.elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}
                if KINDS <= vals:
                    kind_lists.append(f"{rel}:{node.lineno}")
    funcs.sort(key=lambda f: -f["lines"])
    out_dir = root / "benchmarks" / "out"
    docs = {str(p.relative_to(root)): len(p.read_text().splitlines()) for p in sorted((root / "docs").rglob("*.md"))}
    return {
        "longest_functions": funcs[:15],
        "functions_over_100_lines": sum(f["lines"] > 100 for f in funcs),
        "functions_over_10_params": [f for f in funcs if f["params"] > 10],
        "hasattr_getattr_calls": len(probes),
        "hasattr_getattr_where": probes,
        "solver_kind_list_places": kind_lists,
        "import_cycles": _cycles(graph),
        "benchmarks_out_files": sum(1 for f in out_dir.rglob("*") if f.is_file()) if out_dir.exists() else 0,
        "docs_lines": docs,
        "package_lines": sum(len(p.read_text().splitlines()) for p in files),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=str(Path(__file__).resolve().parents[1]))
    ap.add_argument("--json", help="also write the figures to this file")
    a = ap.parse_args(argv)
    m = measure(Path(a.root))
    print(f"package lines: {m['package_lines']}")
    print("longest functions (compiled kernels left out):")
    for f in m["longest_functions"]:
        print(f"  {f['lines']:4d} lines  {f['params']:2d} params  {f['name']}  ({f['where']})")
    print(f"functions over 100 lines: {m['functions_over_100_lines']}")
    print(f"functions with more than 10 parameters: {len(m['functions_over_10_params'])}")
    for f in m["functions_over_10_params"]:
        print(f"  {f['params']:2d} params  {f['name']}  ({f['where']})")
    print(f"hasattr/getattr calls: {m['hasattr_getattr_calls']}")
    print(
        f"places the solver-kind list appears: {len(m['solver_kind_list_places'])}  "
        + " ".join(m["solver_kind_list_places"])
    )
    print(f"import cycles: {len(m['import_cycles'])}")
    for c in m["import_cycles"]:
        print("  " + " <-> ".join(c))
    print(f"files under benchmarks/out: {m['benchmarks_out_files']}")
    print(
        "docs lines: "
        + ", ".join(f"{Path(k).name} {v}" for k, v in m["docs_lines"].items())
        + f"; total {sum(m['docs_lines'].values())}"
    )
    if a.json:
        Path(a.json).write_text(json.dumps(m, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
