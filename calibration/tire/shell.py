"""The shell-model simulator behind calibration, sensitivities and the posterior check.

`ShellSimulator` implements `calibration.tire.simulator.Simulator` on the batch runner: a batch of
log-parameter vectors becomes one batch per experiment the targets use (every parameter set x every
condition of that experiment, vmapped and sharded over the devices), reduced on the host exactly as
`jtire run` reduces it. Its Jacobian is autodiff through the same programs with the experiments'
traced reductions (`Experiment.traced`): forward mode (vmapped tangents, one per free parameter)
through the static solves, reverse mode through the steady-rolling solves (implicit) and the
transients (checkpointed); the explicit step of each case is held fixed (a numerical setting).

Sensitivity quantities beyond the targets (k_sv, k_l, k_by, k_btheta, k_bgamma, k_f, k_m, footprint
length and width, rolling resistance) come from the experiments' traced reductions at the rated
condition (`SENSITIVITY`).

A free geometry parameter (`geometry.*`) changes the mesh, which is built in numpy and so not traced:
each distinct section gets its own model (same structure: the compiled programs are reused), the
points of an evaluation run grouped by section, and the Jacobian's geometry columns are forward
differences (`FD_STEP` in theta, one evaluation per column).
"""

import threading
import time

import jax
import jax.numpy as jnp
import numpy as np

from ... import batch, cache
from ...config import parse_solver
from ...experiments import REGISTRY, Case, Protocol
from ...results import RATED
from .simulator import Simulator

FD_STEP = 1e-3  # in theta = ln(value): 0.1 %; the static and steady solves converge to ~1e-6 relative
# quantity -> (experiment, table overrides) for sensitivities at the rated condition
SENSITIVITY = {
    "k_sv_N_per_m": ("vertical_stiffness", {}), "deflection_m": ("vertical_stiffness", {}),
    "k_l_N_per_m": ("lateral_stiffness", {"decay_s": 0.0}), "lateral_deflection_m": ("lateral_stiffness", {"decay_s": 0.0}),
    "contact_length_m": ("footprint", {}), "contact_width_m": ("footprint", {}),
    "k_btheta_Nm_per_rad": ("inplane_rotation", {}), "k_by_N_per_m": ("sidewall_translation", {}),
    "k_bgamma_Nm_per_rad": ("sidewall_camber", {}),
    "k_f_N_per_rad": ("cornering", {"slip_angles_deg": [0.0, 1.0, 2.0, 3.0]}),
    "k_m_Nm_per_rad": ("cornering", {"slip_angles_deg": [0.0, 1.0, 2.0, 3.0]}),
    "rolling_resistance_N": ("rolling_resistance", {}),
}


def _table(name, overrides):
    from ...config import validate_table

    raw = dict(overrides)
    if "slip_angles_deg" in raw:  # the table is validated in the file's units
        raw["slip_angles_deg"] = list(raw["slip_angles_deg"])
    return validate_table(raw, REGISTRY[name].schema, name)


