# SPDX-License-Identifier: BSD-3-Clause
"""Shared by the Python tests: the blunt fin, a scene drawn off-screen, image metrics.

The tests import ``mtpt`` from wherever Python finds it: the build tree (ctest sets
PYTHONPATH) or an installed package (Testing/Python/pip_install.sh)."""
import math
import os

import pytest

SOURCE = os.environ.get("MTPT_SOURCE_DIR",
                        os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
DATA = os.path.join(SOURCE, "Data", "bluntfin_tets.vtu")
BACKGROUND = (0.1, 0.1, 0.2)


def load():
    """The blunt fin (187,395 tetrahedra), with Density as its active scalars."""
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(DATA)
    reader.Update()
    grid = reader.GetOutput()
    grid.GetPointData().SetActiveScalars("Density")
    return grid


def rmse(a, b):
    """Root mean square difference of two equally long sequences of values in [0, 1]."""
    assert len(a) == len(b) and len(a) > 0
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)) / len(a))


def covered_pixels(rgb, background, tolerance=2 / 255):
    """Indices of the RGB pixels (flat, values in [0, 1]) that differ from the background."""
    return [p for p in range(len(rgb) // 3)
            if any(abs(rgb[3 * p + c] - background[c]) > tolerance for c in range(3))]


@pytest.fixture(scope="session")
def bluntfin():
    return load()
