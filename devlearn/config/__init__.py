"""A run's configuration: the nested dataclasses (:mod:`~devlearn.config.run_config`), built by
one pipeline from what a command asks for (:mod:`~devlearn.config.resolve`: ``resolve_run``),
``--set`` values and keys (:mod:`~devlearn.config.values`), every key described
(:mod:`~devlearn.config.help`) and the checks of a config before a run
(:mod:`~devlearn.config.checks`). Imports no torch."""
