"""The populated rigid ring against the shell model under the same inputs (docs/rigid-ring.md §8), at
three grid conditions of a finished characterization.

Shell side: the drop test (E04), the drum-cleat (E03) and the lateral release (E09 with its decay)
are read from the characterization's own case folders; the slip-angle step at 5 and 15 m/s is run here
(`experiments.slip_step`), each condition saved the moment it finishes into DIR/validation/cases/<case>/
(signals.csv, then result.json; error.txt for a failure), with DIR/validation/settings.json: a rerun
runs only what is missing or failed, and refuses a folder made with other settings. A failed step is
no silent gap: its rows say "SHELL RUN FAILED" and the error is returned. The same shell is also
solved in steady rolling (E10's method) at each step's speed and angle, into
DIR/validation/steady_<v>_m_s/ (resumed alike): the reference the diagnosis splits the step's
steady force against. The characterization's own lateral springs on the rubber's storage moduli
(`storage_pushes`, E09's static push at its release frequency) are run here too, for `jtire characterize`.
Ring side:
`rigid_ring.params.derive` populates the ring from the same condition's table row and
`rigid_ring.scenarios` runs the same inputs. `rigid_ring.validation.compare` judges every metric
against its tolerance (stated up front there).
"""

import dataclasses
import math
from pathlib import Path

import numpy as np

from . import results, slip_reading, spectra
from . import units as U

DEFAULT_CONDITIONS = ((4625.0, 120.0), (2312.5, 120.0), (4625.0, 70.0))  # (kg, psi): rated, light, soft
RING_STEP_SIGMAS = 8.0  # relaxation lengths the ring's slip step rolls when no shell record sets the distance
BELT_BAND_HZ = (40.0, 300.0)  # where the belt's vertical mode is looked for: above the bounce


def belt_band(t) -> tuple | None:
    """BELT_BAND_HZ cut at the Nyquist frequency of the samples t (E04 saves at drop_test.sample_rate_Hz,
    2500 Hz by default: the whole band), or None when nothing of the band is left. Ring and shell search
    the same band."""
    fs = 1.0 / float(np.median(np.diff(np.asarray(t, float))))
    hi = min(BELT_BAND_HZ[1], 0.5 * fs)
    return (BELT_BAND_HZ[0], hi) if hi > BELT_BAND_HZ[0] * 1.5 else None


def _case_dir(char_dir, experiment, load_N, pressure_Pa):
    """The case folder of an experiment at a condition in a characterization folder (or None)."""
    return results.find_case(results.cases_dir(char_dir, experiment), load_N, pressure_Pa)


def _signals(folder):
    return results.read_signals(folder) or {}


