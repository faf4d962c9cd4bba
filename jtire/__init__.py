"""jtire: a JAX-native, differentiable ring-of-shells tire simulator and calibration toolkit."""
