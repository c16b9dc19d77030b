# SPDX-License-Identifier: BSD-3-Clause
"""The package refuses, with a clear ImportError and no crash, to load beside another VTK
than the one it was built against."""
import os
import shutil
import subprocess
import sys

import pytest

import mtpt
from mtpt import _build


def import_copy(tmp_path, version, common_core):
    """Imports a copy of the installed package whose record names another VTK; returns the
    finished process."""
    copy = tmp_path / "mtpt"
    shutil.copytree(os.path.dirname(mtpt.__file__), copy,
                    ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "_build.py").write_text(f"VTK_VERSION = {version!r}\nVTK_COMMON_CORE = {common_core!r}\n")
    env = dict(os.environ, PYTHONPATH=str(tmp_path), PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, "-c", "import mtpt"], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)


def test_the_record_names_the_running_vtk():
    from vtkmodules.vtkCommonCore import vtkVersion
    assert _build.VTK_VERSION.split(".")[:2] == vtkVersion.GetVTKVersion().split(".")[:2]
    assert os.path.exists(_build.VTK_COMMON_CORE)


def test_another_vtk_version_is_refused(tmp_path):
    done = import_copy(tmp_path, "8.2.0", _build.VTK_COMMON_CORE)
    assert done.returncode == 1, (done.returncode, done.stderr)
    assert "ImportError: mtpt was built against VTK 8.2.0, but this Python imports VTK" in done.stderr


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="Linux's /proc tells the loaded VTK")
def test_a_second_copy_of_vtk_is_refused(tmp_path):
    other = "/opt/another-vtk/lib/" + os.path.basename(_build.VTK_COMMON_CORE)
    done = import_copy(tmp_path, _build.VTK_VERSION, other)
    assert done.returncode == 1, (done.returncode, done.stderr)
    assert "two VTKs cannot share a process" in done.stderr
