# SPDX-License-Identifier: BSD-3-Clause
"""The MTPT plugin in one process (pvpython, or pvbatch without MPI).

Loads the plugin, shows the blunt-fin mesh as the representation "Multi-threaded projected
tetra", checks that it draws with vtkMultiThreadedProjectedTetrahedraMapper, and compares
its image with ParaView's own "Volume" representation ("Projected tetra" mapper) of the same
view. Then each mapper setting is changed through its property and the image checked, and
an interactive render keeps the volume in place of ParaView's LOD geometry.

usage: pvpython test_plugin_render.py PLUGIN DATA OUTPUT_DIR NAME
Writes OUTPUT_DIR/NAME_mtpt.png and NAME_projected_tetra.png; exits non-zero on failure.
"""
import functools
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mtpt_plugin_testing as testing  # noqa: E402
from paraview import simple  # noqa: E402

# RMSE over the whole image in [0, 1] RGB. The two mappers differ by design where MTPT is
# more exact (README: thick-vertex length, alpha/beta interpolation, float colours).
MAX_RMSE_VS_PROJECTED_TETRA = 0.02
# Partition and radix sort give the same order, so the same image.
MAX_RMSE_ORDER_METHODS = 1e-6
# The OpenGL backend blends the same triangles with the same math as the CPU compositor.
MAX_RMSE_BACKENDS = 0.01
# The volume covers at least this fraction of the image (not blank).
MIN_COVERED = 0.10
# Two blocks of the same cells, merged by ParaView: the cells' order in the merged grid
# differs, which can only change the order of cells at exactly equal depth.
MAX_RMSE_MULTIBLOCK = 0.002
# Image sample distance 2 against 1, over the volume's pixels (the mapper's own image test
# measures 0.003 on the blunt fin at 400x300: Testing/Rendering/TestMapperImageSampleDistance).
MAX_RMSE_COVERED_DISTANCE_2 = 0.01
# An interactive render with the cell level of detail against the still render, over the
# volume's pixels: whatever fraction and distance the time allotted gives, at most the
# bound of a quarter of the cells (16/255 measured at 400x300 on the blunt fin:
# Testing/Rendering/TestMapperLevelOfDetail); ParaView's LOD geometry is far from it.
MAX_RMSE_COVERED_INTERACTIVE = 0.1
# A plane through the centre keeping one side moves the volume's covered pixels that far
# (a fraction of the image's width) towards that side.
MIN_CLIP_SHIFT = 0.05
# Maximum intensity against composite blending of the same view: far apart (measured 0.1 and
# more).
MIN_RMSE_BLEND_MODES = 0.03

args = testing.arguments(["PLUGIN", "DATA", "OUTPUT_DIR", "NAME"])
out = functools.partial(testing.output_path, args)


def check_cpu_image_again(view, name, what):
    """Saves the view as out(name) and checks that it is the image out("mtpt_cpu") again:
    `what` says which setting, set back or left at its default, gives it."""
    testing.save(view, out(name))
    rmse = testing.compare(out("mtpt_cpu"), out(name))["rmse"]
    return testing.check(rmse <= MAX_RMSE_ORDER_METHODS, "%s (RMSE %.2g)" % (what, rmse))


