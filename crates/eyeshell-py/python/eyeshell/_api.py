"""The Python API over the extension module ``eyeshell._eyeshell``.

The extension converts (scenes, arrays, errors) and runs the computations with the GIL
released; this module shapes the results (Solution, Growth, RunResult), formats progress,
and runs sweeps in worker processes (``_worker``), from threads of its own or from any
``concurrent.futures.Executor``-like object.
"""

from __future__ import annotations

import json
import math
import operator
import os
import queue
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence, Union

import numpy as np

from . import _eyeshell, _worker
from ._eyeshell import EyeshellError, InputError, SolverError

PathLike = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]
# What names a file: a str, bytes (the file system's encoding), or an os.PathLike of either.
_PATH_TYPES = (str, bytes, os.PathLike)
SceneLike = Union["Scene", PathLike, Mapping[str, Any], None]
Progress = Union[bool, Callable[[float, float], Any], None]


def _path(path: Any, what: str) -> str:
    """`path` (a str, bytes or os.PathLike of either) as the str the extension takes
    (bytes decoded as ``os.fsdecode`` does, so a name that is not UTF-8 reaches the file
    system unchanged)."""
    if not isinstance(path, _PATH_TYPES):
        raise TypeError(f"{what} must be a path (a str, bytes or os.PathLike), not {type(path).__name__}")
    return os.fsdecode(path)


def _key(name: str) -> str:
    """A keyword argument's name as a scene key: ``fibres__D`` is ``fibres.D``."""
    return name.replace("__", ".")


