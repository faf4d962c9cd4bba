"""Virtual experiments (E01-E12 of the study's test programme), one file per family, and the
registry: name -> experiment class. The registry imports the experiments; they never import it."""

from .base import Experiment
from .footprint import Footprint
from .lateral import LateralStiffness
from .phases import Case, Protocol
from .vertical import VerticalStiffness

REGISTRY = {cls.name: cls for cls in (Footprint, VerticalStiffness, LateralStiffness)}

__all__ = ["REGISTRY", "Experiment", "Case", "Protocol"]
