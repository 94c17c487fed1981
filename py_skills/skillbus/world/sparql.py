"""SkiROS2's ``query_ontology`` on the world-model client: the SPARQL query goes to the
world model server (RPC wm.sparql, answered by Rasqal over the server's ontology, the
loaded scene's other triples and the world's elements; the server's prefixes are declared
for the query), and the SPARQL 1.1 JSON results come back as SkiROS2 gives them: one
string per row, each value followed by a space when the row has more than one; with
``cut_prefix`` an IRI as "prefix:name", else in N3 ("<iri>"); a literal as its text (N3
with its datatype when not cut); unbound values left out. An ASK answers ["true"] or
["false"].

    >>> rows_as_strings({"head": {"vars": ["x"]}, "results": {"bindings": [
    ...     {"x": {"type": "uri", "value": "http://rvmi.aau.dk/ontologies/skiros.owl#Cube"}}]}},
    ...     {"skiros": "http://rvmi.aau.dk/ontologies/skiros.owl#"}, cut_prefix=True)
    ['skiros:Cube']

An unbound value (an OPTIONAL that matched nothing) is left out of its row:

    >>> rows_as_strings({"head": {"vars": ["x", "v"]}, "results": {"bindings": [
    ...     {"x": {"type": "uri", "value": "http://rvmi.aau.dk/ontologies/skiros.owl#Cube-3"}},
    ...     {"x": {"type": "uri", "value": "http://rvmi.aau.dk/ontologies/skiros.owl#Cube-4"},
    ...      "v": {"type": "unbound", "value": None}}]}},
    ...     {"skiros": "http://rvmi.aau.dk/ontologies/skiros.owl#"}, cut_prefix=True)
    ['skiros:Cube-3 ', 'skiros:Cube-4 ']
"""

from __future__ import annotations

import json
from typing import Any

from skillbus.msgs import wm_scene_t


def compact(iri: str, prefixes: dict[str, str]) -> str:
    best = max((p for p, ns in prefixes.items() if iri.startswith(ns)), key=lambda p: len(prefixes[p]), default=None)
    return f"{best}:{iri[len(prefixes[best]):]}" if best is not None else iri


def value_text(v: dict[str, Any], prefixes: dict[str, str], cut_prefix: bool) -> str:
    kind, text = v.get("type"), v.get("value", "")
    if kind == "uri":
        return compact(text, prefixes) if cut_prefix else f"<{text}>"
    if kind == "bnode":
        return f"_:{text}"
    if cut_prefix:
        return text
    quoted = json.dumps(text, ensure_ascii=False)
    if v.get("xml:lang"):
        return f"{quoted}@{v['xml:lang']}"
    return f"{quoted}^^<{v['datatype']}>" if v.get("datatype") else quoted


def rows_as_strings(results: dict[str, Any], prefixes: dict[str, str], cut_prefix: bool = True) -> list[str]:
    if "boolean" in results:
        return ["true" if results["boolean"] else "false"]
    names = results.get("head", {}).get("vars", [])
    out = []
    for row in results.get("results", {}).get("bindings", []):
        line = ""
        for name in names:
            if name not in row or row[name].get("type") == "unbound":
                continue  # (unbound: SkiROS2 leaves it out; the server's rows have no key for it)
            line += value_text(row[name], prefixes, cut_prefix) + (" " if len(names) > 1 else "")
        out.append(line)
    return out


class SparqlQueries:
    """Mixed into WorldModelInterface (which provides _call and timeout)."""

    def query_ontology(self, query: str, cut_prefix: bool = True, context: str = "") -> list[str]:
        """SkiROS2's query_ontology (`context` is accepted and ignored: the server has one
        graph). Raises WorldModelError with the server's reason for a query it refuses
        (a syntax error with its line, FROM or SERVICE, results too large for a reply)."""
        rep = self.sparql(query)
        return rows_as_strings(rep["results"], rep["prefixes"], cut_prefix)

    def sparql(self, query: str) -> dict[str, Any]:
        """The server's answer as it is: {"results": SPARQL 1.1 JSON results, "prefixes":
        {prefix: namespace}, "version": the world's version it answered at}."""
        req = wm_scene_t()
        req.turtle = query
        rep = self._call("sparql", req, wm_scene_t, timeout=max(self.timeout, 10.0))  # type: ignore[attr-defined]
        return {"results": json.loads(rep.turtle), "prefixes": json.loads(rep.report or "{}"), "version": rep.version}
