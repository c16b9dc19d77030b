# SPDX-License-Identifier: BSD-3-Clause
"""The mapper from Python (Debian's python3-vtk9): import, settings, and a rendering
compared with VTK's own vtkProjectedTetrahedraMapper on the same scene."""
import math
import os
import sys
import traceback

from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet, vtkPiecewiseFunction
from vtkmodules.vtkFiltersCore import vtkCellCenters
from vtkmodules.vtkFiltersExtraction import vtkExtractCells
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer,
                                         vtkRenderWindow, vtkVolume, vtkVolumeProperty,
                                         vtkWindowToImageFilter)
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper

SOURCE = os.environ.get("MTPT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BACKGROUND = (0.1, 0.1, 0.2)


def load():
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(os.path.join(SOURCE, "Data", "bluntfin_tets.vtu"))
    reader.Update()
    grid = reader.GetOutput()
    grid.GetPointData().SetActiveScalars("Density")
    return grid


def render(grid, mapper, size=200, multisamples=None):
    color = vtkColorTransferFunction()
    color.AddRGBPoint(0.19, 0.2, 0.3, 0.9)
    color.AddRGBPoint(4.98, 0.9, 0.2, 0.1)
    opacity = vtkPiecewiseFunction()
    opacity.AddPoint(0.19, 0.05)
    opacity.AddPoint(4.98, 0.9)
    prop = vtkVolumeProperty()
    prop.SetColor(color)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(1.5)
    mapper.SetInputDataObject(grid)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(*BACKGROUND)
    renderer.AddVolume(volume)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    if multisamples is not None:
        window.SetMultiSamples(multisamples)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(30)
    renderer.GetActiveCamera().Elevation(20)
    renderer.ResetCameraClippingRange()
    window.Render()
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput().GetPointData().GetScalars()
    values = [image.GetValue(i) / 255.0 for i in range(image.GetNumberOfValues())]
    mapper.ReleaseGraphicsResources(window)
    return values


def test_import_and_settings():
    mapper = Mapper()
    assert mapper.GetClassName() == "vtkMultiThreadedProjectedTetrahedraMapper"
    assert mapper.IsA("vtkUnstructuredGridVolumeMapper")
    mapper.SetNumberOfThreads(2)
    assert mapper.GetNumberOfThreads() == 2
    mapper.SetNumberOfThreads(-1)  # rejected with a warning
    assert mapper.GetNumberOfThreads() == 2
    mapper.SetOrderMethodToPartitionSort()
    assert mapper.GetOrderMethod() == Mapper.PARTITION_SORT
    assert mapper.GetOrderMethodAsString() == "PartitionSort"
    mapper.SetBackendToCPU()
    assert mapper.GetBackend() == Mapper.CPU_BACKEND
    # Image sample distance: VTK's ray caster's defaults and range.
    assert mapper.GetAutoAdjustSampleDistances() == 1
    assert (mapper.GetImageSampleDistance(), mapper.GetMinimumImageSampleDistance(),
            mapper.GetMaximumImageSampleDistance()) == (1.0, 1.0, 10.0)
    mapper.AutoAdjustSampleDistancesOff()
    mapper.SetImageSampleDistance(2.5)
    assert mapper.GetImageSampleDistance() == 2.5
    mapper.SetImageSampleDistance(1000)  # clamped, as VTK's ray caster clamps it
    assert mapper.GetImageSampleDistance() == 100.0


def test_render_matches_vtk_pt():
    grid = load()
    # The mapper in the window VTK makes by default (multisampled); VTK's PT without
    # multisampling, where it does not speckle along cell edges (see the C++ image tests).
    ours = render(grid, Mapper())
    theirs = render(grid, vtkProjectedTetrahedraMapper(), multisamples=0)
    rmse = math.sqrt(sum((a - b) ** 2 for a, b in zip(ours, theirs)) / len(ours))
    covered = sum(1 for i in range(0, len(ours), 3)
                  if any(abs(ours[i + c] - BACKGROUND[c]) > 2 / 255 for c in range(3)))
    print("RMSE against vtkProjectedTetrahedraMapper: %.5f; covered pixels: %d" % (rmse, covered))
    # Measured 0.0083 (the C++ image tests explain the difference: the perspective sort and
    # VTK's 8-bit colours, concentrated near the fin's tip).
    assert rmse < 0.02, rmse
    assert covered > 0.15 * len(ours) / 3, covered


def test_multiblock_input_draws_as_the_single_grid():
    # The blunt fin cut into two blocks of interleaved slabs (their own points), as a
    # vtkMultiBlockDataSet: one visibility order over both blocks, the single grid's image.
    grid = load()
    centres = vtkCellCenters()
    centres.SetInputData(grid)
    centres.Update()
    low, high = grid.GetBounds()[0:2]
    halves = [vtkIdList(), vtkIdList()]
    for c in range(grid.GetNumberOfCells()):
        slab = int(6 * (centres.GetOutput().GetPoint(c)[0] - low) / (high - low))
        halves[min(slab, 5) % 2].InsertNextId(c)
    blocks = vtkMultiBlockDataSet()
    blocks.SetNumberOfBlocks(2)
    for b, cells in enumerate(halves):
        extract = vtkExtractCells()
        extract.SetInputData(grid)
        extract.SetCellList(cells)
        extract.Update()
        blocks.SetBlock(b, extract.GetOutput())
    single = render(grid, Mapper())
    composite = render(blocks, Mapper())
    rmse = math.sqrt(sum((a - b) ** 2 for a, b in zip(single, composite)) / len(single))
    print("multi-block input against the single grid: RMSE %.6f" % rmse)
    # The blocks renumber the cells, which can only reorder cells at exactly equal depth.
    assert rmse < 0.002, rmse
    assert any(abs(v - BACKGROUND[i % 3]) > 0.1 for i, v in enumerate(composite))


def main():
    tests = [test_import_and_settings, test_render_matches_vtk_pt,
             test_multiblock_input_draws_as_the_single_grid]
    failed = 0
    for test in tests:
        try:
            test()
            print("PASS", test.__name__)
        except Exception:  # report every failure, then exit non-zero
            failed += 1
            print("FAIL", test.__name__)
            traceback.print_exc()
    print("%d passed, %d failed" % (len(tests) - failed, failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