def _flatten(mapping: Mapping[str, Any], prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(dotted key, value) of a mapping with dotted keys or TOML-like nested tables."""
    for k, v in mapping.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            yield from _flatten(v, key + ".")
        else:
            yield key, v


class Scene:
    """A scene: the shell's parameters and the solver's settings, with the command line's keys.

    ``Scene()`` is the default scene (the paper's shell); ``Scene(mapping)`` sets the keys of
    ``mapping`` on it, given dotted (``{"fibres.D": 200}``) or nested as in a TOML file
    (``{"fibres": {"D": 200}}``); keyword arguments set more keys, with ``__`` for the dot
    (``Scene(fibres__D=200)``). The keys are set together and checked once, as
    ``eyeshell check`` checks a scene file, so keys that are only valid together can be set
    in one call (``Scene(growth__t_end=0.2, output__times=[0.2])``): a bad key or value
    raises :class:`InputError` naming it.

    Values: a number, a bool, a string, or a list of numbers; NumPy scalars and 0-d arrays
    count as the value they hold. An integer key (``solver.nodes``, ...) takes any
    integral number: an ``int``, a NumPy integer (``np.int64(301)``, ``np.array(301)``),
    anything with ``__index__``; a float is refused even when whole (301.0), as in a scene
    file and ``--set``, so that no computed value passes or fails on its last bit.

    >>> s = eyeshell.Scene({"fibres": {"D": 200}}, solver__nodes=301)
    >>> s["fibres.D"], s["solver.nodes"]
    (200.0, 301)
    >>> s.set("pressure.dP", 2.5)["pressure.dP"]
    2.5
    >>> eyeshell.Scene(fibres__D=-1)
    Traceback (most recent call last):
    ...
    eyeshell.InputError: set fibres.D=-1: fibres.D = -1 must be non-negative
    >>> eyeshell.Scene(solver__nodes=np.int64(301))["solver.nodes"]
    301
    >>> eyeshell.Scene(growth__t_end=0.2, output__times=[0.1, 0.2])["output.times"]
    [0.1, 0.2]
    """

    __slots__ = ("_s",)

    def __init__(self, mapping: Mapping[str, Any] | None = None, /, **overrides: Any) -> None:
        self._s = _eyeshell._Scene.defaults()
        self.update(mapping or {}, **overrides)

    @classmethod
    def _wrap(cls, native: Any) -> "Scene":
        scene = cls.__new__(cls)
        scene._s = native
        return scene

    @classmethod
    def from_file(cls, path: PathLike, /, *, sweep: bool = True, **overrides: Any) -> "Scene":
        """Read and validate the scene file ``path`` (TOML, as ``eyeshell solve`` reads it;
        a str, bytes or os.PathLike), then set ``overrides``.

        A sweep file (a scene with a ``[sweep]`` table) is many scenes: it is refused
        (:class:`InputError`, saying so) unless ``sweep=False``, which reads the scene its
        runs start from, without the sweep. To run it, give the file to :func:`sweep`.

        >>> s = eyeshell.Scene.from_file(SCENES + "/const.toml")
        >>> s.grows, s.name
        (True, 'const')
        >>> eyeshell.Scene.from_file(SCENES + "/grow.toml", sweep=False)["fibres.D"]
        100.0
        """
        if not isinstance(sweep, (bool, np.bool_)):
            raise TypeError(f"sweep must be True or False, not {type(sweep).__name__}")
        native = _eyeshell._Scene.from_file(_path(path, "a scene file"), bool(sweep))
        return cls._wrap(native).update(**overrides)

    @classmethod
    def from_toml(cls, text: str, /, **overrides: Any) -> "Scene":
        """Parse and validate a scene from TOML text.

        >>> eyeshell.Scene.from_toml("[fibres]\\nD = 100\\n")["fibres.D"]
        100.0
        """
        return cls._wrap(_eyeshell._Scene.from_toml(text)).update(**overrides)

    def update(self, mapping: Mapping[str, Any] | None = None, /, **overrides: Any) -> "Scene":
        """Set every key of ``mapping`` (dotted or nested), then of ``overrides``
        (``__`` for the dot), in order, and validate once, when all are set (keys such as
        ``growth.t_end`` and ``output.times`` are only valid together); on an error the
        scene is left as it was. Returns the scene."""
        items = list(_flatten(mapping or {})) + [(_key(k), v) for k, v in overrides.items()]
        if items:
            self._s.set_all(items)
        return self

    def set(self, key: str, value: Any) -> "Scene":
        """Set one key (``scene.set("fibres.D", 200)``, as ``--set fibres.D=200``) and
        validate; on an error the scene is left as it was. Returns the scene."""
        self._s.set(key, value)
        return self

    def get(self, key: str) -> Any:
        """The effective value of ``key`` (None for an optional key left unset)."""
        return self._s.get(key)

    __getitem__ = get

    def __setitem__(self, key: str, value: Any) -> None:
        self.set(key, value)

    def copy(self, **overrides: Any) -> "Scene":
        """A copy of the scene, with ``overrides`` set on the copy."""
        return Scene._wrap(_eyeshell._Scene.from_toml(self._s.to_toml(), self._s.origin)).update(
            **overrides
        )

    def to_dict(self) -> dict[str, Any]:
        """Every key in use and its effective value, in the order of ``eyeshell keys``."""
        return self._s.entries()

    def to_toml(self) -> str:
        """The effective scene as TOML (dotted keys); it reads back to the same scene."""
        return self._s.to_toml()

    @property
    def grows(self) -> bool:
        """Does the scene grow (is any ``growth.*`` key set)?"""
        return self._s.grows

    @property
    def name(self) -> str:
        """The scene's ``name``, else its file's stem."""
        return self._s.name

    @property
    def span(self) -> tuple[float, float]:
        """Σ's range [ε, L]: ``solver.epsilon`` and the shell's length."""
        return self._s.span

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scene) and self.to_toml() == other.to_toml()

    def __repr__(self) -> str:
        return f"<eyeshell.Scene {self.name!r} ({'growth' if self.grows else 'elastic'})>"

    def __reduce__(self) -> tuple[Any, ...]:
        return (Scene.from_toml, (self.to_toml(),))


def _as_scene(scene: SceneLike, overrides: Mapping[str, Any]) -> Scene:
    """A new Scene from a Scene, a path or a mapping, with ``overrides`` set."""
    if scene is None:
        result = Scene()
    elif isinstance(scene, Scene):
        result = scene.copy()
    elif isinstance(scene, Mapping):
        result = Scene(scene)
    elif isinstance(scene, _PATH_TYPES):
        result = Scene.from_file(scene)
    else:
        raise TypeError(
            "scene must be a Scene, a mapping of keys, a scene file's path (a str, bytes or "
            f"os.PathLike) or None, not {type(scene).__name__}"
        )
    return result.update(**overrides)


def keys() -> list[dict[str, Any]]:
    """Every scene key (``eyeshell keys``): dicts with key, type, default, doc, range and
    growth (a key of the growth model, used only when the scene grows).

    >>> k = {k["key"]: k for k in eyeshell.keys()}
    >>> k["fibres.D"]["default"], k["solver.nodes"]["type"]
    (0.0, 'integer')
    """
    return _eyeshell.keys()


class Solution:
    """A solved elastic shell: every field at every node as NumPy arrays.

    ``sol.fields`` maps each column of fields.csv (``Sigma``, ``sigma``, ``kappa``,
    ``alpha_s``, ``r``, ``theta``, ``Q``, ``z``, ``s``, ``alpha_phi``, ``alpha_n``, ``h``,
    ``t_s``, ``t_phi``) to an array over the nodes, each also an attribute (``sol.r``).
    ``sol.x``, ``sol.y`` (5×N: κ, α_s, r, θ, Q) and ``sol.yp`` (their d/dΣ, f(x, y)) are
    bvp4c's (x holds each interface of the material data twice, as bvp4c does);
    :meth:`at` evaluates the continuous interpolant; :attr:`summary` is summary.json's
    content; :meth:`to_bvp4c` is the ``sol`` struct of ``eyeshell export --mat``.

    >>> sol = eyeshell.solve(solver__nodes=101)
    >>> sol.y.shape == sol.yp.shape == (5, len(sol.x))
    True
    >>> bool(np.all(np.diff(sol.Sigma) > 0))
    True
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        self._scene_toml = native.scene().to_toml()
        self.fields: dict[str, np.ndarray] = native.fields()
        self.summary: dict[str, Any] = json.loads(native.summary_text())
        # Measured here, where the native solution is: an unpickled one would solve again.
        self._eye: dict[str, Any] = dict(native.eye())
        self._refraction_D: float | None = native.refraction_d()
        self._state: np.ndarray = native.state()
        self._bvp4c: dict[str, Any] | None = None

    @property
    def scene(self) -> Scene:
        """The scene solved."""
        return Scene.from_toml(self._scene_toml)

    def _solved(self) -> Any:
        if self._native is None:  # unpickled: solve again (deterministic, bit for bit)
            self._native = _eyeshell.solve(self.scene._s)
        return self._native

    def __getattr__(self, name: str) -> np.ndarray:
        fields = self.__dict__.get("fields")
        if fields is not None and name in fields:
            return fields[name]
        raise AttributeError(f"Solution has no attribute or field {name!r}")

    def __len__(self) -> int:
        return len(self.fields["Sigma"])

    def at(self, Sigma: float | Sequence[float] | np.ndarray) -> dict[str, Any]:
        """Every field at the material points ``Sigma`` (in [ε, L]) from the continuous
        interpolant (cubic Hermite, as bvp4c's deval): a dict of floats for a number, of
        arrays for an array.

        >>> sol = eyeshell.solve(solver__nodes=101)
        >>> p = sol.at(5.0)
        >>> round(p["Sigma"], 12), sorted(p) == sorted(sol.fields)
        (5.0, True)
        >>> sol.at([1.0, 2.0])["r"].shape
        (2,)
        """
        x = np.asarray(Sigma, dtype=float)
        values = self._solved().at(np.atleast_1d(x).ravel().tolist())
        if x.ndim == 0:
            return {k: float(v[0]) for k, v in values.items()}
        return {k: v.reshape(x.shape) for k, v in values.items()}

    def _export(self) -> dict[str, Any]:
        if self._bvp4c is None:
            self._bvp4c = self._solved().bvp4c()
        return self._bvp4c

    @property
    def x(self) -> np.ndarray:
        """Σ at the nodes (bvp4c's ``sol.x``): :attr:`Sigma`, with each interface (where the
        material data jump or kink: docs/guide/files.md) twice, the limit from below first."""
        return self._export()["x"]

    @property
    def y(self) -> np.ndarray:
        """5×N: κ, α_s, r, θ, Q at the nodes (bvp4c's ``sol.y``)."""
        return self._export()["y"]

    @property
    def yp(self) -> np.ndarray:
        """5×N: d/dΣ of the rows of :attr:`y` at the points of :attr:`x` (bvp4c's ``sol.yp``):
        f(x, y) of docs/MODEL.md §3 on κ, r, θ and Q, and on the algebraic row α_s its
        derivative along the same flow; each copy of an interface from its own side."""
        return self._export()["yp"]

    @property
    def state(self) -> np.ndarray:
        """The unknowns of the discrete problem at the nodes, 5 per node in node order:
        ``[κ_0, r_0, θ_0, q_s0, t_s0, κ_1, …]`` with q_s = Q / r (the shear), as
        :func:`residual` and :func:`jacobian` take them. ``state.reshape(-1, 5)`` has a row
        per node of :attr:`Sigma`.

        >>> sol = eyeshell.solve(solver__nodes=101)
        >>> st = sol.state.reshape(-1, 5)
        >>> bool(np.array_equal(st[:, 1], sol.r)), bool(np.allclose(st[:, 1] * st[:, 3], sol.Q))
        (True, True)
        """
        return self._state.copy()

    @property
    def eye(self) -> dict[str, Any]:
        """The loaded, ungrown eye as a sweep's table measures it (docs/MODEL.md §6):
        ``axial_length``, ``equatorial_radius``, ``retina_minus_blue``,
        ``retina_minus_red`` (mm) and ``class``, and ``refraction_D`` (:attr:`refraction_D`)
        for a scene with optics to compute it with.

        >>> e = eyeshell.solve(solver__nodes=101).eye
        >>> sorted(e)
        ['axial_length', 'class', 'equatorial_radius', 'retina_minus_blue', 'retina_minus_red']
        """
        return dict(self._eye)

    @property
    def refraction_D(self) -> float | None:
        """The refraction (D) at the pole of the loaded, ungrown eye through the naked eye:
        the spectacle power at 12 mm that brings its on-axis best focus onto the retina, a
        growth run's first ``refraction_D`` (summary.json's ``refraction_D``). The optics are
        those a growth run of the scene refracts through (its own with
        ``stimulus.source = "optics"``, else the default optics); ``None`` for a scene that
        neither grows nor computes its optics (no eye to refract through), NaN beyond the
        ±25 D the optics are traced over.

        >>> round(eyeshell.solve(SCENES + "/const.toml", solver__nodes=101).refraction_D, 2)
        10.46
        >>> eyeshell.solve(solver__nodes=101).refraction_D is None
        True
        """
        return self._refraction_D

    def to_mat(self, path: PathLike, /, force: bool = False) -> str:
        """Write the solution to the .mat file ``path`` as ``eyeshell export --mat`` writes
        an elastic run (the struct ``sol`` of :meth:`to_bvp4c`, for MATLAB's ``deval``);
        returns the path. A file eyeshell did not write is replaced only with ``force=True``.
        """
        if not isinstance(force, (bool, np.bool_)):
            raise TypeError(f"force must be True or False, not {type(force).__name__}")
        return self._solved().write_mat(_path(path, "path"), bool(force))

    def to_bvp4c(self) -> dict[str, Any]:
        """A dict shaped like bvp4c's ``sol`` (``solver``, ``x``, ``y``, ``yp``, ``stats``,
        and the other fields), as ``eyeshell export --mat`` writes it: save it with
        ``scipy.io.savemat(path, {"sol": sol.to_bvp4c()})`` for MATLAB's ``deval``.

        >>> b = eyeshell.solve(solver__nodes=101).to_bvp4c()
        >>> b["solver"], b["y"].shape[0], sorted(b["stats"])
        ('bvp4c', 5, ['maxres', 'nBCevals', 'nODEevals', 'nmeshpoints'])
        """
        return dict(self._export())

    def __repr__(self) -> str:
        s = self.summary
        return (
            f"<eyeshell.Solution of {s.get('scene', {}).get('name', '?')!r}: {len(self)} nodes, "
            f"Newton {s.get('newton_iterations')} iterations, residual {s.get('residual_norm'):.2e}>"
        )

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_native"] = None
        state["_bvp4c"] = None
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)


def solve(scene: SceneLike = None, /, **overrides: Any) -> Solution:
    """Solve the loaded elastic shell of ``scene`` (a :class:`Scene`, a scene file's path
    as a str, bytes or os.PathLike, a mapping of keys, or None for the default scene),
    with ``overrides`` set on a copy
    (``solve(scene, fibres__D=200)`` or ``solve(scene, **{"fibres.D": 200})``). The GIL is
    released while it solves.

    Raises :class:`InputError` for bad input (a key, a value, a pressure beyond the
    cornea's limit) and :class:`SolverError` when the solve fails.

    >>> sol = eyeshell.solve(SCENES + "/default.toml", solver__nodes=201)
    >>> sol.summary["nodes"] >= 201 and sol.summary["first_integral_max"] < 1e-8
    True
    """
    s = _as_scene(scene, overrides)
    return Solution(_eyeshell.solve(s._s))


def _state_list(state: Any) -> list[float]:
    a = np.asarray(state, dtype=float)
    if a.ndim != 1:
        raise _input_error(
            f"state must be a 1-D array (5 values per node, as Solution.state), not of shape {a.shape}",
            "state", f"shape {a.shape}", "argument",
        )
    return a.tolist()


def residual(scene: SceneLike, state: Any, /, *, scaled: bool = False, **overrides: Any) -> np.ndarray:
    """The residuals F(state) of the discrete elastic problem of ``scene`` (with
    ``overrides`` set on a copy): the equations eyeshell's Newton iteration solves, on the
    mesh of ``solver.nodes`` (``solver.tol`` and ``solver.richardson`` adapt the mesh and
    are refused). ``state`` is :attr:`Solution.state`'s layout: (κ, r, θ, q_s, t_s) at each
    node in turn, 5 per node. The residuals are, in order, the three pole conditions at
    Σ = ε, five per interval (the scheme's step for κ, r, θ, q_s, t_s) and the two cornea
    conditions: as many as the unknowns. With ``scaled=True`` each is multiplied by the
    scale Newton's convergence test uses (1 over its unknown's typical size: 1/R0 for r,
    1 for θ, …), so that a solved state has ``max |F| <= solver.newton_tol``.

    Raises :class:`InputError` for a state of the wrong length, a value that is not
    finite, or a state at which the equations cannot be evaluated (r <= 0 at a node).

    >>> scene = eyeshell.Scene(solver__nodes=101)
    >>> sol = eyeshell.solve(scene)
    >>> bool(np.max(np.abs(eyeshell.residual(scene, sol.state, scaled=True))) <= 1e-10)
    True
    """
    s = _as_scene(scene, overrides)
    return _eyeshell.residual(s._s, _state_list(state), bool(scaled))


def jacobian(scene: SceneLike, state: Any, /, **overrides: Any) -> Any:
    """The analytic Jacobian ∂F/∂state of :func:`residual` (the matrix eyeshell's Newton
    iteration factors) as a ``scipy.sparse.csr_array`` of 5M × 5M, every entry of its band
    pattern stored (zeros included). SciPy is needed for this function only.

    >>> scene = eyeshell.Scene(solver__nodes=21)
    >>> sol = eyeshell.solve(scene)
    >>> J = eyeshell.jacobian(scene, sol.state)
    >>> J.shape == (sol.state.size, sol.state.size) == (5 * len(sol), 5 * len(sol))
    True
    """
    try:
        import scipy.sparse as sparse
    except ImportError as e:  # pragma: no cover - scipy is optional at import
        raise ImportError("eyeshell.jacobian needs SciPy (pip install scipy)") from e
    s = _as_scene(scene, overrides)
    values, cols, rows, n = _eyeshell.jacobian(s._s, _state_list(state))
    return sparse.csr_array((values, cols, rows), shape=(n, n))


def optics(scene: SceneLike = None, /, **overrides: Any) -> dict[str, Any]:
    """The best-focus surfaces of ``scene``'s schematic eye (its ``optics.*`` keys, with
    ``overrides`` set on a copy), as ``eyeshell optics`` computes them: a dict of 1-D arrays
    with one entry per (wavelength, field angle), in wavelength then field order
    (``wavelength_nm``, ``field_deg``, ``z``, ``r``, ``strehl``, and ``sagittal`` /
    ``tangential``, the focal lines' distances along the chief ray), and ``criterion``,
    ``eye``, ``pupil``, ``z_B``, ``phi_max`` (blue, red: where each surface ends about
    ``z_B``), ``rays_traced`` and ``wall_seconds``. The GIL is released while it traces.

    ``refraction`` is the refraction without growing, as ``eyeshell optics`` writes it to
    refraction.csv and peripheral.csv (docs/guide/optics.md, "Refraction without growing"):
    of the loaded, ungrown retina, a list with one dict per time (t = 0, then each table
    time of optics that change with age) holding ``t``, ``refraction_D`` (the pole's, naked
    eye: a growth run's first), ``peripheral`` (``field_deg``, ``refraction_D``,
    ``relative_D`` arrays) and ``through_lenses`` (one dict per image of the lenses worn:
    ``image_power_D``, None for lenses that form one image, ``refraction_D`` and
    ``peripheral``); None for a scene that neither grows nor computes its optics.

    Raises :class:`InputError` for an optics key that cannot be traced (naming the key,
    the surface, the field angle and the wavelength).

    >>> o = eyeshell.optics(None, **{"optics.focus": "sagittal", "optics.max_field": 20})
    >>> o["z"].shape == (42,) and float(o["field_deg"][20]) == 20.0
    True
    >>> o["refraction"] is None  # the shell alone: no eye to refract through
    True
    >>> r = eyeshell.optics(SCENES + "/const.toml", solver__nodes=101)["refraction"]
    >>> round(r[0]["refraction_D"], 2), r[0]["through_lenses"]
    (10.46, [])
    """
    s = _as_scene(scene, overrides)
    return dict(_eyeshell.optics(s._s))


def _frame(columns: dict[str, Any], frames: bool | None) -> Any:
    """A dict of arrays, or a pandas DataFrame when asked (None: when pandas imports)."""
    if frames is False:
        return columns
    try:
        import pandas
    except ImportError:
        if frames:
            raise
        return columns
    return pandas.DataFrame(columns)


class Growth:
    """A growth run from t = 0 to ``growth.t_end``.

    - ``series``: series.csv's columns (t, axial_length, equatorial_radius,
      retina_minus_blue, retina_minus_red, class, refraction_D, and ``age`` in a scene
      with ``time.unit``: the age of each t in that unit) at each snapshot;
    - ``peripheral``: peripheral.csv's columns (t, field_deg, refraction_D, relative_D;
      with lenses worn, through, image, image_power_D and share: each snapshot's naked rows,
      then its rows through each image of the lenses; and ``age`` with ``time.unit``), the
      peripheral refraction at each snapshot and field angle;
    - ``history``: the same at every recorded time when ``output.history_points`` > 0
      (history.csv), else empty;
    - ``snapshots``: {t: every field at every node (the snapshot files' columns, ending in
      ``age``, the snapshot's age on every node, with ``time.unit``)};
    - ``sensitivities``: with ``grow(..., sensitivities=[...])``, sensitivities.csv's
      columns (t, parameter, d_axial_length, d_equatorial_radius, d_retina_minus_blue,
      scaled_axial_length, and ``age`` with ``time.unit``), one row per recorded time and
      parameter; else empty;
    - ``summary``: summary.json's content;
    - ``error_estimate``: with ``grow(tol=...)`` (``solver.tol``), summary.json's
      ``error_estimate``: each length's estimated error (mm) as {total, space, time}, the
      largest over the output times, and ``per_time`` the same at each; else None;
    - ``rule``: with ``grow(..., stimulus=f)``, the rule's name (``python:`` and f's
      qualified name), its calls (evaluations over all points, differences included) and
      the seconds spent in them, as {name, calls, seconds}; else None.

    ``series``, ``history``, ``peripheral`` and ``sensitivities`` are pandas DataFrames when pandas is
    installed (or ``frames=True``), else dicts of arrays (``frames=False``); the same in
    a sweep's results as from :func:`grow`.
    """

    def __init__(self, raw: dict[str, Any], scene_toml: str, frames: bool | None) -> None:
        self._scene_toml = scene_toml
        sens = dict(raw.get("sensitivities") or _NO_SENSITIVITIES)
        sens["parameter"] = np.array(sens["parameter"], dtype=str)
        self._columns = {
            "series": _series_columns(raw["series"]),
            "history": _series_columns(raw["history"]),
            "sensitivities": sens,
            "peripheral": {k: np.asarray(v) for k, v in raw["peripheral"].items()},
        }
        self._shape(frames)
        self.snapshots: dict[float, dict[str, np.ndarray]] = dict(raw["snapshots"])
        self.summary: dict[str, Any] = json.loads(raw["summary_text"])
        self.rule: dict[str, Any] | None = (
            {"name": raw["rule_name"], "calls": raw["rule_calls"], "seconds": raw["rule_seconds"]}
            if "rule_name" in raw
            else None
        )

    @property
    def error_estimate(self) -> dict[str, Any] | None:
        """The run's estimated error under ``solver.tol`` (summary.json's
        ``error_estimate``), else None."""
        estimate: dict[str, Any] | None = self.summary.get("error_estimate")
        return estimate

    def _shape(self, frames: bool | None) -> "Growth":
        """Set series, history, sensitivities and peripheral as DataFrames or dicts (``frames``)."""
        self.series = _frame(self._columns["series"], frames)
        self.history = _frame(self._columns["history"], frames)
        self.sensitivities = _frame(self._columns["sensitivities"], frames)
        self.peripheral = _frame(self._columns["peripheral"], frames)
        return self

    def __getstate__(self) -> dict[str, Any]:
        # The columns travel, not the frames: a sweep's worker shapes nothing, and the
        # caller's process shapes them as grow() would there.
        return {k: v for k, v in self.__dict__.items() if k not in ("series", "history", "sensitivities", "peripheral")}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._shape(None)

    def to_mat(self, directory: PathLike, /, compress: bool = False) -> list[str]:
        """Write the run to ``directory`` as ``eyeshell export --mat`` writes a growth run:
        one .mat file per output time in the published scripts' layout
        (``snapshot_00002_t0.200000.mat``, each with the row vectors h, s, z, r, sigma,
        rho, zeta, alpha_s, alpha_phi, alpha_n, eta, z_retina, r_retina, Sigma and the
        scalar ``time``), then ``series.mat`` and (with a history) ``history.mat``: the
        series' and history's columns as 1×R rows, ``class`` one char row of the classes
        separated by commas; ``compress``: each variable zlib-compressed (MATLAB's
        default). The directory is written whole or not at all, and replaces only an
        earlier eyeshell export. Returns the files written, the snapshots in time order
        first.

        >>> import tempfile, scipy.io
        >>> g = eyeshell.grow(SCENES + "/const.toml", frames=False, solver__nodes=101)
        >>> files = g.to_mat(tempfile.mkdtemp() + "/mat")
        >>> [f.rsplit("/", 1)[1] for f in files][:2]
        ['snapshot_00000_t0.000000.mat', 'snapshot_00001_t0.100000.mat']
        >>> [f.rsplit("/", 1)[1] for f in files][-2:]
        ['series.mat', 'history.mat']
        >>> m = scipy.io.loadmat(files[-3])
        >>> float(m["time"][0, 0]), m["r"].shape == (1, len(g.final["r"]))
        (1.0, True)
        """
        if not isinstance(compress, (bool, np.bool_)):
            raise TypeError(f"compress must be True or False, not {type(compress).__name__}")
        snapshots = [
            (float(t), {k: np.asarray(v, dtype=float).tolist() for k, v in fields.items()})
            for t, fields in sorted(self.snapshots.items())
        ]
        # A scene in ages names its files by age, as the snapshot files (and so `eyeshell
        # export --mat`) do.
        ages = None
        if "age" in self.series:
            age_of = dict(zip(np.asarray(self.series["t"], dtype=float).tolist(),
                              np.asarray(self.series["age"], dtype=float).tolist()))
            ages = [age_of.get(t) for t, _ in snapshots]
            if any(a is None for a in ages):
                ages = None
        # The series and history as the command line's export holds them (series.mat,
        # history.mat): each cell as text that reads back to the same value.
        def cells(v: Any) -> str:
            return v if isinstance(v, str) else repr(float(v))
        tables = []
        for stem in ("series", "history"):
            columns = self._columns[stem]
            if len(columns.get("t", [])) > 0:
                rows = list(zip(*(list(v) for v in columns.values())))
                tables.append((stem, list(columns), [[cells(v) for v in r] for r in rows]))
        files = _eyeshell.export_growth(
            _path(directory, "directory"), snapshots, bool(compress), ages, tables
        )
        return [os.fsdecode(f) for f in files]

    @property
    def scene(self) -> Scene:
        """The scene grown."""
        return Scene.from_toml(self._scene_toml)

    @property
    def times(self) -> list[float]:
        """The snapshot times, in order."""
        return list(self.snapshots)

    @property
    def final(self) -> dict[str, np.ndarray]:
        """The last snapshot (t_end)."""
        return self.snapshots[self.times[-1]]

    def __repr__(self) -> str:
        last = self.summary.get("final") or {}
        return (
            f"<eyeshell.Growth to t = {last.get('t')}: axial length "
            f"{last.get('axial_length')} mm, {last.get('class')}, {len(self.snapshots)} snapshots>"
        )


_NO_SENSITIVITIES: dict[str, Any] = {
    "t": np.zeros(0),
    "parameter": [],
    "d_axial_length": np.zeros(0),
    "d_equatorial_radius": np.zeros(0),
    "d_retina_minus_blue": np.zeros(0),
    "scaled_axial_length": np.zeros(0),
}


def _series_columns(raw: dict[str, Any]) -> dict[str, Any]:
    columns = dict(raw)
    columns["class"] = np.array(raw["class"], dtype=str)
    return columns


class _Bar:
    """progress=True: a one-line bar on stderr, redrawn at most ten times a second."""

    def __init__(self) -> None:
        self.last = 0.0

    def __call__(self, t: float, t_end: float) -> None:
        now = time.monotonic()
        if now - self.last < 0.1 and t < t_end:
            return
        self.last = now
        done = t / t_end if t_end > 0 else 1.0
        n = int(round(30 * done))
        end = "\n" if t >= t_end else ""
        print(f"\r[{'#' * n}{'.' * (30 - n)}] t = {t:.4f} / {t_end:g}", end=end, file=sys.stderr, flush=True)


def _progress_callable(progress: Progress) -> Callable[[float, float], Any] | None:
    if progress is True:
        return _Bar()
    if progress is False or progress is None:
        return None
    if callable(progress):
        return progress
    raise TypeError("progress must be True, False, None or a callable (t, t_end)")


def grow(
    scene: SceneLike = None,
    /,
    progress: Progress = None,
    frames: bool | None = None,
    sensitivities: Sequence[str] = (),
    sensitivity_error_control: bool = False,
    tol: float | None = None,
    stimulus: Callable[[Any], Any] | None = None,
    **overrides: Any,
) -> Growth:
    """Grow the eye of ``scene`` (as :func:`solve` takes it; the scene must grow: set a
    ``growth.*`` key) from t = 0 to ``growth.t_end``, with the GIL released.

    ``progress=True`` draws a bar on stderr; a callable is called as ``progress(t, t_end)``
    after every step (an exception it raises stops the run and is raised). Ctrl-C stops the
    run after the current step and raises KeyboardInterrupt.

    ``sensitivities=["growth.eta0", ...]``: the forward sensitivities of the run to those
    scene keys (IDAS, as ``eyeshell grow --sensitivities``), in :attr:`Growth.sensitivities`;
    ``sensitivity_error_control=True`` includes them in the local error test: 4–75× slower,
    and the sensitivities then converge with ``solver.rtol`` (without it their error is
    set by the state's steps: 4e-3 relative at rtol 1e-6, 2e-4 at 1e-10 on the const scene
    at 101 nodes, from the growth switching off point by point). Without sensitivities it
    would do nothing, so it is refused (:class:`InputError`), as the command line refuses
    ``--sensitivity-error-control`` without ``--sensitivities``.

    ``tol=1e-4`` sets ``solver.tol`` (mm): eyeshell chooses the material mesh and the
    integrator's rtol and atol so that the outputs' lengths (axial length, equatorial
    radius, the retina's distances to the surfaces, the snapshots' r and z) are within tol
    at every output time, and reports its estimate in :attr:`Growth.error_estimate` and
    what it chose in ``summary["accuracy"]``; ``solver.nodes``, ``solver.rtol`` and
    ``solver.atol`` are then ignored, as with ``solver.tol`` in a scene file.

    ``stimulus=f``: ``f`` is the growth rule instead of ``stimulus.rule``'s (docs/guide/python.md,
    "Rules in Python"). ``f(s)`` receives what every retinal point sees, NumPy arrays
    ``s.sigma``, ``s.z``, ``s.r``, ``s.angle``, ``s.depth_mm`` (positive when the retina
    lies in front of the stimulus surface, the paper's quantity), ``s.depth_red_mm``,
    ``s.defocus_D`` and the time ``s.t`` (a float), and returns g_v (mm), one value per
    point or a scalar; the engine takes its positive part. The Jacobian's partials are
    central differences of ``f`` in the quantities it read, unless it returns them,
    ``(g, {"depth_mm": dg, ...})``. A rule that raises, returns a value that is not a
    finite number per point, or outlasts ``solver.max_seconds`` stops the run with an
    :class:`InputError` (:class:`SolverError` for the time) naming it; Ctrl-C stops it.

    >>> g = eyeshell.grow(SCENES + "/const.toml", frames=False, solver__nodes=51,
    ...                   stimulus=lambda s: np.maximum(s.depth_mm, 0))
    >>> g.rule["name"], g.rule["calls"] > 0
    ('python:<lambda>', True)

    >>> g = eyeshell.grow(SCENES + "/const.toml", frames=False, tol=1e-3)
    >>> bool(g.error_estimate["axial_length"]["total"] <= 1e-3), g.summary["accuracy"]["tol"]
    (True, 0.001)

    >>> g = eyeshell.grow(SCENES + "/const.toml", frames=False, solver__nodes=101,
    ...                   sensitivities=["growth.eta0", "growth.Gamma"])
    >>> g.sensitivities["parameter"][-2:].tolist(), float(g.sensitivities["t"][-1])
    (['growth.eta0', 'growth.Gamma'], 1.0)

    >>> g = eyeshell.grow(SCENES + "/const.toml", frames=False, solver__nodes=101)
    >>> float(g.series["t"][-1]), g.summary["status"], len(g.snapshots)
    (1.0, 'ok', 5)
    >>> bool(g.series["axial_length"][-1] > g.series["axial_length"][0])
    True
    """
    if tol is not None:
        if "solver__tol" in overrides:
            raise TypeError("grow() got both tol and solver__tol: give one")
        overrides = {**overrides, "solver__tol": tol}
    s = _as_scene(scene, overrides)
    if isinstance(sensitivities, str):
        sensitivities = [k for k in sensitivities.split(",") if k.strip()]
    if not isinstance(sensitivity_error_control, (bool, np.bool_)):
        raise TypeError(
            f"sensitivity_error_control must be True or False, not {type(sensitivity_error_control).__name__}"
        )
    raw = _eyeshell.grow(
        s._s,
        _progress_callable(progress),
        list(sensitivities),
        bool(sensitivity_error_control),
        stimulus,
    )
    return Growth(raw, s.to_toml(), frames)


DataLike = Union[PathLike, Mapping[str, Any]]


class FitResult:
    """What :func:`fit` found (``eyeshell fit``'s fit.json, shaped):

    - ``estimates``, ``standard_errors``, ``initial``: {key: value} in the order fitted;
    - ``correlation``, ``covariance``: k×k arrays in that order;
    - ``residuals``: each measurement against the fitted model (t, axial_length, sigma,
      model, residual, weighted, and ``age`` in a scene with ``time.unit``; with refractions
      also ``refraction_D``, NaN where the row is the other quantity's; in a joint fit first
      ``arm``), a DataFrame with pandas, else a dict of arrays;
    - ``scene``: the scene with the estimates (:class:`Scene`; of a joint fit the first
      arm's), ``scenes``: {arm: scene with its estimates} (empty for one scene);
    - ``keys``: the parameters in order, a per-arm key as ``key[arm]``; the dicts below are
      keyed so;
    - ``report``: fit.json's content (χ², iterations, cost history, convergence, data hash);
    - ``notes``: what the numbers alone do not say, one str each (a pair of parameters
      correlated at |ρ| ≥ 0.99: the data determine their combination, not each);
    - ``text``: the table ``eyeshell fit`` prints (estimates and standard errors to 6
      decimals, correlations and χ² to 4, the notes); ``str(result)`` is the same;
    - ``converged``, ``iterations``, ``chi2``.
    """

    def __init__(
        self,
        report_text: str,
        text: str,
        notes: Sequence[str],
        scene: Scene,
        frames: bool | None,
        scenes: Mapping[str, Scene] | None = None,
    ) -> None:
        self.report: dict[str, Any] = json.loads(report_text)
        self.text = text
        self.notes: list[str] = list(notes)
        self.scene = scene
        self.scenes: dict[str, Scene] = dict(scenes or {})
        params = self.report["parameters"]

        def label(p: dict[str, Any]) -> str:
            return f"{p['key']}[{p['arm']}]" if "arm" in p else p["key"]

        self.keys: list[str] = [label(p) for p in params]
        self.estimates: dict[str, float] = {label(p): p["estimate"] for p in params}
        self.standard_errors: dict[str, float] = {label(p): p["standard_error"] for p in params}
        self.initial: dict[str, float] = {label(p): p["initial"] for p in params}
        self.correlation = np.array(self.report["correlation"], dtype=float)
        self.covariance = np.array(self.report["covariance"], dtype=float)
        rows = self.report["residuals"]
        names = ["t", "axial_length", "sigma", "model", "residual", "weighted"]
        if any("refraction_D" in r for r in rows):
            names.insert(2, "refraction_D")
        # fit.json gives each residual its age when the scene counts in ages.
        if rows and "age" in rows[0]:
            names.append("age")
        columns: dict[str, Any] = {}
        if any("arm" in r for r in rows):
            columns["arm"] = np.array([r.get("arm", "") for r in rows], dtype=object)
        for k in names:
            columns[k] = np.array(
                [math.nan if r.get(k) is None else r[k] for r in rows], dtype=float
            )
        self.residuals = _frame(columns, frames)

    @property
    def converged(self) -> bool:
        """Did the iteration converge (rather than stop at max_iterations, or at steps that
        could not be evaluated: ``"refused"``)?"""
        return self.report["convergence"] not in ("iterations", "refused")

    @property
    def iterations(self) -> int:
        return self.report["iterations"]

    @property
    def chi2(self) -> float:
        """Σ ((model − data)/σ)² at the estimates (σ = 1 without a sigma column)."""
        return self.report["chi2"]

    def curve(self, points: int = 201) -> dict[str, np.ndarray]:
        """The fitted model's axial length at ``points`` evenly spaced times over
        [0, t_end], both ends included (t = t_end·k/(points − 1)): {"t": ...,
        "axial_length": ...} (and "age" in a scene with ``time.unit``), from one growth run
        of :attr:`scene` (the curve ``eyeshell fit`` plots). ``points``: a whole number from 2 (the two ends) to 1,000,001;
        Ctrl-C stops the run as it stops :func:`grow`.

        >>> r = eyeshell.fit(SCENES + "/const.toml", SCENES + "/../examples/fit/const_synthetic.csv",
        ...                  fit=["growth.Gamma"], solver__nodes=101)
        >>> r.curve(5)["t"].tolist()
        [0.0, 0.25, 0.5, 0.75, 1.0]
        """
        # Both ends, and the run's history holds t = 0 and output.history_points more.
        n = _whole(points, "curve: points", 2, _eyeshell.MAX_HISTORY_POINTS + 1)
        # No snapshot between the ends (t_end is always one), so no time but the history's.
        # The end as the scene writes times: an age with time.unit.
        ages = self.scene["time.unit"] != "none"
        end = self.scene["time.end"] if ages else self.scene["growth.t_end"]
        scene = self.scene.copy(output__times=[end], output__history_points=n - 1)
        h = grow(scene, frames=False).history
        return {k: np.asarray(h[k]) for k in ("t", "axial_length", "age") if k in h}

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        est = ", ".join(
            f"{k} = {self.estimates[k]:.6g} ± {self.standard_errors[k]:.2g}" for k in self.keys
        )
        return f"<eyeshell.FitResult {est}; χ² {self.chi2:.4g}, {self.iterations} iterations>"


def fit(
    scene: SceneLike | None = None,
    data: DataLike | None = None,
    /,
    fit: Sequence[str] = (),
    max_iterations: int = 50,
    frames: bool | None = None,
    arms: Mapping[str, tuple[SceneLike, DataLike]] | None = None,
    per_arm: Sequence[str] = (),
    **overrides: Any,
) -> FitResult:
    """``eyeshell fit``: fit the scene keys ``fit`` (start values: the scene's) to measured
    axial lengths and/or refractions by Levenberg–Marquardt, each step kept in the key's
    validity range. ``fit`` takes any real-valued key of the model: the keys with a forward
    sensitivity (growth.eta0, growth.Gamma, ...) take IDAS's for the axial length, every
    other column (``optics.surfaces[0].radius``, and the refraction's of every key) is a
    central difference of the growth run (relative step 1e-3).

    ``data`` is a CSV file's path (a str, bytes or os.PathLike; header ``t`` or ``age``,
    then ``axial_length`` and/or ``refraction_D``, each optionally with its σ,
    ``sigma_axial_length`` (or ``sigma``) and ``sigma_refraction_D``, as the command line
    reads it) or a mapping with those columns (a dict of sequences or a pandas DataFrame;
    ``age``: ages in the scene's ``time.unit``, each within [``time.start``,
    ``time.end``]; with both quantities NaN marks a visit that measured one only).
    Refractions need a scene whose stimulus is computed from its optics
    (``stimulus.source = "optics"``).

    Several arms: ``arms={"single-vision": (scene, data), "dual-focus": (scene, data)}``
    (no positional scene and data then) fits every arm at once, one Levenberg–Marquardt over
    the stacked residuals: the ``fit`` keys take one value in every arm, the ``per_arm``
    keys one value in each (reported as ``key[arm]``: ``growth.eta0[dual-focus]``).
    ``overrides`` are set on a copy of each scene. The GIL is released while it fits; Ctrl-C
    stops it within a step of its current growth run and raises KeyboardInterrupt, as in
    :func:`grow`.

    Standard errors come from the Gauss–Newton covariance s²(JᵀWJ)⁻¹: s² = 1 with σ (taken
    as known), the residual variance χ²/(n − k) without. Raises :class:`InputError` for bad
    data or keys, and when the data cannot identify a parameter (naming it and what data
    would).

    >>> r = eyeshell.fit(SCENES + "/const.toml", SCENES + "/../examples/fit/const_synthetic.csv",
    ...                  fit=["growth.Gamma"], solver__nodes=101, growth__Gamma=9)
    >>> r.converged, abs(r.estimates["growth.Gamma"] - 8) < 2 * r.standard_errors["growth.Gamma"]
    (True, True)
    >>> r.scene["growth.Gamma"] == r.estimates["growth.Gamma"]
    True
    >>> ex = SCENES + "/../examples/fit/joint_"
    >>> j = eyeshell.fit(fit=["growth.Gamma"], per_arm=["growth.eta0"], arms={
    ...     "none": (SCENES + "/eyewear/none.toml", ex + "none.csv"),
    ...     "single-vision": (SCENES + "/eyewear/single-vision.toml", ex + "single-vision.csv")},
    ...     solver__nodes=61, output__history_points=0)
    >>> j.keys
    ['growth.Gamma', 'growth.eta0[none]', 'growth.eta0[single-vision]']
    >>> j.scenes["single-vision"]["growth.eta0"] == j.estimates["growth.eta0[single-vision]"]
    True
    """
    if isinstance(fit, str):
        fit = [k for k in fit.split(",") if k.strip()]
    if isinstance(per_arm, str):
        per_arm = [k for k in per_arm.split(",") if k.strip()]
    max_iterations = _whole(max_iterations, "max_iterations", 1, 1000)
    if arms is not None:
        if scene is not None or data is not None:
            raise _input_error(
                "arms: give the arms alone, or a scene and its data, not both", "arms", None, "argument"
            )
        if not isinstance(arms, Mapping):
            raise TypeError(
                f"arms must be a mapping of name -> (scene, data), not {type(arms).__name__}"
            )
        native = []
        for name, pair in arms.items():
            if not isinstance(name, str) or not isinstance(pair, (tuple, list)) or len(pair) != 2:
                raise TypeError(f"arms[{name!r}] must be a (scene, data) pair")
            native.append(_native_arm(name, _as_scene(pair[0], overrides), pair[1]))
    else:
        if scene is None or data is None:
            raise _input_error(
                "fit: give a scene and its data, or arms={name: (scene, data), ...}", "data", None, "argument"
            )
        native = [_native_arm(None, _as_scene(scene, overrides), data)]
    report, text, notes, scenes = _eyeshell.fit(
        native, list(fit), list(per_arm), max_iterations=max_iterations
    )
    names = [a[0] for a in native]
    wrapped = [Scene._wrap(s) for s in scenes]
    return FitResult(report, text, notes, wrapped[0], frames,
                     {n: s for n, s in zip(names, wrapped) if n is not None})


def _native_arm(name: str | None, s: Scene, data: Any) -> tuple[Any, ...]:
    """One arm as the native fit takes it: (name, scene, path, first column, its values,
    the other columns)."""
    if isinstance(data, _PATH_TYPES):
        return (name, s._s, _path(data, "data"), "t", [], [])
    if isinstance(data, Mapping) or hasattr(data, "columns"):
        _check_data_columns(data)

        def col(column: str) -> list[float] | None:
            if column not in data:
                return None
            return [float(x) for x in np.asarray(data[column], dtype=float).ravel()]

        t, age = col("t"), col("age")
        if (t is None) == (age is None) or all(
            col(c) is None for c in ("axial_length", "refraction_D")
        ):
            raise _input_error(
                "data: the columns t (or age, not both) and axial_length or refraction_D are required",
                "data", None, "argument",
            )
        first, times = ("t", t) if t is not None else ("age", age)
        columns = [(c, v) for c in _DATA_COLUMNS[2:] if (v := col(c)) is not None]
        return (name, s._s, None, first, times, columns)
    raise TypeError(
        "data must be a CSV file's path (a str, bytes or os.PathLike) or a mapping of "
        f"columns t (or age), axial_length[, sigma], not {type(data).__name__}"
    )


_DATA_COLUMNS = (
    "t", "age", "axial_length", "sigma", "sigma_axial_length", "refraction_D", "sigma_refraction_D",
)


def _check_data_columns(data: Any) -> None:
    """Refuse a column the fit does not read, as the command line refuses its header: a
    sigma spelt ``sd`` or ``Sigma`` dropped in silence would make the fit unweighted."""
    names = list(data.columns) if hasattr(data, "columns") else list(data.keys())
    unknown = [n for n in names if n not in _DATA_COLUMNS]
    if not unknown:
        return
    first = unknown[0]
    shown = repr(first) if isinstance(first, str) else f"{type(first).__name__} {first!r}"
    shown = shown if len(shown) <= 60 else shown[:59] + "…"
    hint = ""
    if isinstance(first, str):
        close = [c for c in _DATA_COLUMNS if c == first.strip().lower()]
        if close:
            hint = f" (did you mean {close[0]!r}?)"
        elif first.strip().lower() in ("sd", "se", "std", "error", "sigma_mm"):
            hint = " (the standard deviation is the column 'sigma')"
    more = f" and {len(unknown) - 1} more" if len(unknown) > 1 else ""
    raise _input_error(
        f"data: column {shown}{hint}{more} is not one the fit reads: give t (or age), "
        "axial_length and optionally sigma, and/or refraction_D and sigma_refraction_D, "
        "and nothing else",
        str(first), None, "argument",
    )


@dataclass
class RunResult:
    """One run of a sweep: its name and swept values, how it ended, and its result (a
    :class:`Solution` for an elastic scene, a :class:`Growth` for a growing one, shaped as
    :func:`solve` and :func:`grow` shape theirs; None when it failed, ``error`` then saying
    why). ``values``: each swept key's value in this run as its scene holds it (a float
    for ``fibres.D = 0``, an int for ``solver.nodes``), as :meth:`Scene.get` gives it."""

    name: str
    values: dict[str, Any]
    status: str
    result: Solution | Growth | None = None
    error: str | None = None
    seconds: float = 0.0
    index: int = field(default=-1, repr=False)

    @property
    def ok(self) -> bool:
        """Did the run finish?"""
        return self.status == "ok"

    @property
    def summary(self) -> dict[str, Any] | None:
        """The run's summary.json content (None when it failed)."""
        return None if self.result is None else self.result.summary


def _run_here(index: int, name: str, values: dict[str, Any], scene_toml: str) -> RunResult:
    """Run one scene of a sweep in this process (a worker's): a failed run is recorded,
    not raised, as ``eyeshell sweep`` records it."""
    start = time.perf_counter()
    try:
        s = Scene.from_toml(scene_toml)
        if s.grows:
            result: Solution | Growth = Growth(_eyeshell.grow(s._s), scene_toml, False)
        else:
            result = Solution(_eyeshell.solve(s._s))
    except Exception as e:
        message = str(e) if isinstance(e, EyeshellError) else _internal(e)
        return RunResult(name, values, "failed", None, message, time.perf_counter() - start, index)
    return RunResult(name, values, "ok", result, None, time.perf_counter() - start, index)


def _internal(e: BaseException) -> str:
    """An unexpected exception as a run's error, on one line."""
    return " ".join(f"internal error (a bug; please report it): {type(e).__name__}: {e}".split())


def _run_in(
    workers: _worker.Workers, index: int, name: str, values: dict[str, Any], scene_toml: str
) -> RunResult:
    """Run one scene of a sweep in a worker process of `workers`: a run whose process
    ends without a result (an abort) is recorded as failed, saying how it ended."""
    start = time.perf_counter()

    def failed(message: str) -> RunResult:
        return RunResult(name, values, "failed", None, message, time.perf_counter() - start, index)

    try:
        return workers.run((index, name, values, scene_toml))
    except _worker.Lost as e:
        return failed(str(e))
    except OSError as e:
        return failed(f"could not start a process for the run: {e}")
    except _worker.Cancelled:
        raise
    except Exception as e:
        return failed(_internal(e))


def _run_one(index: int, name: str, values: dict[str, Any], scene_toml: str) -> RunResult:
    """What an executor runs for one run of a sweep: the run, in a worker process beside
    the executor's (its pool lives as long as the executor's process), so that a run that
    aborts never takes the executor's process down."""
    return _run_in(_worker.shared(), index, name, values, scene_toml)


def _toml_value(v: Any) -> str:
    """A sweep value as TOML, converted as :meth:`Scene.set` converts it."""
    return _eyeshell.toml_literal(v)


def _values(key: str, v: Any) -> list[Any]:
    """The values of a grid's key: a list, a tuple, an array, any iterable but a string."""
    if isinstance(v, (str, bytes, Mapping)) or not hasattr(v, "__iter__") or getattr(v, "ndim", 1) == 0:
        raise _input_error(f"grid: {key}: give a list of values, not {type(v).__name__} {v!r}",
                           key, v, "argument")
    return list(v)


def _sweep_text(
    scene: SceneLike, grid: Mapping[str, Sequence[Any]] | None, runs: Sequence[Mapping[str, Any]] | None
) -> tuple[str, str]:
    """The sweep's TOML text and origin: a sweep file as it is, or a scene with a grid
    and/or a list of runs added as its [sweep] table (a sweep file's own [sweep] then
    left out: the given one replaces it)."""
    if isinstance(scene, _PATH_TYPES):
        path = _path(scene, "a sweep file")
        if not grid and not runs:
            try:
                with open(path, encoding="utf-8") as f:
                    return f.read(), path
            except OSError as e:
                raise _input_error(f"{path}: cannot read the sweep: {e.strerror}",
                                   str(path), None, str(path)) from None
        base = Scene.from_file(path, sweep=False)
    else:
        base = _as_scene(scene, {})
    lines = [base.to_toml()]
    if grid:
        lines.append("[sweep.grid]")
        lines += [f"{json.dumps(k)} = {_toml_value(_values(k, v))}" for k, v in _flatten(grid)]
    for run in runs or ():
        lines.append("[[sweep.runs]]")
        lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in _flatten(run)]
    return "\n".join(lines) + "\n", f"<sweep of {base.name}>"


