"""``devlearn new PLUGIN_NAME``: write an installable plugin distribution that passes its tests."""

from __future__ import annotations

import argparse
import contextlib
import keyword
import string
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from devlearn.api.errors import UsageError
from devlearn.config.checks import check_out_dir
from devlearn.files import NAME_MAX, temporary_name, write_text_atomically

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
        raise UsageError(f"plugin name '{name[:40]}' must be lower_snake_case (e.g. my_reach)")
    # its longest file name: tests/test_NAME.py, written first as .test_NAME.py.tmp-PID
    longest = NAME_MAX - len(temporary_name(Path("test_.py")).name)
    if len(name) > longest:
        raise UsageError(
            f"plugin name '{name[:40]}...' is {len(name)} characters; at most {longest} fit "
            f"the file names it makes ({NAME_MAX} bytes each)"
        )
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
        UsageError: A bad or too long name, a name an installed plugin already registers, an
            ``out`` that exists and is not empty or cannot be written (nothing is left of a
            write that fails).
    """
    subs = names_for(name)
    if registry is not None and name in registry.behaviors():
        plugin = registry.plugin_of(name)
        raise UsageError(
            f"behaviour '{name}' already exists (plugin '{plugin.name}'); pick another"
        )
    root = Path(out) if out else Path(subs["dist"])
    templates = resources.files("devlearn") / "templates" / "plugin"
    texts = {
        root / target.format(**subs): string.Template(
            templates.joinpath(template).read_text()
        ).substitute(subs)
        for template, target in FILES.items()
    }
    made: list[Path] = []  # what this call created, removed again if a write fails
    try:
        if root.exists() and (not root.is_dir() or any(root.iterdir())):
            raise UsageError(f"{root} already exists and is not empty; choose another --out")
        check_out_dir(root)
        for path, text in texts.items():
            missing = [p for p in (path.parent, *path.parent.parents) if not p.exists()]
            path.parent.mkdir(parents=True, exist_ok=True)
            made += reversed(missing)
            write_text_atomically(path, text)
            made.append(path)
    except OSError as exc:  # a name too long for the file system, a full disk, /proc...
        for path in reversed(made):
            with contextlib.suppress(OSError):
                path.rmdir() if path.is_dir() else path.unlink()
        raise UsageError(f"cannot write the plugin to {root}: {exc.strerror or exc}") from None
    return list(texts)


def run(args: argparse.Namespace, registry: PluginRegistry) -> int:
    """Write the plugin and print the next commands."""
    files = write_plugin(args.name, args.out, registry)
    root = files[0].parent
    print(f"wrote plugin '{args.name}' to {root}/ ({len(files)} files). Next:")
    print(f"  pip install -e {root}            # devlearn plugins now lists it")
    print(f"  python -m pytest {root}/tests    # conformance, reward by hand, a tiny run")
    print(f"  devlearn run {args.name} --steps 20000 --envs 4 --out runs/{args.name}")
    return 0
