#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Dependent components (IndependentComponentsOff) on a tetrahedralized wavelet: MTPT (both
backends), VTK's vtkProjectedTetrahedraMapper and the exact reference, for four unsigned-char
components (RGBA) and two float components (colour scalar, opacity scalar), from three
directions. Prints each image's covered-pixel RMSE and worst pixel (in 0-255) against VTK's PT
and against the reference, and writes a picture: per case, MTPT, VTK's PT, the reference.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/dependent-components.py
         [--size 256] [--extent 15] [--picture dependent_components.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless)."""
import argparse
import math

from vtkmodules.vtkCommonCore import vtkFloatArray, vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid
from vtkmodules.vtkFiltersCore import vtkImageAppend
from vtkmodules.vtkRenderingCore import vtkRenderWindow
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper
import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=256)
parser.add_argument("--extent", type=int, default=15, help="wavelet extent: -E..E per axis")
parser.add_argument("--picture", default="dependent_components.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)
VIEWS = ((30, 20), (210, -10), (100, 60))  # azimuth, elevation


def with_components(grid, kind):
    """A copy of `grid` whose active point scalars are dependent components."""
    data = grid.GetPointData().GetArray("RTData")
    low, high = data.GetRange()
    rgba = vtkUnsignedCharArray() if kind == "rgba8" else vtkFloatArray()
    rgba.SetName(kind)
    rgba.SetNumberOfComponents(4 if kind == "rgba8" else 2)
    rgba.SetNumberOfTuples(grid.GetNumberOfPoints())
    e = float(args.extent)
    for i in range(grid.GetNumberOfPoints()):
        x, y, z = (c / e for c in grid.GetPoint(i))
        s = (data.GetValue(i) - low) / (high - low)
        if kind == "rgba8":
            values = (s, 0.5 + 0.5 * math.sin(3 * x + y), 0.5 + 0.5 * math.cos(2 * z - y),
                      max(0.0, min(1.0, 1.6 * s - 0.4)) * 0.6)
            rgba.SetTuple(i, [math.floor(255 * v + 0.5) for v in values])
        else:
            rgba.SetTuple(i, (s, 0.5 + 0.5 * math.sin(2.5 * x - 1.5 * y + z)))
    copy = vtkUnstructuredGrid()
    copy.ShallowCopy(grid)
    copy.GetPointData().SetScalars(rgba)
    return copy


def dependent_property():
    prop = figures.volume_property(
        colours=((0.0, 0.2, 0.3, 0.9), (0.5, 0.95, 0.95, 0.6), (1.0, 0.9, 0.2, 0.1)),
        opacities=((0.0, 0.0), (0.4, 0.02), (1.0, 0.5)), unit_distance=2.0)
    prop.IndependentComponentsOff()
    return prop


def render(grid, mapper, view, multisamples=None):
    """The image (RGB doubles, the window's bytes / 255), the renderer and volume."""
    renderer, volume = figures.volume_scene(grid, mapper, dependent_property(), BACKGROUND)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    if multisamples is not None:
        window.SetMultiSamples(multisamples)
    window.SetSize(args.size, args.size)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(view[0])
    renderer.GetActiveCamera().Elevation(view[1])
    renderer.GetActiveCamera().OrthogonalizeViewUp()
    renderer.ResetCameraClippingRange()
    window.Render()
    return figures.grab(window), renderer, volume, window


_, grid = figures.wavelet(args.extent)
print(f"tetrahedralized wavelet: {grid.GetNumberOfCells()} tetrahedra, {args.size}x{args.size}")
rows = []
for kind in ("rgba8", "two"):
    data = with_components(grid, kind)
    for v, view in enumerate(VIEWS):
        theirs, *_ = render(data, vtkProjectedTetrahedraMapper(), view, multisamples=0)
        exact = None
        for backend in (Mapper.OPENGL_BACKEND, Mapper.CPU_BACKEND):
            mapper = Mapper()
            mapper.SetBackend(backend)
            ours, renderer, volume, window = render(data, mapper, view)
            if exact is None:
                exact = figures.reference(renderer, volume)
            name = "gl" if backend == Mapper.OPENGL_BACKEND else "cpu"
            vtk_rmse, vtk_worst = figures.difference(ours, theirs, BACKGROUND, 255)
            ref_rmse, ref_worst = figures.difference(ours, exact, BACKGROUND, 255)
            print(f"{kind:5s} view {v} {name:3s}: against VTK's PT RMSE {vtk_rmse:5.2f} worst "
                  f"{vtk_worst:3.0f}; against the reference RMSE {ref_rmse:5.2f} worst "
                  f"{ref_worst:3.0f} (of 255)")
            if v == 0 and backend == Mapper.CPU_BACKEND:
                pt_rmse, pt_worst = figures.difference(theirs, exact, BACKGROUND, 255)
                print(f"{kind:5s} view 0 VTK's PT against the reference RMSE {pt_rmse:5.2f} "
                      f"worst {pt_worst:3.0f}")
                row = vtkImageAppend()
                row.SetAppendAxis(0)
                for image in (ours, theirs, exact):
                    row.AddInputData(image)
                row.Update()
                rows.append(row.GetOutput())
            mapper.ReleaseGraphicsResources(window)
figures.write_picture(args.picture, list(reversed(rows)), 1)  # first case on top
print(f"wrote {args.picture}: rows four unsigned chars, two floats; columns MTPT (CPU backend), "
      "VTK's PT, the exact reference")
