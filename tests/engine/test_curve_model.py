import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError


def test_self_loops_and_duplicate_edges_are_dropped():
    v = np.eye(3)
    c = CurveSkeleton.from_raw(v, [[0, 1], [1, 0], [1, 1], [1, 2], [2, 1]])
    assert c.edges.tolist() == [[0, 1], [1, 2]]
    assert c.degrees().tolist() == [1, 2, 1]


def test_nan_vertices_and_their_edges_are_dropped_with_a_warning():
    v = np.array([[0, 0, 0], [np.nan, 0, 0], [1, 0, 0], [2, 0, 0]], float)
    with pytest.warns(UserWarning, match="NaN"):
        c = CurveSkeleton.from_raw(v, [[0, 1], [1, 2], [2, 3]], path="s.ply")
    assert c.n_vertices == 3
    assert c.edges.tolist() == [[1, 2]]
    assert c.vertex_map.tolist() == [0, 2, 3]


def test_edge_index_out_of_range_names_file_and_index():
    with pytest.raises(SkelInputError, match=r"s\.obj: edge index 5 out of range for 3 vertices"):
        CurveSkeleton.from_raw(np.eye(3), [[0, 5]], path="s.obj")
    with pytest.raises(SkelInputError, match="-1"):
        CurveSkeleton.from_raw(np.eye(3), [[0, -1]], path="s.obj")


def test_inf_vertex_is_an_error():
    with pytest.raises(SkelInputError, match="inf"):
        CurveSkeleton.from_raw([[0, 0, np.inf], [0, 0, 0]], [[0, 1]])


def test_edge_lengths():
    c = CurveSkeleton.from_raw([[0, 0, 0], [3, 4, 0]], [[1, 0]])
    assert c.edge_lengths().tolist() == [5.0]
