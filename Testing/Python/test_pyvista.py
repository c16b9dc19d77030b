# SPDX-License-Identifier: BSD-3-Clause
"""mtpt.pyvista.add_volume: PyVista's transfer functions and property for the same
arguments, MTPT as the mapper, and an image that matches VTK's PT given that volume.

Needs PyVista (Debian's python3-pyvista, in the Debian unstable chroot of
scripts/install/sid-chroot.sh). Debian bookworm has no PyVista, and PyPI's pulls in PyPI's VTK
beside the system's, so there the module is skipped (Documentation/testing.md)."""
import numpy as np
import pytest

pyvista = pytest.importorskip("pyvista")

from vtkmodules.vtkRenderingCore import vtkVolume  # noqa: E402
from vtkmodules.vtkRenderingVolume import vtkProjectedTetrahedraMapper  # noqa: E402
import vtkmodules.vtkRenderingOpenGL2  # noqa: E402,F401 (factory overrides)
import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: E402,F401

from vtkmodules.util import numpy_support  # noqa: E402

from mtpt import vtkMTPTReferenceRenderer  # noqa: E402
from mtpt import vtkMultiThreadedProjectedTetrahedraMapper as Mapper  # noqa: E402
from mtpt.pyvista import add_volume  # noqa: E402

from conftest import BACKGROUND, DATA  # noqa: E402

SIZE = (300, 240)

# Argument sets of pyvista.Plotter.add_volume, each given to both.
CASES = {
    "defaults": {},
    "named": dict(scalars="Density", cmap="magma", opacity="sigmoid", clim=(0.5, 4.0),
                  n_colors=64, opacity_unit_distance=0.8, show_scalar_bar=False),
    "list": dict(scalars="Density", cmap="coolwarm", opacity=[0.0, 0.05, 0.3, 0.9],
                 n_colors=16, flip_scalars=True),
    "constant": dict(cmap="bone", opacity=0.4, clim=[1.0, 3.0], n_colors=8),
    "cells": dict(scalars="DensityCells", cmap="plasma", opacity="geom",
                  preference="cell"),
}


@pytest.fixture(scope="module")
def mesh():
    grid = pyvista.read(DATA)
    grid.cell_data["DensityCells"] = grid.point_data_to_cell_data()["Density"]
    grid.set_active_scalars("Density")
    return grid


def plotter(multi_samples=None, off_screen=True):
    pl = pyvista.Plotter(off_screen=off_screen, window_size=SIZE)
    pl.background_color = BACKGROUND
    if multi_samples is not None:
        pl.ren_win.SetMultiSamples(multi_samples)
    return pl


def nodes(function, width):
    values = []
    for i in range(function.GetSize()):
        node = [0.0] * width
        function.GetNodeValue(i, node)
        values.append(node)
    return np.array(values)


def transfer_functions(actor):
    prop = actor.GetProperty()
    color, opacity = prop.GetRGBTransferFunction(0), prop.GetScalarOpacity(0)
    return dict(color=nodes(color, 6), opacity=nodes(opacity, 4),
                color_range=color.GetRange(), opacity_range=opacity.GetRange(),
                clamping=(color.GetClamping(), opacity.GetClamping()),
                unit_distance=prop.GetScalarOpacityUnitDistance(0),
                interpolation=prop.GetInterpolationType(),
                shade=prop.GetShade(0), ambient=prop.GetAmbient(0), diffuse=prop.GetDiffuse(0))


def view(pl):
    pl.camera_position = "xy"
    pl.camera.azimuth = 30
    pl.camera.elevation = 20
    pl.reset_camera()


def snapshot(pl):
    return pl.screenshot(return_img=True).astype(np.float64) / 255.0


