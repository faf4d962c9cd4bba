"""JAX's persistent compilation cache, on by default for the command line.

Every jtire program (an experiment over a batch shape) takes tens of seconds to compile; the
persistent cache keeps the compiled programs on disk so a second process with the same job compiles
nothing. The folder is the user's cache folder, keyed by machine (CPU model, platform, JAX version),
so programs compiled for one machine are never loaded on another:
    $JTIRE_CACHE_DIR if set, else $XDG_CACHE_HOME/jtire/<key>, else ~/.cache/jtire/<key>.
`jtire --no-cache ...` (or JTIRE_CACHE_DIR=off) turns it off.
"""

import hashlib
import os
import platform
from pathlib import Path


def machine_key() -> str:
    import jax

    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        cpu = platform.processor()
    raw = f"{platform.machine()}|{platform.system()}|{cpu}|jax {jax.__version__}"
    return f"{platform.machine()}-jax{jax.__version__}-{hashlib.sha1(raw.encode()).hexdigest()[:10]}"


def cache_dir():
    """The cache folder to use, or None when turned off."""
    env = os.environ.get("JTIRE_CACHE_DIR")
    if env is not None:
        return None if env.strip().lower() in ("", "0", "off", "none") else Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "jtire" / machine_key()


def enable(path=None):
    """Turn JAX's persistent compilation cache on (every program, however fast it compiled).
    Returns the folder, or None when turned off or the folder cannot be made."""
    import jax

    path = cache_dir() if path is None else Path(path)
    if path is None:
        return None
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    return path


def active_dir():
    """The folder this process's persistent cache writes to, or None when it is off."""
    import jax

    d = jax.config.jax_compilation_cache_dir
    return Path(d) if d else None


# ---- compiled programs held in memory ---------------------------------------------------------------
# XLA on the CPU keeps every compiled program's kernels in memory maps of their own (hundreds per
# program: docs/design-notes.md), and Linux caps a process at vm.max_map_count maps (65,530 by
# default). Past it the code loader cannot map the next program and the process dies with a
# segmentation fault (docs/speed.md). So long jobs drop JAX's in-memory programs when the maps near
# the cap; they reload from the persistent cache when needed.
CROWDED_FRACTION = 0.7  # of vm.max_map_count: leaves room for the programs of one more run or Jacobian (docs/design-notes.md)


def map_count():
    """Memory maps of this process (Linux), or None where /proc is not there."""
    try:
        with open("/proc/self/maps", "rb") as f:
            return sum(1 for _ in f)
    except OSError:
        return None


def map_limit():
    """The kernel's per-process cap on memory maps, or None where it cannot be read."""
    try:
        return int(Path("/proc/sys/vm/max_map_count").read_text())
    except (OSError, ValueError):
        return None


def release_programs_if_crowded(fraction: float = CROWDED_FRACTION) -> bool:
    """Clear JAX's in-memory compiled programs when this process's memory maps pass `fraction` of the
    kernel's cap. Returns whether it cleared them."""
    n, cap = map_count(), map_limit()
    if n is None or cap is None or n < fraction * cap:
        return False
    import gc

    import jax

    jax.clear_caches()
    gc.collect()
    _CLEARS[0] += 1
    return True


_CLEARS = [0]


def return_free_memory() -> bool:
    """Hand the heap's free pages back to the system (glibc's malloc_trim). Compiling or loading a
    program frees gigabytes that glibc otherwise keeps mapped in this process, so a long job's resident
    memory climbs with every program it makes (docs/speed.md). False where there is no glibc."""
    try:
        import ctypes

        return bool(ctypes.CDLL("libc.so.6").malloc_trim(0))
    except (OSError, AttributeError):
        return False


def clears() -> int:
    """How many times this process dropped its in-memory programs (a program used after a clear is
    traced again, so tests that count traces account for it)."""
    return _CLEARS[0]


# tracing, lowering and compiling (or loading from the persistent cache) a program: jax.monitoring's
# compile events, each also recorded as a time span
COMPILE_EVENTS = ("/jax/core/compile/jaxpr_trace_duration", "/jax/core/compile/jaxpr_to_mlir_module_duration",
                  "/jax/core/compile/backend_compile_duration")


class CompileClock:
    """Wall seconds spent making programs (COMPILE_EVENTS) while the `with` block runs: the union of
    the events' time spans, so a trace nested in another's, or compiles on two threads at once, count
    once. A cost measured in run time can then leave out what a warm compilation cache would not pay."""

    def __enter__(self):
        import jax

        self._spans = []
        jax.monitoring.register_event_time_span_listener(self._on)
        return self

    def _on(self, event, start, end, **_):
        if event in COMPILE_EVENTS:
            self._spans.append((start, end))

    def __exit__(self, *exc):
        import jax

        jax.monitoring.unregister_event_time_span_listener(self._on)

    @property
    def seconds(self) -> float:
        total, top = 0.0, -float("inf")
        for a, b in sorted(self._spans):
            if b > top:
                total += b - max(a, top)
                top = b
        return total
