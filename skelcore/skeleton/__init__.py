"""The skeletonizers (Laplacian-based contraction, Cao et al. 2010) and the paper's degradations.

``pipeline.skeletonize`` is the entry point: ``method="cao"`` (default) is the authors' toolbox
step by step (``cao_ring``, ``cao``, ``cao_curve``), ``method="skelscope"`` our variant
(``contraction`` + ``curve_extraction``); ``solve`` is their shared linear solve; ``degrade`` holds
the noise models and downsamplers of the paper's study. docs/skeletonize.md has the details.
"""

from .skeleton_params import CaoParams, SkeletonizeInfo, SkeletonizeParams
from .pipeline import METHODS, skeletonize
from .contraction import contract
from .curve_extraction import extract_curve

__all__ = ["CaoParams", "SkeletonizeParams", "SkeletonizeInfo", "METHODS", "skeletonize", "contract",
           "extract_curve"]
