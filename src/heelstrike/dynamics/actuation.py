"""Actuation of powered walkers: a push-off impulse and hip torque laws.

Small frozen dataclasses that :func:`heelstrike.dynamics.hybrid.simulate` accepts directly:

- :class:`PushOff` has the ``PushOff`` signature of :mod:`heelstrike.dynamics.hybrid`
  ``(walker, q, q_dot) -> (q_dot_after, work)`` and is applied just before heel strike
  (pre-emptive push-off, Kuo 2002);
- :class:`EnergyTracking`, :class:`SwingLegPD` and :class:`CustomTorque` have the
  :class:`~heelstrike.dynamics.single_support.TorqueLaw` signature ``(t, q, q_dot) -> u`` with
  ``u`` of shape ``(..., n_u)`` (N m). :class:`EnergyTracking` and :class:`SwingLegPD` act at
  the hip (:attr:`~heelstrike.models.base.PlanarWalker.hip_joint`: ``B = e4`` of the compass
  gait, i.e. a torque on the swing leg with its reaction on the stance leg) of a walker whose
  one actuator is its hip. Torque laws add with ``+``.

The actuator work of a torque law is integrated along the motion by the simulation as an extra
state (``dW/dt = (B u) . q_dot``); the push-off work is the kinetic-energy change it causes.
On a periodic level gait the energy theorem of Font & Kövecses (2008), eq. (14), gives
``W_act = -W_col``, and eq. (15) ``|W_col| = T_c``.

All torque laws saturate: ``|u| <= max_torque``.

Default gains
-------------
The defaults (:data:`DEFAULT_ENERGY_GAIN`, :data:`DEFAULT_PD_KP`, :data:`DEFAULT_PD_KD`,
:data:`DEFAULT_MAX_TORQUE`) are chosen so that ``heelstrike powered`` finds the default target,
0.5 m/s on level ground, for the paper's walker (``m_H = 10``, ``m = 5`` kg, ``l = 1``,
``b = 0.5`` m) with point feet and with ``R = 0.3`` m. Their physical reasons are given with each
constant. Another walker gets the same dimensionless gains (:func:`default_gains`: torques scaled
by its ``m g l``, times by its ``sqrt(l / g)``). On level ground a hip torque alone powers the
gait only through the swing leg (its reaction on the stance leg pushes the stance leg forward)
and, with no stiffness of its own, the step period stays near the swing leg's pendulum
half-period ``pi sqrt(b / g) = 0.71 s``; the speed ``L_S / T`` then grows only through longer
steps.
"""


from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray
from heelstrike.core.impact import kinetic_energy
from heelstrike.models.base import PlanarWalker, WalkerScale

__all__ = [
    "DEFAULT_ENERGY_GAIN",
    "DEFAULT_MAX_TORQUE",
    "DEFAULT_PD_KD",
    "DEFAULT_PD_KP",
    "CustomTorque",
    "EnergyTracking",
    "HipTorque",
    "PushOff",
    "SwingLegPD",
    "TorqueSum",
    "default_gains",
    "mechanical_energy",
    "push_off_velocity_change",
]

#: Energy-tracking gain ``k`` (s/rad: ``u = -k (E - E_ref) q4_dot`` in N m with ``E`` in J).
#: In single support the energy error decays at the rate ``k q4_dot^2``; with ``q4_dot^2`` of
#: order 3 (rad/s)^2 on 0.5 m/s gaits, ``k = 3`` makes that rate ~9 1/s, about one step
#: frequency (``2 pi / T`` with ``T ~ 0.7 s``): the energy is restored over a step, not in a
#: burst. Larger gains make the closed loop faster than the step dynamics and the equations
#: stiff (right-hand-side evaluations per step grow with ``k``: ~200 at k = 1, ~500 at k = 10)
#: without buying much reach: with point feet the *stable* gaits level off at ~0.42 m/s for
#: k = 10 (20 N m limit) and had reached only 0.47 m/s at k = 100 (100 N m) when a step cost
#: ~1 s, so at 0.5 m/s with point feet the default gives an unstable gait (found by Newton,
#: reported as such); with ``R = 0.3`` m it is stable.
DEFAULT_ENERGY_GAIN = 3.0