def iter_sweep(
    scene: SceneLike,
    /,
    *,
    jobs: int | None = None,
    executor: Any = None,
    grid: Mapping[str, Sequence[Any]] | None = None,
    runs: Sequence[Mapping[str, Any]] | None = None,
    frames: bool | None = None,
    **overrides: Any,
) -> Iterator[RunResult]:
    """The runs of a sweep, each yielded as it finishes (see :func:`sweep`);
    ``SweepResults(iter_sweep(...))`` collects them for :meth:`SweepResults.to_frame`."""
    text, origin = _sweep_text(scene, grid, runs)
    sets = [f"{_key(k)}={_toml_value(v)}" for k, v in overrides.items()]
    plan = _eyeshell.expand_sweep(text, origin, sets)
    if jobs is not None:
        jobs = _whole(jobs, "jobs", 1, _MAX_JOBS)
    own = executor is None
    workers = _worker.Workers() if own else None
    pool = ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) if own else executor
    # Finished runs arrive through a queue, so that this thread never waits on a future's
    # lock: a KeyboardInterrupt landing just after such a lock is taken (inside `with`'s
    # __enter__) leaves it held, and the worker finishing that future then blocks on it
    # forever while shutdown() waits for the worker.
    finished: queue.SimpleQueue[Any] = queue.SimpleQueue()
    pending = []
    try:
        for i, (name, values, native) in enumerate(plan):
            args = (i, name, dict(values), native.to_toml())
            if own:
                pending.append(pool.submit(_run_into, finished, workers, args))
            else:
                f = pool.submit(_run_one, *args)
                f.add_done_callback(lambda f, args=args: finished.put(_Remote(f, args)))
                pending.append(f)
        for _ in range(len(pending)):
            run = _next_finished(finished).result()
            if frames is not None and isinstance(run.result, Growth):
                run.result._shape(frames)
            yield run
    except BaseException:
        # Ctrl-C (or a bug): no new run starts, and our own runs stop at once (their
        # processes are killed); an executor's running tasks are its own to stop.
        if workers is not None:
            workers.close(kill=True)
        for f in pending:
            f.cancel()
        raise
    finally:
        if own:
            pool.shutdown(wait=True, cancel_futures=True)
            workers.close()


