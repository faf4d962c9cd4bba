"""The virtual test programme over the condition grid: every experiment at every load x pressure, into
the rigid-ring tables, trend verdicts, a Magic Formula fit and an MF-Swift `.tir`.

A characterization config (`configs/characterize.toml`) names the tire file, the experiments (default:
all), the grid (loads in kg, pressures in psi; the study's 3 x 3 by default), the solver and any
experiment table. Each experiment runs as batches of its grid cases through `jtire.batch` (E05, E07, E08,
E13 once per pressure: the load does not enter; E10 at every slip angle of every condition, one case each;
E11 is sigma = k_f / k_l from E10 and E09 at each condition). Every case is saved the moment its batch
returns (`DIR/<experiment>/cases/<case>/result.json`, `signals.csv`); `DIR/settings.json` holds
everything that determines the numbers, so a killed run resumes with nothing recomputed and a rerun with
other settings refuses. Then E09's static push on the rubber's storage moduli at E09's release
frequency, per condition (`lateral_springs`, DIR/lateral_storage/): how much stiffer the lateral springs
are at the lateral mode than in a static push (the row's k_l_storage; `rigid_ring.params`).
"""

import dataclasses
from pathlib import Path


from . import batch, results
from . import units as U
from .config import parse_solver, read_tire_file, read_toml, validate_table
from .errors import ConfigError
from .fingerprint import claim_folder, code_version
from .io import check_writable
from .schema import Field

DEFAULT_EXPERIMENTS = ("footprint", "vertical_stiffness", "drum_cleat", "drop_test", "inplane_rotation", "traction",
                       "sidewall_translation", "sidewall_camber", "lateral_stiffness", "cornering", "rolling_resistance",
                       "sidewall_longitudinal", "longitudinal_stiffness")
GRID_SCHEMA = {**results.GRID_SCHEMA, **results.RATED_SCHEMA}
TOP_KEYS = {"description", "tire_file", "experiments", "grid", "solver", "validation"}
# the rigid ring's validation against the shell (`jtire.validate`): the shell's slip step resolves the force's
# build-up over a short light-load patch only from 4 contact points per segment on (docs/rigid-ring.md, Validation)
VALIDATION_SCHEMA = {"step_contact_subpoints": Field(int, 1, 1, 8, 8)}


@dataclasses.dataclass(frozen=True)
class Plan:
    """A validated characterization: tire, experiments (instances), grid conditions, rated condition."""

    path: Path
    tire: object
    tire_path: Path
    experiments: tuple
    conditions: tuple  # load x pressure, SI dicts
    pressures: tuple  # Pa
    rated: dict
    solver: dict
    tables: dict = dataclasses.field(default_factory=dict)  # experiment name -> its validated table (SI)
    validation: dict = dataclasses.field(default_factory=lambda: {k: f.default for k, f in VALIDATION_SCHEMA.items()})


