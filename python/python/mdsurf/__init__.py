"""Gaussian density surfaces for molecular dynamics trajectories.

The engine of the ``mdsurf`` command line (Krone et al., EuroVis 2012; VMD's QuickSurf) on
numpy arrays: each atom is a Gaussian of width ``radius * radius_scale``, the surface is where
the density sum equals ``isovalue``, extracted by Marching Cubes on a grid of ``spacing`` Å.
Defaults are those of ``mdsurf surface``, so areas and volumes equal its ``--stats``.

Lengths are in Å, areas in Å², volumes in Å³. Bad input raises ``ValueError`` with the same
one-line message as the command line; a grid too large for memory raises ``MemoryError``; a GPU
that cannot start (``backend="gpu"``) raises ``RuntimeError``.

The GPU device is opened lazily, in the process that first computes with ``backend="gpu"`` or
``"auto"`` (never at import), so the package works in forked workers (``multiprocessing``, Dask).

``mdsurf.Scene`` measures the representations of ``mdsurf surface`` (``select=``, ``state=`` or
the defaults) frame by frame, through the command line's frame transformations (whole
molecules, ``center``, ``fit``, ``smooth``). ``mdsurf.analysis.GaussianSurface`` is an
MDAnalysis analysis (serial, multiprocessing, dask).
"""

import os

import numpy as np

# Mesa's Vulkan device-select layer prints "error: XDG_RUNTIME_DIR is invalid or not set" when
# there is no desktop session (SSH, clusters, CI) and has nothing to choose by there; its own
# switch turns it off, as the command line does for itself. Set before any device is opened.
if not os.environ.get("XDG_RUNTIME_DIR"):
    os.environ.setdefault("NODEVICE_SELECT", "1")

from . import _mdsurf  # noqa: E402
from ._mdsurf import Grid, Surface, element_radius, guess_element  # noqa: E402

__all__ = [
    "Grid",
    "Scene",
    "Surface",
    "element_radius",
    "engine_info",
    "guess_element",
    "measure",
    "surface",
    "topology_radii",
]

__version__ = "0.1.0"


def _f32(a, name):
    """``a`` as a float32 numpy array (no copy when it already is one)."""
    try:
        return np.asarray(a, dtype=np.float32)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name} must be an array of numbers: {e}") from None


def surface(
    positions,
    radii,
    colors=None,
    spacing=1.0,
    radius_scale=1.0,
    isovalue=0.5,
    quality="medium",
    backend="auto",
    vertices="interpolated",
):
    """The Gaussian density surface of one set of atoms.

    Parameters
    ----------
    positions : array_like, shape (N, 3)
        Atom positions in Å (converted to float32).
    radii : array_like, shape (N,)
        Atom radii in Å, positive (see :func:`topology_radii` for the CLI's radii).
    colors : array_like, shape (N, 3), optional
        Linear RGB colour per atom in 0..1; the surface's vertex colours blend them.
    spacing : float
        Grid spacing H in Å (default 1.0).
    radius_scale : float
        Radius scale R: Gaussian width alpha = radius * R (default 1.0).
    isovalue : float
        Isovalue I of the density; 1.0 is the peak of one isolated atom (default 0.5).
    quality : str
        Gaussian cutoff: "low" (2 alpha), "medium" (2.5, default), "high" (3), "max" (4).
    backend : str
        "cpu", "gpu", or "auto" (the GPU on a hardware adapter, else the CPU).
    vertices : str
        "interpolated" (default, as the paper) or "refined" (on the exact Gaussian sum).

    Returns
    -------
    Surface
        ``vertices`` (V, 3) and ``normals`` (V, 3) float32, ``colors`` (V, 3) or None,
        ``triangles`` (T, 3) uint32, ``area`` (Å²), ``volume`` (Å³), ``grid`` (``origin`` in
        Å, ``spacing`` in Å, ``dims``) and ``engine`` ("cpu" or "gpu").
    """
    return _mdsurf.surface(
        _f32(positions, "positions"),
        _f32(radii, "radii"),
        None if colors is None else _f32(colors, "colors"),
        float(spacing),
        float(radius_scale),
        float(isovalue),
        str(quality),
        str(backend),
        str(vertices),
    )


def measure(
    trajectory,
    radii,
    spacing=1.0,
    radius_scale=1.0,
    isovalue=0.5,
    quality="medium",
    backend="auto",
    vertices="interpolated",
    boxes=None,
):
    """Surface area and enclosed volume of every frame, without building meshes in Python.

    Parameters
    ----------
    trajectory : array_like, shape (F, N, 3)
        Positions in Å of N atoms in F frames (converted to float32).
    radii : array_like, shape (N,)
        Atom radii in Å.
    spacing, radius_scale, isovalue, quality, backend, vertices
        As in :func:`surface`.
    boxes : array_like, shape (F, 3, 3), optional
        Each frame's periodic box (rows a, b, c in Å): the surfaces are then periodic in it,
        as ``mdsurf surface --periodic`` computes them (area and volume per cell; CPU,
        interpolated vertices).

    Returns
    -------
    (area, volume) : tuple of numpy.ndarray, shape (F,), float64
        Area in Å² and volume in Å³ per frame. An error names the frame (``frame 3: ...``).
    """
    return _mdsurf.measure(
        _f32(trajectory, "trajectory"),
        _f32(radii, "radii"),
        float(spacing),
        float(radius_scale),
        float(isovalue),
        str(quality),
        str(backend),
        str(vertices),
        boxes=None if boxes is None else _f32(boxes, "boxes"),
    )


def topology_radii(names, resnames=None, elements=None, positions=None):
    """Radii in Å (float32 array) as ``mdsurf surface`` assigns them to these atoms.

    Elements come from ``elements`` where an entry is a valid symbol, else are guessed from the
    atom name and residue name; coarse-grained (Martini) systems get the bead radius 2.35 Å;
    particles without an element are sized from their spacing in ``positions`` (N, 3, Å) when
    given. Pass the whole system, then index the result, so that these system-wide rules see
    what the CLI sees.
    """
    names = [str(n) for n in names]
    resnames = None if resnames is None else [str(r) for r in resnames]
    elements = None if elements is None else [str(e) for e in elements]
    if positions is not None:
        positions = _f32(positions, "positions")
    return _mdsurf.topology_radii(names, resnames, elements, positions)


def engine_info(backend="auto"):
    """Which engine ``backend`` uses in this process, and why (opens the GPU if needed).

    For example ``"cpu (no usable GPU: ...)"`` or ``"gpu (NVIDIA H100 (Vulkan))"``.
    """
    return _mdsurf.engine_info(str(backend))


from .scene import Scene  # noqa: E402
