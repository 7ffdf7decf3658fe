"""One check that a motion empties a chamber (theory §11), for a flight and for a blow on the rock
(``Chambers.check_volumes``): the chamber it names is the one whose volume, computed here point by
point, reaches 0 (the rear one first), and each caller keeps its own advice."""

import numpy as np
import pytest

from impactbar.drives.circuit import Chambers
from impactbar.drives.circuit.endflight import _EMPTIED_IN_BLOW
from impactbar.drives.circuit.flight import _OVERTRAVEL

CH = Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2)


@pytest.mark.parametrize("w", [np.array([0.1, 0.45]), np.array([-0.41, 0.0]), np.array([-0.5, 0.5]),
                               np.array([-0.39, 0.39]), np.array([0.4]), np.array([-0.4])])
def test_the_chamber_named_is_the_one_that_empties(w):
    rear, front = CH.rear_volume - w, CH.front_volume + CH.area_ratio * w  # (each point's volumes)
    which = "rear" if (rear <= 0).any() else "front" if (front <= 0).any() else None
    if which is None:
        CH.check_volumes(w, 0.0, _OVERTRAVEL)  # (no chamber empties: nothing refused)
        return
    with pytest.raises(ValueError, match=f"^the {which} chamber empties") as err:
        CH.check_volumes(w, 0.0, _OVERTRAVEL)
    assert f"larger {which}_volume (now {getattr(CH, which + '_volume'):g})" in str(err.value)


def test_each_caller_keeps_its_advice():
    """The flight's and the blow's messages, as each read before they shared the check."""
    w, t = np.array([0.5]), 1.2345678
    with pytest.raises(ValueError) as flight:
        CH.check_volumes(w, t, _OVERTRAVEL)
    with pytest.raises(ValueError) as blow:
        CH.check_volumes(w, t, _EMPTIED_IN_BLOW)
    assert str(flight.value) == (f"the rear chamber empties (V <= 0) near t = {t:.6g}: the piston "
                                 f"overtravels it; give a larger rear_volume (now {0.4:g}) or a switch "
                                 "position nearer the stop")
    assert str(blow.value) == (f"the rear chamber empties (V <= 0) during the blow near t = {t:.6g}: give a "
                               f"larger rear_volume (now {0.4:g})")
