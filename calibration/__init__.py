"""Calibration and uncertainty (installed as `jtire.calibration`).

    tire/        calibrating a tire to measurements: parameter space, targets, simulators, ARSM and
                 Levenberg-Marquardt, run log, reports, the calibrated tire file, sensitivities
    posterior/   the posterior of a calibration's parameters: emulator, emcee, predictive, check
    soil/        the optimizer competition on the soil block (Table 4-3)
    arsm.py      single-objective ARSM (the competition's method; the tire's multi-response ARSM builds on it)
    history.py   append-only JSON-lines histories that a killed run resumes from
"""
