"""Sidewall stiffness and damping with a rigid belt: E05 (in-plane rotation), E07 (lateral
translation), E08 (camber-wise rotation), and E13 (fore-aft translation: jtire's addition, not in the
study, which assumed k_bx = k_bz; `direction = "z"` pushes the belt vertically instead).

Rim locked in all six DOFs, no road, the belt (crown part: belt, undertread, tread) rigid
(`physics.rigid_belt`), so only the sidewalls deform; rigid from the start, through the inflation too
(the study's rigid tread/undertread is a rigid body throughout).

    1. inflate with the rim held;
    2. hold: the belt load on: the static stiffness k = load / steady motion;
    3. release: ramp the belt load off in `release_ramp` (1 ms: a step for the 25-40 Hz belt modes)
       with the settle damping OFF and record the belt's rigid motion; reduce it with
       `decay` (two peaks and a damped-sine fit) about the unloaded level, C = xi 2 M omega_n with M
       the model's own rigid belt (`Mesh.masses()`: E05 I_by, E07 m_b, E08 I_bx); E05 and E08 take the
       study's inertias from the tire file's [reference] with `inertia = "study"` in their table.

Loads, as the resultant `Drive.belt_load` takes (force, moment about the belt's mass centre):
    E05: circumferential force F at the belt radius r  -> M_y = F r    (k_btheta = F r / theta_ss)
    E07: F at the top and F at the bottom, same side  -> F_y = 2 F    (k_by = 2 F / y_ss)
    E08: F at the top and F at the bottom, opposite   -> M_x = 2 F r  (k_bgamma = 2 F r / gamma_ss)
    E13: F at the top and F at the bottom, fore-aft   -> F_x = 2 F    (k_bx = 2 F / x_ss)
r is the belt radius at its centre line (the distance from the axle to the belt where the forces act,
measured on the inflated state; the static method takes it at rest, which a rigid belt keeps through
the inflation, checked). On a rigid body only the resultant matters. The load does not enter.

Method "static" (the default): steps 1 and 2 are static equilibria (`jtire.equilibrium`, long-term
moduli: the belt held "until steady" with the rubber fully relaxed), and the release is the explicit
transient from the held state (every Maxwell branch relaxed, at rest). Method "transient": steps 1
and 2 by dynamic relaxation too (settle damping on, settled when the kinetic energy is below the
protocol's tolerance), as before.
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import equilibrium as EQ
from .. import signals, solve
from .. import units as U
from ..errors import ConfigError
from ..physics.rigid_belt import belt_motion
from ..schema import Field
from ..state import TireState
from .base import Experiment
from .decay import decay_checks, decay_names, decay_quantities, release_branch, sample_times
from .loads import RIM_LOCKED
from .phases import FAR, Case, flat_road, make_drive
from .program import Phase, check_phase, f64, phase, run_info, run_plan, run_plan_vmapped
from .result import ExperimentResult
from .static_path import static_summary

ZERO6 = np.zeros(6)


INERTIAS = ("model", "study")


def _belt_hold(model, params, pressure, load6):
    """Inflation and the belt load `load6` as static levels (rigid belt, rim held): a Path of 2 levels."""
    return EQ.static_path(model, params, pressure, EQ.belt_levels(pressure, load6[None]), rigid_belt=True)


# compiled once for E05, E07, E08 and E13 (same level count): a Newton solver is long to compile
_belt_hold_jit = eqx.filter_jit(_belt_hold)


def decay_inertia(spec, own: dict, key: str, inertia: str = "model") -> float:
    """The belt inertia `key` (belt_Iy_kgm2, belt_Ix_kgm2) of C = 2 I omega_n: the model's own (`own`:
    `Mesh.masses()`), or the study's from the tire file's [reference] (inertia = "study"). The rigid
    ring takes the same one, so its damping ratio is the one measured."""
    return float(spec.reference[key]) if inertia == "study" else float(own[key])


def belt_radius(model, y):
    """Largest distance (m) of a belt node from the axle: the belt's centre line (traced)."""
    r = jnp.hypot(y.x.x - y.q[0], y.x.z - y.q[2])
    return jnp.max(jnp.where(model.belt_mask > 0, r, 0.0))


