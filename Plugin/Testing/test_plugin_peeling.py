# SPDX-License-Identifier: BSD-3-Clause
"""A translucent surface and the MTPT volume together in ParaView, the view depth-peeling
volumes (its "Depth Peeling" and "Depth Peeling for Volumes", both on by default).

The blunt-fin mesh as the representation "Multi-threaded projected tetra" with a translucent
sphere in front of it, behind it and inside it. In front and behind, the correct picture is
known from the layers alone: each of the sphere and the volume is rendered by itself over a
black and a white background, which gives its premultiplied colour and its opacity per
pixel, and the two are composited in depth order over the view's background. The view with
both must match that composite, for both backends; ParaView's own "Projected tetra" (VTK's
PT, which does not take part in depth peeling) is measured against the same composite and
must fail it, which shows that the check tells the two apart. ParaView's views smooth edges
with FXAA by default, and VTK applies FXAA after translucent geometry and before volumes
(vtkOpenGLRenderer::UpdateGeometry): a volume drawn inside the peeling is smoothed with the
surfaces, a volume drawn alone is not, so with FXAA on (as ParaView starts) the worst pixel is
taken away from the layers' edges, and the scene is checked again with FXAA off over every
pixel. FXAA works on the window's pixels whichever backend drew them: the scene with FXAA on
is drawn with the CPU backend, the one with FXAA off with both (on llvmpipe a capture with
the OpenGL backend inside the peeling takes many times as long: Documentation/paraview.md).
Inside, the sphere must be seen through the volume's front part and the volume's back part
through the sphere: the picture differs from both layer composites. (The exact picture of a
surface inside the volume is tested against the exact reference in
Testing/Rendering/TestMapperDepthPeeling.cxx.)

usage: pvpython test_plugin_peeling.py PLUGIN DATA OUTPUT_DIR NAME
Writes OUTPUT_DIR/NAME_*.png; exits non-zero on failure.
"""
import functools
import math
import os
import sys

import numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mtpt_plugin_testing as testing  # noqa: E402
from paraview import simple  # noqa: E402

# Covered-pixel RMSE and worst channel, in [0, 1], of the view against the composite of its
# layers. Each layer's colour and opacity come from two 8-bit images, so the composite is
# itself uncertain by a few 1/255 where the layers are nearly opaque.
MAX_RMSE_LAYERS = 0.005
MAX_WORST_LAYERS = 0.03
# The picture with the sphere inside differs from either layer composite over this fraction
# of the pixels the sphere covers (by more than 4/255).
MIN_DIFFERENT_INSIDE = 0.2

args = testing.arguments(["PLUGIN", "DATA", "OUTPUT_DIR", "NAME"])
out = functools.partial(testing.output_path, args)


def capture(view, suffix, background=None):
    """The view's image as floats (pixels, 3), over `background` if given."""
    saved = list(view.Background)
    if background is not None:
        view.Background = background
    testing.save(view, out(suffix))
    view.Background = saved
    return testing.read_rgb(out(suffix))[1]


def layer(view, shown, hidden, suffix):
    """Premultiplied colour and opacity per pixel of the display `shown` alone."""
    hidden.Visibility = 0
    shown.Visibility = 1
    black = capture(view, suffix + "_black", [0.0, 0.0, 0.0])
    white = capture(view, suffix + "_white", [1.0, 1.0, 1.0])
    hidden.Visibility = 1
    return black, numpy.clip(1.0 - (white - black), 0.0, 1.0)


def over(front, back):
    """Premultiplied `front` over `back` (colour, opacity)."""
    return front[0] + (1.0 - front[1]) * back[0], front[1] + (1.0 - front[1]) * back[1]


def edges(layers):
    """Pixels within one pixel of the edge of any layer's covered region."""
    band = numpy.zeros(testing.IMAGE_SIZE[::-1], dtype=bool)
    for _, opacity in layers:
        covered = (opacity > 0.01).any(axis=1).reshape(band.shape)
        edge = numpy.zeros_like(band)
        for axis in (0, 1):
            edge |= covered != numpy.roll(covered, 1, axis)
            edge |= covered != numpy.roll(covered, -1, axis)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                band |= numpy.roll(numpy.roll(edge, dy, 0), dx, 1)
    return band.ravel()


def difference(image, expected, skip=None):
    """Covered-pixel RMSE, and worst channel difference over the covered pixels not in
    `skip`."""
    background = numpy.array(testing.BACKGROUND)
    covered = ((abs(image - background) > 2.5 / 255.0) |
               (abs(expected - background) > 2.5 / 255.0)).any(axis=1)
    d = image - expected
    worst = d[covered & ~skip] if skip is not None else d[covered]
    return math.sqrt(float((d[covered] ** 2).mean())), float(abs(worst).max())


