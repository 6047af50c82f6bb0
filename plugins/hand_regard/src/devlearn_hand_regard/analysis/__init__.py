"""Offline analyses of hand regard's published policies (issue #39's, run as
``python -m devlearn_hand_regard.analysis.NAME``): which hand the detector credits on a
policy's own frames (:mod:`.attribution`), gated attribution rules (:mod:`.gate`) and the
visibility model's predictions (:mod:`.view_prior`)."""