#: Swing-leg PD stiffness (N m/rad). The swing leg's own gravitational stiffness about the hip is
#: ``m g b = 24.5 N m/rad``; with a much weaker PD (the former 5 N m/rad) the leg swings
#: passively, the period stays ~0.75 s and point-foot gaits cannot exceed ~0.42 m/s. Twice the
#: gravitational stiffness makes the set point, not gravity, place the swing foot and triples
#: the leg's stiffness, which shortens the swing (half-period ``pi sqrt(J / (k_p + m g b))``
#: ~0.41 s with ``J = m b^2 = 1.25 kg m^2``): 0.5 m/s is then a stable gait with point feet
#: (``A ~ 0.19 rad``) and with ``R = 0.3`` m (``A ~ 0.07 rad``).
DEFAULT_PD_KP = 50.0

#: Swing-leg PD damping (N m s/rad): damping ratio ``k_d / (2 sqrt(J (k_p + m g b)))`` ~0.26 for
#: the paper's walker: light enough not to brake the swing (the hip pays for what it damps),
#: enough to stop the leg ringing about its set point within a step.
DEFAULT_PD_KD = 5.0

#: Hip torque limit (N m) of the built-in laws: about twice the largest gravitational torque on
#: the swing leg (``m g b = 24.5 N m`` when horizontal), so the 0.5 m/s gaits are not clipped
#: (the PD's peak is ``k_p`` times a tracking error of up to ~0.5 rad) while the transients of
#: the seed iterations stay bounded.
DEFAULT_MAX_TORQUE = 50.0

#: ``m g l`` (N m) and ``sqrt(l / g)`` (s) of the paper's walker (``m_total = 20 kg``,
#: ``l = 1 m``, ``g = 9.81 m/s^2``), for which the defaults above were chosen.
_REFERENCE_TORQUE, _REFERENCE_TIME = 20.0 * 9.81 * 1.0, math.sqrt(1.0 / 9.81)


def default_gains(scale: WalkerScale) -> dict[str, float]:
    """The hip laws' default gains for a walker of this scale.

    The ``DEFAULT_*`` constants, chosen for the paper's walker, held at the same dimensionless
    values: torques (``kp`` per radian, ``max_torque``) scale with the walker's ``m g l``,
    times with its ``sqrt(l / g)`` (``kd = torque x time``, ``gain = time``: ``u = -k (E -
    E_ref) q_dot`` with ``E`` in units of ``m g l``). A 1.6 kg walker (``kneed.toml``) so gets
    ``kp = 4 N m/rad``, not the 50 N m/rad that would lock its 0.5 kg legs to the set point.
    For the paper's walker the factors are exactly 1.

    Parameters
    ----------
    scale : WalkerScale
        The walker's :attr:`~heelstrike.models.base.PlanarWalker.scale` (scalars).

    Returns
    -------
    dict
        ``gain`` (s/rad), ``kp`` (N m/rad), ``kd`` (N m s/rad), ``max_torque`` (N m).
    """
    torque = float(scale.total_mass) * float(scale.gravity) * float(scale.leg_length)
    time = math.sqrt(float(scale.leg_length) / float(scale.gravity))
    # the factors to 12 significant digits: a walker of the paper's scale computed another way
    # (a described walker's g from its potential) gets the documented values, not 2.9999...
    f_torque = float(f"{torque / _REFERENCE_TORQUE:.12g}")
    f_time = float(f"{time / _REFERENCE_TIME:.12g}")
    return {
        "gain": DEFAULT_ENERGY_GAIN * f_time,
        "kp": DEFAULT_PD_KP * f_torque,
        "kd": DEFAULT_PD_KD * f_torque * f_time,
        "max_torque": DEFAULT_MAX_TORQUE * f_torque,
    }


def mechanical_energy(
    walker: PlanarWalker, q: ArrayLike, q_dot: ArrayLike, slope: float = 0.0
) -> FloatArray:
    """Mechanical energy ``E = T + V`` (J), shape (...).

    ``T = 1/2 q_dot^T M(q) q_dot`` (eq. 1) and ``V`` the walker's gravitational potential in the
    ground frame (zero at its origin); on level ground (``slope = 0``) ``V`` does not depend on
    the position along the ground, so ``E`` is comparable from step to step. The walker
    evaluates it (:meth:`~heelstrike.models.base.PlanarWalker.mechanical_energy`; the compass
    gait has a plain-float path for one state on level ground).
    """
    q_ = np.asarray(q, dtype=float)
    qd = np.asarray(q_dot, dtype=float)
    return np.asarray(walker.mechanical_energy(q_, qd, slope))


