"""Robot files checked as written: one bounded parse of a URDF or MJCF file, then checks of the
file's own values, before Pinocchio's loader reads it.

The loaders change what they cannot hold without a word (a negative MJCF mass becomes 0 kg, a
short ``diaginertia`` is padded, a second free body is dropped, two bodies of one name merge)
and their parsers recurse once per nested body (10,000 of them crash the process; 1,000 nested
MJCF bodies take tens of GB). So a robot file is read here first, once:

- as a regular file of at most :data:`MAX_FILE_BYTES` (:func:`heelstrike.io.read_regular_file`);
- by expat in one call (linear in the file's size, a long comment included), with a document
  type declaration or an entity refused (only the five XML entities and character references
  are read), at most :data:`MAX_XML_DEPTH` nested elements and :data:`MAX_ELEMENTS` elements,
  counted as they open, before anything recurses;
- with at most :data:`MAX_BODIES` links (URDF) or bodies (MJCF), :data:`MAX_JOINTS` joints
  and :data:`MAX_CHAIN` bodies from the root to the deepest one (Talos has 60 links, 14 deep;
  Tiago dual 130 links, 21 deep).

Then the values the file gives, URDF and MJCF alike: masses finite and not negative (a massless
link of frames is allowed), inertia tensors finite, positive semi-definite (a point mass's zero
tensor is allowed) and obeying the triangle inequality (the largest principal moment at most
the sum of the other two), both up to the rounding of the file's numbers; ``diaginertia`` with
3 values and ``fullinertia`` with 6; ``density`` finite and not negative; names of links or
bodies, of joints and of sites unique and free of control characters; joint axes finite and
nonzero; joint limits finite and not inverted; one free (floating) joint at most, at the root.
Each refusal names the file, the element and what is allowed.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from heelstrike._typing import FloatArray
from heelstrike.io import InputFileError, read_regular_file
from heelstrike.robots.loading import RobotError

__all__ = [
    "MAX_BODIES",
    "MAX_CHAIN",
    "MAX_ELEMENTS",
    "MAX_FILE_BYTES",
    "MAX_JOINTS",
    "MAX_XML_DEPTH",
    "RobotFile",
    "read_robot_file",
]

#: Largest robot file read (bytes): 8 MiB (example-robot-data's largest URDF has 211 KB).
MAX_FILE_BYTES = 8 << 20
#: Most XML elements in a robot file (Tiago dual's URDF has 3,851).
MAX_ELEMENTS = 100_000
#: Most nested XML elements (an MJCF nests one element per body of a chain).
MAX_XML_DEPTH = 128
#: Most links (URDF) or bodies (MJCF).
MAX_BODIES = 1_000
#: Most joints.
MAX_JOINTS = 1_000
#: Most bodies on one chain from the root (Pinocchio's MJCF parser needs memory growing with
#: the square of this: 64 nested bodies take 90 MB, 200 take 360 MB).
MAX_CHAIN = 64

#: Principal moments below zero by more than this share of the file's largest inertia entry
#: are refused: what rounding leaves (iCub's -5e-20 kg m^2, Tiago's -3.5e-8 kg m^2) passes.
_PSD_TOLERANCE = 1e-6
#: Triangle inequality broken by more than this share of the file's largest inertia entry is
#: refused: CAD placeholders of a few 1e-6 kg m^2 on a dummy base link (ANYmal B, Go1, B1, HyQ)
#: pass, a tensor that no body has (PR2's sensor mount, Romeo's shoulders) does not.
_TRIANGLE_TOLERANCE = 1e-4

_LINK_KINDS = ("revolute", "continuous", "prismatic", "planar")
_LIMITED_KINDS = ("revolute", "prismatic")
_MJCF_JOINT_TYPES = ("hinge", "slide", "ball", "free")


@dataclass(frozen=True, kw_only=True)
class RobotFile:
    """A robot file read and checked by :func:`read_robot_file`.

    Attributes
    ----------
    path : Path
        The file.
    kind : {"URDF", "MJCF"}
        Its format.
    data : bytes
        The bytes checked (the loader must read these: see :meth:`require_unchanged`).
    root : xml.etree.ElementTree.Element
        The parsed document's root element (attributes only; no text).
    couplings : tuple of str
        Coupling elements the model cannot hold (URDF ``mimic`` of a moving joint, MJCF
        ``equality``, ``tendon``).
    """

    path: Path
    kind: str
    data: bytes
    root: ET.Element
    couplings: tuple[str, ...]

    def require_unchanged(self) -> None:
        """Refuse the file if its bytes are no longer those checked (it changed while
        Pinocchio's loader read it, so the model may hold values never checked)."""
        if _read(self.path, self.kind) != self.data:
            raise RobotError(f"{self.path}: the file changed while it was being loaded; "
                             "load it again")


def _read(path: Path, kind: str) -> bytes:
    try:
        return read_regular_file(path, what=f"{kind} file", max_bytes=MAX_FILE_BYTES)
    except InputFileError as exc:
        raise RobotError(str(exc)) from None


def read_robot_file(path: str | Path, kind: str) -> RobotFile:
    """Read a URDF or MJCF file once, bounded, and check the values it gives (module doc).

    Parameters
    ----------
    path : str or Path
        The file.
    kind : {"URDF", "MJCF"}
        Its format.

    Returns
    -------
    RobotFile

    Raises
    ------
    RobotError
        Naming the file and what is wrong: not a regular file, too large, not well-formed XML,
        an entity or document type declaration, a bound passed, or a value no robot has.
    """
    p = Path(path)
    data = _read(p, kind)
    root = _parse(data, p, kind)
    couplings = _check_urdf(root, p) if kind == "URDF" else _check_mjcf(root, p)
    return RobotFile(path=p, kind=kind, data=data, root=root, couplings=couplings)


class _Refused(Exception):
    """Raised inside expat's handlers to stop the parse with a message."""


def _parse(data: bytes, path: Path, kind: str) -> ET.Element:
    """The element tree of ``data`` (attributes only), parsed by expat in one call with
    entities refused and elements counted as they open."""
    from xml.parsers import expat

    builder = ET.TreeBuilder()
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    depth = count = 0

    def start(tag: str, attrs: dict[str, str]) -> None:
        nonlocal depth, count
        depth += 1
        count += 1
        if depth > MAX_XML_DEPTH:
            raise _Refused(f"elements nested more than {MAX_XML_DEPTH} deep (at <{tag}>, "
                           f"line {parser.CurrentLineNumber}); at most {MAX_CHAIN} bodies on "
                           "one chain are allowed")
        if count > MAX_ELEMENTS:
            raise _Refused(f"more than {MAX_ELEMENTS} XML elements (at line "
                           f"{parser.CurrentLineNumber})")
        builder.start(tag, attrs)

    def end(tag: str) -> None:
        nonlocal depth
        depth -= 1
        builder.end(tag)

    def doctype(*_: object) -> None:
        raise _Refused("a document type declaration (<!DOCTYPE ...>): robot files need none, "
                       "and its entities are not read")

    def entity(*_: object) -> None:
        raise _Refused("an entity declaration (<!ENTITY ...>), which is not read")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.StartDoctypeDeclHandler = doctype
    parser.EntityDeclHandler = entity
    robot = f"not {'an' if kind == 'MJCF' else 'a'} {kind} robot"
    try:
        parser.Parse(data, True)
    except _Refused as exc:
        raise RobotError(f"{path}: {robot}: it has {exc}") from None
    except expat.ExpatError as exc:
        reason = expat.errors.messages[exc.code] if exc.code else str(exc)
        undefined = expat.errors.codes[expat.errors.XML_ERROR_UNDEFINED_ENTITY]
        hint = (": only &amp; &lt; &gt; &quot; &apos; and character references such as &#160; "
                "are read" if exc.code == undefined else "")
        raise RobotError(f"{path}: {robot} (not well-formed XML: {reason} at line "
                         f"{exc.lineno}, column {exc.offset + 1}){hint}") from None
    return builder.close()


# -- values ---------------------------------------------------------------------------------
def _numbers(text: str | None, n: int | None, where: str, default: str | None = None,
             ) -> list[float]:
    """The ``n`` finite numbers of an attribute's text (any count if ``n`` is None), else a
    :class:`RobotError` naming ``where``; ``default`` if the attribute is absent."""
    if text is None:
        if default is None:
            raise RobotError(f"{where} is missing")
        text = default
    parts = text.split()
    try:
        values = [float(x) for x in parts]
    except ValueError:
        raise RobotError(f"{where} is {text.strip()[:60]!r}: numbers are needed") from None
    if n is not None and len(values) != n:
        raise RobotError(f"{where} has {len(values)} values ({text.strip()[:60]!r}): exactly "
                         f"{n} are allowed")
    if not all(math.isfinite(x) for x in values):
        raise RobotError(f"{where} is {text.strip()[:60]!r}: finite numbers are needed")
    return values


def _mass(text: str | None, where: str, default: str | None = None) -> float:
    (m,) = _numbers(text, 1, where, default)
    if m < 0.0:
        raise RobotError(f"{where} is {m:g} kg: a mass is >= 0 kg")
    return m


def _name(element: ET.Element, what: str) -> str:
    """The element's ``name``, refused if it holds control characters (they would reach the
    terminal in every listing)."""
    name = element.get("name") or ""
    if any(ord(ch) < 32 or 127 <= ord(ch) < 160 for ch in name):
        raise RobotError(f"the {what} named {name!r} has control characters in its name: "
                         "printable names only")
    return name


def _unique(names: list[str], what: str) -> None:
    seen: set[str] = set()
    for name in names:
        if name and name in seen:
            raise RobotError(f"two {what}s are named {name!r}: names must be unique (the "
                             "loader would merge or drop one)")
        seen.add(name)


def _check_inertias(tensors: list[tuple[str, FloatArray]]) -> None:
    """Refuse a tensor no rigid body has: a principal moment below zero, or the largest above
    the sum of the other two, beyond the rounding tolerances of the file's numbers."""
    scale = max((float(np.abs(t).max()) for _, t in tensors), default=0.0)
    moments: list[tuple[str, float, float, float]] = []
    for where, tensor in tensors:
        low, mid, high = (float(x) for x in np.linalg.eigvalsh(tensor))
        moments.append((where, low, mid, high))
    for where, low, _, _ in moments:  # a negative moment first: the worse fault
        if low < -_PSD_TOLERANCE * scale:
            raise RobotError(f"{where} has an inertia tensor that no rigid body has (a "
                             f"principal moment of {low:.3g} kg m^2): it must be positive "
                             "semi-definite")
    for where, low, mid, high in moments:
        if high > low + mid + _TRIANGLE_TOLERANCE * scale:
            raise RobotError(
                f"{where} has an inertia tensor that no rigid body has (principal moments "
                f"{low:.3g}, {mid:.3g}, {high:.3g} kg m^2): the largest must be at most the sum "
                "of the other two (triangle inequality)")


def _sym(xx: float, yy: float, zz: float, xy: float, xz: float, yz: float) -> FloatArray:
    return np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _chain_depths(parent: dict[str, str], names: list[str], path: Path) -> None:
    """Refuse a kinematic chain longer than :data:`MAX_CHAIN` (or a loop), without recursion."""
    depth: dict[str, int] = {}
    for name in names:
        trail = []
        node = name
        while node in parent and node not in depth:
            trail.append(node)
            node = parent[node]
            if len(trail) > len(names):
                raise RobotError(f"{path}: the joints make a loop through link {name!r}: a "
                                 "robot is a tree")
        d = depth.get(node, 0)
        for n in reversed(trail):
            d += 1
            depth[n] = d
            if d > MAX_CHAIN:
                raise RobotError(f"{path}: link {n!r} is {d} links from the root: at most "
                                 f"{MAX_CHAIN} are allowed on one chain")


# -- URDF -----------------------------------------------------------------------------------
def _check_urdf(root: ET.Element, path: Path) -> tuple[str, ...]:
    """Check a URDF's own values (module doc); return its couplings (``("mimic",)`` if a
    moving joint mimics another)."""
    if root.tag != "robot":
        raise RobotError(f"{path}: not a URDF robot (its root element is <{root.tag}>, a URDF's "
                         "is <robot>)")
    links, joints = root.findall("link"), root.findall("joint")
    for items, what, bound in ((links, "link", MAX_BODIES), (joints, "joint", MAX_JOINTS)):
        if len(items) > bound:
            raise RobotError(f"{path}: {len(items)} {what}s: at most {bound} are allowed")
    try:
        _unique([_name(x, "link") for x in links], "link")
        _unique([_name(x, "joint") for x in joints], "joint")
        tensors = [t for link in links for t in _urdf_link(link)]
        _check_inertias(tensors)
        parent: dict[str, str] = {}
        floating = []
        mimic = False
        for joint in joints:
            kind, child, up = _urdf_joint(joint)
            if child is not None and up is not None:
                parent[child] = up
            if kind == "floating":
                floating.append((str(joint.get("name")), up))
            mimic = mimic or (kind != "fixed" and joint.find("mimic") is not None)
    except RobotError as exc:
        raise RobotError(f"{path}: {exc}") from None
    _chain_depths(parent, [str(x.get("name")) for x in links], path)
    for name, up in floating:
        if up in parent:
            raise RobotError(f"{path}: joint {name!r} is floating but not at the root: its "
                             "child would be a second free body, not part of the robot")
    if len(floating) > 1:
        raise RobotError(f"{path}: {len(floating)} floating joints ("
                         f"{', '.join(repr(n) for n, _ in floating)}): one at most, at the root")
    return ("mimic",) if mimic else ()


def _urdf_origin(element: ET.Element, where: str) -> None:
    origin = element.find("origin")
    if origin is not None:
        _numbers(origin.get("xyz"), 3, f"{where} <origin xyz>", "0 0 0")
        _numbers(origin.get("rpy"), 3, f"{where} <origin rpy>", "0 0 0")


def _urdf_link(link: ET.Element) -> Iterator[tuple[str, FloatArray]]:
    """Check a link's inertial; yield its inertia tensor, named."""
    where = f"link {link.get('name')!r}"
    inertial = link.find("inertial")
    if inertial is None:
        return
    _urdf_origin(inertial, f"{where}:")
    mass = inertial.find("mass")
    _mass(mass.get("value") if mass is not None else None, f"{where}: <mass value>", "0")
    inertia = inertial.find("inertia")
    if inertia is None:
        return
    xx, yy, zz, xy, xz, yz = (_numbers(inertia.get(k), 1, f"{where}: <inertia {k}>", "0")[0]
                              for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"))
    yield where, _sym(xx, yy, zz, xy, xz, yz)


def _urdf_joint(joint: ET.Element) -> tuple[str, str | None, str | None]:
    """Check a joint's origin, axis and limits; return its type, child and parent links."""
    kind = joint.get("type", "")
    where = f"joint {joint.get('name')!r}"
    _urdf_origin(joint, f"{where}:")
    if kind in _LINK_KINDS:
        axis = joint.find("axis")
        if axis is not None:
            xyz = _numbers(axis.get("xyz"), 3, f"{where}: <axis xyz>", "1 0 0")
            if not any(xyz):
                raise RobotError(f"{where}: <axis xyz> is zero: a joint axis must be nonzero")
    limit = joint.find("limit")
    if kind in _LIMITED_KINDS and limit is not None:
        (lo,) = _numbers(limit.get("lower"), 1, f"{where}: <limit lower>", "0")
        (hi,) = _numbers(limit.get("upper"), 1, f"{where}: <limit upper>", "0")
        if lo > hi:
            raise RobotError(f"{where}: <limit lower={lo:g} upper={hi:g}> is inverted: lower "
                             "must be at most upper")
    child, up = joint.find("child"), joint.find("parent")
    return (kind, child.get("link") if child is not None else None,
            up.get("link") if up is not None else None)


# -- MJCF -----------------------------------------------------------------------------------
def _check_mjcf(root: ET.Element, path: Path) -> tuple[str, ...]:
    """Check an MJCF's own values (module doc); return its couplings (``equality``,
    ``tendon``)."""
    if root.tag != "mujoco":
        raise RobotError(f"{path}: not an MJCF robot (its root element is <{root.tag}>, an "
                         "MJCF's is <mujoco>)")
    if root.find(".//include") is not None:
        raise RobotError(f"{path}: <include> is not allowed: heelstrike checks one file, so "
                         "put the included elements in it")
    try:
        classes = {d.get("class", "main") for d in root.iter("default")}
        for element in root.iter():
            for attr in ("class", "childclass"):
                ref = element.get(attr)
                if ref is not None and element.tag != "default" and ref not in classes:
                    raise RobotError(f"<{element.tag} {attr}={ref!r}> names no <default "
                                     f"class>: the classes are {', '.join(sorted(classes))}")
        for default in root.iter("default"):
            _mjcf_values(default, "<default>")
        bodies, joints, sites = _mjcf_bodies(root)
        _unique(bodies, "body")
        _unique(joints, "joint")
        _unique(sites, "site")
    except RobotError as exc:
        raise RobotError(f"{path}: {exc}") from None
    return tuple(t for t in ("equality", "tendon") if root.find(f".//{t}") is not None)


def _mjcf_bodies(root: ET.Element) -> tuple[list[str], list[str], list[str]]:
    """Walk the bodies without recursion: bounds, inertials, joints, free bodies; return the
    names of bodies, joints and sites."""
    bodies: list[str] = []
    joints: list[str] = []
    sites: list[str] = []
    tensors: list[tuple[str, FloatArray]] = []
    free_bodies: list[str] = []
    stack = [(b, 1) for w in root.findall("worldbody") for b in reversed(w.findall("body"))]
    while stack:
        body, depth = stack.pop()
        name = _name(body, "body")
        where = f"body {name!r}" if name else f"an unnamed body at depth {depth}"
        bodies.append(name)
        if len(bodies) > MAX_BODIES:
            raise RobotError(f"more than {MAX_BODIES} bodies: at most {MAX_BODIES} are allowed")
        if depth > MAX_CHAIN:
            raise RobotError(f"{where} is {depth} bodies from the root: at most {MAX_CHAIN} "
                             "are allowed on one chain")
        _numbers(body.get("pos"), 3, f"{where}: pos", "0 0 0")
        _numbers(body.get("quat"), 4, f"{where}: quat", "1 0 0 0")
        tensors += _mjcf_inertial(body, where)
        _mjcf_values(body, where)
        for joint in (*body.findall("joint"), *body.findall("freejoint")):
            joints.append(_name(joint, "joint"))
            if joint.tag == "freejoint" or joint.get("type") == "free":
                if depth > 1:
                    raise RobotError(f"{where} has a free joint but is not at the root: only a "
                                     "body of <worldbody> may be free")
                free_bodies.append(name)
        sites += [_name(s, "site") for s in body.findall("site")]
        stack += [(b, depth + 1) for b in reversed(body.findall("body"))]
    hidden = sum(1 for w in root.findall("worldbody") for _ in w.iter("body")) - len(bodies)
    if hidden:
        raise RobotError(f"{hidden} bodies sit inside elements other than <body> (e.g. "
                         "<frame>), which these checks and Pinocchio's parser do not follow: "
                         "nest bodies in bodies")
    if len(joints) > MAX_JOINTS:
        raise RobotError(f"{len(joints)} joints: at most {MAX_JOINTS} are allowed")
    if len(free_bodies) > 1:
        raise RobotError(f"{len(free_bodies)} free bodies ({', '.join(map(repr, free_bodies))}):"
                         " one robot has one free body (the loader would drop the others)")
    _check_inertias(tensors)
    return bodies, joints, sites


def _mjcf_inertial(body: ET.Element, where: str) -> list[tuple[str, FloatArray]]:
    inertial = body.find("inertial")
    if inertial is None:
        return []
    w = f"{where}: <inertial"
    _mass(inertial.get("mass"), f"{w} mass>")
    _numbers(inertial.get("pos"), 3, f"{w} pos>", "0 0 0")
    _numbers(inertial.get("quat"), 4, f"{w} quat>", "1 0 0 0")
    if inertial.get("fullinertia") is not None:
        xx, yy, zz, xy, xz, yz = _numbers(inertial.get("fullinertia"), 6, f"{w} fullinertia>")
        return [(where, _sym(xx, yy, zz, xy, xz, yz))]
    if inertial.get("diaginertia") is not None:
        xx, yy, zz = _numbers(inertial.get("diaginertia"), 3, f"{w} diaginertia>")
        return [(where, _sym(xx, yy, zz, 0.0, 0.0, 0.0))]
    return []


def _mjcf_values(parent: ET.Element, where: str) -> None:
    """Check the geoms' masses and densities and the joints' types, axes and ranges among the
    direct children of a body or a ``<default>``."""
    for geom in parent.findall("geom"):
        g = f"{where}: <geom {geom.get('name')!r}" if geom.get("name") else f"{where}: <geom"
        for attr in ("mass", "density"):
            if geom.get(attr) is not None:
                (x,) = _numbers(geom.get(attr), 1, f"{g} {attr}>")
                if x < 0.0:
                    raise RobotError(f"{g} {attr}> is {x:g}: it must be >= 0")
    for joint in parent.findall("joint"):
        j = f"{where}: joint {joint.get('name')!r}" if joint.get("name") else f"{where}: <joint>"
        kind = joint.get("type")
        if kind is not None and kind not in _MJCF_JOINT_TYPES:
            raise RobotError(f"{j} has type {kind!r}: hinge, slide, ball or free are allowed")
        if joint.get("axis") is not None:
            if not any(_numbers(joint.get("axis"), 3, f"{j} axis")):
                raise RobotError(f"{j} axis is zero: a joint axis must be nonzero")
        if joint.get("range") is not None:
            lo, hi = _numbers(joint.get("range"), 2, f"{j} range")
            if lo > hi:
                raise RobotError(f"{j} range \"{lo:g} {hi:g}\" is inverted: the lower limit "
                                 "must be at most the upper one")