def check_places(view, volume, sphere, surface, label, backends):
    """The sphere in front of, behind and inside the volume, drawn with each of `backends`;
    `label` names the view's antialiasing (with FXAA the worst pixel is taken off the layers'
    edges)."""
    ok = True
    background = numpy.array(testing.BACKGROUND)
    smoothed = view.UseFXAA == 1
    composites = {}
    # The camera looks down -z (tilted 30 degrees): the mesh spans z 0 to 5.7.
    for place, centre in (("front", [3.3, 4.2, 8.5]), ("behind", [3.3, 4.2, -2.8]),
                          ("inside", [3.3, 4.2, 2.9])):
        sphere.Center = centre
        for backend in backends:
            volume.SetRepresentationType(testing.MTPT_REPRESENTATION)
            volume.MTPTBackend = backend
            name = "%s_%s%s" % (place, backend.lower(), "_fxaa" if smoothed else "")
            image = capture(view, name)
            s = layer(view, surface, volume, name + "_sphere")
            v = layer(view, volume, surface, name + "_volume")
            ahead, behind = (s, v) if place != "behind" else (v, s)
            layered = over(ahead, over(behind, (background, 1.0)))[0]
            if place != "inside":
                skip = edges((s, v)) if smoothed else None
                rmse, worst = difference(image, layered, skip)
                where = "off the edges" if smoothed else "everywhere"
                print("%s: %s, sphere %s, %s backend: against its layers RMSE %.4f, worst %s "
                      "%.3f" % (args["NAME"], label, place, backend, rmse, where, worst))
                ok &= testing.check(rmse <= MAX_RMSE_LAYERS and worst <= MAX_WORST_LAYERS,
                                    "%s, sphere %s, %s backend: the layers in depth order (RMSE "
                                    "%.4f <= %.2f, worst %s %.3f <= %.2f)" %
                                    (label, place, backend, rmse, MAX_RMSE_LAYERS, where, worst,
                                     MAX_WORST_LAYERS))
                composites[place] = layered
                continue
            # Inside: neither the sphere over the volume nor the volume over the sphere.
            in_front = over(s, over(v, (background, 1.0)))[0]
            sphere_pixels = (s[1] > 0.1).any(axis=1)
            for where, other in (("in front of", in_front), ("behind", layered)):
                differs = (abs(image - other) > 4.0 / 255.0).any(axis=1)[sphere_pixels].mean()
                ok &= testing.check(differs >= MIN_DIFFERENT_INSIDE,
                                    "%s, sphere inside, %s backend: not the sphere %s the "
                                    "volume (%.0f%% of the sphere's pixels differ >= %.0f%%)" %
                                    (label, backend, where, 100 * differs,
                                     100 * MIN_DIFFERENT_INSIDE))

        if place == "inside":
            continue
        # ParaView's Projected tetra in the same scene: VTK's PT takes no part in the peeling.
        volume.SetRepresentationType("Volume")
        volume.SelectMapper = "Projected tetra"
        image = capture(view, "%s_projected_tetra%s" % (place, "_fxaa" if smoothed else ""))
        rmse, worst = difference(image, composites[place])
        print("%s: %s, sphere %s, ParaView's Projected tetra: against the layers RMSE %.4f, "
              "worst %.3f" % (args["NAME"], label, place, rmse, worst))
        ok &= testing.check(rmse > MAX_RMSE_LAYERS,
                            "%s, sphere %s: Projected tetra fails the same check (RMSE %.4f)" %
                            (label, place, rmse))
        volume.SelectMapper = "Smart"
    return ok


def main():
    ok = True
    testing.load_plugin(args["PLUGIN"])
    reader = simple.XMLUnstructuredGridReader(FileName=[args["DATA"]])
    view = testing.make_view()
    view.EnableRenderOnInteraction = 0
    ok &= testing.check(view.DepthPeeling == 1 and view.DepthPeelingForVolumes == 1,
                        "the view peels volumes by default (Depth Peeling %d, for volumes %d, "
                        "at most %d peels, %d samples per pixel)" %
                        (view.DepthPeeling, view.DepthPeelingForVolumes,
                         view.MaximumNumberOfPeels, view.MultiSamples))
    volume = testing.show_volume(reader, view, testing.MTPT_REPRESENTATION)
    sphere = simple.Sphere(Radius=2.2, ThetaResolution=64, PhiResolution=64)
    surface = simple.Show(sphere, view)
    surface.AmbientColor = surface.DiffuseColor = [0.15, 0.85, 0.35]
    surface.Opacity = 0.4

    for fxaa, backends in ((1, ("CPU",)), (0, ("CPU", "OpenGL"))):
        view.UseFXAA = fxaa
        ok &= check_places(view, volume, sphere, surface, "FXAA" if fxaa else "no FXAA", backends)
    return ok


testing.run(main, args["NAME"])
