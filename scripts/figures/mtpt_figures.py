# SPDX-License-Identifier: BSD-3-Clause
"""Shared parts of the figure scripts (dependent-components.py, depth-peeling.py,
clipping-planes.py): the tetrahedralized wavelet, a volume in a renderer and its window,
VTK's GPU ray caster as the figures set it, a window's image, the exact reference as an
image, and the covered-pixel difference of two images. Debian's python3 (python3-vtk9) with
the build's `mtpt` package on PYTHONPATH."""
import math

from vtkmodules.vtkCommonCore import vtkUnsignedCharArray
from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPiecewiseFunction, vtkUnstructuredGrid
from vtkmodules.vtkFiltersGeneral import vtkDataSetTriangleFilter
from vtkmodules.vtkFiltersCore import vtkImageAppend
from vtkmodules.vtkImagingCore import vtkRTAnalyticSource
from vtkmodules.vtkIOImage import vtkPNGWriter
from vtkmodules.vtkRenderingCore import (vtkColorTransferFunction, vtkRenderer, vtkRenderWindow,
                                         vtkVolume, vtkVolumeProperty, vtkWindowToImageFilter)

from vtkmodules.vtkRenderingVolume import vtkGPUVolumeRayCastMapper

from mtpt import vtkMTPTReferenceRenderer, vtkMultiThreadedProjectedTetrahedraMapper


def wavelet(extent):
    """VTK's wavelet over -extent..extent per axis, as image data and tetrahedralized."""
    source = vtkRTAnalyticSource()
    source.SetWholeExtent(-extent, extent, -extent, extent, -extent, extent)
    source.Update()
    image = vtkImageData()
    image.DeepCopy(source.GetOutput())
    tetra = vtkDataSetTriangleFilter()
    tetra.SetInputData(image)
    tetra.Update()
    grid = vtkUnstructuredGrid()
    grid.ShallowCopy(tetra.GetOutput())
    return image, grid


def volume_property(colours, opacities, unit_distance):
    """A volume property from (value, r, g, b) colour and (value, opacity) nodes."""
    colour = vtkColorTransferFunction()
    for node in colours:
        colour.AddRGBPoint(*node)
    opacity = vtkPiecewiseFunction()
    for node in opacities:
        opacity.AddPoint(*node)
    prop = vtkVolumeProperty()
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetScalarOpacityUnitDistance(unit_distance)
    return prop


def gpu_ray_cast():
    """VTK's GPU ray caster as the figures compare with it: a fixed sample distance of 0.1,
    no automatic adjustment."""
    mapper = vtkGPUVolumeRayCastMapper()
    mapper.AutoAdjustSampleDistancesOff()
    mapper.SetSampleDistance(0.1)
    return mapper


def mtpt_mapper(backend, shading="VTKCompatible"):
    """MTPT with `backend` ("CPU", "OpenGL") and `shading` ("VTKCompatible", "PreIntegrated"),
    every pixel and cell drawn (no automatic adjustment)."""
    mapper = vtkMultiThreadedProjectedTetrahedraMapper()
    getattr(mapper, "SetBackendTo" + backend)()
    getattr(mapper, "SetShadingModeTo" + shading)()
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetAutoAdjustCellFraction(0)
    return mapper


def volume_scene(data, mapper, prop, background):
    """A renderer of the given background holding `data` drawn by `mapper` with `prop`; returns
    the renderer and the volume."""
    mapper.SetInputData(data)
    volume = vtkVolume()
    volume.SetMapper(mapper)
    volume.SetProperty(prop)
    renderer = vtkRenderer()
    renderer.SetBackground(*background)
    renderer.AddVolume(volume)
    return renderer, volume


def window_for(renderer, size, multisamples=None):
    """An off-screen size x size window showing `renderer`, its camera reset and turned to the
    figures' view (35 degrees of azimuth, 20 of elevation); `multisamples` None keeps VTK's
    default (multisampled)."""
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    if multisamples is not None:
        window.SetMultiSamples(multisamples)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    camera = renderer.GetActiveCamera()
    camera.Azimuth(35)
    camera.Elevation(20)
    camera.OrthogonalizeViewUp()
    renderer.ResetCameraClippingRange()
    return window


def grab(window):
    """The window's back buffer as RGB image data (a copy), without rendering again."""
    g = vtkWindowToImageFilter()
    g.SetInput(window)
    g.SetInputBufferTypeToRGB()
    g.ReadFrontBufferOff()
    g.ShouldRerenderOff()
    g.Update()
    image = vtkImageData()
    image.DeepCopy(g.GetOutput())
    return image