# At most this many runs at a time, as `eyeshell sweep --jobs`: each is a process.
_MAX_JOBS = 1024


def _input_error(message: str, key: str | None = None, value: Any = None,
                 origin: str | None = None) -> InputError:
    """An :class:`InputError` raised by this layer, with its ``key``, ``value`` (shortened
    as the library shortens one) and ``origin`` as the library's own errors carry them."""
    e = InputError(message)
    e.key = key
    if value is not None:
        text = value if isinstance(value, str) else repr(value)
        e.value = text if len(text) <= 80 else text[:80] + "…"
    e.origin = origin
    return e


def _whole(value: Any, name: str, least: int, most: int) -> int:
    """`value` as an int in [least, most]: any integral number (int, NumPy integer, ...),
    not a bool or a float."""
    try:
        n = operator.index(value)
    except TypeError:
        n = None
    if n is None or isinstance(value, (bool, np.bool_)) or not least <= n <= most:
        raise _input_error(f"{name} = {value!r}: must be a whole number from {least} to {most:,}",
                           name, value, "argument")
    return n


@dataclass(frozen=True)
class _Finished:
    """A run of our own pool: its result, or the exception it raised (read like a future)."""

    run: RunResult | None
    error: BaseException | None

    def result(self) -> RunResult:
        if self.error is not None:
            raise self.error
        assert self.run is not None
        return self.run


