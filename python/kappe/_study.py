"""Design studies from Python: ``kappe.study(file_or_text, client=None)`` runs every design
of a study file (the format of ``kappe study``) locally in parallel, or on a Dask cluster
when given a ``dask.distributed.Client``. The rows equal those of ``kappe study``."""

from __future__ import annotations

import json
from typing import Any, Dict, List, Optional

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["study", "StudyResult"]


def _run_one(text: str, index: int, no_robot: bool, source: str, directory: str) -> str:
    # A module-level function: Dask pickles it by reference to run it on the workers.
    return _kappe.study_run_one(text, index, no_robot, source, directory)


class StudyResult:
    """``rows`` (one dict per design, as study.json), ``csv``, ``html``, ``json``, and per
    design ``summaries[name]`` / ``reports[name]`` (None if it could not run)."""

    def __init__(self, study_json: str, csv: str, html: str, runs: List[Dict[str, Any]]) -> None:
        self.json = study_json
        self.data = json.loads(study_json)
        self.rows: List[Dict[str, Any]] = self.data["rows"]
        self.csv = csv
        self.html = html
        self._runs = runs
        self.summaries = {r["record"]["name"]: r["summary"] for r in runs}
        self.reports = {r["record"]["name"]: r["report_html"] for r in runs}

    def write(self, directory: str, force: bool = False) -> Optional[str]:
        """Writes study.json, study.csv, study.html and designs/<name>/{design.toml,
        summary.json, report.html} as ``kappe study`` does (the same bytes), under its rule: a
        new directory, or one Kappe wrote, is replaced atomically; anything else raises
        ``ValueError`` unless ``force``, which moves it aside (nothing is deleted)."""
        files = [
            (name, text.encode())
            for name, text in (("study.json", self.json), ("study.csv", self.csv), ("study.html", self.html))
        ]
        # Per design the files `kappe study` writes, made by the same library functions
        # (design.toml, summary.json, report.html): the same bytes.
        for run in self._runs:
            files.extend((name, text.encode()) for name, text in run.get("files", []))
        return _kappe.write_output(directory, files, force, "python study")

    def __repr__(self) -> str:
        return f"StudyResult(designs={len(self.rows)})"


def study(
    study: PathOrText,
    client: Optional[Any] = None,
    no_robot: bool = False,
    jobs: Optional[int] = None,
) -> StudyResult:
    """Run a study: ``study`` is a path to a study file or its TOML text. Locally the designs
    run in parallel on ``jobs`` threads (default one per core; the GIL is released), exactly as
    ``kappe study`` runs them; with ``client`` (a ``dask.distributed.Client``) one task per
    design runs on the cluster."""
    text, source, directory = read_source(study, "study")
    if client is not None:
        parsed = json.loads(_kappe.study_parse(text, source, directory))
        indices = [d["index"] for d in parsed["designs"]]
        n = len(indices)
        futures = client.map(_run_one, [text] * n, indices, [no_robot] * n, [source] * n, [directory] * n, pure=False)
        runs = [json.loads(o) for o in client.gather(futures)]
    else:
        # The same parallel run as `kappe study` (Rust threads, the GIL released).
        runs = json.loads(_kappe.study_run_local(text, no_robot, jobs, source, directory))
    records = json.dumps([r["record"] for r in runs])
    study_json, csv, html = _kappe.study_collect(text, records, no_robot, source, directory)
    return StudyResult(study_json, csv, html, runs)
