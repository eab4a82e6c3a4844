"""A passive gait is reported only when its energy books close (issue 36: ``gait --slope
1e-300`` reported three gaits whose books disagreed by 40x)."""

from __future__ import annotations

import pytest

from heelstrike.analysis.limit_cycle import (
    ENERGY_BOOKS_RTOL,
    GaitNotFoundError,
    find_limit_cycles,
)
from heelstrike.cli import main
from heelstrike.models import CompassGait


def test_round_off_gaits_are_not_reported(capsys):
    with pytest.raises(GaitNotFoundError, match="do not close the energy books"):
        find_limit_cycles(CompassGait(), slope=1e-300, method="compiled")
    assert main(["gait", "--slope", "1e-300"]) == 2
    err = capsys.readouterr().err
    assert "energy books" in err and "give a larger slope" in err


def test_small_slope_gaits_whose_books_close_are_kept():
    gaits = find_limit_cycles(CompassGait(), slope=1e-6, method="compiled")
    assert gaits
    for g in gaits:
        assert g.energy_books_close
        released, loss = g.potential_energy_released, g.collision_loss
        assert abs(loss - released) <= ENERGY_BOOKS_RTOL * max(loss, released)
