#!/usr/bin/python3
# SPDX-License-Identifier: BSD-3-Clause
"""Clipping planes against VTK's GPU ray caster: the wavelet as image data through
vtkGPUVolumeRayCastMapper and tetrahedralized through MTPT (both backends, both shadings),
two clipping planes on each mapper (vtkAbstractMapper::AddClippingPlane, world coordinates),
and the exact reference with the same planes. Prints each MTPT image's covered-pixel RMSE
against the ray cast and against the reference (of 255); then the time of a frame whose
plane moves (the camera still) against frames without planes whose camera turns or whose
colours change (the same order composited again), and what the moving-plane frames reused;
and writes a picture: MTPT without planes, MTPT with them, VTK's GPU ray cast with them, the
reference.

usage: PYTHONPATH=build/lib/python3/dist-packages scripts/figures/clipping-planes.py
         [--size 400] [--extent 20] [--frames 7] [--picture clipping_planes.png]
Runs with Debian's python3 (python3-vtk9) under an X server (xvfb-run -a when headless)."""
import argparse
import statistics
import time

from vtkmodules.vtkCommonDataModel import vtkPlane
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401

from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper
import mtpt_figures as figures

parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("--size", type=int, default=400)
parser.add_argument("--extent", type=int, default=20, help="wavelet extent: -E..E per axis")
parser.add_argument("--frames", type=int, default=7, help="timed frames per measurement")
parser.add_argument("--picture", default="clipping_planes.png")
args = parser.parse_args()

BACKGROUND = (0.1, 0.1, 0.2)
# An oblique plane through the centre, and one taking a slab off the top.
PLANES = (((1.0, 0.0, 0.0), (0.6, -0.3, 0.74)), ((0.0, 0.6, 0.0), (0.1, -1.0, 0.2)))


def volume_property():
    prop = figures.volume_property(
        colours=((40, 0.2, 0.3, 0.9), (160, 0.95, 0.95, 0.6), (280, 0.9, 0.2, 0.1)),
        opacities=((40, 0.0), (120, 0.02), (280, 0.25)), unit_distance=2.0)
    prop.SetInterpolationTypeToLinear()
    return prop


def add_planes(mapper, shift=0.0):
    for (origin, normal) in PLANES:
        plane = vtkPlane()
        plane.SetOrigin(origin[0] + shift, origin[1], origin[2])
        plane.SetNormal(*normal)
        mapper.AddClippingPlane(plane)


def scene(data, mapper):
    renderer, volume = figures.volume_scene(data, mapper, volume_property(), BACKGROUND)
    return renderer, volume, figures.window_for(renderer, args.size)



def median_frame(window, step):
    """Median seconds of a frame, `step()` called before each."""
    window.Render()
    seconds = []
    for _ in range(args.frames):
        step()
        start = time.perf_counter()
        window.Render()
        seconds.append(time.perf_counter() - start)
    return statistics.median(seconds)


image_data, grid = figures.wavelet(args.extent)
print(f"wavelet: {grid.GetNumberOfCells()} tetrahedra, {args.size}x{args.size}, VTK's default "
      "window (multisampled), two clipping planes")
ray_mapper = figures.gpu_ray_cast()
add_planes(ray_mapper)
renderer, volume, window = scene(image_data, ray_mapper)
window.Render()
ray_image = figures.grab(window)
images = {}
for backend in ("CPU", "OpenGL"):
    for shading in ("VTKCompatible", "PreIntegrated"):
        m = figures.mtpt_mapper(backend, shading)
        add_planes(m)
        renderer, volume, window = scene(grid, m)
        window.Render()
        image = figures.grab(window)
        exact = figures.reference(renderer, volume)
        ray, _ = figures.difference(image, ray_image, BACKGROUND, 255)
        ref, worst = figures.difference(image, exact, BACKGROUND, 255)
        images[(backend, shading)] = (image, exact)
        print(f"MTPT {backend:6s} {shading:13s}: covered RMSE against VTK's GPU ray cast "
              f"{ray:.1f}/255, against the exact reference {ref:.2f}/255 (worst {worst:.0f})")
pt = vtkProjectedTetrahedraMapper()
add_planes(pt)
renderer, volume, window = scene(grid, pt)
window.Render()
rmse, _ = figures.difference(figures.grab(window), ray_image, BACKGROUND, 255)
print(f"VTK's PT (it ignores clipping planes): covered RMSE against VTK's GPU ray cast "
      f"{rmse:.1f}/255")
m = figures.mtpt_mapper("CPU", "PreIntegrated")
renderer, volume, window = scene(grid, m)
window.Render()
unclipped = figures.grab(window)
ray_unclipped = figures.gpu_ray_cast()
renderer_u, volume_u, window_u = scene(image_data, ray_unclipped)
window_u.Render()
rmse, _ = figures.difference(unclipped, figures.grab(window_u), BACKGROUND, 255)
print(f"without planes, MTPT CPU pre-integrated against VTK's GPU ray cast: {rmse:.1f}/255")

print(f"\nFrame time, MTPT CPU backend (median of {args.frames} frames):")
for shading in ("VTKCompatible", "PreIntegrated"):
    m = figures.mtpt_mapper("CPU", shading)
    renderer, volume, window = scene(grid, m)
    turning = median_frame(window, lambda: renderer.GetActiveCamera().Azimuth(1))
    # The same order composited again: a colour-only change of the transfer function.
    colour = volume.GetProperty().GetRGBTransferFunction(0)
    tints = iter([0.9 + 0.02 * (k % 5) for k in range(100)])
    recoloured = median_frame(window, lambda: colour.AddRGBPoint(160, next(tints), 0.95, 0.6))
    add_planes(m)
    plane = m.GetClippingPlanes().GetItem(0)
    shifts = iter([0.3 * ((k % 5) - 2) for k in range(100)])
    reused = []

    def move():
        origin = list(plane.GetOrigin())
        origin[0] = 1.0 + next(shifts)
        plane.SetOrigin(*origin)
        reused.append(m.GetLastFrameReuse())
    moving = median_frame(window, move)
    order = sum(1 for r in reused[1:] if r & Mapper.REUSED_ORDER)
    print(f"  {shading:13s}: no planes, camera turning {1e3 * turning:.1f} ms, colour "
          f"changing {1e3 * recoloured:.1f} ms; a plane moving {1e3 * moving:.1f} ms "
          f"({moving / turning:.2f}x and {moving / recoloured:.2f}x); the order reused in "
          f"{order} of {len(reused) - 1} moving-plane frames")

figures.write_picture(args.picture, [unclipped, images[("CPU", "PreIntegrated")][0], ray_image,
                                     images[("CPU", "PreIntegrated")][1]], 0)
print(f"\nwrote {args.picture}: MTPT without planes, MTPT with them (CPU, pre-integrated), "
      "VTK's GPU ray cast with them, the exact reference with them")
