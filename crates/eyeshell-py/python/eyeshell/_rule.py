"""Growth rules written in Python (docs/guide/python.md, "Rules in Python"; docs/MODEL.md §6,
"Growth rules").

``eyeshell.grow(scene, stimulus=f)`` runs ``f`` as the growth rule: the integrators call
:func:`evaluate` (from crates/eyeshell-py/src/rule.rs, with the GIL taken back) with what every
retinal point sees, and ``f(s)`` returns the drive g_v (mm) there; the engine takes its
positive part. The Jacobians need the drive's partial derivatives in what a point sees:
``f`` may give them (it returns ``(g, {"depth_mm": dg_ddepth, ...})``, a quantity it does not
name then has none), else they are central differences of ``f``, one vectorised call per
quantity ``f`` read and per sign. Both assume the rule is local: the drive at a point depends
on that point's view alone.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from ._eyeshell import InputError

#: The quantities a rule's partials may be given in, and differenced in: what a point sees
#: (depths in mm, defocus in dioptres) and its place (z, r in mm; the angle in rad, which the
#: engine composes with the angle's own gradient in the retina's place).
PARTIALS = ("depth_mm", "depth_red_mm", "defocus_D", "z", "r", "angle")

#: The view's quantities, in the order crates/eyeshell-py/src/rule.rs passes them.
QUANTITIES = ("sigma", "z", "r", "angle", "depth_mm", "depth_red_mm", "defocus_D")

#: The relative step of the central differences, about the cube root of the machine epsilon
#: (the truncation and rounding errors of a smooth rule balance there: ~1e-11 relative).
STEP = 6e-6


class View:
    """What every retinal point sees, as a growth rule written in Python receives it: each
    attribute a NumPy array over the retinal points (the retina's inner face at the
    integrator's material points, in its order: not sorted by Σ), except ``t``, the growth
    time (a float), and ``n``, the number of points:

    - ``sigma``: Σ, the point's material coordinate (mm);
    - ``z``, ``r``: the retina point (mm);
    - ``angle``: its polar angle about the stimulus surface's centre (rad);
    - ``depth_mm``: the signed distance of the stimulus (blue) surface behind the retina along
      the polar ray, positive when the retina lies in front of it (the paper's quantity);
    - ``depth_red_mm``: the same for the red surface;
    - ``defocus_D``: the defocus of the stimulus image in dioptres, positive when the image
      lies behind the retina (hyperopic), through whatever lens is worn.

    The arrays are fresh for every call: a rule may keep or change them.
    """

    __slots__ = ("_q", "read", "t", "n")

    def __init__(self, q: dict[str, np.ndarray], t: float) -> None:
        self._q = q
        self.t = t
        self.n = len(q["sigma"])
        #: The quantities read so far (the partials are differenced in these alone).
        self.read: set[str] = set()

    def __getattr__(self, name: str) -> Any:
        q = object.__getattribute__(self, "_q")
        if name not in q:
            raise AttributeError(
                f"the view of the retina has no {name!r}: it has t, n, {', '.join(QUANTITIES)}"
            )
        object.__getattribute__(self, "read").add(name)
        return q[name]

    def __dir__(self) -> list[str]:
        return ["t", "n", *QUANTITIES]

    def __repr__(self) -> str:
        return f"<eyeshell growth-rule view of {self.n} retinal points at t = {self.t:g}>"


def _as_values(x: Any, sigma: np.ndarray, name: str, what: str) -> np.ndarray:
    """``x`` as one float64 per point of Σ = ``sigma`` (a scalar counts for every point),
    else InputError naming the rule and ``what`` it returned."""
    n = len(sigma)
    want = f"give an array of {n} numbers, one per retinal point (or a scalar)"
    a = None if isinstance(x, (str, bytes)) or x is None else np.asarray(x)
    if a is None or a.dtype.kind not in "biuf":
        kind = type(x).__name__ if a is None or a.dtype.kind == "O" else f"dtype {a.dtype}"
        raise InputError(f"the growth rule {name} returned {what} of {kind}: {want}")
    if a.shape not in ((), (n,)):
        raise InputError(f"the growth rule {name} returned {what} of shape {a.shape}: {want}")
    a = np.ascontiguousarray(np.broadcast_to(a, (n,)), dtype=np.float64)
    bad = ~np.isfinite(a)
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(
            f"the growth rule {name} returned {what} = {a[k]} at Σ = {sigma[k]:.6f} mm "
            f"(point {k} of {n}): give finite numbers"
        )
    return a


def _call(f: Callable[[View], Any], name: str, view: View) -> Any:
    try:
        return f(view)
    except Exception as e:
        raise InputError(f"the growth rule {name} raised {type(e).__name__}: {e}") from e


def _split(out: Any, sigma: np.ndarray, name: str) -> tuple[np.ndarray, dict[str, np.ndarray] | None]:
    """A rule's answer: g, or (g, {quantity: partial})."""
    if isinstance(out, tuple):
        if len(out) != 2 or not isinstance(out[1], dict):
            raise InputError(
                f"the growth rule {name} returned a tuple of {len(out)}: return g, or (g, {{quantity: partial}}) with quantities from {', '.join(PARTIALS)}"
            )
        g, given = out
        unknown = [k for k in given if k not in PARTIALS]
        if unknown:
            raise InputError(
                f"the growth rule {name} gave a partial in {unknown[0]!r}: the partials are in {', '.join(PARTIALS)}"
            )
        return _as_values(g, sigma, name, "g_v"), {
            k: _as_values(v, sigma, name, f"the partial in {k}") for k, v in given.items()
        }
    return _as_values(out, sigma, name, "g_v"), None


def evaluate(
    f: Callable[[View], Any],
    name: str,
    q: tuple[np.ndarray, ...],
    t: float,
    partials: bool,
) -> tuple[np.ndarray, np.ndarray | None]:
    """The drive of ``f`` at every point of the view ``q`` (arrays in :data:`QUANTITIES`'
    order) and, with ``partials``, its partials as a (len(PARTIALS), n) array in
    :data:`PARTIALS`' order. Raises InputError naming the rule ``name`` for anything but n
    finite numbers; a KeyboardInterrupt passes."""
    arrays = dict(zip(QUANTITIES, q))
    sigma = arrays["sigma"]
    n = len(sigma)
    view = View({k: v.copy() for k, v in arrays.items()}, t)
    g, given = _split(_call(f, name, view), sigma, name)
    if not partials:
        return g, None
    d = np.zeros((len(PARTIALS), n))
    if given is not None:
        for j, k in enumerate(PARTIALS):
            if k in given:
                d[j] = given[k]
        return g, d
    for j, k in enumerate(PARTIALS):
        if k not in view.read:
            continue
        x = arrays[k]
        h = STEP * np.maximum(1.0, np.abs(x))
        sides = []
        for sign in (1.0, -1.0):
            moved = {kk: (vv + sign * h if kk == k else vv.copy()) for kk, vv in arrays.items()}
            sides.append(_split(_call(f, name, View(moved, t)), sigma, name)[0])
        # The step actually taken, as the floating point numbers hold it.
        d[j] = (sides[0] - sides[1]) / ((x + h) - (x - h))
    return g, d
