"""JSON Schemas (draft 2020-12) of the documents other tools read, shipped with the package.

- ``evaluation``: the ``skelcore evaluate --json`` document (:func:`skelcore.io.evaluation_files.to_json_dict`),
  also the ``evaluation`` member of a compare job's record.
- ``compare_job``: a compare job's record, ``jobs/KEY.json`` (:mod:`skelcore.compare.job_store`).
- ``results_csv``: one row of compare's ``results.csv`` as :class:`csv.DictReader` reads it (column ->
  cell text); its ``$defs/header`` describes the ordered header row (:mod:`skelcore.compare.results_csv`).
- ``edit_log``: the edits of a curve skeleton in order (:mod:`skelcore.edit`, ``skelcore edit``).

Every document carries :data:`SCHEMA_VERSION` (the top level of the evaluation document, each job
record, the last column of results.csv): additive changes bump the minor, removals and renames the
major; each schema accepts every minor of its major. docs/output_formats.md describes the fields.

The schemas refer to each other by their ``$id`` (``urn:skelscope:schema:NAME``): :func:`validator`
gives a jsonschema validator that resolves them (jsonschema is needed only there).
"""

from .schema_files import NAMES, SCHEMA_VERSION, schema, schema_id, validator

__all__ = ["SCHEMA_VERSION", "NAMES", "schema", "schema_id", "validator"]
