#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The measurements behind the level of detail's design (Documentation/level-of-detail.md):

  grid    moving frames at fixed cell fractions and image sample distances: the median frame
          and the covered RMSE of the last moving image against the full frame of the same
          view (the camera turning 7 degrees before every frame, as mtpt_bench_interactive).
  orders  the image error of a fraction of the cells chosen by the mapper's importance order
          against the same fraction chosen at random (extracted with vtkExtractCells), both
          with the attenuation compensated by the fraction drawn.

Scenes: the benchmark's (wavelet: vtkRTAnalyticSource over [-30, 30]^3 tetrahedralized,
1.08M tetrahedra; a .vtu file with --array), its transfer functions (cool-warm colours,
opacity rising linearly over the range, unit distance a fiftieth of the diagonal), the CPU
backend, VTK's default (multisampled) window on a white background.

usage: level-of-detail-study.py grid|orders [--mesh wavelet|FILE.vtu] [--array NAME]
                                 [--size 1024] [--fractions ...] [--distances ...]
Run with the Python that has VTK (/usr/bin/python3 on Debian) and the mtpt package on its
path, under a display, e.g.:
  PYTHONPATH=build/lib/python3/dist-packages Testing/xvfb-launch.sh /usr/bin/python3 \\
    scripts/figures/level-of-detail-study.py grid --mesh wavelet