@dataclass(frozen=True)
class _Remote:
    """An executor's future and the run it was for: the run failed if the executor lost
    it (its process died, it was cancelled), so that the other runs' results are kept."""

    future: Any
    args: tuple[Any, ...]

    def result(self) -> RunResult:
        try:
            return self.future.result()
        except Exception as e:
            index, name, values, _ = self.args
            message = f"the executor did not run it: {type(e).__name__}: {e}".rstrip(": ")
            return RunResult(name, values, "failed", None, message, 0.0, index)


def _run_into(finished: queue.SimpleQueue[Any], workers: _worker.Workers, args: tuple[Any, ...]) -> None:
    """Run one scene on our own pool and put what came of it on `finished`."""
    try:
        finished.put(_Finished(_run_in(workers, *args), None))
    except BaseException as e:  # handed to the consuming thread, which raises it
        finished.put(_Finished(None, e))


def _next_finished(finished: queue.SimpleQueue[Any]) -> Any:
    """The next finished run (a :class:`_Finished`, or an executor's future); waits in
    short slices so that Ctrl-C is seen promptly."""
    while True:
        try:
            return finished.get(timeout=0.05)
        except queue.Empty:
            continue


def sweep(
    scene: SceneLike,
    /,
    *,
    jobs: int | None = None,
    executor: Any = None,
    grid: Mapping[str, Sequence[Any]] | None = None,
    runs: Sequence[Mapping[str, Any]] | None = None,
    frames: bool | None = None,
    **overrides: Any,
) -> "SweepResults":
    """Run every run of a sweep and return their :class:`RunResult` in the sweep's order,
    as a :class:`SweepResults` (a list; :meth:`SweepResults.to_frame` makes one table of
    them).

    ``scene`` is a sweep file (a scene with a ``[sweep]`` table, as ``eyeshell sweep``
    reads it), or a scene (a :class:`Scene`, a path or a mapping) with ``grid`` (a mapping
    of keys to lists of values: every combination, in the mapping's order, the last key
    varying fastest) and/or ``runs`` (a list of mappings of keys); a sweep file given with
    ``grid`` or ``runs`` has its own ``[sweep]`` replaced by them
    (``Scene.from_file(path, sweep=False)`` reads its scene alone). ``overrides`` are set
    on every run (a key the sweep sweeps is refused: give its values in ``grid`` or
    ``runs``). The runs are named as ``eyeshell sweep`` names them. Each run's
    :class:`Growth` has its series as :func:`grow` gives them: DataFrames when pandas
    imports, or as ``frames`` says.

    Each run goes to a worker process (``sys.executable`` importing this package, reused
    run after run), as ``eyeshell sweep`` runs its runs: a run that aborts its process (an
    allocation that fails, a stack overflow: the native code aborts, with no exception to
    catch) fails alone, and the interpreter and the other runs' results are kept. Runs go
    ``jobs`` at a time (1 to 1,024; default: one per core), or to ``executor``: anything with
    ``submit(fn, *args)`` returning futures with ``add_done_callback()`` and ``result()``
    — a ``concurrent.futures.ProcessPoolExecutor``, an ``mpi4py.futures.MPIPoolExecutor``,
    a Dask ``distributed.Client``; each task then runs its run in a worker process beside
    the executor's own, so that an abort never breaks the executor (no
    ``BrokenProcessPool``).

    A failed run is recorded (``status == "failed"``, ``error`` saying why: the solver's
    message, or how its process ended, e.g. ``the run's process ended abnormally (killed
    by signal 6: SIGABRT; out of memory or a stack overflow?)``; a run the executor lost
    says so) and the others go on. Ctrl-C stops the sweep: no run starts, the local runs
    stop at once (their processes are ended), and KeyboardInterrupt is raised.

    >>> rs = eyeshell.sweep(eyeshell.Scene(solver__nodes=101), grid={"fibres.D": [0, 200]}, jobs=2)
    >>> [(r.name, r.values, r.status) for r in rs]
    [('D=0', {'fibres.D': 0.0}, 'ok'), ('D=200', {'fibres.D': 200.0}, 'ok')]
    >>> rs[1].result.summary["parameters"]["fibres.D"]
    200.0
    """
    results = sorted(
        iter_sweep(scene, jobs=jobs, executor=executor, grid=grid, runs=runs, frames=frames, **overrides),
        key=lambda r: r.index,
    )
    return SweepResults(results)


