"""eyeshell from Python: the morphoelastic shell model of eye growth, solved through SUNDIALS.

The same library as the ``eyeshell`` command line (the Rust crate ``eyeshell``), called in
process: scenes are the command line's scenes, with the same keys (``eyeshell.keys()``), and
results come back as NumPy arrays.

>>> import eyeshell
>>> sol = eyeshell.solve(eyeshell.Scene(), **{"solver.nodes": 201})
>>> sol.r.shape == sol.Sigma.shape == (sol.summary["nodes"],)
True
>>> sol.summary["residual_norm"] < 1e-8
True

Entry points: :class:`Scene`, :func:`keys`, :func:`solve` (a :class:`Solution`),
:func:`grow` (a :class:`Growth`, with sensitivities on request), :func:`optics` (the
best-focus surfaces of a schematic eye, as arrays), :func:`fit` (a
:class:`FitResult`: calibration to measured axial lengths), :func:`sweep` and
:func:`iter_sweep` (a :class:`SweepResults` list, or an iterator, of :class:`RunResult`;
``SweepResults.to_frame()`` tabulates a whole sweep), :func:`compare` (a
:class:`Comparison`). Errors are
:class:`InputError` (bad input: the command line exits 2) and :class:`SolverError` (a failed
computation: exit 1), both :class:`EyeshellError`, each with the attributes ``key``,
``value`` and ``origin`` (what the error is about, as given, and where it came from) and
``stage`` (what failed), None where not applicable.
"""

from __future__ import annotations

from ._eyeshell import EyeshellError, InputError, SolverError, __version__
from ._eyeshell import sundials_version as _sundials_version
from ._api import (
    Comparison,
    FitResult,
    Growth,
    RunResult,
    Scene,
    Solution,
    SweepResults,
    compare,
    fit,
    grow,
    iter_sweep,
    jacobian,
    keys,
    optics,
    residual,
    solve,
    sweep,
)

__all__ = [
    "Comparison",
    "EyeshellError",
    "FitResult",
    "Growth",
    "InputError",
    "RunResult",
    "Scene",
    "Solution",
    "SolverError",
    "SweepResults",
    "compare",
    "fit",
    "grow",
    "iter_sweep",
    "jacobian",
    "keys",
    "optics",
    "residual",
    "solve",
    "sundials_version",
    "sweep",
    "__version__",
]


def sundials_version() -> str | None:
    """The version of the SUNDIALS library the module loaded (Debian's 6.x), as summary.json names it.

    >>> eyeshell.sundials_version().startswith("6.")
    True
    """
    return _sundials_version()
