"""Virtual experiments (E01-E12 of the study's test programme; E13 and E14, jtire's additions), one file
per family, and the registry: name -> experiment class. The registry imports the experiments; they never import it."""

from .base import Experiment
from .cleat import DrumCleat
from .cornering import Cornering, RelaxationLength
from .drop import DropTest
from .footprint import Footprint
from .lateral import LateralStiffness
from .phases import Case, Protocol
from .rolling import RollingResistance
from .slip_step import SlipStep
from .standstill import LongitudinalStiffness
from .sidewall import InplaneRotation, SidewallCamber, SidewallLongitudinal, SidewallTranslation
from .traction import Traction
from .vertical import VerticalStiffness

REGISTRY = {cls.name: cls for cls in (Footprint, VerticalStiffness, DrumCleat, DropTest, InplaneRotation, Traction,
                                      SidewallTranslation, SidewallCamber, LateralStiffness, Cornering,
                                      RelaxationLength, RollingResistance, SlipStep, SidewallLongitudinal,
                                      LongitudinalStiffness)}

__all__ = ["REGISTRY", "Experiment", "Case", "Protocol"]
