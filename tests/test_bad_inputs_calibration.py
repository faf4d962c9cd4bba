"""Bad inputs of the data and calibration commands (data, compete, calibrate, sample, sensitivity): one
line, exit code 2, before any simulation (test_bad_inputs.py)."""

from pathlib import Path

import pytest

from .bad_input_harness import (
    Case, check_one_line, COMPETITION, POSTERIOR, STUDY, TRACK, _blocked, _comp, _compete_claimed,
    _compete_foreign_history, _data_dir, _exact_track, _out, _track_sub, _w)

def _biased(tmp, bounds, targets='["FX1", "FX2"]'):
    """study.toml beside the shipped tire, its bias entry (free[24]) renamed bias.drag with these bounds
    and targets."""
    text = Path(STUDY).read_text().replace('tire_file = "../tires/xone_xda.toml"',
                                           f'tire_file = "{Path(STUDY).parent.parent / "tires" / "xone_xda.toml"}"')
    old = 'name = "bias.non_tire_drag"\nbounds = [0.0, 3000.0]\ntargets = ["FX1", "FX2"]\n'
    assert old in text
    return _w(tmp, "biased.toml", text.replace(old, f'name = "bias.drag"\n{bounds}\ntargets = {targets}\n'))


def _geometry(tmp, bounds):
    """study.toml beside the shipped tire with the transverse crown radius (free[23]) free within these bounds."""
    text = Path(STUDY).read_text().replace('tire_file = "../tires/xone_xda.toml"',
                                           f'tire_file = "{Path(STUDY).parent.parent / "tires" / "xone_xda.toml"}"')
    old = 'name = "geometry.crown_radius"\nbounds = [1000.0, 8000.0]\n'
    assert old in text
    return _w(tmp, "geometry.toml", text.replace(old, f'name = "geometry.crown_radius"\n{bounds}\n'))