def load_plan(path, tire_file=None, overrides=()) -> Plan:
    """Read and validate a characterization config (`configs/characterize.toml`) into a `Plan`.

    Every table is validated and every experiment built before anything runs; a bad field, an unknown
    experiment, a missing tire file or a rated condition outside the grid is one `ConfigError` line.

    Args:
        path (str | Path): the characterization TOML.
        tire_file (str | Path | None): a tire TOML to use instead of the config's `tire_file` (`--tire`); None: the
            config's, relative to the config.
        overrides (list[str]): `--set` strings; `tire.<section>.<key>=v` go to the tire file, the others to the config.

    Returns:
        The Plan: tire, experiment instances, the load x pressure grid conditions (SI), the pressures
        (Pa), the rated condition ({"load_N", "pressure_Pa"}), the solver settings and the tables.
    """
    from .config import apply_overrides
    from .experiments import REGISTRY
    from .experiments.phases import Protocol

    path = Path(path)
    raw = read_toml(path)
    tire_over = [o[len("tire."):] for o in overrides if o.startswith("tire.")]
    apply_overrides(raw, [o for o in overrides if not o.startswith("tire.")])
    for key in raw:
        if key not in TOP_KEYS and key not in REGISTRY:
            raise ConfigError(f"{key}: unknown field (allowed: {', '.join(sorted(TOP_KEYS))} and experiment tables)")
    names = raw.get("experiments", list(DEFAULT_EXPERIMENTS))
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise ConfigError("experiments: must be a list of experiment names")
    for n in names:
        if n not in REGISTRY:
            raise ConfigError(f"experiments: {n!r} unknown (known: {', '.join(REGISTRY)})")
        if n == "relaxation_length":
            raise ConfigError("experiments: relaxation_length is derived here from cornering and lateral_stiffness; "
                              "list those instead")
    if tire_file is not None:
        tire_path = Path(tire_file).resolve()
    elif isinstance(raw.get("tire_file"), str):
        tire_path = (path.parent / raw["tire_file"]).resolve()
    else:
        raise ConfigError("tire_file: missing (path of the tire TOML, relative to this config), or give --tire")
    _, tire = read_tire_file(tire_path, tire_over)
    solver = parse_solver(raw.get("solver", {}))
    proto = Protocol.from_dict(solver)
    tables = {n: validate_table(raw.get(n, {}), REGISTRY[n].schema, n) for n in names}
    exps = tuple(REGISTRY[n].from_table(tables[n], proto, tire) for n in names)
    g = validate_table(raw.get("grid", {}), GRID_SCHEMA, "grid")
    conditions = tuple(results.grid_conditions(g, "grid"))
    for e in exps:
        if hasattr(e, "check_condition"):
            for c in conditions:
                e.check_condition(c)
    rated = {"load_N": g["rated_load_kg"], "pressure_Pa": g["rated_pressure_psi"]}
    if not any(abs(c["load_N"] - rated["load_N"]) < 1e-6 and abs(c["pressure_Pa"] - rated["pressure_Pa"]) < 1e-3
               for c in conditions):
        raise ConfigError("grid.rated_load_kg, grid.rated_pressure_psi: must be one of the grid's conditions")
    validation = validate_table(raw.get("validation", {}), VALIDATION_SCHEMA, "validation")
    return Plan(path, tire, tire_path, exps, conditions, tuple(g["pressures_psi"]), rated, solver, tables, validation)


def experiment_conditions(plan: Plan, exp) -> list:
    return [{"pressure_Pa": p} for p in plan.pressures] if exp.per_pressure else list(plan.conditions)


def settings(plan: Plan) -> dict:
    return {"tire": plan.tire, "experiments": {e.name: e for e in plan.experiments}, "conditions": plan.conditions,
            "solver": plan.solver, "rated": plan.rated, "jtire": code_version()}


def run(plan: Plan, out, batch_size: int = 1, progress=None, on_case=None, executor=None) -> dict:
    """Run every experiment of the plan into `out` (resuming). Returns {experiment: [result dicts or
    None (failed), one per condition]}. progress: a callable(n_done_increment) or None; on_case(name,
    condition, error_or_None) after every case. executor: where the cases run (`jtire.executor`; default
    the current one: in this process, an experiment after another, unless --cluster named a cluster, which
    gets every unfinished case at once). This process writes every case folder and summary."""
    from .executor import CaseTask, current

    out = Path(out)
    check_writable(out)
    claim_folder(out, settings(plan))
    tasks, where = [], []  # where[k]: (experiment, case folder, condition) of tasks[k]
    for exp in plan.experiments:
        conds = experiment_conditions(plan, exp)
        folder = results.cases_dir(out, exp.name)
        for i, c in enumerate(conds):
            case = folder / results.case_name(i, c)
            if not results.is_done(case):
                tasks.append(CaseTask(exp.name, plan.tables[exp.name], plan.solver, plan.tire, c,
                                      contact_table=exp.name == "footprint"))
                where.append((exp, case, c))

    def save(k, outcome):
        exp, case, cond = where[k]
        if isinstance(outcome.result, batch.CaseFailure):
            results.save_failure(case, outcome.result.error)
            err = outcome.result.error
        else:
            results.save(case, outcome.result, outcome.tables)
            err = None
        if progress is not None:
            progress(len(exp.cases(cond)))
        if on_case is not None:
            on_case(f"{exp.name}/{case.name}", cond, err)

    if tasks:
        (executor or current()).run(tasks, save, batch_size=batch_size)
    found = {}
    for exp in plan.experiments:
        conds = experiment_conditions(plan, exp)
        folder = results.cases_dir(out, exp.name)
        names = [results.case_name(i, c) for i, c in enumerate(conds)]
        found[exp.name] = [results.read_result(folder / n) for n in names]
        results.write_summary(out / exp.name, names, conds, found[exp.name], exp.per_pressure)
    return found