"""
import argparse
import math
import statistics
import time

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkImagingCore import vtkRTAnalyticSource
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow,
                                         vtkVolume, vtkVolumeProperty, vtkWindowToImageFilter)
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

try:
    from vtkmodules.vtkFiltersCore import vtkExtractCells
except ImportError:  # VTK before 9.3
    from vtkmodules.vtkFiltersExtraction import vtkExtractCells

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper


def load(mesh, array):
    if mesh == "wavelet":
        source = vtkRTAnalyticSource()
        source.SetWholeExtent(-30, 30, -30, 30, -30, 30)
        tetrahedralize = vtkDataSetTriangleFilter()
        tetrahedralize.SetInputConnection(source.GetOutputPort())
        tetrahedralize.Update()
        return tetrahedralize.GetOutput()
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(mesh)
    reader.Update()
    grid = reader.GetOutput()
    if array:
        grid.GetPointData().SetActiveScalars(array)
    return grid


class Scene:
    """The grid in VTK's default window with the benchmark's transfer functions."""

    def __init__(self, grid, size):
        low, high = grid.GetPointData().GetScalars().GetRange()
        self.unit = grid.GetLength() / 50
        colour = vtkColorTransferFunction()
        colour.AddRGBPoint(low, 0.23, 0.30, 0.75)
        colour.AddRGBPoint(0.5 * (low + high), 0.87, 0.87, 0.87)
        colour.AddRGBPoint(high, 0.71, 0.02, 0.15)
        opacity = vtkPiecewiseFunction()
        opacity.AddPoint(low, 0.0)
        opacity.AddPoint(high, 1.0)
        self.property = vtkVolumeProperty()
        self.property.SetColor(colour)
        self.property.SetScalarOpacity(opacity)
        self.property.SetScalarOpacityUnitDistance(self.unit)
        self.mapper = Mapper()
        self.mapper.SetBackendToCPU()
        self.mapper.AutoAdjustSampleDistancesOff()
        self.mapper.AutoAdjustCellFractionOff()
        self.mapper.SetInputData(grid)
        volume = vtkVolume()
        volume.SetMapper(self.mapper)
        volume.SetProperty(self.property)
        self.renderer = vtkRenderer()
        self.renderer.AddVolume(volume)
        self.renderer.SetBackground(1, 1, 1)
        self.window = vtkRenderWindow()
        self.window.SetSize(size, size)
        self.window.AddRenderer(self.renderer)
        self.window.SetOffScreenRendering(1)
        camera = self.renderer.GetActiveCamera()
        self.renderer.ResetCamera()
        camera.Azimuth(30)
        camera.Elevation(20)
        camera.OrthogonalizeViewUp()
        self.window.Render()

    def frame(self, turn=7.0):
        self.renderer.GetActiveCamera().Azimuth(turn)
        self.renderer.ResetCameraClippingRange()
        start = time.perf_counter()
        self.window.Render()
        self.window.WaitForCompletion()
        return 1e3 * (time.perf_counter() - start)

    def image(self):
        grab = vtkWindowToImageFilter()
        grab.SetInput(self.window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.ShouldRerenderOff()
        grab.Update()
        return vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).astype(float)

    def full(self):
        """The full frame of the current view."""
        self.mapper.SetCellFraction(1)
        self.mapper.SetImageSampleDistance(1)
        self.window.Render()
        return self.image()


def covered_rmse(a, b):
    covered = np.any(np.abs(a - 255) > 2, axis=1) | np.any(np.abs(b - 255) > 2, axis=1)
    return math.sqrt(float(((a - b)[covered] ** 2).mean())) if covered.any() else 0.0


def grid_study(scene, fractions, distances):
    print("| cell fraction | " + " | ".join("d = %g" % d for d in distances) + " |")
    print("|---:|" + "---:|" * len(distances))
    for fraction in fractions:
        cells = []
        for distance in distances:
            scene.mapper.SetCellFraction(fraction)
            scene.mapper.SetImageSampleDistance(distance)
            times = [scene.frame() for _ in range(5)]
            moving = scene.image()
            error = covered_rmse(moving, scene.full())
            cells.append("%.0f ms, %.1f" % (statistics.median(times), error))
        print("| %g | %s |" % (fraction, " | ".join(cells)), flush=True)


def orders_study(scene, grid, fractions):
    full = scene.full()
    n = grid.GetNumberOfCells()
    random = np.random.default_rng(1).permutation(n)
    print("| fraction | importance order (RMSE of 255) | random (RMSE of 255) |")
    print("|---:|---:|---:|")
    for fraction in fractions:
        scene.mapper.SetCellFraction(fraction)
        scene.window.Render()
        ours = covered_rmse(scene.image(), full)
        kept = int(n * fraction)
        ids = vtkIdList()
        ids.SetNumberOfIds(kept)
        for k, cell in enumerate(np.sort(random[:kept])):
            ids.SetId(k, int(cell))
        extract = vtkExtractCells()
        extract.SetInputData(grid)
        extract.SetCellList(ids)
        extract.Update()
        scene.mapper.SetInputData(extract.GetOutput())
        scene.mapper.SetCellFraction(1)
        scene.property.SetScalarOpacityUnitDistance(scene.unit * kept / n)
        scene.window.Render()
        theirs = covered_rmse(scene.image(), full)
        scene.mapper.SetInputData(grid)
        scene.property.SetScalarOpacityUnitDistance(scene.unit)
        print("| %g | %.2f | %.2f |" % (fraction, ours, theirs), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("study", choices=["grid", "orders"])
    parser.add_argument("--mesh", default="wavelet")
    parser.add_argument("--array", default="")
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--fractions", default="1,0.5,0.25,0.125,0.0625")
    parser.add_argument("--distances", default="1,1.5,2,3,4,6")
    args = parser.parse_args()
    grid = load(args.mesh, args.array)
    scene = Scene(grid, args.size)
    fractions = [float(f) for f in args.fractions.split(",")]
    print("%s, %d tetrahedra, %dx%d\n" % (args.mesh, grid.GetNumberOfCells(), args.size, args.size))
    if args.study == "grid":
        print("Entries: median moving frame, covered RMSE (of 255) against the full frame of "
              "the same view.\n")
        grid_study(scene, fractions, [float(d) for d in args.distances.split(",")])
    else:
        orders_study(scene, grid, [f for f in fractions if f < 1])


if __name__ == "__main__":
    main()