def _leg_direction(theta: FloatArray) -> FloatArray:
    """``e(theta) = (-sin theta, cos theta)``: unit vector up a leg, shape (..., 2)."""
    return np.stack((-np.sin(theta), np.cos(theta)), axis=-1)


def push_off_velocity_change(
    walker: PlanarWalker, q: ArrayLike, impulse: ArrayLike, locks: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Velocity jump caused by a push-off impulse at the trailing ("right") foot.

    The ground pushes the trailing foot's contact point with the impulse ``p e(q3)`` (N s),
    directed along the trailing leg from the foot towards the hip. Its generalized impulse is
    ``f = A_R(q)^T p e(q3)`` (eq. 2 with the trailing foot's contact Jacobian ``A_R``). No
    ground contact is active during the push-off (the leading foot has not landed and the
    trailing foot is free to leave the ground); the walker's locked joints (a kneed walker's
    knees) are, and hold with impulses ``lambda`` of their own:
    ``M(q) dq_dot = f + L^T lambda``, ``L dq_dot = 0``, i.e. ``dq_dot = P_a M^-1 f`` with the
    admissible projector of the lock rows ``L`` (eq. 11). Without locks ``M dq_dot = f``.

    Parameters
    ----------
    walker : PlanarWalker
        The walker, stance (trailing) foot labelled "right".
    q : array_like, shape (..., n)
        Configuration at push-off (that of heel strike).
    impulse : array_like, shape (...)
        Magnitude ``p`` (N s); positive pushes the walker away from the ground.
    locks : array_like, shape (k, n), optional
        Rows ``L`` of the joints locked at the push-off (rows of the identity; the heel
        strike's lock rows). None or ``k = 0``: no joint is locked.

    Returns
    -------
    dq_dot : ndarray, shape (..., n)
        Velocity jump ``P_a M^-1 f`` (``M^-1 f`` without locks).
    f : ndarray, shape (..., n)
        Generalized impulse of the ground ``A_R^T p e(q3)`` (the locks' impulses not included).
    """
    q_ = np.asarray(q, dtype=float)
    p = np.asarray(impulse, dtype=float)
    A = walker.contact_jacobian(q_, "right")
    vec = p[..., None] * _leg_direction(q_[..., 2])
    f = np.einsum("...ji,...j->...i", A, vec)
    M = walker.mass_matrix(q_)
    shape = np.broadcast_shapes(M.shape[:-1], f.shape)
    Mb = np.broadcast_to(M, (*shape, shape[-1]))
    dq = np.asarray(np.linalg.solve(Mb, np.broadcast_to(f, shape)[..., None])[..., 0])
    L = None if locks is None else np.asarray(locks, dtype=float)
    if L is not None and L.shape[-2] > 0:
        from heelstrike.core.impact import impact

        dq = np.asarray(impact(Mb, np.broadcast_to(L, (*shape[:-1], *L.shape[-2:])), dq)
                        .velocity_post)
    return dq, np.asarray(f)


@dataclass(frozen=True, kw_only=True)
class PushOff:
    """Pre-emptive push-off impulse at the trailing foot just before heel strike (Kuo 2002).

    Callable with the ``PushOff`` signature of :mod:`heelstrike.dynamics.hybrid`; see
    :func:`push_off_velocity_change` for the impulse algebra.

    Parameters
    ----------
    impulse : float
        Impulse magnitude ``p`` (N s), along the trailing leg from foot to hip; ``>= 0``.
    """

    impulse: float

    def __post_init__(self) -> None:
        p = float(self.impulse)
        if not np.isfinite(p) or p < 0:
            raise ValueError(f"push-off impulse must be finite and >= 0 (N s), got {p}")
        object.__setattr__(self, "impulse", p)

    def __call__(
        self, walker: PlanarWalker, q: FloatArray, q_dot: FloatArray,
        locks: FloatArray | None = None,
    ) -> tuple[FloatArray, float]:
        """Return ``(q_dot_after, work)``: velocities after the push-off and its work (J).

        ``locks``: rows of the joints locked at the push-off (see
        :func:`push_off_velocity_change`). The work is the kinetic-energy change
        ``T(q_dot+) - T(q_dot-)`` (the configuration does not change during the impulse, so
        neither does ``V``; locked joints do no work).
        """
        q_ = np.asarray(q, dtype=float)
        qd = np.asarray(q_dot, dtype=float)
        dq, _ = push_off_velocity_change(walker, q_, self.impulse, locks)
        after = qd + dq
        M = walker.mass_matrix(q_)
        work = float(kinetic_energy(M, after) - kinetic_energy(M, qd))
        return after, work


#: ``energy(walker, q, q_dot, slope) -> E``: how a law that tracks the mechanical energy
#: evaluates it (:func:`mechanical_energy` by default; the exact step Jacobian passes a
#: complex-capable one, :mod:`heelstrike.dynamics.variational`).
EnergyFunction = Callable[[PlanarWalker, Any, Any, float], Any]


def saturate(u: Any, limit: float) -> Any:
    """``sat(u)`` at ``+-limit`` (N m), decided by the real part: ``u`` inside the limit, the
    constant ``+-limit`` outside. Equal to ``np.clip(u, -limit, limit)`` for real ``u``; for a
    complex step ``u + i h du`` the derivative is kept inside and zero outside."""
    u = np.asarray(u)
    m = float(limit)
    if not np.isfinite(m):
        return u
    re = np.real(u)
    return np.where(np.abs(re) > m, np.sign(re) * m, u)


def call_by_rows(law: Callable[[float, Any, Any], Any], t: float, q: Any, q_dot: Any) -> Any:
    """``law(t, q, q_dot)`` for one state (shape (n,)) or, on a batch (shape (..., n)), state
    by state, stacked to (..., n_u): a torque law takes one state (a scalar ``u`` is returned
    as shape (1,)), so a function reducing over its input (``np.sum``) cannot mix states."""
    q, q_dot = np.asarray(q), np.asarray(q_dot)
    if q.ndim <= 1:
        u = np.asarray(law(t, q, q_dot))
        return u[None] if u.ndim == 0 else u
    rows = [np.atleast_1d(np.asarray(law(t, a, b)))
            for a, b in zip(q.reshape(-1, q.shape[-1]), q_dot.reshape(-1, q.shape[-1]),
                            strict=True)]
    return np.stack(rows).reshape(*q.shape[:-1], -1)


class HipTorque:
    """Base of the hip torque laws: saturation helper and ``+`` composition.

    Each law is written once, in :meth:`evaluate`, for any array type (float, or complex for
    the complex-step derivatives of the exact step Jacobian) and with its differentiable
    parameters (:attr:`parameters`) overridable; calling the law evaluates it in floats.
    """

    max_torque: float

    @property
    def parameters(self) -> dict[str, float]:
        """The law's parameters that can be differentiated in (name -> value); none here."""
        return {}

    def evaluate(self, t: float, q: Any, q_dot: Any, values: Mapping[str, Any] | None = None,
                 *, energy: EnergyFunction | None = None) -> Any:
        """The torque ``u`` (..., n_u) (N m) at ``(t, q, q_dot)``, any array type.

        Parameters
        ----------
        t : float
            Time since the step's start (s).
        q, q_dot : array_like, shape (..., n)
            Coordinates and velocities (float or complex).
        values : mapping, optional
            Values of :attr:`parameters` to use instead of the law's own (others ignored).
        energy : callable, optional
            ``energy(walker, q, q_dot, slope)`` for a law tracking the mechanical energy
            (default :func:`mechanical_energy`).

        A law written before this method, as its own ``__call__`` (the one way before), is
        called state by state (:func:`call_by_rows`): it must then take complex states itself
        for an exact step Jacobian.
        """
        if type(self).__call__ is not HipTorque.__call__:
            return call_by_rows(self, t, q, q_dot)
        raise NotImplementedError(f"{type(self).__name__} defines neither evaluate nor __call__")

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        return np.asarray(self.evaluate(t, np.asarray(q, dtype=float),
                                        np.asarray(q_dot, dtype=float)), dtype=float)

    def _values(self, values: Mapping[str, Any] | None) -> dict[str, Any]:
        """:attr:`parameters` with ``values`` (those of its names) in their place."""
        own = self.parameters
        return own if values is None else {k: values.get(k, v) for k, v in own.items()}

    def _saturate(self, u: Any) -> Any:
        return saturate(u, float(self.max_torque))

    def __add__(self, other: HipTorque) -> TorqueSum:
        return TorqueSum(laws=(self, other))


def _check_limit(value: float) -> float:
    v = float(value)
    if np.isnan(v) or v <= 0:
        raise ValueError(f"max_torque must be > 0 (N m), got {value}")
    return v


def _check_joint(joint: object, n_coordinates: int | None = None) -> int:
    """A hip law's joint: a coordinate index past the base's ``(x, y)`` (and below
    ``n_coordinates`` when known)."""
    if isinstance(joint, bool) or not isinstance(joint, (int, np.integer)) or joint < 2 or (
        n_coordinates is not None and joint >= n_coordinates
    ):
        within = "" if n_coordinates is None else f" and < {n_coordinates}"
        raise ValueError(f"joint must be a coordinate index >= 2{within}, got {joint!r}")
    return int(joint)


@dataclass(frozen=True, kw_only=True)
class TorqueSum(HipTorque):
    """Sum of hip torque laws, saturated again at ``max_torque`` (N m)."""

    laws: tuple[Callable[[float, FloatArray, FloatArray], FloatArray], ...]
    max_torque: float = np.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_torque", _check_limit(self.max_torque))

    @property
    def parameters(self) -> dict[str, float]:
        """The parts' differentiable parameters, but a name two parts share (ambiguous)."""
        names = [k for law in self.laws if isinstance(law, HipTorque) for k in law.parameters]
        return {k: v for law in self.laws if isinstance(law, HipTorque)
                for k, v in law.parameters.items() if names.count(k) == 1}

    def evaluate(self, t: float, q: Any, q_dot: Any, values: Mapping[str, Any] | None = None,
                 *, energy: EnergyFunction | None = None) -> Any:
        """``sat(sum of the parts' torques)`` (:meth:`HipTorque.evaluate`); ``values`` of a
        name two parts share are ignored (each part keeps its own)."""
        mine = self._values(values)
        u = sum(np.asarray(law.evaluate(t, q, q_dot, mine, energy=energy)
                           if isinstance(law, HipTorque) else call_by_rows(law, t, q, q_dot))
                for law in self.laws)
        return self._saturate(np.asarray(u))


@dataclass(frozen=True, kw_only=True)
class EnergyTracking(HipTorque):
    """Hip torque restoring a target mechanical energy (Goswami, Espiau & Keramane 1997).

    .. math:: u = \\operatorname{sat}_{u_{max}}\\big(-k\\,(E - E_{ref})\\,\\dot q_j\\big),
              \\qquad E = T + V,

    with ``T`` the kinetic energy (eq. 1), ``V`` the potential energy on level ground
    (ground-frame origin at zero height) and ``q_j`` the hip angle (``j = 3``, ``q4``, for the
    compass gait). The hip power is ``u q_j_dot`` (``B = e_j``), so in single support
    ``dE/dt = -k (E - E_ref) q_j_dot^2`` (before saturation): the energy moves monotonically
    towards ``E_ref``. Saturation keeps the sign of ``u``, hence the monotonicity.

    Parameters
    ----------
    energy : float
        Target mechanical energy ``E_ref`` (J).
    gain : float
        ``k`` (N m s / (J rad) = s/rad), > 0; default :data:`DEFAULT_ENERGY_GAIN`.
    max_torque : float
        Torque limit (N m), > 0; default :data:`DEFAULT_MAX_TORQUE`.
    slope : float
        Slope (rad) in ``V`` (0: level ground, the case this law is meant for).
    walker : PlanarWalker
        Supplies ``M`` and ``V``.
    joint : int, optional
        Coordinate index ``j`` of the hip angle; default (None) the walker's
        :attr:`~heelstrike.models.base.PlanarWalker.hip_joint`.
    """

    walker: PlanarWalker
    energy: float
    gain: float = DEFAULT_ENERGY_GAIN
    max_torque: float = DEFAULT_MAX_TORQUE
    slope: float = 0.0
    joint: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_torque", _check_limit(self.max_torque))
        if not float(self.gain) > 0:
            raise ValueError(f"gain must be > 0, got {self.gain}")
        joint = self.walker.hip_joint if self.joint is None else self.joint
        object.__setattr__(self, "joint", _check_joint(joint, self.walker.n_coordinates))

    @property
    def parameters(self) -> dict[str, float]:
        """``energy`` (J) and ``gain`` (s/rad)."""
        return {"energy": float(self.energy), "gain": float(self.gain)}

    def evaluate(self, t: float, q: Any, q_dot: Any, values: Mapping[str, Any] | None = None,
                 *, energy: EnergyFunction | None = None) -> Any:
        """``sat(-k (E - E_ref) q_j_dot)`` (:meth:`HipTorque.evaluate`), ``E`` of the law's
        own walker and slope."""
        v = self._values(values)
        qd = np.asarray(q_dot)
        E = (mechanical_energy if energy is None else energy)(self.walker, q, qd, self.slope)
        u = -v["gain"] * (E - v["energy"]) * qd[..., self.joint]
        return self._saturate(np.asarray(u)[..., None])


@dataclass(frozen=True, kw_only=True)
class SwingLegPD(HipTorque):
    """PD control of the hip angle ``q_j`` (the compass gait's inter-leg angle ``q4``, ``j = 3``)
    towards a swing target.

    .. math:: u = \\operatorname{sat}_{u_{max}}\\big(k_p\\,(q_j^{ref}(t) - q_j)
              - k_d\\,\\dot q_j\\big), \\qquad q_j^{ref}(t) = -2 A\\, s(t),

    ``A`` (rad) is the amplitude: the swing leg is driven towards a symmetric stance with
    half-angle ``A`` ahead of the stance leg (at heel strike ``q4 = -2 q3``; for a walker with
    knees, straight legs). ``s(t)`` is a dimensionless profile of the time since the step's
    start (default 1: a set point).

    Parameters
    ----------
    amplitude : float
        ``A`` (rad).
    kp : float
        Stiffness (N m / rad), >= 0; default :data:`DEFAULT_PD_KP`.
    kd : float
        Damping (N m s / rad), >= 0; default :data:`DEFAULT_PD_KD`.
    max_torque : float
        Torque limit (N m), > 0; default :data:`DEFAULT_MAX_TORQUE`.
    profile : callable ``t -> float`` or None
        ``s(t)``; None for a constant 1.
    joint : int
        Coordinate index ``j`` of the hip angle (default 3, the compass gait's; a described
        walker's is its :attr:`~heelstrike.models.base.PlanarWalker.hip_joint`).
    """

    amplitude: float
    kp: float = DEFAULT_PD_KP
    kd: float = DEFAULT_PD_KD
    max_torque: float = DEFAULT_MAX_TORQUE
    profile: Callable[[float], float] | None = None
    joint: int = 3

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_torque", _check_limit(self.max_torque))
        if self.kp < 0 or self.kd < 0:
            raise ValueError("kp and kd must be >= 0")
        object.__setattr__(self, "joint", _check_joint(self.joint))

    def reference(self, t: float) -> float:
        """``q4_ref(t)`` (rad)."""
        return -2.0 * float(self.amplitude) * self._profile(t)

    def _profile(self, t: float) -> float:
        """``s(t)`` (1 without a profile)."""
        return 1.0 if self.profile is None else float(self.profile(t))

    @property
    def parameters(self) -> dict[str, float]:
        """``amplitude`` (rad), ``kp`` (N m/rad) and ``kd`` (N m s/rad)."""
        return {"amplitude": float(self.amplitude), "kp": float(self.kp), "kd": float(self.kd)}

    def evaluate(self, t: float, q: Any, q_dot: Any, values: Mapping[str, Any] | None = None,
                 *, energy: EnergyFunction | None = None) -> Any:
        """``sat(kp (q_ref(t) - q_j) - kd q_j_dot)`` (:meth:`HipTorque.evaluate`)."""
        v = self._values(values)
        q_, qd = np.asarray(q), np.asarray(q_dot)
        j = self.joint
        u = v["kp"] * (-2.0 * v["amplitude"] * self._profile(t) - q_[..., j]) \
            - v["kd"] * qd[..., j]
        return self._saturate(np.asarray(u)[..., None])


@dataclass(frozen=True, kw_only=True)
class CustomTorque(HipTorque):
    """A user function ``(t, q, q_dot) -> u`` (N m), saturated at ``max_torque``.

    ``u`` may be a scalar or have shape ``(..., n_u)``; a scalar is returned as shape ``(1,)``.
    """

    function: Callable[[float, FloatArray, FloatArray], ArrayLike]
    max_torque: float = np.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_torque", _check_limit(self.max_torque))

    def evaluate(self, t: float, q: Any, q_dot: Any, values: Mapping[str, Any] | None = None,
                 *, energy: EnergyFunction | None = None) -> Any:
        """``sat(function(t, q, q_dot))`` (:meth:`HipTorque.evaluate`), the function called
        state by state (:func:`call_by_rows`); complex states reach it as they are (it may or
        may not take them)."""
        return self._saturate(call_by_rows(self.function, t, q, q_dot))