def case_notes(found: dict) -> list:
    """One line per case that finished with something a user must know: rerun by `batch.run` on a
    finer ring (its own discretization check failed on the tire's mesh: which ring and why), or a
    slip-angle sweep that stopped beyond its fit ranges (which angles are missing and why).
    found: `run`'s {experiment: [result dicts]}."""
    lines = []
    for name, res in found.items():
        for r in res:
            info = (r or {}).get("info") or {}
            c = (r or {}).get("condition") or {}
            at = ((f"{c['load_N'] / U.G0:.1f} kg, " if "load_N" in c else "") + f"{c['pressure_Pa'] / U.PSI:.0f} psi"
                  if "pressure_Pa" in c else "")
            if "refined_from_n_theta" in info:
                lines.append(f"{name} at {at}: rerun on {info['n_theta']} segments ({info['refined_because']})")
            if "unsolved_slip_angles_deg" in info:
                angles = ", ".join(f"{v:g}" for v in info["unsolved_slip_angles_deg"])
                lines.append(f"{name} at {at}: slip angles {angles} deg not solved ({info['sweep_stopped']})")
    return lines


def total_cases(plan: Plan, out=None) -> tuple:
    """(all cases, cases already done in `out`) counted in simulated cases (E10: one per slip angle)."""
    total = done = 0
    for exp in plan.experiments:
        for i, c in enumerate(experiment_conditions(plan, exp)):
            n = len(exp.cases(c))
            total += n
            if out is not None and results.is_done(results.cases_dir(out, exp.name) / results.case_name(i, c)):
                done += n
    return total, done


def lateral_springs(plan: Plan, out, found: dict, on_case=None) -> list:
    """E09's static push on the rubber's storage moduli at E09's own release frequency, at every grid
    condition where E09 measured one (`validate.storage_pushes`, resumed from DIR/lateral_storage/<case>):
    the lateral springs the lateral mode sees (`rigid_ring.params.derive`'s lateral_springs="storage").
    Returns one result (or error message, or None: not run) per grid condition. found: `run`'s results."""
    from .validate import storage_pushes

    freqs = [_e09_frequency(plan, found, c) for c in plan.conditions]
    return storage_pushes(Path(out) / results.LATERAL_STORAGE, plan, plan.conditions, freqs, on_case)


def _e09_frequency(plan: Plan, found: dict, cond) -> float | None:
    """E09's release frequency (Hz) at a grid condition, from `run`'s results (None: no release fit)."""
    exp = next((e for e in plan.experiments if e.name == "lateral_stiffness"), None)
    if exp is None:
        return None
    for cc, r in zip(experiment_conditions(plan, exp), found.get(exp.name) or ()):
        if r is not None and _same(cc, cond):
            f = (r.get("quantities") or {}).get("f_d_fit_Hz")
            return float(f) if f else None
    return None


def _same(a: dict, b: dict) -> bool:
    return abs(a["load_N"] - b["load_N"]) < 1e-6 and abs(a["pressure_Pa"] - b["pressure_Pa"]) < 1e-6


def _storage_quantities(plan: Plan, out: Path, found: dict, cond) -> dict:
    """{k_l_storage_N_per_m, f_l_storage_Hz} at a grid condition from `lateral_springs`' folder ({}: none)."""
    f = _e09_frequency(plan, found, cond)
    folder = results.cases_dir(out / results.LATERAL_STORAGE / results.case_name(0, cond))
    d = results.find_case(folder, cond["load_N"], cond["pressure_Pa"]) if f and folder.is_dir() else None
    k = None if d is None else results.read_result(d)["quantities"].get("k_l_N_per_m")
    return {"k_l_storage_N_per_m": float(k), "f_l_storage_Hz": f} if k else {}


