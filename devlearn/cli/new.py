"""``devlearn new PLUGIN_NAME``: write an installable plugin distribution that passes its tests."""

from __future__ import annotations

import argparse
import keyword
import string
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError

if TYPE_CHECKING:
    from devlearn.plugins import PluginRegistry

# Template file -> where it goes in the new distribution (``{module}``: the import name).
FILES = {
    "pyproject.toml.tmpl": "pyproject.toml",
    "README.md.tmpl": "README.md",
    "__init__.py.tmpl": "src/{module}/__init__.py",
    "plugin.py.tmpl": "src/{module}/plugin.py",
    "behavior.py.tmpl": "src/{module}/behavior.py",
    "test_plugin.py.tmpl": "tests/test_{name}.py",
}


def names_for(name: str) -> dict[str, str]:
    """The template's substitutions for behaviour ``name`` (``my_reach``)."""
    from devlearn.plugins import PLUGIN_NAME  # the registry's own rule for a behaviour's name

    if not PLUGIN_NAME.match(name) or keyword.iskeyword(name):
        raise UsageError(f"plugin name '{name}' must be lower_snake_case (e.g. my_reach)")
    return {
        "name": name,
        "module": f"devlearn_{name}",
        "dist": "devlearn-" + name.replace("_", "-"),
        "cls": "".join(part.capitalize() for part in name.split("_")),
    }


def write_plugin(
    name: str, out: str | Path | None = None, registry: PluginRegistry | None = None
) -> list[Path]:
    """Write the plugin distribution for ``name`` into ``out``; return the files written.

    Raises:
        UsageError: A bad name, a name an installed plugin already registers, or an ``out``
            that exists and is not empty.
    """
    subs = names_for(name)
    if registry is not None and name in registry.behaviors():
        plugin = registry.plugin_of(name)
        raise UsageError(
            f"behaviour '{name}' already exists (plugin '{plugin.name}'); pick another"
        )
    root = Path(out) if out else Path(subs["dist"])
    if root.exists() and (not root.is_dir() or any(root.iterdir())):
        raise UsageError(f"{root} already exists and is not empty; choose another --out")
    templates = resources.files("devlearn") / "templates" / "plugin"
    written = []
    for template, target in FILES.items():
        text = string.Template(templates.joinpath(template).read_text()).substitute(subs)
        path = root / target.format(**subs)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        written.append(path)
    return written


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the plugin and print the next commands."""
    files = write_plugin(args.name, args.out, registry)
    root = files[0].parent
    print(f"wrote plugin '{args.name}' to {root}/ ({len(files)} files). Next:")
    print(f"  pip install -e {root}            # devlearn plugins now lists it")
    print(f"  python -m pytest {root}/tests    # conformance, reward by hand, a tiny run")
    print(f"  devlearn run {args.name} --steps 20000 --envs 4 --out runs/{args.name}")
    return 0
