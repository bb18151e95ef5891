"""Kappe: 3D-printed cap ceilings from Python (Rhino 8, COMPAS, Jupyter).

The same pipeline as the ``kappe`` command line (it is the same Rust library):

>>> import kappe
>>> d = kappe.Design()                      # the default design
>>> d["cap"]["rise"] = 0.25
>>> r = kappe.design(d, progress=print)     # form-finding, analysis, robot plan
>>> r.ok, r.summary["mass_kg"], r.path.points.shape

Coordinates and forces come as NumPy arrays. ``Design`` and ``Result`` follow the COMPAS 2
data conventions (``__data__``, ``__from_data__``, ``dtype``) so ``compas.json_dump`` can store
them; COMPAS is not required.
"""

from __future__ import annotations

import copy
import json
import math
from collections.abc import MutableMapping
from functools import cached_property
from typing import Any, Callable, Dict, Iterator, List, Mapping, Optional

import numpy as np

from . import _kappe
from ._kappe import DesignError as _NativeDesignError

__all__ = [
    "Design",
    "DesignError",
    "Result",
    "design",
    "optimize",
    "OptimizeResult",
    "study",
    "buildability_monte_carlo",
    "design_monte_carlo",
    "ceiling",
    "CeilingResult",
    "cem",
    "fe",
    "robot",
]

__version__ = _kappe.__version__

DesignError = _NativeDesignError
"""A design outside what Kappe accepts (a ``ValueError``). ``args`` are
``(message, field, value, allowed)``; the properties ``field``, ``value``, ``allowed`` read them."""


def _prop(i: int):
    return property(lambda self: self.args[i] if len(self.args) > i else "")


DesignError.field = _prop(1)  # type: ignore[attr-defined]
DesignError.value = _prop(2)  # type: ignore[attr-defined]
DesignError.allowed = _prop(3)  # type: ignore[attr-defined]


def _check_plain(value: Any, path: str) -> None:
    """Reject what TOML cannot hold, naming the field: NaN/inf, None, non-string keys."""
    if isinstance(value, bool) or isinstance(value, (int, str)):
        return
    if isinstance(value, float):
        if not math.isfinite(value):
            raise DesignError(
                f"design field `{path}` = {value}: not a finite number", path, str(value), "a finite number"
            )
        return
    if isinstance(value, Mapping):
        for k, v in value.items():
            if not isinstance(k, str):
                raise DesignError(f"design field `{path}`: key {k!r} is not a string", path, repr(k), "string keys")
            _check_plain(v, f"{path}.{k}" if path else k)
        return
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_plain(v, f"{path}[{i}]")
        return
    if isinstance(value, np.generic):
        _check_plain(value.item(), path)
        return
    raise DesignError(
        f"design field `{path}`: a {type(value).__name__} is not a design value",
        path,
        repr(value),
        "numbers, strings, lists, tables",
    )


