"""The walk of config resolution (issue #59's measure for a reader of the code): the files and
``return`` statements a reader meets following ``resolve_run``'s calls within ``devlearn/``.

A static walk of the source (no import, no run): it starts in the body of
``devlearn.config.resolve.resolve_run`` and follows every call whose target is named in the
code: a function of the same module, a function imported from a ``devlearn`` module (at the top
of the module or inside the function), ``module.function`` of an imported ``devlearn`` module,
or ``self.method``/``cls.method`` in a class. Each function reached is entered once; its file
is counted and its ``return`` statements (those of nested functions and lambdas excluded) are
added up.

It does not follow:

- calls on objects handed in (``registry.behavior(...)``, ``behavior.network()``,
  ``read_checkpoint(...)``): the plugin registry's, the behaviour's and the checkpoint's own
  contracts, which the pipeline uses as a reader uses a library;
- constructors of classes (dataclasses and exceptions: no body to read);
- the tools of :data:`TOOLS`: functions a stage hands one job, each named for it and tested
  on its own (set dotted keys: the ``--set`` language with its conversions and messages; read
  a saved config, with the values old runs were trained with; check a config). A reader meets
  them as a call; their files count as touched, their bodies are not walked.

With ``--all`` it follows the tools too (every call named in the code, to the end).

    python scripts/walk_resolve.py            # files and returns, then the functions entered
    python scripts/walk_resolve.py --all      # the same, through the tools
    python scripts/walk_resolve.py --root DIR # another checkout (e.g. ``git worktree add``)
"""

from __future__ import annotations

import argparse
import ast
import sys
from dataclasses import dataclass, field
from pathlib import Path

START = ("devlearn.config.resolve", "resolve_run")
TOOLS = {
    ("devlearn.config.values", "apply_overrides"),
    ("devlearn.config.values", "override_keys"),
    ("devlearn.config.run_config", "from_dict"),
    ("devlearn.config.resolve", "read_config_file"),
    ("devlearn.config.run_config", "finish_config"),
    ("devlearn.config.checks", "check_config"),
    ("devlearn.config.checks", "check_resumed"),
    ("devlearn.config.growth", "keep_growth_on_resume"),
}
"""Functions whose file counts as touched but whose bodies the walk does not enter (the same
list before and after issue #59's pipeline: a name absent from a checkout is never reached)."""


@dataclass
class Module:
    """One parsed module: its functions (``name`` or ``Class.name``) and imported names."""

    path: Path
    functions: dict[str, ast.FunctionDef] = field(default_factory=dict)
    imports: dict[str, tuple[str, str]] = field(default_factory=dict)
    """Local name -> (module, name); name empty for ``import module as local``."""


def parse(root: Path) -> dict[str, Module]:
    """Every module under ``root/devlearn`` by dotted name."""
    modules: dict[str, Module] = {}
    for path in sorted((root / "devlearn").rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        module = Module(path)
        tree = ast.parse(path.read_text())
        for node in tree.body:
            if isinstance(node, ast.FunctionDef):
                module.functions[node.name] = node
            elif isinstance(node, ast.ClassDef):
                for item in node.body:
                    if isinstance(item, ast.FunctionDef):
                        module.functions[f"{node.name}.{item.name}"] = item
        for node in ast.walk(tree):  # imports anywhere (inside functions too)
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("devlearn"):
                for alias in node.names:
                    module.imports[alias.asname or alias.name] = (node.module or "", alias.name)
            elif isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("devlearn"):
                        module.imports[alias.asname or alias.name] = (alias.name, "")
        modules[".".join(parts)] = module
    return modules


def target(
    modules: dict[str, Module], where: str, owner: str, call: ast.Call
) -> tuple[str, str] | None:
    """The (module, function) ``call`` names, or None where it names no devlearn function."""
    module = modules[where]
    func = call.func
    if isinstance(func, ast.Name):
        if func.id in module.functions:
            return where, func.id
        if func.id in module.imports:
            source, name = module.imports[func.id]
            if source in modules and name in modules[source].functions:
                return source, name
            if source in modules and name in modules[source].imports:  # a re-export
                return target_of_name(modules, source, name)
        return None
    if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name):
        base = func.value.id
        if base in ("self", "cls") and owner:
            name = f"{owner}.{func.attr}"
            return (where, name) if name in module.functions else None
        if base in module.imports:  # ``import devlearn.x as base``, ``from devlearn import x``
            source, name = module.imports[base]
            source = f"{source}.{name}" if name else source
            if source in modules and func.attr in modules[source].functions:
                return source, func.attr
    return None


def target_of_name(modules: dict[str, Module], where: str, name: str) -> tuple[str, str] | None:
    """Follow a name re-exported by ``where`` to the module that defines it."""
    source, original = modules[where].imports[name]
    if source in modules and original in modules[source].functions:
        return source, original
    return None


def returns(func: ast.FunctionDef) -> int:
    """``return`` statements in ``func``'s own body (nested functions and lambdas excluded)."""
    count = 0
    stack: list[ast.AST] = list(func.body)
    while stack:
        node = stack.pop()
        if isinstance(node, ast.Return):
            count += 1
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        stack.extend(ast.iter_child_nodes(node))
    return count


def walk(
    root: Path, tools: set[tuple[str, str]] | None = None
) -> tuple[list[Path], int, list[tuple[str, str, int]]]:
    """The files touched, the returns counted and each function entered (module, name,
    returns), from :data:`START`, not walking ``tools`` (default :data:`TOOLS`)."""
    tools = TOOLS if tools is None else tools
    modules = parse(root)
    seen: set[tuple[str, str]] = set()
    entered: list[tuple[str, str, int]] = []
    files: list[Path] = []
    stack = [START]
    while stack:
        where, name = stack.pop()
        if (where, name) in seen:
            continue
        seen.add((where, name))
        path = modules[where].path
        if path not in files:
            files.append(path)
        if (where, name) in tools:
            entered.append((where, name + " (tool, not walked)", 0))
            continue
        func = modules[where].functions[name]
        entered.append((where, name, returns(func)))
        owner = name.split(".")[0] if "." in name else ""
        calls = [node for node in ast.walk(func) if isinstance(node, ast.Call)]
        for call in sorted(calls, key=lambda node: (node.lineno, node.col_offset), reverse=True):
            found = target(modules, where, owner, call)
            if found is not None and found not in seen:
                stack.append(found)
    return [p.relative_to(root) for p in files], sum(n for _, _, n in entered), entered


def main(argv: list[str] | None = None) -> int:
    """Print the walk's files and returns, then every function entered."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=str(Path(__file__).resolve().parent.parent))
    parser.add_argument("--all", action="store_true", help="walk the tools too")
    args = parser.parse_args(argv)
    files, total, entered = walk(Path(args.root), set() if args.all else None)
    print(f"{len(files)} files, {total} returns")
    for path in files:
        print(f"  {path}")
    for where, name, count in entered:
        print(f"    {where}.{name}: {count} returns")
    return 0


if __name__ == "__main__":
    sys.exit(main())
