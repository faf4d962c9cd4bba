"""Shared fixtures. Tests run on the CPU in float64 (importing jtire enables it)."""

import dataclasses
import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import jtire  # noqa: E402,F401  (float64)
import pytest  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
TIRE_TOML = REPO / "configs" / "tires" / "xone_xda.toml"


@pytest.fixture(scope="session")
def spec():
    from jtire.config import load_tire

    return load_tire(TIRE_TOML)


@pytest.fixture(scope="session")
def coarse_tire(spec):
    """The default tire on a coarse ring (32 segments, 4 crown elements): the same physics at a
    quarter of the cost, for invariant and trend tests (not for the reported numbers)."""
    from jtire.tire import make_tire

    return make_tire(dataclasses.replace(spec, n_theta=32, n_crown=4))


@pytest.fixture(scope="session")
def protocol():
    from jtire.experiments.phases import Protocol

    return Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-3, inflate_ramp=0.04, inflate_max=0.4,
                                   load_ramp=0.1, settle_max=0.5))


@pytest.fixture(scope="session")
def short_protocol():
    """A shorter load ramp and settle than `protocol`, for the dynamic-experiment tests on the
    coarse ring: its belt modes are > 25 Hz and near-critically damped while settling, so a
    50 ms ramp is still quasi-static."""
    from jtire.experiments.phases import Protocol

    return Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-3, inflate_ramp=0.04, inflate_max=0.4,
                                   load_ramp=0.05, settle_max=0.3))
