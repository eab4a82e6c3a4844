"""Load URDF/MJCF robots with Pinocchio, floating base, and the robots shipped offline.

Pinocchio (package ``pin``) and the robot files (package ``example-robot-data``, whose wheel
carries the URDF/SRDF files under ``cmeel.prefix/share/example-robot-data/robots``; version 6 has
no Python loader, so the files are located through the package's installed metadata) come with
the optional extra ``heelstrike[robots]``. Nothing is fetched from the network.

Every model gets a floating base ``JointModelFreeFlyer`` as its root joint (a root ``floating``
joint in a URDF or a ``freejoint`` at an MJCF root is kept, and no second one is added).
A robot file is read once and checked as written before Pinocchio's parser reads it
(:mod:`heelstrike.robots.files`: bounded size, depth and counts; the file's own masses,
inertias, names, axes, limits and free joints). Couplings the model cannot hold (URDF
``<mimic>``, MJCF ``<equality>`` and ``<tendon>``) are
dropped by Pinocchio's parsers: they are listed in :attr:`Robot.ignored_couplings` and the
CLI says so. Pinocchio's conventions hold: ``q`` has ``nq`` entries (the base as
position and unit quaternion ``x, y, z, w``), ``v`` has ``nv`` entries (the base's linear and
angular velocity in its own frame), world ``z`` is up.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import importlib.metadata
import math
import os
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._typing import FloatArray

__all__ = [
    "SHIPPED_ROBOTS",
    "Robot",
    "RobotError",
    "RobotSpec",
    "UnitBlock",
    "list_robots",
    "load_mjcf",
    "load_robot",
    "load_urdf",
    "robot_data_dir",
    "unit_blocks",
]



class RobotError(ValueError):
    """Bad robot input: unknown robot or frame, a file that is not a robot, wrong q or v size."""


def _pin() -> Any:
    try:
        import pinocchio
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise RobotError(
            "robots need Pinocchio: pip install '.[robots]' in a clone of heelstrike"
        ) from exc
    return pinocchio


@dataclass(frozen=True, kw_only=True)
class RobotSpec:
    """A robot shipped by ``example-robot-data``.

    Parameters
    ----------
    name : str
        Short name (``heelstrike robot list``).
    urdf : str
        Path of the URDF relative to the package's ``robots/`` directory.
    srdf : str or None
        Path of the SRDF holding the reference pose, or None.
    pose : str or None
        Name of the reference configuration in the SRDF (e.g. ``half_sitting``).
    feet : tuple of (str, str)
        Left and right sole (or foot) frames, used for gait-like states.
    foot_contact : {"flat", "point"}
        Natural contact type of the feet.
    knee_bend : float
        Without SRDF pose: added to the ``*knee*`` joints, and half of it subtracted from the
        ``*hip_pitch*`` and ``*ankle_pitch*`` joints (rad), to stand with bent knees.
    soles : tuple of (str, str, float)
        Sole frames the file lacks, added at load: ``(name, parent frame, depth)``, the new
        frame ``depth`` (m) below its parent along the parent's ``z`` (g1's feet frames are its
        ankle-roll links, 35 mm above the contact spheres of its soles).
    """

    name: str
    urdf: str
    srdf: str | None
    pose: str | None
    feet: tuple[str, str]
    foot_contact: str = "flat"
    knee_bend: float = 0.0
    soles: tuple[tuple[str, str, float], ...] = ()


SHIPPED_ROBOTS: dict[str, RobotSpec] = {
    s.name: s
    for s in (
        RobotSpec(
            name="talos",
            urdf="talos_data/robots/talos_reduced.urdf",
            srdf="talos_data/srdf/talos.srdf",
            pose="half_sitting",
            feet=("left_sole_link", "right_sole_link"),
        ),
        RobotSpec(
            name="g1",
            urdf="g1_description/urdf/g1_29dof_rev_1_0.urdf",
            srdf=None,
            pose=None,
            feet=("left_sole", "right_sole"),
            knee_bend=0.6,
            # the soles' contact spheres: centres 30 mm below the ankle-roll frame, radius 5 mm
            soles=(("left_sole", "left_ankle_roll_link", 0.035),
                   ("right_sole", "right_ankle_roll_link", 0.035)),
        ),
        RobotSpec(
            name="bolt",
            urdf="bolt_description/robots/bolt.urdf",
            srdf="bolt_description/srdf/bolt.srdf",
            pose="standing",
            feet=("FL_FOOT", "FR_FOOT"),
            foot_contact="point",
        ),
    )
}


def robot_data_dir() -> Path:
    """Directory of the robot files installed by ``example-robot-data`` (no network).

    Raises
    ------
    RobotError
        If the package is not installed.
    """
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise RobotError(
            "shipped robots need example-robot-data: pip install '.[robots]' in a clone of "
            "heelstrike"
        ) from exc
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    if not path.is_dir():  # pragma: no cover - broken install
        raise RobotError(f"example-robot-data has no robots directory at {path}")
    return path


@dataclass(frozen=True, kw_only=True)
class UnitBlock:
    """A block ``q[start:stop]`` of a configuration that must have unit norm.

    Attributes
    ----------
    joint : str
        The joint's name.
    start, stop : int
        Its slice of ``q``.
    kind : {"quaternion", "cos_sin"}
        A quaternion ``(x, y, z, w)`` (free flyer, spherical joint) or the ``(cos, sin)`` pair
        of an unbounded revolute (URDF ``continuous``) or planar joint's angle.
    base : bool
        The root free flyer's quaternion.
    """

    joint: str
    start: int
    stop: int
    kind: str
    base: bool = False

    @property
    def unit(self) -> str:
        """``"unit quaternion"`` or ``"unit vector"``: what the block must be."""
        return "unit quaternion" if self.kind == "quaternion" else "unit vector"

    def describe(self) -> str:
        """``"q[3:7], the base's quaternion (x, y, z, w)"`` or the joint's block, named."""
        where = f"q[{self.start}:{self.stop}]"
        if self.base:
            return f"{where}, the base's quaternion (x, y, z, w),"
        what = "quaternion (x, y, z, w)" if self.kind == "quaternion" else "(cos, sin) pair"
        return f"{where}, the {what} of joint {self.joint!r},"