def tire_info(plan: Plan):
    """The rigid-ring TireInfo of the characterized tire (from its config): the belt inertias are the
    ones E05 and E08 took for their damping (the model's own unless their table says inertia = "study")."""
    from .experiments.sidewall import decay_inertia
    from .mesh import build_mesh
    from .rigid_ring.table import TireInfo

    s = plan.tire
    g = s.geometry
    own = build_mesh(g, s.masses, s.n_theta, s.n_side, s.n_crown).masses()
    choice = {e.name: getattr(e, "inertia", "model") for e in plan.experiments}
    I_by = decay_inertia(s, own, "belt_Iy_kgm2", choice.get("inplane_rotation", "model"))
    I_bx = decay_inertia(s, own, "belt_Ix_kgm2", choice.get("sidewall_camber", "model"))
    return TireInfo(name=s.size or plan.tire_path.stem, m_b_kg=s.masses.belt, m_tot_kg=s.masses.tire + s.masses.rim,
                    tire_mass_kg=s.masses.tire, rim_mass_kg=s.masses.rim, I_by_kgm2=I_by, I_bx_kgm2=I_bx,
                    # the ring's rim body carries the tire's non-belt part (sidewalls, beads) in its spin and
                    # camber inertia as m_a = m_tot - m_b carries it in mass: the ring then spins like the shell
                    I_ay_kgm2=s.masses.rim_Iy + own["nonbelt_Iy_kgm2"],
                    I_ax_kgm2=s.masses.rim_Ixz + own["nonbelt_Ix_kgm2"], unloaded_radius_m=g.outer_radius,
                    width_m=g.section_width, rim_radius_m=g.rim_radius, rim_width_m=g.rim_width,
                    aspect_ratio=g.section_height / g.section_width, rated_load_N=plan.rated["load_N"],
                    rated_pressure_Pa=plan.rated["pressure_Pa"],
                    # the whole tire (the .tir's IXX, IYY): the belt as the ring takes it plus the rest
                    tire_Iy_kgm2=I_by + own["nonbelt_Iy_kgm2"], tire_Ix_kgm2=I_bx + own["nonbelt_Ix_kgm2"],
                    relaxation_time_s=float(max(s.relaxation_times)))


def characterization(plan: Plan, out, found: dict):
    """The rigid-ring Characterization of the finished (or partial) run: one row per grid condition,
    quantities merged from every experiment at that condition (per-pressure ones by pressure), E11's
    sigma = k_f / k_l, `lateral_springs`' k_l on the storage moduli where run, and E10's and E06's curves."""
    from .rigid_ring.table import Characterization, row_from_results

    out = Path(out)
    by_name = {e.name: e for e in plan.experiments}
    rows = []
    for c in plan.conditions:
        parts, e10, e06, e06_surface = [], None, None, None
        for name, res_list in found.items():
            conds = experiment_conditions(plan, by_name[name])
            for i, (cc, r) in enumerate(zip(conds, res_list)):
                if r is None or abs(cc["pressure_Pa"] - c["pressure_Pa"]) > 1e-6:
                    continue
                if "load_N" in cc and abs(cc["load_N"] - c["load_N"]) > 1e-6:
                    continue
                parts.append(r | {"study_id": by_name[name].study_id})
                if name == "cornering":
                    s = results.read_signals(results.cases_dir(out, name) / results.case_name(i, cc))
                    e10 = None if s is None else {k: v.tolist() for k, v in s.items()}
                if name == "traction":
                    s = results.read_signals(results.cases_dir(out, name) / results.case_name(i, cc))
                    e06 = None if s is None else {k: v.tolist() for k, v in s.items()}
                    e06_surface = (r.get("info") or {}).get("surface", "drum")  # the transient runs on the drum
        q = {}
        for r in parts:
            q |= r["quantities"]
        if q.get("k_f_N_per_rad") and q.get("k_l_N_per_m"):
            parts.append({"quantities": {"sigma_m": q["k_f_N_per_rad"] / q["k_l_N_per_m"]}})
        parts.append({"quantities": _storage_quantities(plan, out, found, c)})
        rows.append(row_from_results(c["load_N"], c["pressure_Pa"], parts, e10_signals=e10, e06_signals=e06,
                                     e06_surface=e06_surface))
    return Characterization(tire_info(plan), rows)