def reference(renderer, volume):
    """The exact reference of `volume` in `renderer` (with its visible translucent actors),
    rounded to bytes as the window's image is, as RGB image data of the renderer's size."""
    exact = vtkMTPTReferenceRenderer()
    mapper = volume.GetMapper()
    if isinstance(mapper, vtkMultiThreadedProjectedTetrahedraMapper):  # VTK's base has none
        exact.SetAverageIPScalarRange(*mapper.GetAverageIPScalarRange())
    if not exact.Render(renderer, volume):
        raise RuntimeError("no reference image")
    return _rounded(exact, renderer)


def _rounded(exact, renderer):
    """The last image of reference renderer `exact`, rounded to bytes, as RGB image data."""
    values = exact.GetImage()
    pixels = vtkUnsignedCharArray()
    pixels.SetNumberOfComponents(3)
    pixels.SetNumberOfTuples(values.GetNumberOfTuples())
    for i in range(values.GetNumberOfTuples()):
        pixels.SetTuple(i, [min(255, max(0, math.floor(255 * v + 0.5)))
                            for v in values.GetTuple3(i)])
    width, height = renderer.GetSize()
    image = vtkImageData()
    image.SetDimensions(width, height, 1)
    image.GetPointData().SetScalars(pixels)
    return image


def reference_of_volumes(renderer):
    """The exact reference of every visible volume of `renderer` integrated together
    (vtkMTPTReferenceRenderer.RenderVolumes), rounded to bytes, as RGB image data."""
    exact = vtkMTPTReferenceRenderer()
    if not exact.RenderVolumes(renderer, renderer.GetVolumes()):
        raise RuntimeError("no reference image of the volumes")
    return _rounded(exact, renderer)


def difference(a, b, background, scale=1.0):
    """Covered-pixel RMSE and worst channel difference of two RGB images, in bytes / 255 *
    `scale` (1: [0, 1]; 255: 0-255). A pixel is covered unless both images are within 2 of
    `background` (RGB in [0, 1]) in every channel."""
    a, b = a.GetPointData().GetScalars(), b.GetPointData().GetScalars()
    bg = [255 * c for c in background]
    total, count, worst = 0.0, 0, 0.0
    for i in range(a.GetNumberOfTuples()):
        p, q = a.GetTuple3(i), b.GetTuple3(i)
        if all(abs(p[k] - bg[k]) <= 2 and abs(q[k] - bg[k]) <= 2 for k in range(3)):
            continue
        count += 1
        for k in range(3):
            d = (p[k] - q[k]) * scale / 255.0
            total += d * d
            worst = max(worst, abs(d))
    return math.sqrt(total / max(1, 3 * count)), worst


def append(images, axis):
    """`images` side by side (axis 0) or stacked bottom to top (axis 1), as one image."""
    picture = vtkImageAppend()
    picture.SetAppendAxis(axis)
    for image in images:
        picture.AddInputData(image)
    picture.Update()
    return picture.GetOutput()


def write_picture(path, images, axis):
    """Writes `images` side by side (axis 0) or stacked bottom to top (axis 1) as a PNG."""
    writer = vtkPNGWriter()
    writer.SetFileName(path)
    writer.SetInputData(append(images, axis))
    writer.Write()


def labelled(image, text):
    """`image` (RGB image data) with `text` written in its top left corner, as an image."""
    from vtkmodules.vtkRenderingCore import vtkImageActor, vtkTextActor
    import vtkmodules.vtkRenderingFreeType  # noqa: F401 (text rendering)
    width, height, _ = image.GetDimensions()
    actor = vtkImageActor()
    actor.GetMapper().SetInputData(image)
    renderer = vtkRenderer()
    renderer.AddActor(actor)
    label = vtkTextActor()
    label.SetInput(text)
    label.GetTextProperty().SetFontSize(max(12, height // 18))
    label.GetTextProperty().SetColor(1.0, 1.0, 1.0)
    label.GetTextProperty().BoldOn()
    label.GetTextProperty().SetVerticalJustificationToTop()
    label.SetDisplayPosition(8, height - 8)
    renderer.AddActor2D(label)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(width, height)
    window.AddRenderer(renderer)
    camera = renderer.GetActiveCamera()
    camera.ParallelProjectionOn()
    renderer.ResetCamera()
    camera.SetParallelScale(0.5 * (height - 1))
    window.Render()
    return grab(window)