def unit_blocks(model: Any) -> tuple[UnitBlock, ...]:
    """Every block of ``q`` with unit norm in Pinocchio's conventions, joint by joint.

    Raises
    ------
    RobotError
        A joint with ``nq != nv`` of a kind not known here (e.g. a composite joint).
    """
    blocks = []
    for jid in range(1, model.njoints):
        joint = model.joints[jid]
        kind, iq = joint.shortname(), int(joint.idx_q)
        nq, nv, name = int(joint.nq), int(joint.nv), str(model.names[jid])
        if nq == nv:
            continue
        if kind == "JointModelFreeFlyer":
            blocks.append(UnitBlock(joint=name, start=iq + 3, stop=iq + 7, kind="quaternion",
                                    base=jid == 1))
        elif kind == "JointModelSpherical":
            blocks.append(UnitBlock(joint=name, start=iq, stop=iq + 4, kind="quaternion"))
        elif kind == "JointModelPlanar":
            blocks.append(UnitBlock(joint=name, start=iq + 2, stop=iq + 4, kind="cos_sin"))
        elif nq == 2 and nv == 1:  # unbounded revolute (RUBX, RUBY, RUBZ, unaligned)
            blocks.append(UnitBlock(joint=name, start=iq, stop=iq + 2, kind="cos_sin"))
        else:
            raise RobotError(f"joint {name!r} ({kind}, nq={nq}, nv={nv}) is not supported")
    return tuple(blocks)


