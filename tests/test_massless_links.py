"""Massless links (issue #32, item 4): a link of zero mass and zero inertia is accepted where
the mass matrix stays positive definite, e.g. a torso whose mass is a point mass on a massless
rod; a walker whose mass matrix is singular is refused naming the coordinates of its null
vector."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import heelstrike.models.builder as builder_mod
from heelstrike.dynamics.hybrid import simulate
from heelstrike.dynamics.phased import load_phased_walker
from heelstrike.models.builder import load_walker
from heelstrike.models.description import ModelDescriptionError

TORSO_GAIT = [-0.1180757, 0.1118158, 0.5531974, -0.0140899, -0.6214368]


def _torso_text() -> str:
    return (Path(builder_mod.__file__).parent.parent / "walkers" / "torso.toml").read_text()


@pytest.fixture(scope="module")
def rod_torso(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped torso walker with its torso a massless rod carrying a point mass ``mT`` at
    ``cT`` (the torso link's own mass and inertia set to 0)."""
    text = _torso_text().replace('mass = "mT"', "mass = 0.0").replace(
        'inertia = "IT"', "inertia = 0.0")
    assert text.count("mass = 0.0") == 1 and text.count("inertia = 0.0") == 1
    text += '\n[[point_mass]]\nname = "head"\nlink = "torso"\nat = "cT"\nmass = "mT"\n'
    path = tmp_path_factory.mktemp("rod") / "rod_torso.toml"
    path.write_text(text)
    return path


def _e(theta: float) -> np.ndarray:
    """Unit vector at absolute angle ``theta`` from the ground normal, counter-clockwise."""
    return np.array([-np.sin(theta), np.cos(theta)])


def _de(theta: float) -> np.ndarray:
    return np.array([-np.cos(theta), -np.sin(theta)])


QS = [np.array([0.1, 0.0, 0.2, -0.5, 0.3]), np.array([-0.4, 0.0, -0.35, 0.7, -0.9])]


@pytest.mark.parametrize("q", QS)
def test_point_mass_on_a_massless_rod_has_the_closed_form_mass_matrix(
        rod_torso: Path, q: np.ndarray) -> None:
    """``M = M_compass (+) 0 + mT J^T J`` with ``J`` the Jacobian of the head's position
    ``p = (x, y) + l e(q3) + cT e(q3 + q_torso)`` (point feet, R = 0), derived by hand; and
    the same as the torso link carrying the mass itself with no inertia (a lumped form)."""
    w = load_walker(rod_torso)
    p = w.parameters
    l, cT, mT = float(p["l"]), float(p["cT"]), float(p["mT"])
    th1, thT = q[2], q[2] + q[4]
    J = np.zeros((2, 5))
    J[:, 0] = [1.0, 0.0]
    J[:, 1] = [0.0, 1.0]
    J[:, 2] = l * _de(th1) + cT * _de(thT)
    J[:, 4] = cT * _de(thT)
    np.testing.assert_allclose(w.positions(q)["head"], q[:2] + l * _e(th1) + cT * _e(thT),
                               atol=1e-14)
    expected = mT * J.T @ J
    expected[:4, :4] += load_walker("compass").mass_matrix(q[:4])
    np.testing.assert_allclose(w.mass_matrix(q), expected, rtol=1e-13, atol=1e-12)
    lumped = load_walker("torso", IT=0.0)  # the torso link's own mass at cT, no inertia
    np.testing.assert_allclose(w.mass_matrix(q), lumped.mass_matrix(q), rtol=1e-13,
                               atol=1e-12)
    np.testing.assert_allclose(w.potential_energy(q, 0.1), lumped.potential_energy(q, 0.1),
                               rtol=1e-13)
    assert np.linalg.eigvalsh(w.mass_matrix(q))[0] > 1e-3


def test_massless_rod_conserves_energy_over_single_support(rod_torso: Path) -> None:
    """A step of the rod torso walker on the scipy reference: the mechanical energy of every
    sample before the heel strike equals the start's (no impact, no actuation)."""
    w = load_phased_walker(rod_torso)
    q, qd = w.section_to_state(np.asarray(TORSO_GAIT))
    walk = simulate(w, q, qd, slope=0.0, steps=1, rtol=1e-11, atol=1e-11)
    E = np.asarray(walk.mechanical_energy)
    first = np.asarray(walk.step) == 0
    assert first.sum() >= 10 and float(walk.t[first][-1]) > 0.1
    scale = float(w.total_mass * w.scale.gravity * w.scale.leg_length)
    assert np.max(np.abs(E[first] - E[0])) < 1e-8 * scale
    # it moves: the rod turns (the torso is not welded) and the energy is not trivially flat
    assert np.ptp(walk.q[first][:, 4]) > 1e-2


def test_massless_rod_carrying_nothing_is_refused_naming_its_coordinate() -> None:
    """The torso without its mass and inertia: its joint moves nothing (M singular)."""
    with pytest.raises(ModelDescriptionError,
                       match=r"^walker 'torso': its mass matrix is singular .*: coordinate "
                             r"'torso' moves no mass and no inertia \(M's null space, "
                             r"dimension 1;"):
        load_walker("torso", mT=0.0, IT=0.0)
    # a mass or an inertia alone makes it regular again
    for values in ({"mT": 0.0, "IT": 0.01}, {"mT": 1.0, "IT": 0.0}):
        w = load_walker("torso", **values)
        assert np.linalg.eigvalsh(w.mass_matrix(QS[0]))[0] > 0


def test_singular_null_space_of_several_coordinates_names_them_all(tmp_path: Path) -> None:
    """A massless torso rod carrying a massless tail rod, neither carrying anything: M's null
    space has dimension 2 (each rod turns freely) and both coordinates are named."""
    text = _torso_text().replace('mass = "mT"', "mass = 0.0").replace(
        'inertia = "IT"', "inertia = 0.0")
    text = text.replace(
        '[[foot]]\nname = "stance"',
        '[[link]]\nname = "tail"\nparent = "torso"\ndirection = "up"\nlength = 0.3\n'
        'mass = 0.0\ncom = 0.15\njoint = { name = "tail" }\n\n[[foot]]\nname = "stance"', 1)
    assert 'name = "tail"' in text
    path = tmp_path / "tail.toml"
    path.write_text(text)
    with pytest.raises(ModelDescriptionError,
                       match=r"coordinate 'tail' moves no mass and no inertia; coordinate "
                             r"'torso' moves no mass and no inertia \(M's null space, "
                             r"dimension 2"):
        load_walker(path)
    # a point mass at the tail's end makes the chain regular: the rod torso carries it
    text += '\n[[point_mass]]\nname = "tip"\nlink = "tail"\nat = 0.3\nmass = 1.0\n'
    path.write_text(text)
    w = load_walker(path)
    assert np.linalg.eigvalsh(w.mass_matrix(np.array([0.0, 0.0, 0.1, -0.2, 0.3, 0.4])))[0] > 0


def test_negative_link_mass_is_still_refused(tmp_path: Path) -> None:
    text = _torso_text().replace('mass = "mT"', "mass = -1.0")
    path = tmp_path / "neg.toml"
    path.write_text(text)
    with pytest.raises(ModelDescriptionError,
                       match=r"^link\[2\]\.mass: must be > 0, or 0 for a massless link"):
        load_walker(path)
