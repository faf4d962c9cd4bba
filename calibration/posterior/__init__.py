"""The posterior of a calibration's parameters: an emulator of the targets fitted to the calibration's
runs, emcee on it, the predictive, conformal intervals and the check against the simulator."""
