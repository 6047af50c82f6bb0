"""Evaluation: ``evaluate()`` of a checkpoint or baseline, policy files (``devlearn slim``),
export to ONNX or TorchScript, the report over evaluations and a behaviour's description."""
