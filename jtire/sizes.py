"""Tire size designations (ETRTO / TRA metric radial, e.g. 445/50R22.5 or 205/55R16), load indices, and
a first tire file scaled from the shipped ones (`jtire new-tire`).

The dimensions follow from the designation: section width W (mm), aspect ratio A (%), section height
W A / 100, rim diameter (the code in inches), outer diameter rim + 2 section heights. The measuring rim
width is taken from a short table of common sizes, else from a rule fitted by eye to ETRTO's measuring
rims (rounded to 0.25 in; `--rim-width-in` sets it). Everything else (tread and belt widths, crown
radius, masses, rim inertia) is scaled from the shipped truck tire or from the passenger template: a
starting point to calibrate, said so in the file it writes.
"""

import dataclasses
import math
import re

from . import units as U
from .errors import ConfigError

# ISO 4000 / ETRTO load index -> load capacity (kg) at the reference pressure, indices 60-200.
_LI_60_200 = (
    250, 257, 265, 272, 280, 290, 300, 307, 315, 325, 335, 345, 355, 365, 375, 387, 400, 412, 425, 437,  # 60-79
    450, 462, 475, 487, 500, 515, 530, 545, 560, 580, 600, 615, 630, 650, 670, 690, 710, 730, 750, 775,  # 80-99
    800, 825, 850, 875, 900, 925, 950, 975, 1000, 1030, 1060, 1090, 1120, 1150, 1180, 1215, 1250, 1285,  # 100-117
    1320, 1360, 1400, 1450, 1500, 1550, 1600, 1650, 1700, 1750, 1800, 1850, 1900, 1950, 2000, 2060,  # 118-133
    2120, 2180, 2240, 2300, 2360, 2430, 2500, 2575, 2650, 2725, 2800, 2900, 3000, 3075, 3150, 3250,  # 134-149
    3350, 3450, 3550, 3650, 3750, 3875, 4000, 4125, 4250, 4375, 4500, 4625, 4750, 4875, 5000, 5150,  # 150-165
    5300, 5450, 5600, 5800, 6000, 6150, 6300, 6500, 6700, 6900, 7100, 7300, 7500, 7750, 8000, 8250,  # 166-181
    8500, 8750, 9000, 9250, 9500, 9750, 10000, 10300, 10600, 10900, 11200, 11500, 11800, 12150, 12500,  # 182-196
    12850, 13200, 13600, 14000,  # 197-200
)
LOAD_INDEX_RANGE = (60, 200)


def load_index_kg(li: int) -> float:
    """The load capacity (kg) a load index stands for."""
    lo, hi = LOAD_INDEX_RANGE
    if not isinstance(li, int) or not lo <= li <= hi:
        raise ConfigError(f"--load-index {li}: must be an integer from {lo} to {hi}")
    return float(_LI_60_200[li - lo])


# Sizes whose measuring rim, load index (single fitment) and reference pressure are known here:
# size -> (rim width in, load index, pressure kPa). The 445/50R22.5 row is the study's tire (4625 kg, 120 psi).
KNOWN_SIZES = {
    "445/50R22.5": (14.00, 161, 827.4),
    "295/75R22.5": (8.25, 144, 758.4),   # load range G: 2800 kg at 110 psi
    "315/80R22.5": (9.00, 156, 850.0),   # 4000 kg single at 8.5 bar
    "205/55R16": (6.50, 91, 250.0),      # standard load: 615 kg at ETRTO's 2.5 bar reference
}
# reference pressure of a size not in the table (kPa): ETRTO's standard-load passenger reference, and
# the usual truck single-fitment pressure
DEFAULT_PRESSURE_KPA = {"passenger": 250.0, "truck": 830.0}

_SIZE = re.compile(r"^(P)?(\d{3})/(\d{2,3})\s*Z?R\s*(\d{2}(?:\.5)?)$", re.IGNORECASE)


@dataclasses.dataclass(frozen=True)
class Size:
    """A parsed metric radial designation, SI."""

    text: str  # normalised, e.g. "295/75R22.5"
    section_width: float
    aspect_ratio: float  # section height / section width
    rim_diameter: float
    kind: str  # "truck" (a 15-degree drop-centre rim: 17.5, 19.5, 22.5, 24.5 in) or "passenger"

    @property
    def section_height(self) -> float:
        """Section height (m): section width x aspect ratio."""
        return self.section_width * self.aspect_ratio

    @property
    def outer_diameter(self) -> float:
        """Nominal outer diameter (m): rim diameter + 2 section heights."""
        return self.rim_diameter + 2.0 * self.section_height


def parse_size(text: str) -> Size:
    """Parse a metric radial designation (ETRTO / TRA, e.g. "445/50R22.5", "205/55R16", "P205/55ZR16").

    Args:
        text: WIDTH/ASPECT R RIM: section width in mm (100-999), aspect ratio in % (20-120), rim
            diameter code in inches (10-30); an optional P (P-metric) prefix and Z before the R.

    Returns:
        The Size, SI (widths and diameters in m, aspect ratio as a fraction), normalised text, and its
        kind: "truck" for a half-inch rim code (a 15-degree drop-centre rim), else "passenger".

    Raises:
        ConfigError: not a designation, a number out of range, or a P-metric size on a truck rim.
    """
    m = _SIZE.match(text.strip())
    if not m:
        raise ConfigError(f"size {text!r}: not a metric radial designation WIDTH/ASPECT R RIM, e.g. 295/75R22.5 or "
                          "205/55R16 (width 100-999 mm, aspect 20-120 %, rim 10-30 in)")
    width, aspect, rim = int(m.group(2)), int(m.group(3)), float(m.group(4))
    if not 100 <= width <= 999 or not 20 <= aspect <= 120 or not 10 <= rim <= 30:
        raise ConfigError(f"size {text!r}: width {width} mm (100-999), aspect {aspect} % (20-120) or rim {rim:g} in "
                          "(10-30) out of range")
    kind = "truck" if rim % 1 == 0.5 else "passenger"
    if m.group(1) and kind == "truck":
        raise ConfigError(f"size {text!r}: a P-metric (passenger) size on a {rim:g} in truck rim")
    return Size(f"{width}/{aspect}R{rim:g}", width * U.MM, aspect / 100.0, rim * U.INCH, kind)


def measuring_rim_in(size: Size) -> float:
    """The measuring rim width (in): the table's where known, else ETRTO's trend (rim / section width rises as
    the aspect ratio falls), rounded to 0.25 in."""
    if size.text in KNOWN_SIZES:
        return KNOWN_SIZES[size.text][0]
    a = 100.0 * size.aspect_ratio
    ratio = 0.71 + 0.0036 * (75.0 - a) if size.kind == "truck" else 0.73 + 0.0048 * (70.0 - a)
    return round(ratio * size.section_width / U.INCH * 4.0) / 4.0


def rhyne_stiffness(size: Size, pressure_Pa: float) -> float:
    """Vertical stiffness (N/m) of a belted radial tire by Rhyne's formula (Tire Sci. Technol. 33(3),
    136-155, 2005), as usually quoted: K [kgf/mm] = 0.00028 p [kPa] sqrt(W [mm] D [mm]) + 3.45, with W the
    section width and D the outer diameter. An independent check of a generated tire, not an input."""
    k = 0.00028 * (pressure_Pa / 1e3) * math.sqrt(size.section_width / U.MM * size.outer_diameter / U.MM) + 3.45
    return k * U.G0 / U.MM  # kgf/mm -> N/m
