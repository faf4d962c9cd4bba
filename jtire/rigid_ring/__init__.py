"""The rigid-ring tire model of the study (Zegelaar & Pacejka in-plane, Chae out-of-plane) filled
from the virtual experiments, with its Magic Formula fit and `.tir` export (docs/rigid-ring.md).

Modules: table (characterization.json layout and reader), params (derived quantities, the model's
parameters), report (in-/out-of-plane tables), trends (verdicts), model (equations of motion,
diffrax), scenarios (drop, drum-cleat, lateral release, slip step), validation (ring vs shell),
magic_formula (MF 6.1 pure side slip and its fit), tir (.tir writer and reader), synthetic (a
made-up characterization with the study's magnitudes, for tests).
"""