def shell_metrics(char_dir, load_N, pressure_Pa) -> tuple:
    """(metrics, figure signals) of the shell model at one condition from the characterization folder."""
    m, sig = {}, {}
    d = _case_dir(char_dir, "drop_test", load_N, pressure_Pa)
    if d is not None:
        r = results.read_result(d)
        q, chk = r["quantities"], r["checks"]
        s = _signals(d)
        t, fz = s["time_s"], s["contact_force_z_N"]
        band = belt_band(t)
        sp = None if band is None else spectra.first_mode(t, fz, f_band=band, t_start=float(t[np.argmax(fz > 0)]),
                                                          fit=False)
        belt = None if sp is None else sp.interior_peak_Hz()  # a band edge is no mode
        m |= {"drop.static_deflection_m": q["static_deflection_m"], "drop.bounce_f_Hz": q["f_d_fit_Hz"],
              "drop.bounce_zeta": q["xi_fit"], "drop.peak_F_z_N": float(np.nanmax(fz)),
              "drop.belt_mode_Hz": belt}
        sig["drop_band_Hz"] = band
        # rim z from where the wheel rests under the load (first contact at z = -drop height, then the
        # static deflection), time from first contact: the ring's panel is drawn the same way
        rest = -(float(chk["drop_height_m"]) + float(q["static_deflection_m"]))
        sig["drop"] = (t - float(chk["first_contact_t_s"]), s["rim_z_m"] - rest)
    d = _case_dir(char_dir, "drum_cleat", load_N, pressure_Pa)
    if d is not None:
        r = results.read_result(d)
        q, info = r["quantities"], r["info"]
        s = _signals(d)
        t = s["time_s"]
        after = float(info["t_cleat_leave_s"] - info["t_cleat_touch_s"])
        m |= {"drum.vertical_mode_Hz": q["first_mode_fit_fn_Hz"], "drum.vertical_mode_zeta": q["first_mode_xi"]}
        if "axle_force_x_N" in s:
            fa = spectra.first_mode(t, s["axle_force_x_N"], f_band=tuple(info["f_band_Hz"]), t_start=after)
            m |= {"drum.fore_aft_mode_Hz": fa.fn_fit_Hz, "drum.fore_aft_mode_zeta": fa.xi_fit,
                  "drum.F_x_peak_to_peak_N": float(np.ptp(s["axle_force_x_N"][t >= 0]))}
        m["drum.F_z_peak_to_peak_N"] = float(np.ptp(s["axle_force_N"][t >= 0]))
        # time from the cleat under the rim centre (the ring's panel is drawn the same way); a folder
        # made before E03 recorded that time keeps the touch as its origin
        centre = float(info.get("t_cleat_centre_s", info["t_cleat_touch_s"]) - info["t_cleat_touch_s"])
        sig["drum"] = (t - centre, s["axle_force_N"])
    d = _case_dir(char_dir, "lateral_stiffness", load_N, pressure_Pa)
    if d is not None:
        q = results.read_result(d)["quantities"]
        if "f_d_fit_Hz" in q:
            s = _signals(d)
            m |= {"lateral.f_Hz": q["f_d_fit_Hz"], "lateral.zeta": q["xi_fit"]}
            sig["lateral"] = (s["time_s"], s["rim_y_m"])
    return m, sig


def step_metrics(result, speeds=(5.0, 15.0), f_lateral_Hz=None) -> tuple:
    """(metrics, figure signals) of the shell's slip step, read from its signals by `jtire.slip_reading`
    with the steady window of `step_tail` (the ring's scenario is read with the same)."""
    m, sig = {}, {}
    s = result.signals
    for v in speeds:
        k = f"{v:g}"
        dist = s[f"distance_m_{k}"]
        r = slip_reading.readings(dist, s[f"F_y_SAE_N_{k}"], s[f"M_z_SAE_Nm_{k}"],
                                  step_tail(v, f_lateral_Hz, float(dist[-1])))
        m |= {f"step_{k}.F_y_steady_N": r["F_y_steady_SAE_N"], f"step_{k}.M_z_steady_Nm": r["M_z_steady_SAE_Nm"],
              f"step_{k}.s63_m": r["s63_m"]}
        sig[f"step_{k}"] = (s[f"distance_m_{k}"], s[f"F_y_SAE_N_{k}"])
    return m, sig


def step_tail(speed, f_lateral_Hz, record_m=None) -> float | None:
    """The slip step's steady window in the validation (m): one period of the shell's lateral release
    mode (E09) rolled at `speed`, on both sides, since both records still ring in that mode at their ends
    (`jtire.slip_reading`), and at most half the record_m rolled (a short record: its second half);
    None (the last 5 %) without E09's frequency."""
    w = slip_reading.tail_for(speed, f_lateral_Hz)
    return w if w is None or record_m is None else min(w, 0.5 * float(record_m))