class _Sidewall(Experiment):
    """E05 / E07 / E08: the shared plan; subclasses give the load and the measured coordinate."""

    per_pressure = True
    needs_load = False
    saved_field: ClassVar[tuple]  # (saved key, component) of the measured belt motion
    k_name: ClassVar[str]
    c_name: ClassVar[str]
    c_unit: ClassVar[str]
    x_name: ClassVar[str]
    mass_name: ClassVar[str]
    own_key: ClassVar[str]  # M: the model's own rigid-belt mass or inertia (`Mesh.masses()` key)

    force: jax.Array
    decay: jax.Array
    release_ramp: jax.Array
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)
    inertia: str = eqx.field(static=True, default="model")  # E05, E08: "study" takes [reference]'s
    method: str = eqx.field(static=True, default="static")  # inflation and hold: "static" or "transient"
    options: ClassVar[tuple] = ()  # further static fields taken from the table as they are

    @property
    def time_stepped(self) -> bool:
        return True  # the release is a transient whichever way the held state was reached

    @staticmethod
    def schema_for(force_kN, force_help, inertia=False):
        s = {"force_kN": Field(float, U.KN, 0.01, 200, force_kN, force_help),
             "decay_s": Field(float, 1, 0.02, 2, 0.2, "s of free decay after the release"),
             "release_ramp_ms": Field(float, U.MS, 0, 20, 1.0, "ms (0: a step)"),
             "method": Field(str, default="static", choices=("static", "transient"))}
        if inertia:  # the belt inertia of C = 2 I omega_n: the model's own, or the study's ([reference])
            s["inertia"] = Field(str, default="model", choices=INERTIAS)
        return s

    @staticmethod
    def names_for(k_name, x_name, load_name, mass_name, c_name, c_unit) -> tuple:
        """Every quantity `reduce` writes (the subclasses' `quantity_names`)."""
        return (k_name, x_name, load_name, "force_N", "belt_radius_m") + decay_names(mass_name, c_name, c_unit) + (
            "decay_mass_source",)

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        inertia = table.get("inertia", "model")
        if inertia == "study" and not tire_spec.reference[cls.own_key]:
            raise ConfigError(f"{cls.name}.inertia = 'study': the tire file's [reference] gives no {cls.own_key} "
                              f"(allowed: {', '.join(INERTIAS)}; model: the model's own)")
        return cls(proto=proto, force=f64(table["force_kN"]), decay=f64(table["decay_s"]),
                   release_ramp=f64(table["release_ramp_ms"]), inertia=inertia, method=table["method"],
                   **{k: table[k] for k in cls.options if k in table})

    def load6(self, r):
        raise NotImplementedError

    def decay_mass(self, tire) -> float:
        """M of C_c = 2 M omega_n: the model's own rigid belt, or the study's inertia (inertia = "study")."""
        if self.own_key == "belt_kg":
            return self.own_inertia(tire)
        return decay_inertia(tire.spec, tire.mesh.masses(), self.own_key, self.inertia)

    def own_inertia(self, tire) -> float:
        return float(tire.mesh.masses()[self.own_key])

    def simulate(self, model, params, case):
        if self.method == "static":
            return self._simulate_static(model, params, case)
        proto, road = self.proto, flat_road(-FAR)
        kw = dict(surface=road, rigid_belt=True)

        def inflate(y, t, mem):
            d = make_drive(case.pressure, case.dt, pressure0=0.0, t0=t, t1=t + proto.inflate_ramp,
                           damping=proto.settle_damping, belt_load0=ZERO6, belt_load1=ZERO6, **kw)
            return Phase(d, y, proto.inflate_max, proto.inflate_ramp), mem

        def hold(y, t, mem):
            mem = dict(mem, r=belt_radius(model, y))
            d = make_drive(case.pressure, case.dt, t0=t, t1=t + proto.load_ramp, rim_free=RIM_LOCKED,
                           damping=proto.settle_damping, belt_load0=ZERO6, belt_load1=self.load6(mem["r"]), **kw)
            return Phase(d, y, proto.load_ramp + proto.settle_max, proto.load_ramp), mem

        def release(y, t, mem):
            return release_branch(case, surface=road, load0=self.load6(mem["r"]), load1=ZERO6, rim_free=RIM_LOCKED,
                                  ramp=self.release_ramp, duration=self.decay, belt=True, rigid_belt=True)(y, t, mem)

        y0 = TireState.at_rest(model, len(params.relaxation_times))
        outs, y, mem = run_plan(model, params, [inflate, hold, release], y0, {"r": 0.0}, proto.ke_tol, self.n_save)
        # the end state too: the tests check on it that the belt stayed rigid through every phase
        return {"phases": outs, "r": mem["r"], "y": y}

    def _simulate_static(self, model, params, case):
        """Inflation and hold as static levels (rigid belt, rim held), then the release from the held
        state. The belt radius is taken at rest: a rigid belt keeps it through the inflation (the
        inflated state's radius is returned beside it and checked)."""
        y0 = TireState.at_rest(model, len(params.relaxation_times))
        r = belt_radius(model, y0)
        load = self.load6(r)
        path = _belt_hold_jit(model, params, case.pressure, load)
        inflated, held = (jax.tree_util.tree_map(lambda a, k=k: a[k], path.ys) for k in (0, 1))
        pose = lambda y: jnp.stack(belt_motion(y.x, model.x_ref, model.node_mass, model.belt_mask))  # noqa: E731
        def release(c):
            return [release_branch(c, surface=flat_road(-FAR), load0=load, load1=ZERO6, rim_free=RIM_LOCKED,
                                   ramp=self.release_ramp, duration=self.decay, belt=True, rigid_belt=True)]

        # the rigid-belt runs never see the load (per pressure: tests/test_sidewall.py reads their jaxpr)
        blind = Case(f64(0.0), case.pressure, case.dt, case.aux)
        outs, y, _ = run_plan_vmapped(model, params, release, blind, held, {}, self.proto.ke_tol, self.n_save)
        return {"phases": outs, "r": r, "r_inflated": belt_radius(model, inflated), "y": y,
                "static_infos": path.infos, "poses": jnp.stack([pose(inflated), pose(held)])}

    def _coord(self, ph):
        """The measured coordinate at the end of a phase (last saved sample; the phase settled)."""
        key, k = self.saved_field
        s = np.asarray(ph.saved[key])
        ok = np.isfinite(np.asarray(ph.saved["ke"]))
        return float(s[ok][-1, k])

    def traced(self, model, params, condition_cases, outputs):
        out = outputs[0]
        key, k = self.saved_field
        if self.method == "static":
            x = out["poses"][:, 0 if key == "belt_disp" else 1, k]
            x_ss = jnp.abs(x[1] - x[0])
            return {self.k_name: jnp.max(jnp.abs(self.load6(out["r"]))) / x_ss, self.x_name: x_ss}
        ph = out["phases"]

        def end(i):
            s = ph.saved[key][i][:, k]
            ok = jnp.isfinite(ph.saved["ke"][i])
            return s[jnp.max(jnp.where(ok, jnp.arange(s.shape[0]), 0))]

        x_ss = jnp.abs(end(1) - end(0))
        return {self.k_name: jnp.max(jnp.abs(self.load6(out["r"]))) / x_ss, self.x_name: x_ss}

    def _held_static(self, out):
        """(x0, x1, release phase, checks, info) of the static method: the inflated and held coordinates."""
        EQ.check_static(out["static_infos"], lambda k: f"{self.name}: " + ("inflation" if k == 0 else "hold (belt load)"))
        key, k = self.saved_field
        x0, x1 = (float(v) for v in np.asarray(out["poses"])[:, 0 if key == "belt_disp" else 1, k])
        checks, info = static_summary(out["static_infos"])
        r, r_inf = float(out["r"]), float(out["r_inflated"])
        # the load's lever arm is the belt radius at rest; the rigid belt must keep it when inflated
        checks["belt_radius_inflated_rel_change"] = abs(r_inf - r) / r
        return x0, x1, phase(out["phases"], 0), checks, info | {"levels": 2}

    def _held_transient(self, out, model):
        inf, held, rel = (phase(out["phases"], i) for i in range(3))
        check_phase("inflate", inf, model)
        check_phase("hold", held, model)
        checks = {"inflate_settled": bool(inf.settled), "hold_settled": bool(held.settled),
                  "hold_t_s": float(held.t_end - held.t0)}
        return self._coord(inf), self._coord(held), rel, checks, {"method": "transient"}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model = tire.model
        x0, x1, rel, checks, info0 = (self._held_static(out) if self.method == "static"
                                      else self._held_transient(out, model))
        check_phase("release", rel, model, require_settled=False)
        r = float(out["r"])
        load6 = np.asarray(self.load6(r))
        x_ss = x1 - x0
        load = float(np.abs(load6).max())
        decay, ramp = float(self.decay), float(self.release_ramp)
        ts = sample_times(rel, decay, self.n_save)
        key, k = self.saved_field
        x = np.asarray(rel.saved[key])[:, k] - x0
        M = self.decay_mass(tire)
        # the unloaded level is the inflated pose (no friction, no plasticity: the sidewalls return)
        fd = signals.free_decay(ts, x, M, t_start=float(ts[0]) + ramp, x_final=0.0)
        q = {self.k_name: load / abs(x_ss), self.x_name: abs(x_ss),
             ("load_N" if key == "belt_disp" else "moment_Nm"): load, "force_N": float(self.force), "belt_radius_m": r}
        q |= decay_quantities(fd, self.mass_name, self.c_name, self.c_unit)
        q["decay_mass_source"] = self.inertia  # "model": Mesh.masses(); "study": the tire file's [reference]
        own = self.own_inertia(tire)
        checks |= {"model_own_mass_or_inertia": own,
                  # single-DOF check: the rigid belt's own mass (inertia) x omega_n^2 against the static
                  # k; they differ by the sidewalls' share of the motion and viscoelastic stiffening
                  "k_from_frequency_own_mass": own * fd.omega_n_fit**2,
                  "k_dynamic_vs_static_rel": own * fd.omega_n_fit**2 / (load / abs(x_ss)) - 1.0}
        checks |= decay_checks(fd, rel)
        sig = {"time_s": ts - ts[0], self.x_name.replace("_ss", ""): x,
               "rubber_dissipated_J": np.asarray(rel.saved["dissipated"]) - float(np.asarray(rel.saved["dissipated"])[0])}
        info = info0 | run_info(out["phases"]) | {"study_id": self.study_id, "decay_s": decay, "release_ramp_s": ramp,
                                          "load_applied_as": "resultant on the rigid belt (force, moment about its mass centre)"}
        return ExperimentResult(self.name, {"pressure_Pa": condition["pressure_Pa"]}, q, signals=sig, checks=checks,
                                info=info)


