"""The plugin contract: what a plugin author reads, and all a plugin may import beside
``devlearn`` (which re-exports the main names) and :mod:`devlearn.testing`.

- :mod:`~devlearn.api.behavior`: :class:`Behavior`, :class:`Evaluator`, :class:`RunMetrics`.
- :mod:`~devlearn.api.rewards`: :class:`IntrinsicReward` (per environment),
  :class:`BatchedIntrinsicReward` (all environments of a worker at once) and their contexts.
- :mod:`~devlearn.api.learned`: :class:`LearnedReward`, a reward that is a model trained on the
  rollouts (:mod:`~devlearn.api.learned_update`: its torch side).
- :mod:`~devlearn.api.sensors` and :mod:`~devlearn.api.network_spec`: encoders and the network a
  behaviour asks for.
- :mod:`~devlearn.api.curriculum`: :class:`Curriculum` and its :class:`Stage`.
- :mod:`~devlearn.api.hookspecs`: every hook a plugin may implement (its reference doc).
- :mod:`~devlearn.api.errors`: :class:`UsageError`, the one-line error the CLI reports.
- :mod:`~devlearn.api.stats`: mean and t-interval of a sample (an evaluator's per-episode spread).
- :mod:`~devlearn.api.json_files`: the guarded reader of the JSON files a command is given
  (regular files of bounded size and nesting; each refusal one :class:`UsageError` line).

This layer imports nothing of the infant, environments, training, evaluation or CLI (the
infant's type only for annotations); ``lint-imports`` checks it (docs/architecture.md).
"""