def ring_results(row, tire_info, belt_band_Hz=BELT_BAND_HZ, lateral="ring", contact=None, f_lateral_Hz=None,
                 step_distance_m=None) -> dict:
    """The ring's scenarios; belt_band_Hz: where its drop looks for the belt mode (the shell's band,
    or the full BELT_BAND_HZ when the shell has none); lateral: the ring's out-of-plane model in the
    lateral release and the slip step ("ring": belt DOFs, or "reduced"); contact: its tread in the
    rolling ones ("string", "lag"; None: the model's default); f_lateral_Hz: the shell's lateral release
    frequency, which sets the slip step's steady window (`step_tail`); step_distance_m: how far the ring's
    step rolls (the shell's record; None: RING_STEP_SIGMAS relaxation lengths)."""
    from .rigid_ring import scenarios as sc
    from .rigid_ring.model import CONTACT
    from .rigid_ring.params import derive

    contact = contact or CONTACT
    d = derive(row, tire_info)
    out = {"drop": sc.drop_test(d, f_band=tuple(belt_band_Hz)), "drum": sc.drum_cleat(d, contact=contact),
           "lateral": sc.lateral_release(d, lateral=lateral)}
    dist = step_distance_m if step_distance_m is not None or d.sigma is None else RING_STEP_SIGMAS * d.sigma
    for v in (5.0, 15.0):
        out[f"step_{v:g}"] = sc.slip_step(d, speed=v, lateral=lateral, contact=contact,
                                          tail_m=step_tail(v, f_lateral_Hz, dist), distance_m=dist)
    return out


def step_tire(plan):
    """The tire spec the shell's slip step runs on: the plan's tire with at least its config's
    `validation.step_contact_subpoints` contact points per segment (the tire's own when it has more)."""
    n = plan.validation["step_contact_subpoints"]
    return dataclasses.replace(plan.tire, contact_subpoints=max(plan.tire.contact_subpoints, n))


def slip_steps(char_dir, plan, conds, slip_step_table=None, batch_size=1, on_case=None) -> list:
    """The slip-angle step at each condition (SI dicts), on `step_tire(plan)`, resumed from
    DIR/validation. Returns one entry per condition: its ExperimentResult (read back from its folder)
    or its error message (str). on_case(name or None, n_done, n_total): at the start (None) and as
    each condition is saved (the CLI draws a progress bar with it)."""
    from .experiments import REGISTRY

    tire = step_tire(plan)
    exp = REGISTRY["slip_step"].from_table(_step_table(slip_step_table), _protocol(plan), tire)
    return _resumed(Path(char_dir) / "validation", "slip_step", exp, plan, conds, batch_size, on_case, tire=tire)


# load levels of the steady loading at speed, tried in turn for a condition whose loading failed (E10
# takes two; measured at 15 m/s on the default tire: 2 levels failed at half the rated load, 4 at rated,
# both on a first level of 11.3 kN)
REFERENCE_LOAD_LEVELS = (2, 3, 5)