@pytest.mark.parametrize("case", sorted(CASES))
def test_transfer_functions_are_pyvistas(mesh, case):
    ours_plotter, theirs_plotter = plotter(), plotter()
    ours = add_volume(ours_plotter, mesh, **CASES[case])
    theirs = theirs_plotter.add_volume(mesh, **CASES[case])
    assert isinstance(ours.GetMapper(), Mapper)
    mine, pyvistas = transfer_functions(ours), transfer_functions(theirs)
    assert mine.keys() == pyvistas.keys()
    for key in mine:
        assert np.array_equal(np.asarray(mine[key]), np.asarray(pyvistas[key])), key
    assert len(mine["color"]) == CASES[case].get("n_colors", 256)
    # The same data set (PyVista's prepared copy) and the same scalars drawn.
    assert ours.GetMapper().GetScalarMode() == theirs.GetMapper().GetScalarMode()
    ours_data = ours.GetMapper().GetInputDataObject(0, 0)
    theirs_data = theirs.GetMapper().GetInputDataObject(0, 0)
    assert ours_data.GetNumberOfCells() == theirs_data.GetNumberOfCells()
    assert (ours_data.GetPointData().GetScalars().GetName()
            == theirs_data.GetPointData().GetScalars().GetName())
    ours_plotter.close()
    theirs_plotter.close()


def render_both(mesh, arguments):
    """MTPT in the window PyVista makes, and VTK's PT given the very volume property and data
    set, single-sampled (multisampling speckles its cell edges; the C++ image tests).
    No scalar bar: it would be drawn over the volume in one window and not in the other."""
    ours_plotter = plotter()
    actor = add_volume(ours_plotter, mesh, **dict(arguments, show_scalar_bar=False))
    view(ours_plotter)
    ours = snapshot(ours_plotter)
    pt = vtkProjectedTetrahedraMapper()
    pt.SetInputDataObject(actor.GetMapper().GetInputDataObject(0, 0))
    pt.SetScalarMode(actor.GetMapper().GetScalarMode())
    volume = vtkVolume()
    volume.SetMapper(pt)
    volume.SetProperty(actor.GetProperty())
    theirs_plotter = plotter(multi_samples=0)
    theirs_plotter.renderer.AddVolume(volume)
    view(theirs_plotter)
    theirs = snapshot(theirs_plotter)
    reference = vtkMTPTReferenceRenderer()
    assert reference.Render(ours_plotter.renderer, actor)
    width, height = reference.GetSize()
    exact = np.flipud(numpy_support.vtk_to_numpy(reference.GetImage()).reshape(height, width, 3))
    ours_plotter.close()
    theirs_plotter.close()
    covered = np.any(np.abs(ours - np.array(BACKGROUND)) > 2 / 255, axis=2)
    return ours, theirs, exact, covered


def covered_rmse(a, b, covered):
    return float(np.sqrt(np.mean((a[covered] - b[covered]) ** 2)))


# Smooth transfer functions, where VTK's PT is accurate: the two images agree. VTK's PT is
# itself 2.3-3.0/255 from the exact integral here, MTPT 0.3-0.5/255.
IMAGE_CASES = {
    "defaults": {},
    "clim": dict(scalars="Density", cmap="magma", opacity="linear", clim=(0.5, 4.0),
                 n_colors=64, opacity_unit_distance=2.0),
    "cells": dict(scalars="DensityCells", cmap="plasma", opacity="linear", preference="cell",
                  opacity_unit_distance=1.5),
}


@pytest.mark.parametrize("case", sorted(IMAGE_CASES))
def test_image_matches_vtk_pt_given_the_same_volume(mesh, case):
    ours, theirs, exact, covered = render_both(mesh, IMAGE_CASES[case])
    error = covered_rmse(ours, theirs, covered)
    print(f"{case}: covered {covered.mean():.2f} of the window; RMSE against VTK's PT "
          f"{error * 255:.2f}/255, against the exact integral: MTPT "
          f"{covered_rmse(ours, exact, covered) * 255:.2f}/255, VTK's PT "
          f"{covered_rmse(theirs, exact, covered) * 255:.2f}/255")
    assert covered.mean() > 0.05
    assert error <= 3 / 255, error * 255
    assert covered_rmse(ours, exact, covered) <= 1 / 255