def _frame_columns(ages: bool = False) -> list[str]:
    """The columns of SweepResults.to_frame() after run, status and the swept keys: t, the
    age when the runs count in ages (``ages``: a scene with time.unit), and sweep.csv's
    measures of the eye (the table of outputs), at each output time."""
    return ["t", *(["age"] if ages else []), *(q["name"] for q in _eyeshell.output_quantities())]


class SweepResults(list):
    """The runs of a sweep (a list of :class:`RunResult`, in the sweep's order), as
    :func:`sweep` returns them; ``SweepResults(iter_sweep(...))`` collects an iterator's.
    """

    def to_frame(self, frames: bool | None = None) -> Any:
        """One table of the whole sweep: a row per run and output time (a growth run's
        snapshot times; t = 0 for an elastic run, measured as ``eyeshell sweep`` measures
        it), with the columns ``run``, ``status``, each swept key (whatever keys the runs
        set, in the sweep's order: a grid's, a list's, a sampled sweep's; NaN, or None
        for a non-number, where a run does not set it), ``t``, ``axial_length``,
        ``equatorial_radius``, ``retina_minus_blue``, ``retina_minus_red``, ``class``,
        ``refraction_D`` (NaN for an elastic run) and ``error`` (a failed run: one row, its measures NaN);
        ``age`` follows ``t`` when a run counts in ages (time.unit; NaN for a run that does not). A pandas DataFrame when pandas
        imports (or ``frames=True``), else a dict of lists (``frames=False``).

        >>> rs = eyeshell.sweep(SCENES + "/const.toml", grid={"growth.Gamma": [4, 8]},
        ...                     solver__nodes=101)
        >>> df = rs.to_frame()
        >>> list(df.columns)[:4], len(df) == 2 * len(rs[0].result.series)
        (['run', 'status', 'growth.Gamma', 't'], True)
        >>> sorted(set(df["growth.Gamma"]))
        [4.0, 8.0]
        """
        keys: list[str] = []
        for r in self:
            keys += [k for k in r.values if k not in keys]
        ages = any(isinstance(r.result, Growth) and "age" in r.result._columns["series"] for r in self)
        measured = _frame_columns(ages)
        columns: dict[str, list[Any]] = {c: [] for c in ["run", "status", *keys, *measured, "error"]}
        for r in self:
            measures = _measures(r, measured)
            rows = len(measures["t"])
            columns["run"] += [r.name] * rows
            columns["status"] += [r.status] * rows
            for k in keys:
                missing = math.nan if any(isinstance(x.values.get(k), (int, float)) for x in self) else None
                columns[k] += [r.values.get(k, missing)] * rows
            for c in measured:
                columns[c] += list(measures[c])
            columns["error"] += [r.error or ""] * rows
        return _frame(columns, frames)


