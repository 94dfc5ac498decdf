"""Other skeletonizers runnable by name: ``kind = "pygel"``, ``"kimimaro"`` or
``"skimage"`` in a compare manifest, or :func:`run` from Python. One module per tool
(``pygel_ls``, ``kimimaro_teasar``, ``skimage_thinning``), the shared voxelization
(``voxelize``, ``voxel_graph``), the parameter checks (``adapter_params``), the ``registry`` and
the ``child`` process entry point. The tools are the optional ``[skeletonizers]`` extra.
"""

from .adapter_result import AdapterResult
from .registry import ADAPTERS, EXTRA, KINDS, params_of, require, resolve_params, run

__all__ = ["AdapterResult", "ADAPTERS", "EXTRA", "KINDS", "params_of", "require", "resolve_params", "run"]