def test_steep_opacity_is_closer_to_the_exact_integral_than_vtk_pt(mesh):
    # A sigmoid opacity over a narrow range makes the fin's leading edge nearly opaque, where
    # VTK's PT, interpolating opacity linearly across each tetrahedron, is off by more than
    # 3/255; MTPT is then the closer of the two to the exact integral.
    ours, theirs, exact, covered = render_both(mesh, CASES["named"])
    mine, pts = covered_rmse(ours, exact, covered), covered_rmse(theirs, exact, covered)
    print(f"steep: RMSE against the exact integral: MTPT {mine * 255:.2f}/255, VTK's PT "
          f"{pts * 255:.2f}/255 (MTPT against VTK's PT "
          f"{covered_rmse(ours, theirs, covered) * 255:.2f}/255)")
    assert covered.mean() > 0.01
    assert mine < pts


def test_an_on_screen_window_draws_the_off_screen_image(mesh):
    # A window on the display (Xvfb in the tests), shown as plotter.show() shows it.
    images = []
    for off_screen in (True, False):
        pl = plotter(off_screen=off_screen)
        add_volume(pl, mesh, show_scalar_bar=False)
        view(pl)
        if off_screen:
            images.append(snapshot(pl))
        else:
            pl.show(auto_close=False, interactive=False)
            assert not pl.ren_win.GetOffScreenRendering()
            images.append(snapshot(pl))
        pl.close()
    covered = np.any(np.abs(images[0] - np.array(BACKGROUND)) > 2 / 255, axis=2)
    assert covered.mean() > 0.05
    assert np.abs(images[0] - images[1]).max() <= 1 / 255


def test_mtpt_settings(mesh):
    pl = plotter()
    actor = add_volume(pl, mesh, backend="cpu", shading_mode="pre-integrated",
                       image_sample_distance=2, number_of_threads=1)
    mapper = actor.GetMapper()
    assert mapper.GetBackend() == Mapper.CPU_BACKEND
    assert mapper.GetShadingMode() == Mapper.PRE_INTEGRATED_SHADING
    assert (mapper.GetAutoAdjustSampleDistances(), mapper.GetImageSampleDistance()) == (0, 2.0)
    assert mapper.GetNumberOfThreads() == 1
    assert pl.mapper is mapper  # the scalar bar's mapper
    image = snapshot(pl)
    assert np.any(np.abs(image - np.array(BACKGROUND)) > 0.1)
    pl.close()
    defaults = add_volume(plotter(), mesh).GetMapper()
    assert defaults.GetBackend() == Mapper.AUTOMATIC_BACKEND
    assert defaults.GetAutoAdjustSampleDistances() == 1
    assert defaults.GetBlendMode() == 0


@pytest.mark.parametrize("blending, mode", [("maximum", 1), ("min", 2), ("average", 3),
                                             ("additive", 4), (4, 4)])
def test_blending_takes_pyvistas_names(mesh, blending, mode):
    """PyVista's own unstructured-grid mapper takes composite and maximum only; MTPT's takes
    every mode, and draws it."""
    pl = plotter()
    actor = add_volume(pl, mesh, blending=blending, backend="cpu")
    assert actor.GetMapper().GetBlendMode() == mode
    image = snapshot(pl)
    assert actor.GetMapper().GetLastFrameReuse() & Mapper.ORDER_NOT_NEEDED
    assert np.any(np.abs(image - np.array(BACKGROUND)) > 0.1)
    pl.close()


def test_shade_lights_the_volume(mesh):
    """shade=True lights the volume (PyVista's own unstructured-grid mapper ignores it)."""
    images = []
    for shade in (False, True):
        pl = plotter()
        actor = add_volume(pl, mesh, shade=shade, specular=0.3, backend="cpu")
        assert actor.GetProperty().GetShade(0) == int(shade)
        images.append(snapshot(pl))
        pl.close()
    covered = np.any(np.abs(images[0] - np.array(BACKGROUND)) > 2 / 255, axis=2)
    assert covered.mean() > 0.05
    assert np.abs(images[1] - images[0])[covered].mean() > 0.02


