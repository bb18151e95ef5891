"""The design loop from Python: ``kappe.optimize(file_or_text)`` is ``kappe optimize`` (the same
library function, ``kappe::design_loop``): vary the free parameters within their bounds until
every constraint holds, with the least material."""

from __future__ import annotations

import json
from typing import Any, Callable, Dict, Optional

from . import _kappe
from ._source import PathOrText, read_source

__all__ = ["optimize", "OptimizeResult"]


class OptimizeResult:
    """``design`` (the best :class:`kappe.Design` found), ``document`` (``optimize.json`` as a
    dict: every evaluation, the path taken, the verification), ``report`` (the text ``kappe
    optimize`` prints) and ``feasible`` (every constraint holds in the verification)."""

    def __init__(self, design_toml: str, document: str, report: str, feasible: bool) -> None:
        from . import Design

        self.design_toml = design_toml
        self.design = Design.from_toml(design_toml)
        self.document: Dict[str, Any] = json.loads(document)
        self.report = report
        self.feasible = feasible

    def write(self, directory: str, force: bool = False) -> Optional[str]:
        """Writes ``design.toml`` and ``optimize.json`` like ``kappe optimize --out``, under its
        rule: a new directory, or one Kappe wrote, is replaced atomically; anything else raises
        ``ValueError`` unless ``force``, which moves it aside (nothing is deleted)."""
        files = [
            ("design.toml", self.design_toml.encode()),
            ("optimize.json", json.dumps(self.document, indent=2).encode()),
        ]
        return _kappe.write_output(directory, files, force, "python optimize")

    def __repr__(self) -> str:
        evaluations = len(self.document["result"]["evaluations"])
        return f"OptimizeResult(feasible={self.feasible}, evaluations={evaluations})"


def optimize(
    file: PathOrText,
    max_evaluations: Optional[int] = None,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> OptimizeResult:
    """Run the design loop of an optimize file (or a design file with an ``[optimize]`` table):
    ``file`` is a path or the TOML text. ``progress(evaluation)`` is called on this thread after
    every evaluation with its dict (``evaluation``, ``parameters``, ``volume_m3``,
    ``violation``, ``failing``, ``accepted``); raising from it, or Ctrl-C, stops the loop after
    the evaluation under way (KeyboardInterrupt). The GIL is released while it runs."""
    if max_evaluations is not None and (isinstance(max_evaluations, bool) or not isinstance(max_evaluations, int)):
        raise TypeError(f"max_evaluations: expected a whole number, got {max_evaluations!r}")
    text, _, directory = read_source(file, "optimize file")
    if progress is not None and not callable(progress):
        raise TypeError("progress: expected a callable progress(evaluation)")
    on_eval = None if progress is None else (lambda e: progress(json.loads(e)))
    return OptimizeResult(*_kappe.optimize_design(text, directory, max_evaluations, on_eval))
