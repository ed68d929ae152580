"""The engines per process: no GPU opened at import, the GPU engine agrees with the CPU one,
and both work in processes forked after the parent used them."""

import multiprocessing
import os
import subprocess
import sys

import numpy as np
import pytest

import mdsurf

# A small blob of atoms on a jittered lattice (Å): quick even on a software GPU.
RNG = np.random.default_rng(7)
BLOB = (np.indices((5, 5, 4)).reshape(3, -1).T * 1.6 + RNG.normal(0, 0.3, (100, 3))).astype(np.float32)
RADII = np.where(np.arange(100) % 3 == 0, 1.0, 1.5).astype(np.float32)


def gpu_or_skip():
    try:
        return mdsurf.engine_info("gpu")
    except RuntimeError as e:
        if os.environ.get("REQUIRE_GPU") == "1":  # CI: a missing adapter fails, as in Rust
            pytest.fail(f"REQUIRE_GPU=1 but {e}")
        pytest.skip(f"no GPU engine here: {e}")


def test_import_opens_no_device():
    code = (
        "import mdsurf, mdsurf.analysis, numpy as np\n"
        "mdsurf.surface(np.zeros((1, 3)), [1.0], backend='cpu')\n"
        "mdsurf.measure(np.zeros((0, 1, 3)), [1.0])\n"
        "print(mdsurf._mdsurf._gpu_opened())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip() == "False"


def test_single_atom_sphere():
    """DESIGN section 2: one atom's surface is the sphere of radius 1.177 alpha (slightly
    inside it with linear interpolation)."""
    s = mdsurf.surface([[0, 0, 0]], [2.0], colors=[[1.0, 0.5, 0.25]], spacing=0.25, backend="cpu")
    r = 2.0 * np.sqrt(2 * np.log(2))
    assert s.area == pytest.approx(4 * np.pi * r * r, rel=0.02)
    assert s.volume == pytest.approx(4 / 3 * np.pi * r**3, rel=0.03)
    assert s.vertices.dtype == np.float32 and s.triangles.dtype == np.uint32
    assert s.normals.shape == s.vertices.shape == s.colors.shape
    np.testing.assert_allclose(s.colors, np.tile([1.0, 0.5, 0.25], (len(s.colors), 1)), atol=1e-4)
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0, atol=1e-4)
    # Outward normals: along the vertex position for a sphere at the origin.
    assert np.all(np.sum(s.normals * s.vertices, axis=1) > 0)
    assert s.triangles.max() < len(s.vertices)
    assert s.grid.spacing == 0.25 and len(s.grid.dims) == 3
    assert mdsurf.surface([[0, 0, 0]], [2.0], backend="cpu").colors is None


def test_gpu_matches_cpu():
    gpu_or_skip()
    cpu = mdsurf.surface(BLOB, RADII, backend="cpu")
    gpu = mdsurf.surface(BLOB, RADII, backend="gpu")
    assert gpu.engine == "gpu" and cpu.engine == "cpu"
    assert gpu.grid.dims == cpu.grid.dims
    assert gpu.area == pytest.approx(cpu.area, rel=1e-3)
    assert gpu.volume == pytest.approx(cpu.volume, rel=1e-3)
    assert abs(len(gpu.triangles) - len(cpu.triangles)) <= 0.005 * len(cpu.triangles)
    area, _ = mdsurf.measure(np.stack([BLOB, BLOB + 1]), RADII, backend="gpu")
    assert area[0] == pytest.approx(gpu.area, rel=1e-9)


def _area_in_child(backend):
    return mdsurf.surface(BLOB, RADII, backend=backend).area


@pytest.mark.parametrize("backend", ["cpu", "gpu"])
def test_engine_works_after_fork(backend):
    """A forked child does not reuse the parent's threads or device: it opens its own."""
    if backend == "gpu":
        gpu_or_skip()
    here = mdsurf.surface(BLOB, RADII, backend=backend).area  # the parent's engine is open
    with multiprocessing.get_context("fork").Pool(1) as pool:
        there = pool.apply_async(_area_in_child, (backend,)).get(timeout=120)
    assert there == pytest.approx(here, rel=1e-9)


def test_no_driver_noise_without_a_desktop_session():
    """Without XDG_RUNTIME_DIR (SSH, clusters, CI) opening the GPU prints nothing on stderr:
    Mesa's device-select layer would print two 'XDG_RUNTIME_DIR is invalid' lines."""
    gpu_or_skip()
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_RUNTIME_DIR", "NODEVICE_SELECT")}
    code = "import mdsurf, numpy as np\nmdsurf.surface(np.zeros((1, 3)), [1.5], backend='gpu')\n"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "XDG_RUNTIME_DIR" not in out.stderr
    assert out.stderr.strip() == "", out.stderr