def _plain(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


class _CompasData:
    """The COMPAS 2 JSON protocol (``compas.json_dump``/``json_load``) without importing compas."""

    dtype = ""

    @property
    def __dtype__(self) -> str:
        return self.dtype

    def __jsondump__(self, minimal: bool = False) -> Dict[str, Any]:
        return {"dtype": self.dtype, "data": self.__data__}

    @classmethod
    def __jsonload__(cls, data: Mapping[str, Any], guid: Any = None, name: Any = None):
        return cls.__from_data__(data)


class Design(_CompasData, MutableMapping):
    """A cap design: a dict in the design file's schema (``cap``, ``material``, ``print``,
    ``constraints``, ``robot``, ``analysis``), every field filled in.

    ``Design()`` is the default design; ``Design({"cap": {"rise": 0.25}})`` overrides fields.
    Every construction validates: an unknown field, a wrong type or a value out of range raises
    :class:`DesignError` naming the field and what is allowed.
    """

    dtype = "kappe/Design"

    def __init__(self, data: Optional[Mapping[str, Any]] = None, **fields: Any) -> None:
        overrides: Dict[str, Any] = dict(data or {})
        overrides.update(fields)
        _check_plain(overrides, "")
        if overrides:
            toml_text = _kappe.design_from_json(json.dumps(_plain(overrides), allow_nan=False))
        else:
            # No overrides: the default design (a design *file* that sets nothing is an error).
            toml_text = _kappe.default_design_toml()
        self._data: Dict[str, Any] = json.loads(_kappe.design_to_json(toml_text))

    # -- the mapping ----------------------------------------------------------------------------
    def __getitem__(self, key: str) -> Any:
        return self._data[key]

    def __setitem__(self, key: str, value: Any) -> None:
        self._data[key] = value

    def __delitem__(self, key: str) -> None:
        del self._data[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._data)

    def __len__(self) -> int:
        return len(self._data)

    # -- construction -------------------------------------------------------------------------
    @classmethod
    def from_toml(cls, text: str) -> "Design":
        """A design from the text of a design file."""
        return cls(json.loads(_kappe.design_to_json(_kappe.design_from_toml(text))))

    @classmethod
    def from_file(cls, path: str) -> "Design":
        with open(path, encoding="utf-8") as f:
            return cls.from_toml(f.read())

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Design":
        return cls(data)

    def to_dict(self) -> Dict[str, Any]:
        return copy.deepcopy(self._data)

    def to_toml(self) -> str:
        """The design file text (every field); ``kappe design`` reads it."""
        _check_plain(self._data, "")
        return _kappe.design_from_json(json.dumps(_plain(self._data), allow_nan=False))

    def validate(self) -> "Design":
        """Check the (possibly edited) design; raises :class:`DesignError`."""
        self.to_toml()
        return self

    # -- COMPAS 2 data conventions ------------------------------------------------------------
    @property
    def __data__(self) -> Dict[str, Any]:
        return self.to_dict()

    @classmethod
    def __from_data__(cls, data: Mapping[str, Any]) -> "Design":
        return cls(data)

    def copy(self) -> "Design":
        return Design(self.to_dict())

    def __repr__(self) -> str:
        return f"Design(name={self.get('name')!r}, span={self['cap']['span']}, rise={self['cap']['rise']})"


def _as_design(d: Any) -> Design:
    if isinstance(d, Design):
        return d
    if d is None:
        return Design()
    if isinstance(d, str):
        return Design.from_toml(d)
    if isinstance(d, Mapping):
        return Design(d)
    raise TypeError(f"design: expected a kappe.Design, a dict or TOML text, got {type(d).__name__}")


class Layer:
    """One printed layer: its nodes (n×3, m), segment forces (N) and stresses (Pa) in the
    final state, and its overhang over the layer before (m; None for the first)."""

    def __init__(self, data: Mapping[str, Any]) -> None:
        self.id: int = data["id"]
        self.nodes = np.asarray(data["nodes"], dtype=float).reshape(-1, 3)
        self.segment_forces = np.asarray(data["segment_forces"], dtype=float)
        self.segment_stress = np.asarray(data["segment_stress"], dtype=float)
        self.overhang: Optional[float] = data.get("overhang")

    @classmethod
    def _from_arrays(
        cls, id: int, nodes: np.ndarray, forces: np.ndarray, stress: np.ndarray, overhang: Optional[float]
    ) -> "Layer":
        layer = cls.__new__(cls)
        layer.id, layer.nodes, layer.segment_forces, layer.segment_stress = id, nodes, forces, stress
        layer.overhang = overhang
        return layer

    @property
    def __data__(self) -> Dict[str, Any]:
        return {
            "id": self.id,
            "nodes": self.nodes.tolist(),
            "segment_forces": self.segment_forces.tolist(),
            "segment_stress": self.segment_stress.tolist(),
            "overhang": self.overhang,
        }

    def __repr__(self) -> str:
        return f"Layer(id={self.id}, nodes={len(self.nodes)})"


class PrintPath:
    """The print path: tip points (n×3, m), tool axes (n×3), layer id per point, the printed
    length (m) and the time at the print speed (s)."""

    def __init__(self, data: Mapping[str, Any]) -> None:
        self.points = np.asarray(data["points"], dtype=float).reshape(-1, 3)
        self.axis = np.asarray(data["axis"], dtype=float).reshape(-1, 3)
        self.layer = np.asarray(data["layer"], dtype=int)
        self.length: float = data["print_length_m"]
        self.time: float = data.get("time_s", float("nan"))

    @classmethod
    def _from_arrays(
        cls, points: np.ndarray, axis: np.ndarray, layer: np.ndarray, length: float, time: float
    ) -> "PrintPath":
        path = cls.__new__(cls)
        path.points, path.axis, path.layer, path.length, path.time = points, axis, layer, length, time
        return path

    @property
    def __data__(self) -> Dict[str, Any]:
        return {
            "points": self.points.tolist(),
            "axis": self.axis.tolist(),
            "layer": self.layer.tolist(),
            "print_length_m": self.length,
            "time_s": self.time,
        }


class Result(_CompasData):
    """What :func:`design` found: ``summary`` (the dict ``kappe design`` writes as
    summary.json), ``ok`` (the verdict), ``states`` (one dict per print state), ``layers``,
    ``path``, ``trajectory`` (time and joints of the robot plan, or None), ``constraints``
    (the constraint report), ``network`` (the final state's network) and ``report_html``.

    Each part is converted from the native result when first read (arrays straight from
    Rust's vectors), so a run costs what ``kappe design``'s does."""

    dtype = "kappe/Result"

    _KEYS = (
        "summary",
        "ok",
        "print_time_s",
        "constraints",
        "layers",
        "path",
        "trajectory_csv",
        "network",
        "report_html",
    )

    def __init__(self, data: Optional[Mapping[str, Any]] = None, _native: Any = None) -> None:
        self._native = _native
        self._data: Dict[str, Any] = dict(data or {})
        if _native is None:
            missing = [k for k in ("summary", "ok", "print_time_s") if k not in self._data]
            if missing:
                raise ValueError(f"Result data: missing {', '.join(missing)}")

    def _raw(self, key: str, native: Callable[[Any], Any], default: Any = None) -> Any:
        if self._native is not None:
            return native(self._native)
        return self._data.get(key, default)

    @cached_property
    def summary(self) -> Dict[str, Any]:
        return self._raw("summary", lambda n: json.loads(n.summary_json()))

    @property
    def ok(self) -> bool:
        return bool(self._raw("ok", lambda n: n.ok))

    def write(self, directory: str, force: bool = False) -> Optional[str]:
        """Write the output directory ``kappe design --out`` writes (the same files, by the
        same library code): a new directory, or one Kappe wrote, is replaced atomically;
        anything else raises ``ValueError`` unless ``force``, which moves it aside (nothing is
        deleted). Returns a notice when something was moved aside."""
        if self._native is None:
            raise ValueError("this Result was restored from data; run kappe.design() to write its files")
        return _kappe.write_output(directory, self._native.files(), force, "python design")

    @property
    def print_time(self) -> float:
        return float(self._raw("print_time_s", lambda n: n.print_time))

    @property
    def states(self) -> List[Dict[str, Any]]:
        return self.summary.get("states", [])

    @cached_property
    def constraints(self) -> List[Dict[str, Any]]:
        return self._raw("constraints", lambda n: json.loads(n.constraints_json()), [])

    @cached_property
    def layers(self) -> List[Layer]:
        if self._native is not None:
            return [Layer._from_arrays(*t) for t in self._native.layers()]
        return [Layer(x) for x in self._data.get("layers", [])]

    @cached_property
    def path(self) -> PrintPath:
        if self._native is not None:
            return PrintPath._from_arrays(*self._native.path())
        return PrintPath(self._data["path"])

    @cached_property
    def network(self) -> Dict[str, Any]:
        return self._raw("network", lambda n: json.loads(n.network_json()), {})

    @cached_property
    def report_html(self) -> Optional[str]:
        return self._raw("report_html", lambda n: n.report_html())

    @cached_property
    def trajectory_csv(self) -> Optional[str]:
        """trajectory.csv as ``kappe design`` writes it (None without a robot plan)."""
        return self._raw("trajectory_csv", lambda n: n.trajectory_csv())

    @cached_property
    def _trajectory(self) -> Any:
        if self._native is not None:
            return self._native.trajectory()
        csv = self._data.get("trajectory_csv")
        if not csv:
            return None
        lines = [line for line in csv.splitlines() if line and not line.startswith("#")]
        rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
        return lines[0].split(","), np.asarray(rows, dtype=float).reshape(len(rows), -1)

    @property
    def trajectory(self) -> Optional[np.ndarray]:
        """The robot plan's trajectory (rows × columns of ``trajectory_header``), or None."""
        t = self._trajectory
        return None if t is None else t[1]

    @property
    def trajectory_header(self) -> List[str]:
        t = self._trajectory
        return [] if t is None else list(t[0])

    @property
    def node_xyz(self) -> np.ndarray:
        """Coordinates of the final state's network nodes (n×3, m)."""
        return np.asarray([n["xyz"] for n in self.network.get("nodes", [])], dtype=float).reshape(-1, 3)

    @property
    def blf(self) -> np.ndarray:
        """The buckling load factor of every state (NaN where not analysed)."""
        return np.asarray([np.nan if s.get("blf") is None else s["blf"] for s in self.states], dtype=float)

    @property
    def __data__(self) -> Dict[str, Any]:
        return {
            "summary": self.summary,
            "ok": self.ok,
            "print_time_s": self.print_time,
            "constraints": self.constraints,
            "layers": [layer.__data__ for layer in self.layers],
            "path": self.path.__data__,
            "trajectory_csv": self.trajectory_csv,
            "network": self.network,
            "report_html": self.report_html,
        }

    @classmethod
    def __from_data__(cls, data: Mapping[str, Any]) -> "Result":
        return cls(data)

    def __repr__(self) -> str:
        return f"Result(ok={self.ok}, states={len(self.states)}, layers={len(self.layers)})"


def design(
    design: Any = None,
    analysis: Any = "design",
    robot: bool = True,
    progress: Optional[Callable[[str, int, int], Any]] = None,
    allow_fail: bool = False,
    report: bool = True,
) -> Result:
    """Run the pipeline on a design, exactly as ``kappe design`` does.

    ``analysis``: ``"design"`` (the design's own ``[analysis]``, the default), ``None`` (no
    finite-element analysis) or a dict of analysis options (``{"states": "25%"}``).
    ``robot``: plan the robot. ``progress(stage, done, total)`` is called on this thread
    (``stage`` is ``"states"``, ``"analysis"`` or ``"robot"``); raising from it, or Ctrl-C,
    stops the run. The GIL is released while Kappe computes.
    """
    d = _as_design(design)
    if isinstance(analysis, str) and analysis == "design":
        analysis_json = None
    elif analysis is None:
        analysis_json = "null"
    elif isinstance(analysis, Mapping):
        _check_plain(dict(analysis), "analysis")
        analysis_json = json.dumps(_plain(dict(analysis)), allow_nan=False)
    else:
        raise TypeError('analysis: expected "design", None or a dict of analysis options')
    if progress is not None and not callable(progress):
        raise TypeError("progress: expected a callable progress(stage, done, total)")
    native = _kappe.run_design(d.to_toml(), analysis_json, bool(robot), bool(allow_fail), progress, bool(report))
    return Result(_native=native)


from . import cem, fe, robot  # noqa: E402  (submodules use the names above)
from ._buildability import buildability_monte_carlo  # noqa: E402
from ._ceiling import CeilingResult, ceiling  # noqa: E402
from ._design_mc import design_monte_carlo  # noqa: E402
from ._optimize import OptimizeResult, optimize  # noqa: E402
from ._study import study  # noqa: E402
