"""The version written into every output document, the shipped schemas' names and ids, and their
loaders (the package's ``__init__`` re-exports them; its docstring describes the schemas)."""


from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from typing import Any

__all__ = ["SCHEMA_VERSION", "NAMES", "schema", "schema_id", "validator"]

#: the version written into every document described here (one for all of them)
SCHEMA_VERSION = "1.0"

#: the shipped schemas: ``NAME.schema.json`` in this package
NAMES = ("evaluation", "compare_job", "results_csv", "edit_log")


def schema_id(name: str) -> str:
    """The ``$id`` of schema ``name`` (how the others refer to it)."""
    return f"urn:skelscope:schema:{name}"


@lru_cache(maxsize=None)
def _text(name: str) -> str:
    if name not in NAMES:
        raise KeyError(f"no schema {name!r} (known: {', '.join(NAMES)})")
    return resources.files(__package__).joinpath(f"{name}.schema.json").read_text(encoding="utf-8")


def schema(name: str) -> dict[str, Any]:
    """The schema ``name`` (one of :data:`NAMES`) as a dict (a fresh copy)."""
    return json.loads(_text(name))


def validator(name: str, part: str | None = None) -> Any:
    """A ``jsonschema.Draft202012Validator`` for schema ``name`` (or its ``$defs`` entry ``part``, such
    as results_csv's ``header``), every shipped schema registered, so a job record's ``evaluation`` is
    checked against the evaluation schema. Needs jsonschema >= 4.18: ``pip install 'skelscope[schemas]'``."""
    try:
        import jsonschema
        from referencing import Registry, Resource
    except ModuleNotFoundError:
        raise ModuleNotFoundError("validating against the schemas needs jsonschema >= 4.18, not installed: "
                                  "pip install 'skelscope[schemas]'") from None

    registry = Registry().with_resources(
        (schema_id(n), Resource.from_contents(schema(n))) for n in NAMES)
    target = schema(name) if part is None else {"$ref": f"{schema_id(name)}#/$defs/{part}"}
    return jsonschema.Draft202012Validator(target, registry=registry)
