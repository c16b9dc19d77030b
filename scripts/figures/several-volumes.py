#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Two volumes of their own transfer functions whose cells interleave in depth: the
tetrahedralized wavelet cut into slabs of its cells along x, given in turn to two volumes,
each with its own colour map, opacity and unit distance. Drawn by MTPT (the volumes drawn
together in one visibility order, both backends; and one after the other, as VTK draws
volumes, with CompositeWithOtherVolumes off), by VTK's PT (two volumes, one after the other),
and the exact reference of the two (vtkMTPTReferenceRenderer::RenderVolumes). Prints each image's
covered-pixel RMSE and worst pixel against the reference, and writes a picture: MTPT, VTK's
PT and the reference, each labelled.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/several-volumes.py
         [--size 360] [--extent 12] [--slabs 6] [--picture several_volumes.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless)."""
import argparse

from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkFiltersExtraction import vtkExtractCells
from vtkmodules.vtkRenderingCore import vtkVolume
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=360)
parser.add_argument("--extent", type=int, default=12, help="wavelet extent: -E..E per axis")
parser.add_argument("--slabs", type=int, default=6)
parser.add_argument("--picture", default="several_volumes.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)

# (colour nodes, opacity nodes, unit distance) of each volume over the wavelet's scalars.
FUNCTIONS = [
    (((40, 0.1, 0.3, 0.9), (160, 0.3, 0.8, 0.95), (280, 0.9, 0.95, 1.0)),
     ((40, 0.0), (130, 0.1), (280, 0.7)), 2.0),
    (((40, 0.95, 0.85, 0.2), (160, 0.95, 0.45, 0.1), (280, 0.7, 0.05, 0.05)),
     ((40, 0.0), (100, 0.2), (280, 0.5)), 1.5),
]


def halves(grid):
    """The grid's cells in `slabs` slabs along x by their centres, slab i to half i % 2."""
    centres = vtkCellCenters()
    centres.SetInputData(grid)
    centres.Update()
    points = centres.GetOutput().GetPoints()
    low, high = grid.GetBounds()[0:2]
    width = (high - low) / args.slabs
    ids = [vtkIdList(), vtkIdList()]
    for c in range(grid.GetNumberOfCells()):
        slab = min(args.slabs - 1, int((points.GetPoint(c)[0] - low) / width))
        ids[slab % 2].InsertNextId(c)
    parts = []
    for half in ids:
        extract = vtkExtractCells()
        extract.SetInputData(grid)
        extract.SetCellList(half)
        extract.Update()
        parts.append(extract.GetOutput())
    return parts


def properties():
    return [figures.volume_property(*f) for f in FUNCTIONS]


def two_volumes(parts, make_mapper):
    """A renderer of the two halves, each its own volume, mapper and property; its window."""
    renderer = None
    for part, prop in zip(parts, properties()):
        if renderer is None:
            renderer, _ = figures.volume_scene(part, make_mapper(), prop, BACKGROUND)
            continue
        mapper = make_mapper()
        mapper.SetInputData(part)
        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(prop)
        renderer.AddVolume(volume)
    return renderer, figures.window_for(renderer, args.size)


def mtpt(backend, together):
    def make():
        mapper = figures.mtpt_mapper(backend)
        mapper.SetCompositeWithOtherVolumes(together)
        return mapper
    return make


image_data, grid = figures.wavelet(args.extent)
parts = halves(grid)
print(f"wavelet: {grid.GetNumberOfCells()} tetrahedra in {args.slabs} slabs along x, two "
      f"volumes of {parts[0].GetNumberOfCells()} and {parts[1].GetNumberOfCells()}; "
      f"{args.size}x{args.size}, multisampled window")

# The exact reference of the two volumes together, in the view they are seen in.
renderer, window = two_volumes(parts, mtpt("CPU", True))
window.Render()
exact = figures.reference_of_volumes(renderer)

images = {}
contenders = [("MTPT, drawn together (CPU backend)", mtpt("CPU", True)),
              ("MTPT, drawn together (OpenGL backend)", mtpt("OpenGL", True)),
              ("MTPT, one after the other", mtpt("CPU", False)),
              ("VTK's PT, one after the other", vtkProjectedTetrahedraMapper)]
for name, make in contenders:
    renderer, window = two_volumes(parts, make)
    window.Render()
    window.Render()
    images[name] = figures.grab(window)
    rmse, worst = figures.difference(images[name], exact, BACKGROUND)
    print(f"{name:40s} against the reference: covered RMSE {rmse:.4f} ({rmse * 255:.2f}/255), "
          f"worst {worst:.3f}")

figures.write_picture(args.picture, [
    figures.labelled(images["MTPT, drawn together (CPU backend)"], "MTPT"),
    figures.labelled(images["VTK's PT, one after the other"], "VTK's PT"),
    figures.labelled(exact, "exact reference")], 0)
print(f"\nwrote {args.picture}: MTPT (drawn together, CPU backend), VTK's PT, the exact "
      "reference")
