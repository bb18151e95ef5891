"""Design studies from Python: ``kappe.study(file_or_text, client=None)`` runs every design
of a study file (the format of ``kappe study``) locally in parallel, or on a Dask cluster
when given a ``dask.distributed.Client``. The rows equal those of ``kappe study``."""

from __future__ import annotations

import json
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Dict, List, Optional

from . import _kappe

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
        self.summaries = {r["record"]["name"]: r["summary"] for r in runs}
        self.reports = {r["record"]["name"]: r["report_html"] for r in runs}

    def write(self, directory: str) -> None:
        """Writes study.json, study.csv, study.html and designs/<name>/ like ``kappe study``."""
        os.makedirs(os.path.join(directory, "designs"), exist_ok=True)
        for name, text in (("study.json", self.json), ("study.csv", self.csv), ("study.html", self.html)):
            with open(os.path.join(directory, name), "w", encoding="utf-8") as f:
                f.write(text)
        for name, summary in self.summaries.items():
            d = os.path.join(directory, "designs", name)
            os.makedirs(d, exist_ok=True)
            if summary is not None:
                with open(os.path.join(d, "summary.json"), "w", encoding="utf-8") as f:
                    json.dump(summary, f, indent=2)
            if self.reports.get(name):
                with open(os.path.join(d, "report.html"), "w", encoding="utf-8") as f:
                    f.write(self.reports[name])

    def __repr__(self) -> str:
        return f"StudyResult(designs={len(self.rows)})"


def study(
    study: str,
    client: Optional[Any] = None,
    no_robot: bool = False,
    jobs: Optional[int] = None,
) -> StudyResult:
    """Run a study: ``study`` is a path to a study file or its TOML text. Locally the designs
    run in parallel threads (Kappe releases the GIL); with ``client`` (a
    ``dask.distributed.Client``) one task per design runs on the cluster."""
    if not isinstance(study, str):
        raise TypeError(f"study: expected a path or TOML text, got {type(study).__name__}")
    if os.path.isfile(study):
        with open(study, encoding="utf-8") as f:
            text = f.read()
        source, directory = os.path.basename(study), os.path.dirname(os.path.abspath(study))
    else:
        text, source, directory = study, "study.toml", os.getcwd()
    parsed = json.loads(_kappe.study_parse(text, source, directory))
    indices = [d["index"] for d in parsed["designs"]]
    if client is not None:
        futures = client.map(_run_one, [text] * len(indices), indices, [no_robot] * len(indices),
                             [source] * len(indices), [directory] * len(indices), pure=False)
        outputs = client.gather(futures)
    else:
        workers = jobs or os.cpu_count() or 1
        with ThreadPoolExecutor(max_workers=workers) as pool:
            outputs = list(pool.map(lambda i: _run_one(text, i, no_robot, source, directory), indices))
    runs = [json.loads(o) for o in outputs]
    records = json.dumps([r["record"] for r in runs])
    study_json, csv, html = _kappe.study_collect(text, records, no_robot, source, directory)
    return StudyResult(study_json, csv, html, runs)