@dataclass(frozen=True, kw_only=True, eq=False)
class Robot:
    """A floating-base robot loaded into Pinocchio.

    Attributes
    ----------
    name : str
        Robot name.
    source : str
        File it was loaded from.
    model : pinocchio.Model
        The kinematic and inertial model (root joint: free flyer).
    reference_q : ndarray, shape (nq,)
        Reference configuration (SRDF pose, or neutral).
    feet : tuple of str
        Left and right foot frames ("" if unknown).
    foot_contact : str
        Natural foot contact type, ``"flat"`` or ``"point"``.
    data : pinocchio.Data
        Work space reused by this robot's computations (not thread-safe; one per thread).
    cache : dict
        Derived data reused between calls (row layouts of contact sets).
    ignored_couplings : tuple of str
        Elements of the robot file that couple joints and that the model does not hold (URDF
        ``mimic``, MJCF ``equality``, ``tendon``): the joints they couple move independently
        here.
    """

    name: str
    source: str
    model: Any
    reference_q: FloatArray
    feet: tuple[str, str] = ("", "")
    foot_contact: str = "flat"
    data: Any = field(default=None, repr=False, compare=False)
    cache: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)
    ignored_couplings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.data is None:
            object.__setattr__(self, "data", self.model.createData())

    @property
    def nq(self) -> int:
        """Number of configuration entries."""
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        """Number of velocity entries (degrees of freedom)."""
        return int(self.model.nv)

    @property
    def mass(self) -> float:
        """Total mass (kg)."""
        return float(_pin().computeTotalMass(self.model))

    def frame_id(self, frame: str) -> int:
        """Index of a frame; raises :class:`RobotError` naming it if absent (with the frames
        of close names, or, if the robot file names it, why the model has no such frame)."""
        if not isinstance(frame, str):
            raise RobotError(f"a frame is named by a str, got {type(frame).__name__} "
                             f"{frame!r}")
        if not self.model.existFrame(frame):
            import difflib

            names = [str(f.name) for f in self.model.frames]
            close = difflib.get_close_matches(frame, names, n=3)
            hint = f"; did you mean {' or '.join(map(repr, close))}?" if close else ""
            from heelstrike.io import InputFileError, read_regular_file
            from heelstrike.robots.files import MAX_FILE_BYTES

            with contextlib.suppress(InputFileError):
                text = read_regular_file(self.source, what="robot file",
                                         max_bytes=MAX_FILE_BYTES).decode(errors="replace")
                if f'"{frame}"' in text:
                    hint = "; the file names it, but Pinocchio's parser dropped it" + (
                        " (it keeps no site of a root body without <freejoint/>: give that "
                        "body one)" if self.source.endswith(".xml") else "")
            raise RobotError(f"unknown frame {frame!r} in robot {self.name!r}{hint}")
        return int(self.model.getFrameId(frame))

    @property
    def unit_blocks(self) -> tuple[UnitBlock, ...]:
        """The blocks of ``q`` that must have unit norm (:func:`unit_blocks`), cached."""
        blocks = self.cache.get("unit_blocks")
        if blocks is None:
            blocks = self.cache["unit_blocks"] = unit_blocks(self.model)
        return blocks

    def check_state(
        self, q: ArrayLike, v: ArrayLike | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """Validate sizes and finiteness; normalise every unit block of ``q`` (the base
        quaternion, a continuous joint's ``(cos, sin)`` pair, a spherical joint's quaternion:
        :attr:`unit_blocks`).

        Returns
        -------
        q : ndarray, shape (nq,)
        v : ndarray, shape (nv,) (zeros if ``v`` is None)

        Raises
        ------
        RobotError
            Entries that are not real numbers (complex, text), wrong sizes, non-finite
            entries, a base position farther than :data:`MAX_BASE_DISTANCE` from the origin,
            or a unit block of norm outside (0.5, 1.5) (not a slightly perturbed unit vector:
            the joint's angle is then undefined), named.
        """
        nq, nv = self.nq, self.nv
        q_ = real_array(q, "q", copy=True).reshape(-1)  # a copy: normalised below
        if q_.shape != (nq,):
            raise RobotError(f"q has {q_.size} entries, robot {self.name!r} needs nq={nq}")
        v_ = np.zeros(nv) if v is None else real_array(v, "v").reshape(-1)
        if v_.shape != (nv,):
            raise RobotError(f"v has {v_.size} entries, robot {self.name!r} needs nv={nv}")
        # One dot product each decides the common case (finite: finite entries); an infinite
        # or NaN one (or an overflow) takes the entry-wise test.
        if not math.isfinite(float(q_.dot(q_)) + float(v_.dot(v_))) and not (
                np.isfinite(q_).all() and np.isfinite(v_).all()):
            raise RobotError("q and v must be finite")
        base = q_[:3]
        if not float(base.dot(base)) <= MAX_BASE_DISTANCE ** 2:  # the exact test decides
            _check_base_position(q_[None, :3])
        for b in self.unit_blocks:
            block = q_[b.start:b.stop]
            nrm = math.sqrt(float(block.dot(block)))  # np.linalg.norm, without overhead
            if not 0.5 < nrm < 1.5:
                raise RobotError(f"{b.describe()} must be a {b.unit}, "
                                 f"|q[{b.start}:{b.stop}]| = {nrm:g}")
            block /= nrm
        return q_, v_

    def check_states(self, qs: ArrayLike) -> FloatArray:
        """:meth:`check_state` for many configurations at once: (B, nq) with unit blocks
        (one configuration (nq,) is a batch of one).

        Raises
        ------
        RobotError
            As :meth:`check_state`, naming the first offending configuration; an empty batch
            (B = 0).
        """
        q_all = real_array(qs, "configurations")
        if q_all.shape == (self.nq,):
            q_all = q_all[None, :]
        if q_all.ndim != 2 or q_all.shape[1] != self.nq:
            raise RobotError(
                f"configurations must be (B, nq={self.nq}) for robot {self.name!r}, "
                f"got {q_all.shape}"
            )
        if q_all.shape[0] == 0:
            raise RobotError(f"configurations are an empty batch: give at least one (B >= 1) "
                             f"of nq={self.nq} entries")
        if not np.all(np.isfinite(q_all)):
            raise RobotError("q and v must be finite")
        _check_base_position(q_all[:, :3])
        out = q_all.copy()
        for b in self.unit_blocks:
            nrm = np.linalg.norm(q_all[:, b.start:b.stop], axis=1)
            bad = ~((nrm > 0.5) & (nrm < 1.5))
            if np.any(bad):
                i = int(np.argmax(bad))
                raise RobotError(
                    f"{b.describe()} must be a {b.unit}, |q[{b.start}:{b.stop}]| = "
                    f"{nrm[i]:g} (configuration {i})"
                )
            out[:, b.start:b.stop] /= nrm[:, None]
        return out

    def normalised_blocks(self, q: ArrayLike) -> list[tuple[UnitBlock, float]]:
        """The unit blocks of ``q`` that :meth:`check_state` rescales (norm not 1 to
        round-off, 1e-9), with their norms: what a report should mention."""
        q_ = np.asarray(q, dtype=float).reshape(-1)
        out = []
        for b in self.unit_blocks:
            nrm = float(np.linalg.norm(q_[b.start:b.stop]))
            if abs(nrm - 1.0) > 1e-9 and 0.5 < nrm < 1.5:
                out.append((b, nrm))
        return out

    def mass_matrix(self, q: ArrayLike, data: Any = None) -> FloatArray:
        """Joint-space mass matrix ``M(q)`` from ``crba``, symmetrised, shape (nv, nv)."""
        q_, _ = self.check_state(q)
        return self._mass_matrix(q_, self.data if data is None else data)

    def _mass_matrix(self, q: FloatArray, data: Any) -> FloatArray:
        """``crba`` at a checked ``q``, upper triangle mirrored into the lower one."""
        M = np.array(_pin().crba(self.model, data, q))
        np.copyto(M, M.T, where=_strictly_lower(M.shape[0]))
        return M


#: Farthest base position accepted (m from the origin): an impact does not depend on where the
#: robot stands, and beyond this round-off spoils the contact rows (1e-10 m at 1e6 m).
MAX_BASE_DISTANCE = 1e6


def _check_base_position(base: FloatArray) -> None:
    """Refuse base positions (B, 3) farther than :data:`MAX_BASE_DISTANCE` from the origin."""
    dist = np.sqrt(np.einsum("ij,ij->i", base, base))
    if dist.size and not float(dist.max()) <= MAX_BASE_DISTANCE:
        i = int(np.argmax(dist))
        which = f" (configuration {i})" if dist.size > 1 else ""
        raise RobotError(
            f"q[0:3], the base position, is {float(dist[i]):.3g} m from the origin{which}: at "
            f"most {MAX_BASE_DISTANCE:g} m is allowed (the impact does not depend on where the "
            "robot is, and farther away round-off spoils the contact rows): move it near the "
            "origin")


def real_array(x: ArrayLike, what: str, *, copy: bool = False) -> FloatArray:
    """``x`` as a float array, refusing what is not real numbers (complex, text, objects,
    ragged lists) with a message naming ``what``.

    Raises
    ------
    RobotError
        Naming ``what`` and the kind of values found.
    """
    try:
        arr = np.array(x, copy=copy) if copy else np.asarray(x)
    except (ValueError, TypeError) as exc:
        raise RobotError(f"{what} must be an array of real numbers ({exc})") from None
    if arr.dtype.kind not in "biuf":
        kind = {"c": "complex numbers", "U": "text", "S": "bytes", "O": "objects"}.get(
            arr.dtype.kind, f"values of type {arr.dtype}")
        raise RobotError(f"{what} must be real numbers, got {kind}")
    return np.asarray(arr, dtype=float)


def real_number(x: Any, what: str) -> float:
    """``x`` as a float, refusing what is not a real number (text, None, complex) with a
    message naming ``what``.

    Raises
    ------
    RobotError
        Naming ``what`` and the type given.
    """
    import numbers

    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise RobotError(f"{what} must be a real number, got {type(x).__name__} {x!r:.40}")
    return float(x)


@functools.lru_cache(maxsize=16)
def _strictly_lower(n: int) -> NDArray[np.bool_]:
    """Mask of the strictly lower triangle of an (n, n) matrix (read-only)."""
    mask = np.tril(np.ones((n, n), dtype=bool), -1)
    mask.setflags(write=False)
    return mask


@contextlib.contextmanager
def _native_errors() -> Iterator[list[str]]:
    """Keep what the C++ parsers print on file descriptor 2 off the terminal, and collect its
    ``Error:`` lines (urdfdom's reasons: a number that does not parse, a parent link not
    found) into the list yielded, filled when the block ends."""
    errors: list[str] = []
    fd = 2  # the C++ libraries write there, whatever Python's sys.stderr is
    with contextlib.suppress(AttributeError, OSError, ValueError):
        sys.stderr.flush()
    try:
        saved = os.dup(fd)
    except OSError:  # pragma: no cover - no file descriptor 2
        yield errors
        return
    try:
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), fd)
            try:
                yield errors
            finally:
                os.dup2(saved, fd)
                sink.seek(0)
                text = sink.read().decode(errors="replace")
                errors.extend(ln.split(":", 1)[1].strip() for ln in text.splitlines()
                              if ln.lstrip().startswith("Error:") and ln.split(":", 1)[1].strip())
    finally:
        os.close(saved)


