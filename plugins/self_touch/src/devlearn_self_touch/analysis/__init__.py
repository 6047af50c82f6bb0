"""Offline analyses of self-touch's published evaluations (issue #56 moved them here from
results/, run as ``python -m devlearn_self_touch.analysis.NAME``): the sources of the
per-episode imbalance (:mod:`.balance`, issue #43) and the table of every evaluated checkpoint
of issue #20's runs (:mod:`.checkpoint_table`)."""
