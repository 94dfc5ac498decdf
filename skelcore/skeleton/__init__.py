"""The skeletonizer (Laplacian-based contraction, Cao et al. 2010) and the paper's degradations.

``pipeline.skeletonize`` is the entry point; ``contraction`` and ``curve_extraction`` are its two
stages; ``degrade`` holds the noise models and downsamplers of the paper's study.
"""

from .params import CaoParams, SkeletonizeInfo, SkeletonizeParams
from .pipeline import skeletonize
from .contraction import contract
from .curve_extraction import extract_curve

__all__ = ["CaoParams", "SkeletonizeParams", "SkeletonizeInfo", "skeletonize", "contract", "extract_curve"]