def _measures(r: RunResult, columns: list[str]) -> dict[str, list[Any]]:
    """A run's measures of the eye (``columns``) at its output times: one row of NaN for a
    failed run."""
    if isinstance(r.result, Growth):
        series = r.result._columns["series"]
        rows = len(series["t"])
        return {
            c: [x.item() if hasattr(x, "item") else x for x in series[c]] if c in series else [math.nan] * rows
            for c in columns
        }
    if isinstance(r.result, Solution):
        # An elastic run does not grow: what needs growth (refraction_D) is NaN.
        eye = r.result.eye
        return {c: [0.0 if c == "t" else eye.get(c, math.nan)] for c in columns}
    return {c: [math.nan] if c != "class" else [""] for c in columns}


@dataclass
class Comparison:
    """What :func:`compare` found: ``passed``, one report per compared pair (``pairs``:
    dicts with reference, run, time, coordinate, points, passed, per-field ``fields``
    maxima (with ``allowed``, the absolute tolerance applied: tol + rtol·|ref| where |ref|
    is largest) and ``not_compared``: the reference's variables left out, name → why), and
    ``text``, the table ``eyeshell compare`` prints."""

    passed: bool
    pairs: list[dict[str, Any]]
    text: str

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self.text


Comparable = Union[PathLike, "Solution", "Growth"]


