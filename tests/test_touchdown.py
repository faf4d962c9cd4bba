"""Robustness on the default mesh (slow): a 1 m/s touchdown under the rated load runs without
blow-up, settles, and the road ends up carrying the load.

The drop test's rim force (the rated 45.4 kN) accelerates the ~111 kg wheel at ~410 m/s^2, so a drop
of h = v^2 / (2 a) = 1.2 mm reaches the road at 1 m/s. (The E04 default of 20 mm lands at ~4 m/s.)
"""

import json

import pytest

from jtire.cli import main

from .conftest import REPO


@pytest.mark.slow
def test_one_metre_per_second_touchdown_at_rated_load(tmp_path, capsys):
    cfg = REPO / "configs" / "experiments" / "drop_test.toml"
    assert main(["run", str(cfg), "--set", "drop_test.drop_height_mm=1.2", "--set", "drop_test.duration_s=0.2",
                 "--out", str(tmp_path / "drop")]) == 0
    d = json.loads((tmp_path / "drop" / "result.json").read_text())
    c = d["checks"]
    assert c["static_converged"]  # inflation and the rest under the load: static equilibria
    assert c["static_contact_vs_load_rel_error"] < 0.01  # at rest again, the road carries the load
    assert 0 < c["max_deflection_m"] < 0.1  # it landed and rebounded, no tunnelling through the road
    assert d["quantities"]["C_tot_Ns_per_m"] > 0