def _has_free_root(model: Any) -> bool:
    """The model's first joint is a free flyer on the world, and no body is welded to the
    world (a URDF whose ``floating`` joint is not at its root has its root link there)."""
    return (model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"
            and float(model.inertias[0].mass) == 0.0)


def _unphysical(bodies: list[tuple[str, float, FloatArray]]) -> tuple[str, str] | None:
    """The first ``(name, mass (kg), inertia (kg m^2))`` no rigid body has, with why: a
    negative mass, or an inertia tensor with a principal moment below zero by more than 1e-6
    of the largest inertia given: what rounding the file's numbers leaves (iCub's bodies of
    ~1e-18 kg m^2 are at -5e-20, Tiago's antenna link at -3.5e-8) passes."""
    tol = 1e-6 * max((float(np.abs(rot).max()) for *_, rot in bodies), default=0.0)
    for name, mass, rot in bodies:
        if mass < 0.0:
            return name, f"a negative mass, {mass:g} kg"
        low = float(np.linalg.eigvalsh(0.5 * (rot + rot.T))[0])
        if low < -tol:
            return name, (f"an inertia tensor that no rigid body has (a principal moment of "
                          f"{low:.3g} kg m^2)")
    return None


def _check_inertias(model: Any, source: Path) -> None:
    """Refuse a body with a non-finite mass or inertia, or one no rigid body has
    (:func:`_unphysical`: its rotational inertia about its centre of mass), naming its joint."""
    bodies = [(str(model.names[j]), float(model.inertias[j].mass),
               np.array(model.inertias[j].inertia, dtype=float)) for j in range(1, model.njoints)]
    for name, mass, rot in bodies:
        if not (math.isfinite(mass) and np.isfinite(rot).all()):
            raise RobotError(f"{source}: the body moved by joint {name!r} has a non-finite "
                             "mass or inertia")
    bad = _unphysical(bodies)
    if bad is not None:
        raise RobotError(f"{source}: the body moved by joint {bad[0]!r} has {bad[1]}")


