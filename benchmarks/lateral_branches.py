"""The rigid ring's lateral Maxwell branches: which branch layout a characterization can carry. For each
validation condition of a finished characterization, the ring's linear lateral release (`rigid_ring.linear.
lateral_ring_modes`) with the sidewall's branches sized to E09's storage push k_l' at its release frequency
(`identify.maxwell_branch`'s rule), in two layouts: one branch at the rubber's longest relaxation time (the
ring's default) and one branch per relaxation time of the tire's Prony series with its equal weights. Each
is given with every damper at zero (what the branches alone damp) and with E07's and E08's sidewall
dampers (C_cy = 0), beside E09's measured release zeta, which the tread damper C_cy must make up: a layout
whose branches alone damp more than E09 measured cannot be identified (no C_cy >= 0).

    python benchmarks/lateral_branches.py runs/characterize

Prints one markdown table (numpy only, a second).
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("char_dir", help="a finished characterization folder (jtire characterize --out DIR)")
    a = ap.parse_args(argv)
    from jtire import units as U
    from jtire.materials import prony_weights
    from jtire.rigid_ring.identify import branch_storage, sidewall_stiffening
    from jtire.rigid_ring.linear import lateral_ring_modes
    from jtire.rigid_ring.params import derive
    from jtire.rigid_ring.table import read_characterization
    from jtire.validate import DEFAULT_CONDITIONS

    folder = Path(a.char_dir)
    char = read_characterization(folder / "characterization.json")
    taus = np.sort(np.asarray(json.loads((folder / "settings.json").read_text())["tire"]["relaxation_times"], float))
    print(f"relaxation times (ms): {', '.join(f'{t * 1e3:g}' for t in taus)}\n")
    print("| condition | E09 zeta (fit) | layout | f (Hz) | zeta, dampers 0 | zeta, C_by + C_bgamma |")
    print("|---|---|---|---|---|---|")
    for kg, psi in DEFAULT_CONDITIONS:
        row = char.row(kg * U.G0, psi * U.PSI)
        d = derive(row, char.tire, lateral_springs="static")
        f_s, r, z_e09 = row.get("f_l_storage_Hz"), d.lateral_storage_ratio, row.get("xi_l_fit")
        s = None if None in (f_s, r, d.k_cy) else sidewall_stiffening(d.k_l, d.k_by, d.k_bgamma, d.k_cy, d.r_b, r)
        if s is None:
            print(f"| {kg:g} kg, {psi:g} psi | — | (no storage push or lateral springs in the row) | | | |")
            continue
        for name, tt, w in ((f"one, {taus[-1] * 1e3:g} ms", taus[-1:], np.ones(1)),
                            (f"{taus.size}, the Prony series' weights", taus, prony_weights(taus))):
            # weights w, scaled so the branches' storage at f_s is the sidewall's stiffening s
            betas = (s - 1) * w / sum(wi * (branch_storage(1.0, ti, f_s) - 1) for wi, ti in zip(w, tt))
            args = (char.tire, d.r_b, d.k_by, d.k_cy, d.k_bgamma)
            f0, z0 = lateral_ring_modes(*args, 0.0, 0.0, 0.0, (betas, tt))
            _, z1 = lateral_ring_modes(*args, d.C_by, 0.0, d.C_bgamma, (betas, tt))
            zs = "—" if z_e09 is None else f"{z_e09:.4f}"
            print(f"| {kg:g} kg, {psi:g} psi | {zs} | {name} | {f0[0]:.2f} | {z0[0]:.4f} | {z1[0]:.4f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
