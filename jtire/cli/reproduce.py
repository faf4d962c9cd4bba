"""`jtire reproduce [--out DIR] [--quick]`: the whole study in one command (the stages and the report are
`jtire.reproduce`). Each stage is a jtire command into DIR/<stage>; a killed run resumes where it stopped (a
stage's own folder keeps its finished cases), and a folder made with other settings is refused."""

import contextlib
import importlib.util
import io
import time
from pathlib import Path


FINISHED = ("done", "not converged")  # stage statuses a resumed chain skips


def add_arguments(p):
    p.add_argument("--out", default="runs/study", help="output folder (default runs/study); resumes from it")
    p.add_argument("--quick", action="store_true",
                   help="the same chain small, as its test: coarse ring, 3 moduli and the drag bias calibrated in 10 "
                        "runs, the characterization at the rated condition only, a short posterior (a few minutes)). Exit status: "
                        "0 every stage done; 1 the report is written but a stage had failed cases or a posterior "
                        "that did not converge; 2 a stage stopped the chain")


def run_cli(args, say) -> int:
    from tqdm import tqdm

    from .. import reproduce as R
    from ..errors import CasesFailed, JtireError, SimulationError
    from ..io import check_writable
    from . import build_parser

    out = Path(args.out)
    check_writable(out)
    man = R.open_manifest(out, args.quick)
    stage_list = R.stages(out, args.quick)
    done = sum(man["stages"].get(s.name, {}).get("status") in FINISHED for s in stage_list)
    if done:
        say(f"resuming {out}: {done} of {len(stage_list)} stages done", err=True)
    bar = tqdm(total=len(stage_list), initial=done, desc="reproduce", unit="stage")
    parser = build_parser()
    try:
        for st in stage_list:
            if man["stages"].get(st.name, {}).get("status") in FINISHED:
                continue  # a stage with failed cases is rerun: its command retries just those
            bar.set_postfix_str(st.name)
            command = "jtire " + " ".join(st.argv) if st.argv else "python paper_figures/fig*.py"
            say(f"\n== {st.name}: {st.title}\n   {command}", err=True)
            R.record(out, man, st.name, status="running", command=command)
            t0 = time.perf_counter()
            if st.argv:
                sub = parser.parse_args(list(st.argv))
                try:
                    rc = int(sub._module.run_cli(sub, say) or 0)
                except CasesFailed as e:  # the stage wrote its outputs without those cases: the chain goes on
                    say(f"   {st.name}: {e}", err=True)
                    R.record(out, man, st.name, status=f"done, {len(e.failures)} cases failed", failures=e.failures,
                             wall_s=time.perf_counter() - t0)
                    bar.update(1)
                    continue
                except JtireError as e:
                    R.record(out, man, st.name, status="failed", error=str(e), wall_s=time.perf_counter() - t0)
                    raise type(e)(f"stage {st.name}: {e} (fix it and rerun the same command to resume)") from None
                if rc not in st.ok_codes:
                    R.record(out, man, st.name, status=f"failed (exit {rc})", wall_s=time.perf_counter() - t0)
                    raise SimulationError(f"stage {st.name}: `{command}` exited {rc}; rerun to resume")
                status = "not converged" if rc == 1 else "done"
            else:
                status = _figures(R, out, args.quick, say)
            R.record(out, man, st.name, status=status, wall_s=time.perf_counter() - t0)
            bar.update(1)
    finally:  # the bar's last line before any error line
        bar.close()
    md, page = R.write_report(out, man, stage_list)
    say(f"wrote {md} and {page}")
    short = [(st.name, man["stages"].get(st.name, {}).get("status", "")) for st in stage_list]
    short = [(name, status) for name, status in short if status != "done"]
    for name, status in short:
        say(f"  {name}: {status} (the report says so; rerun the same command to retry)", err=True)
    return 1 if short else 0  # 1: the report is written, but not every stage finished clean


def _figures(R, out: Path, quick: bool, say) -> str:
    """Every paper_figures/ script from the chain's folders; each script's output kept in figures/log.txt."""
    from ..io import atomic_write_text

    scripts = R.figure_scripts()
    if not scripts:
        say("   paper_figures/ is not installed (a source checkout has it): no figures", err=True)
        return "skipped (paper_figures/ is in the source checkout only)"
    (out / "figures").mkdir(parents=True, exist_ok=True)
    log, failed = io.StringIO(), []
    for path in scripts:
        spec = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        with contextlib.redirect_stdout(log), contextlib.redirect_stderr(log):
            try:
                spec.loader.exec_module(mod)
                rc = mod.main(R.figure_argv(path, out, quick))
            except Exception as e:  # a figure that cannot be drawn is reported, the others still drawn
                log.write(f"{path.stem}: {type(e).__name__}: {e}\n")
                rc = 1
        if rc:
            failed.append(path.stem)
    atomic_write_text(out / "figures" / "log.txt", log.getvalue())
    if failed:
        say(f"   figures not drawn: {', '.join(failed)} (figures/log.txt says why)", err=True)
        return f"done, {len(scripts) - len(failed)} of {len(scripts)} figures ({', '.join(failed)} failed)"
    return "done"