class InplaneRotation(_Sidewall):
    name = "inplane_rotation"
    study_id = "E05"
    description = "E05 in-plane rotational sidewall stiffness and damping (k_btheta, C_btheta), rigid belt"
    schema = _Sidewall.schema_for(15.0, "kN circumferential on the belt", inertia=True)
    saved_field = ("belt_rot", 1)
    k_name, c_name, c_unit, x_name = "k_btheta_Nm_per_rad", "C_btheta", "Nms_per_rad", "theta_ss_rad"
    mass_name = "decay_inertia_kgm2"
    own_key = "belt_Iy_kgm2"
    traced_names = ("k_btheta_Nm_per_rad", "theta_ss_rad")
    quantity_names = _Sidewall.names_for(k_name, x_name, "moment_Nm", mass_name, c_name, c_unit)

    def load6(self, r):
        return jnp.zeros(6).at[4].set(self.force * r)



class SidewallTranslation(_Sidewall):
    name = "sidewall_translation"
    study_id = "E07"
    description = "E07 sidewall translational stiffness and damping (k_by, C_by), rigid belt"
    schema = _Sidewall.schema_for(2.0, "kN at each of top and bottom (same direction)")
    saved_field = ("belt_disp", 1)
    k_name, c_name, c_unit, x_name = "k_by_N_per_m", "C_by", "Ns_per_m", "y_ss_m"
    mass_name = "decay_mass_kg"
    own_key = "belt_kg"  # the model's belt mass is the tire file's [mass] belt_kg (the mesh is built to it)
    traced_names = ("k_by_N_per_m", "y_ss_m")
    quantity_names = _Sidewall.names_for(k_name, x_name, "load_N", mass_name, c_name, c_unit)

    def load6(self, r):
        return jnp.zeros(6).at[1].set(2 * self.force)



