#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Shading (vtkVolumeProperty::ShadeOn) against VTK's GPU ray caster: the wavelet as image data
through vtkGPUVolumeRayCastMapper and tetrahedralized through MTPT (both backends, both
shadings), lit by the renderer's headlight and by a light kit, with a soft opacity ramp and
with a steep one (a surface), and the exact reference lit the same way. Prints each MTPT
image's covered-pixel RMSE against the ray cast and against the reference (of 255), and that
of the same MTPT image unshaded against the ray cast unshaded, for scale, and VTK's PT's (it
ignores the shading); then the CPU backend's frame time shaded against unshaded, the camera
turning before every frame; and writes a picture: a column per case, VTK's GPU ray cast
below, MTPT (CPU backend, pre-integrated) above.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/shading.py
         [--size 400] [--extent 20] [--frames 7] [--picture shading.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless)."""
import argparse
import statistics
import time

from vtkmodules.vtkRenderingCore import vtkLightKit
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=400)
parser.add_argument("--extent", type=int, default=20, help="wavelet extent: -E..E per axis")
parser.add_argument("--frames", type=int, default=7, help="timed frames per measurement")
parser.add_argument("--picture", default="shading.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)
LIGHTINGS = ("headlight", "light kit")
# Opacity ramps: soft (a cloud) and steep (a surface at scalar 150 to 170).
RAMPS = {"soft": (((40, 0.0), (120, 0.15), (200, 0.6), (280, 0.9)), 10.0),
         "steep": (((40, 0.0), (150, 0.0), (170, 0.8), (280, 0.9)), 2.0)}


def volume_property(shade=True, ramp="soft"):
    opacities, unit_distance = RAMPS[ramp]
    prop = figures.volume_property(
        colours=((40, 0.2, 0.3, 0.9), (160, 0.95, 0.95, 0.6), (280, 0.9, 0.2, 0.1)),
        opacities=opacities, unit_distance=unit_distance)
    prop.SetInterpolationTypeToLinear()
    prop.SetShade(shade)
    prop.SetAmbient(0.2)
    prop.SetDiffuse(0.7)
    prop.SetSpecular(0.3)
    prop.SetSpecularPower(12.0)
    return prop


def scene(data, mapper, lighting, shade=True, ramp="soft"):
    renderer, volume = figures.volume_scene(data, mapper, volume_property(shade, ramp),
                                            BACKGROUND)
    if lighting == "light kit":
        kit = vtkLightKit()
        kit.AddLightsToRenderer(renderer)
    return renderer, volume, figures.window_for(renderer, args.size)


image_data, grid = figures.wavelet(args.extent)
print(f"wavelet: {grid.GetNumberOfCells()} tetrahedra, {args.size}x{args.size}, VTK's default "
      f"window (multisampled); ambient 0.2, diffuse 0.7, specular 0.3, power 12")
def rendered(data, mapper, lighting, shade, ramp, exact=False):
    renderer, volume, window = scene(data, mapper, lighting, shade, ramp)
    window.Render()
    return figures.grab(window), (figures.reference(renderer, volume) if exact else None)


columns = []
for ramp in RAMPS:
    for lighting in LIGHTINGS:
        ray_image, _ = rendered(image_data, figures.gpu_ray_cast(), lighting, True, ramp)
        ray_unlit, _ = rendered(image_data, figures.gpu_ray_cast(), lighting, False, ramp)
        for backend in ("CPU", "OpenGL"):
            for shading in ("PreIntegrated", "VTKCompatible"):
                mapper = figures.mtpt_mapper(backend, shading)
                image, exact = rendered(grid, mapper, lighting, True, ramp, exact=True)
                unlit, _ = rendered(grid, figures.mtpt_mapper(backend, shading), lighting, False,
                                    ramp)
                ray, _ = figures.difference(image, ray_image, BACKGROUND, 255)
                ref, worst = figures.difference(image, exact, BACKGROUND, 255)
                scale, _ = figures.difference(unlit, ray_unlit, BACKGROUND, 255)
                print(f"{ramp:5s} {lighting:9s} MTPT {backend:6s} {shading:13s}: covered RMSE "
                      f"against VTK's GPU ray cast {ray:.1f}/255 (unshaded {scale:.1f}), "
                      f"against the exact reference {ref:.2f}/255 (worst {worst:.0f})")
                if backend == "CPU" and shading == "PreIntegrated":
                    columns.append(figures.append([ray_image, image], 1))
        pt_image, _ = rendered(grid, vtkProjectedTetrahedraMapper(), lighting, True, ramp)
        rmse, _ = figures.difference(pt_image, ray_image, BACKGROUND, 255)
        print(f"{ramp:5s} {lighting:9s} VTK's PT (ignores the shading): covered RMSE against "
              f"VTK's GPU ray cast {rmse:.1f}/255")

print(f"\nFrame time, MTPT CPU backend, the camera turning 2 degrees before each frame "
      f"(median of {args.frames} frames):")
for shading in ("VTKCompatible", "PreIntegrated"):
    unshaded = None
    for lighting, shade in (("headlight", False), ("headlight", True), ("light kit", True)):
        m = figures.mtpt_mapper("CPU", shading)
        renderer, volume, window = scene(grid, m, lighting, shade)
        window.Render()
        seconds, lit_seconds = [], []
        for _ in range(args.frames):
            renderer.GetActiveCamera().Azimuth(2)
            start = time.perf_counter()
            window.Render()
            seconds.append(time.perf_counter() - start)
            lit_seconds.append(m.GetLightingSeconds())
        frame = statistics.median(seconds)
        unshaded = unshaded or frame
        name = f"{lighting}, shaded" if shade else "unshaded"
        print(f"  {shading:13s} {name:19s}: {1e3 * frame:6.1f} ms ({frame / unshaded:.2f}x "
              f"unshaded), lighting the cells "
              f"{1e3 * statistics.median(lit_seconds):.1f} ms")

figures.write_picture(args.picture, columns, 0)
print(f"\nwrote {args.picture}: a column per case (soft ramp: headlight, light kit; steep ramp: "
      "headlight, light kit), VTK's GPU ray cast of the image data below, MTPT (CPU backend, "
      "pre-integrated) above")
