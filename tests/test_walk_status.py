"""One status vocabulary: :class:`WalkStatus` carries every status's message and integer code.

The compiled kernels write ``WalkStatus.code`` integers (module-level constants taken from the
enum); results convert them back with :meth:`WalkStatus.from_code`. The slow test runs the
backend-conformance cases through the compiled ensemble kernels and checks they report the same
member as the scipy reference.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.dynamics import compiled, compiled_phased
from heelstrike.dynamics.compiled_phased import ensemble_walk_phased
from heelstrike.dynamics.hybrid import WalkStatus, simulate
from heelstrike.dynamics.phased import TorsoPD, load_phased_walker, simulate_phased
from heelstrike.models import CompassGait
from test_backend_conformance import CASES, _run


def test_every_code_round_trips() -> None:
    codes = [s.code for s in WalkStatus]
    assert sorted(codes) == list(range(len(WalkStatus)))  # unique, no gaps
    for s in WalkStatus:
        assert WalkStatus.from_code(s.code) is s
        assert WalkStatus.from_code(np.int64(s.code)) is s  # as stored in ensemble arrays
        assert WalkStatus(s.value) is s
        assert WalkStatus.names_by_code()[s.code] == s.value


@pytest.mark.parametrize("bad", [-1, len(WalkStatus), 99])
def test_unknown_code_is_refused(bad: int) -> None:
    with pytest.raises(ValueError, match="no walk status has code"):
        WalkStatus.from_code(bad)


def test_every_status_has_a_message() -> None:
    messages = [s.message for s in WalkStatus]
    assert all(isinstance(m, str) and len(m) > 10 for m in messages)
    assert len(set(messages)) == len(messages)


def test_members_compare_equal_to_their_old_strings() -> None:
    for s in WalkStatus:
        assert s == s.value and str(s) == s.value and f"{s}" == s.value
    assert WalkStatus.FELL_BACKWARD == "fell_backward"
    assert "backward" in WalkStatus.FELL_BACKWARD.message
    # QA sweep 10: McGeer's wheel (R = l) "fell forward to the ground" at q3 = 90 deg with its
    # hip at height l: the guard is the leg reaching the horizontal, and the message says that
    assert "horizontal" in WalkStatus.FELL_FORWARD.message
    assert "ground" not in WalkStatus.FELL_FORWARD.message
    # forward topples reach negative normal force first (basin counts them as lost_contact)
    assert "topples forward" in WalkStatus.LOST_CONTACT.message


def test_codes_of_saved_results_are_stable() -> None:
    """Basin datasets store these integers: the original statuses keep their codes."""
    old = ("completed", "fell_forward", "fell_backward", "trailing_foot_stays", "lost_contact",
           "slipped", "no_heel_strike", "integration_failed")
    assert [WalkStatus(name).code for name in old] == list(range(len(old)))


@pytest.mark.parametrize("module", [compiled, compiled_phased])
def test_kernel_constants_come_from_the_enum(module: object) -> None:
    assert module.STATUS_NAMES == WalkStatus.names_by_code()  # type: ignore[attr-defined]
    for s in WalkStatus:
        const = getattr(module, s.name, None)
        if const is not None:
            assert type(const) is int and const == s.code, s.name
    assert compiled_phased._NO_CONSISTENT_ASSIGNMENT == WalkStatus.NO_CONSISTENT_ASSIGNMENT.code
    assert compiled_phased._NO_SWAP == WalkStatus.NO_LEG_SWAP.code


def test_python_results_carry_members_and_their_messages() -> None:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state([-0.3, 0.3, 0.0])  # too slow: falls backward
    res = simulate(w, q, qd, slope=0.05, steps=2)
    assert res.status is WalkStatus.FELL_BACKWARD
    assert res.message == res.status.message
    pw = load_phased_walker("compass")
    q, qd = pw.section_to_state(np.array([-0.2, 3.5, -2.0]))
    res_p = simulate_phased(pw, q, qd, slope=0.05, steps=2)
    # too fast: the stance normal force is negative at the start (as ``simulate`` reports for
    # CompassGait; it used to integrate on and report fell_forward, issue 9)
    assert res_p.status is WalkStatus.LOST_CONTACT
    assert res_p.message == WalkStatus.LOST_CONTACT.message
    assert simulate(CompassGait(), q, qd, slope=0.05, steps=2).status is res_p.status


@pytest.mark.slow
@pytest.mark.parametrize("case_name", sorted(CASES))
def test_ensemble_kernel_reports_the_reference_member(case_name: str) -> None:
    """Backend-conformance cases through the ensemble kernel (integer codes) against the scipy
    reference's member; the compass cases also through the compass kernel against
    :func:`simulate` (its own reference)."""
    case = CASES[case_name]
    w = load_phased_walker(case.walker)
    ref = _run(simulate_phased, w, case)
    assert ref.status is WalkStatus(case.status)
    opts = dict(case.options)
    if opts.get("torque") == "torso_pd":
        opts["torque"] = TorsoPD(walker=w)
    ens = ensemble_walk_phased(w, np.asarray([case.z]), slope=case.slope, steps=case.steps,
                               rtol=1e-11, atol=1e-11, parallel=False, **opts)
    assert WalkStatus.from_code(int(ens.status[0])) is ref.status
    assert ens.status_names[0] == ref.status.value
    if case.walker == "compass" and not opts:
        cg = CompassGait()
        q, qd = cg.section_to_state(case.z)
        ref_c = simulate(cg, q, qd, slope=case.slope, steps=case.steps, rtol=1e-11, atol=1e-11)
        ens_c = compiled.ensemble_walk(cg, case.z, case.slope, steps=case.steps, rtol=1e-11,
                                       atol=1e-11, parallel=False)
        assert WalkStatus.from_code(int(ens_c.status[0])) is ref_c.status
        one = compiled.step_map_compiled(cg, case.z, case.slope, rtol=1e-11, atol=1e-11)
        assert one.status is ref_c.status or ref_c.n_steps > 0
