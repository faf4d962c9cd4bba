"""The `jtire` command line: `jtire run | sweep | compete | data | calibrate | sample | sensitivity | reproduce |
new-tire | export-vtk`.

One module per subcommand in this package (`jtire.cli.run`, ...); this file only wires them together, and
turns every expected failure (a bad config, an unstable simulation) into one line on stderr and a
non-zero exit. Library modules never print; this is the only place that writes to the terminal.
"""

import argparse
import contextlib
import importlib
import importlib.util
import os
import sys

# subcommand -> (module, one-line help). Each module defines `add_arguments(parser)` and
# `run_cli(args, say) -> int`, and writes to the terminal only through `say` (`say(text)` to
# stdout, `say(text, err=True)` to stderr): this file is the one place that prints.
# Imports are lazy so `jtire --help` is instant.
SUBCOMMANDS = {
    "run": ("jtire.cli.run", "run virtual experiments from a TOML config (default: the static experiments at rated)"),
    "sweep": ("jtire.cli.sweep", "run an experiment over the load x pressure grid (vmapped)"),
    "compete": ("jtire.cli.compete", "ARSM vs GA vs Monte Carlo on the soil-block simulation"),
    "data": ("jtire.cli.data", "measured test-track and sandbox rolling-resistance tables and fits"),
    "characterize": ("jtire.cli.characterize", "every experiment over the load x pressure grid: rigid-ring tables, trends, .tir"),
    "export-tir": ("jtire.cli.export_tir", "rigid-ring tables, trends, MF fit and an MF 6.1 .tir from a characterization"),
    "calibrate": ("jtire.cli.calibrate", "tune the tire's parameters to the calibration targets (ARSM or Levenberg-Marquardt)"),
    "sample": ("jtire.cli.sample", "posterior of the calibrated parameters (emcee on an emulator of the targets)"),
    "sensitivity": ("jtire.cli.sensitivity", "d(quantity)/d(log parameter) table, heat map and identifiable directions"),
    "reproduce": ("jtire.cli.reproduce", "the whole study in one command: data, competition, calibration, characterization, "
                                         "posterior, figures and one report (--quick: the same chain small)"),
    "new-tire": ("jtire.cli.new_tire", "a tire file (and run and characterization configs) from a size, e.g. 295/75R22.5"),
    "export-vtk": ("jtire.cli.export_vtk", "a run's recorded frames as ParaView .vtu files and a .pvd time series"),
}


# subcommands whose cases go to the executor --cluster names (`jtire.executor`; calibrate and sample: the
# shell model's evaluations)
ON_CLUSTER = ("sweep", "characterize", "calibrate", "sample")


@contextlib.contextmanager
def _executor(args):
    """The executor --cluster (or JTIRE_CLUSTER) names, made current for the subcommand; none: in-process."""
    if not args.cluster:
        yield None
        return
    from jtire import executor
    from jtire.errors import ConfigError

    if args.command not in ON_CLUSTER:
        raise ConfigError(f"--cluster {args.cluster}: only {', '.join(ON_CLUSTER)} run on a cluster so far "
                          f"(unset JTIRE_CLUSTER, or drop --cluster, for {args.command})")
    with executor.connect(args.cluster, args.cluster_config) as ex, executor.using(ex):
        yield ex


class UserError(Exception):
    """An error caused by the user's input; reported as one line, no traceback."""


def _available():
    out = {}
    for name, (mod, helptext) in SUBCOMMANDS.items():
        try:
            spec = importlib.util.find_spec(mod)
        except ModuleNotFoundError:
            spec = None
        if spec is not None:
            out[name] = (mod, helptext)
    return out


def _say(text: str = "", err: bool = False) -> None:
    print(text, file=sys.stderr if err else sys.stdout, flush=True)


class _Parser(argparse.ArgumentParser):
    """argparse with the house error format: one line on stderr (no usage block), exit code 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser():
    parser = _Parser(prog="jtire", description=__doc__.splitlines()[0])
    parser.add_argument("--no-cache", action="store_true",
                        help="do not use the persistent compilation cache (default: on, in the user's cache folder; "
                             "JTIRE_CACHE_DIR sets the folder)")
    parser.add_argument("--cluster", default=os.environ.get("JTIRE_CLUSTER") or None, metavar="SPEC",
                        help="run the cases of sweep, characterize, calibrate and sample on a Dask cluster: local:N (N worker "
                             "processes here), tcp://HOST:PORT (a running scheduler), slurm or pbs (settings in "
                             "cluster.toml); default: in this process (JTIRE_CLUSTER sets it too). Needs "
                             "pip install 'jtire[cluster]'")
    parser.add_argument("--cluster-config", default=None, metavar="FILE",
                        help="the cluster.toml of --cluster slurm|pbs (default: $JTIRE_CLUSTER_CONFIG, ./cluster.toml, "
                             "~/.config/jtire/cluster.toml)")
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (mod, helptext) in _available().items():
        p = sub.add_parser(name, help=helptext, description=helptext)
        module = importlib.import_module(mod)
        module.add_arguments(p)
        p.set_defaults(_module=module)
    return parser


def main(argv=None):

    parser = build_parser()
    args = parser.parse_args(argv)
    from jtire.errors import JtireError

    if not args.no_cache:
        from jtire import cache

        cache.enable()
    try:
        with _executor(args):
            return int(args._module.run_cli(args, _say) or 0)
    except JtireError as e:
        _say(f"jtire {args.command}: error: {e}", err=True)
        return 2
    except OSError as e:  # an output folder that cannot be made or written, a disk full, ...
        where = f" {e.filename}" if getattr(e, "filename", None) else ""
        _say(f"jtire {args.command}: error: cannot read or write{where}: {e.strerror or e}", err=True)
        return 2
    except KeyboardInterrupt:
        _say(f"jtire {args.command}: interrupted (progress saved where the command supports it)", err=True)
        return 130


if __name__ == "__main__":
    sys.exit(main())