def compare(
    run: Comparable,
    reference: Comparable,
    /,
    tol: float = 1e-8,
    rtol: float = 1e-8,
    field: str | None = None,
) -> Comparison:
    """``eyeshell compare RUN REFERENCE``: compare a run against a reference,
    interpolating the run at the reference's points; a point fails when
    |run − ref| > tol + rtol·|ref|. The run is a :class:`Solution` or a :class:`Growth`
    (compared as their .mat export: :meth:`Solution.to_mat`, :meth:`Growth.to_mat`; named
    ``Solution`` or ``Growth`` in the report), a run directory, or its .mat or .npz export.
    The reference is any of those, or a .mat file (MATLAB's, Octave's or SciPy's
    ``savemat``), a .npz file or a directory of .mat and .npz files;
    a CSV file is not a reference (compare the run directory that holds it, or its
    export). Paths are str, bytes or os.PathLike. ``field`` names the struct of a .mat reference that holds the
    result (default: ``sol`` if present).

    Unlike the command line, a comparison beyond tolerance is not an error: it returns a
    :class:`Comparison` whose ``passed`` is False. Unreadable or mismatched inputs raise
    :class:`InputError`.
    """
    import tempfile

    with tempfile.TemporaryDirectory(prefix="eyeshell-compare-") as tmp:
        exported: dict[str, tuple[str, str]] = {}
        run_path = _comparable(run, "run", tmp, exported)
        ref_path = _comparable(reference, "reference", tmp, exported)
        pairs, text = _eyeshell.compare(run_path, ref_path, tol, rtol, field)
    # An exported side is named by its kind, and which side it is when both are one kind.
    kinds = [kind for kind, _ in exported.values()]
    for path, (kind, what) in exported.items():
        label = kind if kinds.count(kind) == 1 else f"{kind} ({what})"
        text = text.replace(path, label)
        for p in pairs:
            for k in ("reference", "run"):
                p[k] = p[k].replace(path, label)
    return Comparison(all(p["passed"] for p in pairs), pairs, text)


def _comparable(x: Any, what: str, tmp: str, exported: dict[str, tuple[str, str]]) -> str:
    """A side of :func:`compare` as a path: a Solution or a Growth exported into `tmp`
    (recorded in `exported`: path → its kind and side), a path as it is."""
    if isinstance(x, (Solution, Growth)):
        path = os.path.join(tmp, what + (".mat" if isinstance(x, Solution) else ""))
        x.to_mat(path)
        exported[path] = (type(x).__name__, what)
        return path
    if not isinstance(x, _PATH_TYPES):
        raise TypeError(
            f"{what} must be a Solution, a Growth or a path (a str, bytes or os.PathLike), not {type(x).__name__}"
        )
    return _path(x, what)


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
    "keys",
    "solve",
    "sweep",
]