def _finish(model: Any, name: str, source: Path, q_ref: FloatArray | None,
            feet: tuple[str, str] = ("", ""), foot_contact: str = "flat",
            ignored: tuple[str, ...] = ()) -> Robot:
    pin = _pin()
    if not _has_free_root(model):
        raise RobotError(f"{source}: model has no floating base")
    for jid in range(2, model.njoints):
        if model.joints[jid].shortname() == "JointModelFreeFlyer":
            raise RobotError(
                f"{source}: joint {str(model.names[jid])!r} is floating but not at the root: "
                "its child would be a second free body, not part of the robot")
    _check_inertias(model, source)
    if model.nv <= 6 or pin.computeTotalMass(model) <= 0.0:
        raise RobotError(f"{source}: not a robot (no joints or no mass)")
    q = np.array(pin.neutral(model)) if q_ref is None else np.asarray(q_ref, dtype=float)
    unit_blocks(model)  # a joint the state checks do not know is refused here
    return Robot(name=name, source=str(source), model=model, reference_q=q, feet=feet,
                 foot_contact=foot_contact, ignored_couplings=ignored)


def _checked_file(path: str | Path, kind: str) -> Any:
    """The robot file at ``path`` read once and checked as written
    (:func:`heelstrike.robots.files.read_robot_file`)."""
    from heelstrike.robots.files import read_robot_file

    if not isinstance(path, str | os.PathLike):
        raise RobotError(f"a {kind} file is given by its path (str or Path), got "
                         f"{type(path).__name__}")
    if not str(path):
        raise RobotError(f"the {kind} file's path is empty: give a file")
    return read_robot_file(path, kind)


