"""Researchers' Python objects in and out: Open3D, trimesh, networkx, navis, cloud-volume /
kimimaro skeletons and pandas tables become SkelScope's inputs (:mod:`.objects_in`, recognised by
:mod:`.recognise` without importing any of those libraries); an Evaluation becomes a pandas table
(:mod:`.tables`), a networkx graph (:mod:`.graph_out`) or a coloured Open3D LineSet (:mod:`.open3d_out`).
"""

from .objects_in import curve_parts, is_curve_object, points_of
from .recognise import EXPECTED_CURVE, EXPECTED_POINTS, kind_of

__all__ = ["points_of", "curve_parts", "is_curve_object", "kind_of", "EXPECTED_POINTS", "EXPECTED_CURVE"]
