"""A run's configuration: the nested dataclasses (:mod:`~devlearn.config.run_config`), ``--set``
values and keys (:mod:`~devlearn.config.values`), every key described
(:mod:`~devlearn.config.help`) and the checks of a config before a run
(:mod:`~devlearn.config.checks`). Imports no torch."""