def steady_references(char_dir, plan, conds, slip_step_table=None, batch_size=1, on_case=None) -> dict:
    """{speed (m/s): per condition, the shell's steady cornering solve (E10's method) at the slip
    step's speed over 0, half and all of its angle (ExperimentResult, or its error message)}: what
    the step's force should settle to, so the diagnosis can split the ring's miss into the shell's
    speed dependence and the transient's own gap to the steady solve. Resumed from
    DIR/validation/steady_<v>_m_s/load_levels_<n> (`results.steady_reference_folder`). on_case as for
    slip_steps, counting (condition, speed) pairs (a retry's case moves it too, up to the total)."""
    from .config import validate_table
    from .experiments import REGISTRY

    step = _step_table(slip_step_table)
    a = math.degrees(step["slip_angle_deg"])
    out = {}
    if a == 0:  # no step: nothing to settle to
        return out
    speed_field = REGISTRY["cornering"].schema["speed_mph"]
    lo, hi = speed_field.lo * U.MPH, speed_field.hi * U.MPH
    # past what E10's config takes (the step allows up to 40 m/s): no reference
    speeds = [v for v in step["speeds_m_per_s"] if lo <= v <= hi]
    total, done = len(speeds) * len(conds), [0]

    def tick(name, n_done, n_total):
        if on_case is not None and name is not None:
            done[0] += 1
            on_case(name, min(done[0], total), total)

    if on_case is not None:
        on_case(None, 0, total)
    span = sorted([0.0, a])
    for v in speeds:
        got = [None] * len(conds)
        for n in REFERENCE_LOAD_LEVELS:  # a condition whose loading at speed failed is tried again with more levels
            todo = [i for i, r in enumerate(got) if r is None or isinstance(r, str)]
            if not todo:
                break
            table = validate_table({"method": "steady", "speed_mph": v / U.MPH, "slip_angles_deg": [0.0, a / 2, a],
                                    "kf_range_deg": span, "km_range_deg": span, "steady_load_levels": n},
                                   REGISTRY["cornering"].schema, "cornering")
            exp = REGISTRY["cornering"].from_table(table, _protocol(plan), plan.tire)
            folder = Path(char_dir) / "validation" / results.steady_reference_folder(v) / f"load_levels_{n}"
            for i, r in zip(todo, _resumed(folder, "cornering", exp, plan, [conds[i] for i in todo], batch_size, tick)):
                got[i] = r
        out[float(v)] = got
    return out


def storage_tire(tire, f_hz):
    """`tire` (a TireSpec) with every part's four moduli and the tread's E and G at their storage modulus
    E'(f_hz) of the Prony series (`materials.dynamic_modulus`): the rubber a vibration at f_hz sees (a
    static push sees the long-term moduli)."""
    from .materials import dynamic_modulus

    tau = np.asarray(tire.relaxation_times, float)
    parts = {}
    for name, p in tire.parts.items():
        s = float(dynamic_modulus(p["loss"], tau, f_hz)[1])
        parts[name] = p | {k: p[k] * s for k in ("E_meridional", "E_circumferential", "G_shear", "E_bending")}
    st = float(dynamic_modulus(tire.tread_loss, tau, f_hz)[1])
    return dataclasses.replace(tire, parts=parts, tread_E=tire.tread_E * st, tread_G=tire.tread_G * st)


def storage_pushes(root, plan, conds, freqs, on_case=None) -> list:
    """Per condition, E09's static push (the characterization's table, no release) on `storage_tire` at
    `freqs[i]` (Hz, E09's release frequency there; None: not run): k_l on the moduli the rubber shows at
    the frequency the lateral mode rings at (`characterize.characterization` puts it in the row as
    k_l_storage). Resumed from root/<case>, one folder per condition (each claimed with its own tire)."""
    from .config import validate_table
    from .experiments import REGISTRY

    table = dict(plan.tables.get("lateral_stiffness") or
                 validate_table({}, REGISTRY["lateral_stiffness"].schema, "lateral_stiffness"))
    table |= {"decay_s": 0.0, "method": "static"}
    from .batch import side_by_side

    todo = [(i, c, f) for i, (c, f) in enumerate(zip(conds, freqs)) if f]
    out = [None] * len(conds)
    if on_case is not None:
        on_case(None, 0, len(todo))

    def job(c, f):
        tire = storage_tire(plan.tire, f)
        exp = REGISTRY["lateral_stiffness"].from_table(table, _protocol(plan), tire)
        return lambda d: _resumed(Path(root) / results.case_name(0, c), "lateral_stiffness", exp, plan, [c], 1, None,
                                  tire=tire, device=d)[0]

    n_done = 0

    def done(k, res):
        nonlocal n_done
        i, c, _ = todo[k]
        out[i] = res
        n_done += 1
        if on_case is not None:
            on_case(results.case_name(0, c), n_done, len(todo))

    side_by_side([job(c, f) for _, c, f in todo], done)  # one folder per condition: side by side over the devices
    return out


