"""Reads a .vtu file with VTK's own reader and checks what plydem's test expects of it.

usage: check_vtu.py FILE POINTS CELLS CELL_TYPE NAME=SUM[:COMPONENTS] ...

Each NAME is a point-data or cell-data array (or "points" for the point coordinates) whose absolute
values, summed over all tuples and components, must equal SUM to 1e-12 relative (1e-300 absolute), and
which must have COMPONENTS components (1 if not given). Exits non-zero with a message on the first
mismatch.
"""
import sys

from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader


def fail(message):
    print(f"check_vtu.py: {message}")
    sys.exit(1)


def main(argv):
    if len(argv) < 5:
        fail(__doc__)
    path, points, cells, cell_type = argv[1], int(argv[2]), int(argv[3]), int(argv[4])
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        fail(f"{path}: reader error code {reader.GetErrorCode()}")
    grid = reader.GetOutput()
    if grid.GetNumberOfPoints() != points:
        fail(f"{path}: {grid.GetNumberOfPoints()} points, expected {points}")
    if grid.GetNumberOfCells() != cells:
        fail(f"{path}: {grid.GetNumberOfCells()} cells, expected {cells}")
    for c in range(cells):
        if grid.GetCellType(c) != cell_type:
            fail(f"{path}: cell {c} has type {grid.GetCellType(c)}, expected {cell_type}")
        for k in range(grid.GetCell(c).GetNumberOfPoints()):
            if not 0 <= grid.GetCell(c).GetPointId(k) < points:
                fail(f"{path}: cell {c} refers to a missing point")
    for spec in argv[5:]:
        name, value = spec.split("=", 1)
        expected_components = 1
        if ":" in value:
            value, components = value.split(":")
            expected_components = int(components)
        expected = float(value)
        if name == "points":
            array = grid.GetPoints().GetData()
            tuples = points
        else:
            array = grid.GetPointData().GetArray(name)
            tuples = points
            if array is None:
                array = grid.GetCellData().GetArray(name)
                tuples = cells
            if array is None:
                fail(f"{path}: no array named {name}")
        if array.GetNumberOfTuples() != tuples:
            fail(f"{path}: {name} has {array.GetNumberOfTuples()} tuples, expected {tuples}")
        if array.GetNumberOfComponents() != expected_components:
            fail(f"{path}: {name} has {array.GetNumberOfComponents()} components, "
                 f"expected {expected_components}")
        total = 0.0
        for t in range(array.GetNumberOfTuples()):
            for c in range(array.GetNumberOfComponents()):
                total += abs(array.GetComponent(t, c))
        if abs(total - expected) > 1e-12 * abs(expected) + 1e-300:
            fail(f"{path}: {name} sums to {total!r}, expected {expected!r}")
    print(f"check_vtu.py: {path} OK ({points} points, {cells} cells, {len(argv) - 5} arrays)")


if __name__ == "__main__":
    main(sys.argv)
