"""Slip-angle step while rolling (rigid-ring validation, docs/rigid-ring.md §8.3; not one of the study's
twelve): the tire rolls straight on the flat-track machine (`stages.rolling_plan` at 0 deg, the damping
ramped off), then the road's direction steps to the slip angle at once and the lateral force builds up
over the rolled distance. Read like the ring's scenario (`rigid_ring.scenarios.slip_step`), by
`jtire.slip_reading`: steady F_y and M_z (SAE, the last 5 % of the record), the distance s63 to 63 % of
the steady F_y (~ the relaxation length sigma; it must not change with speed), and the overshoot. Case aux: the speed (m/s).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import slip_reading
from .. import units as U
from ..schema import Field
from .loads import DOWN, RIM_Z_SPIN, lateral_sae
from .phases import flat_road, make_drive
from .program import Phase, f64
from .result import ExperimentResult
from .stages import ROLLING_SCHEMA, Rolling, road_velocity, rolling_plan

PER_SPEED = ("F_y_steady_SAE_N", "M_z_steady_SAE_Nm", "s63_m", "overshoot", "F_y_tail_drift_rel")  # + _<speed>


def _names(speeds) -> tuple:
    return tuple(f"{n}_{v:g}" for v in speeds for n in PER_SPEED) + ("slip_angle_deg", "load_N")


class SlipStep(Rolling):
    name = "slip_step"
    study_id = "V03"
    description = "slip-angle step while rolling: lateral force build-up over distance (rigid-ring validation)"
    schema = {k: v for k, v in ROLLING_SCHEMA.items() if k != "speed_mph"} | {
        "speeds_m_per_s": Field(list, 1, 0.5, 40, [5.0, 15.0], "m/s"),
        "slip_angle_deg": Field(float, U.DEG, -20, 20, 2.0, "deg"),
        "distance_m": Field(float, 1, 0.2, 20, 3.0, "m rolled after the step (~8 relaxation lengths)"),
        "n_samples": Field(int, 1, 101, 4001, 601, "samples over the step record")}
    aux_names = ("speed",)
    quantity_names = _names((5.0, 15.0))  # the default speeds; `produces` names those of the table

    speeds: tuple = eqx.field(static=True, default=())
    alpha: jax.Array = None
    distance: jax.Array = None

    @classmethod
    def produces(cls, table):
        return _names(table["speeds_m_per_s"])

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        fields = cls.rolling_fields(dict(table, speed_mph=table["speeds_m_per_s"][0]), proto, tire_spec)
        fields["n_save"] = int(table["n_samples"])
        return cls(speeds=tuple(table["speeds_m_per_s"]), alpha=f64(table["slip_angle_deg"]),
                   distance=f64(table["distance_m"]), **fields)

    def stages(self):
        return super().stages() + ["step"]

    def cases(self, condition):
        return [dict(condition, speed=v) for v in self.speeds]

    def simulate(self, model, params, case):
        speed = case.aux[0]
        vel = road_velocity(speed, self.alpha)

        def step(y, t, mem):
            d = make_drive(case.pressure, case.dt, force0=case.load * DOWN, force1=case.load * DOWN, t0=t, t1=t,
                           rim_free=RIM_Z_SPIN, surface=flat_road(mem["z_road"], vel), damping=0.0, rim_frame=1.0)
            return Phase(d, y, self.distance / speed, jnp.inf), mem

        outs, y, mem = rolling_plan(model, params, case, self.proto, outer_radius=self.outer_radius, speed=speed,
                                    slip_angle=0.0, settle_s=self.settle_s, ramp_s=self.ramp_s,
                                    release_s=self.release_s, measure_s=self.measure_s, damping=self.damping,
                                    n_save=self.n_save, final=[step])
        return {"phases": outs}

    def reduce(self, tire, condition, outputs):
        model = tire.model
        a = float(self.alpha)
        q, sig, checks = {}, {}, {}
        for out, v in zip(outputs, self.speeds):
            checks |= {f"{k} ({v:g} m/s)": val for k, val in self.check(out, model, where=f"{v:g} m/s: ").items()}
            ph = jax.tree_util.tree_map(lambda x: np.asarray(x[-1]), out["phases"])
            t = np.linspace(float(ph.t0), float(ph.t_end), self.n_save)
            f, m = ph.saved["contact_force"], ph.saved["contact_moment"][:, 2]
            fy = lateral_sae(a, f[:, 0], f[:, 1])
            mz = -m
            s = v * (t - t[0])
            r = slip_reading.readings(s, fy, mz)
            key = f"{v:g}"
            q |= {f"{n}_{key}": r[n] for n in PER_SPEED}
            sig |= {f"distance_m_{key}": s, f"F_y_SAE_N_{key}": fy, f"M_z_SAE_Nm_{key}": mz}
        q |= {"slip_angle_deg": float(np.degrees(a)), "load_N": condition["load_N"]}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks,
                                info={"speeds_m_per_s": list(self.speeds), "distance_m": float(self.distance)})
