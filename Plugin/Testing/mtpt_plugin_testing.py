# SPDX-License-Identifier: BSD-3-Clause
"""Shared parts of the MTPT plugin tests (run by pvpython and pvbatch; scripts/plugin.sh).

One scene for every test: the blunt-fin mesh coloured and made translucent by Density, a
fixed camera, a plain background and no orientation axes, so that images taken with
different representations, executables and numbers of MPI ranks can be compared pixel by
pixel. Images are compared with vtkmodules (ParaView's own VTK) and numpy.
"""
import math
import os
import sys
import traceback

import numpy

from paraview import simple
from vtkmodules.util import numpy_support
from vtkmodules.vtkIOImage import vtkPNGReader, vtkPNGWriter
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

#: The representation type the plugin adds to unstructured grids.
MTPT_REPRESENTATION = "Multi-threaded projected tetra"
MTPT_MAPPER_CLASS = "vtkMultiThreadedProjectedTetrahedraMapper"
IMAGE_SIZE = [640, 480]
BACKGROUND = [0.32, 0.34, 0.43]
DENSITY_RANGE = (0.19, 4.98)  # of bluntfin_tets.vtu (Data/README.md)


def arguments(names):
    """The script's arguments as a dict, with a usage message when some are missing."""
    args = [a for a in sys.argv[1:] if not a.startswith("-")]
    if len(args) < len(names):
        sys.exit("usage: %s %s" % (os.path.basename(sys.argv[0]), " ".join(names)))
    return dict(zip(names, args))


def output_path(args, suffix):
    """OUTPUT_DIR/NAME_suffix.png, from the arguments of a test script."""
    return os.path.join(args["OUTPUT_DIR"], "%s_%s.png" % (args["NAME"], suffix))


def load_plugin(path):
    """Loads the plugin (pvbatch with MPI: on every rank) and checks that the new
    representation type is known."""
    simple.LoadPlugin(path, ns=globals())
    if simple.servermanager.ProxyManager().GetPrototypeProxy(
            "representations", "MTPTUnstructuredGridVolumeRepresentation") is None:
        raise RuntimeError("the plugin did not define the MTPT representation")


def make_view():
    view = simple.CreateView("RenderView")
    view.ViewSize = IMAGE_SIZE
    view.OrientationAxesVisibility = 0
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = BACKGROUND
    return view


def show_volume(source, view, representation):
    """Shows `source` in `view` as a volume coloured by Density with the given
    representation type, with the same transfer functions and camera every time (those of
    Examples/mtpt_render.cxx, so the picture matches the README's)."""
    display = simple.Show(source, view)
    simple.ColorBy(display, ("POINTS", "Density"))
    display.SetRepresentationType(representation)
    lo, hi = DENSITY_RANGE
    at = lambda fraction: lo + fraction * (hi - lo)
    lut = simple.GetColorTransferFunction("Density")
    lut.ColorSpace = "RGB"
    lut.RGBPoints = [lo, 0.23, 0.30, 0.75, at(0.15), 0.87, 0.87, 0.87,
                     at(0.4), 0.96, 0.60, 0.35, hi, 0.71, 0.02, 0.15]
    lut.AutomaticRescaleRangeMode = "Never"
    pwf = simple.GetOpacityTransferFunction("Density")
    pwf.Points = [lo, 0.0, 0.5, 0.0, at(0.15), 0.25, 0.5, 0.0, hi, 1.0, 0.5, 0.0]
    bounds = source.GetDataInformation().GetBounds()
    diagonal = math.sqrt(sum((bounds[2 * i + 1] - bounds[2 * i]) ** 2 for i in range(3)))
    display.ScalarOpacityUnitDistance = diagonal / 40.0
    view.CameraPosition = [0.0, 0.0, 1.0]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.ResetCamera()
    view.GetActiveCamera().Elevation(30.0)
    view.ResetCamera()
    return display


def active_mapper_class(display):
    """Class names of the active representation inside `display` and of the mapper it draws
    with (the objects of this process)."""
    active = display.GetClientSideObject().GetActiveRepresentation()
    return active.GetClassName(), active.GetActiveVolumeMapper().GetClassName()


def save(view, path):
    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=IMAGE_SIZE)


def save_interactive(view, path):
    """An interactive render, as ParaView draws while the user drags the view (its window
    then asks for 5 frames a second, and its LOD applies), written as the window shows it."""
    view.SMProxy.InteractiveRender()
    grab = vtkWindowToImageFilter()
    grab.SetInput(view.GetRenderWindow())
    grab.ShouldRerenderOff()
    grab.ReadFrontBufferOff()
    grab.SetInputBufferTypeToRGB()
    writer = vtkPNGWriter()
    writer.SetInputConnection(grab.GetOutputPort())
    writer.SetFileName(path)
    writer.Write()


def read_rgb(path):
    """The PNG at `path` as a float array of shape (pixels, 3) in [0, 1]."""
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    pixels = numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
    return image.GetDimensions()[:2], pixels[:, :3].astype("float64") / 255.0


def compare(path_a, path_b):
    """RMSE over all pixels and RGB channels in [0, 1], the same over the pixels that either
    image covers (differs from the background), and the covered fraction of each image."""
    size_a, a = read_rgb(path_a)
    size_b, b = read_rgb(path_b)
    if size_a != size_b:
        raise RuntimeError("image sizes differ: %s %s" % (size_a, size_b))
    background = [round(c * 255.0) / 255.0 for c in BACKGROUND]
    covered_a = (abs(a - background) > 2.5 / 255.0).any(axis=1)
    covered_b = (abs(b - background) > 2.5 / 255.0).any(axis=1)
    covered = covered_a | covered_b
    squared = (a - b) ** 2
    rmse = math.sqrt(float(squared.mean()))
    rmse_covered = math.sqrt(float(squared[covered].mean())) if covered.any() else 0.0
    return {
        "rmse": rmse,
        "rmse_covered": rmse_covered,
        "covered_a": float(covered_a.mean()),
        "covered_b": float(covered_b.mean()),
    }


def covered_centre_x(path):
    """Where the covered pixels of the PNG at `path` lie across the image, left to right: the
    mean column of the pixels that differ from the background, a fraction of the width."""
    (width, _), pixels = read_rgb(path)
    background = [round(c * 255.0) / 255.0 for c in BACKGROUND]
    covered = (abs(pixels - background) > 2.5 / 255.0).any(axis=1)
    columns = numpy.arange(len(covered)) % width
    return float(columns[covered].mean()) / width if covered.any() else 0.5


def check(condition, message):
    print(("PASS " if condition else "FAIL ") + message)
    sys.stdout.flush()
    return bool(condition)


def finish(ok, name):
    """Prints the verdict; on failure exits with status 1. On success the script just ends:
    pvbatch under MPI must leave through its own shutdown, which finalizes MPI on every rank
    (sys.exit on rank 0 makes mpiexec kill the others and fail), and pvpython 5.11 leaving
    through sys.exit with a render view alive fails in X (GLXBadContext, exit status 1) even
    with no plugin loaded."""
    print("%s: %s" % (name, "all checks passed" if ok else "FAILED"))
    sys.stdout.flush()
    if not ok:
        sys.exit(1)


def run(main, name):
    """Runs main() (which returns whether every check passed) and finishes: an exception
    counts as a failure, so that it ends the run at once (pvbatch on several MPI ranks waits
    forever after an exception that leaves the script)."""
    try:
        ok = main()
    except Exception:
        traceback.print_exc()
        ok = False
    finish(ok, name)
