"""Where the shipped configs and data live, in a source checkout and in an installed wheel.

The repository keeps them in the top-level `configs/` folder; a wheel carries the same folder as
package data under `jtire/configs/` (pyproject maps it there). Commands that default to a shipped
config or data file find it here, from any working folder.
"""

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def configs_dir() -> Path:
    """The folder holding default.toml, tires/, experiments/, calibration/ and data/."""
    for cand in (_HERE / "configs", _HERE.parent / "configs"):
        if (cand / "default.toml").is_file():
            return cand
    raise FileNotFoundError(f"jtire's configs folder is missing (looked in {_HERE / 'configs'} and {_HERE.parent / 'configs'})")


def config_path(*parts: str) -> Path:
    """A shipped config file, e.g. config_path("tires", "xone_xda.toml")."""
    return configs_dir().joinpath(*parts)