CASES = [
    # ---- data ------------------------------------------------------------------------------------
    Case("data-non-utf8-csv", lambda t: ["data", "--data-dir", _data_dir(t, track=TRACK.encode() + b"9,\xff\n"),
                                         *_out(t)], "track_rolling_resistance.csv", "not UTF-8", "line 35"),
    Case("data-empty-csv", lambda t: ["data", "--data-dir", _data_dir(t, sandbox=""), *_out(t)],
         "sandbox_rolling_resistance.csv", "empty"),
    Case("data-header-only-csv", lambda t: ["data", "--data-dir", _data_dir(t, track="\n".join(
        TRACK.splitlines()[:4]) + "\n"), *_out(t)], "no data rows (only the header)"),
    Case("data-duplicate-column", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "fz_lbs,rrc", "fz_lbs,fz_lbs")), *_out(t)], "line 4", "['fz_lbs'] appear more than once"),
    Case("data-short-row", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1A,28.43782,", "1A,")), *_out(t)], "line 5: 7 fields, the header has 8"),
    Case("data-not-a-number", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1A,28.43782", "1A,lots")), *_out(t)], "line 5: fx_lbs = 'lots': must be a number"),
    Case("data-inf", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub("1A,28.43782", "1A,inf")),
                                *_out(t)], "line 5: fx_lbs = inf: must be finite"),
    Case("data-unterminated-quote", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1,bobtail,120", '1,"bobtail,120')), *_out(t)], "line 5: not valid CSV"),
    Case("data-config-rows-disagree", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1,bobtail,120,1160.95,1A", "1,bobtail,80,1160.95,1A")), *_out(t)],
         "configuration 1 has runs with different pressure_psi"),
    Case("data-exact-fit", lambda t: ["data", "--data-dir", _data_dir(t, track=_exact_track()), *_out(t)],
         "fit track_120psi", "lie exactly on the linear trend"),
    Case("data-no-120-psi-runs", lambda t: ["data", "--data-dir", _data_dir(t, track="\n".join(
        ln for ln in TRACK.splitlines() if ",120," not in ln) + "\n"), *_out(t)],
         "fit track_120psi", "0 points: a fit with confidence intervals needs at least 3"),
    Case("data-missing-dir", lambda t: ["data", "--data-dir", str(Path(t) / "nowhere"), *_out(t)],
         "track_rolling_resistance.csv: not found"),
    Case("data-reference-malformed", lambda t: ["data", "--reference", _w(t, "r.toml", "[calibration\n"), *_out(t)],
         "r.toml: not valid TOML"),
    Case("data-reference-inf", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = inf\nforce_N = 1529.39\n"),
        *_out(t)], "r.toml: calibration.targets.rolling_resistance_1.vertical_load_kN = inf: must be in (0, 500]"),
    Case("data-reference-nan", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = 38.7\nforce_N = nan\n"),
        *_out(t)], "rolling_resistance_1.force_N = nan"),
    Case("data-reference-negative", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = -38.7\nforce_N = 1529.39\n"),
        *_out(t)], "vertical_load_kN = -38.7"),
    Case("data-reference-boolean", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = true\nforce_N = 1529.39\n"),
        *_out(t)], "vertical_load_kN = True: must be a number"),
    Case("data-reference-force-above-load", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = 1.0\nforce_N = 1500.0\n"),
        *_out(t)], "force_N = 1500: must be below the vertical load"),
    Case("data-reference-not-tables", lambda t: ["data", "--reference", _w(t, "r.toml", "calibration = 3\n"),
                                                 *_out(t)], "calibration.targets must be a table"),
    Case("data-reference-folder", lambda t: ["data", "--reference", str(t), *_out(t)], "is a folder"),
    Case("data-reference-non-utf8", lambda t: ["data", "--reference", _w(t, "r.toml", b"\xfe"), *_out(t)],
         "r.toml: not UTF-8"),
    Case("data-confidence-1", lambda t: ["data", "--confidence", "1", *_out(t)], "--confidence 1: must be in (0, 1)"),
    Case("data-confidence-nan", lambda t: ["data", "--confidence", "nan", *_out(t)], "--confidence nan"),
    Case("data-rrc-choice", lambda t: ["data", "--rrc", "both", *_out(t)], "argument --rrc: invalid choice"),
    Case("data-out-unwritable", lambda t: ["data", "--out", _blocked(t)], "cannot read or write", "a_file"),
    # ---- compete ---------------------------------------------------------------------------------
    Case("compete-non-utf8", lambda t: ["compete", _w(t, "bad.toml", b"\xff\xfe"), *_out(t)], "bad.toml",
         "not UTF-8"),
    Case("compete-misspelled-table", lambda t: ["compete", _comp(t, "[competition]", "[competiton]"), *_out(t)],
         "competiton: unknown field"),
    Case("compete-unknown-top-key", lambda t: ["compete", _w(t, "c.toml", "colour = 1\n" + COMPETITION), *_out(t)],
         "colour: unknown field"),
    Case("compete-seeds-boolean", lambda t: ["compete", _comp(t, "seeds = 20", "seeds = true"), *_out(t)],
         "competition.seeds = True: must be an integer"),
    Case("compete-budget-float", lambda t: ["compete", _comp(t, "budget = 50", "budget = 50.5"), *_out(t)],
         "competition.budget = 50.5"),
    Case("compete-unknown-key", lambda t: ["compete", _comp(t, "budget = 50", "budget = 50\nbudgte = 3"), *_out(t)],
         "competition.budgte: unknown field"),
    Case("compete-ga-population-above-budget", lambda t: ["compete", _comp(t, "pop_size = 10", "pop_size = 100"),
                                                          *_out(t)], "competition.options.ga", "pop_size = 100"),
    Case("compete-option-type", lambda t: ["compete", _comp(t, "min_width = 1e-4", 'min_width = "small"'), *_out(t)],
         "competition.options.arsm.min_width = 'small': must be a finite number"),
    Case("compete-anchor-unknown-method", lambda t: ["compete", _comp(t, "arsm = { error", "asrm = { error"),
                                                     *_out(t)], "competition.anchor.asrm: unknown method"),
    Case("compete-soil-unknown", lambda t: ["compete", _comp(t, "bekker_n = 0.7", "bekker_m = 0.7"), *_out(t)],
         "soil.bekker_m: unknown field"),
    Case("compete-soil-nan", lambda t: ["compete", _comp(t, "bekker_n = 0.7", "bekker_n = nan"), *_out(t)],
         "soil.bekker_n = nan"),
    Case("compete-bounds-inverted", lambda t: ["compete", _comp(t, "[1200.0, 2200.0]", "[2200.0, 1200.0]"), *_out(t)],
         "bounds.density_kg_m3"),
    Case("compete-method-twice", lambda t: ["compete", _comp(t, '["arsm", "ga", "mc"]', '["arsm", "arsm"]'),
                                            *_out(t)], "each method at most once"),
    Case("compete-seeds-flag", lambda t: ["compete", _comp(t, "", ""), "--seeds", "0", *_out(t)],
         "--seeds 0: must be in [1, 10000]"),
    Case("compete-methods-flag-empty", lambda t: ["compete", _comp(t, "", ""), "--methods", ",", *_out(t)],
         "--methods ','"),
    Case("compete-set-boolean", lambda t: ["compete", _comp(t, "", ""), "--set", "competition.budget=true", *_out(t)],
         "competition.budget = True"),
    Case("compete-out-unwritable", lambda t: ["compete", _comp(t, "", ""), "--out", _blocked(t)],
         "cannot read or write"),
    Case("compete-resume-other-soil", lambda t: _compete_claimed(t) + ["--set", "soil.pressure_Pa=80000.0"],
         "holds a competition with other soil"),
    Case("compete-history-of-other-settings", lambda t: _compete_foreign_history(t),
         "arsm_seed000.jsonl", "call 0 asks for x"),
    # ---- calibrate -------------------------------------------------------------------------------
    Case("calibrate-non-utf8", lambda t: ["calibrate", _w(t, "c.toml", b"\xff"), "--standin", *_out(t)], "c.toml",
         "not UTF-8"),
    Case("calibrate-seed-boolean", lambda t: ["calibrate", STUDY, "--standin", "--set", "arsm.seed=true", *_out(t)],
         "arsm.seed = True: must be an integer"),
    Case("calibrate-tire-error-names-file", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                       "tire.tire.crown_radius_mm=50", *_out(t)],
         "tire file xone_xda.toml: tire.tire.crown_radius_mm = 50"),
    # the rolling-resistance bias (calibration.tire.space bias.*): non-negative, on named targets of one unit
    Case("calibrate-bias-negative", lambda t: ["calibrate", _biased(t, "bounds = [-5.0, 3000.0]"), "--standin",
                                               *_out(t)], "free[24].bounds = [-5.0, 3000.0] (bias.drag)", "0 <= lo < hi"),
    Case("calibrate-bias-unknown-target", lambda t: ["calibrate", _biased(t, "bounds = [0.0, 3000.0]", '["FX3"]'),
                                                     "--standin", *_out(t)], "free[24].targets", "'FX3' is not a target"),
    Case("calibrate-bias-mixed-units", lambda t: ["calibrate", _biased(t, "bounds = [0.0, 3000.0]", '["DZ", "FX1"]'),
                                                  "--standin", *_out(t)], "free[24].targets", "one unit"),
    Case("calibrate-negative-nodal-damping", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                        "tire.model_form.nodal_damping_per_s=-1", *_out(t)],
         "tire file xone_xda.toml: tire.model_form.nodal_damping_per_s = -1", "[0, 100]"),
    # the section's geometry (issue: a crown radius below the section width; the sidewall's widest point
    # and mid-surface): each a field of the tire file, and a free geometry range whose end is no section
    Case("calibrate-crown-radius-below-width", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                          "tire.tire.crown_radius_mm=400", *_out(t)],
         "tire.tire.crown_radius_mm = 400", "must be above 523.6 mm"),
    Case("calibrate-widest-point-out-of-range", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                           "tire.tire.widest_point_ratio=0.9", *_out(t)],
         "tire.tire.widest_point_ratio = 0.9", "[0.2, 0.8]"),
    Case("calibrate-mid-surface-choice", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                    'tire.tire.mid_surface="outer"', *_out(t)],
         "tire.tire.mid_surface = 'outer'", "section_width, carcass"),
    Case("calibrate-geometry-bounds-no-section", lambda t: ["calibrate", _geometry(t, "bounds = [300.0, 6000.0]"),
                                                            "--standin", *_out(t)],
         "free[23].bounds = [300.0, 6000.0] (geometry.crown_radius)", "at 300 the section is not valid",
         "must be above 523.6 mm"),
    Case("calibrate-budget-below-the-initial-design", lambda t: ["calibrate", STUDY, "--standin", "--budget", "20",
                                                                  *_out(t)],
         "budget = 20: ARSM's initial design alone is d + 2 = 27 evaluations for 25 free parameters",
         "--budget"),
    Case("calibrate-budget-zero", lambda t: ["calibrate", STUDY, "--standin", "--budget", "0", *_out(t)],
         "--budget = 0: must be >= 1"),
    Case("calibrate-unknown-key", lambda t: ["calibrate", STUDY, "--standin", "--set", "colour=1", *_out(t)],
         "colour: unknown field"),
    Case("calibrate-negative-target", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                 "targets.DZ.measured_mm=-1", *_out(t)], "targets.DZ.measured_mm = -1"),
    # a quantity the experiment does not produce (a typo): refused with the allowed names, on the shell
    # model too (it used to simulate for minutes, then end in a KeyError)
    Case("calibrate-target-quantity-typo", lambda t: ["calibrate", STUDY, "--set", 'targets.DZ.quantity="deflection_mm"',
                                                      *_out(t)],
         "targets.DZ.quantity = 'deflection_mm': not a quantity vertical_stiffness produces", "allowed: k_sv_N_per_m",
         "deflection_m"),
    Case("calibrate-target-decay-without-decay", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                            'targets.DY.quantity="C_l_Ns_per_m"', *_out(t)],
         "targets.DY.quantity = 'C_l_Ns_per_m'", "allowed: k_l_N_per_m, lateral_deflection_m, lateral_force_N)"),
    Case("calibrate-out-unwritable", lambda t: ["calibrate", STUDY, "--standin", "--out", _blocked(t)],
         "cannot read or write"),
    Case("calibrate-method-choice", lambda t: ["calibrate", STUDY, "--method", "newton", *_out(t)],
         "argument --method: invalid choice"),
    Case("calibrate-check-tire-missing", lambda t: ["calibrate", STUDY, "--standin", "--check-tire",
                                                    str(Path(t) / "none.toml")], "no such tire file"),
    Case("calibrate-check-tire-not-a-tire", lambda t: ["calibrate", STUDY, "--standin", "--check-tire", STUDY],
         "tire file study.toml"),
    # ---- sample ----------------------------------------------------------------------------------
    Case("sample-no-history", lambda t: ["sample", POSTERIOR, "--history", str(Path(t) / "none"), *_out(t)],
         "no history.jsonl"),
    Case("sample-walkers-boolean", lambda t: ["sample", POSTERIOR, "--set", "sampler.walkers=true", *_out(t)],
         "sampler.walkers = True: must be an integer"),
    Case("sample-walkers-odd", lambda t: ["sample", POSTERIOR, "--set", "sampler.walkers=41", *_out(t)],
         "sampler.walkers = 41: must be even"),
    Case("sample-non-utf8", lambda t: ["sample", _w(t, "p.toml", b"\xfe"), *_out(t)], "p.toml", "not UTF-8"),
    Case("sample-prior-kind", lambda t: ["sample", POSTERIOR, "--set", "prior.kind=flat", *_out(t)],
         "prior.kind = 'flat'"),
    Case("sample-out-unwritable", lambda t: ["sample", POSTERIOR, "--out", _blocked(t)], "cannot read or write"),
    # ---- sensitivity -----------------------------------------------------------------------------
    Case("sensitivity-rel-tol", lambda t: ["sensitivity", STUDY, "--standin", "--rel-tol", "2", *_out(t)],
         "--rel-tol = 2: must be in (0, 1)"),
    Case("sensitivity-at-not-a-calibration", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(t), *_out(t)],
         "no summary.json there"),
    Case("sensitivity-at-non-utf8", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(Path(
        _w(t, "cal/summary.json", b"\xff")).parent), *_out(t)], "summary.json: not UTF-8"),
    Case("sensitivity-at-no-theta", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(Path(
        _w(t, "cal/summary.json", '{"x": 1}')).parent), *_out(t)], "holds no best point"),
    Case("sensitivity-unknown-quantity", lambda t: ["sensitivity", STUDY, "--standin", "--quantities", "nosuch",
                                                    *_out(t)], "--quantities", "nosuch"),
    Case("sensitivity-out-unwritable", lambda t: ["sensitivity", STUDY, "--standin", "--out", _blocked(t)],
         "cannot read or write"),
]


@pytest.mark.parametrize("case", [c.param() for c in CASES])
def test_bad_input_is_one_line_exit_2_before_any_simulation(case, tmp_path, monkeypatch, capsys):
    check_one_line(case, tmp_path, monkeypatch, capsys)