#: What Pinocchio's parsers raise on a file they cannot read (an ``IndexError`` is a C++
#: ``std::out_of_range``, e.g. a name they look up and do not find).
_PARSER_ERRORS = (RuntimeError, ValueError, OSError, IndexError, KeyError)


def load_urdf(
    path: str | Path, *, name: str | None = None, feet: tuple[str, str] | None = None,
    foot_contact: str = "flat",
) -> Robot:
    """Load a URDF with a free-flyer root joint.

    Parameters
    ----------
    path : str or Path
        The URDF file.
    name : str, optional
        The robot's name (default: the file's stem).
    feet : (str, str), optional
        Left and right sole (or foot) frames, for gait-like states
        (:func:`~heelstrike.robots.states.gait_state`); none by default.
    foot_contact : {"flat", "point"}
        Natural contact type of those feet.

    Raises
    ------
    RobotError
        If the file is missing, not a regular file, or fails the checks of what it says
        (:mod:`heelstrike.robots.files`: bounds, masses, inertias, names, axes, limits, free
        joints), is not a URDF robot, or a foot frame is not in it.
    """
    pin = _pin()
    checked = _checked_file(path, "URDF")
    p = checked.path
    try:
        with _native_errors() as errors:
            model = pin.buildModelFromUrdf(str(p))
    except _PARSER_ERRORS as exc:
        reason = errors[0] if errors else _parser_reason(exc)
        raise RobotError(f"{p}: not a URDF robot ({reason[:240]})") from None
    if errors:  # urdfdom dropped an element it could not read (a link's inertial: a typo)
        raise RobotError(f"{p}: {'; '.join(dict.fromkeys(errors))[:240]}")
    if model.njoints > 1 and model.parents[1] == 0 and model.joints[1].shortname() in (
            "JointModelPlanar", "JointModelTranslation"):
        raise RobotError(
            f"{p}: the root joint {str(model.names[1])!r} is "
            f"{model.joints[1].shortname()[len('JointModel'):].lower()}: heelstrike gives "
            "every robot a floating base itself (remove the world link and that joint)")
    if not _has_free_root(model):  # no root floating joint of its own: one is added
        model = pin.buildModelFromUrdf(str(p), pin.JointModelFreeFlyer())
    checked.require_unchanged()
    return _with_feet(_finish(model, name or p.stem, p, None, ignored=checked.couplings),
                      feet, foot_contact)