class SidewallCamber(_Sidewall):
    name = "sidewall_camber"
    study_id = "E08"
    description = "E08 sidewall camber-wise stiffness and damping (k_bgamma, C_bgamma), rigid belt"
    schema = _Sidewall.schema_for(5.0, "kN at each of top and bottom (opposite directions)", inertia=True)
    saved_field = ("belt_rot", 0)
    k_name, c_name, c_unit, x_name = "k_bgamma_Nm_per_rad", "C_bgamma", "Nms_per_rad", "gamma_ss_rad"
    mass_name = "decay_inertia_kgm2"
    own_key = "belt_Ix_kgm2"
    traced_names = ("k_bgamma_Nm_per_rad", "gamma_ss_rad")
    quantity_names = _Sidewall.names_for(k_name, x_name, "moment_Nm", mass_name, c_name, c_unit)

    def load6(self, r):
        return jnp.zeros(6).at[3].set(2 * self.force * r)


DIRECTIONS = {"x": 0, "z": 2}


class SidewallLongitudinal(_Sidewall):
    """E13: the in-plane translational sidewall spring and damper the rigid ring's fore-aft / wind-up
    mode rests on. Without a road the tire is axisymmetric about the axle, so the fore-aft (x) and the
    vertical (z) rigid-belt springs are the same spring seen from two sides (the tests check that)."""

    name = "sidewall_longitudinal"
    study_id = "E13"
    description = "E13 longitudinal sidewall stiffness and damping (k_bx, C_bx), rigid belt (jtire's addition)"
    schema = _Sidewall.schema_for(2.0, "kN at each of top and bottom (same direction)") | {
        "direction": Field(str, default="x", choices=tuple(DIRECTIONS))}
    k_name, c_name, c_unit, x_name = "k_bx_N_per_m", "C_bx", "Ns_per_m", "x_ss_m"
    mass_name = "decay_mass_kg"
    own_key = "belt_kg"
    traced_names = ("k_bx_N_per_m", "x_ss_m")
    quantity_names = _Sidewall.names_for(k_name, x_name, "load_N", mass_name, c_name, c_unit)
    direction: str = eqx.field(static=True, default="x")
    options = ("direction",)

    @property
    def saved_field(self):
        return ("belt_disp", DIRECTIONS[self.direction])

    def load6(self, r):
        return jnp.zeros(6).at[DIRECTIONS[self.direction]].set(2 * self.force)

    def reduce(self, tire, condition, outputs):
        res = super().reduce(tire, condition, outputs)
        res.info["direction"] = self.direction  # "z": the same spring pushed vertically (k_bz of the rigid belt)
        return res
