# SPDX-License-Identifier: BSD-3-Clause
"""The mapper from Python (VTK's own wrapping): import, settings, and a rendering compared
with VTK's own vtkProjectedTetrahedraMapper on the same scene."""
from vtkmodules.vtkCommonCore import vtkIdList
from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet, vtkPiecewiseFunction, vtkPlane
from vtkmodules.vtkFiltersCore import vtkCellCenters
try:  # vtkFiltersCore in today's VTK, vtkFiltersExtraction in VTK 9.1
    from vtkmodules.vtkFiltersCore import vtkExtractCells
except ImportError:
    from vtkmodules.vtkFiltersExtraction import vtkExtractCells
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer,
                                         vtkRenderWindow, vtkVolume, vtkVolumeProperty,
                                         vtkWindowToImageFilter)
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper

from conftest import BACKGROUND, covered_pixels, rmse


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
    # Cell level of detail for moving frames: on, every cell until the view moves.
    assert mapper.GetAutoAdjustCellFraction() == 1
    assert mapper.GetCellFraction() == 1.0
    assert abs(mapper.GetMinimumCellFraction() - 0.05) < 1e-7  # a float
    mapper.AutoAdjustCellFractionOff()
    mapper.SetCellFraction(0.0)  # clamped
    assert abs(mapper.GetCellFraction() - 0.001) < 1e-9


def test_a_cell_fraction_draws_fewer_cells(bluntfin):
    """A quarter of the cells, compensated: close to the full image, not equal to it."""
    full_mapper = Mapper()
    full = render(bluntfin, full_mapper)
    mapper = Mapper()
    mapper.AutoAdjustCellFractionOff()
    mapper.SetCellFraction(0.25)
    quarter = render(bluntfin, mapper)
    assert mapper.GetNumberOfCellsLeftOut() > 0
    assert mapper.GetNumberOfTetrahedra() < full_mapper.GetNumberOfTetrahedra() / 3
    covered = covered_pixels(full, BACKGROUND)
    error = rmse([quarter[3 * p + c] for p in covered for c in range(3)],
                 [full[3 * p + c] for p in covered for c in range(3)])
    print("a quarter of the cells against all: covered RMSE %.4f" % error)
    assert 0 < error < 18 / 255, error


def test_a_clipping_plane_keeps_the_side_its_normal_points_to(bluntfin):
    """Two opposite planes through the fin's centre, from Python: each image keeps part of the
    volume, the two parts differ, and together they cover what the whole image covers."""
    whole = render(bluntfin, Mapper())
    bounds = bluntfin.GetBounds()
    centre = [0.5 * (bounds[2 * i] + bounds[2 * i + 1]) for i in range(3)]
    halves = []
    for sign in (1.0, -1.0):
        plane = vtkPlane()
        plane.SetOrigin(*centre)
        plane.SetNormal(sign, 0.0, 0.0)
        mapper = Mapper()
        mapper.AddClippingPlane(plane)
        halves.append(set(covered_pixels(render(bluntfin, mapper), BACKGROUND)))
    covered = set(covered_pixels(whole, BACKGROUND))
    print("covered pixels: whole %d, the two sides %d and %d" %
          (len(covered), len(halves[0]), len(halves[1])))
    for half in halves:
        assert 0.2 * len(covered) < len(half) < 0.8 * len(covered)
    assert len(halves[0] ^ halves[1]) > 0.5 * len(covered)
    assert len(covered - (halves[0] | halves[1])) < 0.01 * len(covered)


def test_blend_modes_from_python(bluntfin):
    """Maximum intensity through SetBlendModeToMaximumIntensity: its own image, and the order
    not needed; the minimum's differs from it; additive is opaque grey where it covers."""
    composite = render(bluntfin, Mapper())
    images = {}
    for name in ("MaximumIntensity", "MinimumIntensity", "Additive"):
        mapper = Mapper()
        getattr(mapper, "SetBlendModeTo" + name)()
        assert mapper.GetBlendModeAsString() == name
        images[name] = render(bluntfin, mapper)
        assert mapper.GetLastFrameReuse() & Mapper.ORDER_NOT_NEEDED
    covered = covered_pixels(images["MaximumIntensity"], BACKGROUND)
    assert len(covered) > 0.1 * len(composite) / 3
    assert rmse(images["MaximumIntensity"], composite) > 0.02
    assert rmse(images["MaximumIntensity"], images["MinimumIntensity"]) > 0.02
    grey = images["Additive"]
    spread = max(max(grey[3 * p:3 * p + 3]) - min(grey[3 * p:3 * p + 3])
                 for p in covered_pixels(grey, BACKGROUND))
    assert spread <= 1.5 / 255, spread


def test_render_matches_vtk_pt(bluntfin):
    grid = bluntfin
    # The mapper in the window VTK makes by default (multisampled); VTK's PT without
    # multisampling, where it does not speckle along cell edges (see the C++ image tests).
    ours = render(grid, Mapper())
    theirs = render(grid, vtkProjectedTetrahedraMapper(), multisamples=0)
    error = rmse(ours, theirs)
    covered = len(covered_pixels(ours, BACKGROUND))
    print("RMSE against vtkProjectedTetrahedraMapper: %.5f; covered pixels: %d" % (error, covered))
    # Measured 0.0083 (the C++ image tests explain the difference: the perspective sort and
    # VTK's 8-bit colours, concentrated near the fin's tip).
    assert error < 0.02, error
    assert covered > 0.15 * len(ours) / 3, covered


def test_multiblock_input_draws_as_the_single_grid(bluntfin):
    # The blunt fin cut into two blocks of interleaved slabs (their own points), as a
    # vtkMultiBlockDataSet: one visibility order over both blocks, the single grid's image.
    grid = bluntfin
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
    error = rmse(single, composite)
    print("multi-block input against the single grid: RMSE %.6f" % error)
    # The blocks renumber the cells, which can only reorder cells at exactly equal depth.
    assert error < 0.002, error
    assert any(abs(v - BACKGROUND[i % 3]) > 0.1 for i, v in enumerate(composite))

