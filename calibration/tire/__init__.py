"""Calibrating a tire to measurements: the parameter space, the targets, the simulators (shell model and
closed-form stand-in), the searches (multi-response ARSM, Levenberg-Marquardt), the run log, the
reports and the calibrated tire file."""
