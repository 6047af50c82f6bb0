"""Config resolution is one pipeline a reader can follow (issue #59): the walk of
``resolve_run``'s calls (``scripts/walk_resolve.py``) touches at most 4 files and meets at
most 5 ``return`` statements."""

from __future__ import annotations

import importlib.util
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _walker():
    spec = importlib.util.spec_from_file_location("walk_resolve", ROOT / "scripts/walk_resolve.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_the_resolve_walk_touches_at_most_4_files_and_5_returns():
    files, returns, entered = _walker().walk(ROOT)
    assert len(files) <= 4 and returns <= 5, (files, returns)
    walked = {(module, name) for module, name, _ in entered if "(tool" not in name}
    # every stage is a function of the pipeline's module; the core defaults the dataclasses'
    outside = {(m, n) for m, n in walked if m != "devlearn.config.resolve"}
    assert outside == {("devlearn.config.run_config", "new_config")}
    assert len(walked) >= 8  # the stages, not one function hiding them


def test_the_walk_counts_files_and_returns_and_stops_at_tools(tmp_path):
    """The measure can fail: a pipeline calling a helper in another module (two returns),
    its own helper (one) and a tool (whose body is not walked) is counted as such."""
    package = tmp_path / "devlearn" / "config"
    package.mkdir(parents=True)
    (tmp_path / "devlearn" / "__init__.py").write_text("")
    (package / "__init__.py").write_text("")
    (package / "values.py").write_text(
        textwrap.dedent(
            """
            def apply_overrides(cfg, items):
                return helper(cfg)

            def helper(cfg):
                return cfg
            """
        )
    )
    (package / "other.py").write_text(
        textwrap.dedent(
            """
            def build(x):
                if x:
                    return 1
                return 2
            """
        )
    )
    (package / "resolve.py").write_text(
        textwrap.dedent(
            """
            from devlearn.config import other
            from devlearn.config.values import apply_overrides

            def resolve_run(request, registry):
                cfg = _start(request)
                apply_overrides(cfg, [])
                registry.behavior(cfg)  # a call on an object handed in: not followed
                return other.build(cfg)

            def _start(request):
                def nested():
                    return 0  # a nested function's return is not the stage's
                return request
            """
        )
    )
    walker = _walker()
    files, returns, _ = walker.walk(tmp_path)
    assert sorted(str(f) for f in files) == [
        "devlearn/config/other.py",
        "devlearn/config/resolve.py",
        "devlearn/config/values.py",
    ]
    assert returns == 1 + 1 + 2  # resolve_run, _start, other.build; not the tool's
    files, returns, _ = walker.walk(tmp_path, tools=set())
    assert len(files) == 3 and returns == 1 + 1 + 2 + 1 + 1  # the tool and its helper too
