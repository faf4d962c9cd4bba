"""Free decays, shared by E04, E05, E07, E08 and E09: the release phase and its reduction.

A release ramps a held load off (or on, for the drop) in `ramp` seconds with the settle damping OFF,
then lets the structure ring down on its own damping (the rubber's Maxwell branches, the tread). The
record is reduced with `jtire.signals.free_decay`: the study's two-peak log decrement and a
least-squares damped sinusoid over the whole decay, both reported with their disagreement.
"""

import numpy as np

from .. import signals
from .phases import make_drive
from .program import Phase


def release_branch(case, *, surface, load0, load1, rim_free, ramp, duration, belt=False, rigid_belt=False,
                   gravity=np.zeros(3)):
    """A free-decay phase: loads ramp load0 -> load1 over `ramp` s, settle damping off, `duration` s
    in all (no settle stop). load0/load1: (6,) rim force, or belt load when belt=True."""
    kw = dict(belt_load0=load0, belt_load1=load1) if belt else dict(force0=load0, force1=load1)

    def branch(y, t, mem):
        drive = make_drive(case.pressure, case.dt, t0=t, t1=t + ramp, rim_free=rim_free, surface=surface,
                           damping=0.0, rigid_belt=rigid_belt, gravity=gravity, **kw)
        return Phase(drive, y, duration, np.inf), mem
    return branch


def decay_about_fit(t, x, mass, t_start):
    """free_decay about a level that is not known in advance (friction in the patch may keep the
    rim from returning exactly): the first pass fits the asymptote x_inf, the second measures
    the peaks about it (a tail mean of a still-ringing record would be biased by the phase at
    which the record ends)."""
    first = signals.free_decay(t, x, mass, t_start=t_start)
    return signals.free_decay(t, x, mass, t_start=t_start, x_final=first.x_inf_fit)


def decay_names(mass_name: str, c_name: str, c_unit: str) -> tuple:
    """The names `decay_quantities` gives, in its order (for the experiments' `quantity_names`)."""
    return (f"{c_name}_{c_unit}", f"{c_name}_2p_{c_unit}", f"{c_name}_fit_{c_unit}", "damping_method", "xi_2p",
            "xi_fit", "xi_rel_diff_2p_vs_fit", "omega_n_2p_rad_per_s", "omega_n_fit_rad_per_s", "f_d_fit_Hz",
            "log_decrement", mass_name, "xi_formula")


def decay_quantities(fd, mass_name: str, c_name: str, c_unit: str) -> dict:
    """Two-peak and fitted damping of a free_decay result as SI-named quantities.

    `c_name` (e.g. "C_by") gets the two-peak value (the study's method) and, when two peaks could
    not be found, the fit's; `<c_name>_2p_<unit>`, `<c_name>_fit_<unit>` carry both.
    """
    c2p, cfit = fd.c_2p, fd.c_fit
    values = (c2p if fd.two_peak_ok else cfit, c2p, cfit,
              "two peaks" if fd.two_peak_ok else "damped-sine fit (no two clear peaks)",
              fd.xi_2p, fd.xi_fit, fd.rel_diff_xi, fd.omega_n_2p, fd.omega_n_fit, fd.omega_d_fit / (2 * np.pi),
              fd.delta, fd.mass, fd.xi_formula)
    return dict(zip(decay_names(mass_name, c_name, c_unit), values, strict=True))


def decay_checks(fd, out, prefix="release") -> dict:
    """Validity of a decay: fit quality, enough oscillation, no artificial damping, real loss.
    out: the release phase's PhaseOut (numpy)."""
    s = out.saved
    ok = np.isfinite(np.asarray(s["ke"]))
    settle_work = np.asarray(s["settle_work"])[ok]
    diss = np.asarray(s["dissipated"])[ok]
    return {
        f"{prefix}_two_peak_ok": fd.two_peak_ok, f"{prefix}_two_peak_reason": fd.two_peak_reason,
        f"{prefix}_fit_oscillatory": fd.fit_oscillatory, f"{prefix}_fit_rms_relative": fd.fit_rms_relative,
        f"{prefix}_fit_success": fd.fit_success,
        # the level the decay is measured about agrees with the fit's asymptote (1 % of amplitude)
        f"{prefix}_final_level_matches_fit": fd.tail_settled,
        # the settle damping is off in the release: the artificial work must not grow at all
        f"{prefix}_settle_work_J": float(settle_work[-1] - settle_work[0]),
        f"{prefix}_rubber_dissipated_J": float(diss[-1] - diss[0]),
        f"{prefix}_blew_up": bool(out.blew_up), f"{prefix}_steps": int(out.n_steps),
    }


def sample_times(out, duration: float, n_save: int) -> np.ndarray:
    """The save times (s) of a phase that ran its whole `duration` from out.t0."""
    return np.linspace(float(out.t0), float(out.t0) + duration, n_save)


def wheel_mass(spec) -> float:
    """m_wheel = m_tot: tire + rim mass from the tire config (kg)."""
    return spec.masses.tire + spec.masses.rim