def check_image_sample_distance(display, view):
    """The image sample distance through its properties: with automatic adjustment on (the
    default) a still render (ParaView asks for 0.002 frames a second) is drawn in full,
    whatever the distance property says; turned off, the distance property's 2 composites a
    quarter of the pixels, close to the full image but not equal to it; on again, a still
    render draws the full image again. Judged by the images alone: ParaView's Python sees the
    plugin's mapper only as a vtkAbstractVolumeMapper (the plugin has no Python wrapping), so
    the mapper's own accessors are tested in Testing/Rendering/TestMapperImageSampleDistance.
    Expects the CPU backend and the settings of the image out("mtpt_cpu")."""
    ok = True
    display.MTPTImageSampleDistance = 2.0
    ok &= check_cpu_image_again(
        view, "mtpt_still",
        "a still render with automatic adjustment (default) is the full image")

    display.MTPTAutoAdjustSampleDistances = 0
    testing.save(view, out("mtpt_distance_2"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_distance_2"))
    print("%s: image sample distance 2 vs 1: RMSE %.5f (covered pixels only: %.5f)" %
          (args["NAME"], figures["rmse"], figures["rmse_covered"]))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and
                        0.0 < figures["rmse_covered"] <= MAX_RMSE_COVERED_DISTANCE_2,
                        "Image Sample Distance 2, no adjustment: close to the full image, and "
                        "coarser (covered RMSE %.5f <= %.3f)" %
                        (figures["rmse_covered"], MAX_RMSE_COVERED_DISTANCE_2))

    display.MTPTMaximumImageSampleDistance = 8.0
    display.MTPTAutoAdjustSampleDistances = 1
    ok &= check_cpu_image_again(
        view, "mtpt_auto_adjusted",
        "automatic adjustment on again: a still render is the full image again")
    display.MTPTMaximumImageSampleDistance = 10.0
    display.MTPTImageSampleDistance = 1.0
    return ok


def check_memory_limit(display, view):
    """The memory limit through its property: 1 MiB is below what the mesh's buffers need,
    so the render draws nothing (the mapper reports what it needs); 0, the memory
    available, draws the image of out("mtpt_cpu") again."""
    ok = True
    display.MTPTMemoryLimit = 1
    testing.save(view, out("mtpt_memory_limit"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_memory_limit"))
    ok &= testing.check(figures["covered_b"] < 0.001,
                        "Memory Limit 1 MiB: nothing drawn (covered %.4f)" % figures["covered_b"])
    display.MTPTMemoryLimit = 0
    ok &= check_cpu_image_again(
        view, "mtpt_memory_available",
        "Memory Limit 0: the full image again")
    return ok


def check_level_of_detail(display, view):
    """While the view moves, ParaView replaces a volume above its LOD threshold by the grid's
    outline or surface. With the cell level of detail on (the default) the representation
    keeps the volume: an interactive render with the threshold at 0 draws the volume, close
    to the still image; off, ParaView's LOD geometry is drawn instead, far from it. Expects
    the CPU backend and the settings of the image out("mtpt_cpu")."""
    ok = True
    threshold = view.LODThreshold
    view.LODThreshold = 0.0
    simple.Render(view)  # the next interactive render uses ParaView's LOD
    testing.save_interactive(view, out("mtpt_interactive"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_interactive"))
    print("%s: interactive render with the cell level of detail vs still: covered RMSE %.4f" %
          (args["NAME"], figures["rmse_covered"]))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and
                        figures["rmse_covered"] <= MAX_RMSE_COVERED_INTERACTIVE,
                        "the volume stays while the view moves (covered RMSE %.4f <= %.2f)" %
                        (figures["rmse_covered"], MAX_RMSE_COVERED_INTERACTIVE))
    display.MTPTAutoAdjustCellFraction = 0
    simple.Render(view)
    testing.save_interactive(view, out("paraview_lod"))
    figures = testing.compare(out("mtpt_cpu"), out("paraview_lod"))
    ok &= testing.check(figures["rmse_covered"] > MAX_RMSE_COVERED_INTERACTIVE,
                        "off: ParaView's LOD geometry in its place (covered RMSE %.4f)" %
                        figures["rmse_covered"])
    display.MTPTAutoAdjustCellFraction = 1
    view.LODThreshold = threshold
    simple.Render(view)
    return ok


def check_clipping_plane(display, view, reader):
    """A clipping plane through the mesh's centre, normal along world +x (the view's right):
    the volume left is the right part of the image, and with the normal along -x the left
    part; off again, the full image. Expects the CPU backend and the settings of the image
    out("mtpt_cpu")."""
    ok = True
    bounds = reader.GetDataInformation().GetBounds()
    centre = [0.5 * (bounds[2 * i] + bounds[2 * i + 1]) for i in range(3)]
    whole = testing.covered_centre_x(out("mtpt_cpu"))
    display.MTPTClippingPlaneOrigin = centre
    display.MTPTClippingPlane = 1
    sides = {}
    for name, normal in (("right", [1.0, 0.0, 0.0]), ("left", [-1.0, 0.0, 0.0])):
        display.MTPTClippingPlaneNormal = normal
        testing.save(view, out("mtpt_clipped_" + name))
        sides[name] = testing.covered_centre_x(out("mtpt_clipped_" + name))
    print("%s: covered pixels' mean column: whole %.3f, kept right %.3f, kept left %.3f" %
          (args["NAME"], whole, sides["right"], sides["left"]))
    ok &= testing.check(sides["right"] > whole + MIN_CLIP_SHIFT and
                        sides["left"] < whole - MIN_CLIP_SHIFT,
                        "Clipping Plane keeps the side its normal points to")
    display.MTPTClippingPlane = 0
    ok &= check_cpu_image_again(view, "mtpt_unclipped", "Clipping Plane off: the full image again")
    return ok


def check_blend_modes(display, view):
    """Blend Mode: maximum intensity gives another image than composite; additive an opaque
    grey one (red = green = blue over the covered pixels); composite again the first image.
    Expects the CPU backend and the settings of the image out("mtpt_cpu")."""
    ok = True
    display.MTPTBlendMode = 1
    testing.save(view, out("mtpt_maximum"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_maximum"))
    print("%s: maximum intensity vs composite: covered RMSE %.4f" %
          (args["NAME"], figures["rmse_covered"]))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and
                        figures["rmse_covered"] > MIN_RMSE_BLEND_MODES,
                        "Blend Mode Maximum Intensity draws its own image")
    display.MTPTBlendMode = 4
    testing.save(view, out("mtpt_additive"))
    _, pixels = testing.read_rgb(out("mtpt_additive"))
    background = [round(c * 255.0) / 255.0 for c in testing.BACKGROUND]
    covered = (abs(pixels - background) > 2.5 / 255.0).any(axis=1)
    spread = float((pixels[covered].max(axis=1) - pixels[covered].min(axis=1)).max())
    ok &= testing.check(covered.mean() >= MIN_COVERED and spread <= 1.5 / 255.0,
                        "Blend Mode Additive draws grey (largest channel spread %.4f)" % spread)
    display.MTPTBlendMode = 0
    ok &= check_cpu_image_again(
        view, "mtpt_composite_again",
        "Blend Mode Composite: the first image again")
    return ok


def check_shading(display, view):
    """Shade: the lit image differs from the unlit one, and more specular light brightens it;
    Shade off gives the first image again. Expects the CPU backend and the settings of the
    image out("mtpt_cpu")."""
    ok = True
    display.MTPTShade = 1
    testing.save(view, out("mtpt_shaded"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_shaded"))
    print("%s: shaded vs unshaded: covered RMSE %.4f" % (args["NAME"], figures["rmse_covered"]))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and
                        figures["rmse_covered"] > MIN_RMSE_BLEND_MODES,
                        "Shade lights the volume")
    display.MTPTSpecular = 0.9
    testing.save(view, out("mtpt_shaded_specular"))
    _, dull = testing.read_rgb(out("mtpt_shaded"))
    _, shiny = testing.read_rgb(out("mtpt_shaded_specular"))
    ok &= testing.check(float(shiny.mean()) > float(dull.mean()),
                        "Volume Specular brightens the highlights (mean %.4f > %.4f)" %
                        (float(shiny.mean()), float(dull.mean())))
    display.MTPTSpecular = 0.2
    display.MTPTShade = 0
    ok &= check_cpu_image_again(view, "mtpt_unshaded_again", "Shade off: the first image again")
    return ok


def main():
    ok = True

    testing.load_plugin(args["PLUGIN"])
    reader = simple.XMLUnstructuredGridReader(FileName=[args["DATA"]])
    view = testing.make_view()

    display = testing.show_volume(reader, view, testing.MTPT_REPRESENTATION)
    testing.save(view, out("mtpt"))
    representation_class, mapper_class = testing.active_mapper_class(display)
    ok &= testing.check(representation_class == "vtkMTPTUnstructuredGridVolumeRepresentation" and
                        mapper_class == testing.MTPT_MAPPER_CLASS,
                        "representation %s draws with %s" % (representation_class, mapper_class))

    display.SetRepresentationType("Volume")
    display.SelectMapper = "Projected tetra"
    testing.save(view, out("projected_tetra"))
    _, stock_mapper = testing.active_mapper_class(display)
    ok &= testing.check(stock_mapper.endswith("ProjectedTetrahedraMapper") and
                        stock_mapper != testing.MTPT_MAPPER_CLASS,
                        "ParaView's Volume representation draws with %s" % stock_mapper)

    figures = testing.compare(out("mtpt"), out("projected_tetra"))
    print("%s: MTPT vs Projected tetra: RMSE %.4f (covered pixels only: %.4f), volume covers "
          "%.1f%% / %.1f%% of the image" % (args["NAME"], figures["rmse"], figures["rmse_covered"],
                                            100 * figures["covered_a"], 100 * figures["covered_b"]))
    ok &= testing.check(figures["covered_a"] >= MIN_COVERED,
                        "MTPT image not blank (covered %.3f >= %.2f)" % (figures["covered_a"],
                                                                        MIN_COVERED))
    ok &= testing.check(figures["rmse"] <= MAX_RMSE_VS_PROJECTED_TETRA,
                        "RMSE vs Projected tetra %.4f <= %.2f" % (figures["rmse"],
                                                                  MAX_RMSE_VS_PROJECTED_TETRA))

    # The mapper settings, through the properties the Properties panel shows.
    display.SetRepresentationType(testing.MTPT_REPRESENTATION)
    display.MTPTNumberOfThreads = 2
    display.MTPTOrderMethod = "Partition sort"
    testing.save(view, out("mtpt_partition_sort"))
    rmse = testing.compare(out("mtpt"), out("mtpt_partition_sort"))["rmse"]
    ok &= testing.check(rmse <= MAX_RMSE_ORDER_METHODS,
                        "Partition sort, 2 threads: same image as radix sort (RMSE %.2g)" % rmse)

    display.MTPTBackend = "OpenGL"
    testing.save(view, out("mtpt_opengl"))
    display.MTPTBackend = "CPU"
    testing.save(view, out("mtpt_cpu"))
    rmse = testing.compare(out("mtpt_opengl"), out("mtpt_cpu"))["rmse"]
    ok &= testing.check(rmse <= MAX_RMSE_BACKENDS,
                        "OpenGL and CPU backends agree (RMSE %.4f <= %.2f)" % (rmse,
                                                                             MAX_RMSE_BACKENDS))

    display.MTPTShadingMode = "Pre-integrated"
    testing.save(view, out("mtpt_preintegrated"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_preintegrated"))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and figures["rmse"] > 0.0,
                        "Pre-integrated shading renders, and differently (RMSE %.4f vs "
                        "VTK-compatible)" % figures["rmse"])
    display.MTPTShadingMode = "VTK-compatible"

    ok &= check_image_sample_distance(display, view)
    ok &= check_memory_limit(display, view)
    ok &= check_level_of_detail(display, view)
    ok &= check_clipping_plane(display, view, reader)
    ok &= check_blend_modes(display, view)
    ok &= check_shading(display, view)
    simple.Hide(reader, view)

    # A multi-block input: the mesh cut into two blocks of whole cells (the cells inside a
    # plane, with those it cuts, and the cells wholly outside: every cell exactly once),
    # grouped. ParaView hands the representation its blocks merged into one grid, so one
    # order covers both: the image is that of the single grid.
    halves = []
    for side, cut in (("inside", 1), ("outside", 0)):
        half = simple.ExtractCellsByRegion(Input=reader, IntersectWith="Plane",
                                           ExtractionSide=side, Extractintersected=cut)
        half.IntersectWith.Origin = [3.0, 0.0, 0.0]
        half.IntersectWith.Normal = [1.0, 0.2, 0.0]
        halves.append(half)
    blocks = simple.GroupDatasets(Input=halves)
    block_display = testing.show_volume(blocks, view, testing.MTPT_REPRESENTATION)
    block_display.MTPTBackend = "CPU"
    testing.save(view, out("mtpt_multiblock"))
    figures = testing.compare(out("mtpt_cpu"), out("mtpt_multiblock"))
    print("%s: MTPT on two blocks vs one grid: RMSE %.5f" % (args["NAME"], figures["rmse"]))
    ok &= testing.check(figures["covered_b"] >= MIN_COVERED and
                        figures["rmse"] <= MAX_RMSE_MULTIBLOCK,
                        "a multi-block input draws as the single grid (RMSE %.5f <= %.3f)" %
                        (figures["rmse"], MAX_RMSE_MULTIBLOCK))
    return ok


testing.run(main, args["NAME"])