class ShellSimulator(Simulator):
    def __init__(self, spec, tire_spec, solver=None, devices=None):
        from ...tire import make_tire

        self.spec = spec
        self.space = spec.space
        self.response_names = spec.response_names
        self.tire = make_tire(tire_spec)
        self.base = spec.base_params
        self.proto = Protocol.from_dict(parse_solver(solver or {}))
        self._solver = solver
        self.devices = devices
        # targets grouped by (experiment, table): one experiment instance, several conditions
        from ...fingerprint import plain

        self.groups = []
        for j, t in enumerate(spec.targets):
            exp = REGISTRY[t.experiment].from_table(t.table, self.proto, tire_spec)
            key = (exp.name, repr(plain(exp)))
            for g in self.groups:
                if g["key"] == key:
                    g["targets"].append((j, t))
                    break
            else:
                self.groups.append({"key": key, "exp": exp, "targets": [(j, t)]})
        # the price of a target Jacobian in forward runs is measured, not stated: before the first
        # one, a forward evaluation at the same point is timed after compile (`_forward_wall`), and
        # every Jacobian call sets "jacobian" to its own wall over that, less the time it spent making
        # programs (`cache.CompileClock`: a cold cache would otherwise eat a small budget's first call)
        self.cost_forward_equivalents = {"evaluate": 1.0, "jacobian": float("nan")}
        self._forward_wall = None
        # A call holds as many points as fill the devices once with the most conditions any
        # transient target asks per point (E12's two loads: one point per 2 cores); the static
        # solves run case by case anyway. Long jobs evaluate in pieces of this size and save each
        # as it returns. It costs no speed against one call holding every point
        # (benchmarks/bench_batch.py --experiments rolling_resistance --cases 16 --modes sharded sharded-1;
        # docs/design-notes.md).
        n_dev = len(jax.devices()) if devices is None else int(devices)
        per_point = max([len(g["targets"]) for g in self.groups if g["exp"].shardable] or [1])
        self.points_per_call = max(1, n_dev // per_point)
        from ...executor import InProcess, current

        if not isinstance(current(), InProcess):  # a cluster: enough points to give every worker a case
            self.points_per_call = max(self.points_per_call, -(-current().slots() // len(spec.targets)))
        self.last_wall = {}
        self.jacobian_modes = {}  # experiment name -> "forward" / "reverse" (default: see jacobian)
        # on_case(label, n_done, n_total): called as each case of an evaluation finishes (the CLI
        # draws a progress bar with it: an initial ARSM batch is ~40 default-mesh cases, minutes)
        self.on_case = None

    def fingerprint(self) -> dict:
        from ...fingerprint import code_version, plain

        return {"simulator": "shell", "mesh": {"n_theta": self.tire.spec.n_theta, "n_side": self.tire.spec.n_side,
                                               "n_crown": self.tire.spec.n_crown,
                                               "contact_subpoints": self.tire.spec.contact_subpoints},
                "solver": plain(self.proto), "jtire": code_version()}

    def for_targets(self, targets):
        import dataclasses

        spec = dataclasses.replace(self.spec, targets=tuple(targets), weights=(1.0,) * len(targets))
        sim = ShellSimulator(spec, self.tire.spec, self._solver, self.devices)
        sim.on_case = self.on_case
        return sim

    def tire_at(self, theta):
        """The tire with the section at theta (the base tire when no geometry is free)."""
        import dataclasses

        from ...tire import make_tire

        if not self.space.geometry_indices:
            return self.tire
        return make_tire(dataclasses.replace(self.tire.spec, geometry=self.space.geometry_at(theta)))

    def params(self, theta):
        return self.space.to_params(jnp.asarray(theta, dtype=jnp.float64), self.base)

    def evaluate(self, thetas) -> np.ndarray:
        thetas = np.atleast_2d(np.asarray(thetas, float))
        n = len(thetas)
        out = np.full((n, len(self.response_names)), np.nan)
        self.last_failures = {}  # row -> {target: error message} of this call's failed cases
        total = n * sum(len(g["targets"]) for g in self.groups)
        done = [0]
        lock = threading.Lock()  # static experiments report from their own threads

        def count(*_):
            with lock:
                done[0] += 1
                if self.on_case is not None:
                    self.on_case(f"{n} parameter set{'s' * (n > 1)}", done[0], total)

        if self.on_case is not None:  # the bar appears at 0 of total, before the first case runs
            self.on_case(f"{n} parameter set{'s' * (n > 1)}", 0, total)

        from ...executor import InProcess, current

        if not isinstance(current(), InProcess):  # --cluster: every case of the call is a task there
            t0 = time.perf_counter()
            out = self._values_on(current(), self.target_jobs(), thetas, self.response_names, count,
                                  self.last_failures)
            self.last_wall["cluster"] = time.perf_counter() - t0
            return self.space.add_bias(thetas, out, self.response_names)
        plist = [self.params(th) for th in thetas]

        # rows sharing a section run together on its model (all rows: no free geometry)
        sections = {}
        for i, th in enumerate(thetas):
            sections.setdefault(tuple(th[self.space.geometry_indices]), []).append(i)
        sections = [(self.tire_at(thetas[rows[0]]), rows) for rows in sections.values()]

        def run_group(g, device=None):
            for tire, rows in sections:
                run_section(g, tire, rows, device)

        def run_section(g, tire, rows, device):
            exp, tg = g["exp"], g["targets"]
            conds = [t.condition for _, t in tg]
            t0 = time.perf_counter()
            res = batch.run(exp, tire, [c for _ in rows for c in conds],
                            params_list=[plist[i] for i in rows for _ in conds], devices=self.devices,
                            on_result=count, device=device)
            self.last_wall[exp.name] = time.perf_counter() - t0
            for a, i in enumerate(rows):
                for k, (j, t) in enumerate(tg):
                    r = res[a * len(conds) + k]
                    if not isinstance(r, batch.CaseFailure):
                        out[i, j] = float(r.quantities[t.quantity])
                    else:  # the point's row keeps a nan; the history records why
                        self.last_failures.setdefault(i, {})[t.name] = str(r.error)

        # The static solves run case by case on one device each: with several devices, the static
        # experiments run at the same time, each on its own device (threads: JAX releases the GIL
        # while a program runs), faster than one after the other (docs/design-notes.md). The transients
        # then take every device.
        static = [g for g in self.groups if not g["exp"].shardable]
        n_dev = len(jax.devices()) if self.devices is None else int(self.devices)
        if len(static) > 1 and n_dev > 1:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(min(n_dev, len(static))) as pool:
                for f in [pool.submit(run_group, g, k % n_dev) for k, g in enumerate(static)]:
                    f.result()
        else:
            for g in static:
                run_group(g)
        for g in self.groups:
            if g["exp"].shardable:
                run_group(g)
        return self.space.add_bias(thetas, out, self.response_names)  # what the targets measure

    def jacobian(self, theta, quantities=None):
        """(values (q,), J (q, d)) by autodiff, per experiment in the cheaper mode: forward mode
        (jacfwd, one tangent per parameter) through the static solves, whose tangents share one
        factorization (implicit differentiation); reverse mode (jacrev, one checkpointed backward
        sweep per quantity) through a transient when it has fewer quantities than there are
        parameters (E12: 2 quantities against 20 parameters). `jacobian_modes` overrides per
        experiment name ("forward" / "reverse")."""
        theta = np.asarray(theta, float)
        if quantities is None:
            jobs = self.target_jobs()
            names = list(self.response_names)
        else:
            names = list(quantities)
            jobs = []
            for k, q in enumerate(names):
                if q not in SENSITIVITY:
                    raise KeyError(f"{q}: no traced reduction (known: {', '.join(SENSITIVITY)})")
                ename, over = SENSITIVITY[q]
                table = _table(ename, over)
                exp = REGISTRY[ename].from_table(table, self.proto, self.tire.spec)
                cond = RATED if REGISTRY[ename].needs_load else {"pressure_Pa": RATED["pressure_Pa"]}
                jobs.append((exp, table, [cond], [q], [k]))
        extra = 0.0
        if quantities is None and self._forward_wall is None:
            extra = 2.0  # the two reference evaluations are charged to this call
            self.evaluate(theta[None])  # compiles
            t1 = time.perf_counter()
            self.evaluate(theta[None])
            self._forward_wall = time.perf_counter() - t1
            self.last_wall["forward reference"] = self._forward_wall
        values = np.full(len(names), np.nan)
        J = np.full((len(names), self.space.d), np.nan)
        with cache.CompileClock() as clock:
            t0 = time.perf_counter()
            label = f"Jacobian ({self.space.d} parameters; one experiment at a time)"
            for k, (exp, _, conds, qs, idx) in enumerate(jobs):
                if self.on_case is not None:
                    self.on_case(label, k, len(jobs))
                # reverse for fewer quantities than parameters, except through the static solves, whose
                # forward tangents share one factorization; the steady-rolling solve's are one GMRES each
                mode = self.jacobian_modes.get(exp.name) or (
                    "reverse" if (exp.shardable or getattr(exp, "method", None) == "steady") and len(qs) < self.space.d
                    else "forward")
                t1 = time.perf_counter()
                v, jac = traced_jacobian(exp, self.tire_at(theta), self.params, theta, conds, qs, mode=mode)
                self.last_wall[f"jacobian {exp.name} ({mode})"] = time.perf_counter() - t1
                values[idx] = v
                J[idx] = jac
            # geometry columns (the traced ones are 0: the model is held fixed): forward differences of
            # plain runs on both sides (the host reductions, not mixed with the traced ones)
            geo = list(self.space.geometry_indices)
            points = [theta] + [theta + FD_STEP * np.eye(len(theta))[i] for i in geo]
            from ...executor import InProcess, current

            if geo and not isinstance(current(), InProcess):  # --cluster: every column's runs at once
                t1 = time.perf_counter()
                v = self._values_on(current(), jobs, points, names)
                for c, i in enumerate(geo):
                    J[:, i] = (v[c + 1] - v[0]) / FD_STEP
                self.last_wall["jacobian geometry columns (forward differences, cluster)"] = time.perf_counter() - t1
            elif geo:
                v0 = self._values(jobs, theta, len(names))
                for c, i in enumerate(geo):
                    t1 = time.perf_counter()
                    J[:, i] = (self._values(jobs, points[c + 1], len(names)) - v0) / FD_STEP
                    self.last_wall[f"jacobian {self.space.names[i]} (forward difference)"] = time.perf_counter() - t1
            if self.on_case is not None:
                self.on_case(label, len(jobs), len(jobs))
            self.last_wall["jacobian"] = time.perf_counter() - t0
        self.last_wall["jacobian: making its programs (not charged)"] = clock.seconds
        if quantities is None:
            # charged its run time only: what compiling costs depends on the cache, not on the budget's work
            run_s = max(self.last_wall["jacobian"] - clock.seconds, 0.0)
            self.cost_forward_equivalents["jacobian"] = run_s / self._forward_wall + extra
            # the targets measure tire + bias (the tire's columns are 0 there)
            values, J = self.space.add_bias_jacobian(theta, values, J, self.response_names)
        return values, J

    def target_jobs(self) -> list:
        """The targets as (experiment, table, conditions, quantities, response indices), one per group."""
        return [(g["exp"], g["targets"][0][1].table, [t.condition for _, t in g["targets"]],
                 [t.quantity for _, t in g["targets"]], [j for j, _ in g["targets"]]) for g in self.groups]

    def _values(self, jobs, theta, n):
        """The jobs' quantities (n,) at theta by plain runs (a failed case: nan)."""
        out = np.full(n, np.nan)
        tire, p = self.tire_at(theta), self.params(theta)
        for exp, _, conds, qs, idx in jobs:
            res = batch.run(exp, tire, conds, params_list=[p] * len(conds), devices=self.devices)
            for r, q, k in zip(res, qs, idx):
                if not isinstance(r, batch.CaseFailure):
                    out[k] = float(r.quantities[q])
        return out


    def _values_on(self, ex, jobs, points, names, on_case=None, failures=None):
        """The jobs' quantities (len(points), len(names)) at each point, every case a task on the executor
        (a cluster): the point's section and material leaves as plain data; a failed case stays nan
        (and goes into failures[row][names[k]] when given)."""
        from ...config import parse_solver
        from ...executor import CaseTask, params_leaves

        solver = parse_solver(self._solver or {})
        out = np.full((len(points), len(names)), np.nan)
        tasks, where = [], []
        for r, th in enumerate(points):
            spec, leaves = self.tire_at(th).spec, params_leaves(self.params(th))
            for exp, table, conds, qs, idx in jobs:
                for c, q, k in zip(conds, qs, idx):
                    tasks.append(CaseTask(exp.name, table, solver, spec, c, params=leaves))
                    where.append((r, q, k))

        def save(m, outcome):
            r, q, k = where[m]
            if not isinstance(outcome.result, batch.CaseFailure):
                out[r, k] = float(outcome.result.quantities[q])
            elif failures is not None:
                failures.setdefault(r, {})[names[k]] = str(outcome.result.error)
            if on_case is not None:
                on_case()

        ex.run(tasks, save)
        return out


def traced_jacobian(exp, tire, params_of, theta, conditions, quantities, mode: str = "forward"):
    """Values (k,) and Jacobian (k, d) of `quantities` (one per condition, paired in order) of `exp`
    with respect to theta, through the simulation (steps held at their values).

    mode "forward": jax.jacfwd (d tangents carried along one run; stores nothing). "reverse":
    jax.jacrev with every transient phase checkpointed (`experiments.program.reverse_mode`): one
    backward sweep per quantity, whatever d is."""
    cache.release_programs_if_crowded()  # every Jacobian compiles programs of its own
    cache.return_free_memory()  # what the last programs' making freed, before this one makes more
    if (mode == "reverse" or not exp.shardable) and len(conditions) > 1:
        # one condition after another: a backward sweep of a transient holds a lot of memory for one case
        # (benchmarks/bench_gradients.py; docs/design-notes.md), and a vmapped Newton solve (static,
        # steady) runs both branches of every conditional
        parts = [traced_jacobian(exp, tire, params_of, theta, [c], [q], mode) for c, q in zip(conditions, quantities)]
        return np.concatenate([v for v, _ in parts]), np.concatenate([j for _, j in parts])
    model = tire.model
    base = params_of(theta)
    flat = [(i, c) for i, cond in enumerate(conditions) for c in exp.cases(cond)]
    dts = (batch.stable_steps(model, [base] * len(flat), [c["pressure_Pa"] for _, c in flat],
                              float(exp.proto.settle_damping)) if exp.time_stepped else np.full(len(flat), np.nan))
    cases = jax.tree_util.tree_map(lambda *a: jnp.stack(a), *[
        Case.of(c.get("load_N", 0.0), c["pressure_Pa"], dts[k], exp.aux(c)) for k, (_, c) in enumerate(flat)])

    def f(th):
        if len(flat) == 1:
            # one case: no batch axis. jacfwd's tangents are a vmap of their own, and a vmap of the
            # tangents around a vmap of the cases broke JAX's batching of the static solver's Newton
            # loop (carry batch axes swapped: "while_loop body function carry input and carry output
            # must have equal types"); a single case needs no case axis anyway
            one = jax.tree_util.tree_map(lambda a: a[0], cases)
            outs = jax.tree_util.tree_map(lambda a: a[None], exp.simulate(model, params_of(th), one))
        else:
            outs = batch.simulate_batch(exp, model, params_of(th), cases)
        vals = []
        for i, cond in enumerate(conditions):
            mine = [jax.tree_util.tree_map(lambda a: a[k], outs) for k, (ii, _) in enumerate(flat) if ii == i]
            cc = [c for ii, c in flat if ii == i]
            vals.append(exp.traced(model, params_of(th), cc, mine)[quantities[i]])
        return jnp.stack(vals)

    def with_value(th):
        v = f(th)
        return v, v

    th0 = jnp.asarray(theta, dtype=jnp.float64)
    if mode == "forward":
        J, v = jax.jacfwd(with_value, has_aux=True)(th0)
    elif mode == "reverse":
        from ...experiments.program import reverse_mode

        with reverse_mode():
            J, v = jax.jacrev(with_value, has_aux=True)(th0)
    else:
        raise ValueError(f"mode {mode!r}: forward or reverse")
    return np.asarray(v), np.asarray(J)


def make_simulator(config, tire_spec) -> ShellSimulator:
    """The shell-model simulator for a calibration config (calibration.tire.spec.CalibrationSpec:
    its space, targets and base_params) and a validated tire (jtire.config.TireSpec)."""
    return ShellSimulator(config, tire_spec)
