# r: kappe
"""Rhino 8 (ScriptEditor, CPython 3.9): design the default cap and draw its layers and print path.

The `# r: kappe` line above makes Rhino 8 install the package. Outside Rhino, `main()` runs the
same computation and returns the polylines instead of drawing them (the tests call it).
"""

from typing import Any, List, Mapping, Optional, Tuple

import kappe

Point = Tuple[float, ...]


def polylines(result: kappe.Result) -> Tuple[List[List[Point]], List[Point]]:
    """The layers (one polyline per layer) and the print path, as lists of (x, y, z)."""
    layers = [[tuple(p) for p in layer.nodes] for layer in result.layers]
    path = [tuple(p) for p in result.path.points]
    return layers, path


def main(
    design: Optional[Mapping[str, Any]] = None, robot: bool = False
) -> Tuple[kappe.Result, List[List[Point]], List[Point]]:
    d = kappe.Design(design or {})
    result = kappe.design(d, robot=robot, progress=lambda stage, done, total: None)
    layers, path = polylines(result)
    try:
        import Rhino.Geometry as rg  # type: ignore[import-not-found]  # noqa: F401
        import scriptcontext as sc  # type: ignore[import-not-found]
    except ImportError:
        return result, layers, path
    for layer in layers:
        sc.doc.Objects.AddPolyline([rg.Point3d(*p) for p in layer])
    sc.doc.Objects.AddPolyline([rg.Point3d(*p) for p in path])
    sc.doc.Views.Redraw()
    return result, layers, path


if __name__ == "__main__":
    r = main()[0]
    print(r, "mass", round(r.summary["mass_kg"], 2), "kg, ok:", r.ok)