def _with_feet(robot: Robot, feet: tuple[str, str] | None, foot_contact: str) -> Robot:
    """``robot`` with the feet frames ``feet`` (checked: two frames of it) and their contact
    type (``"flat"`` or ``"point"``); ``robot`` itself if ``feet`` is None."""
    if foot_contact not in ("flat", "point"):
        raise RobotError(f"foot_contact must be 'flat' or 'point', got {foot_contact!r}")
    if feet is None:
        return robot
    if len(feet) != 2 or not all(isinstance(f, str) and f for f in feet):
        raise RobotError(f"feet must be two frame names (left, right), got {feet!r}")
    for frame in feet:
        robot.frame_id(frame)
    return dataclasses.replace(robot, feet=(feet[0], feet[1]), foot_contact=foot_contact,
                               data=None, cache={})


def load_mjcf(
    path: str | Path, *, name: str | None = None, feet: tuple[str, str] | None = None,
    foot_contact: str = "flat",
) -> Robot:
    """Load an MJCF (MuJoCo XML) with a free-flyer root joint (kept if it already has one).

    Parameters
    ----------
    path, name, feet, foot_contact
        As :func:`load_urdf`.

    Raises
    ------
    RobotError
        As :func:`load_urdf`, for an MJCF file.
    """
    pin = _pin()
    checked = _checked_file(path, "MJCF")
    p = checked.path
    try:
        with _native_errors() as errors:
            model = pin.buildModelFromMJCF(str(p))
            if not _has_free_root(model):  # a fixed root: a free flyer is added
                model = pin.buildModelFromMJCFAndRootJoint(
                    str(p), pin.JointModelFreeFlyer(), "root_joint")
    except _PARSER_ERRORS as exc:
        reason = errors[0] if errors else _parser_reason(exc)
        raise RobotError(f"{p}: not an MJCF robot ({reason[:240]})") from None
    checked.require_unchanged()
    return _with_feet(_finish(model, name or p.stem, p, None, ignored=checked.couplings),
                      feet, foot_contact)


def _parser_reason(exc: BaseException) -> str:
    """The informative line of a Pinocchio parser error: not its ``From file: ...cpp``
    location line."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    useful = [ln for ln in lines if not ln.startswith(("From file:", "in function:", "at line:"))]
    return (useful or lines or [type(exc).__name__])[-1][:160]


def _bent_neutral(model: Any, bend: float) -> FloatArray:
    pin = _pin()
    q = np.array(pin.neutral(model))
    for jid in range(2, model.njoints):
        jname = model.names[jid]
        iq = model.joints[jid].idx_q
        if "knee" in jname:
            q[iq] += bend
        elif "hip_pitch" in jname or "ankle_pitch" in jname:
            q[iq] -= 0.5 * bend
    return q


def load_robot(name: str) -> Robot:
    """Load a robot shipped by ``example-robot-data`` (see :data:`SHIPPED_ROBOTS`).

    Raises
    ------
    RobotError
        If ``name`` is unknown or the package is not installed.
    """
    pin = _pin()
    spec = SHIPPED_ROBOTS.get(name) if isinstance(name, str) else None
    if spec is None:
        raise RobotError(f"unknown robot {name!r}; known: {', '.join(sorted(SHIPPED_ROBOTS))}")
    root = robot_data_dir()
    path = root / spec.urdf
    checked = _checked_file(path, "URDF")
    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    for sole, parent, depth in spec.soles:
        frame = model.frames[model.getFrameId(parent)]
        model.addFrame(pin.Frame(sole, frame.parentJoint, model.getFrameId(parent),
                                 frame.placement * pin.SE3(np.eye(3), np.array([0, 0, -depth])),
                                 pin.FrameType.OP_FRAME))
    if spec.srdf is not None and spec.pose is not None:
        pin.loadReferenceConfigurations(model, str(root / spec.srdf), False)
        q_ref = np.array(model.referenceConfigurations[spec.pose])
    else:
        q_ref = _bent_neutral(model, spec.knee_bend)
    robot = _finish(model, spec.name, path, q_ref, spec.feet, spec.foot_contact,
                    ignored=checked.couplings)
    for f in spec.feet:
        robot.frame_id(f)
    return robot


def list_robots() -> list[dict[str, Any]]:
    """Name, ``nq``, ``nv``, mass (kg), source file and feet of every shipped robot."""
    out = []
    for name in SHIPPED_ROBOTS:
        r = load_robot(name)
        out.append({"name": r.name, "nq": r.nq, "nv": r.nv, "mass": r.mass,
                    "source": r.source, "feet": list(r.feet), "foot_contact": r.foot_contact})
    return out