@pytest.mark.parametrize("arguments, error", [
    (dict(mapper="gpu"), TypeError),
    (dict(blending="brightest"), ValueError),
    (dict(backend="vulkan"), ValueError),
    (dict(shading_mode="phong"), ValueError),
    (dict(image_sample_distance=0.5), ValueError),
    (dict(number_of_threads=-2), ValueError),
    (dict(opacity="no-such-opacity"), ValueError),  # PyVista's own check
])
def test_bad_arguments_raise(mesh, arguments, error):
    pl = plotter()
    with pytest.raises(error):
        add_volume(pl, mesh, **arguments)
    assert pl.renderer.GetVolumes().GetNumberOfItems() == 0  # nothing half-added
    pl.close()


def test_scalar_bar_range_updates_our_transfer_functions(mesh):
    pl = plotter()
    actor = add_volume(pl, mesh, scalars="Density", clim=(1.0, 2.0))
    pl.update_scalar_bar_range((0.5, 4.5))
    assert actor.GetProperty().GetRGBTransferFunction(0).GetRange() == (0.5, 4.5)
    assert actor.GetMapper().scalar_range == (0.5, 4.5)
    pl.close()


def test_image_data_is_cast_and_drawn():
    wavelet = pyvista.Wavelet(extent=(-8, 8, -8, 8, -8, 8))
    pl = plotter()
    actor = add_volume(pl, wavelet, cmap="viridis", opacity="linear", opacity_unit_distance=4)
    data = actor.GetMapper().GetInputDataObject(0, 0)
    assert data.GetNumberOfCells() == 5 * 16 ** 3 or data.GetNumberOfCells() == 6 * 16 ** 3
    view(pl)
    image = snapshot(pl)
    assert np.any(np.abs(image - np.array(BACKGROUND)) > 0.1)
    pl.close()


def test_two_add_volume_calls_are_one_picture(mesh):
    """The fin in interleaved slabs, each half its own add_volume (its own colour map, opacity
    and unit distance): the first volume's mapper draws both in one visibility order, within
    2/255 of the exact integral of the two; drawn one after the other, as VTK draws volumes,
    they are further from it."""
    x = mesh.cell_centers().points[:, 0]
    low, high = float(x.min()), float(x.max())
    slab = (np.floor((x - low) / ((high - low) / 6)) % 2).astype(bool)
    halves = [mesh.extract_cells(np.flatnonzero(~slab)), mesh.extract_cells(np.flatnonzero(slab))]
    pl = plotter()
    actors = [add_volume(pl, halves[0], scalars="Density", cmap="viridis", opacity="linear",
                         opacity_unit_distance=1.0, show_scalar_bar=False),
              add_volume(pl, halves[1], scalars="Density", cmap="magma", opacity="linear_r",
                         opacity_unit_distance=0.6, show_scalar_bar=False)]
    view(pl)
    together = snapshot(pl)
    # Tetrahedra drawn: those left after culling (transparent ones among them).
    drawn = actors[0].GetMapper().GetNumberOfTetrahedra()
    assert drawn > max(h.n_cells for h in halves) / 2
    assert actors[1].GetMapper().GetNumberOfTetrahedra() == 0
    for actor in actors:
        actor.GetMapper().SetCompositeWithOtherVolumes(False)
    pl.render()
    apart = snapshot(pl)
    assert sum(a.GetMapper().GetNumberOfTetrahedra() for a in actors) == drawn

    # The exact integral of the two volumes together.
    reference = vtkMTPTReferenceRenderer()
    assert reference.RenderVolumes(pl.renderer, pl.renderer.GetVolumes())
    assert reference.GetExactTransferFunctions()
    width, height = reference.GetSize()
    exact = np.flipud(numpy_support.vtk_to_numpy(reference.GetImage()).reshape(height, width, 3))
    pl.close()
    covered = np.any(np.abs(together - np.array(BACKGROUND)) > 2 / 255, axis=2)
    right, wrong = covered_rmse(together, exact, covered), covered_rmse(apart, exact, covered)
    print(f"two add_volume calls: covered RMSE against the exact integral: together "
          f"{right * 255:.2f}/255, one after the other {wrong * 255:.2f}/255")
    assert covered.mean() > 0.05
    assert right <= 2 / 255
    assert wrong > 2 * right
