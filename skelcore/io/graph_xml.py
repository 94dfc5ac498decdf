"""GraphML and GEXF graphs (networkx's ``write_graphml`` / ``write_gexf``, Gephi) as curve skeletons,
and a GraphML writer that networkx reads back.

A node's position is its x, y, z attributes (any case), a "pos"-like attribute holding three numbers,
or GEXF's ``viz:position``; a ``radius`` attribute is kept. The XML is parsed by expat with entity
declarations and external entities refused (no "billion laughs", no file or network reads), so an
untrusted file cannot expand or fetch anything.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable
from xml.parsers import expat

import numpy as np

from ..errors import SkelInputError
from ._common import RawData
from .atomic import atomic_open

__all__ = ["is_graphml", "is_gexf", "read_graphml", "read_gexf", "write_graphml"]

_POSITION_NAMES = ("pos", "position", "xyz", "coords", "coordinates", "point")
_RADIUS_NAMES = ("radius", "r", "radii")
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|inf", re.IGNORECASE)


def is_graphml(text_head: str) -> bool:
    return "<graphml" in text_head[:4096]


def is_gexf(text_head: str) -> bool:
    return "<gexf" in text_head[:4096]


@dataclass
class _Element:
    tag: str
    attrib: dict[str, str]
    children: list["_Element"] = field(default_factory=list)
    text: str = ""

    def find_all(self, tag: str) -> list["_Element"]:
        return [c for c in self.children if c.tag == tag]

    def first(self, tag: str) -> "_Element | None":
        return next((c for c in self.children if c.tag == tag), None)


def _parse(data: bytes, path: Path) -> _Element:
    """A small element tree from expat; namespaces dropped from tag names; DTD entities refused."""
    parser = expat.ParserCreate(namespace_separator="}")
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    root = _Element("", {})
    stack = [root]

    def refuse(*_args) -> None:
        raise SkelInputError("XML declares entities; not read (entity expansion is refused for safety)", path)

    def start(name: str, attrs: dict[str, str]) -> None:
        el = _Element(name.rsplit("}", 1)[-1], {k.rsplit("}", 1)[-1]: v for k, v in attrs.items()})
        stack[-1].children.append(el)
        stack.append(el)

    def end(_name: str) -> None:
        stack.pop()

    def text(chunk: str) -> None:
        stack[-1].text += chunk

    parser.EntityDeclHandler = refuse
    parser.UnparsedEntityDeclHandler = refuse
    parser.ExternalEntityRefHandler = refuse
    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise SkelInputError(f"malformed XML: {expat.ErrorString(exc.code)} at line {exc.lineno}", path) from None
    if not root.children:
        raise SkelInputError("XML file has no root element", path)
    return root.children[0]


def _numbers(text: str) -> list[float]:
    return [float(t) for t in _NUMBER.findall(text)]


def _to_curve(
    node_ids: list[str], attrs: list[dict[str, str]], edges: list[tuple[str, str]], path: Path, fmt: str,
    positions: list[list[float] | None] | None = None,
) -> RawData:
    """Nodes with named attributes (strings) and edges by node id -> RawData (vertices in node order)."""
    if not node_ids:
        raise SkelInputError(f"{fmt} graph has no nodes", path)
    lower = [{k.lower(): v for k, v in a.items()} for a in attrs]
    xyz = np.full((len(node_ids), 3), np.nan)
    for k, a in enumerate(lower):
        pos = positions[k] if positions is not None else None
        if pos is None and all(c in a for c in "xyz"):
            pos = [float(a[c]) for c in "xyz"]
        if pos is None:
            name = next((n for n in _POSITION_NAMES if n in a), None)
            pos = _numbers(a[name]) if name else None
        if pos is None or len(pos) != 3:
            have = ", ".join(attrs[k]) or "none"
            raise SkelInputError(
                f"{fmt} node {node_ids[k]!r} has no 3-D position (expected x, y, z or a 'pos' attribute "
                f"of three numbers; its attributes: {have})",
                path,
            )
        xyz[k] = pos
    index = {n: k for k, n in enumerate(node_ids)}
    if len(index) != len(node_ids):
        raise SkelInputError(f"{fmt} graph has two nodes with the same id", path)
    try:
        e = np.array([(index[a], index[b]) for a, b in edges], dtype=np.int64).reshape(-1, 2)
    except KeyError as exc:
        raise SkelInputError(f"{fmt} edge refers to node {exc.args[0]!r}, which is not in the graph", path) from None
    rname = next((n for n in _RADIUS_NAMES if all(n in a for a in lower)), None)
    radius = None if rname is None else np.array([float(a[rname]) for a in lower])
    return RawData(vertices=xyz, edges=e, format=fmt, radius=radius)


def read_graphml(path: Path, data: bytes) -> RawData:
    """The first ``<graph>`` of a GraphML file: ``<key>`` names (with their ``<default>``) give each
    node's ``<data>`` its attribute name."""
    root = _parse(data, path)
    if root.tag != "graphml":
        raise SkelInputError(f"not a GraphML file (root element <{root.tag}>)", path)
    names: dict[str, str] = {}
    defaults: dict[str, str] = {}
    for key in root.find_all("key"):
        if key.attrib.get("for", "node") in ("node", "all"):
            kid = key.attrib.get("id", "")
            names[kid] = key.attrib.get("attr.name", kid)
            default = key.first("default")
            if default is not None:
                defaults[names[kid]] = default.text.strip()
    graph = root.first("graph")
    if graph is None:
        raise SkelInputError("GraphML file has no <graph> element", path)
    ids, attrs = [], []
    for node in graph.find_all("node"):
        a = dict(defaults)
        for d in node.find_all("data"):
            key = d.attrib.get("key", "")
            if key in names:
                a[names[key]] = d.text.strip()
        ids.append(node.attrib.get("id", ""))
        attrs.append(a)
    edges = [(e.attrib.get("source", ""), e.attrib.get("target", "")) for e in graph.find_all("edge")]
    return _to_curve(ids, attrs, edges, path, "GraphML")


