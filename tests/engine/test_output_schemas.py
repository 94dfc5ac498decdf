"""The output formats' JSON Schemas (skelcore/io/schemas, docs/output_formats.md): each is a valid
draft 2020-12 schema read through the package, they agree with the code's column lists and version,
the ``evaluate --json`` documents the CLI writes validate, and a document missing a required key or
holding a wrong value does not. Compare's job records and results.csv: tests/compare/test_compare_schemas.py."""

from __future__ import annotations

import copy
import json
import re

import pytest

from skelcore import shapes
from skelcore.cli import main
from skelcore.compare.jobs import HELD_COLUMNS, SCORE_COLUMNS
from skelcore.compare.results_csv import COLUMNS
from skelcore.io import write_curve_ply, write_points_ply
from skelcore.io.schemas import NAMES, SCHEMA_VERSION, schema, schema_id, validator

jsonschema = pytest.importorskip("jsonschema")


@pytest.fixture(scope="module")
def documents(tmp_path_factory) -> dict[str, dict]:
    """evaluate --json on a generated Y: both skeletons; the curve alone against a reference curve with
    the scan options (ground_truth, reference and scan blocks; the skeletal blocks null)."""
    d = tmp_path_factory.mktemp("schemas")
    sh = shapes.y_shape(600, seed=2)
    write_points_ply(d / "cloud.ply", sh.cloud)
    write_points_ply(d / "skel.ply", sh.skeletal)
    write_curve_ply(d / "curve.ply", sh.curve_vertices, sh.curve_edges)
    runs = {
        "both": ["--skeletal", d / "skel.ply", "--curve", d / "curve.ply"],
        "curve_reference_scan": ["--curve", d / "curve.ply", "--reference-curve", d / "curve.ply",
                                 "--remove-outliers", "--viewpoint", "0", "0", "5"],
    }
    docs = {}
    for name, extra in runs.items():
        out = d / f"{name}.json"
        assert main([str(a) for a in ["evaluate", d / "cloud.ply", *extra, "--json", out, "--quiet"]]) == 0
        docs[name] = json.loads(out.read_text())
    return docs


def _errors(name: str, doc) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator(name).iter_errors(doc)]


@pytest.mark.parametrize("name", NAMES)
def test_each_schema_is_a_valid_draft_2020_12_schema_read_from_the_package(name):
    s = schema(name)
    jsonschema.Draft202012Validator.check_schema(s)
    assert s["$schema"] == "https://json-schema.org/draft/2020-12/schema" and s["$id"] == schema_id(name)
    # every document's schema_version: the version written now is accepted, another major is not
    version = s["properties"]["schema_version"]
    assert re.fullmatch(version["pattern"], SCHEMA_VERSION) and not re.fullmatch(version["pattern"], "2.0")
    assert schema(name) is not schema(name)  # a fresh copy each time: a caller's edit changes nothing
    with pytest.raises(KeyError, match="no schema"):
        schema("nonsense")


def test_the_schemas_name_the_columns_the_code_writes():
    job = schema("compare_job")
    # the held scores only where the shape's reference has facts (docs/compare.md "Ground truth")
    assert job["properties"]["scores"]["required"] == [k for k in SCORE_COLUMNS if k not in HELD_COLUMNS]
    assert list(job["properties"]["scores"]["properties"]) == list(SCORE_COLUMNS)
    row = schema("results_csv")
    assert row["required"] == [*COLUMNS, "schema_version"]
    assert [p["const"] for p in row["$defs"]["header"]["prefixItems"]] == list(COLUMNS)


def test_evaluate_documents_validate(documents):
    for name, doc in documents.items():
        assert doc["schema_version"] == SCHEMA_VERSION
        assert _errors("evaluation", doc) == [], name
    both, alone = documents["both"], documents["curve_reference_scan"]
    assert both["topology"] is not None and both["diagnostics"] is not None
    assert alone["ground_truth"] is not None and alone["reference"] is not None and "scan" in alone
    assert alone["topology"] is None and alone["inputs"]["skeletal"] is None


def test_nan_and_inf_are_written_as_the_schema_says(documents):
    """NaN -> null and inf -> "inf" (skelcore.io.json_numbers) validate; a bare string does not."""
    doc = copy.deepcopy(documents["both"])
    doc["topology"]["bottleneck"] = None
    doc["smoothness"]["curve"] = "inf"
    doc["coverage"]["skeletal"]["max_gap"] = "-inf"
    assert _errors("evaluation", doc) == []
    doc["boundedness"]["skeletal"] = "nan"
    assert _errors("evaluation", doc) == ["boundedness/skeletal: 'nan' is not valid under any of the given schemas"]


def test_an_evaluate_document_missing_a_required_key_or_with_a_wrong_type_fails(documents):
    for key in ("schema_version", "params", "counts", "warnings"):
        doc = copy.deepcopy(documents["both"])
        del doc[key]
        assert _errors("evaluation", doc) == [f": '{key}' is a required property"]
    doc = copy.deepcopy(documents["both"])
    del doc["inputs"]["cloud"]["n_points"]
    doc["schema_version"] = "2.0"
    doc["counts"]["boundedness"]["curve"] = 1.5
    doc["correspondence"] = "sideways"
    assert len(_errors("evaluation", doc)) == 4
    # an added key is not an error (additive changes stay within the major version)
    doc = copy.deepcopy(documents["both"])
    doc["a_later_block"] = {"x": 1}
    doc["topology"]["a_later_field"] = 2
    assert _errors("evaluation", doc) == []
