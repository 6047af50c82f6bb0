"""Evaluation: an :class:`~devlearn.evaluation.evaluate.Evaluation` of a checkpoint or baseline
under an :class:`~devlearn.evaluation.evaluate.EvalRequest`, policy files (``devlearn slim``),
export to ONNX or TorchScript, the report over evaluations and a behaviour's description."""