def read_gexf(path: Path, data: bytes) -> RawData:
    """A GEXF graph: ``viz:position`` (with z) or node attributes x, y, z / pos; ``<attvalue>`` ids are
    named by the ``<attributes class="node">`` block."""
    root = _parse(data, path)
    if root.tag != "gexf":
        raise SkelInputError(f"not a GEXF file (root element <{root.tag}>)", path)
    graph = root.first("graph")
    if graph is None:
        raise SkelInputError("GEXF file has no <graph> element", path)
    titles: dict[str, str] = {}
    for block in graph.find_all("attributes"):
        if block.attrib.get("class", "node") == "node":
            for att in block.find_all("attribute"):
                titles[att.attrib.get("id", "")] = att.attrib.get("title", att.attrib.get("id", ""))
    nodes_el = graph.first("nodes")
    ids, attrs, positions = [], [], []
    for node in nodes_el.find_all("node") if nodes_el is not None else []:
        a: dict[str, str] = {}
        values = node.first("attvalues")
        for av in values.find_all("attvalue") if values is not None else []:
            key = av.attrib.get("for", av.attrib.get("id", ""))
            a[titles.get(key, key)] = av.attrib.get("value", "")
        viz = node.first("position")
        pos = None
        if viz is not None and all(c in viz.attrib for c in "xyz"):
            pos = [float(viz.attrib[c]) for c in "xyz"]
        ids.append(node.attrib.get("id", ""))
        attrs.append(a)
        positions.append(pos)
    edges_el = graph.first("edges")
    edges = [(e.attrib.get("source", ""), e.attrib.get("target", ""))
             for e in (edges_el.find_all("edge") if edges_el is not None else [])]
    return _to_curve(ids, attrs, edges, path, "GEXF", positions)


def write_graphml(
    path: str | os.PathLike, vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray | None = None, *,
    inputs: Iterable[str | os.PathLike] = (),
) -> None:
    """A curve as GraphML: nodes ``n0``, ``n1``, ... with double x, y, z (and radius) attributes, as
    networkx's ``read_graphml`` expects; numbers written with ``repr`` round-trip exactly."""
    v = np.asarray(vertices, dtype=np.float64)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    names = ["x", "y", "z"] + ([] if radius is None else ["radius"])
    cols = [v[:, 0], v[:, 1], v[:, 2]] + ([] if radius is None else [np.asarray(radius, dtype=np.float64)])
    out = ["<?xml version='1.0' encoding='utf-8'?>",
           '<graphml xmlns="http://graphml.graphdrawing.org/xmlns">']
    out += [f'  <key id="d{k}" for="node" attr.name="{n}" attr.type="double" />' for k, n in enumerate(names)]
    out.append('  <graph edgedefault="undirected">')
    table = np.column_stack(cols) if len(v) else np.empty((0, len(cols)))
    for i, row in enumerate(table.tolist()):
        data = "".join(f'<data key="d{k}">{val!r}</data>' for k, val in enumerate(row))
        out.append(f'    <node id="n{i}">{data}</node>')
    out += [f'    <edge source="n{a}" target="n{b}" />' for a, b in e.tolist()]
    out += ["  </graph>", "</graphml>"]
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write("\n".join(out) + "\n")