def _step_table(slip_step_table):
    from .config import validate_table
    from .experiments import REGISTRY

    return validate_table(slip_step_table or {}, REGISTRY["slip_step"].schema, "slip_step")


def _protocol(plan):
    from .experiments.phases import Protocol

    return Protocol.from_dict(plan.solver)


def _resumed(folder, key, exp, plan, conds, batch_size, on_case, tire=None, device=None) -> list:
    """Run exp on `tire` (default plan.tire) at every condition not yet saved in folder/cases (claimed
    with these settings), then read every condition back: its ExperimentResult or its error message (str)."""
    from . import batch
    from .fingerprint import claim_folder, code_version
    from .io import check_writable
    from .tire import make_tire

    tire = plan.tire if tire is None else tire
    folder = check_writable(Path(folder))
    claim_folder(folder, {key: exp, "tire": tire, "solver": plan.solver, "conditions": conds,
                          "jtire": code_version()})
    names = [results.case_name(i, c) for i, c in enumerate(conds)]
    cases = results.cases_dir(folder)
    todo = [i for i, n in enumerate(names) if not results.is_done(cases / n)]
    done = [len(conds) - len(todo)]
    if on_case is not None:
        on_case(None, done[0], len(conds))

    def save(k, res):
        if isinstance(res, batch.CaseFailure):
            results.save_failure(cases / names[todo[k]], res.error)
        else:
            results.save(cases / names[todo[k]], res)
        done[0] += 1
        if on_case is not None:
            on_case(names[todo[k]], done[0], len(conds))

    if todo:
        batch.run(exp, make_tire(tire), [conds[i] for i in todo], batch=batch_size, on_result=save, device=device)
    return [_read_case(cases / n) for n in names]


def _read_case(folder):
    from .experiments.result import ExperimentResult

    d = results.read_result(folder)
    if d is not None:
        return ExperimentResult(d["experiment"], d["condition"], d["quantities"], signals=_signals(folder),
                                checks=d["checks"], info=d["info"])
    return results.read_error(folder) or "not run"


def validate(char_dir, plan, conditions=DEFAULT_CONDITIONS, slip_step_table=None, on_case=None, on_steady=None):
    """Compare ring and shell at `conditions` ((kg, psi) pairs of the grid). Returns a list of
    (condition dict, comparison rows, shell signals, ring signals, error of the slip step or None).
    on_case, on_steady: progress of the slip steps and the steady references (see slip_steps)."""
    from .rigid_ring import validation
    from .rigid_ring.table import read_characterization

    char = read_characterization(char_dir)
    conds = [{"load_N": kg * U.G0, "pressure_Pa": psi * U.PSI} for kg, psi in conditions]
    steps = slip_steps(char_dir, plan, conds, slip_step_table, on_case=on_case)
    steady_references(char_dir, plan, conds, slip_step_table, on_case=on_steady)  # read back by the diagnosis
    shells = [shell_metrics(char_dir, c["load_N"], c["pressure_Pa"]) for c in conds]
    out = []
    for c, st, (shell, s_sig) in zip(conds, steps, shells):
        row = char.row(c["load_N"], c["pressure_Pa"])
        error = st if isinstance(st, str) else None
        f_lat = shell.get("lateral.f_Hz")
        if error is None:
            m, sg = step_metrics(st, f_lateral_Hz=f_lat)
            shell |= m
            s_sig |= sg
        band = s_sig.pop("drop_band_Hz", None) or BELT_BAND_HZ
        # the ring rolls as far as the shell's record (the same input), read over the same window
        dist = None if error else st.info.get("distance_m")
        rr = ring_results(row, char.tire, band, f_lateral_Hz=f_lat, step_distance_m=dist) if row is not None else {}
        rows = validation.compare(shell, validation.ring_metrics(rr), failed=("step_",) if error else ())
        out.append((c, rows, s_sig, validation.ring_signals(rr), error))
    return out
